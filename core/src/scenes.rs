//! Scenes shared by the firmware example and the std harness, so that both build exactly the
//! same world and can compare state hashes.

use crate::collide::{Collider, Shape};
use crate::effects::{Effect, Effects};
use crate::error::Error;
use crate::head::{Pose, Shake};
use crate::math::{Math, Real, Vec3};
use crate::params::{Mode, Params};
use crate::strand::{Material, Strand};
use crate::world::{StepInput, World};

/// The scene the firmware example (`firmware/`) runs under QEMU and the harness runs as the
/// built-in scene `firmware`: a few strands on a head shaking at 10 rad/s.
pub mod firmware {
    use super::*;

    /// Strands in the scene.
    pub const STRANDS: usize = 4;
    /// Node capacity per strand.
    pub const NODES: usize = 16;
    /// Steps the firmware runs before it prints the hash.
    pub const STEPS: u32 = 1000;

    /// The scene's parameters: rod solver, 1 ms, fixed-cost mode.
    #[must_use]
    pub fn params() -> Params {
        Params {
            effects: Effects::from_slice(&[Effect::Gravity, Effect::Drag, Effect::Collisions]),
            mode: Mode::FixedCost,
            drag: 2.0e-7,
            ..Params::DEFAULT
        }
    }

    /// Fills an empty world with the scene: `STRANDS` strands of 12 to 15 nodes, 1 cm apart,
    /// rooted on a 5 cm sphere that moves with the head.
    pub fn build<M: Math>(world: &mut World<STRANDS, NODES, M>) -> Result<(), Error> {
        world.configure(params())?;
        world.add_collider(Collider {
            shape: Shape::Sphere {
                centre: Vec3::ZERO,
                radius: 0.05,
            },
            attached_to_head: true,
        })?;
        for s in 0..STRANDS {
            let nodes = 12 + s % 4;
            let angle = s as Real * 0.4 - 0.6;
            let direction = Vec3::new(angle, 1.0, 0.3 * angle).normalize();
            let root = direction * 0.05;
            let mut points = [Vec3::ZERO; NODES];
            for (i, p) in points.iter_mut().enumerate().take(nodes) {
                // Out along the normal, then curving sideways: not a straight line.
                let bend = Vec3::new(0.002 * (i * i) as Real, 0.0, 0.0);
                *p = root + direction * (0.01 * i as Real) + bend;
            }
            world.add_strand(Strand::from_polyline(
                &points[..nodes],
                &Material::HUMAN_HAIR,
            )?)?;
        }
        Ok(())
    }

    /// The input of step `k` (0-based): the head shaking at 10 rad/s, pose at `t = (k+1) dt`.
    #[must_use]
    pub fn input<M: Math>(k: u32) -> StepInput<'static> {
        let t = (k + 1) as Real * params().dt;
        StepInput {
            head: Shake::TEN_RAD_PER_S.pose_at::<M>(t),
            accelerations: None,
        }
    }

    /// Builds the scene, runs `steps` steps and returns the state hash.
    pub fn run<M: Math>(world: &mut World<STRANDS, NODES, M>, steps: u32) -> Result<u64, Error> {
        build(world)?;
        for k in 0..steps {
            world.step(&input::<M>(k));
        }
        Ok(world.state_hash())
    }

    /// The head's pose before the first step.
    pub const START: Pose = Pose::IDENTITY;
}
