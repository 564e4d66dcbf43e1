//! The structure-of-arrays block: `W` strands side by side, node index `k` of every lane
//! together (SB15 Sec. 4's particle-level layout; Jolt's vertex-major stride; Box2D's
//! `b2FloatW`). DFTL's pipeline (`pipeline::dftl::step_block`) runs exactly the per-node
//! functions of the per-strand path on it, lane by lane, in the same order, written once on
//! lanes ([`crate::lane`]): with `T = Wide<W>` every operation is a loop over `[Real; W]` with
//! no cross-lane term, which the compiler turns into packed instructions (no `core::simd`, no
//! unsafe), and both paths give the same bits. The only reductions across lanes are maxima
//! and integer counts for the report. The block is quarantined and its roots coupled by the
//! same snapshot, guard and root-coupling stages as a single strand ([`Strands`],
//! [`LastGood`], [`Roots`]).
//!
//! Layout, per node `k`: state (`x`, `v`, 24 bytes per vertex, read and written), rest (`l_k`,
//! `1/m_k`, 8 bytes, read) and shape rest (`x̂_k`, `r_k`, `d_k/L`, 28 bytes, read only when the
//! shape constraints run) in three separate arrays so a stage that is off moves no bytes.
//!
//! Vectorisation needs a square root the compiler can vectorise: `libm::sqrtf` is an inline
//! `sqrtss` on x86-64, which it cannot. A std caller can pass a [`crate::math::Math`] backend
//! whose `sqrt` is `f32::sqrt` (correctly rounded, the same bits) — see the benches'
//! `HostMath`.

// Lane loops index several `[Real; W]` arrays by the same lane: an index reads clearer than a
// zip of six iterators, and `l < W` is the arrays' length, so no index can panic.
#![allow(clippy::needless_range_loop)]

use crate::lane::{Lane, Wide, WideMask, V3};
use crate::math::{Real, Vec3};
use crate::root_coupling::Roots;
use crate::snapshot::{LastGood, Restore, Strands};
use crate::strand::Strand;

use super::node::NodeInput;

/// Lanes per block the harness uses on x86-64. With the lanes' masks as whole 32-bit lanes
/// (`lane::WideMask`), a vector or a mask of 8 lanes takes two of SSE2's sixteen registers
/// and one of 16 lanes four: a pass over 16 lanes spills and runs 5–15 % slower (`dftl_cpu`,
/// DFTL + shape, M vertex-steps per CPU-second; `docs/design-departures.md`). The bits are
/// the same at any width.
pub const RECOMMENDED_LANES: usize = 8;

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

    /// Copies the state (positions, velocities) of `strands` into the lanes they were built
    /// from (lane `l` from `strands[l]`): the inverse of [`Self::store`]. The rest data stays as
    /// it was built.
    pub fn load_state(&mut self, strands: &[Strand<N>]) {
        for (l, strand) in strands.iter().enumerate().take(self.strands.min(W)) {
            let n = self.nodes[l].min(strand.rest.nodes).min(N);
            for k in 0..n {
                set(&mut self.state[k].position, l, strand.state.position[k]);
                set(&mut self.state[k].velocity, l, strand.state.velocity[k]);
            }
        }
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

/// A vector of lanes read from its three coordinate arrays.
#[inline(always)]
#[must_use]
pub fn read_lanes<const W: usize>(v: &VecLanes<W>) -> V3<Wide<W>> {
    V3 {
        x: Wide::new(v[0]),
        y: Wide::new(v[1]),
        z: Wide::new(v[2]),
    }
}

/// A vector of lanes written to its three coordinate arrays.
#[inline(always)]
pub fn write_lanes<const W: usize>(v: &mut VecLanes<W>, value: V3<Wide<W>>) {
    *v = [value.x.0, value.y.0, value.z.0];
}

impl<const W: usize, const N: usize> DftlBlock<W, N> {
    /// Node `k`'s inputs in every lane (`k ≥ 2`): its state, its rest data, the caller's
    /// accelerations (`N` per strand of the block, as the per-strand path reads them) and where
    /// the lane has the node (`active`). `None` past the capacity.
    #[inline(always)]
    #[must_use]
    pub fn node_input(
        &self,
        k: usize,
        active: WideMask<W>,
        accelerations: Option<&[Vec3]>,
    ) -> Option<NodeInput<Wide<W>>> {
        self.node_input_in(&self.state, k, active, accelerations)
    }

    /// [`Self::node_input`] with the state taken from `states` (the block's own, or a copy
    /// kept at the start of the step).
    #[inline(always)]
    #[must_use]
    pub fn node_input_in(
        &self,
        states: &[StateLanes<W>; N],
        k: usize,
        active: WideMask<W>,
        accelerations: Option<&[Vec3]>,
    ) -> Option<NodeInput<Wide<W>>> {
        let (extra, has_extra) = lane_accelerations::<W, N>(accelerations, k);
        let (state, rest, shape) = (states.get(k)?, self.rest.get(k)?, self.shape.get(k)?);
        Some(NodeInput {
            active,
            position: read_lanes(&state.position),
            velocity: read_lanes(&state.velocity),
            extra,
            has_extra,
            mass: Wide::new(*self.mass.get(k)?),
            rest_position: read_lanes(&shape.rest_position),
            local_rest: read_lanes(&shape.local_rest),
            root_distance: Wide::new(shape.root_distance),
            segment_length: Wide::new(rest.segment_length),
            strain_scale: Wide::new(rest.strain_scale),
        })
    }

    /// Node `k`'s position, set where `mask` and left as it is in the other lanes.
    #[inline(always)]
    pub fn store_position_where(&mut self, k: usize, mask: WideMask<W>, position: V3<Wide<W>>) {
        if let Some(state) = self.state.get_mut(k) {
            let position = V3::select(mask, position, read_lanes(&state.position));
            write_lanes(&mut state.position, position);
        }
    }

    /// Node `k`'s velocity, set where `mask` and left as it is in the other lanes. Returns the
    /// velocity now stored (zero past the capacity).
    #[inline(always)]
    pub fn store_velocity_where(
        &mut self,
        k: usize,
        mask: WideMask<W>,
        velocity: V3<Wide<W>>,
    ) -> V3<Wide<W>> {
        let Some(state) = self.state.get_mut(k) else {
            return V3::zero();
        };
        let velocity = V3::select(mask, velocity, read_lanes(&state.velocity));
        write_lanes(&mut state.velocity, velocity);
        velocity
    }
}

/// The caller's acceleration of node `k` in each lane (`N` entries per strand of the block)
/// and where there is one.
#[inline(always)]
fn lane_accelerations<const W: usize, const N: usize>(
    accelerations: Option<&[Vec3]>,
    k: usize,
) -> (V3<Wide<W>>, WideMask<W>) {
    match accelerations {
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
            (extra, WideMask::from_bools(has))
        }
    }
}

impl<const W: usize, const N: usize> Strands for DftlBlock<W, N> {
    #[inline(always)]
    fn count(&self) -> u32 {
        self.strands.min(W) as u32
    }
}

/// A block's last good state: every node's state at the start of the step, the velocities
/// included although a roll-back zeroes them. Copying the state array whole is one contiguous
/// move; copying only the positions interleaved in it took 64 short moves per 64-node block,
/// and a 16-lane step of 4,096 × 64 vertices ran 1.6× slower for it (criterion, alternated).
#[derive(Clone, Debug, PartialEq)]
pub struct BlockState<const W: usize, const N: usize>(pub [StateLanes<W>; N]);

impl<const W: usize, const N: usize> LastGood<DftlBlock<W, N>> for BlockState<W, N> {
    #[inline(always)]
    fn keep(block: &DftlBlock<W, N>) -> Self {
        BlockState(block.state)
    }
}

impl<const W: usize, const N: usize> Restore<DftlBlock<W, N>> for BlockState<W, N> {
    #[inline(always)]
    fn restore(&self, block: &mut DftlBlock<W, N>, l: usize) {
        let nodes = block.max_nodes.min(N);
        for (now, good) in block.state.iter_mut().zip(&self.0).take(nodes) {
            for axis in 0..3 {
                now.position[axis][l] = good.position[axis][l];
                now.velocity[axis][l] = 0.0;
            }
        }
    }
}

impl<const W: usize, const N: usize> Roots for DftlBlock<W, N> {
    type Lane = Wide<W>;

    #[inline(always)]
    fn count(&self) -> u32 {
        self.strands.min(W) as u32
    }

    #[inline(always)]
    fn held(&self, i: usize) -> (V3<Wide<W>>, V3<Wide<W>>) {
        (
            read_lanes(&self.shape[i].rest_position),
            read_lanes(&self.state[i].position),
        )
    }

    #[inline(always)]
    fn set_held(&mut self, i: usize, position: V3<Wide<W>>, velocity: V3<Wide<W>>) {
        let state = &mut self.state[i];
        write_lanes(&mut state.position, position);
        write_lanes(&mut state.velocity, velocity);
    }
}
