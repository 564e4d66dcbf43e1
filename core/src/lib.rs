//! # hairsim-core
//!
//! An allocation-free `#![no_std]` hair-strand simulator with compile-time strand and node
//! capacities, for haptic-controller firmware stepping at 1 kHz with a bounded, deterministic
//! cost: the Kirchhoff-rod model of Kmoch et al. 2009 and Dynamic Follow-The-Leader with shape
//! preservation of Sánchez-Banderas et al. 2015.
//!
//! * [`world::World`] — fixed-capacity strands, colliders and grabs; `step()` each tick.
//! * [`pipeline::step_strands`] — the same step on any slice of strands (the std harness
//!   splits strand blocks over threads with it); [`pipeline`] reads like the papers' Algorithm 1.
//! * [`strand::Strand`] — rest data apart from state; only state is hashed and rolled back.
//! * [`effects::Effects`] — what a scene turns on; a stage that is off is never computed.
//! * [`report::StepReport`] — what a step did: stages, iterations, flags, forces.
//! * [`math::Math`] — the math backend, a zero-sized type per world.
//!
//! Rules the core keeps: no heap, no std, no unsafe, no recursion; every loop bounded by a
//! capacity or an iteration cap; same inputs give the same bits on every target; `step()`
//! never panics and never lets a NaN out.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![deny(clippy::too_many_lines, clippy::too_many_arguments)]

pub mod capacities;
pub mod collide;
pub mod context;
pub mod dftl;
pub mod effects;
pub mod error;
pub mod follow;
pub mod forces;
pub mod frames;
pub mod grab;
pub mod guard;
pub mod hash;
pub mod head;
pub mod lane;
pub mod math;
pub mod params;
pub mod pipeline;
pub mod precision;
pub mod projection;
pub mod report;
pub mod rest;
pub mod rod;
pub mod root_coupling;
pub mod scenes;
pub mod snapshot;
pub mod strand;
pub mod stretch;
pub mod wind;
pub mod world;

pub use collide::{Collider, Shape};
pub use effects::{Effect, Effects, Solver};
pub use error::{BuildError, CapacityError, Error, ParamError};
pub use grab::{Coupling, Grab, GrabStatus};
pub use head::{Pose, Shake};
pub use math::{DefaultMath, Libm, Math, Quat, Real, Vec3};
pub use params::{DftlCoefficients, DftlParams, Mode, Params, WindParams};
pub use pipeline::dftl::{step_blocks, step_strands_in_blocks};
pub use pipeline::rod::RodScratch;
pub use pipeline::rod_lanes::RodBlockScratch;
pub use pipeline::StepScratch;
pub use pipeline::{
    step_strands, step_strands_in_lanes, step_strands_in_lanes_with, step_strands_with,
};
pub use projection::project_constraints;
pub use projection::ProjectionScratch;
pub use report::{Flags, Stage, StepReport};
pub use strand::{Material, Strand};
pub use world::{StepInput, World};

// Unit tests print the figures they measure and use std's float functions; the library never
// links std.
#[cfg(test)]
extern crate std; // cfg(test) only
