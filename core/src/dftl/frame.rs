//! SB15 Algorithm 1 line 21: node frames carried root to tip as TressFX keeps them (Han &
//! Harada 2012), one unit quaternion `R_i` per node whose x-axis is the node's incoming edge.
//!
//! The minimal rotation `q(t_{i−1} → t_i)` applied on the left equals DESIGN.md's
//! `R_{i−1} · q(e_x → R_{i−1}⁻¹ t_i)` (conjugating a rotation by `R_{i−1}` maps its axis),
//! without the inverse rotation: a twist-free discrete Bishop frame. The quaternion formulas are
//! `math.rs`'s scalar helpers, written on lanes (fixed summation order on every target).

use crate::math::{self, Math, Quat, Vec3};

use super::lane::{Lane, Q, V3};

/// The frame whose x-axis is the unit vector `t`, the minimal rotation from `e_x` (`R̂_0`).
/// A `t` opposite to `e_x` turns half a turn about z.
#[must_use]
pub fn from_x_axis<M: Math>(t: Vec3) -> Quat {
    let q = math::quat_between_unnormalized(Vec3::X, t);
    if q.w > 1e-6 {
        math::quat_normalize::<M>(q)
    } else {
        Quat::from_xyzw(0.0, 0.0, 1.0, 0.0)
    }
}

/// Carries the frame `(frame, tangent)` of node `i − 1` over the edge `edge` (of length
/// `length`) to node `i`: `t_i = edge/|edge|`, `R_i = normalise(q(t_{i−1} → t_i) · R_{i−1})`.
/// A zero-length edge keeps the previous direction.
#[inline(always)]
#[must_use]
pub fn transport<M: Math, T: Lane>(
    frame: Q<T>,
    tangent: V3<T>,
    edge: V3<T>,
    length: T,
) -> (Q<T>, V3<T>) {
    let t = V3::select(
        T::splat(0.0).lt(length),
        edge.scale(T::splat(1.0) / length),
        tangent,
    );
    let turn = Q::between_unnormalized(tangent, t);
    (turn.product(frame).normalize::<M>(), t)
}
