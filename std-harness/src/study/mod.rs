//! `hairsim study`: what accuracy costs in time.
//!
//! A sweep over one knob at a time from the scene's own configuration — time step,
//! projection iteration cap and tolerance, twist method, solver, nodes per strand, math
//! backend and DFTL's `s_d` — each configuration run for the same simulated time and compared
//! with a converged reference of the same scene (the rod with the Newton twist, a small time
//! step and a tight tolerance; see [`Config::reference`]). The cost is the median measured
//! step time; the error is the RMS node distance from the reference at the end, the largest
//! stretch and the energy error ([`measure`]). A DFTL configuration's distance from the rod
//! reference is model error as well as numerical error, and is labelled so. [`output`] writes
//! the Markdown table, the CSV and the SVG plot.

pub mod measure;
pub mod output;

use anyhow::{anyhow, Result};
use hairsim_core::params::TwistMethod;
use hairsim_core::{Effect, Mode, Real, Solver, Vec3};

use crate::scene::Prepared;

/// The math backend a configuration is stepped with (the core's `Math` type parameter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Backend {
    /// `hairsim_core::Libm`: correctly rounded libm functions.
    Libm,
    /// `hairsim_core::math::FastMath`: micromath trigonometry.
    FastMath,
}

impl Backend {
    /// The backend's name (`libm`, `fast-math`), as the core's `Math::NAME`.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Backend::Libm => "libm",
            Backend::FastMath => "fast-math",
        }
    }
}

/// The knob a configuration varies (one at a time, from the scene's own configuration).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Knob {
    /// The scene as it is.
    Baseline,
    /// The time step, 0.25 to 4 ms.
    TimeStep,
    /// The time step of the other solver (DFTL for a rod scene, the rod for a DFTL scene).
    OtherSolverTimeStep,
    /// The fast manifold projection's iteration cap (rod).
    IterationCap,
    /// The projection's tolerance, converge mode (rod).
    Tolerance,
    /// Hair-optimised or Newton twist (rod).
    Twist,
    /// Rod or DFTL.
    Solver,
    /// Nodes per strand, as a factor of the scene's.
    Nodes,
    /// `libm` or `fast-math`.
    Math,
    /// DFTL's velocity correction `s_d`.
    Damping,
}

impl Knob {
    /// Every knob a sweep can vary, in the order of the table.
    pub const SWEPT: [Knob; 9] = [
        Knob::TimeStep,
        Knob::OtherSolverTimeStep,
        Knob::IterationCap,
        Knob::Tolerance,
        Knob::Twist,
        Knob::Solver,
        Knob::Nodes,
        Knob::Math,
        Knob::Damping,
    ];

    /// The knob's name in tables, plots and on the command line.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Knob::Baseline => "baseline",
            Knob::TimeStep => "dt",
            Knob::OtherSolverTimeStep => "dt-other",
            Knob::IterationCap => "iterations",
            Knob::Tolerance => "tolerance",
            Knob::Twist => "twist",
            Knob::Solver => "solver",
            Knob::Nodes => "nodes",
            Knob::Math => "math",
            Knob::Damping => "s_d",
        }
    }

    /// The knob called `name`.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Knob> {
        Knob::SWEPT.into_iter().find(|k| k.name() == name)
    }

    /// The solver whose configuration this knob varies, if only one has it: the projection
    /// and twist are the rod's, `s_d` is DFTL's. The others vary the scene's own solver.
    #[must_use]
    pub const fn solver(self) -> Option<Solver> {
        match self {
            Knob::IterationCap | Knob::Tolerance | Knob::Twist => Some(Solver::Rod),
            Knob::Damping => Some(Solver::Dftl),
            _ => None,
        }
    }
}

/// One configuration of a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// The knob this configuration varies.
    pub knob: Knob,
    /// Solver.
    pub solver: Solver,
    /// Time step, s.
    pub dt: Real,
    /// Converge or fixed cost.
    pub mode: Mode,
    /// Projection iteration cap.
    pub projection_iterations: u16,
    /// Projection tolerance.
    pub projection_tolerance: Real,
    /// Twist method.
    pub twist: TwistMethod,
    /// Newton twist iteration cap.
    pub newton_iterations: u16,
    /// Newton twist tolerance, rad.
    pub newton_tolerance: Real,
    /// Nodes per strand as a factor of the scene's (1: the scene's polylines untouched).
    pub node_factor: Real,
    /// Math backend.
    pub math: Backend,
    /// DFTL's `s_d`.
    pub damping: Real,
}

impl Config {
    /// The scene's own configuration (libm, the scene's nodes).
    #[must_use]
    pub fn of_scene(prepared: &Prepared) -> Config {
        let p = &prepared.params;
        Config {
            knob: Knob::Baseline,
            solver: p.solver,
            dt: p.dt,
            mode: p.mode,
            projection_iterations: p.rod.projection_iterations,
            projection_tolerance: p.rod.projection_tolerance,
            twist: p.rod.twist,
            newton_iterations: p.rod.newton_iterations,
            newton_tolerance: p.rod.newton_tolerance,
            node_factor: 1.0,
            math: Backend::Libm,
            damping: p.dftl.damping,
        }
    }

    /// The converged reference: the rod, Newton twist (100 iterations, 1e-7 rad), 0.125 ms,
    /// projection to 1e-7 with a cap of 100, converge mode, libm, the scene's nodes.
    #[must_use]
    pub fn reference(prepared: &Prepared) -> Config {
        Config {
            knob: Knob::Baseline,
            solver: Solver::Rod,
            dt: REFERENCE_DT,
            mode: Mode::Converge,
            projection_iterations: 100,
            projection_tolerance: 1.0e-7,
            twist: TwistMethod::Newton,
            newton_iterations: 100,
            newton_tolerance: 1.0e-7,
            ..Config::of_scene(prepared)
        }
    }

    /// Whether this configuration's error against the rod reference includes model error
    /// (DFTL is a different model from the rod).
    #[must_use]
    pub fn model_error(&self) -> bool {
        self.solver == Solver::Dftl
    }

    /// The value of the knob this configuration varies, as written in tables.
    #[must_use]
    pub fn value(&self) -> String {
        match self.knob {
            Knob::Baseline => "scene".into(),
            Knob::TimeStep => format!("{} ms", ms(self.dt)),
            Knob::OtherSolverTimeStep => format!("{} {} ms", self.solver.name(), ms(self.dt)),
            Knob::IterationCap => format!("{}", self.projection_iterations),
            Knob::Tolerance => format!("{:e}", self.projection_tolerance),
            Knob::Twist => self.twist.name().into(),
            Knob::Solver => self.solver.name().into(),
            Knob::Nodes => format!("x{}", self.node_factor),
            Knob::Math => self.math.name().into(),
            Knob::Damping => format!("{}", self.damping),
        }
    }

    /// Every setting, in one line (also the key that finds a configuration run already).
    #[must_use]
    pub fn describe(&self) -> String {
        let mut s = format!(
            "{} dt={}ms nodes=x{} {}",
            self.solver.name(),
            ms(self.dt),
            self.node_factor,
            self.math.name()
        );
        match self.solver {
            Solver::Rod => s.push_str(&format!(
                " {} cap={} tol={:e} twist={}",
                self.mode.name(),
                self.projection_iterations,
                self.projection_tolerance,
                self.twist.name()
            )),
            Solver::Dftl => s.push_str(&format!(" s_d={}", self.damping)),
        }
        s
    }

    /// The scene with this configuration: parameters set, the effects the other solver
    /// cannot simulate swapped for their nearest counterpart (the rod's bending and twist for
    /// DFTL's shape preservation and back; DFTL drops grabs, which it cannot hold), the
    /// strands resampled to `node_factor` times their nodes (grabs moved to the node at the
    /// same place along the strand).
    pub fn apply(&self, scene: &Prepared) -> Result<Prepared> {
        let mut p = scene.clone();
        let params = &mut p.params;
        if params.solver != self.solver {
            let mut effects = params.effects;
            match self.solver {
                Solver::Rod => {
                    if effects.contains(Effect::Shape) {
                        effects = effects
                            .without(Effect::Shape)
                            .with(Effect::Bending)
                            .with(Effect::Twist);
                    }
                }
                Solver::Dftl => {
                    if effects.contains(Effect::Bending) || effects.contains(Effect::Twist) {
                        effects = effects.with(Effect::Shape);
                    }
                    effects = effects
                        .without(Effect::Bending)
                        .without(Effect::Twist)
                        .without(Effect::Grabs);
                    p.grabs.clear();
                }
            }
            params.effects = effects;
        }
        params.solver = self.solver;
        params.dt = self.dt;
        params.mode = self.mode;
        params.rod.projection_iterations = self.projection_iterations;
        params.rod.projection_tolerance = self.projection_tolerance;
        params.rod.twist = self.twist;
        params.rod.newton_iterations = self.newton_iterations;
        params.rod.newton_tolerance = self.newton_tolerance;
        params.dftl.damping = self.damping;
        params
            .validate()
            .map_err(|e| anyhow!("{}: {e}", self.describe()))?;
        if self.node_factor != 1.0 {
            for g in &mut p.grabs {
                let n = scene
                    .strands
                    .get(g.strand as usize)
                    .map_or(2, |s| s.points.len());
                let k = resampled_nodes(n, self.node_factor);
                let f = g.node as f64 / (n - 1) as f64;
                g.node = (f * (k - 1) as f64).round() as u32;
            }
            for s in &mut p.strands {
                let k = resampled_nodes(s.points.len(), self.node_factor);
                s.points = crate::hairfile::resample_polyline(&s.points, k);
            }
        }
        Ok(p)
    }
}

/// Largest relative stretch a stable run may show (the loosest tolerance swept, 1e-2, shows
/// 5e-3; diverged runs show 1e5 and more).
pub const STABLE_STRETCH: f64 = 0.1;

/// The reference's time step, s.
pub const REFERENCE_DT: Real = 0.000_125;

/// Largest strand a resampled scene may have (the harness's largest capacity).
pub const MAX_NODES: usize = 128;

/// `dt` in milliseconds, as written.
fn ms(dt: Real) -> String {
    format!("{}", (f64::from(dt) * 1e6).round() / 1e3)
}

/// Nodes of a strand of `n` nodes resampled by `factor`: `factor` times the segments, at
/// least 2 segments, at most [`MAX_NODES`] nodes.
#[must_use]
pub fn resampled_nodes(n: usize, factor: Real) -> usize {
    let segments = ((n.saturating_sub(1)) as f64 * f64::from(factor)).round() as usize;
    (segments.max(2) + 1).min(MAX_NODES)
}

/// Cumulative length along a polyline, from 0 at the first point.
#[must_use]
pub fn arc_lengths(points: &[Vec3]) -> Vec<f64> {
    let mut arc = Vec::with_capacity(points.len());
    let mut s = 0.0;
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            s += f64::from(p.distance(points[i - 1]));
        }
        arc.push(s);
    }
    arc
}

/// The point at arc length `s` along `points` (with `arc` its [`arc_lengths`]), linearly
/// between nodes, clamped to the ends.
#[must_use]
pub fn point_at(points: &[Vec3], arc: &[f64], s: f64) -> Vec3 {
    let last = points.len().saturating_sub(1);
    let j = arc.partition_point(|&a| a <= s).clamp(1, last.max(1));
    let (a0, a1) = (arc[j - 1], arc[j.min(last)]);
    let t = if a1 > a0 {
        ((s - a0) / (a1 - a0)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    points[j - 1].lerp(points[j.min(last)], t as f32)
}

/// How long and how widely a study runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// Simulated time every configuration runs for, s.
    pub duration: f64,
    /// The knobs to vary (all by default).
    pub knobs: Vec<Knob>,
    /// Fewer values per knob.
    pub quick: bool,
    /// Timing runs after the first, per configuration.
    pub repeats: usize,
}

impl Default for Plan {
    fn default() -> Self {
        Plan {
            duration: 1.0,
            knobs: Knob::SWEPT.to_vec(),
            quick: false,
            repeats: 2,
        }
    }
}

impl Plan {
    /// The configurations to run, baseline first: for each knob, its values from the
    /// scene's configuration (or the solver's variant of it, for a knob only one solver has).
    #[must_use]
    pub fn configs(&self, scene: &Prepared) -> Vec<Config> {
        let base = Config::of_scene(scene);
        let mut out = vec![base];
        for &knob in &self.knobs {
            let mut from = base;
            let solver = match knob {
                Knob::OtherSolverTimeStep => Some(match base.solver {
                    Solver::Rod => Solver::Dftl,
                    Solver::Dftl => Solver::Rod,
                }),
                _ => knob.solver(),
            };
            if let Some(solver) = solver {
                if solver != from.solver && solver == Solver::Rod {
                    // The rod variant of a DFTL scene twists as the reference does: the
                    // hair-optimised twist is a knob of its own.
                    from.twist = TwistMethod::Newton;
                }
                from.solver = solver;
            }
            from.knob = knob;
            out.extend(self.values(knob, from));
        }
        out
    }

    fn values(&self, knob: Knob, from: Config) -> Vec<Config> {
        let q = self.quick;
        match knob {
            Knob::Baseline => vec![from],
            Knob::TimeStep | Knob::OtherSolverTimeStep => {
                pick(q, &[0.25e-3, 0.5e-3, 1e-3, 2e-3, 4e-3], &[0.5e-3, 2e-3])
                    .into_iter()
                    .map(|dt| Config { dt, ..from })
                    .collect()
            }
            Knob::IterationCap => pick(q, &[1u16, 2, 4, 8, 16, 32], &[1, 8])
                .into_iter()
                .map(|projection_iterations| Config {
                    projection_iterations,
                    ..from
                })
                .collect(),
            // A cap high enough that the tolerance decides when to stop.
            Knob::Tolerance => pick(q, &[1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7], &[1e-2, 1e-6])
                .into_iter()
                .map(|projection_tolerance| Config {
                    projection_tolerance,
                    projection_iterations: from.projection_iterations.max(64),
                    mode: Mode::Converge,
                    ..from
                })
                .collect(),
            Knob::Twist => [TwistMethod::HairOptimised, TwistMethod::Newton]
                .into_iter()
                .map(|twist| Config { twist, ..from })
                .collect(),
            Knob::Solver => [Solver::Rod, Solver::Dftl]
                .into_iter()
                .map(|solver| Config { solver, ..from })
                .collect(),
            Knob::Nodes => pick(q, &[0.5, 1.0, 2.0, 4.0], &[0.5, 2.0])
                .into_iter()
                .map(|node_factor| Config {
                    node_factor,
                    ..from
                })
                .collect(),
            Knob::Math => [Backend::Libm, Backend::FastMath]
                .into_iter()
                .map(|math| Config { math, ..from })
                .collect(),
            // From the least `s_d` the validator accepts with the local shape constraint on
            // (`hairsim_core::params::MIN_SHAPE_DAMPING`; below it the strand flutters).
            Knob::Damping => pick(q, &[0.5, 0.6, 0.75, 0.9, 1.0], &[0.5, 0.9])
                .into_iter()
                .map(|damping| Config { damping, ..from })
                .collect(),
        }
    }
}

fn pick<T: Copy>(quick: bool, full: &[T], short: &[T]) -> Vec<T> {
    if quick { short } else { full }.to_vec()
}

/// One configuration's measured cost and error.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The configuration.
    pub config: Config,
    /// Median measured step time, µs.
    pub us_per_step: f64,
    /// The step time times the steps per simulated millisecond: what a real-time loop spends
    /// per millisecond (per tick of a 1 kHz loop), µs.
    pub us_per_ms: f64,
    /// RMS node distance from the reference after the simulated time, m (at the reference's
    /// nodes, by arc length along the strand).
    pub rms_distance: f64,
    /// Largest relative segment stretch over the run.
    pub max_stretch: f64,
    /// Largest difference of mechanical energy from the reference's at the sampled times, as
    /// a fraction of `Σ m |g| L`.
    pub energy_error: f64,
    /// Strands rolled back over the run.
    pub rolled_back: u64,
    /// The groom at the end: mean turning angle and kinked nodes against the rest groom
    /// (what DFTL's configurations keep of the hair's shape, beside their cost).
    pub groom: crate::groom::Groom,
    /// Whether every value stayed finite.
    pub finite: bool,
    /// Whether the run stayed stable: finite, no roll-back, no segment stretched by more
    /// than [`STABLE_STRETCH`].
    pub stable: bool,
    /// On the Pareto front of cost (`us_per_ms`) against `rms_distance`.
    pub pareto: bool,
}

/// A finished study.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// The scene's name.
    pub scene: String,
    /// The scene's solver.
    pub solver: Solver,
    /// Simulated time of every run, s.
    pub duration: f64,
    /// The reference's description.
    pub reference: String,
    /// The reference's own step cost, µs per simulated ms.
    pub reference_us_per_ms: f64,
    /// The reference's largest relative stretch.
    pub reference_max_stretch: f64,
    /// One row per configuration, in plan order (a configuration two knobs share appears
    /// under each, measured once).
    pub rows: Vec<Row>,
}

/// Runs `plan` on `scene`; `progress` is told each configuration as it starts.
///
/// Each distinct configuration runs once for its error, then `plan.repeats` more times for
/// its cost, the configurations taken in turn, so that a change in the machine's load falls
/// on all of them alike; its cost is the least of its runs' median step times.
pub fn run(scene: &Prepared, plan: &Plan, mut progress: impl FnMut(&str)) -> Result<Study> {
    if !(plan.duration > 0.0 && plan.duration <= 60.0) {
        anyhow::bail!(
            "--duration: {} s is out of range, allowed above 0 to 60 s",
            plan.duration
        );
    }
    let reference_config = Config::reference(scene);
    progress(&format!("reference: {}", reference_config.describe()));
    let reference = measure::simulate(
        &reference_config.apply(scene)?,
        reference_config.math,
        plan.duration,
    )?;
    if !reference.finite || reference.rolled_back > 0 {
        anyhow::bail!(
            "the reference run of {} did not stay finite without roll-backs",
            scene.name
        );
    }
    let configs = plan.configs(scene);
    let mut distinct: Vec<(String, Config, Prepared, Row)> = Vec::new();
    for config in &configs {
        let key = config.describe();
        if distinct.iter().any(|(k, ..)| *k == key) {
            continue;
        }
        progress(&format!(
            "{} = {}: {key}",
            config.knob.name(),
            config.value()
        ));
        let prepared = config.apply(scene)?;
        let trace = measure::simulate(&prepared, config.math, plan.duration)?;
        let row = measure::compare(*config, &trace, &reference);
        distinct.push((key, *config, prepared, row));
    }
    for pass in 0..plan.repeats {
        progress(&format!("timing pass {} of {}", pass + 1, plan.repeats));
        for (_, config, prepared, row) in &mut distinct {
            let trace = measure::simulate(prepared, config.math, plan.duration)?;
            if trace.us_per_step < row.us_per_step {
                row.us_per_step = trace.us_per_step;
                row.us_per_ms = trace.us_per_step * 1e-3 / f64::from(config.dt);
            }
        }
    }
    let mut rows: Vec<Row> = configs
        .iter()
        .filter_map(|config| {
            let key = config.describe();
            distinct
                .iter()
                .find(|(k, ..)| *k == key)
                .map(|(.., row)| Row {
                    config: *config,
                    ..row.clone()
                })
        })
        .collect();
    mark_pareto(&mut rows);
    Ok(Study {
        scene: scene.name.clone(),
        solver: scene.params.solver,
        duration: plan.duration,
        reference: reference_config.describe(),
        reference_us_per_ms: reference.us_per_step * 1e-3 / f64::from(reference_config.dt),
        reference_max_stretch: reference.max_stretch,
        rows,
    })
}

/// Marks the rows on the Pareto front of cost (`us_per_ms`) against `rms_distance`: no other
/// row is at least as cheap and at least as accurate, and strictly better in one. Rows that
/// did not stay stable are never on it.
pub fn mark_pareto(rows: &mut [Row]) {
    let points: Vec<(f64, f64, bool)> = rows
        .iter()
        .map(|r| (r.us_per_ms, r.rms_distance, r.stable))
        .collect();
    for (i, row) in rows.iter_mut().enumerate() {
        let (c, e, ok) = points[i];
        row.pareto = ok
            && !points.iter().enumerate().any(|(j, &(cj, ej, okj))| {
                j != i && okj && cj <= c && ej <= e && (cj < c || ej < e)
            });
    }
}

/// Whether `a` dominates `b` (as cheap and as accurate, better in one).
#[must_use]
pub fn dominates(a: &Row, b: &Row) -> bool {
    a.us_per_ms <= b.us_per_ms
        && a.rms_distance <= b.rms_distance
        && (a.us_per_ms < b.us_per_ms || a.rms_distance < b.rms_distance)
}

impl Study {
    /// The most accurate stable configuration whose cost per simulated millisecond fits
    /// `budget_us` (what a 1 kHz loop can spend per tick at `budget_us = 1000`).
    #[must_use]
    pub fn best_within(&self, budget_us: f64) -> Option<&Row> {
        self.rows
            .iter()
            .filter(|r| r.stable && r.us_per_ms <= budget_us)
            .min_by(|a, b| a.rms_distance.total_cmp(&b.rms_distance))
    }

    /// The rows on the Pareto front, cheapest first, each configuration once.
    #[must_use]
    pub fn front(&self) -> Vec<&Row> {
        let mut front: Vec<&Row> = Vec::new();
        for r in self.rows.iter().filter(|r| r.pareto) {
            if !front
                .iter()
                .any(|f| f.config.describe() == r.config.describe())
            {
                front.push(r);
            }
        }
        front.sort_by(|a, b| a.us_per_ms.total_cmp(&b.us_per_ms));
        front
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_keeps_the_ends_and_spaces_by_arc_length() {
        let points = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 3.0, 0.0),
        ];
        let r = crate::hairfile::resample_polyline(&points, 5);
        assert_eq!(r.len(), 5);
        assert_eq!(r[0], points[0]);
        assert!(r[4].distance(points[2]) < 1e-6);
        // Total length 4: one point per unit of length.
        assert!(r[1].distance(Vec3::new(1.0, 0.0, 0.0)) < 1e-6);
        assert!(r[2].distance(Vec3::new(1.0, 1.0, 0.0)) < 1e-6);
        let arc = arc_lengths(&points);
        assert!(point_at(&points, &arc, 2.5).distance(Vec3::new(1.0, 1.5, 0.0)) < 1e-6);
        assert_eq!(point_at(&points, &arc, -1.0), points[0]);
        assert_eq!(point_at(&points, &arc, 9.0), points[2]);
        assert_eq!(resampled_nodes(15, 0.5), 8);
        assert_eq!(resampled_nodes(15, 4.0), 57);
        assert_eq!(resampled_nodes(3, 0.1), 3);
        assert_eq!(resampled_nodes(100, 4.0), MAX_NODES);
    }
}
