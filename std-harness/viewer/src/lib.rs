//! # hairsim-viewer
//!
//! The simulation behind `hairsim view`'s page, compiled to `wasm32-unknown-unknown`: the
//! harness's scenes, scene files and hair-file readers (crate `hairsim-files`, which has no
//! threads and no clock) and the core's pipeline on one thread ([`stepper`]), driven by the
//! page through plain C exports ([`exports`]) and a small ES-module loader
//! (`web/simulation.js`).
//!
//! Why plain exports and not wasm-bindgen: the page needs a dozen calls that pass numbers, a
//! byte buffer in and a text or float buffer out. Plain exports need no code generator (whose
//! CLI must match the crate's version on every machine that builds the page) and no unsafe
//! code: the page writes into and reads from buffers this module owns, by their addresses.
//!
//! The bits are those of `hairsim run`: the same scene preparation, the same start
//! ([`hairsim_files::scene::start`]), the same pipeline and the same math (WebAssembly's `f32`
//! arithmetic is IEEE single precision with no fused operations, and libm is plain Rust). A
//! scene's hair–hair interaction (SPH) is not simulated in the page; the page says so.

#![deny(unsafe_code)]

pub mod exports;
pub mod session;
pub mod stepper;
