//! SB15 Algorithm 1 line 18: global and local shape constraints, eqs. (8)–(9), (11)–(12)
//! (Han & Harada 2012). Each moves the predicted node a fraction of the way to its target; the
//! fractions are per step at the world's `dt` (`DftlParams::at_step`) and fade linearly with
//! rest distance from the root.

use crate::math::{self, Quat, Real, Vec3};

use super::Setup;

/// SB15 eq. (11): `Δx^gbl_i = s_g (p_i − x*_i)`, `p_i = T_head(x̂_i)` — the rest position
/// carried rigidly by the head.
#[inline(always)]
#[must_use]
pub fn global_correction(setup: &Setup, rest_position: Vec3, root_distance: Real, x: Vec3) -> Vec3 {
    let s = setup.coefficients.global_shape
        * (1.0 - setup.coefficients.global_shape_fade * root_distance);
    let target = setup.head_rotation * rest_position + setup.head_position;
    (target - x) * s
}

/// SB15 eq. (12): `Δx^lcl_i = s_l (p^{i−1}_i − x*_i)`, `p^{i−1}_i = x*_{i−1} + R_{i−1} r_i` — the
/// rest offset carried by the (already final) previous node's frame.
#[inline(always)]
#[must_use]
pub fn local_correction(
    setup: &Setup,
    previous: Vec3,
    previous_frame: Quat,
    local_rest: Vec3,
    root_distance: Real,
    x: Vec3,
) -> Vec3 {
    let s = setup.coefficients.local_shape
        * (1.0 - setup.coefficients.local_shape_fade * root_distance);
    let target = previous + math::rotate(previous_frame, local_rest);
    (target - x) * s
}
