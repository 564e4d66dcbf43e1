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

pub use super::frames::{material_angles, material_curvature, representative_near, RodFrames};
use super::{ClampedLanes, ClampedSegments, ElasticTerms};
use crate::precision::{Arithmetic, Kernel, Precision, Trigonometry, Vector};
use crate::strand::RodRest;

/// `B^j = diag(µα^j, α^j)`, or zero when bending is off.
#[inline(always)]
#[must_use]
pub fn bending_matrix<const N: usize, R: Arithmetic>(
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
pub fn twist_stiffness<const N: usize, R: Arithmetic>(
    rest: &RodRest<N, R>,
    terms: ElasticTerms,
) -> R {
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
pub fn node_bending_energy<P: Kernel, const N: usize>(
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
pub fn node_twist_energy<const N: usize, R: Arithmetic>(
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
pub fn elastic_energy<P: Trigonometry, const N: usize>(
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

/// `∂E_bend/∂θ^j` from node `i` (frame `j = i − 1 + k`, `b` its [`bending_matrix`]):
/// `(1/l̂_i)(ω₂ (Bδ)₁ − ω₁ (Bδ)₂)`, and the vector `(1/l̂_i)(m2^j (Bδ)₁ − m1^j (Bδ)₂) =
/// ∂E/∂(κb)_i` from the same term.
#[inline(always)]
fn bending_terms<P: Kernel, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    (i, k): (usize, usize),
    b: [P::R; 2],
    cos_sin: [P::R; 2],
) -> (P::R, P::V) {
    let j = i - 1 + k;
    let omega = material_curvature(frames.bishop_curvature[i][k], cos_sin);
    let rest_omega = rest.rest_curvature[i][k];
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
pub fn bending_twist_derivative<P: Kernel, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    terms: ElasticTerms,
    j: usize,
    cos_sin: [P::R; 2],
) -> P::R {
    let n = frames.interior();
    let mut g = P::R::ZERO;
    // Segment j's matrix, at both of its nodes.
    let b = bending_matrix(rest, terms, j);
    if j >= 1 && j <= n {
        g += bending_terms(frames, rest, (j, 1), b, cos_sin).0;
    }
    if j < n {
        g += bending_terms(frames, rest, (j + 1, 0), b, cos_sin).0;
    }
    g
}

/// `∂E_twist/∂θ^j = 2β[(m_j − m̂_j)/l̂_j − (m_{j+1} − m̂_{j+1})/l̂_{j+1}]` (terms at nodes 0 and
/// `n + 1` dropped).
#[must_use]
pub fn twist_twist_derivative<const N: usize, R: Arithmetic>(
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
/// leaves out; `docs/design-departures.md`): bending at nodes `j`, `j + 1` in frame `j` plus twist.
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
/// them), on one strand or on `W` in lanes (`lane::Lanes`, `clamped` then one set per lane).
/// Out of line: inlined into a block's step or not as unrelated code moved, its lanes' code
/// came out 8 % dearer when it was.
#[inline(never)]
pub fn elastic_forces_with_angles<P: Kernel, C: ClampedLanes<P::R>, const N: usize>(
    frames: &RodFrames<P, N>,
    theta: &[P::R],
    cos_sin: &[[P::R; 2]; N],
    rest: &RodRest<N, P::R>,
    clamped: &C,
    terms: ElasticTerms,
    forces: &mut [P::V],
) {
    let zero = <P::V as Vector<P::R>>::ZERO;
    let nodes = frames.nodes.min(forces.len()).min(theta.len() + 1);
    let n = nodes.saturating_sub(2);
    if n == 0 {
        for f in forces.iter_mut().take(nodes) {
            *f = zero;
        }
        return;
    }
    let two = P::R::of(2.0);
    // Holonomy weight suffix sum W_k = Σ_{j ≥ k} w_j, built from the tip.
    let mut suffix = P::R::ZERO;
    // ∂E_bend/∂θ^j from node j + 1 (frame j), carried down from the previous (k + 1) node.
    let mut carried = P::R::ZERO;
    // The forces on nodes k + 1 and k, summed in registers and stored once each: the same
    // additions in the same order as `+=` on the slice (node k + 1 takes node k + 2's share,
    // its own, then node k's), without loading and storing three nodes per interior node.
    let (mut ahead, mut here) = (zero, zero);
    // Segment k's bending matrix, taken at node k + 1 and handed down to node k.
    let mut b_segment = bending_matrix(rest, terms, n);
    for k in (1..=n).rev() {
        // Node k's bending terms in frames k − 1 and k.
        let (b_here, b_prev) = (b_segment, bending_matrix(rest, terms, k - 1));
        b_segment = b_prev;
        let (g_prev, kb_gradient_prev) =
            bending_terms(frames, rest, (k, 0), b_prev, cos_sin[k - 1]);
        let (g_here, kb_gradient_here) = bending_terms(frames, rest, (k, 1), b_here, cos_sin[k]);
        let kb_gradient = kb_gradient_prev + kb_gradient_here;
        // Segment k is now complete: ∂E_bend/∂θ^k = (node k, frame k) + (node k + 1, frame k).
        let bend_k = g_here + carried;
        carried = g_prev;
        let mut w = -bend_k;
        let held = clamped.clamped(k);
        if P::R::any(held) {
            let with_twist = w + (bend_k + twist_twist_derivative(rest, terms, theta, k, n));
            w = P::R::select(held, with_twist, w);
        }
        suffix += w;
        // Curvature binormal gradient: ∂E/∂x from (κb)_k.
        let kb = frames.curvature_binormal[k];
        let inv_d = frames.inverse_denominator[k];
        let e_prev = frames.edge[k - 1];
        let e_next = frames.edge[k];
        let kb_dot = kb.dot(kb_gradient);
        let a = (kb_gradient.cross(e_next) * two + e_next * kb_dot) * inv_d;
        let c = (kb_gradient.cross(e_prev) * two - e_prev * kb_dot) * inv_d;
        // Holonomy gradient of ψ_k, exact form: ±κ̃b_k / (2|e|), κ̃b_k from the frame pass.
        let half_holonomy = kb * frames.holonomy_scale[k];
        let psi_prev = half_holonomy * frames.inverse_length[k - 1];
        let psi_next = -(half_holonomy * frames.inverse_length[k]);
        forces[k + 1] = ahead + (psi_next * suffix - c);
        ahead = here + (a + c - (psi_prev + psi_next) * suffix);
        here = zero + (psi_prev * suffix - a);
    }
    forces[1] = ahead;
    forces[0] = here;
}

#[cfg(test)]
pub(crate) mod tests;
