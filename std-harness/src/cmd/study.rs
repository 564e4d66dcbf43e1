//! `hairsim study [SCENE]`.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{anyhow, Result};

use crate::run::{load, HairFileOptions};
use crate::study::{output, Knob, Plan};

/// The arguments of `hairsim study`.
#[derive(Clone, Debug)]
pub struct Args {
    /// SCENE.
    pub scene: String,
    /// `--out`.
    pub out: PathBuf,
    /// `--duration`, s.
    pub duration: Option<f64>,
    /// `--quick`.
    pub quick: bool,
    /// `--knob` (all when empty).
    pub knobs: Vec<String>,
    /// `--budget-us`.
    pub budget_us: Option<f64>,
}

/// Simulated time of a quick study, s.
pub const QUICK_DURATION: f64 = 0.2;

/// Runs the study, writes its files; what it found as text.
pub fn study(args: &Args) -> Result<String> {
    let loaded = load(&args.scene, &HairFileOptions::default())?;
    let knobs = if args.knobs.is_empty() {
        Knob::SWEPT.to_vec()
    } else {
        args.knobs
            .iter()
            .map(|k| {
                Knob::from_name(k).ok_or_else(|| {
                    let names: Vec<&str> = Knob::SWEPT.iter().map(|k| k.name()).collect();
                    anyhow!("--knob: {k}: not a knob, allowed {}", names.join(", "))
                })
            })
            .collect::<Result<Vec<_>>>()?
    };
    if let Some(b) = args.budget_us {
        if !(b.is_finite() && b > 0.0) {
            anyhow::bail!("--budget-us: {b} is out of range, allowed a finite value > 0");
        }
    }
    let plan = Plan {
        duration: args
            .duration
            .unwrap_or(if args.quick { QUICK_DURATION } else { 1.0 }),
        knobs,
        quick: args.quick,
        repeats: if args.quick { 0 } else { 2 },
    };
    let study = crate::study::run(&loaded.prepared, &plan, |what| eprintln!("study: {what}"))?;
    let written = output::write(&study, &args.out)?;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: {} configurations, {} s simulated each; reference {} ({:.1} us per simulated ms)",
        study.scene,
        study.rows.len(),
        study.duration,
        study.reference,
        study.reference_us_per_ms
    );
    s.push_str("Pareto front (us per simulated ms, RMS distance m):\n");
    for r in study.front() {
        let _ = writeln!(
            s,
            "  {:9.1}  {:.2e}  {}{}",
            r.us_per_ms,
            r.rms_distance,
            r.config.describe(),
            if r.config.model_error() {
                "  (model + numerical error)"
            } else {
                ""
            }
        );
    }
    if let Some(budget) = args.budget_us {
        let _ = match study.best_within(budget) {
            Some(r) => writeln!(
                s,
                "Most accurate within {budget} us per simulated ms: {} ({:.1} us per simulated ms, {:.1} us per step, RMS distance {:.2e} m)",
                r.config.describe(),
                r.us_per_ms,
                r.us_per_step,
                r.rms_distance
            ),
            None => writeln!(
                s,
                "Nothing measured fits {budget} us per simulated ms (cheapest: {:.1})",
                study
                    .rows
                    .iter()
                    .map(|r| r.us_per_ms)
                    .fold(f64::INFINITY, f64::min)
            ),
        };
    }
    let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    let _ = write!(s, "wrote {}", names.join(", "));
    Ok(s)
}
