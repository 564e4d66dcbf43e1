//! The fast manifold projection on arbitrary strands, constraints and colliders: finite in →
//! finite out, no panic, and the residual it reports is never lower than the true one.
//!
//! "Finite in" means a hair-sized scene: coordinates and radii within ±10 m (`LIMIT`). Far
//! beyond it `e·e` itself overflows f32; the fuzzer found NaN with 400 m segments inside 200 m
//! spheres (kept in `regressions/projection/huge-colliders-nan`). There the step's guard rolls
//! the strand back, so no NaN leaves `step()`.
#![no_main]

use arbitrary::Arbitrary;
use hairsim_core::context::StepContext;
use hairsim_core::projection::lanes::{project_strand, StrandProjection};
use hairsim_core::{
    Collider, Effect, Effects, Grab, Libm, Material, Mode, Params, Pose, Shape, StepReport, Strand,
    Vec3,
};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
enum FuzzShape {
    Sphere([f32; 3], f32),
    Capsule([f32; 3], [f32; 3], f32),
    Plane([f32; 3], [f32; 3]),
}

#[derive(Arbitrary, Debug)]
struct Input {
    rest: Vec<[f32; 3]>,
    /// Displacements of the state from rest (the "predicted" positions).
    moved: Vec<[f32; 3]>,
    shapes: Vec<FuzzShape>,
    grabs: Vec<(u8, [f32; 3], f32)>,
    inextensibility: bool,
    collisions: bool,
    fixed_cost: bool,
    iterations: u8,
    tolerance_exponent: u8,
}

const N: usize = 24;
/// Largest coordinate magnitude the target feeds in, m.
const LIMIT: f32 = 10.0;

fn in_range(v: [f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite() && c.abs() <= LIMIT)
}

fn shape(s: &FuzzShape) -> Shape {
    match *s {
        FuzzShape::Sphere(c, r) => Shape::Sphere {
            centre: Vec3::from_array(c),
            radius: r,
        },
        FuzzShape::Capsule(a, b, r) => Shape::Capsule {
            a: Vec3::from_array(a),
            b: Vec3::from_array(b),
            radius: r,
        },
        FuzzShape::Plane(p, n) => Shape::Plane {
            point: Vec3::from_array(p),
            normal: Vec3::from_array(n).normalize_or(Vec3::Y),
        },
    }
}

fuzz_target!(|input: Input| {
    let shapes_ok = input.shapes.iter().all(|s| match s {
        FuzzShape::Sphere(c, r) => in_range(*c) && r.abs() <= LIMIT,
        FuzzShape::Capsule(a, b, r) => in_range(*a) && in_range(*b) && r.abs() <= LIMIT,
        FuzzShape::Plane(p, _) => in_range(*p),
    });
    if !(input.rest.iter().chain(&input.moved).all(|p| in_range(*p))
        && input.grabs.iter().all(|g| in_range(g.1))
        && shapes_ok)
    {
        return;
    }
    let rest: Vec<Vec3> = input
        .rest
        .iter()
        .take(N)
        .map(|p| Vec3::from_array(*p))
        .collect();
    let Ok(mut strand) = Strand::<N>::from_polyline(&rest, &Material::HUMAN_HAIR) else {
        return;
    };
    let n = strand.nodes();
    for (x, d) in strand.state.position[2..n].iter_mut().zip(&input.moved) {
        *x += Vec3::from_array(*d);
    }
    if !strand.is_finite() {
        return;
    }
    let mut effects = Effects::NONE.with(Effect::Grabs);
    if input.inextensibility {
        effects = effects.with(Effect::Inextensibility);
    }
    if input.collisions {
        effects = effects.with(Effect::Collisions);
    }
    let mut params = Params {
        effects,
        mode: if input.fixed_cost {
            Mode::FixedCost
        } else {
            Mode::Converge
        },
        ..Params::DEFAULT
    };
    params.rod.projection_iterations = u16::from(input.iterations % 32) + 1;
    params.rod.projection_tolerance = 10f32.powi(-i32::from(input.tolerance_exponent % 9));
    if params.validate().is_err() {
        return;
    }
    let colliders: Vec<Collider> = input
        .shapes
        .iter()
        .take(hairsim_core::collide::MAX_COLLIDERS)
        .map(|s| Collider {
            shape: shape(s),
            attached_to_head: false,
        })
        .filter(|c| c.shape.is_valid())
        .collect();
    let grabs: Vec<Grab> = input
        .grabs
        .iter()
        .take(hairsim_core::grab::MAX_GRABS)
        .map(|&(node, target, limit)| {
            Grab::new(
                0,
                2 + u32::from(node) % (n as u32 - 2),
                Vec3::from_array(target),
                limit,
            )
        })
        .filter(|g| g.target.is_finite() && g.force_limit > 0.0)
        .collect();
    let ctx = StepContext::new(&params, Pose::IDENTITY, Pose::IDENTITY, &colliders);
    let mut report = StepReport::default();
    let mut scratch = StrandProjection::new();
    let at = (&grabs[..], 0);
    let outcome = project_strand::<Libm, N>(&mut strand, &ctx, at, &mut scratch, &mut report);
    assert!(strand.is_finite(), "finite in, non-finite out");
    assert!(outcome.iterations <= u32::from(params.rod.projection_iterations));
    // Fixed-cost mode may stop early on a singular solve (degenerate colliders): its cost is
    // bounded by the cap either way, which is what firmware relies on.
    // Honest residual: never below the inextensibility residual recomputed here.
    if input.inextensibility && grabs.is_empty() {
        let x = &strand.state.position;
        let mut worst = 0.0f32;
        for j in 1..n - 1 {
            let e = x[j + 1] - x[j];
            let rest2 = strand.rest.segment_length[j] * strand.rest.segment_length[j];
            worst = worst.max((e.dot(e) - rest2).abs() / rest2);
        }
        assert!(
            outcome.residual >= worst * 0.999,
            "reported residual {} below the true {}",
            outcome.residual,
            worst
        );
    }
});
