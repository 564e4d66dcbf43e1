#!/usr/bin/env python3
"""Where a step's instructions go on the Cortex-M4F: reads a QEMU execution trace of a
profiling build (`HAIRSIM_PROFILE=rod|dftl|dftl_noshape|draped|draped_clear`, see
`src/latency.rs`) and counts the instructions executed between the firmware's `step_begins`
and `step_ends` markers, per function of the core (the innermost one, inlined or not) and per
source line, and the dynamic share of VDIV/VSQRT and of the multiply-accumulates, fused or
chained (against the static share `latency.py` assumes), and the executed mix by kind of
instruction: floating-point arithmetic (flops, counting a multiply-accumulate as two), loads
and stores, moves, integer work and branches (`docs/study/floors.md` sets the floating-point
part against the models' floors), and the instructions per stage of the step.

    cd firmware && HAIRSIM_PROFILE=dftl_noshape cargo build --release
    qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic -icount shift=0 \\
      -semihosting-config enable=on,target=native -d in_asm,exec,nochain -D /tmp/trace.log \\
      -kernel target/thumbv7em-none-eabihf/release/hairsim-firmware
    python3 profile.py /tmp/trace.log target/thumbv7em-none-eabihf/release/hairsim-firmware

Usage: profile.py TRACE ELF [ROWS]
"""
import collections
import re
import subprocess
import sys

# The Cortex-M4F's 3-cycle multiply-accumulates (`latency.py`'s model).
MULTIPLY_ACCUMULATE = ("vfma", "vfms", "vfnma", "vfnms", "vmla", "vmls", "vnmla", "vnmls")

# Kinds of instruction, first match wins (by mnemonic prefix); the rest is integer work.
KINDS = (
    ("VDIV/VSQRT", ("vdiv", "vsqrt")),
    ("multiply-accumulate", MULTIPLY_ACCUMULATE),
    ("other FP arithmetic", ("vadd", "vsub", "vmul", "vnmul", "vneg", "vabs")),
    ("FP compare", ("vcmp", "vmrs")),
    ("FP load", ("vldr", "vldm", "vpop")),
    ("FP store", ("vstr", "vstm", "vpush")),
    ("FP move/convert/select", ("vmov", "vsel", "vcvt")),
    ("load", ("ldr", "ldm", "pop")),
    ("store", ("str", "stm", "push")),
    ("branch/IT", ("b", "cb", "it")),
)


def kind(mnemonic):
    """The instruction's kind in `KINDS`, or integer work."""
    for name, prefixes in KINDS:
        if mnemonic.startswith(prefixes):
            return name
    return "integer"


def markers(elf):
    """Entry addresses of the step markers: True where a step begins."""
    out = subprocess.run(["llvm-nm", elf], check=True, capture_output=True, text=True).stdout
    found = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and ("step_begins" in parts[2] or "step_ends" in parts[2]):
            found[int(parts[0], 16) & ~1] = "step_begins" in parts[2]
    if len(found) != 2:
        sys.exit("no step markers in the ELF: build with HAIRSIM_PROFILE set")
    return found


def read_trace(path, marks):
    """Translated blocks (start → [(address, mnemonic)]) and, between the markers, how often
    each block ran."""
    blocks, runs = {}, collections.Counter()
    block, inside = None, False
    for line in open(path, errors="replace"):
        if line.startswith("Trace"):
            pc = int(re.search(r"\[[0-9a-f]+/([0-9a-f]+)/", line).group(1), 16)
            inside = marks.get(pc, inside)
            if inside:
                runs[pc] += 1
            block = None
        elif line.startswith("IN:"):
            block = []
        elif block is not None:
            m = re.match(r"0x([0-9a-f]+):\s+[0-9a-f]{4}(?: [0-9a-f]{4})?\s+(\S+)", line)
            if m:
                if not block:
                    blocks[int(m.group(1), 16)] = block
                block.append((int(m.group(1), 16), m.group(2)))
            elif not line.strip():
                block = None
    return blocks, runs


# The stage an instruction belongs to: the module of the outermost frame of the core's inline
# chain that lies outside the pipeline's own files (which only sequence the stages). Functions
# that are not inlined start a chain of their own, so a helper called from several stages
# (libm, the compiler's memset and memcpy) counts under its own name.
STAGES = (
    ("rod/frames.rs", "frame passes"),
    ("src/frames.rs", "frame passes"),
    ("rod/energy.rs", "elastic forces"),
    ("rod/integrate.rs", "symplectic Euler"),
    ("rod/substeps.rs", "substep plan"),
    ("rod/twist.rs", "twist"),
    ("projection/", "projection and velocities"),
    ("root_coupling.rs", "root coupling"),
    ("guard.rs", "guard and snapshot"),
    ("snapshot.rs", "guard and snapshot"),
    ("forces.rs", "external forces"),
    ("collide.rs", "projection and velocities"),
)


def stage(core, pairs):
    """The stage of an instruction whose inline chain (innermost first) is `pairs`, of which
    `core` are the frames in the core's source."""
    for _, where in reversed(core):
        if "/pipeline/" in where:
            continue
        for part, name in STAGES:
            if part in where:
                return name
        return "other core: " + where.split("/core/src/")[-1].split(":")[0]
    if core:
        return "pipeline (sequencing, gathering, bookkeeping)"
    # No line of the core's source: name the chain by its outermost function.
    outermost = re.sub(r"<.*", "", pairs[-1][0])
    if outermost.startswith(("sincos", "fmax", "fmin", "atan", "floor")):
        return "libm (sincosf, fmaxf, fminf)"
    if outermost.startswith("elastic_forces"):
        return "elastic forces"
    # compiler-builtins: memory fills and copies, and software `f64` (libm's `sincosf` works
    # in `f64` for angles away from zero).
    return "compiler-builtins (memory fills and copies, software f64)"


def main():
    trace, elf = sys.argv[1], sys.argv[2]
    rows = int(sys.argv[3]) if len(sys.argv) > 3 else 30
    marks = markers(elf)
    blocks, runs = read_trace(trace, marks)
    steps = runs.get(min(a for a, begins in marks.items() if begins), 0)
    per_address, kinds = collections.Counter(), collections.Counter()
    for pc, n in runs.items():
        for address, mnemonic in blocks.get(pc, []):
            per_address[address] += n
            kinds[kind(mnemonic)] += n
    total = sum(per_address.values())
    if not total or not steps:
        sys.exit("no step in the trace")
    addresses = sorted(per_address)
    out = subprocess.run(["llvm-symbolizer", "--obj=" + elf, "--inlining", "--functions=short"],
                         input="\n".join(hex(a) for a in addresses), check=True,
                         capture_output=True, text=True).stdout
    by_function, by_line, by_stage = (collections.Counter() for _ in range(3))
    for address, frames in zip(addresses, out.strip("\n").split("\n\n")):
        lines = frames.split("\n")
        pairs = [(lines[i], lines[i + 1]) for i in range(0, len(lines) - 1, 2)]
        # Innermost frame in the core's own source (glam and core::ops fold into it).
        core = [p for p in pairs if "/core/src/" in p[1] and "/library/core/" not in p[1]]
        function, where = core[0] if core else pairs[0]
        by_function[function] += per_address[address]
        by_line["/".join(where.split("/")[-2:])] += per_address[address]
        by_stage[stage(core, pairs)] += per_address[address]
    slow, mac = kinds["VDIV/VSQRT"], kinds["multiply-accumulate"]
    print(f"{steps} steps, {total / steps:.0f} instructions per step; executed VDIV/VSQRT "
          f"{100 * slow / total:.2f} %, multiply-accumulate {100 * mac / total:.2f} % -> "
          f"{1 + (13 * slow + 2 * mac) / total:.3f} cycles per instruction")
    flops = kinds["other FP arithmetic"] + 2 * mac + slow
    fp_cycles = kinds["other FP arithmetic"] + 3 * mac + 14 * slow
    print(f"floating-point arithmetic per step: {flops / steps:.0f} flops (a multiply-accumulate "
          f"is two), {fp_cycles / steps:.0f} cycles of it in the model")
    print("\n| kind | instructions per step | share |\n|---|---:|---:|")
    for name, n in kinds.most_common():
        print(f"| {name} | {n / steps:.0f} | {100 * n / total:.1f} % |")
    for title, counter in (("stage", by_stage), ("function", by_function),
                           ("source line", by_line)):
        print(f"\n| {title} | instructions per step | share |\n|---|---:|---:|")
        for name, n in counter.most_common(rows):
            print(f"| {name} | {n / steps:.0f} | {100 * n / total:.1f} % |")


if __name__ == "__main__":
    main()
