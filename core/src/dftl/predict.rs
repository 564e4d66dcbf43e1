//! SB15 Algorithm 1 lines 13–14: external accelerations and the prediction, eq. (1).

use crate::math::{Real, Vec3};

use super::Setup;

/// External acceleration of a free node: gravity and wind (`setup.base_acceleration`), drag
/// `−ν v / m` when on, and the caller's acceleration (SPH, outside wind) if any.
#[inline(always)]
#[must_use]
pub fn acceleration(
    setup: &Setup,
    velocity: Vec3,
    inverse_mass: Real,
    extra: Option<Vec3>,
) -> Vec3 {
    let mut a = setup.base_acceleration;
    if setup.drag {
        a -= velocity * (setup.drag_coefficient * inverse_mass);
    }
    if let Some(extra) = extra {
        a += extra;
    }
    a
}

/// SB15 eq. (1): `x* = x + v Δt + a Δt²` (coefficient 1, not ½: symplectic Euler).
#[inline(always)]
#[must_use]
pub fn predicted_position(
    setup: &Setup,
    position: Vec3,
    velocity: Vec3,
    acceleration: Vec3,
) -> Vec3 {
    position + velocity * setup.dt + acceleration * setup.dt_squared
}
