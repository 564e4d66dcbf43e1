//! A closed haptic loop around a coupled grab, for testing and for choosing a coupling: a
//! simulated device (a mass with its own damping on each axis) whose position is the grab's
//! target each tick and which is pushed by the force the coupling renders, times a gain,
//! through an exact zero-order hold at the loop's rate; and a hand (a spring and a damper to an
//! anchor) that drags the device past the strand's reach, holds it there and lets go.
//!
//! The sampled-data passivity bound of a virtual coupling (Colgate, Stanley and Brown 1995;
//! Adams and Hannaford 1999) is `b > K T/2 + |B|`, with `b` the device's own damping, `T` the
//! loop's period and `K`, `B` the stiffness and damping the device renders: the gain times the
//! coupling's ([`LoopSetup::bound_ratio`]). `docs/haptics.md` says how to choose them.

use hairsim_core::{
    Coupling, Effect, Effects, Grab, GrabStatus, Libm, Material, Mode, Params, Pose, Real, Solver,
    StepInput, Strand, Vec3, World,
};

/// Node capacity of the loop's strand.
const N: usize = 32;

/// A haptic device, the same on each axis: a mass with viscous damping of its own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Device {
    /// kg.
    pub mass: f64,
    /// `b`, N·s/m.
    pub damping: f64,
}

/// The hand holding the device: a spring and a damper to an anchor the hand moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hand {
    /// N/m.
    pub stiffness: f64,
    /// N·s/m.
    pub damping: f64,
}

/// One closed-loop experiment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopSetup {
    /// The solver of the strand.
    pub solver: Solver,
    /// The loop's period `T` (and the simulation's step), s.
    pub period: Real,
    /// The device.
    pub device: Device,
    /// The hand.
    pub hand: Hand,
    /// The grab's coupling (the hair's side).
    pub coupling: Coupling,
    /// The gain `G` from the coupling's force to the force the device renders.
    pub gain: f64,
    /// Nodes of the strand (1 cm segments).
    pub nodes: usize,
    /// How far past the strand's reach the hand's anchor drags the device, m.
    pub overshoot: f64,
    /// Seconds the hand takes to drag, holds, and waits after letting go.
    pub drag: f64,
    /// See `drag`.
    pub hold: f64,
    /// See `drag`.
    pub after: f64,
    /// How many times the hand drags and lets go.
    pub pulls: usize,
}

impl LoopSetup {
    /// The loop: a device of 0.1 kg with 0.3 N·s/m of its own at 1 kHz, a hand of
    /// 200 N/m and 2 N·s/m that drags the device 5 cm past a 30-node strand's reach over
    /// 0.5 s, holds 0.5 s and lets go, 100 times; the coupling 1 N/m and `damping` N·s/m on the
    /// hair's side, rendered with gain `gain`.
    #[must_use]
    pub fn standard(solver: Solver, gain: f64, damping: Real) -> Self {
        LoopSetup {
            solver,
            period: 0.001,
            device: Device {
                mass: 0.1,
                damping: 0.3,
            },
            hand: Hand {
                stiffness: 200.0,
                damping: 2.0,
            },
            coupling: Coupling::new(1.0, damping),
            gain,
            nodes: 30,
            overshoot: 0.05,
            drag: 0.5,
            hold: 0.5,
            after: 1.0,
            pulls: 100,
        }
    }

    /// Seconds a free device's kinetic energy takes to fall to 1 % (`e^{−2bt/m}`): with no
    /// force on it after the release, `m ln 100 / (2b)`, 0.77 s for the standard device.
    #[must_use]
    pub fn free_settle(&self) -> f64 {
        self.device.mass * 100f64.ln() / (2.0 * self.device.damping)
    }

    /// `(G K T/2 + G |B|) / b`: below 1 the rendered coupling is within the sampled-data
    /// passivity bound.
    #[must_use]
    pub fn bound_ratio(&self) -> f64 {
        let t = f64::from(self.period);
        let k = self.gain * f64::from(self.coupling.stiffness);
        let b = self.gain * f64::from(self.coupling.damping);
        (k * t / 2.0 + b.abs()) / self.device.damping
    }
}

/// What one pull did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pull {
    /// The force the device rendered at the end of the hold, N.
    pub held_force: f64,
    /// The energy in the rendered coupling's spring when the hand let go, J.
    pub released_energy: f64,
    /// The device's largest kinetic energy after the release, J.
    pub peak_energy: f64,
    /// Seconds from that peak until the kinetic energy stays below 1 % of it (`None`: not
    /// within the wait after the release).
    pub settle: Option<f64>,
    /// The largest ratio of the kinetic energy after the peak to a free device's from the
    /// same peak (`peak · e^{−2b(t − t_peak)/m}`): above 1, something pushed the device.
    pub above_free_decay: f64,
    /// The device's kinetic energy at the end of the wait, J.
    pub final_energy: f64,
    /// Whether the grab held through the pull (its limit is 1000 N).
    pub held: bool,
}

/// The state of the device: position and velocity per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
struct State {
    x: [f64; 3],
    v: [f64; 3],
}

/// The hand's anchor at a time: where it is and how fast it moves (`None`: let go).
type Anchor = Option<([f64; 3], [f64; 3])>;

/// The device over one period with the rendered force `force` held (zero-order hold) and the
/// hand's anchor moving from `from` at constant velocity: classical Runge–Kutta in 50
/// substeps, far finer than the device's dynamics (its fastest mode with the hand is below
/// 100 rad/s).
fn advance(
    device: &Device,
    hand: &Hand,
    state: State,
    force: [f64; 3],
    anchor: Anchor,
    t: f64,
) -> State {
    const SUBSTEPS: usize = 50;
    let h = t / SUBSTEPS as f64;
    let acceleration = |s: &State, time: f64| -> [f64; 3] {
        core::array::from_fn(|a| {
            let hand_force = anchor.map_or(0.0, |(p, u)| {
                let anchor_at = p[a] + u[a] * time;
                hand.stiffness * (anchor_at - s.x[a]) + hand.damping * (u[a] - s.v[a])
            });
            (force[a] + hand_force - device.damping * s.v[a]) / device.mass
        })
    };
    let mut s = state;
    let mut time = 0.0;
    for _ in 0..SUBSTEPS {
        let k1 = (s.v, acceleration(&s, time));
        let at = |k: &([f64; 3], [f64; 3]), f: f64| State {
            x: core::array::from_fn(|a| s.x[a] + f * h * k.0[a]),
            v: core::array::from_fn(|a| s.v[a] + f * h * k.1[a]),
        };
        let s2 = at(&k1, 0.5);
        let k2 = (s2.v, acceleration(&s2, time + 0.5 * h));
        let s3 = at(&k2, 0.5);
        let k3 = (s3.v, acceleration(&s3, time + 0.5 * h));
        let s4 = at(&k3, 1.0);
        let k4 = (s4.v, acceleration(&s4, time + h));
        s = State {
            x: core::array::from_fn(|a| {
                s.x[a] + h / 6.0 * (k1.0[a] + 2.0 * k2.0[a] + 2.0 * k3.0[a] + k4.0[a])
            }),
            v: core::array::from_fn(|a| {
                s.v[a] + h / 6.0 * (k1.1[a] + 2.0 * k2.1[a] + 2.0 * k3.1[a] + k4.1[a])
            }),
        };
        time += h;
    }
    s
}

fn kinetic(device: &Device, s: &State) -> f64 {
    0.5 * device.mass * s.v.iter().map(|v| v * v).sum::<f64>()
}

fn to_vec3(x: [f64; 3]) -> Vec3 {
    Vec3::new(x[0] as Real, x[1] as Real, x[2] as Real)
}

/// The world of the loop: one strand of `nodes` nodes 1 cm apart along +x from the origin,
/// held by a still head, its tip grabbed through `coupling` (limit 1000 N: it never slips).
fn hair(setup: &LoopSetup) -> World<1, N, Libm> {
    let mut effects = Effects::from_slice(&[
        Effect::Gravity,
        Effect::Drag,
        Effect::Inextensibility,
        Effect::Grabs,
    ]);
    effects = match setup.solver {
        Solver::Rod => effects.with(Effect::Bending).with(Effect::Twist),
        Solver::Dftl => effects.with(Effect::Shape),
    };
    let params = Params {
        solver: setup.solver,
        dt: setup.period,
        mode: Mode::FixedCost,
        effects,
        drag: 2.0e-7,
        ..Params::DEFAULT
    };
    let mut world = World::with_params(params).expect("the loop's parameters are valid");
    let points: Vec<Vec3> = (0..setup.nodes)
        .map(|i| Vec3::new(0.01 * i as Real, 0.0, 0.0))
        .collect();
    let strand = Strand::from_polyline(&points, &Material::HUMAN_HAIR).expect("a valid strand");
    world.add_strand(strand).expect("room for one strand");
    let tip = (setup.nodes - 1) as u32;
    let grab = Grab::new(0, tip, points[setup.nodes - 1], 1000.0).with_coupling(setup.coupling);
    world.add_grab(grab).expect("a valid grab");
    world
}

/// Runs the loop: each pull, the hand takes the device where it is and drags its anchor to
/// `overshoot` past the strand's reach along +x (from node 1, at the strand's rest length)
/// in `drag` seconds, holds `hold` seconds and lets go; the device is then watched for
/// `after` seconds.
#[must_use]
pub fn run(setup: &LoopSetup) -> Vec<Pull> {
    let mut world = hair(setup);
    let device = setup.device;
    let t = f64::from(setup.period);
    let ticks = |seconds: f64| (seconds / t).round() as usize;
    let reach = 0.01 + 0.01 * (setup.nodes - 2) as f64;
    let goal = [reach + setup.overshoot, 0.0, 0.0];
    let tip = world.grabs()[0].target;
    let mut state = State {
        x: [f64::from(tip.x), f64::from(tip.y), f64::from(tip.z)],
        v: [0.0; 3],
    };
    let mut force = [0.0; 3];
    let mut tick = |state: &mut State, force: &mut [f64; 3], anchor: Anchor| {
        *state = advance(&device, &setup.hand, *state, *force, anchor, t);
        world.set_grab_target(0, to_vec3(state.x));
        let report = world.step(&StepInput {
            head: Pose::IDENTITY,
            accelerations: None,
        });
        let felt = report.grab_forces[0];
        *force = [felt.x, felt.y, felt.z].map(|f| setup.gain * f64::from(f));
        world.grabs()[0].status == GrabStatus::Held
    };
    let mut pulls = Vec::with_capacity(setup.pulls);
    for _ in 0..setup.pulls {
        let start = state.x;
        let n = ticks(setup.drag);
        let velocity: [f64; 3] = core::array::from_fn(|a| (goal[a] - start[a]) / setup.drag);
        let mut held = true;
        for k in 0..n {
            let from = core::array::from_fn(|a| start[a] + velocity[a] * k as f64 * t);
            held &= tick(&mut state, &mut force, Some((from, velocity)));
        }
        for _ in 0..ticks(setup.hold) {
            held &= tick(&mut state, &mut force, Some((goal, [0.0; 3])));
        }
        let held_force = force.iter().map(|f| f * f).sum::<f64>().sqrt();
        let stiffness = setup.gain * f64::from(setup.coupling.stiffness);
        let released_energy = 0.5 * held_force * held_force / stiffness;
        let mut energies = Vec::with_capacity(ticks(setup.after));
        for _ in 0..ticks(setup.after) {
            held &= tick(&mut state, &mut force, None);
            energies.push(kinetic(&device, &state));
        }
        let (peak_at, peak_energy) =
            energies
                .iter()
                .copied()
                .enumerate()
                .fold(
                    (0, 0.0),
                    |best, (k, e)| if e > best.1 { (k, e) } else { best },
                );
        let last_above = energies
            .iter()
            .rposition(|&e| e >= 0.01 * peak_energy)
            .unwrap_or(peak_at);
        let settle =
            (last_above + 1 < energies.len()).then(|| (last_above + 1 - peak_at) as f64 * t);
        let rate = 2.0 * device.damping / device.mass;
        let above_free_decay = energies[peak_at..]
            .iter()
            .enumerate()
            .map(|(k, &e)| e / (peak_energy * (-rate * k as f64 * t).exp()))
            .fold(0.0, f64::max);
        pulls.push(Pull {
            held_force,
            released_energy,
            peak_energy,
            settle,
            above_free_decay,
            final_energy: energies.last().copied().unwrap_or(0.0),
            held,
        });
        if !held || !state.x.iter().chain(&state.v).all(|c| c.is_finite()) {
            break;
        }
    }
    pulls
}
