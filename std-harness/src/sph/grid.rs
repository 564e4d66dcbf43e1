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

/// The grid: the counting sort's output and its scratch.
#[derive(Clone, Debug)]
pub struct Grid {
    inverse_cell: f32,
    row_mask: u32,
    /// `bucket_start[b] .. bucket_start[b + 1]` are bucket `b`'s particles in sorted order
    /// (one entry more, the counting sort's scratch).
    pub bucket_start: Vec<u32>,
    /// Particle `p` is at sorted position `rank[p]`.
    pub rank: Vec<u32>,
}

impl Grid {
    /// A grid for `particles` particles and cells of size `h`: about one bucket per particle
    /// (a power of two, whole rows), so that unrelated cells are mostly apart.
    #[must_use]
    pub fn new(particles: usize, h: f32) -> Grid {
        let rows = (particles.next_power_of_two() / ROW as usize).max(16);
        let buckets = rows * ROW as usize;
        Grid {
            inverse_cell: 1.0 / h,
            row_mask: (rows - 1) as u32,
            bucket_start: vec![0; buckets + 2],
            rank: vec![0; particles],
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

    /// Sorts particles `0 .. bucket.len()` by their buckets and moves each one's `record`
    /// to its sorted place (`sorted[rank[p]] = record[p]`). Stable: within a bucket
    /// particles keep their index order — so the order, and every sum taken in it, is a
    /// function of the positions alone. One pass to count, one to place: the records are
    /// read in order and each written once (no second, random-read gather).
    pub fn sort<T: Copy>(&mut self, bucket: &[u32], record: &[T], sorted: &mut [T]) {
        // `bucket_start[b + 1]` counts bucket `b`, then (prefix sums) is where it starts,
        // then (each placement moves it on) where it ends: the start of bucket `b + 1`.
        let starts = &mut self.bucket_start;
        starts.fill(0);
        for &b in bucket {
            if let Some(count) = starts.get_mut(b as usize + 2) {
                *count += 1;
            }
        }
        let mut sum = 0;
        for start in starts.iter_mut() {
            sum += *start;
            *start = sum;
        }
        for ((&b, rank), r) in bucket.iter().zip(&mut self.rank).zip(record) {
            let Some(cursor) = starts.get_mut(b as usize + 1) else {
                continue;
            };
            *rank = *cursor;
            if let Some(slot) = sorted.get_mut(*cursor as usize) {
                *slot = *r;
            }
            *cursor += 1;
        }
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
        let points: Vec<Vec3> = (0..500)
            .map(|i| {
                let t = i as f32;
                Vec3::new((t * 0.37).sin(), (t * 0.11).cos(), (t * 0.07).sin()) * 0.05
            })
            .collect();
        let mut grid = Grid::new(points.len(), 0.01);
        let bucket: Vec<u32> = points
            .iter()
            .map(|&p| bucket_of(cell_of(p, grid.inverse_cell()), grid.row_mask()))
            .collect();
        let index: Vec<u32> = (0..points.len() as u32).collect();
        let mut order = vec![u32::MAX; points.len()];
        grid.sort(&bucket, &index, &mut order);
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
        assert!(seen.iter().all(|&s| s));
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
            let index: Vec<u32> = (0..points.len() as u32).collect();
            let mut order = vec![0; points.len()];
            grid.sort(&bucket, &index, &mut order);
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
