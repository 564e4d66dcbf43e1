//! Follower strands (Kmoch 2009 Sec. 3; TressFX's follow hair): drawn, not simulated. A
//! follower copies one simulated leader shifted by a root offset, or blends two leaders by
//! weights. Shared by both solvers and not part of the step: the caller fills its own buffer
//! after stepping (per frame, for rendering or export).

use crate::head::Pose;
use crate::math::{self, Real, Vec3};

/// Writes the follower of `leader` whose root sits `root_offset` (head frame, m) from the
/// leader's: `y_i = x_i + R_head · root_offset`. The offset turns with the head, so the
/// follower's root stays on the scalp. Writes `min(leader.len(), out.len())` nodes and returns
/// that count.
pub fn copy_leader(leader: &[Vec3], head: &Pose, root_offset: Vec3, out: &mut [Vec3]) -> usize {
    let offset = math::rotate(head.rotation, root_offset);
    let mut written = 0;
    for (y, x) in out.iter_mut().zip(leader) {
        *y = *x + offset;
        written += 1;
    }
    written
}

/// Writes the blend of two leaders `y_i = w_a a_i + w_b b_i` (weights as given: pass weights
/// that sum to 1 for a follower between the two). Writes `min` of the three lengths nodes and
/// returns that count.
pub fn blend_leaders(
    a: &[Vec3],
    b: &[Vec3],
    weight_a: Real,
    weight_b: Real,
    out: &mut [Vec3],
) -> usize {
    let mut written = 0;
    for (y, (xa, xb)) in out.iter_mut().zip(a.iter().zip(b)) {
        *y = *xa * weight_a + *xb * weight_b;
        written += 1;
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;

    #[test]
    fn copy_keeps_the_offset_in_the_head_frame() {
        let leader = [
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.1, 0.0),
            Vec3::new(0.05, 1.2, 0.0),
        ];
        let head = Pose {
            position: Vec3::ZERO,
            rotation: math::quat_from_axis_angle::<Libm>(Vec3::Y, core::f32::consts::FRAC_PI_2),
        };
        let mut out = [Vec3::splat(9.0); 4];
        assert_eq!(
            copy_leader(&leader, &head, Vec3::new(0.01, 0.0, 0.0), &mut out),
            3
        );
        // +x in the head frame is −z in the world after a quarter turn about +y.
        assert!((out[2] - (leader[2] + Vec3::new(0.0, 0.0, -0.01))).length() < 1e-7);
        assert_eq!(out[3], Vec3::splat(9.0));
    }

    #[test]
    fn blend_interpolates_and_stops_at_the_shorter() {
        let a = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let b = [Vec3::Z, Vec3::Z];
        let mut out = [Vec3::ZERO; 3];
        assert_eq!(blend_leaders(&a, &b, 0.25, 0.75, &mut out), 2);
        assert_eq!(out[1], Vec3::new(0.25, 0.0, 0.75));
    }
}
