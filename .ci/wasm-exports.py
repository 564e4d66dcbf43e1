#!/usr/bin/env python3
"""Checks the viewer's .wasm: it imports nothing the page's loader does not give (no imports at
all: wasm32-unknown-unknown's std needs none) and exports every call the page makes.

Usage: wasm-exports.py FILE.wasm NAME...
"""
import sys


def leb(data, at):
    """An unsigned LEB128 number at `at`: (value, next offset)."""
    value, shift = 0, 0
    while True:
        byte = data[at]
        at += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return value, at


def name(data, at):
    length, at = leb(data, at)
    return data[at:at + length].decode(), at + length


def sections(data):
    if data[:4] != b"\0asm":
        sys.exit("not a WebAssembly module")
    at = 8
    while at < len(data):
        kind = data[at]
        size, at = leb(data, at + 1)
        yield kind, data[at:at + size]
        at += size


def main():
    path, wanted = sys.argv[1], sys.argv[2:]
    data = open(path, "rb").read()
    imports, exports = [], []
    for kind, body in sections(data):
        if kind in (2, 7):
            count, at = leb(body, 0)
            for _ in range(count):
                first, at = name(body, at)
                if kind == 2:
                    second, at = name(body, at)
                    imports.append(f"{first}.{second}")
                    break  # one is enough to fail
                exports.append(first)
                at += 1  # export kind
                _, at = leb(body, at)  # index
    print(f"{path}: {len(data)} bytes, {len(exports)} exports, {len(imports)} imports")
    if imports:
        sys.exit(f"the viewer's module imports {imports[0]}: the page's loader gives nothing")
    missing = [w for w in wanted if w not in exports]
    if missing:
        sys.exit(f"the viewer's module lacks the exports {missing}")


main()
