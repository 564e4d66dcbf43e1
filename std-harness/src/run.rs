//! Running a scene: pick the strand capacity, step it (on threads), time every step,
//! record or replay the inputs, and summarise.
#![deny(clippy::too_many_lines, clippy::too_many_arguments)]

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};
use hairsim_core::grab::GrabStatus;
use hairsim_core::{DefaultMath, Math, StepReport};

use crate::builtin;
pub use crate::hairscene::HairFileOptions;
use crate::output;
use crate::record::{BuildIdentity, Checkpoint, RecordedInputs, Recording, CAPACITIES, VERSION};
use crate::scene::{HairSpec, Prepared, Scene, SceneError};
use crate::sim::{scene_inputs, Sim, StepInputs};
use crate::summary::{hash_string, HairFileUsed, Summary};

/// A scene ready to run, and where it came from.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// `builtin:NAME` or the file path.
    pub source: String,
    /// The scene as written.
    pub scene: Scene,
    /// The checked plan.
    pub prepared: Prepared,
}

/// Loads SCENE: a built-in name, a TOML scene file, or a hair file (`.hair`, `.tfx`, or
/// hairsim's `.obj`, `.ply`, `.usda`).
pub fn load(spec: &str, hair: &HairFileOptions) -> Result<Loaded> {
    if let Some(b) = builtin::find(spec) {
        let scene = (b.scene)();
        let prepared = scene.prepare().map_err(|e| anyhow!(e.in_builtin(b.name)))?;
        return Ok(Loaded {
            source: format!("builtin:{}", b.name),
            scene,
            prepared,
        });
    }
    let path = Path::new(spec);
    if crate::hairfile::is_hair_file(spec) {
        let scene_error = |e: crate::scene::FieldError| {
            anyhow!(SceneError {
                file: format!("{spec} (default scene)"),
                line: 0,
                field: e.field,
                message: e.message,
            })
        };
        let scene = crate::hairscene::scene_for_hair_file(path, hair).map_err(scene_error)?;
        let prepared = scene.prepare().map_err(scene_error)?;
        let scene = with_absolute_hair_file(scene, Path::new("."));
        return Ok(Loaded {
            source: spec.to_string(),
            scene,
            prepared,
        });
    }
    if !path.exists() {
        let names: Vec<&str> = builtin::BUILTINS.iter().map(|b| b.name).collect();
        bail!(
            "{spec}: no such scene: not a built-in scene ({}) nor an existing file",
            names.join(", ")
        );
    }
    let (scene, prepared) = Scene::load(path)?;
    Ok(Loaded {
        source: spec.to_string(),
        scene: with_absolute_hair_file(scene, path.parent().unwrap_or(Path::new("."))),
        prepared,
    })
}

/// The scene with its hair file's path made absolute (from `base`), so that a recording of it
/// replays from any folder.
fn with_absolute_hair_file(mut scene: Scene, base: &Path) -> Scene {
    if let Some(crate::scene::HairSpec::File(file)) = &mut scene.hair {
        if file.path.starts_with(crate::scene::prepare::SAMPLES_PREFIX) {
            return scene;
        }
        let joined = base.join(&file.path);
        if let Ok(absolute) = std::path::absolute(&joined) {
            file.path = absolute.display().to_string();
        }
    }
    scene
}

/// Options of `hairsim run` that do not depend on the scene.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Overrides the scene's step count.
    pub steps: Option<u64>,
    /// Threads stepping strand blocks (the result never depends on it).
    pub threads: usize,
    /// Frames (with `out`) and checkpoints (with `record`) every this many steps.
    pub every: Option<u64>,
    /// Folder for frames and pictures.
    pub out: Option<PathBuf>,
    /// File to record the run to.
    pub record: Option<PathBuf>,
    /// Show a progress bar (only on a terminal, only past one second).
    pub progress: bool,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            steps: None,
            threads: 1,
            every: None,
            out: None,
            record: None,
            progress: false,
        }
    }
}

/// Accumulates step reports over a run.
#[derive(Clone, Debug, Default)]
pub struct Totals {
    /// Largest stretch seen.
    pub max_stretch: f32,
    /// Deepest penetration seen.
    pub max_penetration: f32,
    /// Iterations summed.
    pub iterations: u64,
    /// Caps hit summed.
    pub caps_hit: u64,
    /// Roll-backs summed.
    pub rolled_back: u64,
}

impl Totals {
    /// Folds one step's report in.
    pub fn add(&mut self, report: &StepReport) {
        self.max_stretch = self.max_stretch.max(report.max_stretch);
        self.max_penetration = self.max_penetration.max(report.max_penetration);
        self.iterations += u64::from(report.iterations_total);
        self.caps_hit += u64::from(report.cap_hits);
        self.rolled_back += u64::from(report.rolled_back);
    }
}

/// Median of `times` (seconds) in milliseconds (0 for none).
#[must_use]
pub fn median_ms(times: &mut [f64]) -> f64 {
    if times.is_empty() {
        return 0.0;
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2] * 1e3
}

/// The smallest capacity of this build that holds `nodes` nodes.
pub fn capacity_for(nodes: usize) -> Result<usize> {
    CAPACITIES
        .iter()
        .copied()
        .find(|&c| nodes <= c)
        .ok_or_else(|| {
            anyhow!(
                "a strand has {nodes} nodes, allowed at most {} in this build",
                CAPACITIES[CAPACITIES.len() - 1]
            )
        })
}

/// Where a run's inputs come from.
enum Inputs<'a> {
    /// Computed from the scene.
    Scene,
    /// Read from a recording; the run checks its hashes.
    Replay(&'a Recording),
}

/// Runs a loaded scene.
pub fn run(loaded: &Loaded, options: &RunOptions) -> Result<Summary> {
    if options.threads == 0 || options.threads > 1024 {
        bail!(
            "--threads: {} is out of range, allowed 1 to 1024",
            options.threads
        );
    }
    if let Some(every) = options.every {
        if every == 0 {
            bail!("--every: 0 is out of range, allowed 1 or more steps");
        }
    }
    if let Some(steps) = options.steps {
        if steps == 0 {
            bail!("--steps: 0 is out of range, allowed 1 or more");
        }
    }
    dispatch(loaded, options, &Inputs::Scene)
}

/// Runs the built-in scene `name` (what `hairsim run NAME` runs).
pub fn run_builtin(name: &str, options: &RunOptions) -> Result<Summary> {
    if builtin::find(name).is_none() {
        bail!("{name}: not a built-in scene (see `hairsim scenes`)");
    }
    run(&load(name, &HairFileOptions::default())?, options)
}

/// Replays a recording: the scene it holds, driven by its inputs, checked against its hashes.
/// Fails at the first checkpoint whose hash differs.
pub fn replay(path: &Path, threads: usize) -> Result<Summary> {
    let recording = Recording::read(path, &BuildIdentity::current::<DefaultMath>())?;
    let label = format!("{}#scene", path.display());
    let base = path.parent().unwrap_or(Path::new("."));
    let (scene, prepared) = Scene::parse_and_prepare(&recording.scene, &label, base)?;
    let loaded = Loaded {
        source: recording.source.clone(),
        scene,
        prepared,
    };
    let options = RunOptions {
        steps: Some(recording.inputs.len() as u64),
        threads,
        ..RunOptions::default()
    };
    if recording.inputs.is_empty() {
        bail!(
            "{}: the recording is damaged: it holds no steps",
            path.display()
        );
    }
    let capacity = capacity_for(loaded.prepared.max_nodes())?;
    if capacity != recording.capacity {
        bail!(
            "{}: recorded with capacity {}, the scene now needs {capacity}",
            path.display(),
            recording.capacity
        );
    }
    dispatch(&loaded, &options, &Inputs::Replay(&recording))
        .map_err(|e| anyhow!("{}: {e:#}", path.display()))
}

fn dispatch(loaded: &Loaded, options: &RunOptions, inputs: &Inputs<'_>) -> Result<Summary> {
    // One arm per entry of `CAPACITIES`.
    match capacity_for(loaded.prepared.max_nodes())? {
        32 => run_n::<32, DefaultMath>(loaded, options, inputs),
        _ => run_n::<128, DefaultMath>(loaded, options, inputs),
    }
}

/// A progress bar that appears once a run has taken a second, on a terminal only.
struct Progress {
    enabled: bool,
    start: Instant,
    steps: u64,
    bar: Option<indicatif::ProgressBar>,
}

impl Progress {
    fn new(enabled: bool, steps: u64) -> Progress {
        Progress {
            enabled: enabled && std::io::stderr().is_terminal(),
            start: Instant::now(),
            steps,
            bar: None,
        }
    }

    fn tick(&mut self, done: u64) {
        if !self.enabled || done % 64 != 0 {
            return;
        }
        if self.bar.is_none() && self.start.elapsed() > Duration::from_secs(1) {
            let bar = indicatif::ProgressBar::new(self.steps);
            if let Ok(style) = indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} steps, {per_sec}, eta {eta}",
            ) {
                bar.set_style(style);
            }
            self.bar = Some(bar);
        }
        if let Some(bar) = &self.bar {
            bar.set_position(done);
        }
    }

    /// Clears the bar (also before an error is printed).
    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

fn run_n<const N: usize, M: Math>(
    loaded: &Loaded,
    options: &RunOptions,
    inputs: &Inputs<'_>,
) -> Result<Summary> {
    let prepared = &loaded.prepared;
    let mut sim = Sim::<N, M>::new(prepared, options.threads).map_err(|e| anyhow!("{e}"))?;
    let mut runner = Runner::new::<M>(loaded, options, inputs, N)?;
    for k in 0..runner.steps {
        let step_inputs: StepInputs = match inputs {
            Inputs::Replay(r) => r.inputs[k as usize].to_inputs(),
            Inputs::Scene => scene_inputs::<M>(prepared, k),
        };
        let start = Instant::now();
        let report = sim.step(&step_inputs);
        runner.after_step(&sim, &step_inputs, k, start, report)?;
    }
    let outcome = runner.finish(&sim, options)?;
    Ok(summary(loaded, options, &sim, outcome))
}

/// A run's bookkeeping around the simulation: step times and totals, the recording it
/// writes, the recording it replays and checks, the frames and the progress bar.
struct Runner<'a> {
    steps: u64,
    totals: Totals,
    /// The last step's report.
    last: StepReport,
    /// Every `stride`-th step's time, s.
    times: Vec<f64>,
    stride: u64,
    recording: Option<Recording>,
    replayed: Option<std::iter::Peekable<std::slice::Iter<'a, Checkpoint>>>,
    frames: Option<output::Frames>,
    progress: Progress,
}

/// What a finished run leaves for its summary.
struct Outcome {
    steps: u64,
    totals: Totals,
    last: StepReport,
    times: Vec<f64>,
    written: Vec<PathBuf>,
}

impl<'a> Runner<'a> {
    fn new<M: Math>(
        loaded: &Loaded,
        options: &RunOptions,
        inputs: &Inputs<'a>,
        capacity: usize,
    ) -> Result<Runner<'a>> {
        let steps = options.steps.unwrap_or(loaded.prepared.steps);
        let every = options.every;
        let recording = options.record.as_ref().map(|_| Recording {
            version: VERSION,
            build: BuildIdentity::current::<M>(),
            source: loaded.source.clone(),
            scene: loaded.scene.to_toml(),
            capacity,
            every: every.unwrap_or(10),
            inputs: Vec::with_capacity(steps.min(1 << 20) as usize),
            checkpoints: Vec::new(),
        });
        let frames = match &options.out {
            Some(dir) => Some(output::Frames::new(dir, &loaded.prepared, every, steps)?),
            None => None,
        };
        // The median step time from at most ~100,000 evenly spread steps: bounded memory on
        // long runs.
        let stride = (steps / 100_000).max(1);
        Ok(Runner {
            steps,
            totals: Totals::default(),
            last: StepReport::default(),
            times: Vec::with_capacity((steps / stride + 1) as usize),
            stride,
            recording,
            replayed: match inputs {
                Inputs::Replay(r) => Some(r.checkpoints.iter().peekable()),
                Inputs::Scene => None,
            },
            frames,
            progress: Progress::new(options.progress, steps),
        })
    }

    /// Books step `k` (0-based), which started at `start` and gave `report`: its time, its
    /// totals, its recording and replay checkpoints, its frame, the progress bar.
    fn after_step<const N: usize, M: Math>(
        &mut self,
        sim: &Sim<N, M>,
        step_inputs: &StepInputs,
        k: u64,
        start: Instant,
        report: StepReport,
    ) -> Result<()> {
        if k % self.stride == 0 {
            self.times.push(start.elapsed().as_secs_f64());
        }
        self.totals.add(&report);
        self.last = report;
        let done = k + 1;
        if let Some(r) = &mut self.recording {
            r.inputs.push(RecordedInputs::from_inputs(step_inputs));
            if done % r.every == 0 || done == self.steps {
                r.checkpoints.push(Checkpoint {
                    step: done,
                    hash: hash_string(sim.state_hash()),
                });
            }
        }
        self.check_replay(sim, done)?;
        if let Some(f) = &mut self.frames {
            f.after_step(done, &sim.strands, &sim.head)?;
        }
        self.progress.tick(done);
        Ok(())
    }

    /// A replay: the recorded hash at step `done`, if there is one, against the state's.
    fn check_replay<const N: usize, M: Math>(&mut self, sim: &Sim<N, M>, done: u64) -> Result<()> {
        let Some(checkpoints) = &mut self.replayed else {
            return Ok(());
        };
        if let Some(c) = checkpoints.next_if(|c| c.step == done) {
            let now = hash_string(sim.state_hash());
            if now != c.hash {
                self.progress.finish();
                bail!(
                    "replay differs at step {done}: recorded state hash {}, replayed {now}",
                    c.hash
                );
            }
        }
        Ok(())
    }

    /// After the last step: no recorded checkpoint left over, the recording written, the
    /// final frame and pictures written.
    fn finish<const N: usize, M: Math>(
        mut self,
        sim: &Sim<N, M>,
        options: &RunOptions,
    ) -> Result<Outcome> {
        self.progress.finish();
        if let Some(c) = self.replayed.as_mut().and_then(Iterator::next) {
            bail!(
                "the recording is damaged: checkpoint at step {} is past its {} steps",
                c.step,
                self.steps
            );
        }
        if let (Some(r), Some(path)) = (&self.recording, &options.record) {
            r.write(path)?;
        }
        let written = match self.frames {
            Some(f) => f.finish(&sim.strands, &sim.head)?,
            None => Vec::new(),
        };
        Ok(Outcome {
            steps: self.steps,
            totals: self.totals,
            last: self.last,
            times: self.times,
            written,
        })
    }
}

/// The summary of a finished run.
fn summary<const N: usize, M: Math>(
    loaded: &Loaded,
    options: &RunOptions,
    sim: &Sim<N, M>,
    mut outcome: Outcome,
) -> Summary {
    let prepared = &loaded.prepared;
    let totals = &outcome.totals;
    Summary {
        scene: prepared.name.clone(),
        solver: prepared.params.solver.name().into(),
        math: M::NAME.into(),
        effects: prepared
            .params
            .effects
            .iter()
            .map(|e| e.name().to_string())
            .collect(),
        hair_file: hair_file_used(&loaded.scene),
        steps: outcome.steps,
        dt: prepared.params.dt,
        strands: sim.strands.len(),
        nodes: prepared.nodes(),
        followers: prepared.followers.len(),
        capacity: N,
        block: prepared.block,
        threads: options.threads,
        state_hash: hash_string(sim.state_hash()),
        max_stretch: totals.max_stretch,
        max_penetration: totals.max_penetration,
        finite: sim.is_finite(),
        groom: crate::groom::measure(&sim.strands),
        ms_per_step: median_ms(&mut outcome.times),
        iterations: totals.iterations,
        caps_hit: totals.caps_hit,
        rolled_back: totals.rolled_back,
        grab_forces: (!sim.grabs.is_empty())
            .then(|| vectors(&outcome.last.grab_forces[..sim.grabs.len()])),
        grab_status: (!sim.grabs.is_empty()).then(|| grab_status(&sim.grabs)),
        sph_neighbours: sim.sph.as_ref().map(|sph| {
            let samples = sph.stats.runs as f64 * sph.particles().max(1) as f64;
            sph.stats.neighbours as f64 / samples.max(1.0)
        }),
        sph_truncated: sim.sph.as_ref().map(|sph| sph.stats.truncated),
        written: outcome
            .written
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
        collider_forces: (!sim.colliders.is_empty())
            .then(|| vectors(&outcome.last.collider_forces[..sim.colliders.len()])),
    }
}

/// The hair file a scene reads, as the summary names it.
fn hair_file_used(scene: &Scene) -> Option<HairFileUsed> {
    match &scene.hair {
        Some(HairSpec::File(file)) => Some(HairFileUsed {
            path: file.path.clone(),
            scale: file.scale.unwrap_or(1.0),
            up: file.up.clone().unwrap_or_else(|| "y".into()),
        }),
        _ => None,
    }
}

/// Forces as arrays, for the summary.
fn vectors(forces: &[hairsim_core::Vec3]) -> Vec<[f32; 3]> {
    forces.iter().map(|f| f.to_array()).collect()
}

/// Each grab's status, by name.
fn grab_status(grabs: &[hairsim_core::Grab]) -> Vec<String> {
    grabs
        .iter()
        .map(|g| {
            match g.status {
                GrabStatus::Held => "held",
                GrabStatus::Slipped => "slipped",
                GrabStatus::Released => "released",
            }
            .to_string()
        })
        .collect()
}
