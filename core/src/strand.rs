//! A strand: its rest data (never changes once built) apart from its state (what a step
//! changes, and the only thing hashed, snapshotted and rolled back).
//!
//! Nodes `x_0 … x_{n+1}`, segments `e^j = x_{j+1} − x_j` for `j = 0 … n` (Kmoch 2009, Sec. 4).
//! Nodes 0 and 1 are held by the head (root coupling), so a strand has at least 3 nodes.
//! `N` is a capacity: each strand has its own node count `≤ N`, and entries past it are zero.

use crate::error::BuildError;
use crate::math::{Libm, Math, Real, Vec3};
use crate::rod::energy::{rest_root_frame, RodRest};

/// Shortest rest segment a strand may have, m.
pub const MIN_SEGMENT_LENGTH: Real = 1.0e-6;

/// A round hair fibre's material (SI units).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Material {
    /// Young's modulus `E`, Pa → bending stiffness `α = E·π·r⁴/4`.
    pub youngs_modulus: Real,
    /// Shear modulus `G`, Pa → twist stiffness `β = G·π·r⁴/2`.
    pub shear_modulus: Real,
    /// Fibre radius `r`, m.
    pub radius: Real,
    /// Density `ρ`, kg/m³ → node mass `ρ·π·r²·(Voronoi length)`.
    pub density: Real,
    /// `µ ≥ 1`: multiplier on bending about the minor axis (elliptic section).
    pub minor_axis_penalty: Real,
}

impl Material {
    /// A human hair: E = 3.5 GPa, G = 1.3 GPa, r = 40 µm, ρ = 1300 kg/m³, µ = 1.
    pub const HUMAN_HAIR: Material = Material {
        youngs_modulus: 3.5e9,
        shear_modulus: 1.3e9,
        radius: 4.0e-5,
        density: 1300.0,
        minor_axis_penalty: 1.0,
    };

    /// Bending stiffness `α = E·π·r⁴/4`, N·m².
    #[must_use]
    pub fn bending_stiffness(&self) -> Real {
        let r2 = self.radius * self.radius;
        self.youngs_modulus * core::f32::consts::PI * r2 * r2 / 4.0
    }

    /// Twist stiffness `β = G·π·r⁴/2`, N·m².
    #[must_use]
    pub fn twist_stiffness(&self) -> Real {
        let r2 = self.radius * self.radius;
        self.shear_modulus * core::f32::consts::PI * r2 * r2 / 2.0
    }

    /// Mass per unit length `ρ·π·r²`, kg/m.
    #[must_use]
    pub fn linear_density(&self) -> Real {
        self.density * core::f32::consts::PI * self.radius * self.radius
    }

    /// Checks every field against its range.
    pub fn validate(&self) -> Result<(), BuildError> {
        let check = |ok: bool, field, allowed| {
            if ok {
                Ok(())
            } else {
                Err(BuildError::InvalidMaterial { field, allowed })
            }
        };
        let positive = |v: Real| v.is_finite() && v > 0.0;
        check(
            self.youngs_modulus.is_finite() && self.youngs_modulus >= 0.0,
            "youngs_modulus",
            "a finite value >= 0 Pa",
        )?;
        check(
            self.shear_modulus.is_finite() && self.shear_modulus >= 0.0,
            "shear_modulus",
            "a finite value >= 0 Pa",
        )?;
        check(
            positive(self.radius) && self.radius <= 0.01,
            "radius",
            "0 < r <= 0.01 m",
        )?;
        check(
            positive(self.density),
            "density",
            "a finite value > 0 kg/m3",
        )?;
        check(
            self.minor_axis_penalty.is_finite() && (1.0..=100.0).contains(&self.minor_axis_penalty),
            "minor_axis_penalty",
            "1 to 100",
        )
    }
}

/// What a strand is at rest; computed once when the strand is built.
#[derive(Clone, Debug, PartialEq)]
pub struct RestStrand<const N: usize> {
    /// Number of nodes `n + 2` (≥ 3, ≤ N).
    pub nodes: usize,
    /// Rest positions `x̂_i` in the head's frame.
    pub position: [Vec3; N],
    /// Rest segment lengths `|ê^j|`, `j = 0 … nodes − 2`.
    pub segment_length: [Real; N],
    /// Node masses: `ρπr²` times the node's Voronoi length (half of each adjacent segment).
    pub mass: [Real; N],
    /// `1 / mass`.
    pub inverse_mass: [Real; N],
    /// Bending stiffness `α^j` per segment, N·m² (may vary along the strand).
    pub bending_stiffness: [Real; N],
    /// `µ`, the minor-axis multiplier: `B^j = diag(µ α^j, α^j)`.
    pub minor_axis_penalty: Real,
    /// Twist stiffness `β`, N·m².
    pub twist_stiffness: Real,
    /// DFTL's rest frames and local rest vectors (Sánchez-Banderas 2015 Sec. 3.1).
    pub dftl: crate::dftl::DftlRest<N>,
    /// The rod energies' rest data (`l̂`, `ω̂`, `m̂`, `θ̂`, the stable time step).
    pub rod: RodRest<N>,
}

/// What a step changes. Only this is hashed, snapshotted and rolled back.
#[derive(Clone, Debug, PartialEq)]
pub struct StrandState<const N: usize> {
    /// Node positions `x_i`, m (world frame).
    pub position: [Vec3; N],
    /// Node velocities `ẋ_i`, m/s.
    pub velocity: [Vec3; N],
    /// Material-frame angle `θ^j` per segment, rad (rod solver; zero for DFTL).
    pub theta: [Real; N],
    /// Bishop frame vector `u^0` of the root segment (unit, perpendicular to `t^0`).
    pub root_frame: Vec3,
}

/// One strand: rest data and state.
#[derive(Clone, Debug, PartialEq)]
pub struct Strand<const N: usize> {
    /// Rest data: never changed by a step.
    pub rest: RestStrand<N>,
    /// State: positions, velocities, twist, root frame.
    pub state: StrandState<N>,
}

impl<const N: usize> Strand<N> {
    const CAPACITY_OK: () = assert!(N >= 3, "a strand needs a capacity of at least 3 nodes");

    /// Builds a strand at rest from its rest polyline (root first, in the head's frame) and a
    /// material. Checks the node count against `N`, every coordinate, every segment's length
    /// and the material's ranges.
    pub fn from_polyline(points: &[Vec3], material: &Material) -> Result<Self, BuildError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::CAPACITY_OK;
        let nodes = points.len();
        if nodes < 3 {
            return Err(BuildError::TooFewNodes { count: nodes });
        }
        if nodes > N {
            return Err(BuildError::TooManyNodes {
                count: nodes,
                capacity: N,
            });
        }
        material.validate()?;
        if let Some(node) = points.iter().position(|p| !crate::math::is_finite(*p)) {
            return Err(BuildError::NonFiniteNode { node });
        }
        let mut rest = RestStrand {
            nodes,
            position: [Vec3::ZERO; N],
            segment_length: [0.0; N],
            mass: [0.0; N],
            inverse_mass: [0.0; N],
            bending_stiffness: [0.0; N],
            minor_axis_penalty: material.minor_axis_penalty,
            twist_stiffness: material.twist_stiffness(),
            dftl: crate::dftl::DftlRest::from_polyline::<Libm>(&[]),
            rod: RodRest::compute::<Libm>(&[], 0.0, 1.0, 0.0, 1.0),
        };
        rest.position[..nodes].copy_from_slice(points);
        let lambda = material.linear_density();
        let alpha = material.bending_stiffness();
        for j in 0..nodes - 1 {
            let e = points[j + 1] - points[j];
            let length = Libm::length(e);
            if !length.is_finite() || length < MIN_SEGMENT_LENGTH {
                return Err(BuildError::DegenerateSegment { segment: j });
            }
            if j > 0 {
                let previous = points[j] - points[j - 1];
                // Turning angle of π: the curvature binormal 2(e×e')/(|e||e'| + e·e') divides by 0.
                if previous.dot(e) <= -0.999_999 * rest.segment_length[j - 1] * length {
                    return Err(BuildError::FoldedSegment { node: j });
                }
            }
            rest.segment_length[j] = length;
            rest.bending_stiffness[j] = alpha;
            rest.mass[j] += 0.5 * lambda * length;
            rest.mass[j + 1] += 0.5 * lambda * length;
        }
        for i in 0..nodes {
            rest.inverse_mass[i] = 1.0 / rest.mass[i];
        }
        rest.dftl = crate::dftl::DftlRest::from_polyline::<Libm>(points);
        // Segments are checked above: the rod's rest data divides by their lengths.
        rest.rod = RodRest::compute::<Libm>(
            points,
            alpha,
            material.minor_axis_penalty,
            material.twist_stiffness(),
            lambda,
        );
        let mut state = StrandState {
            position: [Vec3::ZERO; N],
            velocity: [Vec3::ZERO; N],
            // The rest material frames: a strand starts at rest for the twist solvers too.
            theta: rest.rod.rest_theta,
            root_frame: rest_root_frame::<Libm>(points[0], points[1], rest.segment_length[0]),
        };
        state.position[..nodes].copy_from_slice(points);
        Ok(Strand { rest, state })
    }

    /// Number of nodes of this strand.
    #[must_use]
    pub fn nodes(&self) -> usize {
        self.rest.nodes
    }

    /// The node positions in use.
    #[must_use]
    pub fn positions(&self) -> &[Vec3] {
        &self.state.position[..self.rest.nodes]
    }

    /// Whether every value of the state is finite.
    #[must_use]
    #[allow(clippy::eq_op)] // x − x is the point: 0 for finite x, NaN for ±∞ and NaN.
    pub fn is_finite(&self) -> bool {
        let n = self.rest.nodes.min(N);
        // One sum of `x − x` over every value, no branch per value (the guard runs on every
        // strand every step): 0 while all are finite, NaN as soon as one is not.
        let mut poison: Real = 0.0;
        let state = &self.state;
        for ((p, v), t) in state
            .position
            .iter()
            .zip(&state.velocity)
            .zip(&state.theta)
            .take(n)
        {
            poison = poison
                + ((p.x - p.x) + (p.y - p.y) + (p.z - p.z))
                + ((v.x - v.x) + (v.y - v.y) + (v.z - v.z))
                + (t - t);
        }
        poison == 0.0 && crate::math::is_finite(state.root_frame)
    }
}

/// A unit vector perpendicular to `t` (deterministic: crossed with the axis least aligned).
#[must_use]
pub fn perpendicular_unit(t: Vec3) -> Vec3 {
    let a = t.abs();
    let axis = if a.x <= a.y && a.x <= a.z {
        Vec3::X
    } else if a.y <= a.z {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let u = t.cross(axis);
    let length = Libm::length(u);
    if length > 0.0 {
        u / length
    } else {
        Vec3::X
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize) -> [Vec3; 8] {
        let mut p = [Vec3::ZERO; 8];
        for (i, q) in p.iter_mut().enumerate().take(n) {
            *q = Vec3::new(0.01 * i as Real, 0.0, 0.0);
        }
        p
    }

    #[test]
    fn builds_with_masses_and_lengths() {
        let p = line(5);
        let s = Strand::<8>::from_polyline(&p[..5], &Material::HUMAN_HAIR).unwrap();
        assert_eq!(s.nodes(), 5);
        let total: Real = s.rest.mass.iter().sum();
        let expected = Material::HUMAN_HAIR.linear_density() * 0.04;
        assert!((total - expected).abs() < 1e-6 * expected);
        assert!((s.rest.segment_length[3] - 0.01).abs() < 1e-7);
        assert!(s.state.root_frame.dot(Vec3::X).abs() < 1e-7);
    }

    #[test]
    fn refuses_bad_polylines_with_a_named_reason() {
        let p = line(8);
        assert_eq!(
            Strand::<4>::from_polyline(&p[..6], &Material::HUMAN_HAIR),
            Err(BuildError::TooManyNodes {
                count: 6,
                capacity: 4
            })
        );
        assert_eq!(
            Strand::<8>::from_polyline(&p[..2], &Material::HUMAN_HAIR),
            Err(BuildError::TooFewNodes { count: 2 })
        );
        let mut nan = p;
        nan[2].y = Real::NAN;
        assert_eq!(
            Strand::<8>::from_polyline(&nan[..4], &Material::HUMAN_HAIR),
            Err(BuildError::NonFiniteNode { node: 2 })
        );
        let mut dup = p;
        dup[3] = dup[2];
        assert_eq!(
            Strand::<8>::from_polyline(&dup[..5], &Material::HUMAN_HAIR),
            Err(BuildError::DegenerateSegment { segment: 2 })
        );
        let mut fold = p;
        fold[3] = fold[1];
        assert_eq!(
            Strand::<8>::from_polyline(&fold[..4], &Material::HUMAN_HAIR),
            Err(BuildError::FoldedSegment { node: 2 })
        );
        let soft = Material {
            radius: -1.0,
            ..Material::HUMAN_HAIR
        };
        let e = Strand::<8>::from_polyline(&p[..4], &soft).unwrap_err();
        assert!(matches!(
            e,
            BuildError::InvalidMaterial {
                field: "radius",
                ..
            }
        ));
    }
}
