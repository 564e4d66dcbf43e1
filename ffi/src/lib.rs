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
mod integrity;
mod refusal;
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
    Coupling, DefaultMath, Grab, Material, Math, Params, StepInput, StepReport, Vec3, World,
};

use convert::Result;
use integrity::Checksums;
use refusal::{Function, Name, Record, Refused};
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
    /// The outcome of the last call on the world (`hairsim_last_refusal`); only reached
    /// through a [`Lease`].
    record: Record,
    /// The strands' rest-data checksums (`hairsim_check`); only reached through a [`Lease`].
    checksums: Checksums<S>,
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
    /// The world's record of its last call's outcome.
    record: &'a mut Record,
    /// The strands' rest-data checksums.
    checksums: &'a mut Checksums,
}

impl Drop for Lease<'_> {
    fn drop(&mut self) {
        self.state.store(IDLE, Ordering::Release);
    }
}

/// `code` about `argument`.
fn refused(code: hairsim_error, argument: Name) -> Refused {
    Refused::from(code).argument(argument)
}

/// Checks that `p` (the argument `argument`) is non-NULL and aligned for `T`.
fn check_ptr<T>(p: *const T, argument: Name) -> Result<()> {
    if p.is_null() {
        Err(refused(hairsim_error::NullPointer, argument))
    } else if !p.is_aligned() {
        Err(refused(hairsim_error::Misaligned, argument))
    } else {
        Ok(())
    }
}

/// Checks an optional pointer: NULL, or aligned for `T`.
fn check_optional<T>(p: *const T, argument: Name) -> Result<()> {
    if p.is_null() || p.is_aligned() {
        Ok(())
    } else {
        Err(refused(hairsim_error::Misaligned, argument))
    }
}

/// Checks that `count` `T`s at `p` do not overlap the world's buffer: the world is borrowed
/// mutably while they are read or written.
fn check_disjoint<T>(
    p: *const T,
    count: usize,
    world: *const hairsim_world,
    argument: Name,
) -> Result<()> {
    if p.is_null() || count == 0 {
        return Ok(());
    }
    let start = p as usize;
    let end = start.saturating_add(count.saturating_mul(size_of::<T>()));
    let world_start = world as usize;
    let world_end = world_start.saturating_add(WORLD_SIZE);
    if start < world_end && world_start < end {
        Err(refused(hairsim_error::Overlap, argument))
    } else {
        Ok(())
    }
}

/// Copies the `T` at `p` (the argument `argument`) out of the caller's memory.
///
/// # Safety
/// `p`, if not NULL, must be valid for reads of a `T`, and `T` must be plain data for which
/// every bit pattern is a valid value.
unsafe fn read<T: Copy>(p: *const T, argument: Name) -> Result<T> {
    check_ptr(p, argument)?;
    // SAFETY: `p` is non-NULL and aligned (checked), valid for reads of a `T` (the caller's
    // promise), and every `T` used here is a `#[repr(C)]` struct of integers, floats and raw
    // pointers: every bit pattern is a valid value.
    Ok(unsafe { ptr::read(p) })
}

/// Writes `value` to `p` (the argument `argument`).
///
/// # Safety
/// `p`, if not NULL, must be valid for writes of a `T`.
unsafe fn write<T>(p: *mut T, value: T, argument: Name) -> Result<()> {
    check_ptr(p, argument)?;
    // SAFETY: `p` is non-NULL and aligned (checked) and valid for writes of a `T` (the
    // caller's promise); `T` is plain data with no destructor: nothing is dropped.
    unsafe { ptr::write(p, value) };
    Ok(())
}

/// Writes `value` to `p` if `p` is not NULL (an optional output, checked beforehand).
///
/// # Safety
/// `p`, if not NULL, must be valid for writes of a `T`.
unsafe fn write_optional<T>(p: *mut T, value: T, argument: Name) -> Result<()> {
    if p.is_null() {
        return Ok(());
    }
    // SAFETY: the caller's promise for a non-NULL `p`.
    unsafe { write(p, value, argument) }
}

/// Writes the C form of the step report `r` to `p` if `p` is not NULL (the argument
/// `report`), in place.
///
/// # Safety
/// `p`, if not NULL, must be valid for writes of a `hairsim_step_report` that nothing else
/// reads or writes meanwhile.
unsafe fn write_report(p: *mut hairsim_step_report, r: &StepReport) -> Result<()> {
    if p.is_null() {
        return Ok(());
    }
    check_ptr(p, Name::Report)?;
    // SAFETY: `p` is non-NULL and aligned (checked) and valid for writes of a report (the
    // caller's promise). Zeroed first, its bytes are a valid report (integers and floats
    // only), so the reference below is to a valid value, and nothing else reaches it.
    let out = unsafe {
        ptr::write_bytes(p, 0, 1);
        &mut *p
    };
    convert::report_into_c(r, out);
    Ok(())
}

/// The caller's array `(p, count)` (the argument `argument`) as a slice, after checking the
/// pointer; `count` 0 accepts NULL. `count` must already be bounded by a capacity, so that
/// `count * size_of::<T>()` is far below `isize::MAX`.
///
/// # Safety
/// `p`, if not NULL, must be valid for reads of `count` `T`s that nothing writes while the
/// slice lives, and every bit pattern of `T` must be a valid value.
unsafe fn slice<'a, T>(p: *const T, count: usize, argument: Name) -> Result<&'a [T]> {
    if count == 0 {
        return Ok(&[]);
    }
    check_ptr(p, argument)?;
    // SAFETY: `p` is non-NULL and aligned (checked) and valid for reads of `count` elements
    // nothing writes meanwhile (the caller's promise); `count` is bounded by a capacity, so
    // the slice is far smaller than `isize::MAX` bytes; every bit pattern of `T` is valid.
    Ok(unsafe { core::slice::from_raw_parts(p, count) })
}

/// Takes the state word of an initialised world: from `IDLE` to `BUSY`. A refusal here is
/// about the argument `world`, and nothing can be recorded in it.
///
/// # Safety
/// `world`, if not NULL, must be valid for reads and writes of `HAIRSIM_WORLD_SIZE` bytes for
/// the length of the call.
unsafe fn take<'a>(world: *mut hairsim_world) -> Result<(&'a AtomicU32, *mut Cell)> {
    let cell = world.cast::<Cell>();
    check_ptr(cell, Name::World)?;
    // SAFETY: `cell` is non-NULL and aligned for `Cell` (checked) and the buffer is valid for
    // `size_of::<Cell>()` bytes (the caller's promise), so its first field is a valid
    // `AtomicU32` place: any bit pattern is a `u32`. It is only ever accessed atomically, here
    // and in other calls, so shared references to it may coexist.
    let state = unsafe { &*addr_of!((*cell).state) };
    match state.compare_exchange(IDLE, BUSY, Ordering::Acquire, Ordering::Relaxed) {
        Ok(_) => Ok((state, cell)),
        Err(BUSY) => Err(refused(hairsim_error::Busy, Name::World)),
        Err(_) => Err(refused(hairsim_error::NotInitialised, Name::World)),
    }
}

/// The lease of a cell whose state word this call holds at `BUSY`.
///
/// # Safety
/// `cell` as [`take`] returns it, and its world's bytes passed [`integrity::structure`].
unsafe fn lease_of<'a>(state: &'a AtomicU32, cell: *mut Cell) -> Lease<'a> {
    // SAFETY: the state word was `IDLE`, so `hairsim_init` wrote a world, a record and
    // checksums after it, and this call swapped it to `BUSY`: every other call refuses until
    // the lease is dropped, so these are the only references to them (fields disjoint from
    // the state word and from each other), and the caller's other buffers were checked not
    // to overlap them. A record and checksums are integers only: any bytes are one.
    unsafe {
        Lease {
            state,
            world: &mut *addr_of_mut!((*cell).world),
            record: &mut *addr_of_mut!((*cell).record),
            checksums: &mut *addr_of_mut!((*cell).checksums),
        }
    }
}

/// Takes exclusive use of an initialised world, after the cheap part of its check
/// ([`integrity::structure`]): a world whose bytes fail it is never read as a `World`, the
/// refusal (`HAIRSIM_ERROR_CORRUPT`) is recorded for `function`, and the world stays refused
/// until `hairsim_init`.
///
/// # Safety
/// As [`take`].
unsafe fn lease<'a>(world: *mut hairsim_world, function: Function) -> Result<Lease<'a>> {
    // SAFETY: the caller's promise.
    let (state, cell) = unsafe { take(world) }?;
    // SAFETY: this call holds the state word: nothing writes the cell meanwhile.
    if let Err(why) = unsafe { integrity::structure(cell) } {
        // SAFETY: the record lies in the cell, is integers only, and this call holds it.
        unsafe { addr_of_mut!((*cell).record).write(Record::of(function, Some(why))) };
        state.store(IDLE, Ordering::Release);
        return Err(why);
    }
    // SAFETY: the structure passed.
    Ok(unsafe { lease_of(state, cell) })
}

/// Runs `f` on the world under a lease, and records the outcome of `function` in the world
/// (unless the world itself is refused).
///
/// # Safety
/// As [`lease`].
unsafe fn with_world<T>(
    world: *mut hairsim_world,
    function: Function,
    f: impl FnOnce(&mut SimWorld) -> Result<T>,
) -> Result<T> {
    // SAFETY: the caller's promise.
    unsafe { with_lease(world, function, |lease| f(lease.world)) }
}

/// [`with_world`] with the whole lease: the world, its record and checksums.
///
/// # Safety
/// As [`lease`].
unsafe fn with_lease<T>(
    world: *mut hairsim_world,
    function: Function,
    f: impl FnOnce(&mut Lease<'_>) -> Result<T>,
) -> Result<T> {
    // SAFETY: the caller's promise is `lease`'s.
    let mut lease = unsafe { lease(world, function) }?;
    let result = f(&mut lease);
    *lease.record = Record::of(function, result.as_ref().err().copied());
    result
}

/// Refuses a call of `function` before it reached the world: records why in the world, if
/// the world can be taken, and returns the code.
///
/// # Safety
/// As [`lease`].
unsafe fn refuse(world: *mut hairsim_world, function: Function, why: Refused) -> hairsim_error {
    if why.argument != Name::World {
        // SAFETY: the caller's promise is `lease`'s.
        if let Ok(lease) = unsafe { lease(world, function) } {
            *lease.record = Record::of(function, Some(why));
        }
    }
    why.code
}

fn code(r: Result<()>) -> hairsim_error {
    match r {
        Ok(()) => hairsim_error::Ok,
        Err(e) => e.code,
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
        Err(hairsim_error::VersionMismatch.into())
    } else if strands as usize != STRANDS {
        Err(hairsim_error::StrandsMismatch.into())
    } else if nodes as usize != NODES {
        Err(hairsim_error::NodesMismatch.into())
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
        return e.code;
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
    if let Err(e) = check_ptr(cell, Name::World) {
        return e.code;
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
    // SAFETY: as the world's, for the record and the checksums.
    unsafe {
        ptr::write(addr_of_mut!((*cell).record), Record::NONE);
        ptr::write(addr_of_mut!((*cell).checksums), Checksums::NONE);
    }
    state.store(IDLE, Ordering::Release);
    hairsim_error::Ok
}

/// Fills `out` with the preset of `solver` (a `hairsim_solver`): the effects and values hair
/// needs, at 1 ms in converge mode. The rod (`HAIRSIM_SOLVER_ROD`, Kmoch 2009): gravity, air
/// drag 2e-7 kg/s per node, bending, twist (hair-optimised) and inextensibility (projection
/// capped at 8 iterations, tolerance 1e-6). DFTL (`HAIRSIM_SOLVER_DFTL`, Sanchez-Banderas
/// 2015): gravity, the same drag, inextensibility and shape preservation (s_g 0.0066, s_l
/// 0.022 a millisecond, s_d 0.9); a strand a grab holds runs the rod's projection, 2 iterations
/// every step. Neither has collisions or grabs: turn
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
        Err(e) => return e.code,
    };
    // SAFETY: the caller's promise.
    code(unsafe { write(out, convert::params_to_c(&preset), Name::Out) })
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
    code(unsafe { write(out, convert::params_to_c(&Params::DEFAULT), Name::Out) })
}

/// Fills `out` with a human hair: E = 3.5 GPa, G = 1.3 GPa, r = 40 um, 1300 kg/m^3.
///
/// # Safety
/// `out`, if not NULL, must be valid for writes of a `hairsim_material`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_material_human_hair(out: *mut hairsim_material) -> hairsim_error {
    // SAFETY: the caller's promise.
    code(unsafe {
        write(
            out,
            convert::material_to_c(&Material::HUMAN_HAIR),
            Name::Out,
        )
    })
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
    const F: Function = Function::Configure;
    // SAFETY: the caller's promise for `params`; it is copied before the world is borrowed.
    let checked = check_disjoint(params, 1, world, Name::Params)
        .and_then(|()| unsafe { read(params, Name::Params) })
        .and_then(|p| convert::params(&p).map_err(|r| r.argument(Name::Params)));
    let params = match checked {
        Ok(p) => p,
        // SAFETY: the caller's promise for `world`.
        Err(why) => return unsafe { refuse(world, F, why) },
    };
    let configure = |w: &mut SimWorld| {
        w.configure(params)
            .map_err(|e| convert::param_error(e).argument(Name::Params))
    };
    // SAFETY: the caller's promise for `world`.
    code(unsafe { with_world(world, F, configure) })
}

/// Adds a strand at rest along the polyline `points[0 .. count)` (root first, in the head's
/// frame, 3 to `HAIRSIM_NODES` points, each segment from 1e-6 m to 1 m long), of `material`.
/// Its index goes to `index` if not NULL. A refused point or segment is named by
/// `hairsim_last_refusal` (argument `points`, its index).
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
    const F: Function = Function::AddStrand;
    let checked = if count > NODES {
        Err(refused(hairsim_error::TooManyNodes, Name::Count))
    } else {
        check_disjoint(material, 1, world, Name::Material)
            .and(check_disjoint(points, count, world, Name::Points))
            .and(check_optional(index, Name::Index))
            .and(check_disjoint(index, 1, world, Name::Index))
    }
    // SAFETY: the caller's promise for `material`; it is copied before the world is
    // borrowed.
    .and_then(|()| unsafe { read(material, Name::Material) })
    .and_then(|m| convert::material(&m).map_err(|r| r.argument(Name::Material)))
    .and_then(|m| {
        // SAFETY: the caller's promise for `points`, which nothing writes meanwhile and which
        // do not overlap the world (checked); `count <= NODES` (checked). Their layout is
        // `Vec3`'s (asserted at `Checked`), and every bit pattern is an `f32`.
        let points = unsafe { slice(points.cast::<Vec3>(), count, Name::Points) }?;
        Ok((m, points))
    });
    let (material, points) = match checked {
        Ok(c) => c,
        // SAFETY: the caller's promise for `world`.
        Err(why) => return unsafe { refuse(world, F, why) },
    };
    // Built in the world's storage: no strand-sized value on the stack.
    let add = |lease: &mut Lease<'_>| {
        let i = lease
            .world
            .add_strand_from_polyline(points, &material)
            .map_err(|e| convert::add_error(e, hairsim_error::InvalidMaterial))?;
        lease
            .checksums
            .keep(i, lease.world.strands()[i].rest.checksum());
        Ok(i)
    };
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_lease(world, F, add) } {
        // SAFETY: the caller's promise for `index` (checked; the world is no
        // longer borrowed).
        Ok(i) => code(unsafe { write_optional(index, i as u32, Name::Index) }),
        Err(e) => e.code,
    }
}

/// Adds a collider (at most `HAIRSIM_MAX_COLLIDERS`; `HAIRSIM_EFFECT_COLLISIONS` must be on).
/// Its index goes to `index` if not NULL.
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
    const F: Function = Function::AddCollider;
    let checked = check_disjoint(collider, 1, world, Name::Collider)
        .and(check_optional(index, Name::Index))
        .and(check_disjoint(index, 1, world, Name::Index))
        // SAFETY: the caller's promise for `collider`; it is copied before the world is
        // borrowed.
        .and_then(|()| unsafe { read(collider, Name::Collider) })
        .and_then(|c| convert::collider(&c).map_err(|r| r.argument(Name::Collider)));
    let collider = match checked {
        Ok(c) => c,
        // SAFETY: the caller's promise for `world`.
        Err(why) => return unsafe { refuse(world, F, why) },
    };
    let add = |w: &mut SimWorld| {
        w.add_collider(collider).map_err(|e| {
            convert::add_error(e, hairsim_error::InvalidCollider).argument(Name::Collider)
        })
    };
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, F, add) } {
        // SAFETY: the caller's promise for `index` (checked; the world is no
        // longer borrowed).
        Ok(i) => code(unsafe { write_optional(index, i as u32, Name::Index) }),
        Err(e) => e.code,
    }
}

/// Adds a grab (at most `HAIRSIM_MAX_GRABS`; `HAIRSIM_EFFECT_GRABS` must be on) on a strand
/// already added. Its index goes to `index` if not NULL.
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
    const F: Function = Function::AddGrab;
    let not_finite = |field| refused(hairsim_error::NotFinite, Name::Grab).field(field);
    let checked = check_disjoint(grab, 1, world, Name::Grab)
        .and(check_optional(index, Name::Index))
        .and(check_disjoint(index, 1, world, Name::Index))
        // SAFETY: the caller's promise for `grab`; it is copied before the world is borrowed.
        .and_then(|()| unsafe { read(grab, Name::Grab) })
        .and_then(|g| {
            let target = convert::vec3(g.target).map_err(|_| not_finite(Name::Target))?;
            let finite = [
                (g.force_limit, Name::ForceLimit),
                (g.stiffness, Name::Stiffness),
                (g.damping, Name::Damping),
            ];
            if let Some(&(_, field)) = finite.iter().find(|(value, _)| !value.is_finite()) {
                return Err(not_finite(field));
            }
            let held = Grab::new(g.strand, g.node, target, g.force_limit);
            // Both zero: prescribed at the target; anything else is a coupling, in range or
            // refused by the core (naming the field).
            Ok(if g.stiffness == 0.0 && g.damping == 0.0 {
                held
            } else {
                held.with_coupling(Coupling::new(g.stiffness, g.damping))
            })
        });
    let grab = match checked {
        Ok(g) => g,
        // SAFETY: the caller's promise for `world`.
        Err(why) => return unsafe { refuse(world, F, why) },
    };
    let add = |w: &mut SimWorld| {
        w.add_grab(grab)
            .map_err(|e| convert::add_error(e, hairsim_error::InvalidGrab).argument(Name::Grab))
    };
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, F, add) } {
        // SAFETY: the caller's promise for `index` (checked; the world is no
        // longer borrowed).
        Ok(i) => code(unsafe { write_optional(index, i as u32, Name::Index) }),
        Err(e) => e.code,
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
            return Err(refused(hairsim_error::OutOfRange, Name::Grab));
        }
        w.release_grab(grab as usize);
        Ok(())
    };
    // SAFETY: the caller's promise for `world`.
    code(unsafe { with_world(world, Function::ReleaseGrab, release) })
}

/// What a step takes from its input, checked and copied out of the caller's memory: the head
/// pose, the grab targets and the accelerations (the caller's array, whose layout is the
/// core's `Vec3`'s).
struct Checked<'a> {
    head: hairsim_core::Pose,
    targets: [Vec3; HAIRSIM_MAX_GRABS],
    target_count: usize,
    accelerations: &'a [Vec3],
}

// `hairsim_vec3` and glam's `Vec3` (without SIMD) are both three `f32`s in a `repr(C)` struct.
const _: () = assert!(size_of::<hairsim_vec3>() == size_of::<Vec3>());
const _: () = assert!(align_of::<hairsim_vec3>() == align_of::<Vec3>());

/// Checks a step's input and its arrays.
///
/// # Safety
/// As `hairsim_step` for `input` and `report`.
unsafe fn step_input<'a>(
    world: *mut hairsim_world,
    input: *const hairsim_step_input,
    report: *mut hairsim_step_report,
) -> Result<Checked<'a>> {
    let arg = |r: Refused| r.argument(Name::Input);
    check_disjoint(input, 1, world, Name::Input)?;
    // SAFETY: the caller's promise for `input`; it is copied before the world is borrowed.
    let input = unsafe { read(input, Name::Input) }?;
    let head = convert::pose(&input.head).map_err(arg)?;
    let (target_count, acceleration_count) = (input.grab_target_count, input.acceleration_count);
    if target_count > HAIRSIM_MAX_GRABS {
        return Err(arg(
            Refused::from(hairsim_error::OutOfRange).field(Name::GrabTargetCount)
        ));
    }
    if acceleration_count > STRANDS * NODES {
        let too_many = Refused::from(hairsim_error::OutOfRange).field(Name::AccelerationCount);
        return Err(arg(too_many));
    }
    check_optional(report, Name::Report)?;
    check_disjoint(report, 1, world, Name::Report)?;
    let field = |name: Name| move |r: Refused| arg(r.field(name));
    check_disjoint(input.grab_targets, target_count, world, Name::Input)
        .map_err(field(Name::GrabTargets))?;
    check_disjoint(input.accelerations, acceleration_count, world, Name::Input)
        .map_err(field(Name::Accelerations))?;
    let mut targets = [Vec3::ZERO; HAIRSIM_MAX_GRABS];
    // SAFETY: the caller's promise for the targets; the count is bounded (checked).
    let given = unsafe { slice(input.grab_targets, target_count, Name::Input) }
        .map_err(field(Name::GrabTargets))?;
    for (k, (t, c)) in targets.iter_mut().zip(given).enumerate() {
        *t = convert::vec3(*c).map_err(|r| field(Name::GrabTargets)(r).at(k))?;
    }
    // SAFETY: the caller's promise for the accelerations; the count is bounded (checked), and
    // they do not overlap the world (checked), which is borrowed while they are read. Their
    // layout is `Vec3`'s (asserted above), and every bit pattern is an `f32`.
    let accelerations: &[Vec3] = unsafe {
        slice(
            input.accelerations.cast::<Vec3>(),
            acceleration_count,
            Name::Input,
        )
        .map_err(field(Name::Accelerations))?
    };
    if let Some(k) = accelerations
        .iter()
        .position(|a| !hairsim_core::math::is_finite(*a))
    {
        let not_finite = Refused::from(hairsim_error::NotFinite);
        return Err(field(Name::Accelerations)(not_finite).at(k));
    }
    Ok(Checked {
        head,
        targets,
        target_count,
        accelerations,
    })
}

/// Advances the world by one time step: sets the targets of grabs `0 .. grab_target_count`,
/// moves the head to `input->head` and steps every strand. The report goes to `report` if not
/// NULL. A non-finite or non-unit pose, a non-finite target or acceleration, more targets than
/// grabs or more accelerations than `HAIRSIM_STRANDS * HAIRSIM_NODES` are refused before
/// anything changes (`hairsim_last_refusal` names the field and the element).
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
    const F: Function = Function::Step;
    // SAFETY: the caller's promises for `input` and `report`.
    let checked = match unsafe { step_input(world, input, report) } {
        Ok(c) => c,
        // SAFETY: the caller's promise for `world`.
        Err(why) => return unsafe { refuse(world, F, why) },
    };
    // The report is written here and converted into the caller's: not moved out of the
    // closure (each move of it was a copy on the stack, the frame of every step).
    let mut r = StepReport::default();
    let step = |w: &mut SimWorld| {
        if checked.target_count > w.grabs().len() {
            let more = Refused::from(hairsim_error::OutOfRange).field(Name::GrabTargetCount);
            return Err(more.argument(Name::Input));
        }
        for (g, &t) in checked.targets[..checked.target_count].iter().enumerate() {
            w.set_grab_target(g, t);
        }
        let accelerations = checked.accelerations;
        let input = StepInput {
            head: checked.head,
            accelerations: (!accelerations.is_empty()).then_some(accelerations),
        };
        w.step_into(&input, &mut r);
        Ok(())
    };
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, F, step) } {
        // SAFETY: the caller's promise for `report` (checked; the world is no
        // longer borrowed).
        Ok(()) => code(unsafe { write_report(report, &r) }),
        Err(e) => e.code,
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
    const F: Function = Function::StrandPositions;
    // Only the first `NODES` entries are ever written.
    let used = capacity.min(NODES);
    let out_ok = if capacity == 0 {
        check_optional(out, Name::Out)
    } else {
        check_ptr(out, Name::Out)
    };
    let checked = out_ok
        .and(check_optional(count, Name::Count))
        .and(check_disjoint(count, 1, world, Name::Count))
        .and(check_disjoint(out, used, world, Name::Out));
    if let Err(why) = checked {
        // SAFETY: the caller's promise for `world`.
        return unsafe { refuse(world, F, why) };
    }
    // The node count goes to `count` also when `out` is too short.
    let mut nodes = None;
    let copy = |w: &mut SimWorld| {
        let s = w
            .strands()
            .get(strand as usize)
            .ok_or(refused(hairsim_error::OutOfRange, Name::Strand))?;
        nodes = Some(s.nodes());
        if capacity < s.nodes() {
            return Err(refused(hairsim_error::BufferTooSmall, Name::Capacity));
        }
        let mut positions = [hairsim_vec3::default(); NODES];
        for (c, p) in positions.iter_mut().zip(s.positions()) {
            *c = convert::vec3_to_c(*p);
        }
        Ok(positions)
    };
    // SAFETY: the caller's promise for `world`.
    let outcome = unsafe { with_world(world, F, copy) };
    if let Some(n) = nodes {
        // SAFETY: the caller's promise for `count` (checked; the world is no longer borrowed).
        if let Err(e) = unsafe { write_optional(count, n, Name::Count) } {
            return e.code;
        }
    }
    let positions = match outcome {
        Ok(p) => p,
        Err(e) => return e.code,
    };
    for (i, p) in positions.iter().take(nodes.unwrap_or(0)).enumerate() {
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
    const F: Function = Function::StateHash;
    if let Err(why) = check_ptr(out, Name::Out).and(check_disjoint(out, 1, world, Name::Out)) {
        // SAFETY: the caller's promise for `world`.
        return unsafe { refuse(world, F, why) };
    }
    // SAFETY: the caller's promise for `world`.
    match unsafe { with_world(world, F, |w| Ok(w.state_hash())) } {
        // SAFETY: the caller's promise for `out` (checked; the world is no
        // longer borrowed).
        Ok(h) => code(unsafe { write(out, h, Name::Out) }),
        Err(e) => e.code,
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
    const F: Function = Function::GetInfo;
    if let Err(why) = check_ptr(out, Name::Out).and(check_disjoint(out, 1, world, Name::Out)) {
        // SAFETY: the caller's promise for `world`.
        return unsafe { refuse(world, F, why) };
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
    match unsafe { with_world(world, F, info) } {
        // SAFETY: the caller's promise for `out` (checked; the world is no
        // longer borrowed).
        Ok(i) => code(unsafe { write(out, i, Name::Out) }),
        Err(e) => e.code,
    }
}

/// What the last call on `world` that reached it did: its code (`HAIRSIM_ERROR_OK` when it
/// succeeded) and, when it was refused, the function, the argument and field it refused and
/// the element concerned. Every call on a world but this one records its outcome there,
/// except a call refused because of the world argument itself (NULL, misaligned, not
/// initialised, busy): that refusal cannot be kept in the world. Reading it changes nothing.
///
/// # Safety
/// `world` as for `hairsim_init`; `out`, if not NULL, valid for writes of a
/// `hairsim_refusal`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_last_refusal(
    world: *mut hairsim_world,
    out: *mut hairsim_refusal,
) -> hairsim_error {
    if let Err(why) = check_ptr(out, Name::Out).and(check_disjoint(out, 1, world, Name::Out)) {
        return why.code;
    }
    // SAFETY: the caller's promise for `world`.
    let (state, cell) = match unsafe { take(world) } {
        Ok(taken) => taken,
        Err(e) => return e.code,
    };
    // SAFETY: this call holds the state word; the record alone is read (integers: any bytes
    // are one), not the world, whatever its bytes.
    let record = unsafe { addr_of!((*cell).record).read() };
    state.store(IDLE, Ordering::Release);
    // SAFETY: the caller's promise for `out` (checked; the world is no longer held).
    code(unsafe { write(out, record.to_c(), Name::Out) })
}

/// Checks the world's raw bytes before anything reads them as a world (after a reset in the
/// middle of a call, or to find a stray write into the buffer): the part every call runs
/// first (the enum bytes, the lists' lengths, each strand's node count and schedule, each
/// collider's shape, each grab's status, strand and node, the parameters' ranges), then every
/// strand's state finite and its rest data unchanged since it was added (a checksum).
/// `HAIRSIM_ERROR_CORRUPT`, with `hairsim_last_refusal` naming the part and the element, says
/// the world must be made anew (`hairsim_init`). Costs a pass over every node; the first part
/// alone, which `hairsim_step` runs, a pass over the lists.
///
/// # Safety
/// `world` as for `hairsim_init`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_check(world: *mut hairsim_world) -> hairsim_error {
    let check = |lease: &mut Lease<'_>| integrity::contents(lease.world, lease.checksums);
    // SAFETY: the caller's promise for `world`.
    code(unsafe { with_lease(world, Function::Check, check) })
}

/// Makes a world usable again after a reset that stopped a call half-way (the world in RAM
/// that the reset kept): the state word that call left busy is cleared, then the world is
/// checked as `hairsim_check` checks it. `HAIRSIM_ERROR_OK`: the world steps on from where
/// the interrupted call left it (a step cut short leaves some strands a step ahead of the
/// others). `HAIRSIM_ERROR_CORRUPT`: make it anew with `hairsim_init`.
///
/// Call it only where no call on this world can be running: at start-up, before the tasks
/// and interrupts that use the world start. A call it interrupted would go on with a world
/// it no longer holds.
///
/// # Safety
/// `world` as for `hairsim_init`.
#[no_mangle]
pub unsafe extern "C" fn hairsim_recover(world: *mut hairsim_world) -> hairsim_error {
    let cell = world.cast::<Cell>();
    if let Err(e) = check_ptr(cell, Name::World) {
        return e.code;
    }
    // SAFETY: as in `take`: the first field of a valid, aligned cell, only accessed atomically.
    let state = unsafe { &*addr_of!((*cell).state) };
    match state.load(Ordering::Acquire) {
        // Nothing else can be running (the caller's promise): what held the world is gone.
        BUSY | IDLE => state.store(IDLE, Ordering::Release),
        _ => return hairsim_error::NotInitialised,
    }
    let check = |lease: &mut Lease<'_>| integrity::contents(lease.world, lease.checksums);
    // SAFETY: the caller's promise for `world`.
    code(unsafe { with_lease(world, Function::Recover, check) })
}

/// The firmware's panic hook (`hairsim_set_panic_hook`), as an address (0 for none).
static PANIC_HOOK: core::sync::atomic::AtomicUsize = core::sync::atomic::AtomicUsize::new(0);

/// Sets the function the library calls if it panics, and returns the one set before (NULL
/// for none). The library promises never to panic (it refuses what it cannot take, and checks
/// a world's bytes before it reads them); a panic is a bug. The hook gets the source file
/// (`file_len` bytes, not NUL-terminated) and line; it should log them and reset the device.
/// If it returns, the library stops in an endless loop, as it does without a hook. It may be
/// called from whatever context called the library, an interrupt included.
#[no_mangle]
pub extern "C" fn hairsim_set_panic_hook(hook: hairsim_panic_hook) -> hairsim_panic_hook {
    let new = hook.map_or(0, |f| f as usize);
    let old = PANIC_HOOK.swap(new, Ordering::AcqRel);
    panic_hook(old)
}

/// The hook an address in [`PANIC_HOOK`] stands for.
fn panic_hook(address: usize) -> hairsim_panic_hook {
    // SAFETY: every value ever stored in `PANIC_HOOK` is 0 or the address of a
    // `hairsim_panic_hook` function (`hairsim_set_panic_hook`); an `Option` of a function
    // pointer is a pointer-sized value with 0 for `None`, and function pointers are `usize`
    // wide on every target this library builds for.
    unsafe { core::mem::transmute::<usize, hairsim_panic_hook>(address) }
}

/// A test build's way to panic (feature `panic-test`): the hook's own test under QEMU.
#[cfg(feature = "panic-test")]
#[no_mangle]
pub extern "C" fn hairsim_test_panic() {
    panic!("hairsim_test_panic");
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
    if let Err(e) = check_ptr(out, Name::Out) {
        return e.code;
    }
    // SAFETY: the caller's promise for `shake`.
    let pose = unsafe { read(shake, Name::None) }.and_then(|s| convert::shake_pose(&s, t));
    match pose {
        // SAFETY: the caller's promise for `out`.
        Ok(p) => code(unsafe { write(out, p, Name::Out) }),
        Err(e) => e.code,
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
    if let Err(e) = check_ptr(out, Name::Out) {
        return e.code;
    }
    // SAFETY: the caller's promise for `circle`.
    let target = unsafe { read(circle, Name::None) }.and_then(|c| convert::circle_target(&c, t));
    match target {
        // SAFETY: the caller's promise for `out`.
        Ok(p) => code(unsafe { write(out, p, Name::Out) }),
        Err(e) => e.code,
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
    code(unsafe { write(out, capacity, Name::Out) })
}

/// What `code` means, in words: a static NUL-terminated string, never NULL (an unknown code
/// has a message too).
#[no_mangle]
pub extern "C" fn hairsim_error_message(code: i32) -> *const c_char {
    let message: &'static core::ffi::CStr = match code {
        0 => c"success",
        1 => c"a required pointer is NULL (hairsim_last_refusal names which)",
        2 => c"a pointer is not aligned for its type (hairsim_last_refusal names which)",
        3 => c"a buffer is shorter than it needs (the world's: HAIRSIM_WORLD_SIZE bytes)",
        4 => c"the world buffer was not initialised by hairsim_init",
        5 => c"another call on this world is running (re-entry)",
        6 => c"a value is NaN or infinite, or a result would be",
        7 => c"a value is out of its range (hairsim_last_refusal names the field)",
        8 => c"an effect is on that the solver cannot simulate",
        9 => c"a strand needs at least 3 nodes",
        10 => c"a strand has more nodes than HAIRSIM_NODES",
        11 => c"a polyline segment is shorter than 1e-6 m (hairsim_last_refusal names it)",
        12 => c"the polyline folds back on itself (a turning angle of 180 degrees)",
        13 => c"a material value is out of its range (hairsim_last_refusal names the field)",
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
        24 => c"a polyline segment is longer than 1 m (hairsim_last_refusal names it)",
        25 => {
            c"the world's bytes are not a world: a stray write or a reset mid-call (init it anew)"
        }
        _ => c"unknown error code",
    };
    message.as_ptr()
}

/// The backstop of a library that does not panic: with `panic = "abort"` there is nothing to
/// unwind, so it calls the firmware's hook, if any (`hairsim_set_panic_hook`), with where it
/// happened, and stops here. A std binary that links the rlib (feature `std`) uses std's.
#[cfg(all(not(test), not(feature = "std")))]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    if let Some(hook) = panic_hook(PANIC_HOOK.load(Ordering::Acquire)) {
        let (file, line) = info.location().map_or(("", 0), |l| (l.file(), l.line()));
        // SAFETY: a function the firmware set for this (`hairsim_set_panic_hook`), given a
        // pointer and length of a static string.
        unsafe { hook(file.as_ptr().cast(), file.len(), line) };
    }
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
