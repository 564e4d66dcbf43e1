//! Bounded latency on the host: each scene stepped 10,000 times violent (as built: the head
//! shaking at 10 rad/s, the grab circling) and calm (the same strands, colliders, grabs and
//! effects with the head still and the grab target held), every step timed; the median, p99,
//! maximum step time, and in fixed-cost mode the violent maximum against the calm median.
//! Both the wall clock and the thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`, which stops while
//! the thread is descheduled) are shown: on a shared machine the wall-clock p99 and maximum
//! are the scheduler's time slices, the CPU time's are the step's. Criterion gives neither p99 nor a maximum, so this is a `harness = false` bench
//! that prints a table.
//!
//! `cargo bench -p hairsim-benches --bench latency` runs 10,000 steps per case (one thread);
//! `cargo test --benches` runs 100. The machine's load is printed first.

use std::hint::black_box;
use std::time::Instant;

use cpu_time::ThreadTime;
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

/// What `steps` steps took: wall-clock and thread CPU times, µs, sorted, and the strands
/// rolled back.
struct Timed {
    wall: Vec<f64>,
    cpu: Vec<f64>,
    rolled_back: u64,
}

fn time_steps(prepared: &Prepared, steps: u64) -> Timed {
    let mut sim = Sim::<N, Libm>::new(prepared, 1).expect("scene builds");
    let mut wall = Vec::with_capacity(steps as usize);
    let mut cpu = Vec::with_capacity(steps as usize);
    let mut rolled_back = 0;
    for k in 0..steps {
        let inputs = scene_inputs::<Libm>(prepared, k);
        let cpu_start = ThreadTime::now();
        let start = Instant::now();
        let report = black_box(sim.step(black_box(&inputs)));
        let elapsed = start.elapsed();
        cpu.push(cpu_start.elapsed().as_secs_f64() * 1e6);
        wall.push(elapsed.as_secs_f64() * 1e6);
        rolled_back += u64::from(report.rolled_back);
    }
    wall.sort_by(f64::total_cmp);
    cpu.sort_by(f64::total_cmp);
    Timed {
        wall,
        cpu,
        rolled_back,
    }
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
        "{:<14} {:<10} {:<8} {:>30} {:>30} {:>8}",
        "", "", "", "wall clock µs", "thread CPU time µs", ""
    );
    println!(
        "{:<14} {:<10} {:<8} {:>9} {:>9} {:>10} {:>9} {:>9} {:>10} {:>8}  violent max / calm median (wall, CPU)",
        "scene", "mode", "motion", "median", "p99", "max", "median", "p99", "max", "rollback"
    );
    for name in ["firmware", "firmware-dftl"] {
        let scene = load(name, &HairFileOptions::default())
            .expect("built-in scene")
            .prepared;
        for mode in [Mode::FixedCost, Mode::Converge] {
            let mut violent = scene.clone();
            violent.params.mode = mode;
            let calm_run = time_steps(&calm(&violent), steps);
            let violent_run = time_steps(&violent, steps);
            let calm_median = (quantile(&calm_run.wall, 0.5), quantile(&calm_run.cpu, 0.5));
            for (motion, run) in [("calm", &calm_run), ("violent", &violent_run)] {
                let max = |v: &[f64]| v.last().copied().unwrap_or(f64::NAN);
                let ratio = if motion == "violent" {
                    format!(
                        "{:.2}, {:.2}",
                        max(&run.wall) / calm_median.0,
                        max(&run.cpu) / calm_median.1
                    )
                } else {
                    String::new()
                };
                println!(
                    "{:<14} {:<10} {:<8} {:>9.2} {:>9.2} {:>10.2} {:>9.2} {:>9.2} {:>10.2} {:>8}  {ratio}",
                    name,
                    mode.name(),
                    motion,
                    quantile(&run.wall, 0.5),
                    quantile(&run.wall, 0.99),
                    max(&run.wall),
                    quantile(&run.cpu, 0.5),
                    quantile(&run.cpu, 0.99),
                    max(&run.cpu),
                    run.rolled_back
                );
            }
        }
    }
}
