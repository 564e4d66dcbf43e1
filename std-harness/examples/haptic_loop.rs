//! The closed haptic loop of `hairsim::haptic`: a device of 0.1 kg with 0.3 N·s/m of its own
//! damping at 1 kHz renders a coupled grab on a 30-node strand's tip; a hand drags it 5 cm
//! past the strand's reach, holds and lets go, 100 times. Prints, for each solver and for the
//! rendered coupling inside the sampled-data passivity bound and 4× past it, the force held,
//! the kinetic energy after each release against the energy the coupling's spring held, and
//! how fast it dies away against a free device.
//!
//! `cargo run --release -p hairsim --example haptic_loop [pulls]`

use hairsim::haptic::{run, LoopSetup};
use hairsim_core::Solver;

fn main() {
    let pulls = std::env::args()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .unwrap_or(100);
    for solver in [Solver::Rod, Solver::Dftl] {
        // G K = 50 N/m renders 2 N at the hold; G B = 0.1 N·s/m: 0.42 b. Then 4 b.
        for (gain, damping) in [(50.0, 0.002), (2400.0, 0.0)] {
            let setup = LoopSetup {
                pulls,
                ..LoopSetup::standard(solver, gain, damping)
            };
            let result = run(&setup);
            let count = result.len() as f64;
            let held = result.iter().map(|p| p.held_force).sum::<f64>() / count;
            let given_back = result
                .iter()
                .map(|p| p.peak_energy / p.released_energy)
                .fold(0.0, f64::max);
            let above = result
                .iter()
                .map(|p| p.above_free_decay)
                .fold(0.0, f64::max);
            let slowest = result
                .iter()
                .map(|p| p.settle.unwrap_or(f64::INFINITY))
                .fold(0.0, f64::max);
            println!(
                "{solver:?}: G {gain}, bound ratio {:.2}: held {held:.3} N over {} pulls; \
                 kinetic energy after a release at most {given_back:.3} of the spring's; \
                 at most {above:.3}x a free device's decay; 1 % after at most {slowest:.3} s \
                 (a free device: {:.3} s)",
                setup.bound_ratio(),
                result.len(),
                setup.free_settle()
            );
        }
    }
}
