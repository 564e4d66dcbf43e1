//! External forces (Kmoch 2009 Sec. 7.1, `F^external_i = M_i g − ν ẋ_i`, Alg. 1 line 3):
//! gravity, air drag, wind and the caller's per-node accelerations (SPH, outside wind), as the
//! acceleration the rod's integrators give a node together with its elastic force.
//!
//! DFTL's prediction adds the same forces in another form (`dftl::predict::acceleration`:
//! gravity and wind summed once per step, drag as the velocity scaled by `ν/m`, no elastic
//! force) — other operations, other bits, so it keeps its own function.

use crate::context::StepContext;
use crate::math::{Math, Real};
use crate::precision::Kernel;

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

/// The external forces of a step in a kernel's arithmetic (one strand, or `W` in lanes):
/// gravity and wind summed, and the drag coefficient.
#[derive(Clone, Copy, Debug)]
pub struct External<P: Kernel> {
    /// `g + wind`, m/s² (each zero when off: the step context sees to it).
    pub gravity_and_wind: P::V,
    /// `ν`, kg/s (zero with `drag` off, [`drag`]).
    pub drag: P::R,
}

impl<M: Math> External<M> {
    /// The step's external forces.
    #[inline(always)]
    #[must_use]
    pub fn of(ctx: &StepContext) -> Self {
        External {
            gravity_and_wind: ctx.gravity + ctx.wind,
            drag: drag(ctx),
        }
    }
}

impl<P: Kernel> External<P> {
    /// Node `i`'s acceleration `(g + wind) + (F − ν v)/m` with the force `F` on it (its
    /// elastic force), its velocity `v` and `1/m`, plus the caller's acceleration of node `i`
    /// if `accelerations` has one.
    #[inline(always)]
    #[must_use]
    pub fn acceleration(
        &self,
        force: P::V,
        velocity: P::V,
        inverse_mass: P::R,
        accelerations: Option<&[P::V]>,
        i: usize,
    ) -> P::V {
        let mut a = self.gravity_and_wind + (force - velocity * self.drag) * inverse_mass;
        if let Some(extra) = accelerations.and_then(|acc| acc.get(i)) {
            a += *extra;
        }
        a
    }
}
