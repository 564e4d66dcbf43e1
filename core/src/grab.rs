//! Grabs: a node pinned to a moving target, for user interaction (a haptic tool holding hair).

use crate::math::{Real, Vec3};

/// Most grabs a world holds.
pub const MAX_GRABS: usize = 4;

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
/// A held node is *prescribed* (infinite mass, no constraint rows — DESIGN.md, fast manifold
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

/// After a step: every grab whose bit is set in `report.grabs_slipped` stops holding its node.
pub fn apply_slips(grabs: &mut [Grab], report: &crate::report::StepReport) {
    for (g, grab) in grabs.iter_mut().enumerate().take(MAX_GRABS) {
        if report.grabs_slipped & (1 << g) != 0 {
            grab.status = GrabStatus::Slipped;
        }
    }
}
