//! SB15 Algorithm 1 line 20: collisions. A node inside a collider is moved straight out along
//! the contact normal onto the surface. Not part of the correction fed back into velocity:
//! where a node is pushed out, non-penetration wins over the segment's length (DESIGN.md).
//!
//! Written branch-free (selects, not early returns) with the same arithmetic as
//! `Shape::penetration`, so the structure-of-arrays block path can run one collider over all
//! lanes of a node and give the per-strand path's bits.

use crate::collide::Shape;
use crate::math::{Math, Real, Vec3};

/// `x` moved out of `shape` if it is inside, and whether it was.
#[inline(always)]
#[must_use]
pub fn push_out<M: Math>(shape: &Shape, x: Vec3) -> (Vec3, bool) {
    match *shape {
        Shape::Sphere { centre, radius } => push_out_of_ball::<M>(x, centre, radius),
        Shape::Capsule { a, b, radius } => {
            push_out_of_ball::<M>(x, capsule_centre(x, a, b), radius)
        }
        Shape::Plane { point, normal } => push_out_of_plane(x, point, normal),
    }
}

/// How deep `x` is inside `shape`, m (0 outside): what the report calls penetration.
#[inline(always)]
#[must_use]
pub fn depth<M: Math>(shape: &Shape, x: Vec3) -> Real {
    match *shape {
        Shape::Sphere { centre, radius } => ball_depth::<M>(x, centre, radius),
        Shape::Capsule { a, b, radius } => ball_depth::<M>(x, capsule_centre(x, a, b), radius),
        Shape::Plane { point, normal } => {
            let distance = (x - point).dot(normal);
            if distance < 0.0 {
                -distance
            } else {
                0.0
            }
        }
    }
}

/// The closest point to `x` on the capsule's axis `a`–`b`.
#[inline(always)]
fn capsule_centre(x: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let axis = b - a;
    let length2 = axis.dot(axis);
    let t = if length2 > 0.0 {
        ((x - a).dot(axis) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    a + axis * t
}

/// Onto the sphere of `radius` about `centre` along the radial direction (+y from the exact
/// centre: any fixed direction will do).
#[inline(always)]
fn push_out_of_ball<M: Math>(x: Vec3, centre: Vec3, radius: Real) -> (Vec3, bool) {
    let d = x - centre;
    let distance2 = d.dot(d);
    let inside = distance2 < radius * radius;
    let distance = M::sqrt(distance2);
    let normal = if distance > 0.0 {
        d * (1.0 / distance)
    } else {
        Vec3::Y
    };
    let pushed = x + normal * (radius - distance);
    (if inside { pushed } else { x }, inside)
}

#[inline(always)]
fn ball_depth<M: Math>(x: Vec3, centre: Vec3, radius: Real) -> Real {
    let d = x - centre;
    let distance = M::sqrt(d.dot(d));
    if distance < radius {
        radius - distance
    } else {
        0.0
    }
}

#[inline(always)]
fn push_out_of_plane(x: Vec3, point: Vec3, normal: Vec3) -> (Vec3, bool) {
    let distance = (x - point).dot(normal);
    let inside = distance < 0.0;
    (if inside { x - normal * distance } else { x }, inside)
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
            Vec3::new(0.3, -0.13, 0.0),
            Vec3::new(0.5, 0.5, 0.5),
        ];
        for shape in &shapes {
            for &p in &probes {
                let (q, inside) = push_out::<Libm>(shape, p);
                let contact = shape.penetration::<Libm>(p);
                assert_eq!(inside, contact.is_some(), "{shape:?} {p}");
                if let Some(c) = contact {
                    assert!((depth::<Libm>(shape, p) - c.depth).abs() < 1e-7);
                    assert!((q - (p + c.normal * c.depth)).length() < 1e-6);
                    assert!(depth::<Libm>(shape, q) < 1e-6, "{shape:?} {p} -> {q}");
                } else {
                    assert_eq!(q, p);
                    assert_eq!(depth::<Libm>(shape, p), 0.0);
                }
            }
        }
    }
}
