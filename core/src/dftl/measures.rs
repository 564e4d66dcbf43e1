//! What a DFTL step measures along its pass, for the report: each segment's strain (stretched
//! or compressed, with or without a node pushed out of a collider), how deep nodes are left
//! inside colliders, how many were pushed, and the momentum the colliders gave.
//!
//! Segment strain is measured as `(|e|² − l²)/(2l²)` (no square root) and turned into a
//! relative stretch once per strand ([`Measures::stretches`]).

use crate::capacities::MAX_COLLIDERS;
use crate::lane::{Lane, V3};
use crate::math::{Math, Real, Vec3};
use crate::report::StepReport;

use super::node::NodeInput;

/// What a step measures along the way, per lane: strain extremes, penetration and contacts
/// (the momentum the colliders gave is kept apart, in a [`ColliderPush`]: these few running
/// values can then live in registers through the node loop). Nothing is ever summed across
/// lanes; sums run along each strand in node order in both paths, so they are the same bits.
#[derive(Clone, Copy, Debug)]
pub struct Measures<T> {
    /// Largest strain `(|e|² − l²)/(2 l²)` of a segment without contact (≥ 0).
    pub stretched: T,
    /// Largest `−strain` of a segment without contact (≥ 0).
    pub compressed: T,
    /// Largest strain of a segment with a pushed node.
    pub contact_stretched: T,
    /// Largest `−strain` of a segment with a pushed node.
    pub contact_compressed: T,
    /// Deepest node left inside a collider.
    pub penetration: T,
    /// Nodes pushed out.
    pub contacts: T,
}

/// `Σ m Δx^push` per collider (the push-outs, mass weighted), per lane.
pub type ColliderPush<T> = [V3<T>; MAX_COLLIDERS];

/// What a strand's free nodes' momentum lost over a step to the corrections, per lane:
/// `Σ m (v + a Δt) − Σ m v⁺`, the momentum each node would end the step with under the
/// external forces alone less the momentum it ends with, summed in node order as the pass goes
/// (each node's terms where the pass has them in registers, `pipeline::dftl`). One sum, not
/// the two momenta apart: on the Cortex-M4F the second sum's three registers spilled in the
/// node loop. The head transmits it, less the colliders' share ([`Tally::head_force`]).
#[derive(Clone, Copy, Debug)]
pub struct Momenta<T: Lane> {
    /// `Σ m (v + a Δt) − Σ m v⁺` so far.
    pub lost: V3<T>,
}

impl<T: Lane> Momenta<T> {
    /// Before the first node.
    #[inline(always)]
    #[must_use]
    pub fn zero() -> Self {
        Momenta { lost: V3::zero() }
    }
}

impl<T: Lane> Default for Measures<T> {
    fn default() -> Self {
        let zero = T::splat(0.0);
        Measures {
            stretched: zero,
            compressed: zero,
            contact_stretched: zero,
            contact_compressed: zero,
            penetration: zero,
            contacts: zero,
        }
    }
}

/// The segment from the final node `i − 1` to node `i`: its edge and squared length, which
/// the frame update reads next.
#[derive(Clone, Copy, Debug)]
pub struct Segment<T> {
    /// `e = x*_i − x*_{i−1}`.
    pub edge: V3<T>,
    /// `|e|²`.
    pub squared_length: T,
}

impl<T: Lane> Measures<T> {
    /// Measures the segment from `previous` to the final `x` of `node`: its strain
    /// `(|e|² − l²)/(2l²) = δ + δ²/2` for the relative stretch δ (no square root; turned into
    /// δ once per strand), into the extremes of segments with contact where `touched` (a
    /// collider pushed this node or the one before) when `collisions`, without otherwise.
    #[inline(always)]
    pub fn segment(
        &mut self,
        collisions: bool,
        previous: V3<T>,
        x: V3<T>,
        node: &NodeInput<T>,
        touched: T::Mask,
    ) -> Segment<T> {
        let active = node.active;
        let edge = x - previous;
        let squared_length = edge.dot(edge);
        let strain =
            (squared_length - node.segment_length * node.segment_length) * node.strain_scale;
        if collisions {
            let free = active & !touched;
            if T::all(free) {
                // The common case, every lane free: the masked form below selects `strain`
                // for the free extremes and adds a 0 to the (non-negative) contact ones, which
                // leaves them as they are — the same bits, without the selects.
                self.stretched = self.stretched.max(strain);
                self.compressed = self.compressed.max(-strain);
            } else {
                let pushed = active & touched;
                self.stretched = self.stretched.max_where(free, strain);
                self.compressed = self.compressed.max_where(free, -strain);
                self.contact_stretched = self.contact_stretched.max_where(pushed, strain);
                self.contact_compressed = self.contact_compressed.max_where(pushed, -strain);
            }
        } else {
            // No collider, no contact: the contact extremes stay 0 in both forms.
            self.stretched = self.stretched.max_where(active, strain);
            self.compressed = self.compressed.max_where(active, -strain);
        }
        Segment {
            edge,
            squared_length,
        }
    }

    /// The largest relative stretch of a segment without and with a pushed node, per lane.
    #[inline(always)]
    #[must_use]
    pub fn stretches<M: Math>(&self) -> (T, T) {
        (
            largest_stretch::<M, T>(self.stretched, self.compressed),
            largest_stretch::<M, T>(self.contact_stretched, self.contact_compressed),
        )
    }
}

/// The relative stretch `δ` of a strain `s = δ + δ²/2`: `δ = 2s / (1 + √(1 + 2s))` (the form
/// without cancellation for small `s`), on lanes so a block turns all its strands' strains at
/// once.
#[inline(always)]
fn relative_stretch<M: Math, T: Lane>(strain: T) -> T {
    let (one, two) = (T::splat(1.0), T::splat(2.0));
    two * strain / (one + (one + two * strain).max(T::splat(0.0)).sqrt::<M>())
}

/// The largest `|δ|` of the strains between `−down` and `up`: `δ(s)` grows with `s`, so it is
/// at one end or the other.
#[inline(always)]
fn largest_stretch<M: Math, T: Lane>(up: T, down: T) -> T {
    // Both extremes still at their start, 0 (no segment of the kind, as the contact ones of a
    // strand without contact: the extremes are maxima from 0 and never NaN): δ is 0 at both
    // ends, `+0` as the formula gives it, without its two square roots and divisions.
    let zero = T::splat(0.0);
    if !T::any(zero.lt(up)) && !T::any(zero.lt(down)) {
        return zero;
    }
    relative_stretch::<M, T>(up).max(-relative_stretch::<M, T>(-down))
}

/// What a strand (or a block's lane) tells the report about its segments and contacts.
#[derive(Clone, Copy, Debug, Default)]
pub struct Tally {
    /// Largest relative stretch `| |e| − l | / l` of a segment without a pushed node.
    pub stretch: Real,
    /// Largest relative stretch of a segment with a pushed node.
    pub contact_stretch: Real,
    /// Deepest node left inside a collider.
    pub penetration: Real,
    /// Nodes pushed out.
    pub contacts: u32,
    /// `Σ m (v + a Δt) − Σ m v⁺` over the free nodes ([`Momenta::lost`]).
    pub lost: Vec3,
    /// The force the head feels from the strand ([`Tally::head_force`]), N; the report takes
    /// it after the guard, from strands that were not rolled back.
    pub head_force: Vec3,
}

impl Tally {
    /// One strand's measures as the report gives them (a block builds its lanes' tallies
    /// from [`Measures::stretches`] of all lanes at once); `collider_push` are the pushes on
    /// the scene's colliders in use (one entry each: [`Tally::head_force`]); `momenta` are
    /// the free nodes' momenta over the pass ([`Momenta`]).
    #[must_use]
    pub fn from_measures<M: Math>(
        m: &Measures<Real>,
        collider_push: &[V3<Real>],
        momenta: Momenta<Real>,
        inv_dt: Real,
    ) -> Self {
        let (stretch, contact_stretch) = m.stretches::<M>();
        let lost = momenta.lost.into();
        Tally {
            stretch,
            contact_stretch,
            penetration: m.penetration,
            contacts: m.contacts as u32,
            lost,
            head_force: Self::head_force(lost, collider_push, inv_dt),
        }
    }

    /// The force the head feels from one DFTL strand, N. DFTL moves nodes by one-sided
    /// corrections (follow-the-leader, shape, the eq. 14 damping), so no constraint force can
    /// be read off a node; what the held root nodes transmit is the change of the free
    /// nodes' momentum that the external forces and the colliders do not explain, with the
    /// opposite sign: `(Σ m (v + a Δt) − Σ m v⁺)/Δt + Σ m Δx^push/Δt²` (the colliders feel
    /// `−Σ m Δx^push/Δt²`), `lost` being the difference of the sums ([`Momenta::lost`]),
    /// `collider_push` the pushes on the scene's colliders in use (0 with collisions off: the
    /// others have none). At rest: the weight the strand does not lay on a collider. It
    /// counts the shape springs' pull (their targets move with the head) and the damping's;
    /// the force a grab's device feels is subtracted by the caller where the strand is held.
    #[must_use]
    pub fn head_force(lost: Vec3, collider_push: &[V3<Real>], inv_dt: Real) -> Vec3 {
        let pushed = collider_push
            .iter()
            .fold(Vec3::ZERO, |sum, &p| sum + Vec3::from(p));
        lost * inv_dt + pushed * (inv_dt * inv_dt)
    }

    /// Folds the tally's maxima and counts into `report`. The pushes on the colliders wait for
    /// the guard's verdict ([`Tally::report_pushes`]).
    pub fn report(&self, report: &mut StepReport) {
        // `Lane::max`, a compare: `f32::max` is a library call on the Cortex-M4F.
        report.max_stretch = Lane::max(report.max_stretch, self.stretch);
        report.max_contact_stretch = Lane::max(report.max_contact_stretch, self.contact_stretch);
        report.max_penetration = Lane::max(report.max_penetration, self.penetration);
        report.contacts += self.contacts;
    }

    /// Each collider's contact force `−Σ m Δx^push / Δt²` (the hair's push on the collider, as
    /// the rod solver reports it) from `collider_push` into `report`, for the scene's colliders
    /// in use, whose pushes `collider_push` holds (none with collisions off; the others have no
    /// push to add). Added strand by strand in strand order, for a strand whose step the guard
    /// kept: a strand rolled back did not push (and a lane that went NaN would add NaN).
    pub fn report_pushes(report: &mut StepReport, collider_push: &[V3<Real>], inv_dt: Real) {
        let scale = -(inv_dt * inv_dt);
        for (force, &push) in report.collider_forces.iter_mut().zip(collider_push) {
            *force += Vec3::from(push) * scale;
        }
    }
}
