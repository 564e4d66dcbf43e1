//! The viewer's simulation (what `hairsim view`'s page runs, here on the host) gives the bits
//! of `hairsim run`: the same scenes, hair files read from bytes as from disk, and the page's
//! switches and grabs going through the scene's checks.

use std::path::PathBuf;

use hairsim::run::{load, run, HairFileOptions, RunOptions};
use hairsim_core::{Effect, Solver, Vec3};
use hairsim_viewer::session::{Session, Source, HAND_COUPLING, HAND_FORCE_LIMIT};

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

/// DFTL strands held by grabs (two coupled, one prescribed) on a turning head: a block holding
/// a grabbed strand steps strand by strand, in the page as in `hairsim run`.
#[test]
fn dftl_strands_held_by_grabs_give_the_bits_of_hairsim_run() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/dftl-grabs.toml");
    let source = Source::SceneFile {
        name: "dftl-grabs.toml".into(),
        text: std::fs::read_to_string(path).unwrap(),
        hair: None,
    };
    let loaded = load(path, &HairFileOptions::default()).unwrap();
    let options = RunOptions {
        threads: 2,
        ..RunOptions::default()
    };
    let native = run(&loaded, &options).unwrap();
    // The grabs hold throughout.
    assert_eq!(
        native.grab_status.as_deref(),
        Some(&["held"; 3].map(String::from)[..])
    );
    assert_eq!(viewer_hash(source, 1500), native.state_hash);
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
    session.grab(0, 5).unwrap();
    session.step(10);
    assert_eq!(session.status()["grab"], "held");
}

/// One 30 cm hair held at its root (`scenes/one-hair.toml`, as the page gets a scene file), let
/// hang for 3 s with `solver`.
fn one_hanging_hair(solver: Solver) -> Session {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/one-hair.toml");
    let source = Source::SceneFile {
        name: "one-hair.toml".into(),
        text: std::fs::read_to_string(path).unwrap(),
        hair: None,
    };
    let mut session = Session::load(source).unwrap();
    session.set_solver(solver).unwrap();
    session.step(3000);
    session
}

/// Node `node` of strand 0 where it is, m.
fn node_position(session: &Session, node: usize) -> Vec3 {
    let mut positions = Vec::new();
    let mut offsets = Vec::new();
    session.positions(&mut positions, &mut offsets);
    let at = 3 * (offsets[0] as usize + node);
    Vec3::new(positions[at], positions[at + 1], positions[at + 2])
}

/// A component of the status's vector `key`.
fn status_vector(status: &serde_json::Value, key: &str) -> Vec3 {
    let component = |i: usize| status[key][i].as_f64().unwrap() as f32;
    Vec3::new(component(0), component(1), component(2))
}

#[test]
fn the_hand_pulls_the_hair_toward_its_target_harder_the_further_it_drags() {
    for solver in [Solver::Rod, Solver::Dftl] {
        let mut session = one_hanging_hair(solver);
        // A middle node, dragged sideways and up.
        let node = 15;
        let start = node_position(&session, node);
        session.grab(0, node).unwrap();
        // Up and toward the root's side: within the strand's reach, hanging (the rod) or held
        // out along +x by its rest shape (DFTL).
        let direction = Vec3::new(-1.0, 1.0, 0.0).normalize();
        let mut forces = Vec::new();
        for k in 1..=4 {
            let target = start + direction * (0.01 * k as f32);
            session.move_hand(target);
            session.step(1000);
            // The strand follows: the node within 1 mm of the hand.
            let lag = (node_position(&session, node) - target).length();
            assert!(
                lag < 1.0e-3,
                "{solver:?} drag {k}: the node is {lag} m from the hand"
            );
            // The mean over 0.5 s: the hanging part still swings a little.
            let mut sum = Vec3::ZERO;
            for _ in 0..500 {
                session.step(1);
                let status = session.status();
                assert_eq!(status["grab"], "held", "{solver:?} drag {k}");
                sum += status_vector(&status, "grab_force");
            }
            let force = sum / 500.0;
            eprintln!("{solver:?} drag {k}: {force}, the node {lag:.1e} m from the hand");
            forces.push(force);
        }
        // Each centimetre further, the hand pulls harder along the drag: the force's change
        // points along it (the force itself also holds the strand's weight and, with DFTL, its
        // shape, which at the first centimetre can outweigh the drag's share).
        assert!(
            forces
                .windows(2)
                .all(|w| (w[1] - w[0]).dot(direction) > 0.0),
            "{solver:?}: {forces:?}"
        );
        session.release();
        session.step(1);
        assert_eq!(session.status()["grab"], "none");
        assert_eq!(session.status()["grab_force"][0], 0.0);
    }
}

/// The hand's grab is coupled (`session::HAND_COUPLING`): pulled straight down past the
/// strand's reach, it holds, the strand taut and inextensible, with the spring's force
/// `K |x − T|`; pulled on, it slips when that force passes `HAND_FORCE_LIMIT`, not before.
#[test]
fn the_hand_holds_past_the_strands_reach_and_slips_only_on_its_force_limit() {
    let stiffness = HAND_COUPLING.stiffness;
    for solver in [Solver::Rod, Solver::Dftl] {
        let mut session = one_hanging_hair(solver);
        let tip = 30;
        let root = node_position(&session, 1);
        // The rest arc length from node 1 to the tip: 29 segments of 1 cm.
        let reach = 0.29;
        session.grab(0, tip).unwrap();
        // 5 cm past the reach (a prescribed grab slips at once), reached over 0.5 s.
        let down = Vec3::NEG_Y;
        let past = |d: f32| root + down * (reach + d);
        let start = node_position(&session, tip);
        for k in 1..=500 {
            let d = (past(0.05) - start) * (k as f32 / 500.0);
            session.move_hand(start + d);
            session.step(1);
        }
        session.step(500);
        let status = session.status();
        assert_eq!(status["grab"], "held", "{solver:?}: 5 cm past its reach");
        let stretch = (node_position(&session, tip) - past(0.05)).length();
        let force = status_vector(&status, "grab_force");
        let segment_stretch = status["report"]["max_stretch"].as_f64().unwrap();
        eprintln!(
            "{solver:?}: 5 cm past the reach, held: the spring stretched {stretch:.4} m, {:.4} N; \
             segments stretched {segment_stretch:.1e}",
            force.length(),
        );
        assert!(stretch > 0.049, "{solver:?}: the strand gave {stretch} m");
        let expected = stiffness * stretch;
        assert!(
            (force.length() - expected).abs() < 0.01 * expected,
            "{solver:?}: {force} against K |x − T| = {expected}"
        );
        assert!(segment_stretch < 1.0e-3, "{solver:?}: {segment_stretch}");
        // On, 0.1 mm a step: the force grows by 5e-4 N a step and passes the limit 20 cm
        // past the reach.
        session.take_events();
        let mut slipped_at = None;
        for step in 1..=4000 {
            session.move_hand(past(0.05 + 1.0e-4 * step as f32));
            session.step(1);
            if session.status()["grab"] == "slipped" {
                slipped_at = Some(0.05 + 1.0e-4 * step as f32);
                break;
            }
        }
        let slipped_at = slipped_at.expect("pulled far past the force limit, the grab held");
        let held = session.take_events()["slipped_at"].as_f64().unwrap() as f32;
        eprintln!("{solver:?}: slipped {slipped_at:.4} m past the reach, holding {held:.4} N");
        let limit = HAND_FORCE_LIMIT;
        assert!(
            (0.99 * limit..=limit).contains(&held),
            "{solver:?}: {held} N"
        );
        let expected = limit / stiffness;
        assert!(
            (slipped_at - expected).abs() < 0.01,
            "{solver:?}: {slipped_at} m"
        );
    }
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
    assert_eq!(stuck["steps"], 100, "{stuck}");
    assert_eq!(
        stuck["rolled_back_min"],
        session.status()["strands"],
        "{stuck}"
    );
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
