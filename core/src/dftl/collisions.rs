//! SB15 Algorithm 1 line 20: collisions. A node inside a collider is moved straight out along
//! the contact normal onto the surface. Not part of the correction fed back into velocity:
//! where a node is pushed out, non-penetration wins over the segment's length.
//!
//! Branch-free (selects) with the arithmetic of `Shape::penetration`, on lanes.

use crate::collide::Shape;
use crate::lane::{Lane, V3};
use crate::math::{Math, Real, Vec3};

use super::measures::Measures;

/// SB15 Algorithm 1 line 20 for one node of mass `mass`: `x` pushed out of each collider in
/// turn (in the scene's order), each push weighed by the mass into that collider's momentum
/// where the lane is `active`; then, where a lane was pushed, the depth it is left at (the deepest
/// over the colliders) and one more contact, into `measures`. Returns the node and where a
/// collider pushed it.
#[inline(always)]
#[must_use]
pub fn resolve<M: Math, T: Lane>(
    colliders: &[Shape],
    x: V3<T>,
    (active, mass): (T::Mask, T),
    measures: &mut Measures<T>,
    collider_push: &mut [V3<T>],
) -> (V3<T>, T::Mask) {
    let mut x = x;
    let mut contact = T::mask(false);
    for (shape, push) in colliders.iter().zip(collider_push.iter_mut()) {
        let (pushed, inside) = push_out::<M, T>(shape, x);
        // Where no lane was pushed, `pushed − x` is 0 in every lane: nothing to add. (The
        // mass is rest data: a `1/inverse_mass` here was hoisted out of the branch by the
        // compiler, a 14-cycle division at every node on the Cortex-M4F.)
        if T::any(inside) {
            *push += V3::select(active, (pushed - x).scale(mass), V3::zero());
        }
        x = pushed;
        contact = contact | inside;
    }
    // A node no collider pushed passed every collider's inside test where it now is: it is
    // outside them all (at most an ulp inside the radius, rounding), so only the pushed ones
    // are measured.
    let pushed = active & contact;
    if T::any(pushed) {
        for shape in colliders {
            let depth = depth::<M, T>(shape, x);
            measures.penetration = measures.penetration.max_where(pushed, depth);
        }
        // (Where no lane was pushed this adds 0 to every lane: skipped.)
        measures.contacts = measures.contacts + T::select(pushed, T::splat(1.0), T::splat(0.0));
    }
    (x, contact)
}

/// `x` moved out of `shape` where it is inside, and where it was.
#[inline(always)]
#[must_use]
pub fn push_out<M: Math, T: Lane>(shape: &Shape, x: V3<T>) -> (V3<T>, T::Mask) {
    match *shape {
        Shape::Sphere { centre, radius } => push_out_of_ball::<M, T>(x, V3::splat(centre), radius),
        Shape::Capsule { a, b, radius } => {
            push_out_of_ball::<M, T>(x, capsule_centre(x, a, b), radius)
        }
        Shape::Plane { point, normal } => {
            let normal = V3::splat(normal);
            let distance = (x - V3::splat(point)).dot(normal);
            let inside = distance.lt(T::splat(0.0));
            (V3::select(inside, x - normal.scale(distance), x), inside)
        }
    }
}

/// How deep `x` is inside `shape`, m (0 outside): what the report calls penetration.
#[inline(always)]
#[must_use]
pub fn depth<M: Math, T: Lane>(shape: &Shape, x: V3<T>) -> T {
    match *shape {
        Shape::Sphere { centre, radius } => ball_depth::<M, T>(x, V3::splat(centre), radius),
        Shape::Capsule { a, b, radius } => ball_depth::<M, T>(x, capsule_centre(x, a, b), radius),
        Shape::Plane { point, normal } => {
            let distance = (x - V3::splat(point)).dot(V3::splat(normal));
            T::select(distance.lt(T::splat(0.0)), -distance, T::splat(0.0))
        }
    }
}

/// The closest point to `x` on the capsule's axis `a`–`b`.
#[inline(always)]
fn capsule_centre<T: Lane>(x: V3<T>, a: Vec3, b: Vec3) -> V3<T> {
    let axis = b - a;
    let length2 = axis.dot(axis);
    let t = (x - V3::splat(a)).dot(V3::splat(axis)) / T::splat(length2);
    // clamp(0, 1) as selects; a degenerate axis (a = b) is its end point a.
    let t = T::select(t.lt(T::splat(0.0)), T::splat(0.0), t);
    let t = T::select(T::splat(1.0).lt(t), T::splat(1.0), t);
    let t = T::select(T::mask(length2 > 0.0), t, T::splat(0.0));
    V3::splat(a) + V3::splat(axis).scale(t)
}

/// Onto the sphere of `radius` about `centre` along the radial direction (+y from the exact
/// centre: any fixed direction will do).
#[inline(always)]
fn push_out_of_ball<M: Math, T: Lane>(x: V3<T>, centre: V3<T>, radius: Real) -> (V3<T>, T::Mask) {
    let d = x - centre;
    let distance2 = d.dot(d);
    let inside = distance2.lt(T::splat(radius * radius));
    if !T::any(inside) {
        // Every lane keeps `x` (the select below): no square root, no division.
        return (x, inside);
    }
    let distance = distance2.sqrt::<M>();
    let normal = V3::select(
        T::splat(0.0).lt(distance),
        d.scale(T::splat(1.0) / distance),
        V3::splat(Vec3::Y),
    );
    let pushed = x + normal.scale(T::splat(radius) - distance);
    (V3::select(inside, pushed, x), inside)
}

#[inline(always)]
fn ball_depth<M: Math, T: Lane>(x: V3<T>, centre: V3<T>, radius: Real) -> T {
    let d = x - centre;
    let distance2 = d.dot(d);
    // `√d² < r` needs `d² < r² (1 + 2⁻²³)²` (a correctly rounded root): with a margin of 1e-5
    // no lane beyond it can be inside, and the select below would give 0 everywhere.
    if !T::any(distance2.lt(T::splat(radius * radius * (1.0 + 1e-5)))) {
        return T::splat(0.0);
    }
    let distance = distance2.sqrt::<M>();
    T::select(
        distance.lt(T::splat(radius)),
        T::splat(radius) - distance,
        T::splat(0.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;

    #[test]
    fn pushed_points_end_on_the_surface_and_agree_with_penetration() {
        let shapes = [
            Shape::Sphere {
                centre: Vec3::new(0.1, 0.0, 0.0),
                radius: 0.05,
            },
            Shape::Capsule {
                a: Vec3::ZERO,
                b: Vec3::new(0.0, 0.2, 0.0),
                radius: 0.03,
            },
            Shape::Plane {
                point: Vec3::new(0.0, -0.1, 0.0),
                normal: Vec3::Y,
            },
        ];
        let probes = [
            Vec3::new(0.12, 0.01, -0.02),
            Vec3::new(0.01, 0.1, 0.005),
            Vec3::new(0.01, -0.01, 0.005),
            Vec3::new(0.3, -0.13, 0.0),
            Vec3::new(0.5, 0.5, 0.5),
        ];
        for shape in &shapes {
            for &p in &probes {
                let (q, inside) = push_out::<Libm, Real>(shape, p.into());
                let q = Vec3::from(q);
                let contact = shape.penetration::<Libm>(p);
                assert_eq!(inside, contact.is_some(), "{shape:?} {p}");
                if let Some(c) = contact {
                    assert!((depth::<Libm, Real>(shape, p.into()) - c.depth).abs() < 1e-7);
                    assert!((q - (p + c.normal * c.depth)).length() < 1e-6);
                    assert!(
                        depth::<Libm, Real>(shape, q.into()) < 1e-6,
                        "{shape:?} {p} -> {q}"
                    );
                } else {
                    assert_eq!(q, p);
                    assert_eq!(depth::<Libm, Real>(shape, p.into()), 0.0);
                }
            }
        }
    }
}
