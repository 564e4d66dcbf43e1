//! SB15 Algorithm 1 line 19: follow-the-leader inextensibility, eqs. (10), (13) (Müller, Kim,
//! Chentanez 2012, eq. 5): node `i` alone moves onto the sphere of radius `l_i` about the final
//! node `i − 1` — one-sided and single-pass, the paper's point (TressFX moves both and iterates).

use crate::math::Math;

use super::lane::{Lane, V3};

/// `Δx^inex_i = (1 − l_i / |x*_{i−1} − x*_i|)(x*_{i−1} − x*_i)`. Coincident nodes give no
/// direction and no correction (a select, not a branch).
#[inline(always)]
#[must_use]
pub fn correction<M: Math, T: Lane>(previous: V3<T>, x: V3<T>, segment_length: T) -> V3<T> {
    let d = previous - x;
    let length = d.dot(d).sqrt::<M>();
    let k = T::select(
        T::splat(0.0).lt(length),
        T::splat(1.0) - segment_length / length,
        T::splat(0.0),
    );
    d.scale(k)
}
