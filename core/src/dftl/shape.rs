//! SB15 Algorithm 1 line 18: global and local shape constraints, eqs. (8)–(9), (11)–(12)
//! (Han & Harada 2012). Each moves the predicted node a fraction of the way to its target; the
//! fractions are per step at the world's `dt` (`DftlParams::at_step`) and fade linearly with
//! rest distance from the root.

use super::frame;
use super::node::Setup;
use crate::lane::{Lane, V3};

/// SB15 eq. (11): `Δx^gbl_i = s_g (p_i − x*_i)`, `p_i = T_head(x̂_i)` — the rest position
/// carried rigidly by the head.
#[inline(always)]
#[must_use]
pub fn global_correction<T: Lane>(
    setup: &Setup,
    rest_position: V3<T>,
    root_distance: T,
    x: V3<T>,
) -> V3<T> {
    let c = &setup.coefficients;
    let s =
        T::splat(c.global_shape) * (T::splat(1.0) - T::splat(c.global_shape_fade) * root_distance);
    let target = setup.head_rotate(rest_position) + V3::splat(setup.head_position);
    (target - x).scale(s)
}

/// SB15 eq. (12): `Δx^lcl_i = s_l (p^{i−1}_i − x*_i)`, `p^{i−1}_i = x*_{i−1} + R_{i−1} r_i` — the
/// rest offset carried by the (already final) previous node's frame `R_{i−1} = (t, n, t × n)`:
/// a rotation of the rest vector, no square root.
#[inline(always)]
#[must_use]
pub fn local_correction<T: Lane>(
    setup: &Setup,
    previous: V3<T>,
    previous_tangent: V3<T>,
    previous_normal: V3<T>,
    local_rest: V3<T>,
    root_distance: T,
    x: V3<T>,
) -> V3<T> {
    let c = &setup.coefficients;
    let s =
        T::splat(c.local_shape) * (T::splat(1.0) - T::splat(c.local_shape_fade) * root_distance);
    let target = previous + frame::rotate(previous_tangent, previous_normal, local_rest);
    (target - x).scale(s)
}
