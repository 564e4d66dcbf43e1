//! Capped neighbour lists (Sánchez-Banderas 2015, Sec. 4, Algorithm 1 line 6): the paper's
//! rough k-nearest list. For each particle, in sorted order, the 27 cells around it are
//! scanned — its own bucket first, then the other buckets in ascending order, each once — and
//! the first `cap` particles within `h` are kept. The order is a function of the positions
//! only, so lists (and truncation) are the same on any number of threads.

use rayon::prelude::*;

use super::forces::SortedParticles;
use super::grid::{bucket_of, cell_of, Grid};
use super::{SphParams, CHUNK};

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

    /// Rebuilds every list from the sorted particles.
    pub fn build(&mut self, grid: &Grid, particles: &SortedParticles, params: &SphParams) -> Found {
        let cap = self.cap;
        let n = particles.position.len();
        let h2 = params.smoothing_length * params.smoothing_length;
        self.list[..n * cap]
            .par_chunks_mut(CHUNK * cap)
            .zip(self.count[..n].par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, (list, count))| {
                let mut found = Found::default();
                for (k, slot) in count.iter_mut().enumerate() {
                    let a = c * CHUNK + k;
                    let mine = &mut list[k * cap..(k + 1) * cap];
                    let (kept, all) = neighbours_of(a, grid, particles, params, h2, mine);
                    *slot = kept;
                    found.kept += u64::from(kept);
                    found.truncated += u64::from(all - kept);
                    found.max_found = found.max_found.max(all);
                }
                found
            })
            .reduce(Found::default, Found::merge)
    }
}

/// The buckets of the 27 cells around `cell`, own bucket first, each bucket once.
fn buckets_around(cell: [i32; 3], mask: u32) -> ([u32; 27], usize) {
    let own = bucket_of(cell, mask);
    let mut others = [0u32; 26];
    let mut n = 0;
    for dx in -1..=1 {
        for dy in -1..=1 {
            for dz in -1..=1 {
                let b = bucket_of([cell[0] + dx, cell[1] + dy, cell[2] + dz], mask);
                if b != own {
                    others[n] = b;
                    n += 1;
                }
            }
        }
    }
    let others = &mut others[..n];
    others.sort_unstable();
    let mut out = [own; 27];
    let mut m = 1;
    for (i, &b) in others.iter().enumerate() {
        if i == 0 || b != others[i - 1] {
            out[m] = b;
            m += 1;
        }
    }
    (out, m)
}

/// Fills `out` with the first neighbours of sorted particle `a`; returns (kept, found).
fn neighbours_of(
    a: usize,
    grid: &Grid,
    particles: &SortedParticles,
    params: &SphParams,
    h2: f32,
    out: &mut [u32],
) -> (u32, u32) {
    let x = particles.position[a];
    let strand = particles.strand[a];
    let node = particles.node[a];
    let (buckets, count) = buckets_around(cell_of(x, grid.inverse_cell()), grid.mask());
    let mut kept = 0usize;
    let mut found = 0u32;
    for &b in &buckets[..count] {
        let range = grid.bucket_start[b as usize]..grid.bucket_start[b as usize + 1];
        for j in range {
            let j = j as usize;
            if j == a {
                continue;
            }
            let d = x - particles.position[j];
            if d.dot(d) >= h2 {
                continue;
            }
            if particles.strand[j] == strand
                && particles.node[j].abs_diff(node) <= params.same_strand_gap
            {
                continue;
            }
            found += 1;
            if kept < out.len() {
                out[kept] = j as u32;
                kept += 1;
            }
        }
    }
    (kept as u32, found)
}
