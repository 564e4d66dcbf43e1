//! The rod's substep policy: how many explicit substeps of the forces and the integration a
//! strand takes per step, or whether it takes one linearly implicit bending step instead, and
//! the check that refuses a strand no policy can step stably
//! ([`Params::validate_strand`](crate::params::Params::validate_strand)).
//!
//! # Stiff hair: a fixed number of substeps, decided by the scene
//!
//! Symplectic Euler on the bending forces is stable for `dt ≤ dt_max = (h²/2)·√(ρA/(max(1,µ)α))`
//! (docs/architecture.md, "Stability of explicit bending";
//! [`RodRest::stable_time_step`](crate::strand::RodRest)). Human hair at 1 cm segments sits at
//! 60–90 % of it at 1 ms, so stiffer hair (or µ > 1) would chatter. The remedy chosen here is a
//! **fixed** number of substeps per strand: the forces and the integration (lines 3–4) run
//! `k = ⌈dt · FOLD_ALLOWANCE / (SAFETY · dt_max)⌉` times with `dt / k` ([`substeps`]). `k`
//! depends only on rest data and `dt`, so it is decided when the scene is set up and a step's
//! cost does not depend on the state (fixed-cost mode: the same work on a calm and a violent
//! step). A configuration that needs more than [`MAX_SUBSTEPS`] is refused by
//! [`Params::validate_strand`](crate::params::Params::validate_strand).
//!
//! Why [`FOLD_ALLOWANCE`]: the bending stiffness of the discrete rod is not the rest stiffness.
//! `(κb)_i = 2 tan(φ_i/2)` makes the Hessian grow like `1/d_i²`, so the explicit limit of a
//! strand bent to a turning angle `φ` is `dt_max · (1 + cos φ)/2` ([`substeps_for_shape`]). A
//! shaking head bends strands at the root to `φ ≈ 2 rad` (`1 + cos φ ≈ 0.5`, measured on the
//! firmware scene); a count from the straight limit alone let its stiffest mode run at 3× the
//! limit and blow up. The allowance 4 covers turning angles up to 120°. In *fixed-cost* mode
//! that count holds on every step, whatever the shape (a sharper fold than 120° between two
//! 1 cm segments is not hair-like; the projection and the guard keep it finite). In
//! *converge* mode the count comes instead from the shape each step starts from, with
//! [`STEP_ALLOWANCE`] for the fold to tighten during the step ([`substeps_within_step`]):
//! 3 substeps rather than 4 for human hair at 1 cm and 1 ms while its turning angles stay
//! small, more for a sharper fold (up to [`MAX_SUBSTEPS`]).
//!
//! With [`PROJECTED_SUBSTEPS_FROM`] or more substeps the segment lengths are also projected
//! between substeps (`inextensibility_between_substeps`): a curved strand's bending forces
//! have components along its segments, and left unconstrained for a whole step they pumped
//! energy into ×10 stiff hair on a shaking head and blew up 2 mm curls within 30 steps.
//!
//! Cost, measured on x86-64 (callgrind) for a 30-node strand: frames ≈ 6.0k instructions,
//! forces ≈ 12.2k, so ≈ 18k per substep; one square root per segment and no trigonometry per
//! substep (the material angles' sines and cosines are computed once per step). At 1 cm and
//! 1 ms, µ = 1, `k = 4, 12, 38, 119` for ×1, ×10, ×100, ×1000 human bending stiffness
//! (`√µ` more for µ > 1), see the tests. Wall time of a whole step of one 30-node strand on a
//! shaking head, fixed-cost mode, projection cap 8 (test profile, opt-level 2, on this 2-core
//! machine at load average 12, so an upper figure): 91 µs (×1), 219 µs (×10), 518 µs (×100),
//! 1089 µs (×1000) — the substep counts those figures were taken with; from 8 substeps on a
//! strand now takes the implicit step below instead. Human hair keeps the substeps: they
//! integrate the very forces the finite-difference tests check (no linearisation, no linear
//! solve, no artificial damping), and at 4 substeps they cost no more than the implicit step.
//!
//! # Stiffer than human hair: one linearly implicit step
//!
//! From [`IMPLICIT_FROM`] = 8 fixed substeps on (×10 human hair at 1 cm and 1 ms: 12; ×1000:
//! 119; 2 mm curls: 94), lines 3–4 are instead **one linearly implicit step**
//! ([`super::implicit`]): `(M + dt² H̃) v⁺ = M (v + dt a)`, `x⁺ = x + dt v⁺`, with `a` the
//! same explicit forces and `H̃` a banded positive semi-definite approximation of the bending
//! Hessian (Gauss–Newton of the curvature binormals, a bound on the holonomy part, an axial
//! term for the segment lengths), solved per strand in O(n) (half-bandwidth 8). Its cost does
//! not grow with the stiffness: about 2.4 force evaluations on x86-64 (callgrind: frames
//! ≈ 410, forces ≈ 380, matrix ≈ 800, factor ≈ 500, solve ≈ 330 instructions per node), more
//! on the Cortex-M4F (the latency scene of 1 cm human hair, k = 4, measured 6,270 instructions
//! per node per step implicit against 5,540 with the substeps), so human hair (k = 4) keeps
//! its substeps and hair that needs 8 or more takes the implicit step. What it changes: the stiffest
//! bending modes of the discrete strand (`dt²λ ≫ 1`, where a saw-tooth would live) lose
//! energy each step instead of being resolved; slow motion and static equilibria are those
//! of the explicit forces. The choice depends only on rest data and `dt` (set-up time, fixed
//! cost).

use super::frames::RodFrames;
use crate::context::{Gates, StepContext};
use crate::effects::{Effect, Effects};
use crate::error::ParamError;
use crate::lane::{Lane, Lanes, Wide};
use crate::math::{Math, Real};
use crate::params::{Mode, Params, Solver};
use crate::precision::Kernel;
use crate::strand::{RodRest, Schedule, Strand};

pub use crate::capacities::MAX_SUBSTEPS;

/// Fraction of the stability limit a substep may use: symplectic Euler's highest mode is
/// bounded below the limit, but its amplitude grows like `1/√(1 − (dt/dt_max)²)`; at 0.7 a
/// perturbation of the stiffest mode stays within 1.4× its size, and the bound (computed for
/// uniform segments) keeps a margin for curved and uneven ones.
pub const SAFETY: Real = 0.7;
/// How much stiffer than straight the fixed substep count allows the strand to get by bending:
/// `2/(1 + cos φ)` at the sharpest turning angle `φ`; 4 is `φ = 120°`.
pub const FOLD_ALLOWANCE: Real = 4.0;

/// Fewest fixed substeps ([`substeps`]) from which a strand takes one linearly implicit step
/// instead: [`PROJECTED_SUBSTEPS_FROM`], where the substeps start to need a projection
/// between them. Below it the substeps are cheaper or about as cheap (the implicit step costs
/// about as much as 4–5 substeps on the Cortex-M4F, measured under QEMU, see the module
/// documentation): human hair at 1 cm and 1 ms (4, and 6 with µ = 2) stays explicit, stiffer
/// hair (×10: 12 and more) and tight curls do not pay for their stiffness. (With µ = 2 and
/// 6 substeps switched to the implicit step, a turned helix without inextensibility drifted
/// 7e-6 m in 10 s along its unconstrained segment lengths, `step::tests`.)
pub const IMPLICIT_FROM: u32 = PROJECTED_SUBSTEPS_FROM;

/// Whether a strand a grab holds bends with the implicit step. A device moves a held node
/// at up to 1 m/s with components up to 30 Hz (the haptic tests' paths): the folds it drives
/// along the strand tighten within a step faster than the substep plan allows for, and with
/// twist the explicit substeps then gave the hair energy no force put in (up to 9 % of the
/// work the device did, 3 seeds of 20 at 0.5 ms and 1 ms; one fold blew up to 48 J), where
/// the implicit step, which dissipates, passes every seed (`tests/haptic.rs`, passivity).
pub const HELD_IMPLICIT: bool = true;

/// How a strand integrates its forces this step (Kmoch Alg. 1 lines 3–4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integration {
    /// `k` substeps of the explicit forces and symplectic Euler, each of `dt / k`.
    Explicit(u32),
    /// One linearly implicit bending step (`rod::implicit`).
    Implicit,
}

impl Integration {
    /// The explicit substeps to take: `k`, or 1 for a strand the implicit step cannot take
    /// (the policy chooses it only for a strand with frames).
    #[must_use]
    pub fn substeps(self) -> u32 {
        match self {
            Integration::Explicit(k) => k,
            Integration::Implicit => 1,
        }
    }
}

/// The policy for one step of a strand with rest data `rest` and schedule `schedule`, whose
/// frames' [`smallest_binormal_denominator`] `smallest` gives (asked for only with bending
/// on, when the strand has frames): the implicit step when the strand
/// needs [`IMPLICIT_FROM`] or more fixed substeps, or its schedule says so; else, when its
/// shape is folded sharper than substeps can hold (≥ 137° for human hair at 1 cm and 1 ms),
/// the implicit step from now on (the schedule remembers: one switch per strand, so the cost
/// per step stays bounded by the implicit step's); else explicit substeps, counted from rest
/// data and the allowance in fixed-cost mode ([`substeps`]), from the shape the step starts
/// from with a margin for the fold to tighten within the step in converge mode
/// ([`substeps_within_step`]). Without bending, one substep. A strand a grab holds
/// (`held`) takes the implicit step while it is held ([`HELD_IMPLICIT`]).
pub fn plan<const N: usize>(
    ctx: &StepContext,
    rest: &RodRest<N>,
    (schedule, held): (&mut Schedule, bool),
    smallest: impl FnOnce() -> Real,
) -> Integration {
    let bending = ctx.gates.bending;
    let fixed = substeps(rest, ctx.dt, bending);
    // (Bending on means frames.)
    if !bending {
        return Integration::Explicit(fixed);
    }
    if fixed >= IMPLICIT_FROM || schedule.implicit_bending || (held && HELD_IMPLICIT) {
        return Integration::Implicit;
    }
    // The sharpest fold's `1 + cos φ` (2 when straight), in the shape the step starts from.
    let smallest = smallest();
    if substeps_for_shape(rest, ctx.dt, true, smallest) >= IMPLICIT_FROM {
        schedule.implicit_bending = true;
        return Integration::Implicit;
    }
    match ctx.params.mode {
        Mode::Converge => Integration::Explicit(substeps_within_step(rest, ctx.dt, smallest)),
        Mode::FixedCost => Integration::Explicit(fixed),
    }
}

/// The fixed substeps per step for this strand: `⌈dt · FOLD_ALLOWANCE / (SAFETY · dt_max)⌉`,
/// at least 1, at most [`MAX_SUBSTEPS`]. Depends only on rest data and `dt` (decided at set-up;
/// [`needed_substeps`] says whether the cap cuts it short).
#[must_use]
pub fn substeps<const N: usize>(rest: &RodRest<N>, dt: Real, bending: bool) -> u32 {
    substeps_at_stiffness(rest, dt, bending, FOLD_ALLOWANCE)
}

/// The substeps [`substeps`] would take without the cap, or `None` when more than
/// [`MAX_SUBSTEPS`] (or no finite count) are needed: the configuration cannot be made stable.
#[must_use]
pub fn needed_substeps<const N: usize>(rest: &RodRest<N>, dt: Real, bending: bool) -> Option<u32> {
    if !bending || !rest.stable_time_step.is_finite() {
        return Some(1);
    }
    let ratio = dt * FOLD_ALLOWANCE / (SAFETY * rest.stable_time_step);
    if ratio <= 1.0 {
        Some(1)
    } else if ratio <= MAX_SUBSTEPS as Real {
        Some(libm::ceilf(ratio) as u32)
    } else {
        None
    }
}

/// Smallest `d_i / (|ê^{i−1}||ê^i|)` over the interior nodes of `frames`, with
/// `d_i = |ê^{i−1}||ê^i| + e^{i−1}·e^i` the curvature binormal's denominator: `1 + cos φ_i`
/// for a turning angle `φ_i` at rest lengths, 2 for a straight node, 0 at a fold. `2` when
/// the strand has no interior node.
#[must_use]
pub fn smallest_binormal_denominator<M: Math, const N: usize>(
    frames: &RodFrames<M, N>,
    rest_length: &[Real; N],
) -> Real {
    smallest_relative_denominator(frames, rest_length)
}

/// [`smallest_binormal_denominator`] of each lane of the frames of `W` strands in lanes, at
/// once: lane `l` gets the bits its strand gets alone.
#[must_use]
pub fn smallest_binormal_denominators_in_lanes<M: Math, const N: usize, const W: usize>(
    frames: &RodFrames<Lanes<M, W>, N>,
    rest_length: &[Wide<W>; N],
) -> [Real; W] {
    smallest_relative_denominator(frames, rest_length).0
}

/// `min d_i / (|ê^{i−1}||ê^i|)` over the interior nodes (NaN when any is NaN), 2 when none.
#[inline(always)]
fn smallest_relative_denominator<P: Kernel, const N: usize>(
    frames: &RodFrames<P, N>,
    rest_length: &[P::R; N],
) -> P::R
where
    P::R: Lane,
{
    let mut smallest = P::R::splat(2.0);
    for i in 1..=frames.interior().min(N.saturating_sub(1)) {
        let scale = rest_length[i - 1] * rest_length[i];
        let relative = frames.denominator[i] / scale;
        // A NaN counts as a fold (the guard rolls the strand back after the step).
        let take = relative.lt(smallest) | relative.is_nan();
        smallest = P::R::select(take, relative, smallest);
    }
    smallest
}

/// Substeps for the strand's *current* shape: the bending stiffness of the discrete rod grows
/// with the turning angle. `(κb)_i = 2 tan(φ_i/2) b̂` has `∇(κb)_i ∝ 1/d_i`
/// (docs/architecture.md, the Kirchhoff rod step), so the Hessian of `E_bend` grows like
/// `1/d_i²` and the explicit limit shrinks like `d_i`: with `g = min_i d_i/(|ê^{i−1}||ê^i|)`
/// (2 when straight, [`smallest_binormal_denominator`]), `dt_max(x) = dt_max · g/2`. A strand
/// swung hard at the root reaches `φ ≈ 2 rad` (`g ≈ 0.5`, 4× shorter limit; the eigenvalues
/// of `M⁻¹K` measured on the firmware scene follow this within a factor 1.4), so a count from
/// rest data alone
/// lets the stiffest mode run past the limit and chatter, which folds the strand further
/// (positive feedback). Near a fold (`g → 0`) the count reaches the cap [`MAX_SUBSTEPS`].
#[must_use]
pub fn substeps_for_shape<const N: usize>(
    rest: &RodRest<N>,
    dt: Real,
    bending: bool,
    smallest_denominator: Real,
) -> u32 {
    substeps_at_stiffness(rest, dt, bending, stiffening(smallest_denominator))
}

/// How much stiffer than straight the shape with smallest binormal denominator `g` bends:
/// `2/min(g, 2)`; a non-positive or NaN denominator (a fold) is infinitely stiff, so its count
/// takes the cap.
fn stiffening(smallest_denominator: Real) -> Real {
    if smallest_denominator > 0.0 {
        2.0 / smallest_denominator.min(2.0)
    } else {
        Real::INFINITY
    }
}

/// How much a fold may tighten within one step in converge mode, as a factor on the
/// stiffening `2/(1 + cos φ)` of the shape the step starts from ([`substeps_within_step`]):
/// 2.2 lets `φ` go from 0 to 95° in one step. With 1.5 (2 substeps for straight human hair)
/// the rest-drift test saw 1.13e-6 m, above its bound (`step::tests`); with 2.2 (3 substeps)
/// at most 0.90e-6 m.
pub const STEP_ALLOWANCE: Real = 2.2;

/// Converge mode's substeps: the limit of the shape the step starts from
/// ([`substeps_for_shape`]) with [`STEP_ALLOWANCE`] for the fold to tighten during the step,
/// in place of [`FOLD_ALLOWANCE`]'s worst fold. A human hair hanging or swinging on a shaking
/// head (turning angles below ~30°) takes 3 substeps at 1 cm and 1 ms instead of the fixed 4;
/// the cost of a step then follows the shape (not fixed cost's promise).
#[must_use]
pub fn substeps_within_step<const N: usize>(
    rest: &RodRest<N>,
    dt: Real,
    smallest_denominator: Real,
) -> u32 {
    substeps_at_stiffness(
        rest,
        dt,
        true,
        stiffening(smallest_denominator) * STEP_ALLOWANCE,
    )
}

/// `⌈dt · stiffening / (SAFETY · dt_max)⌉` clamped to `1 ..= MAX_SUBSTEPS`; `stiffening ≥ 1`
/// divides the rest limit `dt_max`.
fn substeps_at_stiffness<const N: usize>(
    rest: &RodRest<N>,
    dt: Real,
    bending: bool,
    stiffening: Real,
) -> u32 {
    if !bending || !rest.stable_time_step.is_finite() {
        return 1;
    }
    let ratio = dt * stiffening / (SAFETY * rest.stable_time_step);
    if ratio <= 1.0 {
        1
    } else if ratio < MAX_SUBSTEPS as Real {
        libm::ceilf(ratio) as u32
    } else {
        // Also a NaN ratio: the most work, never an out-of-range cast.
        MAX_SUBSTEPS
    }
}

/// Fewest substeps at which the segment lengths are also projected between substeps
/// (`inextensibility_between_substeps`). Human hair at 1 cm and 1 ms takes 4 and is left
/// as it was: with projections between its substeps the firmware scene's mean chatter rose from
/// 1.2–1.45 to 1.6–1.7 rad and, with the hair-optimised twist, 2 of 13 shake frequencies
/// reached 7–9.5 rad (`tests/stability.rs`) — its grab and contacts are only enforced at the
/// end of the step. From 8 on (×10 stiffness at 1 cm: 12; curls in 2 mm segments: 94) they are
/// what keeps the strand stable. An empirical threshold between measured cases, not a bound.
pub const PROJECTED_SUBSTEPS_FROM: u32 = 8;
/// Relative stretch (`|e·e − ê·ê| / ê·ê`) below which a projection between substeps does
/// nothing; the step's own projection still meets the scene's tolerance.
pub const SUBSTEP_PROJECTION_TOLERANCE: Real = 1.0e-4;

/// Whether `k` substeps project the segment lengths between them
/// ([`inextensibility_between_substeps`]).
#[inline(always)]
#[must_use]
pub fn projects_between_substeps(ctx: &StepContext, k: u32) -> bool {
    k >= PROJECTED_SUBSTEPS_FROM && ctx.has(Effect::Inextensibility)
}

/// The context of the inextensibility projection run between substeps of `h` (when
/// [`projects_between_substeps`]): the substep's `h`, inextensibility only (contacts and grabs
/// wait for the step's own projection, with the head's end-of-step pose).
///
/// Why: the substeps resolve bending's fast modes, but a curved strand's bending forces have
/// components along its segments, and without the constraint those move freely for the whole
/// step. A helix of radius 2 mm in 2 mm segments (94 substeps at 1 ms) stretched unchecked for
/// 1 ms, the step's projection snapped it back (`v += Δx/dt`), and it blew up within 30 steps
/// even on a still head; with the lengths kept at every substep it holds
/// (`tests/torture.rs`). Cost: `k − 1` more tridiagonal projections per step.
#[inline(always)]
#[must_use]
pub fn inextensibility_between_substeps(ctx: &StepContext, h: Real) -> StepContext {
    let mut sub = ctx.clone();
    sub.dt = h;
    sub.inv_dt = 1.0 / h;
    sub.effects = Effects::NONE.with(Effect::Inextensibility);
    sub.gates = Gates::of(sub.effects, sub.collider_count);
    // Only a stretch worth undoing: a projection writes positions, and its velocity update
    // `Δx/h` turns their rounding (~4e-9 m at 0.1 m) into ~1e-3 m/s of noise at the µs
    // substeps of stiff or curly hair, so a strand at rest must not be projected at all.
    // Converge mode with the tolerance raised to SUBSTEP_PROJECTION_TOLERANCE does that; the
    // cost of these projections therefore depends on the state (at most `(k − 1)` × the cap).
    sub.params.mode = Mode::Converge;
    if sub.params.rod.projection_tolerance < SUBSTEP_PROJECTION_TOLERANCE {
        sub.params.rod.projection_tolerance = SUBSTEP_PROJECTION_TOLERANCE;
    }
    sub
}

impl Params {
    /// Checks that `strand` can be stepped stably with these parameters: with the rod solver and
    /// bending on, the fixed substep count that keeps explicit bending within its stability
    /// bound ([`needed_substeps`]) must fit [`MAX_SUBSTEPS`].
    /// Stiffer hair, shorter segments or a larger `µ` lower the limit like
    /// `h² / √(max(1, µ)·α)`; such a strand with too large a `dt` is refused here rather than
    /// left to chatter or explode.
    pub fn validate_strand<const N: usize>(&self, strand: &Strand<N>) -> Result<(), ParamError> {
        let bending = self.solver == Solver::Rod && self.effects.contains(Effect::Bending);
        match needed_substeps(&strand.rest.rod, self.dt, bending) {
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
}
