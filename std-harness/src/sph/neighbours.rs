//! Candidate lists (Sánchez-Banderas 2015, Sec. 4, Algorithm 1 line 6): each particle's
//! list of the particles within `h + skin` of it, found through the grid ([`super::grid`]) in
//! the frame the skin is measured in ([`super::skin`]), when the lists are rebuilt. Between
//! rebuilds every step filters them by the distance `h` itself ([`super::density`]), so a
//! step's neighbours do not depend on when the lists were built.
//!
//! Each particle's cell comes from its sorted position; the nine rows around it
//! ([`RowsAround`]) are computed once per run of particles in one row, and the 27 cells are read
//! as nine ranges of three cells (more where the row wraps around) of the sorted
//! structure-of-arrays positions, looked up once per cell (the sorted particles of a cell are
//! consecutive), the empty ones dropped; a particle alone in its 27 cells tests nothing. Each
//! range is tested where it lies, four candidates at a time for
//! `r² < R²` (no square root; one packed compare on x86-64), in pieces of eight with no branch
//! on the range's length, and the hits of many pieces are taken from one mask, a byte a piece
//! ([`test_ranges`]). A particle itself and its own strand's near nodes are never candidates.
//!
//! Lists are stored compactly: a chunk of particles writes its lists one after another into
//! its own vector, which keeps its capacity from one rebuild to the next.

#![deny(clippy::too_many_lines, clippy::too_many_arguments)]
use hairsim_core::Vec3;
use rayon::prelude::*;

use super::grid::{cell_of, Grid, Layout, RowsAround, MAX_RANGES};
use super::CHUNK;

/// Entries past the last particle in the position arrays: a range is tested in pieces of
/// [`SHORT`] candidates whatever its length (at least that many).
pub const PADDING: usize = 16;

/// Lanes of the distance test: one SSE register on the x86-64 baseline.
const LANES: usize = 4;

/// Bits of a particle's key holding its node index; the strand is above them.
pub const NODE_BITS: u32 = 8;

/// Candidates a particle has room for when the lists are first sized: a step allocates only
/// when a chunk of particles has more candidates than ever before and more than this many a
/// particle.
pub const ROOM: usize = 8;

/// The particles in the grid's sorted order, as the search reads them: positions in the
/// skin's frame as structure of arrays (with [`PADDING`] entries past the last, never a
/// candidate) and keys.
#[derive(Clone, Debug, Default)]
pub struct Sorted {
    /// Positions, m: x.
    pub x: Vec<f32>,
    /// Positions, m: y.
    pub y: Vec<f32>,
    /// Positions, m: z.
    pub z: Vec<f32>,
    /// Keys: `strand << NODE_BITS | node`.
    pub key: Vec<u32>,
}

impl Sorted {
    /// Buffers for `n` particles.
    #[must_use]
    pub fn new(n: usize) -> Sorted {
        Sorted {
            x: vec![0.0; n + PADDING],
            y: vec![0.0; n + PADDING],
            z: vec![0.0; n + PADDING],
            key: vec![0; n],
        }
    }

    /// Fills the sorted arrays: sorted particle `k` is particle `order[k]`, at `frame[p]`,
    /// with key `key[p]` (Algorithm 1 line 5), chunk by chunk in parallel.
    pub fn gather(&mut self, order: &[u32], frame: &[[f32; 3]], key: &[u32]) {
        let n = order.len().min(self.key.len());
        (
            self.x[..n].par_chunks_mut(CHUNK),
            self.y[..n].par_chunks_mut(CHUNK),
            self.z[..n].par_chunks_mut(CHUNK),
            self.key[..n].par_chunks_mut(CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(c, (x, y, z, k))| {
                for (i, &p) in order[c * CHUNK..].iter().take(x.len()).enumerate() {
                    let (Some(position), Some(&own)) = (frame.get(p as usize), key.get(p as usize))
                    else {
                        continue;
                    };
                    [x[i], y[i], z[i]] = *position;
                    k[i] = own;
                }
            });
    }
}

/// Every sorted particle's candidate list, in sorted indices.
#[derive(Clone, Debug, Default)]
pub struct CandidateLists {
    /// Chunk `c`'s lists (sorted particles `c · CHUNK ..`), one after another.
    pub lists: Vec<Vec<u32>>,
    /// Where each sorted particle's list starts in its chunk's vector.
    pub start: Vec<u32>,
    /// How many candidates each sorted particle has.
    pub count: Vec<u32>,
}

impl CandidateLists {
    /// Lists for `particles` particles, with room for [`ROOM`] candidates a particle.
    #[must_use]
    pub fn new(particles: usize) -> CandidateLists {
        CandidateLists {
            lists: (0..particles.div_ceil(CHUNK))
                .map(|_| Vec::with_capacity(CHUNK * ROOM))
                .collect(),
            start: vec![0; particles],
            count: vec![0; particles],
        }
    }

    /// The candidates of sorted particle `k`.
    #[inline]
    #[must_use]
    pub fn of(&self, k: usize) -> &[u32] {
        let (start, count) = (self.start[k] as usize, self.count[k] as usize);
        self.lists
            .get(k / CHUNK)
            .and_then(|l| l.get(start..start + count))
            .unwrap_or(&[])
    }

    /// Rebuilds every list from the sorted particles `p` in `grid`: the particles within
    /// `reach` of each, but itself and its own strand's nodes at most `gap` apart. Returns how
    /// many candidates there are in all.
    pub fn build(&mut self, grid: &Grid, p: &Sorted, reach: f32, gap: u32) -> u64 {
        let n = p.key.len();
        let search = Search {
            xyz: (&p.x, &p.y, &p.z),
            key: &p.key,
            gap,
            reach_squared: reach * reach,
            grid,
            inverse_cell: grid.inverse_cell(),
            layout: grid.layout(),
        };
        self.lists
            .par_iter_mut()
            .zip(self.start[..n].par_chunks_mut(CHUNK))
            .zip(self.count[..n].par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, ((list, start), count))| {
                search.chunk(c, list, start, count);
                list.len() as u64
            })
            .sum()
    }
}

/// What every chunk's search reads: the sorted particles, the grid, and the parameters as
/// the search uses them.
struct Search<'a> {
    xyz: (&'a [f32], &'a [f32], &'a [f32]),
    key: &'a [u32],
    gap: u32,
    reach_squared: f32,
    grid: &'a Grid,
    inverse_cell: f32,
    layout: Layout,
}

impl Search<'_> {
    /// Sorted particle `a`'s position.
    #[inline(always)]
    fn at(&self, a: usize) -> [f32; 3] {
        [self.xyz.0[a], self.xyz.1[a], self.xyz.2[a]]
    }

    /// Every list of chunk `c`, one particle after another.
    fn chunk(&self, c: usize, list: &mut Vec<u32>, start: &mut [u32], count: &mut [u32]) {
        list.clear();
        let mut rows = RowsAround::NONE;
        let mut ranges = [(0u32, 0u32); MAX_RANGES];
        // The cell whose 27 cells `ranges` holds, and how many: sorted particles of one cell
        // are consecutive and share them.
        let mut ranged: Option<([i32; 3], usize)> = None;
        // Particles in those cells, the particle itself among them.
        let mut around = 0u32;
        for (k, (start, count)) in start.iter_mut().zip(count.iter_mut()).enumerate() {
            let a = c * CHUNK + k;
            let me = self.at(a);
            let cell = cell_of(Vec3::from_array(me), self.inverse_cell);
            rows.update(cell, self.layout);
            let m = match ranged {
                Some((of, m)) if of == cell => m,
                _ => {
                    let all = rows.ranges(self.grid, cell, &mut ranges);
                    let m;
                    (m, around) = without_empty(&mut ranges, all);
                    ranged = Some((cell, m));
                    m
                }
            };
            let first = list.len();
            // Alone in its 27 cells: no candidate, and nothing to test.
            if around <= 1 {
                *start = first as u32;
                *count = 0;
                continue;
            }
            let own = self.key.get(a).copied().unwrap_or(0);
            let (key, gap) = (self.key, self.gap);
            test_ranges(
                &ranges[..m],
                self.xyz,
                a,
                me,
                self.reach_squared,
                &mut |j| {
                    let other = key.get(j).copied().unwrap_or(own);
                    if !near_on_strand(other, own, gap) {
                        list.push(j as u32);
                    }
                },
            );
            *start = first as u32;
            *count = (list.len() - first) as u32;
        }
    }
}

/// The first `m` of `ranges` without the empty ones, in their order (the particle's own range,
/// never empty, stays first), without a branch on their lengths; returns how many remain and
/// the particles they hold.
#[inline(always)]
fn without_empty(ranges: &mut [(u32, u32); MAX_RANGES], m: usize) -> (usize, u32) {
    let (mut kept, mut total) = (0, 0u32);
    for k in 0..m.min(MAX_RANGES) {
        let (s, e) = ranges[k];
        let length = e.saturating_sub(s);
        ranges[kept] = (s, e);
        kept += usize::from(length > 0);
        total += length;
    }
    (kept, total)
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

const _: () = assert!(PADDING >= SHORT && SHORT == 8 && GROUP * SHORT == 128);

/// A piece's hits past the end of its range are masked off with `TAIL[(e − s).min(SHORT)]`:
/// a table, not a variable shift.
const TAIL: [u8; SHORT + 1] = {
    let mut tail = [0u8; SHORT + 1];
    let mut k = 0;
    while k < SHORT {
        tail[k + 1] = tail[k] << 1 | 1;
        k += 1;
    }
    tail
};

/// Calls `hit(j)` for every sorted particle `j` of `ranges` but `own` with `r² < reach²`
/// (`reach_squared`) from `me`, in order (range by range, each in sorted order), testing them
/// where they lie. A range is tested in pieces of [`SHORT`] (most ranges are one or two
/// pieces), each as two blocks of [`LANES`] with the lanes past the range's end masked off —
/// the position arrays have [`PADDING`] entries past the last particle — and the hits of up to
/// [`GROUP`] pieces go into one mask, a byte a piece, so that neither a range's length nor its
/// hits cost a branch of their own; the hits are then taken from the mask in one loop.
#[inline(always)]
fn test_ranges(
    ranges: &[(u32, u32)],
    xyz: (&[f32], &[f32], &[f32]),
    own: usize,
    me: [f32; 3],
    reach_squared: f32,
    hit: &mut impl FnMut(usize),
) {
    let mut hits = [0u8; GROUP];
    let mut starts = [0u32; GROUP];
    let mut held = 0;
    for (r, &(s, e)) in ranges.iter().enumerate() {
        let e = e.max(s);
        let mut s = s;
        // Bounded: `s` moves on by SHORT a pass until it reaches `e`.
        loop {
            if held == GROUP {
                take_hits(u128::from_le_bytes(hits), &starts, hit);
                hits = [0; GROUP];
                held = 0;
            }
            let tail = TAIL[((e - s) as usize).min(SHORT)];
            // The particle itself lies in the first range (its own row): dropped here.
            let itself = if r == 0 { not_at(own, s) } else { u8::MAX };
            hits[held] = piece(xyz, s as usize, me, reach_squared) & tail & itself;
            starts[held] = s;
            held += 1;
            s += SHORT as u32;
            if s >= e {
                break;
            }
        }
    }
    take_hits(u128::from_le_bytes(hits), &starts, hit);
}

/// All bits of a piece starting at `s` but particle `own`'s.
#[inline(always)]
fn not_at(own: usize, s: u32) -> u8 {
    let offset = own.wrapping_sub(s as usize);
    if offset < SHORT {
        !(1 << offset)
    } else {
        u8::MAX
    }
}

/// A bit per candidate `s .. s + SHORT` with `r² < reach_squared` from `me` (all of them read:
/// the arrays are padded), as two blocks of [`LANES`].
#[inline(always)]
fn piece((x, y, z): (&[f32], &[f32], &[f32]), s: usize, me: [f32; 3], reach_squared: f32) -> u8 {
    let (Some(bx), Some(by), Some(bz)) = (block(x, s), block(y, s), block(z, s)) else {
        return 0;
    };
    let ((Some(x0), Some(x1)), (Some(y0), Some(y1)), (Some(z0), Some(z1))) =
        (halves(bx), halves(by), halves(bz))
    else {
        return 0;
    };
    let low = within(x0, y0, z0, me, reach_squared);
    let high = within(x1, y1, z1, me, reach_squared);
    (low | high << LANES) as u8
}

/// Calls `hit` for each set bit of `mask` (bit `SHORT · g + l`: particle `starts[g] + l`), in
/// bit order.
#[inline(always)]
fn take_hits(mut mask: u128, starts: &[u32; GROUP], hit: &mut impl FnMut(usize)) {
    while mask != 0 {
        let bit = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        hit(starts[bit / SHORT] as usize + bit % SHORT);
    }
}

/// The two blocks of a piece.
#[inline(always)]
fn halves(v: &[f32; SHORT]) -> (Option<&[f32; LANES]>, Option<&[f32; LANES]>) {
    (v.first_chunk::<LANES>(), v.last_chunk::<LANES>())
}

/// The `SHORT` entries of `v` from `at`.
#[inline(always)]
fn block(v: &[f32], at: usize) -> Option<&[f32; SHORT]> {
    v.get(at..at + SHORT)?.try_into().ok()
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
    fn empty_ranges_are_dropped_in_order_and_the_particles_counted() {
        let mut ranges = [(0u32, 0u32); MAX_RANGES];
        let given = [(4, 6), (9, 9), (1, 2), (7, 7), (3, 3), (10, 15), (20, 20)];
        ranges[..given.len()].copy_from_slice(&given);
        // Past `m`, nothing is read.
        ranges[given.len()] = (30, 40);
        let (kept, total) = without_empty(&mut ranges, given.len());
        assert_eq!(&ranges[..kept], &[(4, 6), (1, 2), (10, 15)]);
        assert_eq!(total, 2 + 1 + 5);
        // A particle alone in its cells: only its own range, holding itself.
        let mut alone = [(0u32, 0u32); MAX_RANGES];
        alone[0] = (8, 9);
        assert_eq!(without_empty(&mut alone, 9), (1, 1));
    }

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
