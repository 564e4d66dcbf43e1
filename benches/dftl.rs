//! DFTL throughput on the sizes of Sánchez-Banderas 2015 Table 2 (1,024 × 8 … 16,384 × 64
//! vertices), in vertex-steps per second: per-strand path vs the structure-of-arrays block path,
//! DFTL (gravity + inextensibility) and DFTL + shape, one thread; and the block path split over
//! two threads by a fixed partition of the blocks (as the harness will do).
//!
//! `HostMath` routes `sqrt` to `f32::sqrt` (correctly rounded: the same bits as `libm`), which
//! the compiler can vectorise; `libm::sqrtf` is an inline `sqrtss` on x86-64 that it cannot.
//!
//! Short runs: `cargo bench -p hairsim-benches --bench dftl -- --warm-up-time 1 --measurement-time 3`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use hairsim_core::context::StepContext;
use hairsim_core::dftl::DftlBlock;
use hairsim_core::step_blocks;
use hairsim_core::{
    step_strands, Effect, Effects, Material, Math, Params, Pose, Real, Shake, Solver, StepReport,
    Strand, Vec3,
};

/// Lanes per block of the wide rows, beside the harness's 8 (`RECOMMENDED_LANES`): a pass
/// over 16 lanes spills the SSE2 registers, and these rows show what that costs.
const W: usize = 16;

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

fn params(shape: bool) -> Params {
    let mut effects = Effects::from_slice(&[Effect::Gravity, Effect::Inextensibility]);
    if shape {
        effects = effects.with(Effect::Shape);
    }
    Params {
        solver: Solver::Dftl,
        effects,
        ..Params::DEFAULT
    }
}

/// `count` wavy strands of `nodes` nodes rooted on a 10 cm scalp, 1 cm segments.
fn strands<const N: usize>(count: usize, nodes: usize) -> Vec<Strand<N>> {
    (0..count)
        .map(|s| {
            let a = s as Real * 2.399_963; // golden angle: spread over the scalp
            let up = (s as Real + 0.5) / count as Real;
            let r = (1.0 - up * up).sqrt();
            let normal = Vec3::new(r * a.cos(), up, r * a.sin());
            let side = normal.cross(Vec3::Y).normalize_or(Vec3::X);
            let points: Vec<Vec3> = (0..nodes)
                .map(|i| {
                    let t = i as Real * 0.01;
                    normal * (0.1 + t) + side * (0.003 * (30.0 * t).sin())
                })
                .collect();
            Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
        })
        .collect()
}

fn context(p: &Params, k: u32) -> StepContext {
    let t0 = k as Real * p.dt;
    let shake = Shake::TEN_RAD_PER_S;
    StepContext::with_coefficients(
        p,
        p.dftl.at_step(p.dt),
        shake.pose_at::<HostMath>(t0),
        shake.pose_at::<HostMath>(t0 + p.dt),
        &[],
    )
}

fn bench_size<const N: usize>(c: &mut Criterion, count: usize) {
    let vertices = (count * N) as u64;
    let mut group = c.benchmark_group(format!("dftl {count} x {N}"));
    group.throughput(Throughput::Elements(vertices));
    group.sample_size(10);
    for shape in [false, true] {
        let p = params(shape);
        let label = if shape { "dftl+shape" } else { "dftl" };
        let contexts: Vec<StepContext> = (0..64).map(|k| context(&p, k)).collect();
        let mut per_strand = strands::<N>(count, N);
        let mut k = 0usize;
        group.bench_function(BenchmarkId::new("per-strand", label), |b| {
            b.iter(|| {
                let mut report = StepReport::default();
                step_strands::<HostMath, N>(
                    &contexts[k % 64],
                    &mut per_strand,
                    0,
                    &[],
                    None,
                    &mut report,
                );
                k += 1;
                black_box(report.max_stretch)
            })
        });
        let source = strands::<N>(count, N);
        let mut narrow: Vec<DftlBlock<8, N>> =
            source.chunks(8).map(DftlBlock::from_strands).collect();
        group.bench_function(BenchmarkId::new("block-8", label), |b| {
            b.iter(|| {
                let mut report = StepReport::default();
                step_blocks::<HostMath, 8, N>(&contexts[k % 64], &mut narrow, 0, None, &mut report);
                k += 1;
                black_box(report.max_stretch)
            })
        });
        let mut blocks: Vec<DftlBlock<W, N>> =
            source.chunks(W).map(DftlBlock::from_strands).collect();
        group.bench_function(BenchmarkId::new("block-16", label), |b| {
            b.iter(|| {
                let mut report = StepReport::default();
                step_blocks::<HostMath, W, N>(&contexts[k % 64], &mut blocks, 0, None, &mut report);
                k += 1;
                black_box(report.max_stretch)
            })
        });
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a pool of two threads");
        group.bench_function(BenchmarkId::new("block-16 2 threads", label), |b| {
            b.iter(|| {
                let ctx = &contexts[k % 64];
                k += 1;
                let half = blocks.len().div_ceil(2);
                let (left, right) = blocks.split_at_mut(half);
                let mut reports = [StepReport::default(), StepReport::default()];
                let (ra, rb) = reports.split_at_mut(1);
                pool.install(|| {
                    rayon::join(
                        || step_blocks::<HostMath, W, N>(ctx, left, 0, None, &mut ra[0]),
                        || {
                            let first = (half * W) as u32;
                            step_blocks::<HostMath, W, N>(ctx, right, first, None, &mut rb[0])
                        },
                    )
                });
                let [mut a, b2] = reports;
                a.merge(&b2);
                black_box(a.max_stretch)
            })
        });
    }
    group.finish();
    let _ = Pose::IDENTITY;
}

fn table_2(c: &mut Criterion) {
    bench_size::<8>(c, 1024);
    bench_size::<32>(c, 1024);
    bench_size::<32>(c, 4096);
    bench_size::<64>(c, 4096);
    bench_size::<64>(c, 16384);
}

criterion_group!(benches, table_2);
criterion_main!(benches);
