//! The viewer's simulation (what `hairsim view`'s page runs, here on the host) gives the bits
//! of `hairsim run`: the same scenes, hair files read from bytes as from disk, and the page's
//! switches and grabs going through the scene's checks.

use std::path::PathBuf;

use hairsim::run::{load, run, HairFileOptions, RunOptions};
use hairsim_core::{Effect, Solver, Vec3};
use hairsim_viewer::session::{Session, Source};

/// `hairsim run SCENE --steps N`'s state hash.
fn native_hash(scene: &str, steps: u64) -> String {
    let loaded = load(scene, &HairFileOptions::default()).unwrap();
    let options = RunOptions {
        steps: Some(steps),
        threads: 2,
        ..RunOptions::default()
    };
    run(&loaded, &options).unwrap().state_hash
}

fn viewer_hash(source: Source, steps: u32) -> String {
    let mut session = Session::load(source).unwrap();
    // In uneven batches, as the page steps: the bits never depend on them.
    let mut done = 0;
    for batch in [1, 16, 17].into_iter().cycle() {
        let n = batch.min(steps - done);
        session.step(n);
        done += n;
        if done == steps {
            break;
        }
    }
    session.status()["state_hash"].as_str().unwrap().to_string()
}

#[test]
fn builtin_scenes_give_the_bits_of_hairsim_run() {
    for (scene, steps) in [("firmware", 400), ("firmware-dftl", 400), ("head-2", 60)] {
        let page = viewer_hash(Source::builtin(scene).unwrap(), steps);
        assert_eq!(page, native_hash(scene, u64::from(steps)), "{scene}");
    }
}

#[test]
fn a_hair_file_from_bytes_gives_the_bits_of_hairsim_run_on_the_path() {
    let samples = std::env::var_os("HAIRSIM_SAMPLES")
        .map(PathBuf::from)
        .expect("HAIRSIM_SAMPLES names the folder of the sample hair files");
    let path = samples.join("sintel_hair.tfx");
    let bytes = std::fs::read(&path).unwrap();
    let source = Source::HairFile {
        name: "sintel_hair.tfx".into(),
        bytes,
    };
    let page = viewer_hash(source, 30);
    assert_eq!(page, native_hash(path.to_str().unwrap(), 30));
}

#[test]
fn a_forged_hair_file_is_refused_with_the_readers_message() {
    let source = Source::HairFile {
        name: "forged.tfx".into(),
        bytes: vec![7; 40],
    };
    let error = Session::load(source).unwrap_err();
    assert!(error.contains("forged.tfx"), "{error}");
}

#[test]
fn switches_go_through_the_scenes_checks() {
    let mut session = Session::load(Source::builtin("firmware").unwrap()).unwrap();
    session.step(10);
    // The rod cannot preserve shape: refused, the running scene kept.
    assert!(session.set_effect(Effect::Shape, true).is_err());
    assert_eq!(session.steps(), 10);
    session.set_effect(Effect::Wind, false).unwrap();
    session.set_twist("newton").unwrap();
    assert_eq!(session.status()["twist"], "newton");
    session.set_solver(Solver::Dftl).unwrap();
    assert_eq!(session.steps(), 0);
    assert_eq!(session.status()["solver"], "dftl");
    assert!(session.grab(0, 5).is_err(), "DFTL has no grab");
}

#[test]
fn the_hand_pulls_the_hair_toward_its_target_harder_the_further_it_drags() {
    // A scene file as the page gets it (by text): one 30 cm hair, let hang for 3 s.
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/one-hair.toml");
    let source = Source::SceneFile {
        name: "one-hair.toml".into(),
        text: std::fs::read_to_string(path).unwrap(),
        hair: None,
    };
    let mut session = Session::load(source).unwrap();
    session.step(3000);
    let mut positions = Vec::new();
    let mut offsets = Vec::new();
    session.positions(&mut positions, &mut offsets);
    // A middle node, dragged sideways and up: toward the root's height, so the target
    // stays within the strand's reach (a target out of reach lets go).
    let node = (offsets[1] - offsets[0]) as usize / 2;
    let at = 3 * (offsets[0] as usize + node);
    let start = Vec3::new(positions[at], positions[at + 1], positions[at + 2]);
    session.grab(0, node).unwrap();
    let direction = Vec3::new(1.0, 1.0, 0.0).normalize();
    let mut magnitudes = Vec::new();
    for k in 1..=4 {
        let target = start + direction * (0.01 * k as f32);
        session.move_hand(target);
        session.step(1000);
        // The mean over 0.5 s: the hanging part still swings a little.
        let mut sum = Vec3::ZERO;
        for _ in 0..500 {
            session.step(1);
            let status = session.status();
            assert_eq!(status["grab"], "held", "drag {k}");
            let f = &status["grab_force"];
            let component = |i: usize| f[i].as_f64().unwrap() as f32;
            sum += Vec3::new(component(0), component(1), component(2));
        }
        let force = sum / 500.0;
        eprintln!("drag {k}: {force}");
        assert!(force.dot(direction) > 0.0, "drag {k}: {force}");
        magnitudes.push(force.length());
    }
    assert!(magnitudes.windows(2).all(|w| w[1] > w[0]), "{magnitudes:?}");
    session.release();
    session.step(1);
    assert_eq!(session.status()["grab"], "none");
    assert_eq!(session.status()["grab_force"][0], 0.0);
}

/// The rod with inextensibility off stretches its strands many times over until every strand
/// is rolled back at every step (the page says the simulation is stuck); turned back on, the
/// stretched strands are pulled back and the hair moves again: no roll-back and every
/// segment within 1 % of its rest length over the next second.
#[test]
fn inextensibility_turned_back_on_recovers_the_hair() {
    let mut session = Session::load(Source::builtin("head-2").unwrap()).unwrap();
    assert_eq!(session.status()["solver"], "rod");
    session.step(100);
    session.set_effect(Effect::Inextensibility, false).unwrap();
    session.step(400);
    session.take_events();
    session.step(100);
    let stuck = session.take_events();
    assert_eq!(stuck["all_rolled_back"], 100, "{stuck}");
    assert!(stuck["max_stretch"].as_f64().unwrap() > 1.0, "{stuck}");
    let hash = session.status()["state_hash"].clone();
    session.step(10);
    assert_eq!(
        session.status()["state_hash"],
        hash,
        "stuck: the state no longer changes"
    );
    session.take_events();

    session.set_effect(Effect::Inextensibility, true).unwrap();
    // The first steps push pulled-back nodes out of the head (a contact stretches its
    // segments until the projection catches up); from the second tenth of a second on,
    // every segment is within 1 %.
    for tenth in 0..10 {
        session.step(100);
        let events = session.take_events();
        assert_eq!(events["rolled_back_max"], 0, "tenth {tenth}: {events}");
        let stretch = events["max_stretch"].as_f64().unwrap();
        assert!(tenth == 0 || stretch < 0.01, "tenth {tenth}: {events}");
    }
    assert_ne!(session.status()["state_hash"], hash);
}

/// An effect the scene cannot use is refused with the reason the panel shows beside it.
#[test]
fn effects_a_scene_cannot_use_say_why() {
    let mut session = Session::load(Source::builtin("head-2").unwrap()).unwrap();
    let unusable = session.status()["unusable"].clone();
    for (effect, reason) in [
        ("wind", "no [wind]"),
        ("grabs", "no [[grabs]]"),
        ("shape", "rod has no shape"),
        ("hair-hair", "not in the page"),
    ] {
        let said = unusable[effect].as_str().unwrap_or_default();
        assert!(said.contains(reason), "{effect}: {said:?}");
    }
    assert!(unusable.get("gravity").is_none(), "{unusable}");
    let error = session.set_effect(Effect::Wind, true).unwrap_err();
    assert!(
        error.starts_with("wind: the scene has no [wind]"),
        "{error}"
    );
}

/// hairsim's own `.obj`, `.ply` and `.usda` exports run as hair files: by path in `hairsim
/// run`, named by a scene file, and dropped on the page as bytes, with the same bits.
#[test]
fn hairsims_text_exports_run_as_hair_files() {
    let loaded = load("head-1", &HairFileOptions::default()).unwrap();
    let strands: Vec<Vec<Vec3>> = loaded
        .prepared
        .strands
        .iter()
        .map(|s| s.points.clone())
        .collect();
    let dir = std::env::temp_dir().join(format!("hairsim-viewer-exports-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for format in ["obj", "ply", "usda"] {
        let name = format!("groom.{format}");
        let path = dir.join(&name);
        hairsim::export::save(&path, &strands).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let page = viewer_hash(
            Source::HairFile {
                name: name.clone(),
                bytes: bytes.clone(),
            },
            20,
        );
        assert_eq!(page, native_hash(path.to_str().unwrap(), 20), "{name}");
        let scene = format!(
            "format = 1\nname = \"from-{format}\"\nsolver = \"dftl\"\ndt = 0.001\nsteps = 20\n\
             effects = [\"gravity\", \"inextensibility\", \"shape\"]\n\n[hair.file]\npath = \"{name}\"\n"
        );
        assert_eq!(
            hairsim_viewer::session::scene_hair_file("s.toml", &scene).unwrap(),
            Some(name.clone())
        );
        let source = Source::SceneFile {
            name: "s.toml".into(),
            text: scene,
            hair: Some((name.clone(), bytes)),
        };
        assert!(
            Session::load(source).is_ok(),
            "{name} named by a scene file"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
