//! The scene loader on arbitrary text: a scene or one `FILE:LINE: field: message` error, never
//! a panic; a scene that loads round-trips through its TOML (what a recording stores).
//!
//! The parser and the checks only: this target links `hairsim-files`, not the solver. The
//! strands a scene prepares are what `strand_step` and `dftl_step` fuzz the solver with.
#![no_main]

use std::path::Path;

use hairsim_files::scene::Scene;
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
            let again = Scene::from_toml(&scene.to_toml(), "again.toml").expect("round trip");
            assert_eq!(again, scene);
            // Prepared strands are polylines the core accepts: finite points.
            assert!(prepared
                .strands
                .iter()
                .all(|s| s.points.iter().all(|p| p.is_finite())));
        }
    }
});
