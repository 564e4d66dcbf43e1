//! Vertex-steps per second of whole harness steps (`hairsim::sim::Sim`) on the sizes of
//! Sánchez-Banderas 2015 Table 1 — Mannequin A and B (the built-in scenes), and scalps with the
//! strand and vertex counts of Horse Louis, Bunny and Hectroll — for DFTL, DFTL + shape and
//! DFTL + shape + hair–hair, on one and two threads, with the split of the SPH stage's time among
//! hash, sort (counting sort + rearranging), neighbour search (with density) and forces.
//!
//! Each configuration runs half a second of warm-up (the hair leaves its combed start and the
//! neighbour lists reach their working size), then times `STEPS` steps — enough for the
//! candidate lists' rebuilds to be counted at their rate — by the wall clock and by the
//! process's CPU time (`/proc/self/stat`; on a shared machine the CPU figure is the steadier).
//! The SPH line gives the stage's split, its rebuilds per 100 steps and the particles with a
//! candidate.
//!
//! `cargo bench -p hairsim-benches --bench sph` (everything), or picking scenes, columns and
//! thread counts by name: `cargo bench -p hairsim-benches --bench sph -- mannequin-a
//! dftl+shape+hair-hair 2t`; `dt=0.001` runs the scenes at another step (1 ms, the
//! project's rate) than their own 1/60 s. With `stage`, the SPH stage alone on the picked sizes (after the
//! warm-up, its accelerations computed again and again on one state, on one and two threads:
//! the fastest of `STAGE_REPEATS` per phase — the least disturbed by other processes — and the
//! CPU time of all of them). With `moves`, the share of nodes that move more than `h / 2`, `h`
//! and `2 h` in one step after the warm-up, in the head's frame. Under `cargo test --benches`
//! each configuration of the two smallest sizes runs two steps.

use std::time::{Duration, Instant};

use hairsim::sim::{scene_inputs, Sim, StepInputs};
use hairsim_benches::cpu_seconds;
use hairsim_benches::table1::{scene, Size, COLUMNS, SIZES};
use hairsim_core::DefaultMath;

/// Seconds of the scene before timing.
const WARM_UP_SECONDS: f32 = 0.5;
/// Steps timed.
const STEPS: u64 = 300;

/// Times the SPH stage runs on one state with `stage`.
const STAGE_REPEATS: usize = 15;

/// How a run goes: the step (the scene's own when `None`), steps of warm-up and timed.
#[derive(Clone, Copy)]
struct Timing {
    dt: Option<f32>,
    warm_up: u64,
    steps: u64,
}

fn run<const N: usize>(size: &Size, column: &str, threads: usize, timing: Timing) {
    let Timing { dt, warm_up, steps } = timing;
    let prepared = scene(size, column, dt);
    let inputs: Vec<StepInputs> = (0..warm_up + steps)
        .map(|k| scene_inputs::<DefaultMath>(&prepared, k))
        .collect();
    let mut sim = Sim::<N, DefaultMath>::new(&prepared, threads).unwrap();
    let vertices = prepared.nodes();
    let (wall, cpu, split) = sim.in_pool(|sim| {
        for i in &inputs[..warm_up as usize] {
            sim.step(i);
        }
        let before = sim.sph.as_ref().map(|s| s.stats.clone());
        let (cpu0, wall0) = (cpu_seconds(), Instant::now());
        for i in &inputs[warm_up as usize..] {
            sim.step(i);
        }
        let (wall, cpu) = (wall0.elapsed().as_secs_f64(), cpu_seconds() - cpu0);
        let split = sim.sph.as_ref().zip(before).map(|(sph, b)| {
            let s = &sph.stats;
            let ms = |t: Duration| t.as_secs_f64() * 1e3 / steps as f64;
            format!(
                "  sph ms/step: hash {:.3}, sort {:.3}, neighbours {:.3}, forces {:.3}; {:.2} neighbours/node (cap {}, {:.1} dropped/node, most found {}); {:.1} rebuilds per 100 steps, {:.3} active/node, {:.2} candidates/node",
                ms(s.time_hash - b.time_hash),
                ms(s.time_sort - b.time_sort),
                ms(s.time_neighbours - b.time_neighbours),
                ms(s.time_forces - b.time_forces),
                (s.neighbours - b.neighbours) as f64 / (steps as f64 * vertices as f64),
                sph.params().neighbour_cap,
                (s.truncated - b.truncated) as f64 / (steps as f64 * vertices as f64),
                s.max_neighbours_found,
                (s.rebuilds - b.rebuilds) as f64 * 100.0 / steps as f64,
                (s.active - b.active) as f64 / (steps as f64 * vertices as f64),
                (s.candidates - b.candidates) as f64 / (steps as f64 * vertices as f64),
            )
        });
        (wall, cpu, split)
    });
    assert!(sim.is_finite(), "{} {column}: not finite", size.name);
    let work = vertices as f64 * steps as f64 / 1e6;
    println!(
        "{:<12} {:>8} vertices {:<16} {} thread(s): {:>7.2} M vertex-steps/s wall, {:>7.2} M/CPU-s, {:>8.3} ms/step, dt {:.4} s{}",
        size.name,
        vertices,
        column,
        threads,
        work / wall,
        work / cpu.max(0.01),
        wall * 1e3 / steps as f64,
        prepared.params.dt,
        split.unwrap_or_default()
    );
}

/// The SPH stage alone on `size`'s warmed-up state, on one and two threads.
fn stage<const N: usize>(size: &Size, warm_up: u64, repeats: usize) {
    let prepared = scene(size, "dftl+shape+hair-hair", None);
    let mut sim = Sim::<N, DefaultMath>::new(&prepared, 2).unwrap();
    sim.in_pool(|sim| {
        for k in 0..warm_up {
            sim.step(&scene_inputs::<DefaultMath>(&prepared, k));
        }
    });
    let dt = prepared.params.dt;
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut sph = sim.sph.clone().unwrap();
        let (strands, head) = (&sim.strands, sim.head);
        let (phases, cpu, wall) = pool.install(|| {
            sph.accelerations(strands, dt, head);
            let mut phases = [f64::INFINITY; 5];
            let (cpu0, wall0) = (cpu_time::ProcessTime::now(), Instant::now());
            for _ in 0..repeats {
                let b = sph.stats.clone();
                let t = Instant::now();
                sph.accelerations(strands, dt, head);
                let total = t.elapsed();
                let s = &sph.stats;
                let times = [
                    s.time_hash - b.time_hash,
                    s.time_sort - b.time_sort,
                    s.time_neighbours - b.time_neighbours,
                    s.time_forces - b.time_forces,
                    total,
                ];
                for (p, t) in phases.iter_mut().zip(times) {
                    *p = p.min(t.as_secs_f64() * 1e3);
                }
            }
            (
                phases,
                cpu0.elapsed().as_secs_f64(),
                wall0.elapsed().as_secs_f64(),
            )
        });
        let per = |t: f64| t * 1e3 / repeats as f64;
        println!(
            "{:<12} {:>8} vertices SPH stage {} thread(s): fastest ms: hash {:.2}, sort {:.2}, neighbours {:.2}, forces {:.2}, all {:.2}; mean {:.2} ms wall, {:.2} ms CPU",
            size.name,
            prepared.nodes(),
            threads,
            phases[0],
            phases[1],
            phases[2],
            phases[3],
            phases[4],
            per(wall),
            per(cpu),
        );
    }
}

/// How far `size`'s nodes move in one step in the head's frame, after the warm-up: the share
/// moving more than `h / 2`, `h` and `2 h`. A list kept with a skin lasts a step only while no
/// node moves half its skin: the share says how much of the search any skin, or an
/// incremental rebuild of the nodes that moved, could save at the scene's step.
fn moves<const N: usize>(size: &Size, dt: Option<f32>, warm_up: u64) {
    let prepared = scene(size, "dftl+shape+hair-hair", dt);
    let mut sim = Sim::<N, DefaultMath>::new(&prepared, 2).unwrap();
    let h = sim.sph.as_ref().unwrap().params().smoothing_length;
    let positions = |sim: &Sim<N, DefaultMath>| -> Vec<hairsim_core::Vec3> {
        let (turn, at) = (sim.head.rotation.inverse(), sim.head.position);
        sim.strands
            .iter()
            .flat_map(|s| {
                s.state.position[..s.nodes()]
                    .iter()
                    .map(move |&x| turn * (x - at))
            })
            .collect()
    };
    sim.in_pool(|sim| {
        for k in 0..warm_up {
            sim.step(&scene_inputs::<DefaultMath>(&prepared, k));
        }
    });
    let before = positions(&sim);
    sim.in_pool(|sim| sim.step(&scene_inputs::<DefaultMath>(&prepared, warm_up)));
    let after = positions(&sim);
    let share = |limit: f32| {
        let far = before
            .iter()
            .zip(&after)
            .filter(|(a, b)| a.distance(**b) > limit)
            .count();
        100.0 * far as f64 / before.len().max(1) as f64
    };
    println!(
        "{:<12} {:>8} vertices, dt {:.4} s: nodes moving more than h/2, h, 2h in a step in the head's frame: {:.1} %, {:.1} %, {:.1} % (h {} mm)",
        size.name,
        after.len(),
        prepared.params.dt,
        share(h / 2.0),
        share(h),
        share(2.0 * h),
        h * 1e3,
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--list") {
        return;
    }
    // `cargo bench` passes `--bench`; `cargo test --benches` does not: then the two smallest
    // sizes run two steps each, as a test that the benchmark works, not a measurement.
    let quick = !args.iter().any(|a| a == "--bench");
    let filter: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let number = |name: &str| {
        filter
            .iter()
            .find_map(|f| f.strip_prefix(name)?.parse::<f64>().ok())
    };
    let dt = number("dt=").map(|dt| dt as f32);
    let warm_up = (WARM_UP_SECONDS / dt.unwrap_or(1.0 / 60.0)).round() as u64;
    let (warm_up, steps) = if quick { (1, 1) } else { (warm_up, STEPS) };
    let timing = Timing { dt, warm_up, steps };
    for size in SIZES {
        if quick && size.strands * size.nodes > 10_000 {
            continue;
        }
        let picked = |name: &str, all: &[&str]| {
            let named: Vec<&&String> = filter
                .iter()
                .filter(|f| all.contains(&f.as_str()))
                .collect();
            named.is_empty() || named.iter().any(|f| f.as_str() == name)
        };
        if !picked(size.name, &SIZES.iter().map(|s| s.name).collect::<Vec<_>>()) {
            continue;
        }
        if filter.iter().any(|f| f.as_str() == "moves") {
            match size.nodes {
                0..=16 => moves::<16>(size, dt, warm_up),
                _ => moves::<32>(size, dt, warm_up),
            }
            continue;
        }
        if filter.iter().any(|f| f.as_str() == "stage") {
            let repeats = if quick { 1 } else { STAGE_REPEATS };
            // `warm-up=K` and `repeats=R` (for a run under a profiler or valgrind).
            let warm_up = number("warm-up=").map_or(warm_up, |w| w as u64);
            let repeats = number("repeats=").map_or(repeats, |r| r as usize);
            match size.nodes {
                0..=16 => stage::<16>(size, warm_up, repeats),
                _ => stage::<32>(size, warm_up, repeats),
            }
            continue;
        }
        for column in COLUMNS {
            if !picked(column, COLUMNS) {
                continue;
            }
            for threads in [1, 2] {
                if !picked(&format!("{threads}t"), &["1t", "2t"]) {
                    continue;
                }
                match size.nodes {
                    0..=16 => run::<16>(size, column, threads, timing),
                    _ => run::<32>(size, column, threads, timing),
                }
            }
        }
    }
}
