//! Quarantine (rapier's idea): a strand whose state turns non-finite goes back to its last
//! good state with zero velocity, and the report names it. A NaN never leaves a step.

use crate::report::{Stage, StepReport};
use crate::strand::{Strand, StrandState};

/// Checks `strand` after its step; if any value is non-finite, restores `last_good`, zeroes the
/// velocities and records the strand in `report`. Returns whether it rolled back.
pub fn check<const N: usize>(
    strand: &mut Strand<N>,
    last_good: &StrandState<N>,
    index: u32,
    report: &mut StepReport,
) -> bool {
    report.ran(Stage::Guard);
    if strand.is_finite() {
        return false;
    }
    strand.state.clone_from(last_good);
    let n = strand.rest.nodes;
    for v in &mut strand.state.velocity[..n] {
        *v = crate::math::Vec3::ZERO;
    }
    report.roll_back(index);
    true
}
