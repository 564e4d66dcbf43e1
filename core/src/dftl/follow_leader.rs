//! SB15 Algorithm 1 line 19: follow-the-leader inextensibility, eqs. (10), (13) (Müller, Kim,
//! Chentanez 2012, eq. 5): node `i` alone moves onto the sphere of radius `l_i` about the final
//! node `i − 1` — one-sided and single-pass, the paper's point (TressFX moves both and iterates).

use crate::lane::{Lane, V3};
use crate::math::Math;

/// `x*_i + Δx^inex_i = x*_{i−1} + l_i t_i` with `t_i = (x*_i − x*_{i−1}) / |x*_i − x*_{i−1}|`:
/// eq. (10)'s `x*_i + (1 − l_i/|d|) d`, `d = x*_{i−1} − x*_i`, written so that the segment's
/// unit direction `t_i` — which the frame update needs next — comes with it (one square root
/// and one division per node, the inherent cost of follow-the-leader). Returns the projected
/// node and `t_i`. Coincident nodes give no direction: the node stays and the tangent is
/// `fallback` (a select, not a branch).
#[inline(always)]
#[must_use]
pub fn project<M: Math, T: Lane>(
    previous: V3<T>,
    x: V3<T>,
    segment_length: T,
    fallback: V3<T>,
) -> (V3<T>, V3<T>) {
    let e = x - previous;
    let length = e.dot(e).sqrt::<M>();
    let found = T::splat(0.0).lt(length);
    let tangent = e.scale(T::splat(1.0) / length);
    let projected = previous + tangent.scale(segment_length);
    (
        V3::select(found, projected, x),
        V3::select(found, tangent, fallback),
    )
}
