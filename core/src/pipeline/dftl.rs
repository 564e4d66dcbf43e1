//! DFTL's pipeline: Sánchez-Banderas, Barreiro, García-Fernández, Pérez 2015, Algorithm 1,
//! local dynamics (lines 12–27), on one strand ([`step_strand`]) or on a structure-of-arrays
//! block of `W` strands ([`step_block`]), which gives the per-strand path's bits.
//!
//! | line | Algorithm 1 | stage |
//! |---|---|---|
//! | 1–11 | global dynamics (SPH) | the std harness, an input of the step |
//! | (14) | shape damping below 60 Hz (a departure) | `dftl::damping` |
//! | 12–15 | each particle after the root: external forces, predict `x*` | `dftl::predict` |
//! | (12) | the root follows the head | `root_coupling` |
//! | 18 | shape constraints | `dftl::shape` |
//! | 19 | inextensibility constraint | `dftl::follow_leader` |
//! | 20 | handle collisions | `dftl::collisions` |
//! | 21 | update coordinate frames | `dftl::frame` |
//! | 24–26 | velocity with the correction term; `x ← x*` | `dftl::velocity` |
//!
//! Lines 12–27 run fused, node by node, in one pass from the root ([`advance`] is lines
//! 13–21 for one node); lines 24–26 run two nodes behind, as soon as the corrections of the
//! next two nodes are known, so a step is a single pass whose cost is fixed by the scene. The
//! stages are counted in the algorithm's order: a node's prediction does not depend on the
//! root coupling of nodes 0 and 1, so predicting first is the same computation. Before and
//! after the pass, the quarantine every path shares: `snapshot` and `guard`.

use crate::capacities::MAX_COLLIDERS;
use crate::collide::Shape;
use crate::context::StepContext;
use crate::dftl::block::{read_lanes, BlockState, DftlBlock};
use crate::dftl::measures::{ColliderPush, Measures, Momenta, Tally};
use crate::dftl::node::{Advanced, Chain, NodeInput, Setup};
use crate::dftl::velocity::Pending;
use crate::dftl::{collisions, damping, follow_leader, frame, predict, shape};
use crate::grab::{forces_after_roll_back, grabbed_nodes, Grab, MAX_GRABS};
use crate::guard::guard;
use crate::lane::{component_sum, not_finite_sum, Lane, Wide, WideMask, V3};
use crate::math::{Math, Real, Vec3};
use crate::params::{DftlCoefficients, Mode};
use crate::projection::{project_in_mode, project_in_scratch, ProjectionScratch};
use crate::report::{Stage, StepReport};
use crate::root_coupling::root_coupling;
use crate::snapshot::{snapshot, snapshot_as_passed, PassedPositions};
use crate::strand::{RestStrand, Strand, StrandState};

/// Calls `pass::<…, SHAPE, INEXTENSIBLE, DRAG>(…)` with the scene's three effect switches
/// (`setup.shape`, `.inextensibility`, `.drag`) as constants: each copy of a pass then
/// computes no stage that is off and tests no switch per node. Both paths go through it.
macro_rules! with_effect_switches {
    ($setup:expr, $pass:ident::<$($generic:tt),*>($($argument:expr),* $(,)?)) => {
        match ($setup.shape, $setup.inextensibility, $setup.drag) {
            (false, false, false) => $pass::<$($generic),*, false, false, false>($($argument),*),
            (false, false, true) => $pass::<$($generic),*, false, false, true>($($argument),*),
            (false, true, false) => $pass::<$($generic),*, false, true, false>($($argument),*),
            (false, true, true) => $pass::<$($generic),*, false, true, true>($($argument),*),
            (true, false, false) => $pass::<$($generic),*, true, false, false>($($argument),*),
            (true, false, true) => $pass::<$($generic),*, true, false, true>($($argument),*),
            (true, true, false) => $pass::<$($generic),*, true, true, false>($($argument),*),
            (true, true, true) => $pass::<$($generic),*, true, true, true>($($argument),*),
        }
    };
}

/// DFTL's scratch space for [`step_strand`], kept by its caller from step to step
/// (`pipeline::StepScratch`): nothing in it carries from one strand or step to the next.
pub struct DftlScratch<const N: usize> {
    /// A strand's pushes on the scene's colliders (`Σ m Δx^push`): only the entries of the
    /// colliders in use are written, so only those are zeroed for each strand
    /// ([`DftlScratch::begin`] zeroes them all) — made for each strand, its zeros and copies
    /// were 1.4 % of a DFTL step of 8 × 16 nodes on the Cortex-M4F.
    collider_push: ColliderPush<Real>,
    /// A strand's positions at the start of its step, kept as its pass goes
    /// ([`PassedPositions`]).
    last_good: [Vec3; N],
    /// The projection workspace of a strand a grab holds.
    projection: ProjectionScratch<N>,
}

impl<const N: usize> DftlScratch<N> {
    /// Before its first use.
    #[must_use]
    pub const fn new() -> Self {
        const ZERO: V3<Real> = V3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        };
        DftlScratch {
            collider_push: [ZERO; MAX_COLLIDERS],
            last_good: [Vec3::ZERO; N],
            projection: ProjectionScratch::new(),
        }
    }

    /// Before a call's strands: every push zeroed (the scene's colliders may have changed
    /// since the last call).
    pub fn begin(&mut self) {
        self.collider_push = [V3::zero(); MAX_COLLIDERS];
    }
}

impl<const N: usize> Default for DftlScratch<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// Steps one strand by `ctx.dt` (SB15 Algorithm 1, local dynamics), `setup` being
/// [`Setup::new`] of `ctx` (built once for all strands). `index` is the strand's index in the
/// whole scene (as in `Grab::strand`); `accelerations` (if any) are the caller's per-node
/// accelerations for this strand, indexed by node. `scratch` is the caller's, begun for this
/// call ([`DftlScratch::begin`]), if it keeps one (a `World` does); else the strand's step
/// makes what it needs on the stack: the same bits. A strand that a grab holds this step
/// takes [`step_held_strand`]. Never panics: a strand that writes a non-finite value is
/// rolled back.
pub fn step_strand<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    setup: &Setup,
    ctx: &StepContext,
    at: (&[Grab], u32),
    accelerations: Option<&[Vec3]>,
    scratch: Option<&mut DftlScratch<N>>,
    report: &mut StepReport,
) {
    let (grabs, index) = at;
    // Most strands no grab names: a look at each grab's strand first.
    let named = grabs
        .iter()
        .take(MAX_GRABS)
        .any(|grab| grab.strand == index);
    let held = named && !grabbed_nodes(ctx, grabs, index, strand.rest.nodes.min(N)).is_empty();
    let mut own = None;
    let (push, last_good, projection) = match scratch {
        Some(kept) => (
            &mut kept.collider_push,
            &mut kept.last_good,
            Some(&mut kept.projection),
        ),
        None => {
            let own = own.insert(([V3::zero(); MAX_COLLIDERS], [Vec3::ZERO; N]));
            (&mut own.0, &mut own.1, None)
        }
    };
    // The pushes of the scene's colliders in use, from zero.
    let push = &mut push[..ctx.colliders().len().min(MAX_COLLIDERS)];
    push.fill(V3::zero());
    let step = (accelerations, push, last_good);
    if held {
        return step_held_strand::<M, N>(strand, setup, ctx, at, step, projection, report);
    }
    step_free_strand::<M, N>(strand, setup, ctx, at, step, report);
}

/// What a strand's pass takes besides the strand: the caller's accelerations, the pushes on
/// the scene's colliders in use (zero) and where the positions are kept as the pass goes.
type Passing<'a, const N: usize> = (Option<&'a [Vec3]>, &'a mut [V3<Real>], &'a mut [Vec3; N]);

/// [`step_strand`] of a strand no grab holds this step, `push` the pushes of the scene's
/// colliders in use, zero, `last_good` where its positions are kept as the step goes.
#[inline(always)]
fn step_free_strand<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    setup: &Setup,
    ctx: &StepContext,
    (_, index): (&[Grab], u32),
    (accelerations, push, last_good): Passing<'_, N>,
    report: &mut StepReport,
) {
    // Quarantine: the last good positions, kept as the step goes.
    snapshot_as_passed(strand, last_good, report);
    // Lines 12–15, fused into the pass below: external forces and the prediction.
    count_prediction(ctx, accelerations.is_some(), 1, report);
    // The root follows the head: nodes 0 and 1.
    let roots = root_coupling(strand, ctx, report);
    // Lines 16–27 in one pass from the root: shape, follow-the-leader, collisions, frames, and
    // the velocities one node behind.
    count_constraints(setup, 1, report);
    let mut pass = 0.0;
    let passing = (accelerations, &mut *push, &mut *last_good);
    let tally = strand_pass::<M, N>(setup, ctx, strand, passing, &mut pass);
    tally.report(report);
    // Quarantine: every value written finite, or the last good positions back.
    let good = not_finite_sum(roots + pass) == 0.0;
    let last_good = PassedPositions(last_good);
    let rolled_back = guard(strand, &last_good, |_, _| good, index, report);
    transmit_to_colliders(push, setup.inv_dt, rolled_back, report);
    transmit_to_head(tally.head_force, rolled_back, report);
}

/// Steps one strand that a grab holds this step: two held ends (the root, the grabbed node),
/// which follow-the-leader from the root alone cannot join. The pass runs without
/// follow-the-leader and without eq. 14's feedback of its corrections (prediction, shape,
/// collisions, frames; velocities `(x* − x)/Δt`), then the fast manifold projection (Kmoch
/// Sec. 8.2, the rod's) makes every segment inextensible with the root and the grabbed nodes
/// held — prescribed, or pulled by their couplings — updates the velocities by its moves, and
/// gives the grabs' forces as the rod defines them. It always runs `rod.projection_iterations`
/// (fixed cost, in either mode): a DFTL step's cost does not depend on the state, and a
/// projection stopped at its tolerance kept a held, shaped strand trembling by 0.1 mm
/// (`docs/design-departures.md`, "Grabs in DFTL"). Out of line: the strands no grab holds
/// keep `step_strand` as lean as before.
#[inline(never)]
fn step_held_strand<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    setup: &Setup,
    ctx: &StepContext,
    (grabs, index): (&[Grab], u32),
    (accelerations, push, last_good): Passing<'_, N>,
    scratch: Option<&mut ProjectionScratch<N>>,
    report: &mut StepReport,
) {
    snapshot_as_passed(strand, last_good, report);
    count_prediction(ctx, accelerations.is_some(), 1, report);
    let roots = root_coupling(strand, ctx, report);
    // Lines 16–27 but line 19, which the projection takes, eq. 14's feedback of its
    // corrections, which the projection's own velocity update replaces, and the global shape
    // constraint: the hand holds the strand out of its style, and pulled back toward a style
    // it cannot reach the strand is drawn taut between the two (at 1 kHz, 0.7 mm a node a
    // step on a strand held 14 cm short of its rest: the projection then trembles).
    let unprojected = Setup {
        inextensibility: false,
        global_shape: false,
        damping_over_dt: 0.0,
        coefficients: DftlCoefficients {
            global_shape: 0.0,
            ..setup.coefficients
        },
        ..*setup
    };
    if unprojected.shape {
        report.ran(Stage::Shape);
    }
    let mut pass = 0.0;
    let passing = (accelerations, &mut *push, &mut *last_good);
    let tally = strand_pass::<M, N>(&unprojected, ctx, strand, passing, &mut pass);
    // The pass's push-outs act on the hair (reported after the guard); its strain is the
    // unprojected one: the projection measures the segments and the contacts after it.
    let unprojected_momentum = strand_momentum(strand);
    // Lines 5–8 of Kmoch's Algorithm 1: inextensibility, collisions and the grabs.
    let at = (grabs, index);
    let outcome = match scratch {
        Some(work) => project_in_scratch::<M, N>(strand, ctx, at, Mode::FixedCost, work, report),
        None => project_in_mode::<M, N>(strand, ctx, at, Mode::FixedCost, report),
    };
    let good = not_finite_sum(roots + pass) == 0.0 && strand.is_finite();
    let last_good = PassedPositions(last_good);
    let rolled_back = guard(strand, &last_good, |_, _| good, index, report);
    if rolled_back {
        forces_after_roll_back(ctx, grabs, (strand, index), report);
    }
    transmit_to_colliders(push, setup.inv_dt, rolled_back, report);
    // What the head feels: the momentum the step gave besides the external forces, the
    // colliders' and the grabs' (the projection reports what those feel, so less that).
    let lost = tally.lost + unprojected_momentum - strand_momentum(strand);
    let head =
        Tally::head_force(lost, push, setup.inv_dt) - outcome.collider_felt - outcome.grab_felt;
    transmit_to_head(head, rolled_back, report);
}

/// What one strand's pass pushed on the scene's colliders in use, `push`, into the report's
/// `collider_forces` ([`Tally::report_pushes`]): nothing from a strand rolled back.
#[inline(always)]
fn transmit_to_colliders(
    push: &[V3<Real>],
    inv_dt: Real,
    rolled_back: bool,
    report: &mut StepReport,
) {
    if !rolled_back {
        Tally::report_pushes(report, push, inv_dt);
    }
}

/// What one strand transmits to the head this step, `force`, into the report's `head_force`:
/// nothing from a strand rolled back (its step did not happen) or a force that is not finite.
#[inline(always)]
fn transmit_to_head(force: Vec3, rolled_back: bool, report: &mut StepReport) {
    if !rolled_back && crate::math::is_finite(force) {
        report.head_force += force;
    }
}

/// `Σ m_i v_i` over the free nodes (2 on) of `strand`, in node order.
fn strand_momentum<const N: usize>(strand: &Strand<N>) -> Vec3 {
    let n = strand.rest.nodes.min(N);
    // Slices of the free nodes, not `take(n).skip(2)`: through the adapters each node
    // cost 44 instructions on the Cortex-M4F, a call to `Take::nth` among them.
    let free = 2.min(n)..n;
    let velocity = strand.state.velocity.get(free.clone()).unwrap_or(&[]);
    let mass = strand.rest.mass.get(free).unwrap_or(&[]);
    let mut momentum = V3::<Real>::zero();
    for (v, &m) in velocity.iter().zip(mass) {
        momentum += V3::from(*v).scale(m);
    }
    momentum.into()
}

/// Counts lines 12–15, fused into the pass: the external forces where any act, and the
/// prediction.
fn count_prediction(ctx: &StepContext, accelerations: bool, strands: u32, report: &mut StepReport) {
    if ctx.gates.external || accelerations {
        report.ran_on(Stage::ExternalForces, strands);
    }
    report.ran_on(Stage::Integrate, strands);
}

/// Counts lines 16–27, the stages of the pass that run: shape, follow-the-leader, collisions,
/// velocities.
fn count_constraints(setup: &Setup, strands: u32, report: &mut StepReport) {
    if setup.shape {
        report.ran_on(Stage::Shape, strands);
    }
    if setup.inextensibility {
        report.ran_on(Stage::Projection, strands);
    }
    if setup.collisions {
        report.ran_on(Stage::Collisions, strands);
    }
    report.ran_on(Stage::Velocity, strands);
}

/// The pass over one strand's free nodes with the effect switches fixed, its pushes on the
/// scene's colliders in use added to `push` (zero before), the position each node had before
/// the pass kept in `last_good` ([`PassedPositions`]). Returns its tally for the report, and
/// the [`component_sum`]s of the velocities it wrote, added, in `velocity_total`. (The tally
/// alone is returned: returned in a pair, it was copied once more on the Cortex-M4F, 150
/// instructions a strand.)
fn strand_pass<M: Math, const N: usize>(
    setup: &Setup,
    ctx: &StepContext,
    strand: &mut Strand<N>,
    (accelerations, push, last_good): Passing<'_, N>,
    velocity_total: &mut Real,
) -> Tally {
    if strand.rest.nodes.min(N) < 3 {
        *velocity_total = 0.0;
        return Tally::default();
    }
    let colliders = ctx.colliders();
    let (measures, total, momenta) = with_effect_switches!(
        setup,
        nodes_of_strand::<M, N>(setup, strand, colliders, accelerations, (push, last_good))
    );
    *velocity_total = total;
    Tally::from_measures::<M>(&measures, push, momenta, setup.inv_dt)
}

/// Nodes `2 …` of one strand with the effect switches fixed: lines 13–21 for node `i`, then
/// lines 24–26 for node `i − 1`. Returns what it measured, the [`component_sum`]s of the
/// velocities it wrote, added, and the free nodes' momenta.
#[inline(never)]
fn nodes_of_strand<
    M: Math,
    const N: usize,
    const SHAPE: bool,
    const INEXTENSIBLE: bool,
    const DRAG: bool,
>(
    setup: &Setup,
    strand: &mut Strand<N>,
    colliders: &[Shape],
    accelerations: Option<&[Vec3]>,
    kept: (&mut [V3<Real>], &mut [Vec3; N]),
) -> (Measures<Real>, Real, Momenta<Real>) {
    // Two copies of the node loop, without the caller's accelerations (the firmware's case)
    // and with them: in one loop for both, the compiler kept the test and a select in it, 28
    // more instructions a node on x86-64 (a fifth of a node's cost without shape).
    let fixed = setup.with_switches(SHAPE, INEXTENSIBLE, DRAG);
    match accelerations {
        Some(a) => node_loop::<M, N>(fixed, strand, colliders, |i| a.get(i).copied(), kept),
        None => node_loop::<M, N>(fixed, strand, colliders, |_| None, kept),
    }
}

/// The node loop of [`nodes_of_strand`], `extra(i)` being the caller's acceleration of node
/// `i`, if any; each node's pushes on the colliders added to `collider_push`, its position
/// before the pass kept in `last_good`.
// The loop reads and writes the state at nodes `i − 2`, `i − 1` and `i`: an index it is.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn node_loop<M: Math, const N: usize>(
    setup: Setup,
    strand: &mut Strand<N>,
    colliders: &[Shape],
    extra: impl Fn(usize) -> Option<Vec3>,
    (collider_push, last_good): (&mut [V3<Real>], &mut [Vec3; N]),
) -> (Measures<Real>, Real, Momenta<Real>) {
    let n = strand.rest.nodes.min(N);
    let rest = &strand.rest;
    let state = &mut strand.state;
    let (root_tangent, root_normal) = (rest.dftl.root_tangent, rest.dftl.root_normal);
    let x1 = state.position[1];
    let mut chain = Chain::start(&setup, root_tangent.into(), root_normal.into(), x1.into());
    let mut measures = Measures::default();
    let mut velocity_total: Real = 0.0;
    let mut previous_contact = false;
    let mut pending = Pending::start();
    let mut momenta = Momenta::zero();
    for i in 2..n {
        let node = NodeInput::of_strand(rest, state, i, extra(i));
        last_good[i] = node.position.into();
        // Lines 13–21: predict, shape, follow the leader, collisions, frame.
        let (m, c) = (&mut measures, &mut *collider_push);
        let next = advance::<M, Real>(&setup, colliders, &node, &chain, previous_contact, m, c);
        momenta.lost += kicked(&setup, &node, next.acceleration);
        // Lines 24–26: node i − 1 is final, node i − 2 has its whole reaction.
        if i >= 3 {
            let x = state.position[i - 1].into();
            let (finished, rest_pending) =
                pending.hand_on(&setup, chain.position, x, next.local, next.inextensible);
            state.position[i - 1] = chain.position.into();
            if i >= 4 {
                state.velocity[i - 2] = finished.into();
                velocity_total += component_sum(finished);
                momenta.lost -= finished.scale(rest.mass[i - 2]);
            }
            pending = rest_pending;
        }
        chain = next.chain;
        previous_contact = next.contact;
    }
    // The last two nodes: no node after them (eq. 14 has no node n).
    let zero = V3::zero();
    let at = (&mut pending, &mut momenta);
    velocity_total += hand_on(&setup, (state, rest), (n, n), at, chain.position);
    let at = (&mut pending, &mut momenta);
    velocity_total += hand_on(&setup, (state, rest), (n + 1, n), at, zero);
    (measures, velocity_total, momenta)
}

/// Lines 24–26 past the strand's end (`i ≥ n`, zero corrections), as the node loop does
/// once node `i` is advanced: node `i − 1`'s final position `x_star` is stored (if it exists)
/// and its velocity pends; node `i − 2`'s velocity, now whole, is stored and its momentum
/// counted. Returns the [`component_sum`] of the velocity stored.
#[inline(always)]
fn hand_on<const N: usize>(
    setup: &Setup,
    (state, rest): (&mut StrandState<N>, &RestStrand<N>),
    (i, n): (usize, usize),
    (pending, momenta): (&mut Pending<Real>, &mut Momenta<Real>),
    x_star: V3<Real>,
) -> Real {
    let (local, inextensible) = (V3::zero(), V3::zero());
    let moving = state.position.get_mut(i - 1).filter(|_| i - 1 < n);
    let x = moving.as_ref().map_or(x_star, |x| (**x).into());
    let (finished, next) = pending.hand_on(setup, x_star, x, local, inextensible);
    if let Some(position) = moving {
        *position = x_star.into();
    }
    *pending = next;
    match (state.velocity.get_mut(i - 2), rest.mass.get(i - 2)) {
        (Some(velocity), Some(&mass)) if i >= 4 => {
            *velocity = finished.into();
            momenta.lost -= finished.scale(mass);
            component_sum(finished)
        }
        _ => 0.0,
    }
}

/// SB15 Algorithm 1 lines 13–21 for node `i` of every lane (a lane where the node is not
/// `active` computes but adds nothing): predict, shape, follow the leader, collisions, the
/// frame, and the segment's strain for the report. One function for the per-strand path
/// (`T = Real`) and the block path, so both run the same operations per strand.
#[inline(always)]
#[must_use]
pub fn advance<M: Math, T: Lane>(
    setup: &Setup,
    colliders: &[Shape],
    node: &NodeInput<T>,
    chain: &Chain<T>,
    previous_contact: T::Mask,
    measures: &mut Measures<T>,
    collider_push: &mut [V3<T>],
) -> Advanced<T> {
    // Below 60 Hz the shape damping, then lines 13–14: external accelerations, prediction
    // (eq. 1).
    let (velocity, a) = external_acceleration(setup, node);
    let mut x = predict::predicted_position(setup, node.position, velocity, a);
    // Line 18: shape, eqs. (8), (9) — the local target uses x* after the global step. Eq.
    // (14) feeds back the local and the follow-the-leader corrections, not the global one
    // (`dftl::velocity` says why).
    let mut local = V3::zero();
    if setup.shape {
        if setup.global_shape {
            x = x + shape::global_correction(setup, node.rest_position, node.root_distance, x);
        }
        let (previous, tangent, normal) = (chain.position, chain.tangent, chain.normal);
        let rest = (node.local_rest, node.root_distance);
        local = shape::local_correction(setup, previous, tangent, normal, rest.0, rest.1, x);
        x += local;
    }
    // Line 19: follow the leader, eq. (10); its direction is the frame's next tangent.
    let (mut tangent, mut tangent_known) = (chain.tangent, T::mask(false));
    let mut inextensible = V3::zero();
    if setup.inextensibility {
        let (projected, t) =
            follow_leader::project::<M, T>(chain.position, x, node.segment_length, chain.tangent);
        inextensible = projected - x;
        (x, tangent, tangent_known) = (projected, t, T::mask(true));
    }
    // Line 20: collisions, each collider in turn (not part of the correction).
    let (mut contact, followed) = (T::mask(false), x);
    if setup.collisions {
        let node_mass = (node.active, node.mass);
        (x, contact) =
            collisions::resolve::<M, T>(colliders, x, node_mass, measures, collider_push);
    }
    // The segment's strain, for the report.
    let segment = measures.segment(
        setup.collisions,
        chain.position,
        x,
        node,
        contact | previous_contact,
    );
    // Line 21: the frame, carried only when the shape constraints need it, along
    // follow-the-leader's tangent (the segment's without the projection), turned towards the
    // pushed segment by the push's share of a segment (`frame::carry` says why).
    let (tangent, normal) = if setup.shape {
        let push = (x - followed, contact, node.segment_length);
        frame::carry::<M, T>(chain, &segment, (tangent, tangent_known), push)
    } else {
        (chain.tangent, chain.normal)
    };
    let chain = Chain {
        position: x,
        tangent,
        normal,
    };
    Advanced {
        chain,
        local,
        inextensible,
        contact,
        acceleration: a,
    }
}

/// Node `node`'s velocity after the shape damping (below 60 Hz: the velocity relative to
/// the head's rigid motion, `dftl::damping`) and its external acceleration (lines 13–14),
/// which the prediction takes.
#[inline(always)]
fn external_acceleration<T: Lane>(setup: &Setup, node: &NodeInput<T>) -> (V3<T>, V3<T>) {
    let velocity = if setup.shape && setup.shape_damping {
        damping::damped_velocity(setup, node.position, node.velocity)
    } else {
        node.velocity
    };
    let a = predict::acceleration(setup, velocity, node.mass, node.extra, node.has_extra);
    (velocity, a)
}

/// Node `node`'s momentum at the step's end under the external forces alone, `m (v + a Δt)`
/// with its velocity as the step found it (the shape damping is the head's doing too) and its
/// external acceleration `a`; zero where the lane does not have the node. What the step's
/// corrections change of it is what the head transmits (`Tally::head_force`).
#[inline(always)]
fn kicked<T: Lane>(setup: &Setup, node: &NodeInput<T>, a: V3<T>) -> V3<T> {
    let kicked = (node.velocity + a.scale(T::splat(setup.dt))).scale(node.mass);
    V3::select(node.active, kicked, V3::zero())
}

/// Steps every block of `blocks` (strand `b·W + l` of the scene is lane `l` of block `b`,
/// counted from `first_strand`). `accelerations`, if any, holds `N` entries per strand from
/// the first strand of `blocks` (as `pipeline::step_strands`). The std harness splits the
/// blocks over threads by a fixed partition and merges the reports in block order.
pub fn step_blocks<M: Math, const W: usize, const N: usize>(
    ctx: &StepContext,
    blocks: &mut [DftlBlock<W, N>],
    first_strand: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    // Once for all the blocks, not once a block (about 250 instructions each, callgrind).
    let setup = Setup::new(ctx);
    for (b, block) in blocks.iter_mut().enumerate() {
        let block_accelerations = accelerations.and_then(|a| a.get(b * W * N..));
        let first = first_strand.wrapping_add((b * W) as u32);
        step_block_with::<M, W, N>(ctx, &setup, block, first, block_accelerations, report);
    }
}

/// Steps DFTL strands kept in structure-of-arrays blocks as well (`blocks[b]` built from
/// `strands[b·W ..]`, [`DftlBlock::from_strands`]): each block's state loaded from its strands,
/// stepped in lanes ([`step_block`]) and stored back; a block holding a strand that a grab
/// holds this step steps its strands one by one instead ([`step_strand`]: the held strand's
/// projection works on a strand). The same bits either way. `first_strand` is the index of
/// `strands[0]` in the scene; `accelerations`, if any, holds `N` per strand from it.
pub fn step_strands_in_blocks<M: Math, const W: usize, const N: usize>(
    ctx: &StepContext,
    blocks: &mut [DftlBlock<W, N>],
    strands: &mut [Strand<N>],
    (first_strand, grabs): (u32, &[Grab]),
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let setup = Setup::new(ctx);
    for (b, (block, chunk)) in blocks.iter_mut().zip(strands.chunks_mut(W)).enumerate() {
        let first = first_strand.wrapping_add((b * W) as u32);
        let of_block = accelerations.and_then(|a| a.get(b * W * N..));
        let held = chunk.iter().enumerate().any(|(l, strand)| {
            let index = first.wrapping_add(l as u32);
            !grabbed_nodes(ctx, grabs, index, strand.rest.nodes.min(N)).is_empty()
        });
        if held {
            for (l, strand) in chunk.iter_mut().enumerate() {
                let at = (grabs, first.wrapping_add(l as u32));
                let of_strand = of_block.and_then(|a| a.get(l * N..(l + 1) * N));
                step_strand::<M, N>(strand, &setup, ctx, at, of_strand, None, report);
            }
        } else {
            block.load_state(chunk);
            step_block_with::<M, W, N>(ctx, &setup, block, first, of_block, report);
            block.store(chunk);
        }
    }
}

/// Steps one block by `ctx.dt`: the pipeline of [`step_strand`] on every lane at once, with the
/// same stages, and the same bits on each strand.
pub fn step_block<M: Math, const W: usize, const N: usize>(
    ctx: &StepContext,
    block: &mut DftlBlock<W, N>,
    first_strand: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    step_block_with::<M, W, N>(
        ctx,
        &Setup::new(ctx),
        block,
        first_strand,
        accelerations,
        report,
    );
}

/// [`step_block`] with `setup`, [`Setup::new`] of `ctx`, built once for all blocks.
#[inline(always)]
fn step_block_with<M: Math, const W: usize, const N: usize>(
    ctx: &StepContext,
    setup: &Setup,
    block: &mut DftlBlock<W, N>,
    first_strand: u32,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let lanes = block.strands.min(W) as u32;
    // Quarantine: every lane's last good state.
    let last_good: BlockState<W, N> = snapshot(block, report);
    // Lines 12–15, fused into the pass below: external forces and the prediction.
    count_prediction(ctx, accelerations.is_some(), lanes, report);
    // The root follows the head: nodes 0 and 1 of every lane.
    let roots = root_coupling(block, ctx, report);
    // Lines 16–27 in one pass from the root, all lanes together.
    count_constraints(setup, lanes, report);
    let at = (&mut *block, &last_good);
    let verdict = with_effect_switches!(
        setup,
        block_pass::<M, W, N>(ctx, setup, at, roots, accelerations, report)
    );
    // Quarantine: a lane that wrote a non-finite value gets its last good positions back.
    guard(
        block,
        &last_good,
        |_, l| verdict.0[l] == 0.0,
        first_strand,
        report,
    );
}

/// What the node loop of a block carries from node to node.
struct Carried<'a, const W: usize> {
    chain: &'a mut Chain<Wide<W>>,
    pending: &'a mut Pending<Wide<W>>,
    previous_contact: &'a mut WideMask<W>,
    measures: &'a mut Measures<Wide<W>>,
    collider_push: &'a mut ColliderPush<Wide<W>>,
    velocity_total: &'a mut Wide<W>,
}

/// The whole pass over the nodes of a block with the effect switches fixed, and each lane's
/// tally into the report: its measures and, unless the guard will roll it back (its `roots`
/// sum of the root coupling's velocities and the pass's, non-finite), what it transmits to
/// the colliders and the head. Returns that verdict per lane: `roots` plus the
/// [`component_sum`]s of the velocities the pass wrote, through [`not_finite_sum`] (0 where
/// every value was finite).
#[inline(never)]
fn block_pass<
    M: Math,
    const W: usize,
    const N: usize,
    const SHAPE: bool,
    const INEXTENSIBLE: bool,
    const DRAG: bool,
>(
    ctx: &StepContext,
    setup: &Setup,
    (block, start): (&mut DftlBlock<W, N>, &BlockState<W, N>),
    roots: Wide<W>,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> Wide<W> {
    let setup = setup.with_switches(SHAPE, INEXTENSIBLE, DRAG);
    let max_nodes = block.max_nodes.min(N);
    let mut velocity_total = Wide::splat(0.0);
    if max_nodes < 3 {
        return not_finite_sum(roots);
    }
    let nodes = block.nodes;
    let nodes_real = Wide::new(core::array::from_fn(|l| nodes[l] as Real));
    // The chain at node 1: `R_head R̂_0`, all lanes at once.
    let (tangent, normal) = (
        read_lanes(&block.root_tangent),
        read_lanes(&block.root_normal),
    );
    let mut chain = Chain::start(
        &setup,
        tangent,
        normal,
        read_lanes(&block.state[1].position),
    );
    let mut measures: Measures<Wide<W>> = Measures::default();
    let mut collider_push: ColliderPush<Wide<W>> = [V3::zero(); MAX_COLLIDERS];
    let mut previous_contact = Wide::<W>::mask(false);
    let mut pending = Pending::start();
    // Nodes every lane has: there every lane is active and every selection below is a
    // constant (the same bits as the masked form, without its blends).
    let common = nodes.iter().copied().min().unwrap_or(0).min(max_nodes);
    // Once for the block: the compiler does not hoist `StepContext::colliders` out of the
    // node loop.
    let colliders = ctx.colliders();
    for k in 2..max_nodes {
        let carried = Carried {
            chain: &mut chain,
            pending: &mut pending,
            previous_contact: &mut previous_contact,
            measures: &mut measures,
            collider_push: &mut collider_push,
            velocity_total: &mut velocity_total,
        };
        // Nodes 2 and 3 finish nothing (node 1 is held) and past the shortest lane the masks
        // select: both take the masked copy, so the pass holds two copies of a node, not four.
        let (b, a, n) = (&mut *block, accelerations, nodes_real);
        if k >= 4 && k < common {
            block_node::<M, W, N, true>(colliders, &setup, b, k, n, a, carried);
        } else {
            block_node::<M, W, N, false>(colliders, &setup, b, k, n, a, carried);
        }
    }
    // The last two nodes of the longest lanes: no node after them.
    for k in max_nodes..max_nodes + 2 {
        let zero = V3::zero();
        let (x_star, b) = (chain.position, &mut *block);
        let at = handing_lanes(k, nodes_real);
        let written = hand_on_lanes(&setup, b, at, &mut pending, x_star, (zero, zero));
        velocity_total += written;
    }
    // The head force's sum, after the pass: carried through the node loop beside the chain,
    // its three vectors of lanes spill the loop (8-lane blocks of DFTL + shape a quarter
    // slower).
    let momenta = lost_momenta(&setup, (block, start), accelerations, (nodes_real, common));
    let measured = (&measures, &collider_push, momenta);
    let verdict = not_finite_sum(roots + velocity_total);
    tally_lanes::<M, W, N>(ctx, &setup, (block, verdict), measured, report);
    verdict
}

/// The lanes where node `k` is free (node 1 is held) and exists.
#[inline(always)]
fn free_lanes<const W: usize>(k: usize, nodes_real: Wide<W>) -> WideMask<W> {
    Wide::splat(k as Real).lt(nodes_real) & Wide::<W>::mask(k >= 2)
}

/// Node `k` of every lane (SB15 Algorithm 1 lines 13–21) and lines 24–26 for node `k − 2`
/// where it is free (`k ≥ 4`). With `ALL` every lane has both nodes: the masks are constants.
#[inline(always)]
fn block_node<M: Math, const W: usize, const N: usize, const ALL: bool>(
    colliders: &[Shape],
    setup: &Setup,
    block: &mut DftlBlock<W, N>,
    k: usize,
    nodes_real: Wide<W>,
    accelerations: Option<&[Vec3]>,
    carried: Carried<'_, W>,
) {
    let active = if ALL {
        Wide::<W>::mask(true)
    } else {
        Wide::splat(k as Real).lt(nodes_real)
    };
    let Some(node) = block.node_input(k, active, accelerations) else {
        return;
    };
    // Lines 13–21, the per-strand path's function on every lane.
    let next = advance::<M, Wide<W>>(
        setup,
        colliders,
        &node,
        &*carried.chain,
        *carried.previous_contact,
        carried.measures,
        carried.collider_push,
    );
    // Lines 24–26 for nodes k − 1 and k − 2; a lane past its last node hands on zeros, as
    // the per-strand path does after a strand's last node.
    let local = V3::select(active, next.local, V3::zero());
    let inextensible = V3::select(active, next.inextensible, V3::zero());
    let x_star = carried.chain.position;
    let at = if ALL {
        (k, Wide::<W>::mask(true), Wide::<W>::mask(true))
    } else {
        handing_lanes(k, nodes_real)
    };
    let pending = &mut *carried.pending;
    let written = hand_on_lanes(setup, block, at, pending, x_star, (local, inextensible));
    *carried.velocity_total += written;
    *carried.chain = Chain::select(active, &next.chain, carried.chain);
    *carried.previous_contact = (active & next.contact) | (!active & *carried.previous_contact);
}

/// Lines 24–26 once node `k` of every lane is advanced (or, past a lane's end, with zero
/// corrections), as the per-strand path's `hand_on`: node `k − 1`'s final position `x_star`
/// is stored where `moving` (it is free), and node `k − 2`'s velocity where `finishing` (node
/// `k − 1`'s where `moving` without shape).
/// Returns the [`component_sum`] of the velocities stored, 0 in the other lanes (whose
/// velocities the last guard saw finite): each lane's total adds its strand's per-strand terms
/// in the same order, and zeros, which change no verdict. Constant masks fold away.
#[inline(always)]
fn hand_on_lanes<const W: usize, const N: usize>(
    setup: &Setup,
    block: &mut DftlBlock<W, N>,
    (k, moving, finishing): (usize, WideMask<W>, WideMask<W>),
    pending: &mut Pending<Wide<W>>,
    x_star: V3<Wide<W>>,
    (local, inextensible): (V3<Wide<W>>, V3<Wide<W>>),
) -> Wide<W> {
    let x = block
        .state
        .get(k - 1)
        .map_or(x_star, |s| read_lanes(&s.position));
    let x = V3::select(moving, x, x_star);
    let (finished, next) = pending.hand_on(setup, x_star, x, local, inextensible);
    block.store_position_where(k - 1, moving, x_star);
    if !setup.shape {
        // Without shape no reaction reaches two nodes back: node `k − 1`'s velocity is whole
        // now and is stored beside its position, not carried to the next node (the same
        // values, added to the totals in the same node order).
        let stored = block.store_velocity_where(k - 1, moving, next.velocity);
        return Wide::select(moving, component_sum(stored), Wide::splat(0.0));
    }
    *pending = next;
    let stored = block.store_velocity_where(k - 2, finishing, finished);
    Wide::select(finishing, component_sum(stored), Wide::splat(0.0))
}

/// The free nodes' momenta over a block's pass ([`Momenta`]): each node's momentum under the
/// external forces alone ([`kicked`]), from its state at the step's `start` (the snapshot the
/// guard keeps) and the same acceleration the pass computed from it, and the velocities the
/// pass stored, added in the order the per-strand node loop adds them (node `k`'s kick, then
/// node `k − 2`'s final momentum taken away), so each lane has its strand's bits; `common` is
/// the node count every lane has. Computing the kicks again costs less than an array of them
/// the pass would zero and write for every block.
#[inline(always)]
fn lost_momenta<const W: usize, const N: usize>(
    setup: &Setup,
    (block, start): (&DftlBlock<W, N>, &BlockState<W, N>),
    accelerations: Option<&[Vec3]>,
    (nodes_real, common): (Wide<W>, usize),
) -> Momenta<Wide<W>> {
    let max_nodes = block.max_nodes.min(N);
    let mut lost = V3::zero();
    for k in 2..max_nodes + 2 {
        // As in the pass: where every lane has nodes `k` and `k − 2` free, the masks are
        // constants and their selections fold away.
        let at = (block, start, accelerations);
        if k >= 4 && k < common {
            lose_momentum_at::<W, N, true>(setup, at, k, nodes_real, &mut lost);
        } else {
            lose_momentum_at::<W, N, false>(setup, at, k, nodes_real, &mut lost);
        }
    }
    Momenta { lost }
}

/// [`lost_momenta`] at node `k`: node `k`'s kick added, node `k − 2`'s final momentum taken
/// away. With `ALL` every lane has both nodes free.
#[inline(always)]
fn lose_momentum_at<const W: usize, const N: usize, const ALL: bool>(
    setup: &Setup,
    (block, start, accelerations): (&DftlBlock<W, N>, &BlockState<W, N>, Option<&[Vec3]>),
    k: usize,
    nodes_real: Wide<W>,
    lost: &mut V3<Wide<W>>,
) {
    let (active, finishing) = if ALL {
        (Wide::<W>::mask(true), Wide::<W>::mask(true))
    } else {
        (free_lanes(k, nodes_real), free_lanes(k - 2, nodes_real))
    };
    if k < block.max_nodes {
        if let Some(node) = block.node_input_in(&start.0, k, active, accelerations) {
            let (_, a) = external_acceleration(setup, &node);
            *lost += kicked(setup, &node, a);
        }
    }
    if let (Some(state), Some(mass)) = (block.state.get(k - 2), block.mass.get(k - 2)) {
        let taken = *lost - read_lanes(&state.velocity).scale(Wide::new(*mass));
        *lost = V3::select(finishing, taken, *lost);
    }
}

/// The masks of [`hand_on_lanes`] at node `k`: node `k − 1` free and in the lane, node
/// `k − 2` likewise.
#[inline(always)]
fn handing_lanes<const W: usize>(
    k: usize,
    nodes_real: Wide<W>,
) -> (usize, WideMask<W>, WideMask<W>) {
    (
        k,
        free_lanes(k - 1, nodes_real),
        free_lanes(k - 2, nodes_real),
    )
}

/// Each lane's tally into the report, in lane order, as the per-strand path's: its measures,
/// then, where the guard will keep the lane's step (`verdict` 0), its pushes on the scene's
/// colliders in use and its force on the head (`Tally::head_force`).
fn tally_lanes<M: Math, const W: usize, const N: usize>(
    ctx: &StepContext,
    setup: &Setup,
    (block, verdict): (&DftlBlock<W, N>, Wide<W>),
    (measures, collider_push, momenta): (
        &Measures<Wide<W>>,
        &ColliderPush<Wide<W>>,
        Momenta<Wide<W>>,
    ),
    report: &mut StepReport,
) {
    let (stretch, contact_stretch) = measures.stretches::<M>();
    // The pushes on the scene's colliders in use (none with collisions off), gathered from
    // the lanes for those only.
    let in_use = ctx.colliders().len().min(MAX_COLLIDERS);
    let mut lane_push = [V3::<Real>::zero(); MAX_COLLIDERS];
    for l in 0..block.strands.min(W) {
        for (push, lanes) in lane_push.iter_mut().zip(collider_push).take(in_use) {
            *push = V3::from(lanes.lane(l));
        }
        let push = lane_push.get(..in_use).unwrap_or(&[]);
        let lost = momenta.lost.lane(l);
        let tally = Tally {
            stretch: stretch.0[l],
            contact_stretch: contact_stretch.0[l],
            penetration: measures.penetration.0[l],
            contacts: measures.contacts.0[l] as u32,
            lost,
            head_force: Tally::head_force(lost, push, setup.inv_dt),
        };
        tally.report(report);
        let rolled_back = verdict.0[l] != 0.0;
        transmit_to_colliders(push, setup.inv_dt, rolled_back, report);
        transmit_to_head(tally.head_force, rolled_back, report);
    }
}

#[cfg(test)]
mod tests;
