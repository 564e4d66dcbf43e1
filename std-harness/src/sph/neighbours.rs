//! Capped neighbour lists (Sánchez-Banderas 2015, Sec. 4, Algorithm 1 line 6: the paper's
//! rough k-nearest list), with the density and pressure of each particle (line 7) taken in
//! the same pass, while the distances are at hand.
//!
//! Each particle's cell comes from its sorted position; the nine rows around it
//! ([`RowsAround`]) are hashed once per run of particles in one row, and the 27 cells are read
//! as nine ranges of three cells (more where the row crosses into the next brick) of the
//! sorted structure-of-arrays positions. The candidates of each range are tested eight at a
//! time for `r² < h²` (no square root), and the first `cap` that pass (and are not the
//! particle itself nor its own strand's near nodes) are kept, in scan order. The order is a
//! function of the positions only, so lists, truncation and every sum over a list are the
//! same on any number of threads.
//!
//! Lists are stored compactly: a chunk of particles writes its lists one after another into
//! its own part of the storage, so the few neighbours a particle has (about five on a head)
//! take a few bytes, not a cache line and a half of room for `cap` of them.

use rayon::prelude::*;

use super::forces::{poly6_factor, SortedParticles};
use super::grid::{cell_of, Grid, RowsAround};
use super::{SphParams, CHUNK};

/// Lanes of the distance test, and entries past the last particle in the position arrays.
pub const PADDING: usize = 8;

/// Bits of a particle's key holding its node index; the strand is above them.
pub const NODE_BITS: u32 = 8;

/// One list of at most `cap` neighbours per particle, in sorted indices.
#[derive(Clone, Debug)]
pub struct NeighbourLists {
    cap: usize,
    /// Every list: chunk `c`'s lists one after another from `c · CHUNK · cap`.
    pub list: Vec<u32>,
    /// Where each particle's list starts in `list`.
    pub start: Vec<u32>,
    /// How many neighbours each particle kept.
    pub count: Vec<u32>,
}

/// Counts from one build.
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

impl NeighbourLists {
    /// Lists for `particles` particles of at most `cap` neighbours each.
    #[must_use]
    pub fn new(particles: usize, cap: usize) -> NeighbourLists {
        NeighbourLists {
            cap,
            list: vec![0; particles * cap],
            start: vec![0; particles],
            count: vec![0; particles],
        }
    }

    /// The neighbours of sorted particle `a`.
    #[inline]
    #[must_use]
    pub fn of(&self, a: usize) -> &[u32] {
        let start = self.start[a] as usize;
        &self.list[start..start + self.count[a] as usize]
    }

    /// Rebuilds every list from the sorted particles, and writes each particle's density
    /// (`p.density`) and its packed force inputs (`p.packed`, with the pressure).
    pub fn build(&mut self, grid: &Grid, p: &mut SortedParticles, params: &SphParams) -> Found {
        let cap = self.cap;
        let n = p.mass.len();
        let h = params.smoothing_length;
        let h2 = h * h;
        let c6 = poly6_factor(h);
        let (stiffness, rest) = (params.stiffness, params.rest_density);
        let gap = params.same_strand_gap;
        let (inverse_cell, row_mask) = (grid.inverse_cell(), grid.row_mask());
        let SortedParticles {
            x,
            y,
            z,
            record,
            mass,
            key,
            density,
            packed,
            ..
        } = p;
        let (x, y, z, mass, key, record) =
            (&x[..], &y[..], &z[..], &mass[..], &key[..], &record[..]);
        self.list[..n * cap]
            .par_chunks_mut(CHUNK * cap)
            .zip(self.start[..n].par_chunks_mut(CHUNK))
            .zip(self.count[..n].par_chunks_mut(CHUNK))
            .zip(density.par_chunks_mut(CHUNK))
            .zip(packed.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, ((((list, start), count), density), packed))| {
                let mut found = Found::default();
                let mut rows = RowsAround::NONE;
                let mut used = 0usize;
                for k in 0..count.len() {
                    let a = c * CHUNK + k;
                    let me = [x[a], y[a], z[a]];
                    let cell = cell_of(me.into(), inverse_cell);
                    rows.update(cell, row_mask);
                    let my_key = key[a];
                    let mine = &mut list[used..used + cap];
                    let mut kept = 0usize;
                    let mut all = 0u32;
                    // ρ / (315/(64π h⁹)): own mass, then the kept neighbours in list order.
                    let mut sum = mass[a] * h2 * h2 * h2;
                    rows.ranges(grid, cell, |s, e| {
                        scan(s, e, me, h2, (x, y, z), |j, d2| {
                            if j == a || near_on_strand(key[j], my_key, gap) {
                                return;
                            }
                            all += 1;
                            if kept < cap {
                                mine[kept] = j as u32;
                                kept += 1;
                                let w = h2 - d2;
                                sum += mass[j] * (w * w * w);
                            }
                        });
                    });
                    start[k] = (c * CHUNK * cap + used) as u32;
                    count[k] = kept as u32;
                    used += kept;
                    found.kept += kept as u64;
                    found.truncated += u64::from(all) - kept as u64;
                    found.max_found = found.max_found.max(all);
                    let rho = c6 * sum;
                    let pr = (stiffness * (rho - rest)).max(0.0);
                    density[k] = rho;
                    let [vx, vy, vz] = record[a].velocity;
                    packed[k] = [me[0], me[1], me[2], mass[a] / rho, vx, vy, vz, pr];
                }
                found
            })
            .reduce(Found::default, Found::merge)
    }
}

/// Whether keys `a` and `b` are nodes of one strand at most `gap` apart.
#[inline(always)]
fn near_on_strand(a: u32, b: u32, gap: u32) -> bool {
    let node = (1 << NODE_BITS) - 1;
    (a >> NODE_BITS) == (b >> NODE_BITS) && (a & node).abs_diff(b & node) <= gap
}

/// Calls `hit(j, r²)` for every sorted particle `j` in `s .. e` with `r² < h2`, in order. The
/// distance test runs on blocks of eight (vectorised), the calls only for the hits. Ranges
/// are short (a few cells' particles), so the last block is not done one by one but masked:
/// the position arrays carry [`PADDING`] entries past the last particle for it to read.
#[inline(always)]
fn scan(
    s: usize,
    e: usize,
    [xa, ya, za]: [f32; 3],
    h2: f32,
    (x, y, z): (&[f32], &[f32], &[f32]),
    mut hit: impl FnMut(usize, f32),
) {
    let mut at = s;
    while at < e {
        let (Some(bx), Some(by), Some(bz)) = (
            x.get(at..at + PADDING),
            y.get(at..at + PADDING),
            z.get(at..at + PADDING),
        ) else {
            return;
        };
        let mut d2 = [0.0f32; PADDING];
        let mut mask = 0u32;
        for l in 0..PADDING {
            let (dx, dy, dz) = (xa - bx[l], ya - by[l], za - bz[l]);
            d2[l] = dx * dx + dy * dy + dz * dz;
            mask |= u32::from(d2[l] < h2) << l;
        }
        if e - at < PADDING {
            mask &= (1 << (e - at)) - 1;
        }
        while mask != 0 {
            let l = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            hit(at + l, d2[l]);
        }
        at += PADDING;
    }
}
