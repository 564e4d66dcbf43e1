//! The step context: everything derived once per step and shared by every strand (Box2D's
//! `b2StepContext`, Jolt's hair update context), the stages' gates among it.

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
    /// Which stages and terms run this step, derived from `effects` and the colliders.
    pub gates: Gates,
}

/// Which stages (and terms inside stages) a step runs: derived once from the scene's effects
/// and colliders when the context is built (Jolt's `mNeedsCollision`, `mNeedsGrid`), so each
/// line of a pipeline tests one of these and nothing else. An effect that is off costs
/// nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Gates {
    /// Bending forces (`bending`).
    pub bending: bool,
    /// Twist forces and the quasistatic twist (`twist`).
    pub twist: bool,
    /// The rod's frames: bending or twist.
    pub frames: bool,
    /// `gravity`.
    pub gravity: bool,
    /// `wind`.
    pub wind: bool,
    /// Air drag (`drag`).
    pub drag: bool,
    /// Any external force of the scene's own: gravity, wind or drag.
    pub external: bool,
    /// Inextensibility (`inextensibility`): the rod's projection rows, DFTL's follow-the-leader.
    pub inextensibility: bool,
    /// `collisions`.
    pub collisions: bool,
    /// `collisions` with at least one collider in use.
    pub colliders: bool,
    /// Grabs (`grabs`).
    pub grabs: bool,
    /// The rod's fast manifold projection: inextensibility, collisions or grabs.
    pub projection: bool,
    /// DFTL's global and local shape constraints (`shape`).
    pub shape: bool,
    /// SPH hair–hair interaction (`hair-hair`, computed by the std harness).
    pub hair_hair: bool,
}

impl Gates {
    /// The gates of `effects` with `colliders` colliders in use.
    #[must_use]
    pub const fn of(effects: Effects, colliders: usize) -> Gates {
        let bending = effects.contains(Effect::Bending);
        let twist = effects.contains(Effect::Twist);
        let gravity = effects.contains(Effect::Gravity);
        let wind = effects.contains(Effect::Wind);
        let drag = effects.contains(Effect::Drag);
        let inextensibility = effects.contains(Effect::Inextensibility);
        let collisions = effects.contains(Effect::Collisions);
        let grabs = effects.contains(Effect::Grabs);
        Gates {
            bending,
            twist,
            frames: bending || twist,
            gravity,
            wind,
            drag,
            external: gravity || wind || drag,
            inextensibility,
            collisions,
            colliders: collisions && colliders > 0,
            grabs,
            projection: inextensibility || collisions || grabs,
            shape: effects.contains(Effect::Shape),
            hair_hair: effects.contains(Effect::HairHair),
        }
    }
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
        Self::at(params, dftl, (previous_head, head), colliders, 0.0)
    }

    /// As [`Self::with_coefficients`] for the step ending at time `t` (s; the wind's gusts
    /// depend on it): `with_coefficients(…).at_time(t)`. One expression, so that each part is
    /// computed where the context lies: a context (about 400 bytes) built in a local and then
    /// returned or timed is copied each time, on the Cortex-M4F by a library call.
    #[must_use]
    #[inline(always)]
    pub fn at(
        params: &Params,
        dftl: DftlCoefficients,
        (previous_head, head): (Pose, Pose),
        colliders: &[Collider],
        t: Real,
    ) -> Self {
        let effects = params.effects;
        let collider_count = if effects.contains(Effect::Collisions) {
            colliders.len().min(MAX_COLLIDERS)
        } else {
            0
        };
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
            colliders: placed(colliders.get(..collider_count).unwrap_or(&[]), &head),
            collider_count,
            wind: wind_at(params, t),
            dftl,
            gates: Gates::of(effects, collider_count),
        }
    }

    /// Sets the step's time `t` (its end, s), which the wind's gusts depend on.
    #[must_use]
    pub fn at_time(mut self, t: Real) -> Self {
        self.wind = wind_at(&self.params, t);
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

/// `colliders` (at most [`MAX_COLLIDERS`]) for a step ending with the head at `head`: the
/// attached ones moved with it; the unused slots a placeholder plane.
#[inline(always)]
fn placed(colliders: &[Collider], head: &Pose) -> [Shape; MAX_COLLIDERS] {
    let mut placed = [Shape::Plane {
        point: Vec3::ZERO,
        normal: Vec3::Y,
    }; MAX_COLLIDERS];
    for (slot, c) in placed.iter_mut().zip(colliders) {
        *slot = if c.attached_to_head {
            c.shape.transformed(head)
        } else {
            c.shape
        };
    }
    placed
}

/// The wind's acceleration at time `t`, or zero when the effect is off.
#[inline(always)]
fn wind_at(params: &Params, t: Real) -> Vec3 {
    if params.effects.contains(Effect::Wind) {
        crate::wind::wind_acceleration(&params.wind, t)
    } else {
        Vec3::ZERO
    }
}
