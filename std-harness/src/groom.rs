//! The groom measure: how far a run's hair has bent away from its rest groom, read from the
//! turning angles of the simulated nodes.
//!
//! The turning angle at an interior node `i` is the angle between the segments
//! `x_{i−1} → x_i` and `x_i → x_{i+1}`: 0 on a straight strand, growing with the curvature. A
//! node is *kinked* when it turns more than its own rest turning angle + [`KINK_MARGIN`]: a
//! crinkle or zig-zag the groom did not have. A strand that bends as a whole (sagging under
//! gravity, swinging) turns each node a little; a crinkle turns single nodes a lot.

use hairsim_core::{Strand, Vec3};
use serde::Serialize;

/// A node turning more than its rest turning angle + this is kinked, rad.
pub const KINK_MARGIN: f32 = 0.3;

/// The groom of a set of strands against their rest groom.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Groom {
    /// Mean turning angle over the interior nodes, rad.
    pub mean_turning: f32,
    /// The rest groom's mean turning angle over the same nodes, rad.
    pub rest_mean_turning: f32,
    /// Share of the interior nodes that are kinked, 0–1 (a node with a non-finite position
    /// counts as kinked).
    pub kinked: f32,
    /// Interior nodes measured.
    pub nodes: usize,
}

/// The angle between `b − a` and `c − b`, rad, in `[0, π]`: `atan2(|u × v|, u · v)`, which
/// keeps its accuracy at small angles where `acos` of the cosine loses it.
#[must_use]
pub fn turning_angle(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let (u, v) = (b - a, c - b);
    u.cross(v).length().atan2(u.dot(v))
}

/// The groom of `strands` now against their rest positions.
#[must_use]
pub fn measure<const N: usize>(strands: &[Strand<N>]) -> Groom {
    let (mut now_sum, mut rest_sum, mut kinked, mut count) = (0.0f64, 0.0f64, 0usize, 0usize);
    for strand in strands {
        let n = strand.rest.nodes.min(N);
        let (now, rest) = (&strand.state.position[..n], &strand.rest.position[..n]);
        for i in 1..n.saturating_sub(1) {
            let turning = turning_angle(now[i - 1], now[i], now[i + 1]);
            let rest_turning = turning_angle(rest[i - 1], rest[i], rest[i + 1]);
            count += 1;
            rest_sum += f64::from(rest_turning);
            if turning.is_finite() {
                now_sum += f64::from(turning);
                kinked += usize::from(turning > rest_turning + KINK_MARGIN);
            } else {
                kinked += 1;
            }
        }
    }
    let share = |x: f64| (x / count.max(1) as f64) as f32;
    Groom {
        mean_turning: share(now_sum),
        rest_mean_turning: share(rest_sum),
        kinked: share(kinked as f64),
        nodes: count,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_right_angle_turns_half_pi_and_a_straight_line_none() {
        let (a, b) = (Vec3::ZERO, Vec3::X);
        let right = turning_angle(a, b, Vec3::new(1.0, 1.0, 0.0));
        assert!((right - core::f32::consts::FRAC_PI_2).abs() < 1e-6);
        assert_eq!(turning_angle(a, b, Vec3::new(2.0, 0.0, 0.0)), 0.0);
        let back = turning_angle(a, b, Vec3::ZERO + Vec3::new(0.5, 1e-3, 0.0));
        assert!((back - core::f32::consts::PI).abs() < 1e-2);
    }
}
