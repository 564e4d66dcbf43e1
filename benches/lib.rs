//! Shared helpers for the benchmarks.

/// CPU seconds this process has used so far (user + system), from Linux `/proc/self/stat`
/// (10 ms ticks; 0 where the file is missing). For benches that report throughput per
/// CPU-second on a shared machine, where wall-clock figures are noisy.
#[must_use]
pub fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

/// Sánchez-Banderas 2015 Table 1's scenes (the `sph` bench and the SPH comparison example).
pub mod table1;

/// Kmoch 2009 Table 3's scene (the `rod_projection` bench and its instruction-count example).
pub mod table3;
