//! The `hairsim` command line.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use hairsim::builtin::{BUILTINS, DEFAULT_SCENE};
use hairsim::run::{run_builtin, RunOptions};

/// hairsim: a deterministic hair-strand simulator (Kmoch 2009 rods, Sánchez-Banderas 2015 DFTL).
#[derive(Parser, Debug)]
#[command(name = "hairsim", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene and print a summary with the state hash.
    #[command(after_help = "Examples:\n  hairsim run\n  hairsim run firmware --steps 500 --json")]
    Run {
        /// A built-in scene name (see `hairsim scenes`); the default scene when omitted.
        scene: Option<String>,
        /// Override the scene's number of steps.
        #[arg(long)]
        steps: Option<u64>,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// List the built-in scenes, one per line.
    #[command(after_help = "Example:\n  hairsim scenes")]
    Scenes,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run { scene, steps, json } => {
            let name = scene.as_deref().unwrap_or(DEFAULT_SCENE);
            run_builtin(name, &RunOptions { steps }).map(|summary| {
                if json {
                    println!("{}", summary.to_json());
                } else {
                    println!("{}", summary.to_text());
                }
            })
        }
        Command::Scenes => {
            for b in BUILTINS {
                println!("{:<12} {}", b.name, b.about);
            }
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hairsim: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
