//! Checked conversions between the C structs and the core's types. Everything here is safe
//! code on values already copied out of the caller's memory.

use hairsim_core::collide::Shape;
use hairsim_core::{
    BuildError, CapacityError, Collider, DefaultMath, Effect, Effects, Error, Flags, GrabStatus,
    Material, Math, Mode, ParamError, Params, Pose, Quat, Shake, Solver, StepReport, Vec3,
};

use crate::refusal::{core_field, Name, Refused};
use crate::types::*;

/// The effect bits and the core's effects, one to one.
const EFFECTS: [(u32, Effect); 10] = [
    (HAIRSIM_EFFECT_GRAVITY, Effect::Gravity),
    (HAIRSIM_EFFECT_DRAG, Effect::Drag),
    (HAIRSIM_EFFECT_BENDING, Effect::Bending),
    (HAIRSIM_EFFECT_TWIST, Effect::Twist),
    (HAIRSIM_EFFECT_INEXTENSIBILITY, Effect::Inextensibility),
    (HAIRSIM_EFFECT_COLLISIONS, Effect::Collisions),
    (HAIRSIM_EFFECT_SHAPE, Effect::Shape),
    (HAIRSIM_EFFECT_WIND, Effect::Wind),
    (HAIRSIM_EFFECT_GRABS, Effect::Grabs),
    (HAIRSIM_EFFECT_HAIR_HAIR, Effect::HairHair),
];

/// The flag bits and the core's flags, one to one.
const FLAGS: [(u32, Flags); 9] = [
    (HAIRSIM_FLAG_CAP_HIT, Flags::CAP_HIT),
    (HAIRSIM_FLAG_ROLLED_BACK, Flags::ROLLED_BACK),
    (HAIRSIM_FLAG_GRAB_SLIPPED, Flags::GRAB_SLIPPED),
    (HAIRSIM_FLAG_BAD_INPUT, Flags::BAD_INPUT),
    (HAIRSIM_FLAG_SINGULAR, Flags::SINGULAR),
    (HAIRSIM_FLAG_CONTACTS_TRUNCATED, Flags::CONTACTS_TRUNCATED),
    (HAIRSIM_FLAG_STRETCHED, Flags::STRETCHED),
    (HAIRSIM_FLAG_COLLIDERS_INACTIVE, Flags::COLLIDERS_INACTIVE),
    (HAIRSIM_FLAG_GRABS_INACTIVE, Flags::GRABS_INACTIVE),
];

/// Largest `| |q|^2 - 1 |` a head rotation may have.
const UNIT_QUAT_SLACK: f32 = 1.0e-3;
/// Largest `| |a|^2 - 1 |` a shake axis may have (the core's own slack for unit vectors).
const UNIT_AXIS_SLACK: f32 = 1.0e-4;

pub(crate) type Result<T> = core::result::Result<T, Refused>;

/// `Ok` if every value is finite, else `HAIRSIM_ERROR_NOT_FINITE` naming the first that is
/// not.
fn finite(values: &[(f32, Name)]) -> Result<()> {
    match values.iter().find(|(v, _)| !v.is_finite()) {
        None => Ok(()),
        Some(&(_, field)) => Err(Refused::from(hairsim_error::NotFinite).field(field)),
    }
}

/// `HAIRSIM_ERROR_OUT_OF_RANGE` about `field`.
fn out_of_range(field: Name) -> Refused {
    Refused::from(hairsim_error::OutOfRange).field(field)
}

pub(crate) fn vec3(v: hairsim_vec3) -> Result<Vec3> {
    if v.x.is_finite() && v.y.is_finite() && v.z.is_finite() {
        Ok(Vec3::new(v.x, v.y, v.z))
    } else {
        Err(hairsim_error::NotFinite.into())
    }
}

/// [`vec3`], a refusal naming `field`.
fn vec3_field(v: hairsim_vec3, field: Name) -> Result<Vec3> {
    vec3(v).map_err(|r| r.field(field))
}

pub(crate) fn vec3_to_c(v: Vec3) -> hairsim_vec3 {
    hairsim_vec3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// `Ok(v)` when finite, else the code for a result that overflowed.
fn finite_result(v: Vec3) -> Result<Vec3> {
    if v.x.is_finite() && v.y.is_finite() && v.z.is_finite() {
        Ok(v)
    } else {
        Err(hairsim_error::NotFinite.into())
    }
}

/// A head pose (the field `head` of a step's input).
pub(crate) fn pose(p: &hairsim_pose) -> Result<Pose> {
    let position = vec3_field(p.position, Name::Head)?;
    let q = p.rotation;
    let head = Name::Head;
    finite(&[(q.x, head), (q.y, head), (q.z, head), (q.w, head)])?;
    let n2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
    if (n2 - 1.0).abs() > UNIT_QUAT_SLACK {
        return Err(out_of_range(head));
    }
    Ok(Pose {
        position,
        rotation: Quat::from_xyzw(q.x, q.y, q.z, q.w),
    })
}

pub(crate) fn pose_to_c(p: &Pose) -> hairsim_pose {
    hairsim_pose {
        position: vec3_to_c(p.position),
        rotation: hairsim_quat {
            x: p.rotation.x,
            y: p.rotation.y,
            z: p.rotation.z,
            w: p.rotation.w,
        },
    }
}

/// The core's shake pose at `t`, with the default math.
pub(crate) fn shake_pose(s: &hairsim_shake, t: f32) -> Result<hairsim_pose> {
    let axis = vec3(s.axis)?;
    let centre = vec3(s.centre)?;
    finite(&[
        (s.amplitude, Name::None),
        (s.frequency, Name::None),
        (t, Name::None),
    ])?;
    if (axis.length_squared() - 1.0).abs() > UNIT_AXIS_SLACK {
        return Err(hairsim_error::OutOfRange.into());
    }
    let shake = Shake {
        axis,
        centre,
        amplitude: s.amplitude,
        frequency: s.frequency,
    };
    let pose = shake.pose_at::<DefaultMath>(t);
    finite_result(pose.position)?;
    Ok(pose_to_c(&pose))
}

/// `start + (r (cos w t - 1), 0, r sin w t)`, w = 2 pi f: the operations, in the order, of
/// `scenes::firmware::grab_target` (checked bit for bit by a unit test).
pub(crate) fn circle_target(c: &hairsim_circle, t: f32) -> Result<hairsim_vec3> {
    let start = vec3(c.start)?;
    finite(&[
        (c.radius, Name::None),
        (c.frequency, Name::None),
        (t, Name::None),
    ])?;
    let (s, cos) = DefaultMath::sin_cos(2.0 * core::f32::consts::PI * c.frequency * t);
    let target = start + Vec3::new(c.radius * (cos - 1.0), 0.0, c.radius * s);
    Ok(vec3_to_c(finite_result(target)?))
}

pub(crate) fn material(m: &hairsim_material) -> Result<Material> {
    finite(&[
        (m.youngs_modulus, Name::YoungsModulus),
        (m.shear_modulus, Name::ShearModulus),
        (m.radius, Name::Radius),
        (m.density, Name::Density),
        (m.minor_axis_penalty, Name::MinorAxisPenalty),
    ])?;
    Ok(Material {
        youngs_modulus: m.youngs_modulus,
        shear_modulus: m.shear_modulus,
        radius: m.radius,
        density: m.density,
        minor_axis_penalty: m.minor_axis_penalty,
    })
}

pub(crate) fn material_to_c(m: &Material) -> hairsim_material {
    hairsim_material {
        youngs_modulus: m.youngs_modulus,
        shear_modulus: m.shear_modulus,
        radius: m.radius,
        density: m.density,
        minor_axis_penalty: m.minor_axis_penalty,
    }
}

/// The core's twist methods with their C values. The method's type is not re-exported at the
/// crate root, so its two values are taken from parameters that use them, by name.
fn twist_methods() -> [(u32, &'static str); 2] {
    [
        (hairsim_twist::HairOptimised as u32, "hair-optimised"),
        (hairsim_twist::Newton as u32, "newton"),
    ]
}

fn set_twist(params: &mut Params, code: u32) -> Result<()> {
    let name = twist_methods()
        .into_iter()
        .find(|&(c, _)| c == code)
        .map(|(_, name)| name)
        .ok_or(out_of_range(Name::RodTwist))?;
    let candidates = [
        Params::DEFAULT.rod.twist,
        hairsim_core::scenes::firmware::params().rod.twist,
    ];
    params.rod.twist = candidates
        .into_iter()
        .find(|t| t.name() == name)
        .ok_or(out_of_range(Name::RodTwist))?;
    Ok(())
}

fn twist_to_c(params: &Params) -> u32 {
    let name = params.rod.twist.name();
    twist_methods()
        .into_iter()
        .find(|&(_, n)| n == name)
        .map_or(u32::MAX, |(c, _)| c)
}

/// The C parameters as the core's, every value checked: non-finite floats, unknown enum values
/// and effect bits, integers that do not fit are refused here; the core's ranges by
/// `World::configure`.
pub(crate) fn params(p: &hairsim_params) -> Result<Params> {
    finite(&[
        (p.dt, Name::Dt),
        (p.drag, Name::Drag),
        (p.rod_projection_tolerance, Name::RodProjectionTolerance),
        (p.rod_newton_tolerance, Name::RodNewtonTolerance),
        (p.dftl_damping, Name::DftlDamping),
        (p.dftl_global_shape, Name::DftlGlobalShape),
        (p.dftl_local_shape, Name::DftlLocalShape),
        (p.dftl_reference_dt, Name::DftlReferenceDt),
        (p.dftl_global_shape_fade, Name::DftlGlobalShapeFade),
        (p.dftl_local_shape_fade, Name::DftlLocalShapeFade),
        (p.wind_strength, Name::WindStrength),
        (p.wind_gust, Name::WindGust),
        (p.wind_gust_frequency, Name::WindGustFrequency),
    ])?;
    let mut params = Params::DEFAULT;
    params.solver = solver(p.solver)?;
    params.mode = match p.mode {
        x if x == hairsim_mode::Converge as u32 => Mode::Converge,
        x if x == hairsim_mode::FixedCost as u32 => Mode::FixedCost,
        _ => return Err(out_of_range(Name::Mode)),
    };
    let known = EFFECTS.iter().fold(0, |bits, (bit, _)| bits | bit);
    if p.effects & !known != 0 {
        return Err(out_of_range(Name::Effects));
    }
    params.effects = EFFECTS
        .iter()
        .filter(|(bit, _)| p.effects & bit != 0)
        .fold(Effects::NONE, |set, &(_, effect)| set.with(effect));
    params.dt = p.dt;
    params.gravity = vec3_field(p.gravity, Name::Gravity)?;
    params.drag = p.drag;
    let iterations = |n: u32, field| u16::try_from(n).map_err(|_| out_of_range(field));
    params.rod.projection_iterations =
        iterations(p.rod_projection_iterations, Name::RodProjectionIterations)?;
    params.rod.projection_tolerance = p.rod_projection_tolerance;
    set_twist(&mut params, p.rod_twist)?;
    params.rod.newton_iterations = iterations(p.rod_newton_iterations, Name::RodNewtonIterations)?;
    params.rod.newton_tolerance = p.rod_newton_tolerance;
    params.dftl.damping = p.dftl_damping;
    params.dftl.global_shape = p.dftl_global_shape;
    params.dftl.local_shape = p.dftl_local_shape;
    params.dftl.reference_dt = p.dftl_reference_dt;
    params.dftl.global_shape_fade = p.dftl_global_shape_fade;
    params.dftl.local_shape_fade = p.dftl_local_shape_fade;
    params.wind.direction = vec3_field(p.wind_direction, Name::WindDirection)?;
    params.wind.strength = p.wind_strength;
    params.wind.gust = p.wind_gust;
    params.wind.gust_frequency = p.wind_gust_frequency;
    params.wind.seed = p.wind_seed;
    Ok(params)
}

/// The solver a `hairsim_solver` value names.
pub(crate) fn solver(code: u32) -> Result<Solver> {
    match code {
        x if x == hairsim_solver::Rod as u32 => Ok(Solver::Rod),
        x if x == hairsim_solver::Dftl as u32 => Ok(Solver::Dftl),
        _ => Err(out_of_range(Name::Solver)),
    }
}

pub(crate) fn params_to_c(p: &Params) -> hairsim_params {
    hairsim_params {
        solver: match p.solver {
            Solver::Rod => hairsim_solver::Rod as u32,
            Solver::Dftl => hairsim_solver::Dftl as u32,
        },
        dt: p.dt,
        effects: EFFECTS
            .iter()
            .filter(|(_, effect)| p.effects.contains(*effect))
            .fold(0, |bits, (bit, _)| bits | bit),
        mode: match p.mode {
            Mode::Converge => hairsim_mode::Converge as u32,
            Mode::FixedCost => hairsim_mode::FixedCost as u32,
        },
        gravity: vec3_to_c(p.gravity),
        drag: p.drag,
        rod_projection_iterations: u32::from(p.rod.projection_iterations),
        rod_projection_tolerance: p.rod.projection_tolerance,
        rod_twist: twist_to_c(p),
        rod_newton_iterations: u32::from(p.rod.newton_iterations),
        rod_newton_tolerance: p.rod.newton_tolerance,
        dftl_damping: p.dftl.damping,
        dftl_global_shape: p.dftl.global_shape,
        dftl_local_shape: p.dftl.local_shape,
        dftl_reference_dt: p.dftl.reference_dt,
        dftl_global_shape_fade: p.dftl.global_shape_fade,
        dftl_local_shape_fade: p.dftl.local_shape_fade,
        wind_direction: vec3_to_c(p.wind.direction),
        wind_strength: p.wind.strength,
        wind_gust: p.wind.gust,
        wind_gust_frequency: p.wind.gust_frequency,
        wind_seed: p.wind.seed,
    }
}

pub(crate) fn collider(c: &hairsim_collider) -> Result<Collider> {
    let a = vec3_field(c.a, Name::A)?;
    let b = vec3_field(c.b, Name::B)?;
    finite(&[(c.radius, Name::Radius)])?;
    let shape = match c.shape {
        x if x == hairsim_shape::Sphere as u32 => Shape::Sphere {
            centre: a,
            radius: c.radius,
        },
        x if x == hairsim_shape::Capsule as u32 => Shape::Capsule {
            a,
            b,
            radius: c.radius,
        },
        x if x == hairsim_shape::Plane as u32 => Shape::Plane {
            point: a,
            normal: b,
        },
        _ => return Err(out_of_range(Name::Shape)),
    };
    let attached_to_head = match c.attached_to_head {
        0 => false,
        1 => true,
        _ => return Err(out_of_range(Name::AttachedToHead)),
    };
    Ok(Collider {
        shape,
        attached_to_head,
    })
}

pub(crate) fn grab_status_to_c(status: GrabStatus) -> u32 {
    match status {
        GrabStatus::Held => hairsim_grab_status::Held as u32,
        GrabStatus::Slipped => hairsim_grab_status::Slipped as u32,
        GrabStatus::Released => hairsim_grab_status::Released as u32,
    }
}

/// A strand's build error: its code, with the argument and the node or segment it names.
pub(crate) fn build_error(e: BuildError) -> Refused {
    let code = |code: hairsim_error, argument| Refused::from(code).argument(argument);
    match e {
        BuildError::TooFewNodes { .. } => code(hairsim_error::TooFewNodes, Name::Count),
        BuildError::TooManyNodes { .. } => code(hairsim_error::TooManyNodes, Name::Count),
        BuildError::NonFiniteNode { node } => code(hairsim_error::NotFinite, Name::Points).at(node),
        BuildError::DegenerateSegment { segment } => {
            code(hairsim_error::DegenerateSegment, Name::Points).at(segment)
        }
        BuildError::LongSegment { segment } => {
            code(hairsim_error::LongSegment, Name::Points).at(segment)
        }
        BuildError::FoldedSegment { node } => {
            code(hairsim_error::FoldedSegment, Name::Points).at(node)
        }
        BuildError::InvalidMaterial { field, .. } => {
            code(hairsim_error::InvalidMaterial, Name::Material).field(core_field(field))
        }
    }
}

pub(crate) fn capacity_error(e: CapacityError) -> Refused {
    Refused::from(match e {
        CapacityError::Strands { .. } => hairsim_error::StrandsFull,
        CapacityError::Colliders { .. } => hairsim_error::CollidersFull,
        CapacityError::Grabs { .. } => hairsim_error::GrabsFull,
    })
}

/// A parameter error: its code and the field it names (for an effect, `effects` and the
/// effect's bit).
pub(crate) fn param_error(e: ParamError) -> Refused {
    let effect_bit = |name: &str| {
        EFFECTS
            .iter()
            .position(|(_, effect)| effect.name() == name)
            .unwrap_or(usize::MAX)
    };
    match e {
        ParamError::OutOfRange { field, .. } => out_of_range(core_field(field)),
        ParamError::UnsupportedEffect { effect, .. } => {
            Refused::from(hairsim_error::UnsupportedEffect)
                .field(Name::Effects)
                .at(effect_bit(effect))
        }
        ParamError::EffectOff { effect, .. } => Refused::from(hairsim_error::EffectOff)
            .field(Name::Effects)
            .at(effect_bit(effect)),
    }
}

/// An error of `add_collider` or `add_grab`: a refused value is `invalid`, naming its field.
pub(crate) fn add_error(e: Error, invalid: hairsim_error) -> Refused {
    match e {
        Error::Build(e) => build_error(e),
        Error::Capacity(e) => capacity_error(e),
        Error::Param(ParamError::OutOfRange { field, .. }) => {
            Refused::from(invalid).field(core_field(field))
        }
        Error::Param(e) => param_error(e),
    }
}

/// The grab forces with the header's slot count: this does not compile if the core's differs.
fn grab_forces(report: &StepReport) -> &[Vec3; HAIRSIM_MAX_GRABS] {
    &report.grab_forces
}

/// `r` in its C form, written over `out` field by field (built and returned, it was a copy on
/// the stack of every step).
pub(crate) fn report_into_c(r: &StepReport, out: &mut hairsim_step_report) {
    out.flags = FLAGS
        .iter()
        .filter(|(_, flag)| r.flags.contains(*flag))
        .fold(0, |bits, (bit, _)| bits | bit);
    out.iterations_max = r.iterations_max;
    out.iterations_total = r.iterations_total;
    out.cap_hits = r.cap_hits;
    out.dropped_rows = r.dropped_rows;
    out.contacts = r.contacts;
    out.rolled_back = r.rolled_back;
    out.rolled_back_strand_count = 0;
    out.rolled_back_strands = [0; HAIRSIM_NAMED_STRANDS];
    out.grabs_slipped = u32::from(r.grabs_slipped);
    out.residual = r.residual;
    out.max_stretch = r.max_stretch;
    out.max_contact_stretch = r.max_contact_stretch;
    out.max_penetration = r.max_penetration;
    out.grab_forces = [hairsim_vec3::default(); HAIRSIM_MAX_GRABS];
    out.head_force = vec3_to_c(r.head_force);
    out.collider_forces = [hairsim_vec3::default(); HAIRSIM_MAX_COLLIDERS];
    out.stage_runs = r.stage_runs;
    for (slot, &s) in out
        .rolled_back_strands
        .iter_mut()
        .zip(&r.rolled_back_strands)
    {
        *slot = s;
        out.rolled_back_strand_count += 1;
    }
    for (slot, &f) in out.grab_forces.iter_mut().zip(grab_forces(r)) {
        *slot = vec3_to_c(f);
    }
    for (slot, &f) in out.collider_forces.iter_mut().zip(&r.collider_forces) {
        *slot = vec3_to_c(f);
    }
}
