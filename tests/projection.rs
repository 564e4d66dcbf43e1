//! The fast manifold projection through `World`: a head shaking at 10 rad/s with hair draped
//! on it, grabs holding and slipping, fixed cost. Every figure is checked against the
//! positions themselves (not only against what the report says).

use hairsim_core::collide::{Collider, Shape};
use hairsim_core::{
    Effect, Effects, Flags, Grab, GrabStatus, Libm, Material, Mode, Params, Pose, Real, Shake,
    StepInput, StepReport, Strand, Vec3, World,
};

const STRANDS: usize = 8;
const NODES: usize = 32;
const HEAD_RADIUS: Real = 0.1;

type HairWorld = World<STRANDS, NODES, Libm>;

fn params(mode: Mode) -> Params {
    Params {
        effects: Effects::from_slice(&[
            Effect::Gravity,
            Effect::Inextensibility,
            Effect::Collisions,
            Effect::Grabs,
        ]),
        mode,
        ..Params::DEFAULT
    }
}

/// 30-node strands of 1 cm segments rooted on the upper half of a 10 cm head that moves with
/// the head, leaving it along the normal: under gravity they fall onto the head and drape.
fn head_with_hair(mode: Mode) -> Box<HairWorld> {
    let mut world: Box<HairWorld> = Box::new(World::with_params(params(mode)).unwrap());
    world
        .add_collider(Collider {
            shape: Shape::Sphere {
                centre: Vec3::ZERO,
                radius: HEAD_RADIUS,
            },
            attached_to_head: true,
        })
        .unwrap();
    for s in 0..STRANDS {
        let azimuth = s as Real * 0.785;
        let polar = 0.3 + 0.12 * (s % 3) as Real;
        let normal = Vec3::new(
            polar.sin() * azimuth.cos(),
            polar.cos(),
            polar.sin() * azimuth.sin(),
        );
        // Roots 1 mm outside the surface, so that the prescribed nodes are never inside.
        let root = normal * (HEAD_RADIUS + 0.001);
        let points: Vec<Vec3> = (0..30)
            .map(|i| root + normal * (0.01 * i as Real))
            .collect();
        world
            .add_strand(Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap())
            .unwrap();
    }
    world
}

fn shaking(k: u32) -> StepInput<'static> {
    StepInput {
        head: Shake::TEN_RAD_PER_S.pose_at::<Libm>((k + 1) as Real * 0.001),
        accelerations: None,
    }
}

fn still() -> StepInput<'static> {
    StepInput {
        head: Pose::IDENTITY,
        accelerations: None,
    }
}

/// Largest `| |e| − |ê| | / |ê|` over every segment of every strand, in f64.
fn max_stretch(world: &HairWorld) -> f64 {
    let mut worst: f64 = 0.0;
    for strand in world.strands() {
        let x = strand.positions();
        for j in 0..x.len() - 1 {
            let e = x[j + 1] - x[j];
            let length =
                (f64::from(e.x).powi(2) + f64::from(e.y).powi(2) + f64::from(e.z).powi(2)).sqrt();
            let rest = f64::from(strand.rest.segment_length[j]);
            worst = worst.max((length - rest).abs() / rest);
        }
    }
    worst
}

/// Deepest free node inside the head sphere, m, in f64.
fn max_depth(world: &HairWorld) -> f64 {
    let centre = world.head().position;
    let mut worst: f64 = 0.0;
    for strand in world.strands() {
        for x in &strand.positions()[2..] {
            let d = *x - centre;
            let distance =
                (f64::from(d.x).powi(2) + f64::from(d.y).powi(2) + f64::from(d.z).powi(2)).sqrt();
            worst = worst.max(f64::from(HEAD_RADIUS) - distance);
        }
    }
    worst
}

#[test]
fn shaking_at_ten_rad_per_second_keeps_length_and_stays_out_of_the_head() {
    let mut world = head_with_hair(Mode::Converge);
    let (mut worst_stretch, mut worst_depth, mut contacts, mut cap_hits) = (0.0f64, 0.0f64, 0, 0);
    let mut worst_reported: Real = 0.0;
    for k in 0..1500 {
        let report = world.step(&shaking(k));
        assert!(
            !report.flags.contains(Flags::ROLLED_BACK),
            "step {k}: {report:?}"
        );
        worst_stretch = worst_stretch.max(max_stretch(&world));
        worst_depth = worst_depth.max(max_depth(&world));
        worst_reported = worst_reported.max(report.max_stretch.max(report.max_contact_stretch));
        contacts += report.contacts;
        cap_hits += report.cap_hits;
        assert!(
            report.max_penetration <= 1.0e-4,
            "step {k}: {}",
            report.max_penetration
        );
    }
    println!(
        "stretch {worst_stretch:.3e} (reported {worst_reported:.3e}), depth {worst_depth:.3e} m, \
         {contacts} node contacts, {cap_hits} cap hits over 1500 steps × {STRANDS} strands"
    );
    assert!(
        contacts > 1000,
        "the hair must lie on the head: {contacts} contacts"
    );
    assert!(worst_stretch <= 1.0e-3, "stretch {worst_stretch}");
    assert!(
        worst_depth <= 1.0e-4,
        "a node {worst_depth} m inside the head"
    );
    // The report tells the same story as the positions.
    assert!((f64::from(worst_reported) - worst_stretch).abs() <= 1e-5 + 0.01 * worst_stretch);
}

/// A strand hanging straight down from its root, grabbed at node 2 where it hangs: the grab
/// holds every node from 2 down (segment 1 joins two prescribed nodes and carries nothing).
fn hanging_strand(force_limit: Real) -> (Box<HairWorld>, Real) {
    let mut p = params(Mode::Converge);
    p.effects = Effects::from_slice(&[Effect::Gravity, Effect::Inextensibility, Effect::Grabs]);
    let mut world: Box<HairWorld> = Box::new(World::with_params(p).unwrap());
    let points: Vec<Vec3> = (0..30)
        .map(|i| Vec3::new(0.0, -0.01 * i as Real, 0.0))
        .collect();
    let strand = Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap();
    let held_weight = strand.rest.mass[2..30].iter().sum::<Real>() * 9.81;
    world.add_strand(strand).unwrap();
    world
        .add_grab(Grab::new(0, 2, points[2], force_limit))
        .unwrap();
    (world, held_weight)
}

#[test]
fn a_grab_holding_a_hanging_strand_feels_the_weight_it_holds() {
    let (mut world, weight) = hanging_strand(1.0);
    let mut report = StepReport::default();
    for _ in 0..200 {
        report = world.step(&still());
    }
    let force = report.grab_forces[0];
    println!(
        "grab force {force} N, weight held {weight} N, relative error {:.2e}",
        (force.y + weight).abs() / weight
    );
    // Downward (the device feels the hair pull), equal to the weight within 1 %.
    assert!(
        (force.y + weight).abs() <= 0.01 * weight,
        "{force} vs weight {weight}"
    );
    assert!(force.x.abs() + force.z.abs() <= 1e-3 * weight);
    assert_eq!(world.grabs()[0].status, GrabStatus::Held);
    assert_eq!(report.grabs_slipped, 0);
    // Without the grabbed node's own weight the force would read low by m_2 g / W (≈ 3.6 %):
    // the check above could not pass.
    let own = world.strands()[0].rest.mass[2] * 9.81;
    assert!(own > 0.02 * weight);
    // A held node follows its target exactly, with the velocity of the move: 1 mm sideways,
    // swung about node 1 so that it stays within the 1 cm of hair from there (a target out
    // of reach slips, `grab::slip_unreachable`).
    let start = world.strands()[0].positions()[2];
    let target = Vec3::new(0.001, -0.01 - (0.01f32 * 0.01 - 0.001 * 0.001).sqrt(), 0.0);
    world.set_grab_target(0, target);
    let report = world.step(&still());
    assert_eq!(report.grabs_slipped, 0);
    let strand = &world.strands()[0];
    assert_eq!(strand.positions()[2], target);
    let expected = (target - start) / 0.001;
    assert!((strand.state.velocity[2] - expected).length() < 1e-3);
}

#[test]
fn a_grab_past_its_force_limit_slips_and_lets_go() {
    // The same strand, its grab limited to half the weight it holds.
    let (_, weight) = hanging_strand(1.0);
    let (mut world, _) = hanging_strand(0.5 * weight);
    let report = world.step(&still());
    assert!(report.flags.contains(Flags::GRAB_SLIPPED), "{report:?}");
    assert_eq!(report.grabs_slipped, 1);
    assert!(report.grab_forces[0].length() > 0.5 * weight);
    assert_eq!(world.grabs()[0].status, GrabStatus::Slipped);
    // A slipped grab no longer pins: moving its target 5 cm away leaves the node where the
    // strand holds it, and the grab reports no force.
    let before = world.strands()[0].positions()[2];
    world.set_grab_target(0, before + Vec3::new(0.05, 0.0, 0.0));
    for _ in 0..20 {
        let report = world.step(&still());
        assert_eq!(report.grab_forces[0], Vec3::ZERO);
        assert_eq!(report.grabs_slipped, 0);
    }
    let after = world.strands()[0].positions()[2];
    assert!(
        (after - before).length() < 1e-3,
        "node 2 went to the target: {after}"
    );
    // The grab that holds within its limit keeps holding.
    let (mut strong, _) = hanging_strand(2.0 * weight);
    for _ in 0..20 {
        assert_eq!(strong.step(&still()).grabs_slipped, 0);
    }
    assert_eq!(strong.grabs()[0].status, GrabStatus::Held);
}

#[test]
fn fixed_cost_iterations_do_not_depend_on_the_state() {
    let mut calm = head_with_hair(Mode::FixedCost);
    let mut violent = head_with_hair(Mode::FixedCost);
    let cap = u32::from(params(Mode::FixedCost).rod.projection_iterations);
    for k in 0..300 {
        let a = calm.step(&still());
        let b = violent.step(&shaking(k * 7));
        assert_eq!(a.iterations_total, b.iterations_total, "step {k}");
        assert_eq!(a.iterations_max, cap);
        assert_eq!(b.iterations_total, cap * STRANDS as u32);
    }
    // In converge mode the same two states need different work.
    let mut calm = head_with_hair(Mode::Converge);
    let mut violent = head_with_hair(Mode::Converge);
    let (mut a, mut b) = (0, 0);
    for k in 0..300 {
        a += calm.step(&still()).iterations_total;
        b += violent.step(&shaking(k * 7)).iterations_total;
    }
    assert!(a < b, "converge mode: calm {a}, violent {b} iterations");
}

/// A small deterministic generator (xorshift) for the garbage test.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f32) as usize).min(n - 1)
    }
    fn point(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * scale
    }
}

/// What a fuzz target would do, on a budget: arbitrary strands, colliders (valid or not) and
/// grabs (valid or not) straight into `project_constraints`. It never panics, keeps finite
/// input finite, stays within the cap and reports a residual no smaller than the truth.
#[test]
fn projection_survives_arbitrary_strands_colliders_and_grabs() {
    use hairsim_core::context::StepContext;
    use hairsim_core::project_constraints;
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    for case in 0..3000 {
        let nodes = 3 + rng.below(NODES - 2);
        let rest: Vec<Vec3> = (0..nodes)
            .map(|i| Vec3::new(0.01 * i as Real, 0.0, 0.0))
            .collect();
        let mut strand: Strand<NODES> =
            Strand::from_polyline(&rest, &Material::HUMAN_HAIR).unwrap();
        let scale = [0.01, 0.3, 10.0, 1.0e4][rng.below(4)];
        for i in 2..nodes {
            strand.state.position[i] = match rng.below(4) {
                0 => strand.state.position[i - 1], // coincident with the previous node
                1 => Vec3::ZERO,                   // the sphere's centre below
                _ => rng.point(scale),
            };
        }
        let mut colliders = Vec::new();
        for _ in 0..rng.below(5) {
            let shape = match rng.below(4) {
                0 => Shape::Sphere {
                    centre: Vec3::ZERO,
                    radius: rng.next() * 0.2,
                },
                1 => Shape::Capsule {
                    a: rng.point(0.3),
                    b: rng.point(0.3),
                    radius: rng.next() * 0.05,
                },
                2 => Shape::Plane {
                    point: rng.point(0.3),
                    normal: Vec3::Y,
                },
                // Not unit: an invalid collider the projection must skip.
                _ => Shape::Plane {
                    point: Vec3::ZERO,
                    normal: Vec3::new(0.0, 3.0, 0.0),
                },
            };
            colliders.push(Collider {
                shape,
                attached_to_head: false,
            });
        }
        let grabs: Vec<Grab> = (0..rng.below(4))
            .map(|_| {
                Grab::new(
                    rng.below(2) as u32,
                    rng.below(nodes + 2) as u32,
                    rng.point(0.5),
                    0.1,
                )
            })
            .collect();
        let mode = if case % 2 == 0 {
            Mode::Converge
        } else {
            Mode::FixedCost
        };
        let p = params(mode);
        let ctx = StepContext::new(&p, Pose::IDENTITY, Pose::IDENTITY, &colliders);
        let mut report = StepReport::default();
        let outcome = project_constraints::<Libm, NODES>(&mut strand, &ctx, &grabs, 0, &mut report);
        let cap = u32::from(p.rod.projection_iterations);
        assert!(outcome.iterations <= cap, "case {case}");
        assert!(strand.is_finite(), "case {case}: {:?}", strand.positions());
        assert!(
            report.residual.is_finite() && report.max_penetration.is_finite(),
            "case {case}: {report:?} {outcome:?} {colliders:?} {:?}",
            strand.positions()
        );
        assert!(
            report.grab_forces.iter().all(|f| f.is_finite()),
            "case {case}"
        );
        assert!(
            report.collider_forces.iter().all(|f| f.is_finite()),
            "case {case}"
        );
        // Honest: no segment is further from its length than the residual says.
        let x = strand.positions();
        for j in 0..nodes - 1 {
            let e = x[j + 1] - x[j];
            let l = strand.rest.segment_length[j];
            let relative = (e.dot(e) - l * l).abs() / (l * l);
            let prescribed = j < 1
                || grabs.iter().any(|g| {
                    g.strand == 0
                        && (g.node as usize == j || g.node as usize == j + 1)
                        && g.node >= 2
                });
            if !prescribed {
                assert!(
                    relative <= outcome.residual * 1.001 + 1e-6,
                    "case {case}: segment {j} {relative} > {}",
                    outcome.residual
                );
            }
        }
    }
}
