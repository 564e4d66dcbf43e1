//! Record and replay: a recorded run replays; a tampered recording fails at the right step;
//! recordings from a newer format or another build are refused before anything runs.

use std::path::{Path, PathBuf};

use hairsim::record::{BuildIdentity, Recording};
use hairsim::run::{load, replay, run, HairFileOptions, RunOptions};
use hairsim_core::DefaultMath;

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("hairsim-{}-{name}.rec", std::process::id()))
}

/// Records 300 steps of the haptic scene (a moving grab, so inputs vary), a hash every 50.
fn record(name: &str) -> (PathBuf, Recording) {
    let path = temp(name);
    let loaded = load("haptic", &HairFileOptions::default()).unwrap();
    run(
        &loaded,
        &RunOptions {
            steps: Some(300),
            every: Some(50),
            record: Some(path.clone()),
            ..RunOptions::default()
        },
    )
    .unwrap();
    let recording = Recording::read(&path, &BuildIdentity::current::<DefaultMath>()).unwrap();
    (path, recording)
}

fn rewrite(path: &Path, recording: &Recording) {
    recording.write(path).unwrap();
}

#[test]
fn a_recorded_run_replays() {
    let (path, recording) = record("ok");
    assert_eq!(recording.inputs.len(), 300);
    assert_eq!(recording.checkpoints.len(), 6);
    assert_eq!(recording.checkpoints[5].step, 300);
    // The grab target moves: the inputs really vary.
    assert_ne!(recording.inputs[0].grabs, recording.inputs[299].grabs);
    let summary = replay(&path, 2).unwrap();
    assert_eq!(summary.state_hash, recording.checkpoints[5].hash);
    std::fs::remove_file(path).ok();
}

#[test]
fn a_tampered_hash_fails_at_its_step_with_both_hashes() {
    let (path, mut recording) = record("hash");
    let good = recording.checkpoints[2].hash.clone();
    recording.checkpoints[2].hash = "0x0123456789abcdef".into();
    rewrite(&path, &recording);
    let e = format!("{:#}", replay(&path, 1).unwrap_err());
    assert!(
        e.contains(&format!(
            "replay differs at step 150: recorded state hash 0x0123456789abcdef, replayed {good}"
        )),
        "{e}"
    );
    std::fs::remove_file(path).ok();
}

#[test]
fn a_tampered_input_fails_at_the_next_checkpoint() {
    let (path, mut recording) = record("input");
    // The head's position in step 150 (inputs[149]) moves the roots (root coupling) in the
    // state checked after that step; steps 101 to 149 match, so the failure names step 150.
    recording.inputs[149].head[0] += 0.001;
    rewrite(&path, &recording);
    let e = format!("{:#}", replay(&path, 1).unwrap_err());
    assert!(e.contains("replay differs at step 150:"), "{e}");
    std::fs::remove_file(path).ok();
}

#[test]
fn newer_formats_other_builds_and_strangers_are_refused() {
    let (path, mut recording) = record("refuse");
    let current = BuildIdentity::current::<DefaultMath>();

    recording.version = 2;
    rewrite(&path, &recording);
    let e = format!("{:#}", replay(&path, 1).unwrap_err());
    assert!(
        e.contains("recording format 2 is newer than this build reads (format 1)"),
        "{e}"
    );

    recording.version = 1;
    recording.build.math = "fast-math-from-elsewhere".into();
    rewrite(&path, &recording);
    let e = format!("{:#}", replay(&path, 1).unwrap_err());
    assert!(
        e.contains("recorded by another build") && e.contains("fast-math-from-elsewhere"),
        "{e}"
    );
    recording.build = current;

    std::fs::write(&path, "{\"version\": 1}").unwrap();
    let e = format!("{:#}", replay(&path, 1).unwrap_err());
    assert!(
        e.contains("not a hairsim recording: the first line is not HAIRSIM-RECORDING"),
        "{e}"
    );
    std::fs::remove_file(path).ok();
}
