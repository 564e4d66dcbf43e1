//! The time-varying inputs a scene describes: the head's motion and grab paths. Each
//! is evaluated once per step on the calling thread (never per strand block), and every
//! transcendental goes through the math backend `M`, so inputs are the same bits on every
//! target and thread count.

use std::f32::consts::PI;

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

/// Where a grab's target goes.
#[derive(Clone, Debug, PartialEq)]
pub enum Path {
    /// `(time, target)` keys in increasing time, linear between them.
    Keys(Vec<(Real, Vec3)>),
    /// `start + u · r (cos 2πft − 1) + v · r sin 2πft`.
    Circle {
        /// Target at time 0.
        start: Vec3,
        /// r, m.
        radius: Real,
        /// f, Hz.
        frequency: Real,
        /// Unit axis.
        u: Vec3,
        /// Unit axis.
        v: Vec3,
    },
}

/// A grab's target path and release time.
#[derive(Clone, Debug, PartialEq)]
pub struct GrabPath {
    /// The target's path.
    pub path: Path,
    /// When the grab lets go, s.
    pub release: Option<Real>,
}

impl GrabPath {
    /// The target at time `t`: keys are linear between them and held before the first and
    /// after the last.
    #[must_use]
    pub fn target_at<M: Math>(&self, t: Real) -> Vec3 {
        match &self.path {
            Path::Keys(keys) => keyed_target(keys, t),
            Path::Circle {
                start,
                radius,
                frequency,
                u,
                v,
            } => {
                // The firmware scene's own arithmetic, term by term, so its hash is kept.
                let (s, c) = M::sin_cos(2.0 * PI * *frequency * t);
                *start + *u * (*radius * (c - 1.0)) + *v * (*radius * s)
            }
        }
    }

    /// Whether the grab has let go at time `t`.
    #[must_use]
    pub fn released_at(&self, t: Real) -> bool {
        self.release.is_some_and(|r| t >= r)
    }
}

fn keyed_target(keys: &[(Real, Vec3)], t: Real) -> Vec3 {
    let Some(&(_, first)) = keys.first() else {
        return Vec3::ZERO;
    };
    match keys.iter().position(|k| k.0 > t) {
        None => keys.last().map_or(first, |k| k.1),
        Some(0) => first,
        Some(i) => {
            let (ta, a) = keys[i - 1];
            let (tb, b) = keys[i];
            let s = (t - ta) / (tb - ta);
            a * (1.0 - s) + b * s
        }
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
            path: Path::Keys(vec![(1.0, Vec3::ZERO), (2.0, Vec3::new(0.0, 2.0, 0.0))]),
            release: Some(3.0),
        };
        assert_eq!(path.target_at::<Libm>(0.0), Vec3::ZERO);
        assert_eq!(path.target_at::<Libm>(1.5), Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(path.target_at::<Libm>(9.0), Vec3::new(0.0, 2.0, 0.0));
        assert!(!path.released_at(2.9) && path.released_at(3.0));
        let circle = GrabPath {
            path: Path::Circle {
                start: Vec3::new(1.0, 2.0, 3.0),
                radius: 0.5,
                frequency: 2.0,
                u: Vec3::X,
                v: Vec3::Z,
            },
            release: None,
        };
        assert_eq!(circle.target_at::<Libm>(0.0), Vec3::new(1.0, 2.0, 3.0));
        // A quarter turn: −r along u... plus r along v.
        let q = circle.target_at::<Libm>(0.125);
        assert!((q - Vec3::new(0.5, 2.0, 3.5)).length() < 1e-6, "{q}");
    }
}
