//! A strand: its rest data (never changes once built) apart from its state (what a step
//! changes, and the only thing hashed, snapshotted and rolled back), and the schedule a step
//! keeps for it (which integrator it takes from now on).
//!
//! Nodes `x_0 … x_{n+1}`, segments `e^j = x_{j+1} − x_j` for `j = 0 … n` (Kmoch 2009, Sec. 4).
//! Nodes 0 and 1 are held by the head (root coupling), so a strand has at least 3 nodes.
//! `N` is a capacity: each strand has its own node count `≤ N`, and entries past it are zero.

use crate::error::BuildError;
use crate::math::{Libm, Math, Real, Vec3};

pub use crate::capacities::MIN_SEGMENT_LENGTH;

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

    /// Checks every field against its range ([`MATERIAL_RANGES`]), naming the first out of
    /// it.
    pub fn validate(&self) -> Result<(), BuildError> {
        let values = [
            self.youngs_modulus,
            self.shear_modulus,
            self.radius,
            self.density,
            self.minor_axis_penalty,
        ];
        for (value, range) in values.into_iter().zip(&MATERIAL_RANGES) {
            if !(range.least..=range.most).contains(&value) {
                return Err(BuildError::InvalidMaterial {
                    field: range.field,
                    allowed: range.allowed,
                });
            }
        }
        Ok(())
    }
}

/// A material field's range: `least` to `most`, both allowed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialRange {
    /// The field's name, as in [`Material`].
    pub field: &'static str,
    /// The least value allowed.
    pub least: Real,
    /// The largest value allowed.
    pub most: Real,
    /// The range in words, with its unit.
    pub allowed: &'static str,
}

/// The ranges of [`Material`]'s fields, in their order: from a soft synthetic fibre to about
/// 3,000 times human hair's stiffness (`E`, `G`: the rod takes the linearly implicit bending
/// step for stiff hair), 10 µm to 0.5 mm (`r`), 500 to 3000 kg/m³, and an elliptic section up
/// to 10 times stiffer about its minor axis. Both solvers' presets hold
/// every corner of them: four strands of 16 nodes, 5 mm and 1 cm apart, on a head shaking at
/// 10 rad/s for 300 steps roll back nothing (`tests/materials.rs`); outside them the rod's
/// explicit substeps and its explicit drag (the presets' 2e-7 kg/s on a node of a lighter
/// fibre) were seen to lose strands (with `µ` = 100 and `E` = 1e11 Pa; with `r` = 1 µm and
/// 100 kg/m³).
pub const MATERIAL_RANGES: [MaterialRange; 5] = [
    MaterialRange {
        field: "youngs_modulus",
        least: 1.0e7,
        most: 1.0e13,
        allowed: "1e7 Pa to 1e13 Pa",
    },
    MaterialRange {
        field: "shear_modulus",
        least: 1.0e7,
        most: 1.0e13,
        allowed: "1e7 Pa to 1e13 Pa",
    },
    MaterialRange {
        field: "radius",
        least: 1.0e-5,
        most: 5.0e-4,
        allowed: "1e-5 m to 5e-4 m",
    },
    MaterialRange {
        field: "density",
        least: 500.0,
        most: 3000.0,
        allowed: "500 kg/m3 to 3000 kg/m3",
    },
    MaterialRange {
        field: "minor_axis_penalty",
        least: 1.0,
        most: 10.0,
        allowed: "1 to 10",
    },
];

/// What a strand is at rest; computed once when the strand is built.
#[derive(Clone, Debug, PartialEq)]
#[repr(C)]
pub struct RestStrand<const N: usize> {
    /// Rest positions `x̂_i` in the head's frame.
    pub position: [Vec3; N],
    /// Rest segment lengths `|ê^j|`, `j = 0 … nodes − 2`.
    pub segment_length: [Real; N],
    /// Node masses: `ρπr²` times the node's Voronoi length (half of each adjacent segment).
    pub mass: [Real; N],
    /// `1 / mass`.
    pub inverse_mass: [Real; N],
    /// DFTL's rest frames and local rest vectors (Sánchez-Banderas 2015 Sec. 3.1).
    pub dftl: DftlRest<N>,
    /// Number of nodes `n + 2` (≥ 3, ≤ N).
    pub nodes: usize,
    /// The rod energies' rest data (`l̂`, `ω̂`, `m̂`, `θ̂`, the stiffnesses, the stable time
    /// step).
    pub rod: RodRest<N>,
}

impl<const N: usize> RestStrand<N> {
    /// A checksum of every value of the rest data, word by word (FNV-1a 32 over the `f32`
    /// bit patterns and the node count): what a caller keeps when the strand is built, to
    /// find a stray write into rest data that no step would notice (the C ABI's
    /// `hairsim_check`). Not the state hash: rest data never changes once built.
    #[must_use]
    pub fn checksum(&self) -> u32 {
        let mut sum = Words(0x811c_9dc5);
        sum.word(self.nodes as u32);
        sum.vec3s(&self.position);
        for values in [&self.segment_length, &self.mass, &self.inverse_mass] {
            sum.reals(values);
        }
        let d = &self.dftl;
        sum.vec3s(&[d.root_tangent, d.root_normal]);
        sum.vec3s(&d.local_rest);
        sum.reals(&d.root_distance);
        sum.reals(&d.strain_scale);
        let r = &self.rod;
        for values in [
            &r.rest_length,
            &r.voronoi_length,
            &r.inverse_voronoi_length,
            &r.bending_stiffness,
            &r.rest_theta,
            &r.rest_twist,
        ] {
            sum.reals(values);
        }
        sum.reals(&[r.minor_axis_penalty, r.twist_stiffness, r.stable_time_step]);
        for pair in &r.rest_twist_rotation {
            sum.reals(pair);
        }
        for pairs in &r.rest_curvature {
            sum.reals(&pairs[0]);
            sum.reals(&pairs[1]);
        }
        sum.0
    }
}

/// FNV-1a 32 taken a word at a time.
struct Words(u32);

impl Words {
    fn word(&mut self, w: u32) {
        self.0 = (self.0 ^ w).wrapping_mul(0x0100_0193);
    }
    fn reals(&mut self, values: &[Real]) {
        for v in values {
            self.word(v.to_bits());
        }
    }
    fn vec3s(&mut self, values: &[Vec3]) {
        for v in values {
            self.reals(&[v.x, v.y, v.z]);
        }
    }
}

/// Rest data of the rod energies, computed once when a strand is built
/// ([`RodRest::compute`]): with these, the strand's rest polyline — straight, wavy or helical —
/// has zero elastic energy and zero elastic force under both twist methods.
///
/// Index conventions: per segment `j = 0 … n` (`rest_length`, `bending_stiffness`,
/// `rest_theta`), per interior node `i = 1 … n` (`voronoi_length`, `rest_twist`,
/// `rest_curvature`); unused slots are zero.
#[derive(Clone, Debug, PartialEq)]
#[repr(C)]
pub struct RodRest<const N: usize, R = Real> {
    /// Rest segment lengths `|ê^j|`, m.
    pub rest_length: [R; N],
    /// `l̂_i = |ê^{i−1}| + |ê^i|`, m (twice the node's Voronoi length).
    pub voronoi_length: [R; N],
    /// `1 / l̂_i` (zero where `l̂_i` is unused): the kernels multiply instead of dividing.
    pub inverse_voronoi_length: [R; N],
    /// Bending stiffness `α^j` per segment, N·m².
    pub bending_stiffness: [R; N],
    /// `µ`: `B^j = diag(µ α^j, α^j)`.
    pub minor_axis_penalty: R,
    /// Twist stiffness `β`, N·m².
    pub twist_stiffness: R,
    /// Rest material angles `θ̂^j`: the hair-optimised twist of the rest shape with `θ̂^0 = 0`
    /// (the material frame follows the binormals, as the twist solver will put it).
    pub rest_theta: [R; N],
    /// Rest twist `m̂_i = θ̂^i − θ̂^{i−1}`, rad.
    pub rest_twist: [R; N],
    /// `(cos m̂_i, sin m̂_i)`: the hair-optimised twist continues a segment's frame by this
    /// rotation without calling `sin`/`cos` per node.
    pub rest_twist_rotation: [[R; 2]; N],
    /// Rest material curvatures `[ω̂^{i−1}_i, ω̂^i_i]` per node.
    pub rest_curvature: [[[R; 2]; 2]; N],
    /// Largest stable explicit time step of the bending forces,
    /// `(h²/2)·√(ρA / (max(1, µ) α))` with `h` the shortest segment (docs/architecture.md,
    /// "Stability of explicit bending"); infinite without bending stiffness.
    pub stable_time_step: R,
}

/// What DFTL's shape constraints need of a strand at rest (in the head's frame).
#[derive(Clone, Debug, PartialEq)]
#[repr(C)]
pub struct DftlRest<const N: usize> {
    /// `t̂_0 = R̂_0 e_x`: the first rest segment's direction.
    pub root_tangent: Vec3,
    /// `n̂_0 = R̂_0 e_y`, `R̂_0` the minimal rotation from `e_x` to `t̂_0`.
    pub root_normal: Vec3,
    /// `r_i = R̂_{i−1}⁻¹ (x̂_i − x̂_{i−1})`: node `i`'s rest offset in the frame of node `i − 1`,
    /// as components along `(t̂_{i−1}, n̂_{i−1}, t̂_{i−1} × n̂_{i−1})` (entries 0 and 1 unused:
    /// those nodes are held by the head).
    pub local_rest: [Vec3; N],
    /// `d_i / L`: rest distance from the root along the strand over the strand's length, 0 at
    /// the root and 1 at the tip (for coefficients that fade with distance from the root).
    pub root_distance: [Real; N],
    /// `1 / (2 l_{i−1}²)` for the segment ending at node `i` (0 for `i = 0`): the step measures
    /// the strain `(|e|² − l²)/(2 l²)` without a square root or a division.
    pub strain_scale: [Real; N],
}

/// What a step changes. Only this is hashed, snapshotted and rolled back.
#[derive(Clone, Debug, PartialEq)]
#[repr(C)]
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

impl<const N: usize> StrandState<N> {
    /// All zero: a buffer before its first use.
    pub const EMPTY: Self = StrandState {
        position: [Vec3::ZERO; N],
        velocity: [Vec3::ZERO; N],
        theta: [0.0; N],
        root_frame: Vec3::ZERO,
    };
}

/// What the steps decided for a strand so far, which later steps follow: kept apart from the
/// rest data (which never changes once built) and from the state (which a roll-back restores,
/// and the state hash covers; `crate::hash` says why this is not hashed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Schedule {
    /// Set when the strand's shape was folded sharper than its explicit substeps can hold, or
    /// when it diverged and was rolled back: from then on the rod steps its bending with the
    /// linearly implicit step whatever its substep count (`rod::implicit`). Such states — a
    /// fold near a hairpin, nodes pushed out of a collider — are ones the implicit step holds
    /// (tests/torture.rs); the step's cost stays bounded by the implicit step's. Kept across
    /// roll-backs: a roll-back is what sets it.
    pub implicit_bending: bool,
}

/// One strand: rest data, state and schedule.
///
/// `repr(C)`, as the other strand data: the declared order is the layout. The step's loads
/// reach fields by an immediate offset from the strand, which on the Cortex-M4F is short
/// (±1020 bytes for `VLDR`): the state first, then the rest data in the order of its
/// declaration, keeps the fields a step reads most within it.
#[derive(Clone, Debug, PartialEq)]
#[repr(C)]
pub struct Strand<const N: usize> {
    /// State: positions, velocities, twist, root frame.
    pub state: StrandState<N>,
    /// Rest data: never changed by a step.
    pub rest: RestStrand<N>,
    /// What earlier steps decided for this strand.
    pub schedule: Schedule,
}

impl<const N: usize> Strand<N> {
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

/// A unit vector perpendicular to `t` (deterministic: crossed with the axis least aligned),
/// normalised by dividing by its length, in `f32`: how scenes pick a strand's sideways
/// direction. (The rod's frames normalise by the reciprocal instead,
/// `frames::perpendicular_unit_by_reciprocal`: other bits.)
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
