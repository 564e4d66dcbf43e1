//! Bending and twist energies of a discrete Kirchhoff rod, their gradients, and the elastic
//! forces of Kmoch et al. 2009 Sec. 7.2 (after Bergou et al. 2008, BWR08).
//!
//! Nodes `x_0 … x_{n+1}`, segments `e^j`, `j = 0 … n`, interior nodes `i = 1 … n`. With the
//! Bishop frame `(u^j, v^j)` and the material angle `θ^j` of each segment:
//!
//! * material curvature `ω^j_i = ((κb)_i·m2^j, −(κb)_i·m1^j)` for `j ∈ {i−1, i}`; written as the
//!   Bishop components `p^j_i = ((κb)_i·v^j, −(κb)_i·u^j)` rotated by `−θ^j`, so that `θ` enters
//!   only through `(cos θ^j, sin θ^j)`, computed once per segment;
//! * `E_bend = Σ_i 1/(2 l̂_i) Σ_j (ω^j_i − ω̂^j_i)ᵀ B^j (ω^j_i − ω̂^j_i)`, `B^j = diag(µα^j, α^j)`,
//!   `l̂_i = |ê^{i−1}| + |ê^i|` (the full length, twice the Voronoi length);
//! * `E_twist = Σ_i β (m_i − m̂_i)² / l̂_i`, `m_i = θ^i − θ^{i−1}`.
//!
//! [`elastic_forces`] is `F_i = −∂E/∂x_i + Σ_{c∈C} (∂E/∂θ^c) ∇_iΨ^c` at the current `θ`, in
//! O(n) with suffix sums of the holonomy weights (the literal sum over `∇_iΨ^j` is O(n²)).
//! With `θ` at the twist minimum (Newton) it equals `−dE/dx`; with the hair-optimised twist it
//! is `−∂E/∂x` at fixed `θ` plus the clamped terms.
//!
//! Everything is generic over a [`Precision`] so the finite-difference tests run in `f64`.

use super::twist::binormal_direction;
use super::{ClampedSegments, ElasticTerms};
use crate::frames::{curvature_binormal, parallel_transport, perpendicular_unit};
use crate::math::Real;
use crate::precision::{Precision, Scalar, Vector};

/// Rest data of the rod energies, computed once when a strand is built
/// ([`RodRest::compute`]): with these, the strand's rest polyline — straight, wavy or helical —
/// has zero elastic energy and zero elastic force under both twist methods.
///
/// Index conventions: per segment `j = 0 … n` (`rest_length`, `bending_stiffness`,
/// `rest_theta`), per interior node `i = 1 … n` (`voronoi_length`, `rest_twist`,
/// `rest_curvature`); unused slots are zero.
#[derive(Clone, Debug, PartialEq)]
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
    /// `(h²/2)·√(ρA / (max(1, µ) α))` with `h` the shortest segment (DESIGN.md "Stability");
    /// infinite without bending stiffness.
    pub stable_time_step: R,
    /// Set when the strand's current shape is folded sharper than its explicit substeps can
    /// hold, or when it diverged and was rolled back: from then on it takes the linearly
    /// implicit bending step whatever its substep count (`rod::implicit`). Such states — a
    /// fold near a hairpin, nodes pushed out of a collider — are ones the implicit step
    /// holds (tests/torture.rs); the step's cost stays bounded by the implicit step's. Not
    /// state: a setting the run has earned, kept across roll-backs.
    pub implicit_bending: bool,
}

impl<const N: usize, R: Scalar> RodRest<N, R> {
    /// The rest data of the polyline `points` (at most `N` nodes are read; fewer than 3 give
    /// all zeros; segment lengths and fold-backs are checked by the caller) with uniform stiffnesses and linear density `λ = ρA`, kg/m.
    #[must_use]
    pub fn compute<P: Precision<R = R>>(
        points: &[P::V],
        bending_stiffness: R,
        minor_axis_penalty: R,
        twist_stiffness: R,
        linear_density: R,
    ) -> Self {
        let nodes = points.len().min(N);
        let segments = nodes.saturating_sub(1);
        let mut rest = RodRest {
            rest_length: [R::ZERO; N],
            voronoi_length: [R::ZERO; N],
            inverse_voronoi_length: [R::ZERO; N],
            bending_stiffness: [R::ZERO; N],
            minor_axis_penalty,
            twist_stiffness,
            rest_theta: [R::ZERO; N],
            rest_twist: [R::ZERO; N],
            rest_twist_rotation: [[R::ONE, R::ZERO]; N],
            rest_curvature: [[[R::ZERO; 2]; 2]; N],
            stable_time_step: R::of(f32::INFINITY),
            implicit_bending: false,
        };
        if nodes < 3 {
            return rest;
        }
        let mut shortest = R::of(f32::INFINITY);
        for j in 0..segments {
            let e = points[j + 1] - points[j];
            rest.rest_length[j] = P::sqrt(e.dot(e));
            rest.bending_stiffness[j] = bending_stiffness;
            if rest.rest_length[j] < shortest {
                shortest = rest.rest_length[j];
            }
        }
        for i in 1..segments {
            rest.voronoi_length[i] = rest.rest_length[i - 1] + rest.rest_length[i];
            rest.inverse_voronoi_length[i] = R::ONE / rest.voronoi_length[i];
        }
        let root_frame = rest_root_frame::<P>(points[0], points[1], rest.rest_length[0]);
        let frames = RodFrames::<P, N>::compute(&points[..nodes], root_frame, &rest.rest_length);
        // θ̂: each segment's angle follows its binormals, the representative mod π closest to
        // the previous segment (least rest twist); straight runs continue the previous angle.
        for j in 1..segments {
            let previous = rest.rest_theta[j - 1];
            rest.rest_theta[j] = match binormal_direction(&frames, j) {
                Some(direction) => {
                    let phi = P::atan2(direction[1], direction[0]);
                    representative_near(phi, direction, previous).0
                }
                None => previous,
            };
            rest.rest_twist[j] = rest.rest_theta[j] - rest.rest_theta[j - 1];
            let (s, c) = P::sin_cos(rest.rest_twist[j]);
            rest.rest_twist_rotation[j] = [c, s];
        }
        let cos_sin = material_angles::<P, N>(&rest.rest_theta[..segments]);
        for i in 1..segments {
            for k in 0..2 {
                rest.rest_curvature[i][k] =
                    material_curvature(frames.bishop_curvature[i][k], cos_sin[i - 1 + k]);
            }
        }
        let stiffest = if minor_axis_penalty > R::ONE {
            minor_axis_penalty * bending_stiffness
        } else {
            bending_stiffness
        };
        if stiffest > R::ZERO {
            let half = R::of(0.5);
            rest.stable_time_step = half * shortest * shortest * P::sqrt(linear_density / stiffest);
        }
        rest
    }
}

/// The root segment's Bishop vector `u^0` at rest, which is also its rest material vector
/// `m1^0` (`θ̂^0 = 0`): perpendicular to the rest root tangent. The state starts with it, and
/// the head carries it to set `θ^0` each step.
#[must_use]
pub fn rest_root_frame<P: Precision>(root: P::V, next: P::V, rest_length: P::R) -> P::V {
    perpendicular_unit::<P>((next - root) * (P::R::ONE / rest_length))
}

/// The representative of the direction `(cos φ, sin φ)` (an unoriented line, defined mod π)
/// closest to `reference`: `θ = φ + kπ`, with `φ = atan2(sin φ, cos φ)` given. Returns `θ`,
/// `(cos θ, sin θ)`, and whether `k` is odd (the direction flipped).
#[inline(always)]
#[must_use]
pub fn representative_near<R: Scalar>(
    phi: R,
    direction: [R; 2],
    reference: R,
) -> (R, [R; 2], bool) {
    let [c, s] = direction;
    // On the twist sweep's sequential chain (`reference` is the neighbour's new angle): a
    // multiplication by 1/π rather than a division, and the parity from the integer.
    let (k, odd) = ((reference - phi) * R::FRAC_1_PI + R::of(0.5)).floor_and_parity();
    let cos_sin = if odd { [-c, -s] } else { [c, s] };
    (phi + k * R::PI, cos_sin, odd)
}

/// The frames of a strand's current configuration: segments, tangents, curvature binormals,
/// the Bishop frame in space from the root frame `u^0`, and the binormals' Bishop components.
/// Computed once per force evaluation and shared by the energy, forces and twist.
#[derive(Clone, Debug)]
pub struct RodFrames<P: Precision, const N: usize> {
    /// Nodes in use.
    pub nodes: usize,
    /// `e^j = x_{j+1} − x_j`.
    pub edge: [P::V; N],
    /// `|e^j|`.
    pub length: [P::R; N],
    /// `1 / |e^j|`.
    pub inverse_length: [P::R; N],
    /// `t^j = e^j / |e^j|`.
    pub tangent: [P::V; N],
    /// `(κb)_i`, `i = 1 … n`.
    pub curvature_binormal: [P::V; N],
    /// `d_i = |ê^{i−1}||ê^i| + e^{i−1}·e^i`, the binormal's denominator.
    pub denominator: [P::R; N],
    /// Bishop `u^j`.
    pub bishop_u: [P::V; N],
    /// Bishop `v^j = t^j × u^j`.
    pub bishop_v: [P::V; N],
    /// `[p^{i−1}_i, p^i_i]` with `p^j_i = ((κb)_i·v^j, −(κb)_i·u^j)`: the material curvature at
    /// `θ^j = 0`.
    pub bishop_curvature: [[[P::R; 2]; 2]; N],
}

impl<P: Precision, const N: usize> RodFrames<P, N> {
    /// The frames of the polyline `positions` (≤ `N` nodes) with root Bishop vector
    /// `root_frame` and rest segment lengths `rest_length`.
    #[must_use]
    pub fn compute(positions: &[P::V], root_frame: P::V, rest_length: &[P::R]) -> Self {
        let mut f = Self::empty();
        f.recompute(positions, root_frame, rest_length);
        f
    }

    /// Frames of no polyline: every entry at the value [`Self::compute`] leaves where it
    /// writes nothing (no binormal at the root or the tip, denominator 1).
    #[must_use]
    pub fn empty() -> Self {
        let zero = <P::V as Vector<P::R>>::ZERO;
        RodFrames {
            nodes: 0,
            edge: [zero; N],
            length: [P::R::ZERO; N],
            inverse_length: [P::R::ZERO; N],
            tangent: [zero; N],
            curvature_binormal: [zero; N],
            denominator: [P::R::ONE; N],
            bishop_u: [zero; N],
            bishop_v: [zero; N],
            bishop_curvature: [[[P::R::ZERO; 2]; 2]; N],
        }
    }

    /// [`Self::compute`] in place, for a buffer that is [`Self::empty`] or last held a
    /// polyline of as many nodes: it writes every entry `compute` writes, so the result is
    /// the same, bit for bit, without building (zeroing, then moving) a new one. The rod step
    /// recomputes its frames five times a step (four substeps and the twist): on the
    /// Cortex-M4F the zeroing and moving cost 6 % of the step.
    pub fn recompute(&mut self, positions: &[P::V], root_frame: P::V, rest_length: &[P::R]) {
        let f = self;
        f.nodes = positions.len().min(N);
        let segments = f.nodes.saturating_sub(1).min(rest_length.len());
        // One pass root → tip: segment, tangent, Bishop frame by parallel transport (Kmoch
        // Sec. 5), then the binormal at the node behind it and its Bishop components.
        for j in 0..segments {
            let e = positions[j + 1] - positions[j];
            let length = P::sqrt(e.dot(e));
            let inverse_length = P::R::ONE / length;
            let t = e * inverse_length;
            let u = if j == 0 {
                root_frame
            } else {
                parallel_transport::<P>(f.tangent[j - 1], t, f.bishop_u[j - 1])
            };
            f.edge[j] = e;
            f.length[j] = length;
            f.inverse_length[j] = inverse_length;
            f.tangent[j] = t;
            f.bishop_u[j] = u;
            f.bishop_v[j] = t.cross(u);
            if j > 0 {
                let i = j;
                let (kb, d) =
                    curvature_binormal::<P>(f.edge[i - 1], e, rest_length[i - 1], rest_length[i]);
                f.curvature_binormal[i] = kb;
                f.denominator[i] = d;
                f.bishop_curvature[i] = [
                    [kb.dot(f.bishop_v[i - 1]), -kb.dot(f.bishop_u[i - 1])],
                    [kb.dot(f.bishop_v[i]), -kb.dot(f.bishop_u[i])],
                ];
            }
        }
    }

    /// Number of interior nodes `n` (nodes with a curvature binormal).
    #[must_use]
    pub fn interior(&self) -> usize {
        self.nodes.saturating_sub(2)
    }
}

/// `(cos θ^j, sin θ^j)` per segment: the only trigonometry of a force evaluation, one call per
/// segment (never per holonomy term or per Newton row).
#[must_use]
pub fn material_angles<P: Precision, const N: usize>(theta: &[P::R]) -> [[P::R; 2]; N] {
    let mut cos_sin = [[P::R::ONE, P::R::ZERO]; N];
    for (slot, t) in cos_sin.iter_mut().zip(theta) {
        let (s, c) = P::sin_cos(*t);
        *slot = [c, s];
    }
    cos_sin
}

/// `ω = R(−θ) p`: the Bishop components `p` of a curvature binormal seen in the material frame
/// rotated by `θ` (given as `(cos θ, sin θ)`). `∂ω/∂θ = (ω₂, −ω₁) = −Jω`.
#[inline(always)]
#[must_use]
pub fn material_curvature<R: Scalar>(p: [R; 2], cos_sin: [R; 2]) -> [R; 2] {
    let [c, s] = cos_sin;
    [c * p[0] + s * p[1], c * p[1] - s * p[0]]
}

/// `B^j = diag(µα^j, α^j)`, or zero when bending is off.
#[inline(always)]
#[must_use]
pub fn bending_matrix<const N: usize, R: Scalar>(
    rest: &RodRest<N, R>,
    terms: ElasticTerms,
    j: usize,
) -> [R; 2] {
    match rest.bending_stiffness.get(j) {
        Some(&alpha) if terms.bending => [rest.minor_axis_penalty * alpha, alpha],
        _ => [R::ZERO; 2],
    }
}

/// `β`, or zero when twist is off.
#[inline(always)]
#[must_use]
pub fn twist_stiffness<const N: usize, R: Scalar>(rest: &RodRest<N, R>, terms: ElasticTerms) -> R {
    if terms.twist {
        rest.twist_stiffness
    } else {
        R::ZERO
    }
}

/// Bending energy at node `i` in frame `j = i − 1 + k` given `(cos θ^j, sin θ^j)`:
/// `1/(2 l̂_i) (ω − ω̂)ᵀ B^j (ω − ω̂)`.
#[inline(always)]
#[must_use]
pub fn node_bending_energy<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    terms: ElasticTerms,
    i: usize,
    k: usize,
    cos_sin: [P::R; 2],
) -> P::R {
    let omega = material_curvature(frames.bishop_curvature[i][k], cos_sin);
    let rest_omega = rest.rest_curvature[i][k];
    let b = bending_matrix(rest, terms, i - 1 + k);
    let d0 = omega[0] - rest_omega[0];
    let d1 = omega[1] - rest_omega[1];
    (b[0] * d0 * d0 + b[1] * d1 * d1) * (P::R::of(0.5) * rest.inverse_voronoi_length[i])
}

/// Twist energy at node `i`: `β (θ^i − θ^{i−1} − m̂_i)² / l̂_i`.
#[inline(always)]
#[must_use]
pub fn node_twist_energy<const N: usize, R: Scalar>(
    rest: &RodRest<N, R>,
    terms: ElasticTerms,
    i: usize,
    theta_prev: R,
    theta: R,
) -> R {
    let m = theta - theta_prev - rest.rest_twist[i];
    twist_stiffness(rest, terms) * m * m * rest.inverse_voronoi_length[i]
}

/// The total elastic energy `E_bend + E_twist`, J.
#[must_use]
pub fn elastic_energy<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    theta: &[P::R],
    rest: &RodRest<N, P::R>,
    terms: ElasticTerms,
) -> P::R {
    let cos_sin = material_angles::<P, N>(theta);
    let mut energy = P::R::ZERO;
    // A shorter `theta` truncates the strand rather than reading past it.
    let n = frames.interior().min(theta.len().saturating_sub(1));
    for i in 1..=n {
        for k in 0..2 {
            energy += node_bending_energy(frames, rest, terms, i, k, cos_sin[i - 1 + k]);
        }
        energy += node_twist_energy(rest, terms, i, theta[i - 1], theta[i]);
    }
    energy
}

/// `∂E_bend/∂θ^j` from node `i` (frame `j = i − 1 + k`): `(1/l̂_i)(ω₂ (Bδ)₁ − ω₁ (Bδ)₂)`, and
/// the vector `(1/l̂_i)(m2^j (Bδ)₁ − m1^j (Bδ)₂) = ∂E/∂(κb)_i` from the same term.
#[inline(always)]
fn bending_terms<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    terms: ElasticTerms,
    i: usize,
    k: usize,
    cos_sin: [P::R; 2],
) -> (P::R, P::V) {
    let j = i - 1 + k;
    let omega = material_curvature(frames.bishop_curvature[i][k], cos_sin);
    let rest_omega = rest.rest_curvature[i][k];
    let b = bending_matrix(rest, terms, j);
    let inv_l = rest.inverse_voronoi_length[i];
    let b_delta = [
        b[0] * (omega[0] - rest_omega[0]) * inv_l,
        b[1] * (omega[1] - rest_omega[1]) * inv_l,
    ];
    // m2 (Bδ)₁ − m1 (Bδ)₂ in the Bishop frame (m1 = c u + s v, m2 = −s u + c v), without
    // forming the material frame.
    let [c, s] = cos_sin;
    let along_u = -(s * b_delta[0] + c * b_delta[1]);
    let along_v = c * b_delta[0] - s * b_delta[1];
    (
        omega[1] * b_delta[0] - omega[0] * b_delta[1],
        frames.bishop_u[j] * along_u + frames.bishop_v[j] * along_v,
    )
}

/// `∂E_bend/∂θ^j`: the bending part of the twist derivative (nodes `j` and `j + 1`).
#[must_use]
pub fn bending_twist_derivative<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    terms: ElasticTerms,
    j: usize,
    cos_sin: [P::R; 2],
) -> P::R {
    let n = frames.interior();
    let mut g = P::R::ZERO;
    if j >= 1 && j <= n {
        g += bending_terms(frames, rest, terms, j, 1, cos_sin).0;
    }
    if j < n {
        g += bending_terms(frames, rest, terms, j + 1, 0, cos_sin).0;
    }
    g
}

/// `∂E_twist/∂θ^j = 2β[(m_j − m̂_j)/l̂_j − (m_{j+1} − m̂_{j+1})/l̂_{j+1}]` (terms at nodes 0 and
/// `n + 1` dropped).
#[must_use]
pub fn twist_twist_derivative<const N: usize, R: Scalar>(
    rest: &RodRest<N, R>,
    terms: ElasticTerms,
    theta: &[R],
    j: usize,
    n: usize,
) -> R {
    let two_beta = R::of(2.0) * twist_stiffness(rest, terms);
    let mut g = R::ZERO;
    if j >= 1 && j <= n {
        g += two_beta
            * (theta[j] - theta[j - 1] - rest.rest_twist[j])
            * rest.inverse_voronoi_length[j];
    }
    if j < n {
        g -= two_beta
            * (theta[j + 1] - theta[j] - rest.rest_twist[j + 1])
            * rest.inverse_voronoi_length[j + 1];
    }
    g
}

/// The twist derivative `∂E/∂θ^j` (Kmoch Sec. 7.2 with the rest twist `m̂` that the paper
/// leaves out; DESIGN.md): bending at nodes `j`, `j + 1` in frame `j` plus twist.
#[must_use]
pub fn twist_derivative<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    theta: &[P::R],
    rest: &RodRest<N, P::R>,
    terms: ElasticTerms,
    j: usize,
) -> P::R {
    let Some(&angle) = theta.get(j) else {
        return P::R::ZERO;
    };
    let (s, c) = P::sin_cos(angle);
    let n = frames.interior().min(theta.len().saturating_sub(1));
    bending_twist_derivative(frames, rest, terms, j, [c, s])
        + twist_twist_derivative(rest, terms, theta, j, n)
}

/// The elastic forces (Kmoch Sec. 7.2, BWR08 Sec. 7):
/// `F_i = −∂E/∂x_i + Σ_{c∈C} (∂E/∂θ^c) ∇_iΨ^c` at the current `θ`, written into
/// `forces[..nodes]` (nodes 0 and 1 get theirs too; the head holds them).
///
/// With `∂E/∂x_i = Σ_k (∇_i(κb)_k)ᵀ ∂E/∂(κb)_k + Σ_j (∂E_bend/∂θ^j) ∇_iΨ^j` and
/// `Ψ^j = Σ_{k≤j} ψ_k`, the holonomy part is `Σ_k W_k ∇_iψ_k` with the suffix sums
/// `W_k = Σ_{j≥k} w_j`, `w_j = −∂E_bend/∂θ^j + [j ∈ C] ∂E/∂θ^j`: one sweep tip → root, O(n).
/// The holonomy gradient is the exact form `∇_{k∓1}ψ_k = ±κ̃b_k / (2|e^{k∓1 or k}|)` with
/// `κ̃b_k = 2 t^{k−1}×t^k / (1 + t^{k−1}·t^k)`, exact also for stretched segments.
pub fn elastic_forces<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    theta: &[P::R],
    rest: &RodRest<N, P::R>,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    forces: &mut [P::V],
) {
    let cos_sin =
        material_angles::<P, N>(&theta[..frames.nodes.saturating_sub(1).min(theta.len())]);
    elastic_forces_with_angles(frames, theta, &cos_sin, rest, clamped, terms, forces);
}

/// [`elastic_forces`] with `(cos θ^j, sin θ^j)` already computed (substeps at fixed `θ` share
/// them).
pub fn elastic_forces_with_angles<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    theta: &[P::R],
    cos_sin: &[[P::R; 2]; N],
    rest: &RodRest<N, P::R>,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    forces: &mut [P::V],
) {
    let zero = <P::V as Vector<P::R>>::ZERO;
    let nodes = frames.nodes.min(forces.len()).min(theta.len() + 1);
    let n = nodes.saturating_sub(2);
    for f in forces.iter_mut().take(nodes) {
        *f = zero;
    }
    let two = P::R::of(2.0);
    let half = P::R::of(0.5);
    // Holonomy weight suffix sum W_k = Σ_{j ≥ k} w_j, built from the tip.
    let mut suffix = P::R::ZERO;
    // ∂E_bend/∂θ^j from node j + 1 (frame j), carried down from the previous (k + 1) node.
    let mut carried = P::R::ZERO;
    for k in (1..=n).rev() {
        // Node k's bending terms in frames k − 1 and k.
        let (g_prev, kb_gradient_prev) = bending_terms(frames, rest, terms, k, 0, cos_sin[k - 1]);
        let (g_here, kb_gradient_here) = bending_terms(frames, rest, terms, k, 1, cos_sin[k]);
        let kb_gradient = kb_gradient_prev + kb_gradient_here;
        // Segment k is now complete: ∂E_bend/∂θ^k = (node k, frame k) + (node k + 1, frame k).
        let bend_k = g_here + carried;
        carried = g_prev;
        let mut w = -bend_k;
        if clamped.contains(k) {
            w += bend_k + twist_twist_derivative(rest, terms, theta, k, n);
        }
        suffix += w;
        // Curvature binormal gradient: ∂E/∂x from (κb)_k.
        let kb = frames.curvature_binormal[k];
        let inv_d = P::R::ONE / frames.denominator[k];
        let e_prev = frames.edge[k - 1];
        let e_next = frames.edge[k];
        let kb_dot = kb.dot(kb_gradient);
        let a = (kb_gradient.cross(e_next) * two + e_next * kb_dot) * inv_d;
        let c = (kb_gradient.cross(e_prev) * two - e_prev * kb_dot) * inv_d;
        // Holonomy gradient of ψ_k, exact form.
        let t_prev = frames.tangent[k - 1];
        let t_next = frames.tangent[k];
        let kb_unit = t_prev.cross(t_next) * (two / (P::R::ONE + t_prev.dot(t_next)));
        let psi_prev = kb_unit * (half * frames.inverse_length[k - 1]);
        let psi_next = -(kb_unit * (half * frames.inverse_length[k]));
        forces[k - 1] += psi_prev * suffix - a;
        forces[k + 1] += psi_next * suffix - c;
        forces[k] += a + c - (psi_prev + psi_next) * suffix;
    }
}

#[cfg(test)]
pub(crate) mod tests;
