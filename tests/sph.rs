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
    let mut acc = vec![Vec3::ZERO; strands.len() * N];
    for _ in 0..steps {
        sph.accelerations(strands, params.dt, &mut acc);
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
