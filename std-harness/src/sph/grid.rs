//! The spatial hash and the stable counting sort (Sánchez-Banderas 2015, Sec. 4; Algorithm 1
//! lines 2–4). Cells are cubes of the smoothing length `h`, so every neighbour of a particle
//! lies in its own cell or one of the 26 around it.
//!
//! Cells map to a power-of-two number of buckets laid out in *rows*: a row is 16 cells side by
//! side along x, rows are grouped in bricks of 4 × 4 ([`row_of`]) placed by a hash, and within
//! a row 16 consecutive buckets take `x mod 16`. Three cells side by side along x are then (but
//! where they cross from one row to the next) three consecutive buckets, which after the sort
//! are one contiguous run of particles: the 27 cells around a particle are read as at most 18
//! contiguous ranges of the sorted arrays, 9 in most places. Distinct cells may share a bucket
//! (rows collide); the neighbour search filters by distance.

use hairsim_core::Vec3;
use rayon::prelude::*;

/// Buckets in a row (consecutive cells along x).
pub const ROW: u32 = 16;

/// Integer cell coordinates of `p` for cells of size `1 / inverse_cell`. Coordinates are
/// clamped so that far-away (or non-finite) positions cannot overflow.
#[inline]
#[must_use]
pub fn cell_of(p: Vec3, inverse_cell: f32) -> [i32; 3] {
    [
        floor_clamped(p.x * inverse_cell),
        floor_clamped(p.y * inverse_cell),
        floor_clamped(p.z * inverse_cell),
    ]
}

/// `t.floor().clamp(-1e9, 1e9) as i32` (NaN gives 0), without `floorf`: on the x86-64
/// baseline (no SSE4.1 `roundss`) `floor` is a library call, and the hash takes three per
/// node. Truncation toward zero, minus one where that rounded a negative value up.
#[inline(always)]
#[must_use]
pub fn floor_clamped(t: f32) -> i32 {
    let t = t.clamp(-1.0e9, 1.0e9);
    let i = t as i32;
    i - i32::from((i as f32) > t)
}

/// The row holding cell `(x, y, z)`. Rows come in *bricks* of 4 × 4 rows (16 × 4 × 4 cells),
/// placed by the spatial hash of Teschner et al. 2003 on `(x div 16, y div 4, z div 4)`; within
/// a brick, `(y mod 4, z mod 4)` picks the row. The 9 rows around a cell then mostly lie in one
/// or two bricks: a few kilobytes of the sorted arrays rather than nine random places.
#[inline]
#[must_use]
pub fn row_of(x: i32, y: i32, z: i32, row_mask: u32) -> u32 {
    let brick = brick_x(x >> 4) ^ brick_yz(y, z);
    ((brick << 4) | ((y as u32 & 3) << 2) | (z as u32 & 3)) & row_mask
}

/// The x part of a brick's hash, for the brick `x div 16`.
#[inline(always)]
fn brick_x(brick: i32) -> u32 {
    (brick as u32).wrapping_mul(73_856_093)
}

/// The y and z parts of the hash of the brick holding rows `y`, `z`.
#[inline(always)]
fn brick_yz(y: i32, z: i32) -> u32 {
    ((y >> 2) as u32).wrapping_mul(19_349_663) ^ ((z >> 2) as u32).wrapping_mul(83_492_791)
}

/// The bucket of a cell.
#[inline]
#[must_use]
pub fn bucket_of(cell: [i32; 3], row_mask: u32) -> u32 {
    row_of(cell[0], cell[1], cell[2], row_mask) * ROW + (cell[0] as u32 & (ROW - 1))
}

/// Parts of the bucket range the counting sort's second pass sorts side by side.
const PARTS: usize = 64;

/// Particles per work item of the counting sort's first and last passes (a constant of the
/// code, never derived from the thread count).
const SORT_CHUNK: usize = 8192;

/// The grid: the counting sort's output and its scratch.
#[derive(Clone, Debug)]
pub struct Grid {
    inverse_cell: f32,
    row_mask: u32,
    /// `bucket >> part_shift` is the bucket's part.
    part_shift: u32,
    /// `bucket_start[b] .. bucket_start[b + 1]` are bucket `b`'s particles in sorted order
    /// (and one entry more).
    pub bucket_start: Vec<u32>,
    /// Particle `p` is at sorted position `rank[p]`.
    pub rank: Vec<u32>,
    /// Sorted position `k` holds particle `order[k]`.
    pub order: Vec<u32>,
    /// Each sort chunk's `(bucket, particle)`s grouped by part, in particle order.
    staged: Vec<(u32, u32)>,
    /// Where each part starts in its chunk's `staged` (and the chunk's length).
    chunk_parts: Vec<[u32; PARTS + 1]>,
    /// Where each chunk's particles of each part start in the part-major order.
    part_chunk_start: Vec<[u32; PARTS]>,
    /// The sorted position of each particle in the part-major order.
    placed: Vec<u32>,
    /// Per bucket, the next free sorted position while placing.
    cursor: Vec<u32>,
}

impl Grid {
    /// A grid for `particles` particles and cells of size `h`: about one bucket per particle
    /// (a power of two, whole rows), so that unrelated cells are mostly apart.
    #[must_use]
    pub fn new(particles: usize, h: f32) -> Grid {
        let rows = (particles.next_power_of_two() / ROW as usize).max(16);
        let buckets = rows * ROW as usize;
        let chunks = particles.div_ceil(SORT_CHUNK);
        Grid {
            inverse_cell: 1.0 / h,
            row_mask: (rows - 1) as u32,
            part_shift: (buckets / PARTS).trailing_zeros(),
            bucket_start: vec![0; buckets + 2],
            rank: vec![0; particles],
            order: vec![0; particles],
            staged: vec![(0, 0); particles],
            chunk_parts: vec![[0; PARTS + 1]; chunks],
            part_chunk_start: vec![[0; PARTS]; chunks],
            placed: vec![0; particles],
            cursor: vec![0; buckets],
        }
    }

    /// `1 / h`.
    #[must_use]
    pub fn inverse_cell(&self) -> f32 {
        self.inverse_cell
    }

    /// The row mask (rows − 1).
    #[must_use]
    pub fn row_mask(&self) -> u32 {
        self.row_mask
    }

    /// Sorts particles `0 .. bucket.len()` by their buckets: `order` (sorted position to
    /// particle), `rank` (its inverse) and the buckets' starts. Stable: within a bucket
    /// particles keep their index order — so the order, and every sum taken in it, is a
    /// function of the positions alone.
    ///
    /// In parallel, with every split fixed by the scene (never by the thread count):
    /// 1. each chunk of [`SORT_CHUNK`] particles groups its particles by *part* (a 64th of the
    ///    bucket range) in its own piece of `staged`, stably;
    /// 2. each part counts its buckets, places its particles (chunk by chunk, so still in
    ///    particle order) into its own range of `order`, and sets its own buckets' starts;
    /// 3. each chunk reads back where its particles went, into its own piece of `rank`.
    ///
    /// Every write of a pass lands in a range that pass's work item owns, so the result is
    /// the serial sort's on any number of threads.
    pub fn sort(&mut self, bucket: &[u32]) {
        let n = bucket.len().min(self.rank.len());
        let buckets = self.buckets();
        let shift = self.part_shift;
        let part = |b: u32| ((b >> shift) as usize).min(PARTS - 1);
        // 1. Group by part within each chunk.
        self.staged[..n]
            .par_chunks_mut(SORT_CHUNK)
            .zip(self.chunk_parts.par_iter_mut())
            .enumerate()
            .for_each(|(c, (staged, parts))| {
                let first = c * SORT_CHUNK;
                let mine = &bucket[first..first + staged.len()];
                let mut start = [0u32; PARTS + 1];
                for &b in mine {
                    start[part(b) + 1] += 1;
                }
                for p in 0..PARTS {
                    start[p + 1] += start[p];
                }
                *parts = start;
                for (k, &b) in mine.iter().enumerate() {
                    let slot = &mut start[part(b)];
                    if let Some(s) = staged.get_mut(*slot as usize) {
                        *s = (b, (first + k) as u32);
                    }
                    *slot += 1;
                }
            });
        // Where each part, and each chunk's share of it, starts in the sorted order.
        let chunks = n.div_ceil(SORT_CHUNK);
        let mut part_start = [0u32; PARTS + 1];
        for p in 0..PARTS {
            let mut at = part_start[p];
            for (parts, starts) in self.chunk_parts[..chunks]
                .iter()
                .zip(&mut self.part_chunk_start)
            {
                starts[p] = at;
                at += parts[p + 1] - parts[p];
            }
            part_start[p + 1] = at;
        }
        // 2. Each part sorts its particles by bucket.
        let per_part = buckets / PARTS;
        let shared = Shared {
            staged: &self.staged,
            chunk_parts: &self.chunk_parts[..chunks],
            part_start: &part_start,
            per_part,
        };
        sort_parts(
            &shared,
            0..PARTS,
            &mut self.order[..n],
            &mut self.bucket_start[..buckets],
            &mut self.cursor[..buckets],
            &mut self.placed[..n],
        );
        self.bucket_start[buckets] = n as u32;
        self.bucket_start[buckets + 1] = n as u32;
        // 3. Each chunk's ranks.
        let (staged, placed) = (&self.staged, &self.placed);
        self.rank[..n]
            .par_chunks_mut(SORT_CHUNK)
            .zip(self.chunk_parts.par_iter())
            .zip(self.part_chunk_start.par_iter())
            .enumerate()
            .for_each(|(c, ((rank, parts), starts))| {
                let first = c * SORT_CHUNK;
                for p in 0..PARTS {
                    let (s, e) = (parts[p] as usize, parts[p + 1] as usize);
                    let from = starts[p] as usize;
                    for (i, j) in (s..e).zip(from..) {
                        let (Some(&(_, particle)), Some(&k)) =
                            (staged.get(first + i), placed.get(j))
                        else {
                            continue;
                        };
                        if let Some(r) = rank.get_mut((particle as usize).wrapping_sub(first)) {
                            *r = k;
                        }
                    }
                }
            });
    }

    /// The sorted range of the particles in buckets `first ..= last`.
    #[inline(always)]
    #[must_use]
    pub fn range(&self, first: u32, last: u32) -> (u32, u32) {
        let s = &self.bucket_start;
        (
            s.get(first as usize).copied().unwrap_or(0),
            s.get(last as usize + 1).copied().unwrap_or(0),
        )
    }

    /// The buckets `bucket_start[b] .. bucket_start[b + 1]` start at.
    #[must_use]
    pub fn buckets(&self) -> usize {
        self.bucket_start.len() - 2
    }
}

/// What every part of the sort's second pass reads.
struct Shared<'a> {
    staged: &'a [(u32, u32)],
    chunk_parts: &'a [[u32; PARTS + 1]],
    part_start: &'a [u32; PARTS + 1],
    per_part: usize,
}

/// The second pass for `parts`, whose sorted particles, bucket starts, cursors and part-major
/// positions are the slices given: halves side by side until one part is left.
fn sort_parts(
    shared: &Shared<'_>,
    parts: core::ops::Range<usize>,
    sorted: &mut [u32],
    starts: &mut [u32],
    cursor: &mut [u32],
    placed: &mut [u32],
) {
    if parts.len() > 1 {
        let mid = parts.start + parts.len() / 2;
        let at = (shared.part_start[mid] - shared.part_start[parts.start]) as usize;
        let buckets = (mid - parts.start) * shared.per_part;
        let (sorted_a, sorted_b) = sorted.split_at_mut(at.min(sorted.len()));
        let (starts_a, starts_b) = starts.split_at_mut(buckets.min(starts.len()));
        let (cursor_a, cursor_b) = cursor.split_at_mut(buckets.min(cursor.len()));
        let (placed_a, placed_b) = placed.split_at_mut(at.min(placed.len()));
        rayon::join(
            || {
                sort_parts(
                    shared,
                    parts.start..mid,
                    sorted_a,
                    starts_a,
                    cursor_a,
                    placed_a,
                )
            },
            || {
                sort_parts(
                    shared,
                    mid..parts.end,
                    sorted_b,
                    starts_b,
                    cursor_b,
                    placed_b,
                )
            },
        );
        return;
    }
    let p = parts.start;
    let base = (p * shared.per_part) as u32;
    let offset = shared.part_start[p];
    // This part's particles, chunk by chunk: particle order.
    let mine = || {
        shared
            .chunk_parts
            .iter()
            .enumerate()
            .flat_map(move |(c, at)| {
                let first = c * SORT_CHUNK;
                let (s, e) = (first + at[p] as usize, first + at[p + 1] as usize);
                shared.staged.get(s..e).unwrap_or(&[])
            })
    };
    cursor.fill(0);
    for &(b, _) in mine() {
        if let Some(count) = cursor.get_mut(b.wrapping_sub(base) as usize) {
            *count += 1;
        }
    }
    let mut sum = offset;
    for (start, count) in starts.iter_mut().zip(cursor.iter_mut()) {
        *start = sum;
        sum += *count;
        *count = *start;
    }
    for (&(b, particle), place) in mine().zip(placed.iter_mut()) {
        let Some(next) = cursor.get_mut(b.wrapping_sub(base) as usize) else {
            continue;
        };
        let k = *next;
        *next += 1;
        *place = k;
        if let Some(slot) = sorted.get_mut(k.wrapping_sub(offset) as usize) {
            *slot = particle;
        }
    }
}

/// The nine rows around a cell's row — `(y + dy, z + dz)` for `dy, dz` in −1 ..= 1, own row
/// first, then the others in `(dy, dz)` order — as bucket offsets (row · [`ROW`]), for the
/// brick of `x div 16` and the bricks on either side (read only where `x mod 16` is 0 or 15).
///
/// The nine rows are always distinct, so no bucket is ever read twice: their low four bits are
/// `((y + dy) mod 4, (z + dz) mod 4)`, and three consecutive integers are distinct mod 4.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RowsAround {
    /// The cell's `(x div 16, y, z)` these rows are for.
    key: [i32; 3],
    /// Bucket offset of each row in the cell's brick along x.
    own: [u32; 9],
    /// Each row's hash parts but x's: y and z's part of the brick's hash, and the row's
    /// `(y mod 4, z mod 4)` (for the bricks on either side, seldom read).
    yz: [(u32, u32); 9],
    row_mask: u32,
}

/// `(dy, dz)` of the nine rows, own row first.
const AROUND: [(i32, i32); 9] = [
    (0, 0),
    (-1, -1),
    (-1, 0),
    (-1, 1),
    (0, -1),
    (0, 1),
    (1, -1),
    (1, 0),
    (1, 1),
];

/// At most this many ranges around a cell: nine rows, and one cell across a brick's edge in
/// each.
pub const MAX_RANGES: usize = 18;

impl RowsAround {
    /// Rows that match no cell (`key` out of the clamped range).
    pub const NONE: RowsAround = RowsAround {
        key: [i32::MIN; 3],
        own: [0; 9],
        yz: [(0, 0); 9],
        row_mask: 0,
    };

    /// The rows around `cell`: kept as they are when `cell` is in the same row as the cell
    /// they were computed for (consecutive sorted particles mostly are).
    #[inline]
    pub fn update(&mut self, cell: [i32; 3], row_mask: u32) {
        let [x, y, z] = cell;
        let key = [x >> 4, y, z];
        if key == self.key && row_mask == self.row_mask {
            return;
        }
        self.key = key;
        self.row_mask = row_mask;
        let bx = brick_x(key[0]);
        for (i, (dy, dz)) in AROUND.into_iter().enumerate() {
            let (y, z) = (y.wrapping_add(dy), z.wrapping_add(dz));
            self.yz[i] = (brick_yz(y, z), ((y as u32 & 3) << 2) | (z as u32 & 3));
            self.own[i] = self.row(i, bx);
        }
    }

    /// Bucket offset of row `i` in the brick whose x hash part is `bx`.
    #[inline(always)]
    fn row(&self, i: usize, bx: u32) -> u32 {
        let (yz, low) = self.yz[i];
        ((((bx ^ yz) << 4) | low) & self.row_mask) * ROW
    }

    /// The sorted ranges of the 27 cells around `cell` (whose rows these are), in the fixed
    /// order: per row, cells `x − 1 ..= x + 1` within the row, then the one across the
    /// brick's edge if any. Writes them to `out` and returns how many.
    #[inline(always)]
    pub fn ranges(&self, grid: &Grid, cell: [i32; 3], out: &mut [(u32, u32); MAX_RANGES]) -> usize {
        let low = cell[0] as u32 & (ROW - 1);
        let (first, last) = (low.saturating_sub(1), (low + 1).min(ROW - 1));
        if low != 0 && low != ROW - 1 {
            for (i, o) in out.iter_mut().take(9).enumerate() {
                *o = grid.range(self.own[i] + first, self.own[i] + last);
            }
            return 9;
        }
        // Across the edge: bucket 15 of the brick before, or bucket 0 of the one after.
        let (side, bucket) = if low == 0 {
            (brick_x(self.key[0].wrapping_sub(1)), ROW - 1)
        } else {
            (brick_x(self.key[0].wrapping_add(1)), 0)
        };
        for i in 0..9 {
            out[2 * i] = grid.range(self.own[i] + first, self.own[i] + last);
            let b = self.row(i, side) + bucket;
            out[2 * i + 1] = grid.range(b, b);
        }
        MAX_RANGES
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counting_sort_is_stable_and_complete() {
        // One sort chunk, and several (30,001 particles: four chunks, the last part-filled,
        // each with particles in many of the 64 parts), on one and on two threads.
        for count in [500, 30_001] {
            let points: Vec<Vec3> = (0..count)
                .map(|i| {
                    let t = i as f32;
                    Vec3::new((t * 0.37).sin(), (t * 0.11).cos(), (t * 0.07).sin()) * 0.05
                })
                .collect();
            let mut orders = Vec::new();
            for threads in [1, 2] {
                let mut grid = Grid::new(points.len(), 0.01);
                let bucket: Vec<u32> = points
                    .iter()
                    .map(|&p| bucket_of(cell_of(p, grid.inverse_cell()), grid.row_mask()))
                    .collect();
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| grid.sort(&bucket));
                let order = grid.order.clone();
                let mut seen = vec![false; points.len()];
                for b in 0..grid.buckets() {
                    let range = grid.bucket_start[b] as usize..grid.bucket_start[b + 1] as usize;
                    let members = &order[range.clone()];
                    // Stable: ascending particle index within each bucket.
                    assert!(members.windows(2).all(|w| w[0] < w[1]));
                    for (k, &p) in range.zip(members) {
                        assert_eq!(bucket[p as usize], b as u32);
                        assert_eq!(grid.rank[p as usize], k as u32);
                        seen[p as usize] = true;
                    }
                }
                assert!(
                    seen.iter().all(|&s| s),
                    "{count} particles, {threads} threads"
                );
                assert_eq!(grid.bucket_start[grid.buckets()] as usize, count);
                orders.push(order);
            }
            assert_eq!(orders[0], orders[1], "{count} particles: 1 vs 2 threads");
        }
    }

    #[test]
    fn the_ranges_around_a_cell_hold_its_27_cells_each_particle_once() {
        // Few rows (16), many cells: rows and buckets collide, and x wraps at 0 and 15.
        for centre in [
            [0, 0, 0],
            [15, 3, -2],
            [16, -7, 9],
            [-1, 5, 5],
            [31, 0, 1],
            [14, 1, 2],
        ] {
            let mut points = Vec::new();
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let c = [centre[0] + dx, centre[1] + dy, centre[2] + dz];
                        points.push(Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + 0.5);
                    }
                }
            }
            let near = points.len();
            for k in 0..200 {
                points.push(Vec3::new(
                    k as f32 * 7.0 - 700.0,
                    (k % 13) as f32,
                    (k % 7) as f32,
                ));
            }
            let mut grid = Grid::new(256, 1.0);
            let bucket: Vec<u32> = points
                .iter()
                .map(|&p| bucket_of(cell_of(p, 1.0), grid.row_mask()))
                .collect();
            grid.sort(&bucket);
            let order = &grid.order;
            let mut rows = RowsAround::NONE;
            // Rows computed for another cell of the same row, then reused.
            rows.update([centre[0] & !15, centre[1], centre[2]], grid.row_mask());
            rows.update(centre, grid.row_mask());
            let mut times = vec![0; points.len()];
            let mut ranges = [(0, 0); MAX_RANGES];
            let n = rows.ranges(&grid, centre, &mut ranges);
            for &(s, e) in &ranges[..n] {
                for k in s..e {
                    times[order[k as usize] as usize] += 1;
                }
            }
            assert!(
                times[..near].iter().all(|&t| t == 1),
                "{centre:?}: {times:?}"
            );
            assert!(times.iter().all(|&t| t <= 1), "{centre:?}");
        }
    }

    #[test]
    fn the_fast_floor_is_floor() {
        for t in [
            0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 2.999_999, -2.000_001, 1.0e8, -1.0e8, 3.0e9, -3.0e9,
        ] {
            assert_eq!(
                floor_clamped(t),
                t.floor().clamp(-1.0e9, 1.0e9) as i32,
                "{t}"
            );
        }
        assert_eq!(floor_clamped(f32::NAN), 0);
    }

    #[test]
    fn far_and_non_finite_positions_do_not_overflow() {
        assert_eq!(
            cell_of(Vec3::splat(f32::INFINITY), 100.0),
            [1_000_000_000; 3]
        );
        assert_eq!(cell_of(Vec3::splat(-1.0e30), 100.0), [-1_000_000_000; 3]);
        let _ = bucket_of(cell_of(Vec3::splat(f32::NAN), 100.0), 15);
    }
}
