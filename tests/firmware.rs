//! The firmware under QEMU prints the same state hash as the host for the same scene.
//!
//! `.ci/run` runs the firmware example under `qemu-system-arm -machine mps2-an386`, saves what
//! it printed and points `HAIRSIM_FIRMWARE_LOG` at it. This test compares its hashes of the
//! `firmware`, `firmware-dftl` and `haptic-dftl` scenes with the host's.

use hairsim::run::{run_builtin, RunOptions};
use hairsim_core::scenes::{firmware_dftl, haptic_dftl};
use hairsim_core::{Libm, World};

fn firmware_hash(log: &str, scene: &str) -> Option<String> {
    let line = log
        .lines()
        .find(|l| l.starts_with(&format!("scene {scene} ")))?;
    let at = line.find("state_hash ")? + "state_hash ".len();
    Some(line[at..].split_whitespace().next()?.to_string())
}

#[test]
fn firmware_under_qemu_prints_the_host_hash() {
    let Some(path) = std::env::var_os("HAIRSIM_FIRMWARE_LOG") else {
        eprintln!("skipped: HAIRSIM_FIRMWARE_LOG is unset (.ci/run sets it after running the firmware under QEMU)");
        return;
    };
    let log = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("HAIRSIM_FIRMWARE_LOG={}: {e}", path.to_string_lossy()));
    let target = firmware_hash(&log, "firmware")
        .unwrap_or_else(|| panic!("no `scene firmware … state_hash` line in:\n{log}"));
    let host = run_builtin("firmware", &RunOptions::default()).unwrap();
    assert_eq!(host.state_hash, target, "host and Cortex-M4F hashes differ");
    assert!(log.contains("finite true"));

    // The DFTL scene, stepped on the host exactly as the firmware steps it.
    let target = firmware_hash(&log, "firmware-dftl")
        .unwrap_or_else(|| panic!("no `scene firmware-dftl … state_hash` line in:\n{log}"));
    let mut world: Box<World<{ firmware_dftl::STRANDS }, { firmware_dftl::NODES }, Libm>> =
        Box::default();
    let host = firmware_dftl::run(&mut world, firmware_dftl::STEPS).unwrap();
    assert_eq!(
        format!("0x{host:016x}"),
        target,
        "host and Cortex-M4F DFTL hashes differ"
    );

    // The haptic DFTL scene: a strand held through a coupling, the same bits on both.
    let target = firmware_hash(&log, "haptic-dftl")
        .unwrap_or_else(|| panic!("no `scene haptic-dftl … state_hash` line in:\n{log}"));
    let mut world: Box<World<{ haptic_dftl::STRANDS }, { haptic_dftl::NODES }, Libm>> =
        Box::default();
    let host = haptic_dftl::run(&mut world, haptic_dftl::STEPS).unwrap();
    assert_eq!(
        format!("0x{host:016x}"),
        target,
        "host and Cortex-M4F haptic DFTL hashes differ"
    );
    // And the harness's built-in scene of the same name.
    let harness = run_builtin("haptic-dftl", &RunOptions::default()).unwrap();
    assert_eq!(
        harness.state_hash, target,
        "hairsim run haptic-dftl differs"
    );
}

#[test]
fn hash_line_parsing() {
    let log = "boot\nscene firmware steps 10 strands 4 finite true state_hash 0x00ff\n";
    assert_eq!(firmware_hash(log, "firmware").as_deref(), Some("0x00ff"));
    assert_eq!(firmware_hash(log, "dftl"), None);
}
