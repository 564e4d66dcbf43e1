//! Table 3's projection (a copy of the `rod_projection` bench's scene and captured states:
//! keep them in step) run once over the 16 captured steps, for counting instructions with
//! callgrind — load-independent, unlike criterion on a shared machine. Only `measured` is
//! counted:
//!
//! ```text
//! cargo build --release -p hairsim-benches --example projection_instructions
//! valgrind --tool=callgrind --toggle-collect='*measured*' \
//!     target/release/examples/projection_instructions 50 converge collisions
//! ```
//!
//! Arguments: strands (1 or 50), `converge` or `fixed`, `collisions` or `none`. Prints the
//! iterations, contacts and residual; divide callgrind's total by strands × 16 for the
//! instructions per strand-step.

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

#[inline(never)]
fn measured(strands: &mut [Strand<NODES>], ctx: &StepContext) -> StepReport {
    project_all(strands, ctx)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    assert!(
        args.len() == 4,
        "usage: projection_instructions STRANDS converge|fixed collisions|none"
    );
    let count: usize = args[1].parse().unwrap();
    let mode = if args[2] == "fixed" {
        Mode::FixedCost
    } else {
        Mode::Converge
    };
    let collisions = args[3] == "collisions";
    let states = predicted_states(count);
    let effects: &[Effect] = if collisions {
        &[Effect::Gravity, Effect::Inextensibility, Effect::Collisions]
    } else {
        &[Effect::Gravity, Effect::Inextensibility]
    };
    let p = params(effects, mode);
    let (mut it, mut contacts, mut resid, mut forces) = (0, 0, 0.0f32, 0.0f32);
    for (k, strands) in &states {
        let ctx = context(&p, *k);
        let mut st = strands.clone();
        let r = measured(&mut st, &ctx);
        it += r.iterations_total;
        contacts += r.contacts;
        resid = resid.max(r.residual);
        forces += r.collider_forces[0].length();
    }
    println!("{count} {:?} {collisions}: iterations/strand-step {:.3} contacts/step {:.1} max residual {resid:.2e} mean collider force {:.4} N", mode, it as f64 / (count * states.len()) as f64, contacts as f64 / states.len() as f64, forces / states.len() as f32);
}
