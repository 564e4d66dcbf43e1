//! The stretch a rod step reports when no projection measured it (`inextensibility`,
//! `collisions` and `grabs` all off): the report's `max_stretch` in every configuration, so
//! that a strand left extensible and pulled long raises [`crate::report::Flags::STRETCHED`]
//! instead of stretching silently. The projection (`projection::record`) and DFTL's pass
//! (`dftl::measures`) measure it themselves when they run.

use crate::math::{Math, Real};
use crate::report::StepReport;
use crate::strand::Strand;

/// Folds `strand`'s largest relative stretch `||e| − |ê|| / |ê|` over its segments into
/// `report.max_stretch` (one square root a segment: only when no projection ran).
pub fn record_stretch<M: Math, const N: usize>(strand: &Strand<N>, report: &mut StepReport) {
    let n = strand.rest.nodes.min(N);
    let x = &strand.state.position;
    let mut largest: Real = 0.0;
    for j in 0..n.saturating_sub(1) {
        let rest = strand.rest.segment_length[j];
        let e = x[j + 1] - x[j];
        largest = largest.max((M::sqrt(e.dot(e)) - rest).abs() / rest);
    }
    report.max_stretch = report.max_stretch.max(largest);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Libm, Vec3};
    use crate::strand::Material;

    #[test]
    fn a_strand_pulled_long_reports_its_stretch() {
        let points: [Vec3; 4] = core::array::from_fn(|i| Vec3::new(0.0, -0.01 * i as Real, 0.0));
        let mut strand = Strand::<4>::from_polyline(&points, &Material::HUMAN_HAIR).unwrap();
        let mut report = StepReport::default();
        record_stretch::<Libm, 4>(&strand, &mut report);
        assert!(report.max_stretch < 1e-6, "{}", report.max_stretch);
        strand.state.position[3].y = -0.035;
        record_stretch::<Libm, 4>(&strand, &mut report);
        assert!(
            (report.max_stretch - 0.5).abs() < 1e-4,
            "{}",
            report.max_stretch
        );
    }
}
