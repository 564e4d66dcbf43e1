//! The scene loader on arbitrary text: a scene or one `FILE:LINE: field: message` error, never
//! a panic; small valid scenes also run a few steps and stay finite.
#![no_main]

use std::path::Path;

use hairsim::run::{run, Loaded, RunOptions};
use hairsim::scene::Scene;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    match Scene::parse_and_prepare(text, "fuzz.toml", Path::new("/nonexistent")) {
        Err(e) => {
            let message = e.to_string();
            assert!(message.starts_with("fuzz.toml"), "{message}");
            assert!(!e.message.is_empty());
        }
        Ok((scene, prepared)) => {
            // The scene's TOML round-trips (what a recording stores).
            let again = Scene::from_toml(&scene.to_toml(), "again.toml").expect("round trip");
            assert_eq!(again, scene);
            if prepared.nodes() <= 2_000 && prepared.followers.len() <= 2_000 {
                let loaded = Loaded {
                    source: "fuzz".into(),
                    scene,
                    prepared,
                };
                let options = RunOptions {
                    steps: Some(3),
                    ..RunOptions::default()
                };
                let summary = run(&loaded, &options).expect("a valid small scene runs");
                assert!(summary.finite);
            }
        }
    }
});
