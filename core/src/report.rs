//! The step report: what a step did, instead of failing. Stage counters, iterations and
//! residuals, flags, high-water marks, and the forces a haptic device renders.

use crate::capacities::{MAX_COLLIDERS, MAX_GRABS};
use crate::math::{Real, Vec3};

/// The stages of a step, declared in the order they run: the rod's pipeline (Kmoch 2009
/// Algorithm 1) and DFTL's (Sánchez-Banderas 2015 Algorithm 1) each run a subsequence of this
/// list, in this order, on every strand (`pipeline::rod`, `pipeline::dftl`).
///
/// 0. `HairHair` — SPH hair–hair interaction (SB15 lines 1–11), in the std harness, once per
///    step for all strands at once: its accelerations are an input of the strands' step.
/// 1. `Snapshot` — keep the strand's last good state (quarantine).
/// 2. `ElasticForces` — bending and twist forces (rod, Kmoch Sec. 7.2; Alg. 1 line 3).
/// 3. `ExternalForces` — gravity, drag, wind, the caller's accelerations (rod line 3; DFTL
///    line 13).
/// 4. `Integrate` — symplectic Euler or the implicit bending step (rod line 4); DFTL's
///    prediction `x* = x + vΔt + aΔt²` (line 14).
/// 5. `RootCoupling` — nodes 0 and 1 follow the head (both solvers).
/// 6. `Shape` — global and local shape constraints (DFTL line 18).
/// 7. `Projection` — the rod's fast manifold projection (lines 5–7: inextensibility,
///    collisions, grabs); DFTL's follow-the-leader inextensibility (line 19).
/// 8. `Collisions` — contacts found and resolved (rod: inside the projection; DFTL line 20).
/// 9. `Velocity` — velocities from the position change (rod line 8; DFTL lines 24–26).
/// 10. `Twist` — the Bishop frame in space and the quasistatic twist (rod lines 9–10).
/// 11. `Guard` — non-finite (or blown-up) strands rolled back (rod line 11; after DFTL's pass).
///
/// DFTL fuses its lines 12–27 into one pass from the root, node by node; its stages are
/// counted in the algorithm's order (the predictions of nodes 2 and on do not depend on the
/// root coupling of nodes 0 and 1, so the order is the same computation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Stage {
    /// Hair–hair interaction (SPH, in the harness), before the strands' own stages.
    HairHair = 0,
    /// Keep the last good state.
    Snapshot = 1,
    /// Bending and twist forces.
    ElasticForces = 2,
    /// Gravity, drag, wind, caller accelerations.
    ExternalForces = 3,
    /// Symplectic Euler, implicit bending step, or DFTL's prediction.
    Integrate = 4,
    /// Roots follow the head.
    RootCoupling = 5,
    /// DFTL shape constraints.
    Shape = 6,
    /// Inextensibility: fast manifold projection (rod) or follow-the-leader (DFTL).
    Projection = 7,
    /// Collision handling.
    Collisions = 8,
    /// Velocity update.
    Velocity = 9,
    /// Bishop frame and quasistatic twist.
    Twist = 10,
    /// Non-finite check and rollback.
    Guard = 11,
}

/// Number of [`Stage`]s.
pub const STAGE_COUNT: usize = 12;

pub use crate::capacities::NAMED_STRANDS;

/// The relative stretch above which a step raises [`Flags::STRETCHED`].
pub const STRETCH_LIMIT: Real = 0.01;

/// Flags raised by a step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Flags(u16);

impl Flags {
    /// An iteration cap was hit before the tolerance was reached (or, where coarser, what f32
    /// positions can resolve).
    pub const CAP_HIT: Flags = Flags(1);
    /// A strand turned non-finite and was rolled back.
    pub const ROLLED_BACK: Flags = Flags(2);
    /// A grab exceeded its force limit and slipped.
    pub const GRAB_SLIPPED: Flags = Flags(4);
    /// The caller's input (head pose, accelerations, grab targets) held a non-finite value,
    /// which was ignored.
    pub const BAD_INPUT: Flags = Flags(8);
    /// The projection met dependent constraints (a singular or near-singular pivot, or a
    /// non-finite multiplier) and solved without those rows; see `StepReport::dropped_rows`.
    pub const SINGULAR: Flags = Flags(16);
    /// A node was inside more colliders than it can carry collision rows for
    /// (`projection::constraints::MAX_NODE_CONTACTS`); the extra contacts waited an iteration.
    pub const CONTACTS_TRUNCATED: Flags = Flags(32);
    /// A segment ended the step more than [`STRETCH_LIMIT`] (1 %) longer or shorter than its
    /// rest length (`max_stretch` or `max_contact_stretch`): inextensibility is off, or
    /// contacts or grabs pull harder than the projection holds.
    pub const STRETCHED: Flags = Flags(64);
    /// The world holds colliders but the `collisions` effect is off: they did nothing.
    pub const COLLIDERS_INACTIVE: Flags = Flags(128);
    /// The world holds grabs that hold their node but the `grabs` effect is off: they did
    /// nothing.
    pub const GRABS_INACTIVE: Flags = Flags(256);

    /// Whether every flag of `other` is set.
    #[must_use]
    pub const fn contains(self, other: Flags) -> bool {
        self.0 & other.0 == other.0
    }
    /// Sets the flags of `other`.
    pub fn insert(&mut self, other: Flags) {
        self.0 |= other.0;
    }
    /// Whether no flag is set.
    #[must_use]
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }
}

/// What one step did.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    /// How many strands each [`Stage`] ran on (a stage that is off stays at 0).
    pub stage_runs: [u32; STAGE_COUNT],
    /// Flags raised.
    pub flags: Flags,
    /// Most projection (or Newton) iterations any strand used.
    pub iterations_max: u32,
    /// Projection iterations summed over strands.
    pub iterations_total: u32,
    /// Strands whose projection hit its iteration cap above tolerance.
    pub cap_hits: u32,
    /// Largest final projection residual over strands: `max |e·e − ê·ê| / ê·ê` over segments
    /// and `depth / |ê|` over nodes still inside a collider.
    pub residual: Real,
    /// Constraint rows the projection dropped at a singular pivot, summed over iterations and
    /// strands (see [`Flags::SINGULAR`]).
    pub dropped_rows: u32,
    /// Largest relative stretch `| |e| − |ê| | / |ê|` of a segment without contact.
    pub max_stretch: Real,
    /// Largest relative stretch of a segment with a node pushed out of a collider.
    pub max_contact_stretch: Real,
    /// Deepest node inside a collider after the step, m.
    pub max_penetration: Real,
    /// Nodes that got a collision row in this step's projection (pushed out of a collider).
    pub contacts: u32,
    /// Collision rows the rod's projection solved, summed over its iterations and strands: a
    /// row present at `k` iterates counts `k` times (`projection::Outcome::collision_rows`).
    /// What a collision row costs is the step's cost with the collider less without, divided
    /// by this (`firmware/latency.rs`).
    pub collision_rows: u32,
    /// Strands rolled back to their last good state.
    pub rolled_back: u32,
    /// The first [`NAMED_STRANDS`] rolled-back strands, by index.
    pub rolled_back_strands: heapless::Vec<u32, NAMED_STRANDS>,
    /// Force each grab's device feels, N (zero for unused slots): the pull of the strand on the
    /// held node plus the node's own weight and inertia (at rest: the weight held).
    pub grab_forces: [Vec3; MAX_GRABS],
    /// Grabs that slipped this step (bit `g` for grab `g`).
    pub grabs_slipped: u8,
    /// Force the head feels from the strands, N, summed over strands: what the held root
    /// nodes 0 and 1 of every strand transmit (a device may hold the head too). At rest, with
    /// the grabs' forces, the weight of nodes 2 to the last. The colliders' contact forces
    /// are apart, in `collider_forces` (a head that carries colliders feels those too). The
    /// rod: the elastic forces on nodes 0 and 1 and segment 1's constraint force on node 1;
    /// DFTL, which has no such forces (its corrections are one-sided): the change of the
    /// strand's momentum that no external force, collider or grab explains
    /// (`docs/architecture.md`, "Forces on the head and the grabs").
    pub head_force: Vec3,
    /// Total contact force the hair exerts on each collider, N (from the collision multipliers).
    pub collider_forces: [Vec3; MAX_COLLIDERS],
    /// Every stage this step counted ([`StepReport::ran_on`]), in call order: recorded in the
    /// core's unit tests only, where `pipeline::tests` checks that the pipelines run the
    /// stages in [`Stage`]'s order. In the library it is empty and records nothing: a step
    /// pays nothing for it.
    pub trace: StageTrace,
}

/// The library's stage trace: nothing (zero-sized; [`StageTrace::push`] does nothing). The
/// core's unit tests record the stages instead.
#[cfg(not(test))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StageTrace;

#[cfg(not(test))]
impl StageTrace {
    /// The empty trace.
    #[must_use]
    pub const fn new() -> Self {
        StageTrace
    }

    /// Records nothing.
    #[inline(always)]
    pub fn push(&mut self, _: Stage) -> Result<(), Stage> {
        Ok(())
    }
}

impl Default for StepReport {
    fn default() -> Self {
        StepReport {
            stage_runs: [0; STAGE_COUNT],
            flags: Flags::default(),
            iterations_max: 0,
            iterations_total: 0,
            cap_hits: 0,
            residual: 0.0,
            dropped_rows: 0,
            max_stretch: 0.0,
            max_contact_stretch: 0.0,
            max_penetration: 0.0,
            contacts: 0,
            collision_rows: 0,
            rolled_back: 0,
            rolled_back_strands: heapless::Vec::new(),
            grab_forces: [Vec3::ZERO; MAX_GRABS],
            grabs_slipped: 0,
            head_force: Vec3::ZERO,
            collider_forces: [Vec3::ZERO; MAX_COLLIDERS],
            trace: StageTrace::new(),
        }
    }
}

impl StepReport {
    /// Back to [`Default`], in place (what [`crate::World::step_into`] starts from): every
    /// field named, so that a new one cannot be forgotten; assigning a new default would build
    /// it apart and copy it (on the Cortex-M4F, 370 instructions a step).
    pub fn clear(&mut self) {
        let StepReport {
            stage_runs,
            flags,
            iterations_max,
            iterations_total,
            cap_hits,
            residual,
            dropped_rows,
            max_stretch,
            max_contact_stretch,
            max_penetration,
            contacts,
            collision_rows,
            rolled_back,
            rolled_back_strands,
            grab_forces,
            grabs_slipped,
            head_force,
            collider_forces,
            trace,
        } = self;
        *stage_runs = [0; STAGE_COUNT];
        *flags = Flags::default();
        (*iterations_max, *iterations_total, *cap_hits, *dropped_rows) = (0, 0, 0, 0);
        (
            *residual,
            *max_stretch,
            *max_contact_stretch,
            *max_penetration,
        ) = (0.0, 0.0, 0.0, 0.0);
        (*contacts, *collision_rows, *rolled_back) = (0, 0, 0);
        rolled_back_strands.clear();
        *grab_forces = [Vec3::ZERO; MAX_GRABS];
        *grabs_slipped = 0;
        *head_force = Vec3::ZERO;
        *collider_forces = [Vec3::ZERO; MAX_COLLIDERS];
        *trace = StageTrace::new();
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for StepReport {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "StepReport {{ flags: {}, iterations_max: {}, cap_hits: {}, residual: {}, dropped_rows: {}, max_stretch: {}, max_penetration: {}, contacts: {}, rolled_back: {}, grabs_slipped: {} }}",
            self.flags,
            self.iterations_max,
            self.cap_hits,
            self.residual,
            self.dropped_rows,
            self.max_stretch,
            self.max_penetration,
            self.contacts,
            self.rolled_back,
            self.grabs_slipped
        )
    }
}

impl StepReport {
    /// Counts one strand through `stage`.
    #[inline(always)]
    pub fn ran(&mut self, stage: Stage) {
        self.ran_on(stage, 1);
    }

    /// Counts `strands` strands through `stage` (a block's lanes at once).
    #[inline(always)]
    pub fn ran_on(&mut self, stage: Stage, strands: u32) {
        self.stage_runs[stage as usize] += strands;
        // (In the unit tests, a full trace fails the tests that read it: they check its
        // length.)
        let _ = self.trace.push(stage);
    }

    /// How many strands `stage` ran on.
    #[must_use]
    pub fn runs(&self, stage: Stage) -> u32 {
        self.stage_runs[stage as usize]
    }

    /// Records a strand rolled back to its last good state.
    pub fn roll_back(&mut self, strand: u32) {
        self.rolled_back += 1;
        self.flags.insert(Flags::ROLLED_BACK);
        // The count is exact; beyond the list's capacity the names are dropped.
        let _ = self.rolled_back_strands.push(strand);
    }

    /// Folds the report of a later block of strands into this one. Reports must be merged in
    /// block order (never completion order) so that force sums are the same bits whatever the
    /// thread count.
    pub fn merge(&mut self, other: &StepReport) {
        for (a, b) in self.stage_runs.iter_mut().zip(other.stage_runs) {
            *a += b;
        }
        self.flags.insert(other.flags);
        self.iterations_max = self.iterations_max.max(other.iterations_max);
        self.iterations_total += other.iterations_total;
        self.cap_hits += other.cap_hits;
        self.residual = self.residual.max(other.residual);
        self.dropped_rows += other.dropped_rows;
        self.max_stretch = self.max_stretch.max(other.max_stretch);
        self.max_contact_stretch = self.max_contact_stretch.max(other.max_contact_stretch);
        self.max_penetration = self.max_penetration.max(other.max_penetration);
        self.contacts += other.contacts;
        self.collision_rows += other.collision_rows;
        self.rolled_back += other.rolled_back;
        for &s in &other.rolled_back_strands {
            let _ = self.rolled_back_strands.push(s);
        }
        for (a, b) in self.grab_forces.iter_mut().zip(other.grab_forces) {
            *a += b;
        }
        self.grabs_slipped |= other.grabs_slipped;
        self.head_force += other.head_force;
        for (a, b) in self.collider_forces.iter_mut().zip(other.collider_forces) {
            *a += b;
        }
    }
}

/// The unit tests' stage trace: every stage counted, in call order, up to
/// [`TRACE_CAPACITY`].
#[cfg(test)]
pub type StageTrace = heapless::Vec<Stage, TRACE_CAPACITY>;

/// Entries of the unit tests' [`StageTrace`].
#[cfg(test)]
pub const TRACE_CAPACITY: usize = 256;
