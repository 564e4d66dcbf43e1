//! The structure-of-arrays block path: `W` strands side by side, node index `k` of every lane
//! together (SB15 Sec. 4's particle-level layout; Jolt's vertex-major stride; Box2D's
//! `b2FloatW`). Each lane runs exactly the per-node functions of the per-strand path
//! ([`super::advance`], [`super::collisions::push_out`], [`super::velocity::finish`]) in the
//! same order, written once on lanes ([`super::lane`]): with `T = Wide<W>` every operation is
//! a loop over `[Real; W]` with no cross-lane term, which the compiler turns into packed
//! instructions (no `core::simd`, no unsafe), and both paths give the same bits.
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

use crate::context::StepContext;
use crate::math::{Math, Real, Vec3};
use crate::report::{Stage, StepReport};
use crate::strand::Strand;

use super::lane::{Lane, Wide, WideMask, Q, V3};
use super::{advance, velocity, Chain, ColliderPush, Measures, NodeInput, Setup, Tally};
use crate::collide::MAX_COLLIDERS;

/// Lanes per block the harness should use on x86-64: measured fastest — on the SSE2 baseline
/// 16 lanes ran ≈ 2.5× faster than 8 and than 32 (both spill far more), and with
/// `-C target-cpu=x86-64-v3` (AVX2; the same bits: Rust never fuses a multiply-add) 16 lanes
/// ran ≈ 1.3× faster again.
pub const RECOMMENDED_LANES: usize = 16;

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
    /// `1/(2 l_k²)` (0 for `k = 0`).
    pub strain_scale: Lanes<W>,
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
    /// `t̂_0 = R̂_0 e_x` of each lane.
    pub root_tangent: VecLanes<W>,
    /// `n̂_0 = R̂_0 e_y` of each lane.
    pub root_normal: VecLanes<W>,
    /// State per node.
    pub state: [StateLanes<W>; N],
    /// Rest data per node.
    pub rest: [RestLanes<W>; N],
    /// Shape rest data per node.
    pub shape: [ShapeLanes<W>; N],
    /// `m_k` per node: read only where a collider pushes a node, so kept out of the rest
    /// data every node reads.
    pub mass: [Lanes<W>; N],
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
            root_tangent: zero,
            root_normal: zero,
            state: [StateLanes {
                position: zero,
                velocity: zero,
            }; N],
            rest: [RestLanes {
                segment_length: [0.0; W],
                inverse_mass: [0.0; W],
                strain_scale: [0.0; W],
            }; N],
            shape: [ShapeLanes {
                rest_position: zero,
                local_rest: zero,
                root_distance: [0.0; W],
            }; N],
            mass: [[0.0; W]; N],
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
            set(&mut self.root_tangent, l, strand.rest.dftl.root_tangent);
            set(&mut self.root_normal, l, strand.rest.dftl.root_normal);
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
                self.mass[k][l] = strand.rest.mass[k];
                rest.strain_scale[l] = strand.rest.dftl.strain_scale[k];
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
    let finite = with_effect_switches!(
        setup,
        pass::<M, W, N>(ctx, &setup, block, accelerations, report)
    );
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

#[inline(always)]
fn load<const W: usize>(v: &VecLanes<W>) -> V3<Wide<W>> {
    V3 {
        x: Wide(v[0]),
        y: Wide(v[1]),
        z: Wide(v[2]),
    }
}

#[inline(always)]
fn store<const W: usize>(v: &mut VecLanes<W>, value: V3<Wide<W>>) {
    *v = [value.x.0, value.y.0, value.z.0];
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
    let nodes_real = Wide(core::array::from_fn(|l| nodes[l] as Real));
    let zero = Wide::splat(0.0);
    // 0 while every value a lane wrote is finite.
    let mut poison = zero;
    // Line 12's root: nodes 0 and 1 follow the head, as in the rod solver
    // (`rod::step::held_node`, the same operations on every lane).
    let head_rotation = Q::<Wide<W>>::splat(ctx.head.rotation);
    let head_position = V3::splat(ctx.head.position);
    let inv_dt = Wide::splat(ctx.inv_dt);
    for (state, shape) in block.state.iter_mut().zip(&block.shape).take(2) {
        let target = head_rotation.rotate(load(&shape.rest_position)) + head_position;
        let velocity = (target - load(&state.position)).scale(inv_dt);
        store(&mut state.position, target);
        store(&mut state.velocity, velocity);
        poison = poison + velocity::not_finite(velocity);
    }
    let max_nodes = block.max_nodes.min(N);
    if max_nodes < 3 {
        return core::array::from_fn(|l| poison.0[l] == 0.0);
    }
    // The chain at node 1: `R_head R̂_0`, all lanes at once.
    let mut chain = Chain::start(
        &setup,
        load(&block.root_tangent),
        load(&block.root_normal),
        load(&block.state[1].position),
    );
    let mut measures: Measures<Wide<W>> = Measures::default();
    let mut collider_push: ColliderPush<Wide<W>> = [V3::zero(); MAX_COLLIDERS];
    let mut previous_contact = Wide::<W>::mask(false);
    // Nodes every lane has: there every lane is active and every selection below is a
    // constant (the same bits as the masked form, without its blends).
    let common = nodes.iter().copied().min().unwrap_or(0).min(max_nodes);
    for k in 2..max_nodes {
        let carried = Carried {
            chain: &mut chain,
            measures: &mut measures,
            collider_push: &mut collider_push,
            previous_contact: &mut previous_contact,
            poison: &mut poison,
        };
        // Node 2 finishes nothing (node 1 is held); past the shortest lane the masks select.
        let (b, a, n) = (&mut *block, accelerations, nodes_real);
        match (k == 2, k < common) {
            (true, true) => node::<M, W, N, true, false>(ctx, &setup, b, k, n, a, carried),
            (true, false) => node::<M, W, N, false, false>(ctx, &setup, b, k, n, a, carried),
            (false, true) => node::<M, W, N, true, true>(ctx, &setup, b, k, n, a, carried),
            (false, false) => node::<M, W, N, false, true>(ctx, &setup, b, k, n, a, carried),
        }
    }
    // The last node of the longest lanes: no correction.
    if let Some(last) = block.state.get_mut(max_nodes - 1) {
        let longest = WideMask(core::array::from_fn(|l| nodes[l] == max_nodes));
        let old_position = load(&last.position);
        let old_velocity = load(&last.velocity);
        let (x_new, v_new) = velocity::finish(&setup, chain.position, old_position, V3::zero());
        let x_new = V3::select(longest, x_new, old_position);
        let v_new = V3::select(longest, v_new, old_velocity);
        store(&mut last.position, x_new);
        store(&mut last.velocity, v_new);
        poison = poison + velocity::not_finite(v_new);
    }
    let (stretch, contact_stretch) = measures.stretches::<M>();
    for l in 0..block.strands.min(W) {
        // The pushes are only read with colliders in the scene: no lane gathering without.
        let collider_push = if setup.collisions {
            collider_push.map(|v| Vec3::new(v.x.0[l], v.y.0[l], v.z.0[l]))
        } else {
            [Vec3::ZERO; MAX_COLLIDERS]
        };
        let tally = Tally {
            stretch: stretch.0[l],
            contact_stretch: contact_stretch.0[l],
            penetration: measures.penetration.0[l],
            contacts: measures.contacts.0[l] as u32,
            collider_push,
        };
        tally.report(report, ctx.colliders().len(), setup.inv_dt);
    }
    core::array::from_fn(|l| poison.0[l] == 0.0)
}

/// What the node loop carries from node to node.
struct Carried<'a, const W: usize> {
    chain: &'a mut Chain<Wide<W>>,
    measures: &'a mut Measures<Wide<W>>,
    collider_push: &'a mut ColliderPush<Wide<W>>,
    previous_contact: &'a mut WideMask<W>,
    poison: &'a mut Wide<W>,
}

/// Node `k` of every lane (SB15 Algorithm 1 lines 13–21) and, with `FINISH` (`k > 2`), lines
/// 24–26 for node `k − 1`. With `ALL` every lane has node `k`: the masks are constants.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn node<M: Math, const W: usize, const N: usize, const ALL: bool, const FINISH: bool>(
    ctx: &StepContext,
    setup: &Setup,
    block: &mut DftlBlock<W, N>,
    k: usize,
    nodes_real: Wide<W>,
    accelerations: Option<&[Vec3]>,
    carried: Carried<'_, W>,
) {
    let (done, todo) = block.state.split_at_mut(k);
    let (Some(previous), Some(state), Some(rest), Some(shape), Some(mass)) = (
        done.last_mut(),
        todo.first_mut(),
        block.rest.get(k),
        block.shape.get(k),
        block.mass.get(k),
    ) else {
        return;
    };
    let node_index = Wide::splat(k as Real);
    let (active, finishing) = if ALL {
        (Wide::<W>::mask(true), Wide::<W>::mask(true))
    } else {
        // Node k − 1 exists in this lane and is free: it is finished now.
        (
            node_index.lt(nodes_real),
            (node_index - Wide::splat(1.0)).lt(nodes_real),
        )
    };
    let (extra, has_extra) = match accelerations {
        None => (V3::zero(), Wide::<W>::mask(false)),
        Some(a) => {
            let mut extra: V3<Wide<W>> = V3::zero();
            let mut has = [false; W];
            for l in 0..W {
                if let Some(e) = a.get(l * N + k) {
                    extra.x.0[l] = e.x;
                    extra.y.0[l] = e.y;
                    extra.z.0[l] = e.z;
                    has[l] = true;
                }
            }
            (extra, WideMask(has))
        }
    };
    let node = NodeInput {
        position: load(&state.position),
        velocity: load(&state.velocity),
        extra,
        has_extra,
        mass: Wide(*mass),
        inverse_mass: Wide(rest.inverse_mass),
        rest_position: load(&shape.rest_position),
        local_rest: load(&shape.local_rest),
        root_distance: Wide(shape.root_distance),
        segment_length: Wide(rest.segment_length),
        strain_scale: Wide(rest.strain_scale),
    };
    // Lines 13–21, the per-strand path's function on every lane.
    let next = advance::<M, Wide<W>>(
        setup,
        ctx.colliders(),
        &node,
        &*carried.chain,
        active,
        *carried.previous_contact,
        carried.measures,
        carried.collider_push,
    );
    // Lines 24–26 for node k − 1; the last node of a lane (k == nodes) gets no correction.
    let next_correction = V3::select(active, next.correction, V3::zero());
    if FINISH {
        let old_position = load(&previous.position);
        let old_velocity = load(&previous.velocity);
        let (x_new, v_new) =
            velocity::finish(setup, carried.chain.position, old_position, next_correction);
        let x_new = V3::select(finishing, x_new, old_position);
        let v_new = V3::select(finishing, v_new, old_velocity);
        store(&mut previous.position, x_new);
        store(&mut previous.velocity, v_new);
        *carried.poison = *carried.poison + velocity::not_finite(v_new);
    }
    *carried.chain = Chain::select(active, &next.chain, carried.chain);
    *carried.previous_contact = (active & next.contact) | (!active & *carried.previous_contact);
}
