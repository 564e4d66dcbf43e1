//! Same inputs, same bits: across runs, and through glam's math going to `libm`.

use hairsim_core::scenes::firmware;
use hairsim_core::{Libm, World};

fn run() -> u64 {
    let mut world: Box<World<{ firmware::STRANDS }, { firmware::NODES }, Libm>> = Box::default();
    firmware::run(&mut world, 300).unwrap()
}

#[test]
fn two_runs_give_the_same_state_hash() {
    let a = run();
    assert_eq!(a, run());
    assert_ne!(a, 0);
}

/// Workspace feature unification must never switch glam's math from `libm` to the platform's:
/// glam's transcendental functions must give `libm`'s bits, here where `std` is linked.
#[test]
fn glam_math_goes_through_libm() {
    for i in 0..20_000 {
        let angle = -50.0 + i as f32 * 0.005_123;
        let v = glam::Vec2::from_angle(angle);
        let (s, c) = libm::sincosf(angle);
        assert_eq!(
            (v.y.to_bits(), v.x.to_bits()),
            (s.to_bits(), c.to_bits()),
            "angle {angle}"
        );
    }
}

/// The rod's blocks (`pipeline::rod::step_block`, strands `W` at a time in lanes) against the
/// per-strand path, bit for bit, every step of 1,500: in fixed-cost mode, where every lane of
/// a block takes the same 4 substeps and the lanes run them, and in converge mode on blocks
/// whose strands differ in their substep count, in the implicit switch (a stiff strand), in
/// their projection iterations (the projection runs in lanes), and in a roll-back (a NaN put
/// into one strand's velocity); a grab holds a node of one strand throughout (its clamped
/// segment steps that strand's twist and its projection alone), and the head's sphere
/// touches the strands (contacts found and eliminated lane by lane). The report's projection
/// findings must match too. The twist runs in lanes: the hair-optimised one (the default),
/// and Newton's in a test of its own. Each of those cases is counted and must have occurred.
mod rod_blocks {
    use hairsim_core::collide::{Collider, Shape};
    use hairsim_core::context::StepContext;
    use hairsim_core::hash::state_hash;
    use hairsim_core::params::TwistMethod;
    use hairsim_core::rod::frames::RodFrames;
    use hairsim_core::rod::substeps::{plan, smallest_binormal_denominator, Integration};
    use hairsim_core::{
        step_strands, step_strands_in_lanes, Effect, Effects, Grab, Libm, Material, Math, Mode,
        Params, Pose, Real, Shake, StepReport, Strand, Vec3,
    };

    const N: usize = 32;
    const STRANDS: usize = 12;
    const STEPS: u32 = 1500;

    /// What the blocks met: steps of a block whose lanes all took the same substeps (the
    /// lanes' path), differed in substep count, mixed the implicit step with substeps, had
    /// two strands or more take the implicit step, or differed in projection iterations;
    /// roll-backs; steps with a node held by a grab, and with nodes in contact with the head.
    #[derive(Debug, Default)]
    struct Cases {
        same_substeps: u32,
        different_substeps: u32,
        implicit_beside_explicit: u32,
        implicit_together: u32,
        different_iterations: u32,
        roll_backs: u32,
        grabbed: u32,
        contacts: u32,
    }

    /// A strand of 24 nodes leaving the head along `normal`: straight, wavy or curly.
    fn strand(s: usize) -> Strand<N> {
        let a = s as Real * 2.4;
        let normal = Vec3::new(0.6 * a.cos(), 0.8, 0.6 * a.sin()).normalize();
        let side = normal.cross(Vec3::Z).normalize_or(Vec3::X);
        let other = normal.cross(side);
        let points: Vec<Vec3> = (0..24)
            .map(|i| {
                let t = i as Real * 0.01;
                let wave = match s % 3 {
                    0 => Vec3::ZERO,
                    1 => side * (0.004 * (40.0 * t).sin()),
                    _ => (side * (i as Real).cos() + other * (i as Real).sin()) * 0.004,
                };
                normal * (0.1 + t) + wave
            })
            .collect();
        let mut material = Material::HUMAN_HAIR;
        if s == 5 || s == 6 {
            // Ten times stiffer: 12 fixed substeps, so the implicit step from the first. At 4
            // and at 8 lanes, both take it in the same block, beside explicit lanes.
            material.youngs_modulus *= 10.0;
        }
        Strand::from_polyline(&points, &material).unwrap()
    }

    fn params(mode: Mode, twist: TwistMethod) -> Params {
        let mut p = Params {
            effects: Effects::from_slice(&[
                Effect::Gravity,
                Effect::Drag,
                Effect::Bending,
                Effect::Twist,
                Effect::Inextensibility,
                Effect::Collisions,
                Effect::Grabs,
            ]),
            ..Params::DEFAULT
        };
        p.mode = mode;
        p.rod.twist = twist;
        p
    }

    /// The plan each strand of `strands` would make for this step (its schedule untouched; no
    /// grab holds them).
    fn plans<M: Math>(ctx: &StepContext, strands: &[Strand<N>]) -> Vec<Integration> {
        let mut frames = RodFrames::<M, N>::empty();
        strands
            .iter()
            .map(|s| {
                frames.refresh(s);
                let mut schedule = s.schedule;
                plan(ctx, &s.rest.rod, (&mut schedule, false), || {
                    smallest_binormal_denominator(&frames, &s.rest.rod.rest_length)
                })
            })
            .collect()
    }

    fn check<M: Math, const W: usize>(mode: Mode, twist: TwistMethod) -> Cases {
        let p = params(mode, twist);
        let colliders = [Collider {
            shape: Shape::Sphere {
                centre: Vec3::ZERO,
                radius: 0.1,
            },
            attached_to_head: true,
        }];
        let mut reference: Vec<Strand<N>> = (0..STRANDS).map(strand).collect();
        // A hand holding strand 1 at node 14, moving with the head.
        let held = reference[1].state.position[14];
        let mut grabs = [Grab::new(1, 14, held, 1.0)];
        let mut lanes = reference.clone();
        let coefficients = p.dftl.at_step(p.dt);
        let mut cases = Cases::default();
        let mut previous = Pose::IDENTITY;
        for k in 0..STEPS {
            let t = (k + 1) as Real * p.dt;
            let head = Shake::TEN_RAD_PER_S.pose_at::<Libm>(t);
            let ctx = StepContext::with_coefficients(&p, coefficients, previous, head, &colliders)
                .at_time(t);
            previous = head;
            grabs[0].target = head.transform_point(held);
            if k == 700 && mode == Mode::Converge {
                for strands in [&mut reference, &mut lanes] {
                    strands[2].state.velocity[12].x = Real::NAN;
                }
            }
            let plans = plans::<M>(&ctx, &reference);
            let mut iterations = Vec::new();
            let mut expected = StepReport::default();
            for (s, strand) in reference.chunks_mut(1).enumerate() {
                let mut report = StepReport::default();
                step_strands::<M, N>(&ctx, strand, s as u32, &grabs, None, &mut report);
                iterations.push(report.iterations_max);
                expected.merge(&report);
            }
            let mut report = StepReport::default();
            step_strands_in_lanes::<M, N, W>(&ctx, &mut lanes, 0, &grabs, None, &mut report);
            assert_eq!(report.stage_runs, expected.stage_runs, "step {k}");
            assert_eq!(report.rolled_back, expected.rolled_back, "step {k}");
            assert_eq!(
                report.iterations_total, expected.iterations_total,
                "step {k}"
            );
            let bits = |r: &StepReport| r.grab_forces.map(|f| f.to_array().map(Real::to_bits));
            assert_eq!(bits(&report), bits(&expected), "step {k}");
            // The projection's findings, in lanes or alone.
            let pushes =
                |r: &StepReport| r.collider_forces.map(|f| f.to_array().map(Real::to_bits));
            assert_eq!(pushes(&report), pushes(&expected), "step {k}");
            let measures = |r: &StepReport| {
                let reals = [
                    r.residual,
                    r.max_stretch,
                    r.max_contact_stretch,
                    r.max_penetration,
                ];
                (
                    reals.map(Real::to_bits),
                    r.contacts,
                    r.collision_rows,
                    r.dropped_rows,
                    r.cap_hits,
                    r.flags,
                )
            };
            assert_eq!(measures(&report), measures(&expected), "step {k}");
            cases.contacts += u32::from(report.contacts > 0);
            assert_eq!(state_hash(&lanes), state_hash(&reference), "step {k}");
            cases.roll_backs += report.rolled_back;
            cases.grabbed += u32::from(report.grab_forces[0] != Vec3::ZERO);
            for (block, its) in plans.chunks(W).zip(iterations.chunks(W)) {
                let substeps: Vec<u32> = block
                    .iter()
                    .filter_map(|plan| match plan {
                        Integration::Explicit(k) => Some(*k),
                        Integration::Implicit => None,
                    })
                    .collect();
                let explicit_differ = substeps.iter().any(|&k| k != substeps[0]);
                cases.same_substeps += u32::from(substeps.len() == block.len() && !explicit_differ);
                cases.different_substeps += u32::from(explicit_differ);
                cases.implicit_beside_explicit +=
                    u32::from(!substeps.is_empty() && substeps.len() < block.len());
                cases.implicit_together += u32::from(block.len() - substeps.len() > 1);
                cases.different_iterations += u32::from(its.iter().any(|&i| i != its[0]));
            }
        }
        assert_eq!(lanes, reference);
        eprintln!("{mode:?}, {twist:?}, {W} lanes: {cases:?}");
        cases
    }

    #[test]
    fn blocks_give_the_per_strand_bits() {
        let hair_optimised = TwistMethod::HairOptimised;
        for cases in [
            check::<Libm, 4>(Mode::FixedCost, hair_optimised),
            check::<Libm, 8>(Mode::FixedCost, hair_optimised),
        ] {
            assert!(cases.same_substeps > 0, "{cases:?}");
            assert!(cases.implicit_beside_explicit > 0, "{cases:?}");
            assert!(cases.implicit_together > 0, "{cases:?}");
            assert!(cases.grabbed > 0, "{cases:?}");
            assert!(cases.contacts > 0, "{cases:?}");
        }
        for cases in [
            check::<Libm, 4>(Mode::Converge, hair_optimised),
            check::<Libm, 8>(Mode::Converge, hair_optimised),
        ] {
            assert!(cases.same_substeps > 0, "{cases:?}");
            assert!(cases.different_substeps > 0, "{cases:?}");
            assert!(cases.implicit_beside_explicit > 0, "{cases:?}");
            assert!(cases.implicit_together > 0, "{cases:?}");
            assert!(cases.different_iterations > 0, "{cases:?}");
            assert!(cases.roll_backs > 0, "{cases:?}");
            assert!(cases.grabbed > 0, "{cases:?}");
            assert!(cases.contacts > 0, "{cases:?}");
        }
    }

    /// The same with Newton's twist, in lanes too: in converge mode each lane stops iterating
    /// when its own update is small enough, and its angles stay as they are while the others
    /// go on; in fixed-cost mode every lane runs the cap.
    #[test]
    fn blocks_give_the_per_strand_bits_with_the_newton_twist() {
        let cases = check::<Libm, 4>(Mode::FixedCost, TwistMethod::Newton);
        assert!(cases.same_substeps > 0, "{cases:?}");
        assert!(cases.implicit_beside_explicit > 0, "{cases:?}");
        assert!(cases.implicit_together > 0, "{cases:?}");
        assert!(cases.grabbed > 0 && cases.contacts > 0, "{cases:?}");
        for cases in [
            check::<Libm, 4>(Mode::Converge, TwistMethod::Newton),
            check::<Libm, 8>(Mode::Converge, TwistMethod::Newton),
        ] {
            assert!(cases.different_substeps > 0, "{cases:?}");
            assert!(cases.implicit_beside_explicit > 0, "{cases:?}");
            assert!(cases.implicit_together > 0, "{cases:?}");
            assert!(cases.different_iterations > 0, "{cases:?}");
            assert!(cases.roll_backs > 0, "{cases:?}");
            assert!(cases.grabbed > 0 && cases.contacts > 0, "{cases:?}");
        }
    }
}

/// The scratch tests' effects: bending, twist, inextensibility and collisions under gravity.
/// The scratch tests' head: a sphere of 5 cm at the origin, attached to the head.
fn head_sphere() -> hairsim_core::Collider {
    use hairsim_core::{Shape, Vec3};
    hairsim_core::Collider {
        shape: Shape::Sphere {
            centre: Vec3::ZERO,
            radius: 0.05,
        },
        attached_to_head: true,
    }
}

fn scratch_test_params() -> hairsim_core::Params {
    use hairsim_core::{Effect, Effects, Params};
    Params {
        effects: Effects::from_slice(&[
            Effect::Gravity,
            Effect::Bending,
            Effect::Twist,
            Effect::Inextensibility,
            Effect::Collisions,
        ]),
        ..Params::DEFAULT
    }
}

/// The harness keeps each block's `RodBlockScratch` (the lanes, their frames, the projections'
/// scratch) from step to step. Nothing may carry over: blocks of two strands of 24, 13 and 19
/// nodes (and one block mixing 24 and 13, whose strands step alone) share one scratch space
/// for 800 steps and give the bits each strand gives alone, with bending, twist,
/// inextensibility and the head's sphere on a shaking head.
#[test]
fn a_kept_block_scratch_carries_nothing_between_blocks_or_steps() {
    use hairsim_core::context::StepContext;
    use hairsim_core::hash::state_hash;
    use hairsim_core::pipeline::step_strands_in_lanes_with;
    use hairsim_core::{
        step_strands, Material, Pose, Real, RodBlockScratch, Shake, StepReport, Strand, Vec3,
    };
    const N: usize = 24;
    let p = scratch_test_params();
    let lengths = [24, 24, 13, 13, 19, 19, 24, 13];
    let strand = |s: usize| {
        let normal = Vec3::new(0.1 * s as Real - 0.4, 0.9, 0.2).normalize();
        let side = normal.cross(Vec3::Z).normalize();
        let points: Vec<Vec3> = (0..lengths[s])
            .map(|i| {
                let a = i as Real * (0.5 + 0.1 * s as Real);
                normal * (0.051 + i as Real * 0.008) + side * (0.004 * a.sin())
            })
            .collect();
        Strand::<N>::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
    };
    let colliders = [head_sphere()];
    let mut blocks: Vec<Strand<N>> = (0..lengths.len()).map(strand).collect();
    let mut alone = blocks.clone();
    let mut scratch: Box<RodBlockScratch<Libm, N, 2>> = Box::default();
    let coefficients = p.dftl.at_step(p.dt);
    let mut previous = Pose::IDENTITY;
    for k in 0..800u32 {
        let t = (k + 1) as Real * p.dt;
        let head = Shake::TEN_RAD_PER_S.pose_at::<Libm>(t);
        let ctx =
            StepContext::with_coefficients(&p, coefficients, previous, head, &colliders).at_time(t);
        previous = head;
        let mut report = StepReport::default();
        step_strands_in_lanes_with(&ctx, &mut blocks, (0, &[]), None, &mut scratch, &mut report);
        for (s, strand) in alone.chunks_mut(1).enumerate() {
            step_strands::<Libm, N>(&ctx, strand, s as u32, &[], None, &mut report);
        }
        for (s, (a, b)) in blocks.iter().zip(&alone).enumerate() {
            let (a, b) = (core::slice::from_ref(a), core::slice::from_ref(b));
            assert_eq!(state_hash(a), state_hash(b), "strand {s}, step {k}");
        }
    }
}

/// A `World` keeps DFTL's scratch space (`DftlScratch`: the collider pushes, the last good
/// positions its pass keeps, the held strand's projection workspace) from strand to strand and
/// step to step. Nothing may carry over: three DFTL strands of 24, 13 and 19 nodes with shape
/// draped over the head's sphere, a shaking head, and a coupled grab that moves to the next strand
/// every 100 steps, stepped through a kept scratch space (`step_strands_with`) and, from the
/// same states and contexts, without one (`step_strands`, which makes what it needs on the
/// stack), give the same state bits and the same report at every step of 600. Halfway, the
/// scratch space is made the rod's and DFTL's again, as a world's `configure` does.
#[test]
fn a_kept_dftl_scratch_carries_nothing_between_strands_or_steps() {
    use hairsim_core::context::StepContext;
    use hairsim_core::hash::state_hash;
    use hairsim_core::pipeline::step_strands_with;
    use hairsim_core::{
        step_strands, Coupling, Effect, Effects, Grab, Material, Params, Pose, Real, Shake, Solver,
        StepReport, StepScratch, Strand, Vec3,
    };
    const N: usize = 24;
    let p = Params {
        effects: Effects::from_slice(&[
            Effect::Gravity,
            Effect::Drag,
            Effect::Inextensibility,
            Effect::Shape,
            Effect::Collisions,
            Effect::Grabs,
        ]),
        ..Params::preset(Solver::Dftl)
    };
    let lengths = [24, 13, 19];
    // Draped over the head: from near its top down a great circle, 0.2 mm outside the sphere.
    let strand = |s: usize| {
        let across = Vec3::new((2.0 * s as Real).cos(), 0.0, (2.0 * s as Real).sin());
        let points: Vec<Vec3> = (0..lengths[s])
            .map(|i| {
                let a = 0.3 + i as Real * 0.12;
                (across * a.sin() + Vec3::Y * a.cos()) * 0.0502
            })
            .collect();
        Strand::<N>::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
    };
    let colliders = [head_sphere()];
    let mut kept: Vec<Strand<N>> = (0..3).map(strand).collect();
    let mut made = kept.clone();
    let mut scratch = StepScratch::<Libm, N>::for_solver(Solver::Dftl);
    let mut previous = Pose::IDENTITY;
    let mut contacts = 0;
    for k in 0..600u32 {
        let t = (k + 1) as Real * p.dt;
        let head = Shake::TEN_RAD_PER_S.pose_at::<Libm>(t);
        let ctx = StepContext::new(&p, previous, head, &colliders).at_time(t);
        previous = head;
        let held = (k / 100) % 3;
        let node = lengths[held as usize] as u32 - 2;
        let rest = made[held as usize].positions()[node as usize];
        let circle = Vec3::new((t * 6.0).sin(), 0.0, (t * 6.0).cos()) * 0.01;
        let grab =
            Grab::new(held, node, rest + circle, 1000.0).with_coupling(Coupling::new(50.0, 0.05));
        if k == 300 {
            scratch.suit(Solver::Rod);
            scratch.suit(Solver::Dftl);
        }
        let (mut with, mut without) = (StepReport::default(), StepReport::default());
        let at = (0, core::slice::from_ref(&grab));
        step_strands_with::<Libm, N>(&ctx, &mut kept, at, None, Some(&mut scratch), &mut with);
        step_strands::<Libm, N>(&ctx, &mut made, 0, &[grab], None, &mut without);
        assert_eq!(state_hash(&kept), state_hash(&made), "step {k}");
        assert_eq!(format!("{with:?}"), format!("{without:?}"), "step {k}");
        contacts += with.contacts;
    }
    assert!(
        contacts > 0,
        "no contact in 600 steps: the test would miss the contact rows"
    );
}

/// Strand `s` of the world scratch tests: `nodes` nodes draped out from the head's sphere,
/// wavy, of `material`.
fn scratch_test_strand(
    s: usize,
    nodes: usize,
    material: &hairsim_core::Material,
) -> hairsim_core::Strand<24> {
    use hairsim_core::{Real, Strand, Vec3};
    let normal = Vec3::new(0.3 * s as Real - 0.3, 0.9, 0.2).normalize();
    let side = normal.cross(Vec3::Z).normalize();
    let points: Vec<Vec3> = (0..nodes)
        .map(|i| {
            let a = i as Real * (0.5 + 0.3 * s as Real);
            normal * (0.051 + i as Real * 0.008) + side * (0.004 * a.sin())
        })
        .collect();
    Strand::from_polyline(&points, material).unwrap()
}

/// A world of the world scratch tests: `params`, the head's sphere and `strands`.
fn scratch_test_world(
    params: hairsim_core::Params,
    strands: impl IntoIterator<Item = hairsim_core::Strand<24>>,
) -> Box<World<3, 24, Libm>> {
    use hairsim_core::collide::{Collider, Shape};
    use hairsim_core::Vec3;
    let mut world: Box<World<3, 24, Libm>> = Box::default();
    world.configure(params).unwrap();
    let sphere = Collider {
        shape: Shape::Sphere {
            centre: Vec3::ZERO,
            radius: 0.05,
        },
        attached_to_head: true,
    };
    world.add_collider(sphere).unwrap();
    for strand in strands {
        world.add_strand(strand).unwrap();
    }
    world
}

/// Asserts that strand `s` of `together` has the positions and twist bits of the one strand
/// of `alone` at step `k`.
fn assert_same_strand_bits(
    together: &World<3, 24, Libm>,
    alone: &World<3, 24, Libm>,
    s: usize,
    k: u32,
) {
    let bits = |p: &[hairsim_core::Vec3]| {
        p.iter()
            .map(|v| v.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        bits(together.strands()[s].positions()),
        bits(alone.strands()[0].positions()),
        "strand {s}, step {k}"
    );
    assert_eq!(
        together.strands()[s].state.theta.map(f32::to_bits),
        alone.strands()[0].state.theta.map(f32::to_bits),
        "strand {s}, step {k}"
    );
}

/// A `World` keeps the rod step's scratch space (`RodScratch`: the frames' buffer, the
/// projection's lanes and the rest) from strand to strand and step to step. Nothing may carry
/// over: three strands of 24, 13 and 19 nodes in one world, where each strand's step finds the
/// buffer as a longer or shorter strand left it, give the bits each gives alone in a world of
/// its own, every step of 800 with bending, twist, inextensibility and the head's sphere on a
/// shaking head.
#[test]
fn a_worlds_rod_scratch_carries_nothing_between_strands_or_steps() {
    use hairsim_core::{Material, Real, Shake, StepInput};
    let params = scratch_test_params();
    let lengths = [24, 13, 19];
    let strand = |s: usize| scratch_test_strand(s, lengths[s], &Material::HUMAN_HAIR);
    let build = |which: &[usize]| scratch_test_world(params, which.iter().map(|&s| strand(s)));
    let mut together = build(&[0, 1, 2]);
    let mut alone: Vec<_> = (0..3).map(|s| build(&[s])).collect();
    for k in 0..800u32 {
        let input = StepInput {
            head: Shake::TEN_RAD_PER_S.pose_at::<Libm>((k + 1) as Real * params.dt),
            accelerations: None,
        };
        together.step(&input);
        for (s, world) in alone.iter_mut().enumerate() {
            world.step(&input);
            assert_same_strand_bits(&together, world, s, k);
        }
    }
}

/// The rod's scratch space also holds the general projection's workspace and the implicit
/// step's system, which a held strand uses every step, and the explicit substeps' forces and
/// motion. Nothing may carry over between strands that use them in turn: a held strand of 24
/// nodes (its tip coupled to a circle: the implicit step, then the general projection), a
/// strand of 13 nodes ten times stiffer (the implicit step, then the lanes' projection) and
/// one of 19 (the explicit substeps) in one world give the bits each gives alone, every step
/// of 600 on a shaking head with the head's sphere.
#[test]
fn a_worlds_rod_scratch_carries_nothing_between_held_stiff_and_free_strands() {
    use hairsim_core::{Coupling, Effect, Grab, Material, Real, Shake, StepInput, Vec3};
    let mut params = scratch_test_params();
    params.effects = params.effects.with(Effect::Grabs);
    let lengths = [24, 13, 19];
    let strand = |s: usize| {
        let mut material = Material::HUMAN_HAIR;
        if s == 1 {
            material.youngs_modulus *= 10.0;
            material.shear_modulus *= 10.0;
        }
        scratch_test_strand(s, lengths[s], &material)
    };
    let tip = strand(0).positions()[23];
    let target = |k: u32| {
        let t = (k + 1) as Real * params.dt;
        tip + Vec3::new((20.0 * t).cos() - 1.0, 0.0, (20.0 * t).sin()) * 0.01
    };
    let build = |which: &[usize]| {
        let mut world = scratch_test_world(params, which.iter().map(|&s| strand(s)));
        if let Some(held) = which.iter().position(|&s| s == 0) {
            // Coupled: a prescribed node slips once the shaking head takes the root out of
            // reach of the target.
            let coupling = Coupling::new(50.0, 0.05);
            let grab = Grab::new(held as u32, 23, tip, 1000.0).with_coupling(coupling);
            world.add_grab(grab).unwrap();
        }
        world
    };
    let mut together = build(&[0, 1, 2]);
    let mut alone: Vec<_> = (0..3).map(|s| build(&[s])).collect();
    let mut pulled = 0.0;
    for k in 0..600u32 {
        let input = StepInput {
            head: Shake::TEN_RAD_PER_S.pose_at::<Libm>((k + 1) as Real * params.dt),
            accelerations: None,
        };
        together.set_grab_target(0, target(k));
        alone[0].set_grab_target(0, target(k));
        let report = together.step(&input);
        assert_eq!(report.rolled_back, 0, "step {k}");
        pulled = report.grab_forces[0].length().max(pulled);
        for (s, world) in alone.iter_mut().enumerate() {
            let own = world.step(&input);
            if s == 0 {
                assert_eq!(
                    report.grab_forces[0].to_array().map(f32::to_bits),
                    own.grab_forces[0].to_array().map(f32::to_bits),
                    "grab force, step {k}"
                );
            }
            assert_same_strand_bits(&together, world, s, k);
        }
    }
    // The grab held the strand throughout, and pulled it.
    assert_eq!(together.grabs()[0].status, hairsim_core::GrabStatus::Held);
    assert!(pulled > 0.0, "the grab never pulled: {pulled}");
}
