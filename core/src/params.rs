//! A world's parameters, fixed when the world is built (the time step included).

use crate::effects::{Effect, Effects};
use crate::error::ParamError;
use crate::math::{Real, Vec3};
pub use crate::rod::twist::TwistMethod;

/// Which model steps the strands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Solver {
    /// Discrete Kirchhoff rods with fast manifold projection (Kmoch et al. 2009).
    Rod,
    /// Dynamic Follow-The-Leader with shape preservation (Sánchez-Banderas et al. 2015).
    Dftl,
}

impl Solver {
    /// The solver's name in scene files and reports (`"rod"`, `"dftl"`).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Solver::Rod => "rod",
            Solver::Dftl => "dftl",
        }
    }

    /// Whether this solver can simulate `effect`: bending and twist need the rod's energies,
    /// shape preservation is DFTL's.
    #[must_use]
    pub const fn supports(self, effect: Effect) -> bool {
        match self {
            Solver::Rod => !matches!(effect, Effect::Shape),
            // DFTL has no grab constraint (its single root-to-tip pass cannot hold a middle
            // node): refused, not silently ignored.
            Solver::Dftl => !matches!(effect, Effect::Bending | Effect::Twist | Effect::Grabs),
        }
    }
}

/// How iterative stages decide when to stop.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// Stop early at the tolerance (desktops).
    Converge,
    /// Always run the full iteration caps, so the cost of a step depends on the scene's size
    /// and effects, never on its state (firmware).
    FixedCost,
}

impl Mode {
    /// The mode's name in scene files (`"converge"`, `"fixed-cost"`).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Mode::Converge => "converge",
            Mode::FixedCost => "fixed-cost",
        }
    }
}

/// Parameters of the Kirchhoff-rod solver (Kmoch 2009).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RodParams {
    /// Iteration cap of the fast manifold projection (Sec. 8). Default 8.
    pub projection_iterations: u16,
    /// Relative tolerance `max |e·e − ê·ê| / ê·ê`. Default 1e-6.
    pub projection_tolerance: Real,
    /// The quasistatic twist (`twist` effect): hair-optimised (Sec. 6.2) or Newton (BWR08).
    /// Default hair-optimised.
    pub twist: TwistMethod,
    /// Iteration cap of the Newton twist. Default 10.
    pub newton_iterations: u16,
    /// Newton twist tolerance on the largest angle update, rad. Default 1e-6.
    pub newton_tolerance: Real,
}

/// Parameters of the DFTL solver (Sánchez-Banderas 2015, Sec. 3.1).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DftlParams {
    /// `s_d`: fraction of the follow-the-leader correction fed back into velocity (eq. 14),
    /// not rescaled with Δt. Default 0.9.
    pub damping: Real,
    /// `s_g` per step at `reference_dt`. Default 0.1.
    pub global_shape: Real,
    /// `s_l` per step at `reference_dt`. Default 0.3.
    pub local_shape: Real,
    /// The step at which `s_g`, `s_l` are given. Default 0.016 s.
    pub reference_dt: Real,
    /// How much `s_g` fades from root to tip, linearly with rest distance from the root:
    /// `s_g(i) = s_g · (1 − fade · d_i / L)`. 0 (default) keeps it constant, 1 reaches 0 at
    /// the tip.
    pub global_shape_fade: Real,
    /// The same for `s_l`. Default 0.
    pub local_shape_fade: Real,
}

impl DftlParams {
    /// The per-step fractions at the step `dt`, computed once at set-up (`World::configure`),
    /// never per step: `s(Δt) = 1 − (1 − s_ref)^{Δt/Δt_ref}` (DESIGN.md, DFTL with shape).
    /// `s_d` is a fraction of the correction fed back and is not rescaled.
    #[must_use]
    pub fn at_step(&self, dt: Real) -> DftlCoefficients {
        DftlCoefficients {
            damping: self.damping,
            global_shape: crate::math::relaxation_at_step(self.global_shape, dt, self.reference_dt),
            local_shape: crate::math::relaxation_at_step(self.local_shape, dt, self.reference_dt),
            global_shape_fade: self.global_shape_fade,
            local_shape_fade: self.local_shape_fade,
        }
    }
}

/// DFTL's coefficients at the world's step (see [`DftlParams::at_step`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DftlCoefficients {
    /// `s_d`, as given.
    pub damping: Real,
    /// `s_g` per step at the world's `dt`, at the root.
    pub global_shape: Real,
    /// `s_l` per step at the world's `dt`, at the root.
    pub local_shape: Real,
    /// As [`DftlParams::global_shape_fade`].
    pub global_shape_fade: Real,
    /// As [`DftlParams::local_shape_fade`].
    pub local_shape_fade: Real,
}

/// Wind, an external acceleration on every free node of both solvers (used when `wind` is on):
/// `a(t) = direction · strength · (1 + gust · n(t))`, with `n` a seeded, smooth value noise of
/// time in `[−1, 1]` (see `forces::wind_acceleration`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindParams {
    /// Unit direction the wind blows towards (world frame). Default +x.
    pub direction: Vec3,
    /// Mean acceleration, m/s². Default 2.
    pub strength: Real,
    /// Gust amplitude as a fraction of `strength`, 0 to 10. Default 0.5.
    pub gust: Real,
    /// Gust frequency, Hz (how often the noise picks a new value), 0 to 1000. Default 1.5.
    pub gust_frequency: Real,
    /// Seed of the gust noise: same seed, same gusts on every target.
    pub seed: u32,
}

#[cfg(feature = "defmt")]
impl defmt::Format for WindParams {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "WindParams {{ direction: {}, strength: {}, gust: {}, gust_frequency: {}, seed: {} }}",
            crate::math::DefmtVec3(self.direction),
            self.strength,
            self.gust,
            self.gust_frequency,
            self.seed
        )
    }
}

/// Everything a world needs to know besides its strands, colliders and grabs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// The model.
    pub solver: Solver,
    /// Time step, s. Fixed for the life of the world.
    pub dt: Real,
    /// The effects that run; nothing else does.
    pub effects: Effects,
    /// Converge or fixed cost.
    pub mode: Mode,
    /// Gravitational acceleration, m/s² (used when `gravity` is on).
    pub gravity: Vec3,
    /// Air drag `ν` per node, kg/s (used when `drag` is on).
    pub drag: Real,
    /// Rod solver parameters.
    pub rod: RodParams,
    /// DFTL parameters.
    pub dftl: DftlParams,
    /// Wind (used when `wind` is on).
    pub wind: WindParams,
}

/// Largest time step any scene may use, s.
pub const MAX_DT: Real = 0.02;
/// Largest time step a rod scene may use, s: measured stable at 4 ms on a head shaking at
/// 10 rad/s, divergent at 5 ms (`tests/torture.rs`).
pub const ROD_MAX_DT: Real = 0.004;
/// Smallest time step any scene may use, s.
pub const MIN_DT: Real = 1.0e-5;

impl Params {
    /// Rod, 1 ms, gravity only, converge mode.
    pub const DEFAULT: Params = Params {
        solver: Solver::Rod,
        dt: 0.001,
        effects: Effects::NONE.with(Effect::Gravity),
        mode: Mode::Converge,
        gravity: Vec3::new(0.0, -9.81, 0.0),
        drag: 0.0,
        rod: RodParams {
            projection_iterations: 8,
            projection_tolerance: 1.0e-6,
            twist: TwistMethod::HairOptimised,
            newton_iterations: 10,
            newton_tolerance: 1.0e-6,
        },
        dftl: DftlParams {
            damping: 0.9,
            global_shape: 0.1,
            local_shape: 0.3,
            reference_dt: 0.016,
            global_shape_fade: 0.0,
            local_shape_fade: 0.0,
        },
        wind: WindParams {
            direction: Vec3::X,
            strength: 2.0,
            gust: 0.5,
            gust_frequency: 1.5,
            seed: 0x5EED,
        },
    };

    /// Checks that `strand` can be stepped stably with these parameters: with the rod solver and
    /// bending on, the fixed substep count that keeps explicit bending within its stability
    /// bound ([`crate::rod::step::needed_substeps`]) must fit [`crate::rod::step::MAX_SUBSTEPS`].
    /// Stiffer hair, shorter segments or a larger `µ` lower the limit like
    /// `h² / √(max(1, µ)·α)`; such a strand with too large a `dt` is refused here rather than
    /// left to chatter or explode.
    pub fn validate_strand<const N: usize>(
        &self,
        strand: &crate::strand::Strand<N>,
    ) -> Result<(), ParamError> {
        let bending = self.solver == Solver::Rod && self.effects.contains(Effect::Bending);
        match crate::rod::step::needed_substeps(&strand.rest.rod, self.dt, bending) {
            Some(_) => Ok(()),
            None => Err(ParamError::OutOfRange {
                field: "dt",
                allowed: "at most 128 substeps' worth of the strand's explicit bending limit: \
                          dt <= 128 * 0.7 * dt_max / 4 with dt_max = (h^2/2) * sqrt(rho*A / \
                          (max(1, mu) * E*pi*r^4/4)) for the shortest segment h; use a smaller \
                          dt, longer segments or softer hair",
            }),
        }
    }

    /// Checks every parameter against its range and the effects against the solver.
    pub fn validate(&self) -> Result<(), ParamError> {
        let range = |ok: bool, field, allowed| {
            if ok {
                Ok(())
            } else {
                Err(ParamError::OutOfRange { field, allowed })
            }
        };
        range(
            self.dt.is_finite() && (MIN_DT..=MAX_DT).contains(&self.dt),
            "dt",
            "1e-5 s to 0.02 s",
        )?;
        range(
            self.solver != Solver::Rod || self.dt <= ROD_MAX_DT,
            "dt",
            "1e-5 s to 0.004 s with the rod solver (bending is substepped, but the twist and the \
             projection run once per step: on a head shaking at 10 rad/s the rod holds at \
             4 ms and diverges at 5 ms, tests/torture.rs)",
        )?;
        range(
            crate::math::is_finite(self.gravity),
            "gravity",
            "finite components",
        )?;
        range(
            self.drag.is_finite() && self.drag >= 0.0,
            "drag",
            "a finite value >= 0 kg/s",
        )?;
        range(
            self.rod.projection_iterations >= 1 && self.rod.projection_iterations <= 1000,
            "rod.projection_iterations",
            "1 to 1000",
        )?;
        range(
            self.rod.projection_tolerance.is_finite() && self.rod.projection_tolerance > 0.0,
            "rod.projection_tolerance",
            "a finite value > 0",
        )?;
        range(
            self.rod.newton_iterations >= 1 && self.rod.newton_iterations <= 100,
            "rod.newton_iterations",
            "1 to 100",
        )?;
        range(
            self.rod.newton_tolerance.is_finite() && self.rod.newton_tolerance > 0.0,
            "rod.newton_tolerance",
            "a finite value > 0 rad",
        )?;
        let fraction = |v: Real| v.is_finite() && (0.0..=1.0).contains(&v);
        range(fraction(self.dftl.damping), "dftl.damping", "0 to 1")?;
        range(
            fraction(self.dftl.global_shape),
            "dftl.global_shape",
            "0 to 1",
        )?;
        range(
            fraction(self.dftl.local_shape),
            "dftl.local_shape",
            "0 to 1",
        )?;
        range(
            self.dftl.reference_dt.is_finite() && self.dftl.reference_dt > 0.0,
            "dftl.reference_dt",
            "a finite value > 0 s",
        )?;
        range(
            fraction(self.dftl.global_shape_fade),
            "dftl.global_shape_fade",
            "0 to 1",
        )?;
        range(
            fraction(self.dftl.local_shape_fade),
            "dftl.local_shape_fade",
            "0 to 1",
        )?;
        let wind = &self.wind;
        range(
            crate::math::is_finite(wind.direction)
                && (wind.direction.length_squared() - 1.0).abs() < 1e-4,
            "wind.direction",
            "a finite unit vector",
        )?;
        range(
            wind.strength.is_finite() && wind.strength >= 0.0,
            "wind.strength",
            "a finite value >= 0 m/s2",
        )?;
        range(
            wind.gust.is_finite() && (0.0..=10.0).contains(&wind.gust),
            "wind.gust",
            "0 to 10",
        )?;
        range(
            wind.gust_frequency.is_finite() && (0.0..=1000.0).contains(&wind.gust_frequency),
            "wind.gust_frequency",
            "0 to 1000 Hz",
        )?;
        if let Some(effect) = self.effects.unsupported_by(self.solver) {
            return Err(ParamError::UnsupportedEffect {
                effect: effect.name(),
                solver: self.solver.name(),
            });
        }
        Ok(())
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Params {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "Params {{ solver: {}, dt: {}, effects: {}, mode: {}, gravity: [{}, {}, {}], drag: {}, rod: {}, dftl: {} }}",
            self.solver,
            self.dt,
            self.effects,
            self.mode,
            self.gravity.x,
            self.gravity.y,
            self.gravity.z,
            self.drag,
            self.rod,
            self.dftl
        )
    }
}

impl Default for Params {
    fn default() -> Self {
        Params::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_ranges_are_named() {
        assert_eq!(Params::DEFAULT.validate(), Ok(()));
        let bad = Params {
            dt: 0.5,
            ..Params::DEFAULT
        };
        assert_eq!(
            bad.validate(),
            Err(ParamError::OutOfRange {
                field: "dt",
                allowed: "1e-5 s to 0.02 s"
            })
        );
        let dftl = Params {
            solver: Solver::Dftl,
            ..Params::DEFAULT
        };
        assert_eq!(dftl.validate(), Ok(()));
        let grabs_on_dftl = Params {
            effects: Effects::NONE.with(Effect::Grabs),
            ..dftl
        };
        assert!(matches!(
            grabs_on_dftl.validate(),
            Err(ParamError::UnsupportedEffect {
                effect: "grabs",
                ..
            })
        ));
        let sideways = Params {
            wind: WindParams {
                direction: Vec3::new(1.0, 1.0, 0.0),
                ..Params::DEFAULT.wind
            },
            ..Params::DEFAULT
        };
        assert!(sideways.validate().is_err());
        let mut newton = Params::DEFAULT;
        newton.rod.twist = TwistMethod::Newton;
        assert_eq!(newton.validate(), Ok(()));
        newton.rod.newton_iterations = 0;
        assert!(matches!(
            newton.validate(),
            Err(ParamError::OutOfRange {
                field: "rod.newton_iterations",
                ..
            })
        ));
        let shape_on_rod = Params {
            effects: Effects::NONE.with(Effect::Shape),
            ..Params::DEFAULT
        };
        assert!(matches!(
            shape_on_rod.validate(),
            Err(ParamError::UnsupportedEffect {
                effect: "shape",
                ..
            })
        ));
    }
}
