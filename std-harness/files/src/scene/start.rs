//! A prepared scene's start and its inputs over time: the strands at step 0 and what each
//! step hands the core (head pose, grab targets, releases). Shared by the harness's runs and
//! the viewer's page, so both start from the same bits.

use hairsim_core::{Grab, Math, Pose, Real, Strand, Vec3};

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
    /// the tip and placed at the head's pose at time 0 (which is returned too).
    ///
    /// # Errors
    /// A strand the core refuses, named by its field and index.
    pub fn start_strands<const N: usize, M: Math>(
        &self,
    ) -> Result<(Vec<Strand<N>>, Pose), FieldError> {
        let head = self.motion.pose_at::<M>(0.0);
        let mut strands = Vec::with_capacity(self.strands.len());
        for (i, spec) in self.strands.iter().enumerate() {
            let mut strand = Strand::<N>::from_polyline(&spec.points, &spec.material)
                .map_err(|e| FieldError::new(spec.field.clone(), format!("strand {i}: {e}")))?;
            fade_bending(&mut strand, spec.tip_stiffness);
            if head != Pose::IDENTITY {
                place(&mut strand, &head);
            }
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

/// Moves a strand built in the head's frame to the head's starting pose.
fn place<const N: usize>(strand: &mut Strand<N>, head: &Pose) {
    let n = strand.nodes();
    for p in &mut strand.state.position[..n] {
        *p = head.transform_point(*p);
    }
    strand.state.root_frame = head.transform_vector(strand.state.root_frame);
}
