//! Quarantine, second half (rapier's idea): a strand whose state turns non-finite — or, with
//! inextensibility on, flies apart while staying finite — goes back to the last good state its
//! snapshot kept ([`crate::snapshot`]), with zero velocity, and the report names it. A NaN
//! never leaves a step.
//!
//! One stage for every path ([`guard`]): the rod judges a strand after its step
//! ([`sound`]); DFTL watches every value it writes during its pass and hands the guard its
//! verdict per strand or per lane ([`crate::lane::not_finite_sum`] of the velocities it
//! wrote).

use crate::math::Real;
use crate::report::{Stage, StepReport};
use crate::snapshot::{Restore, Strands};
use crate::strand::Strand;

/// How far past its arc length a node of an inextensible strand may lie from the root before
/// the strand counts as blown up. No physical state comes near it (the projection holds
/// segments within its tolerance, contacts stretch them by millimetres); a strand past it has
/// diverged to finite nonsense (seen at 10⁵–10⁹ m when a configuration is past its stability
/// limit), which a finiteness test alone lets through to the state hash and the pictures.
pub const REACH_FACTOR: Real = 2.0;

/// The guard stage: counts the strands through [`Stage::Guard`]; each strand `k` that is not
/// `good(strands, k)` goes back to `last_good` at rest, and the report names it as strand
/// `first + k`. Returns whether any strand rolled back.
#[inline(always)]
pub fn guard<S: Strands, K: Restore<S>>(
    strands: &mut S,
    last_good: &K,
    good: impl Fn(&S, usize) -> bool,
    first: u32,
    report: &mut StepReport,
) -> bool {
    let count = strands.count();
    report.ran_on(Stage::Guard, count);
    let mut rolled_back = false;
    for k in 0..count as usize {
        if good(strands, k) {
            continue;
        }
        last_good.restore(strands, k);
        report.roll_back(first.wrapping_add(k as u32));
        rolled_back = true;
    }
    rolled_back
}

/// The rod's verdict on a strand after its step: every value finite and, if `inextensible`,
/// every node within [`REACH_FACTOR`] times the rest arc length to it from the root and every
/// segment within [`REACH_FACTOR`] times its rest length. A strand whose explicit bending blew
/// up within a step (a fold tightened past what its substeps hold, under a grab moved at
/// 1 m/s) can end the step crumpled near the root with segments stretched 4- to 60-fold: the
/// first test lets that through, the second does not.
#[inline(always)]
#[must_use]
pub fn sound<const N: usize>(strand: &Strand<N>, inextensible: bool) -> bool {
    strand.is_finite() && (!inextensible || within_reach(strand))
}

/// Whether every node lies within [`REACH_FACTOR`] times its rest arc length of the root
/// (squared distances: no square root, one pass).
fn within_reach<const N: usize>(strand: &Strand<N>) -> bool {
    let n = strand.rest.nodes.min(N);
    let Some(root) = strand.state.position.first().copied() else {
        return true;
    };
    let mut arc: Real = 0.0;
    let mut ok = true;
    let position = &strand.state.position;
    for i in 1..n {
        let rest = strand.rest.segment_length[i - 1];
        arc += rest;
        let reach = REACH_FACTOR * arc;
        let d = position[i] - root;
        let e = position[i] - position[i - 1];
        let longest = REACH_FACTOR * rest;
        ok &= d.dot(d) <= reach * reach && e.dot(e) <= longest * longest;
    }
    ok
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::strand::{Material, StrandState};

    fn hanging() -> Strand<8> {
        let points: [Vec3; 5] = core::array::from_fn(|i| Vec3::new(0.0, -0.01 * i as f32, 0.0));
        Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
    }

    /// The rod's guard as its pipeline calls it.
    fn check(
        strand: &mut Strand<8>,
        good: &StrandState<8>,
        inextensible: bool,
        index: u32,
        report: &mut StepReport,
    ) -> bool {
        guard(strand, good, |s, _| sound(s, inextensible), index, report)
    }

    #[test]
    fn a_finite_blow_up_of_an_inextensible_strand_rolls_back() {
        let mut strand = hanging();
        let good = strand.state.clone();
        strand.state.position[3] = Vec3::new(1.0e5, 0.0, 0.0);
        let mut report = StepReport::default();
        assert!(strand.is_finite());
        // Extensible (inextensibility off): a finite far node is the caller's business.
        assert!(!check(&mut strand, &good, false, 7, &mut report));
        assert!(check(&mut strand, &good, true, 7, &mut report));
        assert_eq!(strand.state.position[3], good.position[3]);
        assert_eq!(report.rolled_back, 1);
        assert_eq!(report.rolled_back_strands.as_slice(), &[7]);
    }

    #[test]
    fn bent_folded_and_slightly_stretched_strands_pass() {
        let mut strand = hanging();
        let good = strand.state.clone();
        // Folded back on itself, and every segment stretched by 50 %: still within reach.
        for i in 0..5 {
            let y = if i <= 2 {
                -0.015 * i as f32
            } else {
                -0.015 * (4 - i) as f32
            };
            strand.state.position[i] = Vec3::new(0.001 * i as f32, y, 0.0);
        }
        let mut report = StepReport::default();
        assert!(!check(&mut strand, &good, true, 0, &mut report));
        assert_eq!(report.rolled_back, 0);
    }
}
