//! Hair–hair interaction as SPH (Sánchez-Banderas et al. 2015, Sec. 3.2 and 4; Müller, Charypar,
//! Gross 2003): the *global dynamics* stage, lines 1–11 of the paper's Algorithm 1.
//!
//! Particles are the strand nodes. The paper hashes, sorts and searches every particle at
//! every step; here the search keeps its lists for as long as they are sure to hold every
//! pair within the smoothing length `h` (Verlet lists with a skin, measured in the head's
//! frame: [`skin`]), and a step works only on the particles that have a candidate. Each step:
//! 1. [`skin`] reads every node and checks whether one has moved by half the skin since the
//!    lists were built; if so, or at the first step, or where the last rebuild found that no
//!    skin would make the lists last (the check is then skipped), the lists are rebuilt:
//!    [`grid`] hashes every node (in the head's frame) into cells of `h + skin` and sorts them
//!    by bucket with a stable counting sort (Algorithm 1 lines 2–4), and [`neighbours`] lists
//!    each particle's candidates within `h + skin`; [`active`] keeps the particles that have
//!    one, in the sorted order, and turns the lists into indices among them;
//! 2. [`active`] gathers this step's positions and velocities of the active particles (line 5);
//! 3. [`density`] filters each one's candidates by `r < h` (line 6, the cap applied to the
//!    smallest keys), with density and pressure (line 7);
//! 4. [`forces`] computes the pressure (spiky gradient) and viscosity (viscosity Laplacian)
//!    forces (lines 8–9);
//! 5. the accelerations go to their slots, `N` per strand, ready for the core's per-node
//!    acceleration input (lines 10–11); a particle with no candidate has zero.
//!
//! A step's result is a function of the state alone: every pair within `h` is a candidate
//! whatever the lists' age, the cap picks by key, and every sum over neighbours has the same
//! bits in any order ([`sum`]). So the bits are the same on any number of threads, from run to
//! run, and when a run is restarted from a recorded state with new lists.
//!
//! Buffers are sized when the [`Sph`] is built for a scene and reused; the candidate lists
//! start with room for [`neighbours::ROOM`] candidates a particle and keep the capacity they
//! grow to, so a step allocates only when the hair packs more densely than ever before.

pub mod active;
pub mod density;
pub mod forces;
pub mod grid;
pub mod neighbours;
pub mod skin;
pub mod sum;

use std::time::{Duration, Instant};

use hairsim_core::{Pose, Strand, Vec3};
use rayon::prelude::*;

/// Particles per parallel work item. A constant of the code, never derived from the thread
/// count, so that the split — and with it every result — is the same on any number of threads.
pub const CHUNK: usize = 1024;

pub use hairsim_files::sph::{SphParams, MAX_CAP};

/// Strands per parallel work item when the accelerations go back to the strands.
const STRANDS_PER_CHUNK: usize = 64;

/// The skin, as a share of `h`, at the start, and the least and most it becomes: the lists hold
/// pairs within `h + skin` and are rebuilt once a node has moved `skin / 2` in the head's frame.
/// A larger skin makes rebuilds rarer and every step's filter longer. At a rebuild the skin is
/// set for the lists to last [`LASTING`] steps at the pace the fastest node moved since the
/// last one; where even the largest skin would not make them last that long, rebuilds come at
/// every step anyway, the skin is the least and the next step rebuilds without reading every
/// node first to check (the rebuild measures the moves as it reads them). It changes the cost,
/// never the result.
pub const SKIN: [f32; 3] = [0.5, 0.05, 1.0];

/// The steps a list is sized to last.
pub const LASTING: f32 = 4.0;

/// What the SPH stage did, cumulative over steps.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SphStats {
    /// Steps the stage ran (stays 0 when `hair-hair` is off).
    pub runs: u64,
    /// Steps that rebuilt the candidate lists.
    pub rebuilds: u64,
    /// Neighbours dropped by the cap, summed over steps.
    pub truncated: u64,
    /// Neighbours kept, summed over steps and particles (divide by runs × particles).
    pub neighbours: u64,
    /// Candidates, summed over steps and particles.
    pub candidates: u64,
    /// Particles with a candidate, summed over steps.
    pub active: u64,
    /// Most neighbours any particle had in the last step (before the cap).
    pub max_neighbours_found: u32,
    /// Time reading the nodes: the skin's check and, at a rebuild, the cells and buckets.
    pub time_hash: Duration,
    /// Time in the counting sort and rearranging into the sorted order (at a rebuild), and
    /// in gathering the active particles' positions and velocities (every step).
    pub time_sort: Duration,
    /// Time in the candidate search (at a rebuild), and in filtering the candidates, with
    /// density and pressure (every step).
    pub time_neighbours: Duration,
    /// Time in the pressure and viscosity forces and the write-back.
    pub time_forces: Duration,
}

/// The SPH stage for one scene: the particle layout and every buffer, sized once.
#[derive(Clone, Debug)]
pub struct Sph {
    params: SphParams,
    /// The skin, m.
    skin: f32,
    /// Steps since the last rebuild.
    since_rebuild: u64,
    /// Whether the last rebuild found that even the largest skin would not make the lists
    /// last: the next step rebuilds without checking the moves first.
    every_step: bool,
    /// How far the fastest node had moved since the rebuild before, measured at the last
    /// rebuild, m (infinite when unknown).
    last_move: f32,
    /// Acceleration slot (`strand · N + node`) of each particle.
    slot: Vec<u32>,
    /// Key (`strand << NODE_BITS | node`) of each particle.
    key: Vec<u32>,
    /// Mass of each particle, kg.
    mass: Vec<f32>,
    /// First particle of each strand, and one past the last strand's.
    first: Vec<u32>,
    /// Each particle's position in the head's frame, at the last rebuild.
    reference: skin::Reference,
    /// Bucket of each particle, at the last rebuild.
    bucket: Vec<u32>,
    grid: grid::Grid,
    sorted: neighbours::Sorted,
    candidates: neighbours::CandidateLists,
    /// How many candidates the lists hold.
    candidate_count: u64,
    /// Scratch of a rebuild: each sorted particle's active index.
    active_of: Vec<u32>,
    /// Each particle's active index, `u32::MAX` for none.
    particle_active: Vec<u32>,
    active: active::Active,
    neighbours: density::Neighbours,
    acceleration: Vec<Vec3>,
    /// The accelerations of every slot, zero where a particle has no candidate.
    output: Vec<Vec3>,
    /// Whether a node of each strand has a neighbour this step.
    acting: Vec<bool>,
    /// The strands `acting` marks, when it was written strand by strand.
    marked: Vec<u32>,
    /// Whether `acting` was written for every strand (`marked` then means nothing).
    marked_all: bool,
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
        let mut key = Vec::with_capacity(count);
        let mut mass = Vec::with_capacity(count);
        let mut first = Vec::with_capacity(strands.len() + 1);
        for (s, strand) in strands.iter().enumerate() {
            first.push(slot.len() as u32);
            for i in 0..strand.nodes() {
                slot.push((s * N + i) as u32);
                key.push((s as u32) << neighbours::NODE_BITS | i as u32);
                mass.push(strand.rest.mass[i]);
            }
        }
        first.push(slot.len() as u32);
        let skin = params.smoothing_length * SKIN[0];
        Ok(Sph {
            params,
            skin,
            since_rebuild: 0,
            every_step: false,
            last_move: f32::INFINITY,
            grid: grid::Grid::new(count, params.smoothing_length + skin, extent(strands)),
            sorted: neighbours::Sorted::new(count),
            candidates: neighbours::CandidateLists::new(count),
            candidate_count: 0,
            reference: skin::Reference::new(count),
            active_of: vec![u32::MAX; count],
            particle_active: vec![u32::MAX; count],
            active: active::Active::with_room(count),
            neighbours: density::Neighbours::with_room(count, params.neighbour_cap),
            acceleration: Vec::with_capacity(count),
            output: vec![Vec3::ZERO; strands.len() * N],
            acting: vec![false; strands.len()],
            marked: Vec::with_capacity(strands.len()),
            marked_all: true,
            slot,
            key,
            mass,
            first,
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

    /// The accelerations of the last step, `N` entries per strand (node `i` of strand `s` at
    /// `s · N + i`; zero where no neighbour acts and in the entries of no node).
    #[must_use]
    pub fn output(&self) -> &[Vec3] {
        &self.output
    }

    /// Each particle's density in the last step, kg/m³, in the particle order (strand by
    /// strand): its own mass's term alone where it has no candidate.
    #[must_use]
    pub fn densities(&self) -> Vec<f32> {
        let h2 = self.params.smoothing_length * self.params.smoothing_length;
        let own = forces::poly6_factor(self.params.smoothing_length) * h2 * h2 * h2;
        (0..self.particles())
            .map(|p| match self.particle_active[p] {
                u32::MAX => own * self.mass[p],
                a => self.neighbours.density[a as usize],
            })
            .collect()
    }

    /// Whether a node of each strand had a neighbour in the last step: the strands whose
    /// [`Sph::output`] may be other than zero.
    #[must_use]
    pub fn acting(&self) -> &[bool] {
        &self.acting
    }

    /// Computes the SPH accelerations of every node of `strands` (the strands [`Sph::new`]
    /// was built for), for a step of `dt` seconds (the viscosity is linearly implicit in it),
    /// `head` being the head's pose at the state's time (any pose gives the same result; the
    /// head's makes rebuilds rare), and returns them as [`Sph::output`]. Runs on the current
    /// rayon pool; the result does not depend on its size.
    pub fn accelerations<const N: usize>(
        &mut self,
        strands: &[Strand<N>],
        dt: f32,
        head: Pose,
    ) -> &[Vec3] {
        let t0 = Instant::now();
        let frame = skin::Frame::of(head);
        self.since_rebuild += 1;
        // Where the lists cannot last a step, reading every node to find that out is skipped:
        // the rebuild measures the moves as it reads the nodes anyway.
        let (moved, furthest) = if self.every_step {
            (true, self.last_move)
        } else {
            self.reference
                .moved(strands, &self.first, &frame, self.skin)
        };
        let mut times = [t0.elapsed(), Duration::ZERO, Duration::ZERO];
        if moved {
            self.adapt_skin(furthest);
            times = self.rebuild(strands, &frame, t0);
        }
        let t1 = Instant::now();
        self.active.gather(strands);
        let t2 = Instant::now();
        let found = self.neighbours.find(&self.active, &self.params);
        let t3 = Instant::now();
        forces::accelerations(&self.neighbours, &self.params, dt, &mut self.acceleration);
        self.write_back::<N>();
        let t4 = Instant::now();
        let stats = &mut self.stats;
        stats.runs += 1;
        stats.rebuilds += u64::from(moved);
        stats.truncated += found.truncated;
        stats.neighbours += found.kept;
        stats.candidates += self.candidate_count;
        stats.active += self.active.len() as u64;
        stats.max_neighbours_found = found.max_found;
        stats.time_hash += times[0];
        stats.time_sort += times[1] + (t2 - t1);
        stats.time_neighbours += times[2] + (t3 - t2);
        stats.time_forces += t4 - t3;
        &self.output
    }

    /// Rebuilds the candidate lists of `strands` in `frame` (the cells, the counting sort, the
    /// search) and the active particles. Returns the time hashing, sorting and searching.
    fn rebuild<const N: usize>(
        &mut self,
        strands: &[Strand<N>],
        frame: &skin::Frame,
        t0: Instant,
    ) -> [Duration; 3] {
        // The particles active until now have no acceleration unless they still are.
        for &slot in &self.active.slot {
            if let Some(a) = self.output.get_mut(slot as usize) {
                *a = Vec3::ZERO;
            }
        }
        self.grid.set_cell(self.params.smoothing_length + self.skin);
        // Algorithm 1, line 2: every node in the frame, and its cell's bucket.
        let (inverse_cell, layout) = (self.grid.inverse_cell(), self.grid.layout());
        let key = &self.key;
        let built = self.reference.built;
        let (largest, furthest) = (
            self.reference.position.par_chunks_mut(CHUNK),
            self.bucket.par_chunks_mut(CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .map(|(c, (reference, bucket))| {
                let (mut largest, mut furthest) = (0.0f32, 0.0f32);
                for (k, (r, b)) in reference.iter_mut().zip(bucket).enumerate() {
                    let own = key[c * CHUNK + k];
                    let (s, i) = (
                        (own >> neighbours::NODE_BITS) as usize,
                        (own & 255) as usize,
                    );
                    let x = strands
                        .get(s)
                        .map_or(Vec3::ZERO, |s| s.state.position[i % N]);
                    let y = frame.local(x);
                    largest = largest.max(x.abs().max_element().max(y.abs().max_element()));
                    furthest = skin::further(furthest, (y - Vec3::from_array(*r)).length_squared());
                    *r = y.to_array();
                    *b = grid::bucket_of(grid::cell_of(y, inverse_cell), layout);
                }
                (largest, furthest)
            })
            .reduce(
                || (0.0, 0.0),
                |a, b| (a.0.max(b.0), skin::further(a.1, b.1)),
            );
        self.last_move = if built {
            furthest.sqrt()
        } else {
            f32::INFINITY
        };
        self.reference.largest = largest;
        self.reference.built = true;
        let t1 = Instant::now();
        // Lines 3–5: stable counting sort by bucket; the positions and keys as the search
        // reads them.
        self.grid.sort(&self.bucket);
        self.sorted
            .gather(&self.grid.order, &self.reference.position, &self.key);
        let t2 = Instant::now();
        // Line 6: every pair within h + skin.
        let reach = self.params.smoothing_length + self.skin;
        let gap = self.params.same_strand_gap;
        self.candidate_count = self.candidates.build(&self.grid, &self.sorted, reach, gap);
        let (slot, mass) = (&self.slot, &self.mass);
        let first = &self.first;
        let particle = move |k: u32| {
            let s = (k >> neighbours::NODE_BITS) as usize;
            first.get(s).map_or(0, |&f| f as usize + (k & 255) as usize)
        };
        self.active.rebuild(
            &self.candidates,
            &self.sorted,
            &mut self.active_of,
            (
                |k| slot.get(particle(k)).copied().unwrap_or(u32::MAX),
                |k| mass.get(particle(k)).copied().unwrap_or(0.0),
            ),
        );
        let n = self.active.len();
        self.neighbours.resize(n, self.params.neighbour_cap);
        self.acceleration.resize(n, Vec3::ZERO);
        self.index_active::<N>();
        let t3 = Instant::now();
        [t1 - t0, t2 - t1, t3 - t2]
    }

    /// The skin for the rebuild about to be made, from how far the fastest node moved since
    /// the last one (`furthest`, m).
    fn adapt_skin(&mut self, furthest: f32) {
        let h = self.params.smoothing_length;
        let steps = std::mem::take(&mut self.since_rebuild).max(1) as f32;
        if !furthest.is_finite() {
            return;
        }
        let wanted = 2.0 * LASTING * furthest / steps;
        self.every_step = wanted > h * SKIN[2];
        self.skin = if self.every_step {
            h * SKIN[1]
        } else {
            wanted.max(h * SKIN[1])
        };
    }

    /// The active particles' accelerations into their slots, and which strands they act on:
    /// by strands in parallel when most particles are active, one by one when few are.
    fn write_back<const N: usize>(&mut self) {
        let (slots, acceleration) = (&self.active.slot, &self.acceleration);
        let count = &self.neighbours.count;
        if slots.len() * 4 < self.slot.len() {
            if self.marked_all {
                self.acting.fill(false);
            } else {
                for &s in &self.marked {
                    self.acting[s as usize] = false;
                }
            }
            self.marked_all = false;
            let marked = &mut self.marked;
            marked.clear();
            for (a, (&slot, &acc)) in slots.iter().zip(acceleration).enumerate() {
                if let Some(out) = self.output.get_mut(slot as usize) {
                    *out = acc;
                }
                let s = slot as usize / N;
                if count[a] > 0 && !self.acting[s] {
                    self.acting[s] = true;
                    marked.push(s as u32);
                }
            }
            return;
        }
        self.marked_all = true;
        let (first, active_of) = (&self.first, &self.particle_active);
        self.output
            .par_chunks_mut(STRANDS_PER_CHUNK * N)
            .zip(self.acting.par_chunks_mut(STRANDS_PER_CHUNK))
            .enumerate()
            .for_each(|(c, (out, acting))| {
                for (k, (slots, acting)) in out.chunks_mut(N).zip(acting).enumerate() {
                    let s = c * STRANDS_PER_CHUNK + k;
                    let (Some(&start), Some(&end)) = (first.get(s), first.get(s + 1)) else {
                        return;
                    };
                    *acting = false;
                    for (out, p) in slots.iter_mut().zip(start..end) {
                        let a = active_of.get(p as usize).copied().unwrap_or(u32::MAX) as usize;
                        *out = acceleration.get(a).copied().unwrap_or(Vec3::ZERO);
                        *acting |= count.get(a).is_some_and(|&c| c > 0);
                    }
                }
            });
    }

    /// Each particle's active index (`u32::MAX` for none), from the active particles' slots.
    fn index_active<const N: usize>(&mut self) {
        self.particle_active.fill(u32::MAX);
        for (a, &slot) in self.active.slot.iter().enumerate() {
            let (s, i) = (slot as usize / N, slot as usize % N);
            let p = self.first.get(s).map_or(usize::MAX, |&f| f as usize + i);
            if let Some(entry) = self.particle_active.get_mut(p) {
                *entry = a as u32;
            }
        }
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
    use hairsim_core::{Material, Quat, Vec3};

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

    /// The accelerations of `strands` through `sph`, in the world's frame.
    fn step(sph: &mut Sph, strands: &[Strand<8>]) -> Vec<Vec3> {
        sph.accelerations(strands, 0.001, Pose::IDENTITY).to_vec()
    }

    /// Each particle's neighbours as (strand, node), sorted, and its density.
    fn found(sph: &Sph) -> Vec<(Vec<(u32, u32)>, f32)> {
        let mut by_particle = vec![(Vec::new(), 0.0); sph.particles()];
        for a in 0..sph.active.len() {
            let key = sph.active.key[a];
            let p =
                sph.first[(key >> neighbours::NODE_BITS) as usize] as usize + (key & 255) as usize;
            let mut got: Vec<(u32, u32)> = sph
                .neighbours
                .of(a)
                .iter()
                .map(|&b| {
                    let key = sph.active.key[b as usize];
                    (key >> neighbours::NODE_BITS, key & 255)
                })
                .collect();
            got.sort();
            by_particle[p] = (got, sph.neighbours.density[a]);
        }
        by_particle
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
            let acc = step(&mut sph, &strands);
            assert_eq!(sph.stats.truncated, 0);
            let (sets, density, expected) = brute_force(&strands, &params);
            assert!(
                sph.stats.neighbours > 1000,
                "a dense test: {} neighbours",
                sph.stats.neighbours
            );
            // Same neighbour sets, exactly; the same densities within rounding.
            for (p, (got, rho)) in found(&sph).into_iter().enumerate() {
                assert_eq!(got, sets[p], "particle {p}");
                if !got.is_empty() {
                    let rel = (rho - density[p]).abs() / density[p];
                    assert!(rel < 1e-5, "density of {p}: {rel}");
                }
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

    /// A tangle of 40 strands and a stage for it, the rest density low enough to push.
    fn tangle_and_stage(seed: u32) -> (Vec<Strand<8>>, Sph) {
        let strands = tangle(40, seed);
        let params = SphParams {
            rest_density: 0.5,
            ..SphParams::default()
        };
        let stage = Sph::new(params, &strands).unwrap();
        (strands, stage)
    }

    /// Steps `kept` on `strands` with the head at `head`, and a stage built anew with the head
    /// at rest: the same bits, or the test fails at step `k`.
    fn same_bits_as_fresh(kept: &mut Sph, strands: &[Strand<8>], head: Pose, k: usize) {
        let bits = |v: &[Vec3]| {
            v.iter()
                .map(|v| v.to_array().map(f32::to_bits))
                .collect::<Vec<_>>()
        };
        let params = *kept.params();
        let a = bits(kept.accelerations(strands, 0.001, head));
        let mut fresh = Sph::new(params, strands).unwrap();
        let b = bits(fresh.accelerations(strands, 0.001, Pose::IDENTITY));
        assert_eq!(a, b, "step {k}");
    }

    #[test]
    fn the_result_does_not_depend_on_the_lists_age_nor_on_the_frame() {
        // One Sph steps along a drifting, turning tangle (its lists rebuilt now and then),
        // another is built anew at every step (its lists fresh): the same bits each step.
        let (mut strands, mut kept) = tangle_and_stage(5);
        for k in 0..40 {
            let head = Pose {
                position: Vec3::new(0.001 * k as f32, 0.0, 0.0),
                rotation: hairsim_core::Quat::from_rotation_y(0.05 * k as f32),
            };
            same_bits_as_fresh(&mut kept, &strands, head, k);
            // Each node drifts by its velocity (0.1 to 1 mm a step) and the whole turns with
            // the head.
            for s in &mut strands {
                for i in 0..8 {
                    let v = s.state.velocity[i] * 0.0005;
                    s.state.position[i] =
                        Quat::from_rotation_y(0.05).mul_vec3(s.state.position[i] + v);
                }
            }
        }
        assert!(
            (2..40).contains(&kept.stats.rebuilds),
            "the lists were kept and rebuilt: {} rebuilds",
            kept.stats.rebuilds
        );
        assert!(kept.stats.neighbours > 1000);
    }

    #[test]
    fn skipping_the_check_where_lists_cannot_last_changes_no_bit() {
        // The tangle moves fast (up to 3.5 mm a step, h = 1 cm: no skin lasts four steps),
        // then stands still, then moves again: the kept stage rebuilds without the check
        // while it moves, keeps its lists while it stands, and every step has the bits of a
        // stage built anew.
        let (mut strands, mut kept) = tangle_and_stage(9);
        let (mut skipped, mut kept_lists) = (0, 0);
        for k in 0..60 {
            let (skipping, rebuilds) = (kept.every_step, kept.stats.rebuilds);
            same_bits_as_fresh(&mut kept, &strands, Pose::IDENTITY, k);
            skipped += u32::from(skipping);
            kept_lists += u32::from(kept.stats.rebuilds == rebuilds);
            let pace = if (20..40).contains(&k) { 0.0 } else { 0.002 };
            for s in &mut strands {
                for i in 0..8 {
                    let v = s.state.velocity[i] * pace;
                    s.state.position[i] += v;
                }
            }
        }
        assert!(
            skipped >= 30 && kept_lists >= 15,
            "{skipped} skipped, {kept_lists} kept"
        );
        assert!(kept.stats.neighbours > 100);
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
        let acc = step(&mut sph, &strands);
        assert!(sph.stats.neighbours > 0);
        assert!(acc.iter().all(|a| *a == Vec3::ZERO));
    }

    #[test]
    fn a_small_cap_keeps_the_smallest_keys_and_says_so() {
        let strands = tangle(40, 3);
        let params = SphParams {
            neighbour_cap: 2,
            ..SphParams::default()
        };
        let mut sph = Sph::new(params, &strands).unwrap();
        step(&mut sph, &strands);
        assert!(sph.stats.truncated > 0);
        assert!(sph.stats.max_neighbours_found > 2);
        assert!(sph.neighbours.count.iter().all(|&c| c <= 2));
        // The two kept are the two smallest keys of the uncapped set.
        let mut all = Sph::new(
            SphParams {
                neighbour_cap: 256,
                ..params
            },
            &strands,
        )
        .unwrap();
        step(&mut all, &strands);
        for (capped, uncapped) in found(&sph).into_iter().zip(found(&all)) {
            let smallest: Vec<_> = uncapped.0.iter().take(2).copied().collect();
            assert_eq!(capped.0, smallest);
        }
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
