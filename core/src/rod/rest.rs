//! Kmoch 2009 Algorithm 1 line 1 for the rod: its rest-state values, precomputed once when a
//! strand is built — rest lengths `|ê^j|`, `l̂_i`, the rest material angles `θ̂^j` (the
//! hair-optimised twist of the rest shape), the rest twist `m̂_i`, the rest material
//! curvatures `ω̂` and the explicit stability limit of the bending forces.

use super::frames::{
    binormal_direction, material_angles, material_curvature, representative_near, RodFrames,
};
use crate::frames::rest_root_frame;
use crate::precision::{Precision, Scalar, Vector};
use crate::strand::RodRest;

impl<const N: usize, R: Scalar> RodRest<N, R> {
    /// The rest data of the polyline `points` (at most `N` nodes are read; fewer than 3 give
    /// all zeros; segment lengths and fold-backs are checked by the caller) with uniform stiffnesses and linear density `λ = ρA`, kg/m.
    #[must_use]
    pub fn compute<P: Precision<R = R>>(
        points: &[P::V],
        bending_stiffness: R,
        minor_axis_penalty: R,
        twist_stiffness: R,
        linear_density: R,
    ) -> Self {
        let mut rest = RodRest {
            rest_length: [R::ZERO; N],
            voronoi_length: [R::ZERO; N],
            inverse_voronoi_length: [R::ZERO; N],
            bending_stiffness: [R::ZERO; N],
            minor_axis_penalty,
            twist_stiffness,
            rest_theta: [R::ZERO; N],
            rest_twist: [R::ZERO; N],
            rest_twist_rotation: [[R::ONE, R::ZERO]; N],
            rest_curvature: [[[R::ZERO; 2]; 2]; N],
            stable_time_step: R::of(f32::INFINITY),
        };
        let stiffness = (bending_stiffness, minor_axis_penalty, twist_stiffness);
        rest.fill::<P>(points, stiffness, linear_density);
        rest
    }

    /// [`Self::compute`] written over `self` in place (every field), with the stiffnesses
    /// `(α, µ, β)`: no rest data of a strand's size is built on the stack.
    pub fn fill<P: Precision<R = R>>(
        &mut self,
        points: &[P::V],
        (bending_stiffness, minor_axis_penalty, twist_stiffness): (R, R, R),
        linear_density: R,
    ) {
        let nodes = points.len().min(N);
        let segments = nodes.saturating_sub(1);
        self.rest_length = [R::ZERO; N];
        self.voronoi_length = [R::ZERO; N];
        self.inverse_voronoi_length = [R::ZERO; N];
        self.bending_stiffness = [R::ZERO; N];
        self.minor_axis_penalty = minor_axis_penalty;
        self.twist_stiffness = twist_stiffness;
        self.rest_theta = [R::ZERO; N];
        self.rest_twist = [R::ZERO; N];
        self.rest_twist_rotation = [[R::ONE, R::ZERO]; N];
        self.rest_curvature = [[[R::ZERO; 2]; 2]; N];
        self.stable_time_step = R::of(f32::INFINITY);
        if nodes < 3 {
            return;
        }
        let shortest = self.lengths::<P>(points, bending_stiffness);
        let root_frame = rest_root_frame::<P>(points[0], points[1], self.rest_length[0]);
        // Computed where they lie: returned by `RodFrames::compute`, they were a copy, the
        // deepest frame of adding a strand (3 KB at 32 nodes).
        let mut frames = RodFrames::<P, N>::empty();
        frames.recompute(&points[..nodes], root_frame, &self.rest_length);
        self.angles_and_curvatures(&frames, segments);
        let stiffest = if minor_axis_penalty > R::ONE {
            minor_axis_penalty * bending_stiffness
        } else {
            bending_stiffness
        };
        if stiffest > R::ZERO {
            let half = R::of(0.5);
            self.stable_time_step = half * shortest * shortest * P::sqrt(linear_density / stiffest);
        }
    }

    /// The rest lengths `|ê^j|` and `l̂_i` with their inverses, and each segment's bending
    /// stiffness; returns the shortest rest segment.
    fn lengths<P: Precision<R = R>>(&mut self, points: &[P::V], bending_stiffness: R) -> R {
        let segments = points.len().min(N).saturating_sub(1);
        let mut shortest = R::of(f32::INFINITY);
        for j in 0..segments {
            let e = points[j + 1] - points[j];
            self.rest_length[j] = P::sqrt(e.dot(e));
            self.bending_stiffness[j] = bending_stiffness;
            if self.rest_length[j] < shortest {
                shortest = self.rest_length[j];
            }
        }
        for i in 1..segments {
            self.voronoi_length[i] = self.rest_length[i - 1] + self.rest_length[i];
            self.inverse_voronoi_length[i] = R::ONE / self.voronoi_length[i];
        }
        shortest
    }

    /// The rest material angles `θ̂^j` (each segment's angle follows its binormals, the
    /// representative mod π closest to the previous segment's: the least rest twist; straight
    /// runs continue the previous angle), the rest twist `m̂_i` with its rotation, and the rest
    /// material curvatures `ω̂`, in the rest shape's frames `frames`.
    fn angles_and_curvatures<P: Precision<R = R>>(
        &mut self,
        frames: &RodFrames<P, N>,
        segments: usize,
    ) {
        for j in 1..segments {
            let previous = self.rest_theta[j - 1];
            self.rest_theta[j] = match binormal_direction(frames, j) {
                Some((direction, phi)) => representative_near::<P>(phi, direction, previous).0,
                None => previous,
            };
            self.rest_twist[j] = self.rest_theta[j] - self.rest_theta[j - 1];
            let (s, c) = P::sin_cos(self.rest_twist[j]);
            self.rest_twist_rotation[j] = [c, s];
        }
        let cos_sin = material_angles::<P, N>(&self.rest_theta[..segments]);
        for i in 1..segments {
            for k in 0..2 {
                self.rest_curvature[i][k] =
                    material_curvature(frames.bishop_curvature[i][k], cos_sin[i - 1 + k]);
            }
        }
    }
}
