//! What each effect costs per step (as the columns of Kmoch 2009 Table 1 and
//! Sánchez-Banderas 2015 Table 1): the firmware scenes (`firmware`: rod, `firmware-dftl`:
//! DFTL) stepped by the harness's `Sim` with every effect the solver supports on, then with
//! each effect turned off in turn. An effect's marginal cost is the step with everything on
//! minus the step without it; a second column adds it alone to a step with nothing on.
//!
//! Every variant is timed stepping from the same 20 states of the all-on run (restored before
//! each timed step): the rod's substep count follows the strands' bends, so variants left to
//! run their own trajectories would differ by their states' cost as much as by their code's.
//!
//! An effect that is off costs within noise of its code not existing. How that is shown:
//! * the stages an effect gates report that they did not run (`StepReport::runs` is 0; checked
//!   below before anything is timed), so none of the effect's code runs, only the test of its
//!   bit (`StepContext::has`, one `u16` AND per stage per strand);
//! * the `gate` benchmark times those tests themselves — every effect's bit tested once per
//!   strand, far more often than a step tests them — and the table compares it with the noise
//!   of the step measurement (the spread of the per-round medians);
//! * for hair–hair, whose code lives in the harness, "off" (SPH set up, its effect bit clear)
//!   and "absent" (no SPH object at all) are both timed and compared directly.
//!
//! `cargo bench -p hairsim-benches --bench effects` prints the table (interleaved rounds of
//! timed steps, medians), then runs criterion on every variant. Under `cargo test --benches`
//! it takes a few steps of each variant only.

use std::hint::black_box;
use std::time::Instant;

use cpu_time::ThreadTime;
use criterion::{criterion_group, Criterion};
use hairsim::run::{load, HairFileOptions};
use hairsim::scene::Prepared;
use hairsim::sim::{scene_inputs, Sim, StepInputs};
use hairsim::sph::SphParams;
use hairsim_core::context::StepContext;
use hairsim_core::{Effect, Effects, Grab, Libm, Params, Pose, Solver, Stage, Strand};

/// The firmware scenes' strands have at most 16 nodes.
const N: usize = 16;

/// A scene with the effects `effects` on (SPH set up when `hair-hair` is, or when `sph`).
fn variant(base: &Prepared, effects: Effects, sph: bool) -> Prepared {
    let mut p = base.clone();
    p.params.effects = effects;
    p.sph = (sph || effects.contains(Effect::HairHair)).then(SphParams::default);
    p
}

/// The scene SCENE with every effect its solver supports.
fn scene(name: &str) -> Prepared {
    let mut p = load(name, &HairFileOptions::default())
        .expect("built-in scene")
        .prepared;
    let all = Effect::ALL
        .into_iter()
        .filter(|e| p.params.solver.supports(*e))
        .fold(Effects::NONE, Effects::with);
    p.params.effects = all;
    p
}

/// The stages an effect gates, which must not run when it is off. (Bending shares the rod's
/// elastic-force stage with twist: its gate is inside that stage, `ElasticTerms`; gravity,
/// drag, wind and grabs are terms inside stages that always run.)
fn gated_stages(effect: Effect, solver: Solver) -> &'static [Stage] {
    match (effect, solver) {
        (Effect::Twist, Solver::Rod) => &[Stage::Twist],
        (Effect::Shape, Solver::Dftl) => &[Stage::Shape],
        (Effect::Inextensibility, Solver::Dftl) => &[Stage::Projection],
        (Effect::Collisions, _) => &[Stage::Collisions],
        _ => &[],
    }
}

/// A state of the all-on run to step from: every variant is timed stepping from the same
/// states, so that a difference is the effect's code, not a different trajectory (the rod's
/// substep count follows the strands' bends).
#[derive(Clone)]
struct Snapshot {
    steps: u64,
    head: Pose,
    strands: Vec<Strand<N>>,
    grabs: Vec<Grab>,
}

/// States of the all-on scene every 50 steps over its first second.
fn snapshots(all_on: &Prepared) -> Vec<Snapshot> {
    let mut sim = Sim::<N, Libm>::new(all_on, 1).expect("scene builds");
    let mut out = Vec::new();
    for k in 0..1000u64 {
        if k % 50 == 25 {
            out.push(Snapshot {
                steps: sim.steps,
                head: sim.head,
                strands: sim.strands.clone(),
                grabs: sim.grabs.clone(),
            });
        }
        sim.step(&scene_inputs::<Libm>(all_on, k));
    }
    out
}

/// One timed variant.
struct Case {
    name: String,
    sim: Sim<N, Libm>,
    prepared: Prepared,
    times: Vec<f64>,
    round_medians: Vec<f64>,
}

impl Case {
    fn new(name: String, prepared: &Prepared) -> Case {
        Case {
            name,
            sim: Sim::new(prepared, 1).expect("scene builds"),
            prepared: prepared.clone(),
            times: Vec::new(),
            round_medians: Vec::new(),
        }
    }

    /// Puts the variant in the state `snapshot`; the inputs of its next step.
    fn restore(&mut self, snapshot: &Snapshot) -> StepInputs {
        self.sim.steps = snapshot.steps;
        self.sim.head = snapshot.head;
        self.sim.strands.clone_from(&snapshot.strands);
        self.sim.grabs.clone_from(&snapshot.grabs);
        scene_inputs::<Libm>(&self.prepared, snapshot.steps)
    }

    /// µs of one step from `snapshot`: the thread's CPU time, which stops while the thread is
    /// descheduled (on a shared machine the wall clock adds other processes' time slices).
    fn step_from(&mut self, snapshot: &Snapshot) -> f64 {
        let inputs = self.restore(snapshot);
        let start = ThreadTime::now();
        black_box(self.sim.step(black_box(&inputs)));
        start.elapsed().as_secs_f64() * 1e6
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Whether this is `cargo bench` (criterion's `--bench`), not `cargo test --benches`.
fn benching() -> bool {
    std::env::args().any(|a| a == "--bench")
}

/// The variants of one scene: all, none, all minus each effect, none plus each effect, and
/// for hair–hair "off" and "absent".
fn cases(base: &Prepared) -> Vec<Case> {
    let all = base.params.effects;
    let solver = base.params.solver;
    let mut out = vec![
        Case::new("all".into(), &variant(base, all, false)),
        Case::new("none".into(), &variant(base, Effects::NONE, false)),
    ];
    for e in all.iter() {
        let without = variant(base, all.without(e), false);
        check_gated_off(&without, e, solver);
        out.push(Case::new(format!("all - {}", e.name()), &without));
        out.push(Case::new(
            format!("none + {}", e.name()),
            &variant(base, Effects::NONE.with(e), false),
        ));
    }
    let no_hair = all.without(Effect::HairHair);
    out.push(Case::new(
        "hair-hair off (SPH set up)".into(),
        &variant(base, no_hair, true),
    ));
    out.push(Case::new(
        "hair-hair absent (no SPH)".into(),
        &variant(base, no_hair, false),
    ));
    out
}

/// An effect that is off runs none of its stages (the report counts only stages that ran).
fn check_gated_off(prepared: &Prepared, effect: Effect, solver: Solver) {
    let mut sim = Sim::<N, Libm>::new(prepared, 1).expect("scene builds");
    let report = sim.step(&scene_inputs::<Libm>(prepared, 0));
    for stage in gated_stages(effect, solver) {
        assert_eq!(
            report.runs(*stage),
            0,
            "{:?} ran with {} off",
            stage,
            effect.name()
        );
    }
    if effect == Effect::HairHair {
        assert!(sim.sph.is_none());
    }
}

/// Times every case in interleaved rounds (a change of the machine's load falls on all alike)
/// and prints the table.
fn table(scene_name: &str, rounds: usize, repeats: usize) {
    let base = scene(scene_name);
    let states = snapshots(&base);
    let mut cases = cases(&base);
    // Finely interleaved: for each state, every case in turn, so that a change of the
    // machine's load falls on all cases alike.
    for _ in 0..rounds {
        let mut round: Vec<Vec<f64>> = vec![Vec::new(); cases.len()];
        for state in &states {
            for (case, times) in cases.iter_mut().zip(&mut round) {
                for _ in 0..repeats {
                    times.push(case.step_from(state));
                }
            }
        }
        for (case, mut times) in cases.iter_mut().zip(round) {
            case.round_medians.push(median(&mut times));
            case.times.extend(times);
        }
    }
    for case in &mut cases {
        case.times.sort_by(f64::total_cmp);
    }
    let med = |name: &str| {
        cases
            .iter()
            .find(|c| c.name == name)
            .and_then(|c| c.times.get(c.times.len() / 2).copied())
            .unwrap_or(f64::NAN)
    };
    let all = med("all");
    let none = med("none");
    // The noise: the standard deviation of the all-on case's round medians.
    let noise = cases.iter().find(|c| c.name == "all").map_or(0.0, |c| {
        let n = c.round_medians.len().max(1) as f64;
        let mean = c.round_medians.iter().sum::<f64>() / n;
        (c.round_medians
            .iter()
            .map(|m| (m - mean).powi(2))
            .sum::<f64>()
            / n)
            .sqrt()
    });
    println!(
        "\n{scene_name} ({} solver, {} strands, {} nodes): median thread-CPU µs of one step from each of the same {} states, {rounds} rounds of {repeats} per state",
        base.params.solver.name(),
        base.strands.len(),
        base.nodes(),
        states.len()
    );
    println!("  all effects on: {all:.2} µs; nothing on: {none:.2} µs; noise (standard deviation of the all-on round medians): {noise:.2} µs");
    println!(
        "  {:<16} {:>16} {:>16}",
        "effect", "all − without", "alone − none"
    );
    for e in base.params.effects.iter() {
        let without = med(&format!("all - {}", e.name()));
        let alone = med(&format!("none + {}", e.name()));
        println!(
            "  {:<16} {:>13.2} µs {:>13.2} µs",
            e.name(),
            all - without,
            alone - none
        );
    }
    let off = med("hair-hair off (SPH set up)");
    let absent = med("hair-hair absent (no SPH)");
    println!(
        "  hair-hair off {off:.2} µs vs absent {absent:.2} µs: difference {:.2} µs (noise {noise:.2} µs)",
        off - absent
    );
    let gate = gate_cost(&base.params, base.strands.len());
    println!(
        "  every effect's gate tested once per strand: {:.4} µs per step ({:.2} % of the all-on step)",
        gate,
        100.0 * gate / all
    );
}

/// µs to test every effect's bit once per strand (far more tests than a step makes for its
/// off effects), the median of many repetitions.
fn gate_cost(params: &Params, strands: usize) -> f64 {
    let ctx = StepContext::with_coefficients(
        params,
        params.dftl.at_step(params.dt),
        Pose::IDENTITY,
        Pose::IDENTITY,
        &[],
    );
    let mut samples: Vec<f64> = (0..201)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..1000 {
                let mut on = 0u32;
                for _ in 0..strands {
                    for e in Effect::ALL {
                        on += u32::from(black_box(&ctx).has(black_box(e)));
                    }
                }
                black_box(on);
            }
            start.elapsed().as_secs_f64() * 1e6 / 1000.0
        })
        .collect();
    median(&mut samples)
}

fn effects(c: &mut Criterion) {
    for scene_name in ["firmware", "firmware-dftl"] {
        let base = scene(scene_name);
        let mut group = c.benchmark_group(format!("effects/{scene_name}"));
        let states = snapshots(&base);
        for mut case in cases(&base) {
            group.bench_function(case.name.clone(), |b| {
                b.iter_custom(|iters| {
                    let mut total = std::time::Duration::ZERO;
                    for i in 0..iters {
                        let inputs = case.restore(&states[i as usize % states.len()]);
                        let start = Instant::now();
                        black_box(case.sim.step(black_box(&inputs)));
                        total += start.elapsed();
                    }
                    total
                })
            });
        }
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2));
    targets = effects
}

fn main() {
    // The table first: interleaved rounds under `cargo bench`, a few steps under `cargo test`.
    let (rounds, repeats) = if benching() { (20, 10) } else { (1, 1) };
    for scene_name in ["firmware", "firmware-dftl"] {
        table(scene_name, rounds, repeats);
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
