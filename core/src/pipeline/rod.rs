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
use crate::grab::Grab;
use crate::guard::{guard, sound};
use crate::math::{unit, Math, Real, Vec3};
use crate::projection::project_constraints;
use crate::report::{Stage, StepReport};
use crate::rod::energy::elastic_forces_with_angles;
use crate::rod::frames::{material_angles, RodFrames};
use crate::rod::integrate::{symplectic_euler, Motion};
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
    let gates = &ctx.gates;
    // Quarantine: the last good state.
    let last_good: StrandState<N> = snapshot(strand, report);
    // Sec. 7.2: the clamped segments C, the root's and each grabbed node's.
    let clamped = ClampedSegments::of_step(gates, grabs, index, strand.rest.nodes);
    // Sec. 5: the frames of the configuration the step starts from, one buffer for the step.
    let mut frames: Option<RodFrames<M, N>> = None;
    if gates.frames {
        frames.insert(RodFrames::empty()).refresh(strand);
    }
    let start = StepStart::capture(strand, &clamped, frames.as_ref());
    // Lines 3–4: forces and integration, in substeps or one linearly implicit step.
    let integration = plan(ctx, &strand.rest.rod, &mut strand.schedule, frames.as_ref());
    let angles = match (integration, frames.as_mut()) {
        (Integration::Implicit, Some(frames)) => {
            implicit_bending(strand, ctx, &clamped, frames, accelerations, report)
        }
        (integration, frames) => {
            let k = integration.substeps();
            explicit_substeps(strand, ctx, &clamped, frames, k, accelerations, report)
        }
    };
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
    if let (true, Some(frames)) = (gates.twist, frames.as_mut()) {
        frames.refresh(strand);
        let saved = start.clamped_frames.as_ref();
        twist::update(strand, ctx, &clamped, frames, saved, &angles, report);
    }
    // Line 11: the guard. A strand the explicit substeps lost takes the implicit step from now.
    let verdict = |s: &Strand<N>, _| sound(s, gates.inextensibility);
    if guard(strand, &last_good, verdict, index, report) {
        strand.schedule.implicit_bending = true;
    }
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
        symplectic_euler(strand, ctx, &forces, h, accelerations, &mut motion);
        if let (Some(sub), true) = (&between, substep + 1 < k) {
            // Segment lengths between substeps; the step's own projection follows the last.
            let mut scratch = StepReport::default();
            project_constraints::<M, N>(strand, sub, &[], 0, &mut scratch);
            motion.restart(strand);
        }
    }
    cos_sin
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
