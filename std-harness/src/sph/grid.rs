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
    let c = |x: f32| (x * inverse_cell).floor().clamp(-1.0e9, 1.0e9) as i32;
    [c(p.x), c(p.y), c(p.z)]
}

/// The row holding cell `(x, y, z)`. Rows come in *bricks* of 4 × 4 rows (16 × 4 × 4 cells),
/// placed by the spatial hash of Teschner et al. 2003 on `(x div 16, y div 4, z div 4)`; within
/// a brick, `(y mod 4, z mod 4)` picks the row. The 9 rows around a cell then mostly lie in one
/// or two bricks: a few kilobytes of the sorted arrays rather than nine random places.
#[inline]
#[must_use]
pub fn row_of(x: i32, y: i32, z: i32, row_mask: u32) -> u32 {
    let brick = ((x >> 4) as u32).wrapping_mul(73_856_093)
        ^ ((y >> 2) as u32).wrapping_mul(19_349_663)
        ^ ((z >> 2) as u32).wrapping_mul(83_492_791);
    ((brick << 4) | ((y as u32 & 3) << 2) | (z as u32 & 3)) & row_mask
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
    /// `bucket_start[b] .. bucket_start[b + 1]` are bucket `b`'s particles in sorted order.
    pub bucket_start: Vec<u32>,
    cursor: Vec<u32>,
    /// Sorted position `k` holds particle `order[k]`.
    pub order: Vec<u32>,
    /// Particle `p` is at sorted position `rank[p]` (the inverse of `order`).
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
            bucket_start: vec![0; buckets + 1],
            cursor: vec![0; buckets],
            order: vec![0; particles],
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

    /// Sorts particles `0 .. bucket.len()` by their buckets. Stable: within a bucket particles
    /// keep their index order — so the order, and every sum taken in it, is a function of
    /// the positions alone.
    pub fn sort(&mut self, bucket: &[u32]) {
        self.bucket_start.fill(0);
        for &b in bucket {
            self.bucket_start[b as usize + 1] += 1;
        }
        for b in 1..self.bucket_start.len() {
            self.bucket_start[b] += self.bucket_start[b - 1];
        }
        let buckets = self.cursor.len();
        self.cursor.copy_from_slice(&self.bucket_start[..buckets]);
        for (p, &b) in bucket.iter().enumerate() {
            let slot = &mut self.cursor[b as usize];
            self.order[*slot as usize] = p as u32;
            self.rank[p] = *slot;
            *slot += 1;
        }
    }

    /// The sorted ranges holding every particle of the 27 cells around `cell`: the span of
    /// buckets of its own three cells along x first, then the others in a fixed order, each
    /// bucket once (rows that collide give the same span twice: it is read once).
    /// Returns the ranges and how many there are.
    #[must_use]
    pub fn ranges_around(&self, cell: [i32; 3]) -> ([(u32, u32); 18], usize) {
        let [x, y, z] = cell;
        let low = x as u32 & (ROW - 1);
        // Bucket spans (first, last) of cells x − 1 ..= x + 1 in the row of (y, z).
        let spans = |y: i32, z: i32| -> [(u32, u32); 2] {
            let row = |x: i32| row_of(x, y, z, self.row_mask) * ROW;
            match low {
                0 => [
                    (row(x), row(x) + 1),
                    (row(x - 1) + ROW - 1, row(x - 1) + ROW - 1),
                ],
                l if l == ROW - 1 => [
                    (row(x) + ROW - 2, row(x) + ROW - 1),
                    (row(x + 1), row(x + 1)),
                ],
                l => [(row(x) + l - 1, row(x) + l + 1), (u32::MAX, u32::MAX)],
            }
        };
        // Own span first (the nearest cells, kept first when the cap truncates), then the
        // others in the fixed (dy, dz) order, a span that collides with one already taken
        // skipped (a linear search over at most 17: cheaper than sorting).
        let own = spans(y, z)[0];
        let mut taken = [own; 18];
        let mut out = [(0, 0); 18];
        out[0] = self.range(own);
        let mut m = 1;
        for dy in -1..=1 {
            for dz in -1..=1 {
                for span in spans(y + dy, z + dz) {
                    if span.0 != u32::MAX && !taken[..m].contains(&span) {
                        taken[m] = span;
                        out[m] = self.range(span);
                        m += 1;
                    }
                }
            }
        }
        (out, m)
    }

    /// The sorted range of buckets `first ..= last`.
    #[inline]
    fn range(&self, (first, last): (u32, u32)) -> (u32, u32) {
        (
            self.bucket_start[first as usize],
            self.bucket_start[last as usize + 1],
        )
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
        grid.sort(&bucket);
        let mut seen = vec![false; points.len()];
        for b in 0..grid.cursor.len() {
            let range = grid.bucket_start[b] as usize..grid.bucket_start[b + 1] as usize;
            let members = &grid.order[range.clone()];
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
        for centre in [[0, 0, 0], [15, 3, -2], [16, -7, 9], [-1, 5, 5], [31, 0, 1]] {
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
            let (ranges, n) = grid.ranges_around(centre);
            let mut times = vec![0; points.len()];
            for &(s, e) in &ranges[..n] {
                for k in s..e {
                    times[grid.order[k as usize] as usize] += 1;
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
    fn far_and_non_finite_positions_do_not_overflow() {
        assert_eq!(
            cell_of(Vec3::splat(f32::INFINITY), 100.0),
            [1_000_000_000; 3]
        );
        assert_eq!(cell_of(Vec3::splat(-1.0e30), 100.0), [-1_000_000_000; 3]);
        let _ = bucket_of(cell_of(Vec3::splat(f32::NAN), 100.0), 15);
    }
}
