//! Root coupling, shared by both solvers and every path: nodes 0 and 1 of every strand are
//! prescribed by the head's rigid motion (Kmoch 2009 Sec. 8.1, `C_R0 = x̂_0 − x_0`,
//! `C_R1 = x̂_1 − x_1`, as prescribed nodes of infinite mass; Sánchez-Banderas 2015
//! Algorithm 1 moves every particle "after root"). Their velocity is the position change over
//! the step.
//!
//! Written once on lanes ([`held_node`]): a rod or DFTL strand couples its roots with
//! `T = Real`, a DFTL block all its lanes' at once, the same operations per strand
//! ([`Roots`]). The rod also carries its root frame with the head ([`carry_root_frame`]).

use crate::context::StepContext;
use crate::frames::{rest_root_frame, transport_in_time, unwrap_near};
use crate::lane::{component_sum, Lane, Q, V3};
use crate::math::{Math, Vec3};
use crate::report::{Stage, StepReport};
use crate::strand::Strand;

/// Strands whose roots the head holds: one strand (`Lane = Real`) or a block's lanes.
pub trait Roots {
    /// The lane type the roots are read and written in.
    type Lane: Lane;
    /// How many strands.
    fn count(&self) -> u32;
    /// Held node `i` (0 or 1): its rest position in the head's frame, and its position.
    fn held(&self, i: usize) -> (V3<Self::Lane>, V3<Self::Lane>);
    /// Sets held node `i`'s position and velocity.
    fn set_held(&mut self, i: usize, position: V3<Self::Lane>, velocity: V3<Self::Lane>);
}

/// The head's pose at the end of the step, in lanes, and `1/h`.
#[derive(Clone, Copy, Debug)]
pub struct Head<T> {
    /// The head's rotation.
    pub rotation: Q<T>,
    /// The head's translation.
    pub position: V3<T>,
    /// `1/h`.
    pub inv_dt: T,
}

impl<T: Lane> Head<T> {
    /// The head of the step `ctx` describes, in every lane.
    #[inline(always)]
    #[must_use]
    pub fn of(ctx: &StepContext) -> Self {
        Head {
            rotation: Q::splat(ctx.head.rotation),
            position: V3::splat(ctx.head.position),
            inv_dt: T::splat(ctx.inv_dt),
        }
    }
}

/// One held root node: its rest position moved with the head (`math::rotate` then the
/// translation, as [`crate::head::Pose::transform_point`]), and the velocity that gets it
/// there from `position` in one step.
#[inline(always)]
#[must_use]
pub fn held_node<T: Lane>(head: &Head<T>, rest_position: V3<T>, position: V3<T>) -> (V3<T>, V3<T>) {
    let target = head.rotation.rotate(rest_position) + head.position;
    (target, (target - position).scale(head.inv_dt))
}

/// The root coupling stage: nodes 0 and 1 of `roots` follow the head. Returns
/// the [`component_sum`] of the two velocities it wrote, added, per lane, for a
/// solver that watches what it writes.
#[inline(always)]
pub fn root_coupling<R: Roots>(
    roots: &mut R,
    ctx: &StepContext,
    report: &mut StepReport,
) -> R::Lane {
    report.ran_on(Stage::RootCoupling, roots.count());
    let head = Head::of(ctx);
    let mut velocity_total = R::Lane::splat(0.0);
    for i in 0..2 {
        let (rest_position, position) = roots.held(i);
        let (target, velocity) = held_node(&head, rest_position, position);
        roots.set_held(i, target, velocity);
        velocity_total = velocity_total + component_sum(velocity);
    }
    velocity_total
}

impl<const N: usize> Roots for Strand<N> {
    type Lane = crate::math::Real;

    #[inline(always)]
    fn count(&self) -> u32 {
        1
    }

    #[inline(always)]
    fn held(&self, i: usize) -> (V3<Self::Lane>, V3<Self::Lane>) {
        (self.rest.position[i].into(), self.state.position[i].into())
    }

    #[inline(always)]
    fn set_held(&mut self, i: usize, position: V3<Self::Lane>, velocity: V3<Self::Lane>) {
        self.state.velocity[i] = velocity.into();
        self.state.position[i] = position.into();
    }
}

/// The velocity the head gives held node `i` of `strand` this step, without moving it (the
/// rod's implicit bending step needs it as a boundary condition before the roots move).
#[inline(always)]
#[must_use]
pub fn held_velocity<const N: usize>(ctx: &StepContext, strand: &Strand<N>, i: usize) -> Vec3 {
    let (rest_position, position) = strand.held(i);
    held_node(&Head::of(ctx), rest_position, position).1.into()
}

/// The rod's root frame after [`root_coupling`] (Kmoch Sec. 5, 6.1): the root Bishop vector
/// `u^0` follows the root tangent from `old_tangent` by time-parallel transport (the root
/// segment is final here: the projection never moves prescribed nodes), and `θ^0` becomes the
/// angle from `u^0` to the head-fixed root material vector, so hair follows head roll.
pub fn carry_root_frame<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    old_tangent: Vec3,
) {
    let state = &mut strand.state;
    let tangent = crate::math::unit::<M>(state.position[1] - state.position[0]);
    let u = transport_in_time::<M>(old_tangent, tangent, state.root_frame);
    let rest = &strand.rest;
    let rest_material =
        rest_root_frame::<M>(rest.position[0], rest.position[1], rest.segment_length[0]);
    let material = ctx.head.transform_vector(rest_material);
    // `angle_in_frame(u, t × u, material)` with the triple product as `t·(u × material)`:
    // the same angle, and exactly 0 when the material vector is `u` (the rest state).
    let angle = M::atan2(tangent.dot(u.cross(material)), u.dot(material));
    state.theta[0] = unwrap_near(angle, state.theta[0]);
    state.root_frame = u;
}

/// The elastic forces the hair exerts on the held nodes 0 and 1 (Kmoch Sec. 7.2's `F_0 + F_1`,
/// which root coupling overrides): the rod's share of what a strand transmits to the head
/// besides its constraint force on node 1. One strand or lanes (`P::V`).
#[inline(always)]
#[must_use]
pub fn elastic_on_root<P: crate::precision::Kernel, const N: usize>(forces: &[P::V; N]) -> P::V {
    forces[0] + forces[1]
}
