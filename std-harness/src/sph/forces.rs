//! Density, pressure and viscosity (Müller, Charypar, Gross 2003; Sánchez-Banderas 2015 Sec. 3.2),
//! over the capped neighbour lists, in sorted order. With `r = |x_a − x_b| < h`:
//! - density `ρ_a = m_a W(0) + Σ_b m_b W_poly6(r)`, `W_poly6(r) = 315/(64π h⁹) (h² − r²)³`
//!   (computed with the lists, [`super::neighbours`]);
//! - pressure `p_a = max(0, k (ρ_a − ρ₀))` — hair is not a fluid at rest density everywhere, so
//!   only compression pushes (repulsion for volume), never suction;
//! - `f^p_a = −Σ_b m_b (p_a + p_b)/(2ρ_b) ∇W_spiky(r)`, `∇W_spiky = −45/(π h⁶) (h − r)² (x_a − x_b)/r`;
//! - `f^v_a = µ Σ_b m_b (v_b − v_a)/ρ_b ∇²W_visc(r)`, `∇²W_visc = 45/(π h⁶) (h − r)`;
//! - `a_a = f^p_a/ρ_a + (f^v_a/ρ_a) / (1 + Δt µ D_a/ρ_a)`, `D_a = Σ_b m_b/ρ_b ∇²W_visc(r)`.
//!
//! The viscosity term is taken *linearly implicitly* (one Jacobi step of
//! `v' = v + Δt (µ/ρ) ∇²v'`): explicit viscosity is stable only for `Δt µ D/ρ < 1`, which at
//! hair densities and `h` of a few mm fails by orders of magnitude for the paper's µ up to 200.
//! The implicit form reduces to the explicit one when `Δt µ D/ρ ≪ 1` and, for any µ, damps the
//! relative velocity of neighbours without ever reversing it.
//!
//! Each particle's sums are taken with the same bits in any order of its neighbours
//! ([`super::sum`]). What a neighbour contributes is read from one packed record of 32 bytes
//! (position, `m/ρ`, velocity, pressure), half a cache line, so a neighbour costs one memory
//! access.

use std::f32::consts::PI;

use hairsim_core::Vec3;
use rayon::prelude::*;

use super::density::Neighbours;
use super::{sum, SphParams, CHUNK, MAX_CAP};

/// `315/(64π h⁹)`.
#[inline]
#[must_use]
pub fn poly6_factor(h: f32) -> f32 {
    let h2 = h * h;
    315.0 / (64.0 * PI * h2 * h2 * h2 * h2 * h)
}

/// `315/(64π h⁹) (h² − r²)³`.
#[inline]
#[must_use]
pub fn poly6(r2: f32, h: f32) -> f32 {
    let h2 = h * h;
    if r2 >= h2 {
        return 0.0;
    }
    let d = h2 - r2;
    poly6_factor(h) * d * d * d
}

/// `45/(π h⁶)`: the magnitude factor of both the spiky gradient and the viscosity Laplacian.
#[inline]
#[must_use]
pub fn spiky_viscosity_factor(h: f32) -> f32 {
    let h2 = h * h;
    45.0 / (PI * h2 * h2 * h2)
}

/// Pressure and viscosity accelerations of every active particle into `acceleration`, for a
/// step of `dt` seconds.
pub fn accelerations(
    neighbours: &Neighbours,
    params: &SphParams,
    dt: f32,
    acceleration: &mut [Vec3],
) {
    let h = params.smoothing_length;
    let factor = spiky_viscosity_factor(h);
    let mu = params.viscosity;
    let (packed, density) = (&neighbours.packed, &neighbours.density);
    acceleration
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| {
            let mut terms = [[0.0f32; sum::LANES]; MAX_CAP];
            for (i, acc) in out.iter_mut().enumerate() {
                let a = c * CHUNK + i;
                let list = neighbours.of(a);
                if list.is_empty() {
                    *acc = Vec3::ZERO;
                    continue;
                }
                for (row, &b) in terms.iter_mut().zip(list) {
                    *row = pair(&packed[a], &packed[b as usize], h);
                }
                let total = sum::lanes(&terms[..list.len()]);
                let (fp, diagonal) = ([total[0], total[1], total[2]], total[3]);
                let fv = [total[4], total[5], total[6]];
                let rho = density[a];
                let rate = mu / rho;
                let implicit = rate * factor / (1.0 + dt * rate * factor * diagonal);
                let pressure = 0.5 * factor / rho;
                *acc = Vec3::from_array(fp) * pressure + Vec3::from_array(fv) * implicit;
            }
        });
}

/// What neighbour `other` adds to particle `me`'s sums, without the kernels' common factor:
/// `[fp_x, fp_y, fp_z, D, fv_x, fv_y, fv_z, 0]` (zero beyond `h`, where rounding put it).
#[inline(always)]
fn pair(me: &[f32; 8], other: &[f32; 8], h: f32) -> [f32; sum::LANES] {
    let d = [me[0] - other[0], me[1] - other[1], me[2] - other[2]];
    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let w = h - r;
    if w <= 0.0 {
        return [0.0; sum::LANES];
    }
    let q = other[3];
    // −∇W_spiky points from b to a: repulsion.
    let s = if r > 0.0 {
        q * (me[7] + other[7]) * w * w / r
    } else {
        0.0
    };
    let laplacian = q * w;
    [
        d[0] * s,
        d[1] * s,
        d[2] * s,
        laplacian,
        (other[4] - me[4]) * laplacian,
        (other[5] - me[5]) * laplacian,
        (other[6] - me[6]) * laplacian,
        0.0,
    ]
}
