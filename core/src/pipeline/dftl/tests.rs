//! DFTL's pipeline: a styled strand at rest stays there, the rest frames put every node on its
//! local target, and the block path gives the per-strand path's bits.

extern crate std;
use super::*;
use crate::collide::Collider;
use crate::context::StepContext;
use crate::dftl::block::DftlBlock;
use crate::dftl::frame;
use crate::effects::{Effect, Effects};
use crate::head::{Pose, Shake};
use crate::math::Libm;
use crate::params::{Params, Solver};
use crate::strand::Material;
use crate::world::{StepInput, World};

fn wavy(nodes: usize, phase: Real) -> std::vec::Vec<Vec3> {
    (0..nodes)
        .map(|i| {
            let s = i as Real * 0.01;
            let (sin, cos) = Libm::sin_cos(40.0 * s + phase);
            Vec3::new(0.004 * sin, 0.05 + s, 0.004 * cos)
        })
        .collect()
}

fn params(effects: &[Effect]) -> Params {
    Params {
        solver: Solver::Dftl,
        effects: Effects::from_slice(effects),
        ..Params::DEFAULT
    }
}

#[test]
fn a_strand_at_rest_with_shape_stays_at_rest() {
    let mut w: World<1, 16, Libm> =
        World::with_params(params(&[Effect::Shape, Effect::Inextensibility])).unwrap();
    let points = wavy(16, 0.3);
    w.add_strand(Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap())
        .unwrap();
    let input = StepInput {
        head: Pose::IDENTITY,
        accelerations: None,
    };
    for _ in 0..200 {
        w.step(&input);
    }
    for (p, q) in w.strands()[0].positions().iter().zip(&points) {
        assert!((*p - *q).length() < 1e-6, "{p} vs {q}");
    }
}

#[test]
fn rest_frames_put_each_node_on_its_local_target() {
    let points = wavy(12, 1.1);
    let s = Strand::<12>::from_polyline(&points, &Material::HUMAN_HAIR).unwrap();
    let ctx = crate::context::StepContext::new(
        &params(&[Effect::Shape]),
        Pose::IDENTITY,
        Pose::IDENTITY,
        &[],
    );
    let setup = Setup::new(&ctx);
    let mut chain = Chain::start(
        &setup,
        s.rest.dftl.root_tangent.into(),
        s.rest.dftl.root_normal.into(),
        points[1].into(),
    );
    for (i, point) in points.iter().enumerate().skip(2) {
        let target = Vec3::from(chain.position)
            + Vec3::from(frame::rotate(
                chain.tangent,
                chain.normal,
                s.rest.dftl.local_rest[i].into(),
            ));
        assert!((target - *point).length() < 1e-7, "node {i}");
        let node = NodeInput {
            active: true,
            position: (*point).into(),
            velocity: V3::zero(),
            extra: V3::zero(),
            has_extra: false,
            mass: s.rest.mass[i],
            rest_position: s.rest.position[i].into(),
            local_rest: s.rest.dftl.local_rest[i].into(),
            root_distance: s.rest.dftl.root_distance[i],
            segment_length: s.rest.segment_length[i - 1],
            strain_scale: s.rest.dftl.strain_scale[i],
        };
        let mut measures = Measures::default();
        let mut push = [V3::zero(); MAX_COLLIDERS];
        let (m, p) = (&mut measures, &mut push);
        chain = advance::<Libm, Real>(&setup, &[], &node, &chain, false, m, p).chain;
        assert!(measures.stretched < 1e-6 && measures.compressed < 1e-6);
    }
    assert_eq!(s.rest.dftl.root_distance[11], 1.0);
}

#[test]
fn block_gives_the_bits_of_the_per_strand_path() {
    // Every specialisation of both passes (`with_effect_switches!`): shape,
    // inextensibility and drag each on and off, with gravity, wind and a collider.
    for switches in 0..8u32 {
        let mut effects = std::vec![Effect::Gravity, Effect::Collisions, Effect::Wind];
        for (bit, effect) in [Effect::Shape, Effect::Inextensibility, Effect::Drag]
            .into_iter()
            .enumerate()
        {
            if switches & (1 << bit) != 0 {
                effects.push(effect);
            }
        }
        // Both colliders reached in every configuration: the contact branches ran too.
        let contacts = block_matches_per_strand::<5, 4>(&effects);
        assert!(contacts > 0, "{effects:?}");
        // Twelve strands in blocks of 8 lanes (the second with four strands).
        let contacts = block_matches_per_strand::<12, 8>(&effects);
        assert!(contacts > 0, "{effects:?}");
    }
}

/// A world of `S` wavy strands of 10 to 14 nodes with `effects`, a head sphere and a capsule
/// across the strands 5 cm above the roots (they touch it with shape on too).
fn world<const S: usize>(effects: &[Effect]) -> World<S, 16, Libm> {
    let p = Params {
        effects: Effects::from_slice(effects),
        drag: 2.0e-7,
        ..params(&[])
    };
    let mut w: World<S, 16, Libm> = World::with_params(p).unwrap();
    let sphere = Shape::Sphere {
        centre: Vec3::ZERO,
        radius: 0.05,
    };
    let capsule = Shape::Capsule {
        a: Vec3::new(-0.02, 0.1, 0.0),
        b: Vec3::new(0.02, 0.1, 0.0),
        radius: 0.005,
    };
    for shape in [sphere, capsule] {
        let collider = Collider {
            shape,
            attached_to_head: true,
        };
        w.add_collider(collider).unwrap();
    }
    for s in 0..S {
        let points = wavy(10 + s % 5, s as Real);
        w.add_strand(Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap())
            .unwrap();
    }
    w
}

/// The report's figures both paths must agree on, as bits.
fn bits(r: &StepReport) -> [u32; 12] {
    let [a, b] = [r.collider_forces[0], r.collider_forces[1]];
    let head = r.head_force;
    [
        r.max_stretch,
        r.max_contact_stretch,
        r.max_penetration,
        a.x,
        a.y,
        a.z,
        b.x,
        b.y,
        b.z,
        head.x,
        head.y,
        head.z,
    ]
    .map(Real::to_bits)
}

/// Steps `S` strands by both paths, in blocks of `W` lanes, 300 steps and checks they agree
/// (state, report); at step 150 a NaN acceleration on the second-last strand rolls it back,
/// and neither path reports a force that is not finite.
/// Returns the contacts seen.
fn block_matches_per_strand<const S: usize, const W: usize>(effects: &[Effect]) -> u32 {
    let mut w = world::<S>(effects);
    let p = *w.params();
    let mut blocks: std::vec::Vec<DftlBlock<W, 16>> =
        w.strands().chunks(W).map(DftlBlock::from_strands).collect();
    let coefficients = p.dftl.at_step(p.dt);
    let mut previous = Pose::IDENTITY;
    let mut contacts = 0;
    let mut accelerations = std::vec![Vec3::ZERO; S * 16];
    for k in 0..300u32 {
        let t = (k + 1) as Real * p.dt;
        let head = Shake::TEN_RAD_PER_S.pose_at::<Libm>(t);
        accelerations[(S - 2) * 16 + 5].x = if k == 150 { Real::NAN } else { 0.0 };
        let report = w.step(&StepInput {
            head,
            accelerations: Some(&accelerations),
        });
        assert_eq!(
            report.rolled_back,
            u32::from(k == 150),
            "{effects:?} step {k}"
        );
        let colliders = w.colliders();
        let ctx =
            StepContext::with_coefficients(&p, coefficients, previous, head, colliders).at_time(t);
        let mut block_report = StepReport::default();
        let a = Some(&accelerations[..]);
        step_blocks::<Libm, W, 16>(&ctx, &mut blocks, 0, a, &mut block_report);
        assert_eq!(report.rolled_back, block_report.rolled_back, "{effects:?}");
        previous = head;
        assert_eq!(report.stage_runs, block_report.stage_runs, "{effects:?}");
        assert_eq!(bits(&report), bits(&block_report), "{effects:?} step {k}");
        // The strand that went NaN passes nothing on: its pushes are not reported.
        let forces = block_report
            .collider_forces
            .iter()
            .chain([&block_report.head_force]);
        assert!(
            forces.into_iter().all(|f| f.is_finite()),
            "{effects:?} step {k}"
        );
        assert_eq!(report.contacts, block_report.contacts, "{effects:?}");
        contacts += report.contacts;
    }
    let mut strands: std::vec::Vec<Strand<16>> = w.strands().to_vec();
    for (block, chunk) in blocks.iter().zip(strands.chunks_mut(W)) {
        block.store(chunk);
    }
    let hash = crate::hash::state_hash(&strands);
    assert_eq!(hash, w.state_hash(), "{effects:?}");
    assert!(w.strands()[4].state.position[10].y != points_y(&wavy(14, 4.0)));
    contacts
}

fn points_y(p: &[Vec3]) -> Real {
    p[10].y
}
