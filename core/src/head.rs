//! The head: a rigid pose that carries the roots (root coupling) and the colliders attached to
//! it, and the head motions tests and scenes use.

use crate::math::{self, Math, Quat, Real, Vec3};

/// A rigid pose: rotation about the head's origin, then translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Translation, m.
    pub position: Vec3,
    /// Orientation (unit quaternion).
    pub rotation: Quat,
}

impl Pose {
    /// The head at the origin, unrotated.
    pub const IDENTITY: Pose = Pose {
        position: Vec3::ZERO,
        rotation: Quat::IDENTITY,
    };

    /// Maps a point from the head's frame to the world.
    #[inline(always)]
    #[must_use]
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        math::rotate(self.rotation, p) + self.position
    }

    /// Maps a direction from the head's frame to the world.
    #[inline(always)]
    #[must_use]
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        math::rotate(self.rotation, v)
    }

    /// Whether every component is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        math::is_finite(self.position)
            && self.rotation.x.is_finite()
            && self.rotation.y.is_finite()
            && self.rotation.z.is_finite()
            && self.rotation.w.is_finite()
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Pose {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "Pose {{ position: [{}, {}, {}], rotation: [{}, {}, {}, {}] }}",
            self.position.x,
            self.position.y,
            self.position.z,
            self.rotation.x,
            self.rotation.y,
            self.rotation.z,
            self.rotation.w
        )
    }
}

/// Rotation about an axis through `centre`, `angle(t) = amplitude · sin(2π f t)`.
///
/// Kmoch 2009's "shaking at 10 rad/s" is `Shake::TEN_RAD_PER_S`: about the vertical axis,
/// amplitude 0.5 rad, peak angular speed `2π f · 0.5 = 10 rad/s` (f ≈ 3.18 Hz).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shake {
    /// Unit rotation axis (world frame).
    pub axis: Vec3,
    /// Point the axis passes through, m.
    pub centre: Vec3,
    /// Amplitude, rad.
    pub amplitude: Real,
    /// Frequency, Hz.
    pub frequency: Real,
}

#[cfg(feature = "defmt")]
impl defmt::Format for Shake {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "Shake {{ axis: [{}, {}, {}], centre: [{}, {}, {}], amplitude: {}, frequency: {} }}",
            self.axis.x,
            self.axis.y,
            self.axis.z,
            self.centre.x,
            self.centre.y,
            self.centre.z,
            self.amplitude,
            self.frequency
        )
    }
}

impl Shake {
    /// About +y through the origin, 0.5 rad, peak angular speed 10 rad/s.
    pub const TEN_RAD_PER_S: Shake = Shake {
        axis: Vec3::Y,
        centre: Vec3::ZERO,
        amplitude: 0.5,
        frequency: 10.0 / (0.5 * 2.0 * core::f32::consts::PI),
    };

    /// The head's pose at time `t`, s.
    #[must_use]
    pub fn pose_at<M: Math>(&self, t: Real) -> Pose {
        let (s, _) = M::sin_cos(2.0 * core::f32::consts::PI * self.frequency * t);
        let rotation = math::quat_from_axis_angle::<M>(self.axis, self.amplitude * s);
        // Rotation about `centre`: x ↦ R (x − c) + c.
        let position = self.centre - math::rotate(rotation, self.centre);
        Pose { position, rotation }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;

    #[test]
    fn shake_peaks_at_ten_rad_per_second() {
        let shake = Shake::TEN_RAD_PER_S;
        let h = 1.0e-4;
        let a0 = shake.pose_at::<Libm>(0.0).rotation;
        let a1 = shake.pose_at::<Libm>(h).rotation;
        // Angle of the relative rotation over h, near t = 0 where the speed peaks.
        let angle = 2.0 * math::quat_mul(math::quat_conjugate(a0), a1).y.abs();
        assert!((angle / h - 10.0).abs() < 0.01, "{}", angle / h);
    }

    #[test]
    fn shake_about_an_offset_centre_keeps_the_centre_fixed() {
        let shake = Shake {
            centre: Vec3::new(0.0, 1.0, 2.0),
            ..Shake::TEN_RAD_PER_S
        };
        let pose = shake.pose_at::<Libm>(0.07);
        assert!((pose.transform_point(shake.centre) - shake.centre).length() < 1e-6);
    }
}
