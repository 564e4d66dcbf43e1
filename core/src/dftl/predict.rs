//! SB15 Algorithm 1 lines 13–14: external accelerations and the prediction, eq. (1).

use super::node::Setup;
use crate::lane::{Lane, V3};

/// External acceleration of a free node: gravity and wind (`setup.base_acceleration`), drag
/// when on, and the caller's acceleration (SPH, outside wind) where `has_extra`.
///
/// Drag is integrated implicitly: `−ν v/(m + ν Δt)`, which multiplies the velocity by
/// `m/(m + ν Δt)` over the step, between 0 and 1 at any step. The explicit `−ν v/m` multiplies
/// it by `1 − (ν/m) Δt`, which reverses and grows it once `(ν/m) Δt > 2`: a 1 mm stub strand of
/// 24 nodes (`Ratboy_mohawk.tfx` has them) has `ν/m` ≈ 600 s⁻¹ at the default drag, past that
/// limit at 4 ms, and its velocity grew 3× a step to 10¹⁰ m/s while follow-the-leader kept its
/// positions in place. Where `(ν/m) Δt` is small the two agree to `O(((ν/m) Δt)²)`.
#[inline(always)]
#[must_use]
pub fn acceleration<T: Lane>(
    setup: &Setup,
    velocity: V3<T>,
    mass: T,
    extra: V3<T>,
    has_extra: T::Mask,
) -> V3<T> {
    let mut a = V3::splat(setup.base_acceleration);
    if setup.drag {
        let nu = T::splat(setup.drag_coefficient);
        a -= velocity.scale(nu / (mass + nu * T::splat(setup.dt)));
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
