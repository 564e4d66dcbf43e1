//! Kmoch 2009 Table 3's scene, shared by the `rod_projection` bench and the
//! `projection_instructions` example: strands of 30 nodes draped on a head shaking at
//! 10 rad/s, and states captured before their projection.

use hairsim_core::collide::{Collider, Shape};
use hairsim_core::context::StepContext;
use hairsim_core::projection::lanes::{project_strand, StrandProjection};
use hairsim_core::{
    step_strands, Effect, Effects, Libm, Material, Mode, Params, Real, Shake, StepReport, Strand,
    Vec3,
};

pub const NODES: usize = 32;
pub const HEAD_RADIUS: Real = 0.1;
pub const WARM_UP_STEPS: u32 = 300;
pub const CAPTURED_STEPS: u32 = 16;

/// The head: a sphere of radius [`HEAD_RADIUS`] at the origin, moving with the head.
pub fn head() -> Collider {
    Collider {
        shape: Shape::Sphere {
            centre: Vec3::ZERO,
            radius: HEAD_RADIUS,
        },
        attached_to_head: true,
    }
}

/// Default parameters with `effects` on, in `mode`.
pub fn params(effects: &[Effect], mode: Mode) -> Params {
    Params {
        effects: Effects::from_slice(effects),
        mode,
        ..Params::DEFAULT
    }
}

/// `count` strands of 30 nodes, 1 cm apart, rooted on the upper part of the head.
pub fn hair(count: usize) -> Vec<Strand<NODES>> {
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

/// Step `k`'s context: the shake from step `k` to `k + 1`, the head collider.
pub fn context(params: &Params, k: u32) -> StepContext {
    let shake = Shake::TEN_RAD_PER_S;
    let before = shake.pose_at::<Libm>(k as Real * params.dt);
    let after = shake.pose_at::<Libm>((k + 1) as Real * params.dt);
    StepContext::new(params, before, after, &[head()])
}

/// Runs the shaking scene, then returns `CAPTURED_STEPS` unprojected states with the step
/// each belongs to.
pub fn predicted_states(count: usize) -> Vec<(u32, Vec<Strand<NODES>>)> {
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

/// Projects every strand once, as the step does (`project_strand`); the summed report.
pub fn project_all(strands: &mut [Strand<NODES>], ctx: &StepContext) -> StepReport {
    let mut report = StepReport::default();
    // One scratch space for the call's strands, as `step_strands` makes.
    let mut scratch = StrandProjection::default();
    for (s, strand) in strands.iter_mut().enumerate() {
        project_strand::<Libm, NODES>(strand, ctx, (&[], s as u32), &mut scratch, &mut report);
    }
    report
}
