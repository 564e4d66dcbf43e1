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
//! Each particle's sums run over its list in order, so the bits do not depend on threads. What a
//! neighbour contributes is read from one packed record of 32 bytes (position, `m/ρ`,
//! velocity, pressure), half a cache line, so a neighbour costs one memory access.

use std::f32::consts::PI;

use hairsim_core::Vec3;
use rayon::prelude::*;

use super::neighbours::{NeighbourLists, PADDING};
use super::{SphParams, CHUNK};

/// What the hash pass reads of each particle (32 bytes), gathered into the sorted order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Record {
    /// Position, m.
    pub position: [f32; 3],
    /// Velocity, m/s.
    pub velocity: [f32; 3],
    /// Mass, kg.
    pub mass: f32,
    /// `strand << NODE_BITS | node`.
    pub key: u32,
}

/// Particles rearranged into the grid's sorted order, and what is computed for them.
#[derive(Clone, Debug, Default)]
pub struct SortedParticles {
    /// Velocities, m/s.
    pub velocity: Vec<[f32; 3]>,
    /// Positions, m: x (and [`PADDING`] entries past the last particle, never a neighbour).
    pub x: Vec<f32>,
    /// Positions, m: y.
    pub y: Vec<f32>,
    /// Positions, m: z.
    pub z: Vec<f32>,
    /// Masses, kg.
    pub mass: Vec<f32>,
    /// Keys: `strand << NODE_BITS | node`.
    pub key: Vec<u32>,
    /// Densities, kg/m³.
    pub density: Vec<f32>,
    /// What a neighbour contributes: `[x, y, z, m/ρ, vx, vy, vz, p]`.
    pub packed: Vec<[f32; 8]>,
    /// Accelerations, m/s².
    pub acceleration: Vec<Vec3>,
}

impl SortedParticles {
    /// Buffers for `n` particles.
    #[must_use]
    pub fn new(n: usize) -> SortedParticles {
        SortedParticles {
            velocity: vec![[0.0; 3]; n],
            x: vec![0.0; n + PADDING],
            y: vec![0.0; n + PADDING],
            z: vec![0.0; n + PADDING],
            mass: vec![0.0; n],
            key: vec![0; n],
            density: vec![0.0; n],
            packed: vec![[0.0; 8]; n],
            acceleration: vec![Vec3::ZERO; n],
        }
    }

    /// Position of sorted particle `k`.
    #[must_use]
    pub fn position(&self, k: usize) -> Vec3 {
        Vec3::new(self.x[k], self.y[k], self.z[k])
    }

    /// Fills the sorted arrays: sorted particle `k` is `record[order[k]]` (Algorithm 1
    /// line 5), chunk by chunk in parallel — each record read once, each array written in
    /// order.
    pub fn gather(&mut self, order: &[u32], record: &[Record]) {
        let n = order.len().min(self.velocity.len());
        (
            self.x[..n].par_chunks_mut(CHUNK),
            self.y[..n].par_chunks_mut(CHUNK),
            self.z[..n].par_chunks_mut(CHUNK),
            self.velocity[..n].par_chunks_mut(CHUNK),
            self.mass[..n].par_chunks_mut(CHUNK),
            self.key[..n].par_chunks_mut(CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(c, (x, y, z, v, m, key))| {
                for (k, &p) in order[c * CHUNK..].iter().take(x.len()).enumerate() {
                    let Some(r) = record.get(p as usize) else {
                        continue;
                    };
                    [x[k], y[k], z[k]] = r.position;
                    (v[k], m[k], key[k]) = (r.velocity, r.mass, r.key);
                }
            });
    }
}

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

/// Pressure and viscosity accelerations of every particle, for a step of `dt` seconds.
pub fn accelerations(p: &mut SortedParticles, lists: &NeighbourLists, params: &SphParams, dt: f32) {
    let h = params.smoothing_length;
    let factor = spiky_viscosity_factor(h);
    let mu = params.viscosity;
    let (packed, density) = (&p.packed, &p.density);
    p.acceleration
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| {
            for (i, acc) in out.iter_mut().enumerate() {
                let a = c * CHUNK + i;
                let me = packed[a];
                let p_a = me[7];
                let (mut fp, mut fv) = ([0.0f32; 3], [0.0f32; 3]);
                let mut diagonal = 0.0;
                for &b in lists.of(a) {
                    let other = &packed[b as usize];
                    let d = [me[0] - other[0], me[1] - other[1], me[2] - other[2]];
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    let w = h - r;
                    if w <= 0.0 {
                        continue;
                    }
                    let q = other[3];
                    if r > 0.0 {
                        // −∇W_spiky points from b to a: repulsion.
                        let s = q * (p_a + other[7]) * w * w / r;
                        for k in 0..3 {
                            fp[k] += d[k] * s;
                        }
                    }
                    let laplacian = q * w;
                    for k in 0..3 {
                        fv[k] += (other[4 + k] - me[4 + k]) * laplacian;
                    }
                    diagonal += laplacian;
                }
                let rho = density[a];
                let rate = mu / rho;
                let implicit = rate * factor / (1.0 + dt * rate * factor * diagonal);
                let pressure = 0.5 * factor / rho;
                *acc = Vec3::from_array(fp) * pressure + Vec3::from_array(fv) * implicit;
            }
        });
}
