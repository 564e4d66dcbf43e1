//! Density, pressure and viscosity (Müller, Charypar, Gross 2003; Sánchez-Banderas 2015 Sec. 3.2),
//! over the capped neighbour lists, in sorted order. With `r = |x_a − x_b| < h`:
//! - density `ρ_a = m_a W(0) + Σ_b m_b W_poly6(r)`, `W_poly6(r) = 315/(64π h⁹) (h² − r²)³`;
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
//! Each particle's sums run over its list in order, so the bits do not depend on threads.

use std::f32::consts::PI;

use hairsim_core::Vec3;
use rayon::prelude::*;

use super::neighbours::NeighbourLists;
use super::{SphParams, CHUNK};

/// Particles rearranged into the grid's sorted order, and what is computed for them.
#[derive(Clone, Debug, Default)]
pub struct SortedParticles {
    /// Positions, m.
    pub position: Vec<Vec3>,
    /// Velocities, m/s.
    pub velocity: Vec<Vec3>,
    /// Masses, kg.
    pub mass: Vec<f32>,
    /// Strand of each particle.
    pub strand: Vec<u32>,
    /// Node index of each particle.
    pub node: Vec<u32>,
    /// Densities, kg/m³.
    pub density: Vec<f32>,
    /// Pressures.
    pub pressure: Vec<f32>,
    /// Accelerations, m/s².
    pub acceleration: Vec<Vec3>,
}

impl SortedParticles {
    /// Buffers for `n` particles.
    #[must_use]
    pub fn new(n: usize) -> SortedParticles {
        SortedParticles {
            position: vec![Vec3::ZERO; n],
            velocity: vec![Vec3::ZERO; n],
            mass: vec![0.0; n],
            strand: vec![0; n],
            node: vec![0; n],
            density: vec![0.0; n],
            pressure: vec![0.0; n],
            acceleration: vec![Vec3::ZERO; n],
        }
    }

    /// Fills slot `k` from particle `order[k]` (position, velocity, mass, strand, node).
    pub fn gather(
        &mut self,
        order: &[u32],
        particle: impl Fn(usize) -> (Vec3, Vec3, f32, u32, u32),
    ) {
        for (k, &p) in order.iter().enumerate() {
            let (x, v, m, s, i) = particle(p as usize);
            self.position[k] = x;
            self.velocity[k] = v;
            self.mass[k] = m;
            self.strand[k] = s;
            self.node[k] = i;
        }
    }
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
    315.0 / (64.0 * PI * h2 * h2 * h2 * h2 * h) * d * d * d
}

/// `45/(π h⁶)`: the magnitude factor of both the spiky gradient and the viscosity Laplacian.
#[inline]
#[must_use]
pub fn spiky_viscosity_factor(h: f32) -> f32 {
    let h2 = h * h;
    45.0 / (PI * h2 * h2 * h2)
}

/// Densities and pressures of every particle.
pub fn density_and_pressure(p: &mut SortedParticles, lists: &NeighbourLists, params: &SphParams) {
    let h = params.smoothing_length;
    let (k, rest) = (params.stiffness, params.rest_density);
    let (position, mass) = (&p.position, &p.mass);
    p.density
        .par_chunks_mut(CHUNK)
        .zip(p.pressure.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(c, (density, pressure))| {
            for (i, (rho, pr)) in density.iter_mut().zip(pressure.iter_mut()).enumerate() {
                let a = c * CHUNK + i;
                let mut sum = mass[a] * poly6(0.0, h);
                for &b in lists.of(a) {
                    let d = position[a] - position[b as usize];
                    sum += mass[b as usize] * poly6(d.dot(d), h);
                }
                *rho = sum;
                *pr = (k * (sum - rest)).max(0.0);
            }
        });
}

/// Pressure and viscosity accelerations of every particle, for a step of `dt` seconds.
pub fn accelerations(p: &mut SortedParticles, lists: &NeighbourLists, params: &SphParams, dt: f32) {
    let h = params.smoothing_length;
    let factor = spiky_viscosity_factor(h);
    let mu = params.viscosity;
    let (position, velocity, mass) = (&p.position, &p.velocity, &p.mass);
    let (density, pressure) = (&p.density, &p.pressure);
    p.acceleration
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| {
            for (i, acc) in out.iter_mut().enumerate() {
                let a = c * CHUNK + i;
                let mut f_pressure = Vec3::ZERO;
                let mut f_viscosity = Vec3::ZERO;
                let mut diagonal = 0.0;
                for &b in lists.of(a) {
                    let b = b as usize;
                    let d = position[a] - position[b];
                    let r = d.dot(d).sqrt();
                    if r >= h {
                        continue;
                    }
                    let w = h - r;
                    if r > 0.0 {
                        // −∇W_spiky points from b to a: repulsion.
                        let s = mass[b] * (pressure[a] + pressure[b]) / (2.0 * density[b])
                            * factor
                            * w
                            * w
                            / r;
                        f_pressure += d * s;
                    }
                    let laplacian = mass[b] / density[b] * factor * w;
                    f_viscosity += (velocity[b] - velocity[a]) * laplacian;
                    diagonal += laplacian;
                }
                let rate = mu / density[a];
                *acc =
                    f_pressure / density[a] + f_viscosity * (rate / (1.0 + dt * rate * diagonal));
            }
        });
}
