//! DFTL hair resting on the head at 1 kHz: two grooms lying on a head sphere, still and
//! shaken, at Δt = 0.5, 1, 4 and 16.7 ms (`docs/design-departures.md`, "DFTL: hair resting
//! on the head").
//!
//! The grooms (`tests/grooming.rs`): `sintel_hair.tfx` in `hairsim run`'s default scene, whose
//! head sphere touches the scalp at its lowest held node, and a generated groom of 300 wavy and
//! curly strands of 40 nodes combed down over a 9 cm head ([`combed_strands`]). Each is run as
//! `tests/groom.rs` runs a groom, and measured as it measures one (the worst sample every
//! 50 ms over the last 0.5 s of 1 s still), with its head as it is and shrunk 1 cm (no
//! contact). Bounds, at every step:
//! - under 1 % of the nodes kinked and the mean turning angle within max(1.25×, + 0.015 rad)
//!   of the rest groom's, still and after the shake;
//! - not frozen by contact: the mean tip sag after 1 s still and the mean tip excursion while
//!   the head shakes within 0.67–1.5× of the same groom on the shrunk head;
//! - no node faster than the head's rigid motion at its place + 1 m/s, stretch ≤ 1e-5;
//! - the combed groom does rest on the head: at least a tenth of its nodes in contact.
//!
//! [`combed_strands`]: hairsim_tests::grooming::combed_strands

use hairsim::sim::Layout;
use hairsim_core::Real;
use hairsim_tests::grooming::{resting_scene, shaken, still, RESTING};

/// The steps of the test: 0.5, 1, 4 and 16.7 ms (SB15's 60 Hz).
const STEPS: [Real; 4] = [0.0005, 0.001, 0.004, 1.0 / 60.0];

/// The head shrunk by this much takes no contact, m.
const SHRINK: Real = 0.01;

/// Whether `value` is within `low`–`high` × `reference`.
fn within(value: Real, reference: Real, low: Real, high: Real) -> bool {
    value >= low * reference && value <= high * reference
}

fn rests_on_the_head(name: &str) {
    for dt in STEPS {
        let start = std::time::Instant::now();
        let on = resting_scene(name, dt, 0.0);
        let off = resting_scene(name, dt, SHRINK);
        let (s, k) = (still(&on, Layout::Blocks), shaken(&on, Layout::Blocks));
        let (free, free_shaken) = (still(&off, Layout::Blocks), shaken(&off, Layout::Blocks));
        let rest = s.rest_turning;
        let turning = (1.25 * rest).max(rest + 0.015);
        let nodes = s.groom.nodes as Real;
        println!(
            "{name} {:.1} ms | kinked {:.2} % (after the shake {:.2} %) | turning {:.4} (after \
             {:.4}; rest {rest:.4}, bound {turning:.4}) | in contact {:.1} % | sag {:.2} mm, \
             free {:.2} ({:.2}x) | excursion {:.2} mm, free {:.2} ({:.2}x) | excess {:.2} m/s | \
             stretch {:.1e} | {:.1} s",
            dt * 1e3,
            s.groom.kinked * 100.0,
            k.groom_after.kinked * 100.0,
            s.groom.mean_turning,
            k.groom_after.mean_turning,
            100.0 * s.contacts / nodes,
            s.sag * 1e3,
            free.sag * 1e3,
            s.sag / free.sag,
            k.excursion * 1e3,
            free_shaken.excursion * 1e3,
            k.excursion / free_shaken.excursion,
            k.speed_excess,
            s.stretch.max(k.stretch),
            start.elapsed().as_secs_f32(),
        );
        assert!(
            free.contacts == 0.0,
            "{name} at {dt}: the shrunk head touched"
        );
        if name == "combed" {
            assert!(s.contacts >= 0.1 * nodes, "{name} at {dt}: not resting");
        }
        for (groom, what) in [(s.groom, "still"), (k.groom_after, "after the shake")] {
            assert!(groom.kinked < 0.01, "{name} at {dt}: kinked {what}");
            assert!(
                groom.mean_turning <= turning,
                "{name} at {dt}: turning {what}"
            );
        }
        assert!(k.speed_excess < 1.0, "{name} at {dt}: flutter");
        assert!(s.stretch.max(k.stretch) <= 1e-5, "{name} at {dt}: stretch");
        assert!(within(s.sag, free.sag, 0.67, 1.5), "{name} at {dt}: sag");
        assert!(
            within(k.excursion, free_shaken.excursion, 0.67, 1.5),
            "{name} at {dt}: excursion"
        );
    }
}

#[test]
fn the_sample_rests_on_its_head() {
    rests_on_the_head(RESTING[0]);
}

#[test]
fn the_combed_groom_rests_on_its_head() {
    rests_on_the_head(RESTING[1]);
}
