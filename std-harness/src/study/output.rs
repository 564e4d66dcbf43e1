//! A study's Markdown table, CSV and SVG plot.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context, Result};
use plotters::prelude::*;

use super::{Knob, Row, Study};

/// Writes `DIR/SCENE.md`, `DIR/SCENE.csv` and `DIR/SCENE.svg`; their paths.
pub fn write(study: &Study, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let md = dir.join(format!("{}.md", study.scene));
    let csv = dir.join(format!("{}.csv", study.scene));
    let svg = dir.join(format!("{}.svg", study.scene));
    std::fs::write(&md, markdown(study)).with_context(|| format!("{}", md.display()))?;
    std::fs::write(&csv, to_csv(study)).with_context(|| format!("{}", csv.display()))?;
    plot(study, &svg)?;
    Ok(vec![md, csv, svg])
}

/// The error column's label: DFTL's distance from the rod reference is model error too.
fn error_kind(row: &Row) -> &'static str {
    if row.config.model_error() {
        "model + numerical"
    } else {
        "numerical"
    }
}

/// The CSV: one line per row, a header first.
#[must_use]
pub fn to_csv(study: &Study) -> String {
    let mut s = String::from(
        "scene,knob,value,config,us_per_step,us_per_sim_ms,rms_distance_m,error_kind,max_stretch,energy_error,rolled_back,mean_turning_rad,rest_mean_turning_rad,kinked_share,finite,stable,pareto\n",
    );
    for r in &study.rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{:.3},{:.3},{:.6e},{},{:.3e},{:.3e},{},{:.4},{:.4},{:.4},{},{},{}",
            study.scene,
            r.config.knob.name(),
            r.config.value(),
            r.config.describe(),
            r.us_per_step,
            r.us_per_ms,
            r.rms_distance,
            error_kind(r),
            r.max_stretch,
            r.energy_error,
            r.rolled_back,
            r.groom.mean_turning,
            r.groom.rest_mean_turning,
            r.groom.kinked,
            r.finite,
            r.stable,
            r.pareto
        );
    }
    s
}

/// The Markdown: what was run, the table, the Pareto front.
#[must_use]
pub fn markdown(study: &Study) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Accuracy against cost: `{}`\n", study.scene);
    let _ = writeln!(
        s,
        "Every configuration simulates {} s of the scene's {} run; error is measured against \
         the converged reference `{}` ({:.1} µs per simulated ms). Cost is the median measured \
         step time on one thread, and that times the steps per simulated millisecond (what a \
         1 kHz loop spends per tick). Rows marked * are on the Pareto front of cost per \
         simulated ms against RMS distance. DFTL's distance from the rod reference is model \
         + numerical error.\n",
        study.duration,
        study.solver.name(),
        study.reference,
        study.reference_us_per_ms
    );
    let _ = writeln!(
        s,
        "The reference's largest stretch: {:.1e}. Energy error: the largest difference of kinetic \
         + gravitational energy from the reference's at ten sampled times, as a fraction of \
         Σ m|g|L. The nodes knob changes the discretisation: its distance is measured at the \
         reference's nodes by arc length, and includes the difference between discretisations. \
         Groom: the mean turning angle at the interior nodes at the end (the rest groom's in \
         brackets) and the share of nodes kinked, turning more than their rest angle + 0.3 rad. \
         A run is marked diverged when it rolled a strand back, went non-finite or stretched a \
         segment by more than 10 %; diverged runs are left out of the plot, the front and the \
         budget.\n",
        study.reference_max_stretch
    );
    s.push_str(
        "| knob | value | µs/step | µs/sim ms | RMS distance (m) | error | max stretch | energy error | groom (rad) | kinked | rolled back | front | configuration |\n",
    );
    s.push_str("|---|---|---:|---:|---:|---|---:|---:|---:|---:|---:|:-:|---|\n");
    for r in &study.rows {
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {:.1} | {} | {} | {:.1e} | {:.1e} | {:.3} ({:.3}) | {:.1} % | {} | {} | `{}` |",
            r.config.knob.name(),
            r.config.value(),
            r.us_per_step,
            r.us_per_ms,
            if r.stable {
                format!("{:.2e}", r.rms_distance)
            } else {
                format!("diverged ({:.0e})", r.rms_distance)
            },
            error_kind(r),
            r.max_stretch,
            r.energy_error,
            r.groom.mean_turning,
            r.groom.rest_mean_turning,
            100.0 * r.groom.kinked,
            r.rolled_back,
            if r.pareto { "*" } else { "" },
            r.config.describe()
        );
    }
    s.push_str("\nPareto front, cheapest first:\n\n");
    for r in study.front() {
        let _ = writeln!(
            s,
            "- {:.1} µs/sim ms, {:.2e} m ({}): `{}`",
            r.us_per_ms,
            r.rms_distance,
            error_kind(r),
            r.config.describe()
        );
    }
    for budget in [100.0, 250.0, 500.0, 1000.0] {
        let _ = match study.best_within(budget) {
            Some(r) => writeln!(
                s,
                "\nBest within {budget} µs per simulated ms: `{}` ({:.1} µs, {:.2e} m).",
                r.config.describe(),
                r.us_per_ms,
                r.rms_distance
            ),
            None => writeln!(s, "\nNothing measured fits {budget} µs per simulated ms."),
        };
    }
    s
}

/// A cost axis tick: no more digits than the value needs.
fn tick(v: f64) -> String {
    if v >= 10.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// The plot: RMS distance against µs per simulated ms, log–log, one curve per knob, the
/// Pareto front in black.
pub fn plot(study: &Study, path: &Path) -> Result<()> {
    let finite: Vec<&Row> = study
        .rows
        .iter()
        .filter(|r| r.stable && r.rms_distance > 0.0)
        .collect();
    let bounds = |f: fn(&Row) -> f64| {
        let lo = finite.iter().map(|r| f(r)).fold(f64::INFINITY, f64::min);
        let hi = finite.iter().map(|r| f(r)).fold(0.0, f64::max);
        if lo.is_finite() && hi > 0.0 {
            (lo / 1.5, hi * 1.5)
        } else {
            (1e-3, 1.0)
        }
    };
    let (x0, x1) = bounds(|r| r.us_per_ms);
    let (y0, y1) = bounds(|r| r.rms_distance);
    let root = SVGBackend::new(path, (960, 640)).into_drawing_area();
    let e = |e: &dyn std::fmt::Display| anyhow!("{}: plot: {e}", path.display());
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}: accuracy against cost ({} s simulated; DFTL error = model + numerical)",
                study.scene, study.duration
            ),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc("µs per simulated ms (one thread; = µs per step at dt 1 ms)")
        .y_desc("RMS node distance from reference (m)")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|x| e(&x))?;
    let knobs: Vec<Knob> = Knob::SWEPT
        .into_iter()
        .filter(|k| finite.iter().any(|r| r.config.knob == *k))
        .collect();
    for (i, knob) in knobs.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let points: Vec<(f64, f64)> = finite
            .iter()
            .filter(|r| r.config.knob == *knob)
            .map(|r| (r.us_per_ms, r.rms_distance))
            .collect();
        // The solver the curve runs, when it is not the scene's.
        let label = match finite
            .iter()
            .find(|r| r.config.knob == *knob && r.config.solver != study.solver)
        {
            Some(r) if *knob != Knob::Solver => {
                format!("{} ({})", knob.name(), r.config.solver.name())
            }
            _ => knob.name().to_string(),
        };
        chart
            .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 4, colour.filled())))
            .map_err(|x| e(&x))?;
    }
    let front: Vec<(f64, f64)> = study
        .front()
        .iter()
        .filter(|r| r.rms_distance > 0.0)
        .map(|r| (r.us_per_ms, r.rms_distance))
        .collect();
    chart
        .draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(1)))
        .map_err(|x| e(&x))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    chart
        .draw_series(
            front
                .iter()
                .map(|&p| Circle::new(p, 7, BLACK.stroke_width(1))),
        )
        .map_err(|x| e(&x))?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}
