//! Kmoch 2009 Table 1: ms per full rod step of the papers' scenes (the harness's built-in
//! `stand-1` … `stand-3`, `head-1` … `head-3`: leaders only, one thread), plus the firmware
//! scene's step.
//!
//! A settled scene converges in no iterations and proves nothing, so every scene is measured
//! in motion: the heads shake at 10 rad/s, and so do the stands (they start horizontal and
//! would otherwise settle while criterion samples). Each scene is
//! first run `WARM_UP_STEPS` steps (the hair is swinging by then), then criterion times the
//! next steps one at a time (state carried on, never reset: each sample is a step of the
//! moving scene). The projection iterations of those steps (mean and max per strand) are
//! printed once per scene, since converge mode's cost follows them.
//!
//! Goals (issue 4): Head #1 ≤ 0.25 ms per step, Stand #1 ≤ 0.015 ms, on one core.
//! `cargo bench -p hairsim-benches --bench step` (CI's `cargo test --benches` runs each case
//! once).

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use hairsim::builtin;
use hairsim::scene::Prepared;
use hairsim::sim::{scene_inputs, Layout, Sim};
use hairsim_core::params::TwistMethod;
use hairsim_core::scenes::firmware;
use hairsim_core::{Libm, StepReport, World};

/// Node capacity of the rod scenes (30 nodes per leader).
const NODES: usize = 32;
/// Steps run before measuring: the stands have fallen half-way, the heads swing.
const WARM_UP_STEPS: u64 = 150;
/// Steps whose iterations are counted for the printed line.
const COUNTED_STEPS: u64 = 200;

const SCENES: [&str; 6] = [
    "stand-1", "stand-2", "stand-3", "head-1", "head-2", "head-3",
];

/// The built-in scene `name`; the stands (no head of their own) get the heads' 10 rad/s
/// shake, so that they stay in motion however many steps criterion takes.
fn prepared(name: &str) -> Prepared {
    let build = |name| (builtin::find(name).expect("built-in scene").scene)();
    let mut scene = build(name);
    if scene.head.is_none() {
        scene.head = build("head-1").head;
    }
    scene.prepare().expect("valid built-in scene")
}

/// A one-thread simulation of `prepared` after `steps` steps.
fn warmed_up(prepared: &Prepared, steps: u64) -> Sim<NODES, Libm> {
    warmed_up_in(prepared, steps, Layout::Blocks)
}

/// [`warmed_up`], stepping the strands in `layout`.
fn warmed_up_in(prepared: &Prepared, steps: u64, layout: Layout) -> Sim<NODES, Libm> {
    let mut sim = Sim::<NODES, Libm>::with_layout(prepared, 1, layout).expect("scene builds");
    for k in 0..steps {
        sim.step(&scene_inputs::<Libm>(prepared, k));
    }
    sim
}

fn rod_table_1(c: &mut Criterion) {
    let mut group = c.benchmark_group("Kmoch Table 1 (ms per step, leaders, one thread)");
    for name in SCENES {
        let prepared = prepared(name);
        // The iterations the measured steps take (converge mode: cost follows them).
        let mut probe = warmed_up(&prepared, WARM_UP_STEPS);
        let strands = probe.strands.len() as u64;
        let (mut total, mut max) = (0u64, 0u32);
        for k in WARM_UP_STEPS..WARM_UP_STEPS + COUNTED_STEPS {
            let report = probe.step(&scene_inputs::<Libm>(&prepared, k));
            total += u64::from(report.iterations_total);
            max = max.max(report.iterations_max);
        }
        println!(
            "{name}: {strands} strands, projection iterations per strand-step mean {:.2} max {max} \
             (steps {WARM_UP_STEPS}..{})",
            total as f64 / (strands * COUNTED_STEPS) as f64,
            WARM_UP_STEPS + COUNTED_STEPS
        );
        let mut sim = warmed_up(&prepared, WARM_UP_STEPS);
        let mut k = WARM_UP_STEPS;
        group.bench_function(name, |b| {
            b.iter(|| {
                let report = sim.step(&scene_inputs::<Libm>(&prepared, k));
                k += 1;
                report
            })
        });
    }
    group.finish();
}

/// Head #1 with ×10 and ×100 human bending stiffness (12 and 38 explicit substeps' worth, so
/// one linearly implicit bending step per strand, `core/src/rod/implicit.rs`): the step's cost
/// should stay near the human-hair figure whatever the stiffness.
fn stiff_hair(c: &mut Criterion) {
    let mut group = c.benchmark_group("Head #1, stiffer hair (ms per step, one thread)");
    for factor in [10.0f32, 100.0] {
        let mut scene = (builtin::find("head-1").expect("built-in scene").scene)();
        let mut material = scene.material.clone().unwrap_or_default();
        material.youngs_modulus = Some(3.5e9 * factor);
        scene.material = Some(material);
        let prepared = scene.prepare().expect("valid stiff scene");
        let mut sim = warmed_up(&prepared, WARM_UP_STEPS);
        let mut k = WARM_UP_STEPS;
        group.bench_function(format!("x{factor}"), |b| {
            b.iter(|| {
                let report = sim.step(&scene_inputs::<Libm>(&prepared, k));
                k += 1;
                report
            })
        });
    }
    group.finish();
}

fn firmware_step(c: &mut Criterion) {
    let mut world: Box<World<{ firmware::STRANDS }, { firmware::NODES }, Libm>> = Box::default();
    firmware::build(&mut world).unwrap();
    let mut k = 0u32;
    let mut report = StepReport::default();
    c.bench_function("firmware scene step", |b| {
        b.iter(|| {
            firmware::step(&mut world, k, &mut report);
            k = k.wrapping_add(1);
            report.max_stretch
        })
    });
}

/// Issue 22: the rod's blocks (strands in lanes, `Layout::Blocks`, the default) against one
/// strand at a time (`Layout::PerStrand`, the firmware's path) in the same run, Head #1 and
/// Stand #1 in motion as in Table 1. Goal: Head #1 in blocks at least 3× faster.
///
/// Both layouts step the same range of the motion, steps [`WARM_UP_STEPS`] to
/// [`WARM_UP_STEPS`] + [`MEASURED_RANGE`] over and over (a fresh warmed-up simulation, not
/// timed, each time round): stepped on for as long as criterion runs it, the faster layout
/// would reach further into the head's shake, with other contacts and other iteration counts
/// than the slower one, and the ratio would compare different steps.
fn rod_lanes(c: &mut Criterion) {
    let mut group = c.benchmark_group("Rod blocks against one strand at a time (ms per step)");
    let mut newton = prepared("head-1");
    newton.params.rod.twist = TwistMethod::Newton;
    let scenes = [
        ("head-1", prepared("head-1")),
        ("head-1 newton", newton),
        ("stand-1", prepared("stand-1")),
    ];
    for (name, prepared) in scenes {
        for (layout, label) in [
            (Layout::PerStrand, "per strand"),
            (Layout::Blocks, "blocks"),
        ] {
            group.bench_function(format!("{name} {label}"), |b| {
                b.iter_custom(|iterations| {
                    let mut measured = Duration::ZERO;
                    let mut done = 0;
                    while done < iterations {
                        let mut sim = warmed_up_in(&prepared, WARM_UP_STEPS, layout);
                        let steps = (iterations - done).min(MEASURED_RANGE);
                        let start = Instant::now();
                        for k in WARM_UP_STEPS..WARM_UP_STEPS + steps {
                            black_box(sim.step(&scene_inputs::<Libm>(&prepared, k)));
                        }
                        measured += start.elapsed();
                        done += steps;
                    }
                    measured
                })
            });
        }
    }
    group.finish();
}

/// The steps [`rod_lanes`] measures, again and again, after the warm-up.
const MEASURED_RANGE: u64 = 300;

criterion_group!(benches, rod_table_1, stiff_hair, firmware_step, rod_lanes);
criterion_main!(benches);
