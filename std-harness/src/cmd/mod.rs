//! The `hairsim` command line: one module per command; `main.rs` only parses and dispatches.

pub mod check;
pub mod replay;
pub mod run;
pub mod scenes;
pub mod study;
pub mod view;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

/// hairsim: a deterministic hair-strand simulator (Kmoch 2009 rods, Sánchez-Banderas 2015 DFTL).
#[derive(Parser, Debug)]
#[command(name = "hairsim", version, about, long_about = None)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

/// Options for a `.hair`/`.tfx` file given as SCENE.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct HairArgs {
    /// Hair file only: factor from the file's units to metres (e.g. 0.01 for centimetres).
    #[arg(long)]
    pub scale: Option<f32>,
    /// Hair file only: the file's up axis, y or z.
    #[arg(long, value_parser = ["y", "z"])]
    pub up: Option<String>,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run a scene and print a summary with the state hash.
    #[command(
        after_help = "Examples:\n  hairsim run\n  hairsim run head-1 --steps 500 --json --threads 2\n  hairsim run head-2 --steps 600 --out out --gif\n  hairsim run scenes/one-hair.toml --record one.rec\n  hairsim run strands.hair --scale 0.01 --up z"
    )]
    Run {
        /// A built-in scene name (see `hairsim scenes`), a TOML scene file, or a .hair/.tfx
        /// hair file (run in a default scene); the built-in default scene when omitted.
        scene: Option<String>,
        /// Override the scene's number of steps.
        #[arg(long)]
        steps: Option<u64>,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
        /// Write frames and pictures into this folder.
        #[arg(long)]
        out: Option<PathBuf>,
        /// With --out: also write DIR/run.gif, an animation of the run (as the scene's
        /// `[output] picture = "gif"`).
        #[arg(long, requires = "out")]
        gif: bool,
        /// Record the inputs and state hashes for `hairsim replay`.
        #[arg(long)]
        record: Option<PathBuf>,
        /// Threads stepping strand blocks (the result is the same bits for any count); all
        /// cores by default.
        #[arg(long, default_value_t = all_cores())]
        threads: usize,
        /// With --out: a frame every K steps; with --record: a state hash every K steps (default 10).
        #[arg(long, value_name = "K")]
        every: Option<u64>,
        /// Hair file options.
        #[command(flatten)]
        hair: HairArgs,
    },
    /// List the built-in scenes, one per line, each starting with its name.
    #[command(after_help = "Example:\n  hairsim scenes")]
    Scenes,
    /// Check a scene without running it: every error says FILE:LINE: field: what is wrong.
    #[command(
        after_help = "Examples:\n  hairsim check scenes/one-hair.toml\n  hairsim check head-1"
    )]
    Check {
        /// A built-in scene name, a TOML scene file, or a .hair/.tfx hair file.
        scene: String,
        /// Hair file options.
        #[command(flatten)]
        hair: HairArgs,
    },
    /// Re-run a recording and fail on the first state hash that differs.
    #[command(
        after_help = "Example:\n  hairsim run haptic --record haptic.rec && hairsim replay haptic.rec"
    )]
    Replay {
        /// A file written by `hairsim run --record`.
        file: PathBuf,
        /// Threads stepping strand blocks.
        #[arg(long, default_value_t = 1)]
        threads: usize,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Sweep one knob at a time (time step, projection cap and tolerance, twist, solver,
    /// nodes, math backend, s_d) and measure each configuration's step time against its error
    /// from a converged reference; writes DIR/SCENE.md, .csv and .svg.
    #[command(
        after_help = "Examples:\n  hairsim study firmware --out docs/study\n  hairsim study firmware-dftl --quick\n  hairsim study firmware --knob dt --knob math --budget-us 1000"
    )]
    Study {
        /// A built-in scene name or a TOML scene file (default: the built-in default scene).
        #[arg(default_value = crate::builtin::DEFAULT_SCENE)]
        scene: String,
        /// Folder for SCENE.md, SCENE.csv and SCENE.svg.
        #[arg(long, default_value = "study")]
        out: PathBuf,
        /// Simulated time of every run, s (default 1, or 0.2 with --quick).
        #[arg(long)]
        duration: Option<f64>,
        /// Fewer values per knob and a shorter run (seconds, not minutes).
        #[arg(long)]
        quick: bool,
        /// Only this knob (repeatable): dt, dt-other (the other solver's dt), iterations, tolerance, twist, solver, nodes, math, s_d.
        #[arg(long = "knob", value_name = "KNOB")]
        knobs: Vec<String>,
        /// Also name the most accurate configuration whose measured cost per simulated
        /// millisecond fits B microseconds (1000 = a 1 kHz loop's whole tick).
        #[arg(long, value_name = "B")]
        budget_us: Option<f64>,
    },
    /// Serve the live viewer: the scene runs in the browser (the core in WebAssembly) in real
    /// time, the mouse grabs a strand and feels its force. Prints the page's address.
    #[command(
        after_help = "Examples:\n  hairsim view\n  hairsim view head-2 --port 8080\n  hairsim view scenes/one-hair.toml\n  hairsim view strands.hair"
    )]
    View {
        /// A built-in scene name, a TOML scene file, or a .hair/.tfx hair file (in a default
        /// scene); the built-in default scene when omitted.
        scene: Option<String>,
        /// Port on 127.0.0.1; 0 picks a free one.
        #[arg(long, default_value_t = 8000)]
        port: u16,
    },
}

/// The machine's cores (1 if it cannot tell).
fn all_cores() -> usize {
    std::thread::available_parallelism().map_or(1, usize::from)
}

impl HairArgs {
    /// As the run module takes them.
    #[must_use]
    pub fn options(&self) -> crate::run::HairFileOptions {
        crate::run::HairFileOptions {
            scale: self.scale,
            up: self.up.clone(),
        }
    }
}

/// Runs a parsed command line; the text to print on success.
pub fn dispatch(cli: Cli) -> anyhow::Result<String> {
    match cli.command {
        Command::Run {
            scene,
            steps,
            json,
            out,
            gif,
            record,
            threads,
            every,
            hair,
        } => run::run(&run::Args {
            scene,
            steps,
            json,
            out,
            gif,
            record,
            threads,
            every,
            hair: hair.options(),
        }),
        Command::Scenes => Ok(scenes::list()),
        Command::Check { scene, hair } => check::check(&scene, &hair.options()),
        Command::Replay {
            file,
            threads,
            json,
        } => replay::replay(&file, threads, json),
        Command::Study {
            scene,
            out,
            duration,
            quick,
            knobs,
            budget_us,
        } => study::study(&study::Args {
            scene,
            out,
            duration,
            quick,
            knobs,
            budget_us,
        }),
        Command::View { scene, port } => view::view(scene.as_deref(), port),
    }
}
