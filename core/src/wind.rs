//! Wind: an external acceleration that changes with time, `a(t) = direction · strength ·
//! (1 + gust · n(t))`, uniform in space, evaluated once per step by the step context (at the
//! step's end time) and added where the solvers add gravity. The gust noise
//! `n(t)` is a seeded value noise: a 32-bit integer hash of the seed and the integer time cell
//! gives a value in `[−1, 1]` per cell, smoothstep-interpolated between cells, plus a second
//! octave at 2.3× the frequency and half the amplitude. Integer hashing and `+ − ×` only: no
//! `rand`, no std, the same bits on every target.

use crate::math::{Real, Vec3};
use crate::params::WindParams;

/// The wind's acceleration at time `t`, s.
#[must_use]
pub fn wind_acceleration(wind: &WindParams, t: Real) -> Vec3 {
    let u = t * wind.gust_frequency;
    // Octave weights sum to 1 so |n| ≤ 1.
    let n = (2.0 / 3.0) * value_noise(wind.seed, u)
        + (1.0 / 3.0) * value_noise(wind.seed ^ 0x9E37_79B9, 2.3 * u);
    wind.direction * (wind.strength * (1.0 + wind.gust * n))
}

/// Smooth value noise of `u` in `[−1, 1]`: hashed values at integer `u`, smoothstep between.
#[must_use]
pub fn value_noise(seed: u32, u: Real) -> Real {
    // Integer cell below u; `as i64` truncates towards zero and saturates, so step down for
    // negative non-integers. Same bits everywhere: no floor from the platform.
    let truncated = u as i64;
    let cell = if (truncated as Real) > u {
        truncated - 1
    } else {
        truncated
    };
    let f = u - cell as Real;
    let s = f * f * (3.0 - 2.0 * f);
    let a = lattice_value(seed, cell);
    let b = lattice_value(seed, cell.wrapping_add(1));
    a + (b - a) * s
}

/// The value at integer time cell `cell`, uniform in `[−1, 1)`.
fn lattice_value(seed: u32, cell: i64) -> Real {
    let h = hash32(seed ^ hash32(cell as u32 ^ hash32((cell >> 32) as u32)));
    // The top 24 bits are exact in an f32.
    (h >> 8) as Real * (2.0 / 16_777_216.0) - 1.0
}

/// A 32-bit integer hash with good avalanche ("lowbias32", C. Wellons).
#[must_use]
pub fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    #[test]
    fn noise_is_bounded_continuous_and_varies() {
        let mut previous = value_noise(7, -3.0);
        let (mut lo, mut hi) = (Real::MAX, Real::MIN);
        for i in 1..20_000 {
            let u = -3.0 + i as Real * 1e-3;
            let n = value_noise(7, u);
            assert!((-1.0..=1.0).contains(&n));
            // Smoothstep of values in [−1, 1]: slope ≤ 1.5 · 2 per unit of u.
            assert!((n - previous).abs() <= 3.0e-3 + 1e-6, "u = {u}");
            previous = n;
            lo = lo.min(n);
            hi = hi.max(n);
        }
        assert!(hi - lo > 0.5, "the noise hardly moves: {lo}..{hi}");
        assert_ne!(value_noise(7, 0.5), value_noise(8, 0.5));
    }

    #[test]
    fn wind_is_steady_without_gusts_and_seeded_with_them() {
        let steady = WindParams {
            gust: 0.0,
            ..Params::DEFAULT.wind
        };
        assert_eq!(wind_acceleration(&steady, 1.234), Vec3::new(2.0, 0.0, 0.0));
        let gusty = Params::DEFAULT.wind;
        let a = wind_acceleration(&gusty, 0.7);
        assert_eq!(a, wind_acceleration(&gusty, 0.7));
        assert!(a.x >= 1.0 && a.x <= 3.0 && a.y == 0.0);
        assert_ne!(a, wind_acceleration(&gusty, 1.9));
    }
}
