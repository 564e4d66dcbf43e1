//! Colliders (sphere, capsule, plane) and their penetration queries, shared by both solvers.
//! A collider may be attached to the head, in which case it is given in the head's frame and
//! moves with it.

use crate::error::ParamError;
use crate::head::Pose;
use crate::math::{Math, Real, Vec3};

pub use crate::capacities::MAX_COLLIDERS;

/// Smallest collider radius, m. Below it a contact row's gradient `2(x − c)` underflows f32
/// (found by the projection fuzz target with a radius of 1e-20 m).
pub const MIN_RADIUS: Real = 1.0e-5;
/// Largest collider radius, m.
pub const MAX_RADIUS: Real = 1.0e4;

/// A collider's geometry.
///
/// `repr(C, u8)`: the variant's index in the first byte (`crate::world::WorldLayout`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, u8)]
pub enum Shape {
    /// A ball.
    Sphere {
        /// Centre, m.
        centre: Vec3,
        /// Radius, m.
        radius: Real,
    },
    /// The points within `radius` of the segment `a`–`b`.
    Capsule {
        /// One end of the axis, m.
        a: Vec3,
        /// The other end, m.
        b: Vec3,
        /// Radius, m.
        radius: Real,
    },
    /// The half-space behind a plane: points with `(p − point)·normal < 0` are inside.
    Plane {
        /// A point on the plane, m.
        point: Vec3,
        /// Unit outward normal.
        normal: Vec3,
    },
}

/// A collider and whether it moves with the head.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Collider {
    /// Geometry (in the head's frame if `attached_to_head`, else in the world).
    pub shape: Shape,
    /// Whether the collider moves rigidly with the head.
    pub attached_to_head: bool,
}

/// A node found inside a collider.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Unit outward normal at the closest surface point.
    pub normal: Vec3,
    /// How deep the node is, m (> 0).
    pub depth: Real,
}

#[cfg(feature = "defmt")]
impl defmt::Format for Shape {
    fn format(&self, f: defmt::Formatter) {
        use crate::math::DefmtVec3 as V;
        match *self {
            Shape::Sphere { centre, radius } => {
                defmt::write!(f, "Sphere {{ centre: {}, radius: {} }}", V(centre), radius)
            }
            Shape::Capsule { a, b, radius } => defmt::write!(
                f,
                "Capsule {{ a: {}, b: {}, radius: {} }}",
                V(a),
                V(b),
                radius
            ),
            Shape::Plane { point, normal } => {
                defmt::write!(f, "Plane {{ point: {}, normal: {} }}", V(point), V(normal))
            }
        }
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Collider {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "Collider {{ shape: {}, attached_to_head: {} }}",
            self.shape,
            self.attached_to_head
        )
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Contact {
    fn format(&self, f: defmt::Formatter) {
        use crate::math::DefmtVec3 as V;
        defmt::write!(
            f,
            "Contact {{ normal: {}, depth: {} }}",
            V(self.normal),
            self.depth
        )
    }
}

impl Shape {
    /// This shape moved by `pose`.
    #[must_use]
    pub fn transformed(&self, pose: &Pose) -> Shape {
        match *self {
            Shape::Sphere { centre, radius } => Shape::Sphere {
                centre: pose.transform_point(centre),
                radius,
            },
            Shape::Capsule { a, b, radius } => Shape::Capsule {
                a: pose.transform_point(a),
                b: pose.transform_point(b),
                radius,
            },
            Shape::Plane { point, normal } => Shape::Plane {
                point: pose.transform_point(point),
                normal: pose.transform_vector(normal),
            },
        }
    }

    /// Whether every parameter is finite and in range ([`Shape::check`]).
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.check().is_ok()
    }

    /// Checks every parameter, naming the first one out of range: finite points, a radius
    /// from [`MIN_RADIUS`] to [`MAX_RADIUS`], a unit plane normal.
    pub fn check(&self) -> Result<(), ParamError> {
        use crate::math::is_finite;
        let point = |ok: bool, field| {
            if ok {
                Ok(())
            } else {
                Err(ParamError::OutOfRange {
                    field,
                    allowed: "finite coordinates, m",
                })
            }
        };
        let radius = |r: Real| {
            if (MIN_RADIUS..=MAX_RADIUS).contains(&r) {
                Ok(())
            } else {
                Err(ParamError::OutOfRange {
                    field: "collider.radius",
                    allowed: "1e-5 m to 1e4 m",
                })
            }
        };
        match *self {
            Shape::Sphere { centre, radius: r } => {
                point(is_finite(centre), "collider.centre")?;
                radius(r)
            }
            Shape::Capsule { a, b, radius: r } => {
                point(is_finite(a), "collider.a")?;
                point(is_finite(b), "collider.b")?;
                radius(r)
            }
            Shape::Plane { point: p, normal } => {
                point(is_finite(p), "collider.point")?;
                let unit = is_finite(normal) && (normal.length_squared() - 1.0).abs() < 1e-4;
                if unit {
                    Ok(())
                } else {
                    Err(ParamError::OutOfRange {
                        field: "collider.normal",
                        allowed: "a finite unit vector",
                    })
                }
            }
        }
    }

    /// The contact of point `p` with this shape, if `p` is strictly inside.
    #[inline]
    #[must_use]
    pub fn penetration<M: Math>(&self, p: Vec3) -> Option<Contact> {
        match *self {
            Shape::Sphere { centre, radius } => ball::<M>(p, centre, radius),
            Shape::Capsule { a, b, radius } => ball::<M>(p, closest_on_segment(p, a, b), radius),
            Shape::Plane { point, normal } => {
                let distance = (p - point).dot(normal);
                (distance < 0.0).then_some(Contact {
                    normal,
                    depth: -distance,
                })
            }
        }
    }
}

/// The point of the segment `a`–`b` closest to `p` (a capsule's axis point for `p`).
#[inline]
#[must_use]
pub fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let axis = b - a;
    let length2 = axis.dot(axis);
    let t = if length2 > 0.0 {
        ((p - a).dot(axis) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    a + axis * t
}

/// Contact of `p` with the ball of `radius` about `centre`. A point exactly at the centre is
/// pushed along +y (any fixed direction will do; it must not depend on the target).
#[inline]
fn ball<M: Math>(p: Vec3, centre: Vec3, radius: Real) -> Option<Contact> {
    let d = p - centre;
    let distance2 = d.dot(d);
    if distance2 >= radius * radius {
        return None;
    }
    let distance = M::sqrt(distance2);
    let normal = if distance > 0.0 {
        d / distance
    } else {
        Vec3::Y
    };
    Some(Contact {
        normal,
        depth: radius - distance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;

    #[test]
    fn penetration_of_each_shape() {
        let sphere = Shape::Sphere {
            centre: Vec3::ZERO,
            radius: 1.0,
        };
        let c = sphere
            .penetration::<Libm>(Vec3::new(0.0, 0.5, 0.0))
            .unwrap();
        assert_eq!(c.normal, Vec3::Y);
        assert!((c.depth - 0.5).abs() < 1e-7);
        assert!(sphere
            .penetration::<Libm>(Vec3::new(0.0, 1.5, 0.0))
            .is_none());

        let capsule = Shape::Capsule {
            a: Vec3::ZERO,
            b: Vec3::new(2.0, 0.0, 0.0),
            radius: 0.5,
        };
        let c = capsule
            .penetration::<Libm>(Vec3::new(1.0, 0.0, 0.25))
            .unwrap();
        assert_eq!(c.normal, Vec3::Z);
        assert!((c.depth - 0.25).abs() < 1e-7);
        assert!(capsule
            .penetration::<Libm>(Vec3::new(2.6, 0.0, 0.0))
            .is_none());

        let plane = Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        };
        assert!(
            (plane
                .penetration::<Libm>(Vec3::new(3.0, -0.2, 1.0))
                .unwrap()
                .depth
                - 0.2)
                .abs()
                < 1e-7
        );
        assert!(plane.is_valid() && sphere.is_valid() && capsule.is_valid());
    }

    /// Regression from the projection fuzz target: a sphere of radius 1e-20 m made a contact
    /// row whose gradient underflowed; such colliders are refused up front.
    #[test]
    fn degenerate_radii_are_refused() {
        let tiny = Shape::Sphere {
            centre: Vec3::ZERO,
            radius: 8.4e-21,
        };
        assert!(!tiny.is_valid());
        let huge = Shape::Capsule {
            a: Vec3::ZERO,
            b: Vec3::X,
            radius: 1.0e5,
        };
        assert!(!huge.is_valid());
        assert!(Shape::Sphere {
            centre: Vec3::ZERO,
            radius: MIN_RADIUS
        }
        .is_valid());
    }

    #[test]
    fn transformed_moves_with_the_pose() {
        let pose = Pose {
            position: Vec3::new(1.0, 0.0, 0.0),
            rotation: crate::math::quat_from_axis_angle::<Libm>(
                Vec3::Z,
                core::f32::consts::FRAC_PI_2,
            ),
        };
        let moved = Shape::Sphere {
            centre: Vec3::X,
            radius: 1.0,
        }
        .transformed(&pose);
        let Shape::Sphere { centre, .. } = moved else {
            panic!()
        };
        assert!((centre - Vec3::new(1.0, 1.0, 0.0)).length() < 1e-6);
    }
}
