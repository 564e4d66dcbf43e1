//! Bounded latency on the host: each scene stepped 10,000 times violent (as built: the head
//! shaking at 10 rad/s, the grab circling) and calm (the same strands, colliders, grabs and
//! effects with the head still and the grab target held), every step timed; the median, p99,
//! p99.9 and maximum step time, and in fixed-cost mode the violent maximum against the calm
//! median. Criterion gives neither p99 nor a maximum, so this is a `harness = false` bench
//! that prints a table.
//!
//! `cargo bench -p hairsim-benches --bench latency` runs 10,000 steps per case (one thread);
//! `cargo test --benches` runs 100. A maximum on a shared machine is the scheduler's as much
//! as the step's: read it with the machine's load, printed first.

use std::hint::black_box;
use std::time::Instant;

use hairsim::run::{load, HairFileOptions};
use hairsim::scene::motion::{Motion, Path};
use hairsim::scene::Prepared;
use hairsim::sim::{scene_inputs, Sim};
use hairsim_core::{Libm, Mode};

/// The firmware scenes' strands have at most 16 nodes.
const N: usize = 16;

/// The scene held still: head at rest, grab targets at their start.
fn calm(prepared: &Prepared) -> Prepared {
    let mut p = prepared.clone();
    p.motion = Motion::Still;
    for g in &mut p.grabs {
        if let Path::Circle { radius, .. } = &mut g.path.path {
            *radius = 0.0;
        }
    }
    p
}

/// Step times of `steps` steps, µs, and the strands rolled back.
fn time_steps(prepared: &Prepared, steps: u64) -> (Vec<f64>, u64) {
    let mut sim = Sim::<N, Libm>::new(prepared, 1).expect("scene builds");
    let mut times = Vec::with_capacity(steps as usize);
    let mut rolled_back = 0;
    for k in 0..steps {
        let inputs = scene_inputs::<Libm>(prepared, k);
        let start = Instant::now();
        let report = black_box(sim.step(black_box(&inputs)));
        times.push(start.elapsed().as_secs_f64() * 1e6);
        rolled_back += u64::from(report.rolled_back);
    }
    times.sort_by(f64::total_cmp);
    (times, rolled_back)
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * q).round() as usize;
    sorted.get(i).copied().unwrap_or(f64::NAN)
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

fn main() {
    let benching = std::env::args().any(|a| a == "--bench");
    let steps: u64 = if benching { 10_000 } else { 100 };
    println!(
        "host step latency, one thread, {steps} steps per case; load average {}; cores {}",
        load_average(),
        std::thread::available_parallelism().map_or(1, usize::from)
    );
    println!(
        "{:<14} {:<10} {:<8} {:>10} {:>10} {:>10} {:>10} {:>8}  violent max / calm median",
        "scene", "mode", "motion", "median µs", "p99 µs", "p99.9 µs", "max µs", "rollback"
    );
    for name in ["firmware", "firmware-dftl"] {
        let scene = load(name, &HairFileOptions::default())
            .expect("built-in scene")
            .prepared;
        for mode in [Mode::FixedCost, Mode::Converge] {
            let mut violent = scene.clone();
            violent.params.mode = mode;
            let calm = calm(&violent);
            let (calm_times, calm_rb) = time_steps(&calm, steps);
            let (violent_times, violent_rb) = time_steps(&violent, steps);
            let calm_median = quantile(&calm_times, 0.5);
            for (motion, times, rb) in [
                ("calm", &calm_times, calm_rb),
                ("violent", &violent_times, violent_rb),
            ] {
                let max = times.last().copied().unwrap_or(f64::NAN);
                let ratio = if motion == "violent" {
                    format!("{:.2}", max / calm_median)
                } else {
                    String::new()
                };
                println!(
                    "{:<14} {:<10} {:<8} {:>10.2} {:>10.2} {:>10.2} {:>10.2} {:>8}  {ratio}",
                    name,
                    mode.name(),
                    motion,
                    quantile(times, 0.5),
                    quantile(times, 0.99),
                    quantile(times, 0.999),
                    max,
                    rb
                );
            }
        }
    }
}
