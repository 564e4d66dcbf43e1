//! Capped neighbour lists (Sánchez-Banderas 2015, Sec. 4, Algorithm 1 line 6: the paper's
//! rough k-nearest list), with the density and pressure of each particle (line 7) taken in
//! the same pass, while the distances are at hand.
//!
//! Each particle's cell comes from its sorted position; the nine rows around it
//! ([`RowsAround`]) are computed once per run of particles in one row, and the 27 cells are read
//! as nine ranges of three cells (more where the row wraps around) of the
//! sorted structure-of-arrays positions, looked up once per cell (the sorted particles of a
//! cell are consecutive). Each range is tested where it lies, four candidates at a time for
//! `r² < h²` (no square root; one packed compare on x86-64), in pieces of eight with no branch
//! on the range's length, and the hits of many pieces are taken from one mask, a byte a piece
//! ([`test_ranges`]). Two consecutive particles of one cell share that pass: each piece is
//! loaded once and tested for both. What costs here is cache misses and mispredicted branches
//! more than instructions: valgrind's branch simulation (the whole pass, 7 SPH steps of
//! Mannequin A, `--toggle-collect='*NeighbourLists*build*'`) counts 11.7 M mispredictions and
//! 4.50 G instructions in the earlier pass, 8.5 M and 3.87 G now (the kept density term
//! without a branch took 2.4 M of the mispredictions; the byte masks and the pairs took the
//! instructions, and no time that could be measured), and the raster grid ([`super::grid`])
//! took about 40 % off the pass's time by keeping the rows it reads in cache. The first `cap`
//! hits (that are not the particle itself nor its own strand's near nodes) are kept, in scan
//! order. The order is a function of the positions only, so lists, truncation and every sum
//! over a list are the same on any number of threads.
//!
//! Lists are stored compactly: a chunk of particles writes its lists one after another into
//! its own part of the storage, so the few neighbours a particle has (about five on a head)
//! take a few bytes, not a cache line and a half of room for `cap` of them.

#![deny(clippy::too_many_lines, clippy::too_many_arguments)]
use hairsim_core::Vec3;
use rayon::prelude::*;

use super::forces::{poly6_factor, SortedParticles};
use super::grid::{cell_of, Grid, Layout, RowsAround, MAX_RANGES};
use super::{SphParams, CHUNK, MAX_CAP};

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
        let h = params.smoothing_length;
        let h2 = h * h;
        let search = Search {
            x,
            y,
            z,
            velocity,
            near: Near {
                key,
                mass,
                cap,
                gap: params.same_strand_gap,
                h2,
            },
            grid,
            inverse_cell: grid.inverse_cell(),
            layout: grid.layout(),
            c6: poly6_factor(h),
            stiffness: params.stiffness,
            rest: params.rest_density,
        };
        self.list
            .par_chunks_mut(CHUNK * cap + 1)
            .zip(self.start[..n].par_chunks_mut(CHUNK))
            .zip(self.count[..n].par_chunks_mut(CHUNK))
            .zip(density.par_chunks_mut(CHUNK))
            .zip(packed.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, ((((list, start), count), density), packed))| {
                let mut chunk = Chunk {
                    c,
                    list,
                    start,
                    count,
                    density,
                    packed,
                    found: Found::default(),
                };
                search.chunk(&mut chunk);
                chunk.found
            })
            .reduce(Found::default, Found::merge)
    }
}

/// What every chunk's search reads: the sorted particles, the grid, and the parameters as
/// the search uses them.
struct Search<'a> {
    x: &'a [f32],
    y: &'a [f32],
    z: &'a [f32],
    velocity: &'a [[f32; 3]],
    /// The sorted keys and masses, the cap, the same-strand gap and `h²`.
    near: Near<'a>,
    grid: &'a Grid,
    inverse_cell: f32,
    layout: Layout,
    /// The poly6 kernel's factor.
    c6: f32,
    stiffness: f32,
    /// Rest density.
    rest: f32,
}

/// One chunk of particles: what its search writes, and its counts.
struct Chunk<'a> {
    /// The chunk's index.
    c: usize,
    /// The chunk's part of the list storage.
    list: &'a mut [u32],
    start: &'a mut [u32],
    count: &'a mut [u32],
    density: &'a mut [f32],
    packed: &'a mut [[f32; 8]],
    found: Found,
}

/// A particle of a chunk (sorted `a`, at `me`) and, when the next one is in the same cell,
/// that one's position: the two take their lists in one pass.
struct Particles {
    a: usize,
    me: [f32; 3],
    pair: Option<[f32; 3]>,
}

/// The 27 cells around the particles' cell, as ranges of sorted particles: the rows around
/// it follow every particle; the ranges are looked up again only when the cell changes.
struct CellRanges {
    rows: RowsAround,
    ranges: [(u32, u32); MAX_RANGES],
    /// The cell whose 27 cells `ranges` holds, and how many ranges: sorted particles of one
    /// cell are consecutive and share them.
    ranged: Option<([i32; 3], usize)>,
}

impl CellRanges {
    /// The ranges around `cell`.
    #[inline(always)]
    fn around(&mut self, grid: &Grid, cell: [i32; 3], layout: Layout) -> &[(u32, u32)] {
        self.rows.update(cell, layout);
        let m = match self.ranged {
            Some((of, m)) if of == cell => m,
            _ => {
                let m = self.rows.ranges(grid, cell, &mut self.ranges);
                self.ranged = Some((cell, m));
                m
            }
        };
        &self.ranges[..m]
    }
}

impl Search<'_> {
    /// Sorted particle `a`'s position.
    #[inline(always)]
    fn at(&self, a: usize) -> [f32; 3] {
        [self.x[a], self.y[a], self.z[a]]
    }

    /// Sorted particle `a`'s cell.
    #[inline(always)]
    fn cell_at(&self, a: usize) -> [i32; 3] {
        cell_of(
            Vec3::new(self.x[a], self.y[a], self.z[a]),
            self.inverse_cell,
        )
    }

    /// Every list of chunk `chunk.c`, one particle after another, or two at once when the
    /// next particle is in the same cell.
    #[inline(always)]
    fn chunk(&self, chunk: &mut Chunk<'_>) {
        let cap = self.near.cap;
        let mut cells = CellRanges {
            rows: RowsAround::NONE,
            ranges: [(0u32, 0u32); MAX_RANGES],
            ranged: None,
        };
        let mut used = 0usize;
        // The second particle of a pair gathers its list here; it is moved next to the first
        // one's once that one's length is known.
        let mut spare = [0u32; MAX_CAP + 1];
        let record_len = chunk.count.len();
        // Particle `k`'s cell when the previous pass looked it up already.
        let mut known = None;
        let mut k = 0;
        // Bounded: `k` moves on by one or two a pass.
        while k < record_len {
            let a = chunk.c * CHUNK + k;
            let me = self.at(a);
            let cell = known.unwrap_or_else(|| self.cell_at(a));
            let ranges = cells.around(self.grid, cell, self.layout);
            // The next particle, if it is in the same cell: the two share one pass over
            // their ranges (the loads, the range and piece bookkeeping).
            let b = a + 1;
            let next = (k + 1 < record_len).then(|| self.cell_at(b));
            let pair = (next == Some(cell)).then(|| self.at(b));
            known = if pair.is_some() { None } else { next };
            let mine = &mut chunk.list[used..used + cap + 1];
            let particles = Particles { a, me, pair };
            let (one, two) = self.gather(ranges, &particles, used, mine, &mut spare[..cap + 1]);
            self.record(chunk, k, a, me, &one);
            used += one.kept;
            if let (Some(mut two), Some(other)) = (two, pair) {
                chunk.list[used..used + two.kept].copy_from_slice(&spare[..two.kept]);
                two.at = used;
                self.record(chunk, k + 1, b, other, &two);
                used += two.kept;
            }
            k += 1 + usize::from(pair.is_some());
        }
    }

    /// The lists of particle `p.a` (into `mine`, which starts at `used` in the chunk's
    /// storage) and, with `p.pair`, of particle `p.a + 1` (into `theirs`), in one pass over
    /// `ranges`.
    #[inline(always)]
    fn gather(
        &self,
        ranges: &[(u32, u32)],
        p: &Particles,
        used: usize,
        mine: &mut [u32],
        theirs: &mut [u32],
    ) -> (Gathered, Option<Gathered>) {
        let (key, mass, h2) = (self.near.key, self.near.mass, self.near.h2);
        let (a, me, near) = (p.a, p.me, &self.near);
        let xyz = (self.x, self.y, self.z);
        let mut one = Gather::new(a, key[a], mass[a] * h2 * h2 * h2, used);
        match p.pair {
            Some(other) => {
                let b = a + 1;
                let mut two = Gather::new(b, key[b], mass[b] * h2 * h2 * h2, 0);
                test_ranges(ranges, xyz, ([a, b], [me, other]), h2, &mut |p, j, d2| {
                    if p == 0 {
                        one.hit(j, d2, near, mine);
                    } else {
                        two.hit(j, d2, near, theirs);
                    }
                });
                (one.done(), Some(two.done()))
            }
            None => {
                test_ranges(ranges, xyz, ([a], [me]), h2, &mut |_, j, d2| {
                    one.hit(j, d2, near, mine);
                });
                (one.done(), None)
            }
        }
    }

    /// Writes particle `k` of the chunk (sorted `a`, at `me`): where its list starts, its
    /// count, its density, and its force inputs with the pressure.
    #[inline(always)]
    fn record(&self, chunk: &mut Chunk<'_>, k: usize, a: usize, me: [f32; 3], list: &Gathered) {
        let cap = self.near.cap;
        let found = &mut chunk.found;
        chunk.start[k] = (chunk.c * (CHUNK * cap + 1) + list.at) as u32;
        chunk.count[k] = list.kept as u32;
        found.kept += list.kept as u64;
        found.truncated += u64::from(list.all) - list.kept as u64;
        found.max_found = found.max_found.max(list.all);
        let rho = self.c6 * list.sum;
        let pr = (self.stiffness * (rho - self.rest)).max(0.0);
        chunk.density[k] = rho;
        let [vx, vy, vz] = self.velocity[a];
        chunk.packed[k] = [me[0], me[1], me[2], self.near.mass[a] / rho, vx, vy, vz, pr];
    }
}

/// What a particle's hits are checked against: the sorted keys and masses, the cap, the
/// same-strand gap and `h²`.
struct Near<'a> {
    key: &'a [u32],
    mass: &'a [f32],
    cap: usize,
    gap: u32,
    h2: f32,
}

/// One particle's list being gathered.
struct Gather {
    /// The particle (sorted index).
    a: usize,
    /// Its key.
    key: u32,
    /// Where its list starts in the chunk's storage.
    at: usize,
    kept: usize,
    all: u32,
    /// `ρ / (315/(64π h⁹))`: own mass, then the kept neighbours in list order.
    sum: f32,
}

/// A gathered list: where it starts, how many were kept and found, and the density sum.
struct Gathered {
    at: usize,
    kept: usize,
    all: u32,
    sum: f32,
}

impl Gather {
    #[inline(always)]
    fn new(a: usize, key: u32, own: f32, at: usize) -> Gather {
        Gather {
            a,
            key,
            at,
            kept: 0,
            all: 0,
            sum: own,
        }
    }

    /// Takes sorted particle `j` at `r² = d2` (within `h`): a neighbour unless it is the
    /// particle itself or a near node of its own strand, kept while there is room under the
    /// cap. It is written to `list` whether it is kept or not, and counted only if it is (no
    /// branch on it: `list` has one entry of room past the cap).
    #[inline(always)]
    fn hit(&mut self, j: usize, d2: f32, near: &Near<'_>, list: &mut [u32]) {
        let (Some(&other), Some(&m)) = (near.key.get(j), near.mass.get(j)) else {
            return;
        };
        let neighbour = (j != self.a) & !near_on_strand(other, self.key, near.gap);
        let keep = neighbour & (self.kept < near.cap);
        if let Some(slot) = list.get_mut(self.kept.min(near.cap)) {
            *slot = j as u32;
        }
        let w = near.h2 - d2;
        // `m · 1` is `m` and `m · 0` is +0 (masses are positive), and adding +0 leaves the
        // sum's bits as they are: the kept term without a branch, which LLVM makes of an
        // `if` here and which mispredicts (a particle's own and same-strand hits come at
        // random places in its list).
        let m = m * f32::from(u8::from(keep));
        self.sum += m * (w * w * w);
        self.kept += usize::from(keep);
        self.all += u32::from(neighbour);
    }

    #[inline(always)]
    fn done(self) -> Gathered {
        Gathered {
            at: self.at,
            kept: self.kept,
            all: self.all,
            sum: self.sum,
        }
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

/// Calls `hit(p, j, r²)` for every sorted particle `j` of `ranges` with `r² < h2` from
/// particle `p`'s position `me[p]`, in order for each `p` (range by range, each in sorted
/// order), testing them where they lie. `P` particles of one cell share the pass: each piece
/// is loaded once and tested for each of them. A range is tested in pieces of [`SHORT`] (most
/// ranges are one piece: a range holds about five particles on a head), each as two blocks of
/// [`LANES`] with the lanes past the range's end masked off — the position arrays have
/// [`PADDING`] entries past the last particle — and the hits of up to [`GROUP`] pieces go into
/// one mask, a byte a piece, so that neither a range's length nor its hits cost a branch of
/// their own; the few hits are then taken from the mask in one loop.
#[inline(always)]
fn test_ranges<const P: usize>(
    ranges: &[(u32, u32)],
    xyz: (&[f32], &[f32], &[f32]),
    (own, me): ([usize; P], [[f32; 3]; P]),
    h2: f32,
    hit: &mut impl FnMut(usize, usize, f32),
) {
    let mut hits = [[0u8; GROUP]; P];
    let mut starts = [0u32; GROUP];
    let mut held = 0;
    for (r, &(s, e)) in ranges.iter().enumerate() {
        let e = e.max(s);
        let mut s = s;
        // Bounded: `s` moves on by SHORT a pass until it reaches `e`.
        loop {
            if held == GROUP {
                take_held(&mut hits, &starts, xyz, me, hit);
                held = 0;
            }
            let tail = TAIL[((e - s) as usize).min(SHORT)];
            let bits = piece(xyz, s as usize, me, h2);
            for ((hits, bits), &own) in hits.iter_mut().zip(bits).zip(&own) {
                // The particle itself lies in the first range (its own row): a hit that is
                // never a neighbour, dropped here rather than taken and thrown away.
                let itself = if r == 0 { not_at(own, s) } else { u8::MAX };
                hits[held % GROUP] = bits & tail & itself;
            }
            starts[held % GROUP] = s;
            held += 1;
            s += SHORT as u32;
            if s >= e {
                break;
            }
        }
    }
    take_held(&mut hits, &starts, xyz, me, hit);
}

/// Takes the hits held for each particle `p` (calling `hit(p, j, r²)`), and clears them.
#[inline(always)]
fn take_held<const P: usize>(
    hits: &mut [[u8; GROUP]; P],
    starts: &[u32; GROUP],
    xyz: (&[f32], &[f32], &[f32]),
    me: [[f32; 3]; P],
    hit: &mut impl FnMut(usize, usize, f32),
) {
    for (p, (hits, me)) in hits.iter_mut().zip(me).enumerate() {
        take_hits(u128::from_le_bytes(*hits), starts, xyz, me, &mut |j, d2| {
            hit(p, j, d2)
        });
        *hits = [0; GROUP];
    }
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

/// A bit per candidate `s .. s + SHORT` with `r² < h2` from each of `me` (all of them read:
/// the arrays are padded), as two blocks of [`LANES`].
#[inline(always)]
fn piece<const P: usize>(
    (x, y, z): (&[f32], &[f32], &[f32]),
    s: usize,
    me: [[f32; 3]; P],
    h2: f32,
) -> [u8; P] {
    let (Some(bx), Some(by), Some(bz)) = (block(x, s), block(y, s), block(z, s)) else {
        return [0; P];
    };
    let ((Some(x0), Some(x1)), (Some(y0), Some(y1)), (Some(z0), Some(z1))) =
        (halves(bx), halves(by), halves(bz))
    else {
        return [0; P];
    };
    let (low, high) = ((x0, y0, z0), (x1, y1, z1));
    me.map(|me| {
        let low = within(low.0, low.1, low.2, me, h2);
        let high = within(high.0, high.1, high.2, me, h2);
        (low | high << LANES) as u8
    })
}

/// Calls `hit` for each set bit of `mask` (bit `SHORT · g + l`: particle `starts[g] + l`), in
/// bit order.
#[inline(always)]
fn take_hits(
    mut mask: u128,
    starts: &[u32; GROUP],
    (x, y, z): (&[f32], &[f32], &[f32]),
    me: [f32; 3],
    hit: &mut impl FnMut(usize, f32),
) {
    while mask != 0 {
        let bit = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let j = starts[bit / SHORT] as usize + bit % SHORT;
        let (Some(&xj), Some(&yj), Some(&zj)) = (x.get(j), y.get(j), z.get(j)) else {
            continue;
        };
        hit(j, distance_squared(me, [xj, yj, zj]));
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
