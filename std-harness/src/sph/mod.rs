//! Hair–hair interaction as SPH (Sánchez-Banderas et al. 2015, Sec. 3.2 and 4; Müller, Charypar,
//! Gross 2003): the *global dynamics* stage, lines 1–11 of the paper's Algorithm 1.
//!
//! Particles are the strand nodes. Each step:
//! 1. [`grid`] hashes every node into cells the size of the smoothing length `h` and sorts them
//!    by bucket with a **stable counting sort** (Algorithm 1 lines 2–4);
//! 2. positions, velocities and masses are rearranged into that order (line 5): each sorted
//!    particle's 32-byte record read once, in parallel over chunks of the sorted order;
//! 3. [`neighbours`] builds a capped neighbour list per node (the paper's rough k-nearest list,
//!    line 6) and, in the same pass, density (poly6) and pressure (line 7);
//! 4. [`forces`] computes the pressure (spiky gradient) and viscosity (viscosity Laplacian)
//!    forces (lines 8–9);
//! 5. the accelerations go back in the unsorted order, `N` slots per strand, ready for the
//!    core's per-node acceleration input (lines 10–11).
//!
//! Every buffer is sized once, when the [`Sph`] is built for a scene, and reused: a step does
//! not allocate. Work is split into fixed chunks of sorted particles and every sum over
//! neighbours runs in list order, so the result is the same bits on any number of threads.

pub mod forces;
pub mod grid;
pub mod neighbours;

use std::time::{Duration, Instant};

use hairsim_core::{Strand, Vec3};
use rayon::prelude::*;

/// Particles per parallel work item. A constant of the code, never derived from the thread
/// count, so that the split — and with it every result — is the same on any number of threads.
pub const CHUNK: usize = 1024;

pub use hairsim_files::sph::{SphParams, MAX_CAP};

/// Strands per parallel work item when the accelerations go back to the strands.
const STRANDS_PER_CHUNK: usize = 64;

/// What the SPH stage did, cumulative over steps.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SphStats {
    /// Steps the stage ran (stays 0 when `hair-hair` is off).
    pub runs: u64,
    /// Neighbours dropped by the cap, summed over steps.
    pub truncated: u64,
    /// Neighbours kept, summed over steps and particles (divide by runs × particles).
    pub neighbours: u64,
    /// Most neighbours any particle had in the last step (before the cap).
    pub max_neighbours_found: u32,
    /// Time hashing: positions and velocities read from the strands, cells and buckets.
    pub time_hash: Duration,
    /// Time in the counting sort and rearranging into the sorted order.
    pub time_sort: Duration,
    /// Time in the neighbour search, with density and pressure.
    pub time_neighbours: Duration,
    /// Time in the pressure and viscosity forces and the write-back.
    pub time_forces: Duration,
}

/// The SPH stage for one scene: the particle layout and every buffer, sized once.
#[derive(Clone, Debug)]
pub struct Sph {
    params: SphParams,
    /// Acceleration slot (`strand · N + node`) of each particle.
    slot: Vec<u32>,
    /// Strand of each particle.
    strand: Vec<u32>,
    /// Node index of each particle.
    node: Vec<u32>,
    /// Mass of each particle, kg.
    mass: Vec<f32>,
    /// First particle of each strand, and one past the last strand's.
    first: Vec<u32>,
    /// Each particle's record, unsorted order.
    record: Vec<forces::Record>,
    /// Bucket of each particle, unsorted order.
    bucket: Vec<u32>,
    grid: grid::Grid,
    sorted: forces::SortedParticles,
    neighbours: neighbours::NeighbourLists,
    /// The statistics so far.
    pub stats: SphStats,
}

impl Sph {
    /// Lays out the particles of `strands` (node `i` of strand `s` in acceleration slot
    /// `s · N + i`) and sizes every buffer.
    pub fn new<const N: usize>(params: SphParams, strands: &[Strand<N>]) -> Result<Sph, String> {
        params.validate()?;
        let count: usize = strands.iter().map(|s| s.nodes()).sum();
        u32::try_from(strands.len() * N).map_err(|_| "too many nodes for SPH")?;
        // A particle's key holds its strand and node in one u32.
        if N > 1 << neighbours::NODE_BITS || strands.len() >= 1 << (32 - neighbours::NODE_BITS) {
            return Err(format!(
                "SPH takes at most {} nodes a strand and {} strands",
                1 << neighbours::NODE_BITS,
                (1u32 << (32 - neighbours::NODE_BITS)) - 1
            ));
        }
        let mut slot = Vec::with_capacity(count);
        let mut strand_of = Vec::with_capacity(count);
        let mut node_of = Vec::with_capacity(count);
        let mut mass = Vec::with_capacity(count);
        let mut first = Vec::with_capacity(strands.len() + 1);
        for (s, strand) in strands.iter().enumerate() {
            first.push(slot.len() as u32);
            for i in 0..strand.nodes() {
                slot.push((s * N + i) as u32);
                strand_of.push(s as u32);
                node_of.push(i as u32);
                mass.push(strand.rest.mass[i]);
            }
        }
        first.push(slot.len() as u32);
        Ok(Sph {
            params,
            grid: grid::Grid::new(count, params.smoothing_length, extent(strands)),
            sorted: forces::SortedParticles::new(count),
            neighbours: neighbours::NeighbourLists::new(count, params.neighbour_cap),
            slot,
            strand: strand_of,
            node: node_of,
            mass,
            first,
            record: vec![forces::Record::default(); count],
            bucket: vec![0; count],
            stats: SphStats::default(),
        })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &SphParams {
        &self.params
    }

    /// Number of particles (nodes).
    #[must_use]
    pub fn particles(&self) -> usize {
        self.slot.len()
    }

    /// Computes the SPH accelerations of every node of `strands` (the strands [`Sph::new`]
    /// was built for), for a step of `dt` seconds (the viscosity is linearly implicit in it),
    /// into `accelerations` (`strands.len() · N` entries, node `i` of strand `s` at
    /// `s · N + i`; other entries are left untouched). Runs on the current rayon pool; the
    /// result does not depend on its size: every parallel pass writes fixed chunks, each
    /// entry a function of the inputs alone.
    pub fn accelerations<const N: usize>(
        &mut self,
        strands: &[Strand<N>],
        dt: f32,
        accelerations: &mut [Vec3],
    ) {
        let t0 = Instant::now();
        // Algorithm 1, line 2: read every node and hash it into a cell of size h.
        let (inverse_cell, layout) = (self.grid.inverse_cell(), self.grid.layout());
        let (strand, node, mass) = (&self.strand, &self.node, &self.mass);
        (
            self.record.par_chunks_mut(CHUNK),
            self.bucket.par_chunks_mut(CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(c, (record, bucket))| {
                for (k, (r, b)) in record.iter_mut().zip(bucket).enumerate() {
                    let p = c * CHUNK + k;
                    let (s, i) = (strand[p], node[p]);
                    let (x, v) = strands
                        .get(s as usize)
                        .map_or((Vec3::ZERO, Vec3::ZERO), |s| {
                            (s.state.position[i as usize], s.state.velocity[i as usize])
                        });
                    *r = forces::Record {
                        position: x.to_array(),
                        velocity: v.to_array(),
                        mass: mass[p],
                        key: s << neighbours::NODE_BITS | i,
                    };
                    *b = grid::bucket_of(grid::cell_of(x, inverse_cell), layout);
                }
            });
        let t1 = Instant::now();
        // Lines 3–5: stable counting sort by bucket, each record moved to its sorted place;
        // then the positions, masses and keys as the search reads them.
        self.grid.sort(&self.bucket);
        self.sorted.gather(&self.grid.order, &self.record);
        let t2 = Instant::now();
        // Lines 6–7: capped neighbour lists, density and pressure.
        let found = self
            .neighbours
            .build(&self.grid, &mut self.sorted, &self.params);
        let t3 = Instant::now();
        // Lines 8–9: pressure and viscosity forces.
        forces::accelerations(&mut self.sorted, &self.neighbours, &self.params, dt);
        // Lines 10–11: back to the unsorted order, as per-node accelerations.
        let (first, rank, sorted) = (&self.first, &self.grid.rank, &self.sorted.acceleration);
        accelerations
            .par_chunks_mut(STRANDS_PER_CHUNK * N)
            .enumerate()
            .for_each(|(c, out)| {
                for (k, slots) in out.chunks_mut(N).enumerate() {
                    let s = c * STRANDS_PER_CHUNK + k;
                    let (Some(&start), Some(&end)) = (first.get(s), first.get(s + 1)) else {
                        return;
                    };
                    for (a, p) in slots.iter_mut().zip(start..end) {
                        *a = sorted[rank[p as usize] as usize];
                    }
                }
            });
        let t4 = Instant::now();
        self.stats.runs += 1;
        self.stats.truncated += found.truncated;
        self.stats.neighbours += found.kept;
        self.stats.max_neighbours_found = found.max_found;
        self.stats.time_hash += t1 - t0;
        self.stats.time_sort += t2 - t1;
        self.stats.time_neighbours += t3 - t2;
        self.stats.time_forces += t4 - t3;
    }
}

/// The size of the box holding every node of `strands`, m (zero for none).
fn extent<const N: usize>(strands: &[Strand<N>]) -> [f32; 3] {
    let mut low = Vec3::splat(f32::INFINITY);
    let mut high = Vec3::splat(f32::NEG_INFINITY);
    for strand in strands {
        for &p in &strand.state.position[..strand.nodes()] {
            (low, high) = (low.min(p), high.max(p));
        }
    }
    (high - low).max(Vec3::ZERO).to_array()
}

#[cfg(test)]
mod tests {
    use super::*;
    use hairsim_core::{Material, Vec3};

    /// Strands of 8 nodes random-walking inside a 2 cm box: many neighbours, several strands.
    fn tangle(strands: usize, seed: u32) -> Vec<Strand<8>> {
        let mut state = seed.wrapping_mul(2_654_435_761).max(1);
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state as f32 / u32::MAX as f32) * 2.0 - 1.0
        };
        (0..strands)
            .map(|_| {
                let mut p = Vec3::new(next(), next(), next()) * 0.01;
                let points: Vec<Vec3> = (0..8)
                    .map(|_| {
                        let q = p;
                        p += Vec3::new(next(), next(), next()).normalize() * 0.004;
                        q
                    })
                    .collect();
                let mut s = Strand::<8>::from_polyline(&points, &Material::HUMAN_HAIR).unwrap();
                for v in s.state.velocity.iter_mut() {
                    *v = Vec3::new(next(), next(), next());
                }
                s
            })
            .collect()
    }

    /// Neighbour sets (strand, node), densities and accelerations, by particle.
    type Reference = (Vec<Vec<(u32, u32)>>, Vec<f32>, Vec<Vec3>);

    /// O(n²) reference: neighbour sets, densities and accelerations by particle.
    fn brute_force(strands: &[Strand<8>], params: &SphParams) -> Reference {
        let parts: Vec<(u32, u32, Vec3, Vec3, f32)> = strands
            .iter()
            .enumerate()
            .flat_map(|(s, st)| {
                (0..st.nodes()).map(move |i| {
                    (
                        s as u32,
                        i as u32,
                        st.state.position[i],
                        st.state.velocity[i],
                        st.rest.mass[i],
                    )
                })
            })
            .collect();
        let h = params.smoothing_length;
        let neighbours: Vec<Vec<usize>> = parts
            .iter()
            .enumerate()
            .map(|(a, pa)| {
                (0..parts.len())
                    .filter(|&b| {
                        let pb = &parts[b];
                        b != a
                            && (pa.2 - pb.2).length_squared() < h * h
                            && !(pa.0 == pb.0 && pa.1.abs_diff(pb.1) <= params.same_strand_gap)
                    })
                    .collect()
            })
            .collect();
        let density: Vec<f32> = (0..parts.len())
            .map(|a| {
                parts[a].4 * forces::poly6(0.0, h)
                    + neighbours[a]
                        .iter()
                        .map(|&b| {
                            parts[b].4
                                * forces::poly6((parts[a].2 - parts[b].2).length_squared(), h)
                        })
                        .sum::<f32>()
            })
            .collect();
        let pressure: Vec<f32> = density
            .iter()
            .map(|d| (params.stiffness * (d - params.rest_density)).max(0.0))
            .collect();
        let k = forces::spiky_viscosity_factor(h);
        let accel = (0..parts.len())
            .map(|a| {
                let mut f = Vec3::ZERO;
                let mut fv = Vec3::ZERO;
                let mut diagonal = 0.0;
                for &b in &neighbours[a] {
                    let d = parts[a].2 - parts[b].2;
                    let r = d.length();
                    let w = h - r;
                    if r > 0.0 {
                        f += d
                            * (parts[b].4 * (pressure[a] + pressure[b]) / (2.0 * density[b])
                                * k
                                * w
                                * w
                                / r);
                    }
                    let laplacian = parts[b].4 / density[b] * k * w;
                    fv += (parts[b].3 - parts[a].3) * laplacian;
                    diagonal += laplacian;
                }
                let rate = params.viscosity / density[a];
                f / density[a] + fv * (rate / (1.0 + 0.001 * rate * diagonal))
            })
            .collect();
        let sets = neighbours
            .iter()
            .map(|list| {
                let mut v: Vec<(u32, u32)> =
                    list.iter().map(|&b| (parts[b].0, parts[b].1)).collect();
                v.sort();
                v
            })
            .collect();
        (sets, density, accel)
    }

    #[test]
    fn matches_brute_force_with_the_cap_above_the_true_count() {
        for seed in 1..4 {
            let strands = tangle(40, seed);
            let params = SphParams {
                neighbour_cap: 256,
                rest_density: 0.0,
                ..SphParams::default()
            };
            let mut sph = Sph::new(params, &strands).unwrap();
            let mut acc = vec![Vec3::ZERO; strands.len() * 8];
            sph.accelerations(&strands, 0.001, &mut acc);
            assert_eq!(sph.stats.truncated, 0);
            let (sets, density, expected) = brute_force(&strands, &params);
            assert!(
                sph.stats.neighbours > 1000,
                "a dense test: {} neighbours",
                sph.stats.neighbours
            );
            // Same neighbour sets, exactly.
            for (p, &k) in sph.grid.rank.iter().enumerate() {
                let k = k as usize;
                let mut got: Vec<(u32, u32)> = sph
                    .neighbours
                    .of(k)
                    .iter()
                    .map(|&b| {
                        let key = sph.sorted.key[b as usize];
                        (key >> neighbours::NODE_BITS, key & 255)
                    })
                    .collect();
                got.sort();
                assert_eq!(got, sets[p], "particle {p}");
                let rel = (sph.sorted.density[k] - density[p]).abs() / density[p];
                assert!(rel < 1e-5, "density of {p}: {rel}");
            }
            // Same accelerations within rounding (sums run in another order).
            let scale = expected.iter().map(|a| a.length()).fold(0.0, f32::max);
            for (p, e) in expected.iter().enumerate() {
                let slot = sph.slot[p] as usize;
                assert!(
                    (acc[slot] - *e).length() <= 1e-4 * scale,
                    "acceleration of {p}: {} vs {}",
                    acc[slot],
                    e
                );
            }
        }
    }

    #[test]
    fn zero_coefficients_give_exactly_zero() {
        let strands = tangle(30, 7);
        let params = SphParams {
            stiffness: 0.0,
            viscosity: 0.0,
            ..SphParams::default()
        };
        let mut sph = Sph::new(params, &strands).unwrap();
        let mut acc = vec![Vec3::ONE; strands.len() * 8];
        sph.accelerations(&strands, 0.001, &mut acc);
        assert!(sph.stats.neighbours > 0);
        assert!(acc.iter().all(|a| *a == Vec3::ZERO));
    }

    #[test]
    fn a_small_cap_truncates_and_says_so() {
        let strands = tangle(40, 3);
        let params = SphParams {
            neighbour_cap: 2,
            ..SphParams::default()
        };
        let mut sph = Sph::new(params, &strands).unwrap();
        let mut acc = vec![Vec3::ZERO; strands.len() * 8];
        sph.accelerations(&strands, 0.001, &mut acc);
        assert!(sph.stats.truncated > 0);
        assert!(sph.stats.max_neighbours_found > 2);
        assert!(sph.neighbours.count.iter().all(|&c| c <= 2));
    }

    #[test]
    fn invalid_parameters_are_named() {
        let bad = SphParams {
            viscosity: 500.0,
            ..SphParams::default()
        };
        assert_eq!(bad.validate().unwrap_err(), "viscosity: allowed 0 to 200");
    }
}
