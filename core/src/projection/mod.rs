//! Fast manifold projection (Kmoch 2009 Sec. 8, Goldenthal et al. 2007): after the
//! unconstrained step, move the nodes to the nearest configuration (in the mass metric) that
//! satisfies the constraints, then feed the position change back into the velocities.
//!
//! Each iteration `k` (at most `RodParams::projection_iterations`):
//! 1. evaluate `C(x_k)` and `∇C(x_k)`: inextensibility of every segment with a free node,
//!    and collision rows for the free nodes found inside a collider *at this iterate* (a node
//!    pushed in by the projection is caught in the same step) — [`constraints`]; in converge
//!    mode also *tentative* rows for nodes just outside, kept only where they push (step 3);
//! 2. stop if `max_j |C_j| / (ê^j·ê^j) ≤ tol` (converge mode only; a row within what f32
//!    positions can resolve counts as met — see [`constraints::resolution_floor`]);
//! 3. solve `(∇C M⁻¹ ∇Cᵀ) δλ = C(x_k)` with a banded LDLᵀ — [`banded`]: each node's collision
//!    rows are eliminated first at their node (no fill), leaving the segments' tridiagonal
//!    band, so contacts cost O(contacts) and never widen the band; tentative rows whose
//!    multiplier pulls are removed and the system solved again (at most three times);
//! 4. `x_{k+1} = x_k − M⁻¹ ∇C(x_k)ᵀ δλ`, scaled down whole if it would move a node further
//!    than ten strand lengths (a trust region that only garbage input meets).
//!
//! Root coupling and grabs are *prescribed* nodes (`w = 0`, no rows): nodes 0 and 1 were set
//! by root coupling, grabbed nodes are set to their targets here. Then
//! `v ← v + Δx/h` with `Δx = x_proj − x_pred` (Kmoch writes `ẋ − Δx/h` with the opposite sign
//! of `Δx`: the same update).
//!
//! Forces, with `Λ = Σ_k δλ_k` (accumulated per iteration with that iteration's gradient, as
//! collision rows come and go): the constraint force on a node is `−∇CᵀΛ/h²`. A collider feels
//! the reaction of its collision rows, `+Σ ∇_{x_i}C_cᵀ δλ_c / h²` (the hair pressing on it).
//! The device holding a grab feels the pull of the adjacent segments on the prescribed node
//! plus the node's own weight and inertia, `−Σ_adjacent ∇_{x_g}C_jᵀΛ_j/h² − m_g(a_g − g)`;
//! `m_g(a_g − g)` (with every external acceleration the node got, not only gravity) is
//! `m_g Δx_g / h²`, the impulse that took the node from its predicted position to the target.
//! (Written `+ m_g(a_g − g)`, the force at rest would subtract the node's own weight from the
//! weight held: the two terms must have the same sign, as the paper's 1.7 % remark says.)

pub mod banded;
pub mod constraints;
pub mod lanes;

use crate::collide::{Shape, MAX_COLLIDERS};
use crate::context::StepContext;
use crate::effects::Effect;
use crate::grab::{grabbed_nodes, Coupling, Grab, GrabbedNodes, MAX_GRABS};
use crate::lane::{Lane, V3};
use crate::math::{self, Math, Real, Vec3};
use crate::params::Mode;
use crate::report::{Flags, Stage, StepReport};
use crate::strand::Strand;

use banded::BandRow;
use constraints::{magnitude, ContactMemory, Layout, Nodes, Rows, MAX_NODE_CONTACTS};

/// What one projection did, besides what it adds to the report.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outcome {
    /// Iterations run (solves), at most the cap.
    pub iterations: u32,
    /// Relative residual at the final positions (see [`constraints::Rows::residual`]).
    pub residual: Real,
    /// Whether the final positions meet the tolerance (or f32's resolution, if coarser).
    pub converged: bool,
    /// Rows dropped at a singular pivot, summed over iterations.
    pub dropped_rows: u32,
    /// Collision rows at the iterates a solve followed, summed over iterations
    /// ([`constraints::Rows::collision_rows`]).
    pub collision_rows: u32,
    /// The force the held node 1 feels from segment 1's row, `−∇_{x_1}C_1ᵀ Λ_1 / h²`, N: the
    /// projection's share of what the strand transmits to the head.
    pub root_pull: Vec3,
    /// The force the colliders feel from this strand's collision rows, summed, N.
    pub collider_felt: Vec3,
    /// The force the devices of this strand's grabs feel, summed, N.
    pub grab_felt: Vec3,
}

#[cfg(feature = "defmt")]
impl defmt::Format for Outcome {
    fn format(&self, f: defmt::Formatter) {
        use crate::math::DefmtVec3;
        defmt::write!(
            f,
            "Outcome {{ iterations: {}, residual: {}, converged: {}, dropped_rows: {}, collision_rows: {}, root_pull: {}, collider_felt: {}, grab_felt: {} }}",
            self.iterations,
            self.residual,
            self.converged,
            self.dropped_rows,
            self.collision_rows,
            DefmtVec3(self.root_pull),
            DefmtVec3(self.collider_felt),
            DefmtVec3(self.grab_felt)
        )
    }
}

/// A projection's workspace kept by its caller from step to step (a `World` keeps one for
/// DFTL's held strands, `pipeline::StepScratch`). [`Workspace::reset`] sets every value a
/// projection reads before it writes it, so the workspace's past never reaches the bits; a
/// fresh workspace's zero fills were a tenth of a held strand's projection on the
/// Cortex-M4F, and its kilobytes a step's deepest stack frame.
pub struct ProjectionScratch<const N: usize> {
    work: Workspace<N>,
    colliders: ColliderSpace,
}

impl<const N: usize> ProjectionScratch<N> {
    /// Before its first use.
    #[must_use]
    pub const fn new() -> Self {
        ProjectionScratch {
            work: Workspace::empty(),
            colliders: ColliderSpace::EMPTY,
        }
    }
}

/// The colliders a projection tests: the step's usable ones ([`usable_colliders_into`]) and
/// those near the strand ([`NearColliders`]). Kept beside the workspace: in a projection's own
/// frame they were 620 bytes of the stack at every step on the Cortex-M4F.
struct ColliderSpace {
    shapes: [(u8, Shape); MAX_COLLIDERS],
    near: NearColliders,
}

impl ColliderSpace {
    /// Before its first use.
    const EMPTY: ColliderSpace = ColliderSpace {
        shapes: [(0, PLACEHOLDER); MAX_COLLIDERS],
        near: NearColliders::none(),
    };
}

/// What an unused collider slot holds.
const PLACEHOLDER: Shape = Shape::Plane {
    point: Vec3::ZERO,
    normal: Vec3::Y,
};

impl<const N: usize> Default for ProjectionScratch<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// Scratch space of one projection: fixed arrays, nothing on the heap.
struct Workspace<const N: usize> {
    /// `x_pred`: the positions after integration and root coupling.
    predicted: [Vec3; N],
    nodes: Nodes<N>,
    /// Which colliders each node touched, and the contact multipliers' sums.
    contacts: ContactMemory<N>,
    rows: Rows<N>,
    band: [BandRow; N],
    multipliers: [Real; N],
    /// `Σ_k −∇_{x_g}C_kᵀ δλ_k` per grab slot: the segments' pull on the grabbed node, × h².
    grab_pull: [Vec3; MAX_GRABS],
    /// `Σ_k −∇_{x_1}C_1ᵀ δλ_1`: segment 1's pull on the held node 1, × h².
    root_pull: Vec3,
    /// One iteration's `Δx` per node.
    step: [Vec3; N],
    /// Longest move of a node in one iteration: ten times the strand's rest length, m.
    trust_radius: Real,
    /// `Σ_k ∇_{x_i}C_kᵀ δλ_k` over each collider's rows: the hair's push on it, × h².
    collider_push: [Vec3; MAX_COLLIDERS],
    truncated: bool,
}

/// The trust radius of one projection iteration, in strand rest lengths (see
/// `solve_and_move`).
const TRUST_RADIUS_IN_STRAND_LENGTHS: Real = 10.0;

/// Compile-time check that row and node indices fit the `u16`s the rows store.
struct IndexFits<const N: usize>;
impl<const N: usize> IndexFits<N> {
    const OK: () = assert!(
        N < u16::MAX as usize,
        "node capacity too large for the projection's u16 row indices"
    );
}

/// Projects strand `strand` (index `strand_index` in the whole scene, as in [`Grab::strand`])
/// onto its constraints after the unconstrained step and updates its velocities; adds its
/// iterations, residual, stretch, contacts and forces to `report`.
///
/// Runs when any of the effects `inextensibility`, `collisions`, `grabs` is on, and builds
/// only the rows of those that are. Callable on any strand, colliders and grabs (so that a
/// fuzz target can drive it with a `StepContext::new` of its own): it never panics, and
/// degenerate input (coincident nodes, a node at a sphere's centre, huge stretch) gives
/// finite positions and an honest residual.
pub fn project_constraints<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    grabs: &[Grab],
    strand_index: u32,
    report: &mut StepReport,
) -> Outcome {
    let at = (grabs, strand_index);
    project_in_mode::<M, N>(strand, ctx, at, ctx.params.mode, report)
}

/// [`project_constraints`] in `mode` rather than the scene's, in a workspace of its own on
/// the stack. Never inlined: its kilobytes stay off the frames of callers that keep a
/// workspace and call it only without one (a DFTL step, `pipeline::dftl`).
#[inline(never)]
pub(crate) fn project_in_mode<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    at: (&[Grab], u32),
    mode: Mode,
    report: &mut StepReport,
) -> Outcome {
    if !projects(ctx) {
        return Outcome::default();
    }
    let mut work = Workspace::new(strand, strand.rest.nodes.min(N));
    let mut colliders = ColliderSpace::EMPTY;
    project_in::<M, N>(strand, ctx, at, mode, (&mut work, &mut colliders), report)
}

/// [`project_in_mode`] in the workspace `scratch` its caller keeps (DFTL's held strands, in
/// fixed-cost mode: `pipeline::dftl`), with the same bits.
pub(crate) fn project_in_scratch<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    at: (&[Grab], u32),
    mode: Mode,
    scratch: &mut ProjectionScratch<N>,
    report: &mut StepReport,
) -> Outcome {
    if !projects(ctx) {
        return Outcome::default();
    }
    scratch.work.reset(strand, strand.rest.nodes.min(N));
    let space = (&mut scratch.work, &mut scratch.colliders);
    project_in::<M, N>(strand, ctx, at, mode, space, report)
}

/// Whether a projection runs: when any of `inextensibility`, `collisions`, `grabs` is on.
fn projects(ctx: &StepContext) -> bool {
    ctx.has(Effect::Inextensibility) || ctx.has(Effect::Collisions) || ctx.has(Effect::Grabs)
}

/// The projection of `strand` in `work`, set up for it ([`Workspace::new`] or
/// [`Workspace::reset`]). Inlined into both: apart, its frame came on top of the workspace's
/// (430 bytes more stack at 16 nodes).
#[inline(always)]
fn project_in<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    (grabs, strand_index): (&[Grab], u32),
    mode: Mode,
    (work, colliders): (&mut Workspace<N>, &mut ColliderSpace),
    report: &mut StepReport,
) -> Outcome {
    #[allow(clippy::let_unit_value)]
    let () = IndexFits::<N>::OK;
    report.ran(Stage::Projection);
    if ctx.has(Effect::Collisions) {
        report.ran(Stage::Collisions);
    }
    let n = strand.rest.nodes.min(N);
    let held = grabbed_nodes(ctx, grabs, strand_index, n);
    prescribe_grabs::<M, N>(strand, ctx, grabs, &held, work);
    let shape_count = usable_colliders_into(ctx, &mut colliders.shapes);
    let layout = layout_in_mode(ctx, shape_count, mode);
    let shapes = colliders.shapes.get(..shape_count).unwrap_or(&[]);
    let near = &mut colliders.near;
    let outcome = iterate::<M, N>(strand, ctx, (shapes, near), layout, &held, work);
    let findings = Findings {
        touched: &work.contacts.touched,
        max_depth: work.rows.max_depth,
        truncated: work.truncated,
        collider_push: &work.collider_push,
    };
    let mut outcome = conclude::<M, N>(strand, &work.predicted, ctx, outcome, findings, report);
    outcome.root_pull = work.root_pull * (ctx.inv_dt * ctx.inv_dt);
    outcome.grab_felt = record_grabs::<M, N>(strand, ctx, grabs, &held, work, report);
    outcome
}

/// The end of a projection from the positions `predicted`: positions kept finite, the
/// velocity update, the report.
fn conclude<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    predicted: &[Vec3; N],
    ctx: &StepContext,
    mut outcome: Outcome,
    findings: Findings<'_, N>,
    report: &mut StepReport,
) -> Outcome {
    let n = strand.rest.nodes.min(N);
    keep_finite(strand, predicted, n, ctx.inv_dt, &mut outcome);
    report.ran(Stage::Velocity);
    update_velocities(strand, predicted, ctx.inv_dt);
    outcome.collider_felt = felt_by_colliders(ctx, findings.collider_push);
    record::<M, N>(strand, ctx, &outcome, findings, report);
    outcome
}

/// The force all colliders feel from one strand's collision rows, N: the sum of the
/// collider pushes (× h²) the report adds collider by collider.
pub(crate) fn felt_by_colliders(ctx: &StepContext, push: &[Vec3; MAX_COLLIDERS]) -> Vec3 {
    let total = push.iter().fold(Vec3::ZERO, |sum, &p| sum + p);
    total * (ctx.inv_dt * ctx.inv_dt)
}

/// The rows the step's effects ask for, with `shape_count` usable colliders.
fn layout_of(ctx: &StepContext, shape_count: usize) -> Layout {
    layout_in_mode(ctx, shape_count, ctx.params.mode)
}

/// [`layout_of`] in `mode` rather than the scene's.
fn layout_in_mode(ctx: &StepContext, shape_count: usize, mode: Mode) -> Layout {
    let collisions = ctx.has(Effect::Collisions);
    Layout {
        inextensibility: ctx.has(Effect::Inextensibility),
        contact_slots: if collisions {
            shape_count.min(MAX_NODE_CONTACTS)
        } else {
            0
        },
        fixed_cost: mode == Mode::FixedCost,
        // Tentative rows may cost a second solve: converge mode only, so that fixed cost
        // keeps one solve per iteration.
        contact_margin: collisions && mode == Mode::Converge,
        residual_only: false,
    }
}

/// The projection's inverse masses of `strand`'s first `n` nodes: nodes 0 and 1 follow the
/// head (root coupling), prescribed, infinite mass; so is a node of no finite positive mass.
#[inline(always)]
fn free_nodes<const N: usize>(strand: &Strand<N>, n: usize) -> Nodes<N> {
    let mut inverse_mass = [0.0; N];
    // Nodes 0 and 1 are held (0 from the fill); over slices of the rest, not `enumerate`,
    // `take` and a test of the index.
    let free = 2.min(n)..n;
    let rest = strand.rest.inverse_mass.get(free.clone()).unwrap_or(&[]);
    for (w, &rest) in inverse_mass
        .get_mut(free)
        .unwrap_or(&mut [])
        .iter_mut()
        .zip(rest)
    {
        // `rest < ∞` as `is_finite` for a positive value (NaN fails `rest > 0`).
        if rest > 0.0 && rest < Real::INFINITY {
            *w = rest;
        }
    }
    Nodes {
        inverse_mass,
        count: n,
    }
}

/// The longest move of a node in one iteration: [`TRUST_RADIUS_IN_STRAND_LENGTHS`] times the
/// rest length of `strand`'s first `n` nodes.
fn trust_radius<const N: usize>(strand: &Strand<N>, n: usize) -> Real {
    TRUST_RADIUS_IN_STRAND_LENGTHS
        * strand
            .rest
            .segment_length
            .iter()
            .take(n.saturating_sub(1))
            .sum::<Real>()
}

/// Finite in, finite out: if a degenerate configuration (found by the fuzz target: a capsule,
/// several planes and a grab on one node) overflowed an iterate, the strand keeps the
/// positions it came in with — finite, unprojected — and the outcome says the constraints are
/// not met, with the inextensibility residual of those positions and one more dropped row.
/// "Overflowed" includes a finite move so large that the velocity update `Δx/h` would not be.
#[allow(clippy::eq_op)] // c − c is the point: 0 for finite c, NaN for ±∞ and NaN.
fn keep_finite<const N: usize>(
    strand: &mut Strand<N>,
    predicted: &[Vec3; N],
    n: usize,
    inv_dt: Real,
    outcome: &mut Outcome,
) {
    let position = &mut strand.state.position;
    // One sum of `c − c` over every component `c` of every `(x − x̃)/h`, no branch per value
    // (as `Strand::is_finite`): 0 while all are finite, NaN as soon as one is not.
    let mut poison: Real = 0.0;
    let moved = position.get(..n).unwrap_or(&[]).iter();
    for (&x, &p) in moved.zip(predicted.get(..n).unwrap_or(&[])) {
        let v = (x - p) * inv_dt;
        poison += (v.x - v.x) + (v.y - v.y) + (v.z - v.z);
    }
    if poison == 0.0 {
        return;
    }
    *position = *predicted;
    outcome.converged = false;
    outcome.dropped_rows += 1;
    let mut residual: Real = 0.0;
    for j in 1..n.saturating_sub(1) {
        let e = position[j + 1] - position[j];
        let rest = strand.rest.segment_length[j];
        let relative = (e.dot(e) - rest * rest).abs() / (rest * rest);
        if relative.is_nan() || relative > residual {
            residual = relative;
        }
    }
    outcome.residual = math::max(outcome.residual, residual);
    if !outcome.residual.is_finite() {
        outcome.residual = Real::MAX;
    }
}

impl<const N: usize> Workspace<N> {
    // Inlined so that the workspace is filled where it lives, not built and copied (on the
    // Cortex-M4F the copies were a fifth of the projection's zero fills and copies).
    #[inline(always)]
    fn new(strand: &Strand<N>, n: usize) -> Self {
        Workspace {
            predicted: strand.state.position,
            nodes: free_nodes(strand, n),
            contacts: ContactMemory::default(),
            rows: Rows::default(),
            band: [[0.0; banded::MAX_HALF_BANDWIDTH + 1]; N],
            multipliers: [0.0; N],
            grab_pull: [Vec3::ZERO; MAX_GRABS],
            root_pull: Vec3::ZERO,
            step: [Vec3::ZERO; N],
            trust_radius: trust_radius(strand, n),
            collider_push: [Vec3::ZERO; MAX_COLLIDERS],
            truncated: false,
        }
    }

    /// Before its first use: what [`Self::reset`] expects of a workspace it has not seen.
    const fn empty() -> Self {
        Workspace {
            predicted: [Vec3::ZERO; N],
            nodes: Nodes {
                inverse_mass: [0.0; N],
                count: 0,
            },
            contacts: ContactMemory::new(),
            rows: Rows::new(),
            band: [[0.0; banded::MAX_HALF_BANDWIDTH + 1]; N],
            multipliers: [0.0; N],
            grab_pull: [Vec3::ZERO; MAX_GRABS],
            root_pull: Vec3::ZERO,
            step: [Vec3::ZERO; N],
            trust_radius: 0.0,
            collider_push: [Vec3::ZERO; MAX_COLLIDERS],
            truncated: false,
        }
    }

    /// As [`Self::new`] for the projection of `strand`, in place: the values a projection
    /// reads before it writes them are set, the rest left as the last projection left them.
    /// Each iteration's evaluation empties the rows it reads (`constraints::evaluate`) but
    /// the nodes' collision rows, which [`Rows::forget_contacts`] empties here as it does
    /// between iterations (without collision slots no evaluation does); the solve writes
    /// the band, the multipliers and the moves of the rows and nodes it then reads; the
    /// contact memory forgets the nodes that touched ([`ContactMemory::forget`]); the sums
    /// start from zero.
    fn reset(&mut self, strand: &Strand<N>, n: usize) {
        self.predicted = strand.state.position;
        self.nodes = free_nodes(strand, n);
        self.contacts.forget();
        self.rows.forget_contacts();
        self.grab_pull = [Vec3::ZERO; MAX_GRABS];
        self.root_pull = Vec3::ZERO;
        self.trust_radius = trust_radius(strand, n);
        self.collider_push = [Vec3::ZERO; MAX_COLLIDERS];
        self.truncated = false;
    }
}

/// The step's colliders that pass their checks (a bad one can come through `step_strands`),
/// each with its index in the step's list, packed at the front; how many in `count`. (The
/// list alone is returned: returned in a pair, it was copied once more on the Cortex-M4F.)
pub(crate) fn usable_colliders(
    ctx: &StepContext,
    count: &mut usize,
) -> [(u8, Shape); MAX_COLLIDERS] {
    // A local, not `PLACEHOLDER`: the constant was copied into each slot by a library call
    // (8.5 k instructions a step of the 32-node rod on the Cortex-M4F).
    let placeholder = Shape::Plane {
        point: Vec3::ZERO,
        normal: Vec3::Y,
    };
    let mut shapes = [(0, placeholder); MAX_COLLIDERS];
    *count = usable_colliders_into(ctx, &mut shapes);
    shapes
}

/// [`usable_colliders`] written into `slots` in place; returns how many. The slots past them
/// keep what they held.
pub(crate) fn usable_colliders_into(
    ctx: &StepContext,
    slots: &mut [(u8, Shape); MAX_COLLIDERS],
) -> usize {
    let mut count = 0;
    for (c, shape) in ctx.colliders().iter().enumerate().take(MAX_COLLIDERS) {
        if let (true, Some(slot)) = (shape.is_valid(), slots.get_mut(count)) {
            // `c < MAX_COLLIDERS = 8`: fits a u8 and the per-node contact bit mask.
            *slot = (c as u8, *shape);
            count += 1;
        }
    }
    count
}

/// Grabbed nodes: a prescribed one is moved to its target, with infinite mass and no rows
/// (Kmoch Sec. 8.1); a coupled one is moved to where its implicit spring-damper alone would
/// take it, with the coupling's stiffness in its mass ([`coupled_node`]), then within the
/// strand's reach of node 1 ([`within_reach_of_root`]).
fn prescribe_grabs<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    grabs: &[Grab],
    held: &GrabbedNodes,
    work: &mut Workspace<N>,
) {
    for (g, node) in held.iter() {
        let state = &mut strand.state;
        let root = state.position.get(1).copied().unwrap_or(Vec3::ZERO);
        if let (Some(grab), Some(x), Some(&v), Some(w)) = (
            grabs.get(g),
            state.position.get_mut(node),
            state.velocity.get(node),
            work.nodes.inverse_mass.get_mut(node),
        ) {
            let Some(coupling) = grab.coupling else {
                (*x, *w) = (grab.target, 0.0);
                continue;
            };
            let (start, inverse_mass) = coupled_node(ctx, grab, &coupling, (*x, v), *w);
            let reach = strand
                .rest
                .segment_length
                .get(1..node)
                .map_or(0.0, |lengths| lengths.iter().sum::<Real>());
            let within = within_reach_of_root::<M>(start, root, reach);
            // The strand's pull that brings the node within reach acts between it and node 1.
            if inverse_mass > 0.0 {
                work.root_pull -= (within - start) * (1.0 / inverse_mass);
            }
            (*x, *w) = (within, inverse_mass);
        }
    }
}

/// A coupled node's start `start` within `reach` of node 1 (at `root`): an inextensible strand
/// holds it there, whatever its spring pulls. Projected onto the ball first (`REACH_SLACK`
/// inside it, so that the strand is not exactly straight, where the projection's Newton
/// steps stall), the projection then starts from a configuration it can reach: from 70 cm
/// out (a target teleported 1 m from a 30-node strand's root, coupled at 1 N/m), 12
/// iterations left the strand stretched 7–17-fold.
fn within_reach_of_root<M: Math>(start: Vec3, root: Vec3, reach: Real) -> Vec3 {
    let radius = reach * (1.0 - crate::grab::REACH_SLACK);
    let out = start - root;
    let distance2 = out.dot(out);
    if distance2 <= radius * radius || !distance2.is_finite() {
        return start;
    }
    root + out * (radius / M::sqrt(distance2))
}

/// A coupled node's start in the projection and its inverse mass there. The coupling's energy
/// over the step, `½ K |x − T|² Δt² + ½ B Δt |Δt (v⁺ − v_T)|²` with `v⁺ = v + (x − x̃)/Δt` (the
/// projection's velocity update), added to the projection's `½ m |x − x̃|²`, is one quadratic
/// `½ M |x − x_c|²`:
///
/// `M = m + K Δt² + B Δt`, `x_c = x̃ + (K Δt² (T − x̃) − B Δt² (v − v_T)) / M`,
///
/// so projecting from `x_c` with mass `M` is the implicit (backward Euler) step of the spring
/// and damper together with the constraints: stable for any `K, B ≥ 0`. `x̃`, `v` are the
/// node's position and velocity after integration; `v_T = (T − T_prev)/Δt` the target's
/// velocity; `w` the node's inverse mass (0 if it has none: then it stays prescribed).
fn coupled_node(
    ctx: &StepContext,
    grab: &Grab,
    coupling: &Coupling,
    (x, v): (Vec3, Vec3),
    w: Real,
) -> (Vec3, Real) {
    if w <= 0.0 {
        return (grab.target, 0.0);
    }
    let dt = ctx.dt;
    let spring = coupling.stiffness * dt * dt;
    let damper = coupling.damping * dt;
    let mass = 1.0 / w + spring + damper;
    let target_velocity = (grab.target - grab.previous_target) * ctx.inv_dt;
    let pull = (grab.target - x) * spring - (v - target_velocity) * (damper * dt);
    (x + pull / mass, 1.0 / mass)
}

/// The projection's iterations: evaluate, test, solve, move — at most the cap, always the cap
/// in fixed-cost mode.
fn iterate<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    (shapes, near): (&[(u8, Shape)], &mut NearColliders),
    layout: Layout,
    held: &GrabbedNodes,
    work: &mut Workspace<N>,
) -> Outcome {
    let cap = u32::from(ctx.params.rod.projection_iterations);
    let tolerance = ctx.params.rod.projection_tolerance;
    let mut outcome = Outcome::default();
    near.restart(strand, &work.nodes, shapes, layout.contact_slots > 0);
    for k in 0..=cap {
        // After the last solve only the residual is wanted: no rows.
        let layout = Layout {
            residual_only: k == cap,
            ..layout
        };
        constraints::evaluate::<M, N>(
            strand,
            &work.nodes,
            near.shapes(shapes),
            layout,
            tolerance,
            &mut work.contacts,
            &mut work.rows,
        );
        work.truncated |= work.rows.truncated;
        outcome.residual = work.rows.residual;
        outcome.converged = work.rows.converged;
        if k == cap || (outcome.converged && !layout.fixed_cost) {
            break;
        }
        outcome.collision_rows += work.rows.collision_rows();
        match solve_and_move::<M, N>(strand, held, work) {
            Some((dropped, moved)) => {
                outcome.dropped_rows += dropped;
                near.moved::<M>(moved);
            }
            // A non-finite multiplier (overflow on absurd input): keep x_k, stop, report.
            None => {
                outcome.dropped_rows += 1;
                if !layout.measures_segments() && layout.inextensibility {
                    let (x, rest_length) = (&strand.state.position, &strand.rest.segment_length);
                    let (nodes, rows) = (&work.nodes, &mut work.rows);
                    constraints::measure_segments(|i| x[i], rest_length, nodes, tolerance, rows);
                    outcome.residual = work.rows.residual;
                    outcome.converged = work.rows.converged;
                }
                break;
            }
        }
        outcome.iterations += 1;
    }
    outcome
}

/// The colliders a strand may touch during its projection, so that the nodes of a strand far
/// from a collider skip its per-node test (Table 3's goal: collisions nearly free where there
/// is no contact).
///
/// The free nodes' bounding box is taken once, at the start of the projection; each iteration
/// moves every node by at most its longest move (`solve_and_move`), so by iterate `k` all
/// free nodes lie in the box grown by the sum of the longest moves so far. A collider that
/// misses that grown box (with a relative slack far above f32's rounding) has no free node
/// inside it: its per-node test would find nothing, so skipping it changes no bit. The grown
/// boxes only grow, so the near set only grows: a node that got a collision row keeps its
/// collider in the set (and so its sticky row, see [`constraints::evaluate`]).
pub(crate) struct NearColliders {
    /// Smallest and largest coordinates of the free nodes at the start.
    low: Vec3,
    high: Vec3,
    /// Slack for f32's rounding of the per-node tests, m.
    rounding: Real,
    /// Sum of the longest moves so far, m.
    grown: Real,
    /// Whether the strand has a free node (else nothing is tested).
    free: bool,
    /// Whether the box is usable: every position and move finite.
    bounded: bool,
    /// Bit `k`: `shapes[k]` is near (once all are, no more tests: the set only grows). The
    /// near shapes, in the step's order.
    mask: u32,
    near: [(u8, Shape); MAX_COLLIDERS],
    count: usize,
}

/// Per component, the smaller of `a` and `b`, `a` where `b` is NaN (as `f32::min` for an `a`
/// that is not NaN): by a compare, where `f32::min` takes ten instructions on the
/// Cortex-M4F, which has no `VMINNM`.
#[inline(always)]
fn smaller(a: Vec3, b: Vec3) -> Vec3 {
    let pick = |a: Real, b: Real| if b < a { b } else { a };
    Vec3::new(pick(a.x, b.x), pick(a.y, b.y), pick(a.z, b.z))
}

/// Per component, the larger of `a` and `b`, `a` where `b` is NaN: [`Lane::max`], by a
/// compare ([`smaller`]'s mirror).
#[inline(always)]
fn larger(a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(
        Lane::max(a.x, b.x),
        Lane::max(a.y, b.y),
        Lane::max(a.z, b.z),
    )
}

impl NearColliders {
    /// [`Self::restart`] of [`Self::none`] (a projection restarts the one it keeps).
    #[cfg(test)]
    pub(crate) fn new<const N: usize>(
        strand: &Strand<N>,
        nodes: &constraints::Nodes<N>,
        shapes: &[(u8, Shape)],
        collisions: bool,
    ) -> Self {
        let mut near = NearColliders::none();
        near.restart(strand, nodes, shapes, collisions);
        near
    }

    /// For a projection's start, in place: the free nodes' box (of `strand`'s free `nodes`;
    /// none without `collisions` or `shapes`), nothing near yet (the near list is read only
    /// as far as it is written, so it is not cleared).
    pub(crate) fn restart<const N: usize>(
        &mut self,
        strand: &Strand<N>,
        nodes: &constraints::Nodes<N>,
        shapes: &[(u8, Shape)],
        collisions: bool,
    ) {
        let mut low = Vec3::splat(Real::MAX);
        let mut high = Vec3::splat(-Real::MAX);
        // NaN and infinities propagate into the sum where min/max would hide them.
        let mut sum = Vec3::ZERO;
        let mut free = false;
        if collisions && !shapes.is_empty() {
            let positions = strand.state.position.iter().zip(nodes.inverse_mass.iter());
            for (&x, &w) in positions.take(nodes.count.min(N)) {
                if w > 0.0 {
                    low = smaller(low, x);
                    high = larger(high, x);
                    sum += x;
                    free = true;
                }
            }
        }
        self.rounding = 1.0e-5 * math::max(magnitude(low), magnitude(high)) + 1.0e-6;
        self.low = low;
        self.high = high;
        self.grown = 0.0;
        self.free = free;
        self.bounded = crate::math::is_finite(sum);
        self.mask = 0;
        self.count = 0;
    }

    /// No collider near: for a scratch space before its first use.
    pub(crate) const fn none() -> Self {
        NearColliders {
            low: Vec3::ZERO,
            high: Vec3::ZERO,
            rounding: 0.0,
            grown: 0.0,
            free: false,
            bounded: false,
            mask: 0,
            near: [(0, PLACEHOLDER); MAX_COLLIDERS],
            count: 0,
        }
    }

    /// Adds an iteration's longest move (squared, before any trust-region scaling: an upper
    /// bound of the move made).
    pub(crate) fn moved<M: Math>(&mut self, longest2: Real) {
        if self.bounded {
            self.grown += M::sqrt(longest2);
            self.bounded = self.grown.is_finite();
        }
    }

    /// The colliders that may hold a free node at this iterate, in the step's order.
    pub(crate) fn shapes<'a>(&'a mut self, shapes: &'a [(u8, Shape)]) -> &'a [(u8, Shape)] {
        if !self.free {
            return &[];
        }
        if !self.bounded {
            // Garbage positions: test every node as ever.
            return shapes;
        }
        let all = (1u32 << shapes.len().min(MAX_COLLIDERS)) - 1;
        if self.mask == all {
            return shapes;
        }
        let slack = self.grown * 1.001 + self.rounding;
        let (low, high) = (self.low - slack, self.high + slack);
        let mut mask = 0;
        for (k, (_, shape)) in shapes.iter().enumerate().take(MAX_COLLIDERS) {
            if may_touch_box(shape, low, high) {
                mask |= 1 << k;
            }
        }
        if mask == all {
            self.mask = all;
            return shapes;
        }
        if mask != self.mask {
            self.mask = mask;
            self.count = 0;
            for (k, near) in shapes.iter().enumerate().take(MAX_COLLIDERS) {
                if let (true, Some(slot)) = (mask & (1 << k) != 0, self.near.get_mut(self.count)) {
                    *slot = *near;
                    self.count += 1;
                }
            }
        }
        self.near.get(..self.count).unwrap_or(&[])
    }
}

/// Whether some point of the box `low`–`high` may lie inside `shape` (never `false` when one
/// does; `true` when unsure). The shape is grown by 1e-5 of its own coordinates, far above
/// the rounding of the per-node tests (`Shape::penetration`) far from the origin.
fn may_touch_box(shape: &Shape, low: Vec3, high: Vec3) -> bool {
    match *shape {
        Shape::Sphere { centre, radius } => {
            let reach = radius + 1.0e-5 * (magnitude(centre) + radius);
            let d = centre - centre.max(low).min(high);
            let distance2 = d.dot(d);
            // NaN (garbage positions) counts as near.
            distance2 <= reach * reach || distance2.is_nan()
        }
        Shape::Capsule { a, b, radius } => {
            let reach = radius + 1.0e-5 * (math::max(magnitude(a), magnitude(b)) + radius);
            let (a_low, a_high) = (a.min(b) - reach, a.max(b) + reach);
            !(a_low.x > high.x
                || a_low.y > high.y
                || a_low.z > high.z
                || a_high.x < low.x
                || a_high.y < low.y
                || a_high.z < low.z)
        }
        Shape::Plane { point, normal } => {
            // The box corner furthest behind the plane.
            let pick = |n: Real, lo: Real, hi: Real| if n >= 0.0 { lo } else { hi };
            let corner = Vec3::new(
                pick(normal.x, low.x, high.x),
                pick(normal.y, low.y, high.y),
                pick(normal.z, low.z, high.z),
            );
            let height = (corner - point).dot(normal);
            height <= 1.0e-5 * magnitude(point) || height.is_nan()
        }
    }
}

/// One projection step: `(∇C M⁻¹ ∇Cᵀ) δλ = C`, `x ← x − M⁻¹ ∇Cᵀ δλ`, and the forces' sums.
/// Returns the rows dropped at a singular pivot and the longest node move asked for (squared,
/// before the trust region), or `None` (and leaves `x` alone) when the multipliers are not
/// finite.
fn solve_and_move<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    held: &GrabbedNodes,
    work: &mut Workspace<N>,
) -> Option<(u32, Real)> {
    let n = work.nodes.count.min(N);
    let count = work.rows.count.min(N);
    let dropped = solve(work, n, count)?;
    let multipliers = work.multipliers.get(..count)?;
    if !multipliers.iter().all(|l| l.is_finite()) {
        return None;
    }
    let (longest2, any_contact) =
        gather_moves(&mut work.step, &work.nodes, &work.rows, multipliers);
    if !longest2.is_finite() {
        return None;
    }
    let scale = trust_scale::<M>(longest2, work.trust_radius);
    for (x, dx) in strand
        .state
        .position
        .iter_mut()
        .zip(work.step.iter())
        .take(n)
    {
        *x += *dx * scale;
    }
    pull_on_grabs(work, held, count, scale);
    pull_on_root(work, scale);
    if any_contact {
        push_on_colliders_alone(work, count, n, scale);
    }
    Some((dropped, longest2))
}

/// Δx into `step`: segments move node i by −w_i (I − P_i) ∇_iC δλ (P_i = 0 without contact),
/// contacts by −d_i. Gathered per node from its two segments (segment i − 1 first, as the rows
/// are in segment order) and its contacts, with the longest move (squared, for the trust
/// region) in the same pass. A node without collision rows has `kept = 0` (see
/// `Rows::contacts`). Returns the longest move and whether some node had a contact.
#[inline(always)]
fn gather_moves<const N: usize>(
    step: &mut [Vec3; N],
    nodes: &Nodes<N>,
    rows: &Rows<N>,
    multipliers: &[Real],
) -> (Real, bool) {
    let mut any_contact = false;
    let mut longest2: Real = 0.0;
    // Segment `i`'s row and multiplier, if it has a row.
    let row_of = |i: usize| {
        let r = rows
            .segment_row
            .get(i)
            .map_or(usize::MAX, |&r| usize::from(r));
        rows.rows().get(r).zip(multipliers.get(r).copied())
    };
    let step = step.get_mut(..nodes.count.min(N)).unwrap_or(&mut []);
    let free = step
        .iter_mut()
        .zip(nodes.inverse_mass.iter())
        .zip(rows.contacts.iter());
    // Node `i` takes segment `i − 1`'s row, which node `i − 1` looked up, then segment `i`'s.
    let mut previous = None;
    for (i, ((dx, &w), contacts)) in free.enumerate() {
        let next = row_of(i);
        let mut delta = Vec3::ZERO;
        if w > 0.0 {
            for (segment, block) in [(previous, 1), (next, 0)] {
                if let Some((row, lambda)) = segment {
                    delta -= row.projected[block] * (w * lambda);
                }
            }
        }
        previous = next;
        if contacts.kept > 0 {
            delta -= contacts.displacement;
            any_contact = true;
        }
        let d2 = delta.dot(delta);
        // Not `max`, which would drop a NaN.
        if d2.is_nan() || d2 > longest2 {
            longest2 = d2;
        }
        *dx = delta;
    }
    (longest2, any_contact)
}

/// The scale of an iteration's moves, the longest `√longest2` long, within the trust radius
/// `bound`. Newton on `e·e − ê·ê` from a nearly collapsed segment (|e| → 0, C → −ê·ê) asks
/// for a move of ê²/(2|e|), unbounded. A step longer than the trust radius is scaled down
/// whole (its direction kept): garbage then converges slowly instead of exploding. Legitimate
/// iterates do overshoot: in a violent step (the firmware scene's strand 1 at ~20 m/s,
/// predicted 2–3 cm off per node) an iterate moved a node 1.5 strand lengths and the next
/// ones converged; a radius of one strand length cut that short and broke the iteration.
/// Hence ten strand lengths ([`TRUST_RADIUS_IN_STRAND_LENGTHS`]).
#[inline(always)]
pub(crate) fn trust_scale<M: Math>(longest2: Real, bound: Real) -> Real {
    if longest2 > bound * bound {
        bound / M::sqrt(longest2)
    } else {
        1.0
    }
}

/// The multipliers `δλ` of `(∇C M⁻¹ ∇Cᵀ) δλ = C` into `work.multipliers`: each node's
/// collision rows eliminated at their node first, then the segments' chain solved. Tentative
/// collision rows (converge mode) stay only where they push: a solve whose tentative rows pull
/// is redone without those rows (an active-set step on the linearised contacts), twice at
/// most, then once more without any tentative row (the solve without the margin) if some
/// still pull. Only the last solve's dropped rows count. On Table 3's draped strands a second
/// solve is needed in one iteration in five. Returns the rows dropped at a singular pivot.
#[inline(always)]
fn solve<const N: usize>(work: &mut Workspace<N>, n: usize, count: usize) -> Option<u32> {
    let mut dropped = 0;
    for pass in 0..4 {
        dropped = banded::eliminate_contacts(&mut work.rows, n);
        let band = work.band.get_mut(..count)?;
        let multipliers = work.multipliers.get_mut(..count)?;
        let (rows, first) = (work.rows.rows(), work.rows.first());
        dropped += banded::solve_chain(rows, first, &work.nodes.inverse_mass, band, multipliers);
        if !work.rows.tentative || !multipliers.iter().all(|l| l.is_finite()) {
            break;
        }
        let all = pass >= 2;
        let inverse_mass = &work.nodes.inverse_mass;
        let pull = |rows: &Rows<N>, i| segment_pull_on_node(rows, multipliers, i);
        if !prune_tentative(&mut work.rows, inverse_mass, n, all, pull) {
            break;
        }
        banded::undo_elimination(&mut work.rows);
    }
    Some(dropped)
}

/// The segments' pull on each held grab's node from the multipliers actually applied
/// (`scale · δλ`), into `work.grab_pull`.
#[inline(always)]
fn pull_on_grabs<const N: usize>(
    work: &mut Workspace<N>,
    held: &GrabbedNodes,
    count: usize,
    scale: Real,
) {
    let (rows, segment_row) = (work.rows.rows(), &work.rows.segment_row);
    let multipliers = work.multipliers.get(..count).unwrap_or(&[]);
    // A held node `i` is in two rows at most, segment `i − 1`'s (as its second node) then
    // segment `i`'s (its first), in row order: those two, not every row's nodes searched.
    for (g, i) in held.iter() {
        let Some(pull) = work.grab_pull.get_mut(g) else {
            continue;
        };
        for (segment, block) in [(i.wrapping_sub(1), 1), (i, 0)] {
            let r = segment_row
                .get(segment)
                .map_or(usize::MAX, |&r| usize::from(r));
            if let (Some(row), Some(&lambda)) = (rows.get(r), multipliers.get(r)) {
                *pull -= row.gradients()[block] * (lambda * scale);
            }
        }
    }
}

/// Segment 1's pull on the held node 1 from the multiplier actually applied (`scale · δλ`),
/// into `work.root_pull`: node 1 is prescribed, so segment 1 is the only row through it.
#[inline(always)]
fn pull_on_root<const N: usize>(work: &mut Workspace<N>, scale: Real) {
    let r = work
        .rows
        .segment_row
        .get(1)
        .map_or(usize::MAX, |&r| usize::from(r));
    if let (Some(row), Some(&lambda)) = (work.rows.rows().get(r), work.multipliers.get(r)) {
        if let Some(k) = row.nodes.iter().position(|&node| node == 1) {
            work.root_pull -= row.gradients()[k] * (lambda * scale);
        }
    }
}

/// [`push_on_colliders`] of one strand's workspace.
fn push_on_colliders_alone<const N: usize>(
    work: &mut Workspace<N>,
    count: usize,
    n: usize,
    scale: Real,
) {
    let multipliers = work.multipliers.get(..count).unwrap_or(&[]);
    let pull = |rows: &Rows<N>, i| segment_pull_on_node(rows, multipliers, i);
    let memory = (&mut work.contacts, &mut work.collider_push);
    push_on_colliders(&work.rows, memory, &work.nodes.inverse_mass, n, scale, pull);
}

/// Each collider's share of the multipliers actually applied (`scale · δλ`), from the nodes
/// that kept a contact row this iteration: its push (`collider_push`), each node's summed
/// multiplier per collider, and the node marked as touching it (a tentative row that stayed
/// pushes: a contact from now on). `segment_pull(rows, i)` is `Σ_s ∇_{x_i}C_s δλ_s` over the
/// segments through node `i` ([`segment_pull_on_node`] for one strand).
#[inline(always)]
pub(crate) fn push_on_colliders<const N: usize, const S: usize>(
    rows: &Rows<N, S>,
    (memory, collider_push): (&mut ContactMemory<N>, &mut [Vec3; MAX_COLLIDERS]),
    inverse_mass: &[Real; N],
    n: usize,
    scale: Real,
    segment_pull: impl Fn(&Rows<N, S>, usize) -> Vec3,
) {
    for k in 0..rows.contact_count.min(N) {
        let i = usize::from(rows.contact_nodes[k]);
        let Some(&contacts) = rows.contacts.get(i) else {
            continue;
        };
        if contacts.kept == 0 || i >= n {
            continue;
        }
        let lambdas =
            banded::contact_multipliers(&contacts, inverse_mass[i], segment_pull(rows, i));
        let kept = usize::from(contacts.kept);
        let each = contacts
            .collider
            .iter()
            .zip(contacts.gradient.iter())
            .zip(lambdas.iter());
        for ((&c, &gradient), &lambda) in each.take(kept) {
            let c = usize::from(c);
            if let Some(push) = collider_push.get_mut(c) {
                *push += gradient * (lambda * scale);
            }
            if let Some(sum) = memory.multipliers[i].get_mut(c) {
                *sum += lambda * scale;
            }
            memory.touched[i] |= 1 << (c % 8);
        }
    }
}

/// Removes the tentative collision rows whose multiplier does not push (`δλ ≥ 0`: the row
/// would hold its node at the surface against the segments pulling it away), or every
/// tentative row when `all`. Returns whether any row was removed (the system must be solved
/// again); `rows.tentative` then says whether tentative rows are left.
pub(crate) fn prune_tentative<const N: usize, const S: usize>(
    rows: &mut Rows<N, S>,
    inverse_mass: &[Real; N],
    n: usize,
    all: bool,
    segment_pull: impl Fn(&Rows<N, S>, usize) -> Vec3,
) -> bool {
    let mut removed = false;
    let mut left = false;
    for k in 0..rows.contact_count.min(N) {
        let i = usize::from(rows.contact_nodes[k]);
        let (Some(&contacts), Some(&w)) = (rows.contacts.get(i), inverse_mass.get(i)) else {
            continue;
        };
        if contacts.tentative == 0 || i >= n {
            continue;
        }
        let mut pulling = contacts.tentative;
        if !all {
            let lambdas = banded::contact_multipliers(&contacts, w, segment_pull(rows, i));
            for (k, &lambda) in lambdas.iter().enumerate() {
                if lambda < 0.0 {
                    pulling &= !(1 << k);
                }
            }
        }
        if pulling != 0 {
            rows.contacts[i].remove(pulling);
            removed = true;
        }
        left |= rows.contacts[i].tentative != 0;
    }
    rows.tentative = left;
    removed
}

/// `Σ_s ∇_{x_i}C_s δλ_s` over the (at most two) segments through node `i`, with the gradients
/// before the elimination.
fn segment_pull_on_node<const N: usize>(rows: &Rows<N>, multipliers: &[Real], i: usize) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for (segment, block) in [(i.wrapping_sub(1), 1), (i, 0)] {
        let r = rows
            .segment_row
            .get(segment)
            .map_or(usize::MAX, |&r| usize::from(r));
        if let (Some(row), Some(&lambda)) = (rows.rows.get(r), multipliers.get(r)) {
            sum += row.gradient_at(block) * lambda;
        }
    }
    sum
}

/// `v ← v + Δx/h`, `Δx = x_proj − x_pred` (Goldenthal 2007; Kmoch Sec. 8.2). Nodes 0 and 1
/// got their velocity from root coupling and were not moved here.
fn update_velocities<const N: usize>(strand: &mut Strand<N>, predicted: &[Vec3; N], inv_dt: Real) {
    let n = strand.rest.nodes.min(N);
    let state = &mut strand.state;
    // Slices of the free nodes, not `take(n).skip(2)` (`dftl::strand_momentum` says why).
    let free = 2.min(n)..n;
    let velocity = state.velocity.get_mut(free.clone()).unwrap_or(&mut []);
    let position = state.position.get(free.clone()).unwrap_or(&[]);
    let predicted = predicted.get(free).unwrap_or(&[]);
    for ((v, &x_proj), &x_pred) in velocity.iter_mut().zip(position).zip(predicted) {
        let delta_x = x_proj - x_pred;
        *v += delta_x * inv_dt;
    }
}

/// What a projection found besides its [`Outcome`], for the report.
pub(crate) struct Findings<'a, const N: usize> {
    /// Per node, the colliders it touched (bit `c`).
    pub touched: &'a [u8; N],
    /// The deepest penetration at the last evaluation, m.
    pub max_depth: Real,
    /// Whether a node had more contacts than its slots.
    pub truncated: bool,
    /// Each collider's push, × h².
    pub collider_push: &'a [Vec3; MAX_COLLIDERS],
}

/// Iterations, residual, flags, stretch, contacts and collider forces into the report.
fn record<M: Math, const N: usize>(
    strand: &Strand<N>,
    ctx: &StepContext,
    outcome: &Outcome,
    work: Findings<'_, N>,
    report: &mut StepReport,
) {
    let n = strand.rest.nodes.min(N);
    record_outcome(ctx, outcome, &work, n, report);
    let x = &strand.state.position;
    for j in 0..n.saturating_sub(1) {
        let rest = strand.rest.segment_length[j];
        let stretch = segment_stretch::<M, Real>((x[j + 1] - x[j]).into(), rest);
        if work.touched[j] != 0 || work.touched[j + 1] != 0 {
            report.max_contact_stretch = math::max(report.max_contact_stretch, stretch);
        } else {
            report.max_stretch = math::max(report.max_stretch, stretch);
        }
    }
}

/// `||e| − |ê|| / |ê|`: the stretch of a segment `e` of rest length `|ê|` = `rest`, for one
/// strand or for lanes of them (`lanes::LaneEnding`), by the same operations.
#[inline(always)]
fn segment_stretch<M: Math, T: Lane>(e: V3<T>, rest: T) -> T {
    (e.dot(e).sqrt::<M>() - rest).abs() / rest
}

/// [`record`] but the stretch, of a strand of `n` nodes: iterations, residual, flags,
/// contacts and collider forces.
fn record_outcome<const N: usize>(
    ctx: &StepContext,
    outcome: &Outcome,
    work: &Findings<'_, N>,
    n: usize,
    report: &mut StepReport,
) {
    report.iterations_max = report.iterations_max.max(outcome.iterations);
    report.iterations_total += outcome.iterations;
    // `max` would hide a NaN residual; the guard rolls such a strand back anyway.
    if outcome.residual.is_nan() || outcome.residual > report.residual {
        report.residual = outcome.residual;
    }
    if !outcome.converged {
        report.cap_hits += 1;
        report.flags.insert(Flags::CAP_HIT);
    }
    report.collision_rows += outcome.collision_rows;
    if outcome.dropped_rows > 0 {
        report.dropped_rows += outcome.dropped_rows;
        report.flags.insert(Flags::SINGULAR);
    }
    if work.truncated {
        report.flags.insert(Flags::CONTACTS_TRUNCATED);
    }
    report.max_penetration = math::max(report.max_penetration, work.max_depth);
    report.contacts += work.touched.iter().take(n).filter(|&&t| t != 0).count() as u32;
    let inv_h2 = ctx.inv_dt * ctx.inv_dt;
    for (force, push) in report
        .collider_forces
        .iter_mut()
        .zip(work.collider_push.iter())
    {
        *force += push * inv_h2;
    }
}

/// Each held grab's force on its device, and whether it slipped. Returns their sum.
fn record_grabs<M: Math, const N: usize>(
    strand: &Strand<N>,
    ctx: &StepContext,
    grabs: &[Grab],
    held: &GrabbedNodes,
    work: &Workspace<N>,
    report: &mut StepReport,
) -> Vec3 {
    let inv_h2 = ctx.inv_dt * ctx.inv_dt;
    let mut total = Vec3::ZERO;
    for (g, node) in held.iter() {
        let state = &strand.state;
        let (Some(grab), Some(&pull), Some(&mass), Some(&x), Some(&v), Some(&x_pred)) = (
            grabs.get(g),
            work.grab_pull.get(g),
            strand.rest.mass.get(node),
            state.position.get(node),
            state.velocity.get(node),
            work.predicted.get(node),
        ) else {
            continue;
        };
        let felt = match grab.coupling {
            // −Σ ∇_{x_g}C_jᵀΛ_j/h² − m_g(a_g − g), with m_g(a_g − g) = m_g Δx_g/h².
            None => (pull - (x - x_pred) * mass) * inv_h2,
            // The coupling's spring and damper at the step's end, as the projection applied
            // them (`coupled_node`).
            Some(c) => crate::grab::coupling_force(&c, x, v, grab, ctx.inv_dt),
        };
        // A strand that blew up before or in its projection (the guard rolls it back) has no
        // force to report: no NaN leaves the step through the grab's force.
        if !crate::math::is_finite(felt) {
            continue;
        }
        total += felt;
        if let Some(force) = report.grab_forces.get_mut(g) {
            *force += felt;
        }
        if M::length(felt) > grab.force_limit {
            report.grabs_slipped |= 1 << g;
            report.flags.insert(Flags::GRAB_SLIPPED);
        }
    }
    total
}

#[cfg(test)]
mod tests;
