//! The DFTL step on arbitrary strands, parameters, head motion, colliders and accelerations:
//! never panics, never leaves a non-finite value in the state.
#![no_main]

use arbitrary::Arbitrary;
use hairsim_core::{
    Collider, Effect, Effects, Libm, Material, Params, Pose, Quat, Shape, Solver, StepInput,
    Strand, Vec3, World,
};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Input {
    strands: Vec<Vec<[f32; 3]>>,
    velocities: Vec<[f32; 3]>,
    effects: u16,
    coefficients: [f32; 4],
    spheres: Vec<([f32; 3], f32)>,
    head: Vec<[f32; 7]>,
    accelerations: Vec<[f32; 3]>,
}

const N: usize = 16;
const S: usize = 4;

fuzz_target!(|input: Input| {
    let effects = Effect::ALL
        .into_iter()
        .filter(|e| input.effects & (1 << *e as u8) != 0)
        .filter(|e| !matches!(e, Effect::Bending | Effect::Twist | Effect::Grabs))
        .fold(Effects::NONE, Effects::with);
    let mut params = Params {
        solver: Solver::Dftl,
        effects,
        ..Params::DEFAULT
    };
    let [damping, global, local, wind] = input.coefficients;
    params.dftl.damping = damping;
    params.dftl.global_shape = global;
    params.dftl.local_shape = local;
    params.wind.strength = wind;
    let Ok(mut world) = World::<S, N, Libm>::with_params(params) else {
        return;
    };
    for points in input.strands.iter().take(S) {
        let points: Vec<Vec3> = points
            .iter()
            .take(N)
            .map(|p| Vec3::from_array(*p))
            .collect();
        if let Ok(mut strand) = Strand::<N>::from_polyline(&points, &Material::HUMAN_HAIR) {
            for (v, w) in strand.state.velocity.iter_mut().zip(&input.velocities) {
                *v = Vec3::from_array(*w);
            }
            if strand.is_finite() {
                let _ = world.add_strand(strand);
            }
        }
    }
    for &(c, r) in input.spheres.iter().take(4) {
        let _ = world.add_collider(Collider {
            shape: Shape::Sphere {
                centre: Vec3::from_array(c),
                radius: r,
            },
            attached_to_head: true,
        });
    }
    let accelerations: Vec<Vec3> = input
        .accelerations
        .iter()
        .map(|a| Vec3::from_array(*a))
        .collect();
    for h in input.head.iter().take(64) {
        let head = Pose {
            position: Vec3::new(h[0], h[1], h[2]),
            rotation: Quat::from_xyzw(h[3], h[4], h[5], h[6]).normalize(),
        };
        world.step(&StepInput {
            head,
            accelerations: Some(&accelerations),
        });
        assert!(
            world.strands().iter().all(|s| s.is_finite()),
            "a step let a non-finite value out"
        );
    }
});
