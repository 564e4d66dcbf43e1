//! The arithmetic the rod's frame and energy kernels are written in.
//!
//! The kernels are generic over a [`Precision`]: every [`Math`] backend is one (`f32`, glam
//! `Vec3`, the backend's `sqrt`/`sin_cos`/`atan2`), which is what the step runs; [`F64`] is the
//! same code in `f64` (`DVec3`, `libm`'s double functions). Finite-difference tests of forces
//! and Hessians need it: in `f32` a central difference stalls near 1e-3 relative error, in
//! `f64` it reaches 1e-7, so a sign or factor error cannot hide in the noise.
//!
//! Only the operations the kernels use are in the traits; glam's inherent methods of the same
//! names (`dot`, `cross`) sum left to right in scalar code on every target.

use core::fmt::Debug;
use core::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, MulAssign, Neg, Not, Sub, SubAssign};

use glam::DVec3;

use crate::math::{Math, Real, Vec3};

/// The arithmetic a kernel is written in: a scalar (`f32`, `f64`) or `W` lanes of `f32`, one
/// strand per lane (`lane::Wide`). Only `+ − × ÷`, constants, and comparisons that give a
/// mask; a branch on a value becomes [`Arithmetic::select`], so the same kernel runs one
/// strand or a block and gives each lane the bits it gives that strand alone.
pub trait Arithmetic:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + 'static
{
    /// One boolean per lane (`bool` for a scalar).
    type Mask: Copy
        + BitAnd<Output = Self::Mask>
        + BitOr<Output = Self::Mask>
        + Not<Output = Self::Mask>;
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// The machine epsilon: the gap between 1 and the next value.
    const EPSILON: Self;
    /// The `f32` value `x` (exact), in every lane.
    fn of(x: f32) -> Self;
    /// `self < other`, per lane (false where either is NaN).
    fn lt(self, other: Self) -> Self::Mask;
    /// `self ≤ other`, per lane (false where either is NaN).
    fn le(self, other: Self) -> Self::Mask;
    /// Whether each lane is finite.
    fn finite(self) -> Self::Mask;
    /// `|x|` per lane.
    fn magnitude(self) -> Self;
    /// `low < self < high`, per lane (false where any is NaN). For a scalar the second
    /// comparison is skipped when the first fails: a branch, where `lt(…) & lt(…)` made the
    /// Cortex-M4F materialise both flags (1.7 % of the rod's step, QEMU, 32 nodes).
    fn between(self, low: Self, high: Self) -> Self::Mask;
    /// Per lane `if mask { a } else { b }`.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// `value` in every lane.
    fn mask(value: bool) -> Self::Mask;
    /// Whether any lane of `mask` is set: only to skip work no lane selects, never to change
    /// a lane's result.
    fn any(mask: Self::Mask) -> bool;
    /// Whether every lane of `mask` is set (as [`Arithmetic::any`], only to skip a select).
    fn all(mask: Self::Mask) -> bool;
}

macro_rules! scalar_arithmetic {
    ($ty:ty) => {
        impl Arithmetic for $ty {
            type Mask = bool;
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const EPSILON: Self = <$ty>::EPSILON;
            #[inline(always)]
            fn of(x: f32) -> Self {
                x.into()
            }
            #[inline(always)]
            fn magnitude(self) -> Self {
                Scalar::abs(self)
            }
            #[inline(always)]
            fn lt(self, other: Self) -> bool {
                self < other
            }
            #[inline(always)]
            fn le(self, other: Self) -> bool {
                self <= other
            }
            #[inline(always)]
            fn finite(self) -> bool {
                self.is_finite()
            }
            #[inline(always)]
            fn between(self, low: Self, high: Self) -> bool {
                low < self && self < high
            }
            #[inline(always)]
            fn select(mask: bool, a: Self, b: Self) -> Self {
                if mask {
                    a
                } else {
                    b
                }
            }
            #[inline(always)]
            fn mask(value: bool) -> bool {
                value
            }
            #[inline(always)]
            fn any(mask: bool) -> bool {
                mask
            }
            #[inline(always)]
            fn all(mask: bool) -> bool {
                mask
            }
        }
    };
}
scalar_arithmetic!(f32);
scalar_arithmetic!(f64);

/// `if mask { a } else { b }` for a value made of several parts, `blend` choosing lane by lane
/// where the lanes disagree: for a scalar one branch, which the Cortex-M4F takes for less than
/// selecting each part (the hair-optimised sweep's choices cost 3 % of the rod's step more
/// as selects).
#[inline(always)]
pub fn select_whole<R: Arithmetic, T>(
    mask: R::Mask,
    a: T,
    b: T,
    blend: impl FnOnce(R::Mask, T, T) -> T,
) -> T {
    if R::all(mask) {
        a
    } else if R::any(mask) {
        blend(mask, a, b)
    } else {
        b
    }
}

/// A floating-point scalar: `f32` or `f64`.
pub trait Scalar: Arithmetic<Mask = bool> + Default + PartialOrd {
    /// π.
    const PI: Self;
    /// 1/π.
    const FRAC_1_PI: Self;
    /// The value rounded to `f32`.
    fn to_f32(self) -> f32;
    /// `|x|`.
    fn abs(self) -> Self;
    /// Largest integer `≤ x` (exact, the same bits on every target) for `|x| < 2³¹`; the
    /// kernels only floor angle ratios. Plain conversions, no libm call.
    fn floor(self) -> Self;
    /// [`Scalar::floor`] and whether that integer is odd, read from the integer itself (a
    /// second floor of `k/2` would sit on the hair-optimised twist's sequential chain).
    fn floor_and_parity(self) -> (Self, bool);
    /// Whether the value is neither infinite nor NaN.
    fn is_finite(self) -> bool;
}

impl Scalar for f32 {
    const PI: Self = core::f32::consts::PI;
    const FRAC_1_PI: Self = core::f32::consts::FRAC_1_PI;
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self
    }
    #[inline(always)]
    fn abs(self) -> Self {
        libm::fabsf(self)
    }
    #[inline(always)]
    fn floor(self) -> Self {
        let truncated = self as i32 as f32;
        if truncated > self {
            truncated - 1.0
        } else {
            truncated
        }
    }
    #[inline(always)]
    fn floor_and_parity(self) -> (Self, bool) {
        let truncated = self as i32;
        let k = if truncated as f32 > self {
            truncated.saturating_sub(1)
        } else {
            truncated
        };
        (k as f32, k & 1 != 0)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
}

impl Scalar for f64 {
    const PI: Self = core::f64::consts::PI;
    const FRAC_1_PI: Self = core::f64::consts::FRAC_1_PI;
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self as f32
    }
    #[inline(always)]
    fn abs(self) -> Self {
        libm::fabs(self)
    }
    #[inline(always)]
    fn floor(self) -> Self {
        let truncated = self as i64 as f64;
        if truncated > self {
            truncated - 1.0
        } else {
            truncated
        }
    }
    #[inline(always)]
    fn floor_and_parity(self) -> (Self, bool) {
        let truncated = self as i64;
        let k = if truncated as f64 > self {
            truncated.saturating_sub(1)
        } else {
            truncated
        };
        (k as f64, k & 1 != 0)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

/// A 3-vector over the arithmetic `R`: glam's `Vec3` or `DVec3`, or `lane::V3` of lanes.
pub trait Vector<R: Arithmetic>:
    Copy
    + Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Neg<Output = Self>
    + Mul<R, Output = Self>
    + AddAssign
    + SubAssign
    + 'static
{
    /// The zero vector.
    const ZERO: Self;
    /// `x + y + z` products summed left to right.
    fn dot(self, other: Self) -> R;
    /// The cross product.
    fn cross(self, other: Self) -> Self;
    /// Per lane `if mask { a } else { b }`.
    fn select(mask: R::Mask, a: Self, b: Self) -> Self;
    /// `[x, y, z]`.
    fn components(self) -> [R; 3];
    /// The vector `[x, y, z]`.
    fn from_components(c: [R; 3]) -> Self;
}

impl Vector<f32> for Vec3 {
    const ZERO: Self = Vec3::ZERO;
    #[inline(always)]
    fn components(self) -> [f32; 3] {
        self.to_array()
    }
    #[inline(always)]
    fn from_components(c: [f32; 3]) -> Self {
        Vec3::from_array(c)
    }
    #[inline(always)]
    fn dot(self, other: Self) -> f32 {
        Vec3::dot(self, other)
    }
    #[inline(always)]
    fn cross(self, other: Self) -> Self {
        Vec3::cross(self, other)
    }
    #[inline(always)]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        if mask {
            a
        } else {
            b
        }
    }
}

impl Vector<f64> for DVec3 {
    const ZERO: Self = DVec3::ZERO;
    #[inline(always)]
    fn components(self) -> [f64; 3] {
        self.to_array()
    }
    #[inline(always)]
    fn from_components(c: [f64; 3]) -> Self {
        DVec3::from_array(c)
    }
    #[inline(always)]
    fn dot(self, other: Self) -> f64 {
        DVec3::dot(self, other)
    }
    #[inline(always)]
    fn cross(self, other: Self) -> Self {
        DVec3::cross(self, other)
    }
    #[inline(always)]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        if mask {
            a
        } else {
            b
        }
    }
}

/// What the lane kernels (the rod's frame pass, elastic forces and integration) are written
/// over: an arithmetic, a vector and the square root. Every [`Precision`] is one, and so is
/// `lane::Lanes`, `W` strands at once.
pub trait Kernel: Copy + 'static {
    /// The scalar type, or lanes of it.
    type R: Arithmetic;
    /// The vector type.
    type V: Vector<Self::R>;
    /// Correctly rounded square root (per lane).
    fn sqrt(x: Self::R) -> Self::R;
}

/// A [`Kernel`] with the few transcendental functions the twist calls, per lane.
pub trait Trigonometry: Kernel {
    /// π.
    const PI: Self::R;
    /// 1/π.
    const FRAC_1_PI: Self::R;
    /// `(sin x, cos x)`.
    fn sin_cos(x: Self::R) -> (Self::R, Self::R);
    /// Four-quadrant arctangent of `y / x`.
    fn atan2(y: Self::R, x: Self::R) -> Self::R;
    /// [`Scalar::floor_and_parity`] per lane.
    fn floor_and_parity(x: Self::R) -> (Self::R, <Self::R as Arithmetic>::Mask);
}

/// A scalar, a vector and the few transcendental functions the kernels call.
pub trait Precision: Trigonometry<R: Scalar> {
    /// The simulation's vector `v` in this precision.
    fn vector(v: Vec3) -> Self::V;
    /// `v` rounded to the simulation's vector.
    fn to_vec3(v: Self::V) -> Vec3;
}

impl<M: Math> Kernel for M {
    type R = Real;
    type V = Vec3;
    #[inline(always)]
    fn sqrt(x: Real) -> Real {
        M::sqrt(x)
    }
}

impl<M: Math> Trigonometry for M {
    const PI: Real = core::f32::consts::PI;
    const FRAC_1_PI: Real = core::f32::consts::FRAC_1_PI;
    #[inline(always)]
    fn sin_cos(x: Real) -> (Real, Real) {
        M::sin_cos(x)
    }
    #[inline(always)]
    fn atan2(y: Real, x: Real) -> Real {
        M::atan2(y, x)
    }
    #[inline(always)]
    fn floor_and_parity(x: Real) -> (Real, bool) {
        Scalar::floor_and_parity(x)
    }
}

/// Every math backend is the `f32` precision the step runs in.
impl<M: Math> Precision for M {
    #[inline(always)]
    fn vector(v: Vec3) -> Vec3 {
        v
    }
    #[inline(always)]
    fn to_vec3(v: Vec3) -> Vec3 {
        v
    }
}

/// Double precision with `libm`'s double functions: the reference for finite-difference tests
/// and accuracy studies. Never used by the step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct F64;

impl Kernel for F64 {
    type R = f64;
    type V = DVec3;
    #[inline(always)]
    fn sqrt(x: f64) -> f64 {
        libm::sqrt(x)
    }
}

impl Trigonometry for F64 {
    const PI: f64 = core::f64::consts::PI;
    const FRAC_1_PI: f64 = core::f64::consts::FRAC_1_PI;
    #[inline(always)]
    fn sin_cos(x: f64) -> (f64, f64) {
        libm::sincos(x)
    }
    #[inline(always)]
    fn atan2(y: f64, x: f64) -> f64 {
        libm::atan2(y, x)
    }
    #[inline(always)]
    fn floor_and_parity(x: f64) -> (f64, bool) {
        Scalar::floor_and_parity(x)
    }
}

impl Precision for F64 {
    #[inline(always)]
    fn vector(v: Vec3) -> DVec3 {
        DVec3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
    }
    #[inline(always)]
    fn to_vec3(v: DVec3) -> Vec3 {
        Vec3::new(v.x as f32, v.y as f32, v.z as f32)
    }
}

/// Length of `v` with the precision's square root.
#[inline(always)]
pub fn length<P: Kernel>(v: P::V) -> P::R {
    P::sqrt(v.dot(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_matches_libm_on_angle_ratios() {
        let mut x = -1000.0_f32;
        while x < 1000.0 {
            assert_eq!(Scalar::floor(x), libm::floorf(x), "{x}");
            assert_eq!(
                Scalar::floor(f64::from(x)),
                libm::floor(f64::from(x)),
                "{x}"
            );
            x += 0.123_7;
        }
        for x in [-2.0_f32, -1.0, -0.0, 0.0, 0.5, -0.5, 1.0, 3.999_999_8] {
            assert_eq!(Scalar::floor(x), libm::floorf(x), "{x}");
        }
    }

    #[test]
    fn floor_and_parity_agree_with_floor() {
        let mut x = -1000.0_f32;
        while x < 1000.0 {
            let k = libm::floorf(x);
            let odd = libm::fmodf(k, 2.0) != 0.0;
            assert_eq!(Scalar::floor_and_parity(x), (k, odd), "{x}");
            let wide = f64::from(x);
            assert_eq!(
                Scalar::floor_and_parity(wide),
                (libm::floor(wide), odd),
                "{x}"
            );
            x += 0.123_7;
        }
        for x in [-3.0_f32, -2.5, -1.0, -0.0, 0.0, 0.5, 1.0, 2.0, 3.999_999_8] {
            let k = libm::floorf(x);
            assert_eq!(
                Scalar::floor_and_parity(x),
                (k, libm::fmodf(k, 2.0) != 0.0),
                "{x}"
            );
        }
    }
}
