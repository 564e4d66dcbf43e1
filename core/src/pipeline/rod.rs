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
use crate::forces::External;
use crate::grab::{forces_after_roll_back, grabbed_nodes, Grab};
use crate::guard::{guard, sound};
use crate::lane::Natural;
use crate::math::{unit, Math, Real, Vec3};
use crate::projection::lanes::{project_strand, BlockProjection, StrandSpace};
use crate::projection::{project_in_scratch, Outcome, ProjectionScratch};
use crate::report::{Stage, StepReport};
use crate::rod::energy::elastic_forces_with_angles;
use crate::rod::frames::{material_angles, RodFrames};
use crate::rod::implicit::BendingSystem;
use crate::rod::integrate::{symplectic_euler, Motion, Nodes};
use crate::rod::substeps::{
    inextensibility_between_substeps, plan, projects_between_substeps,
    smallest_binormal_denominator, Integration,
};
use crate::rod::twist::ClampedFrames;
use crate::rod::{implicit, twist, ClampedSegments, ElasticTerms};
use crate::root_coupling::{carry_root_frame, elastic_on_root, held_velocity, root_coupling};
use crate::snapshot::snapshot_into;
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
    (grabs, index): (&[Grab], u32),
    accelerations: Option<&[Vec3]>,
    scratch: &mut RodScratch<M, N>,
    report: &mut StepReport,
) {
    // Sec. 5: the frames of the configuration the step starts from, one buffer for the step.
    let mut frames = ctx.gates.frames.then_some(&mut scratch.frames);
    if let Some(frames) = frames.as_mut() {
        frames.refresh(strand);
    }
    let begun = begin(
        strand,
        ctx,
        (grabs, index),
        starting_from(frames.as_deref()),
        &mut scratch.last_good,
        report,
    );
    // Lines 3–4: forces and integration, in substeps or one linearly implicit step.
    let (angles, on_root) = integrate(
        strand,
        ctx,
        &begun,
        (
            frames.as_deref_mut(),
            &mut scratch.projection.solves,
            &mut scratch.integration,
        ),
        accelerations,
        report,
    );
    // Lines 5–11.
    let at = (grabs, index, &mut scratch.projection);
    let started = (&begun, &scratch.last_good, on_root);
    finish(strand, ctx, at, started, frames, &angles, report);
}

/// Scratch space for [`step_strand`]: the strand's last good state, the frames' buffer, the
/// substeps' forces and motion ([`IntegrationSpace`]), and the projections' and the implicit
/// step's workspaces ([`RodProjection`]). A [`crate::World`] keeps one, inside
/// `hairsim_init`'s buffer, copied from a constant (`StepScratch::build_rod`); `step_strands`
/// makes one for all the strands of a call. Nothing in it carries from one strand or step to
/// the next (each strand's step sets what it reads): made for each strand, its zeros and
/// copies would be 5 % of the Cortex-M4F's rod step (`firmware/profile.py`), and on the stack
/// its kilobytes would be most of a step's stack (10 KB at 16 nodes).
pub struct RodScratch<M: Math, const N: usize> {
    pub(super) last_good: StrandState<N>,
    pub(super) frames: RodFrames<M, N>,
    pub(super) integration: IntegrationSpace<N>,
    pub(super) projection: RodProjection<M, N>,
}

/// What lines 3–4 of a strand's step work on: the elastic forces, and the substeps' motion
/// ([`Motion`]). Every value a step reads of it, the step has written.
pub(super) struct IntegrationSpace<const N: usize> {
    forces: [Vec3; N],
    motion: Motion<N>,
}

impl<const N: usize> IntegrationSpace<N> {
    /// Before its first use.
    const EMPTY: Self = IntegrationSpace {
        forces: [Vec3::ZERO; N],
        motion: Motion {
            start: [Vec3::ZERO; N],
            displacement: [Vec3::ZERO; N],
        },
    };
}

impl<M: Math, const N: usize> RodScratch<M, N> {
    /// Before its first use.
    #[must_use]
    pub const fn new() -> Self {
        RodScratch {
            last_good: StrandState::EMPTY,
            frames: RodFrames::empty(),
            integration: IntegrationSpace::EMPTY,
            projection: RodProjection {
                lanes: BlockProjection::new(),
                solves: Solves::EMPTY,
            },
        }
    }
}

/// Where a rod strand is projected ([`StrandSpace`]): the lanes' space at one lane, and the
/// general projection's workspace, beside the implicit step's ([`Solves`]).
pub(super) struct RodProjection<M: Math, const N: usize> {
    pub(super) lanes: BlockProjection<N, 1, Natural>,
    pub(super) solves: Solves<M, N>,
}

impl<M: Math, const N: usize> StrandSpace<N> for RodProjection<M, N> {
    #[inline(always)]
    fn lanes(&mut self) -> &mut BlockProjection<N, 1, Natural> {
        &mut self.lanes
    }

    #[inline(always)]
    fn general(&mut self, project: impl FnOnce(&mut ProjectionScratch<N>) -> Outcome) -> Outcome {
        project(&mut self.solves.projection)
    }
}

/// The two solves' workspaces of a strand's step: the general projection's
/// (`projection::project_in_scratch`: a grabbed strand's, and those between substeps) and the
/// implicit step's system (`rod::implicit::BendingSystem`), reached through one pointer (as
/// two, the implicit step took 5 k more instructions on the Cortex-M4F).
pub(super) struct Solves<M: Math, const N: usize> {
    pub(super) projection: ProjectionScratch<N>,
    pub(super) system: BendingSystem<M, N>,
}

impl<M: Math, const N: usize> Solves<M, N> {
    /// Before their first use.
    const EMPTY: Self = Solves {
        projection: ProjectionScratch::new(),
        system: BendingSystem::EMPTY,
    };
}

impl<M: Math, const N: usize> Default for RodScratch<M, N> {
    fn default() -> Self {
        Self::new()
    }
}

/// A copy holds nothing of the original: its contents are never read before they are set.
impl<M: Math, const N: usize> Clone for RodScratch<M, N> {
    fn clone(&self) -> Self {
        Self::new()
    }
}

impl<M: Math, const N: usize> core::fmt::Debug for RodScratch<M, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("RodScratch")
    }
}

/// What a strand's step decided and kept before its forces and integration.
pub(super) struct Begun<M: Math, const N: usize> {
    /// Sec. 7.2: the clamped segments C, the root's and each grabbed node's.
    pub(super) clamped: ClampedSegments,
    /// What the step keeps of the configuration it starts from.
    start: StepStart<M>,
    /// Lines 3–4 as substeps or the implicit step.
    pub(super) integration: Integration,
}

/// What [`begin`] reads of the frames the step starts from (there when bending or twist is on):
/// the sharpest fold, for the plan, and the clamped segments' frames, for the twist.
pub(super) struct Starting<F, C> {
    /// Whether the strand has frames (bending or twist on).
    pub(super) has_frames: bool,
    /// The frames' [`smallest_binormal_denominator`].
    pub(super) smallest_denominator: F,
    /// The clamped segments' frames (`ClampedFrames::save`), asked for only when a segment
    /// other than the root is clamped.
    pub(super) clamped_frames: C,
}

/// [`Starting`] from one strand's `frames`.
#[allow(clippy::type_complexity)] // two closures over the same frames, named by what they give
pub(super) fn starting_from<M: Math, const N: usize>(
    frames: Option<&RodFrames<M, N>>,
) -> Starting<
    impl FnOnce(&Strand<N>) -> Real + '_,
    impl FnOnce(&Strand<N>, &ClampedSegments) -> Option<ClampedFrames<M>> + '_,
> {
    Starting {
        has_frames: frames.is_some(),
        smallest_denominator: move |s: &Strand<N>| {
            frames.map_or(2.0, |f| {
                smallest_binormal_denominator(f, &s.rest.rod.rest_length)
            })
        },
        clamped_frames: move |s: &Strand<N>, clamped: &ClampedSegments| {
            frames.map(|f| ClampedFrames::save(f, &s.state.theta, clamped))
        },
    }
}

/// The start of a strand's step: the snapshot (into `last_good`), the clamped set, what the
/// step keeps of its starting configuration and its integration's plan, from what `starting`
/// says of the strand's frames.
pub(super) fn begin<M: Math, const N: usize, F, C>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    (grabs, index): (&[Grab], u32),
    starting: Starting<F, C>,
    last_good: &mut StrandState<N>,
    report: &mut StepReport,
) -> Begun<M, N>
where
    F: FnOnce(&Strand<N>) -> Real,
    C: FnOnce(&Strand<N>, &ClampedSegments) -> Option<ClampedFrames<M>>,
{
    snapshot_into(strand, last_good, report);
    let clamped = ClampedSegments::of_step(&ctx.gates, grabs, index, strand.rest.nodes);
    let x = &strand.state.position;
    let start = StepStart {
        root_tangent: starting.has_frames.then(|| unit::<M>(x[1] - x[0])),
        clamped_frames: match clamped.others().next() {
            Some(_) if starting.has_frames => (starting.clamped_frames)(strand, &clamped),
            _ => None,
        },
    };
    let mut schedule = strand.schedule;
    let smallest = || (starting.smallest_denominator)(strand);
    let held = ctx.gates.grabs && !grabbed_nodes(ctx, grabs, index, strand.rest.nodes).is_empty();
    let integration = plan(ctx, &strand.rest.rod, (&mut schedule, held), smallest);
    strand.schedule = schedule;
    Begun {
        clamped,
        start,
        integration,
    }
}

/// Lines 3–4 on one strand: its explicit substeps or its implicit step. `frames` are those of
/// the centreline the step starts from; `solves` the workspaces of the projections between
/// substeps and of the implicit step. Returns the angles the forces used and the mean
/// elastic force on the held nodes 0 and 1 over the step ([`Integrated`]).
pub(super) fn integrate<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    begun: &Begun<M, N>,
    (frames, solves, space): Workspaces<'_, M, N>,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> Integrated<N> {
    let clamped = &begun.clamped;
    match (begun.integration, frames) {
        (Integration::Implicit, Some(frames)) => {
            let space = (&*frames, solves, &mut space.forces);
            implicit_bending(strand, ctx, clamped, space, accelerations, report)
        }
        (integration, frames) => {
            let k = integration.substeps();
            let space = (frames, solves, space);
            explicit_substeps(strand, ctx, clamped, space, k, accelerations, report)
        }
    }
}

/// The space lines 3–4 work in: the frames (with bending or twist on), the projection's
/// workspace (between substeps) and the implicit step's system ([`Solves`]), and the forces
/// and the motion ([`IntegrationSpace`]).
pub(super) type Workspaces<'a, M, const N: usize> = (
    Option<&'a mut RodFrames<M, N>>,
    &'a mut Solves<M, N>,
    &'a mut IntegrationSpace<N>,
);

/// What lines 3–4 hand on: the `(cos θ^j, sin θ^j)` the forces used, and the mean elastic
/// force on the held nodes 0 and 1 over the step (`root_coupling::elastic_on_root`).
pub(super) type Integrated<const N: usize> = ([[Real; 2]; N], Vec3);

/// Lines 5–11 of a strand's step, after its forces and integration: [`constrain`], the twist
/// ([`twist_alone`]) and [`judge`], then what the strand transmits to the head into the
/// report ([`transmit_to_head`]: `on_root`, the elastic forces on nodes 0 and 1, and the
/// projection's pull on node 1). `angles` are the `(cos θ^j, sin θ^j)` the forces used;
/// `frames` a buffer for the frames, `projection` the projection's scratch space.
pub(super) fn finish<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    (grabs, index, projection): (&[Grab], u32, &mut RodProjection<M, N>),
    (begun, last_good, on_root): (&Begun<M, N>, &StrandState<N>, Vec3),
    frames: Option<&mut RodFrames<M, N>>,
    angles: &[[Real; 2]; N],
    report: &mut StepReport,
) {
    let pull = constrain(strand, ctx, (grabs, index, projection), begun, report);
    twist_alone(strand, ctx, begun, frames, angles, report);
    let rolled_back = judge(strand, ctx, index, last_good, report);
    transmit(
        strand,
        ctx,
        (grabs, index),
        (on_root + pull, rolled_back),
        report,
    );
}

/// What one rod strand transmits this step into the report: `force` to the head
/// ([`transmit_to_head`]); from a strand rolled back, nothing to the head, and to its grabs'
/// devices the forces of the state it went back to (`grab::forces_after_roll_back`).
#[inline(always)]
pub(super) fn transmit<const N: usize>(
    strand: &Strand<N>,
    ctx: &StepContext,
    (grabs, index): (&[Grab], u32),
    (force, rolled_back): (Vec3, bool),
    report: &mut StepReport,
) {
    transmit_to_head(force, rolled_back, report);
    if rolled_back && ctx.gates.grabs {
        forces_after_roll_back(ctx, grabs, (strand, index), report);
    }
}

/// Lines 5–9 (time): root coupling (Sec. 8.1), the root frame carried in time, then the fast
/// manifold projection (inextensibility, collisions, grabs) and the velocities. Returns the
/// projection's pull on the held node 1 (`projection::Outcome::root_pull`).
#[inline(always)]
pub(super) fn constrain<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    (grabs, index, projection): (&[Grab], u32, &mut RodProjection<M, N>),
    begun: &Begun<M, N>,
    report: &mut StepReport,
) -> Vec3 {
    couple_root(strand, ctx, begun, report);
    if ctx.gates.projection {
        project_strand::<M, N>(strand, ctx, (grabs, index), projection, report).root_pull
    } else {
        Vec3::ZERO
    }
}

/// What one rod strand transmits to the head this step, `force`, into the report's
/// `head_force`: nothing from a strand rolled back (its step did not happen) or a force
/// that is not finite (no NaN leaves a step).
#[inline(always)]
pub(super) fn transmit_to_head(force: Vec3, rolled_back: bool, report: &mut StepReport) {
    if !rolled_back && crate::math::is_finite(force) {
        report.head_force += force;
    }
}

/// Lines 5–8: root coupling (Sec. 8.1) and the root frame carried in time, the first half
/// of [`constrain`].
#[inline(always)]
pub(super) fn couple_root<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    begun: &Begun<M, N>,
    report: &mut StepReport,
) {
    root_coupling(strand, ctx, report);
    if let Some(tangent) = begun.start.root_tangent {
        carry_root_frame::<M, N>(strand, ctx, tangent);
    }
}

/// Lines 9 (space) and 10 on one strand: the Bishop frame of the new centreline in `frames`,
/// then the twist.
#[inline(always)]
pub(super) fn twist_alone<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    begun: &Begun<M, N>,
    frames: Option<&mut RodFrames<M, N>>,
    angles: &[[Real; 2]; N],
    report: &mut StepReport,
) {
    if let (true, Some(frames)) = (ctx.gates.twist, frames) {
        frames.refresh(strand);
        let saved = begun.start.clamped_frames.as_ref();
        twist::update(strand, ctx, &begun.clamped, frames, saved, angles, report);
    }
}

/// Line 11: the guard, back to `last_good` if the step went wrong. A strand the explicit
/// substeps lost takes the implicit step from now. Returns whether the strand was rolled
/// back.
#[inline(always)]
pub(super) fn judge<const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    index: u32,
    last_good: &StrandState<N>,
    report: &mut StepReport,
) -> bool {
    let verdict = |s: &Strand<N>, _| sound(s, ctx.gates.inextensibility);
    let rolled_back = guard(strand, last_good, verdict, index, report);
    if rolled_back {
        strand.schedule.implicit_bending = true;
    }
    rolled_back
}

/// Lines 3–4 as `k` substeps of `h = dt/k` (`rod::substeps`): each the elastic forces of
/// Kmoch Sec. 7.2 at the current `θ` (line 3, with bending or twist on) and symplectic Euler
/// with the external forces (line 4); with many substeps the segment lengths are projected
/// between them (`rod::substeps::inextensibility_between_substeps`). `frames`, there when
/// bending or twist is on, come in as those of the centreline the step starts from and are
/// recomputed in place for each later substep. Returns `(cos θ^j, sin θ^j)` of the angles
/// the forces used (the hair-optimised twist compares against them) and the mean force on the
/// held nodes 0 and 1 over the step: the elastic forces on them and, between substeps, the
/// projections' pull on node 1 (they run in `solves`).
fn explicit_substeps<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    (mut frames, solves, space): Workspaces<'_, M, N>,
    k: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> Integrated<N> {
    let h = ctx.dt / k as Real;
    let terms = ElasticTerms::of(&ctx.gates);
    let IntegrationSpace { forces, motion } = space;
    // Zero without bending or twist, and where the elastic forces write none.
    *forces = [Vec3::ZERO; N];
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
    motion.restart(strand);
    let between = projects_between_substeps(ctx, k);
    let mut on_root = Vec3::ZERO;
    for substep in 0..k {
        if let Some(frames) = frames.as_deref_mut() {
            // The first substep starts where the frames were computed.
            if substep > 0 {
                frames.refresh(strand);
            }
            let (theta, rest) = (&strand.state.theta, &strand.rest.rod);
            elastic_forces_with_angles(frames, theta, &cos_sin, rest, clamped, terms, forces);
            on_root += elastic_on_root::<M, N>(forces);
        }
        let nodes = Nodes::<M, N> {
            count: strand.rest.nodes,
            position: &mut strand.state.position,
            velocity: &mut strand.state.velocity,
            inverse_mass: &strand.rest.inverse_mass,
        };
        symplectic_euler(nodes, &external, forces, h, accelerations, motion, true);
        if between && substep + 1 < k {
            // Segment lengths between substeps; the step's own projection follows the last.
            let projection = &mut solves.projection;
            on_root += project_between_substeps::<M, N>(strand, ctx, h, projection);
            motion.restart(strand);
        }
    }
    // Each substep's forces act for h = dt/k: their mean over the step.
    (cos_sin, on_root * (1.0 / k as Real))
}

/// The segment lengths projected between two substeps of `h`
/// ([`inextensibility_between_substeps`]) in the workspace `projection`. Returns the
/// projection's pull on the held node 1. Out of line: the substeps' context and the report
/// nobody reads stay off the frame of every strand's step (0.8 KB at 16 nodes on the
/// Cortex-M4F); built for each projection, they cost a copy beside a projection.
#[inline(never)]
fn project_between_substeps<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    h: Real,
    projection: &mut ProjectionScratch<N>,
) -> Vec3 {
    let sub = inextensibility_between_substeps(ctx, h);
    let mut unread = StepReport::default();
    let (at, mode) = ((&[][..], 0), sub.params.mode);
    project_in_scratch::<M, N>(strand, &sub, at, mode, projection, &mut unread).root_pull
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
    (frames, solves, forces): (&RodFrames<M, N>, &mut Solves<M, N>, &mut [Vec3; N]),
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> Integrated<N> {
    report.ran(Stage::ElasticForces);
    report.ran(Stage::ExternalForces);
    report.ran(Stage::Integrate);
    let terms = ElasticTerms::of(&ctx.gates);
    let segments = strand.rest.nodes.min(N).saturating_sub(1);
    let cos_sin = material_angles::<M, N>(&strand.state.theta[..segments]);
    // Zero where the elastic forces write none.
    *forces = [Vec3::ZERO; N];
    let (theta, rest) = (&strand.state.theta, &strand.rest.rod);
    elastic_forces_with_angles(frames, theta, &cos_sin, rest, clamped, terms, forces);
    // The head's motion of nodes 0 and 1 this step: the solve's boundary condition.
    let held = [0, 1].map(|i| held_velocity(ctx, strand, i));
    let system = &mut solves.system;
    let on_root = implicit::step(strand, ctx, (frames, system), forces, held, accelerations);
    (cos_sin, on_root)
}

/// What the step keeps of the configuration it starts from: the root tangent (for the
/// time-parallel transport of `u^0`) and the clamped segments' material frames (for the
/// twist), both there when bending or twist is on.
pub(super) struct StepStart<M: Math> {
    root_tangent: Option<Vec3>,
    clamped_frames: Option<ClampedFrames<M>>,
}
