//! The state hash: FNV-1a 64 over the bit patterns of the whole state.
//!
//! Order, for each strand in index order:
//! 1. the node count `n` as a little-endian `u32`;
//! 2. for each node `i = 0 … n−1`: position x, y, z, then velocity x, y, z;
//! 3. for each node slot `j = 0 … n−1`: the twist angle `θ^j` (the last slot is unused and 0);
//! 4. the root frame vector `u^0`: x, y, z.
//!
//! Every `f32` goes in as the little-endian bytes of its bit pattern, so `-0.0` and `0.0`
//! differ. The guard never lets a NaN into the state, so NaN payloads (which differ between
//! x86 and ARM) never reach the hash.
//!
//! Neither the rest data nor a strand's [`Schedule`](crate::strand::Schedule) is hashed. Rest
//! data never changes once a strand is built. The schedule (whether the rod takes the implicit
//! bending step from now on) is a decision the steps derive from the states they passed
//! through, so it adds nothing a comparison of states would not see a step later: two runs
//! whose schedules part ways also part ways in their states. What the hash pins is the
//! physical state, the one thing host and firmware, a recording and its replay, and the
//! golden tables compare; a decision about how to compute the next step is not part of it
//! (and hashing it would change every pinned hash for no new information).

use crate::math::{Real, Vec3};
use crate::strand::Strand;

/// FNV-1a 64-bit offset basis.
pub const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
/// FNV-1a 64-bit prime.
pub const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// An FNV-1a 64 hasher.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Fnv1a(FNV_OFFSET)
    }
}

impl Fnv1a {
    /// Hashes `bytes`.
    #[inline]
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(FNV_PRIME);
        }
    }
    /// Hashes a `u32` as little-endian bytes.
    #[inline]
    pub fn write_u32(&mut self, v: u32) {
        self.write(&v.to_le_bytes());
    }
    /// Hashes the bit pattern of an `f32`.
    #[inline]
    pub fn write_real(&mut self, v: Real) {
        self.write_u32(v.to_bits());
    }
    /// Hashes x, y, z.
    #[inline]
    pub fn write_vec3(&mut self, v: Vec3) {
        self.write_real(v.x);
        self.write_real(v.y);
        self.write_real(v.z);
    }
    /// Hashes one strand's state in the documented order.
    pub fn write_strand<const N: usize>(&mut self, strand: &Strand<N>) {
        let n = strand.rest.nodes.min(N);
        self.write_u32(n as u32);
        for i in 0..n {
            self.write_vec3(strand.state.position[i]);
            self.write_vec3(strand.state.velocity[i]);
        }
        for &theta in &strand.state.theta[..n] {
            self.write_real(theta);
        }
        self.write_vec3(strand.state.root_frame);
    }
    /// The hash so far.
    #[must_use]
    pub const fn finish(&self) -> u64 {
        self.0
    }
}

/// The state hash of `strands`, in index order.
#[must_use]
pub fn state_hash<const N: usize>(strands: &[Strand<N>]) -> u64 {
    let mut h = Fnv1a::default();
    for s in strands {
        h.write_strand(s);
    }
    h.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_reference_values() {
        // Published FNV-1a 64 test vectors.
        let mut h = Fnv1a::default();
        assert_eq!(h.finish(), 0xcbf29ce484222325);
        h.write(b"a");
        assert_eq!(h.finish(), 0xaf63dc4c8601ec8c);
        let mut h = Fnv1a::default();
        h.write(b"foobar");
        assert_eq!(h.finish(), 0x85944171f73967e8);
    }

    #[test]
    fn sign_of_zero_changes_the_hash() {
        let mut a = Fnv1a::default();
        a.write_real(0.0);
        let mut b = Fnv1a::default();
        b.write_real(-0.0);
        assert_ne!(a.finish(), b.finish());
    }
}
