//! Shape damping (a departure from SB15, `docs/design-departures.md`): before the prediction
//! (Algorithm 1 line 14), a node's velocity relative to the head's rigid motion at its place
//! keeps the fraction `r` per step.
//!
//! A shape constraint projected with the fraction `s` dissipates at `−ln(1 − s)/(2Δt)` per
//! second; the spring rule keeps its stiffness at every step but not that dissipation, which
//! falls tenfold from 60 Hz to 1 kHz (`math::shape_damping_retention`). Without it a groom
//! that settles in 60 ms at 60 Hz rings for seconds at 1 ms and whips when the head moves.
//! The damping adds the missing dissipation, and only that: `r` = 1 at and above 60 Hz,
//! where the step is SB15's. It acts relative to the head's motion, as the global constraint
//! does, so a strand carried rigidly by the head is not slowed.

use super::node::Setup;
use crate::lane::{Lane, V3};

/// `v_rigid + r (v − v_rigid) = r v + (1 − r) ω × x + e`, with `v_rigid = ω × (x − t) + ṫ`
/// the velocity of the point `x` carried rigidly by the head over the step and
/// `e = (1 − r)(ṫ − ω × t)`, both computed once per step ([`Setup`]): 9 multiplications and 9
/// additions a node.
#[inline(always)]
#[must_use]
pub fn damped_velocity<T: Lane>(setup: &Setup, position: V3<T>, velocity: V3<T>) -> V3<T> {
    let spin = V3::splat(setup.damping_spin);
    velocity.scale(T::splat(setup.coefficients.shape_retention))
        + spin.cross(position)
        + V3::splat(setup.damping_offset)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::context::StepContext;
    use crate::effects::{Effect, Effects, Solver};
    use crate::head::Pose;
    use crate::math::{quat_from_axis_angle, Libm, Vec3};
    use crate::params::Params;

    fn dftl_params(dt: crate::math::Real) -> Params {
        Params {
            solver: Solver::Dftl,
            effects: Effects::from_slice(&[Effect::Shape, Effect::Inextensibility]),
            dt,
            ..Params::DEFAULT
        }
    }

    #[test]
    fn a_point_carried_by_the_head_keeps_its_velocity() {
        // The head turns 10 rad/s about a tilted axis and moves: a node at the velocity of the
        // point the head carries there is not slowed (to the O(θ²) of the spin's reading).
        let params = dftl_params(0.001);
        let axis = Vec3::new(0.3, 1.0, -0.2).normalize();
        let previous = Pose {
            position: Vec3::new(0.01, 0.02, 0.0),
            rotation: quat_from_axis_angle::<Libm>(axis, 0.4),
        };
        let head = Pose {
            position: Vec3::new(0.0105, 0.0198, 0.0003),
            rotation: quat_from_axis_angle::<Libm>(axis, 0.41),
        };
        let ctx = StepContext::new(&params, previous, head, &[]);
        let setup = Setup::new(&ctx);
        assert!(setup.shape_damping && ctx.dftl.shape_retention < 0.99);
        for x in [Vec3::new(0.1, 0.05, -0.02), Vec3::new(-0.2, 0.3, 0.1)] {
            // Where the head had that point a step ago.
            let in_head = head.rotation.inverse() * (x - head.position);
            let earlier = previous.rotation * in_head + previous.position;
            let rigid = (x - earlier) / params.dt;
            let damped = damped_velocity::<crate::math::Real>(&setup, x.into(), rigid.into());
            let error = (Vec3::from(damped) - rigid).length();
            assert!(
                error < 1e-3 * rigid.length(),
                "{error} of {}",
                rigid.length()
            );
            // A node at rest relative to the world is pulled towards the head's motion.
            let still = Vec3::from(damped_velocity::<crate::math::Real>(
                &setup,
                x.into(),
                Vec3::ZERO.into(),
            ));
            let pull = 1.0 - ctx.dftl.shape_retention;
            assert!((still - rigid * pull).length() < 1e-3 * rigid.length());
        }
    }

    #[test]
    fn the_damping_gives_back_the_dissipation_of_sixty_hertz() {
        use crate::math::{shape_damping_retention, SHAPE_DAMPING_REFERENCE_DT};
        let p = Params::DEFAULT.dftl;
        let retention =
            |dt| shape_damping_retention(p.global_shape, p.local_shape, p.reference_dt, dt);
        // Nothing at and above 60 Hz.
        assert_eq!(retention(SHAPE_DAMPING_REFERENCE_DT), 1.0);
        assert_eq!(retention(0.05), 1.0);
        // Below, projections plus damping dissipate as the 60 Hz projections do: the rate
        // −ln(r)/Δt plus the projections' own is the same at every step.
        let rate = |dt: crate::math::Real| {
            let s = p.at_step(dt);
            let own = -libm::logf((1.0 - s.global_shape) * (1.0 - s.local_shape)) / (2.0 * dt);
            -libm::logf(retention(dt)) / dt + own
        };
        let reference = rate(SHAPE_DAMPING_REFERENCE_DT);
        for dt in [1.0e-4, 5.0e-4, 1.0e-3, 4.0e-3] {
            assert!(
                (rate(dt) / reference - 1.0).abs() < 1e-3,
                "{dt}: {}",
                rate(dt)
            );
        }
        // Defaults at 1 ms: 31 + 59 s⁻¹ at 60 Hz, 3.3 + 11 s⁻¹ of the projections: 76 s⁻¹ added.
        let added = -libm::logf(retention(0.001)) / 0.001;
        assert!((added - 76.0).abs() < 1.0, "{added}");
    }
}
