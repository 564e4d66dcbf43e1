//! A world's parameters, fixed when the world is built (the time step included).

pub use crate::effects::Solver;
use crate::effects::{Effect, Effects};
use crate::error::ParamError;
use crate::math::{Real, Vec3};

/// Which quasistatic twist a scene uses.
///
/// One byte, the variant's index (`repr(u8)`): a world's raw bytes can be checked before they
/// are read as one (`crate::world::WorldLayout`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum TwistMethod {
    /// Kmoch 2009 Sec. 6.2: material frames follow the curvature binormals.
    HairOptimised,
    /// BWR08: Newton's method on the tridiagonal twist Hessian.
    Newton,
}

impl TwistMethod {
    /// The method's name in scene files (`"hair-optimised"`, `"newton"`).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            TwistMethod::HairOptimised => "hair-optimised",
            TwistMethod::Newton => "newton",
        }
    }
}

/// How iterative stages decide when to stop.
///
/// One byte, the variant's index (`repr(u8)`): a world's raw bytes can be checked before they
/// are read as one (`crate::world::WorldLayout`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
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
    /// `s_g` per step at `reference_dt`. Default 0.0066 at 1 ms (the paper's 0.1 at 16 ms,
    /// carried to 1 ms by its relaxation time).
    pub global_shape: Real,
    /// `s_l` per step at `reference_dt`. Default 0.022 at 1 ms (the paper's 0.3 at 16 ms).
    pub local_shape: Real,
    /// The step at which `s_g`, `s_l` are given. Default 0.001 s: at other steps they are
    /// rescaled to the same spring ([`crate::math::relaxation_at_step`]).
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
    /// never per step: `s(Δt) = Δt²/(Δt² + α)` with `α = Δt_ref²(1 − s_ref)/s_ref`, the same
    /// spring at every step ([`crate::math::relaxation_at_step`] says why, and where this
    /// departs from the paper's rule, `docs/design-departures.md`).
    /// `s_d` is a fraction of the correction fed back and is not rescaled.
    #[must_use]
    pub fn at_step(&self, dt: Real) -> DftlCoefficients {
        let local_shape = crate::math::relaxation_at_step(self.local_shape, dt, self.reference_dt);
        DftlCoefficients {
            damping: self.damping,
            global_shape: crate::math::relaxation_at_step(self.global_shape, dt, self.reference_dt),
            local_shape,
            global_shape_fade: self.global_shape_fade,
            local_shape_fade: self.local_shape_fade,
            bending_reaction: 0.5 * (1.0 - local_shape),
            shape_retention: crate::math::shape_damping_retention(
                self.global_shape,
                self.local_shape,
                self.reference_dt,
                dt,
            ),
        }
    }
}

/// DFTL's coefficients at the world's step (see [`DftlParams::at_step`]).
#[derive(Clone, Copy, Debug, PartialEq)]
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
    /// `φ = (1 − s_l)/2`: the share of the local correction's reaction handed to the node
    /// before the previous one, as a bending stencil (`dftl::velocity`).
    pub bending_reaction: Real,
    /// `r`, the per-step velocity retention of the shape damping (`dftl::damping`); 1 at and
    /// above 60 Hz.
    pub shape_retention: Real,
}

impl DftlCoefficients {
    /// No DFTL: every coefficient 0, no damping (`r` = 1).
    pub const NONE: DftlCoefficients = DftlCoefficients {
        damping: 0.0,
        global_shape: 0.0,
        local_shape: 0.0,
        global_shape_fade: 0.0,
        local_shape_fade: 0.0,
        bending_reaction: 0.0,
        shape_retention: 1.0,
    };
}

impl Default for DftlCoefficients {
    fn default() -> Self {
        Self::NONE
    }
}

/// Wind, an external acceleration on every free node of both solvers (used when `wind` is on):
/// `a(t) = direction · strength · (1 + gust · n(t))`, with `n` a seeded, smooth value noise of
/// time in `[−1, 1]` (see `wind::wind_acceleration`).
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
/// `Ok` if `ok`, else the out-of-range error naming `field` and what is `allowed`.
fn range(ok: bool, field: &'static str, allowed: &'static str) -> Result<(), ParamError> {
    if ok {
        Ok(())
    } else {
        Err(ParamError::OutOfRange { field, allowed })
    }
}

/// The least `s_d` DFTL accepts with the local shape constraint on ([`Params::validate`]).
pub const MIN_SHAPE_DAMPING: Real = 0.5;

/// Air drag per node of the presets, kg/s: what the built-in scenes and the scene files in
/// `scenes/` use for human hair at 1 cm segments.
pub const PRESET_DRAG: Real = 2.0e-7;

impl Params {
    /// The rod's preset (Kmoch 2009): gravity, air drag ([`PRESET_DRAG`]), bending, twist
    /// (hair-optimised, Sec. 6.2) and inextensibility (the fast manifold projection, capped at
    /// 8 iterations, tolerance 1e-6), at 1 ms in converge mode. No collisions and no grabs: a
    /// scene turns them on when it adds colliders or grabs (adding one while its effect is off
    /// is refused, [`crate::World::add_collider`]).
    pub const ROD: Params = Params {
        solver: Solver::Rod,
        dt: 0.001,
        effects: Effects::from_slice(&[
            Effect::Gravity,
            Effect::Drag,
            Effect::Bending,
            Effect::Twist,
            Effect::Inextensibility,
        ]),
        mode: Mode::Converge,
        gravity: Vec3::new(0.0, -9.81, 0.0),
        drag: PRESET_DRAG,
        rod: RodParams {
            projection_iterations: 8,
            projection_tolerance: 1.0e-6,
            twist: TwistMethod::HairOptimised,
            newton_iterations: 10,
            newton_tolerance: 1.0e-6,
        },
        dftl: DftlParams {
            damping: 0.9,
            // The paper's s_g = 0.1, s_l = 0.3 at 16 ms carried to 1 ms by its relaxation
            // time, `1 − (1 − s)^{1/16}`, and held as springs from there.
            global_shape: 0.0066,
            local_shape: 0.022,
            reference_dt: 0.001,
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

    /// DFTL's preset (Sánchez-Banderas 2015): gravity, air drag ([`PRESET_DRAG`]),
    /// inextensibility (follow-the-leader) and shape preservation (the paper's `s_g` = 0.1 and
    /// `s_l` = 0.3 at 16 ms, carried to 1 ms; `s_d` = 0.9), at 1 ms. No collisions and no grabs,
    /// as [`Params::ROD`]. A strand a grab holds runs the rod's projection at its cap every step
    /// (`pipeline::dftl`): 2 iterations, not the rod's 8, which hold a held strand's segments
    /// within 1.4e-6 of their length (the `haptic-dftl` scene over 3 s; 2.0e-4 with one) at a
    /// quarter of the cost.
    pub const DFTL: Params = Params {
        solver: Solver::Dftl,
        effects: Effects::from_slice(&[
            Effect::Gravity,
            Effect::Drag,
            Effect::Inextensibility,
            Effect::Shape,
        ]),
        rod: RodParams {
            projection_iterations: 2,
            ..Params::ROD.rod
        },
        ..Params::ROD
    };

    /// The rod's preset, [`Params::ROD`]: what `World::new` starts from. In a build without
    /// the rod (its cargo feature off) DFTL's, [`Params::DFTL`]: a new world is always one this
    /// build can step.
    pub const DEFAULT: Params = if cfg!(feature = "rod") {
        Params::ROD
    } else {
        Params::DFTL
    };

    /// The preset of `solver`: the effects and values hair needs ([`Params::ROD`],
    /// [`Params::DFTL`]). Start from it and change what the scene needs.
    #[must_use]
    pub const fn preset(solver: Solver) -> Params {
        match solver {
            Solver::Rod => Params::ROD,
            Solver::Dftl => Params::DFTL,
        }
    }

    /// Checks every parameter against its range and the effects against the solver (the
    /// first failure, in this order: the solver, time step, forces, rod, DFTL, wind, effects).
    pub fn validate(&self) -> Result<(), ParamError> {
        self.validate_time_step_and_forces()?;
        self.validate_rod()?;
        self.validate_dftl()?;
        self.validate_wind()?;
        if let Some(effect) = self.effects.unsupported_by(self.solver) {
            return Err(ParamError::UnsupportedEffect {
                effect: effect.name(),
                solver: self.solver.name(),
            });
        }
        Ok(())
    }

    /// The time step (for the solver) and the scene's gravity and drag.
    fn validate_time_step_and_forces(&self) -> Result<(), ParamError> {
        range(
            self.solver.is_built(),
            "solver",
            "a solver this build has: `rod` and `dftl`, unless the core was built without one \
             (its cargo feature off)",
        )?;
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
        Ok(())
    }

    /// The rod's iteration caps and tolerances.
    fn validate_rod(&self) -> Result<(), ParamError> {
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
        Ok(())
    }

    /// DFTL's fractions, reference step and fades.
    fn validate_dftl(&self) -> Result<(), ParamError> {
        let fraction = |v: Real| v.is_finite() && (0.0..=1.0).contains(&v);
        range(fraction(self.dftl.damping), "dftl.damping", "0 to 1")?;
        range(
            self.solver != Solver::Dftl
                || !self.effects.contains(Effect::Shape)
                || self.dftl.local_shape == 0.0
                || self.dftl.damping >= MIN_SHAPE_DAMPING,
            "dftl.damping",
            "0.5 to 1 with the local shape constraint on (it pulls node i + 1 into node i's \
             frame with no reaction; without eq. 14's feedback a strand on a head shaking at \
             10 rad/s flutters: 21 m/s at s_d = 0 and 1 ms, 640 m/s at s_d = 0.1 and 10 µs, \
             tests/torture.rs)",
        )?;
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
        Ok(())
    }

    /// The wind.
    fn validate_wind(&self) -> Result<(), ParamError> {
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
    fn presets_are_hair() {
        let rod = Params::preset(Solver::Rod);
        let dftl = Params::preset(Solver::Dftl);
        assert_eq!((rod, dftl), (Params::ROD, Params::DFTL));
        assert_eq!(Params::DEFAULT, Params::ROD);
        let names = |p: &Params| {
            p.effects
                .iter()
                .map(Effect::name)
                .collect::<heapless::Vec<_, 10>>()
        };
        assert_eq!(
            names(&rod),
            ["gravity", "drag", "bending", "twist", "inextensibility"]
        );
        assert_eq!(
            names(&dftl),
            ["gravity", "drag", "inextensibility", "shape"]
        );
        for preset in [rod, dftl] {
            assert_eq!(preset.validate(), Ok(()));
            assert!(preset.drag > 0.0 && preset.gravity.y < 0.0 && preset.dt == 0.001);
        }
    }

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
        let dftl = Params::DFTL;
        assert_eq!(dftl.validate(), Ok(()));
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

    #[test]
    fn dftl_takes_grabs_and_refuses_the_rod_s_energies() {
        let dftl = Params::DFTL;
        let grabs_on_dftl = Params {
            effects: Effects::NONE.with(Effect::Grabs),
            ..dftl
        };
        assert_eq!(grabs_on_dftl.validate(), Ok(()));
        let twist_on_dftl = Params {
            effects: Effects::NONE.with(Effect::Twist),
            ..dftl
        };
        assert!(matches!(
            twist_on_dftl.validate(),
            Err(ParamError::UnsupportedEffect {
                effect: "twist",
                ..
            })
        ));
    }
}
