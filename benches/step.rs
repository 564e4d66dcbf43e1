//! The firmware scene's step, as a first benchmark of the real step path.

use criterion::{criterion_group, criterion_main, Criterion};
use hairsim_core::scenes::firmware;
use hairsim_core::{Libm, World};

fn firmware_step(c: &mut Criterion) {
    let mut world: Box<World<{ firmware::STRANDS }, { firmware::NODES }, Libm>> = Box::default();
    firmware::build(&mut world).unwrap();
    let mut k = 0u32;
    c.bench_function("firmware scene step", |b| {
        b.iter(|| {
            let report = firmware::step(&mut world, k);
            k = k.wrapping_add(1);
            report
        })
    });
}

criterion_group!(benches, firmware_step);
criterion_main!(benches);
