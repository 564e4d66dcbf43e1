//! SB15 Algorithm 1 line 21: node frames carried root to tip as TressFX keeps them (Han &
//! Harada 2012), one unit quaternion `R_i` per node whose x-axis is the node's incoming edge.
//!
//! The minimal rotation `q(t_{i−1} → t_i)` applied on the left equals DESIGN.md's
//! `R_{i−1} · q(e_x → R_{i−1}⁻¹ t_i)` (conjugating a rotation by `R_{i−1}` maps its axis),
//! without the inverse rotation: a twist-free discrete Bishop frame. Scalar quaternion code from
//! `math.rs` only (fixed summation order on every target).

use crate::math::{self, Math, Quat, Real, Vec3};

/// The frame whose x-axis is the unit vector `t` and which has no twist about it relative to
/// the minimal rotation from `e_x` (`R̂_0`). A `t` opposite to `e_x` turns half a turn about z.
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
/// A zero-length edge keeps the previous frame (no direction to turn to).
#[inline(always)]
#[must_use]
pub fn transport<M: Math>(frame: Quat, tangent: Vec3, edge: Vec3, length: Real) -> (Quat, Vec3) {
    let t = if length > 0.0 {
        edge * (1.0 / length)
    } else {
        tangent
    };
    let turn = math::quat_between_unnormalized(tangent, t);
    (math::quat_normalize::<M>(math::quat_mul(turn, frame)), t)
}
