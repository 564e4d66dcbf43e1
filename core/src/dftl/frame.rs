//! SB15 Algorithm 1 line 21: node frames carried root to tip as TressFX keeps them (Han &
//! Harada 2012): a twist-free discrete Bishop frame whose first axis is the node's incoming
//! edge, moved from node to node by the minimal rotation `q(t_{i−1} → t_i)`.
//!
//! The paper writes the frame as a unit quaternion `R_i`; here it is kept as its first two
//! columns, the unit tangent `t_i = R_i e_x` and normal `n_i = R_i e_y` (the third is
//! `t_i × n_i`). The same rotation: `R_i = q(t_{i−1} → t_i) · R_{i−1}` moves `n_{i−1}` exactly
//! as the quaternion product does, but as a Rodrigues rotation of one vector it needs one
//! division and no square root, where the quaternion product needs a renormalisation (a
//! square root and a division per node). The step's tangent comes from the follow-the-leader
//! projection, which already has `1/|e|`, so a frame costs no square root where no collider
//! moved the node.

use crate::lane::{Lane, V3};
use crate::math::{self, Math, Quat, Vec3};

use super::measures::Segment;
use super::node::Chain;

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
///
/// On a normal perpendicular to `t_{i−1}` the rotation also reduces to the two-reflection
/// form `n − (t_i·n)/(1 + c) (t_{i−1} + t_i)`, half the arithmetic; measured on the 16-lane
/// blocks (SSE2) it ran 7–10 % slower than this form (1,024 × 32 and 4,096 × 64),
/// whose independent terms overlap the division, so this one stays.
#[inline(always)]
#[must_use]
pub fn transport<T: Lane>(tangent: V3<T>, normal: V3<T>, t: V3<T>) -> V3<T> {
    let k = tangent.cross(t);
    let c = tangent.dot(t);
    let one_plus_c = T::splat(1.0) + c;
    let turned = normal.scale(c) + k.cross(normal) + k.scale(k.dot(normal) / one_plus_c);
    V3::select(T::splat(1e-6).lt(one_plus_c), turned, normal)
}

/// SB15 Algorithm 1 line 21: the frame of the final node `i` carried from node `i − 1`'s
/// (`chain`). Its tangent is `tangent` where `known` (follow-the-leader's, before a collider
/// moved the node), else the unit edge of `segment` (`chain`'s tangent for a zero edge). Where
/// a collider pushed the node by `push` (`contact`), the tangent turns from
/// follow-the-leader's towards the pushed edge by the push's share of the rest length
/// `length`, all the way from a push of a whole segment on: a push of a few per cent of a
/// segment, a node resting on the head, supports the node without turning the rest shape
/// the nodes after it follow, while a strand whose rest shape runs into the head follows its
/// surface. The normal is [`transport`]ed. Returns `(t_i, n_i)`.
#[inline(always)]
#[must_use]
pub fn carry<M: Math, T: Lane>(
    chain: &Chain<T>,
    segment: &Segment<T>,
    (tangent, known): (V3<T>, T::Mask),
    (push, contact, length): (V3<T>, T::Mask, T),
) -> (V3<T>, V3<T>) {
    let t = if T::all(known) && !T::any(contact) {
        tangent
    } else {
        let edge_length = segment.squared_length.sqrt::<M>();
        let exact = V3::select(
            T::splat(0.0).lt(edge_length),
            segment.edge.scale(T::splat(1.0) / edge_length),
            chain.tangent,
        );
        let t = if T::any(contact) {
            let share = push.dot(push).sqrt::<M>() / length;
            let share = T::select(T::splat(1.0).lt(share), T::splat(1.0), share);
            let turned = tangent + (exact - tangent).scale(share);
            let turned_length = turned.dot(turned).sqrt::<M>();
            let turned = V3::select(
                T::splat(0.0).lt(turned_length),
                turned.scale(T::splat(1.0) / turned_length),
                exact,
            );
            V3::select(contact, turned, tangent)
        } else {
            tangent
        };
        V3::select(known, t, exact)
    };
    (t, transport(chain.tangent, chain.normal, t))
}

/// `R v = v_x t + v_y n + v_z (t × n)`: a vector given in the frame `(t, n)`, in world axes.
#[inline(always)]
#[must_use]
pub fn rotate<T: Lane>(tangent: V3<T>, normal: V3<T>, v: V3<T>) -> V3<T> {
    tangent.scale(v.x) + normal.scale(v.y) + tangent.cross(normal).scale(v.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Libm, Math, Real};

    /// Rodrigues' rotation about `t_{i−1} × t_i` by the angle between the tangents, the
    /// textbook form of the minimal rotation, in f64.
    fn rodrigues(a: [f64; 3], b: [f64; 3], v: [f64; 3]) -> [f64; 3] {
        let cross = |p: [f64; 3], q: [f64; 3]| {
            [
                p[1] * q[2] - p[2] * q[1],
                p[2] * q[0] - p[0] * q[2],
                p[0] * q[1] - p[1] * q[0],
            ]
        };
        let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
        let k = cross(a, b);
        let s = dot(k, k).sqrt();
        let c = dot(a, b);
        let axis = k.map(|x| x / s);
        let axv = cross(axis, v);
        let along = dot(axis, v) * (1.0 - c);
        core::array::from_fn(|i| v[i] * c + axv[i] * s + axis[i] * along)
    }

    #[test]
    fn transport_is_the_minimal_rotation_along_a_helix_and_a_fold() {
        let mut worst: f64 = 0.0;
        let mut tilt: f32 = 0.0;
        let mut t = Vec3::new(0.0, -1.0, 0.0);
        let mut n = Vec3::new(1.0, 0.0, 0.0);
        let unit = |v: Vec3| v * (1.0 / Libm::length(v));
        // A helix of 200 edges turning 0.3 rad per edge, then a fold of about 150°.
        for i in 0..201 {
            let (sin, cos) = Libm::sin_cos(0.3 * i as f32);
            let next = if i == 200 {
                unit(-t + Vec3::new(0.0, 0.0, 0.6))
            } else {
                unit(Vec3::new(0.4 * cos, -1.0, 0.4 * sin))
            };
            let want = rodrigues(
                t.to_array().map(f64::from),
                next.to_array().map(f64::from),
                n.to_array().map(f64::from),
            );
            n = transport(t.into(), n.into(), next.into()).into();
            for (got, want) in n.to_array().into_iter().zip(want) {
                worst = worst.max((f64::from(got) - want).abs());
            }
            tilt = tilt.max(n.dot(next).abs());
            t = next;
        }
        assert!(worst < 1e-6, "differs from Rodrigues by {worst}");
        assert!(tilt < 1e-6, "normal tilted {tilt} towards the tangent");
        assert!(
            (n.length() - 1.0).abs() < 1e-5,
            "normal length {}",
            n.length()
        );
    }

    /// The frame of a node 1 cm from the one before, follow-the-leader's tangent along +x,
    /// pushed along +y by `push`.
    fn carried_after(push: f32, contact: bool) -> Vec3 {
        let chain = Chain {
            position: V3::<Real>::from(Vec3::ZERO),
            tangent: Vec3::X.into(),
            normal: Vec3::Y.into(),
        };
        let push = Vec3::new(0.0, push, 0.0);
        let x = Vec3::new(0.01, 0.0, 0.0) + push;
        let segment = Segment {
            edge: x.into(),
            squared_length: x.length_squared(),
        };
        let (t, _) = carry::<Libm, Real>(
            &chain,
            &segment,
            (Vec3::X.into(), true),
            (push.into(), contact, 0.01),
        );
        t.into()
    }

    #[test]
    fn a_push_turns_the_frame_by_its_share_of_a_segment() {
        // No contact: follow-the-leader's tangent, whatever the segment.
        assert_eq!(carried_after(0.004, false), Vec3::X);
        // A push of a whole segment or more: along the pushed segment.
        let whole = carried_after(0.01, true);
        let edge = Vec3::new(0.01, 0.01, 0.0).normalize();
        assert!((whole - edge).length() < 1e-6, "{whole}");
        // A push of a tenth of a segment: a tenth of the way towards the pushed edge (which is
        // 0.0997 rad off), a unit vector.
        let tenth = carried_after(0.001, true);
        let turned =
            (Vec3::X + (Vec3::new(0.01, 0.001, 0.0).normalize() - Vec3::X) * 0.1).normalize();
        assert!((tenth - turned).length() < 1e-6, "{tenth}");
        assert!((tenth.length() - 1.0).abs() < 1e-6);
        assert!(tenth.y > 0.0 && tenth.y < 0.02, "{tenth}");
    }
}
