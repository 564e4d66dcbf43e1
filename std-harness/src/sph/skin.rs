//! When the candidate lists must be rebuilt: a skin around the smoothing length, measured in
//! the head's frame (Verlet lists; Verlet 1967, as molecular dynamics keeps them).
//!
//! The lists hold every pair within `h + skin` at their last rebuild. A pair within `h` now was
//! within `h + skin` then if neither of its particles has moved more than `skin / 2` since:
//! distances change by at most the sum of the two moves. The moves are measured in a frame
//! that turns and moves with the head — any rigid motion keeps distances, and hair mostly
//! goes where the head takes it — so a turning head costs no rebuild, only the hair moving
//! over the head does. Positions in the frame carry a rounding of a few units in the last
//! place of the largest coordinate; the limit keeps a margin of many times that.

use hairsim_core::math::Mat3;
use hairsim_core::{Pose, Strand, Vec3};
use rayon::prelude::*;

/// Strands per parallel work item of the check.
const STRANDS_PER_CHUNK: usize = 64;

/// A rigid frame: a point's coordinates in it are `R^T (x − t)`.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    inverse_rotation: Mat3,
    origin: Vec3,
}

impl Frame {
    /// The frame of `pose` (the head's), or the world's when `pose` is not finite.
    #[must_use]
    pub fn of(pose: Pose) -> Frame {
        if !pose.is_finite() {
            return Frame::of(Pose::IDENTITY);
        }
        Frame {
            inverse_rotation: Mat3::from_quat(pose.rotation.normalize()).transpose(),
            origin: pose.position,
        }
    }

    /// `x` in this frame.
    #[inline(always)]
    #[must_use]
    pub fn local(&self, x: Vec3) -> Vec3 {
        self.inverse_rotation * (x - self.origin)
    }
}

/// The particles' positions in the frame at the last rebuild, in the particle order (strand
/// by strand), and the largest coordinate seen then.
#[derive(Clone, Debug)]
pub struct Reference {
    /// Each particle's position in the frame at the last rebuild.
    pub position: Vec<[f32; 3]>,
    /// The largest magnitude of any coordinate, world or frame, at the last rebuild, m.
    pub largest: f32,
    /// Whether the lists were ever built.
    pub built: bool,
}

impl Reference {
    /// No reference yet, for `particles` particles.
    #[must_use]
    pub fn new(particles: usize) -> Reference {
        Reference {
            position: vec![[0.0; 3]; particles],
            largest: 0.0,
            built: false,
        }
    }

    /// Whether some particle of `strands` (laid out from `first`) has moved in `frame` by more
    /// than `skin / 2` (less the margin) since the last rebuild, or a position is not finite,
    /// or the lists were never built: the lists must be rebuilt. And how far the particle that
    /// moved most has moved, m (infinite when unknown).
    pub fn moved<const N: usize>(
        &self,
        strands: &[Strand<N>],
        first: &[u32],
        frame: &Frame,
        skin: f32,
    ) -> (bool, f32) {
        if !self.built {
            return (true, f32::INFINITY);
        }
        let (furthest, largest) = strands
            .par_chunks(STRANDS_PER_CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut furthest = 0.0f32;
                let mut largest = 0.0f32;
                for (k, strand) in chunk.iter().enumerate() {
                    let s = c * STRANDS_PER_CHUNK + k;
                    let from = first.get(s).copied().unwrap_or(0) as usize;
                    let nodes = strand.nodes();
                    let Some(reference) = self.position.get(from..from + nodes) else {
                        return (f32::INFINITY, f32::INFINITY);
                    };
                    for (&x, y0) in strand.state.position[..nodes].iter().zip(reference) {
                        let y = frame.local(x);
                        // NaN moves "infinitely": `max` would drop it; once in, it stays.
                        furthest = further(furthest, (y - Vec3::from_array(*y0)).length_squared());
                        largest = largest.max(x.abs().max_element().max(y.abs().max_element()));
                    }
                }
                (furthest, largest)
            })
            .reduce(|| (0.0, 0.0), |a, b| (further(a.0, b.0), a.1.max(b.1)));
        let limit = skin / 2.0 - margin(largest.max(self.largest));
        (!(limit > 0.0 && furthest <= limit * limit), furthest.sqrt())
    }
}

/// The larger of two moves, a NaN move being the largest: `f32::max` would drop it, and once
/// in it stays.
#[inline(always)]
#[must_use]
pub fn further(furthest: f32, d: f32) -> f32 {
    if d > furthest || d.is_nan() {
        d
    } else {
        furthest
    }
}

/// What rounding can take off a distance measured in the frame and in the world, with
/// coordinates up to `largest`: many units in the last place of the largest coordinate.
#[must_use]
pub fn margin(largest: f32) -> f32 {
    64.0 * f32::EPSILON * largest
}

#[cfg(test)]
mod tests {
    use super::*;
    use hairsim_core::{Material, Quat};

    fn strand(offset: Vec3) -> Strand<8> {
        let points: Vec<Vec3> = (0..8)
            .map(|i| offset + Vec3::new(0.0, -0.01 * i as f32, 0.0))
            .collect();
        Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
    }

    fn reference_of(strands: &[Strand<8>], frame: &Frame) -> Reference {
        let mut r = Reference::new(strands.len() * 8);
        for (s, strand) in strands.iter().enumerate() {
            for i in 0..8 {
                r.position[s * 8 + i] = frame.local(strand.state.position[i]).to_array();
            }
        }
        r.built = true;
        r.largest = 1.0;
        r
    }

    impl Reference {
        fn moved_at(&self, s: &[Strand<8>], first: &[u32], frame: &Frame, skin: f32) -> bool {
            self.moved(s, first, frame, skin).0
        }
    }

    #[test]
    fn a_rigid_turn_is_no_move_and_a_move_past_half_the_skin_is() {
        let mut strands = vec![strand(Vec3::new(0.1, 0.0, 0.0)), strand(Vec3::ZERO)];
        let first = [0, 8, 16];
        let start = Pose::IDENTITY;
        let reference = reference_of(&strands, &Frame::of(start));
        assert!(!reference.moved_at(&strands, &first, &Frame::of(start), 0.002));
        // The head and the hair turn and move together: no rebuild.
        let turned = Pose {
            position: Vec3::new(0.01, 0.02, 0.0),
            rotation: Quat::from_rotation_y(0.7),
        };
        for s in &mut strands {
            for x in &mut s.state.position {
                *x = turned.transform_point(*x);
            }
        }
        assert!(!reference.moved_at(&strands, &first, &Frame::of(turned), 0.002));
        // One node slides 0.9 mm over the head, then 1.1 mm: the second passes half of 2 mm.
        let slide = turned.transform_vector(Vec3::new(0.0009, 0.0, 0.0));
        strands[1].state.position[5] += slide;
        assert!(!reference.moved_at(&strands, &first, &Frame::of(turned), 0.002));
        strands[1].state.position[5] += slide * (2.0 / 9.0);
        assert!(reference.moved_at(&strands, &first, &Frame::of(turned), 0.002));
        // A position that is not a number always rebuilds.
        strands[1].state.position[5] = Vec3::NAN;
        assert!(reference.moved_at(&strands, &first, &Frame::of(turned), 0.002));
        assert!(Reference::new(16).moved_at(&strands, &first, &Frame::of(turned), 0.002));
    }
}
