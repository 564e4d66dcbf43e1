//! This machine's memory bandwidth, to compare the DFTL step at 1,048,576 vertices against:
//! a STREAM-like copy (`a = b`) and triad (`a = b + s c`) over arrays far larger than the
//! caches (64 MiB each), on one thread and on two (each thread its own half). Bytes counted
//! as STREAM counts them: 8 per element for copy, 12 for triad (the write-allocate read of
//! `a` not counted). Best of 5 runs.
//!
//! `cargo bench -p hairsim-benches --bench bandwidth`

use std::hint::black_box;
use std::time::Instant;

fn copy(a: &mut [f32], b: &[f32]) {
    a.copy_from_slice(b);
}

fn triad(a: &mut [f32], b: &[f32], c: &[f32], s: f32) {
    for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
        *a = *b + s * *c;
    }
}

/// Runs `kernel` on `threads` equal parts of the arrays at once; returns GB/s (best of 5).
fn measure(
    threads: usize,
    bytes_per_element: usize,
    a: &mut [f32],
    b: &[f32],
    c: &[f32],
    kernel: fn(&mut [f32], &[f32], &[f32]),
) -> f64 {
    let part = a.len().div_ceil(threads);
    let mut best = f64::MAX;
    for _ in 0..5 {
        let start = Instant::now();
        std::thread::scope(|scope| {
            for ((a, b), c) in a.chunks_mut(part).zip(b.chunks(part)).zip(c.chunks(part)) {
                scope.spawn(move || kernel(a, b, c));
            }
        });
        best = best.min(start.elapsed().as_secs_f64());
        black_box(&a[0]);
    }
    (a.len() * bytes_per_element) as f64 / best / 1e9
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    // Under `cargo test --benches` (no `--bench`): a small run that only checks it works.
    let quick = !std::env::args().any(|a| a == "--bench");
    let len = if quick { 1 << 12 } else { 1 << 24 };
    let mut a = vec![0.0f32; len];
    let b: Vec<f32> = (0..len).map(|i| i as f32).collect();
    let c: Vec<f32> = (0..len).map(|i| (i % 7) as f32).collect();
    for threads in [1, 2] {
        let gb_copy = measure(threads, 8, &mut a, &b, &c, |a, b, _| copy(a, b));
        let gb_triad = measure(threads, 12, &mut a, &b, &c, |a, b, c| triad(a, b, c, 3.0));
        println!(
            "{} MiB arrays, {threads} thread(s): copy {gb_copy:.1} GB/s, triad {gb_triad:.1} GB/s",
            (len * 4) >> 20
        );
    }
}
