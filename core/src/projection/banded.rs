//! The banded LDLᵀ of the projection's matrix `A = ∇C M⁻¹ ∇Cᵀ` (Goldenthal 2007 Sec. 4: the
//! matrix of a chain is banded, so a step costs O(n·w²)), in fixed arrays: no dense matrix,
//! no heap.
//!
//! Collision rows come first: each touches one node, so its pivot, taken before the
//! segments', only updates the segment entries of that node, which are in the band already
//! ([`eliminate_contacts`]). What is left is tridiagonal whatever the contacts.
//!
//! Storage is by rows of the lower band: `band[r][0]` holds `A_rr` (then the pivot `D_r`),
//! `band[r][k]` holds `A_{r,r−k}` (then `L_{r,r−k}`), `k ≤ MAX_HALF_BANDWIDTH`. Each row `r`
//! also has an envelope start `first[r]`: entries left of it are zero in `A` and stay zero in
//! `L` (fill-in never leaves the envelope), so the factorisation visits only
//! `first[r] … r` — a profile (skyline) solver inside a fixed band.
//!
//! A pivot that is not clearly positive (a dependent row: two collision rows with the same
//! normal, a segment of zero length, a node held between two collinear prescribed neighbours)
//! is *dropped*: `D_r = 0`, its column of `L` is zero and its multiplier is 0. That solves
//! the system without that row, which is what a rank-deficient `∇C` allows; the caller
//! counts the dropped rows.

use super::constraints::{NodeContacts, Row, RowKind, Rows, NO_ROW};
use crate::math::{Real, Vec3};

/// Largest half-bandwidth the solver takes. The projection's segment rows need 1 (collision
/// rows are eliminated at their node first, see [`eliminate_contacts`]); the room up to 3
/// keeps the solver general (layouts with a node's rows in the band: a
/// finite-mass pin has three) and is what its tests exercise.
pub const MAX_HALF_BANDWIDTH: usize = 3;

/// One row of the lower band: `[A_rr, A_{r,r−1}, …, A_{r,r−MAX_HALF_BANDWIDTH}]`.
pub type BandRow = [Real; MAX_HALF_BANDWIDTH + 1];

/// A pivot below this fraction of its row's diagonal `A_rr` means the row depends on the rows
/// before it (f32 keeps ~1e-7 of `A_rr` through the eliminations: 100× margin).
pub const PIVOT_RATIO: Real = 1.0e-5;

/// The envelope start of row `r`, clamped into the band so that no access can leave it.
#[inline(always)]
fn envelope(first: &[u16], r: usize) -> usize {
    let f = first.get(r).map_or(r, |&f| usize::from(f));
    f.clamp(r.saturating_sub(MAX_HALF_BANDWIDTH), r)
}

/// `A_{rc} = Σ_i w_i h_r^i · h_c^i` over the nodes both rows touch, with `h = (I − P_i)∇C`
/// the gradient blocks after the elimination of the nodes' collision rows.
#[inline(always)]
fn product(a: &Row, b: &Row, inverse_mass: &[Real]) -> Real {
    let mut sum = 0.0;
    for (&na, ga) in a.nodes.iter().zip(a.projected.iter()) {
        for (&nb, gb) in b.nodes.iter().zip(b.projected.iter()) {
            if na == nb {
                let w = inverse_mass.get(usize::from(na)).copied().unwrap_or(0.0);
                sum += w * ga.dot(*gb);
            }
        }
    }
    sum
}

/// Fills `band` with the lower band of `A = ∇C M⁻¹ ∇Cᵀ` for `rows` (envelopes `first`), the
/// Schur complement left by [`eliminate_contacts`]. A padding row gets `A_rr = 1` and no
/// coupling, so its multiplier is 0.
pub fn assemble(rows: &[Row], first: &[u16], inverse_mass: &[Real], band: &mut [BandRow]) {
    for (r, (row, out)) in rows.iter().zip(band.iter_mut()).enumerate() {
        *out = [0.0; MAX_HALF_BANDWIDTH + 1];
        if row.kind == RowKind::Padding {
            out[0] = 1.0;
            continue;
        }
        for c in envelope(first, r)..=r {
            if let (Some(entry), Some(column)) = (out.get_mut(r - c), rows.get(c)) {
                *entry = product(row, column, inverse_mass);
            }
        }
    }
}

/// Eliminates each node's collision rows (Gaussian elimination on their pivots first) and
/// leaves their effect on the segment rows that share the node. With `G` the node's collision
/// gradients (3×k, k ≤ 2) and `w` its inverse mass, the collision block is `w GᵀG`; its
/// Schur complement on two segment rows `s`, `t` through the node is
/// `w ∇_sCᵀ (I − P) ∇_tC` with `P = G (GᵀG)⁻¹ Gᵀ`, and their right-hand sides lose
/// `∇_sC · d` with `d = G (GᵀG)⁻¹ C_G` (`w` cancels). So each segment block on the node is
/// projected onto the contacts' tangent space (`Row::projected`) and `rhs −= ∇C·d`; the node
/// later moves by `−d − w (I − P) Σ_s ∇_sC δλ_s`. A second collision row whose gradient
/// nearly depends on the first (a pivot below [`PIVOT_RATIO`]) is dropped. Returns how many
/// collision rows were dropped. O(contacts): only the nodes of `rows.contact_nodes`.
pub fn eliminate_contacts<const N: usize>(rows: &mut Rows<N>, nodes: usize) -> u32 {
    let mut dropped = 0;
    for k in 0..rows.contact_count.min(N) {
        let i = usize::from(rows.contact_nodes[k]);
        if i >= nodes {
            continue;
        }
        let Some(contacts) = rows.contacts.get_mut(i) else {
            continue;
        };
        dropped += eliminate_at_node(contacts);
        let contacts = *contacts;
        // The segments through node i: i − 1 (node i is its second) and i (its first).
        let through = [(i.wrapping_sub(1), 1), (i, 0)];
        for (segment, block) in through {
            let Some(&r) = rows.segment_row.get(segment) else {
                continue;
            };
            if r == NO_ROW {
                continue;
            }
            if let Some(row) = rows.rows.get_mut(usize::from(r)) {
                row.projected[block] =
                    eliminate_from_segment(&contacts, row.gradient_at(block), &mut row.rhs);
            }
        }
    }
    dropped
}

/// The first half of [`eliminate_contacts`] at one node: the inverse Gram matrix of its
/// collision rows (`kept`) and its displacement `d = G (GᵀG)⁻¹ C_G`. A node without rows gets
/// `kept = 0`. Returns the rows dropped.
#[inline(always)]
pub fn eliminate_at_node(contacts: &mut NodeContacts) -> u32 {
    if contacts.count == 0 {
        contacts.kept = 0;
        return 0;
    }
    let dropped = gram_inverse(contacts);
    let [c0, c1] = contacts.value;
    let [inv00, inv01, inv11] = contacts.inverse_gram;
    let [g0, g1] = contacts.gradient;
    // One kept row (nearly every contact): `P v = g (g·v)/(g·g)`, the two-row formulas
    // without their zero terms.
    contacts.displacement = if contacts.kept <= 1 {
        g0 * (inv00 * c0)
    } else {
        let (a0, a1) = (inv00 * c0 + inv01 * c1, inv01 * c0 + inv11 * c1);
        g0 * a0 + g1 * a1
    };
    dropped
}

/// The second half of [`eliminate_contacts`] on one segment through the node of `contacts`,
/// whose gradient block there is `g`: its right-hand side loses `g·d`; returns the block
/// projected onto the contacts' tangent space, `(I − P) g`.
#[inline(always)]
pub fn eliminate_from_segment(contacts: &NodeContacts, g: Vec3, rhs: &mut Real) -> Vec3 {
    *rhs -= g.dot(contacts.displacement);
    let along = if contacts.kept <= 1 {
        let g0 = contacts.gradient[0];
        g0 * (contacts.inverse_gram[0] * g0.dot(g))
    } else {
        project_onto_normals(contacts, g)
    };
    g - along
}

/// Undoes [`eliminate_contacts`] on the segment rows (`rhs = C`, `projected = ∇C`), so that
/// it can run again on a changed set of collision rows.
pub fn undo_elimination<const N: usize>(rows: &mut Rows<N>) {
    let count = rows.count.min(N);
    for row in rows.rows.iter_mut().take(count) {
        row.rhs = row.value;
        row.projected = row.gradients();
    }
}

/// Fills `contacts.inverse_gram` and `kept`; returns the rows dropped (dependent or empty).
fn gram_inverse(contacts: &mut NodeContacts) -> u32 {
    let [g0, g1] = contacts.gradient;
    let a00 = g0.dot(g0);
    contacts.inverse_gram = [0.0; 3];
    contacts.kept = 0;
    // `!(… > …)` also catches NaN.
    if !(a00 > 0.0 && a00.is_finite()) {
        contacts.value = [0.0; 2];
        return u32::from(contacts.count);
    }
    contacts.kept = 1;
    contacts.inverse_gram[0] = 1.0 / a00;
    if contacts.count < 2 {
        contacts.value[1] = 0.0;
        contacts.gradient[1] = Vec3::ZERO;
        return 0;
    }
    let (a01, a11) = (g0.dot(g1), g1.dot(g1));
    let det = a00 * a11 - a01 * a01;
    if det > PIVOT_RATIO * a00 * a11 && det.is_finite() {
        contacts.kept = 2;
        contacts.inverse_gram = [a11 / det, -a01 / det, a00 / det];
        0
    } else {
        // Nearly the same normal twice: the first row meets both.
        contacts.value[1] = 0.0;
        contacts.gradient[1] = Vec3::ZERO;
        1
    }
}

/// `P v = G (GᵀG)⁻¹ Gᵀ v`: the part of `v` along the node's kept contact gradients.
#[inline(always)]
pub fn project_onto_normals(contacts: &NodeContacts, v: Vec3) -> Vec3 {
    let [g0, g1] = contacts.gradient;
    let (b0, b1) = (g0.dot(v), g1.dot(v));
    let [inv00, inv01, inv11] = contacts.inverse_gram;
    g0 * (inv00 * b0 + inv01 * b1) + g1 * (inv01 * b0 + inv11 * b1)
}

/// The collision multipliers of a node whose segments got `δλ`: with `S = Σ_s ∇_sC δλ_s`
/// over its segments, `δλ_G = (w GᵀG)⁻¹ (C_G − w Gᵀ S) = (GᵀG)⁻¹ (C_G / w − Gᵀ S)`.
#[must_use]
pub fn contact_multipliers(contacts: &NodeContacts, inverse_mass: Real, pull: Vec3) -> [Real; 2] {
    if contacts.kept == 0 || inverse_mass.is_nan() || inverse_mass <= 0.0 {
        return [0.0; 2];
    }
    let [g0, g1] = contacts.gradient;
    let [c0, c1] = contacts.value;
    let b0 = c0 / inverse_mass - g0.dot(pull);
    let b1 = c1 / inverse_mass - g1.dot(pull);
    let [inv00, inv01, inv11] = contacts.inverse_gram;
    [inv00 * b0 + inv01 * b1, inv01 * b0 + inv11 * b1]
}

/// `1/d` for a pivot kept (`d > 0`), 0 for a dropped one: the one division per pivot, shared
/// by the column of `L` below it and its unknown (VDIV is 14 cycles on a Cortex-M4F, a
/// multiplication one).
#[inline(always)]
fn reciprocal(d: Real) -> Real {
    if d > 0.0 {
        1.0 / d
    } else {
        0.0
    }
}

/// Factors `band` in place into `L D Lᵀ` (unit lower `L`). Returns how many rows were dropped
/// at a singular or non-finite pivot. O(rows · w²).
pub fn factor(band: &mut [BandRow], first: &[u16]) -> u32 {
    let mut dropped = 0;
    for r in 0..band.len() {
        let start = envelope(first, r);
        // L_rj = (A_rj − Σ_{p<j} L_rp D_p L_jp) / D_j, for j = start … r−1.
        for j in start..r {
            let inner = start.max(envelope(first, j));
            let mut s = band[r][r - j];
            for p in inner..j {
                s -= band[r][r - p] * band[p][0] * band[j][j - p];
            }
            band[r][r - j] = s * reciprocal(band[j][0]);
        }
        // D_r = A_rr − Σ_p L_rp² D_p.
        let diagonal = band[r][0];
        let mut d = diagonal;
        for p in start..r {
            let l = band[r][r - p];
            d -= l * l * band[p][0];
        }
        // `!(… > …)` also catches NaN.
        if !(diagonal > 0.0 && d > PIVOT_RATIO * diagonal && d.is_finite()) {
            d = 0.0;
            dropped += 1;
        }
        band[r][0] = d;
    }
    dropped
}

/// Solves `L D Lᵀ y = b` in place (`rhs` holds `b`, then `y`); a dropped row's unknown is 0.
pub fn solve(band: &[BandRow], first: &[u16], rhs: &mut [Real]) {
    let count = band.len().min(rhs.len());
    // Forward: L z = b.
    for r in 0..count {
        let mut s = rhs[r];
        for p in envelope(first, r)..r {
            s -= band[r][r - p] * rhs[p];
        }
        rhs[r] = s;
    }
    // Diagonal: D u = z.
    for r in 0..count {
        rhs[r] *= reciprocal(band[r][0]);
    }
    // Backward: Lᵀ y = u, a column of Lᵀ at a time from the last row up.
    for r in (0..count).rev() {
        let y = rhs[r];
        for p in envelope(first, r)..r {
            rhs[p] -= band[r][r - p] * y;
        }
    }
}

/// The projection's own system in one fused pass (the path [`super::project_constraints`]
/// takes): once each node's collision rows are eliminated ([`eliminate_contacts`]) only the
/// segment rows are left and `A` is tridiagonal (row `r` couples to `r − 1` at most, when
/// `first[r] < r`). So assembly, the `L D Lᵀ` factorisation and the forward substitution run
/// together root → tip, and the back substitution tip → root: two passes over the rows and
/// no envelope bookkeeping, where [`assemble`], [`factor`] and [`solve`] take four and
/// handle any half-bandwidth up to [`MAX_HALF_BANDWIDTH`]. Same operations in the same
/// order as those three on a tridiagonal envelope, so the same bits (a unit test checks it).
///
/// On return `multipliers[..rows.len()]` holds `δλ` and `band[r][0]`, `band[r][1]` hold `D_r`
/// and `L_{r,r−1}`. A pivot that is not clearly positive is dropped as in [`factor`]; returns
/// how many were.
pub fn solve_chain(
    rows: &[Row],
    first: &[u16],
    inverse_mass: &[Real],
    band: &mut [BandRow],
    multipliers: &mut [Real],
) -> u32 {
    let count = rows.len().min(band.len()).min(multipliers.len());
    let mut dropped = 0;
    // D, 1/D and z of the previous row (root → tip).
    let (mut d_above, mut inverse_above, mut z_above) = (0.0, 0.0, 0.0);
    for r in 0..count {
        let row = &rows[r];
        let coupled = r > 0 && first.get(r).is_some_and(|&f| usize::from(f) < r);
        let (diagonal, below) = if row.kind == RowKind::Padding {
            (1.0, 0.0)
        } else {
            (
                diagonal_entry(row, inverse_mass),
                match rows.get(r.wrapping_sub(1)) {
                    Some(above) if coupled => coupling(row, above, inverse_mass),
                    _ => 0.0,
                },
            )
        };
        let mut z = row.rhs;
        let mut d = diagonal;
        let mut lower = 0.0;
        if coupled {
            lower = below * inverse_above;
            d -= lower * lower * d_above;
            z -= lower * z_above;
        }
        // `!(… > …)` also catches NaN.
        if !(diagonal > 0.0 && d > PIVOT_RATIO * diagonal && d.is_finite()) {
            d = 0.0;
            dropped += 1;
        }
        let inverse = reciprocal(d);
        band[r][0] = d;
        band[r][1] = lower;
        multipliers[r] = z * inverse;
        (d_above, inverse_above, z_above) = (d, inverse, z);
    }
    // Backward: Lᵀ y = u.
    for r in (1..count).rev() {
        let y = multipliers[r];
        if first.get(r).is_some_and(|&f| usize::from(f) < r) {
            multipliers[r - 1] -= band[r][1] * y;
        }
    }
    dropped
}

/// `A_rr` of a segment row: [`product`] of the row with itself, written out.
#[inline(always)]
fn diagonal_entry(row: &Row, inverse_mass: &[Real]) -> Real {
    let w = |node: u16| inverse_mass.get(usize::from(node)).copied().unwrap_or(0.0);
    let [p0, p1] = row.projected;
    w(row.nodes[0]) * p0.dot(p0) + w(row.nodes[1]) * p1.dot(p1)
}

/// `A_{r,r−1}` of consecutive segment rows, which share the node `row.nodes[0] =
/// above.nodes[1]` (any other pattern goes through [`product`]).
#[inline(always)]
fn coupling(row: &Row, above: &Row, inverse_mass: &[Real]) -> Real {
    let shared = row.nodes[0];
    let distinct = above.nodes[0] != shared && row.nodes[1] != shared;
    if shared == above.nodes[1] && row.nodes[1] != above.nodes[0] && distinct {
        let w = inverse_mass
            .get(usize::from(shared))
            .copied()
            .unwrap_or(0.0);
        w * row.projected[0].dot(above.projected[1])
    } else {
        product(row, above, inverse_mass)
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // dense reference code reads best with indices
mod tests {
    use super::*;

    /// Largest test system (fixed arrays: the core's tests run without `std`).
    const M: usize = 40;
    type Dense = [[f64; M]; M];

    /// A small deterministic generator (xorshift) for test matrices.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Dense Gaussian elimination with partial pivoting in f64: the independent reference.
    fn dense_solve(mut a: Dense, mut b: [f64; M], n: usize) -> [f64; M] {
        for k in 0..n {
            let mut p = k;
            for i in k + 1..n {
                if a[i][k].abs() > a[p][k].abs() {
                    p = i;
                }
            }
            a.swap(k, p);
            b.swap(k, p);
            for i in k + 1..n {
                let f = a[i][k] / a[k][k];
                for j in k..n {
                    a[i][j] -= f * a[k][j];
                }
                b[i] -= f * b[k];
            }
        }
        let mut x = [0.0; M];
        for i in (0..n).rev() {
            let s: f64 = (i + 1..n).map(|j| a[i][j] * x[j]).sum();
            x[i] = (b[i] - s) / a[i][i];
        }
        x
    }

    /// A random symmetric `n × n` matrix of half-bandwidth `w`, made SPD by a diagonal that
    /// dominates its row by a random margin (so it is not trivially diagonal).
    fn random_spd_band(n: usize, w: usize, rng: &mut Rng) -> Dense {
        let mut a = [[0.0; M]; M];
        for i in 0..n {
            for k in 1..=w.min(i) {
                let v = rng.next() * 2.0 - 1.0;
                a[i][i - k] = v;
                a[i - k][i] = v;
            }
        }
        for i in 0..n {
            let off: f64 = (0..n).filter(|&j| j != i).map(|j| a[i][j].abs()).sum();
            a[i][i] = off * (1.0 + rng.next()) + 0.05;
        }
        a
    }

    /// The lower band of `a` within the envelopes `first`.
    fn band_of(a: &Dense, first: &[u16]) -> [BandRow; M] {
        let mut band = [[0.0; MAX_HALF_BANDWIDTH + 1]; M];
        for (r, &f) in first.iter().enumerate() {
            for c in usize::from(f)..=r {
                band[r][r - c] = a[r][c] as Real;
            }
        }
        band
    }

    #[test]
    fn banded_solve_equals_a_dense_reference_on_random_spd_band_matrices() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for trial in 0..300 {
            let n = 1 + trial % M;
            let w = 1 + trial % MAX_HALF_BANDWIDTH;
            let a = random_spd_band(n, w, &mut rng);
            let mut b = [0.0; M];
            for v in b.iter_mut().take(n) {
                *v = rng.next() * 2.0 - 1.0;
            }
            let reference = dense_solve(a, b, n);
            let mut first = [0u16; M];
            for (r, f) in first.iter_mut().enumerate() {
                *f = r.saturating_sub(w) as u16;
            }
            let mut band = band_of(&a, &first[..n]);
            assert_eq!(factor(&mut band[..n], &first[..n]), 0, "trial {trial}");
            let mut y = [0.0 as Real; M];
            for (y, b) in y.iter_mut().zip(b) {
                *y = b as Real;
            }
            solve(&band[..n], &first[..n], &mut y[..n]);
            let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (got, want) in y.iter().zip(&reference).take(n) {
                assert!(
                    (f64::from(*got) - want).abs() <= 1e-4 * scale,
                    "trial {trial}: n {n}, w {w}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn a_profile_envelope_gives_the_same_solution_as_the_full_band() {
        // Tridiagonal chain with one coupling reaching back 3 (a node with two contacts).
        let n = 12;
        let mut rng = Rng(7);
        let mut a = random_spd_band(n, 1, &mut rng);
        a[7][4] = 0.3;
        a[4][7] = 0.3;
        a[7][7] += 1.0;
        a[4][4] += 1.0;
        let mut first = [0u16; 12];
        let mut full = [0u16; 12];
        for r in 0..n {
            first[r] = r.saturating_sub(1) as u16;
            full[r] = r.saturating_sub(3) as u16;
        }
        first[7] = 4;
        let (mut band_env, mut band_full) = (band_of(&a, &first), band_of(&a, &full));
        assert_eq!(factor(&mut band_env[..n], &first), 0);
        assert_eq!(factor(&mut band_full[..n], &full), 0);
        let mut b = [0.0; M];
        let mut y_env = [0.0 as Real; 12];
        for i in 0..n {
            b[i] = i as f64 - 5.0;
            y_env[i] = b[i] as Real;
        }
        let mut y_full = y_env;
        solve(&band_env[..n], &first, &mut y_env);
        solve(&band_full[..n], &full, &mut y_full);
        let reference = dense_solve(a, b, n);
        for ((e, f), r) in y_env.iter().zip(&y_full).zip(&reference) {
            assert!((f64::from(*e) - r).abs() < 1e-4 && (f64::from(*f) - r).abs() < 1e-4);
        }
    }

    #[test]
    fn a_dependent_row_is_dropped_not_divided_by() {
        // Rows 0 and 1 equal (two contacts with the same normal): A = [[1,1],[1,1]] ⊕ [2].
        let mut band = [[0.0 as Real; MAX_HALF_BANDWIDTH + 1]; 3];
        band[0][0] = 1.0;
        band[1][0] = 1.0;
        band[1][1] = 1.0;
        band[2][0] = 2.0;
        let first = [0u16, 0, 2];
        assert_eq!(factor(&mut band, &first), 1);
        let mut y = [3.0, 3.0, 4.0];
        solve(&band, &first, &mut y);
        assert!(y.iter().all(|v| v.is_finite()));
        // The kept rows are satisfied: y0 = 3 (row 1 dropped, its multiplier 0), y2 = 2.
        assert_eq!(y, [3.0, 0.0, 2.0]);
        // A NaN or zero diagonal is dropped too.
        let mut bad = [[0.0 as Real; MAX_HALF_BANDWIDTH + 1]; 2];
        bad[0][0] = Real::NAN;
        let first = [0u16, 1];
        assert_eq!(factor(&mut bad, &first), 2);
        let mut y = [1.0, 1.0];
        solve(&bad, &first, &mut y);
        assert_eq!(y, [0.0, 0.0]);
    }
    #[test]
    fn the_fused_chain_solve_gives_the_bits_of_assemble_factor_solve() {
        let mut rng = Rng(0x5eed_cafe);
        for trial in 0..50 {
            let n = 3 + trial % 20;
            let mut x = [Vec3::ZERO; M];
            let mut w = [0.0 as Real; M];
            for i in 0..n {
                let r = |rng: &mut Rng| (rng.next() * 2.0 - 1.0) as Real;
                x[i] = Vec3::new(
                    i as Real * 0.01 + 0.002 * r(&mut rng),
                    0.003 * r(&mut rng),
                    0.0,
                );
                // Some prescribed nodes (w = 0) and some pivots that must be dropped.
                w[i] = if i < 2 || rng.next() < 0.1 {
                    0.0
                } else {
                    1.0 + rng.next() as Real
                };
            }
            let mut rows = [Row::default(); M];
            let mut first = [0u16; M];
            let fixed_cost = trial % 2 == 0;
            for j in 0..n - 1 {
                if w[j] == 0.0 && w[j + 1] == 0.0 {
                    first[j] = j as u16; // padding row, no coupling
                    continue;
                }
                rows[j] = Row::segment(j, x[j], x[j + 1], 0.01);
                let coupled = j > 0 && (fixed_cost || rows[j - 1].kind == RowKind::Segment);
                first[j] = if coupled { j as u16 - 1 } else { j as u16 };
            }
            let count = n - 1;
            let mut band = [[0.0 as Real; MAX_HALF_BANDWIDTH + 1]; M];
            assemble(&rows[..count], &first[..count], &w, &mut band[..count]);
            let dropped = factor(&mut band[..count], &first[..count]);
            let mut y = [0.0 as Real; M];
            for r in 0..count {
                y[r] = rows[r].rhs;
            }
            solve(&band[..count], &first[..count], &mut y[..count]);
            let mut fused_band = [[0.0 as Real; MAX_HALF_BANDWIDTH + 1]; M];
            let mut fused = [0.0 as Real; M];
            let fused_dropped = solve_chain(
                &rows[..count],
                &first[..count],
                &w,
                &mut fused_band[..count],
                &mut fused[..count],
            );
            assert_eq!(fused_dropped, dropped, "trial {trial}");
            for r in 0..count {
                assert_eq!(fused[r].to_bits(), y[r].to_bits(), "trial {trial} row {r}");
            }
        }
    }
}
