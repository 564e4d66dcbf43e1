//! Quarantine, first half (rapier's idea): before a step, keep each strand's last good state,
//! which the guard ([`crate::guard`]) gives back to a strand the step turned non-finite.
//!
//! One stage for every path: the rod's strands, DFTL's strands and DFTL's structure-of-arrays
//! blocks all keep their last good state, each keeping what its solver writes: the rod writes
//! the whole state and keeps it through [`snapshot`] ([`LastGood`]); DFTL writes positions and
//! velocities only, and a roll-back zeroes the velocities, so a DFTL strand keeps its
//! positions, as its pass reads them ([`snapshot_as_passed`], [`PassedPositions`]). A block
//! keeps its state array whole, which is one contiguous copy (`dftl::block::BlockState` says
//! why).

use crate::math::Vec3;
use crate::report::{Stage, StepReport};
use crate::strand::{Strand, StrandState};

/// Strands a step quarantines: one strand, or a block of strands in lanes.
pub trait Strands {
    /// How many strands (a block's lanes in use).
    fn count(&self) -> u32;
}

/// How a roll-back puts strand `k` of strands `S` back: to its last good state, with zero
/// velocity.
pub trait Restore<S: ?Sized> {
    /// Strand `k` of `strands` back to this state, at rest.
    fn restore(&self, strands: &mut S, k: usize);
}

/// What a snapshot keeps of strands `S` ([`Restore`] puts it back).
pub trait LastGood<S: ?Sized>: Sized + Restore<S> {
    /// The last good state of `strands`.
    fn keep(strands: &S) -> Self;
}

/// The snapshot stage: counts the strands through [`Stage::Snapshot`] and keeps their last good
/// state as `K`.
#[inline(always)]
#[must_use]
pub fn snapshot<S: Strands, K: LastGood<S>>(strands: &S, report: &mut StepReport) -> K {
    report.ran_on(Stage::Snapshot, strands.count());
    K::keep(strands)
}

/// The snapshot stage of one rod strand, its last good state kept in `kept` (a buffer its
/// caller keeps: returned, the state was a copy on the stack, 460 bytes at 16 nodes).
#[inline(always)]
pub fn snapshot_into<const N: usize>(
    strand: &Strand<N>,
    kept: &mut StrandState<N>,
    report: &mut StepReport,
) {
    report.ran_on(Stage::Snapshot, strand.count());
    kept.clone_from(&strand.state);
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
}

impl<const N: usize> Restore<Strand<N>> for StrandState<N> {
    #[inline(always)]
    fn restore(&self, strand: &mut Strand<N>, _: usize) {
        strand.state.clone_from(self);
        stop(strand);
    }
}

/// DFTL's last good positions kept as a step goes ([`snapshot_as_passed`]): nodes 0 and 1
/// before the root coupling moves them, every other node by the pass as it reads the node's
/// position before it writes it (`pipeline::dftl`). No copy of the strand's positions ahead of
/// its step: on the Cortex-M4F that copy was 187 instructions of a strand of 16 nodes, the
/// three stores a node in the pass fewer. A roll-back puts back the strand's nodes.
pub struct PassedPositions<'a, const N: usize>(pub &'a [Vec3; N]);

/// The snapshot stage of a strand whose pass keeps its positions as it goes
/// ([`PassedPositions`]): counts the strand through [`Stage::Snapshot`] and keeps nodes 0 and
/// 1 in `kept`, whose nodes from 2 on the pass fills.
#[inline(always)]
pub fn snapshot_as_passed<const N: usize>(
    strand: &Strand<N>,
    kept: &mut [Vec3; N],
    report: &mut StepReport,
) {
    report.ran_on(Stage::Snapshot, strand.count());
    for (k, &p) in kept.iter_mut().zip(&strand.state.position).take(2) {
        *k = p;
    }
}

impl<const N: usize> Restore<Strand<N>> for PassedPositions<'_, N> {
    #[inline(always)]
    fn restore(&self, strand: &mut Strand<N>, _: usize) {
        let n = strand.rest.nodes.min(N);
        for (x, &kept) in strand.state.position.iter_mut().zip(self.0.iter()).take(n) {
            *x = kept;
        }
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
