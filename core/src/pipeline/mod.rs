//! The step pipelines: one function per solver that reads top to bottom like its paper's
//! Algorithm 1, one stage per line, each gated once by the step's gates
//! (`context::Gates`): [`rod::step_strand`] (Kmoch 2009) and [`dftl::step_strand`] with
//! [`dftl::step_block`] (Sánchez-Banderas 2015). Every path goes through the same snapshot,
//! root-coupling and guard stages.
//!
//! A step, as every caller runs it (the fixed-capacity `World::step` for firmware, the std
//! harness's `Sim::step` over threads):
//!
//! 1. [`begin`]: the caller's inputs checked — grab targets and releases, the head pose (a
//!    non-finite one is flagged `BAD_INPUT` and the last pose kept) — the step's context built
//!    with DFTL's coefficients from set-up and the wind at the step's end time, and the grabs
//!    no strand can reach let go;
//! 2. the caller's per-node accelerations (the harness's SPH, SB15 Algorithm 1 lines 1–11),
//!    an input of the step;
//! 3. [`step_strands`] on the strands, in blocks of the caller's choosing (or
//!    [`dftl::step_blocks`] on DFTL's structure-of-arrays blocks);
//! 4. [`finish`]: the grabs that slipped during the step let go.

pub mod dftl;
pub mod rod;
pub mod rod_lanes;

use crate::collide::Collider;
use crate::context::StepContext;
use crate::dftl::node::Setup;
use crate::effects::{Effect, Solver};
use crate::grab::{apply_slips, retarget, slip_unreachable, Grab, GrabStatus};
use crate::head::Pose;
use crate::math::{Math, Real, Vec3};
use crate::params::{DftlCoefficients, Params};
use crate::report::{Flags, StepReport, STRETCH_LIMIT};
use crate::strand::Strand;
use crate::stretch::record_stretch;
use dftl::DftlScratch;
use rod::RodScratch;
use rod_lanes::RodBlockScratch;

/// Steps a block of strands by one `ctx.dt` through its solver's pipeline. `first_strand` is
/// the index of `strands[0]` in the whole scene (for grabs and the report); `accelerations`,
/// if any, holds `N` entries per strand of this block. Never panics; a strand that turns
/// non-finite is rolled back.
pub fn step_strands<M: Math, const N: usize>(
    ctx: &StepContext,
    strands: &mut [Strand<N>],
    first_strand: u32,
    grabs: &[Grab],
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let at = (first_strand, grabs);
    step_strands_with::<M, N>(ctx, strands, at, accelerations, None, report);
}

/// The scratch space of [`step_strands_with`] that its caller keeps from step to step (a
/// [`crate::World`] keeps one, inside `hairsim_init`'s buffer for the C ABI): the solver's
/// own, one solver's at a time. Not state: never hashed, snapshotted or cloned (a clone is a
/// new one), and every value a step reads of it, the step has written.
///
/// `repr(u32)`: its first word is the variant, 0 for the rod's, 1 for DFTL's and 2 before a
/// solver is chosen (for a caller that checks a world's raw bytes,
/// `crate::world::WorldLayout::scratch`). A word, not a byte: with a byte and three of
/// padding before the payload, a world built in place built its scratch space on the stack
/// and copied it (3 KB at 16 nodes).
///
/// A world is built with [`StepScratch::Unsuited`], one word to write, and [`Self::suit`]
/// builds the solver's where the solver is set (`World::configure`) and, for a world stepped
/// unconfigured, in its first step. Built with the world, the rod's passed through the
/// optimiser's temporaries on the stack of `hairsim_init` (2.5 KB at 16 nodes, 7.3 KB at 32).
// The variants differ by kilobytes; one is kept at a time, in place (no heap to box the
// larger one in, and boxing would defeat keeping it).
#[allow(clippy::large_enum_variant)]
#[repr(u32)]
pub enum StepScratch<M: Math, const N: usize> {
    /// The rod's: its frames' buffer and its projections' workspaces ([`RodScratch`]).
    Rod(RodScratch<M, N>) = 0,
    /// DFTL's: a strand's pushes on the colliders and the projection workspace of a strand
    /// that a grab holds ([`dftl::DftlScratch`]).
    Dftl(DftlScratch<N>) = 1,
    /// Not built yet: what a world starts with.
    Unsuited = 2,
}

impl<M: Math, const N: usize> StepScratch<M, N> {
    /// Before a solver is chosen: [`Self::suit`] builds the solver's.
    #[must_use]
    pub const fn new() -> Self {
        StepScratch::Unsuited
    }

    /// The scratch space of `solver`, before its first use.
    #[must_use]
    pub fn for_solver(solver: Solver) -> Self {
        let mut scratch = Self::new();
        scratch.suit(solver);
        scratch
    }

    /// Made anew for `solver` unless it is `solver`'s already: where the solver is set (a
    /// world's `configure`) and before each step (a compare, once it is built).
    #[inline(always)]
    pub fn suit(&mut self, solver: Solver) {
        if self.solver() != Some(solver) {
            self.build(solver);
        }
    }

    /// `solver`'s, written where it lives. Out of line and cold: rare, and off the frame of a
    /// step. A solver this build leaves out gets none (`Params::validate` refused it).
    #[cold]
    #[inline(never)]
    fn build(&mut self, solver: Solver) {
        match solver {
            Solver::Rod if cfg!(feature = "rod") => self.build_rod(),
            Solver::Dftl if cfg!(feature = "dftl") => self.build_dftl(),
            Solver::Rod | Solver::Dftl => {}
        }
    }

    /// The rod's, copied from a constant (from flash on the Cortex-M4F): built by code, the
    /// optimiser assembled parts of it, or all of it, on the stack first (19 KB at 16 nodes in
    /// one variant). Apart from DFTL's: one function for both held the temporaries of both.
    #[inline(never)]
    fn build_rod(&mut self) {
        *self = Self::EMPTY_ROD;
    }

    /// The rod's, before its first use.
    const EMPTY_ROD: Self = StepScratch::Rod(RodScratch::new());

    /// DFTL's, built in place.
    #[inline(never)]
    fn build_dftl(&mut self) {
        *self = StepScratch::Dftl(DftlScratch::new());
    }

    /// The solver whose scratch space this is, if it has been built.
    #[must_use]
    pub fn solver(&self) -> Option<Solver> {
        match self {
            StepScratch::Rod(_) => Some(Solver::Rod),
            StepScratch::Dftl(_) => Some(Solver::Dftl),
            StepScratch::Unsuited => None,
        }
    }
}

impl<M: Math, const N: usize> Default for StepScratch<M, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M: Math, const N: usize> Clone for StepScratch<M, N> {
    fn clone(&self) -> Self {
        self.solver().map_or_else(Self::new, Self::for_solver)
    }
}

impl<M: Math, const N: usize> core::fmt::Debug for StepScratch<M, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "StepScratch({:?})", self.solver())
    }
}

/// [`step_strands`] with the scratch space kept by the caller ([`StepScratch`]), so that no
/// step builds one. `None`, or another solver's, builds the rod's for the call (if the
/// solver is the rod) and puts DFTL's held strands' projections on the stack: the same bits.
pub fn step_strands_with<M: Math, const N: usize>(
    ctx: &StepContext,
    strands: &mut [Strand<N>],
    (first_strand, grabs): (u32, &[Grab]),
    accelerations: Option<&[Vec3]>,
    scratch: Option<&mut StepScratch<M, N>>,
    report: &mut StepReport,
) {
    // A solver this build leaves out (`Solver::is_built`) steps nothing: `Params::validate`
    // refused it, and its code is not linked.
    match ctx.params.solver {
        Solver::Rod if cfg!(feature = "rod") => match scratch {
            // One scratch space for all the call's strands.
            Some(StepScratch::Rod(kept)) => {
                step_rod_strands::<M, N>(
                    ctx,
                    strands,
                    (first_strand, grabs),
                    accelerations,
                    kept,
                    report,
                );
            }
            _ => step_rod_strands_in_own::<M, N>(
                ctx,
                strands,
                (first_strand, grabs),
                accelerations,
                report,
            ),
        },
        Solver::Dftl if cfg!(feature = "dftl") => {
            let kept = match scratch {
                Some(StepScratch::Dftl(kept)) => Some(kept),
                _ => None,
            };
            let at = (first_strand, grabs);
            step_dftl_strands::<M, N>(ctx, strands, at, accelerations, kept, report);
        }
        Solver::Rod | Solver::Dftl => {}
    }
}

/// DFTL's strands of [`step_strands_with`] in the scratch space `kept`, if any. Out of line:
/// inlined, its locals (the set-up, the colliders placed for the step) sat in the frame
/// under every rod step too (0.8 KB of the C ABI's `hairsim_step` on the Cortex-M4F).
#[inline(never)]
fn step_dftl_strands<M: Math, const N: usize>(
    ctx: &StepContext,
    strands: &mut [Strand<N>],
    (first_strand, grabs): (u32, &[Grab]),
    accelerations: Option<&[Vec3]>,
    mut kept: Option<&mut DftlScratch<N>>,
    report: &mut StepReport,
) {
    // What a DFTL step derives from the context (the head's rotation matrix among it) is the
    // same for every strand: once per block.
    let setup = Setup::new(ctx);
    if let Some(kept) = kept.as_deref_mut() {
        kept.begin();
    }
    for (k, strand) in strands.iter_mut().enumerate() {
        let index = first_strand + k as u32;
        let at = (grabs, index);
        let work = kept.as_deref_mut();
        let of_strand = accelerations.and_then(|a| a.get(k * N..(k + 1) * N));
        dftl::step_strand::<M, N>(strand, &setup, ctx, at, of_strand, work, report);
    }
}

/// The rod's strands of [`step_strands_with`] in the scratch space `scratch`.
#[inline(always)]
fn step_rod_strands<M: Math, const N: usize>(
    ctx: &StepContext,
    strands: &mut [Strand<N>],
    (first_strand, grabs): (u32, &[Grab]),
    accelerations: Option<&[Vec3]>,
    scratch: &mut RodScratch<M, N>,
    report: &mut StepReport,
) {
    for (k, strand) in strands.iter_mut().enumerate() {
        let at = (grabs, first_strand + k as u32);
        let of_strand = accelerations.and_then(|a| a.get(k * N..(k + 1) * N));
        rod::step_strand::<M, N>(strand, ctx, at, of_strand, scratch, report);
        if !ctx.gates.projection {
            record_stretch::<M, N>(strand, report);
        }
    }
}

/// [`step_rod_strands`] in a scratch space of the call's own: out of line, so that its
/// kilobytes are on the stack only when the caller keeps none.
#[inline(never)]
fn step_rod_strands_in_own<M: Math, const N: usize>(
    ctx: &StepContext,
    strands: &mut [Strand<N>],
    at: (u32, &[Grab]),
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let mut own = RodScratch::<M, N>::new();
    step_rod_strands::<M, N>(ctx, strands, at, accelerations, &mut own, report);
}

/// [`step_strands`] with the rod's strands stepped `W` at a time in lanes
/// ([`rod_lanes::step_block`]): the same bits, whatever `W`. DFTL strands step one by one here (its
/// blocks are [`dftl::step_blocks`]'s).
pub fn step_strands_in_lanes<M: Math, const N: usize, const W: usize>(
    ctx: &StepContext,
    strands: &mut [Strand<N>],
    first_strand: u32,
    grabs: &[Grab],
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let mut scratch = RodBlockScratch::<M, N, W>::new();
    let at = (first_strand, grabs);
    step_strands_in_lanes_with::<M, N, W>(ctx, strands, at, accelerations, &mut scratch, report);
}

/// [`step_strands_in_lanes`] with the scratch space `scratch` the caller keeps from step to
/// step ([`rod_lanes::RodBlockScratch`]: the lanes, their frames and the projections' scratch,
/// tens of kilobytes). Every value a block's step reads of it, it has written in the same
/// call, so the scratch's past never reaches the bits.
pub fn step_strands_in_lanes_with<M: Math, const N: usize, const W: usize>(
    ctx: &StepContext,
    strands: &mut [Strand<N>],
    (first_strand, grabs): (u32, &[Grab]),
    accelerations: Option<&[Vec3]>,
    scratch: &mut RodBlockScratch<M, N, W>,
    report: &mut StepReport,
) {
    if ctx.params.solver != Solver::Rod || !cfg!(feature = "rod") {
        return step_strands::<M, N>(ctx, strands, first_strand, grabs, accelerations, report);
    }
    for (b, block) in strands.chunks_mut(W.max(1)).enumerate() {
        let first = b * W.max(1);
        let accelerations = accelerations.and_then(|a| a.get(first * N..(first + block.len()) * N));
        let at = (grabs, first_strand + first as u32);
        rod_lanes::step_block::<M, N, W>(block, ctx, at, accelerations, scratch, report);
        if !ctx.gates.projection {
            block
                .iter()
                .for_each(|strand| record_stretch::<M, N>(strand, report));
        }
    }
}

/// What a step reads and changes of its caller's world.
#[derive(Debug)]
pub struct Stepping<'a, const N: usize> {
    /// The parameters.
    pub params: &'a Params,
    /// DFTL's coefficients at `params.dt`, computed once at set-up.
    pub dftl: DftlCoefficients,
    /// The colliders.
    pub colliders: &'a [Collider],
    /// The grabs, which the step's inputs move and release.
    pub grabs: &'a mut [Grab],
    /// The strands.
    pub strands: &'a [Strand<N>],
    /// The head's pose at the start of the step.
    pub head: Pose,
    /// Steps taken so far.
    pub steps: u64,
}

/// What the caller hands in for one step, before any check.
#[derive(Clone, Copy, Debug)]
pub struct Inputs<'a> {
    /// The head's pose at the end of the step.
    pub head: Pose,
    /// Each grab's new target (a grab past the end keeps its target).
    pub grab_targets: &'a [Vec3],
    /// Each grab: whether the caller lets go of it now (a grab past the end is kept).
    pub released: &'a [bool],
}

/// Begins a step of `world` with `inputs`: releases and moves the grabs (a non-finite target
/// is ignored and flagged [`Flags::BAD_INPUT`]), takes the head pose (a non-finite one is
/// ignored, flagged, and the last pose kept), builds the step's context at the step's end
/// time `(steps + 1) · dt`, and lets go the grabs no strand can reach
/// (`grab::slip_unreachable`). The context's `head` is the pose the step ends at.
pub fn begin<const N: usize>(
    world: Stepping<'_, N>,
    inputs: &Inputs<'_>,
    report: &mut StepReport,
) -> StepContext {
    for (g, grab) in world.grabs.iter_mut().enumerate() {
        if inputs.released.get(g).copied().unwrap_or(false) {
            grab.status = GrabStatus::Released;
        }
        if let Some(&target) = inputs.grab_targets.get(g) {
            if !retarget(grab, target) {
                report.flags.insert(Flags::BAD_INPUT);
            }
        }
    }
    let head = if inputs.head.is_finite() {
        inputs.head
    } else {
        report.flags.insert(Flags::BAD_INPUT);
        world.head
    };
    flag_inactive(world.params, world.colliders, world.grabs, report);
    slip_unreachable(
        (world.params.effects, &head),
        world.grabs,
        world.strands,
        0,
        report,
    );
    let time = (world.steps + 1) as Real * world.params.dt;
    let poses = (world.head, head);
    // The context is the last expression, so that it is built where the caller keeps it (a
    // local returned is copied, 400 bytes).
    StepContext::at(world.params, world.dftl, poses, world.colliders, time)
}

/// Flags colliders and holding grabs whose effect is off: a scene may switch `collisions` or
/// `grabs` off on purpose, and the report says they did nothing.
fn flag_inactive(params: &Params, colliders: &[Collider], grabs: &[Grab], report: &mut StepReport) {
    if !colliders.is_empty() && !params.effects.contains(Effect::Collisions) {
        report.flags.insert(Flags::COLLIDERS_INACTIVE);
    }
    let holding = grabs.iter().any(|g| g.status == GrabStatus::Held);
    if holding && !params.effects.contains(Effect::Grabs) {
        report.flags.insert(Flags::GRABS_INACTIVE);
    }
}

/// Ends a step: every grab that slipped during it (`report.grabs_slipped`) lets go, and a
/// segment stretched past [`STRETCH_LIMIT`] raises [`Flags::STRETCHED`].
pub fn finish(grabs: &mut [Grab], report: &mut StepReport) {
    apply_slips(grabs, report);
    if crate::math::max(report.max_stretch, report.max_contact_stretch) > STRETCH_LIMIT {
        report.flags.insert(Flags::STRETCHED);
    }
}

#[cfg(test)]
mod tests;
