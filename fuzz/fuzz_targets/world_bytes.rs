//! Stray writes into a built world (`hairsim-ffi`): a world of either solver built and stepped
//! through the C functions, then bytes of its buffer changed (any offset, any value), then
//! stepped and checked. Checks: no panic, no out-of-bounds access (the sanitiser sees any),
//! every result a known code; a world the cheap part of the check refuses is refused by every
//! call until `hairsim_init`, which makes it anew.
#![no_main]

use std::mem::MaybeUninit;
use std::ptr;

use arbitrary::Arbitrary;
use hairsim_ffi::*;
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Input {
    dftl: bool,
    /// Steps before the writes.
    warm_up: u8,
    /// (offset, value) pairs: the byte at offset % world size becomes value.
    writes: Vec<(u32, u8)>,
    steps: u8,
}

fn vec3(x: f32, y: f32, z: f32) -> hairsim_vec3 {
    hairsim_vec3 { x, y, z }
}

/// Builds the world: the solver's preset with collisions and grabs, a head sphere, the strands
/// hanging from it, a grab on strand 0 (prescribed on the rod, coupled on DFTL).
unsafe fn build(world: *mut hairsim_world, dftl: bool) {
    let mut params = MaybeUninit::uninit();
    let solver = if dftl {
        hairsim_solver::Dftl
    } else {
        hairsim_solver::Rod
    } as u32;
    assert_eq!(
        hairsim_params_preset(solver, params.as_mut_ptr()),
        hairsim_error::Ok
    );
    let mut params = params.assume_init();
    params.effects |= HAIRSIM_EFFECT_COLLISIONS | HAIRSIM_EFFECT_GRABS;
    assert_eq!(hairsim_configure(world, &params), hairsim_error::Ok);
    let head = hairsim_collider {
        shape: hairsim_shape::Sphere as u32,
        attached_to_head: 1,
        a: vec3(0.0, 0.0, 0.0),
        b: vec3(0.0, 0.0, 0.0),
        radius: 0.05,
    };
    assert_eq!(
        hairsim_add_collider(world, &head, ptr::null_mut()),
        hairsim_error::Ok
    );
    let mut hair = MaybeUninit::uninit();
    assert_eq!(
        hairsim_material_human_hair(hair.as_mut_ptr()),
        hairsim_error::Ok
    );
    let hair = hair.assume_init();
    for s in 0..STRANDS {
        let points: Vec<hairsim_vec3> = (0..NODES)
            .map(|i| vec3(0.05 + 0.002 * s as f32, -0.01 * i as f32, 0.0))
            .collect();
        let add = hairsim_add_strand(world, points.as_ptr(), NODES, &hair, ptr::null_mut());
        assert_eq!(add, hairsim_error::Ok);
    }
    let (stiffness, damping) = if dftl { (50.0, 0.01) } else { (0.0, 0.0) };
    let grab = hairsim_grab {
        strand: 0,
        node: (NODES / 2) as u32,
        target: vec3(0.05, -0.01 * (NODES / 2) as f32, 0.0),
        force_limit: 1.0,
        stiffness,
        damping,
    };
    assert_eq!(
        hairsim_add_grab(world, &grab, ptr::null_mut()),
        hairsim_error::Ok
    );
}

fn step(world: *mut hairsim_world, k: u32) -> hairsim_error {
    let shake = hairsim_shake {
        axis: vec3(0.0, 1.0, 0.0),
        centre: vec3(0.0, 0.0, 0.0),
        amplitude: 0.5,
        frequency: 3.18,
    };
    let mut input = hairsim_step_input {
        head: hairsim_pose::default(),
        grab_targets: ptr::null(),
        grab_target_count: 0,
        accelerations: ptr::null(),
        acceleration_count: 0,
    };
    unsafe {
        assert_eq!(
            hairsim_shake_pose(&shake, (k + 1) as f32 * 0.001, &mut input.head),
            hairsim_error::Ok
        );
        hairsim_step(world, &input, ptr::null_mut())
    }
}

fuzz_target!(|input: Input| {
    let mut capacity = MaybeUninit::<hairsim_capacity>::uninit();
    unsafe { hairsim_get_capacity(capacity.as_mut_ptr()) };
    let size = unsafe { capacity.assume_init() }.world_size;
    // Exactly the world's bytes, as C's static buffer: the sanitiser sees any access past it.
    let mut buffer = vec![0u64; size.div_ceil(8)];
    let bytes = buffer.as_mut_ptr().cast::<u8>();
    let world = buffer.as_mut_ptr().cast::<hairsim_world>();
    unsafe {
        assert_eq!(hairsim_init(world, size), hairsim_error::Ok);
        build(world, input.dftl);
    }
    for k in 0..u32::from(input.warm_up % 16) {
        assert_eq!(step(world, k), hairsim_error::Ok);
    }
    for &(offset, value) in input.writes.iter().take(16) {
        unsafe { *bytes.add(offset as usize % size) = value };
    }
    let mut refused = false;
    for k in 0..u32::from(input.steps % 8) {
        let code = step(world, k);
        assert!((0..=25).contains(&(code as i32)));
        if code == hairsim_error::Corrupt {
            refused = true;
        } else {
            assert!(
                !refused,
                "a world refused as corrupt stepped after: {code:?}"
            );
        }
    }
    let checked = unsafe { hairsim_check(world) };
    assert!(matches!(
        checked,
        hairsim_error::Ok
            | hairsim_error::Corrupt
            | hairsim_error::NotInitialised
            | hairsim_error::Busy
    ));
    // `hairsim_init` makes any of them a world again (but a state word the writes left busy,
    // which only `hairsim_recover` clears).
    if checked != hairsim_error::Busy {
        unsafe {
            assert_eq!(hairsim_init(world, size), hairsim_error::Ok);
            assert_eq!(hairsim_check(world), hairsim_error::Ok);
        }
    }
});
