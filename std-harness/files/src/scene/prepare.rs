//! From a checked [`Scene`] to what a run needs: the core's parameters, rest polylines with
//! their materials, colliders, grabs, the head motion, wind and followers. Checks that need
//! the generated strands (grab nodes, degenerate polylines) happen here.

#![deny(clippy::too_many_lines, clippy::too_many_arguments)]
use std::path::{Path, PathBuf};

use hairsim_core::params::{DftlParams, RodParams, TwistMethod, WindParams};
use hairsim_core::{
    Collider, Coupling, Effect, Effects, Material, Mode, ParamError, Params, Real, Shake, Shape,
    Solver, Strand, Vec3,
};

use super::error::FieldError;
use super::generate::{self, v3, Follower, Style};
use super::motion::{GrabPath, Key, Motion, Path as TargetPath};
use super::validate::{self, MAX_NODES};
use super::{
    ColliderSpec, DftlSpec, GrabSpec, HairFiles, HairSpec, MaterialSpec, MotionSpec, RodSpec,
    ScalpSpec, Scene, StandSpec, StrandSpec, StyleSpec, WindSpec,
};
use crate::sph::SphParams;

/// Strands per block when the scene does not say.
pub const DEFAULT_BLOCK: usize = 16;

/// One strand to build: its rest polyline (head frame, root first) and material.
#[derive(Clone, Debug, PartialEq)]
pub struct RestSpec {
    /// Rest polyline.
    pub points: Vec<Vec3>,
    /// Material.
    pub material: Material,
    /// Bending stiffness at the tip as a fraction of the root's (1: uniform).
    pub tip_stiffness: Real,
    /// The scene field it came from (for error messages).
    pub field: String,
}

/// A grab to place.
#[derive(Clone, Debug, PartialEq)]
pub struct GrabPlan {
    /// Strand index.
    pub strand: u32,
    /// Node index.
    pub node: u32,
    /// N.
    pub force_limit: Real,
    /// The virtual coupling, if any.
    pub coupling: Option<Coupling>,
    /// Target path and release.
    pub path: GrabPath,
}

/// What `--out` writes.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputPlan {
    /// A frame every this many steps (`None`: the final frame only).
    pub every: Option<u64>,
    /// Frame formats.
    pub formats: Vec<String>,
    /// `png` (final.png) or `gif` (final.png and run.gif).
    pub picture: String,
    /// Camera: `front`, `back`, `side` or `top`.
    pub view: String,
    /// Pixels.
    pub width: u32,
    /// Pixels.
    pub height: u32,
    /// Draw followers.
    pub followers: bool,
}

/// A checked scene, ready to build.
#[derive(Clone, Debug, PartialEq)]
pub struct Prepared {
    /// Scene name.
    pub name: String,
    /// The core's parameters (checked by the core too).
    pub params: Params,
    /// Steps to run.
    pub steps: u64,
    /// Strands per block (threads step whole blocks).
    pub block: usize,
    /// The strands.
    pub strands: Vec<RestSpec>,
    /// The colliders.
    pub colliders: Vec<Collider>,
    /// The grabs.
    pub grabs: Vec<GrabPlan>,
    /// The head's motion.
    pub motion: Motion,
    /// SPH parameters, when `hair-hair` is on.
    pub sph: Option<SphParams>,
    /// Followers, drawn around their leaders.
    pub followers: Vec<Follower>,
    /// Output settings.
    pub output: OutputPlan,
}

impl Prepared {
    /// The most nodes any strand has.
    #[must_use]
    pub fn max_nodes(&self) -> usize {
        self.strands
            .iter()
            .map(|s| s.points.len())
            .max()
            .unwrap_or(0)
    }

    /// Total simulated nodes.
    #[must_use]
    pub fn nodes(&self) -> usize {
        self.strands.iter().map(|s| s.points.len()).sum()
    }
}

fn material(base: &Material, spec: Option<&MaterialSpec>) -> (Material, Real) {
    let Some(m) = spec else { return (*base, 1.0) };
    (
        Material {
            youngs_modulus: m.youngs_modulus.unwrap_or(base.youngs_modulus),
            shear_modulus: m.shear_modulus.unwrap_or(base.shear_modulus),
            radius: m.radius.unwrap_or(base.radius),
            density: m.density.unwrap_or(base.density),
            minor_axis_penalty: m.minor_axis_penalty.unwrap_or(base.minor_axis_penalty),
        },
        m.tip_stiffness.unwrap_or(1.0),
    )
}

fn style(s: Option<&StyleSpec>) -> Style {
    let Some(s) = s else { return Style::Straight };
    match s.shape.as_deref() {
        Some("wavy") => Style::Wavy {
            amplitude: f64::from(s.amplitude.unwrap_or_default()),
            period: f64::from(s.period.unwrap_or(1.0)),
        },
        Some("curly") => Style::Curly {
            radius: f64::from(s.radius.unwrap_or_default()),
            period: f64::from(s.period.unwrap_or(1.0)),
        },
        _ => Style::Straight,
    }
}

fn param_field(error: ParamError) -> FieldError {
    match error {
        ParamError::OutOfRange { field, allowed } => {
            FieldError::new(field, format!("out of range, allowed {allowed}"))
        }
        ParamError::UnsupportedEffect { effect, solver } => FieldError::new(
            "effects",
            format!("the {solver} solver cannot do \"{effect}\""),
        ),
        ParamError::EffectOff { effect, item } => {
            FieldError::new("effects", format!("{item} needs \"{effect}\""))
        }
    }
}

fn unit(d: [f32; 3]) -> Vec3 {
    let v = v3(d);
    v / libm::sqrtf(v.dot(v))
}

/// Builds the run's plan from a scene that passed [`validate::check`].
///
/// The checks run in this order, so that the first error a scene gets never changes: the
/// solver and effects, the hair (a hair file is read here), the strands' polylines, the grabs,
/// the parameters, each strand against the time step, then the hair–hair parameters.
pub fn prepare(scene: &Scene, files: HairFiles<'_>) -> Result<Prepared, FieldError> {
    let solver = validate::solver(scene)?;
    let effect_list = validate::effects(scene, solver)?;
    let effects = Effects::from_slice(&effect_list);
    let params = params(scene, solver, effects);
    let (base_material, base_tip) = material(&Material::HUMAN_HAIR, scene.material.as_ref());
    let (mut strands, followers) = hair(scene, files, base_material, base_tip)?;
    strands.extend(listed_strands(scene, &base_material, base_tip));
    check_polylines(&strands)?;
    let colliders = colliders(scene);
    let grabs = grabs(scene, &strands)?;
    // Last, so that the scene's own checks (which name their fields) speak first.
    params.validate().map_err(param_field)?;
    check_time_step(&params, &strands)?;
    let motion = motion(scene);
    let sph = hair_hair(scene, effects)?;
    Ok(Prepared {
        name: scene.name.clone(),
        params,
        steps: step_count(scene),
        block: scene
            .strands_per_block
            .map_or(DEFAULT_BLOCK, |b| b as usize),
        strands,
        colliders,
        grabs,
        motion,
        sph,
        followers,
        output: output_plan(scene),
    })
}

/// The core's parameters: the scene's values, the core's defaults for the rest.
// `..defaults` keeps parameters the solvers add later at their defaults until scenes name them.
#[allow(clippy::needless_update)]
fn params(scene: &Scene, solver: Solver, effects: Effects) -> Params {
    let defaults = Params::DEFAULT;
    Params {
        solver,
        dt: scene.dt,
        effects,
        mode: match scene.mode.as_deref() {
            Some("fixed-cost") => Mode::FixedCost,
            _ => Mode::Converge,
        },
        gravity: scene.gravity.map_or(defaults.gravity, v3),
        drag: scene.drag.unwrap_or(0.0),
        rod: rod_params(&scene.rod.clone().unwrap_or_default(), &defaults.rod),
        dftl: dftl_params(&scene.dftl.clone().unwrap_or_default(), &defaults.dftl),
        wind: scene
            .wind
            .as_ref()
            .map_or(defaults.wind, |w| wind_params(w, &defaults.wind)),
        ..defaults
    }
}

/// The rod's parameters (`[rod]`).
#[allow(clippy::needless_update)]
fn rod_params(rod: &RodSpec, defaults: &RodParams) -> RodParams {
    RodParams {
        projection_iterations: rod
            .projection_iterations
            .map_or(defaults.projection_iterations, |n| n as u16),
        projection_tolerance: rod
            .projection_tolerance
            .unwrap_or(defaults.projection_tolerance),
        twist: match rod.twist.as_deref() {
            Some("newton") => TwistMethod::Newton,
            Some(_) => TwistMethod::HairOptimised,
            None => defaults.twist,
        },
        newton_iterations: rod
            .newton_iterations
            .map_or(defaults.newton_iterations, |n| n as u16),
        newton_tolerance: rod.newton_tolerance.unwrap_or(defaults.newton_tolerance),
        ..*defaults
    }
}

/// DFTL's parameters (`[dftl]`).
#[allow(clippy::needless_update)]
fn dftl_params(dftl: &DftlSpec, defaults: &DftlParams) -> DftlParams {
    DftlParams {
        damping: dftl.damping.unwrap_or(defaults.damping),
        global_shape: dftl.global_shape.unwrap_or(defaults.global_shape),
        local_shape: dftl.local_shape.unwrap_or(defaults.local_shape),
        reference_dt: dftl.reference_dt.unwrap_or(defaults.reference_dt),
        global_shape_fade: dftl.global_shape_fade.unwrap_or(defaults.global_shape_fade),
        local_shape_fade: dftl.local_shape_fade.unwrap_or(defaults.local_shape_fade),
        ..*defaults
    }
}

/// The wind (`[wind]`).
fn wind_params(w: &WindSpec, defaults: &WindParams) -> WindParams {
    WindParams {
        direction: unit(w.direction),
        strength: w.strength,
        gust: w.gust.unwrap_or(defaults.gust),
        gust_frequency: w.gust_frequency.unwrap_or(defaults.gust_frequency),
        seed: w.seed.unwrap_or(defaults.seed),
    }
}

/// Steps to run: `steps`, or `duration / dt` rounded.
fn step_count(scene: &Scene) -> u64 {
    match (scene.steps, scene.duration) {
        (Some(steps), _) => steps,
        (None, Some(duration)) => (f64::from(duration) / f64::from(scene.dt)).round() as u64,
        (None, None) => 0,
    }
}

/// The `[hair]` section's strands (generated, or read from a hair file) and followers.
fn hair(
    scene: &Scene,
    files: HairFiles<'_>,
    material: Material,
    tip_stiffness: Real,
) -> Result<(Vec<RestSpec>, Vec<Follower>), FieldError> {
    let rest = |points, field: &str| RestSpec {
        points,
        material,
        tip_stiffness,
        field: field.into(),
    };
    let mut strands = Vec::new();
    let mut followers = Vec::new();
    match &scene.hair {
        None => {}
        Some(HairSpec::Stand(s)) => {
            for (points, mine) in stand(s) {
                followers.extend(mine);
                strands.push(rest(points, "hair.stand"));
            }
        }
        Some(HairSpec::Scalp(s)) => {
            for (points, mine) in scalp(s) {
                followers.extend(mine);
                strands.push(rest(points, "hair.scalp"));
            }
        }
        Some(HairSpec::File(file)) => {
            for points in read_hair_file(file, files)?.strands {
                strands.push(rest(points, "hair.file"));
            }
        }
    }
    Ok((strands, followers))
}

/// A stand's wisps: each leader's rest polyline and its followers.
fn stand(s: &StandSpec) -> Vec<(Vec<Vec3>, Vec<Follower>)> {
    let origin = s.origin.map_or(Vec3::ZERO, v3);
    let direction = s.direction.map_or(Vec3::Z, unit);
    let spacing = f64::from(s.spacing.unwrap_or(0.02));
    let shape = style(s.style.as_ref());
    generate::stand_roots(s.wisps as usize, origin, spacing)
        .into_iter()
        .enumerate()
        .map(|(k, root)| {
            let points = generate::strand(
                root,
                direction,
                f64::from(s.length),
                s.nodes as usize,
                shape,
            );
            let followers = generate::followers(
                k as u32,
                direction,
                s.followers.unwrap_or(0) as usize,
                spacing * 0.3,
            );
            (points, followers)
        })
        .collect()
}

/// A scalp's leaders: each one's rest polyline and its share of the followers.
fn scalp(s: &ScalpSpec) -> Vec<(Vec<Vec3>, Vec<Follower>)> {
    let radius = f64::from(s.radius.unwrap_or(0.1));
    let cap = f64::from(s.cap_angle.unwrap_or(1.2));
    let leaders = s.leaders as usize;
    let shape = style(s.style.as_ref());
    let roots = generate::scalp_roots(leaders, s.centre.map_or(Vec3::ZERO, v3), radius, cap);
    // Spread followers over about half the distance between neighbouring leaders.
    let cap_area = std::f64::consts::TAU * radius * radius * (1.0 - libm::cos(cap));
    let spread = 0.5 * libm::sqrt(cap_area / leaders as f64);
    let total = s.followers.unwrap_or(0) as usize;
    roots
        .into_iter()
        .enumerate()
        .map(|(k, (root, normal))| {
            let points =
                generate::strand(root, normal, f64::from(s.length), s.nodes as usize, shape);
            // Leader k draws followers k, k + L, k + 2L, … of the total.
            let mine = total / leaders + usize::from(k < total % leaders);
            (points, generate::followers(k as u32, normal, mine, spread))
        })
        .collect()
}

/// The `[[strands]]` listed one by one, after the hair's.
fn listed_strands(scene: &Scene, base_material: &Material, base_tip: Real) -> Vec<RestSpec> {
    let mut strands = Vec::with_capacity(scene.strands.len());
    for (i, s) in scene.strands.iter().enumerate() {
        let (m, tip) = material(base_material, s.material.as_ref());
        let tip = if s.material.as_ref().and_then(|m| m.tip_stiffness).is_some() {
            tip
        } else {
            base_tip
        };
        strands.push(RestSpec {
            points: listed_points(s),
            material: m,
            tip_stiffness: tip,
            field: format!("strands[{i}]"),
        });
    }
    strands
}

/// A listed strand's rest polyline: its points, or one generated from root to length.
fn listed_points(s: &StrandSpec) -> Vec<Vec3> {
    match &s.points {
        Some(points) => points.iter().copied().map(v3).collect(),
        None => generate::strand(
            s.root.map_or(Vec3::ZERO, v3),
            s.direction.map_or(Vec3::Y, unit),
            f64::from(s.length.unwrap_or_default()),
            s.nodes.unwrap_or_default() as usize,
            style(Some(&StyleSpec {
                shape: s.shape.clone(),
                amplitude: s.amplitude,
                period: s.period,
                radius: s.radius,
            })),
        ),
    }
}

/// The core's own checks of every polyline (degenerate or folded segments, material ranges),
/// at the largest capacity; the run builds them again at the capacity it picks.
fn check_polylines(strands: &[RestSpec]) -> Result<(), FieldError> {
    for (i, s) in strands.iter().enumerate() {
        if let Err(e) = Strand::<{ MAX_NODES as usize }>::from_polyline(&s.points, &s.material) {
            let what = if s.field.starts_with("strands[") {
                s.field.clone()
            } else {
                format!("{} (strand {i})", s.field)
            };
            return Err(FieldError::new(
                what,
                format!("{e}, allowed: segments of at least 1e-6 m that never fold back"),
            ));
        }
    }
    Ok(())
}

/// The `[[colliders]]`.
fn colliders(scene: &Scene) -> Vec<Collider> {
    scene
        .colliders
        .iter()
        .map(|c| Collider {
            shape: collider_shape(c),
            attached_to_head: c.attached.unwrap_or(true),
        })
        .collect()
}

fn collider_shape(c: &ColliderSpec) -> Shape {
    match c.shape.as_str() {
        "sphere" => Shape::Sphere {
            centre: c.centre.map_or(Vec3::ZERO, v3),
            radius: c.radius.unwrap_or(1.0),
        },
        "capsule" => Shape::Capsule {
            a: c.a.map_or(Vec3::ZERO, v3),
            b: c.b.map_or(Vec3::ZERO, v3),
            radius: c.radius.unwrap_or(1.0),
        },
        _ => Shape::Plane {
            point: c.point.map_or(Vec3::ZERO, v3),
            normal: c.normal.map_or(Vec3::Y, unit),
        },
    }
}

/// The `[[grabs]]`, each checked against the strand it holds.
fn grabs(scene: &Scene, strands: &[RestSpec]) -> Result<Vec<GrabPlan>, FieldError> {
    let mut grabs = Vec::with_capacity(scene.grabs.len());
    for (i, g) in scene.grabs.iter().enumerate() {
        check_grab(&format!("grabs[{i}]"), g, strands)?;
        grabs.push(GrabPlan {
            strand: g.strand,
            node: g.node,
            force_limit: g.force_limit,
            coupling: g.coupling.map(|c| Coupling::new(c.stiffness, c.damping)),
            path: GrabPath {
                path: grab_path(g),
                release: g.release,
            },
        });
    }
    Ok(grabs)
}

/// A grab holds an existing strand at a free node.
fn check_grab(f: &str, g: &GrabSpec, strands: &[RestSpec]) -> Result<(), FieldError> {
    let Some(strand) = strands.get(g.strand as usize) else {
        return Err(FieldError::new(
            format!("{f}.strand"),
            format!(
                "strand {} does not exist, allowed 0 to {} (hair strands first, then [[strands]])",
                g.strand,
                strands.len().saturating_sub(1)
            ),
        ));
    };
    let last = strand.points.len() as u32 - 1;
    if g.node < 2 || g.node > last {
        return Err(FieldError::new(
            format!("{f}.node"),
            format!(
                "node {} is not a free node of strand {}, allowed 2 to {last}",
                g.node, g.strand
            ),
        ));
    }
    Ok(())
}

/// Where a grab's target goes: a circle, or its keys.
fn grab_path(g: &GrabSpec) -> TargetPath {
    match (&g.path, &g.circle) {
        (_, Some(c)) => TargetPath::Circle {
            start: v3(c.start),
            radius: c.radius,
            frequency: c.frequency,
            u: c.u.map_or(Vec3::X, unit),
            v: c.v.map_or(Vec3::Z, unit),
        },
        (path, None) => TargetPath::Keys(
            path.iter()
                .flatten()
                .map(|k| (k.time, v3(k.target)))
                .collect(),
        ),
    }
}

/// Each strand against the time step: stiff or finely divided rods past the explicit bending
/// limit are refused here, not left to chatter.
fn check_time_step(params: &Params, strands: &[RestSpec]) -> Result<(), FieldError> {
    for (i, s) in strands.iter().enumerate() {
        if let Ok(strand) = Strand::<{ MAX_NODES as usize }>::from_polyline(&s.points, &s.material)
        {
            params.validate_strand(&strand).map_err(|e| {
                let error = param_field(e);
                FieldError::new("dt", format!("{} (strand {i}, {})", error.message, s.field))
            })?;
        }
    }
    Ok(())
}

/// The head's motion.
fn motion(scene: &Scene) -> Motion {
    match scene.head.as_ref().and_then(|h| h.motion.as_ref()) {
        None | Some(MotionSpec::Still) => Motion::Still,
        Some(MotionSpec::Shake(s)) => {
            let amplitude = s.amplitude;
            let frequency = match (s.frequency, s.peak_speed) {
                (Some(f), _) => f,
                (None, Some(w)) if amplitude > 0.0 => w / (amplitude * 2.0 * std::f32::consts::PI),
                _ => 0.0,
            };
            Motion::Shake(Shake {
                axis: unit(s.axis),
                centre: s.centre.map_or(Vec3::ZERO, v3),
                amplitude,
                frequency,
            })
        }
        Some(MotionSpec::Keyframes(k)) => Motion::Keyframes(
            k.keys
                .iter()
                .map(|key| Key {
                    time: key.time,
                    position: key.position.map_or(Vec3::ZERO, v3),
                    axis: key.axis.map_or(Vec3::Y, unit),
                    angle: key.angle.unwrap_or(0.0),
                })
                .collect(),
        ),
    }
}

/// The SPH parameters (`[hair_hair]`), checked, when `hair-hair` is on.
fn hair_hair(scene: &Scene, effects: Effects) -> Result<Option<SphParams>, FieldError> {
    if !effects.contains(Effect::HairHair) {
        return Ok(None);
    }
    let d = SphParams::default();
    let h = scene.hair_hair.clone().unwrap_or_default();
    let sph = SphParams {
        smoothing_length: h.smoothing_length.unwrap_or(d.smoothing_length),
        rest_density: h.rest_density.unwrap_or(d.rest_density),
        stiffness: h.stiffness.unwrap_or(d.stiffness),
        viscosity: h.viscosity.unwrap_or(d.viscosity),
        neighbour_cap: h.max_neighbours.map_or(d.neighbour_cap, |n| n as usize),
        same_strand_gap: h.skip_same_strand.unwrap_or(d.same_strand_gap),
    };
    sph.validate()
        .map_err(|e| FieldError::new("hair-hair", e))?;
    Ok(Some(sph))
}

/// What the run writes (`[output]`).
fn output_plan(scene: &Scene) -> OutputPlan {
    let out = scene.output.clone().unwrap_or_default();
    OutputPlan {
        every: out.every,
        formats: out.formats.unwrap_or_else(|| vec!["obj".into()]),
        picture: out.picture.unwrap_or_else(|| "png".into()),
        view: out.view.unwrap_or_else(|| "front".into()),
        width: out.width.unwrap_or(512),
        height: out.height.unwrap_or(512),
        followers: out.followers.unwrap_or(true),
    }
}

/// A `hair.file.path` starting with this is read from the folder `HAIRSIM_SAMPLES` names:
/// scenes of the sample hair files, which are not part of the repository.
pub const SAMPLES_PREFIX: &str = "$HAIRSIM_SAMPLES/";

/// The folder `HAIRSIM_SAMPLES` names.
fn samples_folder() -> Result<std::path::PathBuf, FieldError> {
    match std::env::var_os("HAIRSIM_SAMPLES") {
        Some(folder) if !folder.is_empty() => Ok(folder.into()),
        _ => Err(FieldError::new(
            "hair.file.path",
            format!("{SAMPLES_PREFIX}…: HAIRSIM_SAMPLES is not set; set it to the folder of the sample hair files"),
        )),
    }
}

/// Where on disk a `[hair.file]` of a scene file in folder `base` is: a path starting with
/// [`SAMPLES_PREFIX`] in the folder `HAIRSIM_SAMPLES` names, any other relative to `base`.
///
/// # Errors
/// The path starts with [`SAMPLES_PREFIX`] and `HAIRSIM_SAMPLES` is not set.
pub fn hair_file_path(file: &super::FileSpec, base: &Path) -> Result<PathBuf, FieldError> {
    Ok(match file.path.strip_prefix(SAMPLES_PREFIX) {
        Some(rest) => samples_folder()?.join(rest),
        None if base == Path::new(".") => Path::new(&file.path).to_path_buf(),
        None => base.join(&file.path),
    })
}

/// Reads the strands of a `[hair.file]` (via the `hairfile` module) from `files`, checked for
/// what the simulator needs: 3 to 128 nodes per strand. On disk, a path starting with
/// [`SAMPLES_PREFIX`] is read from the folder `HAIRSIM_SAMPLES` names.
pub fn read_hair_file(
    file: &super::FileSpec,
    files: HairFiles<'_>,
) -> Result<crate::hairfile::HairModel, FieldError> {
    use crate::hairfile::{read_bytes, read_path, ReadOptions, UpAxis};
    let options = ReadOptions {
        scale: file.scale.unwrap_or(1.0),
        up_axis: if file.up.as_deref() == Some("z") {
            UpAxis::Z
        } else {
            UpAxis::Y
        },
        nodes: file.nodes.map(|n| n as usize),
        max_strands: file.max_strands.map(|n| n as usize),
        min_length: file.min_length.unwrap_or(0.001),
    };
    let (path, model) = match files {
        HairFiles::Disk(base) => {
            let path = hair_file_path(file, base)?;
            let model = read_path(&path, &options);
            (path.display().to_string(), model)
        }
        HairFiles::Memory { name, bytes } => (name.to_string(), read_bytes(name, bytes, &options)),
    };
    let model = model
        .map_err(|e| FieldError::new("hair.file.path", format!("cannot read \"{path}\": {e}")))?;
    let longest = model.strands.iter().map(Vec::len).max().unwrap_or(0);
    let shortest = model.strands.iter().map(Vec::len).min().unwrap_or(0);
    if model.strands.is_empty() {
        return Err(FieldError::new(
            "hair.file.path",
            format!(
                "\"{path}\" holds no strand longer than min_length, allowed: a file with strands"
            ),
        ));
    }
    if longest > MAX_NODES as usize || shortest < 3 {
        return Err(FieldError::new(
            "hair.file.nodes",
            format!(
                "the file's strands have {shortest} to {longest} vertices, allowed 3 to {MAX_NODES}: give nodes = N to resample them"
            ),
        ));
    }
    Ok(model)
}
