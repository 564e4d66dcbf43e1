//! A step of the SPH stage allocates nothing: every buffer is sized when the stage is built.
//! Its own test binary, with a single test, so that nothing else allocates while it counts.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use hairsim::sph::{Sph, SphParams};
use hairsim_core::{Material, Pose, Strand, Vec3};

/// Counts every allocation of this test binary.
struct Counting;
static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}
#[global_allocator]
static GLOBAL: Counting = Counting;

const N: usize = 16;

/// One test running both checks in turn: two tests would run on two threads at once and
/// count each other's allocations.
#[test]
fn sph_and_sim_steps_allocate_nothing() {
    an_sph_step_allocates_nothing();
    a_sim_step_with_hair_hair_allocates_nothing();
}

fn an_sph_step_allocates_nothing() {
    let mut strands: Vec<Strand<N>> = (0..40)
        .map(|k| {
            let offset = Vec3::new(0.0, 0.0001 * k as f32, 0.00007 * (k % 5) as f32);
            let points: Vec<Vec3> = (0..12)
                .map(|i| offset + Vec3::new(0.004 * i as f32, 0.0, 0.0))
                .collect();
            Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap()
        })
        .collect();
    let params = SphParams {
        smoothing_length: 0.004,
        ..SphParams::default()
    };
    let mut sph = Sph::new(params, &strands).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    // Every worker started and registered (a thread's start-up allocates) before counting.
    pool.broadcast(|_| ());
    pool.install(|| {
        // Warm-up: rayon's work-stealing deques grow to their working size on first use.
        for _ in 0..5 {
            sph.accelerations(&strands, 0.001, Pose::IDENTITY);
        }
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        for _ in 0..10 {
            sph.accelerations(&strands, 0.001, Pose::IDENTITY);
            strands[0].state.position[5].x += 1e-4;
        }
        let after = ALLOCATIONS.load(Ordering::Relaxed);
        assert!(sph.stats.neighbours > 0);
        assert_eq!(
            after - before,
            0,
            "SPH steps allocated {} times",
            after - before
        );
    });
}

/// A whole step of the harness's `Sim` — SPH, then the strands' blocks on two threads, the
/// reports merged — with hair–hair on allocates nothing once set up.
fn a_sim_step_with_hair_hair_allocates_nothing() {
    use hairsim::sim::{scene_inputs, Sim};
    use hairsim_core::{DefaultMath, Stage};
    let scene = (hairsim::builtin::find("mannequin-b").unwrap().scene)();
    let prepared = scene.prepare().unwrap();
    let inputs: Vec<_> = (0..20)
        .map(|k| scene_inputs::<DefaultMath>(&prepared, k))
        .collect();
    let mut sim = Sim::<16, DefaultMath>::new(&prepared, 2).unwrap();
    // Inside the Sim's own pool, as a run goes: no work injected from outside per step.
    sim.in_pool(|sim| {
        for i in &inputs[..5] {
            sim.step(i);
        }
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        let mut ran = 0;
        for i in &inputs[5..] {
            ran += sim.step(i).runs(Stage::HairHair);
        }
        let after = ALLOCATIONS.load(Ordering::Relaxed);
        assert_eq!(ran, 15 * 500, "hair-hair ran on every strand at every step");
        assert_eq!(
            after - before,
            0,
            "Sim steps allocated {} times",
            after - before
        );
    });
}
