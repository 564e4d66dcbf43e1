//! SPH hair–hair interaction through the core's per-node acceleration input: pressure pushes
//! overlapping wisps apart, viscosity slows their relative motion, and results do not depend
//! on the thread count. (`sph_alloc.rs` checks that a step allocates nothing.)

use hairsim::sph::{Sph, SphParams};
use hairsim_core::{
    context::StepContext, hash::state_hash, step_strands, Effect, Effects, Libm, Material, Params,
    Pose, StepReport, Strand, Vec3,
};

const N: usize = 16;

/// A wisp of `count` straight strands along +x, centred on `centre` in y–z within `spread`.
fn wisp(centre: Vec3, count: usize, spread: f32, velocity: Vec3) -> Vec<Strand<N>> {
    (0..count)
        .map(|k| {
            let angle = k as f32 * 2.399_963; // golden angle: an even disc of roots
            let radius = spread * ((k as f32 + 0.5) / count as f32).sqrt();
            let offset = Vec3::new(0.0, radius * angle.cos(), radius * angle.sin());
            let points: Vec<Vec3> = (0..12)
                .map(|i| centre + offset + Vec3::new(0.005 * i as f32, 0.0, 0.0))
                .collect();
            let mut s = Strand::<N>::from_polyline(&points, &Material::HUMAN_HAIR).unwrap();
            for v in &mut s.state.velocity[2..12] {
                *v = velocity;
            }
            s
        })
        .collect()
}

fn params() -> Params {
    Params {
        effects: Effects::NONE.with(Effect::HairHair),
        ..Params::DEFAULT
    }
}

/// Steps `strands` with SPH accelerations for `steps` steps.
fn run(strands: &mut [Strand<N>], sph: &mut Sph, steps: usize) {
    let params = params();
    let ctx = StepContext::new(&params, Pose::IDENTITY, Pose::IDENTITY, &[]);
    for _ in 0..steps {
        let acc = sph
            .accelerations(strands, params.dt, Pose::IDENTITY)
            .to_vec();
        let mut report = StepReport::default();
        step_strands::<Libm, N>(&ctx, strands, 0, &[], Some(&acc), &mut report);
        assert_eq!(report.rolled_back, 0);
    }
}

fn centroid(strands: &[Strand<N>]) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let mut n = 0.0;
    for s in strands {
        for p in &s.state.position[2..s.nodes()] {
            sum += *p;
            n += 1.0;
        }
    }
    sum / n
}

fn sph_params(stiffness: f32, viscosity: f32) -> SphParams {
    SphParams {
        smoothing_length: 0.004,
        rest_density: 0.5,
        stiffness,
        viscosity,
        neighbour_cap: 32,
        same_strand_gap: 3,
    }
}

#[test]
fn pressure_pushes_overlapping_wisps_apart() {
    let separation = |stiffness: f32| {
        let mut strands = wisp(Vec3::new(0.0, 0.0, 0.0), 20, 0.002, Vec3::ZERO);
        strands.extend(wisp(Vec3::new(0.0, 0.0015, 0.0), 20, 0.002, Vec3::ZERO));
        let mut sph = Sph::new(sph_params(stiffness, 0.0), &strands).unwrap();
        run(&mut strands, &mut sph, 200);
        (centroid(&strands[20..]) - centroid(&strands[..20])).y
    };
    let (still, pushed) = (separation(0.0), separation(0.5));
    assert!(
        (still - 0.0015).abs() < 1e-6,
        "without pressure the wisps stay put: {still}"
    );
    assert!(
        pushed > still + 5e-4,
        "pressure separates the wisps: {pushed} vs {still}"
    );
}

#[test]
fn viscosity_reduces_relative_velocity() {
    let relative = |viscosity: f32| {
        let mut strands = wisp(Vec3::ZERO, 20, 0.002, Vec3::new(0.0, 0.0, 0.05));
        strands.extend(wisp(
            Vec3::new(0.0, 0.001, 0.0),
            20,
            0.002,
            Vec3::new(0.0, 0.0, -0.05),
        ));
        let mut sph = Sph::new(sph_params(0.0, viscosity), &strands).unwrap();
        run(&mut strands, &mut sph, 20);
        let mean_vz =
            |s: &[Strand<N>]| s.iter().map(|s| s.state.velocity[8].z).sum::<f32>() / s.len() as f32;
        mean_vz(&strands[..20]) - mean_vz(&strands[20..])
    };
    let (free, damped) = (relative(0.0), relative(200.0));
    assert!(
        (free - 0.1).abs() < 1e-6,
        "no viscosity, no friction: {free}"
    );
    assert!(
        damped < 0.8 * free,
        "viscosity slows the wisps against each other: {damped} vs {free}"
    );
    assert!(
        damped > -0.01,
        "friction does not reverse the motion: {damped}"
    );
}

#[test]
fn one_and_two_threads_give_the_same_state_hash_after_200_steps() {
    let hash = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            // Enough particles for several parallel chunks.
            let mut strands = Vec::new();
            for w in 0..12 {
                strands.extend(wisp(
                    Vec3::new(0.0, 0.002 * w as f32, 0.0),
                    30,
                    0.003,
                    Vec3::new(0.0, 0.0, 0.01 * w as f32),
                ));
            }
            let mut sph = Sph::new(sph_params(0.3, 50.0), &strands).unwrap();
            run(&mut strands, &mut sph, 200);
            assert!(sph.stats.neighbours > 0);
            state_hash(&strands)
        })
    };
    assert_eq!(hash(1), hash(2));
}

/// Mannequin B (the built-in, DFTL + shape + hair–hair), with or without `hair-hair`.
fn mannequin_b(hair_hair: bool) -> hairsim::scene::Prepared {
    let mut scene = (hairsim::builtin::find("mannequin-b").unwrap().scene)();
    if !hair_hair {
        scene.effects.retain(|e| e != "hair-hair");
    }
    scene.prepare().unwrap()
}

#[test]
fn the_stage_counter_says_whether_hair_hair_ran() {
    use hairsim::sim::{scene_inputs, Sim};
    use hairsim_core::{DefaultMath, Stage};
    for on in [false, true] {
        let prepared = mannequin_b(on);
        let mut sim = Sim::<16, DefaultMath>::new(&prepared, 1).unwrap();
        assert_eq!(sim.sph.is_some(), on);
        for k in 0..3 {
            let report = sim.step(&scene_inputs::<DefaultMath>(&prepared, k));
            let expected = if on { prepared.strands.len() as u32 } else { 0 };
            assert_eq!(report.runs(Stage::HairHair), expected, "hair-hair {on}");
            // The strands' own stages ran either way.
            assert_eq!(report.runs(Stage::Shape), prepared.strands.len() as u32);
        }
        if let Some(sph) = &sim.sph {
            assert_eq!(sph.stats.runs, 3);
        }
    }
}

#[test]
fn the_harness_gives_one_and_two_threads_the_same_hash_with_hair_hair() {
    use hairsim::sim::{scene_inputs, Sim};
    use hairsim_core::DefaultMath;
    let prepared = mannequin_b(true);
    let hash = |threads: usize| {
        let mut sim = Sim::<16, DefaultMath>::new(&prepared, threads).unwrap();
        for k in 0..200 {
            sim.step(&scene_inputs::<DefaultMath>(&prepared, k));
        }
        assert!(sim.is_finite());
        assert!(sim.sph.as_ref().unwrap().stats.neighbours > 0);
        sim.state_hash()
    };
    assert_eq!(hash(1), hash(2));
}

/// A flat wisp of `count` straight strands along +x, 8 mm apart along z, at height `y`: no node
/// is within the smoothing length (4 mm) of another.
fn sheet(y: f32, count: usize) -> Vec<Strand<N>> {
    (0..count)
        .map(|k| {
            let points: Vec<Vec3> = (0..12)
                .map(|i| Vec3::new(0.005 * i as f32, y, 0.008 * k as f32))
                .collect();
            Strand::<N>::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
        })
        .collect()
}

/// Two wisps 3 cm apart, whose nodes are all further than the smoothing length from each
/// other, rest for 0.5 s; then one is thrown at the other. While apart nothing is near anything
/// and the stage finds nothing; once they meet, every step must still find every pair: at each
/// step the accelerations equal, bit for bit, those of a stage built anew from that step's
/// state, the wisps interact, and the hair–hair forces stop them before they pass through.
#[test]
fn two_wisps_pushed_together_after_half_a_second_are_found() {
    let run_wisps = |stiffness: f32| {
        let mut strands = sheet(0.0, 5);
        strands.extend(sheet(0.03, 5));
        let sph_params = sph_params(stiffness, 20.0);
        let mut sph = Sph::new(sph_params, &strands).unwrap();
        let params = params();
        let ctx = StepContext::new(&params, Pose::IDENTITY, Pose::IDENTITY, &[]);
        let mut closest = f32::INFINITY;
        for k in 0..800 {
            if k == 500 {
                // Thrown at 0.3 m/s: 3 cm in 0.1 s.
                for s in &mut strands[5..] {
                    for v in &mut s.state.velocity[2..12] {
                        *v = Vec3::new(0.0, -0.3, 0.0);
                    }
                }
            }
            let acc = sph
                .accelerations(&strands, params.dt, Pose::IDENTITY)
                .to_vec();
            let fresh = Sph::new(sph_params, &strands)
                .unwrap()
                .accelerations(&strands, params.dt, Pose::IDENTITY)
                .to_vec();
            let bits = |a: &[Vec3]| {
                a.iter()
                    .map(|v| v.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&acc), bits(&fresh), "step {k}");
            if k == 499 {
                assert_eq!(sph.stats.neighbours, 0, "apart: no neighbour");
                assert_eq!(sph.stats.active, 0, "apart: nothing to work on");
            }
            let mut report = StepReport::default();
            step_strands::<Libm, N>(&ctx, &mut strands, 0, &[], Some(&acc), &mut report);
            closest = closest.min(centroid(&strands[5..]).y - centroid(&strands[..5]).y);
        }
        assert!(sph.stats.neighbours > 0, "they met: {:?}", sph.stats);
        closest
    };
    // They came together from 3 cm, and the hair–hair forces stopped them before they passed
    // through each other.
    let closest = run_wisps(0.5);
    assert!(
        closest > 0.0 && closest < 0.01,
        "the wisps met and held: closest {closest}"
    );
}

/// A run restarted from a recorded state (a new stage, its lists built anew) gives the same
/// bits as the run that went on.
#[test]
fn a_restart_from_a_recorded_state_gives_the_same_bits() {
    use hairsim::sim::{scene_inputs, Sim};
    use hairsim_core::DefaultMath;
    let prepared = mannequin_b(true);
    let mut whole = Sim::<16, DefaultMath>::new(&prepared, 2).unwrap();
    let mut restarted = Sim::<16, DefaultMath>::new(&prepared, 1).unwrap();
    for k in 0..200 {
        if k == 100 {
            // The recorded state: strands, head, grabs, step count.
            restarted = Sim::<16, DefaultMath>::new(&prepared, 1).unwrap();
            restarted.strands = whole.strands.clone();
            restarted.head = whole.head;
            restarted.grabs = whole.grabs.clone();
            restarted.steps = whole.steps;
        }
        let inputs = scene_inputs::<DefaultMath>(&prepared, k);
        whole.step(&inputs);
        if k >= 100 {
            restarted.step(&inputs);
            assert_eq!(whole.state_hash(), restarted.state_hash(), "step {k}");
        }
    }
    let stats = &whole.sph.as_ref().unwrap().stats;
    assert!(stats.neighbours > 0, "{stats:?}");
}
