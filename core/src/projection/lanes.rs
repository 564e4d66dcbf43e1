//! The fast manifold projection (Kmoch 2009 Sec. 8) of a block's strands in lanes
//! (`lane::Wide`), one strand per lane: the segment rows, their banded `L D Lᵀ` and the moves
//! of `W` strands at once. Each lane's contacts are found, eliminated at their nodes and
//! pruned strand by strand, through the very functions [`super::project_constraints`] calls
//! (few nodes touch a collider, and each touches its own way). Every lane takes the
//! operations its strand takes alone, in the same order, and a lane that has converged or
//! failed keeps still while the others iterate: each strand gets the bits it gets alone.
//!
//! The lanes take strands whose rows are laid out alike: inextensibility on, every node past
//! the root's two free (no grab holds one), the same node count, three nodes or more. Then
//! segment `j ≥ 1` is row `j − 1`, coupled to the row before it, and segment 0, between the
//! two prescribed root nodes, has none.
//!
//! A strand projected alone with that layout goes through the same kernel at one lane
//! ([`project_strand`]): it lays no row map out and handles no grab, and on the Cortex-M4F
//! the rod's step executes 540 k instructions instead of 566 k with the general kernel, the
//! same bits.

use crate::collide::{Shape, MAX_COLLIDERS};
use crate::context::StepContext;
use crate::effects::Effect;
use crate::grab::{grabbed_nodes, Grab};
use crate::lane::{self, Aligned, Alignment, Lane as _, Natural, Wide, WideMask, V3};
use crate::math::{self, Math, Real, Vec3};
use crate::params::Mode;
use crate::precision::Vector;
use crate::report::{Stage, StepReport};
use crate::strand::Strand;

use super::banded::{eliminate_at_node, eliminate_from_segment, PIVOT_RATIO};
use super::constraints::{
    evaluate_contacts, measure_segments, resolution_floor, ContactMemory, Layout, Nodes, Rows,
};
use super::{
    conclude, felt_by_colliders, free_nodes, layout_of, project_in_scratch, prune_tentative,
    push_on_colliders, record_outcome, segment_stretch, trust_radius, trust_scale,
    usable_colliders, Findings, NearColliders, Outcome, ProjectionScratch,
};

/// Whether strand `strand` (index `index` in the scene) can be projected in lanes with
/// strands of `nodes` nodes: see the module documentation.
#[must_use]
pub fn fits_lanes<const N: usize>(
    strand: &Strand<N>,
    ctx: &StepContext,
    grabs: &[Grab],
    index: u32,
    nodes: usize,
) -> bool {
    let n = strand.rest.nodes.min(N);
    let free = strand.rest.inverse_mass.iter().take(n).skip(2);
    n == nodes
        && n >= 3
        && ctx.has(Effect::Inextensibility)
        && free.clone().all(|&w| w > 0.0 && w.is_finite())
        && grabbed_nodes(ctx, grabs, index, n).is_empty()
}

/// Projects strand `strand` (index `strand_index` in the scene) as
/// [`super::project_constraints`] does, with the same bits, through the kernel that fits it:
/// a strand laid out as most are ([`fits_lanes`]: no grab, every node past the root's two
/// free) through the lanes' kernel at one lane, which knows its rows' layout in advance; any
/// other through the general projection, which lays its rows out each iteration. What the
/// rod's step calls for one strand, in `space` ([`StrandSpace`]).
pub fn project_strand<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    (grabs, strand_index): (&[Grab], u32),
    space: &mut impl StrandSpace<N>,
    report: &mut StepReport,
) -> Outcome {
    let nodes = strand.rest.nodes.min(N);
    if fits_lanes(strand, ctx, grabs, strand_index, nodes) {
        project_alone::<M, N>(strand, ctx, space.lanes(), report)
    } else {
        let (at, mode) = ((grabs, strand_index), ctx.params.mode);
        space.general(|work| project_in_scratch::<M, N>(strand, ctx, at, mode, work, report))
    }
}

/// Where [`project_strand`] projects one strand, kept by its caller (a rod `World`'s, inside
/// `hairsim_init`'s buffer): the lanes' space at one lane, and the general projection's
/// workspace. Nothing in either carries from one strand or step to the next. On the stack,
/// the general projection's workspace was the deepest frame of a rod step on the Cortex-M4F
/// (3.4 KB of its 10 KB at 16 nodes).
pub trait StrandSpace<const N: usize> {
    /// The lanes' space at one lane.
    fn lanes(&mut self) -> &mut BlockProjection<N, 1, Natural>;

    /// `project` run in the general projection's workspace.
    fn general(&mut self, project: impl FnOnce(&mut ProjectionScratch<N>) -> Outcome) -> Outcome;
}

/// A [`StrandSpace`] that holds both spaces at once.
pub struct StrandProjection<const N: usize> {
    lanes: BlockProjection<N, 1, Natural>,
    general: ProjectionScratch<N>,
}

impl<const N: usize> StrandProjection<N> {
    /// Before its first use.
    #[must_use]
    pub const fn new() -> Self {
        StrandProjection {
            lanes: BlockProjection::new(),
            general: ProjectionScratch::new(),
        }
    }
}

impl<const N: usize> Default for StrandProjection<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> StrandSpace<N> for StrandProjection<N> {
    fn lanes(&mut self) -> &mut BlockProjection<N, 1, Natural> {
        &mut self.lanes
    }

    fn general(&mut self, project: impl FnOnce(&mut ProjectionScratch<N>) -> Outcome) -> Outcome {
        project(&mut self.general)
    }
}

/// [`super::project_constraints`] of one strand that [`fits_lanes`], by the lanes' kernel at
/// one lane: no row map, no grab, no padding row. `scratch` is the lanes' space, made once for
/// many strands: nothing in it carries from one strand to the next (`BlockProjection::run`
/// sets what it reads), and made for each strand, its zeros were 4 % of the Cortex-M4F's rod
/// step (`firmware/profile.py`).
#[inline(never)]
pub(crate) fn project_alone<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    scratch: &mut BlockProjection<N, 1, Natural>,
    report: &mut StepReport,
) -> Outcome {
    scratch.run::<M>(core::slice::from_ref(strand), &[true], ctx);
    scratch.finish::<M>(0, strand, ctx, report, None)
}

/// One lane's bookkeeping: what [`super::project_constraints`] keeps for its strand besides
/// the segment rows.
struct Lane<const N: usize> {
    nodes: Nodes<N>,
    /// The contacts (the segment rows live in the lanes: no capacity for them here).
    rows: Rows<N, 0>,
    contacts: ContactMemory<N>,
    collider_push: [Vec3; MAX_COLLIDERS],
    /// Segment 1's pull on the held node 1, × h² (`super::pull_on_root`).
    root_pull: Vec3,
    near: NearColliders,
    outcome: Outcome,
    truncated: bool,
    trust_radius: Real,
    /// Still iterating.
    running: bool,
}

/// The projection of up to `W` strands in lanes: run by [`BlockProjection::run`], then each
/// strand's result taken in scene order by [`BlockProjection::finish`].
pub struct BlockProjection<const N: usize, const W: usize, A: Alignment = Aligned> {
    taken: [bool; W],
    nodes: usize,
    position: [V3<Wide<W, A>>; N],
    inverse_mass: [Wide<W, A>; N],
    /// `ê^j·ê^j` per segment.
    rest_squared: [Wide<W, A>; N],
    /// Row `r` (segment `r + 1`): `C`, the right-hand side after the contacts' elimination,
    /// `∇C` at the segment's second node, and the blocks at its two nodes after it.
    value: [Wide<W, A>; N],
    rhs: [Wide<W, A>; N],
    gradient: [V3<Wide<W, A>>; N],
    projected: [[V3<Wide<W, A>>; 2]; N],
    multipliers: [Wide<W, A>; N],
    /// The chain's factor `L` below the diagonal and its solution in the making
    /// (`solve_chain`): written before they are read, kept here so that no solve zeroes them.
    lower: [Wide<W, A>; N],
    fresh: [Wide<W, A>; N],
    step: [V3<Wide<W, A>>; N],
    /// Whether the last evaluation took the chain's forward elimination on the way
    /// ([`Self::evaluate_and_eliminate`]); the pivots it dropped are then in `lower[0]`, which
    /// the first row has no use for.
    chained: bool,
    lanes: [Lane<N>; W],
}

impl<const N: usize, const W: usize, A: Alignment> Default for BlockProjection<N, W, A> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Lane<N> {
    /// A lane before its first use.
    const EMPTY: Self = Lane {
        nodes: Nodes {
            inverse_mass: [0.0; N],
            count: 0,
        },
        rows: Rows::new(),
        contacts: ContactMemory::new(),
        collider_push: [Vec3::ZERO; MAX_COLLIDERS],
        root_pull: Vec3::ZERO,
        near: NearColliders::none(),
        outcome: Outcome {
            iterations: 0,
            residual: 0.0,
            converged: false,
            dropped_rows: 0,
            collision_rows: 0,
            root_pull: Vec3::ZERO,
            collider_felt: Vec3::ZERO,
            grab_felt: Vec3::ZERO,
        },
        truncated: false,
        trust_radius: 0.0,
        running: false,
    };
}

impl<const N: usize, const W: usize, A: Alignment> BlockProjection<N, W, A> {
    /// A scratch space before its first use (`const`: a world keeps one, built at compile
    /// time, so that no step fills one).
    #[must_use]
    pub const fn new() -> Self {
        let zero = Wide::new([0.0; W]);
        let zero3 = <V3<Wide<W, A>> as Vector<Wide<W, A>>>::ZERO;
        BlockProjection {
            taken: [false; W],
            nodes: 0,
            position: [zero3; N],
            inverse_mass: [zero; N],
            rest_squared: [zero; N],
            value: [zero; N],
            rhs: [zero; N],
            gradient: [zero3; N],
            projected: [[zero3; 2]; N],
            multipliers: [zero; N],
            lower: [zero; N],
            fresh: [zero; N],
            step: [zero3; N],
            chained: false,
            lanes: [const { Lane::EMPTY }; W],
        }
    }
}

impl<const N: usize, const W: usize, A: Alignment> BlockProjection<N, W, A> {
    /// Projects the strands `taken` names (each [`fits_lanes`]) in lanes, in this scratch
    /// space (made once for many blocks: it is large); `false` if it names none. The strands
    /// keep their positions until [`Self::finish`].
    pub fn run<M: Math>(
        &mut self,
        strands: &[Strand<N>],
        taken: &[bool; W],
        ctx: &StepContext,
    ) -> bool {
        self.run_with::<M>(strands, taken, ctx, None)
    }

    /// [`Self::run`], and with `ending`, the ending of every lane measured in lanes
    /// ([`LaneEnding`]), for [`Self::finish`] to take.
    pub fn run_with<M: Math>(
        &mut self,
        strands: &[Strand<N>],
        taken: &[bool; W],
        ctx: &StepContext,
        mut ending: Option<&mut LaneEnding<N, W, A>>,
    ) -> bool {
        let Some(lead) = taken.iter().position(|&t| t).and_then(|f| strands.get(f)) else {
            return false;
        };
        self.taken = core::array::from_fn(|l| taken[l] && l < strands.len());
        // A lane left out computes a copy of the first strand taken, never read.
        let taken = self.taken;
        let source = |l: usize| strands.get(l).filter(|_| taken[l]).unwrap_or(lead);
        let nodes = lead.rest.nodes.min(N);
        self.nodes = nodes;
        let mut shape_count = 0;
        let shapes = usable_colliders(ctx, &mut shape_count);
        let shapes = shapes.get(..shape_count).unwrap_or(&[]);
        let layout = layout_of(ctx, shape_count);
        for (l, book) in self.lanes.iter_mut().enumerate() {
            let strand = source(l);
            book.nodes = free_nodes(strand, nodes);
            book.near
                .restart(strand, &book.nodes, shapes, layout.contact_slots > 0);
            book.contacts.forget();
            book.collider_push = [Vec3::ZERO; MAX_COLLIDERS];
            book.root_pull = Vec3::ZERO;
            book.outcome = Outcome::default();
            book.truncated = false;
            book.trust_radius = trust_radius(strand, nodes);
            book.running = taken[l];
            for i in 0..nodes {
                self.position[i].set_lane(l, strand.state.position[i]);
                self.inverse_mass[i].0[l] = book.nodes.inverse_mass[i];
                let rest = strand.rest.segment_length[i];
                self.rest_squared[i].0[l] = rest * rest;
                if let Some(ending) = ending.as_deref_mut() {
                    ending.rest_length[i].0[l] = rest;
                }
            }
        }
        if let Some(ending) = ending.as_deref_mut() {
            ending.predicted[..nodes].copy_from_slice(&self.position[..nodes]);
        }
        self.iterate::<M>(strands, ctx, shapes, layout);
        if let Some(ending) = ending {
            ending.measure::<M>(self, ctx.inv_dt);
        }
        true
    }

    /// Lane `lane`'s strand takes its projected positions, keeps them finite, updates its
    /// velocities and reports, as [`super::project_constraints`] ends: with what `ending`
    /// measured in the lanes when [`Self::run_with`] took it, else strand by strand.
    pub fn finish<M: Math>(
        &self,
        lane: usize,
        strand: &mut Strand<N>,
        ctx: &StepContext,
        report: &mut StepReport,
        ending: Option<&LaneEnding<N, W, A>>,
    ) -> Outcome {
        let Some(book) = self.lanes.get(lane).filter(|_| self.taken[lane]) else {
            return Outcome::default();
        };
        report.ran(Stage::Projection);
        if ctx.has(Effect::Collisions) {
            report.ran(Stage::Collisions);
        }
        let n = self.nodes;
        let findings = Findings {
            touched: &book.contacts.touched,
            max_depth: book.rows.max_depth,
            truncated: book.truncated,
            collider_push: &book.collider_push,
        };
        let root_pull = book.root_pull * (ctx.inv_dt * ctx.inv_dt);
        let Some(concluded) = ending.map(|e| &e.concluded).filter(|c| c.finite[lane]) else {
            // Measured strand by strand (one strand alone), or an overflow on absurd input
            // (rare): the strand's own ending, which keeps the positions it came in with if
            // need be.
            let predicted = strand.state.position;
            for (x, lanes) in strand.state.position.iter_mut().zip(&self.position).take(n) {
                *x = lanes.lane(lane);
            }
            let outcome = conclude::<M, N>(strand, &predicted, ctx, book.outcome, findings, report);
            return Outcome {
                root_pull,
                ..outcome
            };
        };
        // `conclude`, with what `LaneEnding::measure` measured in lanes: the same bits.
        let state = &mut strand.state;
        for (x, lanes) in state.position.iter_mut().zip(&self.position).take(n) {
            *x = lanes.lane(lane);
        }
        report.ran(Stage::Velocity);
        let free = 2.min(n)..n;
        let velocity = state.velocity.get_mut(free.clone()).unwrap_or(&mut []);
        for (v, change) in velocity.iter_mut().zip(self.step.get(free).unwrap_or(&[])) {
            *v += change.lane(lane);
        }
        record_outcome(ctx, &book.outcome, &findings, n, report);
        report.max_stretch = math::max(report.max_stretch, concluded.free_stretch[lane]);
        let at_contacts = concluded.contact_stretch[lane];
        report.max_contact_stretch = math::max(report.max_contact_stretch, at_contacts);
        Outcome {
            root_pull,
            collider_felt: felt_by_colliders(ctx, &book.collider_push),
            ..book.outcome
        }
    }

    /// `super::iterate` in lanes: evaluate, test, solve, move, each lane until it stops.
    fn iterate<M: Math>(
        &mut self,
        strands: &[Strand<N>],
        ctx: &StepContext,
        shapes: &[(u8, Shape)],
        layout: Layout,
    ) {
        let cap = u32::from(ctx.params.rod.projection_iterations);
        let tolerance = ctx.params.rod.projection_tolerance;
        let fixed_cost = ctx.params.mode == Mode::FixedCost;
        for k in 0..=cap {
            // After the last solve only the residual is wanted: no rows.
            let layout = Layout {
                residual_only: k == cap,
                ..layout
            };
            self.evaluate::<M>(strands, shapes, layout, tolerance);
            let mut any = false;
            for book in self.lanes.iter_mut().filter(|b| b.running) {
                book.truncated |= book.rows.truncated;
                book.outcome.residual = book.rows.residual;
                book.outcome.converged = book.rows.converged;
                book.running = !(k == cap || (book.outcome.converged && !fixed_cost));
                if book.running {
                    book.outcome.collision_rows += book.rows.collision_rows();
                }
                any |= book.running;
            }
            if !any {
                break;
            }
            self.solve_and_move::<M>();
            if fixed_cost {
                self.measure_stopped(strands, k, tolerance);
            }
        }
    }

    /// In fixed cost, the segments' share of the residual of each lane that stopped in
    /// iteration `k` before its last (its multipliers or moves not finite), at the positions
    /// it keeps: its evaluation skipped it (`Layout::measures_segments`).
    fn measure_stopped(&mut self, strands: &[Strand<N>], k: u32, tolerance: Real) {
        let position = &self.position;
        for (l, book) in self.lanes.iter_mut().enumerate() {
            if book.running || book.outcome.iterations != k || !self.taken[l] {
                continue;
            }
            let Some(strand) = strands.get(l) else {
                continue;
            };
            let at = |i: usize| position[i].lane(l);
            let rest_length = &strand.rest.segment_length;
            measure_segments(at, rest_length, &book.nodes, tolerance, &mut book.rows);
            book.outcome.residual = book.rows.residual;
            book.outcome.converged = book.rows.converged;
        }
    }

    /// `constraints::evaluate` in lanes: each running lane's contacts, then the segment rows
    /// of all lanes and their share of each running lane's residual.
    fn evaluate<M: Math>(
        &mut self,
        strands: &[Strand<N>],
        shapes: &[(u8, Shape)],
        layout: Layout,
        tolerance: Real,
    ) {
        let position = &self.position;
        for (l, book) in self.lanes.iter_mut().enumerate() {
            let Some(strand) = strands.get(l).filter(|_| book.running) else {
                continue;
            };
            let at = |i: usize| position[i].lane(l);
            let rest_length = &strand.rest.segment_length;
            let near = book.near.shapes(shapes);
            let found = (&mut book.contacts, &mut book.rows);
            let nodes = &book.nodes;
            evaluate_contacts::<M, N, 0>((at, rest_length), nodes, near, layout, tolerance, found);
        }
        let two = Wide::new([2.0; W]);
        let mut met = Met {
            residual: core::array::from_fn(|l| self.lanes[l].rows.residual),
            converged: core::array::from_fn(|l| self.lanes[l].rows.converged),
        };
        // In fixed cost, with no contact in a running lane, nothing changes the rows between
        // their evaluation and the chain's forward elimination: both run in one pass.
        let contacts = self
            .lanes
            .iter()
            .any(|b| b.running && b.rows.contact_count > 0);
        self.chained = layout.fixed_cost && !layout.residual_only && !contacts;
        if self.chained {
            self.evaluate_and_eliminate(layout, tolerance, &mut met);
        } else {
            for j in 1..self.nodes.saturating_sub(1) {
                let (a, b) = (self.position[j], self.position[j + 1]);
                let e = b - a;
                let rest2 = self.rest_squared[j];
                let value = e.dot(e) - rest2;
                if !layout.residual_only {
                    let r = j - 1;
                    let gradient = e * two;
                    self.value[r] = value;
                    self.rhs[r] = value;
                    self.gradient[r] = gradient;
                    self.projected[r] = [-gradient, gradient];
                }
                if layout.measures_segments() {
                    met.meet(value, rest2, tolerance, (a, b));
                }
            }
        }
        for (l, book) in self.lanes.iter_mut().enumerate() {
            if book.running {
                book.rows.residual = met.residual[l];
                book.rows.converged = met.converged[l];
            }
        }
    }

    /// `super::solve_and_move` in lanes: the multipliers, then each running lane's move
    /// (within its trust radius) and its contacts' push; a lane whose multipliers or moves are
    /// not finite stops where it is.
    fn solve_and_move<M: Math>(&mut self) {
        let n = self.nodes;
        let (dropped, finite) = self.solve();
        let mut moving = WideMask::from_bools([false; W]);
        for (l, book) in self.lanes.iter_mut().enumerate() {
            if !book.running {
                continue;
            }
            if finite[l] {
                moving.set(l, true);
            } else {
                book.outcome.dropped_rows += 1;
                book.running = false;
            }
        }
        let (any_contact, longest2) = self.moves(moving);
        let mut scale = Wide::new([1.0; W]);
        for (l, book) in self.lanes.iter_mut().enumerate() {
            if !moving.get(l) {
                continue;
            }
            if longest2[l].is_finite() {
                scale.0[l] = trust_scale::<M>(longest2[l], book.trust_radius);
            } else {
                book.outcome.dropped_rows += 1;
                book.running = false;
                moving.set(l, false);
            }
        }
        // Most iterations move every lane within its trust radius: `x + Δx · 1` is `x + Δx`
        // to the bit, with no product and no select.
        let whole_moves = moving.to_bools().iter().all(|&m| m) && scale.0.iter().all(|&s| s == 1.0);
        if whole_moves {
            for (x, dx) in self.position.iter_mut().zip(&self.step).take(n) {
                *x += *dx;
            }
        } else {
            for (x, dx) in self.position.iter_mut().zip(&self.step).take(n) {
                *x = V3::select(moving, *x + *dx * scale, *x);
            }
        }
        for (l, book) in self.lanes.iter_mut().enumerate() {
            if !moving.get(l) {
                continue;
            }
            // `super::pull_on_root`: row 0 is segment 1, whose gradient at node 1 is `−∇C`
            // at node 2.
            let at_root = -self.gradient[0].lane(l);
            book.root_pull -= at_root * (self.multipliers[0].0[l] * scale.0[l]);
            if any_contact[l] {
                let (gradient, multipliers) = (&self.gradient, &self.multipliers);
                let pull = |_: &Rows<N, 0>, i| segment_pull(gradient, multipliers, n, i, l);
                let memory = (&mut book.contacts, &mut book.collider_push);
                let inverse_mass = &book.nodes.inverse_mass;
                push_on_colliders(&book.rows, memory, inverse_mass, n, scale.0[l], pull);
            }
            book.outcome.dropped_rows += dropped[l];
            book.near.moved::<M>(longest2[l]);
            book.outcome.iterations += 1;
        }
    }

    /// `Δx` of every node into `step`: from the segments (`−w_i (I − P_i) ∇_iC δλ` over the
    /// two segments through node `i`, segment `i − 1` first; nodes 0 and 1 are prescribed),
    /// then in the lanes `moving` names from the node's contacts (`−d_i`). Returns, per lane,
    /// whether a node moved by its contacts and the longest move (squared).
    fn moves(&mut self, moving: WideMask<W>) -> ([bool; W], [Real; W]) {
        self.segment_moves();
        let n = self.nodes;
        let mut any_contact = [false; W];
        for (l, book) in self.lanes.iter().enumerate() {
            if !moving.get(l) {
                continue;
            }
            for &i in book.rows.contact_nodes() {
                let i = usize::from(i);
                let contacts = &book.rows.contacts[i];
                if contacts.kept > 0 && i < n {
                    let delta = self.step[i].lane(l) - contacts.displacement;
                    self.step[i].set_lane(l, delta);
                    any_contact[l] = true;
                }
            }
        }
        let mut longest2 = [0.0 as Real; W];
        for dx in &self.step[..n] {
            let d2 = dx.dot(*dx);
            for (longest, &d2) in longest2.iter_mut().zip(d2.0.iter()) {
                // Not `max`, which would drop a NaN.
                if d2.is_nan() || d2 > *longest {
                    *longest = d2;
                }
            }
        }
        (any_contact, longest2)
    }

    /// The segments' share of `Δx`: from the blocks the contacts' elimination left, or, after
    /// [`Self::evaluate_and_eliminate`], from the gradients (without contacts the blocks are
    /// `∓∇C`, and negation is exact: the same bits).
    fn segment_moves(&mut self) {
        let (step, w, m) = (&mut self.step, &self.inverse_mass, &self.multipliers);
        if self.chained {
            let gradient = &self.gradient;
            segment_moves_of(step, self.nodes, (w, m), |r| [-gradient[r], gradient[r]]);
        } else {
            let projected = &self.projected;
            segment_moves_of(step, self.nodes, (w, m), |r| projected[r]);
        }
    }

    /// `super::solve` in lanes: each running lane's contacts eliminated at their nodes, the
    /// chain solved in lanes, tentative rows that pull removed and the lane solved again.
    /// Returns each lane's rows dropped at a singular pivot in its last solve, and whether
    /// its multipliers are finite.
    fn solve(&mut self) -> ([u32; W], [bool; W]) {
        let n = self.nodes;
        let mut solving = WideMask::from_bools(core::array::from_fn(|l| self.lanes[l].running));
        let mut dropped = [0; W];
        let mut finite = [false; W];
        for pass in 0..4 {
            // After an evaluation that took the forward elimination (no contacts: nothing to
            // eliminate, no tentative row), only the backward half is left.
            // (`dropped` is still all zero in pass 0.)
            let chain = if self.chained && pass == 0 {
                self.back_substitute(solving, self.lower[0])
            } else {
                for (l, dropped) in dropped.iter_mut().enumerate() {
                    if solving.get(l) {
                        *dropped = self.eliminate_contacts(l);
                    }
                }
                self.solve_chain(solving)
            };
            let mut again = false;
            for (l, dropped) in dropped.iter_mut().enumerate() {
                if !solving.get(l) {
                    continue;
                }
                *dropped += chain[l];
                let count = n.saturating_sub(2);
                finite[l] = self.multipliers[..count].iter().all(|m| m.0[l].is_finite());
                let book = &mut self.lanes[l];
                if !book.rows.tentative || !finite[l] {
                    solving.set(l, false);
                    continue;
                }
                let (gradient, multipliers) = (&self.gradient, &self.multipliers);
                let pull = |_: &Rows<N, 0>, i| segment_pull(gradient, multipliers, n, i, l);
                let inverse_mass = &book.nodes.inverse_mass;
                if !prune_tentative(&mut book.rows, inverse_mass, n, pass >= 2, pull) {
                    solving.set(l, false);
                    continue;
                }
                self.undo_elimination(l);
                again = true;
            }
            if !again {
                break;
            }
        }
        (dropped, finite)
    }

    /// `banded::eliminate_contacts` on lane `lane`: its contact nodes' collision rows
    /// eliminated, their effect left on the segment rows through them.
    fn eliminate_contacts(&mut self, lane: usize) -> u32 {
        let n = self.nodes;
        let rows = &mut self.lanes[lane].rows;
        let mut dropped = 0;
        for k in 0..rows.contact_count.min(N) {
            let i = usize::from(rows.contact_nodes[k]);
            if i >= n {
                continue;
            }
            let Some(contacts) = rows.contacts.get_mut(i) else {
                continue;
            };
            dropped += eliminate_at_node(contacts);
            // The segments through node i: i − 1 (node i is its second) and i (its first).
            for (segment, block) in [(i.wrapping_sub(1), 1), (i, 0)] {
                if !(1..n.saturating_sub(1)).contains(&segment) {
                    continue;
                }
                let r = segment - 1;
                let gradient = self.gradient[r].lane(lane);
                let g = if block == 0 { -gradient } else { gradient };
                let mut rhs = self.rhs[r].0[lane];
                let projected = eliminate_from_segment(contacts, g, &mut rhs);
                self.rhs[r].0[lane] = rhs;
                self.projected[r][block].set_lane(lane, projected);
            }
        }
        dropped
    }

    /// `banded::undo_elimination` on lane `lane`.
    fn undo_elimination(&mut self, lane: usize) {
        let count = self.nodes.saturating_sub(2);
        for r in 0..count {
            self.rhs[r].0[lane] = self.value[r].0[lane];
            let gradient = self.gradient[r].lane(lane);
            self.projected[r][0].set_lane(lane, -gradient);
            self.projected[r][1].set_lane(lane, gradient);
        }
    }

    /// `banded::solve_chain` in lanes on the uniform chain (row `r` couples to `r − 1`),
    /// into the multipliers of the lanes `solving` names. Returns each lane's dropped pivots.
    fn solve_chain(&mut self, solving: WideMask<W>) -> [u32; W] {
        let count = self.nodes.saturating_sub(2);
        let w = &self.inverse_mass;
        let mut forward = Forward::START;
        for r in 0..count {
            let coupled = if r > 0 {
                Some(self.projected[r - 1][1])
            } else {
                None
            };
            let masses = (w[r + 1], w[r + 2]);
            let (lower, fresh) = forward.row(self.projected[r], masses, self.rhs[r], coupled);
            if r > 0 {
                self.lower[r] = lower;
            }
            self.fresh[r] = fresh;
        }
        self.back_substitute(solving, forward.dropped)
    }

    /// The backward half of the chain's solve, `Lᵀ y = u`, after its forward elimination
    /// ([`Self::solve_chain`]'s or [`Self::evaluate_and_eliminate`]'s) dropped `dropped`
    /// pivots: the multipliers of the lanes `solving` names. Returns each lane's dropped
    /// pivots.
    fn back_substitute(&mut self, solving: WideMask<W>, dropped: Wide<W, A>) -> [u32; W] {
        let count = self.nodes.saturating_sub(2);
        let fresh = &mut self.fresh;
        for r in (1..count).rev() {
            let y = fresh[r];
            fresh[r - 1] -= self.lower[r] * y;
        }
        // Most solves take every lane: a copy, no select.
        if <Wide<W, A> as lane::Lane>::all(solving) {
            self.multipliers[..count].copy_from_slice(&fresh[..count]);
        } else {
            for (old, &new) in self.multipliers.iter_mut().zip(fresh.iter()).take(count) {
                *old = lane::Lane::select(solving, new, *old);
            }
        }
        dropped.0.map(|d| d as u32)
    }

    /// The segment rows' evaluation (as [`Self::evaluate`] without `residual_only`) and the
    /// forward elimination of [`Self::solve_chain`] in one pass, for lanes without contacts:
    /// each row's blocks are `∓∇C` and its right-hand side `C`, so the rows stay in registers
    /// and only the gradients, `L` and `z/D` are stored; the same operations on the same
    /// values, so the same bits. Out of line: only fixed cost takes it.
    #[inline(never)]
    fn evaluate_and_eliminate(&mut self, layout: Layout, tolerance: Real, met: &mut Met<W>) {
        let two = Wide::new([2.0; W]);
        let n = self.nodes.min(N);
        let mut forward = Forward::START;
        let mut above = V3::zero();
        for j in 1..n.saturating_sub(1) {
            let (a, b) = (self.position[j], self.position[j + 1]);
            let e = b - a;
            let rest2 = self.rest_squared[j];
            let value = e.dot(e) - rest2;
            let r = j - 1;
            let gradient = e * two;
            self.gradient[r] = gradient;
            let masses = (self.inverse_mass[j], self.inverse_mass[j + 1]);
            let coupled = (r > 0).then_some(above);
            let (lower, fresh) = forward.row([-gradient, gradient], masses, value, coupled);
            if r > 0 {
                self.lower[r] = lower;
            }
            self.fresh[r] = fresh;
            above = gradient;
            if layout.measures_segments() {
                met.meet(value, rest2, tolerance, (a, b));
            }
        }
        self.lower[0] = forward.dropped;
    }
}

/// The forward elimination of the chain's `L D Lᵀ`, root → tip, a row at a time: what
/// [`BlockProjection::solve_chain`] and [`BlockProjection::evaluate_and_eliminate`] share.
#[derive(Clone, Copy)]
struct Forward<const W: usize, A: Alignment> {
    /// `D`, `1/D` and `z` of the previous row.
    d_above: Wide<W, A>,
    inverse_above: Wide<W, A>,
    z_above: Wide<W, A>,
    /// Pivots dropped so far, counted in the lanes (exact below 2^24 rows).
    dropped: Wide<W, A>,
}

impl<const W: usize, A: Alignment> Forward<W, A> {
    const START: Self = Forward {
        d_above: Wide::new([0.0; W]),
        inverse_above: Wide::new([0.0; W]),
        z_above: Wide::new([0.0; W]),
        dropped: Wide::new([0.0; W]),
    };

    /// The next row: blocks `[p0, p1]` at its two nodes (inverse masses `w0`, `w1`),
    /// right-hand side `rhs`, and `coupled`, the previous row's block at the node they share
    /// (none for the first row). Returns its `L` below the diagonal (zero for the first row)
    /// and `z/D`.
    #[inline(always)]
    fn row(
        &mut self,
        [p0, p1]: [V3<Wide<W, A>>; 2],
        (w0, w1): (Wide<W, A>, Wide<W, A>),
        rhs: Wide<W, A>,
        coupled: Option<V3<Wide<W, A>>>,
    ) -> (Wide<W, A>, Wide<W, A>) {
        let diagonal = w0 * p0.dot(p0) + w1 * p1.dot(p1);
        let mut z = rhs;
        let mut d = diagonal;
        let mut lower = Wide::new([0.0; W]);
        if let Some(above) = coupled {
            let below = w0 * p0.dot(above);
            lower = below * self.inverse_above;
            d -= lower * lower * self.d_above;
            z -= lower * self.z_above;
        }
        // A pivot not clearly positive is dropped (`banded::factor`); NaN is not kept.
        // Written without branches, `&` not `&&`, so that the lanes stay in registers.
        let kept: [bool; W] = core::array::from_fn(|l| {
            let (diagonal, d) = (diagonal.0[l], d.0[l]);
            (diagonal > 0.0) & (d > PIVOT_RATIO * diagonal) & d.is_finite()
        });
        self.dropped += Wide::new(kept.map(|k| if k { 0.0 } else { 1.0 }));
        let d = Wide::new(core::array::from_fn(|l| if kept[l] { d.0[l] } else { 0.0 }));
        // `banded::reciprocal`: 1/d for a kept pivot, 0 for a dropped one.
        let inverse = Wide::new(core::array::from_fn(|l| {
            let (d, reciprocal) = (d.0[l], 1.0 / d.0[l]);
            if d > 0.0 {
                reciprocal
            } else {
                0.0
            }
        }));
        (self.d_above, self.inverse_above, self.z_above) = (d, inverse, z);
        (lower, z * inverse)
    }
}

/// `Δx` of the first `nodes` nodes from the segments through them: `−w_i Σ p δλ` over the
/// blocks `p` of the rows at node `i` (`blocks(r)`: row `r`'s at its first and second node),
/// segment `i − 1` first, with the inverse masses and multipliers `(w, m)`. The loop is split
/// where a node's segments change (nodes 0 and 1 prescribed, the tip on one segment), so that
/// the interior runs without branches: the same operations.
#[inline(always)]
fn segment_moves_of<const N: usize, const W: usize, A: Alignment>(
    step: &mut [V3<Wide<W, A>>; N],
    nodes: usize,
    (w, m): (&[Wide<W, A>; N], &[Wide<W, A>; N]),
    blocks: impl Fn(usize) -> [V3<Wide<W, A>>; 2],
) {
    let n = nodes.min(N);
    for step in step.iter_mut().take(n.min(2)) {
        *step = V3::zero();
    }
    for i in 2..n.saturating_sub(1) {
        let mut delta = V3::zero();
        delta -= blocks(i - 2)[1] * (w[i] * m[i - 2]);
        delta -= blocks(i - 1)[0] * (w[i] * m[i - 1]);
        step[i] = delta;
    }
    if n >= 3 {
        let i = n - 1;
        let mut delta = V3::zero();
        delta -= blocks(i - 2)[1] * (w[i] * m[i - 2]);
        step[i] = delta;
    }
}

/// The ending of a block's projection (`super::conclude`) measured in its lanes, for all its
/// strands at once: what the blocks of the harness keep beside their [`BlockProjection`]. One
/// strand alone ends strand by strand: at one lane the copies cost more than they save, and
/// the world's scratch space (`RodScratch`, inside `hairsim_init`'s buffer) would grow by
/// `|ê|`, `x̃` and the findings for nothing.
pub struct LaneEnding<const N: usize, const W: usize, A: Alignment = Aligned> {
    /// `|ê^j|` per segment.
    rest_length: [Wide<W, A>; N],
    /// The positions the projection started from (`x̃`; the strands keep them until
    /// [`BlockProjection::finish`]).
    predicted: [V3<Wide<W, A>>; N],
    /// What [`Self::measure`] found.
    concluded: Concluded<W>,
}

impl<const N: usize, const W: usize, A: Alignment> LaneEnding<N, W, A> {
    /// Before its first use.
    #[must_use]
    pub const fn new() -> Self {
        LaneEnding {
            rest_length: [Wide::new([0.0; W]); N],
            predicted: [<V3<Wide<W, A>> as Vector<Wide<W, A>>>::ZERO; N],
            concluded: Concluded {
                finite: [false; W],
                free_stretch: [0.0; W],
                contact_stretch: [0.0; W],
            },
        }
    }

    /// The end of [`super::conclude`] that the lanes can share, for every lane of
    /// `projection` at once: the velocity change `(x − x̃)/h` of each node (into its `step`,
    /// which the iterations are done with), whether all of a lane's are finite, and the
    /// lane's largest stretch away from and at contacts (`super::record`'s, by the same
    /// operations; a maximum does not depend on the order its values come in).
    fn measure<M: Math>(&mut self, projection: &mut BlockProjection<N, W, A>, inv_dt: Real) {
        let n = projection.nodes.min(N);
        let inv_dt = Wide::splat(inv_dt);
        let mut finite = WideMask::from_bools([true; W]);
        let (position, step) = (&projection.position, &mut projection.step);
        for ((change, &x), &predicted) in step.iter_mut().zip(position).zip(&self.predicted).take(n)
        {
            *change = (x - predicted) * inv_dt;
            finite = finite & change.finite();
        }
        let lanes = &projection.lanes;
        let touched = |l: usize, i: usize| lanes[l].contacts.touched[i] != 0;
        let any_touched = (0..W).any(|l| (0..n).any(|i| touched(l, i)));
        let zero = Wide::splat(0.0);
        let (mut free, mut contact) = (zero, zero);
        for j in 0..n.saturating_sub(1) {
            let e = position[j + 1] - position[j];
            let stretch = segment_stretch::<M, Wide<W, A>>(e, self.rest_length[j]);
            if any_touched {
                let at_contact = WideMask::from_bools(core::array::from_fn(|l| {
                    touched(l, j) || touched(l, j + 1)
                }));
                contact = contact.max_where(at_contact, stretch);
                free = free.max_where(!at_contact, stretch);
            } else {
                free = free.max(stretch);
            }
        }
        self.concluded = Concluded {
            finite: finite.to_bools(),
            free_stretch: free.0,
            contact_stretch: contact.0,
        };
    }
}

impl<const N: usize, const W: usize, A: Alignment> Default for LaneEnding<N, W, A> {
    fn default() -> Self {
        Self::new()
    }
}

/// What [`LaneEnding::measure`] measured of each lane.
#[derive(Clone, Copy)]
struct Concluded<const W: usize> {
    /// Whether every node's velocity change is finite.
    finite: [bool; W],
    /// The largest stretch `||e| − |ê|| / |ê|` of a segment with no node in contact, and of
    /// one with a node in contact.
    free_stretch: [Real; W],
    contact_stretch: [Real; W],
}

/// Each lane's residual and convergence so far in an evaluation.
struct Met<const W: usize> {
    residual: [Real; W],
    converged: [bool; W],
}

impl<const W: usize> Met<W> {
    /// `Rows::meet` in every lane for the segment from `a` to `b` (`C = value`, `ê·ê =
    /// rest2`), the same operations without branches but for the resolution floor (only while
    /// a lane is converged and a row exceeds the tolerance, once an evaluation at most).
    #[inline(always)]
    fn meet<A: Alignment>(
        &mut self,
        value: Wide<W, A>,
        rest2: Wide<W, A>,
        tolerance: Real,
        (a, b): Ends<W, A>,
    ) {
        let mut floor_wanted = false;
        for l in 0..W {
            let (magnitude, rest2) = (value.0[l].abs(), rest2.0[l]);
            let residual = self.residual[l];
            let relative = magnitude / rest2;
            let larger = (magnitude > residual * rest2) | magnitude.is_nan();
            let take = larger & (relative.is_nan() | (relative > residual));
            self.residual[l] = if take { relative } else { residual };
            floor_wanted |= self.converged[l] & (magnitude > tolerance * rest2);
        }
        if !floor_wanted {
            return;
        }
        for l in 0..W {
            let (magnitude, rest2) = (value.0[l].abs(), rest2.0[l]);
            if self.converged[l] && magnitude > tolerance * rest2 {
                let floor = resolution_floor(false, a.lane(l), b.lane(l), 0.0).min(0.01 * rest2);
                self.converged[l] = magnitude <= floor;
            }
        }
    }
}

/// A segment's two nodes in lanes.
type Ends<const W: usize, A> = (V3<Wide<W, A>>, V3<Wide<W, A>>);

/// `Σ_s ∇_{x_i}C_s δλ_s` over the segments through node `i` in lane `lane`, with the
/// gradients before the elimination (`super::segment_pull_on_node` of that strand).
fn segment_pull<const N: usize, const W: usize, A: Alignment>(
    gradient: &[V3<Wide<W, A>>; N],
    multipliers: &[Wide<W, A>; N],
    n: usize,
    i: usize,
    lane: usize,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for (segment, block) in [(i.wrapping_sub(1), 1), (i, 0)] {
        if !(1..n.saturating_sub(1)).contains(&segment) {
            continue;
        }
        let r = segment - 1;
        let g = gradient[r].lane(lane);
        let g = if block == 0 { -g } else { g };
        sum += g * multipliers[r].0[lane];
    }
    sum
}
