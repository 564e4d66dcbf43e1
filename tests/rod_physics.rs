//! The rod against independent physics (issue 4's tests): a clamped strand sagging under its
//! own weight against Euler–Bernoulli beam theory, and the energy of a swinging strand with
//! and without air drag.

use hairsim_core::rod::energy::{elastic_energy, RodFrames};
use hairsim_core::rod::twist::TwistMethod;
use hairsim_core::rod::ElasticTerms;
use hairsim_core::{Effect, Effects, Libm, Material, Params, Pose, StepInput, Strand, Vec3, World};

const N: usize = 40;
type RodWorld = World<1, N, Libm>;

fn effects(list: &[Effect]) -> Effects {
    list.iter().fold(Effects::NONE, |e, &x| e.with(x))
}

fn still() -> StepInput<'static> {
    StepInput {
        head: Pose::IDENTITY,
        accelerations: None,
    }
}

/// A horizontal strand of `nodes` nodes `h` apart along +x from the origin.
fn horizontal(nodes: usize, h: f32) -> Vec<Vec3> {
    (0..nodes)
        .map(|i| Vec3::new(h * i as f32, 0.0, 0.0))
        .collect()
}

#[test]
fn clamped_strand_sags_as_an_euler_bernoulli_cantilever() {
    // 100× human hair (α = 7.04e-7 N·m²), 33 nodes 2 mm apart, nodes 0 and 1 held level
    // (the clamp), gravity. Euler–Bernoulli: tip deflection w L⁴ / (8 EI) with w = ρA g and L
    // the free length from the discrete clamp's effective position, the middle of the first
    // segment (`docs/architecture.md`, Kmoch Sec. 8.1), here 63 mm: 1.0e-4 m, 0.16 % of L — small deflection. dt = 0.1 ms
    // (94 fixed substeps: 2 mm segments of stiff hair), air drag 5e-6 kg/s per node (near
    // critical for the first mode, 46 Hz) settles it within 0.3 s.
    let (nodes, h) = (33, 0.002);
    let material = Material {
        youngs_modulus: Material::HUMAN_HAIR.youngs_modulus * 100.0,
        ..Material::HUMAN_HAIR
    };
    for twist in [TwistMethod::HairOptimised, TwistMethod::Newton] {
        let mut params = Params {
            dt: 1.0e-4,
            effects: effects(&[
                Effect::Gravity,
                Effect::Drag,
                Effect::Bending,
                Effect::Twist,
                Effect::Inextensibility,
            ]),
            drag: 5.0e-6,
            ..Params::DEFAULT
        };
        params.rod.twist = twist;
        params.rod.projection_tolerance = 1.0e-7;
        params.rod.projection_iterations = 20;
        let mut world = RodWorld::with_params(params).unwrap();
        let strand = Strand::from_polyline(&horizontal(nodes, h), &material).unwrap();
        params.validate_strand(&strand).unwrap();
        world.add_strand(strand).unwrap();
        let mut tip = Vec::new();
        for _ in 0..3000 {
            world.step(&still());
            tip.push(world.strands()[0].positions()[nodes - 1].y);
        }
        // Settled: the tip moved by < 0.1 % of its deflection over the last 0.05 s.
        let last = &tip[tip.len() - 500..];
        let (lo, hi) = last
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &y| (a.min(y), b.max(y)));
        let deflection = -f64::from(*tip.last().unwrap());
        assert!(
            f64::from(hi - lo) < 1e-3 * deflection,
            "not settled: {lo} … {hi}"
        );
        let w = f64::from(material.linear_density()) * 9.81;
        let ei = f64::from(material.bending_stiffness());
        let length = f64::from(h) * (nodes as f64 - 1.5);
        let beam = w * length.powi(4) / (8.0 * ei);
        let error = deflection / beam - 1.0;
        println!(
            "{twist:?}: tip deflection {deflection:.4e} m, Euler–Bernoulli {beam:.4e} m, error {:+.2} %",
            100.0 * error
        );
        assert!(error.abs() < 0.02, "{twist:?}: {:+.2} %", 100.0 * error);
    }
}

/// Total energy of the strand: kinetic + gravitational (height × weight) + elastic.
fn energy(world: &RodWorld) -> f64 {
    let strand = &world.strands()[0];
    let n = strand.nodes();
    let mut e = 0.0f64;
    for i in 2..n {
        let m = f64::from(strand.rest.mass[i]);
        let v = strand.state.velocity[i];
        e += 0.5 * m * f64::from(v.dot(v)) + m * 9.81 * f64::from(strand.state.position[i].y);
    }
    let frames = RodFrames::<Libm, N>::compute(
        &strand.state.position[..n],
        strand.state.root_frame,
        &strand.rest.rod.rest_length,
    );
    e + f64::from(elastic_energy(
        &frames,
        &strand.state.theta[..n - 1],
        &strand.rest.rod,
        ElasticTerms::ALL,
    ))
}

/// A 20-node human hair released horizontally: its total energy every step for `steps`.
fn swing(drag: f32, twist: TwistMethod, steps: usize) -> Vec<f64> {
    let mut params = Params {
        effects: effects(&[
            Effect::Gravity,
            Effect::Drag,
            Effect::Bending,
            Effect::Twist,
            Effect::Inextensibility,
        ]),
        drag,
        ..Params::DEFAULT
    };
    params.rod.twist = twist;
    let mut world = RodWorld::with_params(params).unwrap();
    world
        .add_strand(Strand::from_polyline(&horizontal(20, 0.01), &Material::HUMAN_HAIR).unwrap())
        .unwrap();
    let mut energies = vec![energy(&world)];
    for _ in 0..steps {
        let report = world.step(&still());
        assert_eq!(report.rolled_back, 0);
        energies.push(energy(&world));
    }
    energies
}

#[test]
fn with_drag_the_energy_envelope_never_increases() {
    // Air drag 2e-7 kg/s per node (the firmware scene's), no input, 3 s. Envelope: the maximum
    // of the energy over consecutive windows of 100 steps (0.1 s; symplectic Euler's O(dt)
    // oscillation follows the swing, so a window of a few steps does not cover it: with 50
    // steps the envelope rose once by 1.9e-12 J, 2e-6 of the releasable 1.04e-6 J). Each
    // window's maximum must not exceed the previous one's. Measured: every rise ≤ −2.7e-14 J.
    for twist in [TwistMethod::HairOptimised, TwistMethod::Newton] {
        let energies = swing(2.0e-7, twist, 3000);
        let envelope: Vec<f64> = energies
            .chunks(200)
            .map(|w| w.iter().copied().fold(f64::MIN, f64::max))
            .collect();
        let worst_rise = envelope
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::MIN, f64::max);
        println!(
            "{twist:?}: energy {:.4e} J → {:.4e} J, largest envelope rise {worst_rise:.3e} J",
            energies[0],
            energies.last().unwrap()
        );
        assert!(
            worst_rise <= 0.0,
            "{twist:?}: the envelope rose by {worst_rise:e} J"
        );
        assert!(energies.last().unwrap() < &energies[0]);
    }
}

#[test]
fn without_drag_a_swinging_strand_keeps_its_energy_within_a_bound() {
    // No drag, no input, 3 s. The projection removes the energy of the motion along the
    // constraints (the manifold projection with `v += Δx/h` is dissipative), and symplectic
    // Euler oscillates by O(dt): the energy must never rise above its start by more than 1 %
    // of the energy the strand can release (start minus hanging straight down, 1.04e-6 J),
    // nor fall below hanging. Measured: never above the start; down by 48 % of the releasable
    // energy after 3 s (the projection's dissipation).
    for twist in [TwistMethod::HairOptimised, TwistMethod::Newton] {
        let energies = swing(0.0, twist, 3000);
        let start = energies[0];
        let lowest_possible = {
            // Hanging straight down: Σ m g y with y = −(i − 1) h for node i ≥ 2.
            let material = Material::HUMAN_HAIR;
            let m = f64::from(material.linear_density()) * 0.01;
            (2..20)
                .map(|i| {
                    let mass = if i == 19 { m / 2.0 } else { m };
                    -mass * 9.81 * 0.01 * (i as f64 - 1.0)
                })
                .sum::<f64>()
        };
        let scale = start - lowest_possible;
        let highest = energies.iter().copied().fold(f64::MIN, f64::max);
        let lowest = energies.iter().copied().fold(f64::MAX, f64::min);
        println!(
            "{twist:?}: start {start:.4e} J, highest {:+.3e} of the releasable {scale:.3e} J, lowest {:+.3e}",
            (highest - start) / scale,
            (lowest - start) / scale
        );
        assert!(
            highest - start <= 0.01 * scale,
            "{twist:?}: rose to {highest:e} J"
        );
        assert!(
            lowest >= lowest_possible - 0.01 * scale,
            "{twist:?}: fell to {lowest:e} J"
        );
    }
}
