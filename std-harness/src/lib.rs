//! # hairsim (the std harness)
//!
//! Everything around the `no_std` core that a desktop user touches: built-in scenes, runs with
//! a summary (text or JSON), and — as the issues land — scene files, SPH hair–hair interaction,
//! record and replay, hair files in and out, pictures and studies.

pub mod builtin;
pub mod export;
pub mod hairfile;
pub mod picture;
pub mod run;
pub mod sph;
pub mod summary;

pub use hairsim_core as core;
