//! The core's errors. Each says what is wrong in words; none of them is returned by `step()`,
//! which reports instead of failing.

use core::fmt;

/// Why a strand could not be built from a rest polyline.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BuildError {
    /// Fewer than 3 nodes: a rod needs two held root nodes and at least one free node.
    TooFewNodes {
        /// Nodes given.
        count: usize,
    },
    /// More nodes than the strand capacity `N`.
    TooManyNodes {
        /// Nodes given.
        count: usize,
        /// The capacity `N`.
        capacity: usize,
    },
    /// A node coordinate is NaN or infinite.
    NonFiniteNode {
        /// Index of the node, root = 0.
        node: usize,
    },
    /// A segment is shorter than [`crate::capacities::MIN_SEGMENT_LENGTH`].
    DegenerateSegment {
        /// Index of the segment (between nodes `segment` and `segment + 1`).
        segment: usize,
    },
    /// A segment is longer than [`crate::capacities::MAX_SEGMENT_LENGTH`].
    LongSegment {
        /// Index of the segment (between nodes `segment` and `segment + 1`).
        segment: usize,
    },
    /// Two consecutive segments fold back onto each other (turning angle of π): the curvature
    /// binormal is undefined there.
    FoldedSegment {
        /// Index of the node where the polyline reverses.
        node: usize,
    },
    /// A material parameter is out of its range.
    InvalidMaterial {
        /// The field's name.
        field: &'static str,
        /// What is allowed.
        allowed: &'static str,
    },
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            BuildError::TooFewNodes { count } => write!(
                f,
                "a strand needs at least 3 nodes (2 held at the root, 1 free), got {count}"
            ),
            BuildError::TooManyNodes { count, capacity } => write!(
                f,
                "a strand has {count} nodes but the node capacity is {capacity}"
            ),
            BuildError::NonFiniteNode { node } => {
                write!(f, "node {node} has a NaN or infinite coordinate")
            }
            BuildError::DegenerateSegment { segment } => write!(
                f,
                "segment {segment} is shorter than {} m",
                crate::capacities::MIN_SEGMENT_LENGTH
            ),
            BuildError::LongSegment { segment } => write!(
                f,
                "segment {segment} is longer than {} m",
                crate::capacities::MAX_SEGMENT_LENGTH
            ),
            BuildError::FoldedSegment { node } => write!(
                f,
                "the polyline folds back on itself at node {node} (turning angle of 180 degrees)"
            ),
            BuildError::InvalidMaterial { field, allowed } => {
                write!(f, "material {field} is out of range: allowed {allowed}")
            }
        }
    }
}

/// A fixed capacity was exceeded. Nothing was added; the world is unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CapacityError {
    /// The world already holds its `S` strands.
    Strands {
        /// The capacity `S`.
        capacity: usize,
    },
    /// The world already holds [`crate::capacities::MAX_COLLIDERS`] colliders.
    Colliders {
        /// The capacity.
        capacity: usize,
    },
    /// The world already holds [`crate::capacities::MAX_GRABS`] grabs.
    Grabs {
        /// The capacity.
        capacity: usize,
    },
}

impl fmt::Display for CapacityError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            CapacityError::Strands { capacity } => {
                write!(f, "the world is full: it holds at most {capacity} strands")
            }
            CapacityError::Colliders { capacity } => {
                write!(f, "the world holds at most {capacity} colliders")
            }
            CapacityError::Grabs { capacity } => {
                write!(f, "the world holds at most {capacity} grabs")
            }
        }
    }
}

/// Why a set of parameters was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParamError {
    /// A parameter is out of its range.
    OutOfRange {
        /// The parameter's name, as in scene files.
        field: &'static str,
        /// What is allowed.
        allowed: &'static str,
    },
    /// An effect is on that the chosen solver cannot simulate.
    UnsupportedEffect {
        /// The effect's name.
        effect: &'static str,
        /// The solver's name.
        solver: &'static str,
    },
    /// Something was added that only an effect that is off would use: a collider without
    /// `collisions`, a grab without `grabs`.
    EffectOff {
        /// The effect's name.
        effect: &'static str,
        /// What was added ("a collider", "a grab").
        item: &'static str,
    },
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ParamError::OutOfRange { field, allowed } => {
                write!(f, "{field} is out of range: allowed {allowed}")
            }
            ParamError::UnsupportedEffect { effect, solver } => write!(
                f,
                "the {solver} solver cannot simulate the effect \"{effect}\""
            ),
            ParamError::EffectOff { effect, item } => write!(
                f,
                "{item} needs the effect \"{effect}\", which is off: turn it on before adding one"
            ),
        }
    }
}

/// Any error the core's set-up functions return.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// A strand could not be built.
    Build(BuildError),
    /// A capacity was exceeded.
    Capacity(CapacityError),
    /// Parameters were refused.
    Param(ParamError),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Build(e) => e.fmt(f),
            Error::Capacity(e) => e.fmt(f),
            Error::Param(e) => e.fmt(f),
        }
    }
}

impl From<BuildError> for Error {
    fn from(e: BuildError) -> Self {
        Error::Build(e)
    }
}
impl From<CapacityError> for Error {
    fn from(e: CapacityError) -> Self {
        Error::Capacity(e)
    }
}
impl From<ParamError> for Error {
    fn from(e: ParamError) -> Self {
        Error::Param(e)
    }
}

impl core::error::Error for BuildError {}
impl core::error::Error for CapacityError {}
impl core::error::Error for ParamError {}
impl core::error::Error for Error {}
