//! # hairsim-files
//!
//! The harness's files, without the solver: scene files ([`scene`]) and the built-in scenes
//! ([`builtin`]), hair files in ([`hairfile`]) and out ([`export`]), and the default scene for
//! a hair file ([`hairscene`]), and what stepping in lanes needs on one thread or many
//! ([`lanes`]). The `hairsim` crate re-exports every module at the same path
//! (`hairsim::scene`, `hairsim::hairfile`, …); the fuzz targets of the readers and the scene
//! parser link this crate alone, so they build without the simulation.

pub mod builtin;
pub mod export;
pub mod hairfile;
pub mod hairscene;
pub mod lanes;
pub mod scene;
pub mod sph;
