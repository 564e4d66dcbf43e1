//! One rod step, Kmoch 2009 Algorithm 1, as a list of stages each gated by the scene's effects.
//!
//! # Stiff hair: one linearly implicit bending step
//!
//! Symplectic Euler on the bending forces is stable for `dt ≤ dt_max = (h²/2)·√(ρA/(max(1,µ)α))`
//! (DESIGN.md "Stability"; [`RodRest::stable_time_step`](super::energy::RodRest)). Human hair
//! at 1 cm segments sits at 60–90 % of it at 1 ms, ×1000 stiffer hair 20× past it, and a strand
//! bent to a turning angle `φ` lowers it by `(1 + cos φ)/2`. Stages (1) and (2) are therefore
//! one **linearly implicit** step per time step ([`super::implicit`]):
//! `(M + dt² H̃) v⁺ = M (v + dt a)`, `x⁺ = x + dt v⁺`, with `a` the explicit elastic forces of
//! Kmoch Sec. 7.2 (the ones the finite-difference tests check) plus the external forces, and
//! `H̃` a banded positive semi-definite approximation of the bending Hessian (Gauss–Newton of
//! the curvature binormals, a bound on the holonomy part, an axial term for the segment
//! lengths). One banded `L D Lᵀ` solve per strand (half-bandwidth 8, O(n), storage sized by
//! `N`), the same work on a calm and a violent step and at any stiffness the validator
//! accepts. It replaced a fixed number of explicit substeps (`⌈4 dt / (0.7 dt_max)⌉`: 4, 12,
//! 38, 119 for ×1, ×10, ×100, ×1000 human hair at 1 cm and 1 ms, with projections between
//! substeps from 8 on), which cost 4× to 119× the force evaluation.
//!
//! What it changes: the stiffest bending modes of the discrete strand (`dt²λ ≫ 1`, where a
//! saw-tooth would live) lose energy each step instead of being resolved; slow motion and
//! every static equilibrium are those of the explicit forces (`F = 0` is unchanged). The
//! tests that bound it: `tests/rod_physics.rs` (Euler–Bernoulli sag, energy envelope, grab
//! force), `tests/stability.rs`, `tests/torture.rs` (×10 … ×1000, 2 mm curls), and the rest
//! shapes below.
//!
//! [`within_tested_stiffness`] refuses a strand stiffer, relative to `dt`, than the range the
//! step is tested in (the old 128-substep cap, ×1000 human hair at 1 cm and 1 ms).

use super::energy::{
    elastic_forces_with_angles, material_angles, rest_root_frame, RodFrames, RodRest,
};
use super::implicit::BendingSystem;
use super::twist::{hair_optimised_twist_with_angles, newton_twist, ClampedFrames, TwistMethod};
use super::{ClampedSegments, ElasticTerms};
use crate::context::StepContext;
use crate::effects::Effect;
use crate::frames::{angle_in_frame, transport_in_time, unwrap_near};
use crate::grab::Grab;
use crate::math::{Math, Real, Vec3};
use crate::params::Mode;
use crate::report::{Flags, Stage, StepReport};
use crate::strand::Strand;

/// Largest `dt / dt_max` (the explicit limit of the rest shape) the implicit step is used
/// and tested at: `128 · 0.7 / 4`, the range of the 128 explicit substeps it replaced (×1000
/// human hair at 1 cm and 1 ms is 20.8, a 2 mm curl of human hair 16.5).
pub const MAX_STIFFNESS_RATIO: Real = 22.4;

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
    // (1) elastic forces [bending, twist] and (2) external forces, one linearly implicit step.
    let angles = forces_and_integrate::<M, N>(strand, ctx, &clamped, terms, accelerations, report);
    // (3) Root coupling: the head carries nodes 0 and 1, the root frame u^0 and θ^0.
    root_coupling_with_frame::<M, N>(strand, ctx, &start, report);
    // (4) Fast manifold projection [inextensibility, collisions, grabs] and velocity update.
    crate::projection::project_constraints::<M, N>(strand, ctx, grabs, strand_index, report);
    // (5) Twist [twist]: the Bishop frame in space for the new centreline, then θ.
    if ctx.has(Effect::Twist) {
        update_twist::<M, N>(strand, ctx, &clamped, terms, &start, &angles, report);
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

/// Whether the strand's rest stiffness, relative to `dt`, lies in the range the implicit step
/// is tested at: `dt ≤ MAX_STIFFNESS_RATIO · dt_max` (always with bending off).
#[must_use]
pub fn within_tested_stiffness<const N: usize>(rest: &RodRest<N>, dt: Real, bending: bool) -> bool {
    !bending
        || !rest.stable_time_step.is_finite()
        || dt <= MAX_STIFFNESS_RATIO * rest.stable_time_step
}

/// Stages (1) and (2): with bending on, [`implicit_step`]; without it, the elastic forces
/// (twist only, or none) and symplectic Euler, [`external_forces_and_integrate`]. Returns
/// `(cos θ^j, sin θ^j)` of the angles used (the hair-optimised twist compares against them).
fn forces_and_integrate<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> [[Real; 2]; N] {
    if terms.bending {
        return implicit_step::<M, N>(strand, ctx, clamped, terms, accelerations, report);
    }
    let segments = strand.rest.nodes.saturating_sub(1).min(N);
    let mut forces = [Vec3::ZERO; N];
    let cos_sin = if terms.twist {
        report.ran(Stage::ElasticForces);
        let cos_sin = material_angles::<M, N>(&strand.state.theta[..segments]);
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
        cos_sin
    } else {
        [[1.0, 0.0]; N]
    };
    report.ran(Stage::ExternalForces);
    report.ran(Stage::Integrate);
    external_forces_and_integrate(strand, ctx, &forces, ctx.dt, accelerations);
    cos_sin
}

/// Stages (1) and (2) with bending on, as one linearly implicit step of `dt`
/// ([`super::implicit`]): the elastic forces of Kmoch Sec. 7.2 at the current `θ`, the
/// external forces as in [`external_forces_and_integrate`], then
/// `(M + dt² H̃) v⁺ = M (v + dt a)` and `x⁺ = x + dt v⁺`. Returns `(cos θ^j, sin θ^j)`.
fn implicit_step<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> [[Real; 2]; N] {
    report.ran(Stage::ElasticForces);
    report.ran(Stage::ExternalForces);
    report.ran(Stage::Integrate);
    let h = ctx.dt;
    let n = strand.rest.nodes.min(N);
    let segments = n.saturating_sub(1);
    let cos_sin = material_angles::<M, N>(&strand.state.theta[..segments]);
    let frames = strand_frames::<M, N>(strand);
    let mut forces = [Vec3::ZERO; N];
    elastic_forces_with_angles(
        &frames,
        &strand.state.theta,
        &cos_sin,
        &strand.rest.rod,
        clamped,
        terms,
        &mut forces,
    );
    let mut system = BendingSystem::<N>::default();
    system.assemble(&frames, &strand.rest.mass, &strand.rest.rod, h);
    system.factor();
    let drag = drag(ctx);
    // Right-hand side M (v + h a), with a as in the explicit step.
    let mut rhs = [[0.0; 3]; N];
    let state = &mut strand.state;
    let rest = &strand.rest;
    let nodes = rhs
        .iter_mut()
        .zip(&state.velocity)
        .zip(forces.iter().zip(rest.mass.iter().zip(&rest.inverse_mass)))
        .enumerate()
        .take(n)
        .skip(2);
    for (i, ((slot, v), (force, (mass, inverse_mass)))) in nodes {
        let a = acceleration(ctx, *force, *v, drag, *inverse_mass, accelerations, i);
        *slot = ((*v + a * h) * *mass).to_array();
    }
    let held_velocity = [0, 1].map(|i| held_node(ctx, rest.position[i], state.position[i]).1);
    BendingSystem::move_held_nodes(&frames, &rest.rod, h, held_velocity, &mut rhs);
    system.solve(&mut rhs);
    let nodes = rhs
        .iter()
        .zip(state.velocity.iter_mut().zip(state.position.iter_mut()))
        .take(n)
        .skip(2);
    for (solved, (v, x)) in nodes {
        *v = Vec3::from_array(*solved);
        *x += *v * h;
    }
    cos_sin
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
    let drag = drag(ctx);
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
        *v += acceleration(ctx, *force, *v, drag, *inverse_mass, accelerations, i) * h;
        *x += *v * h;
    }
}

/// The air drag coefficient `ν`, or zero with the `drag` effect off.
fn drag(ctx: &StepContext) -> Real {
    if ctx.has(Effect::Drag) {
        ctx.params.drag
    } else {
        0.0
    }
}

/// Node `i`'s acceleration `g + wind + (F − ν v)/m` plus the caller's.
#[inline(always)]
fn acceleration(
    ctx: &StepContext,
    force: Vec3,
    v: Vec3,
    drag: Real,
    inverse_mass: Real,
    accelerations: Option<&[Vec3]>,
    i: usize,
) -> Vec3 {
    let mut a = ctx.gravity + ctx.wind + (force - v * drag) * inverse_mass;
    if let Some(extra) = accelerations.and_then(|acc| acc.get(i)) {
        a += *extra;
    }
    a
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
    angles: &[[Real; 2]; N],
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
        // The angles' cosines and sines from the start of the step: only clamped segments
        // (skipped by the sweep) have moved since.
        TwistMethod::HairOptimised => {
            hair_optimised_twist_with_angles(&frames, rest, clamped, terms, theta, angles);
        }
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
