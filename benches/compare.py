#!/usr/bin/env python3
"""Old against new: the criterion benches of two checkouts, alternated in one sitting.

    python3 benches/compare.py --old ../old-checkout                 # every bench, new = here
    python3 benches/compare.py --old ../a --new ../b --bench dftl --filter 'per-strand' --rounds 6
    python3 benches/compare.py --old . --new .                       # the noise floor

Builds each checkout's benches (`cargo bench --no-run` in that checkout, its own target folder;
the executables are taken from cargo's JSON messages, never guessed from file times), then runs
the two binaries of each bench in turns: old then new in even rounds, new then old in odd
rounds, so that a change of the machine's load falls on both alike. Each row prints both
medians over the rounds, the median of the per-round ratios new/old, and every round's ratio:
the spread of those is the noise to read a ratio against (run a checkout against itself to
see it). A ratio above `--limit` (1.03 by default) in the median is marked.

The criterion benches are compared row by row, and so are two custom ones: `dftl_cpu` (each
row's wall-clock time per million vertex-steps; `--filter` is then its label filter, words
separated by spaces, e.g. `--bench dftl_cpu --filter "block-8 block-16"`) and `sph` (each
configuration's milliseconds per step; `--filter "mannequin-b dftl+shape 2t"`). Wall-clock
ratios on a shared machine move by several per cent between rounds; where a ratio matters,
count instructions as well (for example with callgrind) and say which.

Python 3 standard library only. Progress goes to stderr, the table to stdout.
`--self-test` checks the parser of criterion's output (CI runs it).
"""

import argparse
import re
import statistics
import subprocess
import sys
from pathlib import Path

from performance import bench_executables, cpu_info, log

ROOT = Path(__file__).resolve().parent.parent
CRITERION_BENCHES = ["dftl", "effects", "rod_projection", "rod_twist", "step"]
# Custom benches: each line the parser reads is a row, its value a time (lower is faster).
DFTL_CPU_ROW = re.compile(r"^(\d+ x \d+ \S.*?)\s+[\d.]+ M/CPU-s\s+([\d.]+) M/wall-s", re.M)
SPH_ROW = re.compile(r"^(\S+)\s+\d+ vertices (\S+)\s+(\d) thread\(s\):.*?([\d.]+) ms/step", re.M)
CUSTOM_BENCHES = {
    # Seconds per million vertex-steps.
    "dftl_cpu": lambda out: {m.group(1).strip(): 1.0 / float(m.group(2))
                             for m in DFTL_CPU_ROW.finditer(out) if float(m.group(2)) > 0},
    # Seconds per step.
    "sph": lambda out: {f"{m.group(1)} {m.group(2)} {m.group(3)}t": float(m.group(4)) * 1e-3
                        for m in SPH_ROW.finditer(out)},
}
UNIT = {"ps": 1e-12, "ns": 1e-9, "µs": 1e-6, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def build(checkout, benches):
    """The executables of `benches` in `checkout`, built with `cargo bench --no-run`."""
    log(f"building the benches of {checkout}")
    command = ["cargo", "bench", "--workspace", "--no-run", "--message-format=json"]
    for bench in benches:
        command += ["--bench", bench]
    result = subprocess.run(command, cwd=checkout, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"cargo bench --no-run failed in {checkout}:\n{result.stderr[-3000:]}")
    found = bench_executables(result.stdout)
    missing = [b for b in benches if b not in found]
    if missing:
        sys.exit(f"{checkout}: no executable for {', '.join(missing)}")
    return found


def medians(executable, pattern, criterion_args, bench=None):
    """Criterion's median time (s) of every row of `executable` matching `pattern`; for a custom
    bench, its rows' times."""
    if bench in CUSTOM_BENCHES:
        # `cargo bench` runs a bench in its package's folder.
        output = subprocess.run([executable, "--bench", *pattern.split()], capture_output=True,
                                text=True, cwd=Path(__file__).resolve().parent).stdout
        return CUSTOM_BENCHES[bench](output)
    output = subprocess.run(
        [executable, "--bench", "--noplot", pattern, *criterion_args],
        capture_output=True, text=True,
    ).stdout
    return parse_criterion(output)


def parse_criterion(output):
    """{row: median time in s} from criterion's printed output (a short row name has its
    `time:` on the same line, a long one on the next)."""
    rows, name = {}, None
    for line in output.splitlines():
        same_line = re.match(r"^(\S.*?)\s+time:\s+\[\S+ \S+ (\S+) (\S+) \S+ \S+\]", line)
        if same_line:
            rows[same_line.group(1).strip()] = float(same_line.group(2)) * UNIT[same_line.group(3)]
            continue
        below = re.match(r"^\s+time:\s+\[\S+ \S+ (\S+) (\S+) \S+ \S+\]", line)
        if below and name:
            rows[name] = float(below.group(1)) * UNIT[below.group(2)]
        elif line and not line[0].isspace() and not line.startswith(
            ("Benchmarking", "Found", "Gnuplot", "change", "Performance", "No change")
        ):
            name = line.strip()
    return rows


def compare(old, new, bench, args):
    """The alternated rounds of one bench: {row: (old times, new times)}."""
    times = {}
    criterion_args = ["--warm-up-time", str(args.warm_up), "--measurement-time",
                      str(args.measurement)]
    for r in range(args.rounds):
        order = [("old", old), ("new", new)] if r % 2 == 0 else [("new", new), ("old", old)]
        for label, executable in order:
            log(f"{bench}: round {r + 1} of {args.rounds}, {label}")
            for row, t in medians(executable, args.filter, criterion_args, bench).items():
                times.setdefault(row, {"old": [], "new": []})[label].append(t)
    return times


def report(bench, times, limit):
    print(f"\n{bench}\n")
    print("| row | old | new | new/old (median) | each round |")
    print("|---|---:|---:|---:|---|")
    worst = 0.0
    for row, t in times.items():
        pairs = list(zip(t["old"], t["new"]))
        if not pairs:
            continue
        ratios = [n / o for o, n in pairs if o > 0]
        ratio = statistics.median(ratios)
        worst = max(worst, ratio)
        mark = " **slower**" if ratio > limit else ""
        print(
            f"| {row} | {format_time(statistics.median(t['old']))} | "
            f"{format_time(statistics.median(t['new']))} | {ratio:.3f}{mark} | "
            f"{' '.join(f'{x:.3f}' for x in ratios)} |"
        )
    return worst


def format_time(seconds):
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6)):
        if seconds >= scale:
            return f"{seconds / scale:.3f} {unit}"
    return f"{seconds / 1e-9:.1f} ns"


SAMPLE = """Benchmarking dftl 1024 x 8/per-strand/dftl: Analyzing
dftl 1024 x 8/per-strand/dftl
                        time:   [126.01 µs 128.62 µs 131.20 µs]
                        thrpt:  [62.4 Melem/s 63.7 Melem/s 65.0 Melem/s]
Found 1 outliers among 10 measurements (10.00%)
firmware scene step     time:   [41.032 µs 41.104 µs 41.180 µs]
                        change: [-1.2% +0.1% +1.3%] (p = 0.90 > 0.05)
"""


CUSTOM_SAMPLES = {
    "dftl_cpu": ("1024 x 8 block-16 2 threads dftl+shape         92.3 M/CPU-s    180.5 M/wall-s\n"
                 "state hash (64 x 32, 200 steps, shape): per-strand 0x1\n",
                 {"1024 x 8 block-16 2 threads dftl+shape": 1 / 180.5}),
    "sph": ("mannequin-b      8000 vertices dftl+shape       2 thread(s):   66.70 M vertex-steps/s "
            "wall,   40.00 M/CPU-s,    0.120 ms/step, dt 0.0167 s\n",
            {"mannequin-b dftl+shape 2t": 0.120e-3}),
}


def self_test():
    """The parsers against samples of criterion's and the custom benches' output."""
    rows = parse_criterion(SAMPLE)
    expected = {"dftl 1024 x 8/per-strand/dftl": 128.62e-6, "firmware scene step": 41.104e-6}
    assert rows.keys() == expected.keys(), rows
    for row, t in expected.items():
        assert abs(rows[row] - t) < 1e-12, (row, rows[row])
    for bench, (sample, want) in CUSTOM_SAMPLES.items():
        got = CUSTOM_BENCHES[bench](sample)
        assert got.keys() == want.keys(), (bench, got)
        for row, t in want.items():
            assert abs(got[row] - t) < 1e-12, (bench, row, got[row])
    print("compare.py: parser self-test passed")


def main():
    if sys.argv[1:] == ["--self-test"]:
        self_test()
        return
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--old", required=True, type=Path, help="the old checkout")
    parser.add_argument("--new", default=ROOT, type=Path, help="the new checkout (this one)")
    parser.add_argument("--bench", default=",".join(CRITERION_BENCHES),
                        help="benches to compare, comma-separated")
    parser.add_argument("--filter", default="", help="criterion's row filter (a regex)")
    parser.add_argument("--rounds", type=int, default=4, help="alternated rounds (4)")
    parser.add_argument("--warm-up", type=float, default=1.0, help="criterion warm-up, s")
    parser.add_argument("--measurement", type=float, default=3.0,
                        help="criterion measurement time, s")
    parser.add_argument("--limit", type=float, default=1.03,
                        help="a median ratio above this is marked slower (1.03)")
    args = parser.parse_args()
    benches = [b for b in args.bench.split(",") if b]
    known = CRITERION_BENCHES + list(CUSTOM_BENCHES)
    unknown = [b for b in benches if b not in known]
    if unknown:
        sys.exit(f"not a bench compare.py reads: {', '.join(unknown)} "
                 f"(choose from {', '.join(known)})")
    info = cpu_info()
    cpu = f"{info['model']} (family {info['family']}, model {info['model_number']})"
    old = build(args.old.resolve(), benches)
    new = build(args.new.resolve(), benches)
    print(f"# Old ({args.old}) against new ({args.new}), alternated\n")
    print(f"CPU: {cpu}; {args.rounds} rounds, criterion {args.warm_up} s warm-up, "
          f"{args.measurement} s measurement; filter `{args.filter or 'none'}`.")
    worst = 0.0
    for bench in benches:
        worst = max(worst, report(bench, compare(old[bench], new[bench], bench, args),
                                  args.limit))
    print(f"\nWorst median ratio new/old: {worst:.3f} (limit {args.limit}).")


if __name__ == "__main__":
    main()
