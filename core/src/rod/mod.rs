//! The Kirchhoff-rod solver of Kmoch, Bonanni and Magnenat-Thalmann 2009 (after Bergou et al.
//! 2008): a Bishop frame, hair-optimised twist, symplectic Euler and a fast manifold projection.
//!
//! * [`energy`] — rest state, bending and twist energies, their gradients and the elastic forces.
//! * [`twist`] — the quasistatic twist: hair-optimised (Sec. 6.2) or Newton (BWR08).
//! * [`step`] — Algorithm 1 as a list of stages.

pub mod energy;
pub mod step;
pub mod twist;

/// Most clamped segments besides the root a strand may have (one per grab, with room to spare).
pub const MAX_CLAMPED: usize = 8;

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

    /// Whether segment `segment` is clamped (always for segment 0).
    #[must_use]
    pub fn contains(&self, segment: usize) -> bool {
        segment == 0 || self.others().any(|s| s == segment)
    }

    /// The clamped segments other than the root, in insertion order.
    pub fn others(&self) -> impl Iterator<Item = usize> + '_ {
        self.segments[..self.count as usize]
            .iter()
            .map(|&s| s as usize)
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
    /// Both energies.
    pub const ALL: ElasticTerms = ElasticTerms {
        bending: true,
        twist: true,
    };
}
