//! Capped neighbour lists (Sánchez-Banderas 2015, Sec. 4, Algorithm 1 line 6: the paper's
//! rough k-nearest list), with the density and pressure of each particle (line 7) taken in
//! the same pass, while the distances are at hand.
//!
//! Particles of one cell are consecutive in the sorted order and share the ranges of the 27
//! cells around them ([`Grid::ranges_around`], computed once per such run). For each particle
//! the candidates of each range — contiguous in the sorted structure-of-arrays positions — are
//! tested eight at a time for `r² < h²` (no square root), and the first `cap` that pass (and
//! are not the particle itself nor its own strand's near nodes) are kept, in scan order. The
//! order is a function of the positions only, so lists, truncation and every sum over a list
//! are the same on any number of threads.

use rayon::prelude::*;

use super::forces::{poly6_factor, SortedParticles};
use super::grid::Grid;
use super::{SphParams, CHUNK};

/// Lanes of the distance test, and entries past the last particle in the position arrays.
pub const PADDING: usize = 8;

/// One list of at most `cap` neighbours per particle, in sorted indices.
#[derive(Clone, Debug)]
pub struct NeighbourLists {
    cap: usize,
    /// `list[a · cap .. a · cap + count[a]]` are particle `a`'s neighbours.
    pub list: Vec<u32>,
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

/// What the search needs for one particle.
struct Particle {
    x: [f32; 3],
    strand: u32,
    node: u32,
}

impl NeighbourLists {
    /// Lists for `particles` particles of at most `cap` neighbours each.
    #[must_use]
    pub fn new(particles: usize, cap: usize) -> NeighbourLists {
        NeighbourLists {
            cap,
            list: vec![0; particles * cap],
            count: vec![0; particles],
        }
    }

    /// The neighbours of sorted particle `a`.
    #[inline]
    #[must_use]
    pub fn of(&self, a: usize) -> &[u32] {
        &self.list[a * self.cap..a * self.cap + self.count[a] as usize]
    }

    /// Rebuilds every list from the sorted particles, and writes each particle's density and
    /// pressure (`p.density`, `p.pressure`) and its packed force inputs (`p.packed`).
    pub fn build(&mut self, grid: &Grid, p: &mut SortedParticles, params: &SphParams) -> Found {
        let cap = self.cap;
        let n = p.mass.len();
        let h = params.smoothing_length;
        let h2 = h * h;
        let c6 = poly6_factor(h);
        let (stiffness, rest) = (params.stiffness, params.rest_density);
        let gap = params.same_strand_gap;
        let SortedParticles {
            x,
            y,
            z,
            velocity,
            mass,
            strand,
            node,
            cell,
            density,
            pressure,
            packed,
            ..
        } = p;
        let (x, y, z, mass, strand, node, cell, velocity) = (
            &x[..],
            &y[..],
            &z[..],
            &mass[..],
            &strand[..],
            &node[..],
            &cell[..],
            &velocity[..],
        );
        self.list[..n * cap]
            .par_chunks_mut(CHUNK * cap)
            .zip(self.count[..n].par_chunks_mut(CHUNK))
            .zip(density.par_chunks_mut(CHUNK))
            .zip(pressure.par_chunks_mut(CHUNK))
            .zip(packed.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, ((((list, count), density), pressure), packed))| {
                let mut found = Found::default();
                let mut ranges = ([(0u32, 0u32); 18], 0usize);
                for k in 0..count.len() {
                    let a = c * CHUNK + k;
                    // A new run of one cell: its ranges (the run shares them).
                    if k == 0 || cell[a] != cell[a - 1] {
                        ranges = grid.ranges_around(cell[a]);
                    }
                    let me = Particle {
                        x: [x[a], y[a], z[a]],
                        strand: strand[a],
                        node: node[a],
                    };
                    let mine = &mut list[k * cap..(k + 1) * cap];
                    let mut kept = 0usize;
                    let mut all = 0u32;
                    // ρ / (315/(64π h⁹)): own mass, then the kept neighbours in list order.
                    let mut sum = mass[a] * h2 * h2 * h2;
                    for &(s, e) in &ranges.0[..ranges.1] {
                        scan(s as usize, e as usize, &me, h2, (x, y, z), |j, d2| {
                            if j == a
                                || (strand[j] == me.strand && node[j].abs_diff(me.node) <= gap)
                            {
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
                    }
                    count[k] = kept as u32;
                    found.kept += kept as u64;
                    found.truncated += u64::from(all) - kept as u64;
                    found.max_found = found.max_found.max(all);
                    let rho = c6 * sum;
                    let pr = (stiffness * (rho - rest)).max(0.0);
                    density[k] = rho;
                    pressure[k] = pr;
                    let v = velocity[a];
                    packed[k] = [me.x[0], me.x[1], me.x[2], mass[a] / rho, v.x, v.y, v.z, pr];
                }
                found
            })
            .reduce(Found::default, Found::merge)
    }
}

/// Calls `hit(j, r²)` for every sorted particle `j` in `s .. e` with `r² < h2`, in order. The
/// distance test runs on blocks of eight (vectorised), the calls only for the hits. Ranges
/// are short (a few cells' particles), so the last block is not done one by one but masked:
/// the position arrays carry [`PADDING`] entries past the last particle for it to read.
#[inline(always)]
fn scan(
    s: usize,
    e: usize,
    me: &Particle,
    h2: f32,
    (x, y, z): (&[f32], &[f32], &[f32]),
    mut hit: impl FnMut(usize, f32),
) {
    let [xa, ya, za] = me.x;
    let len = e - s;
    let mut o = 0;
    while o < len {
        let at = s + o;
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
        if len - o < PADDING {
            mask &= (1 << (len - o)) - 1;
        }
        while mask != 0 {
            let l = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            hit(at + l, d2[l]);
        }
        o += PADDING;
    }
}
