//! A running simulation: the harness owns a `Vec<Strand<N>>` and steps it in blocks of a
//! fixed size (the scene's `strands_per_block`), on as many threads as asked. Each block gets
//! its own [`StepReport`] and the reports are merged in block order, so every bit of the state
//! and of the report is the same whatever the thread count.
//!
//! A step is the core's pipeline (`hairsim_core::pipeline`): the core begins it and ends it,
//! and in between the harness adds SPH's accelerations and steps the blocks. The Kirchhoff rod
//! steps each strand with [`hairsim_core::step_strands`]. DFTL steps each block as
//! structure-of-arrays [`DftlBlock`]s of [`RECOMMENDED_LANES`] strands
//! ([`hairsim_core::step_strands_in_blocks`]: the same bits as the per-strand path, several times
//! faster): the blocks keep the rest data, loaded once; every step copies the state in from
//! the strands, steps, and copies it back while it is still in cache, so `strands` stays the
//! state anyone reads or writes.

use hairsim_core::context::StepContext;
use hairsim_core::dftl::DftlBlock;
use hairsim_core::params::DftlCoefficients;
use hairsim_core::pipeline::step_strands_with;
use hairsim_core::pipeline::{self, Inputs, Stepping};
use hairsim_core::{
    step_strands, step_strands_in_blocks, step_strands_in_lanes_with, Collider, Grab, Math, Params,
    Pose, RodBlockScratch, Solver, Stage, StepReport, StepScratch, Strand, Vec3,
};
use rayon::prelude::*;

use crate::scene::{FieldError, Prepared};
use crate::sph::Sph;

pub use crate::scene::start::{scene_inputs, time_after, StepInputs};

pub use crate::lanes::VectorSqrt;
use crate::lanes::{DFTL_LANES as LANES, ROD_LANES};

/// How a simulation steps its strands: the bits are the same either way, only the speed
/// differs (the golden hashes pin both).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Layout {
    /// Structure-of-arrays blocks of several strands in lanes, where the solver has them.
    #[default]
    Blocks,
    /// One strand at a time.
    PerStrand,
}

/// A simulation of strands with capacity `N`, math backend `M`.
pub struct Sim<const N: usize, M: Math> {
    /// Parameters.
    pub params: Params,
    /// The strands.
    pub strands: Vec<Strand<N>>,
    /// Colliders.
    pub colliders: Vec<Collider>,
    /// Grabs.
    pub grabs: Vec<Grab>,
    /// The head's current pose.
    pub head: Pose,
    /// Steps taken.
    pub steps: u64,
    /// The SPH stage, when `hair-hair` is on.
    pub sph: Option<Sph>,
    block: usize,
    /// DFTL only: each block of `block` strands as `block.div_ceil(LANES)` SoA blocks, in
    /// strand order (rest data loaded once; the state copied in and out every step).
    dftl_blocks: Vec<DftlBlock<LANES, N>>,
    dftl: DftlCoefficients,
    /// One report per block of strands, reused every step (a step allocates nothing).
    block_reports: Vec<StepReport>,
    /// The rod's scratch space of each block of strands, kept from step to step (none for
    /// DFTL).
    rod_scratch: Vec<KeptScratch<M, N>>,
    pool: Option<std::sync::Arc<rayon::ThreadPool>>,
    math: std::marker::PhantomData<M>,
}

impl<const N: usize, M: Math> Sim<N, M> {
    /// Builds the strands of `prepared` at capacity `N`, to be stepped on `threads` threads.
    pub fn new(prepared: &Prepared, threads: usize) -> Result<Self, FieldError> {
        Self::with_layout(prepared, threads, Layout::Blocks)
    }

    /// As [`Sim::new`], stepping the strands in `layout`.
    pub fn with_layout(
        prepared: &Prepared,
        threads: usize,
        layout: Layout,
    ) -> Result<Self, FieldError> {
        let (strands, head) = prepared.start_strands::<N, M>()?;
        let grabs = prepared.start_grabs::<M>();
        // A pool even for one thread when SPH runs: its parallel passes would otherwise go to
        // rayon's global pool, with a thread per core.
        let pool = if threads > 1 || prepared.sph.is_some() {
            Some(std::sync::Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .map_err(|e| {
                        FieldError::new("--threads", format!("cannot start threads: {e}"))
                    })?,
            ))
        } else {
            None
        };
        let sph = match &prepared.sph {
            Some(params) => {
                Some(Sph::new(*params, &strands).map_err(|e| FieldError::new("hair-hair", e))?)
            }
            None => None,
        };
        let block = prepared.block.max(1);
        let dftl_blocks = match (prepared.params.solver, layout) {
            (Solver::Dftl, Layout::Blocks) => strands
                .chunks(block)
                .flat_map(|b| b.chunks(LANES))
                .map(DftlBlock::from_strands)
                .collect(),
            _ => Vec::new(),
        };
        let blocks = strands.len().div_ceil(block);
        let rod_scratch = (0..blocks)
            .map(|_| KeptScratch::of(prepared.params.solver, layout))
            .collect();
        Ok(Sim {
            params: prepared.params,
            block_reports: vec![StepReport::default(); blocks],
            rod_scratch,
            strands,
            colliders: prepared.colliders.clone(),
            grabs,
            head,
            steps: 0,
            sph,
            block,
            dftl_blocks,
            // Computed once, as `World::configure` does (two divisions, never per step).
            dftl: prepared.params.dftl.at_step(prepared.params.dt),
            pool,
            math: std::marker::PhantomData,
        })
    }

    /// The state hash of every strand (the core's order).
    #[must_use]
    pub fn state_hash(&self) -> u64 {
        hairsim_core::hash::state_hash(&self.strands)
    }

    /// Whether every strand's state is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.strands.iter().all(Strand::is_finite)
    }

    /// Runs `f` on this simulation inside its thread pool (directly when it has none). Steps
    /// taken inside do not hand work to the pool from outside at every step: a whole run can
    /// go through here, and so can a test that counts allocations (rayon's queue for work
    /// injected from outside allocates a block now and then; a worker's own deque does not).
    pub fn in_pool<R: Send>(&mut self, f: impl FnOnce(&mut Self) -> R + Send) -> R
    where
        M: Send,
    {
        match self.pool.clone() {
            Some(pool) => pool.install(|| f(self)),
            None => f(self),
        }
    }

    /// Advances by one step with `inputs`, a thin caller of the core's pipeline
    /// (`hairsim_core::pipeline`): the core begins the step (input checks, context, grabs out
    /// of reach), SPH adds its accelerations (SB15 Algorithm 1 lines 1–11, an input of the
    /// step), the strands step through their solver's pipeline in blocks over threads, and
    /// the core ends the step.
    #[deny(clippy::too_many_lines, clippy::too_many_arguments)]
    pub fn step(&mut self, inputs: &StepInputs) -> StepReport {
        let mut report = StepReport::default();
        let world = Stepping {
            params: &self.params,
            dftl: self.dftl,
            colliders: &self.colliders,
            grabs: &mut self.grabs,
            strands: &self.strands,
            head: self.head,
            steps: self.steps,
        };
        let inputs = Inputs {
            head: inputs.head,
            grab_targets: &inputs.grab_targets,
            released: &inputs.released,
        };
        let ctx = pipeline::begin(world, &inputs, &mut report);
        let hair_hair = self.hair_hair(&ctx, &mut report);
        self.step_blocks(&ctx, hair_hair, &mut report);
        pipeline::finish(&mut self.grabs, &mut report);
        self.head = ctx.head;
        self.steps += 1;
        report
    }

    /// The SPH stage, when `hair-hair` is on and set up: every node's acceleration into the
    /// stage's output ([`Sph::output`]), counted like the core's stages (the strands it ran on). Returns
    /// whether it ran.
    fn hair_hair(&mut self, ctx: &StepContext, report: &mut StepReport) -> bool {
        let Some(sph) = self.sph.as_mut().filter(|_| ctx.gates.hair_hair) else {
            return false;
        };
        // The strands' state is the previous step's end: the head was at its previous pose.
        let (strands, dt, head) = (&self.strands, ctx.dt, ctx.previous_head);
        match &self.pool {
            Some(pool) => pool.install(|| {
                sph.accelerations(strands, dt, head);
            }),
            None => {
                sph.accelerations(strands, dt, head);
            }
        }
        report.ran_on(
            Stage::HairHair,
            u32::try_from(strands.len()).unwrap_or(u32::MAX),
        );
        true
    }

    /// The strands' step through their solver's pipeline, block by block (on the pool when
    /// there is more than one block), each block with a report of its own, merged in block
    /// order — never completion order: the same sums whatever the thread count.
    fn step_blocks(&mut self, ctx: &StepContext, hair_hair: bool, report: &mut StepReport) {
        let blocks = Blocks {
            ctx,
            block: self.block,
            grabs: &self.grabs,
            accelerations: self
                .sph
                .as_ref()
                .filter(|_| hair_hair)
                .map(|s| (s.output(), s.acting())),
        };
        let reports = &mut self.block_reports;
        let parallel = self.pool.as_ref().filter(|_| reports.len() > 1);
        if self.dftl_blocks.is_empty() {
            let scratch = &mut self.rod_scratch;
            blocks.per_strand::<N, M>(&mut self.strands, reports, scratch, parallel);
        } else {
            blocks.soa::<N, M>(&mut self.strands, &mut self.dftl_blocks, reports, parallel);
        }
        for r in reports.iter() {
            report.merge(r);
        }
    }
}

/// What every block of a step shares: the context, the block size, the grabs and the
/// accelerations of all strands with whether any acts on each strand.
struct Blocks<'a> {
    ctx: &'a StepContext,
    block: usize,
    grabs: &'a [Grab],
    accelerations: Option<(&'a [Vec3], &'a [bool])>,
}

/// The rod's scratch space of one block of strands: the lanes' (with the lanes' square root,
/// [`VectorSqrt`]) or one strand's.
enum KeptScratch<M: Math, const N: usize> {
    /// Rod strands in lanes of [`ROD_LANES`].
    Blocks(Box<RodBlockScratch<VectorSqrt<M>, N, ROD_LANES>>),
    /// Rod strands one at a time.
    PerStrand(Box<StepScratch<M, N>>),
    /// DFTL: none.
    None,
}

impl<M: Math, const N: usize> KeptScratch<M, N> {
    /// The scratch space `solver` stepped in `layout` uses.
    fn of(solver: Solver, layout: Layout) -> Self {
        match (solver, layout) {
            (Solver::Rod, Layout::Blocks) => KeptScratch::Blocks(Box::default()),
            (Solver::Rod, Layout::PerStrand) => {
                KeptScratch::PerStrand(Box::new(StepScratch::for_solver(Solver::Rod)))
            }
            (Solver::Dftl, _) => KeptScratch::None,
        }
    }
}

impl Blocks<'_> {
    /// The accelerations of block `b` of `strands` strands; none where no node of the block
    /// has a neighbour (the step then runs without the input, as it does without hair–hair).
    fn of_block<const N: usize>(&self, b: usize, strands: usize) -> Option<&[Vec3]> {
        let first = b * self.block;
        let (accelerations, acting) = self.accelerations?;
        acting
            .get(first..first + strands)?
            .iter()
            .any(|&a| a)
            .then(|| accelerations.get(first * N..(first + strands) * N))
            .flatten()
    }

    /// Every block of `strands` through the core's per-strand pipeline, the rod's in lanes
    /// or one strand at a time, with each block's scratch space of `scratch` (as many as
    /// `reports`).
    fn per_strand<const N: usize, M: Math>(
        &self,
        strands: &mut [Strand<N>],
        reports: &mut [StepReport],
        scratch: &mut [KeptScratch<M, N>],
        parallel: Option<&std::sync::Arc<rayon::ThreadPool>>,
    ) {
        let step = |b: usize,
                    strands: &mut [Strand<N>],
                    (r, s): (&mut StepReport, &mut KeptScratch<M, N>)| {
            *r = StepReport::default();
            let acc = self.of_block::<N>(b, strands.len());
            let first = (b * self.block) as u32;
            let (ctx, grabs) = (self.ctx, self.grabs);
            let at = (first, grabs);
            match s {
                KeptScratch::Blocks(scratch) => {
                    step_strands_in_lanes_with(ctx, strands, at, acc, scratch, r);
                }
                KeptScratch::PerStrand(scratch) => {
                    step_strands_with::<M, N>(ctx, strands, at, acc, Some(scratch), r);
                }
                KeptScratch::None => step_strands::<M, N>(ctx, strands, first, grabs, acc, r),
            }
        };
        match parallel {
            Some(pool) => pool.install(|| {
                let per_block = reports.par_iter_mut().zip(scratch.par_iter_mut());
                let blocks = strands.par_chunks_mut(self.block).zip(per_block);
                blocks
                    .enumerate()
                    .for_each(|(b, (strands, r))| step(b, strands, r));
            }),
            None => {
                let per_block = reports.iter_mut().zip(scratch.iter_mut());
                let blocks = strands.chunks_mut(self.block).zip(per_block);
                for (b, (strands, r)) in blocks.enumerate() {
                    step(b, strands, r);
                }
            }
        }
    }

    /// Every block of `strands` through the core's block pipeline
    /// ([`step_strands_in_blocks`]): each block's state copied into its SoA blocks `soa`,
    /// stepped, and copied back while it is still in cache; the SoA blocks holding a strand a
    /// grab holds step one strand at a time.
    fn soa<const N: usize, M: Math>(
        &self,
        strands: &mut [Strand<N>],
        soa: &mut [DftlBlock<LANES, N>],
        reports: &mut [StepReport],
        parallel: Option<&std::sync::Arc<rayon::ThreadPool>>,
    ) {
        let per_block = self.block.div_ceil(LANES);
        let step = |b: usize,
                    strands: &mut [Strand<N>],
                    blocks: &mut [DftlBlock<LANES, N>],
                    r: &mut StepReport| {
            *r = StepReport::default();
            let acc = self.of_block::<N>(b, strands.len());
            let at = ((b * self.block) as u32, self.grabs);
            step_strands_in_blocks::<VectorSqrt<M>, LANES, N>(
                self.ctx, blocks, strands, at, acc, r,
            );
        };
        match parallel {
            Some(pool) => pool.install(|| {
                let blocks = strands.par_chunks_mut(self.block);
                let blocks = blocks.zip(soa.par_chunks_mut(per_block));
                blocks
                    .zip(reports.par_iter_mut())
                    .enumerate()
                    .for_each(|(b, ((strands, blocks), r))| step(b, strands, blocks, r));
            }),
            None => {
                let blocks = strands
                    .chunks_mut(self.block)
                    .zip(soa.chunks_mut(per_block));
                for (b, ((strands, blocks), r)) in blocks.zip(reports.iter_mut()).enumerate() {
                    step(b, strands, blocks, r);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hairsim_core::DefaultMath;

    /// The DFTL block path gives the per-strand path's bits (the state and every report),
    /// with hair–hair accelerations, collisions, shape and a turning head, on blocks of a size
    /// that is not a multiple of the lanes (so blocks end in part-filled lanes).
    #[test]
    fn dftl_blocks_step_as_the_per_strand_path() {
        let mut scene = (crate::builtin::find("mannequin-b").unwrap().scene)();
        scene.strands_per_block = Some(44);
        let prepared = scene.prepare().unwrap();
        let mut blocks = Sim::<16, DefaultMath>::new(&prepared, 2).unwrap();
        let mut per_strand =
            Sim::<16, DefaultMath>::with_layout(&prepared, 2, Layout::PerStrand).unwrap();
        // 11 blocks of 44 strands (6 SoA blocks of 8 lanes, the last with 4 strands), then
        // 16 strands (8 + 8).
        assert_eq!(blocks.dftl_blocks.len(), 11 * 6 + 2);
        for k in 0..40 {
            let inputs = scene_inputs::<DefaultMath>(&prepared, k);
            let a = blocks.in_pool(|s| s.step(&inputs));
            let b = per_strand.in_pool(|s| s.step(&inputs));
            assert_eq!(a, b, "report of step {k}");
            assert_eq!(blocks.state_hash(), per_strand.state_hash(), "step {k}");
        }
        assert!(blocks.sph.as_ref().unwrap().stats.neighbours > 0);
    }
}
