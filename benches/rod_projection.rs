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
use hairsim_core::{Effect, Mode};

use hairsim_benches::table3::{context, params, predicted_states, project_all, CAPTURED_STEPS};
use hairsim_core::context::StepContext;

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
