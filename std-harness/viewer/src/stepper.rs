//! One running scene at strand capacity `N`: the core's pipeline, on one thread, with the
//! scene's grabs and the hand's. The bits are those of `hairsim run`: the harness splits the
//! strands into blocks (and DFTL into lanes) only for speed, and every one of its layouts
//! gives the state of one `step_strands` call over all the strands.

use hairsim_core::grab::MAX_GRABS;
use hairsim_core::params::DftlCoefficients;
use hairsim_core::pipeline::{self, Inputs, Stepping};
use hairsim_core::{
    step_strands, Collider, DefaultMath, Grab, GrabStatus, Params, Pose, Real, Shape, StepReport,
    Strand, Vec3,
};
use hairsim_files::scene::start::StepInputs;
use hairsim_files::scene::{FieldError, Prepared};

/// A grab held by the page's pointer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hand {
    /// Index of the hand's grab among the world's grabs (after the scene's own).
    pub grab: usize,
    /// Where the pointer holds the node, m.
    pub target: Vec3,
}

/// The strands, colliders and grabs of a scene, stepped by the core.
#[derive(Debug)]
pub struct Stepper<const N: usize> {
    /// The parameters (the page switches effects and the twist method here).
    pub params: Params,
    dftl: DftlCoefficients,
    /// The strands.
    pub strands: Vec<Strand<N>>,
    colliders: Vec<Collider>,
    /// The scene's grabs, then the hand's.
    grabs: Vec<Grab>,
    hand: Option<Hand>,
    /// The head's pose after the last step.
    pub head: Pose,
    /// Steps taken.
    pub steps: u64,
    /// The last step's report.
    pub report: StepReport,
}

impl<const N: usize> Stepper<N> {
    /// The scene `prepared` at its start.
    ///
    /// # Errors
    /// A strand the core refuses.
    pub fn new(prepared: &Prepared) -> Result<Self, FieldError> {
        let (strands, head) = prepared.start_strands::<N, DefaultMath>()?;
        Ok(Stepper {
            params: prepared.params,
            dftl: prepared.params.dftl.at_step(prepared.params.dt),
            strands,
            colliders: prepared.colliders.clone(),
            grabs: prepared.start_grabs::<DefaultMath>(),
            hand: None,
            head,
            steps: 0,
            report: StepReport::default(),
        })
    }

    /// Replaces the parameters (checked by the caller), keeping the state.
    pub fn set_params(&mut self, params: Params) {
        self.dftl = params.dftl.at_step(params.dt);
        self.params = params;
    }

    /// One step with the scene's `inputs`, the hand's target appended.
    pub fn step(&mut self, inputs: &StepInputs) {
        let mut targets = [Vec3::ZERO; MAX_GRABS];
        let mut released = [false; MAX_GRABS];
        let scene_grabs = inputs.grab_targets.len().min(MAX_GRABS);
        targets[..scene_grabs].copy_from_slice(&inputs.grab_targets[..scene_grabs]);
        released[..scene_grabs].copy_from_slice(&inputs.released[..scene_grabs]);
        let mut count = scene_grabs;
        if let Some(hand) = self.hand {
            targets[hand.grab] = hand.target;
            count = hand.grab + 1;
        }
        let mut report = StepReport::default();
        let world = Stepping {
            params: &self.params,
            dftl: self.dftl,
            colliders: &self.colliders,
            grabs: &mut self.grabs,
            strands: &self.strands,
            head: self.head,
            steps: self.steps,
        };
        let inputs = Inputs {
            head: inputs.head,
            grab_targets: &targets[..count],
            released: &released[..count],
        };
        let ctx = pipeline::begin(world, &inputs, &mut report);
        step_strands::<DefaultMath, N>(&ctx, &mut self.strands, 0, &self.grabs, None, &mut report);
        pipeline::finish(&mut self.grabs, &report);
        self.head = ctx.head;
        self.steps += 1;
        self.report = report;
    }

    /// The state hash of every strand (what `hairsim run --json` prints).
    #[must_use]
    pub fn state_hash(&self) -> u64 {
        hairsim_core::hash::state_hash(&self.strands)
    }

    /// Every node's position, strand after strand, as `x, y, z` into `out`, and each strand's
    /// first node into `offsets` (with one more entry: the total).
    pub fn positions(&self, out: &mut Vec<f32>, offsets: &mut Vec<u32>) {
        out.clear();
        offsets.clear();
        for strand in &self.strands {
            offsets.push(u32::try_from(out.len() / 3).unwrap_or(u32::MAX));
            for p in &strand.state.position[..strand.nodes()] {
                out.extend_from_slice(&p.to_array());
            }
        }
        offsets.push(u32::try_from(out.len() / 3).unwrap_or(u32::MAX));
    }

    /// The colliders where the head has moved them.
    pub fn colliders_now(&self) -> impl Iterator<Item = Shape> + '_ {
        self.colliders.iter().map(|c| {
            if c.attached_to_head {
                c.shape.transformed(&self.head)
            } else {
                c.shape
            }
        })
    }

    /// Grabs node `node` (moved to 2 at least: nodes 0 and 1 are the root's) of `strand` where
    /// it is, slipping above `force_limit` newtons; lets go of any earlier hand grab.
    ///
    /// # Errors
    /// No such strand, or every grab slot taken by the scene's own grabs.
    pub fn grab(&mut self, strand: usize, node: usize, force_limit: Real) -> Result<(), String> {
        self.release();
        let Some(s) = self.strands.get(strand) else {
            return Err(format!(
                "strand {strand}: the scene has {} strands",
                self.strands.len()
            ));
        };
        if s.nodes() < 3 {
            return Err(format!("strand {strand} has no free node to grab"));
        }
        let node = node.clamp(2, s.nodes() - 1);
        if self.grabs.len() >= MAX_GRABS {
            return Err(format!(
                "the scene's own grabs take all {MAX_GRABS} grab slots"
            ));
        }
        let target = s.state.position[node];
        let index = |i: usize| u32::try_from(i).unwrap_or(u32::MAX);
        self.grabs
            .push(Grab::new(index(strand), index(node), target, force_limit));
        self.hand = Some(Hand {
            grab: self.grabs.len() - 1,
            target,
        });
        Ok(())
    }

    /// Moves the hand's target (nothing without a hand grab).
    pub fn move_hand(&mut self, target: Vec3) {
        if let Some(hand) = self.hand.as_mut() {
            hand.target = target;
        }
    }

    /// Lets go of the hand's grab: it leaves the world, its force with it.
    pub fn release(&mut self) {
        if let Some(hand) = self.hand.take() {
            self.grabs.truncate(hand.grab);
        }
    }

    /// The hand's grab, its status and the force it puts on the hair (toward its target; the
    /// hand feels the opposite) at the last step.
    #[must_use]
    pub fn hand(&self) -> Option<(Hand, GrabStatus, Vec3)> {
        let hand = self.hand?;
        let grab = self.grabs.get(hand.grab)?;
        let force = if grab.status == GrabStatus::Held {
            -self.report.grab_forces[hand.grab]
        } else {
            Vec3::ZERO
        };
        Some((hand, grab.status, force))
    }
}
