//! Building a strand: Kmoch 2009 Algorithm 1 line 1, "precompute rest-state values", for both
//! solvers at once. From a rest polyline (root first, in the head's frame) and a material:
//! the rest segment lengths and node masses, the rod's rest data (`rod::rest`) and DFTL's
//! (`dftl::rest`), and a state at rest. Runs once per strand, never in a step.

use crate::capacities::{MAX_SEGMENT_LENGTH, MIN_SEGMENT_LENGTH};
use crate::error::BuildError;
use crate::frames::rest_root_frame;
use crate::math::{Libm, Math, Real, Vec3};
use crate::strand::{DftlRest, Material, RestStrand, RodRest, Schedule, Strand, StrandState};

impl<const N: usize> Strand<N> {
    const CAPACITY_OK: () = assert!(N >= 3, "a strand needs a capacity of at least 3 nodes");

    /// Builds a strand at rest from its rest polyline (root first, in the head's frame) and a
    /// material. Checks the node count against `N`, every coordinate, every segment's length
    /// and the material's ranges.
    pub fn from_polyline(points: &[Vec3], material: &Material) -> Result<Self, BuildError> {
        let mut strand = Self::EMPTY;
        strand.rebuild(points, material)?;
        Ok(strand)
    }

    /// No strand: every value zero (the placeholder [`Self::rebuild`] writes over).
    pub const EMPTY: Strand<N> = Strand {
        state: StrandState {
            position: [Vec3::ZERO; N],
            velocity: [Vec3::ZERO; N],
            theta: [0.0; N],
            root_frame: Vec3::ZERO,
        },
        rest: RestStrand {
            position: [Vec3::ZERO; N],
            segment_length: [0.0; N],
            mass: [0.0; N],
            inverse_mass: [0.0; N],
            dftl: DftlRest {
                root_tangent: Vec3::ZERO,
                root_normal: Vec3::ZERO,
                local_rest: [Vec3::ZERO; N],
                root_distance: [0.0; N],
                strain_scale: [0.0; N],
            },
            nodes: 0,
            rod: RodRest {
                rest_length: [0.0; N],
                voronoi_length: [0.0; N],
                inverse_voronoi_length: [0.0; N],
                bending_stiffness: [0.0; N],
                minor_axis_penalty: 0.0,
                twist_stiffness: 0.0,
                rest_theta: [0.0; N],
                rest_twist: [0.0; N],
                rest_twist_rotation: [[0.0; 2]; N],
                rest_curvature: [[[0.0; 2]; 2]; N],
                stable_time_step: 0.0,
            },
        },
        schedule: Schedule {
            implicit_bending: false,
        },
    };

    /// [`Self::from_polyline`] written over `self` in place: what a world does to build a
    /// strand in its own storage, with no strand-sized value on the stack. On an error `self`
    /// is left part-built (the world drops it).
    pub fn rebuild(&mut self, points: &[Vec3], material: &Material) -> Result<(), BuildError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::CAPACITY_OK;
        check_polyline::<N>(points, material)?;
        let nodes = points.len();
        let rest = &mut self.rest;
        rest.nodes = nodes;
        rest.position = [Vec3::ZERO; N];
        rest.position[..nodes].copy_from_slice(points);
        rest.segment_length = [0.0; N];
        rest.mass = [0.0; N];
        rest.inverse_mass = [0.0; N];
        let lambda = material.linear_density();
        lengths_and_masses(rest, points, lambda)?;
        rest.dftl.fill::<Libm>(points);
        // Segments are checked above: the rod's rest data divides by their lengths.
        let stiffness = (
            material.bending_stiffness(),
            material.minor_axis_penalty,
            material.twist_stiffness(),
        );
        rest.rod.fill::<Libm>(points, stiffness, lambda);
        let state = &mut self.state;
        state.position = [Vec3::ZERO; N];
        state.position[..nodes].copy_from_slice(points);
        state.velocity = [Vec3::ZERO; N];
        // The rest material frames: a strand starts at rest for the twist solvers too.
        state.theta = rest.rod.rest_theta;
        state.root_frame = rest_root_frame::<Libm>(points[0], points[1], rest.segment_length[0]);
        self.schedule = Schedule::default();
        Ok(())
    }
}

/// The checks that need no segment: the node count against `3 ..= N`, the material's ranges,
/// every coordinate finite (in this order: the first that fails is the error).
fn check_polyline<const N: usize>(points: &[Vec3], material: &Material) -> Result<(), BuildError> {
    let nodes = points.len();
    if nodes < 3 {
        return Err(BuildError::TooFewNodes { count: nodes });
    }
    if nodes > N {
        return Err(BuildError::TooManyNodes {
            count: nodes,
            capacity: N,
        });
    }
    material.validate()?;
    if let Some(node) = points.iter().position(|p| !crate::math::is_finite(*p)) {
        return Err(BuildError::NonFiniteNode { node });
    }
    Ok(())
}

/// The rest segment lengths `|ê^j|` and node masses (`ρπr²` times the node's Voronoi length,
/// half of each adjacent segment) with their inverses, root to tip; refuses a segment shorter
/// than [`MIN_SEGMENT_LENGTH`] and a polyline that folds back on itself.
fn lengths_and_masses<const N: usize>(
    rest: &mut RestStrand<N>,
    points: &[Vec3],
    lambda: Real,
) -> Result<(), BuildError> {
    let nodes = points.len();
    for j in 0..nodes - 1 {
        let e = points[j + 1] - points[j];
        let length = Libm::length(e);
        if !length.is_finite() || length > MAX_SEGMENT_LENGTH {
            return Err(BuildError::LongSegment { segment: j });
        }
        if length < MIN_SEGMENT_LENGTH {
            return Err(BuildError::DegenerateSegment { segment: j });
        }
        if j > 0 {
            let previous = points[j] - points[j - 1];
            // Turning angle of π: the curvature binormal 2(e×e')/(|e||e'| + e·e') divides by 0.
            if previous.dot(e) <= -0.999_999 * rest.segment_length[j - 1] * length {
                return Err(BuildError::FoldedSegment { node: j });
            }
        }
        rest.segment_length[j] = length;
        rest.mass[j] += 0.5 * lambda * length;
        rest.mass[j + 1] += 0.5 * lambda * length;
    }
    for i in 0..nodes {
        rest.inverse_mass[i] = 1.0 / rest.mass[i];
    }
    Ok(())
}
