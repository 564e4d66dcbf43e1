//! A block of rod strands in lanes: what the explicit substeps read and write of `W` strands
//! (`pipeline::rod::step_block`), gathered one strand per lane and scattered back. The lanes
//! run the very kernels a strand runs alone (`precision::Kernel`, `lane::Lanes`), so a strand
//! gets the same bits in a block as on its own. The rest data is gathered every step with the
//! state: it is a few values per node beside a few hundred operations per node and substep.

use crate::lane::{Lanes, Wide, V3};
use crate::math::{Math, Real, Vec3};
use crate::precision::Vector;
use crate::rod::frames::material_angles;
use crate::strand::{RodRest, Strand};

/// The lanes of a block: state, rest data and the step's per-node inputs, one strand per lane.
pub struct LaneBlock<const N: usize, const W: usize> {
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

impl<const N: usize, const W: usize> LaneBlock<N, W> {
    /// No strand: every lane zero, `(cos θ, sin θ) = (1, 0)`.
    pub const EMPTY: Self = {
        let zero = Wide::new([0.0; W]);
        let zeros = <V3<Wide<W>> as Vector<Wide<W>>>::ZERO;
        LaneBlock {
            nodes: 0,
            position: [zeros; N],
            velocity: [zeros; N],
            theta: [zero; N],
            cos_sin: [[Wide::new([1.0; W]), zero]; N],
            root_frame: zeros,
            inverse_mass: [zero; N],
            rest: RodRest {
                rest_length: [zero; N],
                voronoi_length: [zero; N],
                inverse_voronoi_length: [zero; N],
                bending_stiffness: [zero; N],
                minor_axis_penalty: zero,
                twist_stiffness: zero,
                rest_theta: [zero; N],
                rest_twist: [zero; N],
                rest_twist_rotation: [[zero; 2]; N],
                rest_curvature: [[[zero; 2]; 2]; N],
                stable_time_step: zero,
            },
            accelerations: None,
        }
    };

    /// Gathers the strands of `strands` (at most `W`) that `gathered` names into their
    /// lanes, with their `accelerations` (`N` per strand of `strands`) if any, in place of
    /// what the lanes held. They have the same node count; at least one is named. A lane left
    /// out holds a copy of a strand that is in, so that it computes nothing out of range; it
    /// is never scattered back.
    ///
    /// Every lane's entries below the node count are written here. Those past it keep
    /// [`Self::EMPTY`]'s values: the lanes are cleared when the node count or the presence of
    /// accelerations differs from the block gathered before (clearing them for every block
    /// was 3 % of Head #1's step in blocks, `perf`).
    pub fn gather<M: Math>(
        &mut self,
        strands: &[Strand<N>],
        gathered: &[bool; W],
        accelerations: Option<&[Vec3]>,
    ) {
        let any = gathered.iter().position(|&g| g).unwrap_or(0);
        let nodes = strands.get(any).map_or(0, |s| s.rest.nodes.min(N));
        if nodes != self.nodes || accelerations.is_some() != self.accelerations.is_some() {
            *self = Self::EMPTY;
            self.nodes = nodes;
            if accelerations.is_some() {
                self.accelerations = Some([V3::zero(); N]);
            }
        }
        for (lane, &is_in) in gathered.iter().enumerate() {
            let source = if is_in { lane } else { any };
            if let Some(strand) = strands.get(source) {
                let extra = accelerations.and_then(|a| a.get(source * N..(source + 1) * N));
                self.put(lane, strand, extra);
            }
        }
        // The material angles' sines and cosines, in lanes: the bits `material_angles` gives
        // each strand.
        let segments = self.nodes.saturating_sub(1);
        self.cos_sin = material_angles::<Lanes<M, W>, N>(&self.theta[..segments]);
    }

    /// Writes `strand` (and its accelerations `extra`, if any) into lane `lane`.
    fn put(&mut self, lane: usize, strand: &Strand<N>, extra: Option<&[Vec3]>) {
        let (state, rest) = (&strand.state, &strand.rest);
        let nodes = self.nodes;
        for i in 0..nodes {
            self.position[i].set_lane(lane, state.position[i]);
            self.velocity[i].set_lane(lane, state.velocity[i]);
            self.inverse_mass[i].0[lane] = rest.inverse_mass[i];
        }
        if let (Some(lanes), Some(extra)) = (self.accelerations.as_mut(), extra) {
            for (slot, a) in lanes.iter_mut().zip(extra).take(nodes) {
                slot.set_lane(lane, *a);
            }
        }
        self.root_frame.set_lane(lane, state.root_frame);
        let segments = nodes.saturating_sub(1);
        for (slot, theta) in self.theta.iter_mut().zip(&state.theta).take(segments) {
            slot.0[lane] = *theta;
        }
        self.put_rest(lane, &rest.rod);
    }

    /// Writes the centreline, root frame and angles of the strands `in_lanes` names (after
    /// their projection: what the twist reads) into their lanes; the others keep theirs.
    pub fn put_centrelines(&mut self, strands: &[Strand<N>], in_lanes: &[bool; W]) {
        for (lane, strand) in strands.iter().enumerate().take(W) {
            if !in_lanes[lane] {
                continue;
            }
            let state = &strand.state;
            for i in 0..self.nodes {
                self.position[i].set_lane(lane, state.position[i]);
                self.theta[i].0[lane] = state.theta[i];
            }
            self.root_frame.set_lane(lane, state.root_frame);
        }
    }

    /// Writes the material angles of the lanes `in_lanes` names back into their strands (the
    /// twist's result; `θ^0` is the root coupling's and stays).
    pub fn take_angles(&self, strands: &mut [Strand<N>], in_lanes: &[bool; W]) {
        let segments = self.nodes.saturating_sub(1);
        for (lane, strand) in strands.iter_mut().enumerate().take(W) {
            if in_lanes[lane] {
                for j in 1..segments {
                    strand.state.theta[j] = self.theta[j].0[lane];
                }
            }
        }
    }

    /// Writes the rod rest data `rod` into lane `lane`.
    fn put_rest(&mut self, lane: usize, rod: &RodRest<N>) {
        let r = &mut self.rest;
        for i in 0..self.nodes {
            r.rest_length[i].0[lane] = rod.rest_length[i];
            r.voronoi_length[i].0[lane] = rod.voronoi_length[i];
            r.inverse_voronoi_length[i].0[lane] = rod.inverse_voronoi_length[i];
            r.bending_stiffness[i].0[lane] = rod.bending_stiffness[i];
            r.rest_theta[i].0[lane] = rod.rest_theta[i];
            r.rest_twist[i].0[lane] = rod.rest_twist[i];
            for k in 0..2 {
                r.rest_twist_rotation[i][k].0[lane] = rod.rest_twist_rotation[i][k];
                for c in 0..2 {
                    r.rest_curvature[i][k][c].0[lane] = rod.rest_curvature[i][k][c];
                }
            }
        }
        r.minor_axis_penalty.0[lane] = rod.minor_axis_penalty;
        r.twist_stiffness.0[lane] = rod.twist_stiffness;
        r.stable_time_step.0[lane] = rod.stable_time_step;
    }

    /// Writes the free nodes' positions and velocities of the lanes `moved` names (those that
    /// took their substeps or their implicit step in lanes) back into `strands`, and their
    /// `(cos θ^j, sin θ^j)` into `angles`.
    pub fn scatter(
        &self,
        strands: &mut [Strand<N>],
        moved: &[bool; W],
        angles: &mut [[[Real; 2]; N]; W],
    ) {
        let lanes = strands.iter_mut().zip(angles.iter_mut()).enumerate();
        for (lane, (strand, angles)) in lanes.take(W) {
            if !moved[lane] {
                continue;
            }
            for i in 2..self.nodes.min(N) {
                strand.state.position[i] = self.position[i].lane(lane);
                strand.state.velocity[i] = self.velocity[i].lane(lane);
            }
            *angles = self.cos_sin.map(|[c, s]| [c.0[lane], s.0[lane]]);
        }
    }
}
