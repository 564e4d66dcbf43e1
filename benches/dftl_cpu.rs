//! DFTL throughput per CPU-second, for a shared machine where wall-clock benchmarks are noisy:
//! each configuration steps a fixed number of vertex-steps and divides by the CPU time the
//! process used (Linux `/proc/self/stat` utime + stime, 10 ms ticks; runs last ≥ 0.3 s), and by
//! the wall time. Sizes of Sánchez-Banderas 2015 Table 2; per-strand path vs blocks of 8 and 16
//! lanes, DFTL (gravity + inextensibility) and DFTL + shape; the 16-lane blocks also split over
//! two threads (a rayon pool, a fixed partition; CPU time then counts both threads).
//! Arguments that are not options select cases whose label contains them (or, ending in `$`,
//! whose label ends with the rest).
//!
//! `cargo bench -p hairsim-benches --bench dftl_cpu`

use std::time::Instant;

use hairsim_benches::cpu_seconds;
use hairsim_core::context::StepContext;
use hairsim_core::dftl::DftlBlock;
use hairsim_core::step_blocks;
use hairsim_core::{
    step_strands, Effect, Effects, Material, Math, Params, Real, Shake, Solver, StepReport, Strand,
    Vec3,
};

/// `libm`'s trigonometry, the hardware's correctly rounded square root (vectorisable).
#[derive(Clone, Copy, Debug, Default)]
struct HostMath;

impl Math for HostMath {
    const NAME: &'static str = "host-sqrt";
    #[inline(always)]
    fn sqrt(x: Real) -> Real {
        x.sqrt()
    }
    #[inline(always)]
    fn sin_cos(x: Real) -> (Real, Real) {
        hairsim_core::math::sin_cos(x)
    }
    #[inline(always)]
    fn atan2(y: Real, x: Real) -> Real {
        hairsim_core::math::atan2(y, x)
    }
}

fn strands<const N: usize>(count: usize) -> Vec<Strand<N>> {
    (0..count)
        .map(|s| {
            let a = s as Real * 2.399_963;
            let up = (s as Real + 0.5) / count as Real;
            let r = (1.0 - up * up).sqrt();
            let normal = Vec3::new(r * a.cos(), up, r * a.sin());
            let side = normal.cross(Vec3::Y).normalize_or(Vec3::X);
            let points: Vec<Vec3> = (0..N)
                .map(|i| {
                    let t = i as Real * 0.01;
                    normal * (0.1 + t) + side * (0.003 * (30.0 * t).sin())
                })
                .collect();
            Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
        })
        .collect()
}

fn contexts(shape: bool, steps: u32) -> Vec<StepContext> {
    let mut effects = Effects::from_slice(&[Effect::Gravity, Effect::Inextensibility]);
    if shape {
        effects = effects.with(Effect::Shape);
    }
    let p = Params {
        solver: Solver::Dftl,
        effects,
        ..Params::DEFAULT
    };
    let c = p.dftl.at_step(p.dt);
    let shake = Shake::TEN_RAD_PER_S;
    (0..steps)
        .map(|k| {
            let t = k as Real * p.dt;
            let (a, b) = (
                shake.pose_at::<HostMath>(t),
                shake.pose_at::<HostMath>(t + p.dt),
            );
            StepContext::with_coefficients(&p, c, a, b, &[])
        })
        .collect()
}

/// Labels to run: the command line's arguments that are not options (all when none).
fn wanted(label: &str) -> bool {
    let filters: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    filters.is_empty()
        || filters.iter().any(|f| match f.strip_suffix('$') {
            // `…dftl$`: the rows that end so (without shape), not the `dftl+shape` ones.
            Some(end) => label.ends_with(end),
            None => label.contains(f.as_str()),
        })
}

fn measure(label: &str, vertices: usize, steps: u32, mut run: impl FnMut()) {
    if !wanted(label) {
        return;
    }
    let (cpu0, wall0) = (cpu_seconds(), Instant::now());
    run();
    let (cpu, wall) = (cpu_seconds() - cpu0, wall0.elapsed().as_secs_f64());
    let work = vertices as f64 * f64::from(steps) / 1e6;
    println!(
        "{label:<40} {:>8.1} M/CPU-s {:>8.1} M/wall-s",
        work / cpu.max(0.01),
        work / wall
    );
}

/// The paths each size times, as its rows' labels name them.
const PATHS: [&str; 4] = ["per-strand", "block-8", "block-16", "block-16 2 threads"];

fn size<const N: usize>(count: usize, quick: bool) {
    let vertices = count * N;
    // About 20 M vertex-steps per run; one step each under `cargo test --benches`.
    let steps = if quick {
        1
    } else {
        (20_000_000 / vertices).max(10) as u32
    };
    for shape in [false, true] {
        let name = if shape { "dftl+shape" } else { "dftl" };
        let label = |path: &str| format!("{count} x {N} {path} {name}");
        // The contexts and strands of a size no row wants are not built: a filtered run
        // (old against new, an instruction count) does only the rows it names.
        if !PATHS.iter().any(|path| wanted(&label(path))) {
            continue;
        }
        let ctx = contexts(shape, steps);
        let mut report = StepReport::default();
        let mut s = strands::<N>(count);
        measure(&label("per-strand"), vertices, steps, || {
            for c in &ctx {
                step_strands::<HostMath, N>(c, &mut s, 0, &[], None, &mut report);
            }
        });
        let source = strands::<N>(count);
        let mut b8: Vec<DftlBlock<8, N>> = source.chunks(8).map(DftlBlock::from_strands).collect();
        measure(&label("block-8"), vertices, steps, || {
            for c in &ctx {
                step_blocks::<HostMath, 8, N>(c, &mut b8, 0, None, &mut report);
            }
        });
        let mut b16: Vec<DftlBlock<16, N>> =
            source.chunks(16).map(DftlBlock::from_strands).collect();
        measure(&label("block-16"), vertices, steps, || {
            for c in &ctx {
                step_blocks::<HostMath, 16, N>(c, &mut b16, 0, None, &mut report);
            }
        });
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a pool of two threads");
        measure(
            &label("block-16 2 threads"),
            vertices,
            steps,
            // Two halves of the blocks on a pool of two threads (a fixed partition: the
            // result does not depend on it), both finished before the next step starts.
            || {
                let half = b16.len().div_ceil(2);
                for c in &ctx {
                    pool.install(|| {
                        let (left, right) = b16.split_at_mut(half);
                        rayon::join(
                            || {
                                let mut r = StepReport::default();
                                step_blocks::<HostMath, 16, N>(c, left, 0, None, &mut r);
                            },
                            || {
                                let mut r = StepReport::default();
                                let first = (half * 16) as u32;
                                step_blocks::<HostMath, 16, N>(c, right, first, None, &mut r);
                            },
                        )
                    });
                }
            },
        );
        std::hint::black_box(&report);
    }
}

/// The state hash of 64 strands × 32 nodes after 200 shaking steps of DFTL + shape, by the
/// per-strand path and by 16-lane blocks. Recorded on the default x86-64 target; the check
/// that `-C target-cpu=native` (AVX-512 here) gives the same bits. The hash covers the material
/// angles `θ`, which DFTL carries at their rest values without reading them, so a change to
/// the hair-optimised twist's arithmetic that moves the rest angles' bits moves it too.
const EXPECTED_HASH: u64 = 0xfa6a_14c2_6b8c_9d68;

fn check_hash() {
    let ctx = contexts(true, 200);
    let mut s = strands::<32>(64);
    let mut blocks: Vec<DftlBlock<16, 32>> = s.chunks(16).map(DftlBlock::from_strands).collect();
    let mut report = StepReport::default();
    for c in &ctx {
        step_strands::<HostMath, 32>(c, &mut s, 0, &[], None, &mut report);
        step_blocks::<HostMath, 16, 32>(c, &mut blocks, 0, None, &mut report);
    }
    let per_strand = hairsim_core::hash::state_hash(&s);
    for (block, chunk) in blocks.iter().zip(s.chunks_mut(16)) {
        block.store(chunk);
    }
    let block = hairsim_core::hash::state_hash(&s);
    println!("state hash (64 x 32, 200 steps, shape): per-strand {per_strand:#018x}, block-16 {block:#018x}, recorded {EXPECTED_HASH:#018x}");
    assert_eq!(
        per_strand, block,
        "block path differs from the per-strand path"
    );
    assert_eq!(
        per_strand, EXPECTED_HASH,
        "the bits changed with the build (target features?)"
    );
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    check_hash();
    // `cargo bench` passes `--bench`; `cargo test --benches` does not: then every case runs
    // once, as a test that the benchmark works, not a measurement.
    let quick = !std::env::args().any(|a| a == "--bench");
    size::<8>(1024, quick);
    size::<32>(1024, quick);
    size::<32>(4096, quick);
    size::<64>(4096, quick);
    size::<64>(16384, quick);
}
