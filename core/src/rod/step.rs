//! One rod step, Kmoch 2009 Algorithm 1, as a list of stages each gated by the scene's effects.
//!
//! # Stiff hair: a fixed number of substeps
//!
//! Symplectic Euler on the bending forces is stable for `dt ≤ dt_max = (h²/2)·√(ρA/(max(1,µ)α))`
//! (DESIGN.md "Stability"; [`RodRest::stable_time_step`](super::energy::RodRest)). Human hair
//! at 1 cm segments sits at 60–90 % of it at 1 ms, so stiffer hair (or µ > 1) would chatter. The
//! remedy chosen here is the simplest one whose cost does not depend on the state: stages (1)
//! and (2) run `k = ⌈dt / (SAFETY · dt_max)⌉` times with `dt / k` ([`substeps`]), `k` fixed per
//! strand by its rest data and `dt` — so a firmware step's cost is known when the scene is
//! built. `θ` is held over the substeps (the twist is quasistatic and solved once per step);
//! the projection and the twist run once per step.
//!
//! Cost: `k` evaluations of the frames and forces (O(n) each; one square root per segment and
//! no trigonometry — the material angles' sines and cosines are computed once per step and
//! shared by the substeps) plus `k` integrations. Measured on x86-64 (callgrind) for a 30-node
//! strand: frames ≈ 6.0k instructions, forces ≈ 12.2k, so ≈ 18k per substep. At 1 cm and
//! 1 ms, `k = 1, 3, 10, 30` for ×1, ×10, ×100, ×1000 human bending stiffness (µ = 1; `√µ` more
//! for µ > 1), see the tests. A linearly implicit bending step (banded, half-bandwidth 8
//! scalars) would cost about 3–4 explicit evaluations at any stiffness, so it wins beyond
//! ≈ ×10–×20; substeps were chosen because they keep the very forces the finite-difference
//! tests check (no linearisation, no linear solve, no extra damping), stay deterministic and
//! bounded, and cost nothing extra for real hair (`k = 1`).

use super::energy::{
    elastic_forces_with_angles, material_angles, rest_root_frame, RodFrames, RodRest,
};
use super::twist::{hair_optimised_twist, newton_twist, ClampedFrames, TwistMethod};
use super::{ClampedSegments, ElasticTerms};
use crate::context::StepContext;
use crate::effects::Effect;
use crate::frames::{angle_in_frame, transport_in_time, unwrap_near};
use crate::grab::Grab;
use crate::math::{Math, Real, Vec3};
use crate::params::Mode;
use crate::report::{Flags, Stage, StepReport};
use crate::strand::Strand;

/// Fraction of the stability limit a substep may use: symplectic Euler's highest mode is
/// bounded below the limit, but its amplitude grows like `1/√(1 − (dt/dt_max)²)`; at 0.7 a
/// perturbation of the stiffest mode stays within 1.4× its size, and the bound (computed for
/// uniform segments) keeps a margin for curved and uneven ones.
pub const SAFETY: Real = 0.7;
/// Most substeps a strand takes per step (bounded latency): enough for 1000× human bending
/// stiffness at 1 cm segments and 1 ms.
pub const MAX_SUBSTEPS: u32 = 64;

/// Steps one strand by `ctx.dt`. `strand_index` is the strand's index in the whole scene (as
/// in [`Grab::strand`]); `accelerations` (if any) are the caller's per-node accelerations for
/// this strand (SPH, wind), indexed by node.
pub fn step<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    grabs: &[Grab],
    strand_index: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    // A grabbed node's segment is clamped like the root's (Kmoch Sec. 7.2).
    let clamped = if ctx.has(Effect::Grabs) {
        ClampedSegments::from_grabs(grabs, strand_index, strand.rest.nodes)
    } else {
        ClampedSegments::ROOT_ONLY
    };
    let terms = elastic_terms(ctx);
    let start = StepStart::<M>::capture(strand, &clamped, terms);
    // (1) elastic forces [bending, twist] and (2) external forces + symplectic Euler, substepped.
    forces_and_integrate::<M, N>(strand, ctx, &clamped, terms, accelerations, report);
    // (3) Root coupling: the head carries nodes 0 and 1, the root frame u^0 and θ^0.
    root_coupling_with_frame::<M, N>(strand, ctx, &start, report);
    // (4) Fast manifold projection [inextensibility, collisions, grabs] and velocity update.
    crate::projection::project_constraints::<M, N>(strand, ctx, grabs, strand_index, report);
    // (5) Twist [twist]: the Bishop frame in space for the new centreline, then θ.
    if ctx.has(Effect::Twist) {
        update_twist::<M, N>(strand, ctx, &clamped, terms, &start, report);
    }
}

/// The elastic energies the scene turns on.
fn elastic_terms(ctx: &StepContext) -> ElasticTerms {
    ElasticTerms {
        bending: ctx.has(Effect::Bending),
        twist: ctx.has(Effect::Twist),
    }
}

/// What the step needs from the configuration it starts from: the root tangent (for the
/// time-parallel transport of `u^0`) and the clamped segments' material frames.
struct StepStart<M: Math> {
    root_tangent: Option<Vec3>,
    clamped_frames: Option<ClampedFrames<M>>,
}

impl<M: Math> StepStart<M> {
    fn capture<const N: usize>(
        strand: &Strand<N>,
        clamped: &ClampedSegments,
        terms: ElasticTerms,
    ) -> Self {
        if !(terms.bending || terms.twist) {
            return StepStart {
                root_tangent: None,
                clamped_frames: None,
            };
        }
        let x = &strand.state.position;
        let clamped_frames = clamped.others().next().map(|_| {
            let frames = strand_frames::<M, N>(strand);
            ClampedFrames::save(&frames, &strand.state.theta, clamped)
        });
        StepStart {
            root_tangent: Some(unit::<M>(x[1] - x[0])),
            clamped_frames,
        }
    }
}

/// `v / |v|` with the backend's square root.
fn unit<M: Math>(v: Vec3) -> Vec3 {
    v * (1.0 / M::length(v))
}

/// The frames of the strand's current centreline.
fn strand_frames<M: Math, const N: usize>(strand: &Strand<N>) -> RodFrames<M, N> {
    let n = strand.rest.nodes.min(N);
    RodFrames::<M, N>::compute(
        &strand.state.position[..n],
        strand.state.root_frame,
        &strand.rest.rod.rest_length,
    )
}

/// Substeps per step for this strand: `⌈dt / (SAFETY · dt_max)⌉`, at least 1, at most
/// [`MAX_SUBSTEPS`]. Depends only on rest data and `dt`, so it is the same every step.
#[must_use]
pub fn substeps<const N: usize>(rest: &RodRest<N>, dt: Real, bending: bool) -> u32 {
    if !bending {
        return 1;
    }
    let ratio = dt / (SAFETY * rest.stable_time_step);
    if ratio <= 1.0 {
        1
    } else if ratio < MAX_SUBSTEPS as Real {
        libm::ceilf(ratio) as u32
    } else {
        MAX_SUBSTEPS
    }
}

/// Stages (1) and (2), `k` times with `h = dt/k` ([`substeps`]): the elastic forces of
/// Kmoch Sec. 7.2 at the current `θ` ([`elastic_forces_with_angles`]), then
/// [`external_forces_and_integrate`].
fn forces_and_integrate<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let elastic = terms.bending || terms.twist;
    let k = substeps(&strand.rest.rod, ctx.dt, terms.bending);
    let h = ctx.dt / k as Real;
    let mut forces = [Vec3::ZERO; N];
    let segments = strand.rest.nodes.saturating_sub(1).min(N);
    // θ is held over the substeps: its sines and cosines are computed once.
    let cos_sin = if elastic {
        report.ran(Stage::ElasticForces);
        material_angles::<M, N>(&strand.state.theta[..segments])
    } else {
        [[1.0, 0.0]; N]
    };
    report.ran(Stage::ExternalForces);
    report.ran(Stage::Integrate);
    for _ in 0..k {
        if elastic {
            let frames = strand_frames::<M, N>(strand);
            elastic_forces_with_angles(
                &frames,
                &strand.state.theta,
                &cos_sin,
                &strand.rest.rod,
                clamped,
                terms,
                &mut forces,
            );
        }
        external_forces_and_integrate(strand, ctx, &forces, h, accelerations);
    }
}

/// Symplectic Euler with the elastic forces `forces` and the external forces `F = M g − ν ẋ`
/// plus caller accelerations: `v ← v + h F/m`, then `x ← x + h v` (Kmoch 2009 Sec. 7,
/// Alg. 1 lines 7–8). Nodes 0 and 1 belong to the head.
fn external_forces_and_integrate<const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    forces: &[Vec3; N],
    h: Real,
    accelerations: Option<&[Vec3]>,
) {
    let n = strand.rest.nodes.min(N);
    let drag = if ctx.has(Effect::Drag) {
        ctx.params.drag
    } else {
        0.0
    };
    let state = &mut strand.state;
    let nodes = state
        .position
        .iter_mut()
        .zip(state.velocity.iter_mut())
        .zip(forces.iter().zip(&strand.rest.inverse_mass))
        .enumerate()
        .take(n)
        .skip(2);
    for (i, ((x, v), (force, inverse_mass))) in nodes {
        let mut a = ctx.gravity + ctx.wind + (*force - *v * drag) * *inverse_mass;
        if let Some(extra) = accelerations.and_then(|acc| acc.get(i)) {
            a += *extra;
        }
        *v += a * h;
        *x += *v * h;
    }
}

/// Root coupling: nodes 0 and 1 are prescribed by the head's rigid motion; their velocity is
/// the position change over the step. Shared by both solvers (DFTL too).
pub(crate) fn root_coupling<const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    report: &mut StepReport,
) {
    report.ran(Stage::RootCoupling);
    for i in 0..2 {
        let (position, velocity) =
            held_node(ctx, strand.rest.position[i], strand.state.position[i]);
        strand.state.velocity[i] = velocity;
        strand.state.position[i] = position;
    }
}

/// One held root node: its rest position moved with the head, and the velocity that gets it
/// there from `position` in one step. (The DFTL block path calls it per lane.)
#[inline(always)]
pub(crate) fn held_node(ctx: &StepContext, rest_position: Vec3, position: Vec3) -> (Vec3, Vec3) {
    let target = ctx.head.transform_point(rest_position);
    (target, (target - position) * ctx.inv_dt)
}

/// [`root_coupling`], then, with bending or twist on, the root Bishop vector `u^0` follows the
/// root tangent by time-parallel transport (Kmoch Sec. 5 — the root segment is final here: the
/// projection never moves prescribed nodes), and `θ^0` is the angle from `u^0` to the
/// head-fixed root material vector, so hair follows head roll.
fn root_coupling_with_frame<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    start: &StepStart<M>,
    report: &mut StepReport,
) {
    root_coupling(strand, ctx, report);
    let Some(old_tangent) = start.root_tangent else {
        return;
    };
    let state = &mut strand.state;
    let tangent = unit::<M>(state.position[1] - state.position[0]);
    let u = transport_in_time::<M>(old_tangent, tangent, state.root_frame);
    let rest = &strand.rest;
    let rest_material =
        rest_root_frame::<M>(rest.position[0], rest.position[1], rest.segment_length[0]);
    let material = ctx.head.transform_vector(rest_material);
    let angle = angle_in_frame::<M>(u, tangent.cross(u), material);
    state.theta[0] = unwrap_near(angle, state.theta[0]);
    state.root_frame = u;
}

/// Stage (5): the quasistatic twist for the new centreline — the clamped segments' frames by
/// time-parallel transport, then the free angles by the scene's [`TwistMethod`].
fn update_twist<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    start: &StepStart<M>,
    report: &mut StepReport,
) {
    report.ran(Stage::Twist);
    let frames = strand_frames::<M, N>(strand);
    let segments = strand.rest.nodes.saturating_sub(1).min(N);
    let rest = &strand.rest.rod;
    let theta = &mut strand.state.theta[..segments];
    if let Some(saved) = &start.clamped_frames {
        saved.transport(&frames, clamped, theta);
    }
    match ctx.params.rod.twist {
        TwistMethod::HairOptimised => hair_optimised_twist(&frames, rest, clamped, terms, theta),
        TwistMethod::Newton => {
            let outcome = newton_twist(
                &frames,
                rest,
                clamped,
                terms,
                ctx.params.rod.newton_iterations,
                ctx.params.rod.newton_tolerance,
                ctx.params.mode == Mode::FixedCost,
                theta,
            );
            report.iterations_max = report.iterations_max.max(outcome.iterations);
            if !outcome.converged {
                report.flags.insert(Flags::CAP_HIT);
            }
        }
    }
}

#[cfg(test)]
mod tests;
