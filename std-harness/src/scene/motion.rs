//! The time-varying inputs a scene describes: the head's motion and grab paths. Each
//! is evaluated once per step on the calling thread (never per strand block), and every
//! transcendental goes through the math backend `M`, so inputs are the same bits on every
//! target and thread count.

use hairsim_core::math::{quat_from_axis_angle, quat_normalize, Quat};
use hairsim_core::{Math, Pose, Real, Shake, Vec3};

/// How the head moves.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// At the identity pose for ever.
    Still,
    /// Rotation about an axis (the core's [`Shake`]).
    Shake(Shake),
    /// Poses at times, interpolated.
    Keyframes(Vec<Key>),
}

/// One key of a keyframed head motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// s.
    pub time: Real,
    /// Translation, m.
    pub position: Vec3,
    /// Axis (unit) and angle, rad, of the rotation.
    pub axis: Vec3,
    /// rad.
    pub angle: Real,
}

impl Motion {
    /// The head's pose at time `t`, s.
    #[must_use]
    pub fn pose_at<M: Math>(&self, t: Real) -> Pose {
        match self {
            Motion::Still => Pose::IDENTITY,
            Motion::Shake(shake) => shake.pose_at::<M>(t),
            Motion::Keyframes(keys) => keyframe_pose::<M>(keys, t),
        }
    }
}

fn key_pose<M: Math>(key: &Key) -> Pose {
    Pose {
        position: key.position,
        rotation: quat_from_axis_angle::<M>(key.axis, key.angle),
    }
}

/// Linear in position, normalised-linear in rotation (on the shorter arc) between the keys
/// around `t`; the first key before it, the last after.
fn keyframe_pose<M: Math>(keys: &[Key], t: Real) -> Pose {
    let Some(first) = keys.first() else {
        return Pose::IDENTITY;
    };
    let next = keys.iter().position(|k| k.time > t);
    let (a, b) = match next {
        None => return key_pose::<M>(keys.last().unwrap_or(first)),
        Some(0) => return key_pose::<M>(first),
        Some(i) => (&keys[i - 1], &keys[i]),
    };
    let s = (t - a.time) / (b.time - a.time);
    let pa = key_pose::<M>(a);
    let pb = key_pose::<M>(b);
    let mut qb = pb.rotation;
    if pa.rotation.dot(qb) < 0.0 {
        qb = -qb;
    }
    let q = pa.rotation * (1.0 - s) + qb * s;
    Pose {
        position: pa.position * (1.0 - s) + pb.position * s,
        rotation: quat_normalize::<M>(Quat::from_xyzw(q.x, q.y, q.z, q.w)),
    }
}

/// A grab's target path and release time.
#[derive(Clone, Debug, PartialEq)]
pub struct GrabPath {
    /// `(time, target)` keys in increasing time.
    pub keys: Vec<(Real, Vec3)>,
    /// When the grab lets go, s.
    pub release: Option<Real>,
}

impl GrabPath {
    /// The target at time `t`: linear between keys, held before the first and after the last.
    #[must_use]
    pub fn target_at(&self, t: Real) -> Vec3 {
        let Some(&(_, first)) = self.keys.first() else {
            return Vec3::ZERO;
        };
        match self.keys.iter().position(|k| k.0 > t) {
            None => self.keys.last().map_or(first, |k| k.1),
            Some(0) => first,
            Some(i) => {
                let (ta, a) = self.keys[i - 1];
                let (tb, b) = self.keys[i];
                let s = (t - ta) / (tb - ta);
                a * (1.0 - s) + b * s
            }
        }
    }

    /// Whether the grab has let go at time `t`.
    #[must_use]
    pub fn released_at(&self, t: Real) -> bool {
        self.release.is_some_and(|r| t >= r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hairsim_core::Libm;

    #[test]
    fn keyframes_interpolate_and_hold() {
        let keys = vec![
            Key {
                time: 0.0,
                position: Vec3::ZERO,
                axis: Vec3::Y,
                angle: 0.0,
            },
            Key {
                time: 1.0,
                position: Vec3::new(1.0, 0.0, 0.0),
                axis: Vec3::Y,
                angle: 1.0,
            },
        ];
        let m = Motion::Keyframes(keys);
        let half = m.pose_at::<Libm>(0.5);
        assert!((half.position.x - 0.5).abs() < 1e-6);
        // nlerp of 0 and 1 rad about y is 0.5 rad by symmetry.
        let angle = 2.0 * half.rotation.y.atan2(half.rotation.w);
        assert!((angle - 0.5).abs() < 1e-5, "{angle}");
        assert_eq!(m.pose_at::<Libm>(7.0).position, Vec3::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn grab_paths_hold_at_the_ends() {
        let path = GrabPath {
            keys: vec![(1.0, Vec3::ZERO), (2.0, Vec3::new(0.0, 2.0, 0.0))],
            release: Some(3.0),
        };
        assert_eq!(path.target_at(0.0), Vec3::ZERO);
        assert_eq!(path.target_at(1.5), Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(path.target_at(9.0), Vec3::new(0.0, 2.0, 0.0));
        assert!(!path.released_at(2.9) && path.released_at(3.0));
    }
}
