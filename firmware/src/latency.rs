//! Bounded latency, measured on the target: SysTick ticks per step of rod and DFTL scenes of
//! growing size, calm (head still, hair hanging) and violent (head shaking at 10 rad/s, hair
//! starting horizontal), in fixed-cost mode; and of the haptic DFTL scene, a device holding a
//! strand through a virtual coupling.
//!
//! Under `qemu-system-arm -icount shift=0` every instruction takes 1 ns of virtual time and
//! SysTick counts the 25 MHz system clock, so one tick is 40 instructions: a deterministic
//! count. `firmware/latency.py` turns the printed ticks into instructions and a Cortex-M4F
//! cycle estimate.

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_semihosting::hprintln;
use hairsim_core::{
    Collider, Effect, Effects, Math, Mode, Params, Pose, Real, Shake, Shape, Solver, StepInput,
    StepReport, Strand, Vec3, World,
};

/// Steps measured per scene.
const STEPS: usize = 200;
/// Steps per run when profiling one scene (a QEMU execution trace grows by ~7 MB per step).
const PROFILE_STEPS: usize = 6;

/// Set at build time (`HAIRSIM_PROFILE=rod|dftl|dftl_noshape|draped|draped_clear|haptic_dftl cargo build
/// --release`): run only that scene, with [`step_begins`] and [`step_ends`] around each step,
/// for `firmware/profile.py` to read a QEMU execution trace by (README, "Measured on the
/// target"): the 128-node rod or the 512-vertex DFTL one for [`PROFILE_STEPS`] steps calm and
/// violent, or the draped 32-node rod strand of [`measure_collision_rows`] with its sphere or
/// without for [`STEPS`] steps.
pub const PROFILE: Option<&str> = option_env!("HAIRSIM_PROFILE");

/// Marks where a measured step starts in an execution trace (a call never inlined away).
#[inline(never)]
fn step_begins() {
    // SAFETY: single-threaded; a volatile write keeps the call.
    unsafe { core::ptr::write_volatile(core::ptr::addr_of_mut!(MARK), 1) }
}

/// Marks where a measured step ends.
#[inline(never)]
fn step_ends() {
    // SAFETY: as in `step_begins`.
    unsafe { core::ptr::write_volatile(core::ptr::addr_of_mut!(MARK), 0) }
}

/// Written by the step markers.
static mut MARK: u32 = 0;

/// Per-step tick counts of the scene being measured.
static mut TICKS: [u32; STEPS] = [0; STEPS];

/// Starts SysTick free-running on the core clock.
pub fn start(syst: &mut SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(0x00FF_FFFF);
    syst.clear_current();
    syst.enable_counter();
}

/// Ticks `f` takes (SysTick counts down; 24 bits).
fn ticks(f: impl FnOnce()) -> u32 {
    let before = SYST::get_current();
    f();
    let after = SYST::get_current();
    before.wrapping_sub(after) & 0x00FF_FFFF
}

/// Minimum, median and maximum of `t` (sorted in place).
fn stats(t: &mut [u32]) -> (u32, u32, u32) {
    t.sort_unstable();
    (t[0], t[t.len() / 2], t[t.len() - 1])
}

fn params(solver: Solver, shape: bool) -> Params {
    let effects = match solver {
        Solver::Rod => Effects::from_slice(&[
            Effect::Gravity,
            Effect::Drag,
            Effect::Bending,
            Effect::Twist,
            Effect::Inextensibility,
            Effect::Collisions,
        ]),
        Solver::Dftl => Effects::from_slice(&[
            Effect::Gravity,
            Effect::Drag,
            Effect::Inextensibility,
            Effect::Collisions,
        ]),
    };
    let effects = if shape {
        effects.with(Effect::Shape)
    } else {
        effects
    };
    let mut params = Params {
        solver,
        effects,
        mode: Mode::FixedCost,
        drag: 2.0e-7,
        ..Params::DEFAULT
    };
    // The rod's projection cap is what these scenes need to meet the 1e-6 tolerance: in
    // converge mode, calm steps take 1 iteration and violent ones 1–3 (measured on the host
    // over 1000 steps of 4 × 32 nodes), so 4 keeps one in hand.
    params.rod.projection_iterations = 4;
    params
}

/// Fills `world` with `strands` strands of `nodes` nodes (1 cm segments) rooted around a 5 cm
/// head (a sphere collider, unless `collider` is false): hanging down (calm) or sticking out
/// horizontally (violent).
fn build<const S: usize, const N: usize, M: Math>(
    world: &mut World<S, N, M>,
    solver: Solver,
    strands: usize,
    nodes: usize,
    violent: bool,
    (shape, collider): (bool, bool),
) -> bool {
    let mut ok = world.configure(params(solver, shape)).is_ok();
    if collider {
        ok &= world
            .add_collider(Collider {
                shape: Shape::Sphere {
                    centre: Vec3::ZERO,
                    radius: 0.05,
                },
                attached_to_head: true,
            })
            .is_ok();
    }
    for s in 0..strands {
        let (sin, cos) = M::sin_cos(s as Real * 2.399_963);
        let out = Vec3::new(cos, 0.0, sin);
        let root = out * 0.05;
        let direction = if violent { out } else { -Vec3::Y };
        let mut points = [Vec3::ZERO; N];
        for (i, p) in points.iter_mut().enumerate().take(nodes) {
            *p = root + direction * (0.01 * i as Real) + out * (0.0001 * i as Real);
        }
        match Strand::<N>::from_polyline(&points[..nodes], &hairsim_core::Material::HUMAN_HAIR) {
            Ok(strand) => ok &= world.add_strand(strand).is_ok(),
            Err(_) => ok = false,
        }
    }
    ok
}

/// Measures one scene over `steps` steps (at most [`STEPS`]) and prints a line: solver,
/// nodes, calm and violent min/median/max ticks.
fn measure<const S: usize, const N: usize, M: Math>(
    world: &mut World<S, N, M>,
    solver: Solver,
    (strands, nodes): (usize, usize),
    shape: bool,
    steps: usize,
) {
    let mut line = [(0u32, 0u32, 0u32); 2];
    for (v, violent) in [false, true].into_iter().enumerate() {
        *world = World::new();
        if !build(world, solver, strands, nodes, violent, (shape, true)) {
            hprintln!(
                "latency error: cannot build {} strands of {} nodes",
                strands,
                nodes
            );
            return;
        }
        // SAFETY: the only access to TICKS: single-threaded, no interrupt touches it.
        let all = unsafe { &mut *core::ptr::addr_of_mut!(TICKS) };
        let t = &mut all[..steps.clamp(1, STEPS)];
        for (k, slot) in t.iter_mut().enumerate() {
            *slot = timed_step(world, k, violent).0;
        }
        line[v] = stats(t);
    }
    let name = match (solver, shape) {
        (Solver::Rod, _) => "rod",
        (Solver::Dftl, true) => "dftl",
        (Solver::Dftl, false) => "dftl_noshape",
    };
    hprintln!(
        "latency {} strands {} nodes {} calm {} {} {} violent {} {} {}",
        name,
        strands,
        strands * nodes,
        line[0].0,
        line[0].1,
        line[0].2,
        line[1].0,
        line[1].1,
        line[1].2
    );
}

/// What a collision row costs: a 32-node rod scene stepped [`STEPS`] times with its head's
/// sphere and without it, the head shaking at 10 rad/s. Two scenes: the latency table's
/// violent one (hair sticking out horizontally) and a draped one (one strand laid over the
/// sphere from its equator round its top, as hair lies on a head). Prints, per scene, the
/// ticks each run took in all and the collision rows the projection solved with the sphere
/// (`StepReport::collision_rows`, summed); `firmware/latency.py` divides the modelled cycles
/// the sphere adds by those rows.
fn measure_collision_rows<const S: usize, const N: usize, M: Math>(world: &mut World<S, N, M>) {
    let nodes = 32;
    for draped in [false, true] {
        let mut totals = [(0, 0); 2];
        for (c, collider) in [true, false].into_iter().enumerate() {
            match collision_scene(world, (nodes, STEPS), (draped, collider)) {
                Some(total) => totals[c] = total,
                None => return hprintln!("latency error: cannot build the collision rows' scene"),
            }
        }
        hprintln!(
            "collision rows rod {} nodes {} steps {} with {} without {} rows {}",
            if draped { "draped" } else { "violent" },
            nodes,
            STEPS,
            totals[0].0,
            totals[1].0,
            totals[0].1
        );
    }
}

/// Builds the collision rows' scene (`draped` or violent, with the sphere or without) in
/// `world` and steps it `steps` times with the step markers; the ticks and collision rows it
/// took in all, or `None` if it cannot be built.
fn collision_scene<const S: usize, const N: usize, M: Math>(
    world: &mut World<S, N, M>,
    (nodes, steps): (usize, usize),
    (draped, collider): (bool, bool),
) -> Option<(u32, u32)> {
    *world = World::new();
    let strands = if draped { 0 } else { 1 };
    let mut ok = build(world, Solver::Rod, strands, nodes, true, (false, collider));
    if draped {
        ok &= add_draped(world, nodes);
    }
    if !ok {
        return None;
    }
    let mut total = (0u32, 0u32);
    for k in 0..steps {
        let (t, rows) = timed_step(world, k, true);
        total = (total.0.wrapping_add(t), total.1.wrapping_add(rows));
    }
    Some(total)
}

/// Step `k` (from 0) of `world`, the head still or shaking at 10 rad/s (`violent`), between
/// the step markers: its ticks and the collision rows its projection solved.
fn timed_step<const S: usize, const N: usize, M: Math>(
    world: &mut World<S, N, M>,
    k: usize,
    violent: bool,
) -> (u32, u32) {
    let time = (k + 1) as Real * world.params().dt;
    let head = if violent {
        Shake::TEN_RAD_PER_S.pose_at::<M>(time)
    } else {
        Pose::IDENTITY
    };
    let input = StepInput {
        head,
        accelerations: None,
    };
    let mut report = StepReport::default();
    let t = ticks(|| {
        step_begins();
        world.step_into(&input, &mut report);
        step_ends();
    });
    (t, report.collision_rows)
}

/// One strand of `nodes` nodes, 1 cm apart along a great circle 0.2 mm outside the 5 cm head,
/// from its equator over its top (an arc of 1 cm per node).
fn add_draped<const S: usize, const N: usize, M: Math>(
    world: &mut World<S, N, M>,
    nodes: usize,
) -> bool {
    let radius = 0.0502;
    let mut points = [Vec3::ZERO; N];
    for (i, p) in points.iter_mut().enumerate().take(nodes) {
        let (sin, cos) = M::sin_cos(0.01 * i as Real / radius);
        *p = Vec3::new(cos, sin, 0.0) * radius;
    }
    let material = &hairsim_core::Material::HUMAN_HAIR;
    match Strand::<N>::from_polyline(&points[..nodes.min(N)], material) {
        Ok(strand) => world.add_strand(strand).is_ok(),
        Err(_) => false,
    }
}

/// The haptic DFTL scene (`hairsim_core::scenes::haptic_dftl`), [`STEPS`] steps as it runs
/// (violent: the head shaking at 10 rad/s, the device going round its circle) and with the head
/// and the device still (calm): prints a `latency haptic-dftl …` line.
fn measure_haptic_dftl<M: Math>(world: &mut HapticWorld<M>, steps: usize) {
    use hairsim_core::scenes::haptic_dftl;
    let mut line = [(0u32, 0u32, 0u32); 2];
    let mut report = StepReport::default();
    for (v, violent) in [false, true].into_iter().enumerate() {
        *world = World::new();
        if haptic_dftl::build(world).is_err() {
            return hprintln!("latency error: cannot build the haptic-dftl scene");
        }
        // SAFETY: the only access to TICKS: single-threaded, no interrupt touches it.
        let all = unsafe { &mut *core::ptr::addr_of_mut!(TICKS) };
        let all = &mut all[..steps.clamp(1, STEPS)];
        for (k, slot) in all.iter_mut().enumerate() {
            let k = k as u32;
            *slot = ticks(|| {
                step_begins();
                if violent {
                    haptic_dftl::step(world, k, &mut report);
                } else {
                    let still = StepInput {
                        head: Pose::IDENTITY,
                        accelerations: None,
                    };
                    world.step_into(&still, &mut report);
                }
                step_ends();
            });
        }
        line[v] = stats(all);
    }
    hprintln!(
        "latency haptic-dftl strands {} nodes {} calm {} {} {} violent {} {} {}",
        haptic_dftl::STRANDS,
        haptic_dftl::STRANDS * haptic_dftl::NODES,
        line[0].0,
        line[0].1,
        line[0].2,
        line[1].0,
        line[1].1,
        line[1].2
    );
}

type RodWorld<M> = World<8, 32, M>;
/// The haptic DFTL scene's world.
type HapticWorld<M> = World<
    { hairsim_core::scenes::haptic_dftl::STRANDS },
    { hairsim_core::scenes::haptic_dftl::NODES },
    M,
>;
/// A world sized for one 16-node strand (the step's scratch arrays scale with the capacity).
type SmallRodWorld<M> = World<1, 16, M>;
type DftlWorld<M> = World<64, 16, M>;

static mut ROD: RodWorld<crate::Vsqrt> = World::new();
static mut SMALL_ROD: SmallRodWorld<crate::Vsqrt> = World::new();
static mut DFTL: DftlWorld<crate::Vsqrt> = World::new();
static mut HAPTIC: HapticWorld<crate::Vsqrt> = World::new();

/// Runs every measurement: rod 16–256 nodes, DFTL 64–1024 vertices with and without shape
/// preservation (`dftl`, `dftl_noshape`); or, when built with [`PROFILE`], that one scene.
pub fn run() {
    // SAFETY: called once from `main`, nothing else touches these statics.
    let small = unsafe { &mut *core::ptr::addr_of_mut!(SMALL_ROD) };
    let rod = unsafe { &mut *core::ptr::addr_of_mut!(ROD) };
    let dftl = unsafe { &mut *core::ptr::addr_of_mut!(DFTL) };
    let haptic = unsafe { &mut *core::ptr::addr_of_mut!(HAPTIC) };
    match PROFILE {
        None => {}
        Some("rod") => return measure(rod, Solver::Rod, (4, 32), false, PROFILE_STEPS),
        Some("dftl") => return measure(dftl, Solver::Dftl, (32, 16), true, PROFILE_STEPS),
        Some("dftl_noshape") => {
            return measure(dftl, Solver::Dftl, (32, 16), false, PROFILE_STEPS);
        }
        // The draped collision rows' scene, with its sphere and without (for a stage table of
        // what the sphere adds): 200 steps, so that the hair has settled on the head.
        Some(scene @ ("draped" | "draped_clear")) => {
            let _ = collision_scene(rod, (32, STEPS), (true, scene == "draped"));
            return;
        }
        Some("haptic_dftl") => return measure_haptic_dftl(haptic, PROFILE_STEPS),
        Some(other) => {
            return hprintln!(
                "latency error: HAIRSIM_PROFILE={} (rod, dftl, dftl_noshape, draped, draped_clear, haptic_dftl)",
                other
            );
        }
    }
    // One 16-node strand as well, in a world of that capacity: the largest rod scene that
    // fits half a tick lies below 32 nodes.
    measure(small, Solver::Rod, (1, 16), false, STEPS);
    for strands in [1, 2, 4, 8] {
        measure(rod, Solver::Rod, (strands, 32), false, STEPS);
    }
    measure_collision_rows(rod);
    // DFTL with shape preservation (the scenes' default), then the same without it.
    for strands in [4, 8, 16, 32, 64] {
        measure(dftl, Solver::Dftl, (strands, 16), true, STEPS);
    }
    for strands in [4, 8, 16, 32, 64] {
        measure(dftl, Solver::Dftl, (strands, 16), false, STEPS);
    }
    measure_haptic_dftl(haptic, STEPS);
}
