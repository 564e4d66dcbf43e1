//! The structure-of-arrays block path: `W` strands side by side, node index `k` of every lane
//! together (SB15 Sec. 4's particle-level layout; Jolt's vertex-major stride; Box2D's
//! `b2FloatW`). Each lane runs exactly the per-node functions of the per-strand path
//! ([`super::project_node`], [`collisions`], [`Chain::advance`], [`velocity::finish`]) in the
//! same order, so both paths give the same bits; the lane loops over `[Real; W]` have no
//! cross-lane operation, which lets the compiler vectorise them (no `core::simd`, no unsafe).
//! The only reductions across lanes are maxima and integer counts for the report.
//!
//! Layout, per node `k`: state (`x`, `v`, 24 bytes per vertex, read and written), rest (`l_k`,
//! `1/m_k`, 8 bytes, read) and shape rest (`x̂_k`, `r_k`, `d_k/L`, 28 bytes, read only when the
//! shape constraints run) in three separate arrays so a stage that is off moves no bytes.
//!
//! Vectorisation needs a square root the compiler can vectorise: `libm::sqrtf` is an inline
//! `sqrtss` on x86-64, which it cannot. A std caller can pass a [`Math`] backend whose `sqrt`
//! is `f32::sqrt` (correctly rounded, the same bits) — see the benches' `HostMath`.

// Lane loops index several `[Real; W]` arrays by the same lane: an index reads clearer than a
// zip of six iterators, and `l < W` is the arrays' length, so no index can panic.
#![allow(clippy::needless_range_loop)]

use crate::collide::Shape;
use crate::context::StepContext;
use crate::math::{Math, Quat, Real, Vec3};
use crate::report::{Stage, StepReport};
use crate::strand::Strand;

use super::{collisions, velocity, Chain, NodeInput, Setup, Tally};

/// `W` values, one per strand of a block.
pub type Lanes<const W: usize> = [Real; W];

/// A vector per lane: x, y, z each `W` wide.
pub type VecLanes<const W: usize> = [Lanes<W>; 3];

/// State of node `k` of every lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateLanes<const W: usize> {
    /// `x_k`.
    pub position: VecLanes<W>,
    /// `v_k`.
    pub velocity: VecLanes<W>,
}

/// Rest data of node `k` every step reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestLanes<const W: usize> {
    /// `l_k = |x̂_k − x̂_{k−1}|` (0 for `k = 0`).
    pub segment_length: Lanes<W>,
    /// `1/m_k`.
    pub inverse_mass: Lanes<W>,
}

/// Rest data of node `k` the shape constraints (and root coupling) read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeLanes<const W: usize> {
    /// `x̂_k` in the head's frame.
    pub rest_position: VecLanes<W>,
    /// `r_k`.
    pub local_rest: VecLanes<W>,
    /// `d_k / L`.
    pub root_distance: Lanes<W>,
}

/// Up to `W` strands of up to `N` nodes in structure-of-arrays form.
#[derive(Clone, Debug, PartialEq)]
pub struct DftlBlock<const W: usize, const N: usize> {
    /// Lanes in use: `0 … strands − 1`.
    pub strands: usize,
    /// Node count of each lane (0 for a lane not in use).
    pub nodes: [usize; W],
    /// The largest node count.
    pub max_nodes: usize,
    /// `R̂_0` of each lane: x, y, z, w.
    pub root_frame: [Lanes<W>; 4],
    /// State per node.
    pub state: [StateLanes<W>; N],
    /// Rest data per node.
    pub rest: [RestLanes<W>; N],
    /// Shape rest data per node.
    pub shape: [ShapeLanes<W>; N],
}

impl<const W: usize, const N: usize> Default for DftlBlock<W, N> {
    fn default() -> Self {
        Self::new()
    }
}

#[inline(always)]
fn get<const W: usize>(v: &VecLanes<W>, l: usize) -> Vec3 {
    Vec3::new(v[0][l], v[1][l], v[2][l])
}

#[inline(always)]
fn set<const W: usize>(v: &mut VecLanes<W>, l: usize, value: Vec3) {
    v[0][l] = value.x;
    v[1][l] = value.y;
    v[2][l] = value.z;
}

impl<const W: usize, const N: usize> DftlBlock<W, N> {
    /// An empty block.
    #[must_use]
    pub const fn new() -> Self {
        const { assert!(W >= 1, "a block needs at least one lane") };
        let zero = [[0.0; W]; 3];
        DftlBlock {
            strands: 0,
            nodes: [0; W],
            max_nodes: 0,
            root_frame: [[0.0; W], [0.0; W], [0.0; W], [1.0; W]],
            state: [StateLanes {
                position: zero,
                velocity: zero,
            }; N],
            rest: [RestLanes {
                segment_length: [0.0; W],
                inverse_mass: [0.0; W],
            }; N],
            shape: [ShapeLanes {
                rest_position: zero,
                local_rest: zero,
                root_distance: [0.0; W],
            }; N],
        }
    }

    /// Fills the block with the first `min(W, strands.len())` strands (rest data and state);
    /// unused lanes are emptied. Returns how many strands it took.
    pub fn load(&mut self, strands: &[Strand<N>]) -> usize {
        *self = Self::new();
        let count = strands.len().min(W);
        self.strands = count;
        for (l, strand) in strands.iter().take(count).enumerate() {
            let n = strand.rest.nodes.min(N);
            self.nodes[l] = n;
            self.max_nodes = self.max_nodes.max(n);
            let q = strand.rest.dftl.root_frame;
            for (axis, value) in self.root_frame.iter_mut().zip([q.x, q.y, q.z, q.w]) {
                axis[l] = value;
            }
            for k in 0..n {
                let state = &mut self.state[k];
                set(&mut state.position, l, strand.state.position[k]);
                set(&mut state.velocity, l, strand.state.velocity[k]);
                let rest = &mut self.rest[k];
                rest.segment_length[l] = if k > 0 {
                    strand.rest.segment_length[k - 1]
                } else {
                    0.0
                };
                rest.inverse_mass[l] = strand.rest.inverse_mass[k];
                let shape = &mut self.shape[k];
                set(&mut shape.rest_position, l, strand.rest.position[k]);
                set(&mut shape.local_rest, l, strand.rest.dftl.local_rest[k]);
                shape.root_distance[l] = strand.rest.dftl.root_distance[k];
            }
        }
        count
    }

    /// A block holding the first `min(W, strands.len())` strands.
    #[must_use]
    pub fn from_strands(strands: &[Strand<N>]) -> Self {
        let mut block = Self::new();
        block.load(strands);
        block
    }

    /// Writes the block's state (positions, velocities) back into `strands`, lane `l` into
    /// `strands[l]`; the strands must be the ones loaded, in order.
    pub fn store(&self, strands: &mut [Strand<N>]) {
        for (l, strand) in strands.iter_mut().take(self.strands).enumerate() {
            let n = self.nodes[l].min(strand.rest.nodes).min(N);
            for k in 0..n {
                strand.state.position[k] = get(&self.state[k].position, l);
                strand.state.velocity[k] = get(&self.state[k].velocity, l);
            }
        }
    }
}

/// Steps every block of `blocks` (strand `b·W + l` of the scene is lane `l` of block `b`,
/// counted from `first_strand`). `accelerations`, if any, holds `N` entries per strand from
/// the first strand of `blocks` (as [`crate::world::step_strands`]). The std harness splits
/// the blocks over threads by a fixed partition and merges the reports in block order.
pub fn step_blocks<M: Math, const W: usize, const N: usize>(
    ctx: &StepContext,
    blocks: &mut [DftlBlock<W, N>],
    first_strand: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    for (b, block) in blocks.iter_mut().enumerate() {
        let block_accelerations = accelerations.and_then(|a| a.get(b * W * N..));
        let first = first_strand.wrapping_add((b * W) as u32);
        step_block::<M, W, N>(ctx, block, first, block_accelerations, report);
    }
}

/// Steps one block by `ctx.dt`: snapshot, SB15 Algorithm 1 lane by lane, guard. Gives the bits
/// of [`crate::world::step_strands`] with the DFTL solver on the same strands.
pub fn step_block<M: Math, const W: usize, const N: usize>(
    ctx: &StepContext,
    block: &mut DftlBlock<W, N>,
    first_strand: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let lanes = block.strands.min(W) as u32;
    report.stage_runs[Stage::Snapshot as usize] += lanes;
    let last_good = block.state;
    let setup = Setup::new(ctx);
    report.stage_runs[Stage::RootCoupling as usize] += lanes;
    setup.count_stages(ctx, accelerations.is_some(), lanes, report);
    // The effect switches become constants in each copy of the pass, so a stage that is off
    // is not computed (and the lane loops have no branch to vectorise around).
    let finite = match (setup.shape, setup.inextensibility, setup.drag) {
        (false, false, false) => {
            pass::<M, W, N, false, false, false>(ctx, &setup, block, accelerations, report)
        }
        (false, false, true) => {
            pass::<M, W, N, false, false, true>(ctx, &setup, block, accelerations, report)
        }
        (false, true, false) => {
            pass::<M, W, N, false, true, false>(ctx, &setup, block, accelerations, report)
        }
        (false, true, true) => {
            pass::<M, W, N, false, true, true>(ctx, &setup, block, accelerations, report)
        }
        (true, false, false) => {
            pass::<M, W, N, true, false, false>(ctx, &setup, block, accelerations, report)
        }
        (true, false, true) => {
            pass::<M, W, N, true, false, true>(ctx, &setup, block, accelerations, report)
        }
        (true, true, false) => {
            pass::<M, W, N, true, true, false>(ctx, &setup, block, accelerations, report)
        }
        (true, true, true) => {
            pass::<M, W, N, true, true, true>(ctx, &setup, block, accelerations, report)
        }
    };
    // Guard (as `guard::check`): a lane that turned non-finite gets its last good state back
    // with zero velocity, and the report names it.
    report.stage_runs[Stage::Guard as usize] += lanes;
    for (l, ok) in finite.iter().enumerate().take(block.strands) {
        if *ok {
            continue;
        }
        for (now, good) in block.state.iter_mut().zip(&last_good) {
            for axis in 0..3 {
                now.position[axis][l] = good.position[axis][l];
                now.velocity[axis][l] = 0.0;
            }
        }
        report.roll_back(first_strand.wrapping_add(l as u32));
    }
}

/// Per-lane values carried from node `k − 1` to node `k`.
struct ChainLanes<const W: usize> {
    position: VecLanes<W>,
    frame: [Lanes<W>; 4],
    tangent: VecLanes<W>,
}

impl<const W: usize> ChainLanes<W> {
    #[inline(always)]
    fn get(&self, l: usize) -> Chain {
        Chain {
            position: get(&self.position, l),
            frame: Quat::from_xyzw(
                self.frame[0][l],
                self.frame[1][l],
                self.frame[2][l],
                self.frame[3][l],
            ),
            tangent: get(&self.tangent, l),
        }
    }

    #[inline(always)]
    fn set(&mut self, l: usize, chain: &Chain) {
        set(&mut self.position, l, chain.position);
        let q = chain.frame;
        self.frame[0][l] = q.x;
        self.frame[1][l] = q.y;
        self.frame[2][l] = q.z;
        self.frame[3][l] = q.w;
        set(&mut self.tangent, l, chain.tangent);
    }
}

/// The whole pass over the nodes of a block with the effect switches fixed. Returns which
/// lanes stayed finite.
#[inline(never)]
fn pass<
    M: Math,
    const W: usize,
    const N: usize,
    const SHAPE: bool,
    const INEXTENSIBLE: bool,
    const DRAG: bool,
>(
    ctx: &StepContext,
    setup: &Setup,
    block: &mut DftlBlock<W, N>,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> [bool; W] {
    let setup = Setup {
        shape: SHAPE,
        inextensibility: INEXTENSIBLE,
        drag: DRAG,
        ..*setup
    };
    let nodes = block.nodes;
    let mut finite = [true; W];
    // Line 12's root: nodes 0 and 1 follow the head, as in the rod solver.
    for (state, shape) in block.state.iter_mut().zip(&block.shape).take(2) {
        for l in 0..W {
            let rest = get(&shape.rest_position, l);
            let (x, v) = crate::rod::step::held_node(ctx, rest, get(&state.position, l));
            set(&mut state.position, l, x);
            set(&mut state.velocity, l, v);
            finite[l] &= crate::math::is_finite(x) && crate::math::is_finite(v);
        }
    }
    let max_nodes = block.max_nodes.min(N);
    if max_nodes < 3 {
        return finite;
    }
    let mut chain = ChainLanes {
        position: [[0.0; W]; 3],
        frame: block.root_frame,
        tangent: [[0.0; W]; 3],
    };
    for l in 0..W {
        let root_frame = Quat::from_xyzw(
            chain.frame[0][l],
            chain.frame[1][l],
            chain.frame[2][l],
            chain.frame[3][l],
        );
        let x0 = get(&block.state[0].position, l);
        let x1 = get(&block.state[1].position, l);
        let start = Chain::start::<M>(&setup, root_frame, x0, x1);
        chain.set(l, &start);
    }
    // Per-lane report values and flags as `Real` lanes and selects (no branch in a lane loop,
    // so the compiler vectorises it). Contact flags are 0 or 1.
    let nodes_real: Lanes<W> = core::array::from_fn(|l| nodes[l] as Real);
    let mut stretch: Lanes<W> = [0.0; W];
    let mut contact_stretch: Lanes<W> = [0.0; W];
    let mut penetration: Lanes<W> = [0.0; W];
    let mut contacts: Lanes<W> = [0.0; W];
    // 0 while every value a lane wrote is finite (x − x is NaN for ±∞ and NaN).
    let mut poison: Lanes<W> = [0.0; W];
    let mut previous_contact: Lanes<W> = [0.0; W];
    for k in 2..max_nodes {
        let (done, todo) = block.state.split_at_mut(k);
        let (Some(previous), Some(state), Some(rest), Some(shape)) = (
            done.last_mut(),
            todo.first_mut(),
            block.rest.get(k),
            block.shape.get(k),
        ) else {
            break;
        };
        let node = k as Real;
        // Lines 13–19: predict, shape, follow the leader.
        let mut x = [[0.0; W]; 3];
        let mut correction = [[0.0; W]; 3];
        match accelerations {
            None => project_lanes::<M, W>(
                &setup,
                state,
                rest,
                shape,
                &chain,
                &mut x,
                &mut correction,
                |_| None,
            ),
            Some(a) => project_lanes::<M, W>(
                &setup,
                state,
                rest,
                shape,
                &chain,
                &mut x,
                &mut correction,
                |l| a.get(l * N + k).copied(),
            ),
        }
        // Line 20: collisions, one collider over all lanes at a time (the same order of
        // colliders as the per-strand path, so the same bits).
        let mut contact = [0.0; W];
        if setup.collisions {
            for collider in ctx.colliders() {
                push_out_lanes::<M, W>(collider, &mut x, &mut contact);
            }
            for collider in ctx.colliders() {
                for l in 0..W {
                    let depth = collisions::depth::<M>(collider, get(&x, l));
                    let depth = if node < nodes_real[l] { depth } else { 0.0 };
                    penetration[l] = penetration[l].max(depth);
                }
            }
            for l in 0..W {
                contacts[l] += if node < nodes_real[l] {
                    contact[l]
                } else {
                    0.0
                };
            }
        }
        // Line 21 and lines 24–26 for node k − 1.
        let after_first = k > 2;
        for l in 0..W {
            let active = node < nodes_real[l];
            // Node k − 1 exists in this lane (and is free): finish it now.
            let finishing = after_first && node - 1.0 < nodes_real[l];
            let here = chain.get(l);
            let (next, s) = here.advance::<M>(&setup, get(&x, l), rest.segment_length[l]);
            let touched = contact[l] + previous_contact[l] > 0.0;
            stretch[l] = stretch[l].max(if active && !touched { s } else { 0.0 });
            contact_stretch[l] = contact_stretch[l].max(if active && touched { s } else { 0.0 });
            // The last node of a lane (k == nodes[l]) gets no correction.
            let next_correction = if active {
                get(&correction, l)
            } else {
                Vec3::ZERO
            };
            let old_position = get(&previous.position, l);
            let old_velocity = get(&previous.velocity, l);
            let (x_new, v_new) =
                velocity::finish(&setup, here.position, old_position, next_correction);
            let (x_new, v_new) = if finishing {
                (x_new, v_new)
            } else {
                (old_position, old_velocity)
            };
            set(&mut previous.position, l, x_new);
            set(&mut previous.velocity, l, v_new);
            poison[l] += not_finite(x_new) + not_finite(v_new);
            let kept = if active { next } else { here };
            chain.set(l, &kept);
            previous_contact[l] = if active {
                contact[l]
            } else {
                previous_contact[l]
            };
        }
    }
    // The last node of the longest lanes: no correction.
    if let Some(last) = block.state.get_mut(max_nodes - 1) {
        let longest = max_nodes as Real;
        for l in 0..W {
            let here = chain.get(l);
            let old_position = get(&last.position, l);
            let old_velocity = get(&last.velocity, l);
            let (x_new, v_new) = velocity::finish(&setup, here.position, old_position, Vec3::ZERO);
            let (x_new, v_new) = if nodes_real[l] == longest {
                (x_new, v_new)
            } else {
                (old_position, old_velocity)
            };
            set(&mut last.position, l, x_new);
            set(&mut last.velocity, l, v_new);
            poison[l] += not_finite(x_new) + not_finite(v_new);
        }
    }
    for l in 0..block.strands.min(W) {
        Tally {
            stretch: stretch[l],
            contact_stretch: contact_stretch[l],
            penetration: penetration[l],
            contacts: contacts[l] as u32,
        }
        .report(report);
        finite[l] &= poison[l] == 0.0;
    }
    finite
}

/// 0 when every component of `v` is finite, NaN otherwise (`x − x`), summed per lane.
#[inline(always)]
#[allow(clippy::eq_op)] // x − x is the point: 0 for finite x, NaN for ±∞ and NaN.
fn not_finite(v: Vec3) -> Real {
    (v.x - v.x) + (v.y - v.y) + (v.z - v.z)
}

/// Lines 13–19 over the lanes of one node.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn project_lanes<M: Math, const W: usize>(
    setup: &Setup,
    state: &StateLanes<W>,
    rest: &RestLanes<W>,
    shape: &ShapeLanes<W>,
    chain: &ChainLanes<W>,
    x: &mut VecLanes<W>,
    correction: &mut VecLanes<W>,
    extra: impl Fn(usize) -> Option<Vec3>,
) {
    for l in 0..W {
        let node = NodeInput {
            position: get(&state.position, l),
            velocity: get(&state.velocity, l),
            extra: extra(l),
            inverse_mass: rest.inverse_mass[l],
            rest_position: get(&shape.rest_position, l),
            local_rest: get(&shape.local_rest, l),
            root_distance: shape.root_distance[l],
            segment_length: rest.segment_length[l],
        };
        let (projected, c) = super::project_node::<M>(setup, &node, &chain.get(l));
        set(x, l, projected);
        set(correction, l, c);
    }
}

/// Line 20 for one collider over the lanes of one node.
#[inline(always)]
fn push_out_lanes<M: Math, const W: usize>(
    collider: &Shape,
    x: &mut VecLanes<W>,
    contact: &mut Lanes<W>,
) {
    for l in 0..W {
        let (pushed, inside) = collisions::push_out::<M>(collider, get(x, l));
        set(x, l, pushed);
        contact[l] = if inside { 1.0 } else { contact[l] };
    }
}
