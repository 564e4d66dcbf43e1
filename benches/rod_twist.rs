//! Kmoch 2009 Table 2 — the cost of the quasistatic twist alone, Newton (BWR08, to 1e-6 rad
//! with at most 10 iterations) against the hair-optimised twist (Sec. 6.2), on 1×30 and 3×30
//! nodes — plus the elastic forces per strand (divide by 30 for per node) and the full step of
//! a 50×30 head with bending and twist. Goal: hair-optimised ≤ 0.3× Newton's time.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use hairsim_core::effects::{Effect, Effects};
use hairsim_core::params::{Params, TwistMethod};
use hairsim_core::rod::energy::{elastic_forces, RodFrames};
use hairsim_core::rod::twist::{hair_optimised_twist, newton_twist, NewtonSettings};
use hairsim_core::rod::{ClampedSegments, ElasticTerms};
use hairsim_core::{Libm, Material, Pose, StepInput, Strand, Vec3, World};
use std::hint::black_box;

const NODES: usize = 30;

/// A wavy rest strand of 1 cm segments, and a bent, swung copy of it as the current state
/// (what the twist sees mid-simulation).
fn strand(seed: usize) -> (Strand<NODES>, [Vec3; NODES]) {
    let phase = seed as f32 * 0.7;
    let rest: [Vec3; NODES] = core::array::from_fn(|i| {
        let s = i as f32;
        Vec3::new(
            0.003 * (0.8 * s + phase).sin(),
            -0.0095 * s,
            0.003 * (0.8 * s + phase).cos(),
        )
    });
    let strand = Strand::from_polyline(&rest, &Material::HUMAN_HAIR).expect("valid strand");
    let bent: [Vec3; NODES] = core::array::from_fn(|i| {
        let s = i as f32 * 0.01;
        rest[i] + Vec3::new(0.4 * s * s, 0.0, 0.2 * s * s * s)
    });
    (strand, bent)
}

fn frames(strand: &Strand<NODES>, bent: &[Vec3; NODES]) -> RodFrames<Libm, NODES> {
    RodFrames::compute(bent, strand.state.root_frame, &strand.rest.rod.rest_length)
}

fn twist_table_2(c: &mut Criterion) {
    let mut group = c.benchmark_group("Kmoch Table 2: twist");
    for strands in [1usize, 3] {
        let set: Vec<_> = (0..strands)
            .map(|k| {
                let (s, bent) = strand(k);
                let f = frames(&s, &bent);
                (s, f)
            })
            .collect();
        let clamped = ClampedSegments::ROOT_ONLY;
        let label = format!("{strands}x{NODES}");
        group.bench_function(BenchmarkId::new("hair-optimised", &label), |b| {
            b.iter(|| {
                for (s, f) in &set {
                    let mut theta = s.state.theta;
                    hair_optimised_twist(
                        f,
                        &s.rest.rod,
                        &clamped,
                        ElasticTerms::ALL,
                        &mut theta[..NODES - 1],
                    );
                    black_box(theta);
                }
            })
        });
        group.bench_function(BenchmarkId::new("newton 1e-6 rad, <= 10 it", &label), |b| {
            b.iter(|| {
                for (s, f) in &set {
                    let mut theta = s.state.theta;
                    let outcome = newton_twist(
                        f,
                        &s.rest.rod,
                        &clamped,
                        ElasticTerms::ALL,
                        NewtonSettings {
                            iterations: 10,
                            tolerance: 1e-6,
                            fixed_cost: false,
                        },
                        &mut theta[..NODES - 1],
                    );
                    black_box((theta, outcome));
                }
            })
        });
    }
    group.finish();
}

fn elastic_force_cost(c: &mut Criterion) {
    let (s, bent) = strand(0);
    let clamped = ClampedSegments::ROOT_ONLY;
    c.bench_function("elastic forces, 1x30 nodes (frames + forces)", |b| {
        b.iter(|| {
            let f = frames(&s, black_box(&bent));
            let mut forces = [Vec3::ZERO; NODES];
            elastic_forces(
                &f,
                &s.state.theta,
                &s.rest.rod,
                &clamped,
                ElasticTerms::ALL,
                &mut forces,
            );
            black_box(forces)
        })
    });
}

/// 50 strands of 30 nodes rooted on a 9 cm head, gravity, bending and twist.
fn head_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("rod step 50x30");
    for twist in [TwistMethod::HairOptimised, TwistMethod::Newton] {
        let mut params = Params {
            effects: Effects::from_slice(&[Effect::Gravity, Effect::Bending, Effect::Twist]),
            ..Params::DEFAULT
        };
        params.rod.twist = twist;
        let mut world: Box<World<50, NODES, Libm>> = Box::default();
        world.configure(params).expect("valid params");
        for k in 0..50 {
            let a = k as f32 * 0.4;
            let normal = Vec3::new(a.cos() * 0.8, 0.5, a.sin() * 0.8).normalize();
            let points: [Vec3; NODES] = core::array::from_fn(|i| normal * (0.09 + 0.01 * i as f32));
            world
                .add_strand(Strand::from_polyline(&points, &Material::HUMAN_HAIR).expect("valid"))
                .expect("capacity");
        }
        let input = StepInput {
            head: Pose::IDENTITY,
            accelerations: None,
        };
        // Let the strands fall into a bent state first.
        for _ in 0..200 {
            world.step(&input);
        }
        group.bench_function(twist.name(), |b| b.iter(|| world.step(black_box(&input))));
    }
    group.finish();
}

criterion_group!(benches, twist_table_2, elastic_force_cost, head_step);
criterion_main!(benches);
