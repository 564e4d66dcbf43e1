//! # hairsim-ffi
//!
//! A C ABI for `hairsim-core`: one static library and one header (`include/hairsim.h`) for C
//! firmware. The caller gives the world its memory — a buffer of `HAIRSIM_WORLD_SIZE` bytes
//! aligned to `HAIRSIM_WORLD_ALIGN`, usually a `static` — configures it, adds strands,
//! colliders and grabs, then calls `hairsim_step` once per tick. No heap, no panic, and the
//! same state hash as `hairsim run` for the same scene.
//!
//! The capacities are chosen when the library is built: `HAIRSIM_STRANDS` and `HAIRSIM_NODES`
//! (default 4 × 16), read by `build.rs`.
//!
//! ## What the functions promise
//!
//! Given pointers valid for their stated lengths (the world: `HAIRSIM_WORLD_SIZE` bytes; a
//! struct: its size; an array: its count), no argument value causes undefined behaviour or a
//! panic. NULL, misalignment, short buffers, NaN and out-of-range values, capacity overflow, a
//! call before `hairsim_init` (the world's magic word is wrong) and re-entry (another call on
//! the same world still running, from an interrupt or a thread) are refused with a
//! [`hairsim_error`] code, and a refused call changes nothing.
//!
//! ## Soundness
//!
//! The world buffer holds a [`Cell`]: a state word, which is both the magic that says the
//! buffer was initialised and the busy flag, and the world. A call that touches the world first
//! swaps the state word from `IDLE` to `BUSY` atomically and puts `IDLE` back when it returns
//! ([`Lease`]); it is the only way to a `&mut World`, so no two references to one world ever
//! coexist, whatever interrupts do. Every `unsafe` block says why it is sound (`// SAFETY:`).
#![no_std]
#![deny(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]
#![deny(clippy::undocumented_unsafe_blocks)]

#[cfg(any(test, feature = "std"))]
extern crate std;

mod convert;
pub mod types;

#[cfg(test)]
mod scene_header;
#[cfg(test)]
mod tests;

use core::ffi::c_char;
use core::mem::{align_of, size_of};
use core::ptr::{self, addr_of, addr_of_mut};
use core::sync::atomic::{AtomicU32, Ordering};

use hairsim_core::{
    Coupling, DefaultMath, Grab, Material, Math, Params, StepInput, Strand, Vec3, World,
};

use convert::Result;
pub use types::*;

/// The build-time capacities (`build.rs`).
mod capacity {
    include!(concat!(env!("OUT_DIR"), "/capacity.rs"));
}
pub use capacity::{NODES, STRANDS};

/// The world type behind the C functions: the default math (libm), never fast-math.
pub(crate) type SimWorld = World<STRANDS, NODES, DefaultMath>;

const fn same_str(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}
// The C library gives `hairsim run`'s hashes only with the default math.
const _: () = assert!(same_str(<DefaultMath as Math>::NAME, "libm"));

/// The state word of an initialised world no call is using ("HAIR").
const IDLE: u32 = 0x4841_4952;
/// The state word while a call uses the world ("HAIr").
const BUSY: u32 = 0x4841_4972;

/// What the caller's world buffer holds, for a world of `S` strands of `N` nodes.
#[repr(C)]
pub(crate) struct CellOf<const S: usize, const N: usize> {
    /// `IDLE`, `BUSY`, or anything else before `hairsim_init`.
    state: AtomicU32,
    /// The world; only reached through a [`Lease`].
    world: World<S, N, DefaultMath>,
}

/// What the caller's world buffer holds, at the build-time capacities.
pub(crate) type Cell = CellOf<STRANDS, NODES>;

/// Bytes a world buffer needs on this target.
pub(crate) const WORLD_SIZE: usize = size_of::<Cell>();
/// Alignment a world buffer needs on this target.
pub(crate) const WORLD_ALIGN: usize = align_of::<Cell>();

/// Exclusive use of one world for the length of a call: holds the state word at `BUSY` and
/// puts `IDLE` back when dropped.
struct Lease<'a> {
    state: &'a AtomicU32,
    world: &'a mut SimWorld,
}

impl Drop for Lease<'_> {
    fn drop(&mut self) {
        self.state.store(IDLE, Ordering::Release);
    }
}

/// Checks that `p` is non-NULL and aligned for `T`.
fn check_ptr<T>(p: *const T) -> Result<()> {
    if p.is_null() {
        Err(hairsim_error::NullPointer)
    } else if !p.is_aligned() {
        Err(hairsim_error::Misaligned)
    } else {
        Ok(())
    }
}

/// Checks an optional pointer: NULL, or aligned for `T`.
fn check_optional<T>(p: *const T) -> Result<()> {
    if p.is_null() || p.is_aligned() {
        Ok(())
    } else {
        Err(hairsim_error::Misaligned)
    }
}

/// Checks that `count` `T`s at `p` do not overlap the world's buffer: the world is borrowed
/// mutably while they are read or written.
fn check_disjoint<T>(p: *const T, count: usize, world: *const hairsim_world) -> Result<()> {
    if p.is_null() || count == 0 {
        return Ok(());
    }
    let start = p as usize;
    let end = start.saturating_add(count.saturating_mul(size_of::<T>()));
    let world_start = world as usize;
    let world_end = world_start.saturating_add(WORLD_SIZE);
    if start < world_end && world_start < end {
        Err(hairsim_error::Overlap)
    } else {
        Ok(())
    }
}

/// Copies the `T` at `p` out of the caller's memory.
///
/// # Safety
/// `p`, if not NULL, must be valid for reads of a `T`, and `T` must be plain data for which
/// every bit pattern is a valid value.
unsafe fn read<T: Copy>(p: *const T) -> Result<T> {
    check_ptr(p)?;
    // SAFETY: `p` is non-NULL and aligned (checked), valid for reads of a `T` (the caller's
    // promise), and every `T` used here is a `#[repr(C)]` struct of integers, floats and raw
    // pointers: every bit pattern is a valid value.
    Ok(unsafe { ptr::read(p) })
}

/// Writes `value` to `p`.
///
/// # Safety
/// `p`, if not NULL, must be valid for writes of a `T`.
unsafe fn write<T>(p: *mut T, value: T) -> Result<()> {
    check_ptr(p)?;
    // SAFETY: `p` is non-NULL and aligned (checked) and valid for writes of a `T` (the
    // caller's promise); `T` is plain data with no destructor: nothing is dropped.
    unsafe { ptr::write(p, value) };
    Ok(())
}

/// Writes `value` to `p` if `p` is not NULL (an optional output).
///
/// # Safety
/// `p`, if not NULL, must be valid for writes of a `T`.
unsafe fn write_optional<T>(p: *mut T, value: T) -> Result<()> {
    if p.is_null() {
        return Ok(());
    }
    // SAFETY: the caller's promise for a non-NULL `p`.
    unsafe { write(p, value) }
}

/// The caller's array `(p, count)` as a slice, after checking the pointer; `count` 0 accepts
/// NULL. `count` must already be bounded by a capacity, so that `count * size_of::<T>()` is
/// far below `isize::MAX`.
///
/// # Safety
/// `p`, if not NULL, must be valid for reads of `count` `T`s that nothing writes while the
/// slice lives, and every bit pattern of `T` must be a valid value.
unsafe fn slice<'a, T>(p: *const T, count: usize) -> Result<&'a [T]> {
    if count == 0 {
        return Ok(&[]);
    }
    check_ptr(p)?;
    // SAFETY: `p` is non-NULL and aligned (checked) and valid for reads of `count` elements
    // nothing writes meanwhile (the caller's promise); `count` is bounded by a capacity, so
    // the slice is far smaller than `isize::MAX` bytes; every bit pattern of `T` is valid.
    Ok(unsafe { core::slice::from_raw_parts(p, count) })
}

/// Takes exclusive use of an initialised world.
///
/// # Safety
/// `world`, if not NULL, must be valid for reads and writes of `HAIRSIM_WORLD_SIZE` bytes for
/// the length of the call.
unsafe fn lease<'a>(world: *mut hairsim_world) -> Result<Lease<'a>> {
    let cell = world.cast::<Cell>();
    check_ptr(cell)?;
    // SAFETY: `cell` is non-NULL and aligned for `Cell` (checked) and the buffer is valid for
    // `size_of::<Cell>()` bytes (the caller's promise), so its first field is a valid
    // `AtomicU32` place: any bit pattern is a `u32`. It is only ever accessed atomically, here
    // and in other calls, so shared references to it may coexist.
    let state = unsafe { &*addr_of!((*cell).state) };
    match state.compare_exchange(IDLE, BUSY, Ordering::Acquire, Ordering::Relaxed) {
        Ok(_) => {}
        Err(BUSY) => return Err(hairsim_error::Busy),
        Err(_) => return Err(hairsim_error::NotInitialised),
    }
    // SAFETY: the state word was `IDLE`, so `hairsim_init` wrote a valid world after it, and
    // this call swapped it to `BUSY`: every other call refuses until the lease is dropped, so
    // this is the only reference to the world (a field disjoint from the state word), and the
    // caller's other buffers were checked not to overlap it.
    let world = unsafe { &mut *addr_of_mut!((*cell).world) };
    Ok(Lease { state, world })
}

/// Runs `f` on the world under a lease.
///
/// # Safety
/// As [`lease`].
unsafe fn with_world<T>(
    world: *mut hairsim_world,
    f: impl FnOnce(&mut SimWorld) -> Result<T>,
) -> Result<T> {
    // SAFETY: the caller's promise is `lease`'s.
    let lease = unsafe { lease(world) }?;
    f(lease.world)
}

fn code(r: Result<()>) -> hairsim_error {
    match r {
        Ok(()) => hairsim_error::Ok,
        Err(e) => e,
    }
}

/// Whether a header of version `version` (`HAIRSIM_VERSION`) built for `strands` × `nodes`
/// matches this library: the same major version and, while it is 0, the same minor version
/// (from 1 on, a minor version no newer than the library's); the same capacities.
fn check_header(version: u32, strands: u32, nodes: u32) -> Result<()> {
    let (major, minor) = (version >> 16, (version >> 8) & 0xff);
    let minor_works = if HAIRSIM_VERSION_MAJOR == 0 {
        minor == HAIRSIM_VERSION_MINOR
    } else {
        minor <= HAIRSIM_VERSION_MINOR
    };
    if major != HAIRSIM_VERSION_MAJOR || !minor_works {
        Err(hairsim_error::VersionMismatch)
    } else if strands as usize != STRANDS {
        Err(hairsim_error::StrandsMismatch)
    } else if nodes as usize != NODES {
        Err(hairsim_error::NodesMismatch)
    } else {
        Ok(())
    }
}

/// The library's version, `HAIRSIM_VERSION` of the header it was built with: `0x00MMmmpp`
/// (major, minor, patch).
#[no_mangle]
pub extern "C" fn hairsim_version() -> u32 {
    HAIRSIM_VERSION
}

/// What the header's `hairsim_init(buffer, len)` macro calls: checks that the header the
/// caller was compiled with (its `HAIRSIM_VERSION`, `HAIRSIM_STRANDS` and `HAIRSIM_NODES`,
/// which the macro passes) matches this library, then makes `buffer` an empty world with the
/// default parameters (those of `hairsim_params_default`), ready for `hairsim_configure`.
/// A mismatch is refused before the buffer is touched: `HAIRSIM_ERROR_VERSION_MISMATCH`,
/// `HAIRSIM_ERROR_STRANDS_MISMATCH` or `HAIRSIM_ERROR_NODES_MISMATCH`.
///
/// `len` is the buffer's size in bytes, at least `HAIRSIM_WORLD_SIZE`; the buffer is aligned to
/// `HAIRSIM_WORLD_ALIGN`. Calling it again on a world resets it. The world is written in place:
/// no world-sized copy on the stack. From then on the buffer belongs to the library: C code
/// must not write it, except through these functions. A buffer is recognised as a world by a
/// magic word in its first bytes: zero a buffer (static storage is) before its first
/// `hairsim_init`, so that bytes left from an earlier world at the same place do not pass for
/// one.
///
/// # Safety
/// `buffer`, if not NULL, must be valid for reads and writes of `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn hairsim_init_versioned(
    buffer: *mut hairsim_world,
    len: usize,
    version: u32,
    strands: u32,
    nodes: u32,
) -> hairsim_error {
    if let Err(e) = check_header(version, strands, nodes) {
        return e;
    }
    // SAFETY: the caller's promise.
    unsafe { init(buffer, len) }
}

/// What the header's `hairsim_init` macro does, for Rust callers of this crate (its tests, the
/// fuzz target): `hairsim_init_versioned` with this library's own version and capacities.
///
/// # Safety
/// As `hairsim_init_versioned`.
pub unsafe fn hairsim_init(buffer: *mut hairsim_world, len: usize) -> hairsim_error {
    // SAFETY: the caller's promise.
    unsafe { hairsim_init_versioned(buffer, len, HAIRSIM_VERSION, STRANDS as u32, NODES as u32) }
}

/// Makes `buffer` an empty world (`hairsim_init_versioned`, after its header check).
///
/// # Safety
/// As `hairsim_init_versioned`.
// Inlined, so that `.ci/ffi` finds the world's construction in `hairsim_init_versioned`'s
// frame.
#[inline(always)]
unsafe fn init(buffer: *mut hairsim_world, len: usize) -> hairsim_error {
    let cell = buffer.cast::<Cell>();
    if let Err(e) = check_ptr(cell) {
        return e;
    }
    if len < size_of::<Cell>() {
        return hairsim_error::BufferTooSmall;
    }
    // SAFETY: as in `lease`: non-NULL, aligned, valid for `size_of::<Cell>()` bytes (checked
    // against `len`), and the state word is only ever accessed atomically.
    let state = unsafe { &*addr_of!((*cell).state) };
    let previous = state.load(Ordering::Acquire);
    if previous == BUSY {
        return hairsim_error::Busy;
    }
    if previous == IDLE {
        // An initialised world: take it as any call would, so that no other call is using it.
        if state
            .compare_exchange(IDLE, BUSY, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            return hairsim_error::Busy;
        }
    } else if state
        .compare_exchange(previous, BUSY, Ordering::Acquire, Ordering::Relaxed)
        .is_err()
    {
        // Not a world yet, but another `hairsim_init` got here first.
        return hairsim_error::Busy;
    }
    // SAFETY: the world field lies inside the buffer (valid for writes, size checked) and is
    // aligned (the cell is); the state word is `BUSY` and was set by this call, so no other
    // call reads or writes the world. `ptr::write` neither reads nor drops what was there.
    // The optimiser builds the empty world in place, a fill of the buffer and a copy of the
    // default parameters, not on the stack (`.ci/ffi` checks `hairsim_init`'s frame in the
    // thumbv7em disassembly); a `const` empty world would be a world-sized copy from flash.
    unsafe { ptr::write(addr_of_mut!((*cell).world), SimWorld::new()) };
    state.store(IDLE, Ordering::Release);
    hairsim_error::Ok
}

/// Fills `out` with the preset of `solver` (a `hairsim_solver`): the effects and values hair
/// needs, at 1 ms in converge mode. The rod (`HAIRSIM_SOLVER_ROD`, Kmoch 2009): gravity, air
/// drag 2e-7 kg/s per node, bending, twist (hair-optimised) and inextensibility (projection
/// capped at 8 iterations, tolerance 1e-6). DFTL (`HAIRSIM_SOLVER_DFTL`, Sanchez-Banderas
/// 2015): gravity, the same drag, inextensibility and shape preservation (s_g 0.0066, s_l
/// 0.022 a millisecond, s_d 0.9). Neither has collisions or grabs: turn
/// `HAIRSIM_EFFECT_COLLISIONS` or `HAIRSIM_EFFECT_GRABS` on before adding a collider or a grab.
/// An unknown solver is `HAIRSIM_ERROR_OUT_OF_RANGE`.
///
/// # Safety
/// `out`, if not NULL, must be valid for writes of a `hairsim_params`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_params_preset(
    solver: u32,
    out: *mut hairsim_params,
) -> hairsim_error {
    let preset = match convert::solver(solver) {
        Ok(solver) => Params::preset(solver),
        Err(e) => return e,
    };
    // SAFETY: the caller's promise.
    code(unsafe { write(out, convert::params_to_c(&preset)) })
}

/// Fills `out` with the parameters `hairsim_init` gives a world: the rod's preset,
/// `hairsim_params_preset(HAIRSIM_SOLVER_ROD, out)` (DFTL's in a library built without the
/// rod).
///
/// # Safety
/// `out`, if not NULL, must be valid for writes of a `hairsim_params`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_params_default(out: *mut hairsim_params) -> hairsim_error {
    // SAFETY: the caller's promise.
    code(unsafe { write(out, convert::params_to_c(&Params::DEFAULT)) })
}

/// Fills `out` with a human hair: E = 3.5 GPa, G = 1.3 GPa, r = 40 um, 1300 kg/m^3.
///
/// # Safety
/// `out`, if not NULL, must be valid for writes of a `hairsim_material`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_material_human_hair(out: *mut hairsim_material) -> hairsim_error {
    // SAFETY: the caller's promise.
    code(unsafe { write(out, convert::material_to_c(&Material::HUMAN_HAIR)) })
}

/// Sets the world's parameters and effects (the time step included), after checking every
/// value. Strands, colliders and grabs already added stay.
///
/// # Safety
/// `world` as for `hairsim_init` (`HAIRSIM_WORLD_SIZE` bytes); `params`, if not NULL, valid
/// for reads of a `hairsim_params`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_configure(
    world: *mut hairsim_world,
    params: *const hairsim_params,
) -> hairsim_error {
    if let Err(e) = check_disjoint(params, 1, world) {
        return e;
    }
    // SAFETY: the caller's promise for `params`; it is copied before the world is borrowed.
    let params = match unsafe { read(params) }.and_then(|p| convert::params(&p)) {
        Ok(p) => p,
        Err(e) => return e,
    };
    let configure = |w: &mut SimWorld| w.configure(params).map_err(convert::param_error);
    // SAFETY: the caller's promise for `world`.
    code(unsafe { with_world(world, configure) })
}

/// Adds a strand at rest along the polyline `points[0 .. count)` (root first, in the head's
/// frame, 3 to `HAIRSIM_NODES` points), of `material`. Its index goes to `index` if not NULL.
///
/// # Safety
/// `world` as for `hairsim_init`; `points`, if not NULL, valid for reads of `count`
/// `hairsim_vec3`; `material`, if not NULL, of one `hairsim_material`; `index`, if not NULL,
/// valid for writes of a `uint32_t`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_add_strand(
    world: *mut hairsim_world,
    points: *const hairsim_vec3,
    count: usize,
    material: *const hairsim_material,
    index: *mut u32,
) -> hairsim_error {
    if count > NODES {
        return hairsim_error::TooManyNodes;
    }
    let checks = check_disjoint(material, 1, world)
        .and(check_disjoint(points, count, world))
        .and(check_optional(index))
        .and(check_disjoint(index, 1, world));
    if let Err(e) = checks {
        return e;
    }
    // SAFETY: the caller's promise for `material`; it is copied before the world is borrowed.
    let material = match unsafe { read(material) }.and_then(|m| convert::material(&m)) {
        Ok(m) => m,
        Err(e) => return e,
    };
    let mut polyline = [Vec3::ZERO; NODES];
    // SAFETY: the caller's promise for `points`; `count <= NODES` (checked). The points are
    // copied before the world is borrowed.
    match unsafe { slice(points, count) } {
        Ok(points) => {
            for (p, c) in polyline.iter_mut().zip(points) {
                *p = Vec3::new(c.x, c.y, c.z);
            }
        }
        Err(e) => return e,
    }
    let add = |w: &mut SimWorld| {
        let strand = Strand::<NODES>::from_polyline(&polyline[..count], &material)
            .map_err(convert::build_error)?;
        w.add_strand(strand).map_err(convert::capacity_error)
    };
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, add) } {
        // SAFETY: the caller's promise for `index` (the world is no longer borrowed).
        Ok(i) => code(unsafe { write_optional(index, i as u32) }),
        Err(e) => e,
    }
}

/// Adds a collider (at most `HAIRSIM_MAX_COLLIDERS`). Its index goes to `index` if not NULL.
///
/// # Safety
/// `world` as for `hairsim_init`; `collider`, if not NULL, valid for reads of a
/// `hairsim_collider`; `index`, if not NULL, valid for writes of a `uint32_t`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_add_collider(
    world: *mut hairsim_world,
    collider: *const hairsim_collider,
    index: *mut u32,
) -> hairsim_error {
    let checks = check_disjoint(collider, 1, world)
        .and(check_optional(index))
        .and(check_disjoint(index, 1, world));
    if let Err(e) = checks {
        return e;
    }
    // SAFETY: the caller's promise for `collider`; it is copied before the world is borrowed.
    let collider = match unsafe { read(collider) }.and_then(|c| convert::collider(&c)) {
        Ok(c) => c,
        Err(e) => return e,
    };
    let add = |w: &mut SimWorld| {
        w.add_collider(collider)
            .map_err(|e| convert::add_error(e, hairsim_error::InvalidCollider))
    };
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, add) } {
        // SAFETY: the caller's promise for `index` (the world is no longer borrowed).
        Ok(i) => code(unsafe { write_optional(index, i as u32) }),
        Err(e) => e,
    }
}

/// Adds a grab (at most `HAIRSIM_MAX_GRABS`) on a strand already added. Its index goes to
/// `index` if not NULL.
///
/// # Safety
/// `world` as for `hairsim_init`; `grab`, if not NULL, valid for reads of a `hairsim_grab`;
/// `index`, if not NULL, valid for writes of a `uint32_t`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_add_grab(
    world: *mut hairsim_world,
    grab: *const hairsim_grab,
    index: *mut u32,
) -> hairsim_error {
    let checks = check_disjoint(grab, 1, world)
        .and(check_optional(index))
        .and(check_disjoint(index, 1, world));
    if let Err(e) = checks {
        return e;
    }
    // SAFETY: the caller's promise for `grab`; it is copied before the world is borrowed.
    let grab = match unsafe { read(grab) } {
        Ok(g) => g,
        Err(e) => return e,
    };
    let target = match convert::vec3(grab.target) {
        Ok(t) => t,
        Err(e) => return e,
    };
    if !(grab.force_limit.is_finite() && grab.stiffness.is_finite() && grab.damping.is_finite()) {
        return hairsim_error::NotFinite;
    }
    let held = Grab::new(grab.strand, grab.node, target, grab.force_limit);
    let held = if grab.stiffness == 0.0 && grab.damping == 0.0 {
        held
    } else {
        held.with_coupling(Coupling::new(grab.stiffness, grab.damping))
    };
    let add = |w: &mut SimWorld| {
        w.add_grab(held)
            .map_err(|e| convert::add_error(e, hairsim_error::InvalidGrab))
    };
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, add) } {
        // SAFETY: the caller's promise for `index` (the world is no longer borrowed).
        Ok(i) => code(unsafe { write_optional(index, i as u32) }),
        Err(e) => e,
    }
}

/// Releases grab `grab` for good: its node is free from the next step on.
///
/// # Safety
/// `world` as for `hairsim_init`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_release_grab(
    world: *mut hairsim_world,
    grab: u32,
) -> hairsim_error {
    let release = |w: &mut SimWorld| {
        if grab as usize >= w.grabs().len() {
            return Err(hairsim_error::OutOfRange);
        }
        w.release_grab(grab as usize);
        Ok(())
    };
    // SAFETY: the caller's promise for `world`.
    code(unsafe { with_world(world, release) })
}

/// A step with caller accelerations (checked finite), copied into the core's vectors in a
/// frame of its own, so that a step without them does not pay for the buffer.
#[inline(never)]
fn step_with_accelerations(
    world: &mut SimWorld,
    head: hairsim_core::Pose,
    accelerations: &[hairsim_vec3],
) -> hairsim_core::StepReport {
    let mut buffer = [Vec3::ZERO; STRANDS * NODES];
    for (a, c) in buffer.iter_mut().zip(accelerations) {
        *a = Vec3::new(c.x, c.y, c.z);
    }
    world.step(&StepInput {
        head,
        accelerations: buffer.get(..accelerations.len()),
    })
}

/// Advances the world by one time step: sets the targets of grabs `0 .. grab_target_count`,
/// moves the head to `input->head` and steps every strand. The report goes to `report` if not
/// NULL. A non-finite or non-unit pose, a non-finite target or acceleration, more targets than
/// grabs or more accelerations than `HAIRSIM_STRANDS * HAIRSIM_NODES` are refused before
/// anything changes.
///
/// # Safety
/// `world` as for `hairsim_init`; `input`, if not NULL, valid for reads of a
/// `hairsim_step_input` whose arrays are valid for reads of their counts; `report`, if not
/// NULL, valid for writes of a `hairsim_step_report`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_step(
    world: *mut hairsim_world,
    input: *const hairsim_step_input,
    report: *mut hairsim_step_report,
) -> hairsim_error {
    if let Err(e) = check_disjoint(input, 1, world) {
        return e;
    }
    // SAFETY: the caller's promise for `input`; it is copied before the world is borrowed.
    let input = match unsafe { read(input) } {
        Ok(i) => i,
        Err(e) => return e,
    };
    let head = match convert::pose(&input.head) {
        Ok(h) => h,
        Err(e) => return e,
    };
    let (grab_count, acceleration_count) = (input.grab_target_count, input.acceleration_count);
    if grab_count > HAIRSIM_MAX_GRABS || acceleration_count > STRANDS * NODES {
        return hairsim_error::OutOfRange;
    }
    let checks = check_optional(report)
        .and(check_disjoint(report, 1, world))
        .and(check_disjoint(input.grab_targets, grab_count, world))
        .and(check_disjoint(
            input.accelerations,
            acceleration_count,
            world,
        ));
    if let Err(e) = checks {
        return e;
    }
    let mut targets = [Vec3::ZERO; HAIRSIM_MAX_GRABS];
    // SAFETY: the caller's promise for the targets; the count is bounded (checked). They are
    // copied before the world is borrowed.
    match unsafe { slice(input.grab_targets, grab_count) } {
        Ok(given) => {
            for (t, c) in targets.iter_mut().zip(given) {
                match convert::vec3(*c) {
                    Ok(v) => *t = v,
                    Err(e) => return e,
                }
            }
        }
        Err(e) => return e,
    }
    // SAFETY: the caller's promise for the accelerations; the count is bounded (checked), and
    // they do not overlap the world (checked), which is borrowed while they are read.
    let accelerations = match unsafe { slice(input.accelerations, acceleration_count) } {
        Ok(a) => a,
        Err(e) => return e,
    };
    if accelerations.iter().any(|a| convert::vec3(*a).is_err()) {
        return hairsim_error::NotFinite;
    }
    let step = |w: &mut SimWorld| {
        if grab_count > w.grabs().len() {
            return Err(hairsim_error::OutOfRange);
        }
        for (g, &t) in targets.iter().take(grab_count).enumerate() {
            w.set_grab_target(g, t);
        }
        Ok(if accelerations.is_empty() {
            w.step(&StepInput {
                head,
                accelerations: None,
            })
        } else {
            step_with_accelerations(w, head, accelerations)
        })
    };
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, step) } {
        // SAFETY: the caller's promise for `report` (the world is no longer borrowed).
        Ok(r) => code(unsafe { write_optional(report, convert::report_to_c(&r)) }),
        Err(e) => e,
    }
}

/// Copies strand `strand`'s node positions (m, world frame) into `out[0 .. nodes)`, where
/// `capacity` is `out`'s length in `hairsim_vec3`s (`out` may be NULL if it is 0). The node
/// count goes to `count` if not NULL, also when `out` is too short
/// (`HAIRSIM_ERROR_BUFFER_TOO_SMALL`, nothing copied).
///
/// # Safety
/// `world` as for `hairsim_init`; `out`, if not NULL, valid for writes of `capacity`
/// `hairsim_vec3`; `count`, if not NULL, valid for writes of a `size_t`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_strand_positions(
    world: *mut hairsim_world,
    strand: u32,
    out: *mut hairsim_vec3,
    capacity: usize,
    count: *mut usize,
) -> hairsim_error {
    let checks = if capacity == 0 {
        check_optional(out)
    } else {
        check_ptr(out)
    };
    // Only the first `NODES` entries are ever written.
    let used = capacity.min(NODES);
    let checks = checks
        .and(check_optional(count))
        .and(check_disjoint(count, 1, world))
        .and(check_disjoint(out, used, world));
    if let Err(e) = checks {
        return e;
    }
    let copy = |w: &mut SimWorld| {
        let s = w
            .strands()
            .get(strand as usize)
            .ok_or(hairsim_error::OutOfRange)?;
        let mut positions = [hairsim_vec3::default(); NODES];
        for (c, p) in positions.iter_mut().zip(s.positions()) {
            *c = convert::vec3_to_c(*p);
        }
        Ok((positions, s.nodes()))
    };
    // SAFETY: the caller's promise for `world`.
    let (positions, nodes) = match unsafe { with_world(world, copy) } {
        Ok(p) => p,
        Err(e) => return e,
    };
    // SAFETY: the caller's promise for `count` (checked aligned; the world is no longer
    // borrowed).
    if let Err(e) = unsafe { write_optional(count, nodes) } {
        return e;
    }
    if capacity < nodes {
        return hairsim_error::BufferTooSmall;
    }
    for (i, p) in positions.iter().take(nodes).enumerate() {
        // SAFETY: `i < nodes <= capacity`, and `out` is valid for `capacity` writes (the
        // caller's promise), non-NULL (capacity > 0 here) and aligned (checked).
        unsafe { ptr::write(out.add(i), *p) };
    }
    hairsim_error::Ok
}

/// The state hash of every strand (FNV-1a 64 over positions, velocities, twist angles and root
/// frames): the same as `hairsim run`'s `state_hash` for the same scene.
///
/// # Safety
/// `world` as for `hairsim_init`; `out`, if not NULL, valid for writes of a `uint64_t`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_state_hash(
    world: *mut hairsim_world,
    out: *mut u64,
) -> hairsim_error {
    if let Err(e) = check_ptr(out).and(check_disjoint(out, 1, world)) {
        return e;
    }
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, |w| Ok(w.state_hash())) } {
        // SAFETY: the caller's promise for `out` (the world is no longer borrowed).
        Ok(h) => code(unsafe { write(out, h) }),
        Err(e) => e,
    }
}

/// What the world holds: steps taken, strands, colliders, grabs and their states.
///
/// # Safety
/// `world` as for `hairsim_init`; `out`, if not NULL, valid for writes of a
/// `hairsim_world_info`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_get_info(
    world: *mut hairsim_world,
    out: *mut hairsim_world_info,
) -> hairsim_error {
    if let Err(e) = check_ptr(out).and(check_disjoint(out, 1, world)) {
        return e;
    }
    let info = |w: &mut SimWorld| {
        let mut info = hairsim_world_info {
            steps: w.steps(),
            strands: w.strands().len() as u32,
            colliders: w.colliders().len() as u32,
            grabs: w.grabs().len() as u32,
            grab_status: [hairsim_grab_status::None as u32; HAIRSIM_MAX_GRABS],
        };
        for (slot, g) in info.grab_status.iter_mut().zip(w.grabs()) {
            *slot = convert::grab_status_to_c(g.status);
        }
        Ok(info)
    };
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, info) } {
        // SAFETY: the caller's promise for `out` (the world is no longer borrowed).
        Ok(i) => code(unsafe { write(out, i) }),
        Err(e) => e,
    }
}

/// The head's pose at time `t` (s) of `shake`, computed as the core computes it with the
/// default math: the same bits as the Rust scenes, and no C math library.
///
/// # Safety
/// `shake`, if not NULL, valid for reads of a `hairsim_shake`; `out`, if not NULL, valid for
/// writes of a `hairsim_pose`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_shake_pose(
    shake: *const hairsim_shake,
    t: f32,
    out: *mut hairsim_pose,
) -> hairsim_error {
    if let Err(e) = check_ptr(out) {
        return e;
    }
    // SAFETY: the caller's promise for `shake`.
    let pose = unsafe { read(shake) }.and_then(|s| convert::shake_pose(&s, t));
    match pose {
        // SAFETY: the caller's promise for `out`.
        Ok(p) => code(unsafe { write(out, p) }),
        Err(e) => e,
    }
}

/// Where a point going round `circle` is at time `t` (s), for a grab target: computed as the
/// core's scenes compute it.
///
/// # Safety
/// `circle`, if not NULL, valid for reads of a `hairsim_circle`; `out`, if not NULL, valid for
/// writes of a `hairsim_vec3`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_circle_target(
    circle: *const hairsim_circle,
    t: f32,
    out: *mut hairsim_vec3,
) -> hairsim_error {
    if let Err(e) = check_ptr(out) {
        return e;
    }
    // SAFETY: the caller's promise for `circle`.
    let target = unsafe { read(circle) }.and_then(|c| convert::circle_target(&c, t));
    match target {
        // SAFETY: the caller's promise for `out`.
        Ok(p) => code(unsafe { write(out, p) }),
        Err(e) => e,
    }
}

/// The library's capacities and the world's size and alignment on this target, to check
/// against the header's `HAIRSIM_*` constants.
///
/// # Safety
/// `out`, if not NULL, valid for writes of a `hairsim_capacity`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_get_capacity(out: *mut hairsim_capacity) -> hairsim_error {
    let capacity = hairsim_capacity {
        strands: STRANDS as u32,
        nodes: NODES as u32,
        colliders: HAIRSIM_MAX_COLLIDERS as u32,
        grabs: HAIRSIM_MAX_GRABS as u32,
        world_size: WORLD_SIZE,
        world_align: WORLD_ALIGN,
    };
    // SAFETY: the caller's promise for `out`.
    code(unsafe { write(out, capacity) })
}

/// What `code` means, in words: a static NUL-terminated string, never NULL (an unknown code
/// has a message too).
#[no_mangle]
pub extern "C" fn hairsim_error_message(code: i32) -> *const c_char {
    let message: &'static core::ffi::CStr = match code {
        0 => c"success",
        1 => c"a required pointer is NULL",
        2 => c"a pointer is not aligned for its type (the world: HAIRSIM_WORLD_ALIGN)",
        3 => c"a buffer is too small (the world: HAIRSIM_WORLD_SIZE bytes)",
        4 => c"the world buffer was not initialised by hairsim_init",
        5 => c"another call on this world is running (re-entry)",
        6 => c"a value is NaN or infinite, or a result would be",
        7 => c"a value is out of its range (a parameter, an enum value, a flag bit, an index)",
        8 => c"an effect is on that the solver cannot simulate",
        9 => c"a strand needs at least 3 nodes",
        10 => c"a strand has more nodes than HAIRSIM_NODES",
        11 => c"a polyline segment is shorter than 1e-6 m",
        12 => c"the polyline folds back on itself (a turning angle of 180 degrees)",
        13 => c"a material value is out of range",
        14 => c"the world holds HAIRSIM_STRANDS strands already",
        15 => c"the world holds HAIRSIM_MAX_COLLIDERS colliders already",
        16 => c"the world holds HAIRSIM_MAX_GRABS grabs already",
        17 => c"a collider is out of range (finite, a radius from 1e-5 to 1e4 m, a unit normal)",
        18 => c"a grab names no strand, a node outside 2 to the last, or a force limit <= 0",
        19 => c"an argument's buffer overlaps the world's",
        20 => c"hairsim.h is of another version than the library (HAIRSIM_VERSION_MAJOR, MINOR)",
        21 => c"hairsim.h was generated for another HAIRSIM_STRANDS than the library",
        22 => c"hairsim.h was generated for another HAIRSIM_NODES than the library",
        23 => c"a collider needs HAIRSIM_EFFECT_COLLISIONS on, a grab HAIRSIM_EFFECT_GRABS",
        _ => c"unknown error code",
    };
    message.as_ptr()
}

/// The backstop of a library that does not panic: with `panic = "abort"` there is nothing to
/// unwind, so it stops here. A std binary that links the rlib (feature `std`) uses std's.
#[cfg(all(not(test), not(feature = "std")))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}

/// The unwinding personality routine that a hosted target's precompiled `core` (built to
/// unwind) refers to. Nothing unwinds through this library (`panic = "abort"`, and no call
/// back into C), so it is never called; it only lets a C program on such a host link. Bare
/// metal targets' `core` does not refer to it.
#[cfg(all(not(test), not(feature = "std"), not(target_os = "none")))]
#[no_mangle]
pub extern "C" fn rust_eh_personality() {
    loop {
        core::hint::spin_loop();
    }
}
