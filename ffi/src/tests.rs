//! The C functions called from Rust: the firmware scene through them gives the core's hash,
//! the helpers give the scene's bits, and every refused case has its code.
// Every pointer passed below is to a live local or buffer of the stated type and length, or
// deliberately NULL, misaligned or overlapping the world (which the functions refuse unread).
#![allow(clippy::undocumented_unsafe_blocks)]

use std::boxed::Box;
use std::format;
use std::vec;
use std::vec::Vec;

use hairsim_core::scenes::firmware;
use hairsim_core::{DefaultMath, World};

use crate::scene_header::{self, Scene};
use crate::*;

use hairsim_error as E;

/// A zeroed, 8-byte aligned buffer of `WORLD_SIZE` bytes, as a C `static` would be.
struct Storage(Vec<u64>);

impl Storage {
    fn new() -> Storage {
        Storage(vec![0; WORLD_SIZE.div_ceil(8) + 1])
    }
    fn world(&mut self) -> *mut hairsim_world {
        self.0.as_mut_ptr().cast()
    }
    fn len(&self) -> usize {
        self.0.len() * 8
    }
    fn init(&mut self) -> *mut hairsim_world {
        let len = self.len();
        let world = self.world();
        assert_eq!(unsafe { hairsim_init(world, len) }, E::Ok);
        world
    }
}

fn step_time(k: u32, dt: f32) -> f32 {
    (k + 1) as f32 * dt
}

/// Builds the firmware scene through the C functions, as the C programs do.
fn build(world: *mut hairsim_world, scene: &Scene) {
    unsafe {
        assert_eq!(hairsim_configure(world, &scene.params), E::Ok);
        for c in &scene.colliders {
            assert_eq!(hairsim_add_collider(world, c, ptr::null_mut()), E::Ok);
        }
        for (s, points) in scene.strands.iter().enumerate() {
            let mut index = u32::MAX;
            let code = hairsim_add_strand(
                world,
                points.as_ptr(),
                points.len(),
                &scene.material,
                &mut index,
            );
            assert_eq!((code, index), (E::Ok, s as u32));
        }
        for g in &scene.grabs {
            assert_eq!(hairsim_add_grab(world, g, ptr::null_mut()), E::Ok);
        }
    }
}

fn step(world: *mut hairsim_world, scene: &Scene, k: u32) -> hairsim_step_report {
    let t = step_time(k, scene.params.dt);
    let mut input = hairsim_step_input {
        head: hairsim_pose::default(),
        grab_targets: ptr::null(),
        grab_target_count: 0,
        accelerations: ptr::null(),
        acceleration_count: 0,
    };
    let mut targets = [hairsim_vec3::default(); HAIRSIM_MAX_GRABS];
    let mut report = core::mem::MaybeUninit::<hairsim_step_report>::uninit();
    unsafe {
        assert_eq!(hairsim_shake_pose(&scene.shake, t, &mut input.head), E::Ok);
        for (target, circle) in targets.iter_mut().zip(&scene.circles) {
            assert_eq!(hairsim_circle_target(circle, t, target), E::Ok);
        }
        input.grab_targets = targets.as_ptr();
        input.grab_target_count = scene.circles.len();
        assert_eq!(hairsim_step(world, &input, report.as_mut_ptr()), E::Ok);
        report.assume_init()
    }
}

fn hash(world: *mut hairsim_world) -> u64 {
    let mut h = 0;
    assert_eq!(unsafe { hairsim_state_hash(world, &mut h) }, E::Ok);
    h
}

fn rust_firmware_hash() -> u64 {
    let mut world: Box<World<{ firmware::STRANDS }, { firmware::NODES }, DefaultMath>> =
        Box::default();
    firmware::run(&mut world, firmware::STEPS).unwrap()
}

/// Bytes of a world of `S` strands of `N` nodes, for each capacity of a grid: what
/// [`world_size_formula`] is fitted to and checked against.
macro_rules! world_sizes {
    ($($s:literal x [$($n:literal),*]),*) => {
        [$($(($s, $n, core::mem::size_of::<CellOf<$s, $n>>()),)*)*]
    };
}

/// `(A, B, C, D)` of `A + B N + S (C + D N)`: the bytes a world of `S` strands of `N` nodes
/// needs at most, measured on this 64-bit host (a 32-bit target's world is no larger: only its
/// `usize` fields shrink). A world is a fixed part, a scratch space that grows with `N`, and
/// `S` strands of `C + D N` bytes each (exactly: the strand and its rest data's checksum);
/// the fixed part and the scratch space are rounded to 8 bytes at a few places, so `A + B N`
/// is their upper envelope.
fn world_size_formula() -> (usize, usize, usize, usize) {
    let sizes = world_sizes!(
        1 x [3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 15, 16, 17, 23, 24, 31, 32, 33, 48, 63, 64,
             100, 127, 128, 255, 256, 511, 1000, 1024, 2047, 4096],
        2 x [3, 4, 5, 16, 17, 64, 4096],
        3 x [3, 16, 33],
        8 x [3, 24, 32, 1000],
        64 x [7, 16, 32],
        4096 x [3, 4096]
    );
    let size = |s, n| sizes.iter().find(|&&(a, b, _)| (a, b) == (s, n)).unwrap().2;
    // Per strand, from the most strands and two at two node counts (a strand's checksum is
    // 4 bytes: over one strand, the 8-byte rounding hides it).
    let strand = |n| (size(4096, n) - size(2, n)).div_ceil(4096 - 2);
    let d = (strand(4096) - strand(3)) / (4096 - 3);
    let c = strand(3) - 3 * d;
    // The rest: its slope from the fewest nodes to the most, rounded up, then the least
    // intercept that covers every point of the grid, plus one 8-byte rounding for the node
    // counts between them.
    let rest = |n: usize| size(1, n) - (c + d * n);
    let b = (rest(4096) - rest(3)).div_ceil(4096 - 3);
    let ones = sizes.iter().filter(|t| t.0 == 1).map(|t| t.1);
    let a = ones.map(|n| rest(n) as i64 - (b * n) as i64).max().unwrap() + 8;
    let a = usize::try_from(a).expect("the fixed part is positive");
    for &(s, n, bytes) in &sizes {
        let formula = a + b * n + s * (c + d * n);
        assert!(bytes <= formula, "{s} x {n}: {bytes} > {formula}");
        assert!(
            formula - bytes <= 8 * 16,
            "{s} x {n}: {bytes} far below {formula}"
        );
    }
    (a, b, c, d)
}

/// `generate-header.sh` reads the capacities' defaults and the world's size formula from here.
#[test]
fn header_defines() {
    let (a, b, c, d) = world_size_formula();
    assert!(a + b * NODES + STRANDS * (c + d * NODES) >= WORLD_SIZE);
    let text = format!(
        "/**
 * The capacities the library was built with (HAIRSIM_STRANDS and HAIRSIM_NODES in cargo's
 * environment; 4 and 16 when unset). Define them to the library's before including this
 * header when they are not the defaults: hairsim_init refuses a world of other capacities.
 */
#ifndef HAIRSIM_STRANDS
#define HAIRSIM_STRANDS 4
#endif
#ifndef HAIRSIM_NODES
#define HAIRSIM_NODES 16
#endif
/**
 * Bytes of a world buffer of `strands` strands of `nodes` nodes: measured on a 64-bit host,
 * no fewer than a 32-bit target needs (hairsim_get_capacity gives the running target's own).
 */
#define HAIRSIM_WORLD_SIZE_FOR(strands, nodes) \\
  ((size_t){a}u + (size_t){b}u * (size_t)(nodes) + \\
   (size_t)(strands) * ((size_t){c}u + (size_t){d}u * (size_t)(nodes)))
/** Bytes of a world buffer at HAIRSIM_STRANDS and HAIRSIM_NODES. */
#define HAIRSIM_WORLD_SIZE HAIRSIM_WORLD_SIZE_FOR(HAIRSIM_STRANDS, HAIRSIM_NODES)
/** Alignment of a world buffer, bytes. */
#define HAIRSIM_WORLD_ALIGN {WORLD_ALIGN}"
    );
    std::println!("@HAIRSIM_CAPACITY_BEGIN@\n{text}\n@HAIRSIM_CAPACITY_END@");
    const { assert!(usize::BITS == 64, "measure on a 64-bit host") };
}

#[test]
fn the_capacity_function_tells_the_layout() {
    assert_eq!(WORLD_ALIGN, 8);
    let mut capacity = hairsim_capacity::default();
    assert_eq!(unsafe { hairsim_get_capacity(&mut capacity) }, E::Ok);
    assert_eq!(capacity.world_size, WORLD_SIZE);
    assert_eq!(
        (capacity.strands, capacity.nodes),
        (STRANDS as u32, NODES as u32)
    );
    std::println!("world: {WORLD_SIZE} bytes, aligned to {WORLD_ALIGN}");
}

#[test]
fn init_refuses_a_header_of_another_version_or_capacity() {
    let mut storage = Storage::new();
    let (world, len) = (storage.world(), storage.len());
    let (strands, nodes) = (STRANDS as u32, NODES as u32);
    let init = |version, strands, nodes| unsafe {
        hairsim_init_versioned(world, len, version, strands, nodes)
    };
    let version = |major: u32, minor: u32, patch: u32| (major << 16) | (minor << 8) | patch;
    assert_eq!(hairsim_version(), HAIRSIM_VERSION);
    assert_eq!(
        env!("CARGO_PKG_VERSION"),
        format!("{HAIRSIM_VERSION_MAJOR}.{HAIRSIM_VERSION_MINOR}.{HAIRSIM_VERSION_PATCH}")
    );
    let (major, minor) = (HAIRSIM_VERSION_MAJOR, HAIRSIM_VERSION_MINOR);
    for refused in [
        version(major + 1, minor, 0),
        version(major, minor + 1, 0),
        version(major, minor.wrapping_sub(1) & 0xff, 0),
        0,
        u32::MAX,
    ] {
        assert_eq!(
            init(refused, strands, nodes),
            E::VersionMismatch,
            "{refused:#x}"
        );
    }
    assert_eq!(
        init(HAIRSIM_VERSION, strands + 1, nodes),
        E::StrandsMismatch
    );
    assert_eq!(init(HAIRSIM_VERSION, strands, nodes - 1), E::NodesMismatch);
    // A version mismatch is told first: the other numbers may mean something else there.
    assert_eq!(init(0, strands + 1, nodes + 1), E::VersionMismatch);
    // Refused before the buffer is touched: NULL is not looked at.
    let refused = unsafe { hairsim_init_versioned(ptr::null_mut(), 0, 0, strands, nodes) };
    assert_eq!(refused, E::VersionMismatch);
    let mut h = 0;
    assert_eq!(
        unsafe { hairsim_state_hash(world, &mut h) },
        E::NotInitialised
    );
    // Another patch version works.
    let patched = version(major, minor, HAIRSIM_VERSION_PATCH + 1);
    assert_eq!(init(patched, strands, nodes), E::Ok);
    assert_eq!(init(HAIRSIM_VERSION, strands, nodes), E::Ok);
}

#[test]
fn presets_are_hair_and_effects_that_are_off_refuse_what_needs_them() {
    let preset = |solver: u32| {
        let mut p = hairsim_params::default();
        (unsafe { hairsim_params_preset(solver, &mut p) }, p)
    };
    let (code, rod) = preset(hairsim_solver::Rod as u32);
    assert_eq!(code, E::Ok);
    let rod_effects = HAIRSIM_EFFECT_GRAVITY
        | HAIRSIM_EFFECT_DRAG
        | HAIRSIM_EFFECT_BENDING
        | HAIRSIM_EFFECT_TWIST
        | HAIRSIM_EFFECT_INEXTENSIBILITY;
    assert_eq!(
        (rod.effects, rod.solver),
        (rod_effects, hairsim_solver::Rod as u32)
    );
    assert!(rod.drag > 0.0 && rod.gravity.y < 0.0);
    let mut default = hairsim_params::default();
    assert_eq!(unsafe { hairsim_params_default(&mut default) }, E::Ok);
    assert_eq!(default, rod);
    let (code, dftl) = preset(hairsim_solver::Dftl as u32);
    assert_eq!(code, E::Ok);
    let dftl_effects = HAIRSIM_EFFECT_GRAVITY
        | HAIRSIM_EFFECT_DRAG
        | HAIRSIM_EFFECT_INEXTENSIBILITY
        | HAIRSIM_EFFECT_SHAPE;
    assert_eq!(
        (dftl.effects, dftl.solver),
        (dftl_effects, hairsim_solver::Dftl as u32)
    );
    assert_eq!(preset(2).0, E::OutOfRange);

    let scene = Scene::firmware();
    let mut storage = Storage::new();
    let world = storage.init();
    let (mut collider, grab) = (scene.colliders[0], scene.grabs[0]);
    // Away from the strand: holding the grab takes no fight with a contact.
    collider.a.y -= 1.0;
    // 16 cm across, rooted at the origin: gravity pulls it long without inextensibility.
    let points: Vec<hairsim_vec3> = (0..NODES)
        .map(|i| hairsim_vec3 {
            x: 0.16 * i as f32 / (NODES - 1) as f32,
            ..Default::default()
        })
        .collect();
    let material = scene.material;
    let flags_of_steps = |world, steps: u32| {
        let mut flags = 0;
        for _ in 0..steps {
            let mut report = core::mem::MaybeUninit::uninit();
            let code = unsafe { hairsim_step(world, &input(identity()), report.as_mut_ptr()) };
            assert_eq!(code, E::Ok);
            flags |= unsafe { report.assume_init() }.flags;
        }
        flags
    };
    unsafe {
        assert_eq!(hairsim_configure(world, &rod), E::Ok);
        let add = hairsim_add_strand(world, points.as_ptr(), NODES, &material, ptr::null_mut());
        assert_eq!(add, E::Ok);
        assert_eq!(
            hairsim_add_collider(world, &collider, ptr::null_mut()),
            E::EffectOff
        );
        assert_eq!(
            hairsim_add_grab(world, &grab, ptr::null_mut()),
            E::EffectOff
        );
        // The preset holds the strand's length.
        assert_eq!(flags_of_steps(world, 100) & HAIRSIM_FLAG_STRETCHED, 0);
        let mut on = rod;
        on.effects |= HAIRSIM_EFFECT_COLLISIONS | HAIRSIM_EFFECT_GRABS;
        assert_eq!(hairsim_configure(world, &on), E::Ok);
        assert_eq!(
            hairsim_add_collider(world, &collider, ptr::null_mut()),
            E::Ok
        );
        // Held where node 3 is now.
        let mut now = [hairsim_vec3::default(); NODES];
        let copied = hairsim_strand_positions(world, 0, now.as_mut_ptr(), NODES, ptr::null_mut());
        assert_eq!(copied, E::Ok);
        let grab = hairsim_grab {
            strand: 0,
            node: 3,
            target: now[3],
            force_limit: 10.0,
            ..Default::default()
        };
        assert_eq!(hairsim_add_grab(world, &grab, ptr::null_mut()), E::Ok);
        let inactive = HAIRSIM_FLAG_COLLIDERS_INACTIVE | HAIRSIM_FLAG_GRABS_INACTIVE;
        assert_eq!(flags_of_steps(world, 1) & inactive, 0);
        // Switched off on purpose: they stay, and the report says they did nothing.
        assert_eq!(hairsim_configure(world, &rod), E::Ok);
        assert_eq!(flags_of_steps(world, 1) & inactive, inactive);
        // Gravity alone: the strand stretches, and the report says so.
        let mut loose = rod;
        loose.effects = HAIRSIM_EFFECT_GRAVITY;
        assert_eq!(hairsim_configure(world, &loose), E::Ok);
        assert_ne!(flags_of_steps(world, 100) & HAIRSIM_FLAG_STRETCHED, 0);
    }
}

/// The last refusal of `world`: code, function, argument, field and index.
fn last(world: *mut hairsim_world) -> (i32, std::string::String, u32) {
    let mut r = core::mem::MaybeUninit::<hairsim_refusal>::uninit();
    assert_eq!(
        unsafe { hairsim_last_refusal(world, r.as_mut_ptr()) },
        E::Ok
    );
    let r = unsafe { r.assume_init() };
    let text = |p| unsafe { core::ffi::CStr::from_ptr(p) }.to_str().unwrap();
    let mut what = std::string::String::from(text(r.function));
    for (separator, part) in [(" ", text(r.argument)), (".", text(r.field))] {
        if !part.is_empty() {
            what = what + separator + part;
        }
    }
    (r.code, what, r.index)
}

#[test]
fn refusals_name_the_argument_the_field_and_the_element() {
    let scene = Scene::firmware();
    let mut storage = Storage::new();
    let world = storage.init();
    let expect = |code: E, what: &str, index: u32| {
        let (c, w, i) = last(world);
        assert_eq!((c, w.as_str(), i), (code as i32, what, index));
    };
    let none = u32::MAX;
    expect(E::Ok, "", none);
    unsafe {
        let mut p = scene.params;
        p.dt = f32::NAN;
        assert_eq!(hairsim_configure(world, &p), E::NotFinite);
        expect(E::NotFinite, "hairsim_configure params.dt", none);
        p = scene.params;
        p.rod_projection_iterations = 0;
        assert_eq!(hairsim_configure(world, &p), E::OutOfRange);
        expect(
            E::OutOfRange,
            "hairsim_configure params.rod_projection_iterations",
            none,
        );
        p = scene.params;
        p.solver = hairsim_solver::Dftl as u32;
        assert_eq!(hairsim_configure(world, &p), E::UnsupportedEffect);
        // Bending is the first effect DFTL cannot simulate: bit 2.
        expect(E::UnsupportedEffect, "hairsim_configure params.effects", 2);
        assert_eq!(hairsim_configure(world, ptr::null()), E::NullPointer);
        expect(E::NullPointer, "hairsim_configure params", none);
        assert_eq!(
            hairsim_configure(world, &dftl_preset_with_a_nan_wind()),
            E::NotFinite
        );
        expect(
            E::NotFinite,
            "hairsim_configure params.wind_direction",
            none,
        );
        assert_eq!(hairsim_configure(world, &scene.params), E::Ok);
        expect(E::Ok, "hairsim_configure", none);

        let m = &scene.material;
        let add = |points: &[hairsim_vec3], m: &hairsim_material| {
            hairsim_add_strand(world, points.as_ptr(), points.len(), m, ptr::null_mut())
        };
        let mut bad = scene.strands[0].clone();
        bad[3].z = f32::NAN;
        assert_eq!(add(&bad, m), E::NotFinite);
        expect(E::NotFinite, "hairsim_add_strand points", 3);
        bad = scene.strands[0].clone();
        bad[5] = bad[4];
        assert_eq!(add(&bad, m), E::DegenerateSegment);
        expect(E::DegenerateSegment, "hairsim_add_strand points", 4);
        bad[5].x += 2.0;
        assert_eq!(add(&bad, m), E::LongSegment);
        expect(E::LongSegment, "hairsim_add_strand points", 4);
        assert_eq!(add(&bad[..2], m), E::TooFewNodes);
        expect(E::TooFewNodes, "hairsim_add_strand count", none);
        let mut soft = *m;
        soft.youngs_modulus = 0.0;
        assert_eq!(add(&scene.strands[0], &soft), E::InvalidMaterial);
        expect(
            E::InvalidMaterial,
            "hairsim_add_strand material.youngs_modulus",
            none,
        );
        soft = *m;
        soft.density = f32::INFINITY;
        assert_eq!(add(&scene.strands[0], &soft), E::NotFinite);
        expect(E::NotFinite, "hairsim_add_strand material.density", none);
        assert_eq!(add(&scene.strands[0], m), E::Ok);

        let mut c = scene.colliders[0];
        c.radius = 0.0;
        assert_eq!(
            hairsim_add_collider(world, &c, ptr::null_mut()),
            E::InvalidCollider
        );
        expect(
            E::InvalidCollider,
            "hairsim_add_collider collider.radius",
            none,
        );
        c = hairsim_collider {
            shape: hairsim_shape::Plane as u32,
            b: hairsim_vec3 {
                x: 0.0,
                y: 2.0,
                z: 0.0,
            },
            ..c
        };
        assert_eq!(
            hairsim_add_collider(world, &c, ptr::null_mut()),
            E::InvalidCollider
        );
        expect(E::InvalidCollider, "hairsim_add_collider collider.b", none);
        c.attached_to_head = 7;
        assert_eq!(
            hairsim_add_collider(world, &c, ptr::null_mut()),
            E::OutOfRange
        );
        expect(
            E::OutOfRange,
            "hairsim_add_collider collider.attached_to_head",
            none,
        );

        let mut g = scene.grabs[0];
        g.strand = 3;
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::InvalidGrab);
        expect(E::InvalidGrab, "hairsim_add_grab grab.strand", none);
        g = scene.grabs[0];
        g.node = 1;
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::InvalidGrab);
        expect(E::InvalidGrab, "hairsim_add_grab grab.node", none);
        g.node = scene.grabs[0].node;
        g.force_limit = -1.0;
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::InvalidGrab);
        expect(E::InvalidGrab, "hairsim_add_grab grab.force_limit", none);
        g.force_limit = f32::NAN;
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::NotFinite);
        expect(E::NotFinite, "hairsim_add_grab grab.force_limit", none);
        // A coupling out of its ranges, or not finite.
        g.force_limit = scene.grabs[0].force_limit;
        (g.stiffness, g.damping) = (1.0e6, 0.01);
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::InvalidGrab);
        expect(E::InvalidGrab, "hairsim_add_grab grab.stiffness", none);
        (g.stiffness, g.damping) = (20.0, -1.0);
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::InvalidGrab);
        expect(E::InvalidGrab, "hairsim_add_grab grab.damping", none);
        g.damping = f32::INFINITY;
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::NotFinite);
        expect(E::NotFinite, "hairsim_add_grab grab.damping", none);
        assert_eq!(
            hairsim_add_grab(world, &scene.grabs[0], ptr::null_mut()),
            E::Ok
        );

        let mut i = input(identity());
        let targets = [
            scene.grabs[0].target,
            hairsim_vec3 {
                y: f32::NAN,
                ..Default::default()
            },
        ];
        i.grab_targets = targets.as_ptr();
        i.grab_target_count = 2;
        assert_eq!(hairsim_step(world, &i, ptr::null_mut()), E::NotFinite);
        expect(E::NotFinite, "hairsim_step input.grab_targets", 1);
        i.grab_target_count = 1;
        let accelerations = [
            hairsim_vec3::default(),
            hairsim_vec3 {
                x: f32::INFINITY,
                ..Default::default()
            },
        ];
        i.accelerations = accelerations.as_ptr();
        i.acceleration_count = 2;
        assert_eq!(hairsim_step(world, &i, ptr::null_mut()), E::NotFinite);
        expect(E::NotFinite, "hairsim_step input.accelerations", 1);
        i.acceleration_count = 1;
        let mut head = identity();
        head.rotation.w = 3.0;
        i.head = head;
        assert_eq!(hairsim_step(world, &i, ptr::null_mut()), E::OutOfRange);
        expect(E::OutOfRange, "hairsim_step input.head", none);
        let mut scratch = vec![0u64; 64];
        let odd = scratch
            .as_mut_ptr()
            .cast::<u8>()
            .add(1)
            .cast::<hairsim_step_report>();
        assert_eq!(hairsim_step(world, &input(identity()), odd), E::Misaligned);
        expect(E::Misaligned, "hairsim_step report", none);
        let mut out = [hairsim_vec3::default(); 2];
        let code = hairsim_strand_positions(world, 0, out.as_mut_ptr(), 2, ptr::null_mut());
        assert_eq!(code, E::BufferTooSmall);
        expect(E::BufferTooSmall, "hairsim_strand_positions capacity", none);
        assert_eq!(
            hairsim_step(world, &input(identity()), ptr::null_mut()),
            E::Ok
        );
        expect(E::Ok, "hairsim_step", none);
        // A refusal of the world itself is not kept: the last call's outcome stays.
        assert_eq!(
            hairsim_configure(world.cast::<u8>().add(1).cast(), &scene.params),
            E::Misaligned
        );
        expect(E::Ok, "hairsim_step", none);
        assert_eq!(hairsim_last_refusal(world, ptr::null_mut()), E::NullPointer);
    }
}

/// The firmware scene built in `storage`, stepped 10 times.
fn built(storage: &mut Storage) -> *mut hairsim_world {
    let scene = Scene::firmware();
    let world = storage.init();
    build(world, &scene);
    for k in 0..10 {
        step(world, &scene, k);
    }
    world
}

/// The world's bytes (inside `storage`, past the state word, record and checksums).
fn world_bytes(world: *mut hairsim_world) -> *mut u8 {
    unsafe { world.cast::<u8>().add(core::mem::offset_of!(Cell, world)) }
}

/// The address of element `i` of the list at `offset` in the world (`T`'s heapless vector).
unsafe fn element<T, const C: usize>(
    world: *mut hairsim_world,
    offset: usize,
    i: usize,
) -> *mut u8 {
    unsafe {
        let list = &*world_bytes(world).add(offset).cast::<heapless::Vec<T, C>>();
        list.as_ptr().add(i).cast::<u8>().cast_mut()
    }
}

#[test]
fn check_finds_every_kind_of_corruption_and_init_makes_the_world_anew() {
    use core::mem::offset_of;
    use hairsim_core::{Collider, Grab, Strand};
    let layout = SimWorld::LAYOUT;
    let mut storage = Storage::new();
    let world = built(&mut storage);
    assert_eq!(unsafe { hairsim_check(world) }, E::Ok);
    let pristine = storage.0.clone();
    // (what to corrupt, the byte's new value, the part named, its index)
    type Poke = fn(*mut hairsim_world) -> *mut u8;
    let cases: [(Poke, u8, &str, u32); 11] = [
        (
            |w| unsafe { world_bytes(w).add(SimWorld::LAYOUT.solver) },
            7,
            "world.solver",
            u32::MAX,
        ),
        (
            // The variant's word's last byte: 1 << 24 is no variant either.
            |w| unsafe { world_bytes(w).add(SimWorld::LAYOUT.scratch + 3) },
            1,
            "world.scratch",
            u32::MAX,
        ),
        (
            |w| unsafe { world_bytes(w).add(SimWorld::LAYOUT.bad_target) },
            2,
            "world.bad_target",
            u32::MAX,
        ),
        (
            |w| unsafe { world_bytes(w).add(SimWorld::LAYOUT.twist) },
            2,
            "world.rod_twist",
            u32::MAX,
        ),
        (
            |w| unsafe {
                element::<Strand<NODES>, STRANDS>(w, SimWorld::LAYOUT.strands, 2)
                    .add(offset_of!(Strand<NODES>, rest.nodes))
            },
            200,
            "world.nodes",
            2,
        ),
        (
            |w| unsafe {
                element::<Strand<NODES>, STRANDS>(w, SimWorld::LAYOUT.strands, 1)
                    .add(offset_of!(Strand<NODES>, schedule.implicit_bending))
            },
            2,
            "world.schedule",
            1,
        ),
        (
            |w| unsafe {
                element::<Collider, HAIRSIM_MAX_COLLIDERS>(w, SimWorld::LAYOUT.colliders, 0)
                    .add(offset_of!(Collider, shape))
            },
            3,
            "world.shape",
            0,
        ),
        (
            |w| unsafe {
                element::<Grab, HAIRSIM_MAX_GRABS>(w, SimWorld::LAYOUT.grabs, 0)
                    .add(offset_of!(Grab, status))
            },
            3,
            "world.status",
            0,
        ),
        (
            |w| unsafe {
                element::<Grab, HAIRSIM_MAX_GRABS>(w, SimWorld::LAYOUT.grabs, 0)
                    .add(offset_of!(Grab, node))
            },
            99,
            "world.node",
            0,
        ),
        (
            |w| unsafe {
                element::<Grab, HAIRSIM_MAX_GRABS>(w, SimWorld::LAYOUT.grabs, 0)
                    .add(crate::integrity::COUPLING_TAG)
            },
            2,
            "world.coupling",
            0,
        ),
        (
            |w| unsafe {
                element::<Strand<NODES>, STRANDS>(w, SimWorld::LAYOUT.strands, 3)
                    .add(offset_of!(Strand<NODES>, rest.mass) + 4)
            },
            0x7f,
            "world.rest",
            3,
        ),
    ];
    let _ = layout;
    for (poke, value, part, index) in cases {
        storage.0.copy_from_slice(&pristine);
        unsafe { *poke(world) = value };
        assert_eq!(unsafe { hairsim_check(world) }, E::Corrupt, "{part}");
        let (code, what, i) = last(world);
        assert_eq!(
            (code, what.as_str(), i),
            (E::Corrupt as i32, &*format!("hairsim_check {part}"), index)
        );
        // Every other call refuses it too (but for rest data, which only the check reads).
        let stepped = unsafe { hairsim_step(world, &input(identity()), ptr::null_mut()) };
        assert_eq!(stepped == E::Corrupt, part != "world.rest", "{part}");
        // `hairsim_init` makes it anew.
        assert_eq!(
            unsafe { hairsim_init(world, storage.len()) },
            E::Ok,
            "{part}"
        );
        assert_eq!(unsafe { hairsim_check(world) }, E::Ok, "{part}");
    }
    // A non-finite state: the check names the strand; a step would roll it back.
    storage.0.copy_from_slice(&pristine);
    unsafe {
        let strand = element::<Strand<NODES>, STRANDS>(world, layout.strands, 1);
        let x = strand
            .add(offset_of!(Strand<NODES>, state.position))
            .cast::<f32>();
        x.write(f32::NAN);
    }
    assert_eq!(unsafe { hairsim_check(world) }, E::Corrupt);
    assert_eq!(last(world).1, "hairsim_check world.state");
}

/// `integrity::COUPLING_TAG`: an `Option<Coupling>` keeps its variant in its first byte, 0 for
/// `None` and 1 for `Some`, and its values after it (what rustc does, not what Rust promises).
#[test]
fn a_grab_s_coupling_tag_is_the_option_s_first_byte() {
    use hairsim_core::Coupling;
    const SIZE: usize = core::mem::size_of::<Option<Coupling>>();
    // Every byte set first, so that a tag elsewhere would not read as one here.
    let bytes = |c: Option<Coupling>| {
        let mut buffer = [0xa5u8; SIZE];
        unsafe { ptr::write_unaligned(buffer.as_mut_ptr().cast::<Option<Coupling>>(), c) };
        buffer
    };
    assert_eq!(SIZE, 12);
    assert_eq!(bytes(None)[0], 0);
    let some = bytes(Some(Coupling::new(f32::from_bits(0x4049_0fdb), 0.0)));
    assert_eq!(some[0], 1);
    assert_eq!(some[4..8], 0x4049_0fdbu32.to_ne_bytes());
    // And back: a first byte of 0 or 1 is the variant.
    let mut raw = some;
    let read =
        |raw: &[u8; SIZE]| unsafe { ptr::read_unaligned(raw.as_ptr().cast::<Option<Coupling>>()) };
    assert!(read(&raw).is_some());
    raw[0] = 0;
    assert!(read(&raw).is_none());
}

#[test]
fn recover_clears_a_busy_word_a_reset_left_and_checks_the_world() {
    let mut storage = Storage::new();
    let world = built(&mut storage);
    let state = unsafe { &*world.cast::<AtomicU32>() };
    // A reset in the middle of a call leaves the word busy: every call is refused.
    state.store(BUSY, Ordering::SeqCst);
    assert_eq!(
        unsafe { hairsim_step(world, &input(identity()), ptr::null_mut()) },
        E::Busy
    );
    assert_eq!(unsafe { hairsim_init(world, storage.len()) }, E::Busy);
    assert_eq!(unsafe { hairsim_recover(world) }, E::Ok);
    assert_eq!(last(world).1, "hairsim_recover");
    assert_eq!(
        unsafe { hairsim_step(world, &input(identity()), ptr::null_mut()) },
        E::Ok
    );
    // Busy and corrupt: recovered as refused, until `hairsim_init`.
    state.store(BUSY, Ordering::SeqCst);
    unsafe { *world_bytes(world).add(SimWorld::LAYOUT.mode) = 9 };
    assert_eq!(unsafe { hairsim_recover(world) }, E::Corrupt);
    assert_eq!(last(world).1, "hairsim_recover world.mode");
    assert_eq!(
        unsafe { hairsim_step(world, &input(identity()), ptr::null_mut()) },
        E::Corrupt
    );
    assert_eq!(unsafe { hairsim_init(world, storage.len()) }, E::Ok);
    // Not a world at all.
    let mut zeroed = Storage::new();
    assert_eq!(
        unsafe { hairsim_recover(zeroed.world()) },
        E::NotInitialised
    );
}

#[test]
fn the_panic_hook_is_set_and_swapped() {
    type Hook = unsafe extern "C" fn(*const core::ffi::c_char, usize, u32);
    unsafe extern "C" fn first(_: *const core::ffi::c_char, _: usize, _: u32) {}
    unsafe extern "C" fn second(_: *const core::ffi::c_char, _: usize, _: u32) {}
    let (first, second): (Hook, Hook) = (first, second);
    let address = |hook: hairsim_panic_hook| hook.map(|f| f as usize);
    assert!(hairsim_set_panic_hook(Some(first)).is_none());
    assert_eq!(
        address(hairsim_set_panic_hook(Some(second))),
        Some(first as usize)
    );
    assert_eq!(address(hairsim_set_panic_hook(None)), Some(second as usize));
}

#[test]
fn the_firmware_scene_through_the_c_functions_gives_the_core_hash() {
    let scene = Scene::firmware();
    let mut storage = Storage::new();
    let world = storage.init();
    build(world, &scene);
    let mut held = 0;
    for k in 0..firmware::STEPS {
        let report = step(world, &scene, k);
        held += u32::from(report.flags & HAIRSIM_FLAG_ROLLED_BACK == 0);
    }
    assert_eq!(held, firmware::STEPS, "no strand rolled back");
    let mut info = hairsim_world_info::default();
    assert_eq!(unsafe { hairsim_get_info(world, &mut info) }, E::Ok);
    assert_eq!(
        (info.steps, info.strands, info.colliders, info.grabs),
        (u64::from(firmware::STEPS), 4, 1, 1)
    );
    assert_eq!(hash(world), rust_firmware_hash());
    std::println!("state_hash 0x{:016x}", hash(world));
}

#[test]
fn the_helpers_give_the_scene_bits() {
    let scene = Scene::firmware();
    let dt = firmware::params().dt;
    assert_eq!(scene.params.dt.to_bits(), dt.to_bits());
    for k in 0..=firmware::STEPS + 10 {
        let t = step_time(k, dt);
        let mut pose = hairsim_pose::default();
        assert_eq!(
            unsafe { hairsim_shake_pose(&scene.shake, t, &mut pose) },
            E::Ok
        );
        let expected = convert::pose_to_c(&firmware::input::<DefaultMath>(k).head);
        assert_eq!(format!("{pose:?}"), format!("{expected:?}"), "step {k}");
        let bits = |p: &hairsim_pose| {
            [
                p.position.x,
                p.position.y,
                p.position.z,
                p.rotation.x,
                p.rotation.y,
                p.rotation.z,
                p.rotation.w,
            ]
            .map(f32::to_bits)
        };
        assert_eq!(bits(&pose), bits(&expected), "step {k}");
        let mut target = hairsim_vec3::default();
        let code = unsafe { hairsim_circle_target(&scene.circles[0], t, &mut target) };
        assert_eq!(code, E::Ok);
        // The scene moves the grab to `grab_target(k + 1)` before step k.
        let expected = firmware::grab_target::<DefaultMath>(k + 1);
        assert_eq!(
            [target.x, target.y, target.z].map(f32::to_bits),
            [expected.x, expected.y, expected.z].map(f32::to_bits),
            "step {k}"
        );
    }
}

#[test]
fn hex_literals_are_exact() {
    assert_eq!(scene_header::hex(0.001), "0x1.0624dep-10f");
    assert_eq!(scene_header::hex(0.01), "0x1.47ae14p-7f");
    assert_eq!(scene_header::hex(1.0), "0x1p+0f");
    assert_eq!(scene_header::hex(-2.5), "-0x1.4p+1f");
    assert_eq!(scene_header::hex(0.0), "0x0p+0f");
    assert_eq!(scene_header::hex(-0.0), "-0x0p+0f");
    assert_eq!(scene_header::hex(f32::MIN_POSITIVE / 4.0), "0x0.4p-126f");
    // Every literal of the header parses back to its bits.
    let parse = |s: &str| -> f32 {
        let (negative, s) = s.strip_prefix('-').map_or((false, s), |r| (true, r));
        let s = s.strip_prefix("0x").unwrap().strip_suffix('f').unwrap();
        let (mantissa, power) = s.split_once('p').unwrap();
        let (lead, fraction) = mantissa.split_once('.').unwrap_or((mantissa, ""));
        let mut value = f64::from(u8::from_str_radix(lead, 16).unwrap());
        for (i, d) in fraction.chars().enumerate() {
            value += f64::from(d.to_digit(16).unwrap()) / 16f64.powi(i as i32 + 1);
        }
        let value = value * 2f64.powi(power.parse().unwrap());
        (if negative { -value } else { value }) as f32
    };
    let scene = Scene::firmware();
    for p in scene.strands.iter().flatten() {
        for v in [p.x, p.y, p.z] {
            assert_eq!(parse(&scene_header::hex(v)).to_bits(), v.to_bits());
        }
    }
    for v in [0.001f32, 1.0e-30, 3.0e38, -7.25e-3, f32::MIN_POSITIVE / 3.0] {
        assert_eq!(parse(&scene_header::hex(v)).to_bits(), v.to_bits(), "{v}");
    }
}

#[test]
fn scene_header_is_current() {
    let text = scene_header::generate(&Scene::firmware()) + "\n";
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(scene_header::PATH);
    if std::env::var_os("HAIRSIM_BLESS").is_some() {
        std::fs::write(&path, &text).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == text,
        "{} is stale: run `HAIRSIM_BLESS=1 cargo test` in ffi/",
        path.display()
    );
}

fn input(head: hairsim_pose) -> hairsim_step_input {
    hairsim_step_input {
        head,
        grab_targets: ptr::null(),
        grab_target_count: 0,
        accelerations: ptr::null(),
        acceleration_count: 0,
    }
}

fn identity() -> hairsim_pose {
    hairsim_pose {
        position: hairsim_vec3::default(),
        rotation: hairsim_quat {
            w: 1.0,
            ..Default::default()
        },
    }
}

#[test]
fn refused_arguments_have_their_codes() {
    let scene = Scene::firmware();
    let mut storage = Storage::new();
    let len = storage.len();
    let world = storage.world();
    let bytes = world.cast::<u8>();
    // Misaligned pointers point into this, not into the world (which is refused first).
    let mut scratch = vec![0u64; 64];
    let scratch = scratch.as_mut_ptr().cast::<u8>();
    unsafe {
        // The world buffer.
        assert_eq!(hairsim_init(ptr::null_mut(), len), E::NullPointer);
        assert_eq!(hairsim_init(bytes.add(4).cast(), len - 8), E::Misaligned);
        assert_eq!(hairsim_init(world, WORLD_SIZE - 1), E::BufferTooSmall);
        assert_eq!(hairsim_init(world, 0), E::BufferTooSmall);
        // Before initialisation.
        assert_eq!(hairsim_configure(world, &scene.params), E::NotInitialised);
        assert_eq!(
            hairsim_step(world, &input(identity()), ptr::null_mut()),
            E::NotInitialised
        );
        let mut h = 0u64;
        assert_eq!(hairsim_state_hash(world, &mut h), E::NotInitialised);
        assert_eq!(hairsim_init(world, WORLD_SIZE), E::Ok);
        // Re-entry: a call is running (as an interrupted call leaves it).
        let state = &*world.cast::<AtomicU32>();
        state.store(BUSY, Ordering::SeqCst);
        assert_eq!(hairsim_state_hash(world, &mut h), E::Busy);
        assert_eq!(hairsim_init(world, WORLD_SIZE), E::Busy);
        assert_eq!(
            hairsim_step(world, &input(identity()), ptr::null_mut()),
            E::Busy
        );
        state.store(IDLE, Ordering::SeqCst);
        assert_eq!(hairsim_state_hash(world, &mut h), E::Ok);

        // Parameters.
        let mut params = scene.params;
        assert_eq!(hairsim_configure(world, ptr::null()), E::NullPointer);
        params.dt = f32::NAN;
        assert_eq!(hairsim_configure(world, &params), E::NotFinite);
        params.dt = 1.0;
        assert_eq!(hairsim_configure(world, &params), E::OutOfRange);
        params = scene.params;
        params.solver = 7;
        assert_eq!(hairsim_configure(world, &params), E::OutOfRange);
        params = scene.params;
        params.effects |= 1 << 20;
        assert_eq!(hairsim_configure(world, &params), E::OutOfRange);
        params = scene.params;
        params.rod_projection_iterations = 70_000;
        assert_eq!(hairsim_configure(world, &params), E::OutOfRange);
        params.rod_projection_iterations = 0;
        assert_eq!(hairsim_configure(world, &params), E::OutOfRange);
        params = scene.params;
        params.rod_twist = 2;
        assert_eq!(hairsim_configure(world, &params), E::OutOfRange);
        params = scene.params;
        params.solver = hairsim_solver::Dftl as u32;
        params.dt = 0.001;
        assert_eq!(hairsim_configure(world, &params), E::UnsupportedEffect);
        let misaligned = scratch.add(2).cast::<hairsim_params>();
        assert_eq!(hairsim_configure(world, misaligned), E::Misaligned);
        assert_eq!(hairsim_configure(world, &scene.params), E::Ok);

        // Strands.
        let points = &scene.strands[3];
        let m = &scene.material;
        let add = |p: *const hairsim_vec3, n: usize, m: *const hairsim_material| {
            hairsim_add_strand(world, p, n, m, ptr::null_mut())
        };
        assert_eq!(add(ptr::null(), 5, m), E::NullPointer);
        assert_eq!(add(points.as_ptr(), 5, ptr::null()), E::NullPointer);
        assert_eq!(add(points.as_ptr(), 2, m), E::TooFewNodes);
        assert_eq!(add(points.as_ptr(), NODES + 1, m), E::TooManyNodes);
        assert_eq!(add(points.as_ptr(), usize::MAX, m), E::TooManyNodes);
        let mut bad = points.clone();
        bad[4].y = f32::INFINITY;
        assert_eq!(add(bad.as_ptr(), bad.len(), m), E::NotFinite);
        bad = points.clone();
        bad[4] = bad[3];
        assert_eq!(add(bad.as_ptr(), bad.len(), m), E::DegenerateSegment);
        bad = points.clone();
        bad[4] = bad[2];
        assert_eq!(add(bad.as_ptr(), bad.len(), m), E::FoldedSegment);
        let mut material = *m;
        material.radius = -1.0;
        assert_eq!(add(points.as_ptr(), 5, &material), E::InvalidMaterial);
        material.radius = f32::NAN;
        assert_eq!(add(points.as_ptr(), 5, &material), E::NotFinite);
        let odd = scratch.add(1).cast::<u32>();
        let code = hairsim_add_strand(world, points.as_ptr(), 5, m, odd);
        assert_eq!(code, E::Misaligned);
        for s in 0..STRANDS {
            let mut index = 0;
            let code = hairsim_add_strand(world, points.as_ptr(), points.len(), m, &mut index);
            assert_eq!((code, index), (E::Ok, s as u32));
        }
        assert_eq!(add(points.as_ptr(), points.len(), m), E::StrandsFull);

        // Colliders.
        let sphere = scene.colliders[0];
        let mut c = sphere;
        c.radius = -1.0;
        assert_eq!(
            hairsim_add_collider(world, &c, ptr::null_mut()),
            E::InvalidCollider
        );
        c.shape = 3;
        assert_eq!(
            hairsim_add_collider(world, &c, ptr::null_mut()),
            E::OutOfRange
        );
        c = sphere;
        c.attached_to_head = 2;
        assert_eq!(
            hairsim_add_collider(world, &c, ptr::null_mut()),
            E::OutOfRange
        );
        c = sphere;
        c.a.z = f32::NAN;
        assert_eq!(
            hairsim_add_collider(world, &c, ptr::null_mut()),
            E::NotFinite
        );
        for _ in 0..HAIRSIM_MAX_COLLIDERS {
            assert_eq!(hairsim_add_collider(world, &sphere, ptr::null_mut()), E::Ok);
        }
        let code = hairsim_add_collider(world, &sphere, ptr::null_mut());
        assert_eq!(code, E::CollidersFull);

        // Grabs.
        let grab = scene.grabs[0];
        let mut g = grab;
        g.node = 99;
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::InvalidGrab);
        g = grab;
        g.strand = 99;
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::InvalidGrab);
        g = grab;
        g.force_limit = 0.0;
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::InvalidGrab);
        g.force_limit = f32::NAN;
        assert_eq!(hairsim_add_grab(world, &g, ptr::null_mut()), E::NotFinite);
        for _ in 0..HAIRSIM_MAX_GRABS {
            assert_eq!(hairsim_add_grab(world, &grab, ptr::null_mut()), E::Ok);
        }
        assert_eq!(
            hairsim_add_grab(world, &grab, ptr::null_mut()),
            E::GrabsFull
        );
        assert_eq!(hairsim_release_grab(world, 4), E::OutOfRange);
        assert_eq!(hairsim_release_grab(world, 3), E::Ok);

        // Steps.
        let before = hash(world);
        let mut head = identity();
        head.rotation.w = f32::NAN;
        assert_eq!(
            hairsim_step(world, &input(head), ptr::null_mut()),
            E::NotFinite
        );
        head.rotation.w = 2.0;
        assert_eq!(
            hairsim_step(world, &input(head), ptr::null_mut()),
            E::OutOfRange
        );
        let mut i = input(identity());
        let targets = [grab.target; 5];
        i.grab_targets = targets.as_ptr();
        i.grab_target_count = 5;
        assert_eq!(hairsim_step(world, &i, ptr::null_mut()), E::OutOfRange);
        i.grab_target_count = 1;
        i.grab_targets = ptr::null();
        assert_eq!(hairsim_step(world, &i, ptr::null_mut()), E::NullPointer);
        let nan = [hairsim_vec3 {
            x: f32::NAN,
            ..Default::default()
        }];
        i.grab_targets = nan.as_ptr();
        assert_eq!(hairsim_step(world, &i, ptr::null_mut()), E::NotFinite);
        let mut i = input(identity());
        let accelerations = vec![hairsim_vec3::default(); STRANDS * NODES + 1];
        i.accelerations = accelerations.as_ptr();
        i.acceleration_count = accelerations.len();
        assert_eq!(hairsim_step(world, &i, ptr::null_mut()), E::OutOfRange);
        i.accelerations = world.cast();
        i.acceleration_count = 4;
        assert_eq!(hairsim_step(world, &i, ptr::null_mut()), E::Overlap);
        let report = scratch.add(2).cast::<hairsim_step_report>();
        assert_eq!(
            hairsim_step(world, &input(identity()), report),
            E::Misaligned
        );
        assert_eq!(hash(world), before, "a refused step changes nothing");
        i.accelerations = accelerations.as_ptr();
        i.acceleration_count = STRANDS * NODES;
        assert_eq!(hairsim_step(world, &i, ptr::null_mut()), E::Ok);
        assert_ne!(hash(world), before);

        // Positions.
        let mut out = [hairsim_vec3::default(); 64];
        let mut count = 0usize;
        let code = hairsim_strand_positions(world, 0, out.as_mut_ptr(), 3, &mut count);
        assert_eq!((code, count), (E::BufferTooSmall, points.len()));
        let code = hairsim_strand_positions(world, 0, ptr::null_mut(), 0, &mut count);
        assert_eq!(code, E::BufferTooSmall);
        let code = hairsim_strand_positions(world, 0, ptr::null_mut(), 3, &mut count);
        assert_eq!(code, E::NullPointer);
        let code = hairsim_strand_positions(world, 99, out.as_mut_ptr(), 64, &mut count);
        assert_eq!(code, E::OutOfRange);
        let code = hairsim_strand_positions(world, 0, world.cast(), 64, &mut count);
        assert_eq!(code, E::Overlap);
        let code = hairsim_strand_positions(world, 0, out.as_mut_ptr(), 64, ptr::null_mut());
        assert_eq!(code, E::Ok);
        assert_eq!(out[0], points[0]);
        let odd = scratch.add(1).cast::<u64>();
        assert_eq!(hairsim_state_hash(world, odd), E::Misaligned);
        assert_eq!(hairsim_state_hash(world, ptr::null_mut()), E::NullPointer);

        // Helpers.
        let mut pose = hairsim_pose::default();
        let code = hairsim_shake_pose(&scene.shake, f32::NAN, &mut pose);
        assert_eq!(code, E::NotFinite);
        let mut shake = scene.shake;
        shake.axis.x = 1.0;
        assert_eq!(hairsim_shake_pose(&shake, 0.5, &mut pose), E::OutOfRange);
        let mut circle = scene.circles[0];
        circle.start.x = f32::MAX;
        circle.radius = f32::MAX;
        let mut target = hairsim_vec3::default();
        // cos − 1 ≈ −2 half a turn in: −MAX · 2 overflows.
        let code = hairsim_circle_target(&circle, 0.25, &mut target);
        assert_eq!(code, E::NotFinite);
        assert_eq!(
            hairsim_circle_target(ptr::null(), 0.0, &mut target),
            E::NullPointer
        );

        // Every code has a message; unknown ones too.
        for code in -2..=25 {
            let message = core::ffi::CStr::from_ptr(hairsim_error_message(code));
            assert!(!message.is_empty());
            let unknown = message.to_str().unwrap() == "unknown error code";
            assert_eq!(unknown, !(0..=25).contains(&code), "{code}");
        }
    }
}

/// A DFTL world with a coupled grab, through the C functions: the grab holds and renders its
/// coupling, the head's force is reported, the state hash is the core's; a coupling out of range
/// is refused.
#[test]
fn a_coupled_grab_on_dftl_hair_through_the_c_functions() {
    use hairsim_core::{
        Coupling, Effect, Effects, Grab as CoreGrab, Material as CoreMaterial,
        Params as CoreParams, Pose, Solver, StepInput, Strand as CoreStrand, Vec3 as CoreVec3,
    };
    let params = CoreParams {
        solver: Solver::Dftl,
        effects: Effects::from_slice(&[
            Effect::Gravity,
            Effect::Drag,
            Effect::Inextensibility,
            Effect::Shape,
            Effect::Grabs,
        ]),
        drag: 2.0e-7,
        ..CoreParams::DEFAULT
    };
    let points: Vec<CoreVec3> = (0..16)
        .map(|i| CoreVec3::new(0.01 * i as f32, 0.0, 0.0))
        .collect();
    let tip = points[15];
    let target = |k: u32| tip + CoreVec3::new(-0.02, -0.01, 0.01) * (k as f32 / 200.0).min(1.0);
    let coupling = Coupling::new(20.0, 0.01);
    // The core, directly.
    let mut core_world: Box<World<1, 16, DefaultMath>> = Box::default();
    core_world.configure(params).unwrap();
    let strand = CoreStrand::from_polyline(&points, &CoreMaterial::HUMAN_HAIR).unwrap();
    core_world.add_strand(strand).unwrap();
    core_world
        .add_grab(CoreGrab::new(0, 15, tip, 1.0).with_coupling(coupling))
        .unwrap();
    // Through C.
    let mut storage = Storage::new();
    let world = storage.init();
    let c_points: Vec<hairsim_vec3> = points.iter().map(|p| convert::vec3_to_c(*p)).collect();
    let material = convert::material_to_c(&CoreMaterial::HUMAN_HAIR);
    let mut grab = hairsim_grab {
        strand: 0,
        node: 15,
        target: convert::vec3_to_c(tip),
        force_limit: 1.0,
        stiffness: 1.0e6,
        damping: 0.01,
    };
    unsafe {
        assert_eq!(
            hairsim_configure(world, &convert::params_to_c(&params)),
            E::Ok
        );
        let count = c_points.len();
        let code = hairsim_add_strand(world, c_points.as_ptr(), count, &material, ptr::null_mut());
        assert_eq!(code, E::Ok);
        // 1e6 N/m is past the coupling's range, and the refusal names the field.
        assert_eq!(
            hairsim_add_grab(world, &grab, ptr::null_mut()),
            E::InvalidGrab
        );
        let (code, what, _) = last(world);
        assert_eq!(
            (code, what.as_str()),
            (E::InvalidGrab as i32, "hairsim_add_grab grab.stiffness")
        );
        grab.stiffness = coupling.stiffness;
        assert_eq!(hairsim_add_grab(world, &grab, ptr::null_mut()), E::Ok);
    }
    let mut report = core::mem::MaybeUninit::<hairsim_step_report>::uninit();
    for k in 0..400 {
        let t = convert::vec3_to_c(target(k + 1));
        let mut input = input(identity());
        input.grab_targets = &t;
        input.grab_target_count = 1;
        assert_eq!(
            unsafe { hairsim_step(world, &input, report.as_mut_ptr()) },
            E::Ok
        );
        core_world.set_grab_target(0, target(k + 1));
        core_world.step(&StepInput {
            head: Pose::IDENTITY,
            accelerations: None,
        });
    }
    let report = unsafe { report.assume_init() };
    assert_eq!(report.grabs_slipped, 0);
    let (grab_force, head_force) = (report.grab_forces[0], report.head_force);
    for f in [grab_force, head_force] {
        assert!(f.x.is_finite() && f.y.is_finite() && f.z.is_finite());
    }
    // Held still for the last 200 steps: the grab and the head carry the strand's weight.
    let strand = &core_world.strands()[0];
    let weight: f32 = strand.rest.mass[2..16].iter().sum::<f32>() * 9.81;
    let carried = -(grab_force.y + head_force.y);
    assert!(
        (carried / weight - 1.0).abs() < 0.05,
        "{grab_force:?} {head_force:?} against {weight}"
    );
    assert_eq!(hash(world), core_world.state_hash());
}

/// DFTL's preset with a NaN (sign and payload set) in its wind direction and no gust.
fn dftl_preset_with_a_nan_wind() -> hairsim_params {
    let mut d = core::mem::MaybeUninit::<hairsim_params>::uninit();
    assert_eq!(
        unsafe { hairsim_params_preset(hairsim_solver::Dftl as u32, d.as_mut_ptr()) },
        E::Ok
    );
    let mut d = unsafe { d.assume_init() };
    d.wind_direction.x = f32::from_bits(0xFFFF01FD);
    d.wind_gust = 0.0;
    d
}

/// A refusal on a world fresh from `hairsim_init` is recorded too.
#[test]
fn a_refused_configure_right_after_init_is_recorded() {
    let mut storage = Storage::new();
    let world = storage.init();
    let d = dftl_preset_with_a_nan_wind();
    assert_eq!(unsafe { hairsim_configure(world, &d) }, E::NotFinite);
    let (code, what, _) = last(world);
    assert_eq!(
        (code, what.as_str()),
        (
            E::NotFinite as i32,
            "hairsim_configure params.wind_direction"
        )
    );
}

/// `integrity::LIST_LENGTH`: a `heapless::Vec` keeps its length in its first `usize`, for each
/// of the world's three lists (where heapless lays it out, which its types imply but do not
/// promise).
#[test]
fn a_list_s_length_is_its_first_word() {
    let mut storage = Storage::new();
    let world = built(&mut storage);
    let mut info = hairsim_world_info::default();
    assert_eq!(unsafe { hairsim_get_info(world, &mut info) }, E::Ok);
    let layout = SimWorld::LAYOUT;
    let stored = |offset: usize| unsafe {
        world_bytes(world)
            .add(offset + crate::integrity::LIST_LENGTH)
            .cast::<usize>()
            .read()
    };
    let counts = (info.strands, info.colliders, info.grabs);
    assert_eq!(counts, (4, 1, 1));
    let read = (
        stored(layout.strands),
        stored(layout.colliders),
        stored(layout.grabs),
    );
    assert_eq!(read, (4, 1, 1));
}

/// A list's length past its capacity, even one no slice can have, is refused from its bytes:
/// asking the list its length would first make a slice of it (found by the `world_bytes`
/// fuzz target).
#[test]
fn a_list_length_no_slice_can_have_is_refused() {
    let layout = SimWorld::LAYOUT;
    for (offset, name) in [
        (layout.strands, "hairsim_check world.strands"),
        (layout.colliders, "hairsim_check world.colliders"),
        (layout.grabs, "hairsim_check world.grabs"),
    ] {
        for length in [usize::MAX, usize::MAX / 2, 1 << 40] {
            let mut storage = Storage::new();
            let world = built(&mut storage);
            unsafe {
                world_bytes(world)
                    .add(offset + crate::integrity::LIST_LENGTH)
                    .cast::<usize>()
                    .write(length);
            }
            assert_eq!(
                unsafe { hairsim_check(world) },
                E::Corrupt,
                "{name} {length}"
            );
            assert_eq!(last(world).1, name);
        }
    }
}
