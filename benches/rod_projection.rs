//! Kmoch 2009 Table 3: the time of the constraint enforcement (fast manifold projection) with
//! and without hair–head collisions, on 1 and 50 strands of 30 nodes draped on a head shaking
//! at 10 rad/s. Goal: collisions add at most 5 % to the projection.
//!
//! The strands are in motion, not settled: the scene runs 300 steps of shaking first, then 16
//! consecutive steps are captured *before* their projection (after integration and root
//! coupling) and the benchmark projects clones of them in turn. The iterations each variant
//! needs are printed once, since converge mode's cost follows them.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use hairsim_core::collide::{Collider, Shape};
use hairsim_core::context::StepContext;
use hairsim_core::{
    project_constraints, step_strands, Effect, Effects, Libm, Material, Mode, Params, Real, Shake,
    StepReport, Strand, Vec3,
};

const NODES: usize = 32;
const HEAD_RADIUS: Real = 0.1;
const WARM_UP_STEPS: u32 = 300;
const CAPTURED_STEPS: u32 = 16;

fn head() -> Collider {
    Collider {
        shape: Shape::Sphere {
            centre: Vec3::ZERO,
            radius: HEAD_RADIUS,
        },
        attached_to_head: true,
    }
}

fn params(effects: &[Effect], mode: Mode) -> Params {
    Params {
        effects: Effects::from_slice(effects),
        mode,
        ..Params::DEFAULT
    }
}

/// `count` strands of 30 nodes, 1 cm apart, rooted on the upper part of the head.
fn hair(count: usize) -> Vec<Strand<NODES>> {
    (0..count)
        .map(|s| {
            let azimuth = s as Real * 2.399; // golden angle: spread evenly
            let polar = 0.25 + 0.9 * (s as Real / count.max(1) as Real);
            let normal = Vec3::new(
                polar.sin() * azimuth.cos(),
                polar.cos(),
                polar.sin() * azimuth.sin(),
            );
            let root = normal * (HEAD_RADIUS + 0.001);
            let points: Vec<Vec3> = (0..30)
                .map(|i| root + normal * (0.01 * i as Real))
                .collect();
            Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
        })
        .collect()
}

fn context(params: &Params, k: u32) -> StepContext {
    let shake = Shake::TEN_RAD_PER_S;
    let before = shake.pose_at::<Libm>(k as Real * params.dt);
    let after = shake.pose_at::<Libm>((k + 1) as Real * params.dt);
    StepContext::new(params, before, after, &[head()])
}

/// Runs the shaking scene, then returns `CAPTURED_STEPS` unprojected states with the step
/// each belongs to.
fn predicted_states(count: usize) -> Vec<(u32, Vec<Strand<NODES>>)> {
    let full = params(
        &[Effect::Gravity, Effect::Inextensibility, Effect::Collisions],
        Mode::Converge,
    );
    // The same step with the projection's effects off: integration and root coupling only.
    let unconstrained = params(&[Effect::Gravity], Mode::Converge);
    let mut strands = hair(count);
    let mut report = StepReport::default();
    for k in 0..WARM_UP_STEPS {
        step_strands::<Libm, NODES>(&context(&full, k), &mut strands, 0, &[], None, &mut report);
    }
    let mut captured = Vec::new();
    for k in WARM_UP_STEPS..WARM_UP_STEPS + CAPTURED_STEPS {
        let mut predicted = strands.clone();
        step_strands::<Libm, NODES>(
            &context(&unconstrained, k),
            &mut predicted,
            0,
            &[],
            None,
            &mut report,
        );
        captured.push((k, predicted));
        step_strands::<Libm, NODES>(&context(&full, k), &mut strands, 0, &[], None, &mut report);
    }
    captured
}

fn project_all(strands: &mut [Strand<NODES>], ctx: &StepContext) -> StepReport {
    let mut report = StepReport::default();
    for (s, strand) in strands.iter_mut().enumerate() {
        project_constraints::<Libm, NODES>(strand, ctx, &[], s as u32, &mut report);
    }
    report
}

fn table_3(c: &mut Criterion) {
    let mut group = c.benchmark_group("rod_projection");
    for count in [1usize, 50] {
        let states = predicted_states(count);
        for mode in [Mode::Converge, Mode::FixedCost] {
            for collisions in [false, true] {
                let effects: &[Effect] = if collisions {
                    &[Effect::Gravity, Effect::Inextensibility, Effect::Collisions]
                } else {
                    &[Effect::Gravity, Effect::Inextensibility]
                };
                let p = params(effects, mode);
                let contexts: Vec<StepContext> =
                    states.iter().map(|(k, _)| context(&p, *k)).collect();
                // Iterations and contacts over the captured steps, printed once.
                let (mut iterations, mut contacts, mut cap_hits) = (0, 0, 0);
                for ((_, strands), ctx) in states.iter().zip(&contexts) {
                    let report = project_all(&mut strands.clone(), ctx);
                    iterations += report.iterations_total;
                    contacts += report.contacts;
                    cap_hits += report.cap_hits;
                }
                let name = format!(
                    "{count}x30/{}/{}",
                    mode.name(),
                    if collisions {
                        "collisions"
                    } else {
                        "no-collisions"
                    }
                );
                eprintln!(
                    "{name}: {:.2} iterations per strand-step, {:.1} contacts per step, {cap_hits} cap hits",
                    f64::from(iterations) / (count as f64 * f64::from(CAPTURED_STEPS)),
                    f64::from(contacts) / f64::from(CAPTURED_STEPS),
                );
                let mut next = 0;
                group.bench_function(name, |b| {
                    b.iter_batched_ref(
                        || {
                            next = (next + 1) % states.len();
                            (states[next].1.clone(), next)
                        },
                        |(strands, i)| black_box(project_all(strands, &contexts[*i])),
                        BatchSize::SmallInput,
                    )
                });
            }
        }
    }
    group.finish();
}

criterion_group!(benches, table_3);
criterion_main!(benches);
