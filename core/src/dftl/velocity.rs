//! SB15 Algorithm 1 lines 24–26: velocity update with the DFTL correction, eq. (14) (Müller,
//! Kim, Chentanez 2012, eq. 9), then `x ← x*`.
//!
//! `v_i = (x*_i − x_i)/Δt − s_d Δx^inex_{i+1}/Δt`: the follow-the-leader correction of the
//! *next* node is fed back, which cancels the energy the one-sided projection pumps in and
//! damps the strand numerically (measured in `tests/dftl.rs`). The last node gets none.
//!
//! Only the inextensibility correction is fed back, as in Müller 2012 (where eq. 9's `d_{i+1}`
//! is the follow-the-leader correction), not the shape pulls `Δx^gbl + Δx^lcl` that SB15's
//! eq. (14) also lists. Why: the feedback exists to cancel the velocity the *one-sided*
//! length projection injects (node `i + 1` is moved, node `i` is not). The shape pulls are
//! not such an artefact: they are the shape's restoring motion and are meant to show up in
//! the velocity. Fed back into the previous node they act as a force on node `i` driven by
//! node `i + 1`'s distance from its target — a non-reciprocal coupling that injects energy:
//! measured with the paper's defaults (`s_l` = 0.3, `s_g` = 0.1 at 16 ms, `s_d` = 0.9) a
//! styled strand kept moving 3–7 cm around its rest shape for as long as it ran, and with
//! inextensibility off it diverged. With the inextensibility correction alone the same
//! strands return to rest (`tests/dftl.rs`, `shape_constraints_bring_styled_strands_back`).
//!
//! The solver finishes each node one node behind, as soon as the next node's correction is
//! known, so the whole step is one pass.

use super::lane::{Lane, V3};
use super::Setup;

/// The node's new position and velocity from its predicted-and-projected position `x_star`,
/// its position `x` at the start of the step and the next node's inextensibility correction
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
