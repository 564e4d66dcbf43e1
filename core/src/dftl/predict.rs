//! SB15 Algorithm 1 lines 13–14: external accelerations and the prediction, eq. (1).

use super::node::Setup;
use crate::lane::{Lane, V3};

/// External acceleration of a free node: gravity and wind (`setup.base_acceleration`), drag
/// `−ν v / m` when on, and the caller's acceleration (SPH, outside wind) where `has_extra`.
#[inline(always)]
#[must_use]
pub fn acceleration<T: Lane>(
    setup: &Setup,
    velocity: V3<T>,
    inverse_mass: T,
    extra: V3<T>,
    has_extra: T::Mask,
) -> V3<T> {
    let mut a = V3::splat(setup.base_acceleration);
    if setup.drag {
        a = a - velocity.scale(T::splat(setup.drag_coefficient) * inverse_mass);
    }
    V3::select(has_extra, a + extra, a)
}

/// SB15 eq. (1): `x* = x + v Δt + a Δt²` (coefficient 1, not ½: symplectic Euler).
#[inline(always)]
#[must_use]
pub fn predicted_position<T: Lane>(
    setup: &Setup,
    position: V3<T>,
    velocity: V3<T>,
    acceleration: V3<T>,
) -> V3<T> {
    position + velocity.scale(T::splat(setup.dt)) + acceleration.scale(T::splat(setup.dt_squared))
}
