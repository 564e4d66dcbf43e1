//! The particles that have candidates, compacted: what a step between rebuilds works on
//! (Algorithm 1 line 5, rearranging into the sorted order, for these alone). A particle with
//! no candidate has no neighbour until the next rebuild and an acceleration of zero, so a
//! scene where little touches costs the check of the skin and little else.

use hairsim_core::{Strand, Vec3};
use rayon::prelude::*;

use super::neighbours::{CandidateLists, Sorted, NODE_BITS, ROOM};
use super::CHUNK;

/// The active particles (in the grid's sorted order at the last rebuild), their candidate
/// lists in active indices, and what a step gathers and computes for them.
#[derive(Clone, Debug, Default)]
pub struct Active {
    /// Each active particle's acceleration slot (`strand · N + node`).
    pub slot: Vec<u32>,
    /// Each active particle's key, `strand << NODE_BITS | node`.
    pub key: Vec<u32>,
    /// Each active particle's mass, kg.
    pub mass: Vec<f32>,
    /// Candidate lists of chunk `c` (active particles `c · CHUNK ..`), one after another.
    pub lists: Vec<Vec<u32>>,
    /// Where each active particle's candidates start in its chunk's vector.
    pub start: Vec<u32>,
    /// How many candidates each active particle has.
    pub count: Vec<u32>,
    /// Positions in the world this step, m, and a fourth entry of zero (16 bytes a particle).
    pub position: Vec<[f32; 4]>,
    /// Velocities this step, m/s.
    pub velocity: Vec<[f32; 3]>,
    /// Scratch of a rebuild: the sorted index of each chunk's first active particle.
    firsts: Vec<u32>,
}

impl Active {
    /// Room for `particles` active particles with [`ROOM`] candidates each.
    #[must_use]
    pub fn with_room(particles: usize) -> Active {
        let chunks = particles.div_ceil(CHUNK);
        Active {
            slot: Vec::with_capacity(particles),
            key: Vec::with_capacity(particles),
            mass: Vec::with_capacity(particles),
            lists: (0..chunks)
                .map(|_| Vec::with_capacity(CHUNK * ROOM))
                .collect(),
            start: Vec::with_capacity(particles),
            count: Vec::with_capacity(particles),
            position: Vec::with_capacity(particles),
            velocity: Vec::with_capacity(particles),
            firsts: Vec::with_capacity(chunks),
        }
    }

    /// How many particles are active.
    #[must_use]
    pub fn len(&self) -> usize {
        self.slot.len()
    }

    /// Whether no particle is active.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.slot.is_empty()
    }

    /// The candidates of active particle `a`.
    #[inline]
    #[must_use]
    pub fn candidates(&self, a: usize) -> &[u32] {
        let (start, count) = (self.start[a] as usize, self.count[a] as usize);
        self.lists
            .get(a / CHUNK)
            .and_then(|l| l.get(start..start + count))
            .unwrap_or(&[])
    }

    /// The particles of `candidates` that have candidates, in sorted order, with their lists
    /// turned into active indices. `sorted` gives each sorted particle's key, `slot_of` and
    /// `mass_of` the slot and mass of a key's particle. `active_of` is scratch of one entry
    /// a sorted particle.
    pub fn rebuild(
        &mut self,
        candidates: &CandidateLists,
        sorted: &Sorted,
        active_of: &mut [u32],
        (slot_of, mass_of): (impl Fn(u32) -> u32, impl Fn(u32) -> f32),
    ) {
        self.slot.clear();
        self.key.clear();
        self.mass.clear();
        for (k, (&count, index)) in candidates
            .count
            .iter()
            .zip(active_of.iter_mut())
            .enumerate()
        {
            *index = u32::MAX;
            if count > 0 {
                *index = self.slot.len() as u32;
                let key = sorted.key[k];
                self.slot.push(slot_of(key));
                self.key.push(key);
                self.mass.push(mass_of(key));
            }
        }
        let n = self.slot.len();
        let chunks = n.div_ceil(CHUNK);
        self.lists
            .resize_with(chunks.max(self.lists.len()), Vec::new);
        self.start.resize(n, 0);
        self.count.resize(n, 0);
        self.position.resize(n, [0.0; 4]);
        self.velocity.resize(n, [0.0; 3]);
        // Where each chunk's first active particle is in the sorted order.
        let active_of = &*active_of;
        first_of_each_chunk(active_of, &mut self.firsts);
        let positions = &self.firsts;
        self.lists[..chunks]
            .par_iter_mut()
            .zip(self.start[..n].par_chunks_mut(CHUNK))
            .zip(self.count[..n].par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, ((list, start), count))| {
                list.clear();
                let mut a = c * CHUNK;
                // Sorted particles from the chunk's first active one on, until the chunk is full.
                let mut k = positions.get(c).copied().unwrap_or(u32::MAX) as usize;
                while a < (c + 1) * CHUNK && a < n && k < active_of.len() {
                    if active_of[k] != u32::MAX {
                        start[a - c * CHUNK] = list.len() as u32;
                        let of = candidates.of(k);
                        list.extend(of.iter().map(|&j| active_of[j as usize]));
                        count[a - c * CHUNK] = of.len() as u32;
                        a += 1;
                    }
                    k += 1;
                }
            });
    }

    /// This step's positions and velocities of the active particles, from `strands`.
    pub fn gather<const N: usize>(&mut self, strands: &[Strand<N>]) {
        let key = &self.key;
        self.position
            .par_chunks_mut(CHUNK)
            .zip(self.velocity.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, (position, velocity))| {
                for (i, (x, v)) in position.iter_mut().zip(velocity).enumerate() {
                    let k = key[c * CHUNK + i];
                    let (s, node) = ((k >> NODE_BITS) as usize, (k & 255) as usize);
                    let (p, u) = strands.get(s).map_or((Vec3::ZERO, Vec3::ZERO), |s| {
                        (s.state.position[node % N], s.state.velocity[node % N])
                    });
                    *x = [p.x, p.y, p.z, 0.0];
                    *v = u.to_array();
                }
            });
    }
}

/// The sorted index of the first active particle of each chunk of `CHUNK` active particles,
/// into `firsts`.
fn first_of_each_chunk(active_of: &[u32], firsts: &mut Vec<u32>) {
    firsts.clear();
    for (k, &a) in active_of.iter().enumerate() {
        if a != u32::MAX && a as usize % CHUNK == 0 {
            firsts.push(k as u32);
        }
    }
}
