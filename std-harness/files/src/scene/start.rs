//! A prepared scene's start and its inputs over time: the strands at step 0 and what each
//! step hands the core (head pose, grab targets, releases). Shared by the harness's runs and
//! the viewer's page, so both start from the same bits.

use hairsim_core::{Effect, Grab, Math, Pose, Real, Shape, Strand, Vec3};

use super::{FieldError, Prepared};

/// The time-varying inputs of one step (what a recording stores).
#[derive(Clone, Debug, PartialEq)]
pub struct StepInputs {
    /// The head's pose at the end of the step.
    pub head: Pose,
    /// Each grab's target.
    pub grab_targets: Vec<Vec3>,
    /// Each grab: whether it has been let go.
    pub released: Vec<bool>,
}

/// Time at the end of step `k` (0-based): `(k + 1) · dt`, computed in `f32` exactly as the
/// firmware computes it.
#[must_use]
pub fn time_after(k: u64, dt: Real) -> Real {
    (k + 1) as Real * dt
}

/// The scene's inputs for step `k`.
#[must_use]
pub fn scene_inputs<M: Math>(prepared: &Prepared, k: u64) -> StepInputs {
    let t = time_after(k, prepared.params.dt);
    StepInputs {
        head: prepared.motion.pose_at::<M>(t),
        grab_targets: prepared
            .grabs
            .iter()
            .map(|g| g.path.target_at::<M>(t))
            .collect(),
        released: prepared
            .grabs
            .iter()
            .map(|g| g.path.released_at(t))
            .collect(),
    }
}

impl Prepared {
    /// The strands at capacity `N`, built from their rest polylines, the bending faded toward
    /// the tip and placed at the head's pose at time 0 (which is returned too), with collisions
    /// on, their free nodes started outside the colliders ([`start_outside`]).
    ///
    /// # Errors
    /// A strand the core refuses, named by its field and index.
    pub fn start_strands<const N: usize, M: Math>(
        &self,
    ) -> Result<(Vec<Strand<N>>, Pose), FieldError> {
        let head = self.motion.pose_at::<M>(0.0);
        let shapes: Vec<Shape> = if self.params.effects.contains(Effect::Collisions) {
            self.colliders
                .iter()
                .map(|c| {
                    if c.attached_to_head {
                        c.shape.transformed(&head)
                    } else {
                        c.shape
                    }
                })
                .collect()
        } else {
            Vec::new()
        };
        let mut strands = Vec::with_capacity(self.strands.len());
        for (i, spec) in self.strands.iter().enumerate() {
            let mut strand = Strand::<N>::from_polyline(&spec.points, &spec.material)
                .map_err(|e| FieldError::new(spec.field.clone(), format!("strand {i}: {e}")))?;
            fade_bending(&mut strand, spec.tip_stiffness);
            if head != Pose::IDENTITY {
                place(&mut strand, &head);
            }
            start_outside::<N, M>(&mut strand, &shapes);
            strands.push(strand);
        }
        Ok((strands, head))
    }

    /// The scene's grabs at time 0.
    #[must_use]
    pub fn start_grabs<M: Math>(&self) -> Vec<Grab> {
        self.grabs
            .iter()
            .map(|g| {
                let grab = Grab::new(g.strand, g.node, g.path.target_at::<M>(0.0), g.force_limit);
                match g.coupling {
                    Some(coupling) => grab.with_coupling(coupling),
                    None => grab,
                }
            })
            .collect()
    }
}

/// Bending stiffness fading linearly from the root's to `tip` (≤ 1) times it at the last
/// segment, in the rest data the rod's stages read (`rest.rod.bending_stiffness`), set once
/// before the first step. Only ever lowered, so the rod's stable time step (computed from the
/// root's, the stiffest) stays valid.
fn fade_bending<const N: usize>(strand: &mut Strand<N>, tip: Real) {
    if tip == 1.0 {
        return;
    }
    let segments = strand.nodes() - 1;
    for j in 0..segments {
        let s = j as Real / (segments.max(2) - 1) as Real;
        let factor = 1.0 - s + s * tip;
        strand.rest.rod.bending_stiffness[j] *= factor;
    }
}

/// Rounds of push-out and re-placement [`start_outside`] gives a node: a node whose
/// predecessor is outside every collider is out after one round, and a node in the crease of
/// two colliders (a head sphere and a neck capsule) within a few.
const START_ROUNDS: usize = 8;

/// Moves the free nodes (2 on) of `strand` that start inside one of `shapes` out of it, root
/// to tip, each kept at its segment's rest length from its predecessor (which may have moved):
/// pushed out along the contact normal, then put back at that length along the new direction,
/// until it is outside them all or after [`START_ROUNDS`] rounds. Velocities stay zero.
///
/// A rest polyline partly inside a collider (a hair file's groom dipping into the head sphere
/// fitted to its scalp) would otherwise be pushed out by the first step, several millimetres in
/// one step: at 1 ms, a node moving several metres per second before anything else moved. Only
/// the start state moves; the rest polyline, which the shape constraints pull towards, keeps
/// the groom as made, so such hair rests pressed onto the head. Strands that start outside
/// every collider keep their bits.
fn start_outside<const N: usize, M: Math>(strand: &mut Strand<N>, shapes: &[Shape]) {
    let n = strand.nodes();
    let inside = |x: Vec3| shapes.iter().any(|s| s.penetration::<M>(x).is_some());
    let Some(first) = (2..n).find(|&i| inside(strand.state.position[i])) else {
        return;
    };
    for i in first..n {
        let previous = strand.state.position[i - 1];
        let length = strand.rest.segment_length[i - 1];
        let mut x = strand.state.position[i];
        let at_length = |x: Vec3| {
            let d = x - previous;
            let l = M::length(d);
            if l > 0.0 {
                previous + d * (length / l)
            } else {
                x
            }
        };
        // Where the predecessor moved, the node follows at its length first.
        x = at_length(x);
        for _ in 0..START_ROUNDS {
            if !inside(x) {
                break;
            }
            for shape in shapes {
                if let Some(contact) = shape.penetration::<M>(x) {
                    x += contact.normal * contact.depth;
                }
            }
            x = at_length(x);
        }
        strand.state.position[i] = x;
    }
}

/// Moves a strand built in the head's frame to the head's starting pose.
fn place<const N: usize>(strand: &mut Strand<N>, head: &Pose) {
    let n = strand.nodes();
    for p in &mut strand.state.position[..n] {
        *p = head.transform_point(*p);
    }
    strand.state.root_frame = head.transform_vector(strand.state.root_frame);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use hairsim_core::Libm;
    use std::path::Path;

    /// A straight strand through a sphere (its line passes 1 cm from the centre of a 3 cm
    /// sphere), with or without collisions, and a second strand clear of it.
    fn started(collisions: bool) -> (Vec<Strand<16>>, Prepared) {
        let effects = if collisions {
            r#"["gravity", "inextensibility", "collisions", "shape"]"#
        } else {
            r#"["gravity", "inextensibility", "shape"]"#
        };
        let text = format!(
            r#"format = 1
name = "t"
solver = "dftl"
dt = 0.001
steps = 10
effects = {effects}
[[colliders]]
shape = "sphere"
centre = [0.05, -0.01, 0.0]
radius = 0.03
[[strands]]
root = [0.0, 0.0, 0.0]
direction = [1.0, 0.0, 0.0]
length = 0.1
nodes = 11
[[strands]]
root = [0.0, 0.1, 0.0]
direction = [1.0, 0.0, 0.0]
length = 0.1
nodes = 11
"#
        );
        let (_, prepared) = Scene::parse_and_prepare(&text, "t.toml", Path::new(".")).unwrap();
        let (strands, _) = prepared.start_strands::<16, Libm>().unwrap();
        (strands, prepared)
    }

    #[test]
    fn a_groom_dipping_into_a_collider_starts_outside_it_at_its_lengths() {
        let (strands, prepared) = started(true);
        let Shape::Sphere { centre, radius } = prepared.colliders[0].shape else {
            panic!("a sphere");
        };
        let (through, clear) = (&strands[0], &strands[1]);
        let rest = &through.rest;
        let inside_at_rest = rest.position[..11]
            .iter()
            .filter(|p| (**p - centre).length() < radius)
            .count();
        assert!(inside_at_rest >= 4, "{inside_at_rest}");
        for i in 0..11 {
            let x = through.state.position[i];
            assert!(
                (x - centre).length() >= radius * (1.0 - 1e-6),
                "node {i}: {x}"
            );
            if i > 0 {
                let length = (x - through.state.position[i - 1]).length();
                let expected = rest.segment_length[i - 1];
                assert!((length / expected - 1.0).abs() < 1e-5, "segment {i}");
            }
            // The nodes before the first one inside keep their bits.
            if rest.position[i].x < 0.02 {
                assert_eq!(x, rest.position[i], "node {i}");
            }
        }
        assert!(through.state.velocity.iter().all(|v| *v == Vec3::ZERO));
        // A strand clear of the collider, and the same strand without collisions, keep theirs.
        assert_eq!(clear.state.position, clear.rest.position);
        let (off, _) = started(false);
        assert_eq!(off[0].state.position, off[0].rest.position);
    }
}
