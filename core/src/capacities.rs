//! The core's fixed capacities and limits, in one place at the bottom of the layers: every
//! array the step uses is sized by these or by the const generics `S` (strands) and `N` (nodes
//! per strand), so no step allocates and every loop is bounded.

use crate::math::Real;

/// Most colliders a world holds.
pub const MAX_COLLIDERS: usize = 8;

/// Most grabs a world holds (and force slots a step report has).
pub const MAX_GRABS: usize = 4;

/// Most clamped segments besides the root a strand may have (one per grab, with room to spare).
pub const MAX_CLAMPED: usize = 8;

/// Most substeps a rod strand takes per step (bounded latency): enough for 1000× human bending
/// stiffness at 1 cm segments and 1 ms (119, see `rod::substeps`).
pub const MAX_SUBSTEPS: u32 = 128;

/// Most strand indices a report names individually (the count is always exact).
pub const NAMED_STRANDS: usize = 8;

/// Shortest rest segment a strand may have, m.
pub const MIN_SEGMENT_LENGTH: Real = 1.0e-6;

/// Longest rest segment a strand may have, m: no hair has a metre between two nodes, and a
/// polyline given in the wrong unit (millimetres as metres) is caught here.
pub const MAX_SEGMENT_LENGTH: Real = 1.0;
