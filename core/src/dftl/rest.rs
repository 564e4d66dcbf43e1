//! DFTL's rest data (Sánchez-Banderas 2015 Sec. 3.1 after Han & Harada 2012): the root frame
//! `R̂_0` and the local rest vectors `r_i`, computed once in `Strand::from_polyline`.

use crate::math::{self, Math, Quat, Real, Vec3};

use super::frame;

/// What DFTL's shape constraints need of a strand at rest (in the head's frame).
#[derive(Clone, Debug, PartialEq)]
pub struct DftlRest<const N: usize> {
    /// `R̂_0`: the root frame, whose x-axis is the first rest segment's direction `t̂_0`.
    pub root_frame: Quat,
    /// `r_i = R̂_{i−1}⁻¹ (x̂_i − x̂_{i−1})`: node `i`'s rest offset in the frame of node `i − 1`
    /// (entries 0 and 1 unused: those nodes are held by the head).
    pub local_rest: [Vec3; N],
    /// `d_i / L`: rest distance from the root along the strand over the strand's length, 0 at
    /// the root and 1 at the tip (for coefficients that fade with distance from the root).
    pub root_distance: [Real; N],
}

impl<const N: usize> DftlRest<N> {
    /// Rest data of the polyline `points` (at least 2 nodes, at most `N`, no zero-length
    /// segment: `Strand::from_polyline` checks these first). The frames are carried root to
    /// tip with the same transport the step uses, so a strand at rest is exactly on its local
    /// targets up to rounding.
    #[must_use]
    pub fn from_polyline<M: Math>(points: &[Vec3]) -> Self {
        let mut rest = DftlRest {
            root_frame: Quat::IDENTITY,
            local_rest: [Vec3::ZERO; N],
            root_distance: [0.0; N],
        };
        let n = points.len().min(N);
        if n < 2 {
            return rest;
        }
        let first = points[1] - points[0];
        let tangent = first * (1.0 / M::length(first));
        rest.root_frame = frame::from_x_axis::<M>(tangent);
        let mut frame_i = rest.root_frame;
        let mut tangent_i = tangent;
        let mut distance = M::length(first);
        rest.root_distance[1] = distance;
        for i in 2..n {
            let edge = points[i] - points[i - 1];
            let length = M::length(edge);
            rest.local_rest[i] = math::rotate(math::quat_conjugate(frame_i), edge);
            let (next_frame, next_tangent) =
                frame::transport::<M, Real>(frame_i.into(), tangent_i.into(), edge.into(), length);
            (frame_i, tangent_i) = (next_frame.into(), next_tangent.into());
            distance += length;
            rest.root_distance[i] = distance;
        }
        let total = distance;
        for d in &mut rest.root_distance[..n] {
            *d /= total;
        }
        rest
    }
}
