//! Arbitrary rest polylines, initial velocities and head poses through `Strand::from_polyline`
//! and `World::step`: building either succeeds or returns an error (never panics), and a step
//! never panics and never leaves a non-finite value in the state.
#![no_main]

use arbitrary::Arbitrary;
use hairsim_core::{
    Effect, Effects, Libm, Material, Params, Pose, Quat, StepInput, Strand, Vec3, World,
};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Input {
    points: Vec<[f32; 3]>,
    velocities: Vec<[f32; 3]>,
    effects: u16,
    head: [f32; 7],
    accelerations: Vec<[f32; 3]>,
    steps: u8,
}

const N: usize = 32;

fuzz_target!(|input: Input| {
    let points: Vec<Vec3> = input
        .points
        .iter()
        .take(N + 2)
        .map(|p| Vec3::from_array(*p))
        .collect();
    let Ok(mut strand) = Strand::<N>::from_polyline(&points, &Material::HUMAN_HAIR) else {
        return;
    };
    for (v, w) in strand.state.velocity.iter_mut().zip(&input.velocities) {
        *v = Vec3::from_array(*w);
    }
    let effects = Effect::ALL
        .into_iter()
        .filter(|e| input.effects & (1 << *e as u8) != 0)
        .fold(Effects::NONE, Effects::with);
    let params = Params {
        effects,
        ..Params::DEFAULT
    };
    let Ok(mut world) = World::<1, N, Libm>::with_params(params) else {
        return;
    };
    let start_finite = strand.is_finite();
    world.add_strand(strand).unwrap();
    let h = input.head;
    let head = Pose {
        position: Vec3::new(h[0], h[1], h[2]),
        rotation: Quat::from_xyzw(h[3], h[4], h[5], h[6]).normalize(),
    };
    let accelerations: Vec<Vec3> = input
        .accelerations
        .iter()
        .map(|a| Vec3::from_array(*a))
        .collect();
    for _ in 0..input.steps.min(64) {
        world.step(&StepInput {
            head,
            accelerations: Some(&accelerations),
        });
        if start_finite {
            assert!(
                world.strands()[0].is_finite(),
                "a step let a non-finite value out"
            );
        }
    }
});
