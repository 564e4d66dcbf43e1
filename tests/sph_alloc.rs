//! A step of the SPH stage allocates nothing: every buffer is sized when the stage is built.
//! Its own test binary, so that no other test allocates while this one counts.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use hairsim::sph::{Sph, SphParams};
use hairsim_core::{Material, Strand, Vec3};

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

#[test]
fn a_step_allocates_nothing() {
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
    let mut acc = vec![Vec3::ZERO; strands.len() * N];
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    // Every worker started and registered (a thread's start-up allocates) before counting.
    pool.broadcast(|_| ());
    pool.install(|| {
        // Warm-up: rayon's work-stealing deques grow to their working size on first use.
        for _ in 0..5 {
            sph.accelerations(&strands, 0.001, &mut acc);
        }
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        for _ in 0..10 {
            sph.accelerations(&strands, 0.001, &mut acc);
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
