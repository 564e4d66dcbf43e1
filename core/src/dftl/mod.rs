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
//! Measured behaviour of the correction as specified (eq. 14 feeding back the shape
//! corrections too, `tests/dftl.rs`): with inextensibility only, `s_d = 0.9` removes the energy
//! plain FTL pumps in (78 % of a swing's energy lost in 2 s, vs. plain FTL gaining up to 70×);
//! with the shape constraints, feeding back `Δx^gbl_{i+1}` keeps a styled strand moving a few
//! centimetres around its rest shape (with `s_g` alone and `s_d = 0` it settles to 2 µm), and
//! with inextensibility *off*, shape + `s_d = 0.9` diverges (10^16 m within 3 s, measured).
//!
//! Two forms give the same bits: [`step`] on one `Strand<N>`, and [`block::step_block`] on a
//! structure-of-arrays block of `W` strands, node index `k` of every lane together, calling
//! the same per-node functions lane by lane (the compiler vectorises across lanes; nothing is
//! ever summed across lanes).

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

use crate::context::StepContext;
use crate::effects::Effect;
use crate::math::{self, Mat3, Math, Quat, Real, Vec3};
use crate::params::DftlCoefficients;
use crate::report::{Stage, StepReport};
use crate::strand::Strand;

use lane::{Lane, Q, V3};

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
    /// The head's rotation as a matrix (global targets).
    pub head_rotation: Mat3,
    /// The head's rotation (root frame).
    pub head_quaternion: Quat,
    /// The head's translation.
    pub head_position: Vec3,
}

impl Setup {
    /// The setup of the step described by `ctx`.
    #[must_use]
    pub fn new(ctx: &StepContext) -> Self {
        let q = ctx.head.rotation;
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
            head_rotation: Mat3::from_quat(q),
            head_quaternion: q,
            head_position: ctx.head.position,
        }
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
}

/// What node `i` needs of the final node `i − 1`: its position, frame and unit incoming edge.
#[derive(Clone, Copy, Debug)]
pub struct Chain<T> {
    /// `x*_{i−1}`, final.
    pub position: V3<T>,
    /// `R_{i−1}`.
    pub frame: Q<T>,
    /// `t_{i−1}`, the x-axis of `R_{i−1}`.
    pub tangent: V3<T>,
}

impl Chain<Real> {
    /// The chain at node 1 from the held nodes 0 and 1: `R_1 = R_0 = q_head · R̂_0`.
    #[must_use]
    pub fn start<M: Math>(setup: &Setup, root_frame: Quat, x0: Vec3, x1: Vec3) -> Self {
        let frame = math::quat_normalize::<M>(math::quat_mul(setup.head_quaternion, root_frame));
        let edge = x1 - x0;
        let length = M::sqrt(edge.dot(edge));
        let tangent = if length > 0.0 {
            edge * (1.0 / length)
        } else {
            math::rotate(frame, Vec3::X)
        };
        Chain {
            position: x1.into(),
            frame: frame.into(),
            tangent: tangent.into(),
        }
    }
}

impl<T: Lane> Chain<T> {
    /// Moves the chain on to the final node `x` (line 21: the frame is carried only when the
    /// shape constraints need it) and returns the segment's relative stretch `| |e| − l | / l`.
    #[inline(always)]
    #[must_use]
    pub fn advance<M: Math>(&self, setup: &Setup, x: V3<T>, segment_length: T) -> (Chain<T>, T) {
        let edge = x - self.position;
        let length = edge.dot(edge).sqrt::<M>();
        let stretch = (length - segment_length).abs() / segment_length;
        let (frame, tangent) = if setup.shape {
            frame::transport::<M, T>(self.frame, self.tangent, edge, length)
        } else {
            (self.frame, self.tangent)
        };
        (
            Chain {
                position: x,
                frame,
                tangent,
            },
            stretch,
        )
    }

    /// Per lane `if mask { a } else { b }`.
    #[inline(always)]
    #[must_use]
    pub fn select(mask: T::Mask, a: &Self, b: &Self) -> Self {
        Chain {
            position: V3::select(mask, a.position, b.position),
            frame: Q::select(mask, a.frame, b.frame),
            tangent: V3::select(mask, a.tangent, b.tangent),
        }
    }
}

/// Lines 13–14 and 18–19 for one node: the predicted position after shape and inextensibility,
/// and the total correction `Δx^gbl + Δx^lcl + Δx^inex` that eq. (14) feeds back.
#[inline(always)]
#[must_use]
pub fn project_node<M: Math, T: Lane>(
    setup: &Setup,
    node: &NodeInput<T>,
    chain: &Chain<T>,
) -> (V3<T>, V3<T>) {
    // Lines 13–14: external accelerations, prediction (eq. 1).
    let a = predict::acceleration(
        setup,
        node.velocity,
        node.inverse_mass,
        node.extra,
        node.has_extra,
    );
    let mut x = predict::predicted_position(setup, node.position, node.velocity, a);
    let mut correction = V3::zero();
    // Line 18: shape, eqs. (8), (9) — the local target uses x* after the global step.
    if setup.shape {
        let global = shape::global_correction(setup, node.rest_position, node.root_distance, x);
        x = x + global;
        let local = shape::local_correction(
            setup,
            chain.position,
            chain.frame,
            node.local_rest,
            node.root_distance,
            x,
        );
        x = x + local;
        correction = global + local;
    }
    // Line 19: follow the leader, eq. (10).
    if setup.inextensibility {
        let inextensible =
            follow_leader::correction::<M, T>(chain.position, x, node.segment_length);
        x = x + inextensible;
        correction = correction + inextensible;
    }
    (x, correction)
}

/// What a strand (or a block) tells the report about its segments and contacts.
#[derive(Clone, Copy, Debug, Default)]
pub struct Tally {
    /// Largest stretch of a segment without a pushed node.
    pub stretch: Real,
    /// Largest stretch of a segment with a pushed node.
    pub contact_stretch: Real,
    /// Deepest node left inside a collider.
    pub penetration: Real,
    /// Nodes pushed out.
    pub contacts: u32,
}

impl Tally {
    /// Folds the tally into `report` (maxima and counts only: the same whatever the order).
    pub fn report(&self, report: &mut StepReport) {
        report.max_stretch = report.max_stretch.max(self.stretch);
        report.max_contact_stretch = report.max_contact_stretch.max(self.contact_stretch);
        report.max_penetration = report.max_penetration.max(self.penetration);
        report.contacts += self.contacts;
    }
}

/// Steps one strand by `ctx.dt` (SB15 Algorithm 1, local dynamics). `accelerations` (if any)
/// are the caller's per-node accelerations for this strand, indexed by node. Never panics;
/// the caller's guard rolls back a strand that turns non-finite.
pub fn step<M: Math, const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    accelerations: Option<&[Vec3]>,
    report: &mut StepReport,
) {
    let setup = Setup::new(ctx);
    // Line 12's root: nodes 0 and 1 follow the head, exactly as in the rod solver.
    crate::rod::step::root_coupling(strand, ctx, report);
    setup.count_stages(ctx, accelerations.is_some(), 1, report);
    let n = strand.rest.nodes.min(N);
    if n < 3 {
        return;
    }
    let rest = &strand.rest;
    let state = &mut strand.state;
    let mut chain = Chain::start::<M>(
        &setup,
        rest.dftl.root_frame,
        state.position[0],
        state.position[1],
    );
    let mut tally = Tally::default();
    let mut previous_contact = false;
    for i in 2..n {
        let extra = accelerations.and_then(|a| a.get(i)).copied();
        let node = NodeInput {
            position: state.position[i].into(),
            velocity: state.velocity[i].into(),
            extra: extra.unwrap_or(Vec3::ZERO).into(),
            has_extra: extra.is_some(),
            inverse_mass: rest.inverse_mass[i],
            rest_position: rest.position[i].into(),
            local_rest: rest.dftl.local_rest[i].into(),
            root_distance: rest.dftl.root_distance[i],
            segment_length: rest.segment_length[i - 1],
        };
        // Lines 13–19: predict, shape, follow the leader.
        let (mut x, correction) = project_node::<M, Real>(&setup, &node, &chain);
        // Line 20: collisions, then what is left inside (the report's penetration).
        let mut contact = false;
        if setup.collisions {
            for shape in ctx.colliders() {
                let (pushed, inside) = collisions::push_out::<M, Real>(shape, x);
                x = pushed;
                contact |= inside;
            }
            for shape in ctx.colliders() {
                tally.penetration = tally
                    .penetration
                    .max(collisions::depth::<M, Real>(shape, x));
            }
            tally.contacts += u32::from(contact);
        }
        // Line 21: frame update (and the segment's stretch, with or without contact).
        let (next, stretch) = chain.advance::<M>(&setup, x, node.segment_length);
        if contact || previous_contact {
            tally.contact_stretch = tally.contact_stretch.max(stretch);
        } else {
            tally.stretch = tally.stretch.max(stretch);
        }
        // Lines 24–26 for node i − 1, now that node i's correction is known.
        if i > 2 {
            let (x_new, v_new) = velocity::finish(
                &setup,
                chain.position,
                state.position[i - 1].into(),
                correction,
            );
            state.position[i - 1] = x_new.into();
            state.velocity[i - 1] = v_new.into();
        }
        chain = next;
        previous_contact = contact;
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
    tally.report(report);
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
        let mut chain = Chain::start::<Libm>(&setup, s.rest.dftl.root_frame, points[0], points[1]);
        for (i, point) in points.iter().enumerate().skip(2) {
            let target = Vec3::from(chain.position)
                + math::rotate(chain.frame.into(), s.rest.dftl.local_rest[i]);
            assert!((target - *point).length() < 1e-7, "node {i}");
            let x = (*point).into();
            chain = chain
                .advance::<Libm>(&setup, x, s.rest.segment_length[i - 1])
                .0;
        }
        assert_eq!(s.rest.dftl.root_distance[11], 1.0);
    }

    #[test]
    fn block_gives_the_bits_of_the_per_strand_path() {
        let p = Params {
            effects: Effects::from_slice(&[
                Effect::Gravity,
                Effect::Drag,
                Effect::Shape,
                Effect::Inextensibility,
                Effect::Collisions,
                Effect::Wind,
            ]),
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
        for k in 0..500u32 {
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
            assert_eq!(report.stage_runs, block_report.stage_runs);
            assert_eq!(
                report.max_stretch.to_bits(),
                block_report.max_stretch.to_bits()
            );
            assert_eq!(report.contacts, block_report.contacts);
        }
        let mut strands: std::vec::Vec<Strand<16>> = w.strands().to_vec();
        blocks[0].store(&mut strands[..4]);
        blocks[1].store(&mut strands[4..]);
        assert_eq!(crate::hash::state_hash(&strands), w.state_hash());
        assert!(w.strands()[4].state.position[10].y != points_y(&wavy(14, 4.0)));
    }

    fn points_y(p: &[Vec3]) -> Real {
        p[10].y
    }
}
