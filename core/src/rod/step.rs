//! One rod step, Kmoch 2009 Algorithm 1, as a list of stages each gated by the scene's effects.
//!
//! # Stiff hair: a fixed number of substeps, decided by the scene
//!
//! Symplectic Euler on the bending forces is stable for `dt ≤ dt_max = (h²/2)·√(ρA/(max(1,µ)α))`
//! (DESIGN.md "Stability"; [`RodRest::stable_time_step`](super::energy::RodRest)). Human hair
//! at 1 cm segments sits at 60–90 % of it at 1 ms, so stiffer hair (or µ > 1) would chatter. The
//! remedy chosen here is a **fixed** number of substeps per strand: stages (1) and (2) run
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
//! 119; 2 mm curls: 94), stages (1) and (2) are instead **one linearly implicit step**
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

use super::energy::{
    elastic_forces_with_angles, material_angles, rest_root_frame, RodFrames, RodRest,
};
use super::implicit::BendingSystem;
use super::twist::{hair_optimised_twist_with_angles, newton_twist, ClampedFrames, TwistMethod};
use super::{ClampedSegments, ElasticTerms};
use crate::context::StepContext;
use crate::effects::Effect;
use crate::frames::{angle_in_frame, transport_in_time, unwrap_near};
use crate::grab::Grab;
use crate::math::{Math, Real, Vec3};
use crate::params::Mode;
use crate::report::{Flags, Stage, StepReport};
use crate::strand::Strand;

/// Fraction of the stability limit a substep may use: symplectic Euler's highest mode is
/// bounded below the limit, but its amplitude grows like `1/√(1 − (dt/dt_max)²)`; at 0.7 a
/// perturbation of the stiffest mode stays within 1.4× its size, and the bound (computed for
/// uniform segments) keeps a margin for curved and uneven ones.
pub const SAFETY: Real = 0.7;
/// Most substeps a strand takes per step (bounded latency): enough for 1000× human bending
/// stiffness at 1 cm segments and 1 ms (119, see the module documentation).
pub const MAX_SUBSTEPS: u32 = 128;
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

/// Steps one strand by `ctx.dt`. `strand_index` is the strand's index in the whole scene (as
/// in [`Grab::strand`]); `accelerations` (if any) are the caller's per-node accelerations for
/// this strand (SPH, wind), indexed by node.
pub fn step<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    grabs: &[Grab],
    strand_index: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    // A grabbed node's segment is clamped like the root's (Kmoch Sec. 7.2).
    let clamped = if ctx.has(Effect::Grabs) {
        ClampedSegments::from_grabs(grabs, strand_index, strand.rest.nodes)
    } else {
        ClampedSegments::ROOT_ONLY
    };
    let terms = elastic_terms(ctx);
    // One frames buffer for the step, recomputed in place as the centreline moves; none
    // without bending and twist (nothing to zero: an effect that is off costs nothing).
    let mut frames: Option<RodFrames<M, N>> = None;
    if terms.bending || terms.twist {
        refresh_frames(frames.insert(RodFrames::empty()), strand);
    }
    let start = StepStart::<M>::capture(strand, &clamped, frames.as_ref());
    // (1) elastic forces [bending, twist] and (2) external forces + symplectic Euler, substepped.
    let angles = forces_and_integrate::<M, N>(
        strand,
        ctx,
        &clamped,
        terms,
        frames.as_mut(),
        accelerations,
        report,
    );
    // (3) Root coupling: the head carries nodes 0 and 1, the root frame u^0 and θ^0.
    root_coupling_with_frame::<M, N>(strand, ctx, &start, report);
    // (4) Fast manifold projection [inextensibility, collisions, grabs] and velocity update.
    crate::projection::project_constraints::<M, N>(strand, ctx, grabs, strand_index, report);
    // (5) Twist [twist]: the Bishop frame in space for the new centreline, then θ.
    // (Twist on means frames.)
    if let (true, Some(frames)) = (ctx.has(Effect::Twist), frames.as_mut()) {
        update_twist::<M, N>(strand, ctx, &clamped, frames, &start, &angles, report);
    }
}

/// The elastic energies the scene turns on.
fn elastic_terms(ctx: &StepContext) -> ElasticTerms {
    ElasticTerms {
        bending: ctx.has(Effect::Bending),
        twist: ctx.has(Effect::Twist),
    }
}

/// What the step needs from the configuration it starts from: the root tangent (for the
/// time-parallel transport of `u^0`) and the clamped segments' material frames.
struct StepStart<M: Math> {
    root_tangent: Option<Vec3>,
    clamped_frames: Option<ClampedFrames<M>>,
}

impl<M: Math> StepStart<M> {
    /// `frames` are those of the strand's centreline, there when bending or twist is on.
    fn capture<const N: usize>(
        strand: &Strand<N>,
        clamped: &ClampedSegments,
        frames: Option<&RodFrames<M, N>>,
    ) -> Self {
        let Some(frames) = frames else {
            return StepStart {
                root_tangent: None,
                clamped_frames: None,
            };
        };
        let x = &strand.state.position;
        let clamped_frames = clamped
            .others()
            .next()
            .map(|_| ClampedFrames::save(frames, &strand.state.theta, clamped));
        StepStart {
            root_tangent: Some(unit::<M>(x[1] - x[0])),
            clamped_frames,
        }
    }
}

/// `v / |v|` with the backend's square root.
fn unit<M: Math>(v: Vec3) -> Vec3 {
    v * (1.0 / M::length(v))
}

/// `frames` recomputed in place for the strand's current centreline.
fn refresh_frames<M: Math, const N: usize>(frames: &mut RodFrames<M, N>, strand: &Strand<N>) {
    let n = strand.rest.nodes.min(N);
    frames.recompute(
        &strand.state.position[..n],
        strand.state.root_frame,
        &strand.rest.rod.rest_length,
    );
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
    let mut smallest: Real = 2.0;
    let n = frames.interior().min(N.saturating_sub(1));
    for i in 1..=n {
        let scale = rest_length[i - 1] * rest_length[i];
        let relative = frames.denominator[i] / scale;
        // A NaN counts as a fold (the guard rolls the strand back after the step).
        if relative < smallest || relative.is_nan() {
            smallest = relative;
        }
    }
    smallest
}

/// Substeps for the strand's *current* shape: the bending stiffness of the discrete rod grows
/// with the turning angle. `(κb)_i = 2 tan(φ_i/2) b̂` has `∇(κb)_i ∝ 1/d_i`
/// (DESIGN.md "Kirchhoff rod step"), so the Hessian of `E_bend` grows like `1/d_i²` and the
/// explicit limit shrinks like `d_i`: with `g = min_i d_i/(|ê^{i−1}||ê^i|)` (2 when straight,
/// [`smallest_binormal_denominator`]), `dt_max(x) = dt_max · g/2`. A strand swung hard at the
/// root reaches `φ ≈ 2 rad` (`g ≈ 0.5`, 4× shorter limit; the eigenvalues of `M⁻¹K` measured
/// on the firmware scene follow this within a factor 1.4), so a count from rest data alone
/// lets the stiffest mode run past the limit and chatter, which folds the strand further
/// (positive feedback). Near a fold (`g → 0`) the count reaches the cap [`MAX_SUBSTEPS`].
#[must_use]
pub fn substeps_for_shape<const N: usize>(
    rest: &RodRest<N>,
    dt: Real,
    bending: bool,
    smallest_denominator: Real,
) -> u32 {
    // A non-positive or NaN denominator (a fold) takes the cap.
    let stiffening = if smallest_denominator > 0.0 {
        2.0 / smallest_denominator.min(2.0)
    } else {
        Real::INFINITY
    };
    substeps_at_stiffness(rest, dt, bending, stiffening)
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
    let stiffening = if smallest_denominator > 0.0 {
        2.0 / smallest_denominator.min(2.0)
    } else {
        Real::INFINITY
    };
    substeps_at_stiffness(rest, dt, true, stiffening * STEP_ALLOWANCE)
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

/// Stages (1) and (2), `k` times with `h = dt/k` ([`substeps`]; in converge mode from the
/// current shape, [`substeps_within_step`]): the elastic forces of
/// Kmoch Sec. 7.2 at the current `θ` ([`elastic_forces_with_angles`]), then
/// [`external_forces_and_integrate`]. Returns `(cos θ^j, sin θ^j)` of the angles it used
/// (the hair-optimised twist compares against them). `frames`, there when bending or twist is
/// on, come in as those of the centreline the step starts from and are recomputed in place
/// for each later substep.
fn forces_and_integrate<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    mut frames: Option<&mut RodFrames<M, N>>,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> [[Real; 2]; N] {
    let fixed = substeps(&strand.rest.rod, ctx.dt, terms.bending);
    // (Bending on means frames.)
    let bending_frames = frames.as_deref().filter(|_| terms.bending);
    if let Some(frames) = bending_frames {
        if fixed >= IMPLICIT_FROM || strand.rest.rod.implicit_bending {
            return implicit_step::<M, N>(
                strand,
                ctx,
                clamped,
                terms,
                frames,
                accelerations,
                report,
            );
        }
    }
    // `frames` are those of the shape the step starts from: they set the substep count and
    // serve the first substep's forces. The sharpest fold's `1 + cos φ` (2 when straight;
    // none without bending).
    let smallest = bending_frames
        .map(|frames| smallest_binormal_denominator(frames, &strand.rest.rod.rest_length));
    let for_shape = smallest.map_or(fixed, |smallest| {
        substeps_for_shape(&strand.rest.rod, ctx.dt, true, smallest)
    });
    if let (Some(frames), true) = (bending_frames, for_shape >= IMPLICIT_FROM) {
        // A fold sharper than substeps can hold (≥ 137° for human hair at 1 cm and 1 ms):
        // explicit substeps would whip it and lose it. The implicit step holds it, from now on
        // (one switch per strand, so the cost per step stays bounded by the implicit step's).
        strand.rest.rod.implicit_bending = true;
        return implicit_step::<M, N>(strand, ctx, clamped, terms, frames, accelerations, report);
    }
    // Converge mode counts the substeps from the shape the step starts from (with a margin
    // for the fold to tighten within the step); fixed cost takes the count from rest data
    // and the allowance, the same on every step.
    let k = match (smallest, ctx.params.mode) {
        (Some(smallest), Mode::Converge) => {
            substeps_within_step(&strand.rest.rod, ctx.dt, smallest)
        }
        _ => fixed,
    };
    let h = ctx.dt / k as Real;
    let mut forces = [Vec3::ZERO; N];
    let segments = strand.rest.nodes.saturating_sub(1).min(N);
    // θ is held over the substeps: its sines and cosines are computed once.
    let cos_sin = if frames.is_some() {
        report.ran(Stage::ElasticForces);
        material_angles::<M, N>(&strand.state.theta[..segments])
    } else {
        [[1.0, 0.0]; N]
    };
    report.ran(Stage::ExternalForces);
    report.ran(Stage::Integrate);
    // Positions are the step's start plus a displacement summed over the substeps: adding
    // `v·h` to a position of ~0.1 m rounds at ~4e-9 m, and k roundings per step would add up
    // (a strand at rest drifted 2.4e-6 m in 10 s with k = 4 against 0.6e-6 m with k = 1).
    let mut start = strand.state.position;
    let mut displacement = [Vec3::ZERO; N];
    let substep_projection = inextensibility_between_substeps(ctx, k, h);
    for substep in 0..k {
        if let Some(frames) = frames.as_deref_mut() {
            // The first substep starts where the frames were computed.
            if substep > 0 {
                refresh_frames(frames, strand);
            }
            elastic_forces_with_angles(
                frames,
                &strand.state.theta,
                &cos_sin,
                &strand.rest.rod,
                clamped,
                terms,
                &mut forces,
            );
        }
        external_forces_and_integrate(
            strand,
            ctx,
            &forces,
            h,
            accelerations,
            (&start, &mut displacement),
        );
        if let (Some(sub), true) = (&substep_projection, substep + 1 < k) {
            // Segment lengths between substeps; the step's own projection follows the last.
            let mut scratch = StepReport::default();
            crate::projection::project_constraints::<M, N>(strand, sub, &[], 0, &mut scratch);
            start = strand.state.position;
            displacement = [Vec3::ZERO; N];
        }
    }
    cos_sin
}

/// Stages (1) and (2) with bending on, as one linearly implicit step of `dt`
/// ([`super::implicit`]): the elastic forces of Kmoch Sec. 7.2 at the current `θ`, the
/// external forces as in [`external_forces_and_integrate`], then
/// `(M + dt² H̃) v⁺ = M (v + dt a)` and `x⁺ = x + dt v⁺`, all at `frames`, those of the
/// centreline the step starts from. Returns `(cos θ^j, sin θ^j)`.
///
/// Not inlined: inlined into [`forces_and_integrate`] it made the substep path of human hair
/// 2.4 % dearer on the Cortex-M4F (QEMU, 128 nodes), 1.2 % with it kept apart.
#[inline(never)]
fn implicit_step<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    frames: &RodFrames<M, N>,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> [[Real; 2]; N] {
    report.ran(Stage::ElasticForces);
    report.ran(Stage::ExternalForces);
    report.ran(Stage::Integrate);
    let h = ctx.dt;
    let n = strand.rest.nodes.min(N);
    let segments = n.saturating_sub(1);
    let cos_sin = material_angles::<M, N>(&strand.state.theta[..segments]);
    let mut forces = [Vec3::ZERO; N];
    elastic_forces_with_angles(
        frames,
        &strand.state.theta,
        &cos_sin,
        &strand.rest.rod,
        clamped,
        terms,
        &mut forces,
    );
    let mut system = BendingSystem::<N>::default();
    system.assemble(frames, &strand.rest.mass, &strand.rest.rod, h);
    system.factor();
    let drag = drag(ctx);
    // Right-hand side M (v + h a), with a as in the explicit step.
    let mut rhs = [[0.0; 3]; N];
    let state = &mut strand.state;
    let rest = &strand.rest;
    let nodes = rhs
        .iter_mut()
        .zip(&state.velocity)
        .zip(forces.iter().zip(rest.mass.iter().zip(&rest.inverse_mass)))
        .enumerate()
        .take(n)
        .skip(2);
    for (i, ((slot, v), (force, (mass, inverse_mass)))) in nodes {
        let a = acceleration(ctx, *force, *v, drag, *inverse_mass, accelerations, i);
        *slot = ((*v + a * h) * *mass).to_array();
    }
    let held_velocity = [0, 1].map(|i| held_node(ctx, rest.position[i], state.position[i]).1);
    BendingSystem::move_held_nodes(frames, &rest.rod, h, held_velocity, &mut rhs);
    system.solve(&mut rhs);
    let nodes = rhs
        .iter()
        .zip(state.velocity.iter_mut().zip(state.position.iter_mut()))
        .take(n)
        .skip(2);
    for (solved, (v, x)) in nodes {
        *v = Vec3::from_array(*solved);
        *x += *v * h;
    }
    cos_sin
}

/// The air drag coefficient `ν`, or zero with the `drag` effect off.
fn drag(ctx: &StepContext) -> Real {
    if ctx.has(Effect::Drag) {
        ctx.params.drag
    } else {
        0.0
    }
}

/// Node `i`'s acceleration `g + wind + (F − ν v)/m` plus the caller's.
#[inline(always)]
fn acceleration(
    ctx: &StepContext,
    force: Vec3,
    v: Vec3,
    drag: Real,
    inverse_mass: Real,
    accelerations: Option<&[Vec3]>,
    i: usize,
) -> Vec3 {
    let mut a = ctx.gravity + ctx.wind + (force - v * drag) * inverse_mass;
    if let Some(extra) = accelerations.and_then(|acc| acc.get(i)) {
        a += *extra;
    }
    a
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

/// The context of the inextensibility projection run between substeps (`None` below
/// [`PROJECTED_SUBSTEPS_FROM`] substeps or without `inextensibility`): the substep's `h`,
/// inextensibility only (contacts and grabs wait for the step's own projection, with the
/// head's end-of-step pose).
///
/// Why: the substeps resolve bending's fast modes, but a curved strand's bending forces have
/// components along its segments, and without the constraint those move freely for the whole
/// step. A helix of radius 2 mm in 2 mm segments (94 substeps at 1 ms) stretched unchecked for
/// 1 ms, the step's projection snapped it back (`v += Δx/dt`), and it blew up within 30 steps
/// even on a still head; with the lengths kept at every substep it holds
/// (`tests/torture.rs`). Cost: `k − 1` more tridiagonal projections per step.
fn inextensibility_between_substeps(ctx: &StepContext, k: u32, h: Real) -> Option<StepContext> {
    if k < PROJECTED_SUBSTEPS_FROM || !ctx.has(Effect::Inextensibility) {
        return None;
    }
    let mut sub = ctx.clone();
    sub.dt = h;
    sub.inv_dt = 1.0 / h;
    sub.effects = crate::effects::Effects::NONE.with(Effect::Inextensibility);
    // Only a stretch worth undoing: a projection writes positions, and its velocity update
    // `Δx/h` turns their rounding (~4e-9 m at 0.1 m) into ~1e-3 m/s of noise at the µs
    // substeps of stiff or curly hair, so a strand at rest must not be projected at all.
    // Converge mode with the tolerance raised to SUBSTEP_PROJECTION_TOLERANCE does that; the
    // cost of these projections therefore depends on the state (at most `(k − 1)` × the cap).
    sub.params.mode = Mode::Converge;
    if sub.params.rod.projection_tolerance < SUBSTEP_PROJECTION_TOLERANCE {
        sub.params.rod.projection_tolerance = SUBSTEP_PROJECTION_TOLERANCE;
    }
    Some(sub)
}

/// Symplectic Euler with the elastic forces `forces` and the external forces `F = M g − ν ẋ`
/// plus caller accelerations: `v ← v + h F/m`, then `x ← x + h v` (Kmoch 2009 Sec. 7,
/// Alg. 1 lines 7–8), with `x = x_start + Σ v h` over the substeps so far. Nodes 0 and 1
/// belong to the head.
fn external_forces_and_integrate<const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    forces: &[Vec3; N],
    h: Real,
    accelerations: Option<&[Vec3]>,
    (start, displacement): (&[Vec3; N], &mut [Vec3; N]),
) {
    let n = strand.rest.nodes.min(N);
    let drag = if ctx.has(Effect::Drag) {
        ctx.params.drag
    } else {
        0.0
    };
    let state = &mut strand.state;
    let nodes = state
        .position
        .iter_mut()
        .zip(start.iter().zip(displacement.iter_mut()))
        .zip(state.velocity.iter_mut())
        .zip(forces.iter().zip(&strand.rest.inverse_mass))
        .enumerate()
        .take(n)
        .skip(2);
    for (i, (((x, (x0, d)), v), (force, inverse_mass))) in nodes {
        let mut a = ctx.gravity + ctx.wind + (*force - *v * drag) * *inverse_mass;
        if let Some(extra) = accelerations.and_then(|acc| acc.get(i)) {
            a += *extra;
        }
        *v += a * h;
        *d += *v * h;
        *x = *x0 + *d;
    }
}

/// Root coupling: nodes 0 and 1 are prescribed by the head's rigid motion; their velocity is
/// the position change over the step. Shared by both solvers (DFTL too).
pub(crate) fn root_coupling<const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    report: &mut StepReport,
) {
    report.ran(Stage::RootCoupling);
    for i in 0..2 {
        let (position, velocity) =
            held_node(ctx, strand.rest.position[i], strand.state.position[i]);
        strand.state.velocity[i] = velocity;
        strand.state.position[i] = position;
    }
}

/// One held root node: its rest position moved with the head, and the velocity that gets it
/// there from `position` in one step. (The DFTL block path calls it per lane.)
#[inline(always)]
pub(crate) fn held_node(ctx: &StepContext, rest_position: Vec3, position: Vec3) -> (Vec3, Vec3) {
    let target = ctx.head.transform_point(rest_position);
    (target, (target - position) * ctx.inv_dt)
}

/// [`root_coupling`], then, with bending or twist on, the root Bishop vector `u^0` follows the
/// root tangent by time-parallel transport (Kmoch Sec. 5 — the root segment is final here: the
/// projection never moves prescribed nodes), and `θ^0` is the angle from `u^0` to the
/// head-fixed root material vector, so hair follows head roll.
fn root_coupling_with_frame<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    start: &StepStart<M>,
    report: &mut StepReport,
) {
    root_coupling(strand, ctx, report);
    let Some(old_tangent) = start.root_tangent else {
        return;
    };
    let state = &mut strand.state;
    let tangent = unit::<M>(state.position[1] - state.position[0]);
    let u = transport_in_time::<M>(old_tangent, tangent, state.root_frame);
    let rest = &strand.rest;
    let rest_material =
        rest_root_frame::<M>(rest.position[0], rest.position[1], rest.segment_length[0]);
    let material = ctx.head.transform_vector(rest_material);
    let angle = angle_in_frame::<M>(u, tangent.cross(u), material);
    state.theta[0] = unwrap_near(angle, state.theta[0]);
    state.root_frame = u;
}

/// Stage (5): the quasistatic twist for the new centreline — its frames (recomputed in place
/// in `frames`), the clamped segments' frames by time-parallel transport, then the free angles
/// by the scene's [`TwistMethod`].
fn update_twist<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    frames: &mut RodFrames<M, N>,
    start: &StepStart<M>,
    angles: &[[Real; 2]; N],
    report: &mut StepReport,
) {
    report.ran(Stage::Twist);
    let terms = elastic_terms(ctx);
    refresh_frames(frames, strand);
    let frames = &*frames;
    let segments = strand.rest.nodes.saturating_sub(1).min(N);
    let rest = &strand.rest.rod;
    let theta = &mut strand.state.theta[..segments];
    if let Some(saved) = &start.clamped_frames {
        saved.transport(frames, clamped, theta);
    }
    match ctx.params.rod.twist {
        // The angles' cosines and sines from the start of the step: only clamped segments
        // (skipped by the sweep) have moved since.
        TwistMethod::HairOptimised => {
            hair_optimised_twist_with_angles(frames, rest, clamped, terms, theta, angles);
        }
        TwistMethod::Newton => {
            let outcome = newton_twist(
                frames,
                rest,
                clamped,
                terms,
                ctx.params.rod.newton_iterations,
                ctx.params.rod.newton_tolerance,
                ctx.params.mode == Mode::FixedCost,
                theta,
            );
            report.iterations_max = report.iterations_max.max(outcome.iterations);
            if !outcome.converged {
                report.flags.insert(Flags::CAP_HIT);
            }
        }
    }
}

#[cfg(test)]
mod tests;
