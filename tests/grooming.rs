//! The groom scenes and their measures (`tests/groom.rs`): a DFTL scene still, shaken, and
//! displaced, at a given `dt`, measured on the simulated nodes.
//!
//! The scenes: the sample files `sintel_hair.tfx` and `Ratboy_mohawk.tfx` (their default
//! scenes, through `HAIRSIM_SAMPLES`), the built-in `head-3` with its solver switched to DFTL,
//! and `scenes/curly-head.toml`; each with DFTL + shape + gravity + collisions (and the scene's
//! drag), the head still unless a measure moves it.

use hairsim::groom::{measure, Groom};
use hairsim::run::{load, HairFileOptions};
use hairsim::scene::{Prepared, Scene};
use hairsim::sim::{Layout, Sim, StepInputs};
use hairsim_core::{DefaultMath, Pose, Quat, Real, Shake, Strand, Vec3};

/// The strand capacity of every groom scene (the curly head has 40 nodes).
pub const CAPACITY: usize = 40;

/// A simulation of a groom scene.
pub type GroomSim = Sim<CAPACITY, DefaultMath>;

/// The groom scenes, by name.
pub const SCENES: [&str; 4] = ["sintel", "ratboy", "head-3", "curly-head"];

/// The sample folder (`HAIRSIM_SAMPLES`); a missing folder or file fails the test.
fn sample(file: &str) -> String {
    let folder = std::env::var("HAIRSIM_SAMPLES")
        .expect("HAIRSIM_SAMPLES must name the folder of the sample hair files");
    let path = std::path::Path::new(&folder).join(file);
    assert!(path.exists(), "{}: missing sample file", path.display());
    path.display().to_string()
}

/// The scene `name` as written, before the groom test's changes.
fn scene_as_written(name: &str) -> Scene {
    let spec = match name {
        "sintel" => sample("sintel_hair.tfx"),
        "ratboy" => sample("Ratboy_mohawk.tfx"),
        "head-3" => "head-3".to_string(),
        "curly-head" => concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/curly-head.toml").into(),
        other => panic!("{other}: not a groom scene"),
    };
    load(&spec, &HairFileOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .scene
}

/// The scene `name` as the groom test runs it: DFTL + shape + gravity + collisions, the
/// scene's drag, the head still, 1 s, at `dt`.
#[must_use]
pub fn groom_scene(name: &str, solver: &str, dt: Real) -> Prepared {
    groom_from(scene_as_written(name), name, solver, dt)
}

/// `scene` (called `name`) as the groom test runs it.
fn groom_from(mut scene: Scene, name: &str, solver: &str, dt: Real) -> Prepared {
    scene.solver = solver.into();
    let mut effects = vec!["gravity", "drag", "inextensibility", "collisions"];
    effects.extend(if solver == "dftl" {
        &["shape"][..]
    } else {
        &["bending", "twist"][..]
    });
    scene.effects = effects.iter().map(|e| (*e).to_string()).collect();
    scene.drag = scene.drag.or(Some(2.0e-7));
    scene.dt = dt;
    scene.steps = None;
    scene.duration = Some(1.0);
    scene.head = None;
    scene.output = None;
    scene
        .prepare()
        .unwrap_or_else(|e| panic!("{name} at {dt}: {e}"))
}

/// A simulation of `prepared`, strand by strand or in blocks.
#[must_use]
pub fn simulation(prepared: &Prepared, layout: Layout) -> GroomSim {
    Sim::with_layout(prepared, 1, layout).expect("the groom scene builds")
}

/// Steps needed for `seconds` at `dt`.
#[must_use]
pub fn steps_for(seconds: Real, dt: Real) -> u64 {
    (seconds / dt).round() as u64
}

/// Whether step `k` (0-based, time `(k + 1) dt` after it) ends on a multiple of 50 ms: the
/// groom is sampled there (every 50th step at 1 ms; every step that reaches a new 50 ms at
/// larger steps).
#[must_use]
pub fn sampled(k: u64, dt: Real) -> bool {
    let period = 0.05;
    let before = (k as Real * dt / period).floor();
    let after = ((k + 1) as Real * dt / period).floor();
    after > before
}

/// A still head for one step.
#[must_use]
pub fn held(pose: Pose) -> StepInputs {
    StepInputs {
        head: pose,
        grab_targets: Vec::new(),
        released: Vec::new(),
    }
}

/// The worse of two grooms (by mean turning angle and by kinked share, each on its own).
#[must_use]
pub fn worse(a: Groom, b: Groom) -> Groom {
    Groom {
        mean_turning: a.mean_turning.max(b.mean_turning),
        kinked: a.kinked.max(b.kinked),
        ..b
    }
}

/// What a still run measures: the worst groom sampled over the last 0.5 s of 1 s, the mean
/// tip sag after 1 s, and the largest stretch seen.
#[derive(Clone, Copy, Debug)]
pub struct Still {
    /// The worst groom sampled over the last 0.5 s.
    pub groom: Groom,
    /// The rest groom's mean turning angle, rad.
    pub rest_turning: Real,
    /// Mean over strands of the tip's drop along gravity from its rest position after 1 s, m.
    pub sag: Real,
    /// The largest relative stretch any step reported.
    pub stretch: Real,
    /// Nodes a collider pushed out per step, on average over the last 0.5 s.
    pub contacts: Real,
}

/// Runs `prepared` still for 1 s.
#[must_use]
pub fn still(prepared: &Prepared, layout: Layout) -> Still {
    let dt = prepared.params.dt;
    let mut sim = simulation(prepared, layout);
    let mut groom: Option<Groom> = None;
    let mut stretch: Real = 0.0;
    let (mut contacts, mut late_steps) = (0u64, 0u64);
    let steps = steps_for(1.0, dt);
    for k in 0..steps {
        let report = sim.step(&held(Pose::IDENTITY));
        stretch = stretch.max(report.max_stretch);
        let late = (k + 1) as Real * dt > 0.5 + 0.5 * dt;
        if late {
            contacts += u64::from(report.contacts);
            late_steps += 1;
        }
        if late && sampled(k, dt) {
            let now = measure(&sim.strands);
            groom = Some(groom.map_or(now, |g| worse(g, now)));
        }
    }
    let groom = groom.unwrap_or_else(|| measure(&sim.strands));
    Still {
        groom,
        rest_turning: groom.rest_mean_turning,
        sag: mean_sag(&sim.strands, prepared.params.gravity),
        stretch,
        contacts: contacts as Real / late_steps.max(1) as Real,
    }
}

/// Mean over strands of the tip's drop along `gravity` from its rest position, the head at
/// rest.
fn mean_sag(strands: &[Strand<CAPACITY>], gravity: Vec3) -> Real {
    let down = gravity.normalize_or_zero();
    let drops: Vec<Real> = strands
        .iter()
        .map(|s| {
            let tip = s.rest.nodes.min(CAPACITY) - 1;
            (s.state.position[tip] - s.rest.position[tip]).dot(down)
        })
        .collect();
    drops.iter().sum::<Real>() / drops.len().max(1) as Real
}

/// The shaken head: about Kmoch's axis (vertical, through the origin), the angle
/// `A (1 − cos 2π f t)` with `A = 0.5` rad and `f = 10 / (2π A)` ≈ 3.18 Hz, so the angular
/// speed `2π f A sin 2π f t` peaks at 10 rad/s, for two periods (0.63 s); then held. It starts
/// and stops at rest: a head that jumps from rest to 10 rad/s in one step (the sine of
/// `Shake::TEN_RAD_PER_S`) yanks every strand, and a strand catching up moves faster than
/// the head at its place at any step size (1.04 m/s over it at 16.7 ms before this fix).
#[must_use]
pub fn shaken_pose(t: Real) -> Pose {
    let shake = Shake::TEN_RAD_PER_S;
    let omega = 10.0 / shake.amplitude;
    let t = t.clamp(0.0, shake_end());
    let angle = shake.amplitude * (1.0 - (omega * t).cos());
    let rotation = Quat::from_axis_angle(shake.axis, angle);
    Pose {
        position: shake.centre - rotation * shake.centre,
        rotation,
    }
}

/// When the shake stops: after two periods, at rest.
#[must_use]
pub fn shake_end() -> Real {
    let omega = 10.0 / Shake::TEN_RAD_PER_S.amplitude;
    2.0 * core::f32::consts::TAU / omega
}

/// What a shaken run measures.
#[derive(Clone, Copy, Debug)]
pub struct Shaken {
    /// Mean over strands and steps of the tip's distance from its rest position in the head's
    /// frame while the head shakes, m.
    pub excursion: Real,
    /// The largest excess of a node's speed over the head's rigid motion at its position,
    /// m/s (the flutter bound is 1 m/s).
    pub speed_excess: Real,
    /// The worst groom sampled over the last 0.5 s of the 1 s still after the shake.
    pub groom_after: Groom,
    /// The largest relative stretch any step reported.
    pub stretch: Real,
}

/// Runs `prepared` shaken at 10 rad/s until [`shake_end`], then still for 1 s.
#[must_use]
pub fn shaken(prepared: &Prepared, layout: Layout) -> Shaken {
    let dt = prepared.params.dt;
    let mut sim = simulation(prepared, layout);
    let (mut excursion, mut samples) = (0.0f64, 0u64);
    let (mut speed_excess, mut stretch): (Real, Real) = (0.0, 0.0);
    let mut groom_after: Option<Groom> = None;
    let mut before = Pose::IDENTITY;
    let end = shake_end();
    for k in 0..steps_for(end + 1.0, dt) {
        let t = (k + 1) as Real * dt;
        let pose = shaken_pose(t);
        let report = sim.step(&held(pose));
        stretch = stretch.max(report.max_stretch);
        speed_excess = speed_excess.max(excess_speed(&sim.strands, before, pose, dt));
        before = pose;
        if t <= end + 0.5 * dt {
            excursion += tip_excursion(&sim.strands, pose);
            samples += 1;
        }
        if t > end + 0.5 + 0.5 * dt && sampled(k, dt) {
            let now = measure(&sim.strands);
            groom_after = Some(groom_after.map_or(now, |g| worse(g, now)));
        }
    }
    Shaken {
        excursion: (excursion / samples.max(1) as f64) as Real,
        speed_excess,
        groom_after: groom_after.unwrap_or_else(|| measure(&sim.strands)),
        stretch,
    }
}

/// Mean over strands of the tip's distance from its rest position in the frame of the head
/// at `pose`.
fn tip_excursion(strands: &[Strand<CAPACITY>], pose: Pose) -> f64 {
    let inverse = pose.rotation.inverse();
    let sum: f64 = strands
        .iter()
        .map(|s| {
            let tip = s.rest.nodes.min(CAPACITY) - 1;
            let in_head = inverse * (s.state.position[tip] - pose.position);
            f64::from((in_head - s.rest.position[tip]).length())
        })
        .sum();
    sum / strands.len().max(1) as f64
}

/// The largest `|v| − |v_rigid| ` over the free nodes, `v_rigid` being the velocity of the
/// point at the node's position carried rigidly by the head from `before` to `after` over
/// `dt`.
fn excess_speed(strands: &[Strand<CAPACITY>], before: Pose, after: Pose, dt: Real) -> Real {
    let back: Quat = before.rotation * after.rotation.inverse();
    let mut worst: Real = 0.0;
    for s in strands {
        for i in 2..s.rest.nodes.min(CAPACITY) {
            let x = s.state.position[i];
            let earlier = back * (x - after.position) + before.position;
            let rigid = (x - earlier) / dt;
            let excess = s.state.velocity[i].length() - rigid.length();
            worst = if excess.is_finite() {
                worst.max(excess)
            } else {
                Real::INFINITY
            };
        }
    }
    worst
}

/// The time a displaced groom takes to relax back: every strand's free nodes turned 0.3 rad
/// about its node 1 (about the horizontal axis across the strand), then the head held still;
/// the time after which the mean tip distance from an undisturbed run's stays under 10 % of
/// its start, s (`None`: not within 1.5 s).
#[must_use]
pub fn relaxation_time(prepared: &Prepared, layout: Layout) -> Option<Real> {
    let dt = prepared.params.dt;
    let mut undisturbed = simulation(prepared, layout);
    let mut displaced = simulation(prepared, layout);
    for s in &mut displaced.strands {
        displace(s, 0.3);
    }
    let start = tip_distance(&displaced.strands, &undisturbed.strands);
    let threshold = 0.1 * start;
    // The last time the distance crossed the threshold downwards, interpolated linearly
    // between the two steps around the crossing (a step of 16.7 ms is too coarse to read).
    let (mut crossing, mut previous) = (Some(0.0), start);
    let steps = steps_for(1.5, dt);
    for k in 0..steps {
        undisturbed.step(&held(Pose::IDENTITY));
        displaced.step(&held(Pose::IDENTITY));
        let distance = tip_distance(&displaced.strands, &undisturbed.strands);
        if distance > threshold {
            crossing = None;
        } else if crossing.is_none() || k == 0 {
            let fraction = (previous - threshold) / (previous - distance);
            crossing = crossing.or(Some((k as Real + fraction) * dt));
        }
        previous = distance;
    }
    crossing
}

/// Turns the free nodes of `strand` by `angle` about node 1, about the horizontal axis across
/// the strand's root segment (velocities zero).
fn displace(strand: &mut Strand<CAPACITY>, angle: Real) {
    let n = strand.rest.nodes.min(CAPACITY);
    let pivot = strand.state.position[1];
    let along = (strand.state.position[1] - strand.state.position[0]).normalize_or_zero();
    let mut axis = along.cross(Vec3::Y).normalize_or_zero();
    if axis == Vec3::ZERO {
        axis = Vec3::X;
    }
    let turn = Quat::from_axis_angle(axis, angle);
    for i in 2..n {
        strand.state.position[i] = pivot + turn * (strand.state.position[i] - pivot);
        strand.state.velocity[i] = Vec3::ZERO;
    }
}

/// Mean over strands of the distance between the tips of `a` and `b`.
fn tip_distance(a: &[Strand<CAPACITY>], b: &[Strand<CAPACITY>]) -> Real {
    let sum: Real = a
        .iter()
        .zip(b)
        .map(|(x, y)| {
            let tip = x.rest.nodes.min(CAPACITY) - 1;
            (x.state.position[tip] - y.state.position[tip]).length()
        })
        .sum();
    sum / a.len().max(1) as Real
}

/// Radius of the generated head the combed groom rests on, m.
pub const COMBED_HEAD_RADIUS: f64 = 0.09;

/// The generated groom resting on a head sphere of [`COMBED_HEAD_RADIUS`] about the origin:
/// 300 strands of 40 nodes and 25 cm, rooted 2 mm outside the sphere on a cap of 1.1 rad
/// about +y (a Fibonacci spiral), combed down the meridians over the sphere, on its surface
/// from 2 cm on, and hanging straight down past its equator; every other strand wavy (5 mm
/// across, 5 cm wavelength, the wave in the surface) and the others curly (a helix of 5 mm
/// radius and 3 cm pitch whose inner side touches the sphere). The rest groom lies on the
/// sphere and nowhere inside it: gravity alone presses it on.
#[must_use]
pub fn combed_strands() -> Vec<Vec<Vec3>> {
    let leaders = 300;
    let cap: f64 = 1.1;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..leaders)
        .map(|k| {
            let y = 1.0 - (1.0 - cap.cos()) * (k as f64 + 0.5) / leaders as f64;
            let ring = (1.0 - y * y).max(0.0).sqrt();
            let phi = golden * k as f64;
            let normal = [ring * phi.cos(), y, ring * phi.sin()];
            let dense = combed_centreline(normal, k % 2 == 0);
            resample(&dense, 40, 0.25)
        })
        .collect()
}

/// A 3-vector in `f64`.
type D3 = [f64; 3];

fn add(a: D3, b: D3, s: f64) -> D3 {
    [a[0] + b[0] * s, a[1] + b[1] * s, a[2] + b[2] * s]
}

fn dot(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(a: D3) -> D3 {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

fn cross(a: D3, b: D3) -> D3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A combed strand rooted at the unit `normal` of the head, as a dense polyline (0.1 mm apart
/// along the comb, longer than the strand).
fn combed_centreline(normal: D3, wavy: bool) -> Vec<D3> {
    let radius = COMBED_HEAD_RADIUS;
    let (lift, landing) = (0.002, 0.02);
    // Down the meridian: the unit tangent at the root pointing away from the crown.
    let down = if normal[1] > 1.0 - 1e-9 {
        [1.0, 0.0, 0.0]
    } else {
        unit(add([0.0, -1.0, 0.0], normal, normal[1]))
    };
    // The arc to the equator, where the meridian turns vertical; then straight down.
    let to_equator = radius * (std::f64::consts::FRAC_PI_2 - normal[1].clamp(-1.0, 1.0).acos());
    (0..4000)
        .map(|j| {
            let s = 1e-4 * f64::from(j);
            let angle = s.min(to_equator) / radius;
            let out = add(normal.map(|v| v * angle.cos()), down, angle.sin());
            let along = add(down.map(|v| v * angle.cos()), normal, -angle.sin());
            let side = cross(along, out);
            let height = radius + lift * (1.0 - s / landing).max(0.0).powi(2);
            let on = add(
                out.map(|v| v * height),
                [0.0, -1.0, 0.0],
                (s - to_equator).max(0.0),
            );
            if wavy {
                let across = 0.005 * (std::f64::consts::TAU * s / 0.05).sin();
                let p = add(on, side, across);
                // On the sphere, the wave stays on its surface (at the lifted root's height).
                if s < to_equator {
                    unit(p).map(|v| v * height)
                } else {
                    p
                }
            } else {
                let (helix, pitch) = (0.005, 0.03);
                let turn = std::f64::consts::TAU * s / pitch;
                let p = add(on, out, helix * (1.0 - turn.cos()));
                add(p, side, helix * turn.sin())
            }
        })
        .collect()
}

/// `nodes` points equally spaced by arc length along the first `length` of `dense`.
fn resample(dense: &[D3], nodes: usize, length: f64) -> Vec<Vec3> {
    let mut arc = vec![0.0];
    for w in dense.windows(2) {
        let d = add(w[1], w[0], -1.0);
        arc.push(arc[arc.len() - 1] + dot(d, d).sqrt());
    }
    let mut j = 0;
    (0..nodes)
        .map(|i| {
            let s = length * i as f64 / (nodes - 1) as f64;
            while arc[j + 1] < s {
                j += 1;
            }
            let f = (s - arc[j]) / (arc[j + 1] - arc[j]);
            let p = add(dense[j], add(dense[j + 1], dense[j], -1.0), f);
            Vec3::new(p[0] as Real, p[1] as Real, p[2] as Real)
        })
        .collect()
}

/// The resting grooms: a sample file in `hairsim run`'s default scene, whose head sphere
/// touches its scalp, and the generated [`combed_strands`].
pub const RESTING: [&str; 2] = ["sintel-on-head", "combed"];

/// The resting groom `name` as [`groom_scene`] runs a groom (DFTL + shape + gravity +
/// collisions, drag, the head still, 1 s at `dt`), its head sphere `shrink` m smaller.
#[must_use]
pub fn resting_scene(name: &str, dt: Real, shrink: Real) -> Prepared {
    let mut scene = match name {
        "sintel-on-head" => scene_as_written("sintel"),
        "combed" => {
            // head-3 (a 10 cm sphere, DFTL's default shape) with the combed strands.
            let mut scene = scene_as_written("head-3");
            scene.hair = None;
            scene.strands = combed_strands()
                .into_iter()
                .map(|points| hairsim::scene::StrandSpec {
                    points: Some(points.iter().map(|p| p.to_array()).collect()),
                    ..Default::default()
                })
                .collect();
            scene.colliders[0].radius = Some(COMBED_HEAD_RADIUS as Real);
            scene
        }
        other => panic!("{other}: not a resting groom"),
    };
    for collider in &mut scene.colliders {
        if let Some(r) = collider.radius.as_mut() {
            *r -= shrink;
        }
    }
    groom_from(scene, name, "dftl", dt)
}
