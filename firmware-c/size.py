#!/usr/bin/env python3
"""Flash and RAM of the C example by origin, from the linker map: the hairsim static library,
the C code, and newlib and libgcc. Usage: size.py build/hairsim-c.map"""
import re
import sys

FLASH = {".vectors", ".text", ".ARM.exidx", ".data"}
RAM = {".data", ".bss"}
ONE_LINE = re.compile(r"^ (\.\S+|COMMON)\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")
NEWLIB = ("libc.a", "libc_nano.a", "libg.a", "libg_nano.a", "libnosys.a", "libgcc.a")
SECOND_LINE = re.compile(r"^\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")


def origin(path):
    if "libhairsim_ffi.a" in path or "libhairsim.a" in path:
        return "hairsim library"
    if any(f"/{lib}(" in path for lib in NEWLIB):
        return "newlib + libgcc"
    return "C example"


def by_origin(path):
    """Flash and static RAM bytes by origin: two dicts keyed like `origin` names."""
    flash, ram = {}, {}
    output = None
    in_map = False
    for line in open(path, encoding="utf-8", errors="replace"):
        line = line.rstrip("\n")
        if line.startswith("Linker script and memory map"):
            in_map = True
            continue
        if not in_map:
            continue
        head = re.match(r"^(\.\S+|/DISCARD/)", line)
        if head:
            output = head.group(1)
            continue
        m = ONE_LINE.match(line)
        if m:
            size, where = int(m.group(3), 16), m.group(4)
        else:
            m = SECOND_LINE.match(line)
            if not m:
                continue
            size, where = int(m.group(2), 16), m.group(3)
        if size == 0 or where.startswith("load address"):
            continue
        who = origin(where)
        if output in FLASH:
            flash[who] = flash.get(who, 0) + size
        if output in RAM:
            ram[who] = ram.get(who, 0) + size
    return flash, ram


def main(path):
    flash, ram = by_origin(path)
    order = ["hairsim library", "C example", "newlib + libgcc"]
    print("flash by origin, bytes: " + ", ".join(f"{k} {flash.get(k, 0)}" for k in order)
          + f" (total {sum(flash.values())})")
    print("static RAM by origin, bytes: " + ", ".join(f"{k} {ram.get(k, 0)}" for k in order)
          + f" (total {sum(ram.values())}; the stack is the linker script's)")


if __name__ == "__main__":
    main(sys.argv[1])
