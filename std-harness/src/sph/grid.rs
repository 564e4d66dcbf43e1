//! The spatial hash and the stable counting sort (Sánchez-Banderas 2015, Sec. 4; Algorithm 1
//! lines 2–4). Cells are cubes of the smoothing length `h`, so every neighbour of a particle
//! lies in its own cell or one of the 26 around it. Cells map to a power-of-two number of
//! buckets by a hash of their integer coordinates; distinct cells may share a bucket, which the
//! neighbour search filters by distance.

use hairsim_core::Vec3;

/// The grid: bucket of each particle, the counting sort's output, and its scratch.
#[derive(Clone, Debug)]
pub struct Grid {
    inverse_cell: f32,
    mask: u32,
    /// Bucket of each particle (unsorted order).
    bucket: Vec<u32>,
    /// `bucket_start[b] .. bucket_start[b + 1]` are bucket `b`'s particles in sorted order.
    pub bucket_start: Vec<u32>,
    cursor: Vec<u32>,
    /// Sorted position `k` holds particle `order[k]`.
    pub order: Vec<u32>,
}

/// Integer cell coordinates of `p` for cells of size `1 / inverse_cell`. Coordinates are
/// clamped so that far-away (or non-finite) positions cannot overflow.
#[inline]
#[must_use]
pub fn cell_of(p: Vec3, inverse_cell: f32) -> [i32; 3] {
    let c = |x: f32| (x * inverse_cell).floor().clamp(-1.0e9, 1.0e9) as i32;
    [c(p.x), c(p.y), c(p.z)]
}

/// The bucket of a cell: the classic spatial hash of Teschner et al. 2003.
#[inline]
#[must_use]
pub fn bucket_of(cell: [i32; 3], mask: u32) -> u32 {
    let h = (cell[0] as u32).wrapping_mul(73_856_093)
        ^ (cell[1] as u32).wrapping_mul(19_349_663)
        ^ (cell[2] as u32).wrapping_mul(83_492_791);
    h & mask
}

impl Grid {
    /// A grid for `particles` particles and cells of size `h`: twice as many buckets as
    /// particles (rounded up to a power of two) keeps unrelated cells mostly apart.
    #[must_use]
    pub fn new(particles: usize, h: f32) -> Grid {
        let buckets = (2 * particles).next_power_of_two().max(16);
        Grid {
            inverse_cell: 1.0 / h,
            mask: (buckets - 1) as u32,
            bucket: vec![0; particles],
            bucket_start: vec![0; buckets + 1],
            cursor: vec![0; buckets],
            order: vec![0; particles],
        }
    }

    /// `1 / h`.
    #[must_use]
    pub fn inverse_cell(&self) -> f32 {
        self.inverse_cell
    }

    /// The bucket mask (buckets − 1).
    #[must_use]
    pub fn mask(&self) -> u32 {
        self.mask
    }

    /// Hashes particles `0 .. count` (position given by `position`) and sorts them by bucket.
    /// Stable: within a bucket, particles keep their index order — so the order, and every sum
    /// taken in it, is a function of the positions alone.
    pub fn hash_and_sort(&mut self, count: usize, position: impl Fn(usize) -> Vec3) {
        for (p, b) in self.bucket.iter_mut().enumerate().take(count) {
            *b = bucket_of(cell_of(position(p), self.inverse_cell), self.mask);
        }
        self.bucket_start.fill(0);
        for &b in &self.bucket[..count] {
            self.bucket_start[b as usize + 1] += 1;
        }
        for b in 1..self.bucket_start.len() {
            self.bucket_start[b] += self.bucket_start[b - 1];
        }
        let buckets = self.cursor.len();
        self.cursor.copy_from_slice(&self.bucket_start[..buckets]);
        for (p, &b) in self.bucket[..count].iter().enumerate() {
            let slot = &mut self.cursor[b as usize];
            self.order[*slot as usize] = p as u32;
            *slot += 1;
        }
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
        grid.hash_and_sort(points.len(), |p| points[p]);
        let mut seen = vec![false; points.len()];
        for b in 0..grid.cursor.len() {
            let range = grid.bucket_start[b] as usize..grid.bucket_start[b + 1] as usize;
            let members = &grid.order[range];
            // Stable: ascending particle index within each bucket.
            assert!(members.windows(2).all(|w| w[0] < w[1]));
            for &p in members {
                assert_eq!(grid.bucket[p as usize], b as u32);
                seen[p as usize] = true;
            }
        }
        assert!(seen.iter().all(|&s| s));
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
