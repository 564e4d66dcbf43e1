//! What the page runs: a scene loaded from a built-in name, a scene file or a hair file (the
//! harness's own readers and checks), stepped at the scene's `dt`, with the solver, the
//! effects and the twist method switched from the page's panel.
//!
//! A switch goes through the scene, never around it: the page edits the scene as a user would
//! edit its file, and the scene's checks (`Scene::prepare_from`) accept or refuse it with
//! their own message. An effect or the twist method changes the parameters of the running
//! strands; the solver restarts the scene (the two models keep different rest data).

use std::path::Path;

use hairsim_core::{Coupling, DefaultMath, Effect, GrabStatus, Real, Shape, Solver, Vec3};
use hairsim_files::builtin;
use hairsim_files::hairscene::{scene_for_hair_file_in, HairFileOptions};
use hairsim_files::scene::start::scene_inputs;
use hairsim_files::scene::{locate, FieldError, HairFiles, HairSpec, Prepared, RodSpec, Scene};
use serde_json::{json, Value};

use crate::stepper::{Events, Stepper};

/// Largest force the hand's grab transmits before it slips, N: about what breaks a human hair
/// (a hair holds about 100 g). Far above what a strand's weight, inertia and stiffness put on
/// the hand (1e-5 to 1e-3 N), so the grab lets go only of a strand pulled well past its reach.
pub const HAND_FORCE_LIMIT: Real = 1.0;

/// The hand's virtual coupling (`docs/haptics.md`): the pointer pulls the node it holds
/// through a spring of 5 N/m and a damper of 1e-3 N·s/m, so a grab slips only on
/// [`HAND_FORCE_LIMIT`], never on reach.
///
/// The pointer is a position source that renders no force, so the sampled-data passivity
/// bound a device needs (`b > G·K·T/2 + G·B`) does not limit `K` and `B` here; they are chosen
/// for what the picture shows. Stiffness: the hair's own pull, at most about 1e-3 N while the
/// strand follows, stretches the spring by 0.2 mm at most, under a pixel at the page's framing:
/// the node stays under the pointer; a strand pulled taut holds until the pointer is
/// `HAND_FORCE_LIMIT / K` = 20 cm past its reach, twice what head-2's shaking head (0.5 rad
/// either way, roots up to 9.3 cm from its axis) moves a root away from a still pointer.
/// Damping: about critical for one hair node (6.5e-8 kg) on that spring, `2√(K m)` =
/// 1.1e-3 N·s/m, and a time constant `B/K` of 0.2 ms, a fifth of a 1 ms step: the damper adds
/// no visible lag to a drag.
pub const HAND_COUPLING: Coupling = Coupling::new(5.0, 1.0e-3);

/// Where the scene came from.
#[derive(Clone, Debug)]
pub enum Source {
    /// A built-in scene, by name.
    Builtin(&'static str),
    /// A hair file (`.hair`, `.tfx`, `.obj`, `.ply`, `.usda`) in its default scene.
    HairFile {
        /// The file's name.
        name: String,
        /// Its bytes.
        bytes: Vec<u8>,
    },
    /// A scene file and, if it reads one, its hair file.
    SceneFile {
        /// The scene file's name.
        name: String,
        /// Its text.
        text: String,
        /// The hair file its `[hair.file]` reads, by name and bytes.
        hair: Option<(String, Vec<u8>)>,
    },
}

impl Source {
    /// A built-in scene called `name`.
    ///
    /// # Errors
    /// No built-in scene has that name.
    pub fn builtin(name: &str) -> Result<Source, String> {
        builtin::find(name)
            .map(|b| Source::Builtin(b.name))
            .ok_or_else(|| {
                let names: Vec<&str> = builtin::BUILTINS.iter().map(|b| b.name).collect();
                format!("{name}: not a built-in scene ({})", names.join(", "))
            })
    }

    fn label(&self) -> String {
        match self {
            Source::Builtin(name) => format!("builtin:{name}"),
            Source::HairFile { name, .. } | Source::SceneFile { name, .. } => name.clone(),
        }
    }

    /// Where the scene's hair file is read from.
    fn files(&self) -> HairFiles<'_> {
        match self {
            Source::HairFile { name, bytes }
            | Source::SceneFile {
                hair: Some((name, bytes)),
                ..
            } => HairFiles::Memory { name, bytes },
            _ => HairFiles::Disk(Path::new(".")),
        }
    }

    /// The scene as loaded, before the page changes anything.
    fn scene(&self) -> Result<Scene, String> {
        match self {
            Source::Builtin(name) => Ok(builtin::find(name)
                .map(|b| (b.scene)())
                .ok_or_else(|| format!("{name}: not a built-in scene"))?),
            Source::HairFile { name, .. } => {
                let path = Path::new(name);
                scene_for_hair_file_in(path, &HairFileOptions::default(), self.files())
                    .map_err(|e| self.error(&e))
            }
            Source::SceneFile { name, text, .. } => {
                Scene::from_toml(text, name).map_err(|e| e.to_string())
            }
        }
    }

    /// `error` from preparing this source's scene, placed as the harness places it.
    fn error(&self, error: &FieldError) -> String {
        match self {
            Source::Builtin(name) => error.in_builtin(name).to_string(),
            Source::HairFile { name, .. } => {
                // The reader's message names the file already ("sintel.tfx: …"): the page
                // says it as it is, not as a field of the default scene around it.
                let unread = format!("cannot read \"{name}\": ");
                let named = format!("{name}: ");
                match error.message.strip_prefix(&unread) {
                    Some(message) if error.field == "hair.file.path" => {
                        format!(
                            "{name}: {}",
                            message.strip_prefix(&named).unwrap_or(message)
                        )
                    }
                    _ => format!("{name} (default scene): {error}"),
                }
            }
            Source::SceneFile { name, text, .. } => locate(error, name, text).to_string(),
        }
    }
}

/// The file name of the hair file the scene file `name` (its `text`) reads, if any: what the
/// page needs dropped with it.
///
/// # Errors
/// The scene file does not parse (its message, placed in the file).
pub fn scene_hair_file(name: &str, text: &str) -> Result<Option<String>, String> {
    let scene = Scene::from_toml(text, name).map_err(|e| e.to_string())?;
    Ok(match scene.hair {
        Some(HairSpec::File(file)) => Some(
            Path::new(&file.path)
                .file_name()
                .map_or_else(|| file.path.clone(), |n| n.to_string_lossy().into_owned()),
        ),
        _ => None,
    })
}

/// The running strands at the capacity the scene needs (the harness's rule: 32 nodes, else
/// 128).
#[derive(Debug)]
enum Running {
    Small(Box<Stepper<32>>),
    Large(Box<Stepper<128>>),
}

/// Runs `$body` with `$s` bound to the stepper, whatever its capacity.
macro_rules! each {
    ($running:expr, $s:ident => $body:expr) => {
        match $running {
            Running::Small($s) => $body,
            Running::Large($s) => $body,
        }
    };
}

impl Running {
    fn new(prepared: &Prepared) -> Result<Running, FieldError> {
        Ok(if prepared.max_nodes() <= 32 {
            Running::Small(Box::new(Stepper::new(prepared)?))
        } else {
            Running::Large(Box::new(Stepper::new(prepared)?))
        })
    }
}

/// A loaded scene, running.
#[derive(Debug)]
pub struct Session {
    source: Source,
    /// The scene as the page has edited it.
    scene: Scene,
    prepared: Prepared,
    running: Running,
    /// Whether the scene asked for hair–hair interaction, which the page does not simulate.
    hair_hair_dropped: bool,
}

impl Session {
    /// Loads `source` and places its strands at the start.
    ///
    /// # Errors
    /// The scene's or the hair file's error, as `hairsim run` words it.
    pub fn load(source: Source) -> Result<Session, String> {
        let mut scene = source.scene()?;
        let hair_hair = Effect::HairHair.name();
        let hair_hair_dropped = scene.effects.iter().any(|e| e == hair_hair);
        scene.effects.retain(|e| e != hair_hair);
        scene.hair_hair = None;
        let prepared = scene
            .prepare_from(source.files())
            .map_err(|e| source.error(&e))?;
        let running = Running::new(&prepared).map_err(|e| source.error(&e))?;
        Ok(Session {
            source,
            scene,
            prepared,
            running,
            hair_hair_dropped,
        })
    }

    /// Back to the start, with the page's changes kept.
    ///
    /// # Errors
    /// A strand the core refuses (it accepted them at load).
    pub fn reset(&mut self) -> Result<(), String> {
        self.running = Running::new(&self.prepared).map_err(|e| self.source.error(&e))?;
        Ok(())
    }

    /// Advances `steps` steps with the scene's head motion and grab paths.
    pub fn step(&mut self, steps: u32) {
        for _ in 0..steps {
            each!(&mut self.running, s => {
                let inputs = scene_inputs::<DefaultMath>(&self.prepared, s.steps);
                s.step(&inputs);
            });
        }
    }

    /// The scene as the page has edited it, as a scene file (`hairsim run` runs it).
    #[must_use]
    pub fn scene_toml(&self) -> String {
        self.scene.to_toml()
    }

    /// Steps taken since the start.
    #[must_use]
    pub fn steps(&self) -> u64 {
        each!(&self.running, s => s.steps)
    }

    /// The state hash (what `hairsim run --json` prints as `state_hash`).
    #[must_use]
    pub fn state_hash(&self) -> u64 {
        each!(&self.running, s => s.state_hash())
    }

    /// Every node's position into `out` and each strand's first node into `offsets`.
    pub fn positions(&self, out: &mut Vec<f32>, offsets: &mut Vec<u32>) {
        each!(&self.running, s => s.positions(out, offsets));
    }

    /// The followers drawn around the leaders (`hairsim run --out` draws them too): four
    /// floats each into `out`, the leader's index and the root offset in the head's frame, m.
    pub fn followers(&self, out: &mut Vec<f32>) {
        out.clear();
        for f in &self.prepared.followers {
            // Exact: leader indices stay far below 2^24.
            #[allow(clippy::cast_precision_loss)]
            out.push(f.leader as f32);
            out.extend_from_slice(&f.offset.to_array());
        }
    }

    /// One byte of flags per strand (`stepper::flag`) into `out`.
    pub fn strand_flags(&mut self, out: &mut Vec<u8>) {
        each!(&mut self.running, s => s.strand_flags(out));
    }

    /// What the steps since the last call reported, as JSON (and starts counting anew).
    pub fn take_events(&mut self) -> Value {
        let Events {
            steps,
            rolled_back_min,
            rolled_back_max,
            cap_hits_max,
            max_stretch,
            slipped,
        } = each!(&mut self.running, s => s.take_events());
        json!({
            "steps": steps,
            "rolled_back_min": rolled_back_min,
            "rolled_back_max": rolled_back_max,
            "cap_hits_max": cap_hits_max,
            "max_stretch": max_stretch,
            "slipped_at": slipped,
        })
    }

    /// The scene edited by `edit`, checked; on success the new plan, the scene kept.
    fn edited(&mut self, edit: impl FnOnce(&mut Scene)) -> Result<(), String> {
        let mut scene = self.scene.clone();
        edit(&mut scene);
        let prepared = scene
            .prepare_from(self.source.files())
            .map_err(|e| self.source.error(&e))?;
        self.scene = scene;
        self.prepared = prepared;
        Ok(())
    }

    /// Switches the solver and restarts: the rod trades `shape` for `bending` and `twist`,
    /// DFTL the other way round; the scene's grabs hold with either.
    ///
    /// # Errors
    /// The scene's checks refuse the switch (the running scene is kept).
    pub fn set_solver(&mut self, solver: Solver) -> Result<(), String> {
        let (name, add, remove): (&str, &[Effect], &[Effect]) = match solver {
            Solver::Rod => ("rod", &[Effect::Bending, Effect::Twist], &[Effect::Shape]),
            Solver::Dftl => ("dftl", &[Effect::Shape], &[Effect::Bending, Effect::Twist]),
        };
        self.edited(|scene| {
            scene.solver = name.into();
            scene
                .effects
                .retain(|e| !remove.iter().any(|r| r.name() == e));
            for effect in add {
                if !scene.effects.iter().any(|e| e == effect.name()) {
                    scene.effects.push(effect.name().into());
                }
            }
        })?;
        self.reset()
    }

    /// Why the running scene cannot use `effect` (none: it can).
    #[must_use]
    pub fn unusable(&self, effect: Effect) -> Option<String> {
        let solver = self.prepared.params.solver;
        Some(match effect {
            Effect::HairHair => "hair–hair (SPH) runs in `hairsim run`, not in the page".into(),
            _ if !solver.supports(effect) => {
                let other = match solver {
                    Solver::Rod => "DFTL",
                    Solver::Dftl => "the rod",
                };
                format!(
                    "{} has no {}: switch to {other}",
                    solver.name(),
                    effect.name()
                )
            }
            Effect::Wind if self.scene.wind.is_none() => "the scene has no [wind] table".into(),
            Effect::Grabs if self.scene.grabs.is_empty() => {
                "the scene has no [[grabs]]: press on a strand to grab it".into()
            }
            _ => return None,
        })
    }

    /// Turns `effect` on or off in the running scene.
    ///
    /// # Errors
    /// Turned on where the running scene cannot use it ([`Session::unusable`]), or the
    /// scene's checks refuse it.
    pub fn set_effect(&mut self, effect: Effect, on: bool) -> Result<(), String> {
        if let Some(reason) = self.unusable(effect).filter(|_| on) {
            return Err(format!("{}: {reason}", effect.name()));
        }
        self.edited(|scene| {
            scene.effects.retain(|e| e != effect.name());
            if on {
                scene.effects.push(effect.name().into());
            }
        })?;
        if !on && effect == Effect::Grabs {
            self.release();
        }
        if on && effect == Effect::Inextensibility {
            each!(&mut self.running, s => s.restore_stretched());
        }
        self.apply_params()
    }

    /// Switches the rod's twist method (`hair-optimised` or `newton`) in the running scene.
    ///
    /// # Errors
    /// The scene's checks refuse the name.
    pub fn set_twist(&mut self, method: &str) -> Result<(), String> {
        self.edited(|scene| {
            scene.rod.get_or_insert_with(RodSpec::default).twist = Some(method.into());
        })?;
        self.apply_params()
    }

    /// The scene's parameters to the running strands, with `grabs` on while the hand holds
    /// one (a scene file may not turn `grabs` on without a grab of its own; the hand's is not
    /// the scene's).
    fn apply_params(&mut self) -> Result<(), String> {
        let mut params = self.prepared.params;
        if each!(&self.running, s => s.hand().is_some()) {
            params.effects = params.effects.with(Effect::Grabs);
            params.validate().map_err(|e| e.to_string())?;
        }
        each!(&mut self.running, s => s.set_params(params));
        Ok(())
    }

    /// Grabs `node` of `strand` where it is, through [`HAND_COUPLING`] (turning `grabs` on).
    ///
    /// # Errors
    /// A grab the core cannot hold (no such strand, every grab slot taken).
    pub fn grab(&mut self, strand: usize, node: usize) -> Result<(), String> {
        let limit = HAND_FORCE_LIMIT;
        each!(&mut self.running, s => s.grab(strand, node, limit, HAND_COUPLING))?;
        self.apply_params()
    }

    /// Moves the hand's target.
    pub fn move_hand(&mut self, target: Vec3) {
        each!(&mut self.running, s => s.move_hand(target));
    }

    /// Lets go of the hand's grab (and turns `grabs` off again unless the scene has it).
    pub fn release(&mut self) {
        each!(&mut self.running, s => s.release());
        let params = self.prepared.params;
        each!(&mut self.running, s => s.set_params(params));
    }

    /// What the page shows and the scene's fixed facts, as JSON.
    #[must_use]
    pub fn status(&self) -> Value {
        let params = &self.prepared.params;
        let (hand, held, head, colliders, report) = each!(&self.running, s => (
            s.hand(),
            s.held_node(),
            s.head,
            s.colliders_now().map(shape_json).collect::<Vec<_>>(),
            json!({
                "contacts": s.report.contacts,
                "rolled_back": s.report.rolled_back,
                "max_stretch": s.report.max_stretch,
                "cap_hits": s.report.cap_hits,
                "iterations_max": s.report.iterations_max,
            }),
        ));
        let (grab, force, target) = match hand {
            Some((hand, status, force)) => (
                match status {
                    GrabStatus::Held => "held",
                    GrabStatus::Slipped => "slipped",
                    GrabStatus::Released => "released",
                },
                force,
                Some(hand.target.to_array()),
            ),
            None => ("none", Vec3::ZERO, None),
        };
        json!({
            "source": self.source.label(),
            "scene": self.prepared.name,
            "steps": self.steps(),
            "time": self.steps() as f64 * f64::from(params.dt),
            "dt": params.dt,
            "state_hash": format!("{:#018x}", self.state_hash()),
            "solver": match params.solver { Solver::Rod => "rod", Solver::Dftl => "dftl" },
            "effects": params.effects.iter().map(Effect::name).collect::<Vec<_>>(),
            "unusable": Effect::ALL
                .into_iter()
                .filter_map(|e| Some((e.name().to_string(), self.unusable(e)?.into())))
                .collect::<serde_json::Map<_, _>>(),
            "hair_hair_dropped": self.hair_hair_dropped,
            "twist": params.rod.twist.name(),
            "grab": grab,
            "grab_force": force.to_array(),
            "grab_target": target,
            "grab_limit": HAND_FORCE_LIMIT,
            "grab_coupling": [HAND_COUPLING.stiffness, HAND_COUPLING.damping],
            "held": held.map(|(strand, node, at)| json!({
                "strand": strand, "node": node, "position": at.to_array(),
            })),
            "head": { "position": head.position.to_array(), "rotation": head.rotation.to_array() },
            "report": report,
            "colliders": colliders,
            "strands": self.prepared.strands.len(),
            "followers": self.prepared.followers.len(),
            "nodes": self.prepared.nodes(),
        })
    }
}

/// A collider for the page to draw.
fn shape_json(shape: Shape) -> Value {
    match shape {
        Shape::Sphere { centre, radius } => {
            json!({"sphere": {"centre": centre.to_array(), "radius": radius}})
        }
        Shape::Capsule { a, b, radius } => {
            json!({"capsule": {"a": a.to_array(), "b": b.to_array(), "radius": radius}})
        }
        Shape::Plane { point, normal } => {
            json!({"plane": {"point": point.to_array(), "normal": normal.to_array()}})
        }
    }
}
