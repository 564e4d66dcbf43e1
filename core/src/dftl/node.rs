//! What DFTL's per-node stages read and hand on, on lanes: the step's [`Setup`] (derived once
//! from the context, shared by every strand and lane), one free node's [`NodeInput`], the
//! [`Chain`] node `i` needs of the final node `i − 1`, and what a node hands on ([`Advanced`]).

use crate::context::StepContext;
use crate::lane::{Lane, V3};
use crate::math::{Mat3, Real, Vec3};
use crate::params::DftlCoefficients;
use crate::strand::{RestStrand, StrandState};

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
    /// Whether the global shape constraint pulls (`s_g` > 0; with `shape`): a held strand's
    /// pass runs without it, and a node skips a correction that would add 0.
    pub global_shape: bool,
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
    /// Whether the shape damping runs (`dftl::damping`): shape on and `r` < 1.
    pub shape_damping: bool,
    /// `(1 − r) ω`: the head's rigid velocity at `x` is `ω × (x − t_head) + ṫ`
    /// (`dftl::damping`).
    pub damping_spin: Vec3,
    /// `(1 − r)(ṫ − ω × t_head)`, `ṫ = (t_head − t_prev)/Δt`.
    pub damping_offset: Vec3,
}

impl Setup {
    /// The setup of the step described by `ctx`: its gates as the three effect switches the
    /// passes are specialised for (`shape`, `inextensibility`, `drag`) and `collisions`.
    #[must_use]
    pub fn new(ctx: &StepContext) -> Self {
        let head_rotation = Mat3::from_quat(ctx.head.rotation);
        let (damping_spin, damping_offset) = damping_terms(ctx, head_rotation);
        Setup {
            dt: ctx.dt,
            dt_squared: ctx.dt * ctx.dt,
            inv_dt: ctx.inv_dt,
            damping_over_dt: ctx.dftl.damping * ctx.inv_dt,
            base_acceleration: ctx.gravity + ctx.wind,
            drag: ctx.gates.drag,
            drag_coefficient: ctx.params.drag,
            shape: ctx.gates.shape,
            global_shape: ctx.dftl.global_shape != 0.0,
            inextensibility: ctx.gates.inextensibility,
            collisions: ctx.gates.colliders,
            coefficients: ctx.dftl,
            head_rotation,
            head_position: ctx.head.position,
            shape_damping: ctx.gates.shape && ctx.dftl.shape_retention < 1.0,
            damping_spin,
            damping_offset,
        }
    }

    /// This setup with the three effect switches given as constants (a specialised pass).
    #[inline(always)]
    #[must_use]
    pub fn with_switches(&self, shape: bool, inextensibility: bool, drag: bool) -> Self {
        Setup {
            shape,
            inextensibility,
            drag,
            ..*self
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
}

/// `(1 − r) ω` and `(1 − r)(ṫ − ω × t)` of [`Setup`], once per step. Over the step the head
/// carries a point `x` from `R_prev R_headᵀ (x − t) + t_prev`: its velocity is
/// `A (x − t)/Δt + ṫ` with `A = I − R_prev R_headᵀ`, and `A` is `[θ]×` (`θ = ω Δt`, the turn of
/// the step) up to `O(θ²)`; `ω` is read from its antisymmetric part (no trigonometry).
fn damping_terms(ctx: &StepContext, head_rotation: Mat3) -> (Vec3, Vec3) {
    let pull = 1.0 - ctx.dftl.shape_retention;
    let carried_back = Mat3::from_quat(ctx.previous_head.rotation) * head_rotation.transpose();
    let a = Mat3::IDENTITY - carried_back;
    // [θ]× has θ_x at (2,1) and −θ_x at (1,2): columns are glam's axes.
    let theta = Vec3::new(
        a.y_axis.z - a.z_axis.y,
        a.z_axis.x - a.x_axis.z,
        a.x_axis.y - a.y_axis.x,
    ) * 0.5;
    let spin = theta * ctx.inv_dt;
    let head_velocity = (ctx.head.position - ctx.previous_head.position) * ctx.inv_dt;
    let offset = head_velocity - spin.cross(ctx.head.position);
    (spin * pull, offset * pull)
}

/// One free node's inputs (per lane): its state at the start of the step and its rest data.
#[derive(Clone, Copy, Debug)]
pub struct NodeInput<T: Lane> {
    /// Whether the lane has this node (a lane past its last node computes but adds nothing).
    pub active: T::Mask,
    /// `x_i`.
    pub position: V3<T>,
    /// `v_i`.
    pub velocity: V3<T>,
    /// The caller's acceleration (used where `has_extra`).
    pub extra: V3<T>,
    /// Whether the caller gave an acceleration.
    pub has_extra: T::Mask,
    /// `m_i` (drag, and weighs the collider's push).
    pub mass: T,
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

impl NodeInput<Real> {
    /// Node `i` of one strand (rest data `rest`, state `state`; `2 ≤ i < nodes`) with the
    /// caller's acceleration `extra`, if any.
    #[inline(always)]
    #[must_use]
    pub fn of_strand<const N: usize>(
        rest: &RestStrand<N>,
        state: &StrandState<N>,
        i: usize,
        extra: Option<Vec3>,
    ) -> Self {
        NodeInput {
            active: true,
            position: state.position[i].into(),
            velocity: state.velocity[i].into(),
            extra: extra.unwrap_or(Vec3::ZERO).into(),
            has_extra: extra.is_some(),
            mass: rest.mass[i],
            rest_position: rest.position[i].into(),
            local_rest: rest.dftl.local_rest[i].into(),
            root_distance: rest.dftl.root_distance[i],
            segment_length: rest.segment_length[i - 1],
            strain_scale: rest.dftl.strain_scale[i],
        }
    }
}

/// What node `i` needs of the final node `i − 1`: its position and frame `(t, n, t × n)`.
#[derive(Clone, Copy, Debug)]
pub struct Chain<T: Lane> {
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

/// What one node hands on: the chain at this node (its final position and frame), its
/// local-shape and follow-the-leader corrections, whose reactions go to the two nodes before
/// it (eq. 14, `dftl::velocity`), and whether a collider pushed it.
#[derive(Clone, Copy, Debug)]
pub struct Advanced<T: Lane> {
    /// The chain at this node.
    pub chain: Chain<T>,
    /// `Δx^lcl_i`.
    pub local: V3<T>,
    /// `Δx^inex_i`.
    pub inextensible: V3<T>,
    /// Whether a collider pushed the node (its segment to the next node is then measured as
    /// a segment with contact).
    pub contact: T::Mask,
    /// The node's external acceleration `a` (lines 13–14), for the head's force
    /// (`dftl::measures::Momenta`).
    pub acceleration: V3<T>,
}
