//! The harness end to end: built-in scenes, thread-count independence, the firmware hash,
//! the shipped scene files and the documented example.

use std::path::{Path, PathBuf};

use hairsim::builtin::BUILTINS;
use hairsim::cmd::run::Args;
use hairsim::run::{load, run, HairFileOptions, RunOptions};
use hairsim::scene::Scene;
use hairsim_core::scenes::{firmware, firmware_dftl};
use hairsim_core::{DefaultMath, Effect, Effects, Params, Solver, World};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn dftl_is_built() -> bool {
    Params {
        solver: Solver::Dftl,
        effects: Effects::NONE,
        ..Params::DEFAULT
    }
    .validate()
    .is_ok()
}

#[test]
fn run_firmware_json_gives_the_firmwares_hash() {
    let text = hairsim::cmd::run::run(&Args {
        scene: Some("firmware".into()),
        json: true,
        threads: 1,
        ..Args::default()
    })
    .unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut world: Box<World<{ firmware::STRANDS }, { firmware::NODES }, DefaultMath>> =
        Box::default();
    let expected = firmware::run(&mut world, firmware::STEPS).unwrap();
    assert_eq!(json["state_hash"], format!("0x{expected:016x}"));
    assert_eq!(json["steps"], u64::from(firmware::STEPS));
    for key in [
        "scene",
        "solver",
        "dt",
        "strands",
        "nodes",
        "max_stretch",
        "max_penetration",
        "finite",
        "ms_per_step",
        "iterations",
        "caps_hit",
        "rolled_back",
        "collider_forces",
        "groom",
    ] {
        assert!(json.get(key).is_some(), "{key} missing from {text}");
    }
}

#[test]
fn the_default_scene_runs() {
    let text = hairsim::cmd::run::run(&Args {
        threads: 1,
        steps: Some(10),
        ..Args::default()
    })
    .unwrap();
    assert!(text.contains("scene       firmware"), "{text}");
}

#[test]
fn every_builtin_runs_100_steps_and_stays_finite() {
    for b in BUILTINS {
        let loaded = load(b.name, &HairFileOptions::default());
        if (b.scene)().solver == "dftl" && !dftl_is_built() {
            let e = loaded.unwrap_err().to_string();
            assert!(e.contains("dftl solver is not built yet"), "{e}");
            continue;
        }
        let loaded = loaded.unwrap_or_else(|e| panic!("{}: {e:#}", b.name));
        let summary = run(
            &loaded,
            &RunOptions {
                steps: Some(100),
                // Mannequin A is 349,000 vertices: all cores (the bits do not depend on it).
                threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
                ..RunOptions::default()
            },
        )
        .unwrap();
        assert!(summary.finite, "{}", b.name);
        assert!(
            summary.max_stretch < 1e-2,
            "{}: stretch {}",
            b.name,
            summary.max_stretch
        );
        assert_eq!(summary.steps, 100);
        assert_eq!(summary.rolled_back, 0, "{}", b.name);
    }
}

/// Blocks are fixed by the scene, reports merged in block order: the thread count changes
/// nothing, not the state, not the forces.
#[test]
fn one_and_two_threads_give_the_same_bits() {
    let mut loaded = load("head-2", &HairFileOptions::default()).unwrap();
    loaded.prepared.block = 4; // 25 strands → 7 blocks
    let with = |threads| {
        run(
            &loaded,
            &RunOptions {
                steps: Some(200),
                threads,
                ..RunOptions::default()
            },
        )
        .unwrap()
    };
    let (one, two) = (with(1), with(2));
    assert_eq!(one.state_hash, two.state_hash);
    assert_eq!(one.collider_forces, two.collider_forces);
    assert_eq!((one.threads, two.threads), (1, 2));
    // And the hash moved: the run did something.
    assert_ne!(
        one.state_hash,
        run(
            &loaded,
            &RunOptions {
                steps: Some(1),
                ..RunOptions::default()
            }
        )
        .unwrap()
        .state_hash
    );
}

#[test]
fn the_groom_measure_covers_every_interior_node() {
    for scene in ["firmware", "firmware-dftl"] {
        let summary = hairsim::run::run_builtin(scene, &RunOptions::default()).unwrap();
        let groom = summary.groom;
        assert_eq!(groom.nodes, summary.nodes - 2 * summary.strands, "{scene}");
        assert!((0.0..=1.0).contains(&groom.kinked), "{scene}: {groom:?}");
        for angle in [groom.mean_turning, groom.rest_mean_turning] {
            assert!(
                (0.0..=core::f32::consts::PI).contains(&angle),
                "{scene}: {groom:?}"
            );
        }
        // The firmware scenes' strands are curved at rest.
        assert!(groom.rest_mean_turning > 0.0, "{scene}: {groom:?}");
        assert!(summary.to_text().contains("groom       mean turning"));
    }
}

#[test]
fn run_firmware_dftl_gives_the_firmwares_hash() {
    let summary = hairsim::run::run_builtin("firmware-dftl", &RunOptions::default()).unwrap();
    let mut world: Box<World<{ firmware_dftl::STRANDS }, { firmware_dftl::NODES }, DefaultMath>> =
        Box::default();
    let expected = firmware_dftl::run(&mut world, firmware_dftl::STEPS).unwrap();
    assert_eq!(summary.state_hash, format!("0x{expected:016x}"));
    assert!(summary.finite);
}

#[test]
fn wind_runs_only_when_called_for_and_is_thread_independent() {
    let text = std::fs::read_to_string(workspace().join("scenes/windy-stand.toml")).unwrap();
    let (scene, prepared) =
        Scene::parse_and_prepare(&text, "windy-stand.toml", Path::new(".")).unwrap();
    let listed: Vec<Effect> = scene
        .effects
        .iter()
        .map(|e| Effect::from_name(e).unwrap())
        .collect();
    assert_eq!(prepared.params.effects, Effects::from_slice(&listed));
    assert!(prepared.params.effects.contains(Effect::Wind));
    assert_eq!(prepared.params.wind.seed, 7);
    let go = |threads, scene: &Scene| {
        let mut loaded = hairsim::run::Loaded {
            source: "windy".into(),
            scene: scene.clone(),
            prepared: scene.prepare().unwrap(),
        };
        loaded.prepared.block = 1;
        run(
            &loaded,
            &RunOptions {
                steps: Some(100),
                threads,
                ..RunOptions::default()
            },
        )
        .unwrap()
    };
    let windy = go(1, &scene);
    assert_eq!(windy.state_hash, go(2, &scene).state_hash);
    // The same scene without the effect: the [wind] table stays, the wind does not blow.
    let mut calm = scene;
    calm.effects.retain(|e| e != "wind");
    assert!(!calm
        .prepare()
        .unwrap()
        .params
        .effects
        .contains(Effect::Wind));
    assert_ne!(go(1, &calm).state_hash, windy.state_hash);
}

/// SPH runs when `hair-hair` is on: it changes the state, and not with the thread count.
#[test]
fn hair_hair_runs_when_called_for_and_is_thread_independent() {
    let mut scene = hairsim::builtin::find("head-2")
        .map(|b| (b.scene)())
        .unwrap();
    let go = |threads, scene: &Scene| {
        let mut loaded = hairsim::run::Loaded {
            source: "sph".into(),
            scene: scene.clone(),
            prepared: scene.prepare().unwrap(),
        };
        loaded.prepared.block = 4;
        run(
            &loaded,
            &RunOptions {
                steps: Some(200),
                threads,
                ..RunOptions::default()
            },
        )
        .unwrap()
    };
    let without = go(1, &scene);
    scene.effects.push("hair-hair".into());
    scene.hair_hair = Some(hairsim::scene::HairHairSpec {
        smoothing_length: Some(0.02),
        // Pressure everywhere (no rest density to stay under): strands push apart.
        rest_density: Some(0.0),
        stiffness: Some(0.5),
        ..Default::default()
    });
    let with = go(1, &scene);
    assert!(with.finite);
    assert_ne!(with.state_hash, without.state_hash);
    assert_eq!(with.state_hash, go(2, &scene).state_hash);
}

#[test]
fn every_shipped_scene_passes_check_and_runs_200_steps() {
    let mut count = 0;
    for entry in std::fs::read_dir(workspace().join("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            hairsim::cmd::check::check(path.to_str().unwrap(), &HairFileOptions::default())
                .unwrap_or_else(|e| panic!("{e:#}"));
            let loaded = load(path.to_str().unwrap(), &HairFileOptions::default()).unwrap();
            let summary = run(
                &loaded,
                &RunOptions {
                    steps: Some(200),
                    threads: 2,
                    ..RunOptions::default()
                },
            )
            .unwrap();
            assert!(summary.finite, "{}", path.display());
            assert!(
                summary.max_stretch < 1e-2,
                "{}: stretch {}",
                path.display(),
                summary.max_stretch
            );
            count += 1;
        }
    }
    assert!(count >= 4, "{count} scenes");
}

#[test]
fn the_documented_example_passes_check() {
    let doc = std::fs::read_to_string(workspace().join("docs/scene-format.md")).unwrap();
    let start = doc.find("```toml\n").expect("a toml block") + "```toml\n".len();
    let end = start + doc[start..].find("```").unwrap();
    let (_, prepared) =
        Scene::parse_and_prepare(&doc[start..end], "scene-format.md", Path::new("."))
            .unwrap_or_else(|e| panic!("{e}"));
    assert!(!prepared.strands.is_empty());
}

#[test]
fn a_missing_scene_is_one_clear_error() {
    let e = load("no-such-scene", &HairFileOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(
            "no-such-scene: no such scene: not a built-in scene (firmware, firmware-dftl, haptic-dftl, stand-1"
        ),
        "{e}"
    );
    let e = load("head.hair", &HairFileOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("head.hair (default scene): hair.file.path: cannot read \"head.hair\""),
        "{e}"
    );
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hairsim-harness-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn out_writes_frames_the_final_obj_and_pictures() {
    let dir = temp_dir("out");
    let loaded = load("stand-1", &HairFileOptions::default()).unwrap();
    let summary = run(
        &loaded,
        &RunOptions {
            steps: Some(40),
            every: Some(20),
            out: Some(dir.clone()),
            ..RunOptions::default()
        },
    )
    .unwrap();
    for file in [
        "final.obj",
        "final.png",
        "frames/frame_000020.obj",
        "frames/frame_000040.obj",
    ] {
        assert!(
            dir.join(file).is_file(),
            "{file} missing; wrote {:?}",
            summary.written
        );
    }
    // final.obj: `v` lines strand by strand, one `l` line per strand — leaders and followers.
    let obj = std::fs::read_to_string(dir.join("final.obj")).unwrap();
    let lines = obj.lines().filter(|l| l.starts_with("l ")).count();
    assert_eq!(lines, 3 + 69);
    assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), 72 * 30);
    std::fs::remove_dir_all(dir).ok();
}

/// A hair file as the scene: read, resampled, a head fitted to its roots, run.
#[test]
fn a_hair_file_runs_in_a_default_scene_with_a_fitted_head() {
    let dir = temp_dir("hairfile");
    let roots = hairsim::scene::generate::scalp_roots(40, hairsim_core::Vec3::ZERO, 10.0, 1.0);
    // In centimetres, 60 vertices per strand: --scale 0.01, resampled to the default nodes.
    let strands: Vec<Vec<hairsim_core::Vec3>> = roots
        .iter()
        .map(|(root, normal)| {
            (0..60)
                .map(|i| *root + *normal * (0.5 * i as f32))
                .collect()
        })
        .collect();
    let path = dir.join("wig.hair");
    hairsim::export::save(&path, &strands).unwrap();
    let options = HairFileOptions {
        scale: Some(0.01),
        up: None,
    };
    let loaded = load(path.to_str().unwrap(), &options).unwrap();
    assert_eq!(loaded.prepared.strands.len(), 40);
    assert_eq!(
        loaded.prepared.max_nodes(),
        hairsim::hairscene::DEFAULT_NODES as usize
    );
    assert_eq!(loaded.prepared.colliders.len(), 1);
    assert!(loaded.prepared.params.effects.contains(Effect::Collisions));
    let summary = run(
        &loaded,
        &RunOptions {
            steps: Some(50),
            ..RunOptions::default()
        },
    )
    .unwrap();
    assert!(summary.finite);
    // The same file from a scene file, relative to the scene's folder; too many vertices
    // without `nodes` is an error that says what to do.
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "format = 1\nname = \"wig\"\nsolver = \"rod\"\ndt = 0.001\nsteps = 5\neffects = [\"gravity\"]\n[hair.file]\npath = \"wig.hair\"\nscale = 0.01\nnodes = 20\n",
    )
    .unwrap();
    let (_, prepared) = Scene::load(&scene).unwrap();
    assert_eq!(prepared.strands.len(), 40);
    std::fs::write(
        &scene,
        "format = 1\nname = \"wig\"\nsolver = \"rod\"\ndt = 0.001\nsteps = 5\neffects = [\"gravity\"]\n[hair.file]\npath = \"wig.hair\"\nscale = 0.001\n",
    )
    .unwrap();
    let dense: Vec<Vec<hairsim_core::Vec3>> = strands
        .iter()
        .map(|s| {
            (0..200)
                .map(|i| s[0] + (s[1] - s[0]) * (0.2 * i as f32))
                .collect()
        })
        .collect();
    hairsim::export::save(&path, &dense).unwrap();
    let e = Scene::load(&scene).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "{}:7: hair.file.nodes: the file's strands have 200 to 200 vertices, allowed 3 to 128: give nodes = N to resample them",
            scene.display()
        )
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn run_options_are_range_checked() {
    let loaded = load("stand-2", &HairFileOptions::default()).unwrap();
    let refused = |options: RunOptions| run(&loaded, &options).unwrap_err().to_string();
    assert_eq!(
        refused(RunOptions {
            threads: 0,
            ..RunOptions::default()
        }),
        "--threads: 0 is out of range, allowed 1 to 1024"
    );
    assert_eq!(
        refused(RunOptions {
            every: Some(0),
            ..RunOptions::default()
        }),
        "--every: 0 is out of range, allowed 1 or more steps"
    );
    assert_eq!(
        refused(RunOptions {
            steps: Some(0),
            ..RunOptions::default()
        }),
        "--steps: 0 is out of range, allowed 1 or more"
    );
}

/// The scene's `[rod] twist` reaches the core: Newton and hair-optimised twist differ.
#[test]
fn the_twist_method_is_the_scenes() {
    // Curved strands on a shaking head: the twist has work to do.
    let mut scene = hairsim::builtin::firmware_scene();
    let go = |scene: &Scene| {
        let loaded = hairsim::run::Loaded {
            source: "twist".into(),
            scene: scene.clone(),
            prepared: scene.prepare().unwrap(),
        };
        run(
            &loaded,
            &RunOptions {
                steps: Some(100),
                ..RunOptions::default()
            },
        )
        .unwrap()
    };
    scene.rod = Some(hairsim::scene::RodSpec {
        twist: Some("hair-optimised".into()),
        ..Default::default()
    });
    let optimised = go(&scene);
    scene.rod = Some(hairsim::scene::RodSpec {
        twist: Some("newton".into()),
        ..Default::default()
    });
    assert_eq!(
        scene.prepare().unwrap().params.rod.twist,
        hairsim_core::params::TwistMethod::Newton
    );
    let newton = go(&scene);
    assert!(optimised.finite && newton.finite);
    assert_ne!(optimised.state_hash, newton.state_hash);
}

/// The haptic scene reports the force its grab transmits.
#[test]
fn the_haptic_scene_reports_its_grab_force() {
    let summary = hairsim::run::run_builtin(
        "haptic",
        &RunOptions {
            steps: Some(300),
            ..RunOptions::default()
        },
    )
    .unwrap();
    let forces = summary.grab_forces.expect("grab forces");
    assert_eq!(forces.len(), 1);
    assert!(forces[0].iter().any(|f| *f != 0.0), "{forces:?}");
    assert_eq!(summary.grab_status.unwrap(), vec!["held".to_string()]);
}

/// `[material] tip_stiffness` reaches the rod's bending forces: a softer tip changes the run.
#[test]
fn a_fading_bending_stiffness_reaches_the_rod() {
    let mut scene = hairsim::builtin::firmware_scene();
    let go = |scene: &Scene| {
        let loaded = hairsim::run::Loaded {
            source: "fade".into(),
            scene: scene.clone(),
            prepared: scene.prepare().unwrap(),
        };
        run(
            &loaded,
            &RunOptions {
                steps: Some(200),
                ..RunOptions::default()
            },
        )
        .unwrap()
    };
    let uniform = go(&scene);
    scene.material = Some(hairsim::scene::MaterialSpec {
        tip_stiffness: Some(0.2),
        ..Default::default()
    });
    let faded = go(&scene);
    assert!(faded.finite);
    assert_ne!(uniform.state_hash, faded.state_hash);
}
