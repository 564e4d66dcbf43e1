//! Checks a world's raw bytes before they are read as Rust types (`hairsim_check`, and its
//! cheap part before every call): a byte that a stray write or a reset in the middle of a call
//! left in an enum or a `bool` would be undefined behaviour to read, a list longer than its
//! capacity or an index past its list a read out of bounds, and a loop bound out of its
//! range a hang. The core says where those bytes are (`World::LAYOUT`, and the public fields'
//! offsets); every other byte of a world is a float or an integer, any value of which is
//! one.
//!
//! The cheap part ([`structure`]), before any call reads the world: the enum and `bool`
//! bytes and the solver's scratch space's variant word, the lists' lengths, each strand's node count and schedule, each collider's shape and
//! flag, each grab's status, strand, node and coupling's tag, then the parameters' ranges
//! (bounding every loop).
//! The rest ([`contents`], `hairsim_check` only): every strand's state finite and its rest
//! data's checksum the one kept when it was added.

use core::mem::offset_of;
use core::ptr::addr_of;

use hairsim_core::world::{Colliders, Grabs, Strands};
use hairsim_core::{Collider, Grab, Strand};

/// Where a grab keeps which variant its `coupling` (an `Option<Coupling>`) is, from the
/// grab's start: rustc gives an `Option` of a type without a niche a tag in its first byte, 0
/// for `None` and 1 for `Some`. Rust does not promise that layout; the unit test
/// `tests::a_grab_s_coupling_tag_is_the_option_s_first_byte` checks it.
pub(crate) const COUPLING_TAG: usize = offset_of!(Grab, coupling);

use crate::refusal::{Name, Refused};
use crate::types::hairsim_error;
use crate::{Cell, SimWorld, NODES, STRANDS};

/// Rest-data checksums of the strands, kept beside the world when each is added.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Checksums<const S: usize = STRANDS>([u32; S]);

impl<const S: usize> Checksums<S> {
    /// Before any strand.
    pub(crate) const NONE: Checksums<S> = Checksums([0; S]);

    /// Keeps strand `index`'s.
    pub(crate) fn keep(&mut self, index: usize, checksum: u32) {
        if let Some(slot) = self.0.get_mut(index) {
            *slot = checksum;
        }
    }
}

/// `HAIRSIM_ERROR_CORRUPT` about `field` of element `index` (`None`: of the world as a whole).
fn corrupt(field: Name, index: Option<usize>) -> Refused {
    let r = Refused::from(hairsim_error::Corrupt)
        .argument(Name::World)
        .field(field);
    index.map_or(r, |i| r.at(i))
}

/// The byte at `offset` from `base`.
///
/// # Safety
/// `base + offset` must be valid for reads of a byte.
unsafe fn byte(base: *const u8, offset: usize) -> u8 {
    // SAFETY: the caller's promise.
    unsafe { base.add(offset).read() }
}

/// The length a `heapless::Vec` at `list` holds, read from its bytes. `len()` cannot be asked:
/// it makes a slice of that length first (the list derefs to one), which for a length past
/// the capacity is undefined behaviour before any comparison. heapless's `VecInner { phantom,
/// len, buffer }` keeps its buffer, which may be unsized, last, and its marker takes no room:
/// the length is the list's first `usize` (`LIST_LENGTH`; the tests check it for the three
/// lists).
///
/// # Safety
/// `list` must be valid for reads of a `usize` and aligned for one.
unsafe fn stored_length(list: *const u8) -> usize {
    // SAFETY: the caller's promise; any bytes are a `usize`.
    unsafe { list.add(LIST_LENGTH).cast::<usize>().read() }
}

/// Where a `heapless::Vec` keeps its length: its first bytes (see [`stored_length`]).
pub(crate) const LIST_LENGTH: usize = 0;

/// `Ok` if `ok`, else [`corrupt`].
fn expect(ok: bool, field: Name, index: Option<usize>) -> Result<(), Refused> {
    if ok {
        Ok(())
    } else {
        Err(corrupt(field, index))
    }
}

/// The cheap part: everything whose bytes must be right before the world is read as a
/// `World`, then the parameters' ranges.
///
/// # Safety
/// `cell` must be valid for reads of a `Cell`, and nothing may write it meanwhile.
pub(crate) unsafe fn structure(cell: *const Cell) -> Result<(), Refused> {
    // SAFETY: the caller's promise; the world lies inside the cell.
    let base = unsafe { addr_of!((*cell).world) }.cast::<u8>();
    let layout = SimWorld::LAYOUT;
    for (offset, field) in [
        (layout.solver, Name::Solver),
        (layout.mode, Name::Mode),
        (layout.twist, Name::RodTwist),
        (layout.bad_target, Name::BadTarget),
    ] {
        // SAFETY: each offset is a field's inside the world.
        expect(unsafe { byte(base, offset) } < 2, field, None)?;
    }
    // SAFETY: the scratch space's variant is a `u32` at its offset inside the world, aligned
    // (the enum is `repr(u32)`); any bytes are a `u32`.
    let scratch = unsafe { base.add(layout.scratch).cast::<u32>().read() };
    expect(scratch < 3, Name::Scratch, None)?;
    // SAFETY: the lists lie at the layout's offsets inside the world, and a `heapless::Vec`'s
    // every byte pattern is a value (its storage is `MaybeUninit`): a reference to one is
    // sound whatever its bytes. Only its capacity and its buffer's address are asked of it;
    // its length is read from its bytes below.
    let (strands, colliders, grabs) = unsafe {
        (
            &*base.add(layout.strands).cast::<Strands<STRANDS, NODES>>(),
            &*base.add(layout.colliders).cast::<Colliders>(),
            &*base.add(layout.grabs).cast::<Grabs>(),
        )
    };
    // SAFETY: each list lies at its offset inside the world, aligned for its `usize` length.
    let (strand_count, collider_count, grab_count) = unsafe {
        (
            stored_length(base.add(layout.strands)),
            stored_length(base.add(layout.colliders)),
            stored_length(base.add(layout.grabs)),
        )
    };
    expect(strand_count <= strands.capacity(), Name::Strands, None)?;
    expect(
        collider_count <= colliders.capacity(),
        Name::Colliders,
        None,
    )?;
    expect(grab_count <= grabs.capacity(), Name::Grabs, None)?;
    let mut nodes = [0usize; STRANDS];
    for (i, count) in nodes.iter_mut().enumerate().take(strand_count) {
        // SAFETY: `i` is below the length, which is at most the capacity: inside the buffer.
        let strand = unsafe { strands.as_ptr().add(i) }.cast::<u8>();
        // SAFETY: the field lies inside the strand; any bytes are a `usize`.
        *count = unsafe {
            strand
                .add(offset_of!(Strand<NODES>, rest.nodes))
                .cast::<usize>()
                .read()
        };
        expect((3..=NODES).contains(count), Name::Nodes, Some(i))?;
        // SAFETY: the field lies inside the strand.
        let schedule =
            unsafe { byte(strand, offset_of!(Strand<NODES>, schedule.implicit_bending)) };
        expect(schedule < 2, Name::Schedule, Some(i))?;
    }
    for i in 0..collider_count {
        // SAFETY: `i` is below the length, at most the capacity.
        let collider = unsafe { colliders.as_ptr().add(i) }.cast::<u8>();
        // SAFETY: the fields lie inside the collider; a `Shape`'s variant is its first byte.
        let (shape, attached) = unsafe {
            (
                byte(collider, offset_of!(Collider, shape)),
                byte(collider, offset_of!(Collider, attached_to_head)),
            )
        };
        expect(shape < 3, Name::Shape, Some(i))?;
        expect(attached < 2, Name::AttachedToHead, Some(i))?;
    }
    for i in 0..grab_count {
        // SAFETY: `i` is below the length, at most the capacity.
        let grab = unsafe { grabs.as_ptr().add(i) }.cast::<u8>();
        // SAFETY: the fields lie inside the grab; any bytes are a `u32`.
        let (status, strand, node, coupling) = unsafe {
            (
                byte(grab, offset_of!(Grab, status)),
                grab.add(offset_of!(Grab, strand)).cast::<u32>().read() as usize,
                grab.add(offset_of!(Grab, node)).cast::<u32>().read() as usize,
                byte(grab, COUPLING_TAG),
            )
        };
        expect(status < 3, Name::Status, Some(i))?;
        expect(coupling < 2, Name::Coupling, Some(i))?;
        expect(strand < strand_count, Name::Strand, Some(i))?;
        expect((2..nodes[strand]).contains(&node), Name::Node, Some(i))?;
    }
    // SAFETY: every byte a `World` reads as an enum, a `bool` or a length is right (above):
    // the world is a `World`.
    let world = unsafe { &*addr_of!((*cell).world) };
    values(world)
}

/// The values the structure holds that bound loops or are refused when set: the parameters'
/// ranges, each collider's geometry and each grab's targets, limit and coupling.
fn values(world: &SimWorld) -> Result<(), Refused> {
    use hairsim_core::math::is_finite;
    expect(world.params().validate().is_ok(), Name::Params, None)?;
    for (i, c) in world.colliders().iter().enumerate() {
        expect(c.shape.check().is_ok(), Name::Shape, Some(i))?;
    }
    for (i, g) in world.grabs().iter().enumerate() {
        // A force limit above 0 (infinite: it never slips); NaN is not.
        let ok = is_finite(g.target) && is_finite(g.previous_target) && g.force_limit > 0.0;
        expect(ok, Name::Grab, Some(i))?;
        let coupling_ok = g.coupling.is_none_or(|c| c.is_valid());
        expect(coupling_ok, Name::Coupling, Some(i))?;
    }
    Ok(())
}

/// The rest (after [`structure`]): every strand's state finite, and its rest data's checksum
/// the one kept when it was added.
pub(crate) fn contents(world: &SimWorld, checksums: &Checksums) -> Result<(), Refused> {
    for (i, (s, &kept)) in world.strands().iter().zip(&checksums.0).enumerate() {
        expect(s.is_finite(), Name::State, Some(i))?;
        expect(s.rest.checksum() == kept, Name::Rest, Some(i))?;
    }
    Ok(())
}
