//! SB15 Algorithm 1 line 19: follow-the-leader inextensibility, eqs. (10), (13) (Müller, Kim,
//! Chentanez 2012, eq. 5): node `i` alone moves onto the sphere of radius `l_i` about the final
//! node `i − 1` — one-sided and single-pass, the paper's point (TressFX moves both and iterates).

use crate::math::{Math, Real, Vec3};

/// `Δx^inex_i = (1 − l_i / |x*_{i−1} − x*_i|)(x*_{i−1} − x*_i)`. Coincident nodes give no
/// direction and no correction (a select, so the block path computes it branch-free too).
#[inline(always)]
#[must_use]
pub fn correction<M: Math>(previous: Vec3, x: Vec3, segment_length: Real) -> Vec3 {
    let d = previous - x;
    let length = M::sqrt(d.dot(d));
    let k = if length > 0.0 {
        1.0 - segment_length / length
    } else {
        0.0
    };
    d * k
}
