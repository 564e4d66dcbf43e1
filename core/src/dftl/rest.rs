//! DFTL's rest data (Sánchez-Banderas 2015 Sec. 3.1 after Han & Harada 2012), precomputed once
//! when a strand is built (`Strand::from_polyline`): the root frame `R̂_0` (as its tangent and
//! normal) and the local rest vectors `r_i`, plus the per-segment factor the step measures
//! strain with.

use crate::math::{self, Math, Real, Vec3};
use crate::strand::DftlRest;

use super::frame;

impl<const N: usize> DftlRest<N> {
    /// Rest data of the polyline `points` (at least 2 nodes, at most `N`, no zero-length
    /// segment: `Strand::from_polyline` checks these first). The frames are carried root to
    /// tip with the same transport the step uses, so a strand at rest is exactly on its local
    /// targets up to rounding.
    #[must_use]
    pub fn from_polyline<M: Math>(points: &[Vec3]) -> Self {
        let mut rest = DftlRest {
            root_tangent: Vec3::X,
            root_normal: Vec3::Y,
            local_rest: [Vec3::ZERO; N],
            root_distance: [0.0; N],
            strain_scale: [0.0; N],
        };
        rest.fill::<M>(points);
        rest
    }

    /// [`Self::from_polyline`] written over `self` in place (every field).
    pub fn fill<M: Math>(&mut self, points: &[Vec3]) {
        let rest = self;
        rest.root_tangent = Vec3::X;
        rest.root_normal = Vec3::Y;
        rest.local_rest = [Vec3::ZERO; N];
        rest.root_distance = [0.0; N];
        rest.strain_scale = [0.0; N];
        let n = points.len().min(N);
        if n < 2 {
            return;
        }
        let first = points[1] - points[0];
        let first_length = M::length(first);
        // As the step computes a tangent: the edge times the reciprocal of its length.
        let mut tangent = first * (1.0 / first_length);
        let root_frame = frame::from_x_axis::<M>(tangent);
        rest.root_tangent = tangent;
        rest.root_normal = math::rotate(root_frame, Vec3::Y);
        rest.strain_scale[1] = 0.5 / (first_length * first_length);
        let mut normal = rest.root_normal;
        let mut distance = first_length;
        rest.root_distance[1] = distance;
        for i in 2..n {
            let edge = points[i] - points[i - 1];
            let length = M::length(edge);
            rest.local_rest[i] = Vec3::new(
                edge.dot(tangent),
                edge.dot(normal),
                edge.dot(tangent.cross(normal)),
            );
            rest.strain_scale[i] = 0.5 / (length * length);
            let next_tangent = edge * (1.0 / length);
            normal =
                frame::transport::<Real>(tangent.into(), normal.into(), next_tangent.into()).into();
            tangent = next_tangent;
            distance += length;
            rest.root_distance[i] = distance;
        }
        let total = distance;
        for d in &mut rest.root_distance[..n] {
            *d /= total;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lane::V3;
    use crate::math::Libm;

    #[test]
    fn local_rest_vectors_rebuild_the_polyline() {
        let points: [Vec3; 6] = core::array::from_fn(|i| {
            let s = i as Real * 0.01;
            Vec3::new(0.004 * (50.0 * s).sin(), s, 0.004 * (50.0 * s).cos())
        });
        let rest = DftlRest::<6>::from_polyline::<Libm>(&points);
        let mut tangent: V3<Real> = rest.root_tangent.into();
        let mut normal: V3<Real> = rest.root_normal.into();
        assert!((Vec3::from(tangent).dot(normal.into())).abs() < 1e-7);
        for i in 2..6 {
            let edge: Vec3 = frame::rotate(tangent, normal, rest.local_rest[i].into()).into();
            let expected = points[i] - points[i - 1];
            assert!(
                (edge - expected).length() < 1e-8,
                "node {i}: {edge} vs {expected}"
            );
            let t = expected * (1.0 / expected.length());
            normal = frame::transport(tangent, normal, t.into());
            tangent = t.into();
            let n: Vec3 = normal.into();
            assert!(n.dot(t).abs() < 1e-6 && (n.length() - 1.0).abs() < 1e-6);
        }
    }
}
