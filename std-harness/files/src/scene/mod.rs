//! Scene files, format 1 (documented in full with a commented example in
//! `docs/scene-format.md`).
//!
//! One structure for everything: a TOML file deserialises into [`Scene`], the built-in scenes
//! are [`Scene`] values written in Rust (`crate::builtin`), and a recording stores the scene as
//! TOML again. [`Scene::prepare`] checks every field and turns the scene into what the
//! simulation needs ([`prepare::Prepared`]); nothing is built from an unchecked scene.
//!
//! Every error reads `FILE:LINE: field: what is wrong, and what is allowed`
//! ([`error::SceneError`]); loading never panics and never falls back silently.

pub mod error;
pub mod generate;
pub mod motion;
pub mod prepare;
mod spans;
pub mod start;
mod validate;

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use error::{FieldError, SceneError};
pub use prepare::Prepared;

/// Where a scene's `[hair.file]` is read from.
#[derive(Clone, Copy, Debug)]
pub enum HairFiles<'a> {
    /// The disk: relative paths from this folder.
    Disk(&'a Path),
    /// One file held in memory, called `name` (a file dropped on the viewer's page, which has
    /// no disk): the scene's hair file is this one, whatever path the scene gives.
    Memory {
        /// The file's name (its extension picks the reader).
        name: &'a str,
        /// The file's bytes.
        bytes: &'a [u8],
    },
}

/// The only scene format this build reads.
pub const FORMAT: u32 = 1;

/// A 3-vector as written in scene files, `[x, y, z]`.
pub type V3 = [f32; 3];

/// A scene, exactly as a scene file spells it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Must be 1.
    pub format: u32,
    /// Name shown in summaries.
    pub name: String,
    /// One line about the scene (shown by `hairsim scenes`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub about: Option<String>,
    /// `"rod"` or `"dftl"`.
    pub solver: String,
    /// Time step, s.
    pub dt: f32,
    /// Number of steps (or give `duration`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
    /// Simulated time, s (or give `steps`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration: Option<f32>,
    /// The effects that run, by the names `docs/scene-format.md` lists; nothing else runs.
    pub effects: Vec<String>,
    /// `"converge"` (default) or `"fixed-cost"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode: Option<String>,
    /// Gravity, m/s² (default `[0, -9.81, 0]`), used when `gravity` is on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<V3>,
    /// Air drag per node, kg/s; required when `drag` is on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drag: Option<f32>,
    /// Strands per block stepped on one thread (default 16). The scene decides it, never the
    /// thread count, so results do not depend on `--threads`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strands_per_block: Option<u32>,
    /// Every strand's material unless a strand overrides it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<MaterialSpec>,
    /// Rod solver parameters.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rod: Option<RodSpec>,
    /// DFTL parameters.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dftl: Option<DftlSpec>,
    /// The head: its motion.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub head: Option<HeadSpec>,
    /// Colliders (sphere, capsule, plane), attached to the head or fixed in the world.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub colliders: Vec<ColliderSpec>,
    /// Generated hair: wisps on a stand, a scalp, or a hair file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hair: Option<HairSpec>,
    /// Single strands, generated or explicit polylines (after the `hair` ones).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub strands: Vec<StrandSpec>,
    /// Grabs whose targets move along a path.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grabs: Vec<GrabSpec>,
    /// Wind, used when `wind` is on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind: Option<WindSpec>,
    /// Hair–hair interaction (SPH) parameters, used when `hair-hair` is on.
    #[serde(default, rename = "hair-hair", skip_serializing_if = "Option::is_none")]
    pub hair_hair: Option<HairHairSpec>,
    /// What `--out DIR` writes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output: Option<OutputSpec>,
}

/// `[material]`, or a strand's `material` override (only the fields given change).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// E, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f32>,
    /// G, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_modulus: Option<f32>,
    /// Fibre radius r, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// ρ, kg/m³.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<f32>,
    /// µ ≥ 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub minor_axis_penalty: Option<f32>,
    /// Bending stiffness at the tip as a fraction of the root's (0 to 1), fading linearly
    /// along the strand (default 1: uniform).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip_stiffness: Option<f32>,
}

/// `[rod]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RodSpec {
    /// `"hair-optimised"` (default) or `"newton"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub twist: Option<String>,
    /// Projection iteration cap.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub projection_iterations: Option<u32>,
    /// Projection tolerance (relative).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub projection_tolerance: Option<f32>,
    /// Iteration cap of the Newton twist.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub newton_iterations: Option<u32>,
    /// Newton twist tolerance on the largest angle update, rad.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub newton_tolerance: Option<f32>,
}

/// `[dftl]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DftlSpec {
    /// s_d.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f32>,
    /// s_g per step at `reference_dt`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub global_shape: Option<f32>,
    /// s_l per step at `reference_dt`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub local_shape: Option<f32>,
    /// s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_dt: Option<f32>,
    /// How much s_g fades from root to tip (0: constant, 1: zero at the tip).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub global_shape_fade: Option<f32>,
    /// How much s_l fades from root to tip.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub local_shape_fade: Option<f32>,
}

/// `[head]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadSpec {
    /// How the head moves (default still).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion: Option<MotionSpec>,
}

/// `head.motion`: `"still"`, `[head.motion.shake]` or `[head.motion.keyframes]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MotionSpec {
    /// The head does not move.
    Still,
    /// Rotation about an axis, `angle(t) = amplitude · sin(2π f t)`.
    Shake(ShakeSpec),
    /// Poses at given times, interpolated linearly (position) and normalised-linearly
    /// (rotation); held after the last key.
    Keyframes(KeyframesSpec),
}

/// `[head.motion.shake]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShakeSpec {
    /// Rotation axis (world frame; normalised).
    pub axis: V3,
    /// A point on the axis, m (default the origin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<V3>,
    /// Amplitude, rad.
    pub amplitude: f32,
    /// Frequency, Hz (give this or `peak_speed`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frequency: Option<f32>,
    /// Peak angular speed, rad/s (`2π f · amplitude`; give this or `frequency`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_speed: Option<f32>,
}

/// `[head.motion.keyframes]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyframesSpec {
    /// The keys, in increasing time, the first at time 0.
    pub keys: Vec<KeySpec>,
}

/// One head pose key.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeySpec {
    /// s.
    pub time: f32,
    /// Head position, m (default the origin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<V3>,
    /// Rotation axis (default +y).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<V3>,
    /// Rotation angle about `axis`, rad (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<f32>,
}

/// `[[colliders]]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColliderSpec {
    /// `"sphere"`, `"capsule"` or `"plane"`.
    pub shape: String,
    /// Whether it moves with the head (default true; then it is given in the head's frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attached: Option<bool>,
    /// Sphere centre, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<V3>,
    /// Sphere or capsule radius, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// Capsule axis end, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<V3>,
    /// Capsule axis end, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b: Option<V3>,
    /// A point on the plane, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<V3>,
    /// Plane outward normal (normalised).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<V3>,
}

/// `[hair.stand]`, `[hair.scalp]` or `[hair.file]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HairSpec {
    /// Wisps hanging from a horizontal bar (Kmoch 2009's "Stand").
    Stand(StandSpec),
    /// Leaders rooted on a spherical cap, with followers (Kmoch 2009's "Head").
    Scalp(ScalpSpec),
    /// Strands read from a `.hair` (Cem Yuksel) or `.tfx` (AMD TressFX) file.
    File(FileSpec),
}

/// How generated strands curl: the fields shared by `[[strands]]`, stand and scalp.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StyleSpec {
    /// `"straight"` (default), `"wavy"` or `"curly"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<String>,
    /// Wavy: amplitude of the wave, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<f32>,
    /// Wavy: wavelength; curly: length along the strand per turn, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period: Option<f32>,
    /// Curly: radius of the helix, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
}

/// `[hair.stand]`: `wisps` leaders along a bar on the x axis through `origin`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StandSpec {
    /// Leader strands (one per wisp).
    pub wisps: u32,
    /// Nodes per leader.
    pub nodes: u32,
    /// Leader length, m.
    pub length: f32,
    /// Distance between roots along the bar, m (default 0.02).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing: Option<f32>,
    /// Middle of the bar, m (default the origin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<V3>,
    /// Root tangent of every wisp (default `[0, 0, 1]`, horizontal: the wisps fall).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<V3>,
    /// Follower strands per wisp (drawn, not simulated; default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub followers: Option<u32>,
    /// Shape of the strands.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub style: Option<StyleSpec>,
}

/// `[hair.scalp]`: `leaders` strands rooted on a spherical cap, pointing out of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScalpSpec {
    /// Simulated leader strands.
    pub leaders: u32,
    /// Nodes per leader.
    pub nodes: u32,
    /// Leader length, m.
    pub length: f32,
    /// Centre of the root sphere in the head's frame, m (default the origin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<V3>,
    /// Radius of the root sphere, m (default 0.1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// Half-angle of the cap around +y covered by roots, rad (default 1.2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cap_angle: Option<f32>,
    /// Follower strands in total, shared among the leaders (drawn, not simulated; default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub followers: Option<u32>,
    /// Shape of the strands.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub style: Option<StyleSpec>,
}

/// `[hair.file]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FileSpec {
    /// Path of the `.hair` or `.tfx` file, relative to the scene file.
    pub path: String,
    /// Factor from the file's units to metres (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f32>,
    /// The file's up axis: `"y"` (default) or `"z"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<String>,
    /// Resample every strand to this many nodes (default: keep the file's vertices).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nodes: Option<u32>,
    /// Keep at most this many strands, picked evenly through the file (default: all).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_strands: Option<u32>,
    /// Drop strands not longer than this, m (default 0.001).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_length: Option<f32>,
}

/// `[[strands]]`: a generated strand (root, direction, length, nodes, style) or an explicit
/// polyline (`points`, root first).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrandSpec {
    /// Root, m (head frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub root: Option<V3>,
    /// Root tangent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<V3>,
    /// Length, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<f32>,
    /// Nodes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nodes: Option<u32>,
    /// `"straight"` (default), `"wavy"` or `"curly"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<String>,
    /// Wavy amplitude, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<f32>,
    /// Wavy wavelength or curly pitch, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period: Option<f32>,
    /// Curly helix radius, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// An explicit rest polyline, root first, m (head frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<V3>>,
    /// This strand's material (overrides `[material]` field by field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<MaterialSpec>,
}

/// `[[grabs]]`: a node held at a target moving along a path.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrabSpec {
    /// Strand index (in build order: `hair` strands first, then `[[strands]]`).
    pub strand: u32,
    /// Node index (2 to the strand's last).
    pub node: u32,
    /// Force at which the grab slips, N.
    pub force_limit: f32,
    /// A virtual coupling pulling the node toward the target (default none: the node is
    /// held at the target and slips when the target leaves the strand's reach).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coupling: Option<CouplingSpec>,
    /// Target path: keys in increasing time, linear between them, held after the last (give
    /// this or `circle`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<Vec<PathKey>>,
    /// A circular target path (give this or `path`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub circle: Option<CircleSpec>,
    /// Time the grab lets go, s (default never).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub release: Option<f32>,
}

/// A grab's virtual coupling: a spring and a damper between the target and the node
/// (`hairsim_core::Coupling`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingSpec {
    /// Spring stiffness, N/m.
    pub stiffness: f32,
    /// Damping, N·s/m (default 0).
    #[serde(default)]
    pub damping: f32,
}

/// A grab target going round a circle from `start`:
/// `target(t) = start + u · r (cos 2πft − 1) + v · r sin 2πft`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircleSpec {
    /// Target at time 0, m (world frame).
    pub start: V3,
    /// Radius r, m.
    pub radius: f32,
    /// Turns per second f, Hz.
    pub frequency: f32,
    /// First axis of the circle's plane (default `[1, 0, 0]`; normalised).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u: Option<V3>,
    /// Second axis of the circle's plane (default `[0, 0, 1]`; normalised).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v: Option<V3>,
}

/// One key of a grab path.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathKey {
    /// s.
    pub time: f32,
    /// Target, m (world frame).
    pub target: V3,
}

/// `[wind]`: an acceleration on every free node, `a(t) = direction · strength · (1 + gust ·
/// n(t))`, `n` a seeded smooth noise in `[−1, 1]` (the core's `WindParams`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindSpec {
    /// Direction the wind blows towards (normalised).
    pub direction: V3,
    /// Mean acceleration, m/s².
    pub strength: f32,
    /// Gust amplitude as a fraction of `strength` (default 0.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust: Option<f32>,
    /// How often the gust noise picks a new value, Hz (default 1.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust_frequency: Option<f32>,
    /// Seed of the gust noise (default 24301).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u32>,
}

/// `[hair-hair]`: SPH parameters (`docs/scene-format.md`, "[hair-hair]"); defaults are
/// the SPH module's.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HairHairSpec {
    /// Smoothing length h, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smoothing_length: Option<f32>,
    /// ρ_0, kg/m³.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_density: Option<f32>,
    /// Pressure stiffness k in `p = k (ρ − ρ_0)`, m²/s².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f32>,
    /// Viscosity µ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viscosity: Option<f32>,
    /// Neighbour list cap per particle.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_neighbours: Option<u32>,
    /// Neighbours on the same strand within this many nodes are skipped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skip_same_strand: Option<u32>,
}

/// `[output]`: what `--out DIR` writes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Write a frame every this many steps (default: only the final frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every: Option<u64>,
    /// Frame formats: any of `"obj"`, `"ply"`, `"hair"`, `"usda"`, `"tfx"` (default `["obj"]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formats: Option<Vec<String>>,
    /// `"png"` (default: `final.png`) or `"gif"` (`final.png` and `run.gif`, an animation of
    /// the frames).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub picture: Option<String>,
    /// Camera of the pictures: `"front"` (default), `"back"`, `"side"` or `"top"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view: Option<String>,
    /// Picture width, pixels (default 512).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<u32>,
    /// Picture height, pixels (default 512).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<u32>,
    /// Draw the follower strands too (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub followers: Option<bool>,
}

impl Scene {
    /// Parses scene-file text (no checks beyond the format's types and fields). `file` names
    /// the text in error messages.
    pub fn from_toml(text: &str, file: &str) -> Result<Scene, SceneError> {
        let index = spans::SpanIndex::parse(text).map_err(|e| error::from_toml(file, text, &e))?;
        let scene: Scene = toml::from_str(text).map_err(|e| index.serde_error(file, text, &e))?;
        Ok(scene)
    }

    /// Reads, parses and checks a scene file.
    pub fn load(path: &Path) -> Result<(Scene, Prepared), SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: file.clone(),
            line: 0,
            field: String::new(),
            message: format!("cannot read the scene file: {e}"),
        })?;
        let scene = Scene::from_toml(&text, &file)?;
        let base = path.parent().unwrap_or(Path::new("."));
        let prepared = scene
            .prepare_in(base)
            .map_err(|e| locate(&e, &file, &text))?;
        Ok((scene, prepared))
    }

    /// Parses and checks scene-file text (for recordings and tests); relative hair-file paths
    /// are taken from `base`.
    pub fn parse_and_prepare(
        text: &str,
        file: &str,
        base: &Path,
    ) -> Result<(Scene, Prepared), SceneError> {
        let scene = Scene::from_toml(text, file)?;
        let prepared = scene.prepare_in(base).map_err(|e| locate(&e, file, text))?;
        Ok((scene, prepared))
    }

    /// Checks the scene and turns it into what a run needs. Relative hair-file paths are taken
    /// from the current directory.
    pub fn prepare(&self) -> Result<Prepared, FieldError> {
        self.prepare_in(Path::new("."))
    }

    /// As [`Scene::prepare`], relative hair-file paths taken from `base`.
    pub fn prepare_in(&self, base: &Path) -> Result<Prepared, FieldError> {
        self.prepare_from(HairFiles::Disk(base))
    }

    /// As [`Scene::prepare`], the hair file read from `files`.
    pub fn prepare_from(&self, files: HairFiles<'_>) -> Result<Prepared, FieldError> {
        validate::check(self)?;
        prepare::prepare(self, files)
    }

    /// The scene as scene-file text (what a recording stores).
    pub fn to_toml(&self) -> String {
        // Every field is a plain value, an array or a table: serialisation cannot fail.
        toml::to_string(self).unwrap_or_else(|e| format!("# could not serialise: {e}\n"))
    }
}

/// Runs only the checks that need no file (what [`Scene::prepare`] runs first).
pub fn validate_only(scene: &Scene) -> Result<(), FieldError> {
    validate::check(scene)
}

/// Places a field error at its line in `text`.
#[must_use]
pub fn locate(error: &FieldError, file: &str, text: &str) -> SceneError {
    let line = spans::SpanIndex::parse(text)
        .map(|index| index.line_of(&error.field, text))
        .unwrap_or(0);
    SceneError {
        file: file.to_string(),
        line,
        field: error.field.clone(),
        message: error.message.clone(),
    }
}

#[cfg(test)]
mod tests;
