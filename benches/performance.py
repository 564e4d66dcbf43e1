#!/usr/bin/env python3
"""Measures hairsim beside the papers' tables and prints docs/performance.md.

    python3 benches/performance.py --record docs/performance.json > docs/performance.md
    python3 benches/performance.py --replay docs/performance.json    # the same page, no bench
    python3 benches/performance.py --quick                            # a short trial run

Prints the machine (CPU model, cores, AVX-512, rustc, date, load average at start and end),
the memory bandwidth measured in the same run, then each paper table with the paper's figures
beside ours, the ratios that do not depend on the machine, and the goals met or missed. Every
figure comes from a bench of `benches/` run by this script: criterion's median
(`new/estimates.json`) or the custom benches' printed lines. The Cortex-M4F table runs the
firmware under QEMU when `qemu-system-arm`, `llvm-objdump` and the thumbv7em-none-eabihf target
are installed, and says so when they are not; so does the C example's table (flash, RAM and
stack of `firmware-c/`, as `bash .ci/ffi` measures them), which also needs arm-none-eabi-gcc
and newlib.

docs/performance.md is this script's output, whole: nothing is written into it by hand. With
`--record FILE` the script also writes what it measured (each command's output and each value
read from the machine, in order) to FILE; `--replay FILE` prints the page again from FILE
without running anything. Kept beside the page as docs/performance.json, the recording lets a
check compare the page with its replay (a hand edit, or a change to this script's text that
was not replayed into the page, shows as a difference) and lets a change to the text be
carried into the page without measuring again (`--replay docs/performance.json >
docs/performance.md`).

Tables measured by other scripts: each `benches/tables/NAME.json` (files taken in name order)
becomes a section of its own, placed after the section its `"after"` names (one of the names
of `--only` below; at the end otherwise). The file is one JSON object:
    {"title": "Strands each solver keeps in real time in the browser",
     "after": "latency",
     "text": "What the table shows, one paragraph.",
     "command": "python3 .ci/viewer-test.py --sweep target/release/hairsim",
     "date": "2026-12-07 10:00 UTC",
     "header": ["solver", "strands × nodes", "real-time ratio"],
     "align": "llr",
     "rows": [["rod", "25 × 30", "1.00"], ["DFTL", "400 × 30", "1.00"]]}
("text", "command", "date" and "align" may be left out; a cell is a string.) The script that
measures the table writes the file; the page is then replayed (or measured again).

A section measured by a bench of its own: write `NAME_section(runner)`, which runs the bench
through `runner.custom(BENCH, [arguments])` (or `runner.criterion`) and returns Markdown, then
add NAME to SECTIONS (its place on the page), to BENCH (the bench it builds) and to `single` in
`measure`.

Progress goes to stderr; the Markdown is printed to stdout at the end. Python 3 standard
library only. Options:
  --quick     short criterion times, one run of each custom bench: for trying it out;
  --native    also build `dftl_cpu` with `-C target-cpu=native` (in target/native) and add its
              columns, AVX-512 where the CPU has it; off by default: it compiles the benches a
              second time;
  --runs N    runs of `dftl_cpu` and `sph` (medians; 3, or 1 with --quick);
  --no-build  run the bench binaries already built, without cargo;
  --only a,b  some sections only: bandwidth, step, twist, projection, dftl, sph, effects,
              latency, firmware, c (the C example's flash, RAM and stack);
  --record F  also write what was measured to F;
  --replay F  print the page from F, measuring nothing.
"""

import argparse
import datetime
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SECTIONS = ["bandwidth", "step", "twist", "projection", "dftl", "sph", "effects", "latency",
            "firmware", "c"]
# Tables measured by other scripts (see the docstring).
TABLES = "benches/tables"
# The SPH bench's second run: the scenes at 1 ms, two threads, with and without hair–hair.
SPH_MILLISECOND = ["dt=0.001", "2t", "dftl+shape", "dftl+shape+hair-hair"]
# The bench binary each section runs.
BENCH = {"bandwidth": "bandwidth", "step": "step", "twist": "rod_twist",
         "projection": "rod_projection", "dftl": "dftl_cpu", "sph": "sph", "effects": "effects",
         "latency": "latency"}
START = time.time()

# Bytes a vertex-step moves (read and written once, no write-allocate reads): DFTL's state
# (position, velocity, previous position, correction, rest length…) and shape's rest data on
# top (rest position, local rest vector, root distance: 28 bytes).
BYTES_DFTL = 60
BYTES_SHAPE = 88


def log(message):
    print(f"[{time.time() - START:6.0f} s] {message}", file=sys.stderr, flush=True)


class Tape:
    """What a run measured, in the order it measured it: every command's output, every value
    read from the machine (CPU, load, clock). `--record FILE` writes it; `--replay FILE` prints
    the document again from it without running anything, as CI does to check that
    docs/performance.md is this script's output, whole."""

    def __init__(self):
        self.mode, self.entries, self.position = None, [], 0

    def take(self, kind, key, compute):
        """`compute()`, recorded under (`kind`, `key`); when replaying, what was recorded."""
        if self.mode == "replay":
            if self.position >= len(self.entries):
                sys.exit(f"the recording ends before {kind} {key}: record it again")
            entry = self.entries[self.position]
            self.position += 1
            if entry[:2] != [kind, key]:
                sys.exit(f"entry {self.position - 1} of the recording is {entry[:2]}, not "
                         f"{[kind, key]}: the script measures something else now; record again")
            return entry[2]
        value = compute()
        if self.mode == "record":
            self.entries.append([kind, key, value])
        return value


TAPE = Tape()


def run(cmd, env=None, cwd=ROOT, timeout=None, quiet=False):
    """Runs `cmd`; returns (return code, stdout, stderr). Recorded by the tape under the
    program's name (paths differ from one checkout to another)."""
    program = Path(cmd[1] if Path(cmd[0]).name.startswith("python") else cmd[0]).name
    return TAPE.take("run", program, lambda: run_now(cmd, env, cwd, timeout, quiet))


def which(tool):
    """`shutil.which(tool)`, recorded."""
    return TAPE.take("which", tool, lambda: shutil.which(tool))


def read_repository_file(path):
    """The text of `path` in the repository ("" when missing), recorded."""
    return TAPE.take("read", path, lambda: (ROOT / path).read_text()
                     if (ROOT / path).exists() else "")


def run_now(cmd, env=None, cwd=ROOT, timeout=None, quiet=False):
    """Runs `cmd`; returns (return code, stdout, stderr)."""
    if not quiet:
        log("$ " + " ".join(cmd))
    try:
        p = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True,
                           timeout=timeout)
    except subprocess.TimeoutExpired as e:
        out = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
        return 124, out, f"timed out after {timeout} s"
    except OSError as e:
        return 127, "", str(e)
    return p.returncode, p.stdout, p.stderr


def tail(text, lines=6):
    return " / ".join(line.strip() for line in text.strip().splitlines()[-lines:])


# ---------------------------------------------------------------------------------------------
# Formatting


def num(x, digits=3):
    """`x` to `digits` significant figures (all the digits before the point), thousands
    separated."""
    if x is None or x != x:  # missing or NaN
        return "–"
    if x == 0:
        return "0"
    decimals = max(0, digits - 1 - math.floor(math.log10(abs(x))))
    return f"{x:,.{decimals}f}"


def ratio(a, b, digits=2):
    if a is None or b is None or b == 0:
        return "–"
    return f"{a / b:.{digits}f}"


def verdict(ok):
    return "**met**" if ok else "**missed**"


def median(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def starts_block(word):
    """Whether a line starting with `word` would start a list, quote, heading or table."""
    return word in ("+", "-", "*", ">") or re.match(r"^(#|\||\d+[.)]$)", word) is not None


def wrap_paragraph(words, width):
    """Greedy wrapping that never starts a line with a word that `starts_block`."""
    lines = []
    for word in words:
        if lines and len(lines[-1]) + 1 + len(word) <= width:
            lines[-1] = lines[-1] + " " + word
            continue
        if lines and starts_block(word):
            # Take the previous line's last word along.
            head, _, last = lines[-1].rpartition(" ")
            if head:
                lines[-1] = head
                lines.append(last + " " + word)
                continue
        lines.append(word)
    return lines


def wrap(markdown, width=96):
    """Wraps the paragraphs of `markdown` (not its headings, tables, lists or code)."""
    out, paragraph, code = [], [], False

    def flush():
        if paragraph:
            out.extend(wrap_paragraph(" ".join(paragraph).split(), width))
            paragraph.clear()

    for line in markdown.splitlines():
        if line.startswith("```"):
            flush()
            code = not code
            out.append(line)
        elif code or not line.strip() or line.startswith(("|", "#", "- ")):
            flush()
            out.append(line)
        else:
            paragraph.append(line)
    flush()
    return "\n".join(out)


def table(header, rows, align=None):
    """A Markdown table; `align` is a string of l/r per column."""
    align = align or "l" * len(header)
    out = ["| " + " | ".join(header) + " |",
           "|" + "|".join("---:" if a == "r" else "---" for a in align) + "|"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


# ---------------------------------------------------------------------------------------------
# The machine


def bench_executables(cargo_json):
    """{bench name: executable} from the JSON messages of `cargo bench --no-run
    --message-format=json…` (where cargo put each bench, never guessed from file times)."""
    found = {}
    for line in cargo_json.splitlines():
        try:
            message = json.loads(line)
        except ValueError:
            continue
        if message.get("reason") == "compiler-artifact" and message.get("executable") \
                and "bench" in message["target"]["kind"]:
            found[message["target"]["name"]] = Path(message["executable"])
    return found


def cpu_info():
    """The machine's CPU, cores, caches and memory (recorded)."""
    return TAPE.take("value", "cpu", read_cpu_info)


def read_cpu_info():
    text = Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").exists() else ""
    fields = {}
    for line in text.split("\n\n")[0].splitlines():
        if ":" in line:
            key, value = line.split(":", 1)
            fields.setdefault(key.strip(), value.strip())
    flags = set(fields.get("flags", "").split())
    cores = set()
    for block in text.split("\n\n"):
        d = dict((k.strip(), v.strip()) for k, v in
                 (line.split(":", 1) for line in block.splitlines() if ":" in line))
        if "core id" in d:
            cores.add((d.get("physical id"), d["core id"]))
    caches = []
    for index in sorted(Path("/sys/devices/system/cpu/cpu0/cache").glob("index*")):
        try:
            level = (index / "level").read_text().strip()
            kind = (index / "type").read_text().strip()
            size = (index / "size").read_text().strip()
        except OSError:
            continue
        if kind != "Instruction":
            caches.append(f"L{level}{'d' if kind == 'Data' else ''} {size}")
    memory = None
    if Path("/proc/meminfo").exists():
        m = re.search(r"MemTotal:\s+(\d+) kB", Path("/proc/meminfo").read_text())
        memory = int(m.group(1)) / 2 ** 20 if m else None
    return {
        "model": fields.get("model name", "unknown"),
        "family": fields.get("cpu family"),
        "model_number": fields.get("model"),
        "logical": os.cpu_count(),
        "physical": len(cores) or None,
        "avx512": sorted(f for f in flags if f.startswith("avx512")),
        "avx2": "avx2" in flags,
        "fma": "fma" in flags,
        "caches": caches,
        "memory_gib": memory,
    }


def rustc_version():
    rc, out, _ = run(["rustc", "-V"], quiet=True)
    if rc != 0:
        return "unknown"
    # Drop the compiler's commit hash: "rustc 1.95.0 (59807616e 2026-04-14)" -> "(2026-04-14)".
    return re.sub(r"\(\s*[0-9a-f]{7,40}\s+", "(", out.strip())


def load_average(when):
    """The load average of the last minute, recorded as `when`'s."""
    return TAPE.take("value", f"load {when}", load_average_now)


def load_average_now():
    try:
        return os.getloadavg()[0]
    except OSError:
        return None


# ---------------------------------------------------------------------------------------------
# Running the benches


class Runner:
    def __init__(self, args):
        self.args = args
        self.failures = []
        self.criterion_home = Path(tempfile.mkdtemp(prefix="hairsim-criterion-"))
        if args.quick:
            self.criterion_args = ["--warm-up-time", "0.5", "--measurement-time", "1"]
        else:
            self.criterion_args = ["--warm-up-time", "1", "--measurement-time", "4"]
        self.executables = {}
        self.build_seconds = 0.0

    def fail(self, section, what):
        self.failures.append(f"{section}: {what}")
        log(f"FAILED {section}: {what}")

    def build(self, benches, native=False):
        """Builds the bench binaries (so that compiling is not timed with them) and notes where
        cargo put them; with --no-build, takes the newest ones already built."""
        found, failures, seconds = TAPE.take(
            "build", [benches, native], lambda: self.build_now(benches, native))
        self.build_seconds += seconds
        for section, what in failures:
            self.fail(section, what)
        for name, executable in found.items():
            self.executables[(name, native)] = Path(executable)
        return not failures

    def build_now(self, benches, native):
        """[{bench: executable}, failures, seconds building] of [`Runner.build`]."""
        started = time.time()
        executables, failures = self.build_benches(benches, native)
        return [{name: str(path) for name, path in executables.items()}, failures,
                time.time() - started]

    def build_benches(self, benches, native):
        """({bench: executable}, [(section, failure)]) of [`Runner.build`]."""
        target = ROOT / "target" / ("native" if native else "") / "release" / "deps"
        if self.args.no_build:
            executables, failures = {}, []
            for b in benches:
                found = [p for p in target.glob(f"{b}-*") if p.suffix == "" and os.access(p, os.X_OK)]
                if found:
                    executables[b] = max(found, key=lambda p: p.stat().st_mtime)
                else:
                    failures.append(("build", f"no built {b} bench in {target} (--no-build)"))
            return executables, failures
        cmd = ["cargo", "bench", "-p", "hairsim-benches"]
        for b in benches:
            cmd += ["--bench", b]
        cmd += ["--no-run", "--message-format=json-render-diagnostics"]
        rc, out, err = run_now(cmd, env=self.env(native))
        if rc != 0:
            return {}, [("build" + (" (native)" if native else ""), tail(err))]
        return bench_executables(out), []

    def env(self, native=False, criterion_dir=None):
        env = dict(os.environ)
        if native:
            env["RUSTFLAGS"] = (env.get("RUSTFLAGS", "") + " -C target-cpu=native").strip()
            env["CARGO_TARGET_DIR"] = str(ROOT / "target" / "native")
        if criterion_dir is not None:
            env["CRITERION_HOME"] = str(criterion_dir)
        return env

    def bench_command(self, bench, native=False):
        """The bench binary as `cargo bench` runs it (`--bench` tells it that it is measuring)."""
        executable = self.executables.get((bench, native))
        if executable is None:
            return None
        return [str(executable), "--bench"]

    def custom(self, bench, extra=(), native=False):
        """Runs a `harness = false` bench; its stdout + stderr, or None."""
        cmd = self.bench_command(bench, native)
        if cmd is None:
            self.fail(bench, "not built")
            return None
        # `cargo bench` runs a bench in its package's folder.
        rc, out, err = run(cmd + list(extra), env=self.env(native), cwd=ROOT / "benches")
        if rc != 0:
            self.fail(bench, tail(err))
            return None
        return out + "\n" + err

    def criterion(self, bench, filter_regex):
        """Runs criterion cases whose id matches `filter_regex`: ({full id: median ns}, text)."""
        results, text, failure = TAPE.take("criterion", [bench, filter_regex],
                                           lambda: self.criterion_now(bench, filter_regex))
        if failure:
            self.fail(bench, failure)
        return results, text

    def criterion_now(self, bench, filter_regex):
        """[{full id: median ns}, text, failure or None] of [`Runner.criterion`]."""
        home = self.criterion_home / bench
        shutil.rmtree(home, ignore_errors=True)
        cmd = self.bench_command(bench)
        if cmd is None:
            return {}, "", "not built"
        cmd += [filter_regex, "--noplot", *self.criterion_args]
        rc, out, err = run_now(cmd, env=self.env(criterion_dir=home), cwd=ROOT / "benches")
        if rc != 0:
            return {}, out + err, tail(err)
        results = {}
        for meta_path in home.rglob("new/benchmark.json"):
            meta = json.loads(meta_path.read_text())
            estimates = json.loads((meta_path.parent / "estimates.json").read_text())
            results[meta["full_id"]] = estimates["median"]["point_estimate"]
        return results, out + "\n" + err, None


# ---------------------------------------------------------------------------------------------
# Sections. Each returns Markdown.


def command_line(bench, extra=""):
    return f"`cargo bench -p hairsim-benches --bench {bench}{(' -- ' + extra) if extra else ''}`"


BANDWIDTH_LINE = re.compile(
    r"(\d+) MiB arrays, (\d+) thread\(s\): copy ([\d.]+) GB/s, triad ([\d.]+) GB/s")


def measure_bandwidth(runner):
    """{threads: (copy, triad)} in GB/s, or {}."""
    out = runner.custom("bandwidth")
    found = {}
    for m in BANDWIDTH_LINE.finditer(out or ""):
        found[int(m.group(2))] = (float(m.group(3)), float(m.group(4)))
    if out is not None and not found:
        runner.fail("bandwidth", "no result lines in its output")
    return found


def bandwidth_section(runs):
    """`runs`: the measurements at the start and at the end of this run."""
    rows = []
    for threads in (1, 2):
        values = [r.get(threads) for r in runs]
        if not any(values):
            continue
        copy = [v[0] for v in values if v]
        triad = [v[1] for v in values if v]
        rows.append([threads, " / ".join(num(c) for c in copy), " / ".join(num(t) for t in triad),
                     num(max(copy)), num(max(triad))])
    text = ["## Memory bandwidth", "",
            "STREAM-like copy (`a = b`, 8 bytes an element) and triad (`a = b + s·c`, 12 bytes), "
            "64 MiB arrays, the best of 5 passes, measured at the start and at the end of this "
            "run; the best of the two is what the DFTL figures are set against. "
            + command_line("bandwidth") + ".", ""]
    if rows:
        text.append(table(["threads", "copy GB/s (start / end)", "triad GB/s (start / end)",
                           "copy, best", "triad, best"], rows, "rllrr"))
    else:
        text.append("Not measured: the bench failed (see the command's standard error).")
    return "\n".join(text)


def best_bandwidth(runs):
    out = {}
    for threads in (1, 2):
        values = [r[threads] for r in runs if threads in r]
        if values:
            out[threads] = (max(v[0] for v in values), max(v[1] for v in values))
    return out


# Kmoch 2009 Table 1: scene, leaders × nodes, the paper's ms per step (Core 2 Quad 2.66 GHz).
KMOCH_T1 = [
    ("stand-1", "Stand #1 long", "3 × 30", 1.10, 0.015),
    ("stand-2", "Stand #2 short", "3 × 5", 0.13, None),
    ("stand-3", "Stand #3 short", "18 × 5", 0.52, None),
    ("head-1", "Head #1 straight", "50 × 30", 24.49, 0.25),
    ("head-2", "Head #2 straight", "25 × 30", 12.93, None),
    ("head-3", "Head #3 wavy", "25 × 30", 13.27, None),
]
T1_GROUP = "Kmoch Table 1 (ms per step, leaders, one thread)"
STIFF_GROUP = "Head #1, stiffer hair (ms per step, one thread)"
LANES_GROUP = "Rod blocks against one strand at a time (ms per step)"


def step_section(runner):
    results, text = runner.criterion(
        "step", "^(Kmoch Table 1|Head #1, stiffer|firmware scene|Rod blocks)")
    iterations = {}
    for m in re.finditer(r"^(\S+): (\d+) strands, projection iterations per strand-step mean "
                         r"([\d.]+) max (\d+)", text, re.M):
        iterations[m.group(1)] = (m.group(3), m.group(4))
    ms = lambda key: results[key] / 1e6 if key in results else None
    rows = []
    for name, label, size, paper, goal in KMOCH_T1:
        ours = ms(f"{T1_GROUP}/{name}")
        it = iterations.get(name)
        goal_text = ""
        if goal is not None and ours is not None:
            goal_text = f"≤ {goal}: {verdict(ours <= goal)}"
        rows.append([f"{label} (`{name}`)", size, f"{paper:.2f}", num(ours), ratio(paper, ours, 0)
                     if ours else "–", f"{it[0]} / {it[1]}" if it else "–", goal_text])
    head1 = ms(f"{T1_GROUP}/head-1")
    stiff = [(f, ms(f"{STIFF_GROUP}/x{f}")) for f in ("10", "100")]
    firmware_step = results.get("firmware scene step")
    out = ["## Kmoch 2009 Table 1: the rod step", "",
           "Milliseconds per full rod step of the leaders, one thread, the head shaking at "
           "10 rad/s (the stands get the same shake, so that they never settle); criterion's "
           "median over the steps after the first 150, the state carried on from step to step. "
           "The iterations are the projection's per strand-step over steps 150–350 (converge "
           "mode: the cost follows them; they do not depend on the machine). "
           + command_line("step") + ".", "",
           table(["scene", "leaders × nodes", "paper (ms)", "hairsim (ms)",
                  "paper ÷ hairsim", "iterations mean / max", "goal (ms)"], rows, "llrrrll")]
    lines = []
    if head1 and all(s for _, s in stiff):
        lines.append("Head #1 with stiffer hair (one linearly implicit bending step instead of "
                     "explicit substeps): "
                     + ", ".join(f"×{f} {num(s)} ms ({ratio(s, head1)} × human hair)"
                                 for f, s in stiff) + ".")
    if firmware_step:
        lines.append(f"The `firmware` scene's step on this host: {num(firmware_step / 1e3)} µs.")
    if lines:
        out += ["", " ".join(lines)]
    lane_rows = []
    for name, label, goal in (("head-1", "Head #1", 3.0), ("stand-1", "Stand #1", None)):
        alone, block = ms(f"{LANES_GROUP}/{name} per strand"), ms(f"{LANES_GROUP}/{name} blocks")
        if alone and block:
            goal_text = f"≥ {goal:g}×: {verdict(alone / block >= goal)}" if goal else ""
            lane_rows.append([label, num(alone), num(block), ratio(alone, block), goal_text])
    if lane_rows:
        out += ["", "The rod's blocks (issue 22): the strands of a block 4 at a time in lanes "
                "(the frame passes, the explicit substeps or the linearly implicit step, both "
                "twists and the fast manifold projection; each lane's contacts, root coupling and "
                "the guard strand by strand) against one strand at a time, the firmware's path, "
                "in the same run (the same bits). Issue 22 also asks ≤ 0.2 ms a step in blocks on "
                "a Zen 5 (≤ 0.28 ms on a Zen 3): the CPU is named at the top.", "",
                table(["scene", "one strand at a time (ms)", "blocks of 4 (ms)",
                       "per strand ÷ blocks", "goal"], lane_rows, "lrrrl")]
    return "\n".join(out)


KMOCH_T2 = {"1x30": (140, 60), "3x30": (410, 180)}


def twist_section(runner):
    results, _ = runner.criterion("rod_twist", "^(Kmoch Table 2|rod step 50x30)")
    rows = []
    for size, (paper_newton, paper_opt) in KMOCH_T2.items():
        newton = results.get(f"Kmoch Table 2: twist/newton 1e-6 rad, <= 10 it/{size}")
        opt = results.get(f"Kmoch Table 2: twist/hair-optimised/{size}")
        r = opt / newton if opt and newton else None
        rows.append([size.replace("x", " × "), str(paper_newton), str(paper_opt),
                     ratio(paper_opt, paper_newton),
                     num(newton / 1e3) if newton else "–", num(opt / 1e3) if opt else "–",
                     f"{r:.2f}" if r else "–",
                     f"≤ 0.3: {verdict(r <= 0.3)}" if r else ""])
    out = ["## Kmoch 2009 Table 2: the twist", "",
           "Microseconds for the quasistatic twist alone on a bent, swung strand: Newton's "
           "method (to 1e-6 rad, at most 10 iterations) against the hair-optimised twist. "
           + command_line("rod_twist") + ".", "",
           table(["leaders × nodes", "paper Newton (µs)", "paper hair-optimised (µs)",
                  "paper ratio", "hairsim Newton (µs)", "hairsim hair-optimised (µs)",
                  "hairsim ratio", "goal"], rows, "lrrrrrrl")]
    full_opt = results.get("rod step 50x30/hair-optimised")
    full_newton = results.get("rod step 50x30/newton")
    if full_opt and full_newton:
        out += ["", f"The whole step of 50 × 30 nodes with bending and twist: "
                f"{num(full_opt / 1e6)} ms with the hair-optimised twist, "
                f"{num(full_newton / 1e6)} ms with Newton's "
                f"(ratio {ratio(full_opt, full_newton)})."]
    return "\n".join(out)


def projection_section(runner):
    results, text = runner.criterion("rod_projection", "^rod_projection/")
    counts = {}
    for m in re.finditer(r"^(\S+): ([\d.]+) iterations per strand-step, ([\d.]+) contacts per "
                         r"step, (\d+) cap hits", text, re.M):
        counts[m.group(1)] = (m.group(2), m.group(3))
    rows = []
    for size in ("50x30", "1x30"):
        for mode in ("converge", "fixed-cost"):
            key = f"{size}/{mode}"
            without = results.get(f"rod_projection/{key}/no-collisions")
            with_ = results.get(f"rod_projection/{key}/collisions")
            r = with_ / without if with_ and without else None
            paper = "13.54 / 14.35 (1.06)" if key == "50x30/converge" else ""
            goal = f"≤ 1.05: {verdict(r <= 1.05)}" if r and key == "50x30/converge" else ""
            c0, c1 = counts.get(f"{key}/no-collisions"), counts.get(f"{key}/collisions")
            rows.append([
                f"{size.replace('x', ' × ')}, {mode}" + (" (cap 8)" if mode == "fixed-cost"
                                                        else ""),
                paper, num(without / 1e3) if without else "–",
                num(with_ / 1e3) if with_ else "–", f"{r:.2f}" if r else "–",
                f"{c0[0]} / {c1[0]}" if c0 and c1 else "–", c1[1] if c1 else "–", goal])
    out = ["## Kmoch 2009 Table 3: the projection with and without collisions", "",
           "Microseconds for the fast manifold projection (inextensibility) of strands draped on "
           "a head shaking at 10 rad/s, without and with hair–head collisions: 16 consecutive "
           "steps captured before their projection after 300 steps, projected in turn. "
           + command_line("rod_projection") + ". Why ≤ 5 % cannot be met with a third of the "
           "nodes in contact: [floors](study/floors.md), section 3.", "",
           table(["case", "paper without / with (ms)", "hairsim without (µs)",
                  "hairsim with (µs)", "with ÷ without", "iterations per strand-step "
                  "without / with", "contacts per step", "goal"], rows, "llrrrlrl")]
    return "\n".join(out)


DFTL_LINE = re.compile(r"^(\d+) x (\d+) (per-strand|block-8|block-16 2 threads|block-16) "
                       r"(dftl\+shape|dftl)\s+([\d.]+) M/CPU-s\s+([\d.]+) M/wall-s", re.M)
DFTL_SIZES = [(1024, 8), (1024, 32), (4096, 32), (4096, 64), (16384, 64)]


def parse_dftl(text):
    found = {}
    for m in DFTL_LINE.finditer(text or ""):
        key = (int(m.group(1)), int(m.group(2)), m.group(3), m.group(4))
        found[key] = float(m.group(6))
    return found


def dftl_section(runner, bandwidth, native_runs, default_runs):
    """SB15 Table 2 sizes: medians of the runs' wall-clock M vertex-steps per second."""
    def med(runs, key):
        return median([r.get(key) for r in runs])

    d = lambda s, n, path, shape: med(default_runs, (s, n, path, "dftl+shape" if shape else "dftl"))
    nat = lambda s, n, path, shape: med(native_runs, (s, n, path,
                                                      "dftl+shape" if shape else "dftl"))
    pair = lambda a, b: f"{num(a)} / {num(b)}"
    have_native = bool(native_runs) and any(native_runs)
    header = ["strands × vertices", "per-strand", "block-8", "block-16", "block-16, 2 threads"]
    if have_native:
        header += ["native block-16", "native block-16, 2 threads"]
    rows, ratio_rows = [], []
    for s, n in DFTL_SIZES:
        label = f"{s:,} × {n}" + (f" ({s * n:,})" if s * n >= 1 << 20 else "")
        row = [label]
        for path in ("per-strand", "block-8", "block-16", "block-16 2 threads"):
            row.append(pair(d(s, n, path, False), d(s, n, path, True)))
        if have_native:
            for path in ("block-16", "block-16 2 threads"):
                row.append(pair(nat(s, n, path, False), nat(s, n, path, True)))
        rows.append(row)
        per = (d(s, n, "per-strand", False), d(s, n, "per-strand", True))
        b16 = (d(s, n, "block-16", False), d(s, n, "block-16", True))
        b8 = (d(s, n, "block-8", False), d(s, n, "block-8", True))
        two = (d(s, n, "block-16 2 threads", False), d(s, n, "block-16 2 threads", True))
        rr = [label,
              f"{ratio(b16[0], per[0], 1)} / {ratio(b16[1], per[1], 1)}",
              f"{ratio(b16[0], b8[0])} / {ratio(b16[1], b8[1])}",
              f"{ratio(two[0], b16[0])} / {ratio(two[1], b16[1])}",
              f"{ratio(b16[0], b16[1])} / {ratio(two[0], two[1])}"]
        if have_native:
            nb16 = (nat(s, n, "block-16", False), nat(s, n, "block-16", True))
            rr.append(f"{ratio(nb16[0], b16[0])} / {ratio(nb16[1], b16[1])}")
        ratio_rows.append(rr)
    ratio_header = ["strands × vertices", "block-16 ÷ per-strand", "block-16 ÷ block-8",
                    "2 threads ÷ 1 thread", "DFTL + shape time ÷ DFTL time, 1 / 2 threads"]
    if have_native:
        ratio_header.append("native ÷ default, block-16")
    runs = len(default_runs)
    out = ["## Sánchez-Banderas 2015 Table 2 sizes: DFTL on the CPU", "",
           "Million vertex-steps per second (wall clock), DFTL (gravity + inextensibility) / "
           "DFTL + shape, each cell the median of "
           f"{runs} run{'s' if runs != 1 else ''} of the bench"
           + (" alternating with the native build" if have_native else "")
           + "; the per-strand path against structure-of-arrays blocks of 8 and 16 strands "
           "(the same bits, checked by the bench's state hash), the 16-lane blocks also split "
           "over a pool of two threads. The default build targets baseline x86-64 (SSE2); "
           + ("the native build is the same bench with `RUSTFLAGS=\"-C target-cpu=native\"` "
              "(its own target folder, `target/native`), "
              + ("AVX-512 on this machine. " if runner.cpu["avx512"] else
                 "which on this machine has AVX2 and FMA but no AVX-512. ")
              if have_native else
              "`--native` adds columns for the same bench built with `-C target-cpu=native` "
              "(AVX-512 where the CPU has it). ")
           + command_line("dftl_cpu") + " (`-- \"16384 x 64\"` picks one size; `--bench dftl` "
           "times the same cases with criterion). The paper's GTX 650 did 77.6 M vertex-steps per "
           "second for DFTL alone; the goals are for DFTL + shape.", "",
           table(header, rows, "l" + "r" * (len(header) - 1)), "",
           "Ratios, each DFTL / DFTL + shape except the last (one / two threads):", "",
           table(ratio_header, ratio_rows, "l" + "r" * (len(ratio_header) - 1))]

    # Goals.
    cache = [d(s, n, "block-16", True) for s, n in DFTL_SIZES[:4]]
    goals = []
    if all(cache):
        goals.append(f"DFTL + shape ≥ 100 M on one thread at the cache-resident sizes (the "
                     f"first four): {num(min(cache))}–{num(max(cache))} M, "
                     f"{verdict(min(cache) >= 100)}")
    big2 = d(16384, 64, "block-16 2 threads", True)
    if big2:
        goals.append(f"DFTL + shape ≥ 150 M on two threads at 1,048,576 vertices: {num(big2)} M"
                     f", {verdict(big2 >= 150)}"
                     + (f" ({num(nat(16384, 64, 'block-16 2 threads', True))} M native)"
                        if have_native else ""))
    shape_ratios = [d(s, n, "block-16", False) / d(s, n, "block-16", True)
                    for s, n in DFTL_SIZES
                    if d(s, n, "block-16", False) and d(s, n, "block-16", True)]
    if shape_ratios:
        goals.append(f"shape ≤ 10 % over DFTL (time ratio ≤ 1.10): "
                     f"{min(shape_ratios):.2f}–{max(shape_ratios):.2f} on one thread, "
                     f"{verdict(max(shape_ratios) <= 1.10)}; why it cannot be: "
                     f"[floors](study/floors.md)")
    if goals:
        out += ["", "Goals: " + "; ".join(goals) + "."]

    # The 1 M row against the memory bandwidth.
    mem_rows = []
    for build, get in (("default", d), ("native", nat)) if have_native else (("default", d),):
        for threads, path in ((1, "block-16"), (2, "block-16 2 threads")):
            bw = bandwidth.get(threads)
            for shape, bytes_ in ((False, BYTES_DFTL), (True, BYTES_SHAPE)):
                m = get(16384, 64, path, shape)
                if not m or not bw:
                    continue
                moved = m * 1e6 * bytes_ / 1e9
                mem_rows.append([build, threads, "DFTL + shape" if shape else "DFTL", num(m),
                                 bytes_, num(moved), f"{moved / bw[1]:.2f}",
                                 f"{moved / bw[0]:.2f}"])
    if mem_rows:
        out += ["", "At 1,048,576 vertices the state does not fit in the caches. Vertex-steps "
                "per second × bytes per vertex-step (each read and written once: DFTL "
                f"{BYTES_DFTL} B, DFTL + shape {BYTES_SHAPE} B, more counting the write-allocate "
                "reads) against the bandwidth measured in this run on as many threads — 1.0 "
                "would be the step as fast as memory allows:", "",
                table(["build", "threads", "solver", "M vertex-steps/s", "bytes per vertex-step",
                       "GB/s moved", "÷ triad bandwidth", "÷ copy bandwidth"], mem_rows,
                      "lrlrrrrr")]
    return "\n".join(out)


SPH_LINE = re.compile(r"^(\S+)\s+(\d+) vertices (\S+)\s+(\d+) thread\(s\):\s+([\d.]+) M "
                      r"vertex-steps/s wall,\s+([\d.]+) M/CPU-s,\s+([\d.]+) ms/step"
                      r"(?:, dt ([\d.]+) s)?(.*)$", re.M)
SPH_SPLIT = re.compile(r"hash ([\d.]+), sort ([\d.]+), neighbours ([\d.]+), forces ([\d.]+); "
                       r"([\d.]+) neighbours/node \(cap (\d+), ([\d.]+) dropped/node, most "
                       r"found (\d+)\)(?:; ([\d.]+) rebuilds per 100 steps, ([\d.]+) active/node, "
                       r"([\d.]+) candidates/node)?")
# Scene, label, the paper's FPS with DFTL + shape and with hair–hair too (Table 1, GTX 650),
# and the goal for hair–hair ÷ DFTL + shape in step time.
SPH_SCENES = [("mannequin-a", "Mannequin A", (124.0, 21.5), 2.0),
              ("mannequin-b", "Mannequin B", (172.6, 147.4), 1.2),
              ("horse-louis", "Horse Louis by count", None, 1.2),
              ("bunny", "Bunny by count", None, 1.2),
              ("hectroll", "Hectroll by count", None, 1.2)]
# The paper's hair–hair ÷ DFTL + shape in frame time where Table 1 gives only the ratio.
SPH_PAPER_RATIO = {"horse-louis": 1.30, "bunny": 1.30, "hectroll": 1.13}
SPH_COLUMNS = ["dftl", "dftl+shape", "dftl+shape+hair-hair"]
HAIR_HAIR = "dftl+shape+hair-hair"


def parse_sph(runs):
    """{(scene, column, threads): [M vertex-steps/s]}, {same: [SPH split]}, {scene: vertices},
    {scene: dt} from the runs' outputs."""
    values, splits, vertices, dts = {}, {}, {}, {}
    for text in runs:
        for m in SPH_LINE.finditer(text or ""):
            key = (m.group(1), m.group(3), int(m.group(4)))
            vertices[m.group(1)] = int(m.group(2))
            if m.group(8):
                dts[m.group(1)] = float(m.group(8))
            values.setdefault(key, []).append(float(m.group(5)))
            split = SPH_SPLIT.search(m.group(9))
            if split:
                splits.setdefault(key, []).append(split.groups())
    return values, splits, vertices, dts


def sph_paper_ratio(scene, paper):
    if paper:
        return paper[0] / paper[1]
    return SPH_PAPER_RATIO.get(scene)


def sph_stage_rows(values, splits, vertices):
    """The SPH stage's split on two threads, the median run (by neighbour time), per scene."""
    rows = []
    for scene, label, _, _ in SPH_SCENES:
        split = splits.get((scene, HAIR_HAIR, 2))
        if scene not in vertices or not split:
            continue
        split = sorted(split, key=lambda s: float(s[2]))[len(split) // 2]
        rebuilds = split[8] if split[8] is not None else "–"
        active = split[9] if split[9] is not None else "–"
        rows.append([label, *split[:4], rebuilds, f"{split[4]} (cap {split[5]}, "
                     f"{split[6]} dropped, most {split[7]})", active])
    return rows


def sph_section(runs, millisecond_runs):
    """`runs`: the outputs of the whole bench at the scenes' own step; `millisecond_runs`: at
    1 ms, two threads. Medians per configuration."""
    values, splits, vertices, dts = parse_sph(runs)
    v = lambda scene, col, t: median(values.get((scene, col, t), []))
    rows, ratio_rows, goals = [], [], []
    for scene, label, paper, goal in SPH_SCENES:
        if scene not in vertices:
            continue
        row = [f"{label} ({vertices[scene]:,})"]
        for col in SPH_COLUMNS:
            row.append(f"{num(v(scene, col, 1))} / {num(v(scene, col, 2))}")
        rows.append(row)
        # Step-time ratios: time ∝ 1 / throughput.
        shape_r = [ratio(v(scene, "dftl", t), v(scene, "dftl+shape", t)) for t in (1, 2)]
        hh = [v(scene, "dftl+shape", t) / v(scene, HAIR_HAIR, t)
              if v(scene, "dftl+shape", t) and v(scene, HAIR_HAIR, t) else None for t in (1, 2)]
        threads_r = [ratio(v(scene, col, 2), v(scene, col, 1)) for col in SPH_COLUMNS]
        paper_ratio = sph_paper_ratio(scene, paper)
        ratio_rows.append([label, " / ".join(shape_r),
                           " / ".join(f"{x:.2f}" if x else "–" for x in hh),
                           f"{paper_ratio:.2f}" if paper_ratio else "–",
                           f"{hh[1] / paper_ratio:.2f}" if hh[1] and paper_ratio else "–",
                           " / ".join(threads_r)])
        if hh[1]:
            goals.append(f"{label} {hh[1]:.2f} (≤ {goal}: {verdict(hh[1] <= goal)})")
    dt = next(iter(dts.values()), None)
    out = ["## Sánchez-Banderas 2015 Table 1 scenes: DFTL, shape and SPH hair–hair", "",
           "Million vertex-steps per second (wall clock) of whole harness steps (`Sim`, "
           "blocks of strands, SPH hair–hair interaction), one / two threads, each scene at "
           + (f"its own step ({dt:.4f} s, the paper's 1/60 s)" if dt else "its own step")
           + ", after half a second of warm-up, over 300 steps (so that the candidate lists' "
           f"rebuilds are counted at their rate); each the median of {len(runs)} "
           f"run{'s' if len(runs) != 1 else ''} of the whole bench. Mannequin A and B are the "
           "built-in scenes; the others are scalps with the strand and vertex counts of the "
           "paper's models. " + command_line("sph")
           + " (`-- mannequin-a dftl+shape+hair-hair 2t` for one cell).", ""]
    if not rows:
        out.append("Not measured: the bench failed (see the command's standard error).")
        return "\n".join(out)
    out += [table(["scene (vertices)", "DFTL", "DFTL + shape", "DFTL + shape + hair–hair"],
                  rows, "lrrr"), "",
            "Ratios of step times, one / two threads (the thread ratios for DFTL / + shape / + "
            "hair–hair). The paper's hair–hair ÷ DFTL + shape is Table 1's frame times (FPS "
            "124.0 → 21.5 and 172.6 → 147.4 for the mannequins; the ratios it gives for the "
            "others):", "",
            table(["scene", "DFTL + shape ÷ DFTL", "hair–hair ÷ DFTL + shape",
                   "paper, hair–hair ÷ DFTL + shape", "hairsim ÷ paper, two threads",
                   "2 threads ÷ 1 thread"], ratio_rows, "lrrrrr"), "",
            "Where the SPH stage's time goes on two threads, milliseconds a step (hash: reading "
            "the nodes, the skin's check and at a rebuild the cells; sort: at a rebuild the "
            "counting sort, every step gathering the active particles; neighbours: at a rebuild "
            "the candidate search, every step their filter with density; forces: pressure, "
            "viscosity and the write-back), how often the candidate lists were rebuilt, the "
            "neighbours a node has and the share of nodes with a candidate:", "",
            table(["scene", "hash", "sort", "neighbours", "forces", "rebuilds per 100 steps",
                   "neighbours per node", "active per node"],
                  sph_stage_rows(values, splits, vertices), "lrrrrrlr")]
    ms_values, ms_splits, ms_vertices, _ = parse_sph(millisecond_runs)
    ms = lambda scene, col: median(ms_values.get((scene, col, 2), []))
    ms_rows = []
    for scene, label, _, _ in SPH_SCENES:
        shape, both = ms(scene, "dftl+shape"), ms(scene, HAIR_HAIR)
        if shape and both:
            ms_rows.append([label, num(shape), num(both), f"{shape / both:.2f}"])
    if ms_rows:
        out += ["", "The same scenes at 1 ms, the project's rate (`-- "
                + " ".join(SPH_MILLISECOND) + "`), two threads: M vertex-steps per second and "
                "the ratio of step times, then the SPH stage's split:", "",
                table(["scene", "DFTL + shape", "DFTL + shape + hair–hair",
                       "hair–hair ÷ DFTL + shape"], ms_rows, "lrrr"), "",
                table(["scene", "hash", "sort", "neighbours", "forces", "rebuilds per 100 steps",
                       "neighbours per node", "active per node"],
                      sph_stage_rows(ms_values, ms_splits, ms_vertices), "lrrrrrlr")]
    if goals:
        out += ["", "Goals, two threads, each scene at its own step: hair–hair ÷ DFTL + shape in "
                "step time " + "; ".join(goals) + "."]
    return "\n".join(out)


def effects_section(text):
    out = ["## What each effect costs", "",
           "The firmware scenes (`firmware`: rod, 16 nodes a strand; `firmware-dftl`: DFTL) "
           "stepped by the harness with every effect their solver supports, then with each "
           "effect off in turn and alone: the median thread-CPU time of one step from each of "
           "the same 20 states (interleaved rounds). An effect's cost is the step with all on "
           "minus the step without it, and its share of the all-on step does not depend much "
           "on the machine. " + command_line("effects", "no-criterion-cases")
           + " (the table only; without the filter criterion then times every variant too).",
           ""]
    blocks = re.split(r"\n(?=\S+ \(\w+ solver, )", text or "")
    found = False
    for block in blocks:
        head = re.match(r"(\S+) \((\w+) solver, (\d+) strands, (\d+) nodes\)", block)
        totals = re.search(r"all effects on: ([\d.]+) µs; nothing on: ([\d.]+) µs; noise .*?: "
                           r"([\d.]+) µs", block)
        if not head or not totals:
            continue
        found = True
        all_on, none, noise = (float(x) for x in totals.groups())
        rows = []
        for m in re.finditer(r"^  (\S+)\s+(-?[\d.]+) µs\s+(-?[\d.]+) µs$", block, re.M):
            share = 100 * float(m.group(2)) / all_on
            rows.append([m.group(1), m.group(2), f"{share:.0f} %" if abs(share) >= 0.5
                         else "0 %", m.group(3)])
        off = re.search(r"hair-hair off ([\d.]+) µs vs absent ([\d.]+) µs: difference "
                        r"(-?[\d.]+) µs", block)
        gate = re.search(r"tested once per strand: ([\d.]+) µs per step \(([\d.]+) %", block)
        out += [f"`{head.group(1)}` ({head.group(2)}, {head.group(3)} strands, {head.group(4)} "
                f"nodes): all effects on {all_on:.2f} µs, none {none:.2f} µs, noise (the "
                f"standard deviation of the all-on round medians) {noise:.2f} µs.", "",
                table(["effect", "all − without (µs)", "share of the all-on step",
                       "alone − none (µs)"], rows, "lrrr"), ""]
        notes = []
        if off:
            notes.append(f"hair–hair off (SPH set up) against absent: {off.group(3)} µs")
        if gate:
            notes.append(f"every effect's gate tested once per strand: {gate.group(1)} µs "
                         f"({gate.group(2)} % of the step)")
        if notes:
            out += ["An effect that is off: " + "; ".join(notes) + ".", ""]
    if not found:
        out.append("Not measured: the bench failed (see the command's standard error).")
    return "\n".join(out).rstrip()


LATENCY_LINE = re.compile(r"^(firmware\S*)\s+(fixed-cost|converge)\s+(calm|violent)\s+"
                          r"([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+"
                          r"(\d+)", re.M)


def latency_section(text):
    data = {}
    for m in LATENCY_LINE.finditer(text or ""):
        data[(m.group(1), m.group(2), m.group(3))] = [float(x) for x in m.groups()[3:9]] + [
            int(m.group(10))]
    rows = []
    for scene in ("firmware", "firmware-dftl"):
        for mode in ("fixed-cost", "converge"):
            calm, violent = data.get((scene, mode, "calm")), data.get((scene, mode, "violent"))
            if not calm or not violent:
                continue
            # CPU columns: median, p99, max at 3, 4, 5.
            r = lambda a, b: num(a / b) if b else "–"
            rows.append([f"`{scene}`", mode, num(calm[3]), num(violent[3]),
                         r(violent[3], calm[3]), r(violent[4], calm[3]), r(violent[5], calm[3]),
                         r(violent[2], calm[0]), violent[6]])
    out = ["## Host step latency, calm against violent", "",
           "Each firmware scene stepped 10,000 times calm (head still, grab held) and violent "
           "(head shaking at 10 rad/s, grab circling), one thread, every step timed by the "
           "thread's CPU time (which stops while the thread is descheduled) and by the wall "
           "clock. On a host the maxima are the operating system's (interrupts, cold caches "
           "after a context switch; the calm runs have them too): the 20 % goal for the "
           "fixed-cost worst step is judged on the target, below. " + command_line("latency")
           + ".", ""]
    if rows:
        out.append(table(["scene", "mode", "calm median (µs CPU)", "violent median (µs CPU)",
                          "violent ÷ calm, median", "violent p99 ÷ calm median",
                          "violent max ÷ calm median", "the same, wall clock",
                          "rolled back"], rows, "llrrrrrrr"))
    else:
        out.append("Not measured: the bench failed (see the command's standard error).")
    return "\n".join(out)


FIRMWARE_ROW = re.compile(r"^\| ([\w-]+) \| (\d+) \| ([\d./]+) \| ([\d./]+) \| ([\d.]+) \| (\d+) \| "
                          r"(yes|no) \|$", re.M)
QEMU = ["qemu-system-arm", "-cpu", "cortex-m4", "-machine", "mps2-an386", "-nographic",
        "-icount", "shift=0", "-semihosting-config", "enable=on,target=native", "-kernel"]
SOLVER_NAMES = {"rod": "rod", "dftl": "DFTL + shape", "dftl_noshape": "DFTL, no shape",
                "haptic-dftl": "`haptic-dftl`: DFTL + shape, a coupled grab"}


def build_firmware():
    """[return code, the firmware's ELF or None, cargo's standard error, seconds building]."""
    started = time.time()
    rc, out, err = run_now(["cargo", "build", "--release",
                            "--message-format=json-render-diagnostics"], cwd=ROOT / "firmware")
    elf = None
    for line in out.splitlines():
        try:
            message = json.loads(line)
        except ValueError:
            continue
        if message.get("reason") == "compiler-artifact" and message.get("executable"):
            elf = message["executable"]
    return [rc, elf, err, time.time() - started]


def firmware_section(runner):
    intro = ["## Measured on the target: Cortex-M4F under QEMU", "",
             "The firmware example steps rod scenes and DFTL scenes (with shape preservation, "
             "and without) in fixed-cost mode, calm (head still) and violent (head shaking at "
             "10 rad/s, hair starting horizontal), and the built-in `haptic-dftl` scene (8 "
             "strands × 16 nodes, a device holding one tip through a coupling; violent: the "
             "head shaking, the device going round its circle), under `qemu-system-arm -icount shift=0`: "
             "one instruction per virtual nanosecond, so the counts are deterministic and do "
             "not depend on the host. `firmware/latency.py` turns them into a Cortex-M4F cycle "
             "estimate (1 cycle an instruction, 14 for `VDIV`/`VSQRT`, 3 for the "
             "multiply-accumulates, their share read from the disassembly of the step's code). "
             "The same as the firmware step of `bash .ci/run`: `cd firmware && cargo build "
             "--release`, then `" + " ".join(QEMU) + " "
             "target/thumbv7em-none-eabihf/release/hairsim-firmware > LOG` and `python3 "
             "firmware/latency.py LOG ELF`.", ""]
    missing = [tool for tool in ("qemu-system-arm", "llvm-objdump") if not which(tool)]
    rc, targets, _ = run(["rustup", "target", "list", "--installed"], quiet=True)
    if rc != 0 or "thumbv7em-none-eabihf" not in targets.split():
        missing.append("the thumbv7em-none-eabihf target")
    if missing:
        log("firmware section skipped: " + ", ".join(missing) + " missing")
        return "\n".join(intro + ["Not measured in this run: " + ", ".join(missing)
                                  + " not installed (`bash .ci/run` installs them)."])
    rc, elf, err, seconds = TAPE.take("firmware build", "firmware", build_firmware)
    runner.build_seconds += seconds
    if rc != 0 or elf is None:
        runner.fail("firmware build", tail(err))
        return "\n".join(intro + ["Not measured: the firmware did not build."])
    rc, log_text, err = run(QEMU + [elf], timeout=300)
    if rc != 0 or "latency" not in log_text:
        runner.fail("qemu", tail(err or log_text))
        return "\n".join(intro + ["Not measured: the firmware did not run under QEMU."])
    with tempfile.NamedTemporaryFile("w", suffix=".log", delete=False) as f:
        f.write(log_text)
        log_path = f.name
    rc, out, err = run([sys.executable, str(ROOT / "firmware/latency.py"), log_path, elf])
    os.unlink(log_path)
    if rc != 0:
        runner.fail("latency.py", tail(err))
        return "\n".join(intro + ["Not measured: `firmware/latency.py` failed."])
    cpi = re.search(r"-> ([\d.]+) cycles per instruction", out)
    rows, worst_ratio, largest = [], 0.0, {}
    for m in FIRMWARE_ROW.finditer(out):
        solver, nodes = m.group(1), int(m.group(2))
        calm = [float(x) for x in m.group(3).split("/")]
        violent = [float(x) for x in m.group(4).split("/")]
        r = float(m.group(5))
        worst_ratio = max(worst_ratio, r)
        if m.group(7) == "yes":
            largest[solver] = max(largest.get(solver, 0), nodes)
        rows.append([SOLVER_NAMES.get(solver, solver), f"{nodes:,}", f"{num(calm[1])} k",
                     f"{num(violent[2])} k", f"{r:.3f}", f"{int(m.group(6)):,}", m.group(7)])
    if not rows:
        runner.fail("latency.py", "no table rows in its output")
        return "\n".join(intro + ["Not measured: no latency lines in the firmware's output."])
    out_lines = intro + [
        f"{cpi.group(1) if cpi else '?'} cycles per instruction (from the disassembly).", "",
        table(["solver", "nodes", "calm median (instructions)",
               "violent max (instructions)", "violent max ÷ calm median",
               "est. µs at 168 MHz (violent max)", "fits half a 1 ms tick"], rows, "lrrrrrl"), ""]
    size = lambda s: (f"the largest that fits has {largest[s]:,}" if s in largest
                      else "none of those measured fits")
    out_lines.append(
        f"Goals: fixed-cost mode keeps the worst step within 20 % of the calm median: at most "
        f"{worst_ratio:.3f}, {verdict(worst_ratio <= 1.2)}. In half a 1 ms tick at 168 MHz "
        f"(84,000 cycles): ≥ 128 rod nodes, {size('rod')}, "
        f"{verdict(largest.get('rod', 0) >= 128)}; ≥ 512 DFTL vertices, with shape "
        f"{size('dftl')}, {verdict(largest.get('dftl', 0) >= 512)}, without shape "
        f"{size('dftl_noshape')}, {verdict(largest.get('dftl_noshape', 0) >= 512)}. "
        "What each model needs at the least: [floors](study/floors.md).")
    haptic = [row for row in rows if row[0] == SOLVER_NAMES["haptic-dftl"]]
    if haptic:
        fits, ratio = haptic[0][6] == "yes", float(haptic[0][4])
        out_lines[-1] += (
            f" `haptic-dftl` within half a tick at 168 MHz: {haptic[0][5]} µs, "
            f"{verdict(fits)}; violent max ÷ calm median ≤ 1.2: {ratio:.3f}, "
            f"{verdict(ratio <= 1.2)}.")
    collision = collision_rows(out)
    if collision:
        out_lines += ["", "What a collision row costs (`latency.py`'s `collision rows` lines): the "
                      "modelled cycles the head's sphere adds to a rod scene, divided by the "
                      "collision rows its projection solved (`StepReport::collision_rows`, each "
                      "row counted at every iteration), the head shaking at 10 rad/s. Goal: at "
                      "most 1.5× a collision row's floor.", "", collision]
    return "\n".join(out_lines)


COLLISION_LINE = re.compile(r"^collision rows, rod (\d+) nodes (\S+), (\d+) steps: (\d+) rows "
                            r"\(([\d.]+) a step\); the sphere adds (\d+) cycles a step, (\S+) a "
                            r"row against ([\d.]+) \(1\.5 x (\d+)\): (met|missed)$", re.M)


def collision_rows(latency_output):
    """The table of `latency.py`'s `collision rows` lines, or ""."""
    rows = []
    for m in COLLISION_LINE.finditer(latency_output):
        per_row = m.group(7)
        rows.append([f"`{m.group(2)}` (1 × {m.group(1)})", m.group(5), f"{int(m.group(6)):,}",
                     "—" if per_row == "inf" else f"{int(float(per_row)):,}",
                     f"≤ {m.group(8)}: {verdict(m.group(10) == 'met')}"
                     if per_row != "inf" else "not measurable: no contact"])
    if not rows:
        return ""
    return table(["scene", "collision rows a step", "cycles the sphere adds a step",
                  "per collision row", "goal"], rows, "lrrrl")


def build_c_example():
    """[return code, make's standard error, seconds building] of the C example."""
    started = time.time()
    rc, _, err = run_now(["make", "-s", "-C", "firmware-c", "all"])
    return [rc, err, time.time() - started]


def c_example_section(runner):
    """Flash, RAM and stack of the bare-metal C example (`firmware-c/`), as `bash .ci/ffi`'s last
    step measures them."""
    intro = ["## The C library and the C example on the Cortex-M4F", ""]
    header = read_repository_file("ffi/include/hairsim.h")
    define = lambda name: (re.search(rf"^#define {name} (\d+)", header, re.M) or [None, "?"])[1]
    cargo = read_repository_file("ffi/Cargo.toml")
    release = cargo.split("[profile.release]", 1)[-1].split("\n[", 1)[0] if cargo else ""
    opt = re.search(r"^opt-level\s*=\s*(\S+)", release, re.M)
    lto = re.search(r"^lto\s*=\s*(\S+)", release, re.M)
    profile = ", ".join(x for x in (f"`opt-level = {opt.group(1)}`" if opt else "",
                                     "LTO" if lto and lto.group(1) not in ("false", '"off"')
                                     else "") if x)
    intro.append(
        "Sizes of the `firmware` scene built from C (`firmware-c/`, `-mcpu=cortex-m4 -mthumb "
        "-mfloat-abi=hard -mfpu=fpv4-sp-d16`), linking `libhairsim_ffi.a` for "
        f"`thumbv7em-none-eabihf` at the default capacities ({define('HAIRSIM_STRANDS')} strands "
        f"× {define('HAIRSIM_NODES')} nodes{', ' + profile if profile else ''}): `make -s -C "
        "firmware-c run` (under QEMU), then `arm-none-eabi-size` and `firmware-c/size.py` on "
        "the image it ran, as the last step of `bash .ci/ffi` does. The stack figures are "
        "high-water marks found by painting the stack before each phase.")
    intro.append("")
    missing = [tool for tool in ("arm-none-eabi-gcc", "arm-none-eabi-size", "qemu-system-arm",
                                 "llvm-objdump", "make") if not which(tool)]
    rc, targets, _ = run(["rustup", "target", "list", "--installed"], quiet=True)
    if rc != 0 or "thumbv7em-none-eabihf" not in targets.split():
        missing.append("the thumbv7em-none-eabihf target")
    if which("dpkg") and run(["dpkg", "-s", "libnewlib-arm-none-eabi"], quiet=True)[0]:
        missing.append("libnewlib-arm-none-eabi")
    if missing:
        log("C example section skipped: " + ", ".join(missing) + " missing")
        return "\n".join(intro + ["Not measured in this run: " + ", ".join(missing)
                                  + " not installed (`bash .ci/ffi` installs them)."])
    rc, err, seconds = TAPE.take("c build", "firmware-c", build_c_example)
    runner.build_seconds += seconds
    if rc != 0:
        runner.fail("C example build", tail(err))
        return "\n".join(intro + ["Not measured: the C example did not build."])
    rc, log_text, err = run(["make", "-s", "-C", "firmware-c", "TIMEOUT=300", "run"])
    stack = re.search(r"stack high-water mark, bytes: hairsim_init (\d+), scene build (\d+), "
                      r"step (\d+)", log_text)
    world = re.search(r"world buffer, bytes: (\d+) used of HAIRSIM_WORLD_SIZE (\d+)", log_text)
    if rc != 0 or not stack or not world:
        runner.fail("C example under QEMU", tail(err or log_text))
        return "\n".join(intro + ["Not measured: the C example did not run under QEMU."])
    elf = ROOT / "firmware-c/build/hairsim-c.elf"
    _, size_out, _ = run(["arm-none-eabi-size", str(elf)])
    berkeley = re.search(r"^\s*(\d+)\s+(\d+)\s+(\d+)\s+\d+\s+\S+\s+\S+$", size_out, re.M)
    _, origin_out, _ = run([sys.executable, str(ROOT / "firmware-c/size.py"),
                            str(ROOT / "firmware-c/build/hairsim-c.map")])
    flash = dict(re.findall(r"(hairsim library|C example|newlib \+ libgcc) (\d+)",
                            origin_out.split("static RAM", 1)[0]))
    ram = dict(re.findall(r"(hairsim library|C example|newlib \+ libgcc) (\d+)",
                          origin_out.split("static RAM", 1)[-1]))
    n = lambda x: f"{int(x):,}" if x is not None else "–"
    rows = [
        ["flash, whole image", n(int(berkeley.group(1)) + int(berkeley.group(2)))
         if berkeley else "–"],
        ["– the hairsim library", n(flash.get("hairsim library"))],
        ["– the C example", n(flash.get("C example"))],
        ["– newlib and libgcc", n(flash.get("newlib + libgcc"))],
        ["static RAM: the world buffer (`HAIRSIM_WORLD_SIZE`)",
         f"{n(world.group(2))} ({n(world.group(1))} used on the Cortex-M4F)"],
        ["static RAM of the library itself", n(ram.get("hairsim library"))],
        ["stack: `hairsim_init`", n(stack.group(1))],
        ["stack: building the scene", n(stack.group(2))],
        ["stack: one step", n(stack.group(3))],
    ]
    out = intro + [table(["", "bytes"], rows, "lr"), ""]
    _, init_s, _ = run(["llvm-objdump", "-d", "--no-show-raw-insn",
                        "--disassemble-symbols=hairsim_init_versioned", str(elf)], quiet=True)
    pushes = re.findall(r"\bv?push(?:\.w)?\s+\{([^}]*)\}", init_s)
    registers = sum(len(p.split(",")) for p in pushes)
    adjust = max([int(x) for x in re.findall(r"sub(?:\.w)?\s+sp, (?:sp, )?#(\d+)", init_s)],
                 default=0)
    if pushes:
        out.append(f"`hairsim_init` builds the world in place: its frame is {registers} pushed "
                   f"registers and {'no stack adjustment' if adjust == 0 else f'{adjust} bytes'} "
                   "(`.ci/ffi` checks the disassembly). `HAIRSIM_WORLD_SIZE` is measured on the "
                   "64-bit host, where `usize` fields are wider; the Cortex-M4F needs a little "
                   "less, and `hairsim_init` checks the length and alignment it is given on the "
                   "running target.")
    return "\n".join(out).rstrip()


# ---------------------------------------------------------------------------------------------


INTRO = """# Performance

hairsim's speed beside the papers' tables: Kmoch, Bonanni and Magnenat-Thalmann 2009 (the rod;
their machine a Core 2 Quad at 2.66 GHz) and Sánchez-Banderas et al. 2015 (DFTL, shape and SPH
hair–hair; a GTX 650 GPU), then what each effect costs, the host's step latency, the
Cortex-M4F's instruction counts, and the flash, RAM and stack of the C example. This whole
file is printed by one command, which builds and runs every bench below and measures the
machine's memory bandwidth in the same run (`--quick`: a short trial run; `--replay
docs/performance.json`: the same page again from what was measured, running nothing):

```sh
python3 benches/performance.py --record docs/performance.json > docs/performance.md
```

An absolute figure belongs to the machine it was measured on, described first; the machine
may differ from one run of the command to the next. The ratios (hair-optimised ÷ Newton, with ÷
without collisions, blocks ÷ per-strand, two threads ÷ one, DFTL + shape ÷ DFTL, hair–hair ÷
none, the share of the memory bandwidth) depend far less on it: compare those across runs. Each
section names the bench that gives it, to reproduce one table alone. Two versions of the code
are compared, old against new alternated in one sitting, by `python3 benches/compare.py --old
OLD-CHECKOUT` (every criterion row, the median of the per-round ratios)."""


def machine_section(args, cpu, rustc, load_start, load_end, bandwidth, wall, build):
    command = "python3 benches/performance.py" + (" --quick" if args.quick else "")
    if args.native:
        command += " --native"
    if args.no_build:
        command += " --no-build"
    if args.runs is not None:
        command += f" --runs {args.runs}"
    if args.only:
        command += f" --only {args.only}"
    if args.record:
        command += f" --record {args.record}"
    model = cpu["model"]
    if cpu["family"]:
        model += f" (family {cpu['family']}, model {cpu['model_number']})"
    cores = f"{cpu['logical']} logical"
    if cpu["physical"]:
        cores += f", {cpu['physical']} physical"
    vector = ("AVX-512: yes (" + ", ".join(cpu["avx512"]) + ")" if cpu["avx512"]
              else "AVX-512: no") + (", AVX2" if cpu["avx2"] else "") + (
        ", FMA" if cpu["fma"] else "")
    bw = "; ".join(f"{t} thread{'s' if t > 1 else ''}: copy {num(c)}, triad {num(tr)} GB/s"
                   for t, (c, tr) in sorted(bandwidth.items())) or "not measured"
    load = (f"{load_start:.2f} at the start, {load_end:.2f} at the end"
            if load_start is not None and load_end is not None else "unknown")
    # The last benches run on two threads, so the end's average climbs toward 2 by this
    # command's own work: only more than that says other processes were running.
    loaded = (load_start or 0) > 1 or (load_end or 0) > 2.2
    if loaded:
        load += (" — **other processes shared the machine** (above 1 at the start or 2.2 at "
                 "the end, after the two-thread benches), so the absolute figures may be low; "
                 "the ratios suffer less")
    elif load_end is not None and load_end > 1:
        load += " (the end's from this command's own two-thread benches)"
    rows = [
        ["command", f"`{command}`" + (" (a trial run: short measurements)" if args.quick
                                      else "")],
        ["date", TAPE.take("value", "date", lambda: datetime.datetime.now(
            datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"))],
        ["CPU", model],
        ["cores", cores],
        ["vector extensions", vector],
        ["caches", ", ".join(cpu["caches"]) or "unknown"],
        ["memory", (f"{cpu['memory_gib']:.0f} GiB; " if cpu["memory_gib"] else "")
         + f"bandwidth measured in this run (best of start and end): {bw}"],
        ["compiler", rustc + ", the bench profile (release, baseline x86-64 unless a column "
         "says native)"],
        ["criterion", " ".join(["--warm-up-time", "0.5", "--measurement-time", "1"]
                               if args.quick else
                               ["--warm-up-time", "1", "--measurement-time", "4"])
         + ", the median"],
        ["load average (1 minute)", load],
        ["wall time of the command", f"{wall / 60:.1f} minutes"
         + (f", {build / 60:.1f} of them building the benches" if build >= 30 else "")],
    ]
    return "\n".join(["## The machine and the run", "", table(["", ""], rows)])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="short criterion times, one run of each custom bench")
    parser.add_argument("--native", action="store_true",
                        help="also build and run dftl_cpu with -C target-cpu=native")
    parser.add_argument("--no-build", action="store_true",
                        help="run the newest bench binaries already built, without cargo")
    parser.add_argument("--runs", type=int, default=None,
                        help="runs of dftl_cpu and sph, medians (default 3, 1 with --quick)")
    parser.add_argument("--only", default="", help="comma-separated sections: "
                        + ", ".join(SECTIONS))
    parser.add_argument("--record", type=Path, help="also write what was measured to this file")
    parser.add_argument("--replay", type=Path,
                        help="print the document again from a recording, running nothing")
    args = parser.parse_args()
    record_to, replaying = args.record, args.replay is not None
    if replaying:
        recording = json.loads(args.replay.read_text())
        TAPE.mode, TAPE.entries = "replay", recording["entries"]
        args, record_to = argparse.Namespace(**recording["args"]), None
    elif record_to:
        TAPE.mode = "record"
    runs = args.runs if args.runs is not None else (1 if args.quick else 3)
    only = [s for s in args.only.split(",") if s] or SECTIONS
    unknown = [s for s in only if s not in SECTIONS]
    if unknown:
        parser.error(f"unknown sections {unknown}; known: {SECTIONS}")
    document, failures = measure(args, runs, only)
    print(document)
    if record_to:
        arguments = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()}
        record_to.write_text(json.dumps({"args": arguments, "entries": TAPE.entries},
                                        indent=0) + "\n")
    return 1 if failures and not replaying else 0


def measure(args, runs, only):
    """Runs (or replays) every section of `only`: (the document, the failures)."""
    load_start = load_average("start")
    log(f"load average {load_start}")
    cpu = cpu_info()
    rustc = rustc_version()
    runner = Runner(args)
    runner.cpu = cpu

    benches = sorted({BENCH[s] for s in only if s in BENCH} | {"bandwidth"})
    runner.build(benches)
    native = args.native and "dftl" in only
    if native and not runner.build(["dftl_cpu"], native=True):
        native = False

    bandwidth_runs = [measure_bandwidth(runner)]
    # A section measured on its own: its name, and how it is measured and written.
    single = {"step": step_section, "twist": twist_section, "projection": projection_section,
              "effects": lambda r: effects_section(r.custom("effects", ["no-criterion-cases"])),
              "latency": lambda r: latency_section(r.custom("latency")),
              "firmware": firmware_section, "c": c_example_section}
    sections = {name: write(runner) for name, write in single.items() if name in only}
    dftl_default, dftl_native = [], []
    if "dftl" in only:
        for _ in range(runs):
            dftl_default.append(parse_dftl(runner.custom("dftl_cpu")))
            if native:
                dftl_native.append(parse_dftl(runner.custom("dftl_cpu", native=True)))
    sph_runs, sph_millisecond = [], []
    if "sph" in only:
        for _ in range(runs):
            sph_runs.append(runner.custom("sph"))
            sph_millisecond.append(runner.custom("sph", SPH_MILLISECOND))
    bandwidth_runs.append(measure_bandwidth(runner))
    bandwidth = best_bandwidth(bandwidth_runs)
    if "dftl" in only:
        sections["dftl"] = dftl_section(runner, bandwidth, dftl_native, dftl_default)
    if "sph" in only:
        sections["sph"] = sph_section(sph_runs, sph_millisecond)
    sections["bandwidth"] = bandwidth_section(bandwidth_runs)
    load_end = load_average("end")
    log(f"load average {load_end}")
    wall = TAPE.take("value", "wall", lambda: time.time() - START)

    parts = [INTRO, machine_section(args, cpu, rustc, load_start, load_end, bandwidth,
                                    wall, runner.build_seconds)]
    tables = data_tables()
    for name in SECTIONS:
        if name in sections:
            parts.append(sections[name])
        parts += [table_section(t) for t in tables if t.get("after") == name]
    parts += [table_section(t) for t in tables if t.get("after") not in SECTIONS]
    if runner.failures:
        parts.append("## Not measured\n\n" + "\n".join(f"- {f}" for f in runner.failures))
    shutil.rmtree(runner.criterion_home, ignore_errors=True)
    log(f"done in {(time.time() - START) / 60:.1f} minutes")
    return wrap("\n\n".join(parts)), runner.failures


def data_tables():
    """The tables other scripts measure, from `benches/tables/*.json`, in file-name order."""
    return [json.loads(path.read_text()) for path in sorted((ROOT / TABLES).glob("*.json"))]


def table_section(data):
    """A section from a table file: its heading, text, table and the command that measured it."""
    out = [f"## {data['title']}", ""]
    if data.get("text"):
        out += [data["text"], ""]
    if data.get("command"):
        out += [f"Measured by `{data['command']}`" + (f" on {data['date']}" if data.get("date")
                                                      else "") + ".", ""]
    out.append(table(data["header"], data["rows"], data.get("align")))
    return "\n".join(out)


if __name__ == "__main__":
    sys.exit(main())
