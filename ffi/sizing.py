#!/usr/bin/env python3
"""The sizing table: the C library at each capacity of SIZES, measured under QEMU
(mps2-an386, Cortex-M4F), written into docs/embedding.md (between its `sizing` markers) and
into the header's summary (ffi/sizing.txt, which ffi/generate-header.sh puts in hairsim.h).

For each capacity it builds libhairsim_ffi.a for thumbv7em-none-eabihf and firmware-c/sizing.c
against it (`make -C firmware-c sizing`), and runs that under QEMU with -icount shift=0 (one
instruction per virtual nanosecond, SysTick at 25 MHz: 40 instructions a tick, a deterministic
count). sizing.c prints, for each solver's preset with a head sphere and one grab, calm and
violent (and, for the rod, violent with hair ten times stiffer: the implicit bending step), in
converge and fixed-cost mode: the instructions of each step and the stack high-water marks of
initialisation, of adding the scene and of its steps. Flash is the library's share of the
image (firmware-c/size.py); world RAM is the world's size on the target.

Microseconds at 168 MHz come from the instruction counts by firmware/latency.py's model: a
Cortex-M4F takes one cycle for most instructions, 14 for VDIV and VSQRT and 3 for the
multiply-accumulates, weighted by their share of the step's code in the disassembly.

It also runs firmware-c/corrupt.c (1,000 stray writes into a world) and writes its outcomes
into docs/embedding.md (between its `corruption` markers).

Usage:
  python3 ffi/sizing.py            measure, then write docs/embedding.md and ffi/sizing.txt
  python3 ffi/sizing.py --check    measure, then fail if a committed figure is off by more
                                   than the tolerance (see check())
  python3 ffi/sizing.py --sizes 4x16,16x32 ...   only these capacities (with --check: their rows)
  python3 ffi/sizing.py --corruption LOG        check a corruption run's output (.ci/ffi's)
"""
import argparse
import concurrent.futures
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "firmware"))
sys.path.insert(0, str(ROOT / "firmware-c"))
import latency  # noqa: E402  (firmware/latency.py: the cycle model)
import size  # noqa: E402  (firmware-c/size.py: flash by origin)

SIZES = [(1, 16), (4, 16), (8, 16), (4, 32), (8, 24), (16, 32)]
TARGET = "thumbv7em-none-eabihf"
DOC = ROOT / "docs/embedding.md"
SUMMARY = ROOT / "ffi/sizing.txt"
BEGIN, END = "<!-- sizing: begin -->", "<!-- sizing: end -->"
CORRUPTION = ("<!-- corruption: begin -->", "<!-- corruption: end -->")
QEMU = ["qemu-system-arm", "-cpu", "cortex-m4", "-machine", "mps2-an386", "-nographic",
        "-icount", "shift=0", "-semihosting-config", "enable=on,target=native", "-kernel"]
MHZ = 168
# A committed figure may differ from a new measurement by this much (relative) before
# `--check` fails: instruction counts and stack move by a few per cent with any change to the
# core's code, and the table is for sizing a part, not for tracking them.
TOLERANCE = 0.05


def run(cmd, env=None, cwd=ROOT):
    """Runs `cmd`; its standard output and error (QEMU prints semihosting's output on the
    latter)."""
    done = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"sizing: {' '.join(map(str, cmd))} failed:\n{done.stdout}{done.stderr}")
    return done.stdout + done.stderr


# The libraries measured at each capacity: both solvers (cargo's default features, in ffi/target
# as the rest of the checks build it), and each solver alone (in target folders of their own,
# so that switching features does not rebuild the core each time).
FEATURE_SETS = {"": None, "rod": "target/solo-rod", "dftl": "target/solo-dftl"}


def build(strands, nodes, features, work):
    """Builds the library and sizing.elf for one capacity and feature set; returns the ELF's
    path."""
    env = dict(os.environ, HAIRSIM_STRANDS=str(strands), HAIRSIM_NODES=str(nodes))
    build_dir = work / f"build-{strands}x{nodes}-{features or 'both'}"
    make = ["make", "-s", "-C", "firmware-c", "sizing", f"BUILD={build_dir}"]
    if features:
        make += [f"FEATURES={features}", f"CARGO_TARGET_DIR={ROOT / 'ffi' / FEATURE_SETS[features]}"]
    run(make, env=env)
    return build_dir / "sizing.elf"


def measure(strands, nodes, elf):
    """Runs sizing.elf under QEMU; returns its figures."""
    out = run(["timeout", "900", *QEMU, str(elf)])
    if "sizing done" not in out:
        sys.exit(f"sizing: {strands}x{nodes} did not finish:\n{out}")
    head = re.search(r"sizing strands (\d+) nodes (\d+) world (\d+) header (\d+) stack init (\d+)",
                     out)
    figures = {"strands": strands, "nodes": nodes, "world": int(head.group(3)),
               "header": int(head.group(4)), "init": int(head.group(5)), "scenes": {}}
    figures["absent"] = sorted({m.group(1) for m in
                                re.finditer(r"sizing scene (\w+) \w+ \S+ not built", out)})
    for m in re.finditer(r"sizing scene (\w+) (\w+) (converge|fixed-cost) ticks (\d+) (\d+) (\d+) "
                         r"stack build (\d+) step (\d+) rolled_back (\d+) grab (\w+) "
                         r"contacts (\d+) flags (\d+)", out):
        solver, motion, mode = m.group(1), m.group(2), m.group(3)
        ticks = [int(m.group(i)) * latency.INSTRUCTIONS_PER_TICK for i in (4, 5, 6)]
        figures["scenes"][(solver, motion, mode)] = {
            "min": ticks[0], "median": ticks[1], "max": ticks[2],
            "build": int(m.group(7)), "step": int(m.group(8)), "rolled_back": int(m.group(9)),
            "grab": m.group(10), "contacts": int(m.group(11)), "flags": int(m.group(12)),
        }
    flash, _ = size.by_origin(str(elf.with_name("sizing.map")))
    figures["flash"] = flash.get("hairsim library", 0)
    total, divsqrt, fma = latency.shares(str(elf))
    figures["cycles_per_instruction"] = 1 + 13 * divsqrt + 2 * fma
    return figures


def measure_all(sizes):
    """Builds every capacity and feature set in turn while QEMU runs the ones built; returns,
    per capacity, the figures of the library with both solvers and, in `alone`, each
    solver's library alone."""
    results = {}
    with tempfile.TemporaryDirectory(prefix="hairsim-sizing-") as tmp, \
            concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        running = {}
        for features in FEATURE_SETS:
            for strands, nodes in sizes:
                elf = build(strands, nodes, features, Path(tmp))
                running[(strands, nodes, features)] = pool.submit(measure, strands, nodes, elf)
        for (strands, nodes, features), future in running.items():
            figures = future.result()
            if features:
                results[(strands, nodes)]["alone"][features] = figures
            else:
                results[(strands, nodes)] = dict(figures, alone={})
        for (strands, nodes), f in results.items():
            for solver, alone in f["alone"].items():
                other = {"rod": "dftl", "dftl": "rod"}[solver]
                if set(alone["absent"]) != {other} or other in {k[0] for k in alone["scenes"]}:
                    sys.exit(f"sizing: the {solver}-only library at {strands}x{nodes} did not "
                             f"refuse {other} alone: {alone['absent']}")
    # The library of the default capacity again, as the rest of the checks expect it.
    run(["cargo", "build", "-q", "--release", "--target", TARGET], cwd=ROOT / "ffi")
    return results


def measure_corruption():
    """Builds firmware-c/corrupt.c against the library with its panic-test feature and runs it
    under QEMU; returns its output."""
    run(["make", "-s", "-C", "firmware-c", "corrupt", "BUILD=build/corrupt",
         "FEATURES=rod,dftl,panic-test"])
    return run(["timeout", "900", *QEMU, str(ROOT / "firmware-c/build/corrupt/corrupt.elf")])


def corruption_counts(text):
    """The corruption run's outcomes, error codes and check refusals, from its output."""
    m = re.search(r"^corruption trials (\d+) stepped (\d+) error (\d+) hook (\d+) "
                  r"hardfault (\d+) hang (\d+)$", text, re.M)
    if not m:
        sys.exit(f"sizing: no corruption counts in:\n{text}")
    counts = dict(zip(["trials", "stepped", "error", "hook", "hardfault", "hang"],
                      map(int, m.groups())))
    checked = re.search(r"^corruption stepped, then refused by hairsim_check: (\d+)$", text, re.M)
    counts["check"] = int(checked.group(1)) if checked else 0
    counts["hooked"] = bool(re.search(r"^corruption panic hook called", text, re.M))
    return counts


def corruption_markdown(c):
    return (f"| outcome | trials |\n|---|---|\n"
            f"| stepped three times (no call refused it) | {c['stepped']} |\n"
            f"| – of which `hairsim_check` then refused as corrupt (state or rest data) | "
            f"{c['check']} |\n"
            f"| refused with an error (`HAIRSIM_ERROR_CORRUPT`) | {c['error']} |\n"
            f"| the panic hook called | {c['hook']} |\n"
            f"| hard fault | {c['hardfault']} |\n"
            f"| hang | {c['hang']} |")


def check_corruption(log):
    """The corruption run's log against the committed table: no hard fault, no hang, the
    hook called by the panic test, and every count within TOLERANCE of the trials."""
    new = corruption_counts(Path(log).read_text())
    failures = []
    if new["hardfault"] or new["hang"] or not new["hooked"]:
        failures.append(f"hard faults {new['hardfault']}, hangs {new['hang']}, "
                        f"panic hook called: {new['hooked']}")
    committed = DOC.read_text().split(CORRUPTION[0], 1)[-1].split(CORRUPTION[1], 1)[0]
    old = numbers(committed)
    fresh = numbers(corruption_markdown(new))
    if len(old) != len(fresh) or any(abs(a - b) > TOLERANCE * new["trials"]
                                      for a, b in zip(old, fresh)):
        failures.append(f"docs/embedding.md's corruption table is stale: committed {old}, "
                        f"measured {fresh}")
    return failures


def k(instructions):
    return f"{instructions / 1000:,.1f}"


def us(figures, instructions):
    return f"{instructions * figures['cycles_per_instruction'] / MHZ:,.0f}"


def rows(results):
    """The table's rows: one per capacity and solver (and the rod's implicit step)."""
    out = []
    for (strands, nodes), f in results.items():
        s = f["scenes"]
        for solver, calm, violent, label in [
            ("rod", "calm", "violent", "rod"),
            ("rod", None, "stiff", "rod, 10× stiffer (implicit bending)"),
            ("dftl", "calm", "violent", "DFTL"),
        ]:
            get = lambda motion, mode, what: s[(solver, motion, mode)][what]
            # The deepest of the row's scenes, in both modes.
            deepest = lambda what: max(get(m, mode, what) for m in (calm, violent) if m
                                       for mode in ("converge", "fixed-cost"))
            alone = f["alone"][solver]["flash"]
            cells = [
                f"{strands} × {nodes}", label, f"{f['flash']:,} / {alone:,}", f"{f['world']:,}",
                f"{f['init']:,} / {deepest('build'):,} / {deepest('step'):,}",
                (f"{k(get(calm, 'converge', 'median'))} / {k(get(calm, 'fixed-cost', 'median'))}"
                 if calm else "–"),
                f"{k(get(violent, 'converge', 'max'))} / {k(get(violent, 'fixed-cost', 'max'))}",
                f"{us(f, get(violent, 'converge', 'max'))} / "
                f"{us(f, get(violent, 'fixed-cost', 'max'))}",
                "held" if all(get(m, mode, "grab") == "held" for m in (calm, violent) if m
                              for mode in ("converge", "fixed-cost")) else "slipped",
            ]
            out.append(cells)
    return out


HEADINGS = ["strands × nodes", "solver", "flash: both solvers / this one alone (bytes)",
            "world RAM (bytes)",
            "stack: init / add scene / step (bytes)", "calm median (k instr): converge / fixed",
            "violent max (k instr): converge / fixed", "µs at 168 MHz, violent max: converge / fixed",
            "grab"]


def markdown(results):
    lines = ["| " + " | ".join(HEADINGS) + " |", "|" + "---|" * len(HEADINGS)]
    lines += ["| " + " | ".join(r) + " |" for r in rows(results)]
    return "\n".join(lines)


def summary(results):
    """The header's summary: a C comment's lines."""
    lines = [" * Sizing on a Cortex-M4F at 168 MHz (docs/embedding.md has the whole table): a full",
             " * world of each solver's preset, a head sphere and one grab, the head shaking at",
             " * 10 rad/s; the slowest step of 200 in fixed-cost mode, and the deepest stack.",
             " *",
             " *   strands x nodes  world RAM  stack  rod us  DFTL us"]
    for (strands, nodes), f in results.items():
        s = f["scenes"]
        stack = max(v["step"] for v in s.values())
        rod = us(f, s[("rod", "violent", "fixed-cost")]["max"])
        dftl = us(f, s[("dftl", "violent", "fixed-cost")]["max"])
        lines.append(f" *   {strands:>3} x {nodes:<3}        {f['world']:>7}  {stack:>5}  "
                     f"{rod:>6}  {dftl:>7}")
    return "\n".join(lines) + "\n"


def numbers(text):
    return [float(x.replace(",", "")) for x in re.findall(r"\d[\d,]*(?:\.\d+)?", text)]


def check(results, doc, sizes):
    """Compares the committed table's rows of `sizes` with the new measurements: every number
    within TOLERANCE (relative), the labels equal."""
    committed = {}
    for line in doc.split(BEGIN, 1)[-1].split(END, 1)[0].splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == len(HEADINGS) and "×" in cells[0] and cells[0] != HEADINGS[0]:
            committed[(cells[0], cells[1])] = cells
    failures = []
    for new in rows(results):
        old = committed.get((new[0], new[1]))
        if old is None:
            failures.append(f"no committed row for {new[0]} {new[1]}")
            continue
        for heading, a, b in zip(HEADINGS, old, new):
            na, nb = numbers(a), numbers(b)
            if not na and a != b:
                failures.append(f"{new[0]} {new[1]} {heading}: committed {a!r}, measured {b!r}")
                continue
            if not close(na, nb):
                failures.append(f"{new[0]} {new[1]} {heading}: committed {a}, measured {b}")
    summary_lines = {tuple(numbers(line)[:2]): line for line in summary(results).splitlines()
                     if re.match(r" \*\s+\d+ x \d+", line)}
    committed_lines = {tuple(numbers(line)[:2]): line
                       for line in SUMMARY.read_text().splitlines()
                       if re.match(r" \*\s+\d+ x \d+", line)}
    for key, line in summary_lines.items():
        old = committed_lines.get(key)
        if old is None or not close(numbers(old), numbers(line)):
            failures.append(f"ffi/sizing.txt: committed {old!r}, measured {line!r}")
    return failures


def close(a, b):
    """Whether two lists of numbers are the same within TOLERANCE."""
    return len(a) == len(b) and all(abs(x - y) <= TOLERANCE * max(abs(x), abs(y), 1.0)
                                    for x, y in zip(a, b))


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--check", action="store_true")
    parser.add_argument("--sizes", help="e.g. 4x16,16x32 (default: all)")
    parser.add_argument("--corruption", metavar="LOG",
                        help="only check the corruption run's LOG against docs/embedding.md")
    args = parser.parse_args()
    if args.corruption:
        failures = check_corruption(args.corruption)
        if failures:
            sys.exit("sizing: " + "\n  ".join(failures))
        print("sizing: the corruption run holds: no hard fault, no hang, the hook called")
        return
    sizes = SIZES
    if args.sizes:
        sizes = [tuple(int(x) for x in s.split("x")) for s in args.sizes.split(",")]
    results = measure_all(sizes)
    doc = DOC.read_text()
    if args.check:
        failures = check(results, doc, sizes)
        print(markdown(results))
        if failures:
            sys.exit("sizing: docs/embedding.md is stale (run python3 ffi/sizing.py):\n  "
                     + "\n  ".join(failures))
        print(f"sizing: docs/embedding.md holds for {', '.join(f'{s}x{n}' for s, n in sizes)}")
        return
    if sizes != SIZES:
        sys.exit("sizing: writing the table needs every capacity (no --sizes)")
    before, rest = doc.split(BEGIN, 1)
    after = rest.split(END, 1)[1]
    doc = f"{before}{BEGIN}\n{markdown(results)}\n{END}{after}"
    counts = corruption_counts(measure_corruption())
    before, rest = doc.split(CORRUPTION[0], 1)
    after = rest.split(CORRUPTION[1], 1)[1]
    DOC.write_text(f"{before}{CORRUPTION[0]}\n{corruption_markdown(counts)}\n{CORRUPTION[1]}{after}")
    SUMMARY.write_text(summary(results))
    run(["bash", "ffi/generate-header.sh"])
    print(markdown(results))


if __name__ == "__main__":
    main()
