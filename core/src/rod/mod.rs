//! The stages of the Kirchhoff-rod solver of Kmoch, Bonanni and Magnenat-Thalmann 2009 (after
//! Bergou et al. 2008): a Bishop frame, hair-optimised twist, symplectic Euler and a fast
//! manifold projection (`crate::projection`). The pipeline that runs them is `pipeline::rod`.
//!
//! * [`rest`] — Algorithm 1 line 1: the rest-state values.
//! * [`frames`] — the frames of a configuration: segments, binormals, the Bishop frame in space.
//! * [`energy`] — bending and twist energies, their gradients and the elastic forces (line 3).
//! * [`substeps`] — how many explicit substeps a strand takes, or the implicit step (lines 3–4).
//! * [`integrate`] — symplectic Euler (line 4).
//! * [`implicit`] — the linearly implicit bending step for stiff strands (lines 3–4).
//! * [`twist`] — the quasistatic twist: hair-optimised (Sec. 6.2) or Newton (BWR08) (line 10).

use crate::context::Gates;
use crate::grab::{Grab, GrabStatus};
use crate::lane::{Wide, WideMask};
use crate::precision::{Arithmetic, Scalar};

pub mod block;
pub mod energy;
pub mod frames;
pub mod implicit;
pub mod integrate;
pub mod rest;
pub mod substeps;
pub mod twist;

pub use crate::capacities::MAX_CLAMPED;

/// The clamped set `C` of Kmoch Sec. 7.2: segments whose material frame is held rather than
/// solved for by the twist. The root segment 0 is always clamped (the head holds it); a grabbed
/// node's segment is clamped too, and the projection passes those here.
///
/// A clamped segment's `θ` is left alone by both twist methods (a Dirichlet row for Newton) and
/// adds `∂E/∂θ^c ∇Ψ^c` to the elastic forces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClampedSegments {
    segments: [u16; MAX_CLAMPED],
    count: u8,
}

impl ClampedSegments {
    /// Only the root segment.
    pub const ROOT_ONLY: ClampedSegments = ClampedSegments {
        segments: [0; MAX_CLAMPED],
        count: 0,
    };

    /// Adds segment `segment` (segment 0 is always in the set). Returns `false`, and leaves
    /// the set unchanged, when [`MAX_CLAMPED`] segments are already held.
    pub fn insert(&mut self, segment: usize) -> bool {
        if segment == 0 || self.contains(segment) {
            return true;
        }
        match self.segments.get_mut(self.count as usize) {
            Some(slot) if segment <= u16::MAX as usize => {
                *slot = segment as u16;
                self.count += 1;
                true
            }
            _ => false,
        }
    }

    /// The clamped set of strand `strand_index` (`nodes` nodes) under `grabs`: the root, plus
    /// for each held grab of a node `g ≥ 2` of this strand the segment `e^g` that starts at it
    /// (`e^{g−1}` for the tip node). Grabs beyond [`MAX_CLAMPED`] are not clamped (they still
    /// pin their node in the projection). A coupled grab clamps nothing: its spring holds a
    /// point, which turns freely.
    #[must_use]
    pub fn from_grabs(grabs: &[Grab], strand_index: u32, nodes: usize) -> ClampedSegments {
        let mut set = ClampedSegments::ROOT_ONLY;
        for grab in grabs {
            let node = grab.node as usize;
            if grab.strand != strand_index
                || grab.status != GrabStatus::Held
                || grab.is_coupled()
                || node >= nodes
            {
                continue;
            }
            let segment = if node + 1 < nodes {
                node
            } else {
                node.saturating_sub(1)
            };
            let _ = set.insert(segment);
        }
        set
    }

    /// The clamped set of a step: [`Self::from_grabs`] with the `grabs` effect on, the root
    /// alone without.
    #[must_use]
    pub fn of_step(gates: &Gates, grabs: &[Grab], strand_index: u32, nodes: usize) -> Self {
        if gates.grabs {
            ClampedSegments::from_grabs(grabs, strand_index, nodes)
        } else {
            ClampedSegments::ROOT_ONLY
        }
    }

    /// Whether segment `segment` is clamped (always for segment 0). Inlined: the twist asks it
    /// of every segment, and a call cost 2 % of the hair-optimised twist's time.
    #[inline]
    #[must_use]
    pub fn contains(&self, segment: usize) -> bool {
        segment == 0 || self.others().any(|s| s == segment)
    }

    /// The clamped segments other than the root, in insertion order.
    #[inline]
    pub fn others(&self) -> impl Iterator<Item = usize> + '_ {
        self.segments[..self.count as usize]
            .iter()
            .map(|&s| s as usize)
    }
}

/// The clamped sets of the strands a kernel runs on: one strand's [`ClampedSegments`], or one
/// per lane of a block.
pub trait ClampedLanes<R: Arithmetic> {
    /// Whether segment `segment` is clamped, per lane.
    fn clamped(&self, segment: usize) -> R::Mask;
}

impl<R: Scalar> ClampedLanes<R> for ClampedSegments {
    #[inline(always)]
    fn clamped(&self, segment: usize) -> bool {
        self.contains(segment)
    }
}

/// Strands that hold no segment but the root's, known when the code is compiled: their
/// kernels (the twist of a block's strands in lanes) then carry no test of a clamped segment
/// past the root at all, whatever the compiler makes of a set passed at run time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RootOnly;

impl<R: Arithmetic> ClampedLanes<R> for RootOnly {
    #[inline(always)]
    fn clamped(&self, segment: usize) -> R::Mask {
        R::mask(segment == 0)
    }
}

impl<const W: usize> ClampedLanes<Wide<W>> for [ClampedSegments; W] {
    #[inline(always)]
    fn clamped(&self, segment: usize) -> WideMask<W> {
        // Most blocks hold no grab: no lane's set to search.
        if self.iter().all(|set| set.count == 0) {
            return WideMask::from_bools([segment == 0; W]);
        }
        WideMask::from_bools(core::array::from_fn(|lane| self[lane].contains(segment)))
    }
}

/// Which elastic energies are on (the `bending` and `twist` effects).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ElasticTerms {
    /// Bending energy (`bending` effect).
    pub bending: bool,
    /// Twist energy (`twist` effect).
    pub twist: bool,
}

impl ElasticTerms {
    /// The energies a step's gates turn on.
    #[inline(always)]
    #[must_use]
    pub fn of(gates: &Gates) -> Self {
        ElasticTerms {
            bending: gates.bending,
            twist: gates.twist,
        }
    }

    /// Both energies.
    pub const ALL: ElasticTerms = ElasticTerms {
        bending: true,
        twist: true,
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    #[test]
    fn grabs_clamp_their_segment_on_their_strand_only() {
        let mut released = Grab::new(1, 5, Vec3::ZERO, 1.0);
        released.status = GrabStatus::Released;
        let grabs = [
            Grab::new(1, 4, Vec3::ZERO, 1.0),
            Grab::new(0, 7, Vec3::ZERO, 1.0),
            Grab::new(1, 9, Vec3::ZERO, 1.0),
            released,
        ];
        let set = ClampedSegments::from_grabs(&grabs, 1, 10);
        assert!(set.contains(0) && set.contains(4) && set.contains(8));
        assert!(!set.contains(5) && !set.contains(7) && !set.contains(9));
        assert_eq!(set.others().count(), 2);
        let mut full = ClampedSegments::ROOT_ONLY;
        for s in 1..=MAX_CLAMPED {
            assert!(full.insert(s));
        }
        assert!(!full.insert(MAX_CLAMPED + 1) && full.insert(3));
    }
}
