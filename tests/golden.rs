//! Golden state hashes: every built-in scene, both solvers, both twist methods, stepped per
//! strand and in blocks, on 1 and 2 threads.
//!
//! Bits change only on purpose. A commit that moves one of these hashes updates the table in
//! the same commit and says why in its message. The layout and the thread count never move a
//! hash: every layout × thread combination of a row must give the row's one hash, and the
//! native configuration must also give it through `hairsim run` (the command-line path).
//!
//! To print the whole table after an intended change:
//! `HAIRSIM_GOLDEN_PRINT=1 cargo test -p hairsim-tests --test golden -- --nocapture`.

use hairsim::builtin::{self, BUILTINS};
use hairsim::run::{capacity_for, run_builtin, RunOptions};
use hairsim::scene::{Prepared, RodSpec, Scene};
use hairsim::sim::{scene_inputs, Layout, Sim};
use hairsim_core::{DefaultMath, Effect, Solver};

/// One pinned configuration: a built-in scene, the solver it runs, the rod's twist method.
struct Golden {
    scene: &'static str,
    solver: &'static str,
    /// `"hair-optimised"` or `"newton"` for the rod; `"-"` for DFTL.
    twist: &'static str,
    steps: u64,
    hash: u64,
}

const fn g(
    scene: &'static str,
    solver: &'static str,
    twist: &'static str,
    steps: u64,
    hash: u64,
) -> Golden {
    Golden {
        scene,
        solver,
        twist,
        steps,
        hash,
    }
}

/// The table. Scenes of many strands run fewer steps so the whole test stays within a minute.
#[rustfmt::skip]
const TABLE: &[Golden] = &[
    g("firmware", "rod", "hair-optimised", 1000, 0xa4302e96550cb1fc),
    g("firmware", "rod", "newton", 1000, 0xfdd2f0c1d2029c76),
    g("firmware", "dftl", "-", 1000, 0x7206d645f6751130),
    g("firmware-dftl", "dftl", "-", 1000, 0x7a9b1bc6a76b5d62),
    g("firmware-dftl", "rod", "hair-optimised", 1000, 0x7ee1495757ff1600),
    g("firmware-dftl", "rod", "newton", 1000, 0x7ee1495757ff1600),
    g("stand-1", "rod", "hair-optimised", 1000, 0x68dc648c02e000ba),
    g("stand-1", "rod", "newton", 1000, 0x68dc648c02e000ba),
    g("stand-1", "dftl", "-", 1000, 0x21b7ce7473611f86),
    g("stand-2", "rod", "hair-optimised", 1000, 0x00ce18564c3f2fc4),
    g("stand-2", "rod", "newton", 1000, 0x00ce18564c3f2fc4),
    g("stand-2", "dftl", "-", 1000, 0xc1685b65b8cdb4a5),
    g("stand-3", "rod", "hair-optimised", 1000, 0x95b9aa999b7b27f5),
    g("stand-3", "rod", "newton", 1000, 0x95b9aa999b7b27f5),
    g("stand-3", "dftl", "-", 1000, 0x81b1d8def6988b89),
    g("head-1", "rod", "hair-optimised", 300, 0xe22a0444895cb67e),
    g("head-1", "rod", "newton", 300, 0x581cf8daac7a1bae),
    g("head-1", "dftl", "-", 300, 0x92d4378c1fb07c00),
    g("head-2", "rod", "hair-optimised", 300, 0x6a806c639f52d265),
    g("head-2", "rod", "newton", 300, 0x17a5af02d9d89114),
    g("head-2", "dftl", "-", 300, 0xe98db9abdc8795a2),
    g("head-3", "rod", "hair-optimised", 300, 0xbf99d3eac0e15afb),
    g("head-3", "rod", "newton", 300, 0xeae630b081b6aa8b),
    g("head-3", "dftl", "-", 300, 0xedb1905ba959a014),
    g("mannequin-a", "dftl", "-", 4, 0x0de2a68dda3d6b63),
    g("mannequin-a", "rod", "hair-optimised", 4, 0xc9ebffa215f17571),
    g("mannequin-a", "rod", "newton", 4, 0xc9ebffa215f17571),
    g("mannequin-b", "dftl", "-", 100, 0x59e993feabcecd62),
    g("mannequin-b", "rod", "hair-optimised", 100, 0xf961f00e8fdecbbc),
    g("mannequin-b", "rod", "newton", 100, 0xf961f00e8fdecbbc),
    g("haptic", "rod", "hair-optimised", 1000, 0xf02f8d193ec024b9),
    g("haptic", "rod", "newton", 1000, 0xf02f8d193ec024b9),
    g("haptic", "dftl", "-", 1000, 0x9aab657da012e0cf),
    g("haptic-dftl", "dftl", "-", 1000, 0xc7c12b7a1ee374b3),
    g("haptic-dftl", "rod", "hair-optimised", 1000, 0x72c960e28e9eefed),
    g("haptic-dftl", "rod", "newton", 1000, 0x72c960e28e9eefed),
];

/// The rod's largest time step (`Params::validate`).
const ROD_DT_MAX: f32 = 0.004;

/// The built-in scene `row.scene`, switched to `row.solver` and `row.twist`. Effects the other
/// solver cannot simulate are dropped, and a DFTL scene run by the rod takes the rod's largest
/// time step if its own is larger; nothing else changes.
fn configured(row: &Golden) -> Scene {
    let mut scene = (builtin::find(row.scene).expect("a built-in scene").scene)();
    let solver = match row.solver {
        "rod" => Solver::Rod,
        _ => Solver::Dftl,
    };
    scene.solver = row.solver.into();
    scene
        .effects
        .retain(|name| Effect::from_name(name).is_some_and(|effect| solver.supports(effect)));
    match solver {
        // `[rod]` stays: DFTL's held strands take the rod's projection with its caps.
        Solver::Dftl => {}
        Solver::Rod => {
            scene.dftl = None;
            scene.dt = scene.dt.min(ROD_DT_MAX);
            let rod = scene.rod.get_or_insert_with(RodSpec::default);
            rod.twist = Some(row.twist.into());
        }
    }
    scene
}

fn run_sim<const N: usize>(prepared: &Prepared, steps: u64, layout: Layout, threads: usize) -> u64 {
    let mut sim =
        Sim::<N, DefaultMath>::with_layout(prepared, threads, layout).expect("the scene builds");
    sim.in_pool(|sim| {
        for k in 0..steps {
            sim.step(&scene_inputs::<DefaultMath>(prepared, k));
        }
    });
    assert!(sim.is_finite());
    sim.state_hash()
}

fn hash_of(prepared: &Prepared, steps: u64, layout: Layout, threads: usize) -> u64 {
    match capacity_for(prepared.max_nodes()).expect("a capacity of this build") {
        16 => run_sim::<16>(prepared, steps, layout, threads),
        32 => run_sim::<32>(prepared, steps, layout, threads),
        64 => run_sim::<64>(prepared, steps, layout, threads),
        _ => run_sim::<128>(prepared, steps, layout, threads),
    }
}

/// The row's one hash, after checking that every layout and thread count gives it.
fn row_hash(row: &Golden) -> u64 {
    let prepared = configured(row).prepare().expect("the scene prepares");
    let mut hashes = Vec::new();
    for layout in [Layout::PerStrand, Layout::Blocks] {
        for threads in [1, 2] {
            hashes.push((
                layout,
                threads,
                hash_of(&prepared, row.steps, layout, threads),
            ));
        }
    }
    let first = hashes[0].2;
    for (layout, threads, hash) in &hashes {
        assert_eq!(
            *hash, first,
            "{} {} {}: {layout:?} on {threads} threads gives {hash:#018x}, per strand on 1 \
             thread {first:#018x}",
            row.scene, row.solver, row.twist
        );
    }
    first
}

#[test]
fn every_builtin_scene_has_rows() {
    for builtin in BUILTINS {
        assert!(
            TABLE.iter().any(|row| row.scene == builtin.name),
            "built-in scene {} has no golden hash",
            builtin.name
        );
    }
}

#[test]
fn state_hashes_are_the_recorded_ones() {
    let print = std::env::var_os("HAIRSIM_GOLDEN_PRINT").is_some();
    let mut wrong = Vec::new();
    for row in TABLE {
        let hash = row_hash(row);
        if print {
            println!(
                "    g({:?}, {:?}, {:?}, {}, {hash:#018x}),",
                row.scene, row.solver, row.twist, row.steps
            );
        }
        if hash != row.hash {
            wrong.push(format!(
                "{} {} {} after {} steps: {hash:#018x}, recorded {:#018x}",
                row.scene, row.solver, row.twist, row.steps, row.hash
            ));
        }
    }
    assert!(
        wrong.is_empty(),
        "state hashes moved:\n{}",
        wrong.join("\n")
    );
}

/// The native configuration of each built-in scene gives its golden hash through `hairsim run`
/// (the command line's path, with its own set-up), not only through [`Sim`].
#[test]
fn the_command_line_gives_the_recorded_hashes() {
    for builtin in BUILTINS {
        let native = (builtin.scene)();
        let row = TABLE
            .iter()
            .find(|row| {
                row.scene == builtin.name
                    && row.solver == native.solver
                    && (row.solver == "dftl"
                        || row.twist
                            == native
                                .rod
                                .as_ref()
                                .and_then(|r| r.twist.as_deref())
                                .unwrap_or("hair-optimised"))
            })
            .expect("a row for the native configuration");
        let options = RunOptions {
            steps: Some(row.steps),
            ..RunOptions::default()
        };
        let summary = run_builtin(builtin.name, &options).expect("the scene runs");
        assert_eq!(
            summary.state_hash,
            format!("{:#018x}", row.hash),
            "hairsim run {} --steps {}",
            builtin.name,
            row.steps
        );
    }
}
