//! Running a scene: step it, time every step, and summarise.

use std::time::Instant;

use anyhow::{bail, Result};
use hairsim_core::scenes::firmware;
use hairsim_core::{DefaultMath, Math, StepReport, World};

use crate::summary::{hash_string, Summary};

/// Options of `hairsim run` that do not depend on the scene.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Overrides the scene's step count.
    pub steps: Option<u64>,
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

/// Median of `times` in milliseconds (0 for none).
#[must_use]
pub fn median_ms(times: &mut [f64]) -> f64 {
    if times.is_empty() {
        return 0.0;
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2] * 1e3
}

/// Runs the built-in scene `name`.
pub fn run_builtin(name: &str, options: &RunOptions) -> Result<Summary> {
    match name {
        "firmware" => run_firmware::<DefaultMath>(options),
        other => bail!(
            "unknown scene \"{other}\": not a built-in scene (see `hairsim scenes`) nor an existing file"
        ),
    }
}

/// The firmware example's scene, stepped exactly as `firmware/` steps it under QEMU.
fn run_firmware<M: Math>(options: &RunOptions) -> Result<Summary> {
    let mut world: Box<World<{ firmware::STRANDS }, { firmware::NODES }, M>> = Box::default();
    firmware::build(&mut world).map_err(|e| anyhow::anyhow!("building the firmware scene: {e}"))?;
    let steps = options.steps.unwrap_or(u64::from(firmware::STEPS));
    let mut totals = Totals::default();
    let mut times = Vec::with_capacity(steps as usize);
    for k in 0..steps {
        let start = Instant::now();
        let report = firmware::step(&mut world, k as u32);
        times.push(start.elapsed().as_secs_f64());
        totals.add(&report);
    }
    Ok(Summary {
        scene: "firmware".into(),
        solver: world.params().solver.name().into(),
        math: M::NAME.into(),
        steps,
        dt: world.params().dt,
        strands: world.strands().len(),
        nodes: world.strands().iter().map(|s| s.nodes()).sum(),
        state_hash: hash_string(world.state_hash()),
        max_stretch: totals.max_stretch,
        max_penetration: totals.max_penetration,
        finite: world.strands().iter().all(|s| s.is_finite()),
        ms_per_step: median_ms(&mut times),
        iterations: totals.iterations,
        caps_hit: totals.caps_hit,
        rolled_back: totals.rolled_back,
    })
}
