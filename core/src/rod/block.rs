//! A block of rod strands in lanes: what the explicit substeps read and write of `W` strands
//! (`pipeline::rod::step_block`), gathered one strand per lane and scattered back. The lanes
//! run the very kernels a strand runs alone (`precision::Kernel`, `lane::Lanes`), so a strand
//! gets the same bits in a block as on its own. The rest data is gathered every step with the
//! state: it is a few values per node beside a few hundred operations per node and substep.

use crate::lane::{Lane, Wide, V3};
use crate::math::{Math, Real, Vec3};
use crate::rod::frames::material_angles;
use crate::strand::{RodRest, Strand};

/// The lanes of a block: state, rest data and the step's per-node inputs, one strand per lane.
pub struct LaneBlock<const N: usize, const W: usize> {
    /// Strands in the block (`≤ W`; the lanes past them repeat the last strand).
    pub strands: usize,
    /// Nodes per strand (the same in every lane).
    pub nodes: usize,
    /// `x`.
    pub position: [V3<Wide<W>>; N],
    /// `v`.
    pub velocity: [V3<Wide<W>>; N],
    /// `θ^j`.
    pub theta: [Wide<W>; N],
    /// `(cos θ^j, sin θ^j)`, computed per strand by the backend.
    pub cos_sin: [[Wide<W>; 2]; N],
    /// `u^0`.
    pub root_frame: V3<Wide<W>>,
    /// `1/m`.
    pub inverse_mass: [Wide<W>; N],
    /// The rod's rest data.
    pub rest: RodRest<N, Wide<W>>,
    /// The caller's accelerations per node, if any.
    pub accelerations: Option<[V3<Wide<W>>; N]>,
}

/// `[f(strand 0), …, f(strand W−1)]` as lanes, the last strand repeated past the block's.
#[inline(always)]
fn lanes_of<const N: usize, const W: usize>(
    strands: &[Strand<N>],
    f: impl Fn(&Strand<N>) -> Real,
) -> Wide<W> {
    let last = strands.len().saturating_sub(1);
    Wide(core::array::from_fn(|l| f(&strands[l.min(last)])))
}

/// As [`lanes_of`] for a vector.
#[inline(always)]
fn vectors_of<const N: usize, const W: usize>(
    strands: &[Strand<N>],
    f: impl Fn(&Strand<N>) -> Vec3,
) -> V3<Wide<W>> {
    V3 {
        x: lanes_of(strands, |s| f(s).x),
        y: lanes_of(strands, |s| f(s).y),
        z: lanes_of(strands, |s| f(s).z),
    }
}

impl<const N: usize, const W: usize> LaneBlock<N, W> {
    /// `strands` (1 to `W` of them, with the same node count) in lanes, with their
    /// `accelerations` (`N` per strand) if any.
    #[must_use]
    pub fn gather<M: Math>(strands: &[Strand<N>], accelerations: Option<&[Vec3]>) -> Self {
        let nodes = strands.first().map_or(0, |s| s.rest.nodes.min(N));
        let segments = nodes.saturating_sub(1);
        let at = |i: usize| {
            let position = vectors_of(strands, |s| s.state.position[i]);
            let velocity = vectors_of(strands, |s| s.state.velocity[i]);
            (position, velocity)
        };
        let states: [(V3<Wide<W>>, V3<Wide<W>>); N] = core::array::from_fn(at);
        // The material angles' sines and cosines strand by strand, as `material_angles`.
        let mut cos_sin = [[Wide::splat(1.0), Wide::splat(0.0)]; N];
        let last = strands.len().saturating_sub(1);
        for lane in 0..W {
            let strand = &strands[lane.min(last)];
            let angles = material_angles::<M, N>(&strand.state.theta[..segments]);
            for (slot, [c, s]) in cos_sin.iter_mut().zip(angles) {
                slot[0].0[lane] = c;
                slot[1].0[lane] = s;
            }
        }
        let accelerations = accelerations.map(|a| {
            core::array::from_fn(|i| {
                let per_lane = |l: usize| a.get(l.min(last) * N + i).copied().unwrap_or(Vec3::ZERO);
                V3 {
                    x: Wide(core::array::from_fn(|l| per_lane(l).x)),
                    y: Wide(core::array::from_fn(|l| per_lane(l).y)),
                    z: Wide(core::array::from_fn(|l| per_lane(l).z)),
                }
            })
        });
        LaneBlock {
            strands: strands.len().min(W),
            nodes,
            position: states.map(|s| s.0),
            velocity: states.map(|s| s.1),
            theta: core::array::from_fn(|j| lanes_of(strands, |s| s.state.theta[j])),
            cos_sin,
            root_frame: vectors_of(strands, |s| s.state.root_frame),
            inverse_mass: core::array::from_fn(|i| lanes_of(strands, |s| s.rest.inverse_mass[i])),
            rest: gather_rest(strands),
            accelerations,
        }
    }

    /// Writes the free nodes' positions and velocities back into `strands` and returns each
    /// strand's `(cos θ^j, sin θ^j)`.
    pub fn scatter(&self, strands: &mut [Strand<N>]) -> [[[Real; 2]; N]; W] {
        for (lane, strand) in strands.iter_mut().take(self.strands).enumerate() {
            for i in 2..self.nodes.min(N) {
                strand.state.position[i] = self.position[i].lane(lane);
                strand.state.velocity[i] = self.velocity[i].lane(lane);
            }
        }
        core::array::from_fn(|lane| self.cos_sin.map(|[c, s]| [c.0[lane], s.0[lane]]))
    }
}

/// The rod rest data of `strands` in lanes.
fn gather_rest<const N: usize, const W: usize>(strands: &[Strand<N>]) -> RodRest<N, Wide<W>> {
    let per_node = |f: fn(&RodRest<N>, usize) -> Real| -> [Wide<W>; N] {
        core::array::from_fn(|i| lanes_of(strands, |s| f(&s.rest.rod, i)))
    };
    let pair = |f: fn(&RodRest<N>, usize, usize) -> Real| -> [[Wide<W>; 2]; N] {
        core::array::from_fn(|i| [0, 1].map(|k| lanes_of(strands, |s| f(&s.rest.rod, i, k))))
    };
    RodRest {
        rest_length: per_node(|r, i| r.rest_length[i]),
        voronoi_length: per_node(|r, i| r.voronoi_length[i]),
        inverse_voronoi_length: per_node(|r, i| r.inverse_voronoi_length[i]),
        bending_stiffness: per_node(|r, i| r.bending_stiffness[i]),
        minor_axis_penalty: lanes_of(strands, |s| s.rest.rod.minor_axis_penalty),
        twist_stiffness: lanes_of(strands, |s| s.rest.rod.twist_stiffness),
        rest_theta: per_node(|r, i| r.rest_theta[i]),
        rest_twist: per_node(|r, i| r.rest_twist[i]),
        rest_twist_rotation: pair(|r, i, k| r.rest_twist_rotation[i][k]),
        rest_curvature: core::array::from_fn(|i| {
            [0, 1]
                .map(|k| [0, 1].map(|c| lanes_of(strands, |s| s.rest.rod.rest_curvature[i][k][c])))
        }),
        stable_time_step: lanes_of(strands, |s| s.rest.rod.stable_time_step),
    }
}
