//! # hairsim (the std harness)
//!
//! Everything around the `no_std` core that a desktop user touches: scene files
//! ([`scene`]), built-in scenes ([`builtin`]), runs on threads with a summary ([`run`],
//! [`sim`], [`summary`]), record and replay ([`record`]), and the command line ([`cmd`]).

pub mod builtin;
pub mod cmd;
pub mod hairscene;
pub mod output;
pub mod record;
pub mod run;
pub mod scene;
pub mod sim;
pub mod summary;

pub use hairsim_core as core;
