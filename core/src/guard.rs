//! Quarantine (rapier's idea): a strand whose state turns non-finite — or, with
//! inextensibility on, flies apart while staying finite — goes back to its last good state with
//! zero velocity, and the report names it. A NaN never leaves a step.

use crate::math::{Real, Vec3};
use crate::report::{Stage, StepReport};
use crate::strand::{Strand, StrandState};

/// How far past its arc length a node of an inextensible strand may lie from the root before
/// the strand counts as blown up. No physical state comes near it (the projection holds
/// segments within its tolerance, contacts stretch them by millimetres); a strand past it has
/// diverged to finite nonsense (seen at 10⁵–10⁹ m when a configuration is past its stability
/// limit), which a finiteness test alone lets through to the state hash and the pictures.
pub const REACH_FACTOR: Real = 2.0;

/// Checks `strand` after its step; if any value is non-finite, or `inextensible` and a node
/// lies farther from the root than [`REACH_FACTOR`] times the arc length to it, restores
/// `last_good`, zeroes the velocities and records the strand in `report`. Returns whether it
/// rolled back.
pub fn check<const N: usize>(
    strand: &mut Strand<N>,
    last_good: &StrandState<N>,
    inextensible: bool,
    index: u32,
    report: &mut StepReport,
) -> bool {
    report.ran(Stage::Guard);
    if strand.is_finite() && (!inextensible || within_reach(strand)) {
        return false;
    }
    strand.state.clone_from(last_good);
    stop_and_report(strand, index, report);
    true
}

/// The guard with its verdict already known, for a solver that watched every value it wrote
/// (the DFTL step, [`crate::dftl::velocity::not_finite`]) and writes positions and velocities
/// only (no twist, no root frame): a strand that is not `good` gets `last_good`, its positions
/// at the start of the step, back — the last good state, since a roll-back zeroes the
/// velocities anyway — and the report names it, as in [`check`]. Returns whether it rolled
/// back.
pub fn restore_positions_unless<const N: usize>(
    good: bool,
    strand: &mut Strand<N>,
    last_good: &[Vec3; N],
    index: u32,
    report: &mut StepReport,
) -> bool {
    report.ran(Stage::Guard);
    if good {
        return false;
    }
    strand.state.position = *last_good;
    stop_and_report(strand, index, report);
    true
}

/// The rest of a roll-back: the restored strand starts from rest, and the report names it.
fn stop_and_report<const N: usize>(strand: &mut Strand<N>, index: u32, report: &mut StepReport) {
    let n = strand.rest.nodes;
    for v in strand.state.velocity.iter_mut().take(n) {
        *v = Vec3::ZERO;
    }
    report.roll_back(index);
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
    for i in 1..n {
        arc += strand.rest.segment_length[i - 1];
        let reach = REACH_FACTOR * arc;
        let d = strand.state.position[i] - root;
        ok &= d.dot(d) <= reach * reach;
    }
    ok
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::strand::Material;

    fn hanging() -> Strand<8> {
        let points: [Vec3; 5] = core::array::from_fn(|i| Vec3::new(0.0, -0.01 * i as f32, 0.0));
        Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
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
