//! Grabs a haptic loop can trust, for both solvers: the forces at rest and in motion against
//! the strand's weight and momentum, the work a device does on the hair against the energy the
//! hair stores (passivity), the force's smoothness and latency, bad input, and a closed loop
//! with a simulated device.

use hairsim_core::rod::energy::{elastic_energy, RodFrames};
use hairsim_core::rod::ElasticTerms;
use hairsim_core::{
    Coupling, Effect, Effects, Flags, Grab, GrabStatus, Libm, Material, Mode, Params, Pose, Real,
    Solver, StepInput, StepReport, Strand, Vec3, World,
};

const N: usize = 32;
type Hair = World<1, N, Libm>;

const GRAVITY: f64 = 9.81;

/// The effects a solver's hair needs, with grabs.
fn effects(solver: Solver, shape: bool) -> Effects {
    let common = [
        Effect::Gravity,
        Effect::Drag,
        Effect::Inextensibility,
        Effect::Grabs,
    ];
    let own: &[Effect] = match (solver, shape) {
        (Solver::Rod, _) => &[Effect::Bending, Effect::Twist],
        (Solver::Dftl, true) => &[Effect::Shape],
        (Solver::Dftl, false) => &[],
    };
    own.iter()
        .fold(Effects::from_slice(&common), |e, &x| e.with(x))
}

fn params(solver: Solver, dt: Real, mode: Mode, shape: bool) -> Params {
    let mut params = Params {
        solver,
        dt,
        mode,
        effects: effects(solver, shape),
        drag: 2.0e-7,
        ..Params::DEFAULT
    };
    params.rod.projection_iterations = 12;
    params
}

/// `params` with ten times the air's drag: a swinging strand comes to rest within 3 s
/// (amplitude `e^{−ν t/2m}`, `ν/m` = 30/s), where still air's leaves it swinging by a tenth of
/// a millimetre.
fn settling(params: Params) -> Params {
    Params {
        drag: 2.0e-6,
        ..params
    }
}

/// A straight strand of `nodes` nodes 1 cm apart along +x from the origin.
fn straight(nodes: usize) -> Strand<N> {
    let points: Vec<Vec3> = (0..nodes)
        .map(|i| Vec3::new(0.01 * i as Real, 0.0, 0.0))
        .collect();
    Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
}

fn world(params: Params, nodes: usize) -> Hair {
    let mut world = Hair::with_params(params).unwrap();
    world.add_strand(straight(nodes)).unwrap();
    world
}

fn still() -> StepInput<'static> {
    StepInput {
        head: Pose::IDENTITY,
        accelerations: None,
    }
}

/// The weight of nodes 2 to the last, N.
fn weight(world: &Hair) -> f64 {
    let strand = &world.strands()[0];
    let mass: f64 = strand.rest.mass[2..strand.nodes()]
        .iter()
        .map(|&m| f64::from(m))
        .sum();
    mass * GRAVITY
}

/// The momentum of nodes 2 to the last, kg·m/s.
fn momentum(world: &Hair) -> [f64; 3] {
    let strand = &world.strands()[0];
    let mut p = [0.0; 3];
    for i in 2..strand.nodes() {
        let (v, m) = (strand.state.velocity[i], f64::from(strand.rest.mass[i]));
        for (axis, component) in p.iter_mut().zip(v.to_array()) {
            *axis += m * f64::from(component);
        }
    }
    p
}

fn to_f64(v: Vec3) -> [f64; 3] {
    v.to_array().map(f64::from)
}

fn norm(v: [f64; 3]) -> f64 {
    v.iter().map(|c| c * c).sum::<f64>().sqrt()
}

/// Grabs node `node` of `world`'s strand where it rests and brings the target to `to` in
/// 0.5 s, smoothly (a half cosine): a target that jumps folds a strand in one step.
fn grab_and_bring(world: &mut Hair, node: u32, coupling: Option<Coupling>, to: Vec3) {
    let from = world.strands()[0].positions()[node as usize];
    let grab = Grab::new(0, node, from, 1000.0);
    world
        .add_grab(coupling.map_or(grab, |c| grab.with_coupling(c)))
        .unwrap();
    let steps = (0.5 / world.params().dt).round() as usize;
    for k in 1..=steps {
        let s = 0.5 - 0.5 * (core::f32::consts::PI * k as Real / steps as Real).cos();
        world.set_grab_target(0, from + (to - from) * s);
        world.step(&still());
    }
}

/// A strand of 30 nodes held at its root and grabbed at its tip, brought to 15 cm from the
/// root, hanging as a U under gravity, left to come to rest (3 s in all): returns the world
/// and the last report.
fn hanging_u(solver: Solver, shape: bool, coupling: Option<Coupling>) -> (Hair, StepReport) {
    let mut world = world(settling(params(solver, 0.001, Mode::Converge, shape)), 30);
    grab_and_bring(&mut world, 29, coupling, Vec3::new(0.15, 0.0, 0.0));
    let mut report = StepReport::default();
    for _ in 0..2500 {
        report = world.step(&still());
    }
    assert_eq!(world.grabs()[0].status, GrabStatus::Held);
    (world, report)
}

/// Statics, both solvers: a strand held at its root and grabbed at its tip hangs as a U at
/// rest; the vertical forces the grab's device and the head feel add up to the weight of nodes
/// 2 to the last (the grabbed node included) within 1 %. DFTL with its shape constraints on and
/// off: its head force counts the shape springs' pull. The rod's split between the two ends
/// is the catenary's: each end carries the weight of the hair between it and the lowest point.
#[test]
fn a_hanging_u_weighs_on_the_grab_and_the_head() {
    for (solver, shape) in [
        (Solver::Rod, false),
        (Solver::Dftl, false),
        (Solver::Dftl, true),
    ] {
        for coupling in [None, Some(Coupling::new(1.0, 0.002))] {
            let (world, report) = hanging_u(solver, shape, coupling);
            let w = weight(&world);
            let grab = to_f64(report.grab_forces[0]);
            let head = to_f64(report.head_force);
            let sum = -(grab[1] + head[1]);
            let what = format!("{solver:?} shape {shape} coupling {coupling:?}");
            println!(
                "{what}: grab {:.4e} head {:.4e} sum {:.4e} weight {:.4e} ({:+.3} %)",
                -grab[1],
                -head[1],
                sum,
                w,
                100.0 * (sum / w - 1.0)
            );
            assert!((sum / w - 1.0).abs() < 0.01, "{what}: {sum} against {w}");
            // Horizontally the two ends pull against each other.
            assert!(
                (grab[0] + head[0]).abs() < 0.01 * w,
                "{what}: {grab:?} {head:?}"
            );
            if solver == Solver::Rod || !shape {
                // The split: the hair between the lowest node and each end hangs from that end.
                let strand = &world.strands()[0];
                let y = |i: usize| strand.positions()[i].y;
                let lowest = (2..30).min_by(|&a, &b| y(a).total_cmp(&y(b))).unwrap();
                let mass = |range: core::ops::Range<usize>| -> f64 {
                    range.map(|i| f64::from(strand.rest.mass[i])).sum()
                };
                let grab_share = (mass(lowest + 1..30) + 0.5 * mass(lowest..lowest + 1)) * GRAVITY;
                println!(
                    "  grab carries {:.4e}, the catenary {grab_share:.4e}",
                    -grab[1]
                );
                assert!(
                    (-grab[1] / grab_share - 1.0).abs() < 0.1,
                    "{what}: the grab carries {} of the catenary's {grab_share}",
                    -grab[1]
                );
            }
        }
    }
}

/// Dynamics, the rod: a 30-node strand whose node 15 a grab moves on a figure of eight (within
/// the strand's reach), its tail hanging onto a sphere, in gusty wind. Every step, the change of
/// the momentum of nodes 2 to the last equals the forces on them times `dt` — gravity, drag
/// (`−ν v` at the step's start: a material soft enough for one substep, so the drag each node
/// feels is that of its velocity at the step's start), wind, the sphere's push, the grab's and
/// the head's — within 1e-3 of its size (or of the step's weight impulse, where the forces
/// nearly balance). Nothing else moves the hair: the elastic forces are internal but for what
/// they do to the held nodes 0 and 1, which the head force carries.
#[test]
fn the_rod_s_momentum_changes_by_the_forces_reported() {
    use hairsim_core::wind::wind_acceleration;
    use hairsim_core::{Collider, Shape};
    let material = Material {
        youngs_modulus: 0.05e9,
        ..Material::HUMAN_HAIR
    };
    for coupling in [None, Some(Coupling::new(1.0, 0.002))] {
        let mut params = params(Solver::Rod, 0.001, Mode::Converge, false);
        params.effects = params.effects.with(Effect::Wind).with(Effect::Collisions);
        params.rod.projection_tolerance = 1.0e-7;
        params.rod.projection_iterations = 30;
        let mut world = Hair::with_params(params).unwrap();
        let points: Vec<Vec3> = (0..30)
            .map(|i| Vec3::new(0.01 * i as Real, 0.0, 0.0))
            .collect();
        world
            .add_strand(Strand::from_polyline(&points, &material).unwrap())
            .unwrap();
        world
            .add_collider(Collider {
                shape: Shape::Sphere {
                    centre: Vec3::new(0.08, -0.2, 0.0),
                    radius: 0.05,
                },
                attached_to_head: false,
            })
            .unwrap();
        // 8.1 cm from node 1, ±2.5 cm on each axis: within the 14 cm of hair to node 15.
        let centre = Vec3::new(0.05, -0.07, 0.0);
        let figure_of_eight = |t: Real| {
            let (s, c) = ((6.0 * t).sin(), (6.0 * t).cos());
            centre + Vec3::new(0.025 * s, 0.025 * s * c, 0.025 * (1.0 - c))
        };
        grab_and_bring(&mut world, 15, coupling, centre);
        for _ in 0..500 {
            world.step(&still());
        }
        let (dt, nu) = (f64::from(params.dt), f64::from(params.drag));
        let weight = weight(&world);
        let (mut worst, mut raw): (f64, f64) = (0.0, 0.0);
        let mut touched = 0;
        let start = world.steps();
        for k in 0..2000 {
            let t = (start + k + 1) as Real * params.dt;
            world.set_grab_target(0, figure_of_eight((k + 1) as Real * params.dt));
            let before = momentum(&world);
            let strand = &world.strands()[0];
            let mut external = [0.0; 3];
            let g_and_wind = to_f64(params.gravity + wind_acceleration(&params.wind, t));
            for i in 2..30 {
                let (m, v) = (
                    f64::from(strand.rest.mass[i]),
                    to_f64(strand.state.velocity[i]),
                );
                for a in 0..3 {
                    external[a] += m * g_and_wind[a] - nu * v[a];
                }
            }
            let report = world.step(&still());
            assert!(
                report.rolled_back == 0 && report.dropped_rows == 0,
                "step {k}"
            );
            assert_eq!(world.grabs()[0].status, GrabStatus::Held, "step {k}");
            let after = momentum(&world);
            let (grab, head) = (to_f64(report.grab_forces[0]), to_f64(report.head_force));
            let collider = to_f64(report.collider_forces[0]);
            touched += usize::from(report.contacts > 0);
            let change: [f64; 3] = core::array::from_fn(|a| after[a] - before[a]);
            let forces: [f64; 3] =
                core::array::from_fn(|a| (external[a] - collider[a] - grab[a] - head[a]) * dt);
            let error: [f64; 3] = core::array::from_fn(|a| change[a] - forces[a]);
            // Where the forces nearly balance the change is as small as f32 velocities resolve
            // (1e-12 kg·m/s here): measured against the step's weight impulse at least. A
            // coupling's force is known to `(K + B/Δt)` times the spacing of f32 positions
            // (its node's and target's, rounded): that much of an impulse is resolution, not
            // error.
            let resolution = coupling.map_or(0.0, |c| {
                let spacing = 0.1 * f64::from(Real::EPSILON);
                (f64::from(c.stiffness) + f64::from(c.damping) / dt) * spacing * dt
            });
            let size = norm(change).max(weight * dt);
            raw = raw.max(norm(error) / size);
            worst = worst.max((norm(error) - resolution).max(0.0) / size);
        }
        println!("coupling {coupling:?}: worst relative momentum error {worst:.2e} ({raw:.2e} before the coupling's f32 resolution), {touched} of 2000 steps in contact");
        assert!(touched > 500, "the tail should lie on the sphere");
        assert!(worst < 1.0e-3, "{coupling:?}: {worst}");
    }
}

/// Smooth, both solvers: with the target still after the hair has settled, the force the
/// device feels changes per step by at most 1 % of the weight it holds; converge and
/// fixed-cost modes agree within 1 %.
#[test]
fn a_still_grab_s_force_is_smooth_and_the_same_in_both_modes() {
    for (solver, shape) in [(Solver::Rod, false), (Solver::Dftl, true)] {
        for coupling in [None, Some(Coupling::new(1.0, 0.002))] {
            let mut settled = Vec::new();
            for mode in [Mode::Converge, Mode::FixedCost] {
                let mut world = world(settling(params(solver, 0.001, mode, shape)), 30);
                grab_and_bring(&mut world, 29, coupling, Vec3::new(0.15, 0.0, 0.0));
                for _ in 0..2500 {
                    world.step(&still());
                }
                let mut previous = world.step(&still()).grab_forces[0];
                let held = f64::from(previous.length());
                let mut jitter: f64 = 0.0;
                for _ in 0..1000 {
                    let force = world.step(&still()).grab_forces[0];
                    jitter = jitter.max(f64::from((force - previous).length()));
                    previous = force;
                }
                println!(
                    "{solver:?} {mode:?} {coupling:?}: holds {held:.4e} N, largest change a step {jitter:.2e} N ({:.3} %)",
                    100.0 * jitter / held
                );
                assert!(
                    jitter <= 0.01 * held,
                    "{solver:?} {mode:?}: {jitter} of {held}"
                );
                settled.push(previous);
            }
            let difference = f64::from((settled[0] - settled[1]).length());
            let held = f64::from(settled[0].length());
            assert!(
                difference <= 0.01 * held,
                "{solver:?} {coupling:?}: converge {:?} fixed cost {:?}",
                settled[0],
                settled[1]
            );
        }
    }
}

/// Same tick, both solvers: a step of the target shows in the force of the step that takes it.
#[test]
fn a_step_of_the_target_shows_in_the_same_step_s_force() {
    for (solver, shape) in [(Solver::Rod, false), (Solver::Dftl, true)] {
        for coupling in [None, Some(Coupling::new(1.0, 0.002))] {
            let mut world = world(params(solver, 0.001, Mode::FixedCost, shape), 30);
            let start = Vec3::new(0.15, 0.0, 0.0);
            grab_and_bring(&mut world, 29, coupling, start);
            for _ in 0..1500 {
                world.step(&still());
            }
            let before = world.step(&still()).grab_forces[0];
            let held = before.length();
            // 1 mm sideways in one step.
            world.set_grab_target(0, start + Vec3::new(0.0, 0.0, 0.001));
            let after = world.step(&still()).grab_forces[0];
            let change = after - before;
            println!("{solver:?} {coupling:?}: {before:?} -> {after:?}");
            // The device is pulled back along −z at once, by more than the whole force held.
            assert!(
                -change.z > held,
                "{solver:?} {coupling:?}: {change:?} against {held}"
            );
        }
    }
}

/// Bad input, both solvers: a NaN or infinite target keeps the previous one and flags bad
/// input; a target teleported out of reach slips a prescribed grab (a coupled one holds, and
/// its force says how far); every force stays finite.
#[test]
fn bad_targets_are_ignored_and_flagged_and_unreachable_ones_slip() {
    for (solver, shape) in [(Solver::Rod, false), (Solver::Dftl, true)] {
        for coupling in [None, Some(Coupling::new(1.0, 0.002))] {
            let mut world = world(params(solver, 0.001, Mode::Converge, shape), 30);
            let start = Vec3::new(0.15, 0.0, 0.0);
            grab_and_bring(&mut world, 29, coupling, start);
            for bad in [Real::NAN, Real::INFINITY, Real::NEG_INFINITY] {
                world.set_grab_target(0, Vec3::new(bad, 0.0, 0.0));
                let report = world.step(&still());
                assert!(report.flags.contains(Flags::BAD_INPUT), "{solver:?}: {bad}");
                assert_eq!(world.grabs()[0].target, start);
                assert!(report.grab_forces[0].is_finite() && report.head_force.is_finite());
                assert_eq!(world.grabs()[0].status, GrabStatus::Held);
            }
            // A good target clears the flag.
            world.set_grab_target(0, start);
            assert!(!world.step(&still()).flags.contains(Flags::BAD_INPUT));
            // 1 m away: beyond the strand's 28 cm.
            world.set_grab_target(0, Vec3::new(1.0, 0.0, 0.0));
            let report = world.step(&still());
            assert!(report.grab_forces[0].is_finite() && report.head_force.is_finite());
            if coupling.is_none() {
                assert_eq!(report.grabs_slipped, 1, "{solver:?}");
                assert_eq!(world.grabs()[0].status, GrabStatus::Slipped);
            }
            let mut report = report;
            for _ in 0..100 {
                report = world.step(&still());
                assert!(report.grab_forces[0].is_finite() && report.head_force.is_finite());
                assert!(world.strands()[0].is_finite());
            }
            if let Some(c) = coupling {
                // The spring pulls the device back from 1 m toward the tip, at most 29 cm
                // out (DFTL's strand follows, taut; the rod's, yanked 70 cm in a step, stays
                // where it was, rolled back every step: the device feels the spring anyway).
                assert_eq!(world.grabs()[0].status, GrabStatus::Held);
                let felt = report.grab_forces[0].x;
                assert!(felt <= -c.stiffness * 0.7, "{solver:?}: {felt}");
                // Brought back within reach, the strand holds again.
                world.set_grab_target(0, start);
                for _ in 0..500 {
                    report = world.step(&still());
                }
                assert_eq!(world.grabs()[0].status, GrabStatus::Held);
                assert!(
                    report.max_stretch < 1.0e-3,
                    "{solver:?}: {}",
                    report.max_stretch
                );
                assert_eq!(report.rolled_back, 0, "{solver:?}");
            }
        }
    }
}

/// The energy the hair of `world` stores, J: kinetic and gravitational of nodes 2 to the last;
/// the rod's bending and twist, or DFTL's shape springs (`dftl_shape_energy`); and the
/// coupling's spring, if the grab has one.
fn stored_energy(world: &Hair) -> f64 {
    let strand = &world.strands()[0];
    let params = world.params();
    let n = strand.nodes();
    let mut e = 0.0;
    for i in 2..n {
        let m = f64::from(strand.rest.mass[i]);
        let (x, v) = (
            to_f64(strand.state.position[i]),
            to_f64(strand.state.velocity[i]),
        );
        let g = to_f64(params.gravity);
        e += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
            - m * (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]);
    }
    match params.solver {
        Solver::Rod => {
            let frames = RodFrames::<Libm, N>::compute(
                &strand.state.position[..n],
                strand.state.root_frame,
                &strand.rest.rod.rest_length,
            );
            let theta = &strand.state.theta[..n - 1];
            let rest = &strand.rest.rod;
            e += f64::from(elastic_energy(&frames, theta, rest, ElasticTerms::ALL));
        }
        Solver::Dftl if params.effects.contains(Effect::Shape) => e += dftl_shape_energy(world),
        Solver::Dftl => {}
    }
    for grab in world.grabs() {
        if let (Some(c), GrabStatus::Held) = (grab.coupling, grab.status) {
            let x = strand.state.position[grab.node as usize];
            let d = to_f64(x - grab.target);
            e += 0.5 * f64::from(c.stiffness) * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        }
    }
    e
}

/// The energy DFTL's shape springs store (head still, coefficients that do not fade): a
/// correction `s (p − x*)` each step is an implicit spring of stiffness `k = m/α` with
/// `s = Δt²/(Δt² + α)` (`docs/architecture.md`, "DFTL with shape"), so the global constraint
/// stores `½ k_g |p_i − x_i|²` (`p_i` the rest position) and the local one
/// `½ k_l |x_{i−1} + R_{i−1} r_i − x_i|²`, with the frames `R` carried from the root along the
/// strand as the step carries them. A strand a grab holds has no global constraint
/// (`pipeline::dftl::step_held_strand`).
fn dftl_shape_energy(world: &Hair) -> f64 {
    let strand = &world.strands()[0];
    let params = world.params();
    let dt = f64::from(params.dt);
    let c = params.dftl.at_step(params.dt);
    let alpha = |s: Real| dt * dt * (1.0 - f64::from(s)) / f64::from(s);
    let held = world.grabs().iter().any(|g| g.status == GrabStatus::Held);
    let (alpha_global, alpha_local) = (alpha(c.global_shape), alpha(c.local_shape));
    let x = |i: usize| to_f64(strand.state.position[i]);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let scale = |a: [f64; 3], s: f64| a.map(|c| c * s);
    let add = |a: [f64; 3], b: [f64; 3]| [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
    let (mut t, mut nrm) = (
        to_f64(strand.rest.dftl.root_tangent),
        to_f64(strand.rest.dftl.root_normal),
    );
    let mut e = 0.0;
    for i in 2..strand.nodes() {
        let m = f64::from(strand.rest.mass[i]);
        let rest = to_f64(strand.rest.position[i]);
        if !held {
            let global = sub(rest, x(i));
            e += 0.5 * m / alpha_global * dot(global, global);
        }
        let r = to_f64(strand.rest.dftl.local_rest[i]);
        let target = add(
            x(i - 1),
            add(
                add(scale(t, r[0]), scale(nrm, r[1])),
                scale(cross(t, nrm), r[2]),
            ),
        );
        let local = sub(target, x(i));
        e += 0.5 * m / alpha_local * dot(local, local);
        // The frame carried to node i by the minimal rotation (`dftl::frame::transport`).
        let edge = sub(x(i), x(i - 1));
        let next = scale(edge, 1.0 / dot(edge, edge).sqrt());
        let k = cross(t, next);
        let cos = dot(t, next);
        nrm = add(
            add(scale(nrm, cos), cross(k, nrm)),
            scale(k, dot(k, nrm) / (1.0 + cos)),
        );
        t = next;
    }
    e
}

/// A random smooth path about `centre`: per axis, six sines of frequencies from 0.1 to 30 Hz
/// (log-uniform), with amplitudes scaled so that the path stays within `radius` of the centre
/// and moves at most 1 m/s.
struct SmoothPath {
    terms: Vec<[f64; 4]>, // axis, amplitude, angular frequency, phase
}

impl SmoothPath {
    fn new(seed: u64, radius: f64) -> Self {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut terms = Vec::new();
        for axis in 0..3 {
            let raw: Vec<[f64; 3]> = (0..6)
                .map(|_| {
                    let frequency = 0.1 * 300f64.powf(uniform());
                    [
                        uniform(),
                        2.0 * std::f64::consts::PI * frequency,
                        6.3 * uniform(),
                    ]
                })
                .collect();
            let reach: f64 = raw.iter().map(|r| r[0]).sum();
            let speed: f64 = raw.iter().map(|r| r[0] * r[1]).sum();
            // Each axis within radius/√3 and 1/√3 m/s: the whole path within both bounds (an
            // offset from the start spans twice the amplitudes).
            let s = (radius / (2.0 * reach)).min(1.0 / speed) / 3f64.sqrt();
            terms.extend(raw.iter().map(|r| [axis as f64, r[0] * s, r[1], r[2]]));
        }
        SmoothPath { terms }
    }

    /// The offset from the centre at time `t`, zero at `t = 0`.
    fn at(&self, t: f64) -> [f64; 3] {
        let mut p = [0.0; 3];
        for &[axis, a, w, phase] in &self.terms {
            p[axis as usize] += a * ((w * t + phase).sin() - phase.sin());
        }
        p
    }
}

/// What one passivity run found: the work the device did, its lowest excess over the bound,
/// and the energies.
struct Passivity {
    /// `W` at the end, J.
    work: f64,
    /// `Σ |F·Δx|`, J.
    absolute: f64,
    /// The smallest `W_k + (E(0) − min E) + 1e-3 Σ|F·Δx|` over the run: ≥ 0 when passive.
    margin: f64,
    /// `W + 1e-3 Σ|F·Δx|` at the end: ≥ 0 when passive.
    end_margin: f64,
}

/// One passivity run: node 20 of a 30-node strand grabbed at `dt`, its target brought in
/// 0.5 s from the node's rest to 13.6 cm from the root (72 % of the 19 cm of hair between),
/// left 1 s, then moved on the random path `seed` (within 4 cm of there, at most 1 m/s) for
/// 10 s, brought back to the start in 0.5 s and held 2 s. `W = Σ F_k · (x_{k+1} − x_k)` is the
/// work the device did on the hair, `F_k` the force on the hair over step `k`, which moves the
/// target from `x_k` to `x_{k+1}` (minus the force the device felt, `StepReport::grab_forces`).
/// A device that holds each step's force for the next step instead (a zero-order hold) adds
/// the hold's own energy, which `tests/haptic.rs`'s closed loop and its passivity bound are
/// about.
fn passivity_run(
    solver: Solver,
    dt: Real,
    mode: Mode,
    coupling: Option<Coupling>,
    seed: u64,
) -> Passivity {
    let mut world = world(params(solver, dt, mode, solver == Solver::Dftl), 30);
    let centre = Vec3::new(0.12, -0.08, 0.0);
    grab_and_bring(&mut world, 20, coupling, centre);
    let dt64 = f64::from(dt);
    let steps = |seconds: f64| (seconds / dt64).round() as usize;
    let blend = |a: Vec3, b: Vec3, s: f64| {
        let w = (0.5 - 0.5 * (std::f64::consts::PI * s.clamp(0.0, 1.0)).cos()) as Real;
        a + (b - a) * w
    };
    for _ in 0..steps(1.0) {
        world.step(&still());
    }
    let path = SmoothPath::new(seed, 0.04);
    let at = |t: f64| centre + Vec3::from_array(path.at(t).map(|c| c as Real));
    let end = at(10.0);
    let target = |k: usize| {
        let t = k as f64 * dt64;
        if t <= 10.0 {
            at(t)
        } else {
            blend(end, centre, (t - 10.0) / 0.5)
        }
    };
    let e0 = stored_energy(&world);
    let mut energies = vec![e0];
    let mut works = Vec::new();
    let (mut work, mut absolute) = (0.0, 0.0);
    let mut x = world.grabs()[0].target;
    for k in 1..=steps(12.5) {
        let next = target(k);
        world.set_grab_target(0, next);
        let report = world.step(&still());
        assert_eq!(
            world.grabs()[0].status,
            GrabStatus::Held,
            "seed {seed} step {k}"
        );
        assert!(report.grab_forces[0].is_finite());
        // Over the step the device moved from x to next, pushing the hair with minus the
        // force it felt.
        let dw = -f64::from(report.grab_forces[0].dot(next - x));
        work += dw;
        absolute += dw.abs();
        x = next;
        energies.push(stored_energy(&world));
        works.push((work, absolute));
    }
    let min_e = energies.iter().copied().fold(f64::INFINITY, f64::min);
    let margin = works
        .iter()
        .map(|&(w, a)| w + (e0 - min_e) + 1.0e-3 * a)
        .fold(f64::INFINITY, f64::min);
    Passivity {
        work,
        absolute,
        margin,
        end_margin: work + 1.0e-3 * absolute,
    }
}

/// Passive, both solvers: 20 seeds of random smooth target paths, at dt 0.5, 1 and 4 ms,
/// prescribed and coupled. The device never gets back more than the energy the hair stored
/// at the start above its lowest (`W ≥ −(E(0) − min E) − 1e-3 Σ|F·Δx|` at every step), and
/// over the whole path, back at the start, it has done work on the hair, not taken it
/// (`W ≥ −1e-3 Σ|F·Δx|`).
#[test]
fn a_device_moving_the_hair_gets_no_energy_out_of_it() {
    use rayon::prelude::*;
    let mut cases = Vec::new();
    for solver in [Solver::Rod, Solver::Dftl] {
        for dt in [0.0005, 0.001, 0.004] {
            for coupling in [None, Some(Coupling::new(1.0, 0.002))] {
                cases.push((solver, dt, coupling));
            }
        }
    }
    let results: Vec<_> = cases
        .par_iter()
        .map(|&(solver, dt, coupling)| {
            let runs: Vec<Passivity> = (0..20)
                .map(|seed| passivity_run(solver, dt, Mode::Converge, coupling, seed))
                .collect();
            (solver, dt, coupling, runs)
        })
        .collect();
    for (solver, dt, coupling, runs) in results {
        let worst = runs.iter().map(|r| r.margin).fold(f64::INFINITY, f64::min);
        let worst_end = runs
            .iter()
            .map(|r| r.end_margin)
            .fold(f64::INFINITY, f64::min);
        let work: f64 = runs.iter().map(|r| r.work).sum::<f64>() / runs.len() as f64;
        let absolute: f64 = runs.iter().map(|r| r.absolute).sum::<f64>() / runs.len() as f64;
        println!(
            "{solver:?} dt {dt} {coupling:?}: mean W {work:.3e} J of Σ|F·Δx| {absolute:.3e} J; worst margin {worst:.3e} J, at the end {worst_end:.3e} J"
        );
        assert!(
            worst >= 0.0,
            "{solver:?} dt {dt} {coupling:?}: margin {worst}"
        );
        assert!(
            worst_end >= 0.0,
            "{solver:?} dt {dt} {coupling:?}: end margin {worst_end}"
        );
    }
}

/// A closed haptic loop, both solvers (`hairsim::haptic`): a device of 0.1 kg with 0.3 N·s/m
/// of its own at 1 kHz (exact zero-order hold) renders the coupled grab of a 30-node strand's
/// tip with a gain that makes the taut strand 5 cm past its reach render 2 N against a hand of
/// 200 N/m and 2 N·s/m; the hand drags, holds and lets go, 100 times.
///
/// Within the sampled-data passivity bound (`G K T/2 + G B` = 0.42 b), every release gives
/// the device less kinetic energy than the coupling's spring held, and from its peak the
/// device slows exactly as a free device does (its kinetic energy at most 5 % above
/// `e^{−2bt/m}` of the peak: nothing pushes it) — so it falls to 1 % in the free device's
/// own 0.77 s, no later. (A device whose own damping is `b` cannot stop faster than that after
/// the hand lets go: the coupling, a spring to a strand that goes slack as the device springs
/// back toward the head, has nothing to brake it with.) Past the bound (4 b) the coupling
/// gives back more energy than it held: what the bound prevents.
#[test]
fn a_closed_loop_gives_back_no_more_than_its_coupling_held() {
    use hairsim::haptic::{run, LoopSetup};
    use rayon::prelude::*;
    let cases: Vec<(Solver, f64, Real)> = [Solver::Rod, Solver::Dftl]
        .into_iter()
        .flat_map(|solver| [(solver, 50.0, 0.002), (solver, 2400.0, 0.0)])
        .collect();
    let results: Vec<_> = cases
        .par_iter()
        .map(|&(solver, gain, damping)| {
            let setup = LoopSetup::standard(solver, gain, damping);
            (setup, run(&setup))
        })
        .collect();
    for (setup, pulls) in results {
        assert_eq!(pulls.len(), setup.pulls);
        assert!(pulls.iter().all(|p| p.held && p.peak_energy.is_finite()));
        let given_back = pulls
            .iter()
            .map(|p| p.peak_energy / p.released_energy)
            .fold(0.0, f64::max);
        let above = pulls.iter().map(|p| p.above_free_decay).fold(0.0, f64::max);
        let slowest = pulls
            .iter()
            .map(|p| p.settle.unwrap_or(f64::INFINITY))
            .fold(0.0, f64::max);
        let held = pulls.iter().map(|p| p.held_force).sum::<f64>() / pulls.len() as f64;
        let (solver, ratio) = (setup.solver, setup.bound_ratio());
        println!(
            "{solver:?}, bound ratio {ratio:.2}: held {held:.3} N; kinetic energy after a release at most {given_back:.3} of the spring's; at most {above:.3}× a free device's decay; 1 % after at most {slowest:.3} s (a free device: {:.3} s)",
            setup.free_settle()
        );
        if ratio <= 1.0 {
            assert!((held / 2.0 - 1.0).abs() < 0.05, "{solver:?}: {held} N");
            assert!(given_back < 1.0, "{solver:?}: {given_back}");
            assert!(above < 1.05, "{solver:?}: {above}");
            assert!(
                slowest <= 1.02 * setup.free_settle(),
                "{solver:?}: {slowest}"
            );
        } else {
            assert!(given_back > 1.0, "{solver:?} past the bound: {given_back}");
        }
    }
}

/// The example scene `scenes/tug.toml` (two grabs tug at one wisp, the tip's let go at 1 s)
/// with `solver = "dftl"`: DFTL holds both grabs, the strand inextensible between them, and
/// reports both forces.
#[test]
fn tug_holds_both_grabs_with_dftl() {
    use hairsim::scene::Scene;
    use hairsim::sim::{scene_inputs, Sim};
    use hairsim_core::DefaultMath;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/tug.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let text = text
        .replace("solver = \"rod\"", "solver = \"dftl\"")
        .replace("\"bending\", \"twist\", ", "");
    assert!(text.contains("solver = \"dftl\"") && !text.contains("\"twist\""));
    let (_, prepared) =
        Scene::parse_and_prepare(&text, "tug.toml", std::path::Path::new("scenes")).unwrap();
    let mut sim = Sim::<32, DefaultMath>::new(&prepared, 1).unwrap();
    let mut largest: Real = 0.0;
    for k in 0..950 {
        let report = sim.step(&scene_inputs::<DefaultMath>(&prepared, k));
        assert!(
            sim.grabs.iter().all(|g| g.status == GrabStatus::Held),
            "step {k}: {:?}",
            sim.grabs
        );
        assert!(report.grab_forces[..2].iter().all(|f| f.length() > 0.0));
        largest = largest.max(report.max_stretch);
    }
    println!("tug with DFTL: largest stretch {largest:.2e}");
    assert!(largest <= 1.0e-3, "{largest}");
}
