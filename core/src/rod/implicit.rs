//! Linearly implicit bending: one elastic step per time step at any bending stiffness the
//! validator accepts, with a banded solve per strand in fixed storage. A strand takes it when
//! it would need [`IMPLICIT_FROM`](super::substeps::IMPLICIT_FROM) or more explicit substeps
//! (stiffer than human hair, tight curls; `rod::substeps` says why not below).
//!
//! Symplectic Euler on the bending forces is only stable for `dt ≤ dt_max`
//! ([`RodRest::stable_time_step`](crate::strand::RodRest)); human hair at 1 cm and 1 ms sits
//! near that limit and ×1000 stiffer hair 20× past it. Linearised backward Euler on the
//! velocities (Baraff & Witkin 1998, eq. 6, written for the new velocity):
//!
//! `(M + h² H̃) v⁺ = M v + h (F(x) + F_ext)`, then `x⁺ = x + h v⁺`,
//!
//! with `F` the exact elastic forces of Kmoch Sec. 7.2 (the same ones the finite-difference
//! tests check) and `H̃` a positive semi-definite approximation of the bending Hessian: the
//! Gauss–Newton matrix of `E_bend` with the material frames held and `B^j` bounded by its
//! largest entry,
//!
//! `H̃ = Σ_i (2 b_i / l̂_i) J_iᵀ J_i + Σ_i D_i ∇ψ_i∇ψ_iᵀ + Σ_j k (t^j t^jᵀ on e^j)`,
//! `J_i = ∂(κb)_i / ∂(x_{i−1}, x_i, x_{i+1})`, `b_i = max(1, µ) max(α^{i−1}, α^i)`:
//! bending, a bound on the holonomy part ([`HOLONOMY_SHARE`], `holonomy_weights`) and an
//! axial term that stands for inextensibility in the solve ([`AXIAL_PENALTY`]).
//!
//! For a straight strand at rest with `µ = 1` it is the exact Hessian (the test below checks
//! it against finite differences of the forces); elsewhere it leaves out the terms weighted
//! by `ω − ω̂` and the holonomy. Why it is stable: for a mode of true stiffness `λ` and
//! approximate stiffness `λ̃` the scheme's amplification matrix has determinant
//! `1/(1 + h²λ̃) < 1` and stays stable while `h²λ ≤ 4 + 2h²λ̃`, so `H̃` may miss up to half of a
//! stiff mode's true stiffness; `(κb)_i ∝ 1/d_i` puts the stiffening of a sharp bend into
//! `J_i`, so no fold allowance is needed. What it costs: the modes with `h²λ̃ ≫ 1` (only the
//! stiffest bending modes of the discrete strand, the ones a saw-tooth would live in) lose
//! energy each step; slow motion (a swing, a sag) is untouched (`h²λ̃ ≈ 1e-5` there) and a
//! static equilibrium (`F = 0`) is exactly that of the explicit forces.
//!
//! Structure: `J_i` couples three consecutive nodes, so `H̃` is block-pentadiagonal in the
//! nodes, a band of half-width [`BAND`] = 8 in the `3n` scalar unknowns. Nodes 0 and 1 belong
//! to the head and stay put during this stage (as in the explicit step); they are left out of
//! the system. The band is factored as `L D Lᵀ` (no square roots; one division per row) and
//! solved in O(n), in storage sized by `N`.

use super::frames::RodFrames;
use super::integrate::Nodes;
use crate::context::StepContext;
use crate::forces::External;
use crate::math::{Math, Real, Vec3};
use crate::precision::{Arithmetic, Kernel, Vector};
use crate::strand::{RodRest, Strand};

/// Half-bandwidth of `M + h² H̃` in scalar unknowns: node `i`'s row reaches node `i − 2`'s
/// last axis, `3·2 + 2`.
pub const BAND: usize = 8;

/// One scalar row of the band: `[A(r, r), A(r, r − 1), …, A(r, r − BAND)]`.
type BandRow<R> = [R; BAND + 1];

/// `M + h² H̃` for one strand, or for `W` strands in lanes (lower band, rows node-major then
/// axis), factored in place. Written over a [`Kernel`], as the explicit substeps are, so a
/// strand in a block's lane gets the bits it gets alone.
#[derive(Clone, Debug)]
pub struct BendingSystem<P: Kernel, const N: usize> {
    band: [[BandRow<P::R>; 3]; N],
    inverse_pivot: [[P::R; 3]; N],
    nodes: usize,
    /// Smallest pivot [`Self::factor`] accepts: half the lightest unknown node's mass.
    pivot_floor: P::R,
}

impl<P: Kernel, const N: usize> Default for BendingSystem<P, N> {
    fn default() -> Self {
        let zero = P::R::ZERO;
        BendingSystem {
            band: [[[zero; BAND + 1]; 3]; N],
            inverse_pivot: [[zero; 3]; N],
            nodes: 0,
            pivot_floor: zero,
        }
    }
}

impl<M: Math, const N: usize> BendingSystem<M, N> {
    /// One strand's, before its first use (`const`: a world's scratch space).
    pub const EMPTY: Self = BendingSystem {
        band: [[[0.0; BAND + 1]; 3]; N],
        inverse_pivot: [[0.0; 3]; N],
        nodes: 0,
        pivot_floor: 0.0,
    };
}

/// Smallest pivot the factorisation keeps, relative to its row's diagonal: 2⁻²⁰, eight units
/// in the last place of an f32 (a pivot smaller than that is what is left of the diagonal
/// after cancellation, rounding noise; see `factor_row`).
pub const PIVOT_RESOLUTION: Real = 1.0 / 1_048_576.0;

/// First unknown row: nodes 0 and 1 are held by the head.
const FIRST_ROW: usize = 6;

/// The larger of `a` and `b` (`b` where `a < b`): `f32::max` for the finite stiffnesses it
/// compares, as a select, so that it runs in lanes.
#[inline(always)]
fn larger<R: Arithmetic>(a: R, b: R) -> R {
    R::select(a.lt(b), b, a)
}

/// `e × x̂`, `e × ŷ`, `e × ẑ`: the columns of `v ↦ e × v`.
#[inline(always)]
fn cross_columns<P: Kernel>(e: P::V) -> [P::V; 3] {
    let [x, y, z] = e.components();
    let zero = P::R::ZERO;
    [
        P::V::from_components([zero, z, -y]),
        P::V::from_components([-z, zero, x]),
        P::V::from_components([y, -x, zero]),
    ]
}

/// The columns of `∂(κb)/∂e^{i−1}` and `∂(κb)/∂e^i` for `(κb) = 2 e^{i−1}×e^i / d`,
/// `d = |ê^{i−1}||ê^i| + e^{i−1}·e^i`: `A = (−2[e^i]× − κb e^{iᵀ}) / d`,
/// `C = (2[e^{i−1}]× − κb e^{i−1ᵀ}) / d` with `[e]× v = e × v`, column `b` of each, given `1/d`.
#[inline(always)]
fn binormal_jacobians<P: Kernel>(
    e_prev: P::V,
    e_next: P::V,
    kb: P::V,
    inv_d: P::R,
) -> ([P::V; 3], [P::V; 3]) {
    let two_inv_d = P::R::of(2.0) * inv_d;
    let kb_d = kb * inv_d;
    let n = cross_columns::<P>(e_next);
    let p = cross_columns::<P>(e_prev);
    let en = e_next.components();
    let ep = e_prev.components();
    let a = [
        -(n[0] * two_inv_d) - kb_d * en[0],
        -(n[1] * two_inv_d) - kb_d * en[1],
        -(n[2] * two_inv_d) - kb_d * en[2],
    ];
    let c = [
        p[0] * two_inv_d - kb_d * ep[0],
        p[1] * two_inv_d - kb_d * ep[1],
        p[2] * two_inv_d - kb_d * ep[2],
    ];
    (a, c)
}

/// `XᵀY` for matrices given by columns: `[p][q] = x_p · y_q`.
#[inline(always)]
fn gram<P: Kernel>(x: &[P::V; 3], y: &[P::V; 3]) -> [[P::R; 3]; 3] {
    let mut g = [[P::R::ZERO; 3]; 3];
    for (row, xp) in g.iter_mut().zip(x) {
        for (slot, yq) in row.iter_mut().zip(y) {
            *slot = xp.dot(*yq);
        }
    }
    g
}

/// `h² · 2 b_i / l̂_i`: the weight of node `i`'s term, both frames' bending terms bounded by
/// `b_i = max(1, µ) max(α^{i−1}, α^i)`.
#[inline(always)]
fn node_weight<R: Arithmetic, const N: usize>(rest: &RodRest<N, R>, i: usize, h: R) -> R {
    let penalty = larger(rest.minor_axis_penalty, R::ONE);
    let alpha = larger(rest.bending_stiffness[i - 1], rest.bending_stiffness[i]);
    h * h * R::of(2.0) * penalty * alpha * rest.inverse_voronoi_length[i]
}

/// `J_i = ∂(κb)_i/∂(x_{i−1}, x_i, x_{i+1}) = (−A, A − C, C)` from `frames`
/// ([`binormal_jacobians`]), by columns per node.
#[inline(always)]
fn node_jacobian<P: Kernel, const N: usize>(frames: &RodFrames<P, N>, i: usize) -> [[P::V; 3]; 3] {
    let (a, c) = binormal_jacobians::<P>(
        frames.edge[i - 1],
        frames.edge[i],
        frames.curvature_binormal[i],
        frames.inverse_denominator[i],
    );
    [
        [-a[0], -a[1], -a[2]],
        [a[0] - c[0], a[1] - c[1], a[2] - c[2]],
        c,
    ]
}

/// `h² k` of the axial term on each free segment, in units of the segment's mean node mass.
///
/// Why: the strand is inextensible, but only the projection after this stage says so. A
/// curved strand's bending forces have components along its segments; left free in the
/// velocity solve they stretch it within the step, the projection snaps it back with
/// `v += Δx/h`, and the pair pumps energy: a 2 mm curl (40 nodes, 2 mm segments) reached
/// 4–7 m/s within 20 steps on a still head and blew up. A stiff axial spring `k (t tᵀ)` on
/// each segment *in the matrix only* (no force goes with it) makes the solve keep segment
/// lengths to first order; it removes only the stretching part of the velocity, which the
/// projection removes anyway (`1/(1 + 1000)` of it is left), so it adds no damping on the
/// constraint manifold. (The explicit substeps did the same job with a projection between
/// substeps.)
pub const AXIAL_PENALTY: Real = 1.0e3;

/// The share of the Gershgorin bound of the holonomy part taken into `H̃`
/// (`holonomy_weights`).
///
/// Why not all of it: with 1 (a bound on the whole part, and in the linear analysis of the
/// elastic step alone stable on a 2 mm curl) a 40-node 2 mm curl on a shaking head grew a slow
/// mode by 3 % per step from step ~250 and burst at step ~300 with the hair-optimised twist
/// (with Newton it stayed calm for 2000 steps; with 2 it burst at step ~170, with 0.5 it
/// stays calm): the hair-optimised twist is not an energy minimiser, so the elastic forces
/// are not conservative along its θ(x), and the extra damping of the implicit step drives a
/// slow mode of such a system (damping can destabilise a non-conservative system; Ziegler's
/// paradox). With 0.5 the elastic step's linear analysis needs `H̃` × 1.25 on that curl at
/// rest (the test states it) and the whole step — projection included — is stable in every
/// test. A measured compromise, not a bound.
pub const HOLONOMY_SHARE: Real = 0.5;

/// `∇ψ_i` on `(x_{i−1}, x_i, x_{i+1})`, the holonomy gradient of the force code:
/// `(κ̃b/(2|e^{i−1}|), −(first + last), −κ̃b/(2|e^i|))`, `κ̃b = 2 t^{i−1}×t^i/(1 + t^{i−1}·t^i)`.
#[inline(always)]
fn holonomy_gradient<P: Kernel, const N: usize>(frames: &RodFrames<P, N>, i: usize) -> [P::V; 3] {
    let (t_prev, t_next) = (frames.tangent[i - 1], frames.tangent[i]);
    let kb_unit = t_prev.cross(t_next) * (P::R::of(2.0) / (P::R::ONE + t_prev.dot(t_next)));
    let first = kb_unit * (P::R::of(0.5) * frames.inverse_length[i - 1]);
    let last = -(kb_unit * (P::R::of(0.5) * frames.inverse_length[i]));
    [first, -(first + last), last]
}

/// `h² D_i`: the weights of `∇ψ_i ∇ψ_iᵀ` that bound the stiffness the holonomy gives the
/// elastic forces at fixed `θ`.
///
/// Why: with `θ` held over the step, moving a node turns every material frame downstream by
/// `δΨ^j = Σ_{k≤j} δψ_k` about its tangent, and `ω^j_i` changes by `−(κ1, κ2) δΨ^j` (the
/// frames' turn with their tangents does not change `ω`: `κb ⊥ t`). The Gauss–Newton Hessian
/// of that part is `Σ_j c_j ∇Ψ^jᵀ∇Ψ^j`, `c_j = Σ_{i∈{j,j+1}} b_i |κb_i|² / l̂_i`: a dense
/// matrix `S_kl = C_{max(k,l)}` (suffix sums `C_k = Σ_{j≥k} c_j`) in the `ψ_k`. On a tight
/// curl it is what makes the step stable (2 mm helix: without it the rest state needs the
/// matrix ×4 to be stable, see the tests). `S` has positive entries, so its row sums bound it
/// (Gershgorin: `diag(Σ_l S_kl) − S` is diagonally dominant): `D_k = k C_k + Σ_{l>k} C_l`,
/// which keeps the band. The cross terms between `J` and this part are bounded by taking
/// both at full weight (`(a + b)² ≤ 2a² + 2b²`, and the stability bound allows a factor 2).
fn holonomy_weights<P: Kernel, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    h: P::R,
) -> [P::R; N] {
    let zero = P::R::ZERO;
    let n = frames.interior().min(N.saturating_sub(2));
    let mut q = [zero; N];
    for (i, (slot, kb)) in q
        .iter_mut()
        .zip(&frames.curvature_binormal)
        .enumerate()
        .take(n + 1)
        .skip(1)
    {
        *slot = node_weight(rest, i, P::R::ONE) * P::R::of(0.5) * kb.dot(*kb);
    }
    let mut weights = [zero; N];
    // Frames j = 1 … n; c_j = q_j + q_{j+1}; C_k and Σ_{l>k} C_l from the tip.
    let mut suffix = zero;
    let mut beyond = zero;
    let share = P::R::of(HOLONOMY_SHARE);
    for k in (1..=n).rev() {
        let next = if k < n { q[k + 1] } else { zero };
        suffix += q[k] + next;
        weights[k] = share * h * h * (P::R::of(k as Real) * suffix + beyond);
        beyond += suffix;
    }
    weights
}

/// The six blocks `(a, b)`, `b ≤ a`, of node `i`'s terms on its triple
/// `(x_{i−1}, x_i, x_{i+1})`, in the order `(0,0), (1,0), (1,1), (2,0), (2,1), (2,2)`: bending
/// `s J_aᵀJ_b`, holonomy `d ∇_aψ_i ∇_bψ_iᵀ`, and the axial term of segment `i` (nodes `i`,
/// `i + 1`). `block[p][q]` is row axis `p`, column axis `q`.
#[inline(always)]
fn node_blocks<P: Kernel, const N: usize>(
    frames: &RodFrames<P, N>,
    (mass, rest): (&[P::R; N], &RodRest<N, P::R>),
    i: usize,
    h: P::R,
    holonomy: P::R,
) -> [[[P::R; 3]; 3]; 6] {
    let s = node_weight(rest, i, h);
    let (a, c) = binormal_jacobians::<P>(
        frames.edge[i - 1],
        frames.edge[i],
        frames.curvature_binormal[i],
        frames.inverse_denominator[i],
    );
    let aa = gram::<P>(&a, &a);
    let cc = gram::<P>(&c, &c);
    let ac = gram::<P>(&a, &c);
    // ∇ψ_i = γ_k κ̃b on the triple (holonomy_gradient).
    let (t_prev, t_next) = (frames.tangent[i - 1], frames.tangent[i]);
    let kb_unit = t_prev.cross(t_next) * (P::R::of(2.0) / (P::R::ONE + t_prev.dot(t_next)));
    let first = P::R::of(0.5) * frames.inverse_length[i - 1];
    let last = P::R::of(-0.5) * frames.inverse_length[i];
    let middle = -(first + last);
    let kk = outer::<P>(kb_unit);
    // Axial term of segment i (nodes i, i + 1).
    let axial = P::R::of(AXIAL_PENALTY * 0.5) * (mass[i] + mass[i + 1]);
    let tt = outer::<P>(t_next);
    let hol = [
        holonomy * first * first,
        holonomy * middle * first,
        holonomy * middle * middle,
        holonomy * last * first,
        holonomy * last * middle,
        holonomy * last * last,
    ];
    let mut blocks = [[[P::R::ZERO; 3]; 3]; 6];
    for p in 0..3 {
        for q in 0..3 {
            // J = (−A, A − C, C): J_aᵀJ_b from AᵀA, CᵀC, AᵀC (ac[q][p] = c_p·a_q).
            let (aa, cc, ac, ca) = (aa[p][q], cc[p][q], ac[p][q], ac[q][p]);
            let (kk, tt) = (kk[p][q], tt[p][q]);
            blocks[0][p][q] = s * aa + hol[0] * kk;
            blocks[1][p][q] = s * (ca - aa) + hol[1] * kk;
            blocks[2][p][q] = s * (aa - ac - ca + cc) + hol[2] * kk + axial * tt;
            blocks[3][p][q] = -(s * ca) + hol[3] * kk;
            blocks[4][p][q] = s * (ca - cc) + hol[4] * kk - axial * tt;
            blocks[5][p][q] = s * cc + hol[5] * kk + axial * tt;
        }
    }
    blocks
}

/// `u uᵀ`.
#[inline(always)]
fn outer<P: Kernel>(u: P::V) -> [[P::R; 3]; 3] {
    let [x, y, z] = u.components();
    [
        [x * x, x * y, x * z],
        [y * x, y * y, y * z],
        [z * x, z * y, z * z],
    ]
}

/// Adds `block` to the rows `rows` of one node at column node `OFFSET` nodes back (lower
/// triangle only on the diagonal block). Constant offsets: no run-time index checks.
#[inline(always)]
fn add_block<R: Arithmetic, const OFFSET: usize>(rows: &mut [BandRow<R>; 3], block: &[[R; 3]; 3]) {
    for (p, row) in rows.iter_mut().enumerate() {
        for (q, value) in block[p].iter().enumerate() {
            if OFFSET == 0 && q > p {
                continue;
            }
            row[3 * OFFSET + p - q] += *value;
        }
    }
}

/// One row `r ≥ BAND` of the `L D Lᵀ` factorisation: `previous[k]` is the factored row
/// `r − BAND + k`, `inverse_pivot[k]` its `1/D`. Returns `1/D(r)`.
#[inline(always)]
fn factor_row<R: Arithmetic>(
    row: &mut BandRow<R>,
    previous: &[BandRow<R>; BAND],
    inverse_pivot: &[R; BAND],
    mass_floor: R,
) -> R {
    // ld[m] = L(r, r − m) D(r − m), filled from the farthest column in. (Exclusive ranges:
    // `a..=b` iterates with an extra check per step.)
    let mut ld = [R::ZERO; BAND + 1];
    for m in (1..BAND + 1).rev() {
        let column = &previous[BAND - m];
        let mut sum = row[m];
        for q in m + 1..BAND + 1 {
            sum -= ld[q] * column[q - m];
        }
        ld[m] = sum;
        row[m] = sum * inverse_pivot[BAND - m];
    }
    let diagonal = row[0];
    let mut pivot = diagonal;
    for m in 1..BAND + 1 {
        pivot -= row[m] * ld[m];
    }
    // Each pivot of `M + h² H̃` (H̃ positive semi-definite) is a Schur complement, so at least
    // the smallest eigenvalue and at least the lightest node's mass. Where `h² H̃` dwarfs `M`
    // by more than f32 resolves (a hairpin fold: `|κb| ≈ 400`, diagonal entries 1e13 times
    // the mass), the subtraction above cancels to rounding noise, and a pivot near zero or
    // below turned the step into NaN. A pivot under [`PIVOT_RESOLUTION`] of its diagonal is
    // that noise: it is floored there (and never below half the lightest mass), as in a
    // modified Cholesky factorisation. The factor stays positive definite and the solve
    // finite; in that direction the step is stiffer than the model. A system f32 resolves
    // never reaches the floor, so its bits are unchanged (every recorded hash holds).
    // Selects, not branches (and not `f32::max`, a library call on the Cortex-M4F): a NaN
    // pivot fails `floor ≤ pivot` and takes the floor.
    let relative = R::of(PIVOT_RESOLUTION) * diagonal;
    let floor = larger(mass_floor, relative);
    pivot = R::select(floor.le(pivot), pivot, floor);
    row[0] = pivot;
    R::ONE / pivot
}

/// The smallest of `mass` beyond the held nodes 0 and 1 (∞ when there is none).
fn lightest<R: Arithmetic>(mass: &[R]) -> R {
    let infinity = R::of(Real::INFINITY);
    mass.iter()
        .skip(2)
        .fold(infinity, |m, x| R::select(x.lt(m), *x, m))
}

impl<P: Kernel, const N: usize> BendingSystem<P, N> {
    /// Assembles `M + h² H̃` for the strand of `frames` (see the module documentation) with
    /// node masses `mass`, the stiffnesses of `rest` and the step `h`.
    pub fn assemble(
        &mut self,
        frames: &RodFrames<P, N>,
        mass: &[P::R; N],
        rest: &RodRest<N, P::R>,
        h: P::R,
    ) {
        let nodes = frames.nodes.min(N);
        self.nodes = nodes;
        self.pivot_floor = P::R::of(0.5) * lightest(&mass[..nodes]);
        for (i, rows) in self.band.iter_mut().enumerate().take(nodes) {
            let diagonal = if i >= 2 { mass[i] } else { P::R::ONE };
            let mut row = [P::R::ZERO; BAND + 1];
            row[0] = diagonal;
            *rows = [row; 3];
        }
        let holonomy = holonomy_weights(frames, rest, h);
        for (i, weight) in holonomy
            .iter()
            .enumerate()
            .take(nodes.saturating_sub(1))
            .skip(1)
        {
            let blocks = node_blocks(frames, (mass, rest), i, h, *weight);
            let [b00, b10, b11, b20, b21, b22] = &blocks;
            // Rows and columns of the held nodes 0 and 1 are not unknowns.
            if i >= 3 {
                if let Some(rows) = self.band.get_mut(i - 1) {
                    add_block::<_, 0>(rows, b00);
                }
            }
            if i >= 2 {
                if let Some(rows) = self.band.get_mut(i) {
                    if i >= 3 {
                        add_block::<_, 1>(rows, b10);
                    }
                    add_block::<_, 0>(rows, b11);
                }
            }
            if let Some(rows) = self.band.get_mut(i + 1) {
                if i >= 3 {
                    add_block::<_, 2>(rows, b20);
                }
                if i >= 2 {
                    add_block::<_, 1>(rows, b21);
                }
                add_block::<_, 0>(rows, b22);
            }
        }
    }

    /// Moves the held nodes' part of `h² H̃ v⁺` to the right-hand side: nodes 0 and 1 move
    /// with `held_velocity` (the head's motion over the step, which the root coupling gives
    /// them), so a stiff strand turns with the head within the step instead of lagging a step
    /// behind it. Subtracts `h² H̃_{free,held} v_held` from `rhs`.
    pub fn move_held_nodes(
        frames: &RodFrames<P, N>,
        rest: &RodRest<N, P::R>,
        h: P::R,
        held_velocity: [P::V; 2],
        rhs: &mut [[P::R; 3]; N],
    ) {
        let nodes = frames.nodes.min(N);
        let holonomy = holonomy_weights(frames, rest, h);
        // Interior nodes 1 and 2 are the only terms that reach a held node.
        let reach = nodes.saturating_sub(1).min(3);
        for (i, d) in holonomy.iter().copied().enumerate().take(reach).skip(1) {
            let s = node_weight(rest, i, h);
            let j = node_jacobian(frames, i);
            let g = holonomy_gradient(frames, i);
            let apply = |m: &[P::V; 3], v: P::V| {
                let [x, y, z] = v.components();
                m[0] * x + m[1] * y + m[2] * z
            };
            // s J' v_held over the held nodes of the triple (i − 1 + k < 2).
            let mut jv = P::V::ZERO;
            for (k, jk) in j.iter().enumerate() {
                if let Some(v) = held_velocity.get(i - 1 + k) {
                    jv += apply(jk, *v);
                }
            }
            let mut gv = P::R::ZERO;
            for (k, gk) in g.iter().enumerate() {
                if let Some(v) = held_velocity.get(i - 1 + k) {
                    gv += gk.dot(*v);
                }
            }
            let (jv, gv) = (jv * s, gv * d);
            for (k, (jk, gk)) in j.iter().zip(&g).enumerate() {
                let node = i - 1 + k;
                if node < 2 {
                    continue;
                }
                if let Some(row) = rhs.get_mut(node) {
                    let gk = gk.components();
                    for ((slot, column), gkp) in row.iter_mut().zip(jk).zip(gk) {
                        *slot -= column.dot(jv) + gkp * gv;
                    }
                }
            }
        }
    }

    /// Factors the band as `L D Lᵀ` in place (`L` strictly below the diagonal with unit
    /// diagonal, `D` on the diagonal) over the unknown rows. The held nodes' rows stay the
    /// identity, with nothing coupling to them, so that full windows of [`BAND`] rows can
    /// reach into them.
    pub fn factor(&mut self) {
        let band = self.band.as_flattened_mut();
        let inverse_pivot = self.inverse_pivot.as_flattened_mut();
        let rows = (3 * self.nodes).min(band.len()).min(inverse_pivot.len());
        let floor = self.pivot_floor;
        for slot in inverse_pivot.iter_mut().take(FIRST_ROW) {
            *slot = P::R::ONE;
        }
        for r in FIRST_ROW..rows {
            let (done, rest) = band.split_at_mut(r);
            let (pivots_done, pivots_rest) = inverse_pivot.split_at_mut(r);
            let (Some(row), Some(pivot)) = (rest.first_mut(), pivots_rest.first_mut()) else {
                break;
            };
            let start = r.saturating_sub(BAND);
            let windows = (
                <&[BandRow<P::R>; BAND]>::try_from(&done[start..]),
                <&[P::R; BAND]>::try_from(&pivots_done[start..]),
            );
            *pivot = match windows {
                (Ok(previous), Ok(pivots)) => factor_row(row, previous, pivots, floor),
                // The first rows (r < BAND): the same with a shorter reach.
                _ => {
                    let mut previous = [[P::R::ZERO; BAND + 1]; BAND];
                    let mut pivots = [P::R::ONE; BAND];
                    let reach = r - start;
                    for k in 0..reach {
                        previous[BAND - reach + k] = done[start + k];
                        pivots[BAND - reach + k] = pivots_done[start + k];
                    }
                    factor_row(row, &previous, &pivots, floor)
                }
            };
        }
    }

    /// Solves `L D Lᵀ z = rhs` in place after [`Self::factor`]; the held nodes' entries are
    /// left as they are (zero in the step).
    pub fn solve(&self, rhs: &mut [[P::R; 3]; N]) {
        let band = self.band.as_flattened();
        let inverse_pivot = self.inverse_pivot.as_flattened();
        let z = rhs.as_flattened_mut();
        let rows = (3 * self.nodes).min(band.len()).min(z.len());
        // L y = rhs: z[r] −= Σ_m L(r, r − m) z[r − m].
        for r in FIRST_ROW..rows {
            let row = &band[r];
            let start = r.saturating_sub(BAND);
            let mut sum = z[r];
            for (l, previous) in row[1..].iter().zip(z[start..r].iter().rev()) {
                sum -= *l * *previous;
            }
            z[r] = sum;
        }
        for (value, inverse) in z.iter_mut().zip(inverse_pivot).take(rows).skip(FIRST_ROW) {
            *value *= *inverse;
        }
        // Lᵀ x = y: z[r] −= Σ_m L(r + m, r) z[r + m].
        for r in (FIRST_ROW..rows).rev() {
            let end = rows.min(r + BAND + 1);
            let (head, tail) = z.split_at_mut(r + 1);
            let (Some(value), Some(below)) = (head.last_mut(), band.get(r + 1..end)) else {
                continue;
            };
            let mut sum = *value;
            for (m, (row, solved)) in below.iter().zip(tail.iter()).enumerate() {
                sum -= row[m + 1] * *solved;
            }
            *value = sum;
        }
    }
}

/// What the implicit step reads of the strands it moves besides their nodes: the masses, the
/// rod's rest data, and the elastic and external forces with the step `h`.
pub struct Loads<'a, P: Kernel, const N: usize> {
    /// `m` per node.
    pub mass: &'a [P::R; N],
    /// The rod's rest data.
    pub rest: &'a RodRest<N, P::R>,
    /// The elastic forces at the step's start (Kmoch Sec. 7.2).
    pub forces: &'a [P::V; N],
    /// The external forces.
    pub external: &'a External<P>,
    /// The caller's accelerations per node, if any.
    pub accelerations: Option<&'a [P::V]>,
}

/// Kmoch 2009 Algorithm 1 line 4 as one linearly implicit step of `h = dt` for the bending
/// (see the module documentation): `(M + h² H̃) v⁺ = M (v + h a)` and `x⁺ = x + h v⁺`, with
/// `a` the acceleration of the explicit step from the elastic forces `forces` and the
/// external forces ([`crate::forces::External::acceleration`]), and `H̃` assembled at `frames`, those of
/// the centreline the step starts from. Nodes 0 and 1 stay put; `held_velocity` is the
/// velocity the head gives them this step (`root_coupling::held_velocity`), a boundary
/// condition of the solve.
pub fn step<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    (frames, system): (&RodFrames<M, N>, &mut BendingSystem<M, N>),
    forces: &[Vec3; N],
    held_velocity: [Vec3; 2],
    accelerations: Option<&[Vec3]>,
) -> Vec3 {
    let state = &mut strand.state;
    let rest = &strand.rest;
    let nodes = Nodes::<M, N> {
        count: rest.nodes.min(N),
        position: &mut state.position,
        velocity: &mut state.velocity,
        inverse_mass: &rest.inverse_mass,
    };
    let external = External::<M>::of(ctx);
    let loads = Loads {
        mass: &rest.mass,
        rest: &rest.rod,
        forces,
        external: &external,
        accelerations,
    };
    step_nodes(
        nodes,
        &loads,
        (frames, system),
        (ctx.dt, held_velocity),
        true,
    )
}

/// [`step`] of one strand's nodes or of `W` strands' in lanes (`lane::Lanes`): the same
/// operations on each lane. Lanes outside `active` keep their positions and velocities (a
/// strand in a block that takes the explicit substeps): `true` for one strand. `system` is
/// the caller's space for the system: [`BendingSystem::assemble`] writes every entry that
/// [`BendingSystem::factor`] and [`BendingSystem::solve`] read (those of the strand's rows),
/// so what it held before never reaches the bits.
pub fn step_nodes<P: Kernel, const N: usize>(
    nodes: Nodes<'_, P, N>,
    loads: &Loads<'_, P, N>,
    (frames, system): (&RodFrames<P, N>, &mut BendingSystem<P, N>),
    (h, held_velocity): (P::R, [P::V; 2]),
    active: <P::R as Arithmetic>::Mask,
) -> P::V {
    let n = nodes.count.min(N);
    system.assemble(frames, loads.mass, loads.rest, h);
    system.factor();
    // Right-hand side M (v + h a), with a as in the explicit step.
    let mut rhs = [[P::R::ZERO; 3]; N];
    let mut explicit_momentum = P::V::ZERO;
    for (i, slot) in rhs.iter_mut().enumerate().take(n).skip(2) {
        let v = nodes.velocity[i];
        let (force, inverse_mass) = (loads.forces[i], nodes.inverse_mass[i]);
        let a = (loads.external).acceleration(force, v, inverse_mass, loads.accelerations, i);
        let momentum = (v + a * h) * loads.mass[i];
        explicit_momentum += momentum;
        *slot = momentum.components();
    }
    BendingSystem::move_held_nodes(frames, loads.rest, h, held_velocity, &mut rhs);
    system.solve(&mut rhs);
    let mut momentum = P::V::ZERO;
    for (i, solved) in rhs.iter().enumerate().take(n).skip(2) {
        let (v, x) = (P::V::from_components(*solved), nodes.position[i]);
        momentum += v * loads.mass[i];
        nodes.velocity[i] = P::V::select(active, v, nodes.velocity[i]);
        nodes.position[i] = P::V::select(active, x + v * h, x);
    }
    on_held_nodes::<P, N>(loads.forces, momentum - explicit_momentum, h)
}

/// The mean force on the held nodes 0 and 1 over an implicit step: their elastic forces
/// `F_0 + F_1` and their share of the implicit term, `−h (H̃ v⁺)_{0,1}`. `H̃` is built from
/// gradients of a translation-invariant energy, so its columns sum to zero and the held rows'
/// share is minus the free rows': `h Σ_free (H̃ v⁺)_i = −(Σ_free m_i v⁺_i − Σ_free m_i (v_i +
/// h a_i))`, the momentum the implicit term took from the free nodes (`implicit_change`).
fn on_held_nodes<P: Kernel, const N: usize>(
    forces: &[P::V; N],
    implicit_change: P::V,
    h: P::R,
) -> P::V {
    crate::root_coupling::elastic_on_root::<P, N>(forces) - implicit_change * (P::R::ONE / h)
}

#[cfg(test)]
mod tests;
