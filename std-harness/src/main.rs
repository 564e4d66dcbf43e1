//! The `hairsim` command line: parse, dispatch to `hairsim::cmd`, print.

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;
use hairsim::cmd::{dispatch, Cli};

fn main() -> ExitCode {
    match dispatch(Cli::parse()) {
        Ok(text) => {
            // A reader that stops early (`hairsim scenes | head -1`) is not an error.
            let _ = writeln!(std::io::stdout().lock(), "{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hairsim: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
