//! `hairsim study`: a tiny sweep writes its table, CSV and plot, and its Pareto front is what
//! it claims (no row on it is dominated; every row off it is).

use hairsim::run::{load, HairFileOptions};
use hairsim::study::{dominates, output, run, Knob, Plan};

#[test]
fn tiny_study_writes_its_files_and_an_undominated_front() {
    let loaded = load("firmware", &HairFileOptions::default()).expect("built-in scene");
    let plan = Plan {
        duration: 0.02,
        knobs: vec![Knob::TimeStep, Knob::Solver, Knob::Math],
        quick: true,
        repeats: 0,
    };
    let study = run(&loaded.prepared, &plan, |_| {}).expect("study runs");
    // Baseline, two time steps, two solvers, two backends.
    assert_eq!(study.rows.len(), 7);
    assert!(study.rows.iter().any(|r| r.config.model_error()));
    for r in &study.rows {
        assert!(r.us_per_step > 0.0 && r.us_per_ms > 0.0, "{r:?}");
        assert!(r.rms_distance.is_finite() && r.rms_distance >= 0.0, "{r:?}");
    }
    let front: Vec<_> = study.rows.iter().filter(|r| r.pareto).collect();
    assert!(!front.is_empty());
    for f in &front {
        assert!(f.stable);
        assert!(
            !study.rows.iter().any(|r| r.stable && dominates(r, f)),
            "{} is dominated",
            f.config.describe()
        );
    }
    for r in study.rows.iter().filter(|r| !r.pareto && r.stable) {
        assert!(
            study.rows.iter().any(|o| o.stable && dominates(o, r)),
            "{} is off the front but undominated",
            r.config.describe()
        );
    }
    // The budget picks the most accurate row that fits, and nothing when nothing fits.
    let cheapest = study
        .rows
        .iter()
        .map(|r| r.us_per_ms)
        .fold(f64::INFINITY, f64::min);
    assert!(study.best_within(cheapest * 0.5).is_none());
    let best = study.best_within(f64::MAX).expect("something fits");
    assert!(study
        .rows
        .iter()
        .filter(|r| r.stable)
        .all(|r| r.rms_distance >= best.rms_distance));

    let dir = std::env::temp_dir().join(format!("hairsim-study-{}", std::process::id()));
    let written = output::write(&study, &dir).expect("files written");
    assert_eq!(written.len(), 3);
    for path in &written {
        let text = std::fs::read_to_string(path).expect("readable");
        assert!(text.len() > 100, "{}", path.display());
    }
    let csv = std::fs::read_to_string(dir.join("firmware.csv")).expect("csv");
    assert_eq!(csv.lines().count(), 1 + study.rows.len());
    assert!(csv.contains("model + numerical"));
    let svg = std::fs::read_to_string(dir.join("firmware.svg")).expect("svg");
    assert!(svg.starts_with("<svg") && svg.contains("Pareto front"));
    std::fs::remove_dir_all(&dir).ok();
}
