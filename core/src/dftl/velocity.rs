//! SB15 Algorithm 1 lines 24–26: velocity update with the DFTL correction, eq. (14) (Müller,
//! Kim, Chentanez 2012, eq. 9), then `x ← x*`.
//!
//! `v_i = (x*_i − x_i)/Δt − s_d (Δx^lcl_{i+1} + Δx^inex_{i+1})/Δt`: the corrections of the
//! *next* node that come from node `i` itself are fed back, which cancels the energy the
//! one-sided projection pumps in and damps the strand numerically (measured in
//! `tests/dftl.rs`). The last node gets none.
//!
//! SB15's eq. (14) also lists the global correction `Δx^gbl_{i+1}`; it is left out here, with
//! this reason. The feedback is a reaction: the follow-the-leader and local-shape constraints
//! are *between* nodes `i` and `i + 1` but move node `i + 1` alone, and `−s_d Δx_{i+1}` hands
//! node `i` (most of) the equal and opposite share. The global constraint ties node `i + 1`
//! to the head, not to node `i`: feeding it back pushes node `i` by its neighbour's distance
//! from the head's target, a coupling with no partner that sustains motion. Measured
//! (`tests/dftl.rs`, styled strands pushed for 0.2 s then left 3 s, paper defaults
//! `s_g` = 0.1, `s_l` = 0.3 at 16 ms, `s_d` = 0.9): all three fed back, 3–7 cm from rest
//! after 3 s; local + inextensibility (this), 2.3 cm. Inextensibility alone (Müller 2012's
//! original) is worse: the local constraint's one-sided pull then has no reaction at all, and
//! a styled strand at rest with shape on is unstable — its tip drifted from 1e-10 m to 0.8 mm
//! in 0.18 s, growing exponentially (measured), where both other forms stay within 1e-7 m.
//!
//! The solver finishes each node one node behind, as soon as the next node's correction is
//! known, so the whole step is one pass.

use super::node::Setup;
use crate::lane::{Lane, V3};

/// The node's new position and velocity from its predicted-and-projected position `x_star`,
/// its position `x` at the start of the step and the next node's local-shape plus
/// inextensibility correction
/// (zero for the last node: `a − 0·c` is `a` bit for bit).
#[inline(always)]
#[must_use]
pub fn finish<T: Lane>(
    setup: &Setup,
    x_star: V3<T>,
    x: V3<T>,
    next_correction: V3<T>,
) -> (V3<T>, V3<T>) {
    let v = (x_star - x).scale(T::splat(setup.inv_dt))
        - next_correction.scale(T::splat(setup.damping_over_dt));
    (x_star, v)
}
