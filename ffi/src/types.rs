//! The C-visible types: plain `#[repr(C)]` structs of integers, floats and pointers (every bit
//! pattern of every field is a valid value, so reading one a C caller filled is never undefined
//! behaviour), the enums that name the values of their integer fields, and the constants.
//!
//! No field is a Rust `enum` or `bool`: a C caller could store any integer there. Each such
//! field is a `u32` checked on the way in.
#![allow(non_camel_case_types)]

/// The library's major version. While it is 0, `HAIRSIM_VERSION_MINOR` changes whenever the C
/// ABI does (a function, struct, constant or code changes or goes), and a header works only
/// with a library of the same major and minor version; from 1 on, the major version changes
/// when the ABI breaks and the minor version when it only grows.
pub const HAIRSIM_VERSION_MAJOR: u32 = 0;
/// The library's minor version (see `HAIRSIM_VERSION_MAJOR`).
pub const HAIRSIM_VERSION_MINOR: u32 = 5;
/// The library's patch version: changes that no header sees (fixes, speed).
pub const HAIRSIM_VERSION_PATCH: u32 = 0;
/// The three parts in one word, `0x00MMmmpp`, as `hairsim_version()` returns it; the header's
/// is what the `hairsim_init` macro passes to `hairsim_init_versioned`.
pub const HAIRSIM_VERSION: u32 =
    (HAIRSIM_VERSION_MAJOR << 16) | (HAIRSIM_VERSION_MINOR << 8) | HAIRSIM_VERSION_PATCH;

/// `text` as a number: the parts of Cargo's package version, at compile time.
const fn parse_u32(text: &str) -> u32 {
    let bytes = text.as_bytes();
    let mut value = 0;
    let mut i = 0;
    while i < bytes.len() {
        assert!(bytes[i].is_ascii_digit(), "a version part is a number");
        value = value * 10 + (bytes[i] - b'0') as u32;
        i += 1;
    }
    value
}
// The header's version is the crate's (`ffi/Cargo.toml`): a mismatch fails the build. Each
// part takes one byte of `HAIRSIM_VERSION`.
const _: () = assert!(HAIRSIM_VERSION_MAJOR == parse_u32(env!("CARGO_PKG_VERSION_MAJOR")));
const _: () = assert!(HAIRSIM_VERSION_MINOR == parse_u32(env!("CARGO_PKG_VERSION_MINOR")));
const _: () = assert!(HAIRSIM_VERSION_PATCH == parse_u32(env!("CARGO_PKG_VERSION_PATCH")));
const _: () = assert!(
    HAIRSIM_VERSION_MAJOR < 256 && HAIRSIM_VERSION_MINOR < 256 && HAIRSIM_VERSION_PATCH < 256
);

/// Most colliders a world holds.
pub const HAIRSIM_MAX_COLLIDERS: usize = 8;
/// Most grabs a world holds.
pub const HAIRSIM_MAX_GRABS: usize = 4;
/// Most rolled-back strands a step report names (the count is always exact).
pub const HAIRSIM_NAMED_STRANDS: usize = 8;
/// Number of stages a step report counts (`hairsim_step_report::stage_runs`).
pub const HAIRSIM_STAGE_COUNT: usize = 12;

// The header's constants are the core's (a mismatch fails the build). `MAX_GRABS` is checked
// by the type of `report::grab_forces` in `convert::report_to_c`.
const _: () = assert!(HAIRSIM_MAX_COLLIDERS == hairsim_core::collide::MAX_COLLIDERS);
const _: () = assert!(HAIRSIM_NAMED_STRANDS == hairsim_core::report::NAMED_STRANDS);
const _: () = assert!(HAIRSIM_STAGE_COUNT == hairsim_core::report::STAGE_COUNT);

/// Effect bits of `hairsim_params::effects`.
pub const HAIRSIM_EFFECT_GRAVITY: u32 = 1 << 0;
/// Air drag per node.
pub const HAIRSIM_EFFECT_DRAG: u32 = 1 << 1;
/// Bending elasticity (rod solver only).
pub const HAIRSIM_EFFECT_BENDING: u32 = 1 << 2;
/// Twisting elasticity (rod solver only).
pub const HAIRSIM_EFFECT_TWIST: u32 = 1 << 3;
/// Segments keep their rest length.
pub const HAIRSIM_EFFECT_INEXTENSIBILITY: u32 = 1 << 4;
/// Nodes are kept outside the colliders.
pub const HAIRSIM_EFFECT_COLLISIONS: u32 = 1 << 5;
/// Global and local shape preservation (DFTL solver only).
pub const HAIRSIM_EFFECT_SHAPE: u32 = 1 << 6;
/// Wind as an external acceleration.
pub const HAIRSIM_EFFECT_WIND: u32 = 1 << 7;
/// Nodes held by grabs, prescribed or through a virtual coupling (both solvers).
pub const HAIRSIM_EFFECT_GRABS: u32 = 1 << 8;
/// Hair-hair interaction: accelerations the caller computes and passes to `hairsim_step`.
pub const HAIRSIM_EFFECT_HAIR_HAIR: u32 = 1 << 9;

/// Flag bits of `hairsim_step_report::flags`: an iteration cap was hit above tolerance.
pub const HAIRSIM_FLAG_CAP_HIT: u32 = 1 << 0;
/// A strand turned non-finite and was rolled back to its last good state.
pub const HAIRSIM_FLAG_ROLLED_BACK: u32 = 1 << 1;
/// A grab exceeded its force limit (or its target was out of reach) and slipped.
pub const HAIRSIM_FLAG_GRAB_SLIPPED: u32 = 1 << 2;
/// The core ignored a non-finite input (the C functions refuse those before it sees them).
pub const HAIRSIM_FLAG_BAD_INPUT: u32 = 1 << 3;
/// The projection met dependent constraints and solved without some rows.
pub const HAIRSIM_FLAG_SINGULAR: u32 = 1 << 4;
/// A node was inside more colliders than it has collision rows for.
pub const HAIRSIM_FLAG_CONTACTS_TRUNCATED: u32 = 1 << 5;
/// A segment ended the step more than 1 % longer or shorter than its rest length
/// (`max_stretch` or `max_contact_stretch` above 0.01): inextensibility is off, or contacts
/// or grabs pull harder than the constraints hold.
pub const HAIRSIM_FLAG_STRETCHED: u32 = 1 << 6;
/// The world holds colliders but `HAIRSIM_EFFECT_COLLISIONS` is off: they did nothing.
pub const HAIRSIM_FLAG_COLLIDERS_INACTIVE: u32 = 1 << 7;
/// The world holds grabs that hold their node but `HAIRSIM_EFFECT_GRABS` is off: they did
/// nothing.
pub const HAIRSIM_FLAG_GRABS_INACTIVE: u32 = 1 << 8;

/// What every function returns: `HAIRSIM_ERROR_OK` (0) or why it refused. A refused call
/// changes nothing. `hairsim_error_message(code)` says it in words.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum hairsim_error {
    /// Success.
    Ok = 0,
    /// A required pointer is NULL.
    NullPointer = 1,
    /// A pointer is not aligned for its type (the world: `HAIRSIM_WORLD_ALIGN`).
    Misaligned = 2,
    /// A buffer is shorter than needed (the world: `HAIRSIM_WORLD_SIZE`; positions: the
    /// strand's node count).
    BufferTooSmall = 3,
    /// The world buffer was not initialised by `hairsim_init` (its magic word is wrong).
    NotInitialised = 4,
    /// Another call on this world is running (re-entry from an interrupt or another thread).
    Busy = 5,
    /// A float argument is NaN or infinite, or a result would be.
    NotFinite = 6,
    /// A value is outside its range: a parameter, an unknown enum value or flag bit, an index.
    OutOfRange = 7,
    /// An effect is on that the chosen solver cannot simulate.
    UnsupportedEffect = 8,
    /// A polyline has fewer than 3 points.
    TooFewNodes = 9,
    /// A polyline has more points than `HAIRSIM_NODES`.
    TooManyNodes = 10,
    /// A polyline segment is shorter than 1 micrometre (`hairsim_last_refusal` gives its
    /// index).
    DegenerateSegment = 11,
    /// A polyline folds back on itself (a turning angle of 180 degrees).
    FoldedSegment = 12,
    /// A material value is out of its range.
    InvalidMaterial = 13,
    /// The world already holds `HAIRSIM_STRANDS` strands.
    StrandsFull = 14,
    /// The world already holds `HAIRSIM_MAX_COLLIDERS` colliders.
    CollidersFull = 15,
    /// The world already holds `HAIRSIM_MAX_GRABS` grabs.
    GrabsFull = 16,
    /// A collider's geometry is out of range (radius, unit plane normal).
    InvalidCollider = 17,
    /// A grab names no strand, a node outside 2 to the strand's last, a force limit <= 0, or
    /// a coupling out of range.
    InvalidGrab = 18,
    /// An argument's buffer overlaps the world's.
    Overlap = 19,
    /// `hairsim_init`: the header's version is not one this library works with (another
    /// `HAIRSIM_VERSION_MAJOR`, or while it is 0, another `HAIRSIM_VERSION_MINOR`).
    VersionMismatch = 20,
    /// `hairsim_init`: the header's `HAIRSIM_STRANDS` is not the library's.
    StrandsMismatch = 21,
    /// `hairsim_init`: the header's `HAIRSIM_NODES` is not the library's.
    NodesMismatch = 22,
    /// A collider was added while `HAIRSIM_EFFECT_COLLISIONS` is off, or a grab while
    /// `HAIRSIM_EFFECT_GRABS` is off: it would do nothing. Turn the effect on first.
    EffectOff = 23,
    /// A polyline segment is longer than 1 m.
    LongSegment = 24,
    /// The world's bytes are not a world the library wrote: a stray write into the buffer, or
    /// a reset in the middle of a call (`hairsim_check`, `hairsim_recover`;
    /// `hairsim_last_refusal` names the part, argument `world`). Every call but
    /// `hairsim_init`, `hairsim_recover` and `hairsim_last_refusal` refuses the world until
    /// `hairsim_init` makes it anew.
    Corrupt = 25,
}

/// The model (`hairsim_params::solver`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum hairsim_solver {
    /// Discrete Kirchhoff rods (Kmoch et al. 2009).
    Rod = 0,
    /// Dynamic Follow-The-Leader with shape (Sanchez-Banderas et al. 2015).
    Dftl = 1,
}

/// How iterative stages stop (`hairsim_params::mode`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum hairsim_mode {
    /// Stop early at the tolerance.
    Converge = 0,
    /// Always run the full iteration caps: a cost that does not depend on the state.
    FixedCost = 1,
}

/// The rod's quasistatic twist (`hairsim_params::rod_twist`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum hairsim_twist {
    /// Material frames follow the curvature binormals (Kmoch 2009, Sec. 6.2).
    HairOptimised = 0,
    /// Newton's method on the twist Hessian.
    Newton = 1,
}

/// A collider's geometry (`hairsim_collider::shape`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum hairsim_shape {
    /// A ball: centre `a`, `radius`.
    Sphere = 0,
    /// The points within `radius` of the segment `a`-`b`.
    Capsule = 1,
    /// The half-space behind a plane through `a` with unit outward normal `b`.
    Plane = 2,
}

/// A grab's state (`hairsim_world_info::grab_status`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum hairsim_grab_status {
    /// No grab in this slot.
    None = 0,
    /// The node follows the target.
    Held = 1,
    /// The force limit was exceeded: the node is free for good.
    Slipped = 2,
    /// Released by `hairsim_release_grab`.
    Released = 3,
}

/// Where a world lives: a caller-provided buffer of `HAIRSIM_WORLD_SIZE` bytes aligned to
/// `HAIRSIM_WORLD_ALIGN`, cast to `hairsim_world *`. Opaque to C.
pub struct hairsim_world {
    _opaque: [u8; 0],
}

/// A 3-vector: m, m/s^2 or N.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_vec3 {
    /// x.
    pub x: f32,
    /// y.
    pub y: f32,
    /// z.
    pub z: f32,
}

/// A unit quaternion.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_quat {
    /// x.
    pub x: f32,
    /// y.
    pub y: f32,
    /// z.
    pub z: f32,
    /// w (1 for the identity).
    pub w: f32,
}

/// A rigid pose: rotation about the head's origin, then translation.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_pose {
    /// Translation, m.
    pub position: hairsim_vec3,
    /// Orientation, a unit quaternion (|q|^2 within 1e-3 of 1).
    pub rotation: hairsim_quat,
}

/// A head shake: rotation about the unit `axis` through `centre` by
/// `amplitude * sin(2 pi frequency t)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_shake {
    /// Unit rotation axis.
    pub axis: hairsim_vec3,
    /// A point on the axis, m.
    pub centre: hairsim_vec3,
    /// Amplitude, rad.
    pub amplitude: f32,
    /// Frequency, Hz.
    pub frequency: f32,
}

/// A point going round a horizontal circle (the x-z plane) at `frequency` Hz, at `start` at
/// t = 0: `start + (radius (cos w t - 1), 0, radius sin w t)`, w = 2 pi frequency.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_circle {
    /// Where the point is at t = 0, m (the centre is `start - (radius, 0, 0)`).
    pub start: hairsim_vec3,
    /// Radius, m.
    pub radius: f32,
    /// Turns per second, Hz.
    pub frequency: f32,
}

/// A round hair fibre's material (SI units). Each field has a range (outside it:
/// `HAIRSIM_ERROR_INVALID_MATERIAL`, the field named by `hairsim_last_refusal`); both solvers'
/// presets hold at every corner of the ranges (docs/embedding.md).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_material {
    /// Young's modulus E, Pa: 1e7 to 1e13 (human hair 3.5e9).
    pub youngs_modulus: f32,
    /// Shear modulus G, Pa: 1e7 to 1e13 (human hair 1.3e9).
    pub shear_modulus: f32,
    /// Fibre radius, m: 1e-5 to 5e-4 (human hair 4e-5).
    pub radius: f32,
    /// Density, kg/m^3: 500 to 3000 (human hair 1300).
    pub density: f32,
    /// Multiplier on bending about the minor axis (an elliptic section), 1 to 10.
    pub minor_axis_penalty: f32,
}

/// A world's parameters and effects. Start from `hairsim_params_preset` and change fields.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_params {
    /// A `hairsim_solver`.
    pub solver: u32,
    /// Time step, s (1e-5 to 0.02; at most 0.004 with the rod solver).
    pub dt: f32,
    /// `HAIRSIM_EFFECT_*` bits.
    pub effects: u32,
    /// A `hairsim_mode`.
    pub mode: u32,
    /// Gravitational acceleration, m/s^2.
    pub gravity: hairsim_vec3,
    /// Air drag per node, kg/s (>= 0).
    pub drag: f32,
    /// Rod: projection iteration cap, 1 to 1000.
    pub rod_projection_iterations: u32,
    /// Rod: projection tolerance (> 0).
    pub rod_projection_tolerance: f32,
    /// Rod: a `hairsim_twist`.
    pub rod_twist: u32,
    /// Rod: Newton twist iteration cap, 1 to 100.
    pub rod_newton_iterations: u32,
    /// Rod: Newton twist tolerance, rad (> 0).
    pub rod_newton_tolerance: f32,
    /// DFTL: velocity feedback s_d, 0 to 1.
    pub dftl_damping: f32,
    /// DFTL: global shape fraction s_g per step at `dftl_reference_dt`, 0 to 1.
    pub dftl_global_shape: f32,
    /// DFTL: local shape fraction s_l per step at `dftl_reference_dt`, 0 to 1.
    pub dftl_local_shape: f32,
    /// DFTL: the step s_g and s_l are given at, s (> 0).
    pub dftl_reference_dt: f32,
    /// DFTL: how much s_g fades from root to tip, 0 to 1.
    pub dftl_global_shape_fade: f32,
    /// DFTL: how much s_l fades from root to tip, 0 to 1.
    pub dftl_local_shape_fade: f32,
    /// Wind: unit direction.
    pub wind_direction: hairsim_vec3,
    /// Wind: mean acceleration, m/s^2 (>= 0).
    pub wind_strength: f32,
    /// Wind: gust amplitude as a fraction of the strength, 0 to 10.
    pub wind_gust: f32,
    /// Wind: gust frequency, 0 to 1000 Hz.
    pub wind_gust_frequency: f32,
    /// Wind: seed of the gust noise.
    pub wind_seed: u32,
}

/// A collider. Given in the head's frame if `attached_to_head` is 1, else in the world's.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_collider {
    /// A `hairsim_shape`.
    pub shape: u32,
    /// 1: moves with the head; 0: fixed in the world.
    pub attached_to_head: u32,
    /// Sphere: centre. Capsule: one end. Plane: a point on it. (m)
    pub a: hairsim_vec3,
    /// Capsule: the other end, m. Plane: the unit outward normal. Sphere: unused.
    pub b: hairsim_vec3,
    /// Sphere and capsule radius, 1e-5 to 1e4 m. Plane: unused.
    pub radius: f32,
}

/// A node held at a target the caller moves each step.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_grab {
    /// Index of the strand.
    pub strand: u32,
    /// Index of the node, from 2 (nodes 0 and 1 follow the head) to the strand's last.
    pub node: u32,
    /// Where the node is held, m (world frame).
    pub target: hairsim_vec3,
    /// Largest force the grab transmits before it slips, N (> 0).
    pub force_limit: f32,
    /// A virtual coupling's spring, N/m: 0 (with `damping` 0) holds the node at the target
    /// (it slips when the target leaves the strand's reach); from 1e-3 to 1e5, a spring and a
    /// damper pull the node toward the target (it slips only past `force_limit`).
    pub stiffness: f32,
    /// The coupling's damper, N·s/m, from 0 to 1e3 (0 without a coupling).
    pub damping: f32,
}

/// What one step takes.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct hairsim_step_input {
    /// The head's pose at the end of this step.
    pub head: hairsim_pose,
    /// New targets of grabs 0 to `grab_target_count - 1` (NULL if the count is 0).
    pub grab_targets: *const hairsim_vec3,
    /// At most the number of grabs added.
    pub grab_target_count: usize,
    /// Optional per-node accelerations, m/s^2: node i of strand s at `s * HAIRSIM_NODES + i`
    /// (NULL if the count is 0).
    pub accelerations: *const hairsim_vec3,
    /// At most `HAIRSIM_STRANDS * HAIRSIM_NODES`; strands past the end get none.
    pub acceleration_count: usize,
}

/// What one step did.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct hairsim_step_report {
    /// `HAIRSIM_FLAG_*` bits.
    pub flags: u32,
    /// Most projection (or Newton) iterations any strand used.
    pub iterations_max: u32,
    /// Projection iterations summed over strands.
    pub iterations_total: u32,
    /// Strands whose projection hit its iteration cap above tolerance.
    pub cap_hits: u32,
    /// Constraint rows the projection dropped at a singular pivot.
    pub dropped_rows: u32,
    /// Nodes pushed out of a collider.
    pub contacts: u32,
    /// Strands rolled back to their last good state.
    pub rolled_back: u32,
    /// How many of `rolled_back_strands` are set (at most `HAIRSIM_NAMED_STRANDS`).
    pub rolled_back_strand_count: u32,
    /// The first rolled-back strands, by index.
    pub rolled_back_strands: [u32; HAIRSIM_NAMED_STRANDS],
    /// Grabs that slipped this step: bit g for grab g.
    pub grabs_slipped: u32,
    /// Largest final projection residual over strands.
    pub residual: f32,
    /// Largest relative stretch of a segment without contact.
    pub max_stretch: f32,
    /// Largest relative stretch of a segment with a node pushed out of a collider.
    pub max_contact_stretch: f32,
    /// Deepest node inside a collider after the step, m.
    pub max_penetration: f32,
    /// Force each grab's device feels, N (zero for unused slots): a coupled grab's is its
    /// coupling's.
    pub grab_forces: [hairsim_vec3; HAIRSIM_MAX_GRABS],
    /// Force the head feels from the strands' held roots (nodes 0 and 1), N, summed: with the
    /// grabs' forces, the hair's weight at rest (the colliders' are in `collider_forces`).
    pub head_force: hairsim_vec3,
    /// Total contact force the hair exerts on each collider, N.
    pub collider_forces: [hairsim_vec3; HAIRSIM_MAX_COLLIDERS],
    /// How many strands each stage ran on, in the core's stage order.
    pub stage_runs: [u32; HAIRSIM_STAGE_COUNT],
}

/// What a world holds.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_world_info {
    /// Steps taken.
    pub steps: u64,
    /// Strands added.
    pub strands: u32,
    /// Colliders added.
    pub colliders: u32,
    /// Grabs added.
    pub grabs: u32,
    /// A `hairsim_grab_status` per grab slot.
    pub grab_status: [u32; HAIRSIM_MAX_GRABS],
}

/// What the last call on a world that reached it refused, or that it succeeded
/// (`hairsim_last_refusal`). The strings are static and never NULL ("" for none).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct hairsim_refusal {
    /// The `hairsim_error` the call returned (`HAIRSIM_ERROR_OK` when it succeeded).
    pub code: i32,
    /// The function, e.g. "hairsim_add_strand" ("" before any call).
    pub function: *const core::ffi::c_char,
    /// The argument refused, as the header names it, e.g. "material" ("" for none).
    pub argument: *const core::ffi::c_char,
    /// The field of that argument, as the header names it, e.g. "radius" ("" for the whole
    /// argument).
    pub field: *const core::ffi::c_char,
    /// The node, segment, strand or array element concerned, or `UINT32_MAX` for none: the
    /// node of a non-finite point, the segment too short or too long, the node a polyline
    /// folds at, the grab target or acceleration that is not finite.
    pub index: u32,
}

/// A function the library calls if it panics (`hairsim_set_panic_hook`), or NULL for none: it
/// gets the source file (`file_len` bytes, not NUL-terminated) and line.
pub type hairsim_panic_hook =
    Option<unsafe extern "C" fn(file: *const core::ffi::c_char, file_len: usize, line: u32)>;

/// The library's build-time capacities and world layout, to check against the header.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct hairsim_capacity {
    /// Strand capacity (`HAIRSIM_STRANDS`).
    pub strands: u32,
    /// Node capacity per strand (`HAIRSIM_NODES`).
    pub nodes: u32,
    /// `HAIRSIM_MAX_COLLIDERS`.
    pub colliders: u32,
    /// `HAIRSIM_MAX_GRABS`.
    pub grabs: u32,
    /// Bytes a world needs on this target (at most `HAIRSIM_WORLD_SIZE`).
    pub world_size: usize,
    /// Alignment a world needs on this target (at most `HAIRSIM_WORLD_ALIGN`).
    pub world_align: usize,
}
