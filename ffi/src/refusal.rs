//! Which argument or field a call refused. A call on a world keeps its outcome in the world
//! (`Record`: the code, the function, the argument, the field, an index), and
//! `hairsim_last_refusal` reads it back as names. Inside the library a refusal is a
//! [`Refused`]: the `hairsim_error` code with what it is about.

use core::ffi::CStr;

use crate::types::hairsim_error;

/// Declares a `u8` enum of names with their C strings, and the table that reads a stored `u8`
/// back (an out-of-range byte reads as no name).
macro_rules! names {
    ($(#[$doc:meta])* $name:ident { $($variant:ident = $text:literal),* $(,)? }) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        #[repr(u8)]
        pub(crate) enum $name {
            $($variant),*
        }

        impl $name {
            const ALL: &'static [($name, &'static CStr)] = &[$(($name::$variant, $text)),*];

            /// The name as C reads it.
            pub(crate) fn text(self) -> &'static CStr {
                Self::ALL[self as usize].1
            }

            /// The name a stored byte stands for (`None` for no name).
            pub(crate) fn from_byte(byte: u8) -> Option<$name> {
                Self::ALL.get(usize::from(byte)).map(|&(name, _)| name)
            }
        }
    };
}

names! {
    /// The functions that keep their outcome in the world.
    Function {
        None = c"",
        Configure = c"hairsim_configure",
        AddStrand = c"hairsim_add_strand",
        AddCollider = c"hairsim_add_collider",
        AddGrab = c"hairsim_add_grab",
        ReleaseGrab = c"hairsim_release_grab",
        Step = c"hairsim_step",
        StrandPositions = c"hairsim_strand_positions",
        StateHash = c"hairsim_state_hash",
        GetInfo = c"hairsim_get_info",
        Check = c"hairsim_check",
        Recover = c"hairsim_recover",
    }
}

names! {
    /// Arguments of the functions and fields of the C structs, as the header spells them.
    Name {
        None = c"",
        World = c"world",
        Params = c"params",
        Points = c"points",
        Count = c"count",
        Material = c"material",
        Index = c"index",
        Collider = c"collider",
        Grab = c"grab",
        Input = c"input",
        Report = c"report",
        Strand = c"strand",
        Out = c"out",
        Capacity = c"capacity",
        Solver = c"solver",
        Dt = c"dt",
        Effects = c"effects",
        Mode = c"mode",
        Gravity = c"gravity",
        Drag = c"drag",
        RodProjectionIterations = c"rod_projection_iterations",
        RodProjectionTolerance = c"rod_projection_tolerance",
        RodTwist = c"rod_twist",
        RodNewtonIterations = c"rod_newton_iterations",
        RodNewtonTolerance = c"rod_newton_tolerance",
        DftlDamping = c"dftl_damping",
        DftlGlobalShape = c"dftl_global_shape",
        DftlLocalShape = c"dftl_local_shape",
        DftlReferenceDt = c"dftl_reference_dt",
        DftlGlobalShapeFade = c"dftl_global_shape_fade",
        DftlLocalShapeFade = c"dftl_local_shape_fade",
        WindDirection = c"wind_direction",
        WindStrength = c"wind_strength",
        WindGust = c"wind_gust",
        WindGustFrequency = c"wind_gust_frequency",
        WindSeed = c"wind_seed",
        YoungsModulus = c"youngs_modulus",
        ShearModulus = c"shear_modulus",
        Radius = c"radius",
        Density = c"density",
        MinorAxisPenalty = c"minor_axis_penalty",
        Shape = c"shape",
        AttachedToHead = c"attached_to_head",
        A = c"a",
        B = c"b",
        Node = c"node",
        Target = c"target",
        ForceLimit = c"force_limit",
        Stiffness = c"stiffness",
        Damping = c"damping",
        Head = c"head",
        GrabTargets = c"grab_targets",
        GrabTargetCount = c"grab_target_count",
        Accelerations = c"accelerations",
        AccelerationCount = c"acceleration_count",
        Strands = c"strands",
        Colliders = c"colliders",
        Grabs = c"grabs",
        Nodes = c"nodes",
        Schedule = c"schedule",
        Status = c"status",
        Coupling = c"coupling",
        BadTarget = c"bad_target",
        Scratch = c"scratch",
        State = c"state",
        Rest = c"rest",
    }
}

/// The field of a C struct that a field of the core's parameters or a collider's or grab's
/// check names (`ParamError::OutOfRange::field`, `BuildError::InvalidMaterial::field`).
pub(crate) fn core_field(field: &str) -> Name {
    const FIELDS: [(&str, Name); 35] = [
        ("solver", Name::Solver),
        ("dt", Name::Dt),
        ("gravity", Name::Gravity),
        ("drag", Name::Drag),
        ("rod.projection_iterations", Name::RodProjectionIterations),
        ("rod.projection_tolerance", Name::RodProjectionTolerance),
        ("rod.newton_iterations", Name::RodNewtonIterations),
        ("rod.newton_tolerance", Name::RodNewtonTolerance),
        ("dftl.damping", Name::DftlDamping),
        ("dftl.global_shape", Name::DftlGlobalShape),
        ("dftl.local_shape", Name::DftlLocalShape),
        ("dftl.reference_dt", Name::DftlReferenceDt),
        ("dftl.global_shape_fade", Name::DftlGlobalShapeFade),
        ("dftl.local_shape_fade", Name::DftlLocalShapeFade),
        ("wind.direction", Name::WindDirection),
        ("wind.strength", Name::WindStrength),
        ("wind.gust", Name::WindGust),
        ("wind.gust_frequency", Name::WindGustFrequency),
        ("youngs_modulus", Name::YoungsModulus),
        ("shear_modulus", Name::ShearModulus),
        ("radius", Name::Radius),
        ("density", Name::Density),
        ("minor_axis_penalty", Name::MinorAxisPenalty),
        ("collider.centre", Name::A),
        ("collider.a", Name::A),
        ("collider.point", Name::A),
        ("collider.b", Name::B),
        ("collider.normal", Name::B),
        ("collider.radius", Name::Radius),
        ("grab.strand", Name::Strand),
        ("grab.node", Name::Node),
        ("grab.target", Name::Target),
        ("grab.force_limit", Name::ForceLimit),
        ("grab.coupling.stiffness", Name::Stiffness),
        ("grab.coupling.damping", Name::Damping),
    ];
    FIELDS
        .iter()
        .find(|(name, _)| *name == field)
        .map_or(Name::None, |&(_, c)| c)
}

/// No index: `hairsim_refusal::index` is `UINT32_MAX`.
pub(crate) const NO_INDEX: u32 = u32::MAX;

/// A refused call: its code, and the argument, field and element it is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Refused {
    /// What the call returns.
    pub(crate) code: hairsim_error,
    /// The argument refused.
    pub(crate) argument: Name,
    /// The field of that argument.
    pub(crate) field: Name,
    /// The array element, node or segment concerned, or [`NO_INDEX`].
    pub(crate) index: u32,
}

impl From<hairsim_error> for Refused {
    fn from(code: hairsim_error) -> Self {
        Refused {
            code,
            argument: Name::None,
            field: Name::None,
            index: NO_INDEX,
        }
    }
}

impl Refused {
    /// This refusal about `argument` (unless it names one already).
    pub(crate) fn argument(mut self, argument: Name) -> Self {
        if self.argument == Name::None {
            self.argument = argument;
        }
        self
    }

    /// This refusal about `field` (unless it names one already).
    pub(crate) fn field(mut self, field: Name) -> Self {
        if self.field == Name::None {
            self.field = field;
        }
        self
    }

    /// This refusal about element `index`.
    pub(crate) fn at(mut self, index: usize) -> Self {
        self.index = u32::try_from(index).unwrap_or(NO_INDEX);
        self
    }
}

/// A call's outcome as the world keeps it: integers only, so that any bytes read back are a
/// record (unknown codes and names read as none).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Record {
    code: i32,
    function: u8,
    argument: u8,
    field: u8,
    /// Padding made explicit: every byte of a record is written.
    unused: u8,
    index: u32,
}

impl Record {
    /// No call yet.
    pub(crate) const NONE: Record = Record {
        code: 0,
        function: Function::None as u8,
        argument: Name::None as u8,
        field: Name::None as u8,
        unused: 0,
        index: NO_INDEX,
    };

    /// The outcome of `function`: success, or `refused`.
    pub(crate) fn of(function: Function, refused: Option<Refused>) -> Record {
        let r = refused.unwrap_or(Refused::from(hairsim_error::Ok));
        Record {
            code: r.code as i32,
            function: function as u8,
            argument: r.argument as u8,
            field: r.field as u8,
            unused: 0,
            index: r.index,
        }
    }

    /// The record as C reads it.
    pub(crate) fn to_c(self) -> crate::types::hairsim_refusal {
        let text = |byte: u8| Name::from_byte(byte).unwrap_or(Name::None).text().as_ptr();
        crate::types::hairsim_refusal {
            code: self.code,
            function: Function::from_byte(self.function)
                .unwrap_or(Function::None)
                .text()
                .as_ptr(),
            argument: text(self.argument),
            field: text(self.field),
            index: self.index,
        }
    }
}
