//! The quasistatic twist: the material angles `θ^j` of the unclamped segments, solved after
//! each step for the new centreline (Kmoch 2009 Sec. 6; BWR08 Sec. 5).
//!
//! * [`hair_optimised_twist`] — Kmoch Sec. 6.2: each segment's material frame follows its
//!   curvature binormals; one sweep root → tip, choosing among `θ`, `θ ± π` by the exact local
//!   energies. One `atan2` and a few square roots per segment, no iteration.
//! * [`newton_twist`] — BWR08: minimise `E` over the free `θ` with Newton's method on the
//!   tridiagonal Hessian, Gauss–Newton when the full Hessian is not positive definite, an
//!   iteration cap and a tolerance. The baseline of Kmoch's Table 2.
//!
//! Clamped segments (the root, grabbed segments) keep their `θ`, which [`ClampedFrames`] moves
//! by the time-parallel transport of their material frame.

use super::energy::{
    bending_matrix, bending_twist_derivative, elastic_energy, twist_stiffness,
    twist_twist_derivative,
};
use super::frames::{
    binormal_direction_in_lanes, material_angles, material_curvature, representative_near,
    RodFrames,
};
use super::{ClampedLanes, ClampedSegments, ElasticTerms};
use crate::capacities::MAX_CLAMPED;
use crate::context::StepContext;
use crate::frames::{angle_in_frame, material_frame, parallel_transport, unwrap_near};
use crate::lane::Wide;
use crate::math::{Math, Real};
use crate::params::Mode;
use crate::precision::{select_whole, Arithmetic, Kernel, Precision, Scalar, Trigonometry, Vector};
use crate::report::{Flags, Stage, StepReport};
use crate::strand::{RodRest, Strand};

pub use crate::params::TwistMethod;

/// Kmoch 2009 Algorithm 1 line 10, "compute twist", for the strand's new centreline, whose
/// frames `frames` are (line 9): the clamped segments' material frames by time-parallel
/// transport from `saved` (Sec. 6.1; none with only the root clamped), then the free angles
/// by the scene's [`TwistMethod`]. `angles` are `(cos θ^j, sin θ^j)` from the start of the
/// step: only clamped segments (skipped by the sweep) have moved since.
pub fn update<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    clamped: &ClampedSegments,
    frames: &RodFrames<M, N>,
    saved: Option<&ClampedFrames<M>>,
    angles: &[[Real; 2]; N],
    report: &mut StepReport,
) {
    report.ran(Stage::Twist);
    let terms = ElasticTerms::of(&ctx.gates);
    let segments = strand.rest.nodes.saturating_sub(1).min(N);
    let rest = &strand.rest.rod;
    let theta = &mut strand.state.theta[..segments];
    if let Some(saved) = saved {
        saved.transport(frames, clamped, theta);
    }
    match ctx.params.rod.twist {
        TwistMethod::HairOptimised => {
            hair_optimised_twist_with_angles(frames, rest, clamped, terms, theta, angles);
        }
        TwistMethod::Newton => {
            let settings = NewtonSettings::of(ctx);
            let outcome = newton_twist(frames, rest, clamped, terms, settings, theta);
            outcome.report(report);
        }
    }
}

/// The bending energy of nodes `j`, `j + 1` in frame `j` at `θ` and at `θ ± π`:
/// `Σ_i ½(1/l̂_i)(±ω − ω̂)ᵀB(±ω − ω̂)`, since `ω(θ ± π) = −ω(θ)`. Each is summed as squares
/// (not expanded), so near rest the comparison is not lost to cancellation.
#[inline(always)]
fn local_bending<P: Kernel, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    terms: ElasticTerms,
    j: usize,
    cos_sin: [P::R; 2],
) -> (P::R, P::R) {
    let n = frames.interior();
    let b = bending_matrix(rest, terms, j);
    let mut energies = (P::R::ZERO, P::R::ZERO);
    if j >= 1 && j <= n {
        add_node_bending(frames, rest, b, (j, 1), cos_sin, &mut energies);
    }
    if j < n {
        add_node_bending(frames, rest, b, (j + 1, 0), cos_sin, &mut energies);
    }
    energies
}

/// [`local_bending`]'s term of node `i` (`k`: which of its two frames), added to `energies`.
/// A function, not a closure: in lanes the compiler left the closure a call per node.
#[inline(always)]
fn add_node_bending<P: Kernel, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    b: [P::R; 2],
    (i, k): (usize, usize),
    cos_sin: [P::R; 2],
    energies: &mut (P::R, P::R),
) {
    let w = material_curvature(frames.bishop_curvature[i][k], cos_sin);
    let r = rest.rest_curvature[i][k];
    let scale = P::R::of(0.5) * rest.inverse_voronoi_length[i];
    let (d0, d1) = (w[0] - r[0], w[1] - r[1]);
    let (f0, f1) = (w[0] + r[0], w[1] + r[1]);
    energies.0 += (b[0] * d0 * d0 + b[1] * d1 * d1) * scale;
    energies.1 += (b[0] * f0 * f0 + b[1] * f1 * f1) * scale;
}

/// The twist energy of nodes `j`, `j + 1` with `θ^j = candidate`, the neighbours' angles as
/// `reference = θ^{j−1} + m̂_j` and `next = θ^{j+1} − m̂_{j+1}`: `w₀(θ^j − reference)² +
/// w₁(next − θ^j)²`, `w` = [`TwistWeights`]. These are the terms of `E`
/// ([`super::energy::node_twist_energy`]) with the rest twist taken into the neighbours' angles
/// once per segment, not once per candidate.
#[inline(always)]
fn local_twist<R: Arithmetic>(weights: &TwistWeights<R>, reference: R, candidate: R) -> R {
    let (before, after) = (candidate - reference, weights.next - candidate);
    weights.weight[0] * before * before + weights.weight[1] * after * after
}

/// What [`local_twist`] needs of segment `j` that does not depend on the sweep.
#[derive(Clone, Copy, Debug)]
struct TwistWeights<R> {
    /// `β/l̂_j` where node `j` is interior (`1 ≤ j ≤ n`), `β/l̂_{j+1}` where node `j + 1` is
    /// (`j < n`); 0 where not.
    weight: [R; 2],
    /// `θ^{j+1} − m̂_{j+1}` (0 past the tip), the angle segment `j + 1` has when the sweep
    /// reaches `j`: it comes later.
    next: R,
}

impl<R: Arithmetic> TwistWeights<R> {
    /// Segment `j`'s, with `θ = theta` as the sweep reaches it (`n` interior nodes).
    #[inline(always)]
    fn of<const N: usize>(
        rest: &RodRest<N, R>,
        terms: ElasticTerms,
        theta: &[R],
        j: usize,
        n: usize,
    ) -> Self {
        let beta = twist_stiffness(rest, terms);
        let interior = |i: usize| i >= 1 && i <= n;
        // Written out, not `[j, j + 1].map(..)`: the compiler left that map out of line in
        // the lanes' sweep (1.6 % of a block's step).
        let weight_at = |i: usize| {
            if interior(i) {
                beta * rest.inverse_voronoi_length[i]
            } else {
                R::ZERO
            }
        };
        let weight = [weight_at(j), weight_at(j + 1)];
        let next = if interior(j + 1) {
            theta[j + 1] - rest.rest_twist[j + 1]
        } else {
            R::ZERO
        };
        TwistWeights { weight, next }
    }
}

/// Kmoch 2009 Sec. 6.2, the hair-optimised twist, in place on `theta` (length ≥ segments):
/// [`hair_optimised_twist_with_angles`] with the cosines and sines of `theta` computed here
/// (one `sin_cos` per segment; the step passes the ones it already has).
pub fn hair_optimised_twist<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    theta: &mut [P::R],
) {
    // No angles given: the sweep takes each segment's `sin_cos` as it reaches it, beside the
    // previous segment's choice rather than in a pass before the sweep.
    hair_optimised_twist_with_angles(frames, rest, clamped, terms, theta, &[]);
}

/// Kmoch 2009 Sec. 6.2, the hair-optimised twist, in place on `theta`; `current[j]` holds
/// `(cos θ^j, sin θ^j)` of the angles passed in.
///
/// Sweep root → tip (a fixed order: determinism) over the unclamped segments, with the
/// already-updated `θ^{j−1}`: take the binormal direction
/// ([`binormal_direction_in_lanes`]) as the representative mod π nearest
/// `θ^{j−1} + m̂_j`, then keep whichever of the candidates has the
/// least local energy, evaluated exactly (the paper's closed-form criteria assume uniform `l̂`
/// and neighbours at rest twist; `ω(θ ± π) = −ω(θ)`). The candidates:
/// * the paper's three, `θ`, `θ + π`, `θ − π`;
/// * the continuation at zero local twist `θ^{j−1} + m̂_j`, also the choice when both binormals
///   vanish: without it a nearly straight strand (binormals of rounding size, directions at
///   random) takes random angles with up to π/2 of twist per segment;
/// * **the current angle `θ^j`**, which wins ties. The local energies are exactly the terms of
///   `E` that touch `θ^j` (bending at nodes `j`, `j+1` in frame `j`, twist at nodes `j`, `j+1`
///   with the neighbours' angles as they are at that point of the sweep), so with the current
///   angle among the candidates every update of the sweep lowers `E(x, θ)` or leaves it: the
///   twist is a descent step, like Newton with its line search. Without it the sweep can move
///   `θ^j` to a candidate of *higher* energy than the angle it had (all the paper's candidates
///   may lie above it), so that each step's θ update adds elastic energy at fixed `x` — an
///   energy pump: the firmware scene shaken at 13 frequencies blew up in 9 of them by step
///   ~770 (`tests/stability.rs`).
///
/// Trigonometry: one `atan2` per segment (θ is stored as an angle); the cosines and sines are
/// carried along the sweep. Angles stay continuous in time: every choice is made relative to
/// the neighbour or the current angle, and `θ^0` is unwrapped against its previous value.
pub fn hair_optimised_twist_with_angles<P: Trigonometry, C: ClampedLanes<P::R>, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    clamped: &C,
    terms: ElasticTerms,
    theta: &mut [P::R],
    current: &[[P::R; 2]],
) {
    let segments = frames.nodes.saturating_sub(1).min(theta.len()).min(N);
    if segments == 0 {
        return;
    }
    let n = frames.interior().min(segments - 1);
    // (cos θ^{j−1}, sin θ^{j−1}), carried down the strand: one sin_cos per strand (and per
    // clamped segment), none per node.
    let (s, c) = P::sin_cos(theta[0]);
    let mut previous = [c, s];
    for j in 1..segments {
        // One pass. A segment's candidates (its binormal direction with the `atan2`, their
        // bending energies) do not depend on the angles the sweep chooses, so the processor
        // computes them while the previous segment's choice completes; computed in a pass of
        // their own before the sweep, the twist took 1.2× the time (Table 2's bench). A
        // clamped segment's candidates are computed and not used (lanes: another strand's
        // segment may be free).
        let held = clamped.clamped(j);
        let (chosen, chosen_cos_sin) = if P::R::all(held) {
            (theta[j], [P::R::ONE, P::R::ZERO])
        } else {
            let at = (&*theta, j, n);
            let prepared = Candidates::of(frames, rest, terms, at, current.get(j).copied());
            choose(rest, terms, frames, theta, j, &prepared, previous)
        };
        if P::R::any(held) {
            let (s, c) = P::sin_cos(theta[j]);
            theta[j] = P::R::select(held, theta[j], chosen);
            previous = [
                P::R::select(held, c, chosen_cos_sin[0]),
                P::R::select(held, s, chosen_cos_sin[1]),
            ];
        } else {
            theta[j] = chosen;
            previous = chosen_cos_sin;
        }
    }
}

/// The sweep's choice for segment `j` (see [`hair_optimised_twist_with_angles`]) with
/// `(cos θ^{j−1}, sin θ^{j−1})` = `previous`: the candidate of least local energy, the current
/// angle winning ties. Returns the angle and its cosine and sine.
#[inline(always)]
fn choose<P: Trigonometry, const N: usize>(
    rest: &RodRest<N, P::R>,
    terms: ElasticTerms,
    frames: &RodFrames<P, N>,
    theta: &[P::R],
    j: usize,
    prepared: &Candidates<P::R>,
    previous: [P::R; 2],
) -> (P::R, [P::R; 2]) {
    // Zero local twist: θ^{j−1} + m̂_j, its cosine and sine by the rest rotation.
    let reference = theta[j - 1] + rest.rest_twist[j];
    let [cm, sm] = rest.rest_twist_rotation[j];
    let reference_cos_sin = [
        previous[0] * cm - previous[1] * sm,
        previous[1] * cm + previous[0] * sm,
    ];
    let twist = |candidate| local_twist(&prepared.twist, reference, candidate);
    // The current angle first: a candidate must be strictly lower to replace it.
    let kept = theta[j];
    let mut best = Choice {
        angle: kept,
        cos_sin: prepared.kept_cos_sin,
        energy: prepared.kept_bending + twist(kept),
    };
    let (continued, _) = local_bending(frames, rest, terms, j, reference_cos_sin);
    let continuation = Choice {
        angle: reference,
        cos_sin: reference_cos_sin,
        energy: continued + twist(reference),
    };
    best = lower_of::<P::R>(P::R::mask(true), continuation, best);
    let binormal = &prepared.binormal;
    if P::R::any(prepared.has_binormal) {
        let some = prepared.has_binormal;
        let (angle, cos_sin, odd) =
            representative_near::<P>(binormal.angle, binormal.direction, reference);
        // `ω(θ + π) = −ω(θ)`: the flipped representative swaps the two energies (the same
        // bits: negation is exact and rounding symmetric).
        let (at, opposite) = binormal.bending;
        let aligned = Choice {
            angle,
            cos_sin,
            energy: P::R::select(odd, opposite, at) + twist(angle),
        };
        best = lower_of::<P::R>(some, aligned, best);
        // `θ + π` and `θ − π` have the same bending energy: only the one of less twist can
        // win, and it is taken as the paper's order would (`+π` first, `−π` if lower still).
        let flipped_bending = P::R::select(odd, at, opposite);
        let (up, down) = (angle + P::PI, angle - P::PI);
        let (up_energy, down_energy) = (flipped_bending + twist(up), flipped_bending + twist(down));
        let lower = down_energy.lt(up_energy);
        let flipped = Choice {
            angle: P::R::select(lower, down, up),
            cos_sin: [-cos_sin[0], -cos_sin[1]],
            energy: P::R::select(lower, down_energy, up_energy),
        };
        best = lower_of::<P::R>(some, flipped, best);
    }
    (best.angle, best.cos_sin)
}

/// `candidate` where `some` and its energy is strictly lower than `best`'s, else `best`,
/// lane by lane.
#[inline(always)]
fn lower_of<R: Arithmetic>(some: R::Mask, candidate: Choice<R>, best: Choice<R>) -> Choice<R> {
    let lower = some & candidate.energy.lt(best.energy);
    let blend = |m, a: Choice<R>, b: Choice<R>| Choice {
        angle: R::select(m, a.angle, b.angle),
        cos_sin: [
            R::select(m, a.cos_sin[0], b.cos_sin[0]),
            R::select(m, a.cos_sin[1], b.cos_sin[1]),
        ],
        energy: R::select(m, a.energy, b.energy),
    };
    select_whole::<R, _>(lower, candidate, best, blend)
}

/// A candidate of the sweep: an angle, its cosine and sine, and its local energy.
#[derive(Clone, Copy)]
struct Choice<R> {
    angle: R,
    cos_sin: [R; 2],
    energy: R,
}

/// What the hair-optimised sweep needs of one segment that does not depend on the angles it
/// chooses before it: the current angle's cosine, sine and bending energy, and the binormal
/// direction's angle and bending energies (where there is one, `has_binormal`), and the
/// twist terms' weights.
#[derive(Clone, Copy, Debug)]
struct Candidates<R: Arithmetic> {
    kept_cos_sin: [R; 2],
    /// Bending energy of nodes `j`, `j + 1` at the current angle.
    kept_bending: R,
    /// Where the segment has a binormal direction.
    has_binormal: R::Mask,
    binormal: Binormal<R>,
    twist: TwistWeights<R>,
}

/// The binormal direction of a segment ([`binormal_direction_in_lanes`]) and what the sweep
/// needs of it.
#[derive(Clone, Copy, Debug)]
struct Binormal<R> {
    /// `(cos φ, sin φ)`.
    direction: [R; 2],
    /// `φ = atan2(sin φ, cos φ)`.
    angle: R,
    /// Bending energies at `φ` and at `φ ± π`.
    bending: (R, R),
}

impl<R: Arithmetic> Binormal<R> {
    /// No direction.
    const NONE: Self = Binormal {
        direction: [R::ONE, R::ZERO],
        angle: R::ZERO,
        bending: (R::ZERO, R::ZERO),
    };
}

impl<R: Arithmetic> Candidates<R> {
    /// Segment `j`'s, with `θ = theta` as the sweep reaches it (`n` interior nodes).
    #[inline(always)]
    fn of<P: Trigonometry<R = R>, const N: usize>(
        frames: &RodFrames<P, N>,
        rest: &RodRest<N, R>,
        terms: ElasticTerms,
        (theta, j, n): (&[R], usize, usize),
        kept_cos_sin: Option<[R; 2]>,
    ) -> Self {
        let kept = theta[j];
        let kept_cos_sin = kept_cos_sin.unwrap_or_else(|| {
            let (s, c) = P::sin_cos(kept);
            [c, s]
        });
        let found = binormal_direction_in_lanes(frames, j);
        let has_binormal = found.some;
        let binormal = if R::any(has_binormal) {
            Binormal {
                direction: found.direction,
                angle: found.angle,
                bending: local_bending(frames, rest, terms, j, found.direction),
            }
        } else {
            Binormal::NONE
        };
        Candidates {
            kept_cos_sin,
            kept_bending: local_bending(frames, rest, terms, j, kept_cos_sin).0,
            has_binormal,
            binormal,
            twist: TwistWeights::of(rest, terms, theta, j, n),
        }
    }
}

/// What a Newton twist solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NewtonOutcome {
    /// Newton iterations run.
    pub iterations: u32,
    /// Whether the last update was within the tolerance.
    pub converged: bool,
    /// Iterations that fell back to Gauss–Newton.
    pub gauss_newton: u32,
}

impl NewtonOutcome {
    /// Into the step's report: the most iterations, and the cap hit when not converged.
    pub fn report(self, report: &mut StepReport) {
        report.iterations_max = report.iterations_max.max(self.iterations);
        if !self.converged {
            report.flags.insert(Flags::CAP_HIT);
        }
    }
}

/// [`NewtonOutcome`] per lane: the counts as reals (exact far past any iteration cap).
#[derive(Clone, Copy, Debug)]
pub struct NewtonLanes<R: Arithmetic> {
    /// Newton iterations the lane ran.
    pub iterations: R,
    /// Whether the lane's last update was within the tolerance.
    pub converged: R::Mask,
    /// Iterations that fell back to Gauss–Newton in the lane.
    pub gauss_newton: R,
}

impl<R: Scalar> NewtonLanes<R> {
    /// The one lane's outcome.
    #[must_use]
    pub fn outcome(self) -> NewtonOutcome {
        NewtonOutcome {
            iterations: self.iterations.to_f32() as u32,
            converged: self.converged,
            gauss_newton: self.gauss_newton.to_f32() as u32,
        }
    }
}

impl<const W: usize> NewtonLanes<Wide<W>> {
    /// Lane `lane`'s outcome.
    #[must_use]
    pub fn lane(&self, lane: usize) -> NewtonOutcome {
        NewtonLanes {
            iterations: self.iterations.0[lane],
            converged: self.converged.get(lane),
            gauss_newton: self.gauss_newton.0[lane],
        }
        .outcome()
    }
}

/// Largest Newton update of one angle, rad: far from the minimum a step of the quadratic model
/// can overshoot by turns; a quarter turn keeps the iteration in the basin.
const MAX_NEWTON_STEP: f32 = core::f32::consts::FRAC_PI_2;

/// Backtracking on the energy (at most [`LINE_SEARCH_HALVINGS`] halvings): takes
/// `θ ← θ − a·s` with the first `a = 1, ½, ¼, …` that does not raise `E`, so the iteration
/// never climbs out of the current basin (without it, on a nearly straight strand with µ > 1,
/// where the twist minimum is shallow, Gauss–Newton steps jump θ by radians from step to step).
/// Lanes outside `active` keep their angles. Returns the largest angle change made, per lane.
fn line_search<P: Trigonometry, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    terms: ElasticTerms,
    step: &[P::R],
    theta: &mut [P::R],
    active: <P::R as Arithmetic>::Mask,
) -> P::R {
    let segments = step.len().min(theta.len()).min(N);
    let mut trial = [P::R::ZERO; N];
    let start = elastic_energy(frames, &theta[..segments], rest, terms);
    let longest = largest_magnitude(step);
    let mut scale = P::R::ONE;
    // No decrease at any scale: θ is at the minimum to rounding, and the change is 0.
    let mut largest = P::R::ZERO;
    let mut searching = active;
    for _ in 0..=LINE_SEARCH_HALVINGS {
        for ((t, theta), s) in trial.iter_mut().zip(theta.iter()).zip(step) {
            *t = *theta - *s * scale;
        }
        let lower = searching & elastic_energy(frames, &trial[..segments], rest, terms).le(start);
        if P::R::any(lower) {
            for (theta, t) in theta[..segments].iter_mut().zip(&trial) {
                *theta = P::R::select(lower, *t, *theta);
            }
            largest = P::R::select(lower, longest * scale, largest);
            searching = searching & !lower;
            if !P::R::any(searching) {
                break;
            }
        }
        scale *= P::R::of(0.5);
    }
    largest
}

/// Most halvings of a Newton step in [`line_search`].
const LINE_SEARCH_HALVINGS: u32 = 4;

/// BWR08's Newton twist: minimises `E` over the unclamped `θ^j` in place
/// ([`newton_twist_in_lanes`] on one strand). Never inlined: its system and trial angles
/// stayed in the frame of every rod step (0.7 KB of stack at 16 nodes on the Cortex-M4F),
/// whichever twist the scene runs.
#[inline(never)]
pub fn newton_twist<P: Precision, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    clamped: &ClampedSegments,
    terms: ElasticTerms,
    settings: NewtonSettings<P::R>,
    theta: &mut [P::R],
) -> NewtonOutcome {
    newton_twist_in_lanes(frames, rest, clamped, terms, settings, theta).outcome()
}

/// BWR08's Newton twist: minimises `E` over the unclamped `θ^j` in place, one strand or one
/// per lane, each lane by the very operations it runs alone.
///
/// Bending is separable in `θ` and only twist couples neighbours, so the Hessian is
/// tridiagonal: `H_jj = Σ_i (1/l̂_i)[(Jω)ᵀB(Jω) − ωᵀB(ω − ω̂)] + 2β/l̂_j + 2β/l̂_{j+1}`,
/// `H_{j−1,j} = −2β/l̂_j`. Clamped segments are Dirichlet rows (an interior clamp splits the
/// system). Far from rest `H_jj` can go negative: when the LDLᵀ of the full Hessian meets a
/// non-positive pivot, the iteration uses Gauss–Newton (the `−ωᵀB(ω−ω̂)` term dropped, positive
/// semi-definite plus the twist Laplacian), and every step is safeguarded by a backtracking
/// line search on `E` (BWR08 leaves globalisation open). A lane stops when its largest update
/// is `≤ tolerance` rad, unless `settings.fixed_cost`, which always runs `settings.iterations`
/// (bounded latency); the others go on, and a lane that has stopped keeps its angles.
pub fn newton_twist_in_lanes<P: Trigonometry, C: ClampedLanes<P::R>, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    clamped: &C,
    terms: ElasticTerms,
    settings: NewtonSettings<P::R>,
    theta: &mut [P::R],
) -> NewtonLanes<P::R> {
    let segments = frames.nodes.saturating_sub(1).min(theta.len());
    let (zero, one) = (P::R::ZERO, P::R::ONE);
    let mut outcome = NewtonLanes {
        iterations: zero,
        converged: P::R::mask(false),
        gauss_newton: zero,
    };
    let mut system = NewtonSystem::<P::R, N>::default();
    let mut step = [zero; N];
    let mut pivots = [one; N];
    let mut active = P::R::mask(true);
    let limit = P::R::of(MAX_NEWTON_STEP);
    for _ in 0..settings.iterations {
        let theta_now = &theta[..segments];
        twist_newton_system(frames, rest, clamped, terms, theta_now, &mut system);
        outcome.iterations += P::R::select(active, one, zero);
        let full = system.solve(segments, &mut pivots, &mut step);
        outcome.gauss_newton += P::R::select(active & !full, one, zero);
        for s in step[..segments].iter_mut() {
            let below = P::R::select(s.lt(-limit), -limit, *s);
            *s = P::R::select(limit.lt(*s), limit, below);
        }
        let largest = line_search(frames, rest, terms, &step[..segments], theta, active);
        let converged = largest.le(settings.tolerance) | largest.le(resolution(&theta[..segments]));
        outcome.converged = (active & converged) | (!active & outcome.converged);
        if !settings.fixed_cost {
            active = active & !converged;
            if !P::R::any(active) {
                break;
            }
        }
    }
    outcome
}

/// The smallest update the angles `theta` can resolve, rad: `2 ε max |θ^j|`. The angles wind
/// up along a bent strand (21 rad at the tip of Table 2's strands, where an `f32` step is
/// 1.9e-6 rad), and below this an update is a rounding: a tolerance under it would be met by
/// luck or not at all, and the iteration would chase it for its whole cap.
fn resolution<R: Arithmetic>(theta: &[R]) -> R {
    R::of(2.0) * R::EPSILON * largest_magnitude(theta)
}

/// `max_j |x_j|` (0 for none).
fn largest_magnitude<R: Arithmetic>(x: &[R]) -> R {
    x.iter().fold(R::ZERO, |m, &v| {
        let size = v.magnitude();
        R::select(m.lt(size), size, m)
    })
}

/// The Newton twist's iteration cap and tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonSettings<R> {
    /// Most iterations.
    pub iterations: u16,
    /// Stop when the largest angle update is at most this, rad, or within what the angles'
    /// precision resolves (`2 ε max |θ^j|`), unless `fixed_cost`.
    pub tolerance: R,
    /// Always run `iterations` (bounded latency).
    pub fixed_cost: bool,
}

impl<R: Arithmetic> NewtonSettings<R> {
    /// The step's: the scene's cap and tolerance, every iteration in fixed-cost mode.
    #[must_use]
    pub fn of(ctx: &StepContext) -> Self {
        NewtonSettings {
            iterations: ctx.params.rod.newton_iterations,
            tolerance: R::of(ctx.params.rod.newton_tolerance),
            fixed_cost: ctx.params.mode == Mode::FixedCost,
        }
    }
}

/// The Newton system of the twist at some `θ` ([`twist_newton_system`]): the gradient
/// `∂E/∂θ^j`, the Hessian diagonal in full and Gauss–Newton, and the coupling `H_{j−1,j}`
/// (stored at `j`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonSystem<R, const N: usize> {
    /// `∂E/∂θ^j`.
    pub gradient: [R; N],
    /// `H_jj`.
    pub full: [R; N],
    /// `H_jj` without the `−ωᵀB(ω − ω̂)` term.
    pub gauss_newton: [R; N],
    /// `H_{j−1,j}`, at `j`.
    pub coupling: [R; N],
}

impl<R: Arithmetic, const N: usize> Default for NewtonSystem<R, N> {
    fn default() -> Self {
        NewtonSystem {
            gradient: [R::ZERO; N],
            full: [R::ZERO; N],
            gauss_newton: [R::ZERO; N],
            coupling: [R::ZERO; N],
        }
    }
}

impl<R: Arithmetic, const N: usize> NewtonSystem<R, N> {
    /// The Newton step `s` of `H s = g` over the first `segments` rows (`pivots` as scratch).
    /// Where the full Hessian is not positive definite, the Gauss–Newton one instead: positive
    /// definite whenever `β > 0`, once its non-positive entries are floored. Returns where
    /// (which lanes) the full Hessian served.
    fn solve(&mut self, segments: usize, pivots: &mut [R; N], step: &mut [R; N]) -> R::Mask {
        let rows = ..segments;
        let full = solve_tridiagonal(
            &self.full[rows],
            &self.coupling[rows],
            &self.gradient[rows],
            &mut pivots[rows],
            &mut step[rows],
        );
        if R::all(full) {
            return full;
        }
        for g in self.gauss_newton[rows].iter_mut() {
            *g = R::select(g.le(R::ZERO) | !g.finite(), R::of(1.0e-30), *g);
        }
        let mut gauss_newton = [R::ZERO; N];
        solve_tridiagonal(
            &self.gauss_newton[rows],
            &self.coupling[rows],
            &self.gradient[rows],
            &mut pivots[rows],
            &mut gauss_newton[rows],
        );
        for (s, g) in step[rows].iter_mut().zip(&gauss_newton) {
            *s = R::select(full, *s, *g);
        }
        full
    }
}

/// The Newton system of the twist at `theta`: gradient `∂E/∂θ^j`, Hessian diagonal (full and
/// Gauss–Newton) and the coupling `H_{j−1,j}` (stored at `j`). Clamped rows are identity rows
/// with zero gradient and no coupling.
pub fn twist_newton_system<P: Trigonometry, C: ClampedLanes<P::R>, const N: usize>(
    frames: &RodFrames<P, N>,
    rest: &RodRest<N, P::R>,
    clamped: &C,
    terms: ElasticTerms,
    theta: &[P::R],
    system: &mut NewtonSystem<P::R, N>,
) {
    let NewtonSystem {
        gradient,
        full,
        gauss_newton,
        coupling,
    } = system;
    let (zero, one) = (P::R::ZERO, P::R::ONE);
    let n = frames.interior().min(theta.len().saturating_sub(1));
    let two_beta = P::R::of(2.0) * twist_stiffness(rest, terms);
    let cos_sin = material_angles::<P, N>(theta);
    for j in 0..theta.len().min(N) {
        coupling[j] = zero;
        let held = clamped.clamped(j);
        if P::R::all(held) {
            gradient[j] = zero;
            full[j] = one;
            gauss_newton[j] = one;
            continue;
        }
        let g = bending_twist_derivative(frames, rest, terms, j, cos_sin[j])
            + twist_twist_derivative(rest, terms, theta, j, n);
        // Per node i touching segment j: (Jω)ᵀB(Jω)/l̂_i, ωᵀB(ω−ω̂)/l̂_i and 2β/l̂_i.
        let b = bending_matrix(rest, terms, j);
        let node = |(i, k): (usize, usize)| {
            let omega = material_curvature(frames.bishop_curvature[i][k], cos_sin[j]);
            let rest_omega = rest.rest_curvature[i][k];
            let inv_l = rest.inverse_voronoi_length[i];
            let gn = (b[0] * omega[1] * omega[1] + b[1] * omega[0] * omega[0]) * inv_l;
            let curvature = (b[0] * omega[0] * (omega[0] - rest_omega[0])
                + b[1] * omega[1] * (omega[1] - rest_omega[1]))
                * inv_l;
            (gn + two_beta * inv_l, curvature)
        };
        let mut gn = zero;
        let mut curvature = zero;
        if j >= 1 && j <= n {
            let (g, c) = node((j, 1));
            gn += g;
            curvature += c;
            let free = !clamped.clamped(j - 1);
            let coupled = -two_beta * rest.inverse_voronoi_length[j];
            coupling[j] = P::R::select(held | !free, zero, coupled);
        }
        if j < n {
            let (g, c) = node((j + 1, 0));
            gn += g;
            curvature += c;
        }
        gradient[j] = P::R::select(held, zero, g);
        gauss_newton[j] = P::R::select(held, one, gn);
        full[j] = P::R::select(held, one, gn - curvature);
    }
}

/// Solves the symmetric tridiagonal system `H s = g` (diagonal `diagonal`, `H_{j−1,j} =
/// coupling[j]`) by LDLᵀ (Thomas), O(n), with `pivots` as scratch, in each lane. Returns where
/// every pivot was positive (positive definite); elsewhere `solution` is zeroed.
pub fn solve_tridiagonal<R: Arithmetic>(
    diagonal: &[R],
    coupling: &[R],
    rhs: &[R],
    pivots: &mut [R],
    solution: &mut [R],
) -> R::Mask {
    let len = diagonal
        .len()
        .min(coupling.len())
        .min(rhs.len())
        .min(pivots.len())
        .min(solution.len());
    let mut definite = R::mask(true);
    // Forward: pivots d_j = H_jj − H_{j−1,j}²/d_{j−1}, y_j = g_j − (H_{j−1,j}/d_{j−1}) y_{j−1}.
    for j in 0..len {
        let (pivot, y) = if j == 0 {
            (diagonal[0], rhs[0])
        } else {
            let l = coupling[j] / pivots[j - 1];
            (diagonal[j] - l * coupling[j], rhs[j] - l * solution[j - 1])
        };
        definite = definite & R::ZERO.lt(pivot) & pivot.finite();
        // No lane left to solve: stop at its first bad pivot.
        if !R::any(definite) {
            for s in solution.iter_mut().take(len) {
                *s = R::ZERO;
            }
            return definite;
        }
        pivots[j] = pivot;
        solution[j] = y;
    }
    // Backward: s_j = (y_j − H_{j,j+1} s_{j+1}) / d_j.
    for j in (0..len).rev() {
        let mut y = solution[j];
        if j + 1 < len {
            y -= coupling[j + 1] * solution[j + 1];
        }
        solution[j] = y / pivots[j];
    }
    if !R::all(definite) {
        for s in solution.iter_mut().take(len) {
            *s = R::select(definite, *s, R::ZERO);
        }
    }
    definite
}

/// The material vectors `m1^c` of the clamped segments other than the root, saved before a
/// step so that afterwards each moves by the time-parallel transport from its old tangent to
/// its new one (`θ^c ← θ^c − ΔΨ^c`, `docs/architecture.md`): a held segment's frame does not spin about
/// its own axis when the strand bends around it.
#[derive(Clone, Copy, Debug)]
pub struct ClampedFrames<P: Precision> {
    tangent: [P::V; MAX_CLAMPED],
    material: [P::V; MAX_CLAMPED],
}

impl<P: Precision> ClampedFrames<P> {
    /// The clamped segments' tangents and `m1` now.
    #[must_use]
    pub fn save<const N: usize>(
        frames: &RodFrames<P, N>,
        theta: &[P::R],
        clamped: &ClampedSegments,
    ) -> Self {
        let zero = <P::V as Vector<P::R>>::ZERO;
        let mut saved = ClampedFrames {
            tangent: [zero; MAX_CLAMPED],
            material: [zero; MAX_CLAMPED],
        };
        for (slot, c) in clamped.others().enumerate().take(MAX_CLAMPED) {
            if let (Some(&t), Some(&angle)) = (frames.tangent.get(c), theta.get(c)) {
                let (s, co) = P::sin_cos(angle);
                saved.tangent[slot] = t;
                saved.material[slot] =
                    material_frame::<P>(frames.bishop_u[c], frames.bishop_v[c], [co, s]).0;
            }
        }
        saved
    }

    /// Sets `θ^c` of each clamped segment to its transported `m1` measured in the new Bishop
    /// frame, continuous with the old angle.
    pub fn transport<const N: usize>(
        &self,
        frames: &RodFrames<P, N>,
        clamped: &ClampedSegments,
        theta: &mut [P::R],
    ) {
        let segments = frames.nodes.saturating_sub(1);
        for (slot, c) in clamped.others().enumerate().take(MAX_CLAMPED) {
            if c >= segments {
                continue;
            }
            if let Some(angle) = theta.get_mut(c) {
                let m1 = parallel_transport::<P>(
                    self.tangent[slot],
                    frames.tangent[c],
                    self.material[slot],
                );
                let measured = angle_in_frame::<P>(frames.bishop_u[c], frames.bishop_v[c], m1);
                *angle = unwrap_near(measured, *angle);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::transport_in_time;
    use crate::precision::F64;
    use crate::rod::energy::elastic_energy;
    use crate::rod::energy::tests::{rest_points, Rng, Shape, NODES};
    use crate::rod::frames::{binormal_direction, BINORMAL_FADE, BINORMAL_MIN_WEIGHT};
    use glam::DVec3;

    type Rest = RodRest<NODES, f64>;

    /// A rest shape, its rest data, and a deformed copy: the rest shape bent by `amplitude`
    /// per coordinate, with both twist results from the rest angles.
    fn both_twists(shape: Shape, mu: f64, amplitude: f64, rng: &mut Rng) -> (f64, f64, f64) {
        let points = rest_points(shape);
        let rest = Rest::compute::<F64>(&points, 1.0, mu, 0.7, 1.0);
        let mut x = points;
        for p in x.iter_mut().skip(2) {
            *p += DVec3::new(rng.next(), rng.next(), rng.next()) * amplitude;
        }
        let t0 = (points[1] - points[0]).normalize();
        let u0 = crate::frames::perpendicular_unit_by_reciprocal::<F64>(t0);
        let u0 = transport_in_time::<F64>(t0, (x[1] - x[0]).normalize(), u0);
        let frames = RodFrames::<F64, NODES>::compute(&x, u0, &rest.rest_length);
        let clamped = ClampedSegments::ROOT_ONLY;
        let mut hair = rest.rest_theta;
        hair_optimised_twist(
            &frames,
            &rest,
            &clamped,
            ElasticTerms::ALL,
            &mut hair[..NODES - 1],
        );
        let mut newton = rest.rest_theta;
        let outcome = newton_twist(
            &frames,
            &rest,
            &clamped,
            ElasticTerms::ALL,
            NewtonSettings {
                iterations: 100,
                tolerance: 1e-13,
                fixed_cost: false,
            },
            &mut newton[..NODES - 1],
        );
        assert!(outcome.converged, "{outcome:?}");
        let gap = hair
            .iter()
            .zip(&newton)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let e_hair = elastic_energy(&frames, &hair, &rest, ElasticTerms::ALL);
        let e_newton = elastic_energy(&frames, &newton, &rest, ElasticTerms::ALL);
        (gap, e_hair, e_newton)
    }

    /// The binormal direction against its definition: `φ = ½ arg Σ_k z_k/r_k` by `atan2`, as
    /// a line (mod π), on random binormals from rounding size to sharp folds, one or two nodes.
    #[test]
    fn binormal_direction_is_half_the_argument_of_the_weighted_squares() {
        let mut rng = Rng(5);
        let mut frames = RodFrames::<F64, NODES>::empty();
        frames.nodes = 4;
        let (mut checked, mut none) = (0, 0);
        for trial in 0..20_000 {
            let magnitude = 10f64.powf(-9.0 + 10.0 * (rng.next() + 0.5));
            let other = 10f64.powf(-9.0 + 10.0 * (rng.next() + 0.5));
            frames.bishop_curvature[1][1] = [rng.next() * magnitude, rng.next() * magnitude];
            frames.bishop_curvature[2][0] = [rng.next() * other, rng.next() * other];
            frames.bishop_curvature[2][1] = [rng.next() * other, rng.next() * other];
            // Segment 1 sees nodes 1 and 2 (in its frame); segment 2, the last with n = 2
            // interior nodes, only node 2.
            let j = 1 + trial % 2;
            let mut z = [0.0; 2];
            let nodes: &[[f64; 2]] = if j == 1 {
                &[frames.bishop_curvature[1][1], frames.bishop_curvature[2][0]]
            } else {
                &[frames.bishop_curvature[2][1]]
            };
            for p in nodes {
                let (a, b) = (-p[1], p[0]);
                let r = a * a + b * b + f64::from(BINORMAL_FADE);
                z[0] += (a * a - b * b) / r;
                z[1] += 2.0 * a * b / r;
            }
            let weight = (z[0] * z[0] + z[1] * z[1]).sqrt();
            let got = binormal_direction(&frames, j);
            let min = f64::from(BINORMAL_MIN_WEIGHT);
            if (weight - min).abs() < 1e-9 {
                continue;
            }
            match got {
                None => {
                    assert!(weight < min, "{trial}: weight {weight} but no direction");
                    none += 1;
                }
                Some(([c, s], angle)) => {
                    assert!(weight > min, "{trial}: weight {weight} but a direction");
                    let phi = 0.5 * z[1].atan2(z[0]);
                    assert!(((c * c + s * s) - 1.0).abs() < 1e-12, "{trial}: not unit");
                    // The same line: the cross product of the two unit vectors vanishes.
                    let across = c * phi.sin() - s * phi.cos();
                    assert!(across.abs() < 1e-9, "{trial}: {c} {s} against φ = {phi}");
                    // The angle is the direction's, not merely its line's.
                    let (sin, cos) = angle.sin_cos();
                    assert!(
                        (cos - c).abs() < 1e-9 && (sin - s).abs() < 1e-9,
                        "{trial}: angle {angle} against ({c}, {s})"
                    );
                    checked += 1;
                }
            }
        }
        assert!(
            checked > 10_000 && none > 100,
            "{checked} directions, {none} none"
        );
    }

    #[test]
    fn hair_optimised_agrees_with_newton_for_curved_strands_with_mu_one() {
        // Curved rest shapes bent by 1 %, 3 % and 10 % of a segment per coordinate (random),
        // 8 strands each: the largest angle gap, over the strand, between the two twists.
        let mut rng = Rng(7);
        for shape in [Shape::Wavy, Shape::Helix] {
            // Measured: ≤ 0.024, 0.096, 0.22 rad.
            for (amplitude, bound) in [(0.01, 0.03), (0.03, 0.12), (0.1, 0.3)] {
                let worst = (0..8)
                    .map(|_| both_twists(shape, 1.0, amplitude, &mut rng).0)
                    .fold(0.0, f64::max);
                std::println!(
                    "{shape:?} µ = 1, bent {amplitude}: max |θ_ho − θ_N| = {worst:.3e} rad"
                );
                assert!(worst < bound, "{shape:?} {amplitude}: {worst} rad");
            }
        }
    }

    #[test]
    fn hair_optimised_energy_stays_near_the_newton_minimum_with_mu_above_one() {
        // Measured: the hair-optimised energy exceeds Newton's minimum by 7–36 % (relative to
        // the small elastic energy of these bent strands); bound 45 %.
        let mut rng = Rng(11);
        for shape in [Shape::Wavy, Shape::Helix] {
            for mu in [1.5, 3.0] {
                for amplitude in [0.01, 0.03, 0.1] {
                    let worst = (0..8)
                        .map(|_| {
                            let (_, e_hair, e_newton) = both_twists(shape, mu, amplitude, &mut rng);
                            assert!(e_hair >= e_newton * (1.0 - 1e-12), "Newton is the minimum");
                            e_hair / e_newton - 1.0
                        })
                        .fold(0.0, f64::max);
                    std::println!(
                        "{shape:?} µ = {mu}, bent {amplitude}: E_ho / E_N − 1 ≤ {worst:.3e}"
                    );
                    assert!(worst < 0.45, "{shape:?} µ {mu} {amplitude}: {worst}");
                }
            }
        }
    }
}
