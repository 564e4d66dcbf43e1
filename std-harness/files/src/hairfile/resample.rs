//! Arc-length resampling of polylines.

use hairsim_core::Vec3;

/// Length of a polyline: the sum of its segment lengths.
#[must_use]
pub fn polyline_length(points: &[Vec3]) -> f32 {
    points.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// `nodes` points evenly spaced by arc length along `points`, the first at the root and the last
/// at the tip (both kept exactly). A polyline of zero length gives `nodes` copies of its root;
/// an empty one gives an empty result; `nodes < 2` gives the root alone (or nothing).
#[must_use]
pub fn resample_polyline(points: &[Vec3], nodes: usize) -> Vec<Vec3> {
    let (Some(&root), Some(&tip)) = (points.first(), points.last()) else {
        return Vec::new();
    };
    if nodes < 2 {
        return vec![root; nodes];
    }
    let total = polyline_length(points);
    if total <= 0.0 || !total.is_finite() {
        return vec![root; nodes];
    }
    let mut out = Vec::with_capacity(nodes);
    out.push(root);
    // Walk the segments once; `walked` is the arc length at the start of segment `seg`.
    let mut seg = 0;
    let mut walked = 0.0f32;
    for k in 1..nodes - 1 {
        let target = total * (k as f32 / (nodes - 1) as f32);
        while seg + 2 < points.len() && walked + points[seg].distance(points[seg + 1]) < target {
            walked += points[seg].distance(points[seg + 1]);
            seg += 1;
        }
        let (a, b) = (points[seg], points[seg + 1]);
        let length = a.distance(b);
        let t = if length > 0.0 {
            ((target - walked) / length).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(a.lerp(b, t));
    }
    out.push(tip);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_a_bent_line_spaces_nodes_evenly_along_it() {
        // An L: 3 along X then 1 along Y, total 4; 5 nodes → spacing 1.
        let l = [
            Vec3::ZERO,
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(3.0, 1.0, 0.0),
        ];
        let r = resample_polyline(&l, 5);
        assert_eq!(r.len(), 5);
        let expected = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(3.0, 1.0, 0.0),
        ];
        for (got, want) in r.iter().zip(expected) {
            assert!(got.distance(want) < 1e-6, "{got} vs {want}");
        }
        assert!((polyline_length(&r) - 4.0).abs() < 1e-6);
    }

    #[test]
    fn resampling_keeps_root_and_tip_and_handles_degenerate_input() {
        let pts: Vec<Vec3> = (0..7)
            .map(|i| Vec3::new((i as f32 * 0.7).sin(), i as f32, 0.0))
            .collect();
        for n in [2, 3, 16, 64] {
            let r = resample_polyline(&pts, n);
            assert_eq!(r.len(), n);
            assert_eq!(r[0], pts[0]);
            assert_eq!(r[n - 1], pts[6]);
            // Spacing is even to float precision.
            let d: Vec<f32> = r.windows(2).map(|w| w[0].distance(w[1])).collect();
            let (lo, hi) = d
                .iter()
                .fold((f32::MAX, 0.0f32), |(a, b), &x| (a.min(x), b.max(x)));
            // Chords on a bent line are shorter than arcs; the bend here is mild.
            assert!(hi - lo < 0.1 * hi, "uneven spacing {lo}..{hi} at n={n}");
        }
        assert!(resample_polyline(&[], 4).is_empty());
        assert_eq!(
            resample_polyline(&[Vec3::ONE, Vec3::ONE], 3),
            vec![Vec3::ONE; 3]
        );
    }
}
