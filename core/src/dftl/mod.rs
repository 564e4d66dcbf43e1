//! Dynamic Follow-The-Leader with shape preservation: Sánchez-Banderas et al. 2015 Sec. 3.1,
//! Algorithm 1 lines 12–27 (local dynamics), after Müller, Kim and Chentanez 2012.
//!
//! Nodes 0 and 1 follow the head (root coupling, shared with the rod solver). Then for each
//! node `i = 2 …` from the root, in order, one line per stage of Algorithm 1:
//!
//! | line  | stage | file |
//! |---|---|---|
//! | 13–14 | external accelerations, prediction `x* = x + vΔt + aΔt²` | [`predict`] |
//! | 18    | global then local shape, eqs. (8)–(9) | [`shape`] |
//! | 19    | follow-the-leader inextensibility, eq. (10) | [`follow_leader`] |
//! | 20    | push out of colliders (not in the correction) | [`collisions`] |
//! | 21    | frame update | [`frame`] |
//! | 24–26 | velocity with the `s_d` correction, eq. (14); `x ← x*` | [`velocity`] |
//!
//! Lines 24–26 run one node behind (node `i − 1` is finished as soon as node `i`'s correction
//! is known), so a step is a single pass whose cost is fixed by the scene.
//!
//! Eq. (14)'s velocity correction feeds back the local-shape and follow-the-leader
//! corrections of the next node, not the global one: [`velocity`] says why and what was
//! measured. With inextensibility only, `s_d = 0.9` removes the energy plain FTL pumps in (78 %
//! of a swing's energy lost in 2 s, vs. plain FTL gaining up to 70×).
//!
//! Frames are carried as tangent and normal vectors ([`frame`]): with the tangent taken from
//! the follow-the-leader step, a node costs one square root and, with shape, two divisions;
//! segment strain is measured as `(|e|² − l²)/(2l²)` (no square root) and turned into a
//! relative stretch once per strand.
//!
//! Two forms give the same bits: [`step`] on one `Strand<N>`, and [`block::step_block`] on a
//! structure-of-arrays block of `W` strands, node index `k` of every lane together, calling
//! the same per-node functions lane by lane (the compiler vectorises across lanes; nothing is
//! ever summed across lanes).

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

pub mod block;
pub mod collisions;
pub mod follow_leader;
pub mod frame;
pub mod lane;
pub mod predict;
pub mod rest;
pub mod shape;
pub mod velocity;

pub use block::{step_block, step_blocks, DftlBlock, RECOMMENDED_LANES};
pub use rest::DftlRest;

use crate::collide::{Shape, MAX_COLLIDERS};
use crate::context::StepContext;
use crate::effects::Effect;
use crate::math::{Mat3, Math, Real, Vec3};
use crate::params::DftlCoefficients;
use crate::report::{Stage, StepReport};
use crate::strand::Strand;

use lane::{Lane, V3};

/// Everything a DFTL step derives once from the context and shares by every strand and lane.
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    /// `Δt`.
    pub dt: Real,
    /// `Δt²`.
    pub dt_squared: Real,
    /// `1/Δt`.
    pub inv_dt: Real,
    /// `s_d / Δt`.
    pub damping_over_dt: Real,
    /// Gravity plus wind (each zero when off).
    pub base_acceleration: Vec3,
    /// Whether drag runs.
    pub drag: bool,
    /// Drag `ν`, kg/s.
    pub drag_coefficient: Real,
    /// Whether the shape constraints (and the frames they need) run.
    pub shape: bool,
    /// Whether follow-the-leader inextensibility runs.
    pub inextensibility: bool,
    /// Whether any collider is in use.
    pub collisions: bool,
    /// `s_g`, `s_l`, `s_d` at this `dt`.
    pub coefficients: DftlCoefficients,
    /// The head's rotation as a matrix (global targets, root frame).
    pub head_rotation: Mat3,
    /// The head's translation.
    pub head_position: Vec3,
}

impl Setup {
    /// The setup of the step described by `ctx`.
    #[must_use]
    pub fn new(ctx: &StepContext) -> Self {
        Setup {
            dt: ctx.dt,
            dt_squared: ctx.dt * ctx.dt,
            inv_dt: ctx.inv_dt,
            damping_over_dt: ctx.dftl.damping * ctx.inv_dt,
            base_acceleration: ctx.gravity + ctx.wind,
            drag: ctx.has(Effect::Drag),
            drag_coefficient: ctx.params.drag,
            shape: ctx.has(Effect::Shape),
            inextensibility: ctx.has(Effect::Inextensibility),
            collisions: !ctx.colliders().is_empty(),
            coefficients: ctx.dftl,
            head_rotation: Mat3::from_quat(ctx.head.rotation),
            head_position: ctx.head.position,
        }
    }

    /// `R_head v`, summed column by column as glam's `Mat3 * Vec3`.
    #[inline(always)]
    #[must_use]
    pub fn head_rotate<T: Lane>(&self, v: V3<T>) -> V3<T> {
        let r = &self.head_rotation;
        V3::splat(r.x_axis).scale(v.x)
            + V3::splat(r.y_axis).scale(v.y)
            + V3::splat(r.z_axis).scale(v.z)
    }

    /// Counts `strands` strands through the stages that run.
    pub fn count_stages(
        &self,
        ctx: &StepContext,
        accelerations: bool,
        strands: u32,
        report: &mut StepReport,
    ) {
        let mut ran = |stage: Stage| report.stage_runs[stage as usize] += strands;
        if ctx.has(Effect::Gravity) || ctx.has(Effect::Wind) || self.drag || accelerations {
            ran(Stage::ExternalForces);
        }
        ran(Stage::Integrate);
        if self.shape {
            ran(Stage::Shape);
        }
        if self.inextensibility {
            ran(Stage::Projection);
        }
        if self.collisions {
            ran(Stage::Collisions);
        }
        ran(Stage::Velocity);
    }
}

/// One free node's inputs (per lane): its state at the start of the step and its rest data.
#[derive(Clone, Copy, Debug)]
pub struct NodeInput<T: Lane> {
    /// `x_i`.
    pub position: V3<T>,
    /// `v_i`.
    pub velocity: V3<T>,
    /// The caller's acceleration (used where `has_extra`).
    pub extra: V3<T>,
    /// Whether the caller gave an acceleration.
    pub has_extra: T::Mask,
    /// `m_i` (weighs the collider's push).
    pub mass: T,
    /// `1/m_i`.
    pub inverse_mass: T,
    /// `x̂_i` (head frame).
    pub rest_position: V3<T>,
    /// `r_i`.
    pub local_rest: V3<T>,
    /// `d_i / L`.
    pub root_distance: T,
    /// `l_i = |x̂_i − x̂_{i−1}|`.
    pub segment_length: T,
    /// `1/(2 l_i²)`.
    pub strain_scale: T,
}

/// What node `i` needs of the final node `i − 1`: its position and frame `(t, n, t × n)`.
#[derive(Clone, Copy, Debug)]
pub struct Chain<T> {
    /// `x*_{i−1}`, final.
    pub position: V3<T>,
    /// `t_{i−1} = R_{i−1} e_x`, the unit incoming edge.
    pub tangent: V3<T>,
    /// `n_{i−1} = R_{i−1} e_y`.
    pub normal: V3<T>,
}

impl<T: Lane> Chain<T> {
    /// The chain at node 1 (held by the head): `R_1 = R_0 = R_head R̂_0`, given by its columns.
    #[inline(always)]
    #[must_use]
    pub fn start(setup: &Setup, root_tangent: V3<T>, root_normal: V3<T>, x1: V3<T>) -> Self {
        Chain {
            position: x1,
            tangent: setup.head_rotate(root_tangent),
            normal: setup.head_rotate(root_normal),
        }
    }

    /// Per lane `if mask { a } else { b }`.
    #[inline(always)]
    #[must_use]
    pub fn select(mask: T::Mask, a: &Self, b: &Self) -> Self {
        Chain {
            position: V3::select(mask, a.position, b.position),
            tangent: V3::select(mask, a.tangent, b.tangent),
            normal: V3::select(mask, a.normal, b.normal),
        }
    }
}

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

/// The outcome of [`advance`] for one node.
#[derive(Clone, Copy, Debug)]
pub struct Advanced<T: Lane> {
    /// The chain at this node (its final position and frame).
    pub chain: Chain<T>,
    /// `Δx^lcl_i + Δx^inex_i`, fed back into node `i − 1`'s velocity (eq. 14).
    pub correction: V3<T>,
    /// Whether a collider pushed the node.
    pub contact: T::Mask,
}

/// SB15 Algorithm 1 lines 13–21 for node `i` of every lane where `active` (a lane past its
/// last node computes but adds nothing): predict, shape, follow the leader, collisions, the
/// segment's strain, the frame. One function for the per-strand path (`T = Real`, `active`
/// true) and the block path, so both run the same operations per strand.
#[inline(always)]
#[must_use]
#[allow(clippy::too_many_arguments)]
pub fn advance<M: Math, T: Lane>(
    setup: &Setup,
    colliders: &[Shape],
    node: &NodeInput<T>,
    chain: &Chain<T>,
    active: T::Mask,
    previous_contact: T::Mask,
    measures: &mut Measures<T>,
    collider_push: &mut ColliderPush<T>,
) -> Advanced<T> {
    let zero = T::splat(0.0);
    // Lines 13–14: external accelerations, prediction (eq. 1).
    let a = predict::acceleration(
        setup,
        node.velocity,
        node.inverse_mass,
        node.extra,
        node.has_extra,
    );
    let mut x = predict::predicted_position(setup, node.position, node.velocity, a);
    // Line 18: shape, eqs. (8), (9) — the local target uses x* after the global step.
    // Eq. (14) feeds back the local and the follow-the-leader corrections, not the global
    // one (see [`velocity`] for why).
    let mut correction = V3::zero();
    if setup.shape {
        x = x + shape::global_correction(setup, node.rest_position, node.root_distance, x);
        correction = shape::local_correction(
            setup,
            chain.position,
            chain.tangent,
            chain.normal,
            node.local_rest,
            node.root_distance,
            x,
        );
        x = x + correction;
    }
    // Line 19: follow the leader, eq. (10); its direction is the frame's next tangent.
    let mut tangent = chain.tangent;
    let mut tangent_known = T::mask(false);
    if setup.inextensibility {
        let (projected, t) =
            follow_leader::project::<M, T>(chain.position, x, node.segment_length, chain.tangent);
        correction = correction + (projected - x);
        x = projected;
        tangent = t;
        tangent_known = T::mask(true);
    }
    // Line 20: collisions (each collider in turn), then what is left inside.
    let mut contact = T::mask(false);
    if setup.collisions {
        for (shape, push) in colliders.iter().zip(collider_push.iter_mut()) {
            let (pushed, inside) = collisions::push_out::<M, T>(shape, x);
            // Where no lane was pushed, `pushed − x` is 0 in every lane: nothing to add. (The
            // mass is rest data: a `1/inverse_mass` here was hoisted out of the branch by the
            // compiler, a 14-cycle division at every node on the Cortex-M4F.)
            if T::any(inside) {
                *push = *push + V3::select(active, (pushed - x).scale(node.mass), V3::zero());
            }
            x = pushed;
            contact = contact | inside;
        }
        // A node no collider pushed passed every collider's inside test where it now is:
        // it is outside them all (at most an ulp inside the radius, rounding), so only the
        // pushed ones are measured.
        let pushed = active & contact;
        if T::any(pushed) {
            for shape in colliders {
                let depth = collisions::depth::<M, T>(shape, x);
                measures.penetration = measures.penetration.max_where(pushed, depth);
            }
            // (Where no lane was pushed this adds 0 to every lane: skipped.)
            measures.contacts = measures.contacts + T::select(pushed, T::splat(1.0), zero);
        }
    }
    // The segment's strain, no square root: `(|e|² − l²)/(2l²) = δ + δ²/2` for the relative
    // stretch δ (turned into δ once per strand, [`Tally::from_measures`]).
    let e = x - chain.position;
    let squared_length = e.dot(e);
    let strain = (squared_length - node.segment_length * node.segment_length) * node.strain_scale;
    if setup.collisions {
        let touched = contact | previous_contact;
        let free = active & !touched;
        if T::all(free) {
            // The common case, every lane free: the masked form below selects `strain`
            // for the free extremes and adds a 0 to the (non-negative) contact ones, which
            // leaves them as they are — the same bits, without the selects.
            measures.stretched = measures.stretched.max(strain);
            measures.compressed = measures.compressed.max(-strain);
        } else {
            let pushed = active & touched;
            measures.stretched = measures.stretched.max_where(free, strain);
            measures.compressed = measures.compressed.max_where(free, -strain);
            measures.contact_stretched = measures.contact_stretched.max_where(pushed, strain);
            measures.contact_compressed = measures.contact_compressed.max_where(pushed, -strain);
        }
    } else {
        // No collider, no contact: the contact extremes stay 0 in both forms.
        measures.stretched = measures.stretched.max_where(active, strain);
        measures.compressed = measures.compressed.max_where(active, -strain);
    }
    // Line 21: the frame, carried only when the shape constraints need it. The tangent from
    // follow-the-leader holds unless a collider moved the node (or there was no projection).
    let next = if setup.shape {
        let known = tangent_known & !contact;
        let t = if T::all(known) {
            tangent
        } else {
            let length = squared_length.sqrt::<M>();
            let exact = V3::select(
                zero.lt(length),
                e.scale(T::splat(1.0) / length),
                chain.tangent,
            );
            V3::select(known, tangent, exact)
        };
        Chain {
            position: x,
            tangent: t,
            normal: frame::transport(chain.tangent, chain.normal, t),
        }
    } else {
        Chain {
            position: x,
            ..*chain
        }
    };
    Advanced {
        chain: next,
        correction,
        contact,
    }
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
    /// `Σ m Δx^push` per collider.
    pub collider_push: [Vec3; MAX_COLLIDERS],
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
    relative_stretch::<M, T>(up).max(-relative_stretch::<M, T>(-down))
}

impl<T: Lane> Measures<T> {
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

impl Tally {
    /// One strand's measures as the report gives them (a block builds its lanes' tallies
    /// from [`Measures::stretches`] of all lanes at once).
    #[must_use]
    pub fn from_measures<M: Math>(m: &Measures<Real>, collider_push: &ColliderPush<Real>) -> Self {
        let (stretch, contact_stretch) = m.stretches::<M>();
        Tally {
            stretch,
            contact_stretch,
            penetration: m.penetration,
            contacts: m.contacts as u32,
            collider_push: collider_push.map(Vec3::from),
        }
    }

    /// Folds the tally into `report`: maxima and counts, and each collider's contact force
    /// `−Σ m Δx^push / Δt²` (the hair's push on the collider, as the rod solver reports it),
    /// added strand by strand in strand order, for the scene's first `colliders` colliders (0
    /// with collisions off; the others have no push to add).
    pub fn report(&self, report: &mut StepReport, colliders: usize, inv_dt: Real) {
        // `Lane::max`, a compare: `f32::max` is a library call on the Cortex-M4F.
        report.max_stretch = Lane::max(report.max_stretch, self.stretch);
        report.max_contact_stretch = Lane::max(report.max_contact_stretch, self.contact_stretch);
        report.max_penetration = Lane::max(report.max_penetration, self.penetration);
        report.contacts += self.contacts;
        let scale = -(inv_dt * inv_dt);
        let forces = report.collider_forces.iter_mut().zip(self.collider_push);
        for (force, push) in forces.take(colliders) {
            *force += push * scale;
        }
    }
}

/// Steps one strand by `ctx.dt` (SB15 Algorithm 1, local dynamics), `setup` being
/// [`Setup::new`] of `ctx` (built once for all strands). `accelerations` (if any) are the
/// caller's per-node accelerations for this strand, indexed by node. Never panics;
/// returns whether every value it wrote is finite ([`velocity::not_finite`]), and the
/// caller's guard rolls back a strand where it is not.
pub fn step<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    setup: &Setup,
    ctx: &StepContext,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) -> bool {
    // Line 12's root: nodes 0 and 1 follow the head, exactly as in the rod solver.
    crate::rod::step::root_coupling(strand, ctx, report);
    setup.count_stages(ctx, accelerations.is_some(), 1, report);
    // 0 while every velocity written is finite.
    let mut poison: Real = 0.0;
    for v in strand.state.velocity.iter().take(2) {
        poison += velocity::not_finite(V3::from(*v));
    }
    if strand.rest.nodes.min(N) < 3 {
        return poison == 0.0;
    }
    let colliders = ctx.colliders();
    let mut collider_push = [V3::zero(); MAX_COLLIDERS];
    let (measures, pass_poison) = with_effect_switches!(
        setup,
        strand_pass::<M, N>(setup, strand, colliders, accelerations, &mut collider_push)
    );
    Tally::from_measures::<M>(&measures, &collider_push).report(
        report,
        colliders.len(),
        setup.inv_dt,
    );
    poison + pass_poison == 0.0
}

/// Nodes `2 …` of one strand with the effect switches fixed: lines 13–21 for node `i`, then
/// lines 24–26 for node `i − 1`. Returns what it measured and the sum of
/// [`velocity::not_finite`] over the velocities it wrote.
#[inline(never)]
fn strand_pass<
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
    collider_push: &mut ColliderPush<Real>,
) -> (Measures<Real>, Real) {
    let setup = Setup {
        shape: SHAPE,
        inextensibility: INEXTENSIBLE,
        drag: DRAG,
        ..*setup
    };
    let n = strand.rest.nodes.min(N);
    let rest = &strand.rest;
    let state = &mut strand.state;
    let mut chain = Chain::start(
        &setup,
        rest.dftl.root_tangent.into(),
        rest.dftl.root_normal.into(),
        state.position[1].into(),
    );
    let mut measures = Measures::default();
    let mut poison: Real = 0.0;
    let mut previous_contact = false;
    for i in 2..n {
        let extra = accelerations.and_then(|a| a.get(i)).copied();
        let node = NodeInput {
            position: state.position[i].into(),
            velocity: state.velocity[i].into(),
            extra: extra.unwrap_or(Vec3::ZERO).into(),
            has_extra: extra.is_some(),
            mass: rest.mass[i],
            inverse_mass: rest.inverse_mass[i],
            rest_position: rest.position[i].into(),
            local_rest: rest.dftl.local_rest[i].into(),
            root_distance: rest.dftl.root_distance[i],
            segment_length: rest.segment_length[i - 1],
            strain_scale: rest.dftl.strain_scale[i],
        };
        // Lines 13–21: predict, shape, follow the leader, collisions, frame.
        let next = advance::<M, Real>(
            &setup,
            colliders,
            &node,
            &chain,
            true,
            previous_contact,
            &mut measures,
            collider_push,
        );
        // Lines 24–26 for node i − 1, now that node i's correction is known.
        if i > 2 {
            let (x_new, v_new) = velocity::finish(
                &setup,
                chain.position,
                state.position[i - 1].into(),
                next.correction,
            );
            state.position[i - 1] = x_new.into();
            state.velocity[i - 1] = v_new.into();
            poison += velocity::not_finite(v_new);
        }
        chain = next.chain;
        previous_contact = next.contact;
    }
    // The last node: no correction (eq. 14 has no node n).
    let (x_new, v_new) = velocity::finish(
        &setup,
        chain.position,
        state.position[n - 1].into(),
        V3::zero(),
    );
    state.position[n - 1] = x_new.into();
    state.velocity[n - 1] = v_new.into();
    poison += velocity::not_finite(v_new);
    (measures, poison)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::collide::{Collider, Shape};
    use crate::effects::Effects;
    use crate::head::{Pose, Shake};
    use crate::math::Libm;
    use crate::params::{Params, Solver};
    use crate::strand::Material;
    use crate::world::{StepInput, World};

    fn wavy(nodes: usize, phase: Real) -> std::vec::Vec<Vec3> {
        (0..nodes)
            .map(|i| {
                let s = i as Real * 0.01;
                let (sin, cos) = Libm::sin_cos(40.0 * s + phase);
                Vec3::new(0.004 * sin, 0.05 + s, 0.004 * cos)
            })
            .collect()
    }

    fn params(effects: &[Effect]) -> Params {
        Params {
            solver: Solver::Dftl,
            effects: Effects::from_slice(effects),
            ..Params::DEFAULT
        }
    }

    #[test]
    fn a_strand_at_rest_with_shape_stays_at_rest() {
        let mut w: World<1, 16, Libm> =
            World::with_params(params(&[Effect::Shape, Effect::Inextensibility])).unwrap();
        let points = wavy(16, 0.3);
        w.add_strand(Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap())
            .unwrap();
        let input = StepInput {
            head: Pose::IDENTITY,
            accelerations: None,
        };
        for _ in 0..200 {
            w.step(&input);
        }
        for (p, q) in w.strands()[0].positions().iter().zip(&points) {
            assert!((*p - *q).length() < 1e-6, "{p} vs {q}");
        }
    }

    #[test]
    fn rest_frames_put_each_node_on_its_local_target() {
        let points = wavy(12, 1.1);
        let s = Strand::<12>::from_polyline(&points, &Material::HUMAN_HAIR).unwrap();
        let ctx = crate::context::StepContext::new(
            &params(&[Effect::Shape]),
            Pose::IDENTITY,
            Pose::IDENTITY,
            &[],
        );
        let setup = Setup::new(&ctx);
        let mut chain = Chain::start(
            &setup,
            s.rest.dftl.root_tangent.into(),
            s.rest.dftl.root_normal.into(),
            points[1].into(),
        );
        for (i, point) in points.iter().enumerate().skip(2) {
            let target = Vec3::from(chain.position)
                + Vec3::from(frame::rotate(
                    chain.tangent,
                    chain.normal,
                    s.rest.dftl.local_rest[i].into(),
                ));
            assert!((target - *point).length() < 1e-7, "node {i}");
            let node = NodeInput {
                position: (*point).into(),
                velocity: V3::zero(),
                extra: V3::zero(),
                has_extra: false,
                mass: s.rest.mass[i],
                inverse_mass: s.rest.inverse_mass[i],
                rest_position: s.rest.position[i].into(),
                local_rest: s.rest.dftl.local_rest[i].into(),
                root_distance: s.rest.dftl.root_distance[i],
                segment_length: s.rest.segment_length[i - 1],
                strain_scale: s.rest.dftl.strain_scale[i],
            };
            let mut measures = Measures::default();
            let mut push = [V3::zero(); MAX_COLLIDERS];
            chain = advance::<Libm, Real>(
                &setup,
                &[],
                &node,
                &chain,
                true,
                false,
                &mut measures,
                &mut push,
            )
            .chain;
            assert!(measures.stretched < 1e-6 && measures.compressed < 1e-6);
        }
        assert_eq!(s.rest.dftl.root_distance[11], 1.0);
    }

    #[test]
    fn block_gives_the_bits_of_the_per_strand_path() {
        // Every specialisation of both passes (`with_effect_switches!`): shape,
        // inextensibility and drag each on and off, with gravity, wind and a collider.
        for switches in 0..8u32 {
            let mut effects = std::vec![Effect::Gravity, Effect::Collisions, Effect::Wind];
            for (bit, effect) in [Effect::Shape, Effect::Inextensibility, Effect::Drag]
                .into_iter()
                .enumerate()
            {
                if switches & (1 << bit) != 0 {
                    effects.push(effect);
                }
            }
            // Both colliders reached in every configuration: the contact branches ran too.
            let contacts = block_matches_per_strand(&effects);
            assert!(contacts > 0, "{effects:?}");
        }
    }

    /// Steps both paths 300 steps and checks they agree (state, report); returns the
    /// contacts seen.
    fn block_matches_per_strand(effects: &[Effect]) -> u32 {
        let p = Params {
            effects: Effects::from_slice(effects),
            drag: 2.0e-7,
            ..params(&[])
        };
        let mut w: World<5, 16, Libm> = World::with_params(p).unwrap();
        w.add_collider(Collider {
            shape: Shape::Sphere {
                centre: Vec3::ZERO,
                radius: 0.05,
            },
            attached_to_head: true,
        })
        .unwrap();
        // A capsule across the strands 5 cm above the roots: they touch it with shape on too.
        w.add_collider(Collider {
            shape: Shape::Capsule {
                a: Vec3::new(-0.02, 0.1, 0.0),
                b: Vec3::new(0.02, 0.1, 0.0),
                radius: 0.005,
            },
            attached_to_head: true,
        })
        .unwrap();
        for s in 0..5 {
            let points = wavy(10 + s, s as Real);
            w.add_strand(Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap())
                .unwrap();
        }
        let mut blocks: [DftlBlock<4, 16>; 2] = [
            DftlBlock::from_strands(&w.strands()[..4]),
            DftlBlock::from_strands(&w.strands()[4..]),
        ];
        let coefficients = p.dftl.at_step(p.dt);
        let mut previous = Pose::IDENTITY;
        let mut contacts = 0;
        for k in 0..300u32 {
            let t = (k + 1) as Real * p.dt;
            let head = Shake::TEN_RAD_PER_S.pose_at::<Libm>(t);
            let report = w.step(&StepInput {
                head,
                accelerations: None,
            });
            let ctx = crate::context::StepContext::with_coefficients(
                &p,
                coefficients,
                previous,
                head,
                w.colliders(),
            )
            .at_time(t);
            let mut block_report = StepReport::default();
            step_blocks::<Libm, 4, 16>(&ctx, &mut blocks, 0, None, &mut block_report);
            previous = head;
            assert_eq!(report.stage_runs, block_report.stage_runs, "{effects:?}");
            let bits = |r: &StepReport| {
                let [a, b] = [r.collider_forces[0], r.collider_forces[1]];
                [
                    r.max_stretch,
                    r.max_contact_stretch,
                    r.max_penetration,
                    a.x,
                    a.y,
                    a.z,
                    b.x,
                    b.y,
                    b.z,
                ]
                .map(Real::to_bits)
            };
            assert_eq!(bits(&report), bits(&block_report), "{effects:?} step {k}");
            assert_eq!(report.contacts, block_report.contacts, "{effects:?}");
            contacts += report.contacts;
        }
        let mut strands: std::vec::Vec<Strand<16>> = w.strands().to_vec();
        blocks[0].store(&mut strands[..4]);
        blocks[1].store(&mut strands[4..]);
        assert_eq!(
            crate::hash::state_hash(&strands),
            w.state_hash(),
            "{effects:?}"
        );
        assert!(w.strands()[4].state.position[10].y != points_y(&wavy(14, 4.0)));
        contacts
    }

    fn points_y(p: &[Vec3]) -> Real {
        p[10].y
    }
}
