//! One rod step, Kmoch 2009 Algorithm 1, as a list of stages each gated by the scene's effects.

use crate::context::StepContext;
use crate::effects::Effect;
use crate::grab::Grab;
use crate::math::{Math, Vec3};
use crate::report::{Stage, StepReport};
use crate::strand::Strand;

/// Steps one strand by `ctx.dt`. `accelerations` (if any) are the caller's per-node
/// accelerations for this strand (SPH, wind), indexed by node.
pub fn step<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    _grabs: &[Grab],
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    external_forces_and_integrate(strand, ctx, accelerations, report);
    root_coupling(strand, ctx, report);
}

/// Symplectic Euler with the external forces `F = M g − ν ẋ` plus caller accelerations:
/// `v ← v + h F/m`, then `x ← x + h v` (Kmoch 2009 Sec. 7, Alg. 1 lines 7–8).
fn external_forces_and_integrate<const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let n = strand.rest.nodes;
    let h = ctx.dt;
    let drag = if ctx.has(Effect::Drag) {
        ctx.params.drag
    } else {
        0.0
    };
    report.ran(Stage::ExternalForces);
    report.ran(Stage::Integrate);
    let state = &mut strand.state;
    for i in 2..n {
        let mut a = ctx.gravity - state.velocity[i] * (drag * strand.rest.inverse_mass[i]);
        if let Some(extra) = accelerations.and_then(|acc| acc.get(i)) {
            a += *extra;
        }
        state.velocity[i] += a * h;
        state.position[i] += state.velocity[i] * h;
    }
}

/// Root coupling: nodes 0 and 1 are prescribed by the head's rigid motion; their velocity is
/// the position change over the step.
fn root_coupling<const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    report: &mut StepReport,
) {
    report.ran(Stage::RootCoupling);
    for i in 0..2 {
        let target = ctx.head.transform_point(strand.rest.position[i]);
        strand.state.velocity[i] = (target - strand.state.position[i]) * ctx.inv_dt;
        strand.state.position[i] = target;
    }
}
