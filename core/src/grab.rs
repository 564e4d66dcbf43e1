//! Grabs: a node held at a moving target, for user interaction (a haptic tool holding hair):
//! pinned to it (prescribed, Kmoch 2009 Sec. 8.1), or pulled toward it by a virtual coupling
//! ([`Coupling`]).

use crate::error::ParamError;
use crate::math::{Real, Vec3};

pub use crate::capacities::MAX_GRABS;

/// Whether a grab holds its node.
///
/// One byte, the variant's index (`repr(u8)`): a world's raw bytes can be checked before they
/// are read as one (`crate::world::WorldLayout`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum GrabStatus {
    /// The node follows the target.
    Held,
    /// The force limit was exceeded: the node is free and the grab stays released.
    Slipped,
    /// Released by the caller.
    Released,
}

/// A virtual coupling between a haptic device and the node it holds (Colgate, Stanley and
/// Brown 1995; Adams and Hannaford 1999): a spring of `stiffness` and a damper of `damping`
/// between the grab's target (the device) and the node, integrated implicitly with the strand
/// (the node's effective mass in the constraint projection is `m + K Δt² + B Δt`), so a step
/// is stable for every value in the ranges below, however light the node (a hair node weighs
/// about 6.5e-8 kg: `K Δt²/m` is in the thousands).
///
/// The force reported is the coupling's, `K (x − target) + B (v − v_target)` on the device,
/// and a coupled grab slips only on its force limit, never on reach: pulling a strand taut is
/// the normal case. `docs/haptics.md` says how to choose `K` and `B` from a device's own
/// damping, the loop's rate and the force gain an application applies (a device renders the
/// gain times `K` and `B`; sampled at `T` it stays passive while `b > gain·K·T/2 + gain·B`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Coupling {
    /// Spring stiffness `K`, N/m, in [`Coupling::STIFFNESS`].
    pub stiffness: Real,
    /// Damping `B`, N·s/m, in [`Coupling::DAMPING`].
    pub damping: Real,
}

impl Coupling {
    /// The stiffnesses a coupling accepts, N/m: from a spring no stiffer than the air's drag
    /// on a strand to ten times the stiffest desk-top haptic device's (about 1e4 N/m).
    pub const STIFFNESS: (Real, Real) = (1.0e-3, 1.0e5);
    /// The dampings a coupling accepts, N·s/m (0: a spring alone).
    pub const DAMPING: (Real, Real) = (0.0, 1.0e3);

    /// A spring of `stiffness` N/m and a damper of `damping` N·s/m.
    #[must_use]
    pub const fn new(stiffness: Real, damping: Real) -> Coupling {
        Coupling { stiffness, damping }
    }

    /// Whether both values lie in their ranges (NaN does not).
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.check().is_ok()
    }

    /// Checks both values, naming the first out of its range (NaN is):
    /// `grab.coupling.stiffness` ([`Coupling::STIFFNESS`]), then `grab.coupling.damping`
    /// ([`Coupling::DAMPING`]).
    pub fn check(&self) -> Result<(), ParamError> {
        let (k_low, k_high) = Self::STIFFNESS;
        let (b_low, b_high) = Self::DAMPING;
        if !(k_low..=k_high).contains(&self.stiffness) {
            return Err(ParamError::OutOfRange {
                field: "grab.coupling.stiffness",
                allowed: "1e-3 to 1e5 N/m",
            });
        }
        if !(b_low..=b_high).contains(&self.damping) {
            return Err(ParamError::OutOfRange {
                field: "grab.coupling.damping",
                allowed: "0 to 1e3 N·s/m",
            });
        }
        Ok(())
    }
}

/// A node held at a target that the caller moves each tick: pinned to it, or pulled toward
/// it by a [`Coupling`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grab {
    /// Index of the strand in the world.
    pub strand: u32,
    /// Index of the node in the strand (≥ 2: nodes 0 and 1 are held by the head).
    pub node: u32,
    /// Where the node is held, m (world frame).
    pub target: Vec3,
    /// Largest force the grab transmits before it slips, N.
    pub force_limit: Real,
    /// Held, slipped or released.
    pub status: GrabStatus,
    /// `None`: the node is prescribed at the target (it follows the target exactly and slips
    /// when the target leaves the strand's reach); `Some`: a virtual coupling pulls it there.
    pub coupling: Option<Coupling>,
    /// The target the last step ended with (at first, the target): a coupling's damper acts
    /// on the node's velocity relative to the target's, `(target − previous_target)/Δt`.
    pub previous_target: Vec3,
}

#[cfg(feature = "defmt")]
impl defmt::Format for Grab {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "Grab {{ strand: {}, node: {}, target: {}, force_limit: {}, status: {}, coupling: {} }}",
            self.strand,
            self.node,
            crate::math::DefmtVec3(self.target),
            self.force_limit,
            self.status,
            self.coupling
        )
    }
}

impl Grab {
    /// A grab of `node` on `strand`, prescribed at `target`, slipping above `force_limit`
    /// newtons.
    #[must_use]
    pub const fn new(strand: u32, node: u32, target: Vec3, force_limit: Real) -> Grab {
        Grab {
            strand,
            node,
            target,
            force_limit,
            status: GrabStatus::Held,
            coupling: None,
            previous_target: target,
        }
    }

    /// The same grab pulled toward its target by `coupling` instead of prescribed there.
    #[must_use]
    pub const fn with_coupling(self, coupling: Coupling) -> Grab {
        Grab {
            coupling: Some(coupling),
            ..self
        }
    }

    /// Whether a coupling pulls the node (rather than the node being prescribed).
    #[must_use]
    pub const fn is_coupled(&self) -> bool {
        self.coupling.is_some()
    }
}

/// The nodes of one strand that grabs hold this step: a set of at most [`MAX_GRABS`] entries,
/// each a grab's index in the world's grab list and the node it pins.
///
/// A held node is *prescribed* (infinite mass, no constraint rows — `docs/architecture.md`, fast manifold
/// projection) and its segment is clamped for the twist, like the root segment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GrabbedNodes {
    grab: [u8; MAX_GRABS],
    node: [u16; MAX_GRABS],
    len: usize,
}

impl GrabbedNodes {
    /// Whether a grab holds `node`.
    #[must_use]
    pub fn contains(&self, node: usize) -> bool {
        self.iter().any(|(_, n)| n == node)
    }

    /// The index in the grab list of the grab holding `node`, if any.
    #[must_use]
    pub fn grab_of(&self, node: usize) -> Option<usize> {
        self.iter().find(|&(_, n)| n == node).map(|(g, _)| g)
    }

    /// `(grab index, node)` pairs, in grab-list order.
    pub fn iter(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.grab
            .iter()
            .zip(self.node.iter())
            .take(self.len)
            .map(|(&g, &n)| (usize::from(g), usize::from(n)))
    }

    /// How many nodes are held.
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no node is held.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// The nodes of strand `strand_index` (its index in the whole scene, as in [`Grab::strand`])
/// pinned this step by the grabs in `grabs`, when the `grabs` effect is on.
///
/// Only the first [`MAX_GRABS`] entries of `grabs` are looked at (the report has that many
/// force slots). A grab counts when it is [`GrabStatus::Held`], names this strand, a node from
/// 2 to `nodes − 1` (nodes 0 and 1 belong to the head) and a finite target; when two grabs
/// name the same node, the first one in the list holds it and the other is ignored.
#[must_use]
pub fn grabbed_nodes(
    ctx: &crate::context::StepContext,
    grabs: &[Grab],
    strand_index: u32,
    nodes: usize,
) -> GrabbedNodes {
    let mut held = GrabbedNodes::default();
    if !ctx.has(crate::effects::Effect::Grabs) {
        return held;
    }
    for (g, grab) in grabs.iter().enumerate().take(MAX_GRABS) {
        let node = grab.node as usize;
        let valid = grab.status == GrabStatus::Held
            && grab.strand == strand_index
            && (2..nodes).contains(&node)
            && node <= usize::from(u16::MAX)
            && crate::math::is_finite(grab.target);
        if valid && !held.contains(node) {
            if let (Some(slot_grab), Some(slot_node)) =
                (held.grab.get_mut(held.len), held.node.get_mut(held.len))
            {
                // `g < MAX_GRABS ≤ u8::MAX` and `node ≤ u16::MAX`: both fit.
                *slot_grab = g as u8;
                *slot_node = node as u16;
                held.len += 1;
            }
        }
    }
    held
}

/// After a strand's step was undone (the guard rolled it back to its last good state, at
/// rest): the forces its grabs' devices feel are those of that state. A prescribed grab feels
/// none (the step did not happen, and what a diverging step computed is no force a device
/// should render); a coupled grab feels its coupling, `K (x − T) + B (v − v_T)`, stretched from
/// the node where it was left. (A slip the step caused stands: a grab that let go of a
/// diverging strand is safe.)
pub fn forces_after_roll_back<const N: usize>(
    ctx: &crate::context::StepContext,
    grabs: &[Grab],
    (strand, strand_index): (&crate::strand::Strand<N>, u32),
    report: &mut crate::report::StepReport,
) {
    let nodes = strand.rest.nodes.min(N);
    for (g, node) in grabbed_nodes(ctx, grabs, strand_index, nodes).iter() {
        let (Some(grab), Some(force)) = (grabs.get(g), report.grab_forces.get_mut(g)) else {
            continue;
        };
        *force = match (grab.coupling, strand.state.position.get(node)) {
            (Some(c), Some(&x)) => {
                let v = strand
                    .state
                    .velocity
                    .get(node)
                    .copied()
                    .unwrap_or(Vec3::ZERO);
                coupling_force(&c, x, v, grab, ctx.inv_dt)
            }
            _ => Vec3::ZERO,
        };
    }
}

/// The force a coupling's device feels with its node at `x`, moving at `v`:
/// `K (x − T) + B (v − v_T)`, `v_T = (T − T_prev)/Δt` (`inv_dt` = `1/Δt`).
#[must_use]
pub fn coupling_force(c: &Coupling, x: Vec3, v: Vec3, grab: &Grab, inv_dt: Real) -> Vec3 {
    let target_velocity = (grab.target - grab.previous_target) * inv_dt;
    (x - grab.target) * c.stiffness + (v - target_velocity) * c.damping
}

/// Moves `grab`'s target to `target` if it is finite (the caller's input: a non-finite
/// target is ignored). Returns whether it moved.
pub fn retarget(grab: &mut Grab, target: Vec3) -> bool {
    if crate::math::is_finite(target) {
        grab.target = target;
        true
    } else {
        false
    }
}

/// After a step: every grab whose bit is set in `report.grabs_slipped` stops holding its node,
/// and every grab remembers the target the step ended with (its coupling's damper measures
/// the target's velocity from it).
pub fn apply_slips(grabs: &mut [Grab], report: &crate::report::StepReport) {
    for (g, grab) in grabs.iter_mut().enumerate() {
        if g < MAX_GRABS && report.grabs_slipped & (1 << g) != 0 {
            grab.status = GrabStatus::Slipped;
        }
        grab.previous_target = grab.target;
    }
}

/// Slack allowed on a grab's reach: the projection's stretch bound (issue 4: 0.1 %).
pub const REACH_SLACK: Real = 1.0e-3;

/// Before a step: a held, prescribed grab whose target no inextensible strand can reach slips
/// at once, and its bit is set in `report.grabs_slipped`. A coupled grab never slips on reach:
/// its node stays on the strand and the coupling's spring stretches instead.
///
/// Holding it would take an unbounded force: the projection, asked for positions that do
/// not exist (prescribed nodes carry no rows), stretches and kinks the strand
/// before the force limit lets go a step or two later, and the strand then whips from that
/// state (measured in `tests/torture.rs`: chatter 3.5 rad). A target is out of reach when
/// it is farther from the strand's head-held node 1 (where the head puts it this step), or
/// from another held grab's target on the same strand, than the rest arc length between the
/// two nodes, with [`REACH_SLACK`]. `strands[k]` is strand `first_strand + k`; `effects` are
/// the step's, `head` the pose it ends at.
pub fn slip_unreachable<const N: usize>(
    (effects, head): (crate::effects::Effects, &crate::head::Pose),
    grabs: &mut [Grab],
    strands: &[crate::strand::Strand<N>],
    first_strand: u32,
    report: &mut crate::report::StepReport,
) {
    if !effects.contains(crate::effects::Effect::Grabs) {
        return;
    }
    let count = grabs.len().min(MAX_GRABS);
    let mut out_of_reach = 0u8;
    for a in 0..count {
        let Some((rest, root, node_a, target_a)) = held(grabs, a, strands, first_strand) else {
            continue;
        };
        let anchor = head.transform_point(root);
        if !within_reach(rest, 1, node_a, anchor, target_a) {
            out_of_reach |= 1 << a;
        }
        for b in a + 1..count {
            let Some((rest_b, _, node_b, target_b)) = held(grabs, b, strands, first_strand) else {
                continue;
            };
            // Two grabs on the same strand share its rest data; on the same node the first
            // holds it and the other is ignored (`grabbed_nodes`), so they are no pair.
            if core::ptr::eq(rest, rest_b)
                && node_a != node_b
                && !within_reach(
                    rest,
                    node_a.min(node_b),
                    node_a.max(node_b),
                    target_a,
                    target_b,
                )
            {
                out_of_reach |= (1 << a) | (1 << b);
            }
        }
    }
    for (g, grab) in grabs.iter_mut().enumerate().take(count) {
        if out_of_reach & (1 << g) != 0 {
            grab.status = GrabStatus::Slipped;
        }
    }
    report.grabs_slipped |= out_of_reach;
}

/// Grab `g` if it prescribes a node of one of `strands`: the strand's rest data, its rest
/// node 1, the grabbed node and the target.
fn held<'a, const N: usize>(
    grabs: &[Grab],
    g: usize,
    strands: &'a [crate::strand::Strand<N>],
    first_strand: u32,
) -> Option<(&'a crate::strand::RestStrand<N>, Vec3, usize, Vec3)> {
    let grab = grabs.get(g)?;
    let strand = strands.get(grab.strand.checked_sub(first_strand)? as usize)?;
    let node = grab.node as usize;
    let usable = grab.status == GrabStatus::Held
        && !grab.is_coupled()
        && (2..strand.nodes()).contains(&node)
        && crate::math::is_finite(grab.target);
    let root = *strand.rest.position.get(1)?;
    usable.then_some((&strand.rest, root, node, grab.target))
}

/// Whether points `a` and `b`, held at nodes `from < to`, are no farther apart than the rest
/// arc length between those nodes (with [`REACH_SLACK`]).
fn within_reach<const N: usize>(
    rest: &crate::strand::RestStrand<N>,
    from: usize,
    to: usize,
    a: Vec3,
    b: Vec3,
) -> bool {
    let arc: Real = rest
        .segment_length
        .get(from..to)
        .map_or(0.0, |lengths| lengths.iter().sum());
    let reach = arc * (1.0 + REACH_SLACK);
    // Squared on both sides: no square root.
    (b - a).length_squared() <= reach * reach
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::{Effect, Effects};
    use crate::head::Pose;
    use crate::math::Libm;
    use crate::params::{Params, Solver};
    use crate::strand::{Material, Strand};
    use crate::world::{StepInput, World};

    #[test]
    fn a_coupling_out_of_range_names_its_field() {
        let out = |field| {
            Err(ParamError::OutOfRange {
                field,
                allowed: match field {
                    "grab.coupling.stiffness" => "1e-3 to 1e5 N/m",
                    _ => "0 to 1e3 N·s/m",
                },
            })
        };
        assert_eq!(Coupling::new(50.0, 0.01).check(), Ok(()));
        assert_eq!(Coupling::new(1.0e-3, 0.0).check(), Ok(()));
        assert_eq!(
            Coupling::new(1.0e6, 0.01).check(),
            out("grab.coupling.stiffness")
        );
        assert_eq!(
            Coupling::new(Real::NAN, 0.01).check(),
            out("grab.coupling.stiffness")
        );
        assert_eq!(
            Coupling::new(50.0, -1.0).check(),
            out("grab.coupling.damping")
        );
        assert!(!Coupling::new(50.0, Real::INFINITY).is_valid());
    }

    /// Two straight 5 cm strands (6 nodes, 1 cm apart) along x, the rod with grabs.
    fn world() -> World<2, 8, Libm> {
        let mut w = World::with_params(Params {
            solver: Solver::Rod,
            effects: Effects::NONE
                .with(Effect::Inextensibility)
                .with(Effect::Grabs),
            ..Params::DEFAULT
        })
        .unwrap();
        for z in [0.0, 0.1] {
            let points: [Vec3; 6] = core::array::from_fn(|i| Vec3::new(0.01 * i as Real, 0.0, z));
            w.add_strand(Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap())
                .unwrap();
        }
        w
    }

    fn step(w: &mut World<2, 8, Libm>) -> crate::report::StepReport {
        w.step(&StepInput {
            head: Pose::IDENTITY,
            accelerations: None,
        })
    }

    #[test]
    fn a_target_within_reach_holds() {
        let mut w = world();
        // Node 5 is 4 cm of hair from node 1: a target 3.9 cm from node 1, off the axis.
        w.add_grab(Grab::new(0, 5, Vec3::new(0.01, 0.039, 0.0), 1.0))
            .unwrap();
        let report = step(&mut w);
        assert_eq!(report.grabs_slipped, 0);
        assert_eq!(w.grabs()[0].status, GrabStatus::Held);
    }

    #[test]
    fn a_target_beyond_the_strand_slips_before_the_step() {
        let mut w = world();
        // 4.1 cm from node 1: out of reach by 2.5 %, whatever the force limit.
        w.add_grab(Grab::new(0, 5, Vec3::new(0.01, 0.041, 0.0), 1.0e9))
            .unwrap();
        let report = step(&mut w);
        assert_eq!(report.grabs_slipped, 1);
        assert_eq!(w.grabs()[0].status, GrabStatus::Slipped);
        // The strand was never stretched towards it.
        assert!(report.max_stretch < 1.0e-3, "{}", report.max_stretch);
    }

    #[test]
    fn two_grabs_farther_apart_than_the_hair_between_them_both_slip() {
        let mut w = world();
        // Nodes 2 and 5 of strand 0: 3 cm of hair; targets 3.2 cm apart, each within reach
        // of node 1. A grab on the other strand, within reach, holds.
        w.add_grab(Grab::new(0, 2, Vec3::new(0.01, -0.005, 0.0), 1.0e9))
            .unwrap();
        w.add_grab(Grab::new(0, 5, Vec3::new(0.01, 0.027, 0.0), 1.0e9))
            .unwrap();
        w.add_grab(Grab::new(1, 5, Vec3::new(0.05, 0.0, 0.1), 1.0e9))
            .unwrap();
        let report = step(&mut w);
        assert_eq!(report.grabs_slipped, 0b011);
        assert_eq!(w.grabs()[2].status, GrabStatus::Held);
    }
}
