//! Grabs: a node pinned to a moving target, for user interaction (a haptic tool holding hair).

use crate::math::{Real, Vec3};

pub use crate::capacities::MAX_GRABS;

/// Whether a grab holds its node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GrabStatus {
    /// The node follows the target.
    Held,
    /// The force limit was exceeded: the node is free and the grab stays released.
    Slipped,
    /// Released by the caller.
    Released,
}

/// A node pinned to a target that the caller moves each tick.
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
}

#[cfg(feature = "defmt")]
impl defmt::Format for Grab {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "Grab {{ strand: {}, node: {}, target: {}, force_limit: {}, status: {} }}",
            self.strand,
            self.node,
            crate::math::DefmtVec3(self.target),
            self.force_limit,
            self.status
        )
    }
}

impl Grab {
    /// A grab of `node` on `strand`, held at `target`, slipping above `force_limit` newtons.
    #[must_use]
    pub const fn new(strand: u32, node: u32, target: Vec3, force_limit: Real) -> Grab {
        Grab {
            strand,
            node,
            target,
            force_limit,
            status: GrabStatus::Held,
        }
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

/// After a step: every grab whose bit is set in `report.grabs_slipped` stops holding its node.
pub fn apply_slips(grabs: &mut [Grab], report: &crate::report::StepReport) {
    for (g, grab) in grabs.iter_mut().enumerate().take(MAX_GRABS) {
        if report.grabs_slipped & (1 << g) != 0 {
            grab.status = GrabStatus::Slipped;
        }
    }
}

/// Slack allowed on a grab's reach: the projection's stretch bound (issue 4: 0.1 %).
pub const REACH_SLACK: Real = 1.0e-3;

/// Before a step: a held grab whose target no inextensible strand can reach slips at once,
/// and its bit is set in `report.grabs_slipped`.
///
/// Holding it would take an unbounded force: the projection, asked for positions that do
/// not exist (prescribed nodes carry no rows), stretches and kinks the strand
/// before the force limit lets go a step or two later, and the strand then whips from that
/// state (measured in `tests/torture.rs`: chatter 3.5 rad). A target is out of reach when
/// it is farther from the strand's head-held node 1 (where the head puts it this step), or
/// from another held grab's target on the same strand, than the rest arc length between the
/// two nodes, with [`REACH_SLACK`]. `strands[k]` is strand `first_strand + k`.
pub fn slip_unreachable<const N: usize>(
    ctx: &crate::context::StepContext,
    grabs: &mut [Grab],
    strands: &[crate::strand::Strand<N>],
    first_strand: u32,
    report: &mut crate::report::StepReport,
) {
    if !ctx.has(crate::effects::Effect::Grabs) {
        return;
    }
    let count = grabs.len().min(MAX_GRABS);
    let mut out_of_reach = 0u8;
    for a in 0..count {
        let Some((rest, root, node_a, target_a)) = held(grabs, a, strands, first_strand) else {
            continue;
        };
        let anchor = ctx.head.transform_point(root);
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

/// Grab `g` if it holds a node of one of `strands`: the strand's rest data, its rest node 1,
/// the grabbed node and the target.
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
