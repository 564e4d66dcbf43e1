//! Quarantine, first half (rapier's idea): before a step, keep each strand's last good state,
//! which the guard ([`crate::guard`]) gives back to a strand the step turned non-finite.
//!
//! One stage for every path: the rod's strands, DFTL's strands and DFTL's structure-of-arrays
//! blocks all keep their last good state through [`snapshot`], each keeping what its solver
//! writes ([`LastGood`]): the rod writes the whole state; DFTL writes positions and velocities
//! only, and a roll-back zeroes the velocities, so a DFTL strand keeps its positions (less than
//! half the state's bytes). A block keeps its state array whole, which is one contiguous copy
//! (`dftl::block::BlockState` says why).

use crate::math::Vec3;
use crate::report::{Stage, StepReport};
use crate::strand::{Strand, StrandState};

/// Strands a step quarantines: one strand, or a block of strands in lanes.
pub trait Strands {
    /// How many strands (a block's lanes in use).
    fn count(&self) -> u32;
}

/// What a snapshot keeps of strands `S`, and how a roll-back puts strand `k` back: its last good
/// state, with zero velocity.
pub trait LastGood<S: ?Sized>: Sized {
    /// The last good state of `strands`.
    fn keep(strands: &S) -> Self;
    /// Strand `k` of `strands` back to this state, at rest.
    fn restore(&self, strands: &mut S, k: usize);
}

/// The snapshot stage: counts the strands through [`Stage::Snapshot`] and keeps their last good
/// state as `K`.
#[inline(always)]
#[must_use]
pub fn snapshot<S: Strands, K: LastGood<S>>(strands: &S, report: &mut StepReport) -> K {
    report.ran_on(Stage::Snapshot, strands.count());
    K::keep(strands)
}

impl<const N: usize> Strands for Strand<N> {
    #[inline(always)]
    fn count(&self) -> u32 {
        1
    }
}

/// The rod's last good state: all of it (positions, velocities, twist, root frame).
impl<const N: usize> LastGood<Strand<N>> for StrandState<N> {
    #[inline(always)]
    fn keep(strand: &Strand<N>) -> Self {
        strand.state.clone()
    }

    #[inline(always)]
    fn restore(&self, strand: &mut Strand<N>, _: usize) {
        strand.state.clone_from(self);
        stop(strand);
    }
}

/// DFTL's last good state: the positions at the start of the step (DFTL writes no twist and no
/// root frame, and a roll-back zeroes the velocities).
#[derive(Clone, Debug, PartialEq)]
pub struct Positions<const N: usize>(pub [Vec3; N]);

impl<const N: usize> LastGood<Strand<N>> for Positions<N> {
    #[inline(always)]
    fn keep(strand: &Strand<N>) -> Self {
        Positions(strand.state.position)
    }

    #[inline(always)]
    fn restore(&self, strand: &mut Strand<N>, _: usize) {
        strand.state.position = self.0;
        stop(strand);
    }
}

/// A restored strand starts from rest.
#[inline(always)]
fn stop<const N: usize>(strand: &mut Strand<N>) {
    let n = strand.rest.nodes;
    for v in strand.state.velocity.iter_mut().take(n) {
        *v = Vec3::ZERO;
    }
}
