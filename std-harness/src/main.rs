//! The `hairsim` command line: parse, dispatch to `hairsim::cmd`, print.

use std::process::ExitCode;

use clap::Parser;
use hairsim::cmd::{dispatch, Cli};

fn main() -> ExitCode {
    match dispatch(Cli::parse()) {
        Ok(text) => {
            println!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hairsim: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
