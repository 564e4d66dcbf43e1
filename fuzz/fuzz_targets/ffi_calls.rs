//! The C ABI (`hairsim-ffi`) called in any order, before initialisation included, with
//! arbitrary arguments: NULL, misaligned and overlapping pointers, short buffers, any float
//! and integer. Every pointer is valid for its stated length (each buffer is allocated to
//! exactly that length, so the sanitiser sees any access past it). Checks: no panic, every
//! result a known code, a refused call changes nothing, a world is "not initialised" exactly
//! until `hairsim_init` succeeds on it, and nothing single-threaded is ever "busy".
#![no_main]

use std::ffi::CStr;
use std::mem::{align_of, size_of, MaybeUninit};
use std::ptr;

use arbitrary::Arbitrary;
use hairsim_ffi::*;
use libfuzzer_sys::fuzz_target;

/// Which world buffer a call gets.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum WorldArg {
    Null,
    /// 4 bytes into world 0's buffer: misaligned for its 8-byte alignment.
    Misaligned,
    /// World 0 or 1.
    World(bool),
}

/// An output pointer.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Out {
    Null,
    Good,
    Misaligned,
    /// Inside the buffer of the world the call is given (refused as an overlap).
    InWorld(u16),
}

/// A length for `hairsim_init`.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Len {
    Exact,
    Zero,
    Short(u16),
}

/// A float: often an ordinary value, sometimes any bit pattern.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum F {
    Small(i8),
    Bits(u32),
}

impl F {
    fn get(self) -> f32 {
        match self {
            F::Small(v) => f32::from(v) * 0.01,
            F::Bits(b) => f32::from_bits(b),
        }
    }
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Base {
    Default,
    /// Rod, every rod effect, fixed cost: the firmware scene's choice.
    Rod,
    Dftl,
}

/// Parameters: a base, then fields overwritten with arbitrary bits.
#[derive(Arbitrary, Debug)]
struct ParamsArg {
    base: Base,
    overrides: Vec<(u8, u32)>,
}

#[derive(Arbitrary, Debug)]
enum Points {
    /// `count` points along `step`, curving by `bend` i² in x.
    Line {
        count: u8,
        step: [F; 3],
        bend: F,
    },
    Raw(Vec<[F; 3]>),
    /// More points claimed than `HAIRSIM_NODES`, with a buffer of only 4: refused unread.
    OverCount(usize),
}

#[derive(Arbitrary, Debug)]
enum MaterialArg {
    HumanHair,
    Raw([F; 5]),
    Null,
}

#[derive(Arbitrary, Debug)]
enum Head {
    Identity,
    Shake(F),
    Raw([F; 7]),
}

#[derive(Arbitrary, Debug)]
enum Call {
    Init(WorldArg, Len),
    ParamsDefault(Out),
    HumanHair(Out),
    Configure(WorldArg, Option<ParamsArg>),
    AddStrand(WorldArg, Points, MaterialArg, Out),
    AddCollider(WorldArg, Option<(u32, u32, [F; 7])>, Out),
    AddGrab(WorldArg, Option<(u32, u32, [F; 6])>, Out),
    ReleaseGrab(WorldArg, u32),
    Step {
        world: WorldArg,
        head: Head,
        targets: Option<Vec<[F; 3]>>,
        accelerations: Option<Vec<[F; 3]>>,
        accelerations_in_world: bool,
        report: Out,
    },
    Positions(WorldArg, u32, u8, Out, Out),
    StateHash(WorldArg, Out),
    Info(WorldArg, Out),
    ShakePose(Option<[F; 8]>, F, Out),
    CircleTarget(Option<[F; 5]>, F, Out),
    Capacity(Out),
    Message(i32),
    LastRefusal(WorldArg, Out),
    Check(WorldArg),
    Recover(WorldArg),
}

/// Two zeroed world buffers, as C `static`s are.
struct Worlds {
    buffers: [Vec<u64>; 2],
    size: usize,
    initialised: [bool; 2],
}

impl Worlds {
    fn new() -> Worlds {
        let mut capacity = MaybeUninit::<hairsim_capacity>::uninit();
        let code = unsafe { hairsim_get_capacity(capacity.as_mut_ptr()) };
        assert_eq!(code, hairsim_error::Ok);
        let size = unsafe { capacity.assume_init() }.world_size;
        let words = size.div_ceil(8);
        Worlds {
            buffers: [vec![0; words], vec![0; words]],
            size,
            initialised: [false; 2],
        }
    }

    fn ptr(&mut self, arg: WorldArg) -> *mut hairsim_world {
        match arg {
            WorldArg::Null => ptr::null_mut(),
            WorldArg::Misaligned => {
                unsafe { self.buffers[0].as_mut_ptr().cast::<u8>().add(4) }.cast()
            }
            WorldArg::World(w) => self.buffers[usize::from(w)].as_mut_ptr().cast(),
        }
    }

    /// The world's hash and info, if it is one: what a refused call must leave unchanged.
    fn snapshot(&mut self, arg: WorldArg) -> Option<(u64, hairsim_world_info)> {
        let WorldArg::World(w) = arg else { return None };
        if !self.initialised[usize::from(w)] {
            return None;
        }
        let world = self.ptr(arg);
        let mut hash = 0u64;
        let mut info = MaybeUninit::<hairsim_world_info>::uninit();
        unsafe {
            assert_eq!(hairsim_state_hash(world, &mut hash), hairsim_error::Ok);
            assert_eq!(
                hairsim_get_info(world, info.as_mut_ptr()),
                hairsim_error::Ok
            );
            Some((hash, info.assume_init()))
        }
    }
}

/// Storage for one output of type `T`, pointed at as `Out` says.
struct OutBuf {
    words: Vec<u64>,
}

impl OutBuf {
    fn new<T>() -> OutBuf {
        // One word more than `T` needs, for the misaligned case.
        OutBuf {
            words: vec![0; size_of::<T>().div_ceil(8) + 1],
        }
    }

    /// `world` is the call's world argument: `None` for a call without one, where `InWorld`
    /// is `Good` (a write into a world's buffer would corrupt it, which the C contract
    /// forbids; a call on a world refuses such a pointer before it writes anything).
    fn ptr<T>(&mut self, out: Out, worlds: &mut Worlds, world: Option<WorldArg>) -> *mut T {
        assert!(align_of::<T>() <= 8);
        match (out, world) {
            (Out::Null, _) => ptr::null_mut(),
            (Out::Good, _) | (Out::InWorld(_), None) => self.words.as_mut_ptr().cast(),
            (Out::Misaligned, _) => unsafe { self.words.as_mut_ptr().cast::<u8>().add(1) }.cast(),
            (Out::InWorld(offset), Some(world)) => {
                let base = match world {
                    WorldArg::World(w) => worlds.buffers[usize::from(w)].as_mut_ptr(),
                    _ => worlds.buffers[0].as_mut_ptr(),
                };
                let room = worlds.size.saturating_sub(size_of::<T>());
                let offset = (usize::from(offset) % (room + 1)) / align_of::<T>() * align_of::<T>();
                unsafe { base.cast::<u8>().add(offset) }.cast()
            }
        }
    }
}

fn params(arg: &ParamsArg) -> hairsim_params {
    let mut p = MaybeUninit::<hairsim_params>::uninit();
    assert_eq!(
        unsafe { hairsim_params_default(p.as_mut_ptr()) },
        hairsim_error::Ok
    );
    let mut p = unsafe { p.assume_init() };
    match arg.base {
        Base::Default => {}
        Base::Rod => {
            p.effects = HAIRSIM_EFFECT_GRAVITY
                | HAIRSIM_EFFECT_DRAG
                | HAIRSIM_EFFECT_BENDING
                | HAIRSIM_EFFECT_TWIST
                | HAIRSIM_EFFECT_INEXTENSIBILITY
                | HAIRSIM_EFFECT_COLLISIONS
                | HAIRSIM_EFFECT_GRABS;
            p.mode = hairsim_mode::FixedCost as u32;
            p.rod_twist = hairsim_twist::Newton as u32;
        }
        Base::Dftl => {
            p.solver = hairsim_solver::Dftl as u32;
            p.effects = HAIRSIM_EFFECT_GRAVITY
                | HAIRSIM_EFFECT_INEXTENSIBILITY
                | HAIRSIM_EFFECT_COLLISIONS
                | HAIRSIM_EFFECT_SHAPE
                | HAIRSIM_EFFECT_WIND;
        }
    }
    // The struct is 26 four-byte fields: overwrite field `k` with `bits`.
    const FIELDS: usize = size_of::<hairsim_params>() / 4;
    let mut words: [u32; FIELDS] = unsafe { std::mem::transmute(p) };
    for &(k, bits) in arg.overrides.iter().take(8) {
        words[usize::from(k) % FIELDS] = bits;
    }
    unsafe { std::mem::transmute(words) }
}

fn vec3(v: [F; 3]) -> hairsim_vec3 {
    hairsim_vec3 {
        x: v[0].get(),
        y: v[1].get(),
        z: v[2].get(),
    }
}

fn identity_pose() -> hairsim_pose {
    hairsim_pose {
        rotation: hairsim_quat {
            w: 1.0,
            ..Default::default()
        },
        ..Default::default()
    }
}

fn check_code(code: hairsim_error) {
    let c = code as i32;
    assert!((0..=25).contains(&c), "unknown code {c}");
    let message = unsafe { CStr::from_ptr(hairsim_error_message(c)) };
    assert!(!message.is_empty());
}

fuzz_target!(|calls: Vec<Call>| {
    let mut worlds = Worlds::new();
    let mut out = OutBuf::new::<hairsim_step_report>();
    for call in calls.into_iter().take(64) {
        let world_arg = match &call {
            Call::Init(w, _)
            | Call::Configure(w, _)
            | Call::AddStrand(w, ..)
            | Call::AddCollider(w, ..)
            | Call::AddGrab(w, ..)
            | Call::ReleaseGrab(w, _)
            | Call::Positions(w, ..)
            | Call::StateHash(w, _)
            | Call::Info(w, _)
            | Call::Check(w)
            | Call::Recover(w) => Some(*w),
            Call::Step { world, .. } => Some(*world),
            _ => None,
        };
        let before = world_arg.and_then(|w| worlds.snapshot(w));
        let code = unsafe { call_one(&call, &mut worlds, &mut out) };
        check_code(code);
        assert_ne!(code, hairsim_error::Busy, "{call:?}");
        if let Some(WorldArg::World(w)) = world_arg {
            let initialised = worlds.initialised[usize::from(w)];
            let refused_as_new = code == hairsim_error::NotInitialised;
            if !matches!(call, Call::Init(..)) {
                assert!(!(initialised && refused_as_new), "{call:?}");
                assert!(initialised || code != hairsim_error::Ok, "{call:?}");
            }
            // Every call that reached an initialised world keeps its outcome there.
            if initialised && !matches!(call, Call::Init(..)) {
                let world = worlds.ptr(WorldArg::World(w));
                let mut refusal = MaybeUninit::<hairsim_refusal>::uninit();
                let read = unsafe { hairsim_last_refusal(world, refusal.as_mut_ptr()) };
                assert_eq!(read, hairsim_error::Ok, "{call:?}");
                let refusal = unsafe { refusal.assume_init() };
                assert_eq!(refusal.code, code as i32, "{call:?}");
            }
            // After the record is read: the snapshot's own calls record their outcomes.
            if code != hairsim_error::Ok {
                assert_eq!(worlds.snapshot(WorldArg::World(w)), before, "{call:?}");
            }
        }
    }
});

/// Makes one call; `Init` updates which worlds are initialised.
unsafe fn call_one(call: &Call, worlds: &mut Worlds, out: &mut OutBuf) -> hairsim_error {
    match call {
        Call::Init(w, len) => {
            let world = worlds.ptr(*w);
            let len = match len {
                Len::Exact => worlds.size,
                Len::Zero => 0,
                Len::Short(n) => worlds.size - 1 - usize::from(*n) % worlds.size,
            };
            // A misaligned world is 4 bytes into world 0: valid for 4 bytes fewer.
            let len = if matches!(w, WorldArg::Misaligned) {
                len.min(worlds.size - 4)
            } else {
                len
            };
            let code = hairsim_init(world, len);
            if let (WorldArg::World(i), hairsim_error::Ok) = (w, code) {
                worlds.initialised[usize::from(*i)] = true;
            }
            code
        }
        Call::ParamsDefault(o) => hairsim_params_default(out.ptr(*o, worlds, None)),
        Call::HumanHair(o) => hairsim_material_human_hair(out.ptr(*o, worlds, None)),
        Call::Configure(w, p) => {
            let world = worlds.ptr(*w);
            match p {
                Some(p) => {
                    let p = Box::new(params(p));
                    hairsim_configure(world, &*p)
                }
                None => hairsim_configure(world, ptr::null()),
            }
        }
        Call::AddStrand(w, points, material, index) => {
            let world = worlds.ptr(*w);
            let (points, count): (Vec<hairsim_vec3>, usize) = match points {
                Points::Line { count, step, bend } => {
                    let count = usize::from(*count) % (NODES + 3);
                    let step = vec3(*step);
                    let bend = bend.get();
                    let p = (0..count)
                        .map(|i| {
                            let i = i as f32;
                            hairsim_vec3 {
                                x: step.x * i + bend * i * i,
                                y: step.y * i,
                                z: step.z * i,
                            }
                        })
                        .collect();
                    (p, count)
                }
                Points::Raw(raw) => {
                    let p: Vec<hairsim_vec3> =
                        raw.iter().take(NODES + 2).map(|v| vec3(*v)).collect();
                    let n = p.len();
                    (p, n)
                }
                Points::OverCount(n) => (
                    vec![hairsim_vec3::default(); 4],
                    NODES + 1 + n % (usize::MAX - NODES - 1),
                ),
            };
            let material = match material {
                MaterialArg::HumanHair => {
                    let mut m = MaybeUninit::<hairsim_material>::uninit();
                    assert_eq!(
                        hairsim_material_human_hair(m.as_mut_ptr()),
                        hairsim_error::Ok
                    );
                    Some(Box::new(m.assume_init()))
                }
                MaterialArg::Raw(f) => Some(Box::new(hairsim_material {
                    youngs_modulus: f[0].get(),
                    shear_modulus: f[1].get(),
                    radius: f[2].get(),
                    density: f[3].get(),
                    minor_axis_penalty: f[4].get(),
                })),
                MaterialArg::Null => None,
            };
            let material = material.as_deref().map_or(ptr::null(), |m| m as *const _);
            let index = out.ptr::<u32>(*index, worlds, Some(*w));
            let points_ptr = if count == 0 && points.is_empty() {
                ptr::null()
            } else {
                points.as_ptr()
            };
            let code = hairsim_add_strand(world, points_ptr, count, material, index);
            if count > NODES && code == hairsim_error::Ok {
                panic!("{count} points accepted");
            }
            code
        }
        Call::AddCollider(w, collider, index) => {
            let world = worlds.ptr(*w);
            let index = out.ptr::<u32>(*index, worlds, Some(*w));
            match collider {
                Some((shape, attached, f)) => {
                    let c = Box::new(hairsim_collider {
                        shape: *shape % 4,
                        attached_to_head: *attached % 3,
                        a: vec3([f[0], f[1], f[2]]),
                        b: vec3([f[3], f[4], f[5]]),
                        radius: f[6].get(),
                    });
                    hairsim_add_collider(world, &*c, index)
                }
                None => hairsim_add_collider(world, ptr::null(), index),
            }
        }
        Call::AddGrab(w, grab, index) => {
            let world = worlds.ptr(*w);
            let index = out.ptr::<u32>(*index, worlds, Some(*w));
            match grab {
                Some((strand, node, f)) => {
                    let g = Box::new(hairsim_grab {
                        strand: *strand % 8,
                        node: *node % 40,
                        target: vec3([f[0], f[1], f[2]]),
                        force_limit: f[3].get(),
                        stiffness: f[4].get(),
                        damping: f[5].get(),
                    });
                    hairsim_add_grab(world, &*g, index)
                }
                None => hairsim_add_grab(world, ptr::null(), index),
            }
        }
        Call::ReleaseGrab(w, g) => hairsim_release_grab(worlds.ptr(*w), *g),
        Call::Step {
            world: w,
            head,
            targets,
            accelerations,
            accelerations_in_world,
            report,
        } => {
            let world = worlds.ptr(*w);
            let head = match head {
                Head::Identity => identity_pose(),
                Head::Shake(t) => {
                    let shake = hairsim_shake {
                        axis: hairsim_vec3 {
                            x: 0.0,
                            y: 1.0,
                            z: 0.0,
                        },
                        centre: hairsim_vec3::default(),
                        amplitude: 0.5,
                        frequency: 3.18,
                    };
                    let mut pose = MaybeUninit::<hairsim_pose>::uninit();
                    let code = hairsim_shake_pose(&shake, t.get(), pose.as_mut_ptr());
                    check_code(code);
                    if code == hairsim_error::Ok {
                        pose.assume_init()
                    } else {
                        // A time the shake refuses (not finite): the step is still made,
                        // with the head at rest, so its outcome is the world's.
                        identity_pose()
                    }
                }
                Head::Raw(f) => hairsim_pose {
                    position: vec3([f[0], f[1], f[2]]),
                    rotation: hairsim_quat {
                        x: f[3].get(),
                        y: f[4].get(),
                        z: f[5].get(),
                        w: f[6].get(),
                    },
                },
            };
            let targets: Option<Vec<hairsim_vec3>> = targets
                .as_ref()
                .map(|t| t.iter().take(6).map(|v| vec3(*v)).collect());
            let accelerations: Option<Vec<hairsim_vec3>> = accelerations.as_ref().map(|a| {
                a.iter()
                    .take(STRANDS * NODES + 2)
                    .map(|v| vec3(*v))
                    .collect()
            });
            let (targets_ptr, target_count) = match &targets {
                Some(t) => (t.as_ptr(), t.len()),
                None => (ptr::null(), 0),
            };
            let (mut acc_ptr, acc_count) = match &accelerations {
                Some(a) => (a.as_ptr(), a.len()),
                None => (ptr::null(), 0),
            };
            if *accelerations_in_world && acc_count > 0 && acc_count * 12 <= worlds.size {
                if let WorldArg::World(i) = w {
                    acc_ptr = worlds.buffers[usize::from(*i)].as_ptr().cast();
                }
            }
            let input = Box::new(hairsim_step_input {
                head,
                grab_targets: targets_ptr,
                grab_target_count: target_count,
                accelerations: acc_ptr,
                acceleration_count: acc_count,
            });
            let report = out.ptr::<hairsim_step_report>(*report, worlds, Some(*w));
            hairsim_step(world, &*input, report)
        }
        Call::Positions(w, strand, capacity, o, count) => {
            let world = worlds.ptr(*w);
            let capacity = usize::from(*capacity % 40);
            let mut buffer = vec![hairsim_vec3::default(); capacity];
            let p = match o {
                Out::Null => ptr::null_mut(),
                Out::Misaligned if capacity > 0 => buffer.as_mut_ptr().cast::<u8>().add(1).cast(),
                Out::InWorld(_) => out.ptr::<hairsim_vec3>(*o, worlds, Some(*w)),
                _ if capacity == 0 => ptr::null_mut(),
                _ => buffer.as_mut_ptr(),
            };
            // A misaligned array is valid for one element fewer.
            let capacity = match o {
                Out::Misaligned => capacity.saturating_sub(1),
                Out::InWorld(_) => capacity.min(1),
                _ => capacity,
            };
            let mut count_buf = OutBuf::new::<usize>();
            let count = count_buf.ptr::<usize>(*count, worlds, Some(*w));
            hairsim_strand_positions(world, *strand % 8, p, capacity, count)
        }
        Call::StateHash(w, o) => {
            let world = worlds.ptr(*w);
            hairsim_state_hash(world, out.ptr(*o, worlds, Some(*w)))
        }
        Call::Info(w, o) => {
            let world = worlds.ptr(*w);
            hairsim_get_info(world, out.ptr(*o, worlds, Some(*w)))
        }
        Call::ShakePose(shake, t, o) => {
            let shake = shake.map(|f| {
                Box::new(hairsim_shake {
                    axis: vec3([f[0], f[1], f[2]]),
                    centre: vec3([f[3], f[4], f[5]]),
                    amplitude: f[6].get(),
                    frequency: f[7].get(),
                })
            });
            let shake = shake.as_deref().map_or(ptr::null(), |s| s as *const _);
            hairsim_shake_pose(shake, t.get(), out.ptr(*o, worlds, None))
        }
        Call::CircleTarget(circle, t, o) => {
            let circle = circle.map(|f| {
                Box::new(hairsim_circle {
                    start: vec3([f[0], f[1], f[2]]),
                    radius: f[3].get(),
                    frequency: f[4].get(),
                })
            });
            let circle = circle.as_deref().map_or(ptr::null(), |c| c as *const _);
            hairsim_circle_target(circle, t.get(), out.ptr(*o, worlds, None))
        }
        Call::Capacity(o) => hairsim_get_capacity(out.ptr(*o, worlds, None)),
        Call::Message(code) => {
            let message = CStr::from_ptr(hairsim_error_message(*code));
            assert!(!message.is_empty());
            hairsim_error::Ok
        }
        // A world the calls built is never corrupt, and nothing else holds it.
        Call::Check(w) => {
            let code = hairsim_check(worlds.ptr(*w));
            assert_ne!(code, hairsim_error::Corrupt, "{call:?}");
            code
        }
        Call::Recover(w) => {
            let code = hairsim_recover(worlds.ptr(*w));
            assert_ne!(code, hairsim_error::Corrupt, "{call:?}");
            code
        }
        Call::LastRefusal(w, o) => {
            let world = worlds.ptr(*w);
            let out = out.ptr::<hairsim_refusal>(*o, worlds, Some(*w));
            let code = hairsim_last_refusal(world, out);
            if code == hairsim_error::Ok {
                let r = &*out;
                assert!((0..=25).contains(&r.code), "unknown code {}", r.code);
                for text in [r.function, r.argument, r.field] {
                    assert!(!text.is_null());
                    let _ = CStr::from_ptr(text);
                }
            }
            code
        }
    }
}
