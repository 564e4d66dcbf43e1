//! The neighbours of this step and the density (Sánchez-Banderas 2015, Algorithm 1 lines 6–7;
//! Müller, Charypar, Gross 2003): each active particle's candidates filtered by `r < h` on this
//! step's positions, the particle itself and its strand's near nodes being no candidates. At
//! most `cap` are kept: when more are found, those with the smallest keys (strand, then node),
//! an order no rebuild changes. In the same pass, while the distances are at hand:
//! - density `ρ_a = m_a W(0) + Σ_b m_b W_poly6(r)`, `W_poly6(r) = 315/(64π h⁹) (h² − r²)³`, the
//!   sum taken in any order with the same bits ([`super::sum`]);
//! - pressure `p_a = max(0, k (ρ_a − ρ₀))` — hair is not a fluid at rest density everywhere, so
//!   only compression pushes (repulsion for volume), never suction;
//! - what a neighbour contributes to the forces, packed in 32 bytes: position, `m/ρ`,
//!   velocity, pressure.

#![deny(clippy::too_many_lines, clippy::too_many_arguments)]
use rayon::prelude::*;

use super::active::Active;
use super::{sum, SphParams, CHUNK, MAX_CAP};

/// Every active particle's neighbours this step, its density and its packed record.
#[derive(Clone, Debug, Default)]
pub struct Neighbours {
    cap: usize,
    /// Chunk `c`'s lists (active particles `c · CHUNK ..`), one after another, `CHUNK · cap + 1`
    /// entries of room a chunk.
    pub lists: Vec<u32>,
    /// Where each active particle's list starts in `lists`.
    pub start: Vec<u32>,
    /// How many neighbours each active particle kept.
    pub count: Vec<u32>,
    /// Densities, kg/m³.
    pub density: Vec<f32>,
    /// What a neighbour contributes: `[x, y, z, m/ρ, vx, vy, vz, p]`.
    pub packed: Vec<[f32; 8]>,
}

/// Counts of one step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Found {
    /// Neighbours kept, summed over particles.
    pub kept: u64,
    /// Neighbours dropped by the cap.
    pub truncated: u64,
    /// Most neighbours one particle had before the cap.
    pub max_found: u32,
}

impl Found {
    fn merge(self, other: Found) -> Found {
        Found {
            kept: self.kept + other.kept,
            truncated: self.truncated + other.truncated,
            max_found: self.max_found.max(other.max_found),
        }
    }
}

/// One active particle's neighbours as found.
struct List {
    kept: usize,
    all: u32,
    /// `Σ m_b (h² − r²)³` over the kept ones, own mass first.
    sum: f32,
}

impl Neighbours {
    /// Room for up to `particles` active particles of at most `cap` neighbours each, none yet.
    #[must_use]
    pub fn with_room(particles: usize, cap: usize) -> Neighbours {
        Neighbours {
            cap,
            lists: vec![0; particles.div_ceil(CHUNK) * (CHUNK * cap + 1)],
            start: Vec::with_capacity(particles),
            count: Vec::with_capacity(particles),
            density: Vec::with_capacity(particles),
            packed: Vec::with_capacity(particles),
        }
    }

    /// Room for `particles` active particles of at most `cap` neighbours each.
    pub fn resize(&mut self, particles: usize, cap: usize) {
        self.cap = cap;
        let room = particles.div_ceil(CHUNK) * (CHUNK * cap + 1);
        if self.lists.len() < room {
            self.lists.resize(room, 0);
        }
        self.start.resize(particles, 0);
        self.count.resize(particles, 0);
        self.density.resize(particles, 0.0);
        self.packed.resize(particles, [0.0; 8]);
    }

    /// The neighbours of active particle `a`.
    #[inline]
    #[must_use]
    pub fn of(&self, a: usize) -> &[u32] {
        let start = self.start[a] as usize;
        &self.lists[start..start + self.count[a] as usize]
    }

    /// Every active particle's neighbours, density, pressure and packed record.
    pub fn find(&mut self, active: &Active, params: &SphParams) -> Found {
        let n = active.len();
        let cap = self.cap;
        let h = params.smoothing_length;
        let filter = Filter {
            active,
            h2: h * h,
            cap,
            c6: super::forces::poly6_factor(h),
            stiffness: params.stiffness,
            rest: params.rest_density,
        };
        self.lists
            .par_chunks_mut(CHUNK * cap + 1)
            .zip(self.start[..n].par_chunks_mut(CHUNK))
            .zip(self.count[..n].par_chunks_mut(CHUNK))
            .zip(self.density[..n].par_chunks_mut(CHUNK))
            .zip(self.packed[..n].par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, ((((lists, start), count), density), packed))| {
                let mut found = Found::default();
                let mut used = 0;
                let mut terms = [0.0f32; MAX_CAP + 1];
                for (i, (((start, count), density), packed)) in start
                    .iter_mut()
                    .zip(count)
                    .zip(density)
                    .zip(packed)
                    .enumerate()
                {
                    let a = c * CHUNK + i;
                    let mine = &mut lists[used..used + cap + 1];
                    let list = filter.list(a, mine, &mut terms);
                    (*start, *count) = ((c * (CHUNK * cap + 1) + used) as u32, list.kept as u32);
                    used += list.kept;
                    found.kept += list.kept as u64;
                    found.truncated += u64::from(list.all) - list.kept as u64;
                    found.max_found = found.max_found.max(list.all);
                    (*density, *packed) = filter.record(a, list.sum);
                }
                found
            })
            .reduce(Found::default, Found::merge)
    }
}

/// What the filter reads: the active particles and the parameters as the pass uses them.
struct Filter<'a> {
    active: &'a Active,
    h2: f32,
    cap: usize,
    /// The poly6 kernel's factor.
    c6: f32,
    stiffness: f32,
    /// Rest density.
    rest: f32,
}

impl Filter<'_> {
    /// `r²` between active particles `a` and `b`, summed as `(dx² + dy²) + dz²`.
    #[inline(always)]
    fn distance_squared(&self, a: [f32; 4], b: usize) -> f32 {
        let o = self
            .active
            .position
            .get(b)
            .copied()
            .unwrap_or([f32::NAN; 4]);
        let (dx, dy, dz) = (a[0] - o[0], a[1] - o[1], a[2] - o[2]);
        dx * dx + dy * dy + dz * dz
    }

    /// `m_b (h² − r²)³`.
    #[inline(always)]
    fn term(&self, b: usize, d2: f32) -> f32 {
        let w = self.h2 - d2;
        self.active.mass.get(b).copied().unwrap_or(0.0) * (w * w * w)
    }

    /// Active particle `a`'s neighbours into `mine` (`cap + 1` entries of room), and their
    /// density terms into `terms`: each candidate is written and counted only if within `h`
    /// (no branch on it), until more than `cap` are found, which [`Filter::capped`] takes over.
    #[inline(always)]
    fn list(&self, a: usize, mine: &mut [u32], terms: &mut [f32; MAX_CAP + 1]) -> List {
        let me = self.active.position[a];
        let mut kept = 0;
        for &b in self.active.candidates(a) {
            let d2 = self.distance_squared(me, b as usize);
            mine[kept] = b;
            terms[kept] = self.term(b as usize, d2);
            kept += usize::from(d2 < self.h2);
            if kept > self.cap {
                return self.capped(a, mine, terms);
            }
        }
        List {
            kept,
            all: kept as u32,
            sum: self.own_and(a, &terms[..kept]),
        }
    }

    /// The exact sum of `a`'s own `m_a h⁶` and `terms`.
    #[inline(always)]
    fn own_and(&self, a: usize, terms: &[f32]) -> f32 {
        let h2 = self.h2;
        sum::one(self.active.mass[a] * h2 * h2 * h2, terms)
    }

    /// More than `cap` neighbours: the `cap` with the smallest keys, whatever the candidates'
    /// order.
    #[cold]
    fn capped(&self, a: usize, mine: &mut [u32], terms: &mut [f32]) -> List {
        let me = self.active.position[a];
        let key = &self.active.key;
        let (mut kept, mut all) = (0, 0u32);
        for &b in self.active.candidates(a) {
            if self.distance_squared(me, b as usize) >= self.h2 {
                continue;
            }
            all += 1;
            if kept < self.cap {
                mine[kept] = b;
                kept += 1;
                continue;
            }
            // Replace the kept neighbour with the largest key if this one's is smaller.
            let (largest, _) = mine[..kept]
                .iter()
                .enumerate()
                .max_by_key(|(_, &j)| key.get(j as usize))
                .unwrap_or((0, &0));
            if key.get(b as usize) < key.get(mine[largest] as usize) {
                mine[largest] = b;
            }
        }
        for (t, &b) in terms.iter_mut().zip(&mine[..kept]) {
            *t = self.term(b as usize, self.distance_squared(me, b as usize));
        }
        List {
            kept,
            all,
            sum: self.own_and(a, &terms[..kept]),
        }
    }

    /// Active particle `a`'s density and packed record, from its density sum.
    #[inline(always)]
    fn record(&self, a: usize, sum: f32) -> (f32, [f32; 8]) {
        let rho = self.c6 * sum;
        let pressure = (self.stiffness * (rho - self.rest)).max(0.0);
        let [x, y, z, _] = self.active.position[a];
        let [vx, vy, vz] = self.active.velocity[a];
        (
            rho,
            [x, y, z, self.active.mass[a] / rho, vx, vy, vz, pressure],
        )
    }
}
