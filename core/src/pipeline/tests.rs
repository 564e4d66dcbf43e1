//! Both pipelines run their stages in [`Stage`]'s declared order on every strand, whatever
//! the path: the rod per strand (every rod effect on, both twist methods, both modes, explicit
//! substeps and the implicit step, a roll-back), DFTL per strand and in blocks.

extern crate std;
use std::vec::Vec;

use super::*;
use crate::collide::Shape;
use crate::dftl::block::DftlBlock;
use crate::effects::{Effect, Effects};
use crate::head::Shake;
use crate::math::Libm;
use crate::params::{Mode, TwistMethod};
use crate::report::{Stage, TRACE_CAPACITY};
use crate::rod::substeps::{substeps, IMPLICIT_FROM};
use crate::strand::Material;
use crate::world::{StepInput, World};

/// The strands of one step's trace: each from its snapshot on.
fn strands_of(report: &StepReport) -> Vec<Vec<Stage>> {
    assert!(report.trace.len() < TRACE_CAPACITY, "trace full");
    let mut strands: Vec<Vec<Stage>> = Vec::new();
    for &stage in &report.trace {
        if stage == Stage::Snapshot || strands.is_empty() {
            strands.push(Vec::new());
        }
        if let Some(last) = strands.last_mut() {
            last.push(stage);
        }
    }
    strands
}

/// Checks that every strand of the step ran `expected` (and, with a roll-back allowed, no
/// more), each stage once, in [`Stage`]'s order: never back.
fn check_order(report: &StepReport, expected: &[Stage], what: &str) {
    let strands = strands_of(report);
    assert!(!strands.is_empty(), "{what}: no stage ran");
    for stages in strands {
        for pair in stages.windows(2) {
            assert!(
                pair[0] < pair[1],
                "{what}: {:?} after {:?} in {stages:?}",
                pair[1],
                pair[0]
            );
        }
        assert_eq!(stages, expected, "{what}");
    }
}

/// The rod with every effect it supports, on a shaking head with a collider and a grab.
fn rod_world(twist: TwistMethod, mode: Mode, stiffness: Real) -> World<2, 16, Libm> {
    let mut params = Params {
        effects: Effects::from_slice(&[
            Effect::Gravity,
            Effect::Drag,
            Effect::Bending,
            Effect::Twist,
            Effect::Inextensibility,
            Effect::Collisions,
            Effect::Wind,
            Effect::Grabs,
        ]),
        mode,
        drag: 2.0e-7,
        ..Params::DEFAULT
    };
    params.rod.twist = twist;
    let mut world = World::with_params(params).unwrap();
    world
        .add_collider(Collider {
            shape: Shape::Sphere {
                centre: Vec3::ZERO,
                radius: 0.05,
            },
            attached_to_head: true,
        })
        .unwrap();
    let material = Material {
        youngs_modulus: Material::HUMAN_HAIR.youngs_modulus * stiffness,
        ..Material::HUMAN_HAIR
    };
    for s in 0..2 {
        let points: [Vec3; 12] = core::array::from_fn(|i| {
            let i = i as Real;
            Vec3::new(0.003 * i * i * 0.1 + 0.01 * s as Real, 0.05 + 0.01 * i, 0.0)
        });
        world
            .add_strand(Strand::from_polyline(&points, &material).unwrap())
            .unwrap();
    }
    world
        .add_grab(Grab::new(1, 11, Vec3::new(0.01, 0.16, 0.0), 1.0e3))
        .unwrap();
    world
}

const ROD: [Stage; 10] = [
    Stage::Snapshot,
    Stage::ElasticForces,
    Stage::ExternalForces,
    Stage::Integrate,
    Stage::RootCoupling,
    Stage::Projection,
    Stage::Collisions,
    Stage::Velocity,
    Stage::Twist,
    Stage::Guard,
];

#[test]
fn the_rod_runs_its_stages_in_order() {
    for twist in [TwistMethod::HairOptimised, TwistMethod::Newton] {
        for mode in [Mode::Converge, Mode::FixedCost] {
            // Human hair takes explicit substeps, ×100 stiffer hair the implicit step.
            for stiffness in [1.0, 100.0] {
                let mut world = rod_world(twist, mode, stiffness);
                let fixed = substeps(&world.strands()[0].rest.rod, 0.001, true);
                assert_eq!(fixed >= IMPLICIT_FROM, stiffness > 1.0);
                let mut accelerations = [Vec3::ZERO; 32];
                for k in 0..60u32 {
                    // A non-finite acceleration at step 40 rolls strand 0 back.
                    accelerations[5].x = if k == 40 { Real::NAN } else { 0.0 };
                    let t = (k + 1) as Real * 0.001;
                    let report = world.step(&StepInput {
                        head: Shake::TEN_RAD_PER_S.pose_at::<Libm>(t),
                        accelerations: Some(&accelerations),
                    });
                    assert_eq!(report.rolled_back, u32::from(k == 40));
                    let what = std::format!("rod {twist:?} {mode:?} ×{stiffness} step {k}");
                    check_order(&report, &ROD, &what);
                }
                // The roll-back switched strand 0 to the implicit step, in its schedule.
                assert!(world.strands()[0].schedule.implicit_bending);
            }
        }
    }
}

/// Three curved strands of 8, 9 and 10 nodes side by side.
fn add_three_strands(world: &mut World<3, 16, Libm>) {
    for s in 0..3 {
        let points: [Vec3; 10] = core::array::from_fn(|i| {
            let i = i as Real;
            Vec3::new(0.002 * i * i * 0.1, 0.05 + 0.01 * i, 0.01 * s as Real)
        });
        world
            .add_strand(Strand::from_polyline(&points[..8 + s], &Material::HUMAN_HAIR).unwrap())
            .unwrap();
    }
}

const DFTL: [Stage; 9] = [
    Stage::Snapshot,
    Stage::ExternalForces,
    Stage::Integrate,
    Stage::RootCoupling,
    Stage::Shape,
    Stage::Projection,
    Stage::Collisions,
    Stage::Velocity,
    Stage::Guard,
];

#[test]
fn dftl_runs_its_stages_in_order_per_strand_and_in_blocks() {
    let params = Params {
        solver: Solver::Dftl,
        effects: Effects::from_slice(&[
            Effect::Gravity,
            Effect::Drag,
            Effect::Shape,
            Effect::Inextensibility,
            Effect::Collisions,
            Effect::Wind,
        ]),
        drag: 2.0e-7,
        ..Params::DEFAULT
    };
    let mut world: World<3, 16, Libm> = World::with_params(params).unwrap();
    world
        .add_collider(Collider {
            shape: Shape::Sphere {
                centre: Vec3::ZERO,
                radius: 0.05,
            },
            attached_to_head: true,
        })
        .unwrap();
    add_three_strands(&mut world);
    let mut blocks: [DftlBlock<2, 16>; 2] = [
        DftlBlock::from_strands(&world.strands()[..2]),
        DftlBlock::from_strands(&world.strands()[2..]),
    ];
    let coefficients = params.dftl.at_step(params.dt);
    let mut previous = Pose::IDENTITY;
    for k in 0..30u32 {
        let t = (k + 1) as Real * params.dt;
        let head = Shake::TEN_RAD_PER_S.pose_at::<Libm>(t);
        let report = world.step(&StepInput {
            head,
            accelerations: None,
        });
        check_order(&report, &DFTL, &std::format!("DFTL per strand, step {k}"));
        let colliders = world.colliders();
        let ctx = StepContext::with_coefficients(&params, coefficients, previous, head, colliders)
            .at_time(t);
        let mut block_report = StepReport::default();
        dftl::step_blocks::<Libm, 2, 16>(&ctx, &mut blocks, 0, None, &mut block_report);
        previous = head;
        check_order(&block_report, &DFTL, &std::format!("DFTL blocks, step {k}"));
        assert_eq!(report.stage_runs, block_report.stage_runs);
    }
}

#[test]
fn dftl_rolls_back_the_same_strands_per_strand_and_in_blocks() {
    let params = Params {
        solver: Solver::Dftl,
        effects: Effects::from_slice(&[Effect::Gravity, Effect::Shape, Effect::Inextensibility]),
        ..Params::DEFAULT
    };
    let mut world: World<3, 16, Libm> = World::with_params(params).unwrap();
    add_three_strands(&mut world);
    let mut blocks: [DftlBlock<2, 16>; 2] = [
        DftlBlock::from_strands(&world.strands()[..2]),
        DftlBlock::from_strands(&world.strands()[2..]),
    ];
    let mut from_blocks = world.strands().to_vec();
    let coefficients = params.dftl.at_step(params.dt);
    let mut accelerations = [Vec3::ZERO; 3 * 16];
    for k in 0..40u32 {
        // Step 20: a NaN in strand 1 and an infinity in strand 2 (each rolled back). Step 30:
        // a huge but finite push on strand 0 (its velocities stay finite: kept).
        accelerations.fill(Vec3::ZERO);
        let expected = match k {
            20 => {
                accelerations[16 + 5].x = Real::NAN;
                accelerations[2 * 16 + 4].y = Real::INFINITY;
                2
            }
            30 => {
                accelerations[6].z = 1.0e30;
                0
            }
            _ => 0,
        };
        let report = world.step(&StepInput {
            head: Pose::IDENTITY,
            accelerations: Some(&accelerations),
        });
        assert_eq!(report.rolled_back, expected, "per strand, step {k}");
        let ctx = StepContext::with_coefficients(
            &params,
            coefficients,
            Pose::IDENTITY,
            Pose::IDENTITY,
            &[],
        );
        let mut block_report = StepReport::default();
        let a = Some(&accelerations[..]);
        dftl::step_blocks::<Libm, 2, 16>(&ctx, &mut blocks, 0, a, &mut block_report);
        assert_eq!(block_report.rolled_back, expected, "blocks, step {k}");
        blocks[0].store(&mut from_blocks[..2]);
        blocks[1].store(&mut from_blocks[2..]);
        for (s, (one, lane)) in world.strands().iter().zip(&from_blocks).enumerate() {
            assert_eq!(
                one.state.position, lane.state.position,
                "strand {s}, step {k}"
            );
            assert!(one.positions().iter().all(|x| x.is_finite()));
        }
    }
}
