//! A world's parameters, fixed when the world is built (the time step included).

use crate::effects::{Effect, Effects};
use crate::error::ParamError;
use crate::math::{Real, Vec3};

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
            Solver::Dftl => !matches!(effect, Effect::Bending | Effect::Twist),
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
}

/// Largest time step any scene may use, s.
pub const MAX_DT: Real = 0.02;
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
        },
        dftl: DftlParams {
            damping: 0.9,
            global_shape: 0.1,
            local_shape: 0.3,
            reference_dt: 0.016,
        },
    };

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
        if self.solver == Solver::Dftl {
            // An error, not a silent fallback, until the DFTL solver lands.
            return Err(ParamError::OutOfRange {
                field: "solver",
                allowed: "\"rod\" (the dftl solver is not built yet)",
            });
        }
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
        assert!(dftl.validate().is_err());
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
