//! SB15 Algorithm 1 line 21: node frames carried root to tip as TressFX keeps them (Han &
//! Harada 2012): a twist-free discrete Bishop frame whose first axis is the node's incoming
//! edge, moved from node to node by the minimal rotation `q(t_{i−1} → t_i)`.
//!
//! DESIGN.md writes the frame as a unit quaternion `R_i`; here it is kept as its first two
//! columns, the unit tangent `t_i = R_i e_x` and normal `n_i = R_i e_y` (the third is
//! `t_i × n_i`). The same rotation: `R_i = q(t_{i−1} → t_i) · R_{i−1}` moves `n_{i−1}` exactly
//! as the quaternion product does, but as a Rodrigues rotation of one vector it needs one
//! division and no square root, where the quaternion product needs a renormalisation (a
//! square root and a division per node). The step's tangent comes from the follow-the-leader
//! projection, which already has `1/|e|`, so a frame costs no square root at all.

use crate::math::{self, Math, Quat, Vec3};

use super::lane::{Lane, V3};

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

/// Carries the normal `n_{i−1}` of node `i − 1` (unit tangent `t_{i−1}`) to node `i` with the
/// unit tangent `t_i`: Rodrigues' formula for the minimal rotation about `k = t_{i−1} × t_i`,
/// `n_i = c n + k × n + k (k·n)/(1 + c)` with `c = t_{i−1}·t_i` (the factor
/// `(1 − c)/|k|² = 1/(1 + c)` for unit tangents). A half turn (`1 + c` ≤ 1e-6) has no unique
/// minimal rotation: the normal stays, still perpendicular to `t_i = −t_{i−1}`.
#[inline(always)]
#[must_use]
pub fn transport<T: Lane>(tangent: V3<T>, normal: V3<T>, t: V3<T>) -> V3<T> {
    let k = tangent.cross(t);
    let c = tangent.dot(t);
    let one_plus_c = T::splat(1.0) + c;
    let turned = normal.scale(c) + k.cross(normal) + k.scale(k.dot(normal) / one_plus_c);
    V3::select(T::splat(1e-6).lt(one_plus_c), turned, normal)
}

/// `R v = v_x t + v_y n + v_z (t × n)`: a vector given in the frame `(t, n)`, in world axes.
#[inline(always)]
#[must_use]
pub fn rotate<T: Lane>(tangent: V3<T>, normal: V3<T>, v: V3<T>) -> V3<T> {
    tangent.scale(v.x) + normal.scale(v.y) + tangent.cross(normal).scale(v.z)
}
