//! External forces (Kmoch 2009 Sec. 7.1, `F^external_i = M_i g − ν ẋ_i`, Alg. 1 line 3):
//! gravity, air drag, wind and the caller's per-node accelerations (SPH, outside wind), as the
//! acceleration the rod's integrators give a node together with its elastic force.
//!
//! DFTL's prediction adds the same forces in another form (`dftl::predict::acceleration`:
//! gravity and wind summed once per step, drag as the velocity scaled by `ν/m`, no elastic
//! force) — other operations, other bits, so it keeps its own function.

use crate::context::StepContext;
use crate::math::{Real, Vec3};

/// The air drag coefficient `ν` this step, kg/s, or zero with the `drag` effect off.
#[inline(always)]
#[must_use]
pub fn drag(ctx: &StepContext) -> Real {
    if ctx.gates.drag {
        ctx.params.drag
    } else {
        0.0
    }
}

/// Node `i`'s acceleration `g + wind + (F − ν v)/m` with the force `F` on it (its elastic
/// force), velocity `v`, drag coefficient `drag` ([`drag`]) and `1/m`, plus the caller's
/// acceleration of node `i` if `accelerations` has one. (Gravity and wind are zero when off:
/// the step context sees to it.)
#[inline(always)]
#[must_use]
pub fn acceleration(
    ctx: &StepContext,
    force: Vec3,
    velocity: Vec3,
    drag: Real,
    inverse_mass: Real,
    accelerations: Option<&[Vec3]>,
    i: usize,
) -> Vec3 {
    let mut a = ctx.gravity + ctx.wind + (force - velocity * drag) * inverse_mass;
    if let Some(extra) = accelerations.and_then(|acc| acc.get(i)) {
        a += *extra;
    }
    a
}
