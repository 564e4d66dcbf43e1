//! The harness end to end: built-in scenes, thread-count independence, the firmware hash,
//! the shipped scene files and the documented example.

use std::path::{Path, PathBuf};

use hairsim::builtin::BUILTINS;
use hairsim::cmd::run::Args;
use hairsim::run::{load, run, HairFileOptions, RunOptions};
use hairsim::scene::Scene;
use hairsim_core::scenes::firmware;
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
                ..RunOptions::default()
            },
        )
        .unwrap();
        assert!(summary.finite, "{}", b.name);
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
fn wind_runs_only_when_called_for_and_is_thread_independent() {
    let text = std::fs::read_to_string(workspace().join("scenes/windy-stand.toml")).unwrap();
    let (scene, prepared) =
        Scene::parse_and_prepare(&text, "windy-stand.toml", Path::new(".")).unwrap();
    assert!(prepared.wind.is_some());
    let listed: Vec<Effect> = scene
        .effects
        .iter()
        .map(|e| Effect::from_name(e).unwrap())
        .collect();
    assert_eq!(prepared.params.effects, Effects::from_slice(&listed));
    let loaded = hairsim::run::Loaded {
        source: "windy".into(),
        scene: scene.clone(),
        prepared: prepared.clone(),
    };
    let go = |threads, loaded: &hairsim::run::Loaded| {
        let mut loaded = loaded.clone();
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
    let windy = go(1, &loaded);
    assert_eq!(windy.state_hash, go(2, &loaded).state_hash);
    // The same scene without the effect: no wind at all, a different state.
    let mut calm = scene;
    calm.effects.retain(|e| e != "wind");
    let calm_prepared = calm.prepare().unwrap();
    assert!(calm_prepared.wind.is_none());
    let calm = hairsim::run::Loaded {
        source: "calm".into(),
        scene: calm,
        prepared: calm_prepared,
    };
    assert_ne!(go(1, &calm).state_hash, windy.state_hash);
}

#[test]
fn every_shipped_scene_passes_check() {
    let mut count = 0;
    for entry in std::fs::read_dir(workspace().join("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            hairsim::cmd::check::check(path.to_str().unwrap(), &HairFileOptions::default())
                .unwrap_or_else(|e| panic!("{e:#}"));
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
        e.starts_with("no-such-scene: no such scene: not a built-in scene (firmware, stand-1"),
        "{e}"
    );
    let e = load("head.hair", &HairFileOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("hair files arrive with the hairfile module"),
        "{e}"
    );
}

#[test]
fn out_is_refused_until_the_export_module_lands() {
    let loaded = load("stand-2", &HairFileOptions::default()).unwrap();
    let e = run(
        &loaded,
        &RunOptions {
            out: Some(std::env::temp_dir().join("hairsim-out")),
            ..RunOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("arrive with the export module"), "{e}");
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
