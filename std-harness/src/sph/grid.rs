//! The spatial hash and the stable counting sort (Sánchez-Banderas 2015, Sec. 4; Algorithm 1
//! lines 2–4). Cells are cubes of the smoothing length `h`, so every neighbour of a particle
//! lies in its own cell or one of the 26 around it.
//!
//! Cells map to a power-of-two number of buckets laid out as a periodic raster ([`Layout`]):
//! a *row* is 64 cells side by side along x, rows follow each other along y, then slabs along
//! z, each axis wrapping around (the hash is a modulo). Three cells side by side along x are
//! then (but where the row wraps around) three consecutive buckets, which after the sort are
//! one contiguous run of particles: the 27 cells around a particle are read as at most 18
//! contiguous ranges of the sorted arrays, 9 in most places. Distinct cells a period apart
//! share a bucket; the neighbour search filters by distance.
//!
//! Why a raster and not a hash of the cell, as the paper's (and Teschner et al. 2003's)
//! spatial hash: the nine rows around a particle are then its own, the ones beside it along y,
//! and those one slab away along z, so a pass over the sorted particles reads a band about
//! three slabs deep, which stays in the core's own cache. An earlier version placed the rows by
//! a hash in bricks of 4 × 4: most particles read rows from several bricks at random places,
//! and the neighbour pass waited on memory (Mannequin A's neighbour search 42–44 → 32 ms on
//! one thread, the stage bench, old and new binary alternately).

use hairsim_core::Vec3;
use rayon::prelude::*;

/// Buckets in a row (consecutive cells along x).
pub const ROW: u32 = 64;

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

/// How cells map to buckets: a periodic raster. Cell `(x, y, z)` is bucket
/// `row · ROW + (x mod ROW)` with `row = (z mod NZ) · NY + (y mod NY)` ([`Layout::row`]):
/// rows of [`ROW`] cells along x, rows along y, then slabs along z, wrapping around in each
/// axis. Cells a period apart share a bucket (the neighbour search filters by distance), and
/// cells side by side are side by side in the buckets: the rows around a row are beside it
/// along y or one slab away along z, so a pass over the sorted particles reads about three
/// slabs at a time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// `NY − 1`.
    y_mask: u32,
    /// `log₂ NY`.
    z_shift: u32,
    /// `NZ − 1`.
    z_mask: u32,
}

impl Layout {
    /// A layout with `2^y_bits` rows along y and `2^z_bits` slabs along z.
    #[must_use]
    pub fn new(y_bits: u32, z_bits: u32) -> Layout {
        Layout {
            y_mask: (1 << y_bits) - 1,
            z_shift: y_bits,
            z_mask: (1 << z_bits) - 1,
        }
    }

    /// `2^row_bits` rows shared between y and z as the box of `cells` (its size along y and
    /// z, in cells) asks: at least four each way (so that the nine rows around a row are
    /// distinct), then each further doubling to the axis whose cells wrap around most.
    #[must_use]
    pub fn fitting(row_bits: u32, cells: [f32; 2]) -> Layout {
        let mut bits = [2u32, 2];
        for _ in 4..row_bits.max(4) {
            // Ties (and a size that is not a number) go to y.
            let wraps = |axis: usize| cells[axis] / (1u64 << bits[axis]) as f32;
            let axis = usize::from(wraps(1) > wraps(0));
            bits[axis] += 1;
        }
        Layout::new(bits[0], bits[1])
    }

    /// The row holding the cells `(·, y, z)`.
    #[inline(always)]
    #[must_use]
    pub fn row(self, y: i32, z: i32) -> u32 {
        ((z as u32 & self.z_mask) << self.z_shift) | (y as u32 & self.y_mask)
    }
}

/// The bucket of a cell.
#[inline]
#[must_use]
pub fn bucket_of(cell: [i32; 3], layout: Layout) -> u32 {
    layout.row(cell[1], cell[2]) * ROW + (cell[0] as u32 & (ROW - 1))
}

/// Parts of the bucket range the counting sort's second pass sorts side by side.
const PARTS: usize = 64;

/// Buckets per particle. Cells a period apart share a bucket, and sparse hair (a shell around
/// the head, whose box holds hundreds of cells per particle) fills its buckets about evenly:
/// with one bucket a particle, the 27 buckets around a particle held about as many unrelated
/// particles, which the search tested for nothing; eight make them eight times rarer, and a
/// particle alone in its 27 buckets is not tested at all (`super::neighbours`).
pub const BUCKETS_PER_PARTICLE: usize = 8;

/// The most rows (of [`ROW`] buckets): 2¹⁹ buckets, 2 MiB of bucket starts. A scene of more
/// than 65,536 particles has fewer than eight buckets a particle (Mannequin A's 345,000 have
/// 1.5, as many as with one a particle rounded up to a power of two).
pub const MAX_ROWS: usize = 1 << 13;

/// Particles per work item of the counting sort's first and last passes (a constant of the
/// code, never derived from the thread count).
const SORT_CHUNK: usize = 8192;

/// The grid: the counting sort's output and its scratch.
#[derive(Clone, Debug)]
pub struct Grid {
    inverse_cell: f32,
    layout: Layout,
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
    /// A grid for `particles` particles and cells of size `h`: about
    /// [`BUCKETS_PER_PARTICLE`] buckets per particle, at most [`MAX_ROWS`] rows (a power of
    /// two, whole rows), so that unrelated cells are mostly apart. `extent` is
    /// the size of the box the particles start in, m: the rows along y and the slabs along z
    /// are shared out as it is ([`Layout::fitting`]), so that the hair's cells wrap around as
    /// little as the buckets allow.
    #[must_use]
    pub fn new(particles: usize, h: f32, extent: [f32; 3]) -> Grid {
        let rows = ((particles * BUCKETS_PER_PARTICLE).next_power_of_two() / ROW as usize)
            .clamp(16, MAX_ROWS);
        let buckets = rows * ROW as usize;
        let chunks = particles.div_ceil(SORT_CHUNK);
        Grid {
            inverse_cell: 1.0 / h,
            layout: Layout::fitting(rows.trailing_zeros(), [extent[1] / h, extent[2] / h]),
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

    /// Cells of `size` from now on (the buckets stay as they are).
    pub fn set_cell(&mut self, size: f32) {
        self.inverse_cell = 1.0 / size;
    }

    /// How cells map to buckets.
    #[must_use]
    pub fn layout(&self) -> Layout {
        self.layout
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
/// first, then the others in `(dy, dz)` order — as bucket offsets (row · [`ROW`]).
///
/// The nine rows are always distinct, so no bucket is ever read twice: a layout has at least
/// four rows along y and four slabs along z, and three consecutive integers are distinct mod 4.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RowsAround {
    /// The cell's `(y, z)` these rows are for.
    key: [i32; 2],
    /// Bucket offset of each row.
    own: [u32; 9],
    layout: Layout,
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

/// At most this many ranges around a cell: nine rows, and in each the cell across the row's
/// wrap-around.
pub const MAX_RANGES: usize = 18;

impl RowsAround {
    /// Rows that match no cell (`key` out of the clamped range).
    pub const NONE: RowsAround = RowsAround {
        key: [i32::MIN; 2],
        own: [0; 9],
        layout: Layout {
            y_mask: 0,
            z_shift: 0,
            z_mask: 0,
        },
    };

    /// The rows around `cell`: kept as they are when `cell` is in the same row as the cell
    /// they were computed for (consecutive sorted particles mostly are).
    #[inline]
    pub fn update(&mut self, cell: [i32; 3], layout: Layout) {
        let [_, y, z] = cell;
        let key = [y, z];
        if key == self.key && layout == self.layout {
            return;
        }
        self.key = key;
        self.layout = layout;
        for (own, (dy, dz)) in self.own.iter_mut().zip(AROUND) {
            *own = layout.row(y.wrapping_add(dy), z.wrapping_add(dz)) * ROW;
        }
    }

    /// The sorted ranges of the 27 cells around `cell` (whose rows these are), in the fixed
    /// order: per row, cells `x − 1 ..= x + 1` within the row, then the one across the row's
    /// wrap-around if any. Writes them to `out` and returns how many.
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
        // Across the wrap-around: the row's last cell, or its first.
        let across = if low == 0 { ROW - 1 } else { 0 };
        for i in 0..9 {
            out[2 * i] = grid.range(self.own[i] + first, self.own[i] + last);
            let b = self.own[i] + across;
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
                let mut grid = Grid::new(points.len(), 0.01, [0.1; 3]);
                let bucket: Vec<u32> = points
                    .iter()
                    .map(|&p| bucket_of(cell_of(p, grid.inverse_cell()), grid.layout()))
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
        // Few rows (16), many cells: rows and buckets collide, and x wraps at 0 and 63.
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
            let mut grid = Grid::new(256, 1.0, [1.0; 3]);
            let bucket: Vec<u32> = points
                .iter()
                .map(|&p| bucket_of(cell_of(p, 1.0), grid.layout()))
                .collect();
            grid.sort(&bucket);
            let order = &grid.order;
            let mut rows = RowsAround::NONE;
            // Rows computed for another cell of the same row, then reused.
            rows.update([centre[0] + 1, centre[1], centre[2]], grid.layout());
            rows.update(centre, grid.layout());
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
    fn rows_are_shared_out_as_the_box_asks() {
        // Mannequin A: a box about 100 cells high (y) and 78 deep (z), 2^13 rows.
        assert_eq!(Layout::fitting(13, [100.0, 78.0]), Layout::new(7, 6));
        // A flat box gets its rows along its long side, keeping four the other way.
        assert_eq!(Layout::fitting(10, [1.0, 5000.0]), Layout::new(2, 8));
        assert_eq!(Layout::fitting(10, [5000.0, 1.0]), Layout::new(8, 2));
        // Too few rows to share: four each way, whatever the box.
        assert_eq!(Layout::fitting(4, [0.0, 0.0]), Layout::new(2, 2));
        assert_eq!(Layout::fitting(0, [f32::NAN, 3.0]), Layout::new(2, 2));
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
        let _ = bucket_of(cell_of(Vec3::splat(f32::NAN), 100.0), Layout::new(2, 2));
    }
}
