#!/usr/bin/env bash
# Writes the C header of hairsim-ffi: include/hairsim.h, or the file given as $1. One header
# serves every capacity: a program built for a library of other capacities than the default
# 4 x 16 defines HAIRSIM_STRANDS and HAIRSIM_NODES before including it. cbindgen writes the
# declarations; the world's size as a formula of the capacities and its alignment, which
# cbindgen cannot evaluate, come from the unit test `tests::header_defines`, run on this 64-bit
# host: a 32-bit target's world is no larger (only its `usize` fields shrink), and
# `hairsim_init` checks the buffer against the running target's own size. The summary of the
# sizing table (ffi/sizing.txt, written by ffi/sizing.py) goes into the banner.
set -euo pipefail
CBINDGEN_VERSION=0.29.4
out=${1:-}
case "$out" in "" | /*) ;; *) out="$(pwd)/$out" ;; esac
cd "$(dirname "$0")"
out=${out:-$PWD/include/hairsim.h}

have=$(cbindgen --version 2>/dev/null || true)
if [ "$have" != "cbindgen $CBINDGEN_VERSION" ]; then
  echo "need cbindgen $CBINDGEN_VERSION, found '${have:-none}':" \
    "cargo install cbindgen --version $CBINDGEN_VERSION --locked" >&2
  exit 1
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# At the default capacities, whatever the environment says: the text does not depend on them.
env -u HAIRSIM_STRANDS -u HAIRSIM_NODES \
  cargo test -q --lib -- --exact tests::header_defines --nocapture >"$tmp/test.out"
sed -n '/^@HAIRSIM_CAPACITY_BEGIN@$/,/^@HAIRSIM_CAPACITY_END@$/p' "$tmp/test.out" |
  sed '1d;$d' >"$tmp/capacity.h"
grep -q '^#define HAIRSIM_WORLD_SIZE_FOR' "$tmp/capacity.h" || {
  echo "tests::header_defines printed no capacities:"; cat "$tmp/test.out"; exit 1
} >&2
cat >>"$tmp/capacity.h" <<'C'
/**
 * Makes `buffer` (`len` bytes) an empty world, after checking that the library was built for
 * this header: its version (HAIRSIM_VERSION_MAJOR and, while that is 0, HAIRSIM_VERSION_MINOR)
 * and its capacities (HAIRSIM_STRANDS, HAIRSIM_NODES). A mismatch returns
 * HAIRSIM_ERROR_VERSION_MISMATCH, HAIRSIM_ERROR_STRANDS_MISMATCH or
 * HAIRSIM_ERROR_NODES_MISMATCH and leaves the buffer alone. See hairsim_init_versioned.
 */
#define hairsim_init(buffer, len) \
  hairsim_init_versioned((buffer), (len), HAIRSIM_VERSION, HAIRSIM_STRANDS, HAIRSIM_NODES)
/** Declares a world buffer of the right size and alignment: `static HAIRSIM_WORLD_STORAGE(w);` */
#if defined(__cplusplus)
#define HAIRSIM_WORLD_STORAGE(name) unsigned char name alignas(HAIRSIM_WORLD_ALIGN)[HAIRSIM_WORLD_SIZE]
#elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L
#define HAIRSIM_WORLD_STORAGE(name) _Alignas(HAIRSIM_WORLD_ALIGN) unsigned char name[HAIRSIM_WORLD_SIZE]
#else
#define HAIRSIM_WORLD_STORAGE(name) unsigned char name[HAIRSIM_WORLD_SIZE] __attribute__((aligned(HAIRSIM_WORLD_ALIGN)))
#endif
C

cbindgen --quiet --config cbindgen.toml --crate hairsim-ffi --output "$tmp/hairsim.h"
# The capacities replace cbindgen's placeholder; the version and the sizing summary go into
# the banner.
awk -v capacity="$tmp/capacity.h" -v version="$CBINDGEN_VERSION" -v sizing="$PWD/sizing.txt" '
  /^\/\* @HAIRSIM_CAPACITY@ \*\/$/ { print ""; while ((getline line < capacity) > 0) print line; next }
  /^ \* @HAIRSIM_SIZING@$/ { while ((getline line < sizing) > 0) print line; next }
  { gsub(/@CBINDGEN_VERSION@/, version); print }
' "$tmp/hairsim.h" >"$out"
echo "wrote $out"
