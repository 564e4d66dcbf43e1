//! # hairsim (the std harness)
//!
//! Everything around the `no_std` core that a desktop user touches: scene files
//! ([`scene`]), built-in scenes ([`builtin`]), runs on threads with a summary ([`run`],
//! [`sim`], [`summary`]), record and replay ([`record`]), the command line ([`cmd`]), SPH
//! hair–hair interaction ([`sph`]), hair files in ([`hairfile`]) and out ([`export`]), and
//! pictures ([`picture`]).
//!
//! The files without the solver ([`scene`], [`builtin`], [`hairfile`], [`hairscene`] and the
//! writers and readers of [`export`]) are the crate `hairsim-files`, re-exported here at the
//! same paths.

pub use hairsim_files::{builtin, hairfile, hairscene, lanes, scene};

pub mod cmd;
pub mod export;
pub mod groom;
pub mod haptic;
pub mod output;
pub mod picture;
pub mod record;
pub mod run;
pub mod sim;
pub mod sph;
pub mod study;
pub mod summary;
pub mod view;

pub use hairsim_core as core;
