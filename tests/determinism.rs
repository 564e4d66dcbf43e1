//! Same inputs, same bits: across runs, and through glam's math going to `libm`.

use hairsim_core::scenes::firmware;
use hairsim_core::{Libm, World};

fn run() -> u64 {
    let mut world: Box<World<{ firmware::STRANDS }, { firmware::NODES }, Libm>> = Box::default();
    firmware::run(&mut world, 300).unwrap()
}

#[test]
fn two_runs_give_the_same_state_hash() {
    let a = run();
    assert_eq!(a, run());
    assert_ne!(a, 0);
}

/// Workspace feature unification must never switch glam's math from `libm` to the platform's:
/// glam's transcendental functions must give `libm`'s bits, here where `std` is linked.
#[test]
fn glam_math_goes_through_libm() {
    for i in 0..20_000 {
        let angle = -50.0 + i as f32 * 0.005_123;
        let v = glam::Vec2::from_angle(angle);
        let (s, c) = libm::sincosf(angle);
        assert_eq!(
            (v.y.to_bits(), v.x.to_bits()),
            (s.to_bits(), c.to_bits()),
            "angle {angle}"
        );
    }
}
