//! Sums over a particle's neighbours whose bits do not depend on the neighbours' order.
//!
//! A floating-point sum depends on the order of its terms, and the order in which a particle
//! meets its neighbours depends on when its candidate list was built (`super::neighbours`).
//! So each sum here is taken in integers: every lane's terms are scaled by one power of two,
//! chosen from the lane's largest magnitude (a maximum, which no order changes), so that the
//! largest term is below 2²², truncated to `i32` and added exactly. The sum's error is at most
//! one unit of 2⁻²¹ of the largest term per term, a few times what adding them in `f32` costs,
//! and the result is the same for any order of the terms.

/// Lanes summed side by side: the force pass's pressure force, its viscosity force and the
/// viscosity's diagonal, `[fp_x, fp_y, fp_z, D, fv_x, fv_y, fv_z, 0]`; the density uses one.
pub const LANES: usize = 8;

/// The most terms a sum takes: with each below 2²², 512 of them stay below 2³¹.
pub const MAX_TERMS: usize = 512;

/// Below this exponent a lane's terms are scaled as if its largest were 2^`FLOOR` (their
/// scale would overflow `f32`): such a lane is summed in units of 2⁻¹²¹.
const FLOOR: i32 = -100;

/// The exact, order-independent sum of each lane of `terms` (at most [`MAX_TERMS`] rows).
/// A lane with a term that is not finite sums to NaN.
#[must_use]
pub fn lanes(terms: &[[f32; LANES]]) -> [f32; LANES] {
    let terms = &terms[..terms.len().min(MAX_TERMS)];
    let mut largest = [0.0f32; LANES];
    let mut finite = [true; LANES];
    for row in terms {
        for l in 0..LANES {
            largest[l] = largest[l].max(row[l].abs());
            finite[l] &= row[l].is_finite();
        }
    }
    let (scale, unscale) = scales(largest);
    let mut total = [0i32; LANES];
    for row in terms {
        for l in 0..LANES {
            // In range by the scale's choice: |row[l] · scale[l]| < 2²².
            total[l] = total[l].wrapping_add((row[l] * scale[l]) as i32);
        }
    }
    core::array::from_fn(|l| {
        if finite[l] {
            total[l] as f32 * unscale[l]
        } else {
            f32::NAN
        }
    })
}

/// The exact, order-independent sum of `first` and `rest` (at most [`MAX_TERMS`] − 1 of them).
#[must_use]
pub fn one(first: f32, rest: &[f32]) -> f32 {
    let rest = &rest[..rest.len().min(MAX_TERMS - 1)];
    let largest = rest.iter().fold(first.abs(), |m, t| m.max(t.abs()));
    let finite = first.is_finite() && rest.iter().all(|t| t.is_finite());
    if !finite {
        return f32::NAN;
    }
    let exponent = exponent_of(largest);
    let (scale, unscale) = (power_of_two(21 - exponent), power_of_two(exponent - 21));
    let total = rest.iter().fold((first * scale) as i32, |sum, t| {
        sum.wrapping_add((t * scale) as i32)
    });
    total as f32 * unscale
}

/// Per lane, `2^(21 − e)` and `2^(e − 21)`, `e` the exponent of the lane's largest term.
#[inline]
fn scales(largest: [f32; LANES]) -> ([f32; LANES], [f32; LANES]) {
    let exponent = largest.map(exponent_of);
    (
        exponent.map(|e| power_of_two(21 - e)),
        exponent.map(|e| power_of_two(e - 21)),
    )
}

/// `e` with `2^e ≤ x < 2^(e+1)` for a normal `x`, at least [`FLOOR`] (and [`FLOOR`] for zero
/// or a subnormal); 127 for infinity or NaN (the sum is NaN then anyway).
#[inline]
fn exponent_of(x: f32) -> i32 {
    let biased = ((x.to_bits() >> 23) & 0xff) as i32;
    (biased - 127).clamp(FLOOR, 127)
}

/// `2^e` for `e` in −126 ..= 127, exactly.
#[inline]
fn power_of_two(e: i32) -> f32 {
    f32::from_bits(((e.clamp(-126, 127) + 127) as u32) << 23)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random(seed: &mut u32) -> f32 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 17;
        *seed ^= *seed << 5;
        (*seed as f32 / u32::MAX as f32) * 2.0 - 1.0
    }

    #[test]
    fn any_order_gives_the_same_bits_and_the_sum_is_close_to_f64() {
        let mut seed = 0x1234_5678;
        for round in 0..500 {
            let count = 1 + round % 40;
            let magnitude = 10f32.powi((round % 13) as i32 - 6);
            let mut terms: Vec<[f32; LANES]> = (0..count)
                .map(|_| core::array::from_fn(|l| random(&mut seed) * magnitude * (l + 1) as f32))
                .collect();
            let sum = lanes(&terms);
            for l in 0..LANES {
                let exact: f64 = terms.iter().map(|t| f64::from(t[l])).sum();
                let largest = terms.iter().map(|t| t[l].abs()).fold(0.0, f32::max);
                let error = (f64::from(sum[l]) - exact).abs();
                assert!(
                    error <= f64::from(largest) * count as f64 * 5e-7 + exact.abs() * 1e-7,
                    "lane {l}: {} against {exact}",
                    sum[l]
                );
            }
            terms.reverse();
            terms.rotate_left(count / 3);
            assert_eq!(
                lanes(&terms).map(f32::to_bits),
                sum.map(f32::to_bits),
                "round {round}"
            );
            let single: Vec<f32> = terms.iter().map(|t| t[3]).collect();
            let a = one(single[0], &single[1..]);
            let mut shuffled = single.clone();
            shuffled.reverse();
            assert_eq!(a.to_bits(), one(shuffled[0], &shuffled[1..]).to_bits());
        }
    }

    #[test]
    fn zeros_tiny_values_and_non_finite_terms() {
        assert_eq!(lanes(&[]), [0.0; LANES]);
        assert_eq!(one(0.0, &[0.0, -0.0]), 0.0);
        assert_eq!(one(3.0, &[]), 3.0);
        assert_eq!(one(1e-38, &[1e-38]), 0.0, "below 2^-121: nothing");
        let mut row = [1.0f32; LANES];
        row[2] = f32::NAN;
        row[5] = f32::INFINITY;
        let sum = lanes(&[row, [2.0; LANES]]);
        assert_eq!(sum[0], 3.0);
        assert!(sum[2].is_nan() && sum[5].is_nan());
        assert!(one(1.0, &[f32::NEG_INFINITY]).is_nan());
        // 512 terms at the scale's top do not overflow the integers.
        let big = vec![[2f32.powi(100); LANES]; MAX_TERMS];
        assert_eq!(lanes(&big)[0], 2f32.powi(109));
    }
}
