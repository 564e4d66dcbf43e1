//! The stages of Dynamic Follow-The-Leader with shape preservation: Sánchez-Banderas et al.
//! 2015 Sec. 3.1, Algorithm 1 lines 12–27 (local dynamics), after Müller, Kim and Chentanez
//! 2012. The pipeline that runs them is `pipeline::dftl`.
//!
//! Nodes 0 and 1 follow the head (the root coupling stage, shared with the rod solver,
//! `root_coupling`). Then for each node `i = 2 …` from the root, in order, one line per stage
//! of Algorithm 1:
//!
//! | line  | stage | file |
//! |---|---|---|
//! | (14)  | shape damping: the velocity relative to the head's rigid motion | [`damping`] |
//! | 13–14 | external accelerations, prediction `x* = x + vΔt + aΔt²` | [`predict`] |
//! | 18    | global then local shape, eqs. (8)–(9) | [`shape`] |
//! | 19    | follow-the-leader inextensibility, eq. (10) | [`follow_leader`] |
//! | 20    | push out of colliders (not in the correction) | [`collisions`] |
//! | 21    | frame update | [`frame`] |
//! | 24–26 | velocity with the `s_d` reaction, eq. (14); `x ← x*` | [`velocity`] |
//!
//! Lines 24–26 run two nodes behind (node `i − 2` is finished as soon as node `i`'s
//! corrections are known), so a step is a single pass whose cost is fixed by the scene.
//!
//! Eq. (14)'s velocity correction feeds back the follow-the-leader correction of the next
//! node and the local-shape corrections of the next two, as a bending stencil, not the global
//! one: [`velocity`] says why and what was measured. With inextensibility only, `s_d = 0.9`
//! removes the energy plain FTL pumps in (78 % of a swing's energy lost in 2 s, vs. plain FTL
//! gaining up to 70×). Below 60 Hz the shape damping ([`damping`]) adds the dissipation the
//! shape projection loses with a smaller step.
//!
//! Frames are carried as tangent and normal vectors ([`frame`]): with the tangent taken from
//! the follow-the-leader step, a node costs one square root and, with shape, two divisions;
//! segment strain is measured as `(|e|² − l²)/(2l²)` (no square root) and turned into a
//! relative stretch once per strand ([`measures`]).
//!
//! Every stage is written once on lanes (`crate::lane`), so the per-strand path (one
//! `Strand<N>`) and the block path (a structure-of-arrays [`DftlBlock`] of `W` strands, node
//! index `k` of every lane together) run the same operations per strand and give the same
//! bits. [`rest`] holds the rest data's precomputation, [`node`] what the stages read and
//! hand on.

pub mod block;
pub mod collisions;
pub mod damping;
pub mod follow_leader;
pub mod frame;
pub mod measures;
pub mod node;
pub mod predict;
pub mod rest;
pub mod shape;
pub mod velocity;

pub use block::{DftlBlock, RECOMMENDED_LANES};
pub use node::Setup;
