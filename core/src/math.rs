//! Scalars, vectors and the math backend.
//!
//! Every transcendental function and every square root the core evaluates goes through a
//! [`Math`] backend, a zero-sized type chosen per world. That is what makes results the same
//! bits on every target: glam's `Vec3`/`Mat3` are scalar code everywhere (and the workspace
//! turns on glam's `scalar-math`, so `Quat` is too), Rust never contracts `a * b + c` into a
//! fused multiply-add on its own, and the functions below are the only place a platform could
//! differ.
//!
//! * [`Libm`]: the `libm` crate's square root and this module's [`sin_cos`] and [`atan2`] —
//!   bit-identical on x86-64 and thumbv7em.
//! * `FastMath` (feature `micromath`): micromath's approximate trigonometry, still the correctly
//!   rounded square root. micromath's own `sqrt` averages ~5 % error and would break every stretch
//!   bound, so it is never used.
//! * Firmware may implement [`Math`] itself to route `sqrt` to the Cortex-M4F `VSQRT`
//!   instruction: IEEE 754 requires a correctly rounded square root, so it gives the same bits
//!   as `libm::sqrtf` in ~14 cycles instead of a software routine.

pub use glam::{Mat3, Quat, Vec2, Vec3};

/// The simulation's scalar type.
pub type Real = f32;

/// A math backend: a zero-sized type that provides the few non-arithmetic functions the core
/// needs. Implementations must give a correctly rounded `sqrt`.
pub trait Math: Copy + Default + 'static {
    /// Short name for reports and recordings (`"libm"`, `"fast-math"`, …).
    const NAME: &'static str;
    /// Correctly rounded square root (IEEE 754 `squareRoot`).
    fn sqrt(x: Real) -> Real;
    /// `(sin x, cos x)`.
    fn sin_cos(x: Real) -> (Real, Real);
    /// Four-quadrant arctangent of `y / x`.
    fn atan2(y: Real, x: Real) -> Real;

    /// Whether `sin_cos` and `atan2` are this module's [`sin_cos`] and [`atan2`] (plain `f32`
    /// arithmetic): then the lanes take them in their own form (`lane::sin_cos_in_lanes`,
    /// `lane::atan2_in_lanes`, the same bits per lane), which the compiler packs; otherwise
    /// lane by lane. Say `true` only for those two functions.
    const PLAIN_TRIGONOMETRY: bool = false;

    /// Euclidean length of `v`, summed as `x² + y² + z²` left to right.
    #[inline(always)]
    fn length(v: Vec3) -> Real {
        Self::sqrt(v.dot(v))
    }
}

/// The `libm` backend: software functions that give the same bits on every target — libm's
/// square root, and this module's [`sin_cos`] and [`atan2`] (plain `f32` arithmetic, cheaper
/// than libm's and as deterministic).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Libm;

impl Math for Libm {
    const NAME: &'static str = "libm";
    const PLAIN_TRIGONOMETRY: bool = true;
    #[inline(always)]
    fn sqrt(x: Real) -> Real {
        libm::sqrtf(x)
    }
    #[inline(always)]
    fn sin_cos(x: Real) -> (Real, Real) {
        sin_cos(x)
    }
    #[inline(always)]
    fn atan2(y: Real, x: Real) -> Real {
        atan2(y, x)
    }
}

/// micromath's approximate trigonometry (a few 1e-3 absolute error), `libm`'s correctly
/// rounded square root. Deterministic too — micromath is plain arithmetic — but its results
/// differ from [`Libm`]'s, so it has golden hashes of its own.
#[cfg(feature = "micromath")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FastMath;

#[cfg(feature = "micromath")]
impl Math for FastMath {
    const NAME: &'static str = "fast-math";
    #[inline(always)]
    fn sqrt(x: Real) -> Real {
        libm::sqrtf(x)
    }
    #[inline(always)]
    fn sin_cos(x: Real) -> (Real, Real) {
        let (s, c) = micromath::F32(x).sin_cos();
        (s.0, c.0)
    }
    #[inline(always)]
    fn atan2(y: Real, x: Real) -> Real {
        micromath::F32(y).atan2(micromath::F32(x)).0
    }
}

/// The backend a world uses unless it names another: [`Libm`], or `FastMath` when the final
/// binary turns on the `fast-math` feature.
#[cfg(not(feature = "fast-math"))]
pub type DefaultMath = Libm;
/// The backend a world uses unless it names another.
#[cfg(feature = "fast-math")]
pub type DefaultMath = FastMath;

/// A `Vec3` formatted for defmt as `[x, y, z]` (glam does not implement `defmt::Format`).
#[cfg(feature = "defmt")]
#[derive(Clone, Copy)]
pub struct DefmtVec3(pub Vec3);

#[cfg(feature = "defmt")]
impl defmt::Format for DefmtVec3 {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(f, "[{}, {}, {}]", self.0.x, self.0.y, self.0.z)
    }
}

/// `true` when every component of `v` is finite.
#[inline(always)]
pub fn is_finite(v: Vec3) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

/// `f32::max` by compares: the larger of `a` and `b`, the other where one is NaN, `a` on a
/// tie. The same value as `a.max(b)` but for the sign of a zero, by two compares where
/// `f32::max` is a call to `fmaxf` on the Cortex-M4F, which has no `VMAXNM`.
#[inline(always)]
#[must_use]
pub fn max(a: Real, b: Real) -> Real {
    if b > a || a.is_nan() {
        b
    } else {
        a
    }
}

/// `v / |v|` as `v · (1/|v|)`, with the backend's square root.
#[inline]
#[must_use]
pub fn unit<M: Math>(v: Vec3) -> Vec3 {
    v * (1.0 / M::length(v))
}

/// `π/2` in three parts for [`sin_cos`]'s reduction (fdlibm's `pio2_1`, `pio2_2`, `pio2_2t`):
/// the first two carry 17 significant bits, so `n · part` is exact for `|n| ≤ 2^7`.
pub(crate) const FRAC_PI_2_PARTS: [Real; 3] = [1.570_785_5, 1.080_427_3e-5, 6.077_1e-11];
/// Largest `|x|` [`sin_cos`] reduces itself: `2^7 · π/2`.
pub(crate) const SIN_COS_REDUCED: Real = 201.0;
/// `sin r = r + r z (s₀ + z (s₁ + z s₂))` and `cos r = 1 − z/2 + z² (c₀ + z (c₁ + z c₂))` with
/// `z = r²` on `[−π/4, π/4]`: Cephes' `sinf` and `cosf` fits.
pub(crate) const SIN_COEFFICIENTS: [Real; 3] = [-1.666_665_5e-1, 8.332_161e-3, -1.951_529_6e-4];
pub(crate) const COS_COEFFICIENTS: [Real; 3] = [4.166_664_6e-2, -1.388_731_6e-3, 2.443_315_7e-5];

/// `(sin x, cos x)` in plain `f32` `+ − × ÷` (no fused multiply-add, no table, no `f64`), so
/// the same bits on every target without a libm call: libm's `sincosf` works in `f64`, which a
/// Cortex-M4F runs in software, a few hundred to two thousand instructions a call for angles
/// away from zero (the step takes one per segment for the material frame).
///
/// `x = n π/2 + r` with `|r| ≤ π/4` (Cody–Waite, `π/2` in three parts, exact for
/// `|x| ≤ 201`), then the fits of [`SIN_COEFFICIENTS`] and [`COS_COEFFICIENTS`] and the
/// quadrant `n mod 4`. Larger or non-finite `x` go to libm's `sincosf` (deterministic too).
/// Accuracy: within 1.2e-7 of the exact values for `|x| ≤ 201` (measured 9.5e-8 against
/// `f64`; libm's `sincosf` is within an ulp, 6e-8 near ±1).
#[inline]
#[must_use]
pub fn sin_cos(x: Real) -> (Real, Real) {
    if x.is_nan() || x.abs() > SIN_COS_REDUCED {
        return libm::sincosf(x);
    }
    // C's `sin(±0) = ±0` (the fit's `r + r z p` would round −0 to +0).
    if x == 0.0 {
        return (x, 1.0);
    }
    // n = round(x · 2/π): `as` truncates towards zero, exactly on every target.
    let q = x * core::f32::consts::FRAC_2_PI;
    let n = (if q < 0.0 { q - 0.5 } else { q + 0.5 }) as i32;
    let m = n as Real;
    let [p0, p1, p2] = FRAC_PI_2_PARTS;
    let r = ((x - m * p0) - m * p1) - m * p2;
    let z = r * r;
    let [s0, s1, s2] = SIN_COEFFICIENTS;
    let [c0, c1, c2] = COS_COEFFICIENTS;
    let sin = r + r * z * (s0 + z * (s1 + z * s2));
    let cos = (1.0 - 0.5 * z) + z * z * (c0 + z * (c1 + z * c2));
    // The quadrant by selects, not a jump: along a twisted strand it changes from segment to
    // segment, which a branch predictor cannot follow. An odd `n` turns `(sin, cos)` by π/2
    // into `(cos, −sin)`, and `n & 2` by π more, negating both (the `match` on `n & 3` it
    // replaces gave the same values).
    let odd = n & 1 != 0;
    let (sin, cos) = (if odd { cos } else { sin }, if odd { -sin } else { cos });
    let half_turn = n & 2 != 0;
    let (sin, cos) = (
        if half_turn { -sin } else { sin },
        if half_turn { -cos } else { cos },
    );
    (sin, cos)
}

/// `atan(t) / t = Σ a_k u^k` with `u = t² ∈ [0, 1]`, lowest power first: a Chebyshev fit of
/// degree 8, rounded to f32 (in f32 its error is about 1e-7 rad for `t ∈ [0, 1]`).
pub(crate) const ATAN_COEFFICIENTS: [Real; 9] = [
    1.0,
    -0.333_330_36,
    0.199_918_72,
    -0.141_977_98,
    0.106_183_71,
    -0.074_568_55,
    0.042_137_623,
    -0.015_731_249,
    0.002_766_283_5,
];

/// Four-quadrant arctangent of `y / x` in plain `+ − × ÷` (one division, no fused
/// multiply-add, no table), so the same bits on every target without a libm call: the
/// hair-optimised twist takes one per segment, and libm's `atan2f` was 28 % of its time.
///
/// Accuracy: within 3.2e-7 rad of the exact angle for finite arguments (measured 3.07e-7:
/// the polynomial's 1e-7, the rounding of `π/2 − a` and `π − a`, and f32's π, 8.7e-8 short);
/// libm's is within an ulp, 2.4e-7 rad near ±π. The signs of zeros follow C's `atan2`
/// (`atan2(±0, −0) = ±π`); infinite `x` with finite `y` gives `0` or `±π`, two infinite
/// arguments NaN, and NaN gives NaN.
#[inline]
#[must_use]
pub fn atan2(y: Real, x: Real) -> Real {
    let (ax, ay) = (x.abs(), y.abs());
    // atan(ay/ax) with the ratio in [0, 1]; above the diagonal, π/2 − atan(ax/ay).
    let steep = ay > ax;
    let (numerator, denominator) = if steep { (ax, ay) } else { (ay, ax) };
    let t = if denominator == 0.0 {
        0.0
    } else {
        numerator / denominator
    };
    // Estrin's scheme, not Horner's: the same polynomial in four dependent steps after `u`
    // instead of eight, which the sweep's independent segments then overlap.
    let a = &ATAN_COEFFICIENTS;
    let u = t * t;
    let u2 = u * u;
    let pairs = [
        a[0] + a[1] * u,
        a[2] + a[3] * u,
        a[4] + a[5] * u,
        a[6] + a[7] * u,
    ];
    let u4 = u2 * u2;
    let quads = [pairs[0] + pairs[1] * u2, pairs[2] + pairs[3] * u2];
    let p = (quads[0] + quads[1] * u4) + a[8] * (u4 * u4);
    let mut angle = t * p;
    if steep {
        angle = core::f32::consts::FRAC_PI_2 - angle;
    }
    if x.is_sign_negative() {
        angle = core::f32::consts::PI - angle;
    }
    if y.is_sign_negative() {
        -angle
    } else {
        angle
    }
}

/// Rotates `v` by the unit quaternion `q` with scalar code written out here, so the order of
/// every sum is fixed on every target (glam's SSE2 quaternion code sums in another order).
#[inline(always)]
pub fn rotate(q: Quat, v: Vec3) -> Vec3 {
    // v' = v + 2w (u × v) + 2 u × (u × v), u = (x, y, z)
    let u = Vec3::new(q.x, q.y, q.z);
    let uv = u.cross(v);
    let uuv = u.cross(uv);
    v + (uv * q.w + uuv) * 2.0
}

/// Hamilton product `a · b` written out in scalar code (see [`rotate`]).
#[inline(always)]
pub fn quat_mul(a: Quat, b: Quat) -> Quat {
    Quat::from_xyzw(
        a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
        a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
        a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
        a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
    )
}

/// Conjugate (the inverse of a unit quaternion).
#[inline(always)]
pub fn quat_conjugate(q: Quat) -> Quat {
    Quat::from_xyzw(-q.x, -q.y, -q.z, q.w)
}

/// Renormalises `q` with the backend's square root; identity if `q` is zero or not finite.
#[inline(always)]
pub fn quat_normalize<M: Math>(q: Quat) -> Quat {
    let n2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
    if n2 > 0.0 && n2.is_finite() {
        let inv = 1.0 / M::sqrt(n2);
        Quat::from_xyzw(q.x * inv, q.y * inv, q.z * inv, q.w * inv)
    } else {
        Quat::IDENTITY
    }
}

/// Unit quaternion for a rotation of `angle` radians about the unit vector `axis`.
#[inline(always)]
pub fn quat_from_axis_angle<M: Math>(axis: Vec3, angle: Real) -> Quat {
    let (s, c) = M::sin_cos(0.5 * angle);
    Quat::from_xyzw(axis.x * s, axis.y * s, axis.z * s, c)
}

/// Minimal rotation (no twist) taking the unit vector `a` to the unit vector `b`, not yet
/// normalised: `(w, xyz) = (1 + a·b, a × b)` has norm `√(2(1 + a·b))`. Callers normalise the
/// product they build with it once (DFTL frame transport), saving a square root per node.
#[inline(always)]
pub fn quat_between_unnormalized(a: Vec3, b: Vec3) -> Quat {
    let c = a.cross(b);
    Quat::from_xyzw(c.x, c.y, c.z, 1.0 + a.dot(b))
}

/// Set-up only (never per step): a shape constraint's per-step fraction `s_ref`, given at the
/// step `reference_dt` (Sánchez-Banderas 2015 give `s_g`, `s_l` at 16 ms), rescaled to the
/// step `dt` so that the constraint is the same *spring* at every step.
///
/// A position-based constraint pulled a fraction `s` of the way each step, with velocities
/// taken from the positions, is a spring of stiffness `s/Δt²` per unit mass. We keep that
/// stiffness, as XPBD does (Macklin, Müller, Chentanez 2016: compliance `α`, `α̃ = α/Δt²`,
/// `s = 1/(1 + α̃)`): `α = Δt_ref² (1 − s_ref)/s_ref` and `s(Δt) = Δt²/(Δt² + α)`, which gives
/// `s_ref` back at `Δt_ref`.
///
/// This departs from the rule `1 − (1 − s_ref)^{Δt/Δt_ref}`, which keeps the relaxation
/// time instead: its `s` shrinks only like `Δt`, so the spring stiffens like `1/Δt`, and the
/// one-sided local constraint (node `i + 1` pulled into node `i`'s frame, no reaction) then
/// flutters as `Δt` shrinks — 78 m/s at Δt = 10 µs, 13 m/s at 0.1 ms on a shaking head
/// (`tests/torture.rs`), where this form stays under 1 m/s at every step from 10 µs to 1 ms,
/// and a styled strand's response to a push is the same curve at every step
/// (`tests/dftl.rs`, `shape_response_does_not_depend_on_the_time_step`).
#[must_use]
pub fn relaxation_at_step(s_ref: Real, dt: Real, reference_dt: Real) -> Real {
    if s_ref >= 1.0 {
        // Full projection every step, whatever the step: (1 − 1)^x = 0.
        return 1.0;
    }
    if s_ref <= 0.0 || s_ref.is_nan() {
        return 0.0;
    }
    let compliance = reference_dt * reference_dt * (1.0 - s_ref) / s_ref;
    let dt2 = dt * dt;
    dt2 / (dt2 + compliance)
}

/// The step whose projection's dissipation the DFTL shape damping keeps: Sánchez-Banderas
/// 2015's 60 Hz, the rate at which DFTL with shape holds a groom.
pub const SHAPE_DAMPING_REFERENCE_DT: Real = 1.0 / 60.0;

/// Set-up only (never per step): the per-step velocity retention `r` of DFTL's shape damping
/// at the step `dt`, for the shape fractions `global_ref`, `local_ref` given at
/// `reference_dt` ([`relaxation_at_step`] rescales them).
///
/// A node pulled a fraction `s` of the way to a target each step, its velocity taken from its
/// positions, oscillates about the target with its amplitude multiplied by `√(1 − s)` per
/// step: the projection dissipates at the rate `c(s, Δt) = −ln(1 − s)/(2Δt)`. With the spring
/// rule `s` shrinks like `Δt²`, so at 1 ms the projections dissipate a tenth of what they do at
/// 60 Hz (defaults: 3.3 and 11 s⁻¹ against 31 and 59 s⁻¹), and a groom that holds at 60 Hz
/// rings at 1 kHz. The shape damping adds, per constraint, what is missing against
/// [`SHAPE_DAMPING_REFERENCE_DT`]: `c = Σ max(0, c(s(Δt_60), Δt_60) − c(s(Δt), Δt))`, as a
/// velocity retention `r = e^{−c Δt}`, and 1 at and above 60 Hz: SB15's step and longer ones
/// are left as the paper has them.
#[must_use]
pub fn shape_damping_retention(
    global_ref: Real,
    local_ref: Real,
    reference_dt: Real,
    dt: Real,
) -> Real {
    let h = SHAPE_DAMPING_REFERENCE_DT;
    if dt.is_nan() || dt >= h {
        // SB15's step and longer ones are left as the paper has them.
        return 1.0;
    }
    let dissipation = |s: Real, step: Real| {
        let kept = 1.0 - s.clamp(0.0, 1.0 - Real::EPSILON);
        -libm::logf(kept) / (2.0 * step)
    };
    let deficit = |s_ref: Real| {
        let reference = dissipation(relaxation_at_step(s_ref, h, reference_dt), h);
        let now = dissipation(relaxation_at_step(s_ref, dt, reference_dt), dt);
        (reference - now).max(0.0)
    };
    let rate = deficit(global_ref) + deficit(local_ref);
    if rate.is_finite() && dt > 0.0 {
        libm::expf(-rate * dt).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atan2_is_within_its_stated_accuracy_in_every_quadrant() {
        let mut worst: f64 = 0.0;
        for k in 0..=200_000 {
            let phi = -core::f64::consts::PI + core::f64::consts::TAU * f64::from(k) / 200_000.0;
            for radius in [1.0e-30_f64, 3.0e-3, 1.0, 7.0e4] {
                let (y, x) = ((radius * phi.sin()) as f32, (radius * phi.cos()) as f32);
                let exact = f64::from(y).atan2(f64::from(x));
                let mut error = (f64::from(atan2(y, x)) - exact).abs();
                // ±π are the same direction.
                error = error.min((error - core::f64::consts::TAU).abs());
                worst = worst.max(error);
            }
        }
        assert!(worst <= 3.2e-7, "worst error {worst:e} rad");
        // C's zeros and the axes.
        assert_eq!(atan2(0.0, 0.0).to_bits(), 0.0_f32.to_bits());
        assert_eq!(atan2(-0.0, 0.0).to_bits(), (-0.0_f32).to_bits());
        assert_eq!(atan2(0.0, -0.0), core::f32::consts::PI);
        assert_eq!(atan2(-0.0, -0.0), -core::f32::consts::PI);
        assert_eq!(atan2(1.0, 0.0), core::f32::consts::FRAC_PI_2);
        assert_eq!(atan2(-2.0, 0.0), -core::f32::consts::FRAC_PI_2);
        assert_eq!(atan2(3.0, f32::INFINITY), 0.0);
        assert_eq!(atan2(3.0, f32::NEG_INFINITY), core::f32::consts::PI);
        assert!(atan2(f32::NAN, 1.0).is_nan() && atan2(1.0, f32::NAN).is_nan());
    }

    #[test]
    fn sin_cos_is_within_its_stated_accuracy() {
        let mut worst: f64 = 0.0;
        let mut check = |x: f32| {
            let (s, c) = sin_cos(x);
            let x = f64::from(x);
            worst = worst.max((f64::from(s) - x.sin()).abs());
            worst = worst.max((f64::from(c) - x.cos()).abs());
        };
        for k in -2_000_000..=2_000_000 {
            check(k as f32 * 1.0e-4);
        }
        for k in -200_000..=200_000 {
            check(k as f32 * 1.0e-3 + 0.000_37);
        }
        // Near the quadrants' edges, where the reduction cancels.
        for q in -128..=128 {
            let edge = q as f32 * core::f32::consts::FRAC_PI_2;
            let mut x = edge;
            for _ in 0..64 {
                check(x);
                x = f32::from_bits(x.to_bits() + 1);
            }
        }
        assert!(worst <= 1.2e-7, "worst error {worst:e}");
        // Zeros keep their sign; beyond the reduced range and non-finite: libm's.
        assert_eq!(sin_cos(0.0).0.to_bits(), 0.0_f32.to_bits());
        assert_eq!(sin_cos(-0.0).0.to_bits(), (-0.0_f32).to_bits());
        assert_eq!(sin_cos(0.0).1, 1.0);
        for x in [250.0, -1.0e6, 3.0e30] {
            let ((s, c), (ls, lc)) = (sin_cos(x), libm::sincosf(x));
            assert_eq!((s.to_bits(), c.to_bits()), (ls.to_bits(), lc.to_bits()));
        }
        let (s, c) = sin_cos(f32::NAN);
        assert!(s.is_nan() && c.is_nan());
        assert!(sin_cos(f32::INFINITY).0.is_nan());
    }

    #[test]
    fn libm_sqrt_is_correctly_rounded_like_the_hardware() {
        // The FPU's sqrt is correctly rounded; so must the backend be, bit for bit.
        let mut x = 1.0e-30_f32;
        while x < 1.0e30 {
            assert_eq!(Libm::sqrt(x).to_bits(), x.sqrt().to_bits(), "x = {x:e}");
            x *= 1.0007;
        }
    }

    #[test]
    fn rotate_matches_glam_rotation() {
        let q = quat_from_axis_angle::<Libm>(Vec3::new(0.0, 0.6, 0.8), 1.1);
        let v = Vec3::new(0.3, -1.2, 2.0);
        assert!((rotate(q, v) - q * v).length() < 1e-6);
        let p = quat_mul(q, quat_conjugate(q));
        assert!((p.w - 1.0).abs() < 1e-6 && p.x.abs() < 1e-6);
    }

    #[test]
    fn shape_fraction_keeps_the_spring_stiffness() {
        // At the reference step the fraction is the one given.
        assert!((relaxation_at_step(0.3, 0.016, 0.016) - 0.3).abs() < 1e-6);
        assert!((relaxation_at_step(0.1, 0.016, 0.016) - 0.1).abs() < 1e-6);
        // The spring s/Δt² is the same at small steps: 0.3 at 16 ms → 1.67e-3 at 1 ms.
        let stiffness = |dt: Real| relaxation_at_step(0.3, dt, 0.016) / (dt * dt);
        let reference = 0.3 / (0.7 * 0.016 * 0.016);
        for dt in [1.0e-5, 1.0e-4, 1.0e-3] {
            assert!(
                (stiffness(dt) / reference - 1.0).abs() < 0.07,
                "{dt}: {}",
                stiffness(dt)
            );
        }
        // Larger steps stay below a full projection.
        assert!(relaxation_at_step(0.3, 1.0, 0.016) < 1.0);
        assert_eq!(relaxation_at_step(1.0, 0.001, 0.016), 1.0);
        assert_eq!(relaxation_at_step(0.0, 0.001, 0.016), 0.0);
    }

    #[test]
    fn minimal_rotation_takes_a_to_b() {
        let a = Vec3::new(0.0, 0.6, 0.8);
        let b = Vec3::new(1.0, 0.0, 0.0);
        let q = quat_normalize::<Libm>(quat_between_unnormalized(a, b));
        assert!((rotate(q, a) - b).length() < 1e-6);
        // Twist-free: the common normal a × b is left alone.
        let n = a.cross(b).normalize();
        assert!((rotate(q, n) - n).length() < 1e-6);
    }

    #[cfg(feature = "micromath")]
    #[test]
    fn fast_math_is_close_to_libm() {
        for i in -100..100 {
            let x = i as f32 * 0.0625;
            let (s, c) = FastMath::sin_cos(x);
            let (ls, lc) = Libm::sin_cos(x);
            assert!((s - ls).abs() < 5e-3 && (c - lc).abs() < 5e-3, "x = {x}");
        }
    }
}
