//! Curvature binormals, parallel transport and the Bishop and material frames of a discrete
//! rod (Bergou et al. 2008 Sec. 4; Kmoch et al. 2009 Sec. 4–5).
//!
//! Everything here is written without trigonometry: a rotation that takes one unit tangent to
//! another is the closed form `P(v) = c v + b × v + (b·v)/(1 + c) b` with `b = t₀ × t₁`,
//! `c = t₀·t₁` (Rodrigues' formula with `sin φ = |b|`, `cos φ = c`), so a frame sweep down a
//! strand costs a few multiply-adds per node and no `sin`/`cos` (software double precision on a
//! Cortex-M4F). Material frames take the cosine and sine of `θ` as inputs for the same reason.
//!
//! All functions are generic over a [`Precision`]: the step runs them in `f32` through its math
//! backend, finite-difference tests in `f64`.

use crate::precision::{Arithmetic, Kernel, Precision, Scalar, Vector};

/// The curvature binormal at the node between segments `e_prev` and `e_next` (Kmoch 2009,
/// Sec. 4; BWR08 eq. 1): `(κb)_i = 2 (e^{i−1} × e^i) / (|ê^{i−1}| |ê^i| + e^{i−1}·e^i)`, with the
/// *rest* lengths in the denominator. Returns `(κb, d, 1/d)` with `d` the denominator, whose
/// reciprocal the gradients multiply by. Its length is `2 tan(φ/2)` for a turning angle `φ`
/// when lengths are at rest.
#[inline(always)]
#[must_use]
pub fn curvature_binormal<P: Kernel>(
    e_prev: P::V,
    e_next: P::V,
    rest_length_prev: P::R,
    rest_length_next: P::R,
) -> (P::V, P::R, P::R) {
    let d = rest_length_prev * rest_length_next + e_prev.dot(e_next);
    let inverse_d = P::R::ONE / d;
    (
        curvature_binormal_over::<P>(e_prev, e_next, inverse_d),
        d,
        inverse_d,
    )
}

/// [`curvature_binormal`] given the reciprocal of its denominator, `1/d`: the rod's frame pass
/// takes `1/d` from a division it shares with another reciprocal.
#[inline(always)]
#[must_use]
pub fn curvature_binormal_over<P: Kernel>(e_prev: P::V, e_next: P::V, inverse_d: P::R) -> P::V {
    e_prev.cross(e_next) * (P::R::of(2.0) * inverse_d)
}

/// The parallel transport of `v` along the rotation about `t_from × t_to` that takes the unit
/// tangent `t_from` to the unit tangent `t_to` (BWR08 Sec. 4.2, "discrete parallel transport").
/// The identity when the tangents are equal; `v` unchanged when they are opposite (a folded
/// strand, refused when a strand is built).
#[inline(always)]
#[must_use]
pub fn parallel_transport<P: Precision>(t_from: P::V, t_to: P::V, v: P::V) -> P::V {
    let b = t_from.cross(t_to);
    let c = t_from.dot(t_to);
    let one_plus_c = P::R::ONE + c;
    let turns_back = one_plus_c <= P::R::of(1.0e-6) || !one_plus_c.is_finite();
    if turns_back {
        return v;
    }
    v * c + b.cross(v) + b * (b.dot(v) / one_plus_c)
}

/// [`parallel_transport`] of a vector `v` perpendicular to `t_from`, given
/// `1 / (1 + t_from·t_to)`: `v − ((t_to·v) / (1 + t_from·t_to)) (t_from + t_to)`, the two
/// reflections (through the planes normal to `t_from + t_to` and to `t_to`) whose product is
/// the rotation, written for `v ⟂ t_from` (the second reflection is then the identity). 16
/// flops where Rodrigues' form takes 41; the result is perpendicular to `t_to` whatever `v`'s
/// component along `t_from`, so rounding does not build up down a strand. `v` unchanged
/// when the tangents are (nearly) opposite, as [`parallel_transport`].
#[inline(always)]
#[must_use]
pub fn transport_perpendicular<P: Kernel>(
    t_from: P::V,
    t_to: P::V,
    v: P::V,
    inverse_one_plus_cos: P::R,
) -> P::V {
    // 1/(1 + c) ≥ 1e6 where `parallel_transport` tests 1 + c ≤ 1e-6 (and NaN fails both).
    let transports = inverse_one_plus_cos.between(P::R::ZERO, P::R::of(1.0e6));
    let transported = || v - (t_from + t_to) * (t_to.dot(v) * inverse_one_plus_cos);
    // Every lane transports but at a fold: for one strand, the early return of old (the
    // select alone cost the Cortex-M4F 1.4 % of the rod's step).
    if P::R::all(transports) {
        transported()
    } else {
        P::V::select(transports, transported(), v)
    }
}

/// The Bishop frame in space (Kmoch Sec. 5): `u^0` given at the root, then
/// `u^j = P_j(u^{j−1})`, the parallel transport from `t^{j−1}` to `t^j`. Fills `u[..tangents.len()]`
/// (a shorter `u` stops early).
pub fn bishop_frame<P: Precision>(tangents: &[P::V], root_frame: P::V, u: &mut [P::V]) {
    let mut previous_tangent = P::V::ZERO;
    let mut previous_u = root_frame;
    for (j, (t, slot)) in tangents.iter().zip(u.iter_mut()).enumerate() {
        if j > 0 {
            previous_u = parallel_transport::<P>(previous_tangent, *t, previous_u);
        }
        *slot = previous_u;
        previous_tangent = *t;
    }
}

/// The Bishop frame in time (Kmoch Sec. 5): after a step the root frame `u^0` moves by the
/// parallel transport that takes the old root tangent to the new one, then is re-orthonormalised
/// against the new tangent so rounding never accumulates over thousands of steps. A root that
/// did not turn keeps its frame bit for bit: the transport is the identity, and rounding it
/// (`t·t` is not always 1 in f32) would turn `θ^0` by an ulp every step.
#[must_use]
pub fn transport_in_time<P: Precision>(old_tangent: P::V, new_tangent: P::V, u: P::V) -> P::V {
    if old_tangent == new_tangent {
        return u;
    }
    let moved = parallel_transport::<P>(old_tangent, new_tangent, u);
    orthonormalise::<P>(moved, new_tangent)
        .unwrap_or_else(|| perpendicular_unit_by_reciprocal::<P>(new_tangent))
}

/// `v` made perpendicular to the unit vector `t` and normalised; `None` if nothing is left.
#[must_use]
pub fn orthonormalise<P: Precision>(v: P::V, t: P::V) -> Option<P::V> {
    let w = v - t * t.dot(v);
    let length_squared = w.dot(w);
    if length_squared > P::R::of(1.0e-20) && length_squared.is_finite() {
        Some(w * (P::R::ONE / P::sqrt(length_squared)))
    } else {
        None
    }
}

/// A unit vector perpendicular to `t`: `t` crossed with the coordinate axis least aligned with
/// it (deterministic), normalised by multiplying with the reciprocal of its length, in any
/// precision. [`crate::strand::perpendicular_unit`] makes the same choice but divides by the
/// length: other operations, other bits, so each keeps its own function.
#[must_use]
pub fn perpendicular_unit_by_reciprocal<P: Precision>(t: P::V) -> P::V {
    let v = P::to_vec3(t).abs();
    let axis = if v.x <= v.y && v.x <= v.z {
        crate::math::Vec3::X
    } else if v.y <= v.z {
        crate::math::Vec3::Y
    } else {
        crate::math::Vec3::Z
    };
    let u = t.cross(P::vector(axis));
    let length_squared = u.dot(u);
    if length_squared > P::R::ZERO {
        u * (P::R::ONE / P::sqrt(length_squared))
    } else {
        P::vector(crate::math::Vec3::X)
    }
}

/// The root segment's Bishop vector `u^0` at rest, which is also its rest material vector
/// `m1^0` (`θ̂^0 = 0`): perpendicular to the rest root tangent. The state starts with it, and
/// the head carries it to set `θ^0` each step.
#[must_use]
pub fn rest_root_frame<P: Precision>(root: P::V, next: P::V, rest_length: P::R) -> P::V {
    perpendicular_unit_by_reciprocal::<P>((next - root) * (P::R::ONE / rest_length))
}

/// The material frame `(m1, m2)` of a segment with Bishop frame `(u, v)` and material angle
/// `θ` given as `(cos θ, sin θ)` (Kmoch Sec. 5): `m1 = cos θ u + sin θ v`,
/// `m2 = −sin θ u + cos θ v`.
#[inline(always)]
#[must_use]
pub fn material_frame<P: Precision>(u: P::V, v: P::V, cos_sin: [P::R; 2]) -> (P::V, P::V) {
    let [c, s] = cos_sin;
    (u * c + v * s, v * c - u * s)
}

/// The angle about `t` from `u` to the direction `d`, with `v = t × u`: `atan2(d·v, d·u)`.
#[inline(always)]
#[must_use]
pub fn angle_in_frame<P: Precision>(u: P::V, v: P::V, d: P::V) -> P::R {
    P::atan2(d.dot(v), d.dot(u))
}

/// `angle + 2πk` closest to `reference`: keeps `θ` continuous in time (no 2π jumps).
#[inline(always)]
#[must_use]
pub fn unwrap_near<R: Scalar>(angle: R, reference: R) -> R {
    let two_pi = R::of(2.0) * R::PI;
    let turns = ((reference - angle) / two_pi + R::of(0.5)).floor();
    angle + turns * two_pi
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::precision::F64;
    use glam::DVec3;

    fn unit(v: DVec3) -> DVec3 {
        v / v.length()
    }

    #[test]
    fn curvature_binormal_has_length_two_tan_half_angle() {
        let phi: f64 = 0.7;
        let e0 = DVec3::new(0.01, 0.0, 0.0);
        let e1 = DVec3::new(phi.cos(), phi.sin(), 0.0) * 0.02;
        let (kb, _, _) = curvature_binormal::<F64>(e0, e1, 0.01, 0.02);
        assert!((kb.length() - 2.0 * (phi / 2.0).tan()).abs() < 1e-12);
        assert!(kb.x.abs() < 1e-15 && kb.y.abs() < 1e-15 && kb.z > 0.0);
    }

    #[test]
    fn parallel_transport_is_the_minimal_rotation() {
        let t0 = unit(DVec3::new(1.0, 0.2, -0.3));
        let t1 = unit(DVec3::new(0.1, 1.0, 0.4));
        // Takes t0 to t1, keeps the binormal axis, preserves lengths and angles.
        assert!((parallel_transport::<F64>(t0, t1, t0) - t1).length() < 1e-12);
        let axis = unit(t0.cross(t1));
        assert!((parallel_transport::<F64>(t0, t1, axis) - axis).length() < 1e-12);
        let v = DVec3::new(0.3, -0.7, 0.2);
        let w = parallel_transport::<F64>(t0, t1, v);
        assert!((w.length() - v.length()).abs() < 1e-12);
        assert!((w.dot(t1) - v.dot(t0)).abs() < 1e-12);
        // Against Rodrigues' formula with explicit trigonometry.
        let angle = t0.dot(t1).acos();
        let rodrigues = v * angle.cos()
            + axis.cross(v) * angle.sin()
            + axis * axis.dot(v) * (1.0 - angle.cos());
        assert!((w - rodrigues).length() < 1e-12);
    }

    #[test]
    fn bishop_frame_stays_orthonormal_along_a_helix() {
        let tangents: [DVec3; 40] = core::array::from_fn(|j| {
            let s = j as f64 * 0.3;
            unit(DVec3::new(-s.sin(), s.cos(), 0.5))
        });
        let mut u = [DVec3::ZERO; 40];
        bishop_frame::<F64>(
            &tangents,
            perpendicular_unit_by_reciprocal::<F64>(tangents[0]),
            &mut u,
        );
        for (t, u) in tangents.iter().zip(&u) {
            assert!(t.dot(*u).abs() < 1e-12 && (u.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn time_transport_keeps_the_root_frame_perpendicular_and_unwrap_is_continuous() {
        let t0 = unit(DVec3::new(0.0, 1.0, 0.0));
        let t1 = unit(DVec3::new(0.3, 1.0, 0.1));
        let u = transport_in_time::<F64>(t0, t1, DVec3::X);
        assert!(u.dot(t1).abs() < 1e-14 && (u.length() - 1.0).abs() < 1e-14);
        assert!((unwrap_near(3.1_f64, -3.1) - (3.1 - 2.0 * core::f64::consts::PI)).abs() < 1e-12);
        assert!((unwrap_near(0.2_f64, 12.7) - (0.2 + 4.0 * core::f64::consts::PI)).abs() < 1e-12);
        let (m1, m2) = material_frame::<F64>(DVec3::X, DVec3::Y, [0.6, 0.8]);
        assert!((m1 - DVec3::new(0.6, 0.8, 0.0)).length() < 1e-15);
        assert!((m2 - DVec3::new(-0.8, 0.6, 0.0)).length() < 1e-15);
        assert!((angle_in_frame::<F64>(DVec3::X, DVec3::Y, m1) - 0.8_f64.atan2(0.6)).abs() < 1e-15);
    }
}
