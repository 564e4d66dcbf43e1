//! `hairsim run [SCENE]`.

use std::path::PathBuf;

use anyhow::Result;

use crate::builtin::DEFAULT_SCENE;
use crate::run::{load, run as run_scene, HairFileOptions, RunOptions};

/// The arguments of `hairsim run`.
#[derive(Clone, Debug, Default)]
pub struct Args {
    /// SCENE (default: the built-in default).
    pub scene: Option<String>,
    /// `--steps`.
    pub steps: Option<u64>,
    /// `--json`.
    pub json: bool,
    /// `--out`.
    pub out: Option<PathBuf>,
    /// `--gif`: also an animation of the run into `--out`.
    pub gif: bool,
    /// `--record`.
    pub record: Option<PathBuf>,
    /// `--threads`.
    pub threads: usize,
    /// `--every`.
    pub every: Option<u64>,
    /// `--scale`, `--up`.
    pub hair: HairFileOptions,
}

/// Runs the scene; the summary as text or JSON.
pub fn run(args: &Args) -> Result<String> {
    let spec = args.scene.as_deref().unwrap_or(DEFAULT_SCENE);
    let mut loaded = load(spec, &args.hair)?;
    if args.gif {
        loaded.prepared.output.picture = "gif".into();
    }
    let summary = run_scene(
        &loaded,
        &RunOptions {
            steps: args.steps,
            threads: args.threads,
            every: args.every,
            out: args.out.clone(),
            record: args.record.clone(),
            progress: true,
        },
    )?;
    Ok(if args.json {
        summary.to_json()
    } else {
        summary.to_text()
    })
}
