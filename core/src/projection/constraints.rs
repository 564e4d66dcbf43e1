//! The constraints of the fast manifold projection (Kmoch 2009 Sec. 8.1): each kind gives its
//! value `C(x)` and its gradient `∇C(x)`, and [`evaluate`] lays them out so that
//! `∇C M⁻¹ ∇Cᵀ` stays banded.
//!
//! * Inextensibility of segment `j`: `C = e^j·e^j − ê^j·ê^j`, `∇_{x_{j+1}}C = 2e^jᵀ = −∇_{x_j}C`.
//! * Collision of node `i` with a sphere or capsule: `C = |x_i − c|² − r²`, `∇C = 2(x_i − c)ᵀ`
//!   (`c` the centre, or the closest point of the capsule's axis; the row uses the secant
//!   slope `(|x_i − c| + r) n`, equal to it on the surface — see [`contact`]); with a plane:
//!   `C = (x_i − p)·n`, `∇C = nᵀ`. Only for nodes found inside, re-detected at every iterate
//!   (in converge mode also tentative rows for nodes just outside, see [`evaluate`]).
//! * Root coupling and grabs have no rows: their nodes are prescribed (`w = 0`). A row on a
//!   node of infinite mass is a zero row and makes the matrix singular, so prescribed nodes
//!   never carry a collision row, and a segment between two prescribed nodes has no row.
//!
//! Ordered `[contacts of node 0], C_0, [contacts of node 1], C_1, …` the half-bandwidth is
//! 1 + the most contacts on one node. A collision row touches one node only, so eliminating
//! it first (its LDLᵀ pivot taken before the segments') fills nothing outside the segments'
//! tridiagonal band: the segments that share the node see it as a node whose inverse mass is
//! projected onto the contact's tangent space ([`super::banded::eliminate_contacts`]). So the
//! segment rows are kept in band order with their envelopes, and each node keeps its
//! collision rows beside it ([`NodeContacts`]); collisions then cost in proportion to the
//! contacts and never widen the band.

use crate::collide::{Shape, MAX_COLLIDERS};
use crate::math::{Math, Real, Vec3};
use crate::strand::Strand;

/// Most collision rows one node carries per iteration; further contacts of the same node (in
/// collider order) are left out that iteration and flagged.
pub const MAX_NODE_CONTACTS: usize = 2;

/// "No row" in [`Rows::segment_row`].
pub const NO_ROW: u16 = u16::MAX;

/// What a row constrains. Four bytes wide, so that a [`Row`] has no padding and an array of
/// default rows is one zero fill (with a one-byte tag the Cortex-M4F build cleared each row
/// with a call of its own, around the padding).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u32)]
pub enum RowKind {
    /// A placeholder that keeps the layout fixed (fixed-cost mode): `A_rr = 1`, `C = 0`.
    #[default]
    Padding,
    /// Inextensibility of the segment from `nodes[0]` to `nodes[1]`.
    Segment,
}

/// One segment row: its value and gradient, and the gradient's two 3-blocks after the collision
/// rows of its nodes were eliminated. The gradient is stored once: its blocks are `∓2e`
/// (see [`Row::gradient_at`]), and negation is exact, so nothing changes but the size.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Row {
    /// `C(x_k)`.
    pub value: Real,
    /// The right-hand side after eliminating collision rows: `C − Σ_i ∇_{x_i}C · d_i`.
    pub rhs: Real,
    /// The two nodes of the segment.
    pub nodes: [u16; 2],
    /// `∇_{x_{nodes[1]}} C = 2e`; `∇_{x_{nodes[0]}} C` is its negation.
    pub gradient: Vec3,
    /// The gradient blocks with each node's contact normals projected out, `(I − P_i)∇C`
    /// (equal to `gradient` at a node without contact).
    pub projected: [Vec3; 2],
    /// What the row constrains.
    pub kind: RowKind,
}

impl Row {
    /// [`Row::default`], as a constant.
    pub const EMPTY: Row = Row {
        value: 0.0,
        rhs: 0.0,
        nodes: [0; 2],
        gradient: Vec3::ZERO,
        projected: [Vec3::ZERO; 2],
        kind: RowKind::Padding,
    };

    /// Inextensibility of segment `j` (nodes `j`, `j + 1`): `C = e·e − ê·ê`.
    #[must_use]
    pub fn segment(j: usize, x_j: Vec3, x_next: Vec3, rest_length: Real) -> Row {
        let e = x_next - x_j;
        let value = e.dot(e) - rest_length * rest_length;
        let gradient = e * 2.0;
        Row {
            value,
            rhs: value,
            nodes: [j as u16, (j + 1) as u16],
            gradient,
            projected: [-gradient, gradient],
            kind: RowKind::Segment,
        }
    }

    /// `∇_{x_{nodes[block]}} C`: `−2e` for block 0, `2e` for block 1 (bit for bit what
    /// `e * -2.0` gives).
    #[inline(always)]
    #[must_use]
    pub fn gradient_at(&self, block: usize) -> Vec3 {
        if block == 0 {
            -self.gradient
        } else {
            self.gradient
        }
    }

    /// Both blocks of the gradient, `[∇_{x_{nodes[0]}} C, ∇_{x_{nodes[1]}} C]`.
    #[inline(always)]
    #[must_use]
    pub fn gradients(&self) -> [Vec3; 2] {
        [-self.gradient, self.gradient]
    }
}

/// Value and gradient of the collision row of a node found `depth` inside `shape` (negative
/// when outside: a contact kept from an earlier iterate) with outward `normal`.
#[must_use]
pub fn contact(shape: &Shape, normal: Vec3, depth: Real) -> (Real, Vec3) {
    match *shape {
        Shape::Sphere { radius, .. } | Shape::Capsule { radius, .. } => {
            // d = |x − c| = r − depth; C = d² − r² = −depth (d + r). The gradient 2(x − c) =
            // 2d·n would send a Newton step to (d² + r²)/(2d) from the centre: five radii out
            // from d = r/10, infinitely far from d = 0. The secant slope (d + r)·n between
            // the node and its surface point lands the step on the surface for any depth
            // (the centre included) and equals 2(x − c) there, at the solution.
            let distance = radius - depth;
            (-depth * (distance + radius), normal * (distance + radius))
        }
        Shape::Plane { .. } => (-depth, normal),
    }
}

/// The collision rows of one node, and what eliminating them leaves for the segments.
///
/// The small fields are `u16` (with the two `u8` colliders: eight bytes) so that the struct
/// has no padding: an array of defaults is then one zero fill, where padding made the
/// Cortex-M4F build clear each node's entry with a call of its own.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodeContacts {
    /// Rows in use (≤ [`MAX_NODE_CONTACTS`]).
    pub count: u16,
    /// The collider of each row (its index in the step's list).
    pub collider: [u8; MAX_NODE_CONTACTS],
    /// `C` of each row.
    pub value: [Real; MAX_NODE_CONTACTS],
    /// `∇_{x_i}C` of each row.
    pub gradient: [Vec3; MAX_NODE_CONTACTS],
    /// Rows kept by the elimination (a row whose gradient depends on the first is dropped).
    pub kept: u16,
    /// `(GᵀG)⁻¹` of the kept gradients `G`, as `[a₀₀, a₀₁, a₁₁]`.
    pub inverse_gram: [Real; 3],
    /// `d = G (GᵀG)⁻¹ C`: minus the smallest move that meets the linearised contacts.
    pub displacement: Vec3,
    /// Bit `k`: row `k` is *tentative* — its node is outside the collider, within
    /// [`CONTACT_MARGIN`] of it (see [`evaluate`]); it stays only if its multiplier pushes.
    pub tentative: u16,
}

impl NodeContacts {
    /// [`NodeContacts::default`], as a constant.
    pub const EMPTY: NodeContacts = NodeContacts {
        count: 0,
        collider: [0; MAX_NODE_CONTACTS],
        value: [0.0; MAX_NODE_CONTACTS],
        gradient: [Vec3::ZERO; MAX_NODE_CONTACTS],
        kept: 0,
        inverse_gram: [0.0; 3],
        displacement: Vec3::ZERO,
        tentative: 0,
    };

    fn push(&mut self, collider: u8, value: Real, gradient: Vec3, tentative: bool) -> bool {
        let mut k = usize::from(self.count);
        if k >= MAX_NODE_CONTACTS && !tentative && self.tentative != 0 {
            // A contact found inside takes the place of a tentative one.
            k = self.tentative.trailing_zeros() as usize;
            self.tentative &= !(1 << k);
            self.count -= 1;
        }
        match (
            self.collider.get_mut(k),
            self.value.get_mut(k),
            self.gradient.get_mut(k),
        ) {
            (Some(c), Some(v), Some(g)) => {
                (*c, *v, *g) = (collider, value, gradient);
                self.count += 1;
                if tentative {
                    self.tentative |= 1 << k;
                }
                true
            }
            _ => false,
        }
    }
}

impl NodeContacts {
    /// Removes the rows whose bit is set in `mask` (those after them move up): tentative
    /// rows whose multiplier turned out to pull.
    pub fn remove(&mut self, mask: u16) {
        let mut kept = NodeContacts::default();
        let count = usize::from(self.count).min(MAX_NODE_CONTACTS);
        for k in 0..count {
            if mask & (1 << k) == 0 {
                let tentative = self.tentative & (1 << k) != 0;
                kept.push(self.collider[k], self.value[k], self.gradient[k], tentative);
            }
        }
        *self = kept;
    }
}

/// What the projection needs to know about each node: its inverse mass (zero when
/// prescribed) and whether it may carry collision rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nodes<const N: usize> {
    /// `w_i = 1/m_i`, or 0 for a prescribed node (root, grab).
    pub inverse_mass: [Real; N],
    /// How many nodes the strand has.
    pub count: usize,
}

impl<const N: usize> Nodes<N> {
    /// Whether node `i` is free to move.
    #[inline(always)]
    #[must_use]
    pub fn is_free(&self, i: usize) -> bool {
        self.inverse_mass.get(i).is_some_and(|&w| w > 0.0)
    }
}

/// Which constraints this projection enforces, and how the layout is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Layout {
    /// Inextensibility rows (effect `inextensibility`).
    pub inextensibility: bool,
    /// Collision rows per free node at most: 0 when `collisions` is off or there is no
    /// collider.
    pub contact_slots: usize,
    /// Fixed cost: a row for every segment that may carry one (padding where it cannot) and
    /// the full band for every row, so the work does not depend on the state.
    pub fixed_cost: bool,
    /// Tentative collision rows for free nodes outside a collider but within
    /// [`CONTACT_MARGIN`] of it (converge mode; see [`evaluate`]).
    pub contact_margin: bool,
    /// Only the residual, the convergence test and the contacts (detected and remembered as
    /// usual): no segment rows are built. The projection's last evaluation, after its last
    /// solve, needs nothing more (one evaluation in `cap + 1` is this one).
    pub residual_only: bool,
}

impl Layout {
    /// Whether an evaluation measures the segments' share of the residual and the
    /// convergence test. Fixed cost runs every iteration whatever they say, so it measures
    /// them once, at its last evaluation (and where a projection stops early,
    /// [`measure_segments`]); converge mode measures them at every evaluation.
    #[inline(always)]
    #[must_use]
    pub fn measures_segments(self) -> bool {
        self.residual_only || !self.fixed_cost
    }
}

/// The segments' share of the residual and the convergence test at the positions `at(i)`
/// (segments with a free node, rest lengths `rest_length`), into `rows`: what the evaluation a
/// fixed-cost projection stopped after did not measure ([`Layout::measures_segments`]).
pub(crate) fn measure_segments<const N: usize, const S: usize>(
    at: impl Fn(usize) -> Vec3,
    rest_length: &[Real; N],
    nodes: &Nodes<N>,
    tolerance: Real,
    rows: &mut Rows<N, S>,
) {
    let count = nodes.count.min(N);
    for (i, &rest) in rest_length.iter().enumerate().take(count.saturating_sub(1)) {
        if nodes.is_free(i) || nodes.is_free(i + 1) {
            let (a, b) = (at(i), at(i + 1));
            let rest2 = rest * rest;
            let e = b - a;
            rows.meet(e.dot(e) - rest2, rest2, tolerance, a, b);
        }
    }
}

/// The constraints at one iterate: segment rows in band order, collision rows by node. `S`
/// is the segment rows' capacity: `N` for the general projection, 0 for a strand's lane in
/// the lanes' projection, whose segment rows live in the lanes (`lanes::BlockProjection`;
/// there they would be 56 bytes a node of a world's scratch space for nothing).
#[derive(Clone, Debug, PartialEq)]
pub struct Rows<const N: usize, const S: usize = N> {
    /// The segment rows, in band order (`count` in use).
    pub rows: [Row; S],
    /// First column of each row's envelope (`first[r] ≤ r`): the previous row when it shares
    /// a node with this one.
    pub first: [u16; S],
    /// Rows in use.
    pub count: usize,
    /// Row index of segment `j`, or [`NO_ROW`].
    pub segment_row: [u16; S],
    /// Each node's collision rows (all empty, `kept = 0`, but those of `contact_nodes`).
    pub contacts: [NodeContacts; N],
    /// The nodes with collision rows at this iterate, in increasing order (`contact_count`
    /// in use): the collision work of the solve visits these only.
    pub contact_nodes: [u16; N],
    /// Entries of `contact_nodes` in use.
    pub contact_count: usize,
    /// `max_j |C_j| / (ê^j·ê^j)` over segment rows and `depth / |ê^{i−1}|` over nodes inside a
    /// collider (with or without a row): the relative residual at this iterate.
    pub residual: Real,
    /// Whether every row is within the tolerance, or within what f32 positions can resolve
    /// when that is coarser (see [`resolution_floor`]).
    pub converged: bool,
    /// Deepest free node inside a collider at this iterate, m.
    pub max_depth: Real,
    /// Whether some node was in more than [`MAX_NODE_CONTACTS`] colliders.
    pub truncated: bool,
    /// Whether some node carries a tentative collision row.
    pub tentative: bool,
}

impl<const N: usize, const S: usize> Default for Rows<N, S> {
    // Inlined so that the arrays are filled in their final place (the projection's
    // workspace), not built on the stack and copied there.
    #[inline(always)]
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, const S: usize> Rows<N, S> {
    /// No rows (`const`: a world's scratch space is built at compile time).
    #[inline(always)]
    #[must_use]
    pub const fn new() -> Self {
        Rows {
            rows: [Row::EMPTY; S],
            first: [0; S],
            count: 0,
            segment_row: [NO_ROW; S],
            contacts: [NodeContacts::EMPTY; N],
            contact_nodes: [0; N],
            contact_count: 0,
            residual: 0.0,
            converged: true,
            max_depth: 0.0,
            truncated: false,
            tentative: false,
        }
    }
}

impl<const N: usize, const S: usize> Rows<N, S> {
    /// The rows in use.
    #[must_use]
    pub fn rows(&self) -> &[Row] {
        self.rows.get(..self.count).unwrap_or(&[])
    }

    /// The collision rows at this iterate: those of the nodes in `contact_nodes`.
    #[must_use]
    pub fn collision_rows(&self) -> u32 {
        let nodes = self.contact_nodes.iter().take(self.contact_count.min(N));
        let rows = nodes.map(|&i| self.contacts.get(usize::from(i)).map_or(0, |c| c.count));
        rows.map(u32::from).sum()
    }

    /// The nodes with collision rows at this iterate, in increasing order.
    #[must_use]
    pub fn contact_nodes(&self) -> &[u16] {
        self.contact_nodes.get(..self.contact_count).unwrap_or(&[])
    }

    /// The envelope starts of the rows in use.
    #[must_use]
    pub fn first(&self) -> &[u16] {
        self.first.get(..self.count).unwrap_or(&[])
    }

    /// Adds the segment from `a` to `b` with `C = value` (rest length² `rest2`) to the
    /// residual and the convergence test.
    #[inline(always)]
    pub(crate) fn meet(&mut self, value: Real, rest2: Real, tolerance: Real, a: Vec3, b: Vec3) {
        // `max` would drop a NaN: keep it visible in the residual. Compared multiplied out,
        // so the division runs only for a new largest row (a few per iterate, not one per
        // segment: VDIV is 14 cycles on a Cortex-M4F).
        let magnitude = value.abs();
        if magnitude > self.residual * rest2 || magnitude.is_nan() {
            let relative = magnitude / rest2;
            if relative.is_nan() || relative > self.residual {
                self.residual = relative;
            }
        }
        // The resolution floor only matters while every row so far is met.
        if self.converged && magnitude > tolerance * rest2 {
            let floor = resolution_floor(false, a, b, 0.0).min(0.01 * rest2);
            self.converged = magnitude <= floor;
        }
    }

    fn push(&mut self, row: Row, first: usize) -> Option<usize> {
        let r = self.count;
        *self.rows.get_mut(r)? = row;
        *self.first.get_mut(r)? = first.min(r) as u16;
        self.count += 1;
        Some(r)
    }
}

/// What the projection remembers of each node's contacts across its iterations.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactMemory<const N: usize> {
    /// Per node, the colliders it got a collision row for (bit `c`) at some iterate.
    pub touched: [u8; N],
    /// `Λ` of each node's row for each collider, summed over iterations (< 0: pushing out).
    pub multipliers: [[Real; MAX_COLLIDERS]; N],
}

impl<const N: usize> ContactMemory<N> {
    /// Back to [`Default`], in place: only the nodes that touched had multipliers.
    pub fn forget(&mut self) {
        for (touched, sums) in self.touched.iter_mut().zip(self.multipliers.iter_mut()) {
            if *touched != 0 {
                *touched = 0;
                *sums = [0.0; MAX_COLLIDERS];
            }
        }
    }
}

impl<const N: usize> Default for ContactMemory<N> {
    #[inline(always)]
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ContactMemory<N> {
    /// Nothing remembered (`const`, as [`Rows::new`]).
    #[inline(always)]
    #[must_use]
    pub const fn new() -> Self {
        ContactMemory {
            touched: [0; N],
            multipliers: [[0.0; MAX_COLLIDERS]; N],
        }
    }
}

/// Largest absolute coordinate of `p` (how far from the origin f32's rounding is measured, and
/// how far a collider reaches).
#[inline(always)]
#[must_use]
pub fn magnitude(p: Vec3) -> Real {
    crate::math::max(crate::math::max(p.x.abs(), p.y.abs()), p.z.abs())
}

/// What f32 positions can resolve of a constraint's value. Each coordinate is rounded to
/// `ε|x|/2`, so `e` is uncertain by `ε·max|x|` per component and `e·e` by `2ε|e|₁·max|x|`
/// (plus its own rounding, `ε e·e`); a contact depth by `ε` of the coordinates involved.
/// Newton steps at that level only move nodes by a rounding and the residual wanders within
/// it (measured: up to ~1.5× the bound once the linear solve's own rounding adds in), so the
/// floor is twice the bound. With 1 cm segments 0.1–0.4 m from the origin that is 5e-6 to
/// 2e-5 of `ê·ê`: above the default tolerance 1e-6, which the iteration would otherwise
/// chase for its whole cap. Rows within this floor count as met; the reported residual
/// stays the true value.
#[must_use]
pub fn resolution_floor(is_contact: bool, a: Vec3, b: Vec3, length_scale: Real) -> Real {
    let eps = Real::EPSILON;
    let m = crate::math::max(magnitude(a), magnitude(b));
    if is_contact {
        4.0 * eps * (m + length_scale)
    } else {
        let e = b - a;
        4.0 * eps * (e.x.abs() + e.y.abs() + e.z.abs()) * m + 2.0 * eps * e.dot(e)
    }
}

/// Outward normal and signed depth (> 0 inside) of `p` against `shape`, inside or not; the
/// same geometry as [`Shape::penetration`], which only answers inside.
fn surface<M: Math>(shape: &Shape, p: Vec3) -> (Vec3, Real) {
    let ball = |centre: Vec3, radius: Real| {
        let d = p - centre;
        let distance = M::sqrt(d.dot(d));
        let normal = if distance > 0.0 {
            d / distance
        } else {
            Vec3::Y
        };
        (normal, radius - distance)
    };
    match *shape {
        Shape::Sphere { centre, radius } => ball(centre, radius),
        Shape::Capsule { a, b, radius } => {
            ball(crate::collide::closest_on_segment(p, a, b), radius)
        }
        Shape::Plane { point, normal } => (normal, -(p - point).dot(normal)),
    }
}

/// Evaluates every constraint at the positions `x` (re-detecting contacts) and lays the rows
/// out. `colliders` are the step's valid colliders with their index in the step's list.
///
/// `memory.touched[i]` has bit `c` set once node `i` got a row for collider `c` in this
/// projection; such a contact keeps its row even when the node is outside, as long as its
/// accumulated multiplier `memory.multipliers[i][c]` pushes (`Λ < 0`: the row moves the node
/// along `−∇C·Λ`, outward). Dropping a row as soon as a step lands its node on the surface
/// lets the next step, blind to the collider, push the node back through it: the contact set
/// then flickers and the iteration does not settle. Keeping a row that pulls would glue the
/// node to the surface, which can be infeasible with the segment lengths (a node held at the
/// surface out of reach of the root).
///
/// With `layout.contact_margin` (converge mode), a free node outside a collider but within
/// [`CONTACT_MARGIN`] of it gets a *tentative* row (`C > 0`, same secant gradient): the
/// solve keeps it only if its multiplier pushes (see `project_constraints`), so a node that
/// the segments would pull into the collider is held at its surface in the same iteration
/// instead of being caught one iteration later. A kept tentative row becomes a contact
/// (`touched`); one that pulls leaves no trace.
pub fn evaluate<M: Math, const N: usize>(
    strand: &Strand<N>,
    nodes: &Nodes<N>,
    colliders: &[(u8, Shape)],
    layout: Layout,
    tolerance: Real,
    memory: &mut ContactMemory<N>,
    rows: &mut Rows<N>,
) {
    let x = &strand.state.position;
    let at = |i: usize| x[i];
    let rest_length = &strand.rest.segment_length;
    let found = (memory, &mut *rows);
    evaluate_contacts::<M, N, N>(
        (at, rest_length),
        nodes,
        colliders,
        layout,
        tolerance,
        found,
    );
    let count = nodes.count.min(N);
    // Contacts first, then segments: the residual is a maximum, the convergence test a
    // conjunction, so the order changes neither (a NaN segment value now always stays
    // visible in the residual, where a later contact's `max` could hide it before).
    lay_out_segments(strand, nodes, layout, tolerance, rows, count);
    if layout.fixed_cost {
        // The full band for every row: the factorisation's work is the same whatever holds.
        for (r, first) in rows.first.iter_mut().enumerate().take(rows.count) {
            *first = r.saturating_sub(1) as u16;
        }
    }
}

/// The first half of [`evaluate`]: forgets the last iterate's rows, then finds the contacts
/// of the nodes at `position(i)` (`rest_length` per segment) into `rows`, with their share of
/// the residual. [`evaluate`] lays the segments out after it; the projection of a block in
/// lanes lays them out in lanes.
#[inline(always)]
pub fn evaluate_contacts<M: Math, const N: usize, const S: usize>(
    (position, rest_length): (impl Fn(usize) -> Vec3, &[Real; N]),
    nodes: &Nodes<N>,
    colliders: &[(u8, Shape)],
    layout: Layout,
    tolerance: Real,
    (memory, rows): (&mut ContactMemory<N>, &mut Rows<N, S>),
) {
    rows.count = 0;
    rows.residual = 0.0;
    rows.converged = true;
    rows.max_depth = 0.0;
    rows.truncated = false;
    rows.tentative = false;
    // Without collision slots no node ever gets a contact (counts stay 0 from `Default`).
    if layout.contact_slots > 0 {
        let at = (position, rest_length);
        detect_contacts::<M, N, S>(at, nodes, colliders, layout, tolerance, memory, rows);
    }
}

/// How far outside a collider a free node gets a tentative collision row, as a fraction of
/// the rest length of the segment before it (see [`evaluate`]). Measured on Table 3's draped
/// strands: nodes a few µm outside the head at the first iterate were pushed 30–45 µm in by
/// the first solve (the segments' shortening pulls the draped run onto its chords), and each
/// such strand needed a third iteration to push them back out.
pub const CONTACT_MARGIN: Real = 5.0e-3;

/// Outward normal and signed depth (> 0 inside) of `p` against `shape` when `p` is inside it
/// or within `margin` outside; the same geometry as [`Shape::penetration`] (a square root only
/// for nodes that pass the squared-distance test).
#[inline(always)]
fn near_surface<M: Math>(shape: &Shape, p: Vec3, margin: Real) -> Option<(Vec3, Real)> {
    let ball = |centre: Vec3, radius: Real| {
        let d = p - centre;
        let distance2 = d.dot(d);
        let reach = radius + margin;
        if distance2 >= reach * reach {
            return None;
        }
        let distance = M::sqrt(distance2);
        let normal = if distance > 0.0 {
            d / distance
        } else {
            Vec3::Y
        };
        Some((normal, radius - distance))
    };
    match *shape {
        Shape::Sphere { centre, radius } => ball(centre, radius),
        Shape::Capsule { a, b, radius } => {
            ball(crate::collide::closest_on_segment(p, a, b), radius)
        }
        Shape::Plane { point, normal } => {
            let height = (p - point).dot(normal);
            (height < margin).then_some((normal, -height))
        }
    }
}

/// Whether `p` is surely further than `margin` outside `shape`: the squared-distance test of
/// [`near_surface`] alone, no square root.
#[inline(always)]
fn beyond(shape: &Shape, p: Vec3, margin: Real) -> bool {
    match *shape {
        Shape::Sphere { centre, radius } => {
            let d = p - centre;
            let reach = radius + margin;
            d.dot(d) >= reach * reach
        }
        Shape::Capsule { a, b, radius } => {
            let d = p - crate::collide::closest_on_segment(p, a, b);
            let reach = radius + margin;
            d.dot(d) >= reach * reach
        }
        Shape::Plane { point, normal } => (p - point).dot(normal) >= margin,
    }
}

/// The collision rows of every free node at this iterate (see [`evaluate`]). One collider
/// at a time over the nodes, so that the common case — a node far from it — is a
/// squared-distance test in a tight loop; each node still gets its rows in collider order.
fn detect_contacts<M: Math, const N: usize, const S: usize>(
    (x, rest_length): (impl Fn(usize) -> Vec3, &[Real; N]),
    nodes: &Nodes<N>,
    colliders: &[(u8, Shape)],
    layout: Layout,
    tolerance: Real,
    memory: &mut ContactMemory<N>,
    rows: &mut Rows<N, S>,
) {
    let count = nodes.count.min(N);
    rows.forget_contacts();
    let margin_fraction = if layout.contact_margin && !layout.residual_only {
        CONTACT_MARGIN
    } else {
        0.0
    };
    let mut ordered = true;
    for &(c, ref shape) in colliders {
        let bit = 1u8 << (c % 8);
        // Nodes 0 and 1 are prescribed (root coupling): never a row.
        for i in 2..count {
            let free = nodes.is_free(i);
            // Test the bit first: most nodes never touch anything.
            let remembered = memory.touched[i] & bit != 0;
            let p = x(i);
            let margin = margin_fraction * rest_length[i - 1];
            if !free || (!remembered && beyond(shape, p, margin)) {
                continue;
            }
            let sticky = remembered
                && memory.multipliers[i]
                    .get(usize::from(c))
                    .is_some_and(|&lambda| lambda < 0.0);
            let found = if sticky {
                Some(surface::<M>(shape, p))
            } else if margin > 0.0 {
                near_surface::<M>(shape, p, margin)
            } else {
                shape.penetration::<M>(p).map(|c| (c.normal, c.depth))
            };
            let Some((normal, depth)) = found else {
                continue;
            };
            if depth > 0.0 {
                rows.meet_contact(depth, rest_length[i - 1], tolerance, shape, p);
            }
            let found = Found {
                node: i,
                collider: c,
                normal,
                depth,
                tentative: !sticky && depth <= 0.0,
            };
            ordered &= rows.add_contact(found, shape, layout, memory);
        }
    }
    if !ordered {
        // A later collider touched an earlier node: list them in node order again (the
        // solve's sums must not depend on the colliders' order).
        rows.order_contact_nodes(count);
    }
}

/// A contact [`detect_contacts`] found: a node, the collider, the outward normal and the
/// depth (≤ 0 outside), and whether its row is tentative.
#[derive(Clone, Copy, Debug)]
struct Found {
    node: usize,
    collider: u8,
    normal: Vec3,
    depth: Real,
    tentative: bool,
}

impl<const N: usize, const S: usize> Rows<N, S> {
    /// Empties the previous iterate's collision rows (every other node's are empty already).
    #[inline(always)]
    pub(crate) fn forget_contacts(&mut self) {
        for k in 0..self.contact_count.min(N) {
            if let Some(contacts) = self.contacts.get_mut(usize::from(self.contact_nodes[k])) {
                (contacts.count, contacts.tentative, contacts.kept) = (0, 0, 0);
            }
        }
        self.contact_count = 0;
    }

    /// A node `depth` inside `shape` at `p`, with `scale` the rest length of the segment
    /// before it: into the residual, the deepest penetration and the convergence test.
    #[inline(always)]
    fn meet_contact(&mut self, depth: Real, scale: Real, tolerance: Real, shape: &Shape, p: Vec3) {
        self.residual = crate::math::max(self.residual, depth / scale);
        self.max_depth = crate::math::max(self.max_depth, depth);
        if self.converged && depth > tolerance * scale {
            let reach = match *shape {
                Shape::Sphere { radius, .. } | Shape::Capsule { radius, .. } => radius,
                Shape::Plane { point, .. } => magnitude(point),
            };
            // Past 1 % of the segment f32 resolves nothing: not converged.
            let floor = resolution_floor(true, p, p, reach).min(0.01 * scale);
            self.converged = depth <= floor;
        }
    }

    /// The collision row of `found` against `shape`, if its node has room (a contact found
    /// inside takes a tentative one's place; past the room it is flagged `truncated`), and the
    /// node listed with the contact nodes when it is its first row. A row that is not
    /// tentative is remembered in `memory`. Returns whether the contact nodes are still in
    /// node order.
    #[inline(always)]
    fn add_contact(
        &mut self,
        found: Found,
        shape: &Shape,
        layout: Layout,
        memory: &mut ContactMemory<N>,
    ) -> bool {
        let (i, c, tentative) = (found.node, found.collider, found.tentative);
        let (value, gradient) = contact(shape, found.normal, found.depth);
        let contacts = &mut self.contacts[i];
        let first = contacts.count == 0;
        let room = usize::from(contacts.count) < layout.contact_slots
            || (!tentative && contacts.tentative != 0);
        if !(room && contacts.push(c, value, gradient, tentative)) {
            if !tentative {
                self.truncated = true;
            }
            return true;
        }
        if tentative {
            self.tentative = true;
        } else {
            memory.touched[i] |= 1u8 << (c % 8);
        }
        let mut ordered = true;
        if first {
            let last = self.contact_count.checked_sub(1);
            ordered = last.is_none_or(|k| usize::from(self.contact_nodes[k]) < i);
            if let Some(slot) = self.contact_nodes.get_mut(self.contact_count) {
                *slot = i as u16;
                self.contact_count += 1;
            }
        }
        ordered
    }

    /// Lists the nodes with collision rows in node order.
    fn order_contact_nodes(&mut self, count: usize) {
        self.contact_count = 0;
        for i in 2..count {
            if self.contacts[i].count > 0 {
                self.contact_nodes[self.contact_count] = i as u16;
                self.contact_count += 1;
            }
        }
    }
}

/// The segment rows in band order (or only their residual, `layout.residual_only`), and
/// `segment_row` for every node.
fn lay_out_segments<const N: usize>(
    strand: &Strand<N>,
    nodes: &Nodes<N>,
    layout: Layout,
    tolerance: Real,
    rows: &mut Rows<N>,
    count: usize,
) {
    let x = &strand.state.position;
    let rest_length = &strand.rest.segment_length;
    for r in rows.segment_row.iter_mut().take(count) {
        *r = NO_ROW;
    }
    if !layout.inextensibility {
        return;
    }
    let mut previous_segment: Option<usize> = None;
    let mut free_here = nodes.is_free(0);
    for i in 0..count.saturating_sub(1) {
        let free_next = nodes.is_free(i + 1);
        if free_here || free_next {
            let (a, b) = (x[i], x[i + 1]);
            let rest2 = rest_length[i] * rest_length[i];
            if layout.residual_only {
                let e = b - a;
                let value = e.dot(e) - rest2;
                rows.meet(value, rest2, tolerance, a, b);
            } else {
                let row = Row::segment(i, a, b, rest_length[i]);
                if layout.measures_segments() {
                    rows.meet(row.value, rest2, tolerance, a, b);
                }
                let first = previous_segment.unwrap_or(rows.count);
                previous_segment = rows.push(row, first);
                if let Some(r) = previous_segment {
                    rows.segment_row[i] = r as u16;
                }
            }
        } else {
            // Both ends prescribed (segment 0, or a grab next to the root or to another grab):
            // nothing can move, so no row. Fixed cost keeps a padding row in its place
            // (segment 0 is always prescribed and needs none), so that the row count does
            // not depend on which grabs hold.
            if layout.fixed_cost && i >= 1 && !layout.residual_only {
                rows.push(Row::default(), rows.count);
            }
            previous_segment = None;
        }
        free_here = free_next;
    }
}
