#!/usr/bin/env python3
"""The SPH stage's physics against the stage before the candidate lists (or another version).

Builds `benches/examples/sph_against.rs` twice — with this checkout's SPH stage, and with the
same checkout whose `std-harness/src/sph/` is an older commit's (by default ff33aa0, the last
before the lists kept with a skin), behind a shim giving it the checkout's interface — and
compares, on states of the five Table 1 scenes captured by this checkout after 0.5 s and 1 s at
their own step:

- each node's density and SPH acceleration, as the RMS of the difference over the RMS of the
  old values, per scene and capture (goal: at most 1 %);
- Mannequin A's volume: the mean distance of its nodes from the head's centre, averaged over
  1 s of steps, each version stepping the whole scene with its own stage (goal: within 2 %).

    python3 benches/sph_against.py [--old COMMIT] [--work DIR]

Prints a Markdown table; exits 1 if a goal is missed. Builds in the checkout's `target/`
(the old copy's crates beside the checkout's) and works in `--work`.
"""

import argparse
import math
import os
import shutil
import struct
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GOAL_RMS = 0.01
GOAL_VOLUME = 0.02

# The old stage's interface made the checkout's: `accelerations(strands, dt, head) -> &[Vec3]`
# (the head does not matter to it), `output`, `acting` (every strand) and `densities`.
SHIM = """
impl Sph {
    /// The checkout's interface over the old stage.
    pub fn accelerations<const N: usize>(
        &mut self,
        strands: &[Strand<N>],
        dt: f32,
        _head: hairsim_core::Pose,
    ) -> &[Vec3] {
        let mut out = std::mem::take(&mut self.shim_output);
        out.resize(strands.len() * N, Vec3::ZERO);
        self.old_accelerations(strands, dt, &mut out);
        self.shim_output = out;
        if self.shim_acting.len() != strands.len() {
            self.shim_acting = vec![true; strands.len()];
        }
        &self.shim_output
    }

    /// The accelerations of the last step.
    #[must_use]
    pub fn output(&self) -> &[Vec3] {
        &self.shim_output
    }

    /// Every strand: the old stage gave every node an acceleration.
    #[must_use]
    pub fn acting(&self) -> &[bool] {
        &self.shim_acting
    }

    /// Each particle's density in the last step, in the particle order.
    #[must_use]
    pub fn densities(&self) -> Vec<f32> {
        (0..self.particles())
            .map(|p| self.sorted.density[self.grid.rank[p] as usize])
            .collect()
    }
}
"""


def run(cmd, cwd, **kw):
    print("$", " ".join(cmd), file=sys.stderr)
    return subprocess.run(cmd, cwd=cwd, check=True, **kw)


def old_copy(old, work):
    """A copy of the checkout's tracked files with the old commit's SPH stage and the shim."""
    if os.path.exists(work):
        shutil.rmtree(work)
    os.makedirs(work)
    files = subprocess.run(
        ["git", "ls-files", "-z"], cwd=ROOT, check=True, capture_output=True
    ).stdout.split(b"\0")
    for f in filter(None, files):
        src, dst = os.path.join(ROOT, f.decode()), os.path.join(work, f.decode())
        if os.path.isfile(src):
            os.makedirs(os.path.dirname(dst), exist_ok=True)
            shutil.copy2(src, dst)
    sph = os.path.join(work, "std-harness/src/sph")
    shutil.rmtree(sph)
    os.makedirs(sph)
    names = subprocess.run(
        ["git", "ls-tree", "--name-only", old, "std-harness/src/sph/"],
        cwd=ROOT, check=True, capture_output=True, text=True,
    ).stdout.split()
    for name in names:
        text = subprocess.run(
            ["git", "show", f"{old}:{name}"], cwd=ROOT, check=True,
            capture_output=True, text=True,
        ).stdout
        if name.endswith("/mod.rs"):
            text = shimmed(text)
        with open(os.path.join(work, name), "w") as f:
            f.write(text)


def shimmed(text):
    def replace(old, new):
        nonlocal text
        if old not in text:
            sys.exit(f"sph_against: the old stage has no `{old.strip()}` to shim")
        text = text.replace(old, new, 1)

    replace("    pub fn accelerations<const N: usize>(", "    pub fn old_accelerations<const N: usize>(")
    replace("    pub stats: SphStats,\n}", "    pub stats: SphStats,\n    shim_output: Vec<Vec3>,\n    shim_acting: Vec<bool>,\n}")
    replace("            stats: SphStats::default(),\n", "            stats: SphStats::default(),\n            shim_output: Vec::new(),\n            shim_acting: Vec::new(),\n")
    return text + SHIM


def build(cwd, target, keep):
    """Builds the example in `cwd` and keeps its binary as `keep` (both versions share the
    target directory, where one's binary replaces the other's)."""
    run(["cargo", "build", "-q", "--release", "-p", "hairsim-benches", "--example",
         "sph_against", "--target-dir", target], cwd)
    shutil.copy2(os.path.join(target, "release/examples/sph_against"), keep)
    return keep


def floats(path):
    with open(path, "rb") as f:
        data = f.read()
    return struct.unpack(f"<{len(data) // 4}f", data)


def relative_rms(new, old):
    diff = sum((a - b) ** 2 for a, b in zip(new, old))
    norm = sum(b * b for b in old)
    return math.sqrt(diff / norm) if norm > 0 else math.sqrt(diff)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--old", default="ff33aa0")
    parser.add_argument("--work", default="/tmp/hairsim-sph-against")
    args = parser.parse_args()
    target = os.path.join(ROOT, "target")
    states = os.path.join(args.work, "states")
    copy = os.path.join(args.work, "old")
    old_copy(args.old, copy)
    new_bin = build(ROOT, target, os.path.join(args.work, "new-sph-against"))
    old_bin = build(copy, target, os.path.join(args.work, "old-sph-against"))
    os.makedirs(states, exist_ok=True)
    run([new_bin, "capture", states], ROOT)
    out, written = {}, {}
    for which, binary in (("new", new_bin), ("old", old_bin)):
        out[which] = os.path.join(args.work, f"{which}.values")
        written[which] = run([binary, "evaluate", states, out[which]], ROOT,
                             capture_output=True, text=True).stdout.split("\n")
    assert written["new"] == written["old"], "the two versions wrote different states"
    new, old = floats(out["new"]), floats(out["old"])
    assert len(new) == len(old), "the two versions wrote different particle counts"
    print(f"New: this checkout; old: {args.old}'s SPH stage. Relative RMS differences of each")
    print("node's density and SPH acceleration on the same captured state:\n")
    print("| scene | captured after | nodes | density | acceleration |")
    print("|---|---|---:|---:|---:|")
    at, missed = 0, False
    for line in filter(None, written["new"]):
        name, seconds, count = line.split()
        count = int(count)
        n, o = new[at : at + 4 * count], old[at : at + 4 * count]
        density = relative_rms(n[0::4], o[0::4])
        acc = relative_rms(
            [v for k in range(1, 4) for v in n[k::4]],
            [v for k in range(1, 4) for v in o[k::4]],
        )
        missed |= density > GOAL_RMS or acc > GOAL_RMS
        print(f"| {name} | {float(seconds):g} s | {count:,} | {density:.2e} | {acc:.2e} |")
        at += 4 * count
    volume = {}
    for which, binary in (("new", new_bin), ("old", old_bin)):
        volume[which] = float(run([binary, "volume"], ROOT, capture_output=True,
                                  text=True).stdout)
    change = volume["new"] / volume["old"] - 1
    missed |= abs(change) > GOAL_VOLUME
    print(
        f"\nMannequin A's mean distance of nodes from the head's centre over 1 s at 1/60 s: "
        f"new {volume['new'] * 1000:.3f} mm, old {volume['old'] * 1000:.3f} mm "
        f"({change * 100:+.3f} %; goal within ±{GOAL_VOLUME * 100:.0f} %)."
    )
    print(f"\nGoals (RMS ≤ {GOAL_RMS * 100:.0f} %, volume ±{GOAL_VOLUME * 100:.0f} %): "
          f"{'missed' if missed else 'met'}.")
    sys.exit(1 if missed else 0)


if __name__ == "__main__":
    main()
