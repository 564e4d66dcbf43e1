//! Rest polylines of generated hair: straight, wavy and curly strands, wisps on a stand and a
//! scalp of leaders, and the followers drawn around them (Kmoch 2009 Sec. 3: followers are
//! interpolated from their leader, never simulated).
//!
//! Computed in `f64` with `libm`, then rounded to `f32`, so a scene generates the same bits on
//! every platform.

use hairsim_core::strand::perpendicular_unit;
use hairsim_core::{Real, Vec3};

use super::V3;

/// How a generated strand curls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Style {
    /// A straight line.
    Straight,
    /// A planar sine wave across the strand.
    Wavy {
        /// m.
        amplitude: f64,
        /// Wavelength, m.
        period: f64,
    },
    /// A helix about the strand's direction.
    Curly {
        /// Helix radius, m.
        radius: f64,
        /// Advance per turn, m.
        period: f64,
    },
}

/// A vector from a scene triple.
#[must_use]
pub fn v3(p: V3) -> Vec3 {
    Vec3::new(p[0], p[1], p[2])
}

fn unit(d: [f64; 3]) -> [f64; 3] {
    let l = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    [d[0] / l, d[1] / l, d[2] / l]
}

fn f64s(v: Vec3) -> [f64; 3] {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `nodes` points from `root` along `direction`, `length` of arc in all, shaped by `style`.
#[must_use]
pub fn strand(root: Vec3, direction: Vec3, length: f64, nodes: usize, style: Style) -> Vec<Vec3> {
    let d = unit(f64s(direction));
    let u = f64s(perpendicular_unit(Vec3::new(
        d[0] as Real,
        d[1] as Real,
        d[2] as Real,
    )));
    let w = cross(d, u);
    let r = f64s(root);
    let segments = (nodes.max(2) - 1) as f64;
    (0..nodes)
        .map(|i| {
            let s = length * i as f64 / segments;
            let (along, du, dw) = match style {
                Style::Straight => (s, 0.0, 0.0),
                Style::Wavy { amplitude, period } => (
                    s,
                    amplitude * libm::sin(std::f64::consts::TAU * s / period),
                    0.0,
                ),
                Style::Curly { radius, period } => {
                    // Parametrised by arc length, so the nodes are equally spaced on the helix.
                    let turn =
                        libm::sqrt((std::f64::consts::TAU * radius).powi(2) + period * period);
                    let phi = std::f64::consts::TAU * s / turn;
                    (
                        period * phi / std::f64::consts::TAU,
                        radius * (libm::cos(phi) - 1.0),
                        radius * libm::sin(phi),
                    )
                }
            };
            Vec3::new(
                (r[0] + d[0] * along + u[0] * du + w[0] * dw) as Real,
                (r[1] + d[1] * along + u[1] * du + w[1] * dw) as Real,
                (r[2] + d[2] * along + u[2] * du + w[2] * dw) as Real,
            )
        })
        .collect()
}

/// Roots and directions of `wisps` strands along the x axis through `origin`, `spacing` apart.
#[must_use]
pub fn stand_roots(wisps: usize, origin: Vec3, spacing: f64) -> Vec<Vec3> {
    let middle = (wisps as f64 - 1.0) / 2.0;
    (0..wisps)
        .map(|k| {
            let x = f64::from(origin.x) + (k as f64 - middle) * spacing;
            Vec3::new(x as Real, origin.y, origin.z)
        })
        .collect()
}

/// Roots (and outward normals) of `leaders` strands spread evenly over the cap of half-angle
/// `cap_angle` about +y of the sphere (`centre`, `radius`): a Fibonacci spiral.
#[must_use]
pub fn scalp_roots(leaders: usize, centre: Vec3, radius: f64, cap_angle: f64) -> Vec<(Vec3, Vec3)> {
    let golden = std::f64::consts::PI * (3.0 - libm::sqrt(5.0));
    let c = f64s(centre);
    let lowest = libm::cos(cap_angle);
    (0..leaders)
        .map(|k| {
            let y = 1.0 - (1.0 - lowest) * (k as f64 + 0.5) / leaders as f64;
            let ring = libm::sqrt((1.0 - y * y).max(0.0));
            let phi = golden * k as f64;
            let n = [ring * libm::cos(phi), y, ring * libm::sin(phi)];
            let root = Vec3::new(
                (c[0] + radius * n[0]) as Real,
                (c[1] + radius * n[1]) as Real,
                (c[2] + radius * n[2]) as Real,
            );
            (root, Vec3::new(n[0] as Real, n[1] as Real, n[2] as Real))
        })
        .collect()
}

/// A follower strand: its leader and a fixed offset across it (head frame). Drawn as the
/// leader's nodes shifted by the offset turned with the head.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Follower {
    /// Index of the leader strand.
    pub leader: u32,
    /// Offset from the leader, m (head frame).
    pub offset: Vec3,
}

/// `count` followers of the leader with root tangent `direction`, spread on a disc of
/// `spread` radius across it (a sunflower pattern, so they fill the disc evenly).
#[must_use]
pub fn followers(leader: u32, direction: Vec3, count: usize, spread: f64) -> Vec<Follower> {
    let d = unit(f64s(direction));
    let u = f64s(perpendicular_unit(direction));
    let w = cross(d, u);
    let golden = std::f64::consts::PI * (3.0 - libm::sqrt(5.0));
    (0..count)
        .map(|k| {
            let r = spread * libm::sqrt((k as f64 + 0.5) / count as f64);
            let phi = golden * k as f64;
            let (a, b) = (r * libm::cos(phi), r * libm::sin(phi));
            Follower {
                leader,
                offset: Vec3::new(
                    (u[0] * a + w[0] * b) as Real,
                    (u[1] * a + w[1] * b) as Real,
                    (u[2] * a + w[2] * b) as Real,
                ),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lengths(points: &[Vec3]) -> Vec<f32> {
        points.windows(2).map(|w| (w[1] - w[0]).length()).collect()
    }

    #[test]
    fn straight_strands_have_equal_segments_and_the_length_asked() {
        let p = strand(
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 2.0),
            0.3,
            31,
            Style::Straight,
        );
        assert_eq!(p.len(), 31);
        for l in lengths(&p) {
            assert!((l - 0.01).abs() < 1e-6);
        }
        assert!((p[30] - Vec3::new(0.0, 0.0, 0.3)).length() < 1e-6);
    }

    #[test]
    fn curly_strands_keep_their_arc_length_and_radius() {
        let style = Style::Curly {
            radius: 0.005,
            period: 0.02,
        };
        let p = strand(Vec3::ZERO, Vec3::Y, 0.2, 101, style);
        let arc: f32 = lengths(&p).iter().sum();
        // Chords are a little shorter than the arc they cut.
        assert!(arc < 0.2 && arc > 0.19, "{arc}");
        for q in &p {
            let axis_distance = Vec3::new(q.x, 0.0, q.z);
            // Distance to the helix axis (through the root offset by −radius·u) is the radius.
            let u = perpendicular_unit(Vec3::Y);
            assert!(((axis_distance + u * 0.005).length() - 0.005).abs() < 1e-5);
        }
    }

    #[test]
    fn scalp_roots_lie_on_the_cap() {
        let roots = scalp_roots(50, Vec3::new(0.0, 1.0, 0.0), 0.1, 1.2);
        for (root, normal) in roots {
            assert!(((root - Vec3::new(0.0, 1.0, 0.0)).length() - 0.1).abs() < 1e-6);
            assert!(normal.y >= 1.2f32.cos() - 1e-6);
        }
    }
}
