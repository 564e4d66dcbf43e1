//! Unit tests of the projection, each against something computed independently of it.

use super::*;
use crate::collide::Collider;
use crate::effects::Effects;
use crate::grab::GrabStatus;
use crate::head::Pose;
use crate::math::Libm;
use crate::params::Params;
use crate::strand::Material;
use std::vec::Vec;

const N: usize = 32;

fn params(effects: &[Effect], mode: Mode, iterations: u16, tolerance: Real) -> Params {
    let mut p = Params {
        effects: Effects::from_slice(effects),
        mode,
        ..Params::DEFAULT
    };
    p.rod.projection_iterations = iterations;
    p.rod.projection_tolerance = tolerance;
    p
}

fn context(params: &Params, colliders: &[Collider]) -> StepContext {
    StepContext::new(params, Pose::IDENTITY, Pose::IDENTITY, colliders)
}

/// A sphere that does not move with the head.
fn still_sphere(centre: Vec3, radius: Real) -> Collider {
    Collider {
        shape: Shape::Sphere { centre, radius },
        attached_to_head: false,
    }
}

/// A straight strand of `nodes` nodes 1 cm apart along `direction` from `root`.
fn line(nodes: usize, root: Vec3, direction: Vec3) -> Strand<N> {
    let points: [Vec3; N] = core::array::from_fn(|i| root + direction * (0.01 * i as Real));
    Strand::from_polyline(&points[..nodes], &Material::HUMAN_HAIR).unwrap()
}

/// `max_j |e·e − ê·ê| / ê·ê`, computed here in f64 from the positions.
fn relative_residual(strand: &Strand<N>) -> f64 {
    let x = strand.positions();
    (0..x.len() - 1)
        .map(|j| {
            let e = [
                x[j + 1].x - x[j].x,
                x[j + 1].y - x[j].y,
                x[j + 1].z - x[j].z,
            ]
            .map(f64::from);
            let l = f64::from(strand.rest.segment_length[j]);
            (e[0] * e[0] + e[1] * e[1] + e[2] * e[2] - l * l).abs() / (l * l)
        })
        .fold(0.0, f64::max)
}

/// What f32 positions can resolve of `|e·e − ê·ê| / ê·ê` for 1 cm segments within 0.3 m of
/// the origin: a few ulps of the coordinates over the segment length.
const F32_FLOOR: f64 = 1.0e-5;

/// Perturbs the free nodes deterministically (a violent unconstrained step).
fn shake_nodes(strand: &mut Strand<N>, amplitude: Real) {
    for i in 2..strand.nodes() {
        let k = i as Real;
        strand.state.position[i] +=
            Vec3::new((k * 1.7).sin(), (k * 2.3).cos(), (k * 0.9).sin()) * amplitude;
    }
}

#[test]
fn converge_mode_stops_at_the_tolerance() {
    let mut used = [0u32; 2];
    for (slot, tolerance) in [1.0e-2, 1.0e-6].into_iter().enumerate() {
        let p = params(&[Effect::Inextensibility], Mode::Converge, 50, tolerance);
        let ctx = context(&p, &[]);
        let mut strand = line(20, Vec3::ZERO, Vec3::X);
        shake_nodes(&mut strand, 0.004);
        let before = relative_residual(&strand);
        let mut report = StepReport::default();
        let outcome = project_constraints::<Libm, N>(&mut strand, &ctx, &[], 0, &mut report);
        let after = relative_residual(&strand);
        assert!(
            before > 0.1,
            "the test needs a real violation, got {before}"
        );
        assert!(outcome.converged && (outcome.residual <= tolerance || tolerance < 1e-5));
        assert!(
            after <= f64::from(tolerance) + F32_FLOOR,
            "residual {after} above {tolerance}"
        );
        assert!((after - f64::from(outcome.residual)).abs() <= F32_FLOOR);
        assert_eq!(report.cap_hits, 0);
        assert!(!report.flags.contains(Flags::CAP_HIT));
        assert!(outcome.iterations < 50);
        used[slot] = outcome.iterations;
    }
    // A looser tolerance stops earlier: converge mode does not run the cap.
    assert!(used[0] < used[1], "iterations {used:?}");
}

#[test]
fn a_low_cap_is_reported_as_a_cap_hit_with_the_true_residual() {
    let p = params(&[Effect::Inextensibility], Mode::Converge, 1, 1.0e-6);
    let ctx = context(&p, &[]);
    let mut strand = line(20, Vec3::ZERO, Vec3::X);
    shake_nodes(&mut strand, 0.004);
    let mut report = StepReport::default();
    let outcome = project_constraints::<Libm, N>(&mut strand, &ctx, &[], 0, &mut report);
    assert_eq!(outcome.iterations, 1);
    assert!(report.flags.contains(Flags::CAP_HIT) && report.cap_hits == 1);
    let truth = relative_residual(&strand);
    assert!(truth > 1e-6);
    assert!((f64::from(report.residual) - truth).abs() <= 1e-3 * truth + F32_FLOOR);
}

#[test]
fn velocities_take_the_position_change_over_h() {
    let p = params(&[Effect::Inextensibility], Mode::Converge, 20, 1.0e-6);
    let ctx = context(&p, &[]);
    let mut strand = line(10, Vec3::ZERO, Vec3::X);
    shake_nodes(&mut strand, 0.002);
    let predicted = strand.state.clone();
    let mut report = StepReport::default();
    project_constraints::<Libm, N>(&mut strand, &ctx, &[], 0, &mut report);
    for i in 0..10 {
        let delta_x = strand.state.position[i] - predicted.position[i];
        let expected = predicted.velocity[i] + delta_x * ctx.inv_dt;
        assert!((strand.state.velocity[i] - expected).length() <= 1e-4 * (1.0 + expected.length()));
        if i < 2 {
            assert_eq!(delta_x, Vec3::ZERO, "root nodes are prescribed");
        }
    }
    assert_eq!(report.runs(Stage::Velocity), 1);
}

#[test]
fn effects_that_are_off_compute_nothing() {
    let p = params(&[Effect::Gravity], Mode::Converge, 8, 1.0e-6);
    let ctx = context(&p, &[]);
    let mut strand = line(10, Vec3::ZERO, Vec3::X);
    shake_nodes(&mut strand, 0.002);
    let before = strand.clone();
    let mut report = StepReport::default();
    project_constraints::<Libm, N>(&mut strand, &ctx, &[], 0, &mut report);
    assert_eq!(strand, before);
    assert_eq!(report, StepReport::default());
    // Collisions alone: no segment rows, so the stretch stays, but nodes leave the collider.
    let floor = Collider {
        shape: Shape::Plane {
            point: Vec3::new(0.0, 0.001, 0.0),
            normal: Vec3::Y,
        },
        attached_to_head: false,
    };
    let p = params(&[Effect::Collisions], Mode::Converge, 8, 1.0e-6);
    let ctx = context(&p, &[floor]);
    let mut report = StepReport::default();
    project_constraints::<Libm, N>(&mut strand, &ctx, &[], 0, &mut report);
    assert_eq!(report.runs(Stage::Collisions), 1);
    assert!(
        relative_residual(&strand) > 0.1,
        "no inextensibility row was built"
    );
    assert!(strand.positions()[2..].iter().all(|x| x.y >= 0.001 - 1e-7));
}

#[test]
fn nodes_end_outside_every_shape_with_segments_at_length() {
    let shapes = [
        Shape::Sphere {
            centre: Vec3::new(0.05, -0.03, 0.0),
            radius: 0.04,
        },
        Shape::Capsule {
            a: Vec3::new(0.0, 0.0, -0.1),
            b: Vec3::new(0.2, 0.0, 0.1),
            radius: 0.015,
        },
        Shape::Plane {
            point: Vec3::new(0.0, 0.004, 0.0),
            normal: Vec3::Y,
        },
    ];
    for shape in shapes {
        let collider = Collider {
            shape,
            attached_to_head: false,
        };
        let p = params(
            &[Effect::Inextensibility, Effect::Collisions],
            Mode::Converge,
            30,
            1.0e-6,
        );
        let ctx = context(&p, &[collider]);
        let mut strand = line(20, Vec3::new(0.0, 0.02, 0.0), Vec3::X);
        // Sink the free nodes: some end up inside the shape.
        for i in 2..20 {
            strand.state.position[i].y -= 0.02;
        }
        let mut report = StepReport::default();
        let outcome = project_constraints::<Libm, N>(&mut strand, &ctx, &[], 0, &mut report);
        assert!(report.contacts > 0, "{shape:?}: the test needs contacts");
        for (i, x) in strand.positions().iter().enumerate().skip(2) {
            let depth = shape.penetration::<Libm>(*x).map_or(0.0, |c| c.depth);
            assert!(depth <= 1e-7, "{shape:?}: node {i} {depth} m deep");
        }
        let truth = relative_residual(&strand);
        assert!(truth <= 1e-6 + F32_FLOOR, "{shape:?}: {truth}");
        assert!(outcome.converged && !report.flags.contains(Flags::CAP_HIT));
        assert!(f64::from(outcome.residual) <= 1e-6 + F32_FLOOR);
        assert!(report.max_penetration <= 1e-7);
    }
}

#[test]
fn a_strand_lying_on_a_floor_presses_on_it_with_its_weight() {
    // Horizontal strand on the plane y = 0, at rest: every step gravity sinks the free nodes
    // by h²g and the contact rows lift them back. The floor must feel the free nodes' weight.
    let floor = Collider {
        shape: Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        },
        attached_to_head: false,
    };
    let p = params(
        &[Effect::Gravity, Effect::Inextensibility, Effect::Collisions],
        Mode::Converge,
        8,
        1.0e-6,
    );
    let mut world = crate::world::World::<1, N, Libm>::with_params(p).unwrap();
    world.add_collider(floor).unwrap();
    world.add_strand(line(30, Vec3::ZERO, Vec3::X)).unwrap();
    let input = crate::world::StepInput {
        head: Pose::IDENTITY,
        accelerations: None,
    };
    let mut report = StepReport::default();
    for _ in 0..50 {
        report = world.step(&input);
    }
    let strand = &world.strands()[0];
    let free_weight: Real = strand.rest.mass[2..30].iter().sum::<Real>() * 9.81;
    let force = report.collider_forces[0];
    assert!(
        (force.y + free_weight).abs() <= 0.01 * free_weight,
        "{force} vs {free_weight}"
    );
    assert!(force.x.abs() + force.z.abs() <= 1e-3 * free_weight);
    assert_eq!(report.contacts, 28);
    assert!(report.max_contact_stretch <= 1e-5 && report.max_penetration <= 1e-7);
}

#[test]
fn garbage_gives_finite_positions_and_an_honest_residual() {
    let sphere = Collider {
        shape: Shape::Sphere {
            centre: Vec3::new(0.05, 0.0, 0.0),
            radius: 0.02,
        },
        attached_to_head: false,
    };
    let effects = [Effect::Inextensibility, Effect::Collisions, Effect::Grabs];
    for mode in [Mode::Converge, Mode::FixedCost] {
        for case in 0..4 {
            let p = params(&effects, mode, 8, 1.0e-6);
            let ctx = context(&p, &[sphere]);
            let mut strand = line(12, Vec3::ZERO, Vec3::X);
            match case {
                // Every free node at one point.
                0 => (2..12).for_each(|i| strand.state.position[i] = Vec3::new(0.3, 0.3, 0.3)),
                // Huge stretch: a node 100 m away.
                1 => strand.state.position[7] = Vec3::new(100.0, -50.0, 20.0),
                // A node exactly at the sphere's centre, its neighbours at one point.
                2 => {
                    strand.state.position[5] = Vec3::new(0.05, 0.0, 0.0);
                    strand.state.position[6] = strand.state.position[7];
                }
                // All of it, with a grab on a node next to the root and one on a far node.
                _ => {
                    (2..6).for_each(|i| strand.state.position[i] = Vec3::new(0.05, 0.0, 0.0));
                    strand.state.position[9] = Vec3::new(1.0e4, 0.0, 0.0);
                }
            }
            let grabs = [
                Grab::new(0, 2, Vec3::new(0.02, 0.0, 0.0), 1.0),
                Grab::new(0, 11, Vec3::new(-3.0, 0.0, 0.0), 1.0),
            ];
            let grabs = if case == 3 { &grabs[..] } else { &[] };
            let mut report = StepReport::default();
            let outcome = project_constraints::<Libm, N>(&mut strand, &ctx, grabs, 0, &mut report);
            assert!(
                strand.is_finite(),
                "{mode:?} case {case}: {:?}",
                strand.positions()
            );
            assert!(outcome.residual.is_finite() && report.residual.is_finite());
            // Honest: the reported residual is the residual of the final positions (with any
            // node still inside the sphere), or larger when a contact remains.
            let truth = relative_residual(&strand);
            assert!(
                f64::from(outcome.residual) >= truth * (1.0 - 1e-3),
                "case {case}"
            );
            if outcome.residual > 1.0e-3 {
                assert!(!outcome.converged);
                assert!(
                    report.flags.contains(Flags::CAP_HIT),
                    "{mode:?} case {case}"
                );
            }
            if mode == Mode::FixedCost {
                assert_eq!(outcome.iterations, 8);
            }
        }
    }
}

#[test]
fn two_contacts_with_the_same_normal_are_dropped_not_divided_by() {
    // Two identical planes: two collision rows with the same gradient on each node inside.
    let plane = Collider {
        shape: Shape::Plane {
            point: Vec3::new(0.0, 0.001, 0.0),
            normal: Vec3::Y,
        },
        attached_to_head: false,
    };
    let p = params(
        &[Effect::Inextensibility, Effect::Collisions],
        Mode::Converge,
        8,
        1.0e-6,
    );
    let ctx = context(&p, &[plane, plane]);
    let mut strand = line(10, Vec3::ZERO, Vec3::X);
    let mut report = StepReport::default();
    let outcome = project_constraints::<Libm, N>(&mut strand, &ctx, &[], 0, &mut report);
    assert!(strand.is_finite());
    assert!(outcome.dropped_rows > 0 && report.flags.contains(Flags::SINGULAR));
    assert!(strand.positions()[2..].iter().all(|x| x.y >= 0.001 - 1e-7));
    assert!(relative_residual(&strand) <= 1e-6 + F32_FLOOR);
}

#[test]
fn fixed_cost_runs_the_cap_whatever_the_state() {
    let sphere = still_sphere(Vec3::new(0.05, -0.005, 0.0), 0.025);
    let effects = [Effect::Inextensibility, Effect::Collisions];
    let p = params(&effects, Mode::FixedCost, 6, 1.0e-6);
    let ctx = context(&p, &[sphere]);
    let mut calm = line(20, Vec3::new(0.0, 0.03, 0.0), Vec3::X);
    let mut violent = calm.clone();
    shake_nodes(&mut violent, 0.02);
    let (mut a, mut b) = (StepReport::default(), StepReport::default());
    let calm_outcome = project_constraints::<Libm, N>(&mut calm, &ctx, &[], 0, &mut a);
    let violent_outcome = project_constraints::<Libm, N>(&mut violent, &ctx, &[], 0, &mut b);
    assert_eq!(calm_outcome.iterations, 6);
    assert_eq!(violent_outcome.iterations, 6);
    assert_eq!(a.iterations_total, b.iterations_total);
    assert!(
        b.contacts > 0 && a.contacts == 0,
        "contacts {} and {}",
        a.contacts,
        b.contacts
    );
}

#[test]
fn grabbed_nodes_follow_the_rules() {
    let p = params(&[Effect::Grabs], Mode::Converge, 8, 1.0e-6);
    let ctx = context(&p, &[]);
    let target = Vec3::ONE;
    let mut released = Grab::new(0, 4, target, 1.0);
    released.status = GrabStatus::Released;
    let grabs = [
        Grab::new(0, 1, target, 1.0),     // a root node: refused
        Grab::new(1, 3, target, 1.0),     // another strand
        Grab::new(0, 5, target, 1.0),     // held
        Grab::new(0, 5, Vec3::ZERO, 1.0), // same node: the first one holds it
        released,                         // past MAX_GRABS anyway
    ];
    let held = grabbed_nodes(&ctx, &grabs, 0, 10);
    assert_eq!(held.len(), 1);
    assert_eq!(held.iter().next(), Some((2, 5)));
    assert!(held.contains(5) && !held.contains(3));
    assert_eq!(grabbed_nodes(&ctx, &grabs, 1, 10).grab_of(3), Some(1));
    assert!(
        grabbed_nodes(&ctx, &grabs, 0, 5).is_empty(),
        "node 5 of a 5-node strand"
    );
    let off = context(
        &params(&[Effect::Inextensibility], Mode::Converge, 8, 1e-6),
        &[],
    );
    assert!(
        grabbed_nodes(&off, &grabs, 0, 10).is_empty(),
        "grabs effect off"
    );
}

#[test]
fn the_box_test_never_misses_a_node_inside_and_culls_far_shapes() {
    // xorshift: deterministic points about the shapes, some far from the origin.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as Real / (1u64 << 24) as Real * 2.0 - 1.0
    };
    let mut inside = 0;
    for trial in 0..4000 {
        let offset = Vec3::new(next(), next(), next()) * if trial % 2 == 0 { 0.5 } else { 50.0 };
        let shape = match trial % 3 {
            0 => Shape::Sphere {
                centre: offset,
                radius: 0.1,
            },
            1 => Shape::Capsule {
                a: offset,
                b: offset + Vec3::new(0.2, -0.1, 0.05),
                radius: 0.03,
            },
            _ => Shape::Plane {
                point: offset,
                normal: Vec3::new(0.3, 0.9, -0.2).normalize(),
            },
        };
        let p = offset + Vec3::new(next(), next(), next()) * 0.15;
        if shape.penetration::<Libm>(p).is_some() {
            inside += 1;
            // The degenerate box of the point itself, and a box reaching away from it.
            assert!(may_touch_box(&shape, p, p), "trial {trial}: {shape:?} {p}");
            let far = p + Vec3::new(next(), next(), next()).abs();
            assert!(may_touch_box(&shape, p.min(far), p.max(far)));
        }
    }
    assert!(inside > 500, "only {inside} points inside");
    // A box a metre away misses every bounded shape, and the half-space it is in front of.
    let (low, high) = (Vec3::splat(1.0), Vec3::splat(1.3));
    let sphere = Shape::Sphere {
        centre: Vec3::ZERO,
        radius: 0.1,
    };
    let capsule = Shape::Capsule {
        a: Vec3::ZERO,
        b: Vec3::X * 0.5,
        radius: 0.1,
    };
    let floor = Shape::Plane {
        point: Vec3::ZERO,
        normal: Vec3::Y,
    };
    for shape in [sphere, capsule, floor] {
        assert!(!may_touch_box(&shape, low, high), "{shape:?}");
    }
}

#[test]
fn strands_far_from_a_collider_skip_it_and_strands_on_it_do_not() {
    let shapes = [
        (
            0,
            Shape::Sphere {
                centre: Vec3::new(0.0, -1.0, 0.0),
                radius: 0.1,
            },
        ),
        (
            1,
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Y,
            },
        ),
    ];
    // Lying on the floor y = 0, 1 m above the ball: only the floor is near.
    let mut strand = line(10, Vec3::new(0.0, 0.0, 0.0), Vec3::X);
    shake_nodes(&mut strand, 0.002);
    let mut work = Workspace::new(&strand, 10);
    let mut near = NearColliders::new(&strand, &work.nodes, &shapes, true);
    let found = near.shapes(&shapes);
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].0, 1);
    // After a move of 1 m the ball may be reached: it joins, in the step's order.
    near.moved::<Libm>(1.0);
    let found = near.shapes(&shapes);
    assert_eq!(
        found.iter().map(|s| s.0).collect::<std::vec::Vec<_>>(),
        [0, 1]
    );
    // Prescribed everywhere: nothing to test.
    work.nodes.inverse_mass = [0.0; N];
    let mut none = NearColliders::new(&strand, &work.nodes, &shapes, true);
    assert!(none.shapes(&shapes).is_empty());
}

#[test]
fn a_node_just_outside_that_moves_away_is_not_held() {
    // A strand 20 µm above a floor (within the tentative margin, 50 µm at 1 cm segments),
    // perturbed upward: the solve lifts the nodes, so every tentative row pulls and is
    // removed. The result is the projection without the floor, bit for bit, and the floor
    // feels nothing.
    let floor = Collider {
        shape: Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        },
        attached_to_head: false,
    };
    let mut strand = line(20, Vec3::new(0.0, 2.0e-5, 0.0), Vec3::X);
    for i in 2..20 {
        let k = i as Real;
        strand.state.position[i] += Vec3::new(0.0, 0.002 * (k * 1.3).sin().abs(), 0.0);
    }
    let mut results: [(Strand<N>, StepReport, Outcome); 2] =
        core::array::from_fn(|_| (strand.clone(), StepReport::default(), Outcome::default()));
    for (collisions, (strand, report, outcome)) in results.iter_mut().enumerate() {
        let effects: &[Effect] = if collisions == 1 {
            &[Effect::Inextensibility, Effect::Collisions]
        } else {
            &[Effect::Inextensibility]
        };
        let p = params(effects, Mode::Converge, 30, 1.0e-6);
        let ctx = context(&p, &[floor]);
        *outcome = project_constraints::<Libm, N>(strand, &ctx, &[], 0, report);
    }
    let [(free, _, free_outcome), (floored, report, outcome)] = &results;
    assert!(floored.positions().iter().all(|x| x.y > 0.0));
    assert_eq!(free.positions(), floored.positions());
    assert_eq!(free_outcome.iterations, outcome.iterations);
    assert_eq!(report.contacts, 0);
    assert_eq!(report.collider_forces[0], Vec3::ZERO);
}

#[test]
fn a_node_just_outside_that_the_segments_pull_in_is_held_in_the_same_iteration() {
    // A strand draped over a sphere 1 µm off its surface, every segment 1 % too long: the
    // solve shortens the segments, pulling the nodes onto their chords, into the sphere.
    // Tentative rows hold them at the surface in the first solve, so collisions cost no
    // iteration over the projection without the sphere, and the nodes end outside.
    let radius: Real = 0.1;
    let sphere = Collider {
        shape: Shape::Sphere {
            centre: Vec3::ZERO,
            radius,
        },
        attached_to_head: false,
    };
    // Rest shape: 1 cm chords of the circle of radius r + 1 µm in the x–y plane.
    let arc = radius + 1.0e-6;
    let step = 2.0 * libm::asinf(0.005 / arc);
    let on_arc = |i: usize, scale: Real| {
        let angle = 0.3 - step * scale * i as Real;
        Vec3::new(libm::cosf(angle), libm::sinf(angle), 0.0) * arc
    };
    let points: [Vec3; 15] = core::array::from_fn(|i| on_arc(i, 1.0));
    let rest = Strand::<N>::from_polyline(&points, &Material::HUMAN_HAIR).unwrap();
    let mut iterations = [0; 2];
    for (collisions, used) in iterations.iter_mut().enumerate() {
        let mut strand = rest.clone();
        for i in 2..15 {
            strand.state.position[i] = on_arc(i, 1.01);
        }
        let effects: &[Effect] = if collisions == 1 {
            &[Effect::Inextensibility, Effect::Collisions]
        } else {
            &[Effect::Inextensibility]
        };
        let p = params(effects, Mode::Converge, 30, 1.0e-6);
        let ctx = context(&p, &[sphere]);
        let mut report = StepReport::default();
        let outcome = project_constraints::<Libm, N>(&mut strand, &ctx, &[], 0, &mut report);
        assert!(outcome.converged);
        *used = outcome.iterations;
        if collisions == 1 {
            assert!(
                report.contacts > 5,
                "the test needs contacts: {}",
                report.contacts
            );
            for (i, x) in strand.positions().iter().enumerate() {
                let depth = sphere
                    .shape
                    .penetration::<Libm>(*x)
                    .map_or(0.0, |c| c.depth);
                assert!(depth <= 1e-7, "node {i} {depth} m deep");
            }
            // The hair presses on the sphere: towards its centre, here −x mostly.
            let force = report.collider_forces[0];
            assert!(force.dot(on_arc(7, 1.0)) < 0.0, "{force}");
        }
    }
    assert_eq!(iterations[0], iterations[1], "{iterations:?}");
}

/// `collision_rows` counts each collision row once per iterate a solve followed: in fixed-cost
/// mode (no tentative rows) one iteration solves the rows of the nodes inside the sphere at
/// the start, counted here from the positions; more iterations add the rows of their
/// iterates; a strand clear of the collider has none.
#[test]
fn collision_rows_count_each_row_once_per_solved_iterate() {
    let sphere = still_sphere(Vec3::new(0.05, -0.03, 0.0), 0.04);
    let effects = [Effect::Inextensibility, Effect::Collisions];
    let sunk = || {
        let mut strand = line(20, Vec3::new(0.0, 0.02, 0.0), Vec3::X);
        for i in 2..20 {
            strand.state.position[i].y -= 0.02;
        }
        strand
    };
    let start = sunk().state.position;
    let inside = (2..20)
        .filter(|&i| sphere.shape.penetration::<Libm>(start[i]).is_some())
        .count() as u32;
    assert!(inside > 3, "the test needs nodes inside: {inside}");
    let mut rows = [0; 2];
    for (k, cap) in [1, 6].into_iter().enumerate() {
        let p = params(&effects, Mode::FixedCost, cap, 1.0e-6);
        let ctx = context(&p, &[sphere]);
        for kernel in 0..2 {
            let (mut strand, mut report) = (sunk(), StepReport::default());
            let outcome = if kernel == 0 {
                project_constraints::<Libm, N>(&mut strand, &ctx, &[], 0, &mut report)
            } else {
                let mut scratch = lanes::BlockProjection::default();
                lanes::project_alone::<Libm, N>(&mut strand, &ctx, &mut scratch, &mut report)
            };
            assert_eq!(outcome.collision_rows, report.collision_rows);
            rows[k] = report.collision_rows;
        }
    }
    assert_eq!(rows[0], inside);
    assert!(rows[1] > rows[0] && rows[1] <= 6 * 18, "{rows:?}");
    let p = params(&effects, Mode::FixedCost, 6, 1.0e-6);
    let mut clear = line(20, Vec3::new(0.0, 0.2, 0.0), Vec3::X);
    let mut report = StepReport::default();
    project_constraints::<Libm, N>(&mut clear, &context(&p, &[sphere]), &[], 0, &mut report);
    assert_eq!(report.collision_rows, 0);
}

/// The bits of what a projection leaves: positions, velocities, outcome and report (but its
/// flags).
fn projected_bits(strand: &Strand<N>, outcome: &Outcome, report: &StepReport) -> Vec<u32> {
    let state = strand.state.position.iter().chain(&strand.state.velocity);
    let mut bits: Vec<u32> = state.flat_map(|v| v.to_array().map(f32::to_bits)).collect();
    bits.extend([outcome.iterations, outcome.residual.to_bits()]);
    bits.extend([u32::from(outcome.converged), outcome.dropped_rows]);
    bits.extend([outcome.collision_rows, report.collision_rows]);
    let measures = [
        report.residual,
        report.max_stretch,
        report.max_contact_stretch,
    ];
    bits.extend(measures.map(f32::to_bits));
    bits.extend([
        report.max_penetration.to_bits(),
        report.contacts,
        report.cap_hits,
    ]);
    bits.extend([report.iterations_total, report.dropped_rows]);
    bits.extend(report.stage_runs);
    let pushed = report.collider_forces.iter().flat_map(|f| f.to_array());
    bits.extend(pushed.map(f32::to_bits));
    bits
}

/// `lanes::project_strand` takes a strand that `lanes::fits_lanes` through the lanes' kernel
/// at one lane; the general kernel, `project_constraints`, must give that strand the same
/// bits: shaken strands, in both modes, with and without a sphere they fall into, converging,
/// stopped at a low cap, or stopped early by garbage.
#[test]
fn the_lanes_kernel_and_the_general_one_give_the_same_bits() {
    let sphere = Collider {
        shape: Shape::Sphere {
            centre: Vec3::new(0.1, -0.045, 0.0),
            radius: 0.05,
        },
        attached_to_head: false,
    };
    let (mut contacts, mut stopped) = (0, 0);
    for mode in [Mode::FixedCost, Mode::Converge] {
        for (effects, colliders) in [
            (&[Effect::Inextensibility][..], &[][..]),
            (
                &[Effect::Inextensibility, Effect::Collisions][..],
                &[sphere][..],
            ),
        ] {
            for (cap, tolerance) in [(8, 1.0e-6), (2, 1.0e-6), (20, 1.0e-3)] {
                let p = params(effects, mode, cap, tolerance);
                let ctx = context(&p, colliders);
                for k in 0..6 {
                    let direction = Vec3::new(1.0, -0.1 * k as Real, 0.05).normalize();
                    let mut strand = line(20, Vec3::ZERO, direction);
                    shake_nodes(&mut strand, 0.001 * (k + 1) as Real);
                    if k == 5 {
                        // Garbage: `e·e` overflows, the multipliers are not finite, the
                        // projection stops before its cap.
                        strand.state.position[7] = Vec3::splat(3.0e19);
                    }
                    assert!(lanes::fits_lanes(&strand, &ctx, &[], 0, 20));
                    let mut general = strand.clone();
                    let (mut a, mut b) = (StepReport::default(), StepReport::default());
                    let mut scratch = lanes::StrandProjection::default();
                    let at = (&[][..], 0);
                    let outcome = lanes::project_strand::<Libm, N>(
                        &mut strand,
                        &ctx,
                        at,
                        &mut scratch,
                        &mut a,
                    );
                    let other = project_constraints::<Libm, N>(&mut general, &ctx, &[], 0, &mut b);
                    let case = std::format!("{mode:?} {effects:?} cap {cap} k {k}");
                    assert_eq!(
                        projected_bits(&strand, &outcome, &a),
                        projected_bits(&general, &other, &b),
                        "{case}"
                    );
                    assert_eq!(a.flags, b.flags, "{case}");
                    contacts += a.contacts;
                    stopped += u32::from(k == 5 && outcome.iterations < u32::from(cap));
                }
            }
        }
    }
    assert!(contacts > 100, "the sphere was touched {contacts} times");
    assert_eq!(
        stopped, 12,
        "garbage stopped the projection early in {stopped} cases of 12"
    );
}

/// A strand that blew up before its projection (a grabbed node's predicted position is NaN;
/// the guard rolls the strand back after it) has no force to report on its grab: no NaN
/// leaves the step through `grab_forces`.
#[test]
fn a_grabbed_strand_that_blew_up_reports_no_nan_force() {
    let p = params(
        &[Effect::Inextensibility, Effect::Grabs],
        Mode::FixedCost,
        4,
        1.0e-6,
    );
    let ctx = context(&p, &[]);
    let mut strand = line(12, Vec3::ZERO, Vec3::X);
    strand.state.position[9] = Vec3::NAN;
    let grabs = [Grab::new(0, 9, Vec3::new(0.09, 0.0, 0.0), 1.0)];
    let mut report = StepReport::default();
    project_constraints::<Libm, N>(&mut strand, &ctx, &grabs, 0, &mut report);
    assert!(
        report.grab_forces.iter().all(|f| f.is_finite()),
        "{:?}",
        report.grab_forces
    );
}
