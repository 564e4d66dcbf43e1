//! The `hairsim` binary: help with examples, one-line errors with a non-zero exit, JSON.

use std::process::{Command, Output};

use hairsim_core::scenes::firmware;
use hairsim_core::{DefaultMath, World};

fn hairsim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hairsim"))
        .args(args)
        .output()
        .expect("the hairsim binary runs")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn every_command_has_help_with_an_example() {
    for command in ["run", "scenes", "check", "replay"] {
        let o = hairsim(&[command, "--help"]);
        assert!(o.status.success(), "{command}");
        let text = stdout(&o);
        assert!(text.contains("Example"), "{command}: {text}");
        assert!(text.contains("hairsim "), "{command}: {text}");
    }
}

#[test]
fn scenes_lists_one_builtin_per_line_starting_with_its_name() {
    let o = hairsim(&["scenes"]);
    assert!(o.status.success());
    let text = stdout(&o);
    let names: Vec<&str> = text
        .lines()
        .map(|l| l.split_whitespace().next().unwrap())
        .collect();
    for name in [
        "firmware",
        "stand-1",
        "stand-2",
        "stand-3",
        "head-1",
        "head-2",
        "head-3",
        "mannequin-a",
        "mannequin-b",
        "haptic",
    ] {
        assert!(names.contains(&name), "{name} missing from\n{text}");
    }
}

#[test]
fn run_firmware_json_prints_the_firmware_hash() {
    let o = hairsim(&["run", "firmware", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
    let mut world: Box<World<{ firmware::STRANDS }, { firmware::NODES }, DefaultMath>> =
        Box::default();
    let expected = firmware::run(&mut world, firmware::STEPS).unwrap();
    assert_eq!(json["state_hash"], format!("0x{expected:016x}"));
}

#[test]
fn threads_do_not_change_the_hash() {
    let hash = |threads: &str| {
        let o = hairsim(&[
            "run",
            "head-2",
            "--steps",
            "50",
            "--json",
            "--threads",
            threads,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let json: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
        json["state_hash"].as_str().unwrap().to_string()
    };
    assert_eq!(hash("1"), hash("2"));
}

#[test]
fn errors_are_one_line_on_stderr_with_a_non_zero_exit() {
    let dir = std::env::temp_dir().join(format!("hairsim-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.toml");
    std::fs::write(
        &file,
        "format = 1\nname = \"x\"\nsolver = \"rod\"\ndt = 0.5\nsteps = 3\neffects = []\n",
    )
    .unwrap();
    let o = hairsim(&["check", file.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert_eq!(e.lines().count(), 1, "{e}");
    assert_eq!(
        e.trim(),
        format!(
            "hairsim: error: {}:4: dt: 0.5 is out of range, allowed 0.00001 to 0.02 s",
            file.display()
        )
    );
    let o = hairsim(&["run", "nothing-here"]);
    assert!(!o.status.success());
    assert_eq!(stderr(&o).lines().count(), 1);
    std::fs::remove_dir_all(dir).ok();
}
