//! The rod's pipeline: Kmoch, Bonanni and Magnenat-Thalmann 2009, Algorithm 1, on one strand.
//!
//! | line | Algorithm 1 | stage |
//! |---|---|---|
//! | 1 | precompute rest-state values | `rest`, `rod::rest` (when the strand is built) |
//! | 2 | while simulation running | `World::step`, `pipeline::step_strands` |
//! | 3 | compute forces | `rod::energy` (elastic), `forces` (external) |
//! | 4 | integrate equations of motion | `rod::integrate` (`rod::substeps`), `rod::implicit` |
//! | 5–7 | detect collisions; enforce the constraints | `root_coupling`, then `projection` |
//! | 8 | update velocities | `projection` |
//! | 9 | update Bishop frame | `root_coupling::carry_root_frame` (time), `rod::frames` (space) |
//! | 10 | compute twist | `rod::twist` |
//! | 11 | end | `guard` (after the `snapshot` the step began with) |
//!
//! [`step_strand`] reads top to bottom like the table, one stage per line, each gated once by
//! the step's gates (`context::Gates`); the substeps of lines 3–4 are
//! [`explicit_substeps`], and the linearly implicit step for stiff strands and sharp folds is
//! [`implicit_bending`].

use crate::context::StepContext;
use crate::forces::{drag, External};
use crate::grab::Grab;
use crate::guard::{guard, sound};
use crate::lane::{Lane, Lanes, Wide, V3};
use crate::math::{unit, Math, Real, Vec3};
use crate::projection::project_constraints;
use crate::report::{Stage, StepReport};
use crate::rod::block::LaneBlock;
use crate::rod::energy::elastic_forces_with_angles;
use crate::rod::frames::{material_angles, RodFrames};
use crate::rod::integrate::{starting_at, symplectic_euler, Motion, Nodes};
use crate::rod::substeps::{inextensibility_between_substeps, plan, Integration};
use crate::rod::twist::ClampedFrames;
use crate::rod::{implicit, twist, ClampedSegments, ElasticTerms};
use crate::root_coupling::{carry_root_frame, held_velocity, root_coupling};
use crate::snapshot::snapshot;
use crate::strand::{Strand, StrandState};

/// Steps one strand by `ctx.dt` (Kmoch Algorithm 1, lines 3–11). `index` is the strand's
/// index in the whole scene (as in [`Grab::strand`]); `accelerations` (if any) are the
/// caller's per-node accelerations for this strand (SPH, wind), indexed by node. Never panics;
/// a strand that turns non-finite (or flies apart) is rolled back.
///
/// Not inlined into its callers: kept apart, the rod's step takes 0.6–0.8 % fewer
/// instructions on the Cortex-M4F than inlined into `step_strands` (QEMU, the latency scenes
/// of 16 to 256 nodes), and the DFTL step beside it 0.3 % fewer.
#[inline(never)]
pub fn step_strand<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    grabs: &[Grab],
    index: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    // Sec. 5: the frames of the configuration the step starts from, one buffer for the step.
    let mut frames: Option<RodFrames<M, N>> = None;
    if ctx.gates.frames {
        frames.insert(RodFrames::empty()).refresh(strand);
    }
    let begun = begin(strand, ctx, grabs, index, frames.as_ref(), report);
    // Lines 3–4: forces and integration, in substeps or one linearly implicit step.
    let angles = integrate(strand, ctx, &begun, frames.as_mut(), accelerations, report);
    finish(
        strand,
        ctx,
        grabs,
        index,
        &begun,
        frames.as_mut(),
        &angles,
        report,
    );
}

/// Steps `strands` (at most `W`; `W` strands of a block) by `ctx.dt`, as [`step_strand`] does
/// each, with the same bits: the explicit substeps (lines 3–4, the bulk of a step) of all of
/// them at once in lanes ([`explicit_substeps_in_lanes`]) when they take the same number of
/// substeps and have as many nodes, and every other stage strand by strand. `first_strand` is
/// the index of `strands[0]` in the scene; `accelerations`, if any, holds `N` per strand.
pub fn step_block<M: Math, const N: usize, const W: usize>(
    strands: &mut [Strand<N>],
    ctx: &StepContext,
    grabs: &[Grab],
    first_strand: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let lanes = strands.len().min(W);
    let of_strand = |k: usize| accelerations.and_then(|a| a.get(k * N..(k + 1) * N));
    let mut frames: Option<RodFrames<M, N>> = ctx.gates.frames.then(RodFrames::empty);
    let mut begun: [Option<Begun<M, N>>; W] = [const { None }; W];
    for (lane, strand) in strands.iter_mut().take(lanes).enumerate() {
        if let Some(frames) = frames.as_mut() {
            frames.refresh(strand);
        }
        let index = first_strand + lane as u32;
        begun[lane] = Some(begin(strand, ctx, grabs, index, frames.as_ref(), report));
    }
    let mut angles = [[[1.0, 0.0]; N]; W];
    match lanes_substeps(ctx, &strands[..lanes], &begun) {
        Some(k) if lanes > 1 => {
            let clamped = begun.each_ref().map(|b| b.as_ref().map(|b| b.clamped));
            let clamped = clamped.map(|c| c.unwrap_or(ClampedSegments::ROOT_ONLY));
            angles = explicit_substeps_in_lanes::<M, N, W>(
                &mut strands[..lanes],
                ctx,
                &clamped,
                k,
                accelerations,
                report,
            );
        }
        _ => {
            for (lane, strand) in strands.iter_mut().take(lanes).enumerate() {
                let Some(begun) = begun[lane].as_ref() else {
                    continue;
                };
                if let Some(frames) = frames.as_mut() {
                    frames.refresh(strand);
                }
                angles[lane] =
                    integrate(strand, ctx, begun, frames.as_mut(), of_strand(lane), report);
            }
        }
    }
    for (lane, strand) in strands.iter_mut().take(lanes).enumerate() {
        let Some(begun) = begun[lane].as_ref() else {
            continue;
        };
        let index = first_strand + lane as u32;
        finish(
            strand,
            ctx,
            grabs,
            index,
            begun,
            frames.as_mut(),
            &angles[lane],
            report,
        );
    }
}

/// What a strand's step decided and kept before its forces and integration.
struct Begun<M: Math, const N: usize> {
    /// Quarantine: the last good state.
    last_good: StrandState<N>,
    /// Sec. 7.2: the clamped segments C, the root's and each grabbed node's.
    clamped: ClampedSegments,
    /// What the step keeps of the configuration it starts from.
    start: StepStart<M>,
    /// Lines 3–4 as substeps or the implicit step.
    integration: Integration,
}

/// The start of a strand's step: the snapshot, the clamped set, what the step keeps of its
/// starting configuration and its integration's plan. `frames`, there when bending or twist is
/// on, are those of the strand's centreline.
fn begin<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    grabs: &[Grab],
    index: u32,
    frames: Option<&RodFrames<M, N>>,
    report: &mut StepReport,
) -> Begun<M, N> {
    let last_good: StrandState<N> = snapshot(strand, report);
    let clamped = ClampedSegments::of_step(&ctx.gates, grabs, index, strand.rest.nodes);
    let start = StepStart::capture(strand, &clamped, frames);
    let integration = plan(ctx, &strand.rest.rod, &mut strand.schedule, frames);
    Begun {
        last_good,
        clamped,
        start,
        integration,
    }
}

/// Lines 3–4 on one strand: its explicit substeps or its implicit step. `frames` are those of
/// the centreline the step starts from.
fn integrate<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    begun: &Begun<M, N>,
    frames: Option<&mut RodFrames<M, N>>,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> [[Real; 2]; N] {
    let clamped = &begun.clamped;
    match (begun.integration, frames) {
        (Integration::Implicit, Some(frames)) => {
            implicit_bending(strand, ctx, clamped, frames, accelerations, report)
        }
        (integration, frames) => {
            let k = integration.substeps();
            explicit_substeps(strand, ctx, clamped, frames, k, accelerations, report)
        }
    }
}

/// Lines 5–11 of a strand's step, after its forces and integration: root coupling, the root
/// frame in time, the projection, the Bishop frame in space and the twist, the guard.
/// `angles` are the `(cos θ^j, sin θ^j)` the forces used; `frames` a buffer for the frames.
#[allow(clippy::too_many_arguments)] // the step's inputs, its strand, and what it began with
fn finish<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    grabs: &[Grab],
    index: u32,
    begun: &Begun<M, N>,
    frames: Option<&mut RodFrames<M, N>>,
    angles: &[[Real; 2]; N],
    report: &mut StepReport,
) {
    let gates = &ctx.gates;
    let (start, clamped) = (&begun.start, &begun.clamped);
    // Sec. 8.1: root coupling; the root frame follows in time (line 9).
    root_coupling(strand, ctx, report);
    if let Some(tangent) = start.root_tangent {
        carry_root_frame::<M, N>(strand, ctx, tangent);
    }
    // Lines 5–8: fast manifold projection (inextensibility, collisions, grabs), velocities.
    if gates.projection {
        project_constraints::<M, N>(strand, ctx, grabs, index, report);
    }
    // Lines 9–10: the Bishop frame in space of the new centreline, then the twist.
    if let (true, Some(frames)) = (gates.twist, frames) {
        frames.refresh(strand);
        let saved = start.clamped_frames.as_ref();
        twist::update(strand, ctx, clamped, frames, saved, angles, report);
    }
    // Line 11: the guard. A strand the explicit substeps lost takes the implicit step from now.
    let verdict = |s: &Strand<N>, _| sound(s, gates.inextensibility);
    if guard(strand, &begun.last_good, verdict, index, report) {
        strand.schedule.implicit_bending = true;
    }
}

/// The substep count `k` that every strand of a block takes in lanes, or `None` when they
/// differ in it, in their node count, or in needing anything the lanes do not do (the
/// implicit step, frames off, projections between substeps): those strands step one by one.
fn lanes_substeps<M: Math, const N: usize, const W: usize>(
    ctx: &StepContext,
    strands: &[Strand<N>],
    begun: &[Option<Begun<M, N>>; W],
) -> Option<u32> {
    let nodes = strands.first()?.rest.nodes;
    let k = match begun.first()?.as_ref()?.integration {
        Integration::Explicit(k) => k,
        Integration::Implicit => return None,
    };
    let same = strands.iter().zip(begun).all(|(strand, begun)| {
        let plan = begun.as_ref().map(|b| b.integration);
        strand.rest.nodes == nodes && plan == Some(Integration::Explicit(k))
    });
    let h = ctx.dt / k as Real;
    let plain = ctx.gates.frames && inextensibility_between_substeps(ctx, k, h).is_none();
    (same && plain).then_some(k)
}

/// Lines 3–4 as `k` substeps of `h = dt/k` (`rod::substeps`): each the elastic forces of
/// Kmoch Sec. 7.2 at the current `θ` (line 3, with bending or twist on) and symplectic Euler
/// with the external forces (line 4); with many substeps the segment lengths are projected
/// between them (`rod::substeps::inextensibility_between_substeps`). `frames`, there when
/// bending or twist is on, come in as those of the centreline the step starts from and are
/// recomputed in place for each later substep. Returns `(cos θ^j, sin θ^j)` of the angles
/// the forces used (the hair-optimised twist compares against them).
fn explicit_substeps<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    mut frames: Option<&mut RodFrames<M, N>>,
    k: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> [[Real; 2]; N] {
    let h = ctx.dt / k as Real;
    let terms = ElasticTerms::of(&ctx.gates);
    let mut forces = [Vec3::ZERO; N];
    let segments = strand.rest.nodes.saturating_sub(1).min(N);
    // θ is held over the substeps: its sines and cosines are computed once.
    let cos_sin = if frames.is_some() {
        report.ran(Stage::ElasticForces);
        material_angles::<M, N>(&strand.state.theta[..segments])
    } else {
        [[1.0, 0.0]; N]
    };
    report.ran(Stage::ExternalForces);
    report.ran(Stage::Integrate);
    let external = External::<M>::of(ctx);
    let mut motion = Motion::from(strand);
    let between = inextensibility_between_substeps(ctx, k, h);
    for substep in 0..k {
        if let Some(frames) = frames.as_deref_mut() {
            // The first substep starts where the frames were computed.
            if substep > 0 {
                frames.refresh(strand);
            }
            let (theta, rest) = (&strand.state.theta, &strand.rest.rod);
            elastic_forces_with_angles(frames, theta, &cos_sin, rest, clamped, terms, &mut forces);
        }
        let nodes = Nodes::<M, N> {
            count: strand.rest.nodes,
            position: &mut strand.state.position,
            velocity: &mut strand.state.velocity,
            inverse_mass: &strand.rest.inverse_mass,
        };
        symplectic_euler(nodes, &external, &forces, h, accelerations, &mut motion);
        if let (Some(sub), true) = (&between, substep + 1 < k) {
            // Segment lengths between substeps; the step's own projection follows the last.
            let mut scratch = StepReport::default();
            project_constraints::<M, N>(strand, sub, &[], 0, &mut scratch);
            motion.restart(strand);
        }
    }
    cos_sin
}

/// [`explicit_substeps`] of up to `W` strands at once, one per lane (`lane::Lanes`): the same
/// kernels — frame pass, elastic forces, symplectic Euler — on the strands' values gathered
/// into lanes, so each strand gets the bits [`explicit_substeps`] gives it (a lane past the
/// block's strands repeats the last strand and is dropped). For strands with frames, the same
/// `k` and node count, and no projection between substeps ([`lanes_substeps`]).
fn explicit_substeps_in_lanes<M: Math, const N: usize, const W: usize>(
    strands: &mut [Strand<N>],
    ctx: &StepContext,
    clamped: &[ClampedSegments; W],
    k: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> [[[Real; 2]; N]; W] {
    let lanes = strands.len().min(W) as u32;
    report.ran_on(Stage::ElasticForces, lanes);
    report.ran_on(Stage::ExternalForces, lanes);
    report.ran_on(Stage::Integrate, lanes);
    let mut block = LaneBlock::<N, W>::gather::<M>(strands, accelerations);
    let h = Wide::splat(ctx.dt / k as Real);
    let terms = ElasticTerms::of(&ctx.gates);
    let external = External::<Lanes<M, W>> {
        gravity_and_wind: V3::splat(ctx.gravity + ctx.wind),
        drag: Wide::splat(drag(ctx)),
    };
    let mut frames = RodFrames::<Lanes<M, W>, N>::empty();
    let mut forces = [V3::<Wide<W>>::zero(); N];
    let mut motion = starting_at::<Lanes<M, W>, N>(block.position);
    let nodes = block.nodes;
    for _ in 0..k {
        frames.recompute(
            &block.position[..nodes],
            block.root_frame,
            &block.rest.rest_length,
        );
        let (theta, rest) = (&block.theta, &block.rest);
        elastic_forces_with_angles(
            &frames,
            theta,
            &block.cos_sin,
            rest,
            clamped,
            terms,
            &mut forces,
        );
        let lane_nodes = Nodes::<Lanes<M, W>, N> {
            count: nodes,
            position: &mut block.position,
            velocity: &mut block.velocity,
            inverse_mass: &block.inverse_mass,
        };
        let acc = block.accelerations.as_ref().map(|a| &a[..]);
        symplectic_euler(lane_nodes, &external, &forces, h, acc, &mut motion);
    }
    block.scatter(strands)
}

/// Lines 3–4 as one linearly implicit bending step of `dt` (`rod::implicit`): the elastic
/// forces of Kmoch Sec. 7.2 at the current `θ` (line 3), then `(M + dt² H̃) v⁺ = M (v + dt a)`
/// and `x⁺ = x + dt v⁺` with the external forces in `a` (line 4), all at `frames`, those of the
/// centreline the step starts from. Returns `(cos θ^j, sin θ^j)`.
///
/// Not inlined: inlined into the pipeline it made the substep path of human hair 2.4 % dearer
/// on the Cortex-M4F (QEMU, 128 nodes), 1.2 % with it kept apart.
#[inline(never)]
fn implicit_bending<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    frames: &RodFrames<M, N>,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> [[Real; 2]; N] {
    report.ran(Stage::ElasticForces);
    report.ran(Stage::ExternalForces);
    report.ran(Stage::Integrate);
    let terms = ElasticTerms::of(&ctx.gates);
    let segments = strand.rest.nodes.min(N).saturating_sub(1);
    let cos_sin = material_angles::<M, N>(&strand.state.theta[..segments]);
    let mut forces = [Vec3::ZERO; N];
    let (theta, rest) = (&strand.state.theta, &strand.rest.rod);
    elastic_forces_with_angles(frames, theta, &cos_sin, rest, clamped, terms, &mut forces);
    // The head's motion of nodes 0 and 1 this step: the solve's boundary condition.
    let held = [0, 1].map(|i| held_velocity(ctx, strand, i));
    implicit::step(strand, ctx, frames, &forces, held, accelerations);
    cos_sin
}

/// What the step keeps of the configuration it starts from: the root tangent (for the
/// time-parallel transport of `u^0`) and the clamped segments' material frames (for the
/// twist), both there when bending or twist is on.
struct StepStart<M: Math> {
    root_tangent: Option<Vec3>,
    clamped_frames: Option<ClampedFrames<M>>,
}

impl<M: Math> StepStart<M> {
    /// `frames` are those of the strand's centreline, there when bending or twist is on.
    fn capture<const N: usize>(
        strand: &Strand<N>,
        clamped: &ClampedSegments,
        frames: Option<&RodFrames<M, N>>,
    ) -> Self {
        let Some(frames) = frames else {
            return StepStart {
                root_tangent: None,
                clamped_frames: None,
            };
        };
        let x = &strand.state.position;
        let clamped_frames = clamped
            .others()
            .next()
            .map(|_| ClampedFrames::save(frames, &strand.state.theta, clamped));
        StepStart {
            root_tangent: Some(unit::<M>(x[1] - x[0])),
            clamped_frames,
        }
    }
}

#[cfg(test)]
mod tests;
