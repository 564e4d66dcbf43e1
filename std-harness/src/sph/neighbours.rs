//! Capped neighbour lists (Sánchez-Banderas 2015, Sec. 4, Algorithm 1 line 6: the paper's
//! rough k-nearest list), with the density and pressure of each particle (line 7) taken in
//! the same pass, while the distances are at hand.
//!
//! Each particle's cell comes from its sorted position; the nine rows around it
//! ([`RowsAround`]) are hashed once per run of particles in one row, and the 27 cells are read
//! as nine ranges of three cells (more where the row crosses into the next brick) of the
//! sorted structure-of-arrays positions, gathered once per cell (the sorted particles of a cell
//! are consecutive and share them: on Mannequin A 71 % of particles gather, and sharing cut
//! the search by ~13 %). The candidates are tested eight at a
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
use super::grid::{cell_of, Grid, RowsAround, MAX_RANGES};
use super::{SphParams, CHUNK};

/// Entries past the last particle in the position arrays: a range is copied as this many
/// candidates whatever its length.
pub const PADDING: usize = 16;

/// Lanes of the distance test.
const LANES: usize = 8;

/// Bits of a particle's key holding its node index; the strand is above them.
pub const NODE_BITS: u32 = 8;

/// One list of at most `cap` neighbours per particle, in sorted indices.
#[derive(Clone, Debug)]
pub struct NeighbourLists {
    cap: usize,
    /// Every list: chunk `c`'s lists one after another from `c · (CHUNK · cap + 1)`.
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
            list: vec![0; particles.div_ceil(CHUNK) * (CHUNK * cap + 1)],
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
        self.list
            .par_chunks_mut(CHUNK * cap + 1)
            .zip(self.start[..n].par_chunks_mut(CHUNK))
            .zip(self.count[..n].par_chunks_mut(CHUNK))
            .zip(density.par_chunks_mut(CHUNK))
            .zip(packed.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, ((((list, start), count), density), packed))| {
                let mut found = Found::default();
                let mut rows = RowsAround::NONE;
                let mut ranges = [(0u32, 0u32); MAX_RANGES];
                let mut candidates = Candidates::new();
                // The cell whose 27 cells `candidates` holds, all of them: sorted particles of
                // one cell are consecutive and share their candidates.
                let mut gathered: Option<[i32; 3]> = None;
                let mut used = 0usize;
                for k in 0..count.len() {
                    let a = c * CHUNK + k;
                    let me = [x[a], y[a], z[a]];
                    let cell = cell_of(me.into(), inverse_cell);
                    rows.update(cell, row_mask);
                    let my_key = key[a];
                    // One entry of room past the cap: a hit is written whether it is kept or
                    // not, and counted only if it is (no branch on it).
                    let mine = &mut list[used..used + cap + 1];
                    let mut kept = 0usize;
                    let mut all = 0u32;
                    // ρ / (315/(64π h⁹)): own mass, then the kept neighbours in list order.
                    let mut sum = mass[a] * h2 * h2 * h2;
                    let mut hit = |j: usize, d2: f32| {
                        let (Some(&other), Some(&m)) = (key.get(j), mass.get(j)) else {
                            return;
                        };
                        let neighbour = (j != a) & !near_on_strand(other, my_key, gap);
                        let keep = neighbour & (kept < cap);
                        mine[kept.min(cap)] = j as u32;
                        let w = h2 - d2;
                        // Adding +0 leaves the sum's bits as they are.
                        sum += if keep { m * (w * w * w) } else { 0.0 };
                        kept += usize::from(keep);
                        all += u32::from(neighbour);
                    };
                    if gathered != Some(cell) {
                        let m = rows.ranges(grid, cell, &mut ranges);
                        candidates.clear();
                        for &(s, e) in &ranges[..m] {
                            candidates.take(s as usize, e as usize, (x, y, z), me, h2, &mut hit);
                        }
                        // More than the buffer holds was tested in turns for this particle
                        // and let go: the next particle of the cell gathers again.
                        gathered = (!candidates.flushed).then_some(cell);
                    }
                    candidates.test(me, h2, &mut hit);
                    start[k] = (c * (CHUNK * cap + 1) + used) as u32;
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

/// Whether keys `a` and `b` are nodes of one strand at most `gap` apart (no branch).
#[inline(always)]
fn near_on_strand(a: u32, b: u32, gap: u32) -> bool {
    let node = (1 << NODE_BITS) - 1;
    ((a >> NODE_BITS) == (b >> NODE_BITS)) & ((a & node).abs_diff(b & node) <= gap)
}

/// Candidates held for one distance test: room for this many (most particles have a few
/// dozen; more are tested in turns). One bit each in the test's mask.
const ROOM: usize = 128;

/// The candidates of one particle, gathered from its ranges into one contiguous run so that
/// the distance test runs over them in full blocks of eight, not a part-filled block per
/// range. A range of at most [`PADDING`] is copied as that many whatever its length (no
/// branch on the length; the lanes past it are overwritten by the next range or masked off).
struct Candidates {
    x: [f32; ROOM + PADDING],
    y: [f32; ROOM + PADDING],
    z: [f32; ROOM + PADDING],
    index: [u32; ROOM + PADDING],
    d2: [f32; ROOM + PADDING],
    len: usize,
    /// Whether candidates were tested and dropped since [`Candidates::clear`] (more than
    /// [`ROOM`]): then the buffer no longer holds them all.
    flushed: bool,
}

/// The sorted indices `0 .. PADDING`, added to a range's start.
const STEPS: [u32; PADDING] = {
    let mut steps = [0; PADDING];
    let mut l = 0;
    while l < PADDING {
        steps[l] = l as u32;
        l += 1;
    }
    steps
};

impl Candidates {
    fn new() -> Candidates {
        Candidates {
            x: [0.0; ROOM + PADDING],
            y: [0.0; ROOM + PADDING],
            z: [0.0; ROOM + PADDING],
            index: [0; ROOM + PADDING],
            d2: [0.0; ROOM + PADDING],
            len: 0,
            flushed: false,
        }
    }

    fn clear(&mut self) {
        self.len = 0;
        self.flushed = false;
    }

    /// Appends sorted particles `s .. e`, testing what is held first when there is no room.
    #[inline(always)]
    fn take(
        &mut self,
        s: usize,
        e: usize,
        xyz: (&[f32], &[f32], &[f32]),
        me: [f32; 3],
        h2: f32,
        hit: &mut impl FnMut(usize, f32),
    ) {
        let len = e.saturating_sub(s);
        if len <= PADDING && self.len + PADDING <= ROOM {
            self.copy(s, xyz);
            self.len += len;
        } else {
            self.take_long(s, e, xyz, me, h2, hit);
        }
    }

    /// [`Candidates::take`] for a long range or a full buffer.
    #[inline(never)]
    fn take_long(
        &mut self,
        mut s: usize,
        e: usize,
        xyz: (&[f32], &[f32], &[f32]),
        me: [f32; 3],
        h2: f32,
        hit: &mut impl FnMut(usize, f32),
    ) {
        while s < e {
            if self.len + PADDING > ROOM {
                self.test(me, h2, hit);
                self.len = 0;
                self.flushed = true;
            }
            self.copy(s, xyz);
            let taken = (e - s).min(PADDING);
            self.len += taken;
            s += taken;
        }
    }

    /// Copies sorted particles `s .. s + PADDING` to the end of the held ones (not counted).
    /// Both ends have the room: the position arrays [`PADDING`] past the last particle, the
    /// buffer [`PADDING`] past [`ROOM`].
    #[inline(always)]
    fn copy(&mut self, s: usize, (x, y, z): (&[f32], &[f32], &[f32])) {
        let at = self.len;
        self.x[at..at + PADDING].copy_from_slice(&x[s..s + PADDING]);
        self.y[at..at + PADDING].copy_from_slice(&y[s..s + PADDING]);
        self.z[at..at + PADDING].copy_from_slice(&z[s..s + PADDING]);
        let first = s as u32;
        // On a fixed-size array, so that it is four vector adds, not sixteen scalar ones.
        if let Ok(index) = <&mut [u32; PADDING]>::try_from(&mut self.index[at..at + PADDING]) {
            for (i, l) in index.iter_mut().zip(STEPS) {
                *i = first + l;
            }
        }
    }

    /// Calls `hit(j, r²)` for every held candidate `j` with `r² < h2`, in order. The
    /// distance test runs on blocks of eight (vectorised) into one mask for all of them;
    /// then one loop over its set bits calls `hit`.
    #[inline(always)]
    fn test(&mut self, me: [f32; 3], h2: f32, hit: &mut impl FnMut(usize, f32)) {
        let blocks = self.len.div_ceil(LANES);
        let mut mask = 0u128;
        for (b, (((bx, by), bz), d2)) in self
            .x
            .chunks_exact(LANES)
            .zip(self.y.chunks_exact(LANES))
            .zip(self.z.chunks_exact(LANES))
            .zip(self.d2.chunks_exact_mut(LANES))
            .take(blocks)
            .enumerate()
        {
            let (Ok(bx), Ok(by), Ok(bz)) = (bx.try_into(), by.try_into(), bz.try_into()) else {
                continue;
            };
            // Into a local array first: stores into `self.d2` between the loads of
            // `self.x` would keep the compiler from vectorising.
            let (bits, r2) = block(bx, by, bz, me, h2);
            d2.copy_from_slice(&r2);
            mask |= u128::from(bits) << (b * LANES);
        }
        if self.len < ROOM {
            mask &= (1u128 << self.len) - 1;
        }
        while mask != 0 {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            hit(self.index[i] as usize, self.d2[i]);
        }
    }
}

/// A bit per candidate with `r² < h2`, and `r²` from `me` to eight candidates.
#[inline(always)]
fn block(
    x: &[f32; LANES],
    y: &[f32; LANES],
    z: &[f32; LANES],
    [xa, ya, za]: [f32; 3],
    h2: f32,
) -> (u32, [f32; LANES]) {
    let mut d2 = [0.0; LANES];
    let mut bits = [0u32; LANES];
    for l in 0..LANES {
        let (dx, dy, dz) = (xa - x[l], ya - y[l], za - z[l]);
        d2[l] = dx * dx + dy * dy + dz * dz;
        bits[l] = if d2[l] < h2 { 1 << l } else { 0 };
    }
    (bits.iter().fold(0, |m, &b| m | b), d2)
}
