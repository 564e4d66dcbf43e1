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
