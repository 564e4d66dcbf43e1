//! The material ranges (`hairsim_core::strand::MATERIAL_RANGES`) hold what they promise: at
//! every corner of them (each field at its least or its largest value), four strands of 16
//! nodes, 5 mm and 1 cm apart, sticking out of a head sphere shaking at 10 rad/s, step 300
//! times with each solver's preset (plus collisions) without a strand rolled back, every
//! value finite, every segment within its solver's stretch. Outside them a material is
//! refused by name.

use hairsim_core::strand::MATERIAL_RANGES;
use hairsim_core::{
    BuildError, Collider, Effect, Libm, Material, Params, Shake, Shape, Solver, StepInput, Strand,
    Vec3, World,
};

const N: usize = 16;

/// The corner `corner` (bit `k` picks field `k`'s largest value) of the ranges.
fn corner(corner: u32) -> Material {
    let v: [f32; 5] = core::array::from_fn(|k| {
        let range = &MATERIAL_RANGES[k];
        if corner & (1 << k) != 0 {
            range.most
        } else {
            range.least
        }
    });
    Material {
        youngs_modulus: v[0],
        shear_modulus: v[1],
        radius: v[2],
        density: v[3],
        minor_axis_penalty: v[4],
    }
}

/// Steps the shaking head 300 times; the strands rolled back and the largest free stretch.
fn shake(solver: Solver, material: &Material, segment: f32) -> (u32, f32) {
    let mut world = World::<4, N, Libm>::new();
    let params = Params::preset(solver);
    let effects = params.effects.with(Effect::Collisions);
    world.configure(Params { effects, ..params }).unwrap();
    world
        .add_collider(Collider {
            shape: Shape::Sphere {
                centre: Vec3::ZERO,
                radius: 0.05,
            },
            attached_to_head: true,
        })
        .unwrap();
    for side in [Vec3::X, Vec3::Z, -Vec3::X, -Vec3::Z] {
        let points: [Vec3; N] = core::array::from_fn(|i| {
            side * (0.05 + segment * i as f32) + Vec3::Y * (0.0001 * i as f32)
        });
        world
            .add_strand(Strand::from_polyline(&points, material).unwrap())
            .unwrap();
    }
    let (mut rolled_back, mut stretch) = (0, 0.0f32);
    for k in 0..300 {
        let head = Shake::TEN_RAD_PER_S.pose_at::<Libm>((k + 1) as f32 * 0.001);
        let report = world.step(&StepInput {
            head,
            accelerations: None,
        });
        rolled_back += report.rolled_back;
        stretch = stretch.max(report.max_stretch);
    }
    assert!(world.strands().iter().all(Strand::is_finite));
    (rolled_back, stretch)
}

#[test]
fn every_corner_of_the_ranges_steps_with_both_presets() {
    for solver in [Solver::Rod, Solver::Dftl] {
        for c in 0..32 {
            let material = corner(c);
            for segment in [0.005, 0.01] {
                let (rolled_back, stretch) = shake(solver, &material, segment);
                let case = format!("{solver:?} {material:?}, {segment} m");
                assert_eq!(rolled_back, 0, "{case}");
                assert!(stretch < 1.0e-3, "{case}: stretch {stretch}");
            }
        }
    }
}

#[test]
fn a_material_outside_its_ranges_is_refused_by_name() {
    let points: [Vec3; 4] = core::array::from_fn(|i| Vec3::new(0.01 * i as f32, 0.0, 0.0));
    for (k, range) in MATERIAL_RANGES.iter().enumerate() {
        for value in [range.least * 0.5, range.most * 2.0, f32::NAN, f32::INFINITY] {
            let mut v = [
                Material::HUMAN_HAIR.youngs_modulus,
                Material::HUMAN_HAIR.shear_modulus,
                Material::HUMAN_HAIR.radius,
                Material::HUMAN_HAIR.density,
                Material::HUMAN_HAIR.minor_axis_penalty,
            ];
            v[k] = value;
            let material = Material {
                youngs_modulus: v[0],
                shear_modulus: v[1],
                radius: v[2],
                density: v[3],
                minor_axis_penalty: v[4],
            };
            assert_eq!(
                Strand::<N>::from_polyline(&points, &material),
                Err(BuildError::InvalidMaterial {
                    field: range.field,
                    allowed: range.allowed
                }),
                "{} = {value}",
                range.field
            );
        }
    }
    // Human hair is inside every range.
    assert!(Material::HUMAN_HAIR.validate().is_ok());
}

#[test]
fn a_segment_too_long_is_named_as_one() {
    let far = [
        Vec3::ZERO,
        Vec3::new(0.01, 0.0, 0.0),
        Vec3::new(1.0e30, 0.0, 0.0),
    ];
    let long = Strand::<N>::from_polyline(&far, &Material::HUMAN_HAIR).unwrap_err();
    assert_eq!(long, BuildError::LongSegment { segment: 1 });
    assert_eq!(long.to_string(), "segment 1 is longer than 1 m");
    let near = [
        Vec3::ZERO,
        Vec3::new(0.01, 0.0, 0.0),
        Vec3::new(0.01, 1e-8, 0.0),
    ];
    let short = Strand::<N>::from_polyline(&near, &Material::HUMAN_HAIR).unwrap_err();
    assert_eq!(short, BuildError::DegenerateSegment { segment: 1 });
    assert_eq!(short.to_string(), "segment 1 is shorter than 0.000001 m");
}
