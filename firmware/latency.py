#!/usr/bin/env python3
"""Turns the firmware's `latency …` lines (SysTick ticks per step under QEMU -icount shift=0)
into instructions and a Cortex-M4F cycle estimate, and names the largest rod and DFTL scenes
that fit half of a 1 ms tick on a 168 MHz part. For the `haptic-dftl` scene (a device holding a
DFTL strand through a coupling) it fails unless its violent maximum fits half a tick at
168 MHz and is at most 1.2x its calm median (docs/study/floors.md section 5: the model's
margin, and what the scene's executed mix of instructions gives).

Model (stated, not measured on silicon): QEMU's icount makes each instruction 1 ns and SysTick
counts the 25 MHz system clock, so one tick is 40 instructions. On a Cortex-M4F most
instructions take 1 cycle; VDIV.F32 and VSQRT.F32 take 14, and the multiply-accumulates 3: the
fused VFMA family and the chained VMLA/VMLS/VNMLA/VNMLS, which the Cortex-M4 TRM times alike
(the compiler emits the chained ones for `a + b·c`, the same bits as a multiply and an add;
counting them as 1 cycle understated the estimate by ~13 %). Their share of the step's
instructions is taken from the disassembly of the step's code — the functions of the core and
of libm, not the formatting, semihosting and start-up code around them (a static share
standing in for the dynamic one):
cycles = instructions × (1 + 13·share(VDIV, VSQRT) + 2·share(multiply-accumulate)).

The `collision rows` lines give what a collision row costs: the modelled cycles the head's
sphere adds to a 32-node rod scene (its steps with the sphere less its steps without) divided
by the collision rows its projection solved (each row counted at every iterate a solve
followed), against 1.5x a collision row's floor of 61 cycles (docs/study/floors.md section 3).
Two scenes: the latency table's violent one and one strand draped over the head.

Usage: latency.py FIRMWARE_LOG FIRMWARE_ELF
"""
import re
import subprocess
import sys

INSTRUCTIONS_PER_TICK = 40
CLOCK_HZ = 168e6
BUDGET_CYCLES = 0.5e-3 * CLOCK_HZ
# The haptic DFTL scene's violent maximum over its calm median, at most.
HAPTIC_RATIO = 1.2
# A collision row's floor, cycles, and the share of it the goal allows.
COLLISION_ROW_FLOOR = 61
COLLISION_ROW_GOAL = 1.5 * COLLISION_ROW_FLOOR
# The 3-cycle multiply-accumulates of the Cortex-M4F's FPU, fused and chained.
MULTIPLY_ACCUMULATE = ("vfma", "vfms", "vfnma", "vfnms", "vmla", "vmls", "vnmla", "vnmls")


def shares(elf):
    out = subprocess.run(["llvm-objdump", "-d", "--no-show-raw-insn", elf],
                         check=True, capture_output=True, text=True).stdout
    total = divsqrt = fma = 0
    in_step = False
    for line in out.splitlines():
        # A function's label (`$t`/`$d` are mapping symbols inside one): the step's code is
        # the core's functions and libm's.
        label = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
        if label:
            if not label.group(1).startswith("$"):
                in_step = "hairsim_core" in label.group(1) or "libm" in label.group(1)
            continue
        m = re.match(r"\s+[0-9a-f]+:\s+(\S+)", line)
        if not m or not in_step:
            continue
        total += 1
        op = m.group(1)
        if op.startswith(("vdiv", "vsqrt")):
            divsqrt += 1
        elif op.startswith(MULTIPLY_ACCUMULATE):
            fma += 1
    return total, divsqrt / total, fma / total


def main():
    log, elf = sys.argv[1], sys.argv[2]
    total, s_divsqrt, s_fma = shares(elf)
    factor = 1 + 13 * s_divsqrt + 2 * s_fma
    print(f"disassembly of the step's code: {total} instructions, VDIV/VSQRT {100 * s_divsqrt:.2f} %, "
          f"multiply-accumulate {100 * s_fma:.2f} % -> {factor:.3f} cycles per instruction")
    print("| solver | nodes | calm min / median / max (k instr) | violent min / median / max (k instr) "
          "| violent max / calm median | est. µs at 168 MHz (violent max) | fits 0.5 ms |")
    print("|---|---|---|---|---|---|---|")
    best = {}
    haptic = None
    for line in open(log):
        m = re.match(r"latency ([\w-]+) strands (\d+) nodes (\d+) calm (\d+) (\d+) (\d+) "
                     r"violent (\d+) (\d+) (\d+)", line)
        if not m:
            continue
        solver, nodes = m.group(1), int(m.group(3))
        calm = [int(m.group(i)) * INSTRUCTIONS_PER_TICK for i in (4, 5, 6)]
        violent = [int(m.group(i)) * INSTRUCTIONS_PER_TICK for i in (7, 8, 9)]
        cycles = violent[2] * factor
        fits = cycles <= BUDGET_CYCLES
        if fits:
            best[solver] = max(best.get(solver, 0), nodes)
        k = lambda v: "/".join(f"{x / 1000:.1f}" for x in v)
        ratio = violent[2] / calm[1]
        print(f"| {solver} | {nodes} | {k(calm)} | {k(violent)} | "
              f"{ratio:.3f} | {cycles / CLOCK_HZ * 1e6:.0f} | {'yes' if fits else 'no'} |")
        if solver == "haptic-dftl":
            haptic = (fits, ratio, cycles)
    for line in open(log):
        m = re.match(r"collision rows rod (\w+) nodes (\d+) steps (\d+) "
                     r"with (\d+) without (\d+) rows (\d+)", line)
        if not m:
            continue
        scene = m.group(1)
        nodes, steps, with_, without, rows = (int(g) for g in m.groups()[1:])
        added = (with_ - without) * INSTRUCTIONS_PER_TICK * factor
        per_row = added / rows if rows else float("inf")
        verdict = "met" if per_row <= COLLISION_ROW_GOAL else "missed"
        print(f"collision rows, rod {nodes} nodes {scene}, {steps} steps: {rows} rows "
              f"({rows / steps:.1f} a step); the sphere adds {added / steps:.0f} cycles a step, "
              f"{per_row:.0f} a row against {COLLISION_ROW_GOAL:.1f} "
              f"(1.5 x {COLLISION_ROW_FLOOR}): {verdict}")
    for solver in ("rod", "dftl", "dftl_noshape"):
        print(f"largest {solver} scene within half a 1 ms tick at 168 MHz: "
              f"{best.get(solver, 0) or 'none of those measured'} nodes")
    # The haptic scene: its violent maximum within half a tick, and within 20 % of calm.
    if haptic is None:
        sys.exit("no `latency haptic-dftl` line in the log")
    fits, ratio, cycles = haptic
    verdict = (f"haptic-dftl: violent maximum {cycles / CLOCK_HZ * 1e6:.0f} µs at 168 MHz, "
               f"{'within' if fits else 'NOT within'} half a tick; violent / calm {ratio:.3f}")
    if not fits or ratio > HAPTIC_RATIO:
        sys.exit(f"{verdict}: the goal is half a tick "
                 f"({BUDGET_CYCLES / CLOCK_HZ * 1e6:.0f} µs) and the ratio {HAPTIC_RATIO} at most")
    print(verdict)


if __name__ == "__main__":
    main()
