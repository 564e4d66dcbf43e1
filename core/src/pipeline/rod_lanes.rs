//! The rod's pipeline on a block of `W` strands (Kmoch 2009 Algorithm 1, as
//! [`super::rod::step_strand`] on each). The explicit substeps and the linearly implicit step
//! of lines 3–4, the frame passes, the fast manifold projection (line 9, `projection::lanes`)
//! and the twist (lines 9–10, both methods) run for the block's strands at once, one per lane
//! (`lane::Lanes`), through the very operations a strand runs alone, so every strand gets the
//! bits it gets alone. The other stages run strand by strand: the snapshot and plan, root
//! coupling, the guard.
//!
//! Strands that differ in their substep count are masked once they have taken theirs, and
//! strands that differ in their projection iterations once they have converged; the strands
//! that take the linearly implicit step (`rod::implicit`) take it in lanes too, the others
//! masked. A strand that projects between substeps, or has another node count than the
//! block's, steps alone; so does the twist and the projection of a strand holding a grabbed
//! node.

use crate::context::StepContext;
use crate::forces::{drag, External};
use crate::grab::Grab;
use crate::lane::{Lane, Lanes, Wide, WideMask, V3};
use crate::math::{Math, Real, Vec3};
use crate::projection::lanes::{
    fits_lanes, project_alone, project_strand, BlockProjection, LaneEnding,
};
use crate::report::{Stage, StepReport};
use crate::rod::block::LaneBlock;
use crate::rod::energy::elastic_forces_with_angles;
use crate::rod::frames::RodFrames;
use crate::rod::implicit::{step_nodes, BendingSystem, Loads};
use crate::rod::integrate::{starting_at, symplectic_euler, Nodes};
use crate::rod::substeps::{
    projects_between_substeps, smallest_binormal_denominators_in_lanes, Integration,
};
use crate::rod::twist::{
    hair_optimised_twist_with_angles, newton_twist_in_lanes, ClampedFrames, NewtonSettings,
    TwistMethod,
};
use crate::rod::{ClampedSegments, ElasticTerms, RootOnly};
use crate::root_coupling::{elastic_on_root, held_velocity};
use crate::strand::{Strand, StrandState};

use super::rod::{
    begin, couple_root, integrate, judge, starting_from, transmit, twist_alone, Begun,
    RodProjection, RodScratch, Starting,
};

/// Scratch space for [`step_block`], kept by the caller from step to step: the lanes, their
/// frames, one strand's frames and projection (for the strands that step alone), and the
/// projection's lanes. Built for each block, their zeros and copies were 7 % of Head #1's
/// step in blocks (`perf`). Nothing in it carries from one block or step to the next: each
/// block's step sets what it reads (the lanes are cleared as they are gathered).
pub struct RodBlockScratch<M: Math, const N: usize, const W: usize> {
    /// The block's lanes.
    block: LaneBlock<N, W>,
    /// Each strand's last good state.
    last_good: [StrandState<N>; W],
    /// The lanes' frames.
    lane_frames: RodFrames<Lanes<M, W>, N>,
    /// One strand's frames and projection.
    strand: RodScratch<M, N>,
    /// The projection's lanes, and its ending measured in them.
    projection: BlockProjection<N, W>,
    ending: LaneEnding<N, W>,
}

impl<M: Math, const N: usize, const W: usize> RodBlockScratch<M, N, W> {
    /// Before its first use.
    #[must_use]
    pub const fn new() -> Self {
        RodBlockScratch {
            block: LaneBlock::EMPTY,
            last_good: [const { StrandState::EMPTY }; W],
            lane_frames: RodFrames::empty(),
            strand: RodScratch::new(),
            projection: BlockProjection::new(),
            ending: LaneEnding::new(),
        }
    }
}

impl<M: Math, const N: usize, const W: usize> Default for RodBlockScratch<M, N, W> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M: Math, const N: usize, const W: usize> core::fmt::Debug for RodBlockScratch<M, N, W> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("RodBlockScratch")
    }
}

/// Steps `strands` (at most `W`) by `ctx.dt`, as [`super::rod::step_strand`] steps each, with
/// the same bits. `first_strand` is the index of `strands[0]` in the scene; `accelerations`,
/// if any, holds `N` per strand. `scratch` is scratch space, made once for many blocks.
pub fn step_block<M: Math, const N: usize, const W: usize>(
    strands: &mut [Strand<N>],
    ctx: &StepContext,
    (grabs, first_strand): (&[Grab], u32),
    accelerations: Option<&[Vec3]>,
    scratch: &mut RodBlockScratch<M, N, W>,
    report: &mut StepReport,
) {
    let count = strands.len().min(W);
    let strands = &mut strands[..count];
    // Sec. 5: the lanes' frames of the configuration the step starts from.
    let mut step = BlockStep::<M, N, W>::gather(strands, ctx, accelerations, scratch);
    // Snapshot, clamped set, what the step keeps, the plan: strand by strand.
    step.begin(strands, ctx, grabs, first_strand, report);
    // Lines 3–4: in lanes, or alone.
    step.integrate(strands, ctx, accelerations, report);
    // Lines 5–11, strand by strand.
    step.finish(strands, ctx, (grabs, first_strand), report);
}

/// A block's step in the making: its lanes, their frames, and each strand's start.
struct BlockStep<'s, M: Math, const N: usize, const W: usize> {
    /// Which strands are in the lanes: those with the first one's node count, when strands
    /// have frames (bending or twist on).
    gathered: [bool; W],
    /// Whether the lanes hold a block: two strands or more in them.
    lanes: bool,
    /// The lanes, their frames (of the configuration the step starts from), one strand's
    /// frames (for the strands that step alone and for the twist) and the projections.
    scratch: &'s mut RodBlockScratch<M, N, W>,
    /// Each strand's start.
    begun: [Option<Begun<M, N>>; W],
    /// The substeps each lane takes in the block (0: none there).
    substeps: [u32; W],
    /// The lanes that take the implicit step in the block.
    implicit: [bool; W],
    /// `(cos θ^j, sin θ^j)` each strand's forces used.
    angles: [[[Real; 2]; N]; W],
    /// Each strand's mean elastic force on its held nodes 0 and 1 over the step.
    on_root: [Vec3; W],
}

impl<'s, M: Math, const N: usize, const W: usize> BlockStep<'s, M, N, W> {
    /// The lanes of `strands` and their frames, in `scratch`.
    fn gather(
        strands: &[Strand<N>],
        ctx: &StepContext,
        accelerations: Option<&[Vec3]>,
        scratch: &'s mut RodBlockScratch<M, N, W>,
    ) -> Self {
        let nodes = strands.first().map_or(0, |s| s.rest.nodes);
        let gathered: [bool; W] = core::array::from_fn(|l| {
            ctx.gates.frames && strands.get(l).is_some_and(|s| s.rest.nodes == nodes)
        });
        let lanes = gathered.iter().filter(|&&g| g).count() > 1;
        if lanes {
            let block = &mut scratch.block;
            block.gather::<M>(strands, &gathered, accelerations);
            let (position, rest_length) = (&block.position[..block.nodes], &block.rest.rest_length);
            (scratch.lane_frames).recompute(position, block.root_frame, rest_length);
        }
        BlockStep {
            gathered,
            lanes,
            scratch,
            begun: [const { None }; W],
            substeps: [0; W],
            implicit: [false; W],
            angles: [[[1.0, 0.0]; N]; W],
            on_root: [Vec3::ZERO; W],
        }
    }

    /// Each strand's start (`super::rod::begin`): the plan from its lane's frames, or from
    /// frames of its own; then the substeps each lane takes in the block.
    fn begin(
        &mut self,
        strands: &mut [Strand<N>],
        ctx: &StepContext,
        grabs: &[Grab],
        first_strand: u32,
        report: &mut StepReport,
    ) {
        let has_frames = ctx.gates.frames;
        let RodBlockScratch {
            block,
            last_good,
            lane_frames,
            strand: alone,
            ..
        } = &mut *self.scratch;
        // The sharpest folds of all the lanes at once (a plan that does not ask for its
        // lane's wastes a few packed operations).
        let smallest = if self.lanes && has_frames {
            smallest_binormal_denominators_in_lanes(lane_frames, &block.rest.rest_length)
        } else {
            [2.0; W]
        };
        for ((lane, strand), kept) in strands.iter_mut().enumerate().zip(last_good).take(W) {
            let index = first_strand + lane as u32;
            let at = (grabs, index);
            let started = match (self.lanes, has_frames.then_some(&mut alone.frames)) {
                (true, Some(scratch)) if self.gathered[lane] => {
                    let starting = Starting {
                        has_frames: true,
                        smallest_denominator: |_: &Strand<N>| smallest[lane],
                        clamped_frames: |s: &Strand<N>, clamped: &ClampedSegments| {
                            scratch.refresh(s);
                            Some(ClampedFrames::save(scratch, &s.state.theta, clamped))
                        },
                    };
                    begin(strand, ctx, at, starting, kept, report)
                }
                (_, frames) => {
                    let frames = frames.map(|f| {
                        f.refresh(strand);
                        &*f
                    });
                    begin(strand, ctx, at, starting_from(frames), kept, report)
                }
            };
            self.begun[lane] = Some(started);
        }
        self.substeps = core::array::from_fn(|lane| match &self.begun[lane] {
            Some(b) if self.gathered[lane] => match b.integration {
                Integration::Explicit(k) if plain(ctx, k) => k,
                _ => 0,
            },
            _ => 0,
        });
        if self.substeps.iter().filter(|&&k| k > 0).count() < 2 {
            self.substeps = [0; W];
        }
        // The implicit step runs in lanes whenever the block has lanes, even for one strand:
        // the lanes that switch to it and those that do not are masked, none steps alone.
        self.implicit = core::array::from_fn(|lane| {
            let implicit = |b: &Begun<M, N>| b.integration == Integration::Implicit;
            let started = self.begun[lane].as_ref().is_some_and(implicit);
            self.lanes && self.gathered[lane] && started
        });
    }

    /// Lines 3–4: the lanes' implicit step, then their substeps (which recompute the frames
    /// the implicit step reads), then each strand that steps alone.
    fn integrate(
        &mut self,
        strands: &mut [Strand<N>],
        ctx: &StepContext,
        accelerations: Option<&[Vec3]>,
        report: &mut StepReport,
    ) {
        let clamped = self
            .begun
            .each_ref()
            .map(|b| b.as_ref().map_or_else(Default::default, |b| b.clamped));
        let RodBlockScratch {
            block,
            lane_frames,
            strand: alone,
            ..
        } = &mut *self.scratch;
        if self.lanes && self.implicit.contains(&true) {
            let implicit = &self.implicit;
            let on_root = implicit_in_lanes(
                block,
                lane_frames,
                (strands, implicit),
                ctx,
                &clamped,
                report,
            );
            block.scatter(strands, implicit, &mut self.angles);
            take_lanes(&mut self.on_root, implicit, on_root);
        }
        if self.lanes && self.substeps.iter().any(|&k| k > 0) {
            let substeps = &self.substeps;
            let on_root =
                explicit_substeps_in_lanes(block, lane_frames, ctx, &clamped, substeps, report);
            let in_lanes = substeps.map(|k| k > 0);
            block.scatter(strands, &in_lanes, &mut self.angles);
            take_lanes(&mut self.on_root, &in_lanes, on_root);
        }
        let of_strand = |k: usize| accelerations.and_then(|a| a.get(k * N..(k + 1) * N));
        for (lane, strand) in strands.iter_mut().enumerate().take(W) {
            let on_its_own = self.substeps[lane] == 0 && !self.implicit[lane];
            let Some(begun) = self.begun[lane].as_ref().filter(|_| on_its_own) else {
                continue;
            };
            let frames = ctx.gates.frames.then(|| {
                alone.frames.refresh(strand);
                &mut alone.frames
            });
            let space = (frames, &mut alone.projection.solves, &mut alone.integration);
            let acc = of_strand(lane);
            (self.angles[lane], self.on_root[lane]) =
                integrate(strand, ctx, begun, space, acc, report);
        }
    }

    /// Lines 5–11: the constraints strand by strand (`super::rod::constrain`), the twist of
    /// the lanes' strands in lanes ([`twist_in_lanes`]) and of the others alone, the guard
    /// strand by strand.
    fn finish(
        &mut self,
        strands: &mut [Strand<N>],
        ctx: &StepContext,
        (grabs, first_strand): (&[Grab], u32),
        report: &mut StepReport,
    ) {
        for (lane, strand) in strands.iter_mut().enumerate().take(W) {
            if let Some(begun) = self.begun[lane].as_ref() {
                couple_root(strand, ctx, begun, report);
            }
        }
        let RodBlockScratch {
            block,
            last_good,
            lane_frames,
            strand: alone,
            projection,
            ending,
        } = &mut *self.scratch;
        let projections = ((projection, ending), &mut alone.projection);
        let at = (grabs, first_strand);
        let pulls = project(strands, &self.begun, ctx, at, projections, report);
        // The twist in lanes for the strands in them that hold no segment but the root (a
        // grabbed segment's saved frame is transported strand by strand).
        let in_lanes: [bool; W] = core::array::from_fn(|lane| {
            let free = self.begun[lane]
                .as_ref()
                .is_some_and(|b| b.clamped.others().next().is_none());
            free && self.gathered[lane]
        });
        let lanes_twist = ctx.gates.twist && in_lanes.iter().filter(|&&l| l).count() > 1;
        if lanes_twist {
            twist_in_lanes(block, lane_frames, strands, &in_lanes, ctx, report);
        }
        for (lane, strand) in strands.iter_mut().enumerate().take(W) {
            let Some(begun) = self.begun[lane].as_ref() else {
                continue;
            };
            if !(lanes_twist && in_lanes[lane]) {
                let frames = ctx.gates.frames.then_some(&mut alone.frames);
                twist_alone(strand, ctx, begun, frames, &self.angles[lane], report);
            }
            let index = first_strand + lane as u32;
            let rolled_back = judge(strand, ctx, index, &last_good[lane], report);
            let force = self.on_root[lane] + pulls[lane];
            transmit(strand, ctx, (grabs, index), (force, rolled_back), report);
        }
    }
}

/// Lane `l` of `lanes` into `each[l]` where `taken[l]`.
fn take_lanes<const W: usize>(each: &mut [Vec3; W], taken: &[bool; W], lanes: V3<Wide<W>>) {
    for (l, slot) in each.iter_mut().enumerate() {
        if taken[l] {
            *slot = lanes.lane(l);
        }
    }
}

/// Line 9 (time) of each strand with a start in `begun`: the fast manifold projection, in
/// lanes for the strands laid out alike (`projection::lanes::fits_lanes`) when two or more
/// are, alone for the others; each strand's result taken in scene order. Returns each
/// strand's pull on its held node 1 (`projection::Outcome::root_pull`).
fn project<M: Math, const N: usize, const W: usize>(
    strands: &mut [Strand<N>],
    begun: &[Option<Begun<M, N>>; W],
    ctx: &StepContext,
    (grabs, first_strand): (&[Grab], u32),
    ((lanes, ending), alone): ProjectionScratch<'_, M, N, W>,
    report: &mut StepReport,
) -> [Vec3; W] {
    let mut pulls = [Vec3::ZERO; W];
    if !ctx.gates.projection {
        return pulls;
    }
    let nodes = strands.first().map_or(0, |s| s.rest.nodes.min(N));
    let taken: [bool; W] = core::array::from_fn(|lane| {
        let index = first_strand + lane as u32;
        let fits = |s: &Strand<N>| fits_lanes(s, ctx, grabs, index, nodes);
        begun[lane].is_some() && strands.get(lane).is_some_and(fits)
    });
    let in_lanes = taken.iter().filter(|&&t| t).count() > 1
        && lanes.run_with::<M>(strands, &taken, ctx, Some(&mut *ending));
    for (lane, strand) in strands.iter_mut().enumerate().take(W) {
        if begun[lane].is_none() {
            continue;
        }
        // A strand `taken` fits the lanes' kernel: no second `fits_lanes` for it.
        let outcome = if in_lanes && taken[lane] {
            lanes.finish::<M>(lane, strand, ctx, report, Some(&*ending))
        } else if taken[lane] {
            project_alone::<M, N>(strand, ctx, &mut alone.lanes, report)
        } else {
            let at = (grabs, first_strand + lane as u32);
            project_strand::<M, N>(strand, ctx, at, alone, report)
        };
        pulls[lane] = outcome.root_pull;
    }
    pulls
}

/// The projections' scratch space of a block: its lanes with their ending, and one strand's.
type ProjectionScratch<'s, M, const N: usize, const W: usize> = (
    (&'s mut BlockProjection<N, W>, &'s mut LaneEnding<N, W>),
    &'s mut RodProjection<M, N>,
);

/// Lines 9 (space) and 10 for the strands `in_lanes` names, in lanes: their new centrelines
/// and root frames gathered, the lanes' frame pass, the twist by the scene's method, the
/// angles scattered back. The same kernels as `super::rod::twist_alone` on each strand alone,
/// the hair-optimised twist with the angles its forces used (the block's, from the start of
/// the step); each lane's Newton outcome reported as that strand's.
fn twist_in_lanes<M: Math, const N: usize, const W: usize>(
    block: &mut LaneBlock<N, W>,
    frames: &mut RodFrames<Lanes<M, W>, N>,
    strands: &mut [Strand<N>],
    in_lanes: &[bool; W],
    ctx: &StepContext,
    report: &mut StepReport,
) {
    report.ran_on(Stage::Twist, in_lanes.iter().filter(|&&l| l).count() as u32);
    block.put_centrelines(strands, in_lanes);
    let nodes = block.nodes;
    frames.recompute(
        &block.position[..nodes],
        block.root_frame,
        &block.rest.rest_length,
    );
    let segments = nodes.saturating_sub(1);
    // The strands in lanes hold no segment but the root's (`in_lanes`).
    let (terms, clamped) = (ElasticTerms::of(&ctx.gates), RootOnly);
    let theta = &mut block.theta[..segments];
    match ctx.params.rod.twist {
        TwistMethod::HairOptimised => {
            let cos_sin = &block.cos_sin;
            hair_optimised_twist_with_angles(frames, &block.rest, &clamped, terms, theta, cos_sin);
        }
        TwistMethod::Newton => {
            let settings = NewtonSettings::of(ctx);
            let outcome =
                newton_twist_in_lanes(frames, &block.rest, &clamped, terms, settings, theta);
            for lane in (0..W).filter(|&lane| in_lanes[lane]) {
                outcome.lane(lane).report(report);
            }
        }
    }
    block.take_angles(strands, in_lanes);
}

/// `super::rod::implicit_bending` of the lanes `implicit` names (`strands` are the block's):
/// the elastic forces at the frames the step starts from, the held nodes' velocities strand
/// by strand, then `rod::implicit::step_nodes` in lanes, the other lanes masked. The same
/// kernels on each lane's values, so each strand gets the bits it gets alone.
#[inline(never)]
fn implicit_in_lanes<M: Math, const N: usize, const W: usize>(
    block: &mut LaneBlock<N, W>,
    frames: &RodFrames<Lanes<M, W>, N>,
    (strands, implicit): (&[Strand<N>], &[bool; W]),
    ctx: &StepContext,
    clamped: &[ClampedSegments; W],
    report: &mut StepReport,
) -> V3<Wide<W>> {
    let lanes = implicit.iter().filter(|&&i| i).count() as u32;
    report.ran_on(Stage::ElasticForces, lanes);
    report.ran_on(Stage::ExternalForces, lanes);
    report.ran_on(Stage::Integrate, lanes);
    let terms = ElasticTerms::of(&ctx.gates);
    let mut forces = [V3::<Wide<W>>::zero(); N];
    let (theta, rest, cos_sin) = (&block.theta, &block.rest, &block.cos_sin);
    elastic_forces_with_angles(frames, theta, cos_sin, rest, clamped, terms, &mut forces);
    // The masses and the head's motion of nodes 0 and 1 of the lanes that take the step (the
    // others, masked, keep 1 and 0: finite values).
    let mut mass = [Wide::splat(1.0); N];
    let mut held = [V3::<Wide<W>>::zero(); 2];
    let nodes = block.nodes;
    for (lane, strand) in strands.iter().enumerate().take(W) {
        if implicit[lane] {
            for (slot, m) in mass.iter_mut().zip(&strand.rest.mass).take(nodes) {
                slot.0[lane] = *m;
            }
            for (i, slot) in held.iter_mut().enumerate() {
                slot.set_lane(lane, held_velocity(ctx, strand, i));
            }
        }
    }
    let external = External::<Lanes<M, W>> {
        gravity_and_wind: V3::splat(ctx.gravity + ctx.wind),
        drag: Wide::splat(drag(ctx)),
    };
    let lane_nodes = Nodes::<Lanes<M, W>, N> {
        count: nodes,
        position: &mut block.position,
        velocity: &mut block.velocity,
        inverse_mass: &block.inverse_mass,
    };
    let loads = Loads {
        mass: &mass,
        rest: &block.rest,
        forces: &forces,
        external: &external,
        accelerations: block.accelerations.as_ref().map(|a| &a[..]),
    };
    let h = Wide::splat(ctx.dt);
    let mut system = BendingSystem::default();
    step_nodes(
        lane_nodes,
        &loads,
        (frames, &mut system),
        (h, held),
        WideMask::from_bools(*implicit),
    )
}

/// Whether `k` substeps run without a projection between them (what the lanes do).
fn plain(ctx: &StepContext, k: u32) -> bool {
    !projects_between_substeps(ctx, k)
}

/// `super::rod::explicit_substeps` of the lanes of `block`, lane `l` taking `substeps[l]` of
/// `dt / substeps[l]` (none for 0) and keeping still once it has taken them: the same kernels
/// — frame pass, elastic forces, symplectic Euler — on each lane's values, so each strand gets
/// the bits it gets alone. `frames` come in as those of the configuration the step starts
/// from and are recomputed in place for each later substep. Returns each lane's mean
/// elastic force on its held nodes 0 and 1 over the step.
fn explicit_substeps_in_lanes<M: Math, const N: usize, const W: usize>(
    block: &mut LaneBlock<N, W>,
    frames: &mut RodFrames<Lanes<M, W>, N>,
    ctx: &StepContext,
    clamped: &[ClampedSegments; W],
    substeps: &[u32; W],
    report: &mut StepReport,
) -> V3<Wide<W>> {
    let lanes = substeps.iter().filter(|&&k| k > 0).count() as u32;
    report.ran_on(Stage::ElasticForces, lanes);
    report.ran_on(Stage::ExternalForces, lanes);
    report.ran_on(Stage::Integrate, lanes);
    let most = substeps.iter().copied().max().unwrap_or(0);
    let h = Wide::new(substeps.map(|k| ctx.dt / k.max(1) as Real));
    let terms = ElasticTerms::of(&ctx.gates);
    let external = External::<Lanes<M, W>> {
        gravity_and_wind: V3::splat(ctx.gravity + ctx.wind),
        drag: Wide::splat(drag(ctx)),
    };
    let mut forces = [V3::<Wide<W>>::zero(); N];
    let mut motion = starting_at::<Lanes<M, W>, N>(block.position);
    let nodes = block.nodes;
    let mut on_root = V3::<Wide<W>>::zero();
    for substep in 0..most {
        // The first substep starts where the frames were computed.
        if substep > 0 {
            frames.recompute(
                &block.position[..nodes],
                block.root_frame,
                &block.rest.rest_length,
            );
        }
        let (theta, rest, cos_sin) = (&block.theta, &block.rest, &block.cos_sin);
        elastic_forces_with_angles(frames, theta, cos_sin, rest, clamped, terms, &mut forces);
        let lane_nodes = Nodes::<Lanes<M, W>, N> {
            count: nodes,
            position: &mut block.position,
            velocity: &mut block.velocity,
            inverse_mass: &block.inverse_mass,
        };
        let active = WideMask::from_bools(substeps.map(|k| substep < k));
        let share = elastic_on_root::<Lanes<M, W>, N>(&forces);
        on_root = V3::select(active, on_root + share, on_root);
        let acc = block.accelerations.as_ref().map(|a| &a[..]);
        symplectic_euler(lane_nodes, &external, &forces, h, acc, &mut motion, active);
    }
    // As `super::rod::explicit_substeps`: the mean over each lane's substeps.
    on_root * Wide::new(substeps.map(|k| 1.0 / k.max(1) as Real))
}
