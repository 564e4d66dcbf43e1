//! One running scene at strand capacity `N`: the core's pipeline, on one thread, with the
//! scene's grabs and the hand's, in the lanes `hairsim run` steps them in (the rod's strands
//! [`ROD_LANES`] at a time, DFTL's as structure-of-arrays blocks of [`DFTL_LANES`], a block
//! holding a grabbed strand strand by strand). The bits are those of `hairsim run`: every
//! layout of the core gives the state of one `step_strands` call over all the strands.

use hairsim_core::dftl::{collisions, follow_leader, DftlBlock};
use hairsim_core::grab::MAX_GRABS;
use hairsim_core::lane::V3;
use hairsim_core::params::DftlCoefficients;
use hairsim_core::pipeline::{self, Inputs, Stepping};
use hairsim_core::{
    step_strands_in_blocks, step_strands_in_lanes_with, Collider, Coupling, DefaultMath, Grab,
    GrabStatus, Params, Pose, Real, RodBlockScratch, Shape, Solver, StepReport, Strand, Vec3,
};
use hairsim_files::lanes::{VectorSqrt, DFTL_LANES, ROD_LANES};
use hairsim_files::scene::start::StepInputs;
use hairsim_files::scene::{FieldError, Prepared};

/// The math of the lanes: the default backend with the hardware's square root (the same
/// bits; `wasm32` has no other fast one).
type LaneMath = VectorSqrt<DefaultMath>;

/// The strands' lanes: the rod's scratch space, or DFTL's blocks (rest data loaded once, the
/// state copied in and out every step by [`step_strands_in_blocks`]).
#[derive(Debug)]
enum Lanes<const N: usize> {
    Rod(Box<RodBlockScratch<LaneMath, N, ROD_LANES>>),
    Dftl(Vec<DftlBlock<DFTL_LANES, N>>),
}

impl<const N: usize> Lanes<N> {
    fn new(solver: Solver, strands: &[Strand<N>]) -> Self {
        match solver {
            Solver::Rod => Lanes::Rod(Box::default()),
            Solver::Dftl => Lanes::Dftl(
                strands
                    .chunks(DFTL_LANES)
                    .map(DftlBlock::from_strands)
                    .collect(),
            ),
        }
    }
}

/// A grab held by the page's pointer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hand {
    /// Index of the hand's grab among the world's grabs (after the scene's own).
    pub grab: usize,
    /// Where the pointer holds the node, m.
    pub target: Vec3,
}

/// What the steps since the page last asked ([`Stepper::take_events`]) reported: what the
/// page must show as it happens rather than leave to one step's report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Events {
    /// Steps taken.
    pub steps: u32,
    /// Fewest strands rolled back in one step (0 without steps): more than none means some
    /// strand was rolled back at every step, the sign of a simulation that no longer moves
    /// on (a strand rolled back keeps its last good state, so it is rolled back again).
    pub rolled_back_min: u32,
    /// Most strands rolled back in one step.
    pub rolled_back_max: u32,
    /// Most strands whose projection hit its iteration cap in one step.
    pub cap_hits_max: u32,
    /// Largest stretch: of a segment without contact in the reports (`max_stretch`), and of
    /// any segment of the strands as they are when the events are taken.
    pub max_stretch: Real,
    /// Whether the hand's grab slipped, and the force it held before (N).
    pub slipped: Option<Real>,
}

/// Per-strand flags of [`Stepper::strand_flags`].
pub mod flag {
    /// Rolled back since the page last asked.
    pub const ROLLED_BACK: u8 = 1;
    /// A segment stretched by more than [`super::STRETCH_WARNING`].
    pub const STRETCHED: u8 = 2;
    /// The hand holds (or held, before it slipped) this strand.
    pub const HELD: u8 = 4;
}

/// Relative stretch past which a strand is drawn in the warning colour: 1 %.
pub const STRETCH_WARNING: Real = 0.01;

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
    lanes: Lanes<N>,
    events: Events,
    /// [`flag::ROLLED_BACK`] of each strand since the page last asked.
    rolled_back: Vec<bool>,
    /// The force the hand's grab held at the last step it held, N.
    held_force: Real,
}

impl<const N: usize> Stepper<N> {
    /// The scene `prepared` at its start.
    ///
    /// # Errors
    /// A strand the core refuses.
    pub fn new(prepared: &Prepared) -> Result<Self, FieldError> {
        let (strands, head) = prepared.start_strands::<N, DefaultMath>()?;
        Ok(Stepper {
            lanes: Lanes::new(prepared.params.solver, &strands),
            events: Events::default(),
            rolled_back: vec![false; strands.len()],
            held_force: 0.0,
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
        match &mut self.lanes {
            Lanes::Rod(scratch) => {
                let at = (0, self.grabs.as_slice());
                step_strands_in_lanes_with(&ctx, &mut self.strands, at, None, scratch, &mut report);
            }
            Lanes::Dftl(blocks) => {
                // A block holding a grabbed strand steps strand by strand (the same bits):
                // `step_blocks` alone would step a held strand as if nothing held it.
                let at = (0, self.grabs.as_slice());
                let strands = &mut self.strands;
                step_strands_in_blocks::<LaneMath, DFTL_LANES, N>(
                    &ctx,
                    blocks,
                    strands,
                    at,
                    None,
                    &mut report,
                );
            }
        }
        pipeline::finish(&mut self.grabs, &mut report);
        self.head = ctx.head;
        self.steps += 1;
        self.report = report;
        self.count_events();
    }

    /// Adds the last step's report to the events and the strands' flags.
    fn count_events(&mut self) {
        let report = &self.report;
        let events = &mut self.events;
        events.rolled_back_min = if events.steps == 0 {
            report.rolled_back
        } else {
            events.rolled_back_min.min(report.rolled_back)
        };
        events.steps += 1;
        let all = u32::try_from(self.strands.len()).unwrap_or(u32::MAX);
        if report.rolled_back >= all && all > 0 {
            self.rolled_back.fill(true);
        }
        for &s in &report.rolled_back_strands {
            if let Some(flag) = self.rolled_back.get_mut(s as usize) {
                *flag = true;
            }
        }
        events.rolled_back_max = events.rolled_back_max.max(report.rolled_back);
        events.cap_hits_max = events.cap_hits_max.max(report.cap_hits);
        events.max_stretch = events.max_stretch.max(report.max_stretch);
        if let Some(hand) = self.hand {
            let slipped = report.grabs_slipped & (1 << hand.grab) != 0;
            if slipped {
                events.slipped = Some(self.held_force);
            } else if self.grabs.get(hand.grab).map(|g| g.status) == Some(GrabStatus::Held) {
                self.held_force = report.grab_forces[hand.grab].length();
            }
        }
    }

    /// The events since the last call (and starts counting anew), the stretch as the strands
    /// are now too: a rolled-back strand's report measures the step the guard threw away.
    pub fn take_events(&mut self) -> Events {
        let now = self.strands.iter().map(stretch).fold(0.0, Real::max);
        let mut events = std::mem::take(&mut self.events);
        events.max_stretch = events.max_stretch.max(now);
        events
    }

    /// One byte of [`flag`]s per strand into `out`; the roll-backs are counted anew.
    pub fn strand_flags(&mut self, out: &mut Vec<u8>) {
        out.clear();
        let held = self
            .hand
            .and_then(|hand| self.grabs.get(hand.grab))
            .map(|grab| grab.strand as usize);
        for (s, strand) in self.strands.iter().enumerate() {
            let mut flags = 0;
            if std::mem::take(&mut self.rolled_back[s]) {
                flags |= flag::ROLLED_BACK;
            }
            if stretch(strand) > STRETCH_WARNING {
                flags |= flag::STRETCHED;
            }
            if held == Some(s) {
                flags |= flag::HELD;
            }
            out.push(flags);
        }
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
    /// it is, through `coupling`, slipping above `force_limit` newtons; lets go of any earlier
    /// hand grab.
    ///
    /// # Errors
    /// No such strand, or every grab slot taken by the scene's own grabs.
    pub fn grab(
        &mut self,
        strand: usize,
        node: usize,
        force_limit: Real,
        coupling: Coupling,
    ) -> Result<(), String> {
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
        let grab = Grab::new(index(strand), index(node), target, force_limit);
        self.grabs.push(grab.with_coupling(coupling));
        self.hand = Some(Hand {
            grab: self.grabs.len() - 1,
            target,
        });
        self.held_force = 0.0;
        Ok(())
    }

    /// Moves the hand's target (nothing without a hand grab).
    pub fn move_hand(&mut self, target: Vec3) {
        if let Some(hand) = self.hand.as_mut() {
            hand.target = target;
        }
    }

    /// Pulls every strand stretched past [`STRETCH_WARNING`] back to its rest lengths (see
    /// [`restore_lengths`]); returns how many it pulled. For inextensibility turned back on: the
    /// projection, from a strand stretched many times over, cannot get back within its cap
    /// before the guard rolls the strand back to the same stretched state, every step.
    pub fn restore_stretched(&mut self) -> usize {
        let shapes: Vec<Shape> = self.colliders_now().collect();
        let mut pulled = 0;
        for strand in &mut self.strands {
            if stretch(strand) > STRETCH_WARNING {
                restore_lengths(strand, &shapes);
                if sharpest_fold(strand) < FOLD_COSINE {
                    rest_shape(strand, &self.head);
                }
                pulled += 1;
            }
        }
        pulled
    }

    /// The held node's position (where the hand's grab holds it, or where it went after a
    /// slip), with its strand and node.
    #[must_use]
    pub fn held_node(&self) -> Option<(usize, usize, Vec3)> {
        let grab = self.grabs.get(self.hand?.grab)?;
        let (strand, node) = (grab.strand as usize, grab.node as usize);
        let position = *self.strands.get(strand)?.state.position.get(node)?;
        Some((strand, node, position))
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

/// The largest relative stretch `| |e| − |ê| | / |ê|` of a segment of `strand`.
fn stretch<const N: usize>(strand: &Strand<N>) -> Real {
    let positions = strand.positions();
    positions
        .windows(2)
        .zip(&strand.rest.segment_length)
        .map(|(pair, &rest)| ((pair[1] - pair[0]).length() - rest).abs() / rest.max(Real::EPSILON))
        .fold(0.0, Real::max)
}

/// The cosine of the sharpest fold [`Stepper::restore_stretched`] keeps (120°: what the rod's
/// fixed-cost substeps allow for); a strand pulled back into a sharper one goes to its rest
/// shape instead (the rod rolls back a strand folded into a near hairpin step after step).
const FOLD_COSINE: Real = -0.5;

/// The cosine of the sharpest turning angle between consecutive segments of `strand`.
fn sharpest_fold<const N: usize>(strand: &Strand<N>) -> Real {
    strand
        .positions()
        .windows(3)
        .map(|p| {
            (p[1] - p[0])
                .normalize_or_zero()
                .dot((p[2] - p[1]).normalize_or_zero())
        })
        .fold(1.0, Real::min)
}

/// `strand` in its rest shape where the head is now, at rest.
fn rest_shape<const N: usize>(strand: &mut Strand<N>, head: &Pose) {
    let nodes = strand.nodes();
    for (x, rest) in strand.state.position[..nodes]
        .iter_mut()
        .zip(&strand.rest.position)
    {
        *x = head.transform_point(*rest);
    }
    strand.state.velocity[..nodes].fill(Vec3::ZERO);
}

/// Pulls each segment of `strand` back to its rest length, root to tip, along its present
/// direction, and each node out of the colliders `shapes` — DFTL's follow-the-leader step and
/// its collisions (SB15 eq. 10 and Algorithm 1 line 20: [`follow_leader::project`],
/// [`collisions::push_out`]) without the dynamics — and stops the strand (zero velocity).
/// Nodes 0 and 1 stay with the head.
fn restore_lengths<const N: usize>(strand: &mut Strand<N>, shapes: &[Shape]) {
    let nodes = strand.nodes();
    let state = &mut strand.state;
    for i in 2..nodes {
        let previous = V3::from(state.position[i - 1]);
        let fallback = V3::from(Vec3::NEG_Y);
        let length = strand.rest.segment_length[i - 1];
        let x = state.position[i].into();
        let (mut x, _) = follow_leader::project::<LaneMath, Real>(previous, x, length, fallback);
        for shape in shapes {
            x = collisions::push_out::<LaneMath, Real>(shape, x).0;
        }
        state.position[i] = x.into();
    }
    state.velocity[..nodes].fill(Vec3::ZERO);
}
