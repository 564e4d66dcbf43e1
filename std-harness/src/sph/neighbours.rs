//! Capped neighbour lists (Sánchez-Banderas 2015, Sec. 4, Algorithm 1 line 6: the paper's
//! rough k-nearest list), with the density and pressure of each particle (line 7) taken in
//! the same pass, while the distances are at hand.
//!
//! Each particle's cell comes from its sorted position; the nine rows around it
//! ([`RowsAround`]) are hashed once per run of particles in one row, and the 27 cells are read
//! as nine ranges of three cells (more where the row crosses into the next brick) of the
//! sorted structure-of-arrays positions, looked up once per cell (the sorted particles of a
//! cell are consecutive). Each range is tested where it lies, four candidates at a time for
//! `r² < h²` (no square root; one packed compare on x86-64), in pieces of eight with no branch
//! on the range's length, and the hits of many pieces are taken from one mask
//! ([`test_ranges`]): what costs here is mispredicted branches more than instructions (session
//! 4 copied the candidates into one run to avoid them; valgrind's branch simulation counts 7.5 M
//! mispredictions per 7 steps of Mannequin A now, 11.6 M then, and 1,190 instructions per
//! particle against 1,930). The first `cap` hits (that are not the
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

/// Entries past the last particle in the position arrays: a range is tested in pieces of
/// [`SHORT`] candidates whatever its length (at least that many).
pub const PADDING: usize = 16;

/// Lanes of the distance test: one SSE register on the x86-64 baseline.
const LANES: usize = 4;

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
            velocity,
            mass,
            key,
            density,
            packed,
            ..
        } = p;
        let (x, y, z, mass, key, velocity) =
            (&x[..], &y[..], &z[..], &mass[..], &key[..], &velocity[..]);
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
                // The cell whose 27 cells `ranges` holds: sorted particles of one cell are
                // consecutive and share them.
                let mut ranged: Option<([i32; 3], usize)> = None;
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
                    let m = match ranged {
                        Some((of, m)) if of == cell => m,
                        _ => {
                            let m = rows.ranges(grid, cell, &mut ranges);
                            ranged = Some((cell, m));
                            m
                        }
                    };
                    test_ranges(&ranges[..m], (x, y, z), me, h2, &mut hit);
                    start[k] = (c * (CHUNK * cap + 1) + used) as u32;
                    count[k] = kept as u32;
                    used += kept;
                    found.kept += kept as u64;
                    found.truncated += u64::from(all) - kept as u64;
                    found.max_found = found.max_found.max(all);
                    let rho = c6 * sum;
                    let pr = (stiffness * (rho - rest)).max(0.0);
                    density[k] = rho;
                    let [vx, vy, vz] = velocity[a];
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

/// Pieces of ranges whose hits are collected in one mask, [`SHORT`] bits each: the nine
/// ranges of most particles and a few long ones, so that most particles take their hits in
/// one loop.
const GROUP: usize = 16;

/// A range is tested in pieces of this many particles: two blocks, whatever its length.
const SHORT: usize = 2 * LANES;

const _: () = assert!(PADDING >= SHORT && GROUP * SHORT <= 128);

/// Calls `hit(j, r²)` for every sorted particle `j` of `ranges` with `r² < h2`, in order
/// (range by range, each in sorted order), testing them where they lie. A range is tested in
/// pieces of [`SHORT`] (most ranges are one piece: a range holds about five particles on a
/// head), each as two blocks of [`LANES`] with the lanes past the range's end masked off — the
/// position arrays have [`PADDING`] entries past the last particle — and the hits of up to
/// [`GROUP`] pieces go into one mask, so that neither a range's length nor its hits cost a
/// branch of their own; the few hits are then taken from the mask in one loop.
#[inline(always)]
fn test_ranges(
    ranges: &[(u32, u32)],
    xyz: (&[f32], &[f32], &[f32]),
    me: [f32; 3],
    h2: f32,
    hit: &mut impl FnMut(usize, f32),
) {
    let (x, y, z) = xyz;
    let mut mask = 0u128;
    let mut starts = [0usize; GROUP];
    let mut held = 0;
    for &(s, e) in ranges {
        let (mut s, e) = (s as usize, e.max(s) as usize);
        // Bounded: `s` moves on by SHORT a pass until it reaches `e`.
        loop {
            if held == GROUP {
                take_hits(&mut mask, &starts, xyz, me, hit);
                held = 0;
            }
            let mut bits = 0;
            for block in 0..SHORT / LANES {
                let at = s + block * LANES;
                if let (Some(bx), Some(by), Some(bz)) = (lanes(x, at), lanes(y, at), lanes(z, at)) {
                    bits |= within(bx, by, bz, me, h2) << (block * LANES);
                }
            }
            bits &= (1 << (e - s).min(SHORT)) - 1;
            mask |= u128::from(bits) << (held * SHORT);
            starts[held] = s;
            held += 1;
            s += SHORT;
            if s >= e {
                break;
            }
        }
    }
    take_hits(&mut mask, &starts, xyz, me, hit);
}

/// Calls `hit` for each set bit of `mask` (bit `SHORT · g + l`: particle `starts[g] + l`), in
/// bit order, and clears the mask.
#[inline(always)]
fn take_hits(
    mask: &mut u128,
    starts: &[usize; GROUP],
    (x, y, z): (&[f32], &[f32], &[f32]),
    me: [f32; 3],
    hit: &mut impl FnMut(usize, f32),
) {
    while *mask != 0 {
        let bit = mask.trailing_zeros() as usize;
        *mask &= *mask - 1;
        let j = starts[bit / SHORT] + bit % SHORT;
        let (Some(&xj), Some(&yj), Some(&zj)) = (x.get(j), y.get(j), z.get(j)) else {
            continue;
        };
        hit(j, distance_squared(me, [xj, yj, zj]));
    }
}

/// The `LANES` entries of `v` from `at`.
#[inline(always)]
fn lanes(v: &[f32], at: usize) -> Option<&[f32; LANES]> {
    v.get(at..at + LANES)?.try_into().ok()
}

/// `|a − b|²`, summed as `(dx² + dy²) + dz²` — the order of [`within`] and of the brute-force
/// reference.
#[inline(always)]
fn distance_squared([xa, ya, za]: [f32; 3], [x, y, z]: [f32; 3]) -> f32 {
    let (dx, dy, dz) = (xa - x, ya - y, za - z);
    dx * dx + dy * dy + dz * dz
}

/// A bit per candidate with `r² < h2`, from `me` to four candidates, with the bits of
/// [`distance_squared`]. On x86-64, one packed subtract, multiply and add per axis, a packed
/// compare and its sign mask (`movmskps`): written lane by lane, LLVM's vectoriser pairs the
/// axes of one lane instead of the lanes of one axis and shuffles (≈ 3× the instructions).
#[inline(always)]
fn within(x: &[f32; LANES], y: &[f32; LANES], z: &[f32; LANES], me: [f32; 3], h2: f32) -> u32 {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    // SAFETY: `within_sse2` needs SSE2, which this build has (the cfg above: x86-64's
    // baseline); it reads only its arguments.
    unsafe {
        within_sse2(x, y, z, me, h2)
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    within_scalar(x, y, z, me, h2)
}

/// [`within`] lane by lane.
#[inline(always)]
#[cfg_attr(all(target_arch = "x86_64", target_feature = "sse2"), allow(dead_code))]
fn within_scalar(
    x: &[f32; LANES],
    y: &[f32; LANES],
    z: &[f32; LANES],
    me: [f32; 3],
    h2: f32,
) -> u32 {
    let mut bits = 0;
    for l in 0..LANES {
        bits |= u32::from(distance_squared(me, [x[l], y[l], z[l]]) < h2) << l;
    }
    bits
}

/// [`within`] in SSE2: each operation is the IEEE single-precision one of the scalar form,
/// in the same order, so the mask is the same bit for bit.
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
#[target_feature(enable = "sse2")]
fn within_sse2(x: &[f32; LANES], y: &[f32; LANES], z: &[f32; LANES], me: [f32; 3], h2: f32) -> u32 {
    use core::arch::x86_64::{
        _mm_add_ps, _mm_cmplt_ps, _mm_movemask_ps, _mm_mul_ps, _mm_set1_ps, _mm_setr_ps, _mm_sub_ps,
    };
    let squared = |v: &[f32; LANES], m: f32| {
        let d = _mm_sub_ps(_mm_set1_ps(m), _mm_setr_ps(v[0], v[1], v[2], v[3]));
        _mm_mul_ps(d, d)
    };
    let d2 = _mm_add_ps(
        _mm_add_ps(squared(x, me[0]), squared(y, me[1])),
        squared(z, me[2]),
    );
    _mm_movemask_ps(_mm_cmplt_ps(d2, _mm_set1_ps(h2))) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_packed_distance_test_is_the_scalar_one_bit_for_bit() {
        let mut state = 0x9e37_79b9u32;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state as f32 / u32::MAX as f32) * 0.02 - 0.01
        };
        let h2 = 0.0045f32 * 0.0045;
        let mut hits = 0;
        for round in 0..20_000 {
            let me = [next(), next(), next()];
            let mut v = [[0.0f32; LANES]; 3];
            for axis in &mut v {
                for c in axis.iter_mut() {
                    *c = next();
                }
            }
            // Edge cases: a candidate exactly at `h`, at the particle, and not finite.
            match round % 4 {
                0 => v[0][0] = me[0] + 0.0045,
                1 => [v[0][1], v[1][1], v[2][1]] = me,
                2 => v[1][2] = f32::NAN,
                _ => v[2][3] = f32::INFINITY,
            }
            let packed = within(&v[0], &v[1], &v[2], me, h2);
            assert_eq!(
                packed,
                within_scalar(&v[0], &v[1], &v[2], me, h2),
                "{me:?} {v:?}"
            );
            hits += packed.count_ones();
        }
        assert!(hits > 1_000, "the test should see hits: {hits}");
    }
}
