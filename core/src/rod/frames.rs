//! The frames of a rod strand's current configuration (Kmoch 2009 Sec. 5, BWR08 Sec. 4): its
//! segments, tangents and curvature binormals, the Bishop frame in space carried from the root
//! frame `u^0`, the binormals' components in it, the material angles' cosines and sines, and
//! the binormal directions the hair-optimised twist follows (Kmoch Sec. 6.2). Computed once per
//! force evaluation and shared by the energies, the forces, the twist and the rest data.
//!
//! Generic over a [`Precision`] so that the finite-difference tests run in `f64`.

use crate::frames::{curvature_binormal_over, transport_perpendicular};
use crate::math::Math;
use crate::precision::{Arithmetic, Kernel, Precision, Trigonometry, Vector};
use crate::strand::Strand;

/// The representative of the direction `(cos φ, sin φ)` (an unoriented line, defined mod π)
/// closest to `reference`: `θ = φ + kπ`, with `φ = atan2(sin φ, cos φ)` given. Returns `θ`,
/// `(cos θ, sin θ)`, and whether `k` is odd (the direction flipped).
#[inline(always)]
#[must_use]
pub fn representative_near<P: Trigonometry>(
    phi: P::R,
    direction: [P::R; 2],
    reference: P::R,
) -> (P::R, [P::R; 2], <P::R as Arithmetic>::Mask) {
    let [c, s] = direction;
    // On the twist sweep's sequential chain (`reference` is the neighbour's new angle): a
    // multiplication by 1/π rather than a division, and the parity from the integer.
    let (k, odd) = P::floor_and_parity((reference - phi) * P::FRAC_1_PI + P::R::of(0.5));
    let cos_sin = [P::R::select(odd, -c, c), P::R::select(odd, -s, s)];
    (phi + k * P::PI, cos_sin, odd)
}

/// The frames of a strand's current configuration: segments, tangents, curvature binormals,
/// the Bishop frame in space from the root frame `u^0`, and the binormals' Bishop components.
/// Computed once per force evaluation and shared by the energy, forces and twist.
#[derive(Clone, Debug)]
pub struct RodFrames<P: Kernel, const N: usize> {
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
    /// `1 / d_i`: the gradients multiply by it.
    pub inverse_denominator: [P::R; N],
    /// `½ κ̃b_i = ½ · 2 t^{i−1}×t^i / (1 + t^{i−1}·t^i)`, the holonomy's binormal (the
    /// curvature binormal with the current lengths), as the factor `κ̃b_i / (2 (κb)_i) =
    /// d_i / (|e^{i−1}||e^i| (1 + t^{i−1}·t^i))` on `(κb)_i`: the frame pass has every part of
    /// it, where the force pass would rebuild the cross product and divide again.
    pub holonomy_scale: [P::R; N],
    /// Bishop `u^j`.
    pub bishop_u: [P::V; N],
    /// Bishop `v^j = t^j × u^j`.
    pub bishop_v: [P::V; N],
    /// `[p^{i−1}_i, p^i_i]` with `p^j_i = ((κb)_i·v^j, −(κb)_i·u^j)`: the material curvature at
    /// `θ^j = 0`.
    pub bishop_curvature: [[[P::R; 2]; 2]; N],
}

impl<P: Kernel, const N: usize> RodFrames<P, N> {
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
    pub const fn empty() -> Self {
        let zero = <P::V as Vector<P::R>>::ZERO;
        RodFrames {
            nodes: 0,
            edge: [zero; N],
            length: [P::R::ZERO; N],
            inverse_length: [P::R::ZERO; N],
            tangent: [zero; N],
            curvature_binormal: [zero; N],
            denominator: [P::R::ONE; N],
            inverse_denominator: [P::R::ONE; N],
            holonomy_scale: [P::R::ZERO; N],
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
            f.edge[j] = e;
            f.length[j] = length;
            f.inverse_length[j] = inverse_length;
            f.tangent[j] = t;
            if j == 0 {
                f.bishop_u[0] = root_frame;
                f.bishop_v[0] = t.cross(root_frame);
                continue;
            }
            let i = j;
            let (e_prev, t_prev) = (f.edge[i - 1], f.tangent[i - 1]);
            let lengths = f.length[i - 1] * length;
            let dot = e_prev.dot(e);
            let d = rest_length[i - 1] * rest_length[i] + dot;
            let (inverse_bracket, inverse_d) = shared_reciprocals(lengths + dot, d);
            let inverse_one_plus_cos = lengths * inverse_bracket;
            let u =
                transport_perpendicular::<P>(t_prev, t, f.bishop_u[i - 1], inverse_one_plus_cos);
            let v = t.cross(u);
            f.bishop_u[i] = u;
            f.bishop_v[i] = v;
            let kb = curvature_binormal_over::<P>(e_prev, e, inverse_d);
            f.curvature_binormal[i] = kb;
            f.denominator[i] = d;
            f.inverse_denominator[i] = inverse_d;
            // `½ d / (|e^{i−1}||e^i| (1 + t^{i−1}·t^i))`, the reciprocal of the bracket.
            f.holonomy_scale[i] = P::R::of(0.5) * d * inverse_bracket;
            // The transport turns about (κb)_i, so the binormal has the same components in
            // the Bishop frames on both sides of node i: two dot products serve both.
            let p = [kb.dot(v), -kb.dot(u)];
            f.bishop_curvature[i] = [p, p];
        }
    }

    /// Number of interior nodes `n` (nodes with a curvature binormal).
    #[must_use]
    pub fn interior(&self) -> usize {
        self.nodes.saturating_sub(2)
    }
}

/// `(1/bracket, 1/d)` from one division, `1/a = b/(ab)`: the frame pass's reciprocals of the
/// cosine's bracket `|e^{i−1}||e^i| (1 + t^{i−1}·t^i) = |e^{i−1}||e^i| + e^{i−1}·e^i` (from the
/// edges, so nothing waits for the tangent) and of the curvature binormal's denominator `d_i`.
/// One `VDIV` (14 cycles on the Cortex-M4F) instead of two. `1/|e^i|` keeps its own: taking
/// all three from one division made the viewer's test of a dragged grab, `tests/viewer.rs`,
/// slip at its second drag.
#[inline(always)]
fn shared_reciprocals<R: Arithmetic>(bracket: R, d: R) -> (R, R) {
    let r = R::ONE / (bracket * d);
    (r * d, r * bracket)
}

impl<M: Math, const N: usize> RodFrames<M, N> {
    /// Kmoch Sec. 5, the Bishop frame in space: these frames recomputed in place for the
    /// strand's current centreline (from its root frame `u^0` and rest lengths).
    pub fn refresh(&mut self, strand: &Strand<N>) {
        let n = strand.rest.nodes.min(N);
        self.recompute(
            &strand.state.position[..n],
            strand.state.root_frame,
            &strand.rest.rod.rest_length,
        );
    }
}

/// `(cos θ^j, sin θ^j)` per segment: the only trigonometry of a force evaluation, one call per
/// segment (never per holonomy term or per Newton row).
#[must_use]
pub fn material_angles<P: Trigonometry, const N: usize>(theta: &[P::R]) -> [[P::R; 2]; N] {
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
pub fn material_curvature<R: Arithmetic>(p: [R; 2], cos_sin: [R; 2]) -> [R; 2] {
    let [c, s] = cos_sin;
    [c * p[0] + s * p[1], c * p[1] - s * p[0]]
}

/// `ε²` in the binormal weights `|κb|² / (|κb|² + ε²)`: binormals much shorter than
/// `ε = 1e-4` (a turning angle of 0.1 mrad) fade out of the average instead of dropping out at a
/// threshold, so `θ` does not jump when a node straightens.
pub const BINORMAL_FADE: f32 = 1.0e-8;
/// Below this weight neither binormal says anything: the segment continues its neighbour.
pub const BINORMAL_MIN_WEIGHT: f32 = 1.0e-2;

/// The direction `(cos φ, sin φ)`, defined mod π, that segment `j`'s material vector `m1`
/// takes in the hair-optimised twist: the mean of the directions of the binormals at nodes `j`
/// and `j + 1` in the Bishop frame of segment `j` (Kmoch Sec. 6.2), averaged as lines:
/// `φ = ½ arg Σ w e^{2iη}`; with the angle `φ`. `None` when both binormals (nearly) vanish.
/// The doubled angle is a complex square, the half angle's direction a square root.
///
/// One division: the weights `1/r_k` are kept as a fraction `Σ z_k/r_k = sum / scale`, whose
/// direction is that of `sum`, and the half angle of `z = X + iY` is `(|z| + X, Y)` (or
/// `(Y, |z| − X)`, the same line, when `X < 0`), normalised once. The angle is the `atan2`
/// of the half angle before it is normalised: it does not wait for the normalisation's square
/// root and division, the longest chain of the twist's segment.
#[inline(always)]
#[must_use]
pub fn binormal_direction<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    j: usize,
) -> Option<([P::R; 2], P::R)> {
    let binormal = binormal_direction_in_lanes(frames, j);
    binormal
        .some
        .then_some((binormal.direction, binormal.angle))
}

/// [`binormal_direction`] per lane.
#[derive(Clone, Copy, Debug)]
pub struct BinormalDirection<R: Arithmetic> {
    /// `(cos φ, sin φ)`.
    pub direction: [R; 2],
    /// `φ`.
    pub angle: R,
    /// Where there is a direction (elsewhere `direction` and `angle` are not meaningful).
    pub some: R::Mask,
}

/// [`binormal_direction`] per lane.
#[inline(always)]
#[must_use]
pub fn binormal_direction_in_lanes<P: Trigonometry, const N: usize>(
    frames: &RodFrames<P, N>,
    j: usize,
) -> BinormalDirection<P::R> {
    let n = frames.interior();
    let fade = P::R::of(BINORMAL_FADE);
    // Σ_k z_k / r_k with z_k = (a² − b², 2ab) and r_k = a² + b² + ε², as `sum / scale`.
    let mut sum = [P::R::ZERO; 2];
    let mut scale = P::R::ONE;
    // (κb·u^j, κb·v^j) = (−p₁, p₀) for node j (frame j = its "next") and node j + 1 ("prev").
    let mut add = |p: [P::R; 2]| {
        let (a, b) = (-p[1], p[0]);
        let r = a * a + b * b + fade;
        sum[0] = sum[0] * r + (a * a - b * b) * scale;
        sum[1] = sum[1] * r + P::R::of(2.0) * a * b * scale;
        scale *= r;
    };
    if j >= 1 && j <= n {
        add(frames.bishop_curvature[j][1]);
    }
    if j < n {
        add(frames.bishop_curvature[j + 1][0]);
    }
    // The weights' fraction `sum / scale` has the direction of `sum` (`scale` > 0), so only
    // the test of its length needs `scale`: `|sum / scale| > min` as `|sum|² > (min scale)²`,
    // no division. `|sum|²` overflows only for curvatures past 1e4 (a fold within a few
    // thousandths of a degree of 180°), which then reads as no direction: the sweep continues
    // the neighbour, as for a non-finite frame.
    let [x, y] = sum;
    let weight2 = x * x + y * y;
    let bound = P::R::of(BINORMAL_MIN_WEIGHT) * scale;
    let some = !(weight2.le(bound * bound) | !weight2.finite());
    if !P::R::any(some) {
        return BinormalDirection {
            direction: [P::R::ONE, P::R::ZERO],
            angle: P::R::ZERO,
            some,
        };
    }
    let weight = P::sqrt(weight2);
    let right = P::R::ZERO.le(x);
    let half_angle = [
        P::R::select(right, weight + x, y),
        P::R::select(right, y, weight - x),
    ];
    // `atan2` is blind to the length: it takes the half angle as it is, beside the
    // normalisation rather than after it.
    let angle = P::atan2(half_angle[1], half_angle[0]);
    let inverse_length =
        P::R::ONE / P::sqrt(half_angle[0] * half_angle[0] + half_angle[1] * half_angle[1]);
    BinormalDirection {
        direction: [
            half_angle[0] * inverse_length,
            half_angle[1] * inverse_length,
        ],
        angle,
        some,
    }
}
