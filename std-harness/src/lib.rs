//! # hairsim (the std harness)
//!
//! Everything around the `no_std` core that a desktop user touches: scene files
//! ([`scene`]), built-in scenes ([`builtin`]), runs on threads with a summary ([`run`],
//! [`sim`], [`summary`]), record and replay ([`record`]), the command line ([`cmd`]), SPH
//! hair–hair interaction ([`sph`]), hair files in ([`hairfile`]) and out ([`export`]), and
//! pictures ([`picture`]).

pub mod builtin;
pub mod cmd;
pub mod export;
pub mod hairfile;
pub mod hairscene;
pub mod output;
pub mod picture;
pub mod record;
pub mod run;
pub mod scene;
pub mod sim;
pub mod sph;
pub mod study;
pub mod summary;

pub use hairsim_core as core;
