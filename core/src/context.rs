//! The step context: everything derived once per step and shared by every strand (Box2D's
//! `b2StepContext`, Jolt's hair update context).

use crate::collide::{Collider, Shape, MAX_COLLIDERS};
use crate::effects::{Effect, Effects};
use crate::head::Pose;
use crate::math::{Real, Vec3};
use crate::params::{DftlCoefficients, Params, Solver};

/// Per-step constants and the colliders placed for this step.
#[derive(Clone, Debug)]
pub struct StepContext {
    /// The world's parameters.
    pub params: Params,
    /// Time step `h`, s.
    pub dt: Real,
    /// `1 / h`.
    pub inv_dt: Real,
    /// The effects that run this step.
    pub effects: Effects,
    /// The head's pose at the end of this step.
    pub head: Pose,
    /// The head's pose at the start of this step.
    pub previous_head: Pose,
    /// Gravity `g`, or zero when the effect is off.
    pub gravity: Vec3,
    /// Colliders in world coordinates for this step (attached ones moved with the head).
    pub colliders: [Shape; MAX_COLLIDERS],
    /// How many entries of `colliders` are in use (0 when `collisions` is off).
    pub collider_count: usize,
    /// Wind acceleration this step, or zero when the effect is off (see [`Self::at_time`]).
    pub wind: Vec3,
    /// DFTL's coefficients at this `dt` (zero unless the solver is DFTL).
    pub dftl: DftlCoefficients,
}

impl StepContext {
    /// The context of a step that moves the head from `previous_head` to `head`. Evaluates
    /// DFTL's rescaled coefficients (two divisions); callers stepping many times should compute
    /// them once with [`crate::params::DftlParams::at_step`] and use [`Self::with_coefficients`].
    #[must_use]
    pub fn new(params: &Params, previous_head: Pose, head: Pose, colliders: &[Collider]) -> Self {
        let dftl = if params.solver == Solver::Dftl {
            params.dftl.at_step(params.dt)
        } else {
            DftlCoefficients::default()
        };
        Self::with_coefficients(params, dftl, previous_head, head, colliders)
    }

    /// As [`Self::new`] with DFTL's coefficients computed once at set-up.
    #[must_use]
    pub fn with_coefficients(
        params: &Params,
        dftl: DftlCoefficients,
        previous_head: Pose,
        head: Pose,
        colliders: &[Collider],
    ) -> Self {
        let effects = params.effects;
        let mut placed = [Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        }; MAX_COLLIDERS];
        let mut collider_count = 0;
        if effects.contains(Effect::Collisions) {
            for (slot, c) in placed.iter_mut().zip(colliders) {
                *slot = if c.attached_to_head {
                    c.shape.transformed(&head)
                } else {
                    c.shape
                };
                collider_count += 1;
            }
        }
        StepContext {
            params: *params,
            dt: params.dt,
            inv_dt: 1.0 / params.dt,
            effects,
            head,
            previous_head,
            gravity: if effects.contains(Effect::Gravity) {
                params.gravity
            } else {
                Vec3::ZERO
            },
            colliders: placed,
            collider_count,
            wind: Vec3::ZERO,
            dftl,
        }
        .at_time(0.0)
    }

    /// Sets the step's time `t` (its end, s), which the wind's gusts depend on.
    #[must_use]
    pub fn at_time(mut self, t: Real) -> Self {
        if self.effects.contains(Effect::Wind) {
            self.wind = crate::forces::wind_acceleration(&self.params.wind, t);
        }
        self
    }

    /// The colliders in use this step.
    #[must_use]
    pub fn colliders(&self) -> &[Shape] {
        &self.colliders[..self.collider_count]
    }

    /// Whether `effect` runs this step.
    #[inline(always)]
    #[must_use]
    pub fn has(&self, effect: Effect) -> bool {
        self.effects.contains(effect)
    }
}
