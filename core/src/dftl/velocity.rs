//! SB15 Algorithm 1 lines 24–26: velocity update with the DFTL correction, eq. (14) (Müller,
//! Kim, Chentanez 2012, eq. 9), then `x ← x*`.
//!
//! `v_i = (x*_i − x_i)/Δt − s_d (Δx^gbl_{i+1} + Δx^lcl_{i+1} + Δx^inex_{i+1})/Δt`: the correction
//! of the *next* node is fed back, which cancels the energy the one-sided projection pumps in
//! and damps the strand numerically (measured in `tests/dftl.rs`). The last node gets none.
//! The solver finishes each node one node behind, as soon as the next node's correction is
//! known, so the whole step is one pass.

use super::lane::{Lane, V3};
use super::Setup;

/// The node's new position and velocity from its predicted-and-projected position `x_star`,
/// its position `x` at the start of the step and the next node's total correction (zero for
/// the last node: `a − 0·c` is `a` bit for bit).
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
