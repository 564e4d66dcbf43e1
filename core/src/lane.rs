//! Lanes: the arithmetic the DFTL stages and the shared root coupling and guard are written
//! in, generic over a lane type `T` so the per-strand path (`T = Real`) and the block path
//! (`T = Wide<W>`, one strand per lane) run the very same sequence of IEEE operations on each
//! strand — the same bits by construction (Box2D's `b2FloatW` with its scalar fallback).
//!
//! Every operation on [`Wide`] is a loop over its `W` lanes with no cross-lane term, which the
//! compiler turns into packed instructions; nothing ever sums across lanes. Comparisons give a
//! mask and branches become [`Lane::select`], so a stage has no data-dependent branch.
//! `V3`/`Q` spell out their sums in the order of glam's scalar `Vec3` and `math.rs`'s
//! quaternion helpers.

use core::marker::PhantomData;
use core::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, MulAssign, Neg, Not, Sub, SubAssign};

use crate::math::{self, Math, Quat, Real, Vec3};
use crate::precision::{Arithmetic, Kernel, Trigonometry, Vector};

/// A scalar or a fixed-width bundle of scalars, operated on lane by lane.
pub trait Lane:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// One boolean per lane.
    type Mask: Copy
        + core::fmt::Debug
        + BitAnd<Output = Self::Mask>
        + BitOr<Output = Self::Mask>
        + Not<Output = Self::Mask>;
    /// `x` in every lane.
    fn splat(x: Real) -> Self;
    /// Correctly rounded square root through the backend `M`.
    fn sqrt<M: Math>(self) -> Self;
    /// `|x|`.
    fn abs(self) -> Self;
    /// The larger of the two per lane; `self` where they are equal or `other` is NaN (the
    /// running maximum keeps its value). A compare and a select: `f32::max` is a library
    /// call on the Cortex-M4F (no `VMAXNM`) and a five-instruction NaN fix-up on SSE2.
    fn max(self, other: Self) -> Self;
    /// `self.max(select(mask, value, 0))`: a running maximum (≥ 0) fed where `mask` is set.
    /// (A branch instead of the select made the scalar DFTL step 7 % dearer on the
    /// Cortex-M4F: the selects compile to predicated moves.)
    #[inline(always)]
    fn max_where(self, mask: Self::Mask, value: Self) -> Self {
        self.max(Self::select(mask, value, Self::splat(0.0)))
    }
    /// `self < other` per lane.
    fn lt(self, other: Self) -> Self::Mask;
    /// Whether each lane is finite.
    fn finite(self) -> Self::Mask;
    /// Whether each lane is NaN.
    fn is_nan(self) -> Self::Mask;
    /// `if mask { a } else { b }` per lane.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// A mask with `value` in every lane.
    fn mask(value: bool) -> Self::Mask;
    /// Whether every lane of `mask` is set (to skip work no lane needs: never to change a
    /// lane's result, so a block and the per-strand path still give the same bits).
    fn all(mask: Self::Mask) -> bool;
    /// Whether any lane of `mask` is set (as [`Lane::all`]: only to skip work whose result no
    /// lane would select).
    fn any(mask: Self::Mask) -> bool;
}

impl Lane for Real {
    type Mask = bool;
    #[inline(always)]
    fn splat(x: Real) -> Self {
        x
    }
    #[inline(always)]
    fn sqrt<M: Math>(self) -> Self {
        M::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Real::abs(self)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        if other > self {
            other
        } else {
            self
        }
    }
    #[inline(always)]
    fn lt(self, other: Self) -> bool {
        self < other
    }
    #[inline(always)]
    fn finite(self) -> bool {
        self.is_finite()
    }
    #[inline(always)]
    fn is_nan(self) -> bool {
        Real::is_nan(self)
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
    fn all(mask: bool) -> bool {
        mask
    }
    #[inline(always)]
    fn any(mask: bool) -> bool {
        mask
    }
}

/// `W` scalars, one per strand of a block, laid out as `A` says: by default on 16 bytes, so
/// that SSE2's packed arithmetic reads a lane vector straight from memory (it takes no
/// unaligned operand: at the scalars' own alignment each operand took a load of its own, 3 %
/// of a rod block's instructions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wide<const W: usize, A: Alignment = Aligned>(pub [Real; W], pub A);

/// How a [`Wide`] is laid out: a zero-sized field that sets its alignment.
pub trait Alignment: Copy + core::fmt::Debug + PartialEq + 'static {
    /// The field's value.
    const FIELD: Self;
}

/// On 16 bytes: the blocks' lanes (a lane vector is an SSE2 register).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(align(16))]
pub struct Aligned;

/// The scalars' own alignment: one lane (a strand projected alone, the firmware's path),
/// where 16 bytes would quadruple the projection's space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Natural;

impl Alignment for Aligned {
    const FIELD: Self = Aligned;
}

impl Alignment for Natural {
    const FIELD: Self = Natural;
}

impl<const W: usize, A: Alignment> Wide<W, A> {
    /// The lanes `lanes`.
    #[inline(always)]
    #[must_use]
    pub const fn new(lanes: [Real; W]) -> Self {
        Wide(lanes, A::FIELD)
    }
}

/// `W` booleans, each lane all ones (set) or all zeros, as a packed comparison leaves it: a
/// comparison, `&` and a select are then one packed instruction each. Held as `[bool; W]`,
/// every comparison was unpacked into bytes and packed again for the select (about 30
/// integer instructions a mask: without them the blocks' twist executes a tenth fewer).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WideMask<const W: usize>([u32; W]);

impl<const W: usize> WideMask<W> {
    /// The mask set in the lanes where `lanes` is `true`.
    #[inline(always)]
    #[must_use]
    pub fn from_bools(lanes: [bool; W]) -> Self {
        WideMask(lanes.map(lane_mask))
    }
    /// Whether lane `lane` is set.
    #[inline(always)]
    #[must_use]
    pub fn get(&self, lane: usize) -> bool {
        self.0[lane] != 0
    }
    /// Sets or clears lane `lane`.
    #[inline(always)]
    pub fn set(&mut self, lane: usize, value: bool) {
        self.0[lane] = lane_mask(value);
    }
    /// One `bool` per lane.
    #[inline(always)]
    #[must_use]
    pub fn to_bools(self) -> [bool; W] {
        self.0.map(|m| m != 0)
    }
}

/// All ones for `true`, zero for `false` (what a packed comparison gives).
#[inline(always)]
fn lane_mask(value: bool) -> u32 {
    u32::from(value).wrapping_neg()
}

macro_rules! lanewise {
    ($trait:ident, $method:ident, $ty:ident, $op:tt) => {
        impl<const W: usize, A: Alignment> $trait for $ty<W, A> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, other: Self) -> Self {
                $ty::new(core::array::from_fn(|l| self.0[l] $op other.0[l]))
            }
        }
    };
}
lanewise!(Add, add, Wide, +);
lanewise!(Sub, sub, Wide, -);
lanewise!(Mul, mul, Wide, *);
lanewise!(Div, div, Wide, /);

/// `f` of each pair of lanes, in a plain loop: `array::from_fn`'s closure is sometimes left
/// out of line at 16 lanes (DFTL's 16-lane blocks took 4.4× the time when the masks' ops were
/// written with it).
#[inline(always)]
fn lane_pairs<A: Copy, B: Copy, C: Copy + Default, const W: usize>(
    a: [A; W],
    b: [B; W],
    f: impl Fn(A, B) -> C,
) -> [C; W] {
    let mut out = [C::default(); W];
    for ((out, a), b) in out.iter_mut().zip(a).zip(b) {
        *out = f(a, b);
    }
    out
}

impl<const W: usize> BitAnd for WideMask<W> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, other: Self) -> Self {
        WideMask(lane_pairs(self.0, other.0, |a, b| a & b))
    }
}

impl<const W: usize> BitOr for WideMask<W> {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, other: Self) -> Self {
        WideMask(lane_pairs(self.0, other.0, |a, b| a | b))
    }
}

impl<const W: usize, A: Alignment> Neg for Wide<W, A> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Wide::new(self.0.map(|x| -x))
    }
}

impl<const W: usize> Not for WideMask<W> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        WideMask(lane_pairs(self.0, self.0, |m, _| !m))
    }
}

macro_rules! lanewise_assign {
    ($trait:ident, $method:ident, $op:tt) => {
        impl<const W: usize, A: Alignment> $trait for Wide<W, A> {
            #[inline(always)]
            fn $method(&mut self, other: Self) {
                for (a, b) in self.0.iter_mut().zip(other.0) {
                    *a $op b;
                }
            }
        }
    };
}
lanewise_assign!(AddAssign, add_assign, +=);
lanewise_assign!(SubAssign, sub_assign, -=);
lanewise_assign!(MulAssign, mul_assign, *=);

/// The rod's kernels (`precision::Kernel`) on `W` lanes: each lane's operations are the
/// scalar kernel's, in its order, so each lane gets the bits that strand gets alone.
impl<const W: usize, A: Alignment> Arithmetic for Wide<W, A> {
    type Mask = WideMask<W>;
    const ZERO: Self = Wide::new([0.0; W]);
    const ONE: Self = Wide::new([1.0; W]);
    const EPSILON: Self = Wide::new([Real::EPSILON; W]);
    #[inline(always)]
    fn of(x: f32) -> Self {
        Wide::new([x; W])
    }
    #[inline(always)]
    fn magnitude(self) -> Self {
        <Self as Lane>::abs(self)
    }
    #[inline(always)]
    fn lt(self, other: Self) -> WideMask<W> {
        <Self as Lane>::lt(self, other)
    }
    #[inline(always)]
    fn le(self, other: Self) -> WideMask<W> {
        WideMask(lane_pairs(self.0, other.0, |a, b| lane_mask(a <= b)))
    }
    #[inline(always)]
    fn finite(self) -> WideMask<W> {
        <Self as Lane>::finite(self)
    }
    #[inline(always)]
    fn between(self, low: Self, high: Self) -> WideMask<W> {
        <Self as Lane>::lt(low, self) & <Self as Lane>::lt(self, high)
    }
    #[inline(always)]
    fn select(mask: WideMask<W>, a: Self, b: Self) -> Self {
        <Self as Lane>::select(mask, a, b)
    }
    #[inline(always)]
    fn mask(value: bool) -> WideMask<W> {
        WideMask([lane_mask(value); W])
    }
    #[inline(always)]
    fn any(mask: WideMask<W>) -> bool {
        <Self as Lane>::any(mask)
    }
    #[inline(always)]
    fn all(mask: WideMask<W>) -> bool {
        <Self as Lane>::all(mask)
    }
}

/// The kernel of `W` lanes with the backend `M`'s square root in each.
#[derive(Clone, Copy, Debug, Default)]
pub struct Lanes<M, const W: usize>(PhantomData<M>);

impl<M: Math, const W: usize> Kernel for Lanes<M, W> {
    type R = Wide<W>;
    type V = V3<Wide<W>>;
    #[inline(always)]
    fn sqrt(x: Wide<W>) -> Wide<W> {
        Lane::sqrt::<M>(x)
    }
}

/// The twist's trigonometry with the bits `M` gives each strand: in the lanes' own forms of
/// this crate's plain functions (`Math::PLAIN_TRIGONOMETRY`), else lane by lane through `M`.
impl<M: Math, const W: usize> Trigonometry for Lanes<M, W> {
    const PI: Wide<W> = Wide::new([core::f32::consts::PI; W]);
    const FRAC_1_PI: Wide<W> = Wide::new([core::f32::consts::FRAC_1_PI; W]);
    #[inline(always)]
    fn sin_cos(x: Wide<W>) -> (Wide<W>, Wide<W>) {
        if M::PLAIN_TRIGONOMETRY {
            sin_cos_in_lanes(x)
        } else {
            let both = x.0.map(M::sin_cos);
            (Wide::new(both.map(|b| b.0)), Wide::new(both.map(|b| b.1)))
        }
    }
    #[inline(always)]
    fn atan2(y: Wide<W>, x: Wide<W>) -> Wide<W> {
        if M::PLAIN_TRIGONOMETRY {
            atan2_in_lanes(y, x)
        } else {
            let mut angle = [0.0; W];
            for ((angle, &y), &x) in angle.iter_mut().zip(&y.0).zip(&x.0) {
                *angle = M::atan2(y, x);
            }
            Wide::new(angle)
        }
    }
    #[inline(always)]
    fn floor_and_parity(x: Wide<W>) -> (Wide<W>, WideMask<W>) {
        floor_and_parity_in_lanes(x)
    }
}

impl<const W: usize, A: Alignment> Lane for Wide<W, A> {
    type Mask = WideMask<W>;
    #[inline(always)]
    fn splat(x: Real) -> Self {
        Wide::new([x; W])
    }
    #[inline(always)]
    fn sqrt<M: Math>(self) -> Self {
        Wide::new(self.0.map(M::sqrt))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Wide::new(self.0.map(Real::abs))
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        Wide::new(core::array::from_fn(|l| {
            if other.0[l] > self.0[l] {
                other.0[l]
            } else {
                self.0[l]
            }
        }))
    }
    #[inline(always)]
    fn lt(self, other: Self) -> WideMask<W> {
        WideMask(lane_pairs(self.0, other.0, |a, b| lane_mask(a < b)))
    }
    #[inline(always)]
    fn finite(self) -> WideMask<W> {
        WideMask(lane_pairs(self.0, self.0, |x, _| lane_mask(x.is_finite())))
    }
    #[inline(always)]
    fn is_nan(self) -> WideMask<W> {
        WideMask(lane_pairs(self.0, self.0, |x, _| lane_mask(x.is_nan())))
    }
    /// The bits of `a` where `mask` is set, of `b` elsewhere: `(a & m) | (b & !m)`, exact.
    #[inline(always)]
    fn select(mask: WideMask<W>, a: Self, b: Self) -> Self {
        let mut out = b.0;
        for ((out, a), m) in out.iter_mut().zip(a.0).zip(mask.0) {
            *out = Real::from_bits((a.to_bits() & m) | (out.to_bits() & !m));
        }
        Wide::new(out)
    }
    #[inline(always)]
    fn mask(value: bool) -> WideMask<W> {
        WideMask([lane_mask(value); W])
    }
    #[inline(always)]
    fn all(mask: WideMask<W>) -> bool {
        mask.0.iter().fold(u32::MAX, |a, &b| a & b) != 0
    }
    #[inline(always)]
    fn any(mask: WideMask<W>) -> bool {
        mask.0.iter().fold(0, |a, &b| a | b) != 0
    }
}

/// A vector of lanes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<T> {
    /// x.
    pub x: T,
    /// y.
    pub y: T,
    /// z.
    pub z: T,
}

impl<T: Lane> V3<T> {
    /// `v` in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        V3 {
            x: T::splat(v.x),
            y: T::splat(v.y),
            z: T::splat(v.z),
        }
    }
    /// Zero.
    #[inline(always)]
    pub fn zero() -> Self {
        Self::splat(Vec3::ZERO)
    }
    /// `self · s`.
    #[inline(always)]
    pub fn scale(self, s: T) -> Self {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    /// `x·x' + y·y' + z·z'`, summed left to right.
    #[inline(always)]
    pub fn dot(self, o: Self) -> T {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// `self × o`.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }
    /// Per lane `if mask { a } else { b }`.
    #[inline(always)]
    pub fn select(mask: T::Mask, a: Self, b: Self) -> Self {
        V3 {
            x: T::select(mask, a.x, b.x),
            y: T::select(mask, a.y, b.y),
            z: T::select(mask, a.z, b.z),
        }
    }
    /// Whether every component is finite, per lane.
    #[inline(always)]
    pub fn finite(self) -> T::Mask {
        self.x.finite() & self.y.finite() & self.z.finite()
    }
}

impl<T: Lane> Add for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<T: Lane> Sub for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<T: Lane> Neg for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl<T: Lane> Mul<T> for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: T) -> Self {
        self.scale(s)
    }
}

impl<T: Lane> AddAssign for V3<T> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl<T: Lane> SubAssign for V3<T> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

impl<const W: usize, A: Alignment> Vector<Wide<W, A>> for V3<Wide<W, A>> {
    const ZERO: Self = V3 {
        x: Wide::ZERO,
        y: Wide::ZERO,
        z: Wide::ZERO,
    };
    #[inline(always)]
    fn components(self) -> [Wide<W, A>; 3] {
        [self.x, self.y, self.z]
    }
    #[inline(always)]
    fn from_components([x, y, z]: [Wide<W, A>; 3]) -> Self {
        V3 { x, y, z }
    }
    #[inline(always)]
    fn dot(self, other: Self) -> Wide<W, A> {
        V3::dot(self, other)
    }
    #[inline(always)]
    fn cross(self, other: Self) -> Self {
        V3::cross(self, other)
    }
    #[inline(always)]
    fn select(mask: WideMask<W>, a: Self, b: Self) -> Self {
        V3::select(mask, a, b)
    }
}

impl<const W: usize, A: Alignment> V3<Wide<W, A>> {
    /// Lane `lane` as a vector.
    #[inline(always)]
    #[must_use]
    pub fn lane(&self, lane: usize) -> Vec3 {
        Vec3::new(self.x.0[lane], self.y.0[lane], self.z.0[lane])
    }
    /// Writes `v` into lane `lane`.
    #[inline(always)]
    pub fn set_lane(&mut self, lane: usize, v: Vec3) {
        self.x.0[lane] = v.x;
        self.y.0[lane] = v.y;
        self.z.0[lane] = v.z;
    }
}

impl From<Vec3> for V3<Real> {
    #[inline(always)]
    fn from(v: Vec3) -> Self {
        V3 {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
}

impl From<V3<Real>> for Vec3 {
    #[inline(always)]
    fn from(v: V3<Real>) -> Self {
        Vec3::new(v.x, v.y, v.z)
    }
}

/// A quaternion of lanes (`math.rs`'s scalar formulas).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Q<T> {
    /// x.
    pub x: T,
    /// y.
    pub y: T,
    /// z.
    pub z: T,
    /// w.
    pub w: T,
}

impl<T: Lane> Q<T> {
    /// `q` in every lane.
    #[inline(always)]
    pub fn splat(q: Quat) -> Self {
        Q {
            x: T::splat(q.x),
            y: T::splat(q.y),
            z: T::splat(q.z),
            w: T::splat(q.w),
        }
    }
    /// Hamilton product `self · b` (as `math::quat_mul`).
    #[inline(always)]
    pub fn product(self, b: Self) -> Self {
        let a = self;
        Q {
            x: a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
            y: a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
            z: a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
            w: a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
        }
    }
    /// Rotates `v` (as `math::rotate`): `v + 2w (u × v) + 2 u × (u × v)`.
    #[inline(always)]
    pub fn rotate(self, v: V3<T>) -> V3<T> {
        let u = V3 {
            x: self.x,
            y: self.y,
            z: self.z,
        };
        let uv = u.cross(v);
        let uuv = u.cross(uv);
        v + (uv.scale(self.w) + uuv).scale(T::splat(2.0))
    }
    /// Renormalised with the backend's square root; identity where the norm is zero or not
    /// finite (as `math::quat_normalize`).
    #[inline(always)]
    pub fn normalize<M: Math>(self) -> Self {
        let n2 = self.x * self.x + self.y * self.y + self.z * self.z + self.w * self.w;
        let ok = T::splat(0.0).lt(n2) & n2.finite();
        let inv = T::splat(1.0) / n2.sqrt::<M>();
        Q {
            x: T::select(ok, self.x * inv, T::splat(0.0)),
            y: T::select(ok, self.y * inv, T::splat(0.0)),
            z: T::select(ok, self.z * inv, T::splat(0.0)),
            w: T::select(ok, self.w * inv, T::splat(1.0)),
        }
    }
    /// The minimal rotation from unit `a` to unit `b`, not normalised:
    /// `(a × b, 1 + a·b)` (as `math::quat_between_unnormalized`).
    #[inline(always)]
    pub fn between_unnormalized(a: V3<T>, b: V3<T>) -> Self {
        let c = a.cross(b);
        Q {
            x: c.x,
            y: c.y,
            z: c.z,
            w: T::splat(1.0) + a.dot(b),
        }
    }
    /// Per lane `if mask { a } else { b }`.
    #[inline(always)]
    pub fn select(mask: T::Mask, a: Self, b: Self) -> Self {
        Q {
            x: T::select(mask, a.x, b.x),
            y: T::select(mask, a.y, b.y),
            z: T::select(mask, a.z, b.z),
            w: T::select(mask, a.w, b.w),
        }
    }
}

impl From<Quat> for Q<Real> {
    #[inline(always)]
    fn from(q: Quat) -> Self {
        Q {
            x: q.x,
            y: q.y,
            z: q.z,
            w: q.w,
        }
    }
}

impl From<Q<Real>> for Quat {
    #[inline(always)]
    fn from(q: Q<Real>) -> Self {
        Quat::from_xyzw(q.x, q.y, q.z, q.w)
    }
}

/// `x + y + z` of `v`. Summed over the velocities a DFTL step writes (the root coupling's and
/// the pass's), the total is finite exactly when they all are, short of overflow, so
/// [`not_finite_sum`] of it is the whole verdict of the DFTL guard: three additions a node. An
/// overflowing total means a velocity beyond ~10³⁶ m/s: a blow-up, rolled back all the same.
///
/// Velocities only: a node's new velocity is `(x* − x)/Δt − (s_d/Δt) c` (or
/// `(target − x)/Δt` for a held node), and with `x` finite (the last step's guard saw to
/// that) and `1/Δt` finite and positive, a non-finite `x*` makes it non-finite too (`±∞` stays
/// `±∞` or meets `∓∞` and turns NaN; NaN stays NaN) — so the positions need no check of their
/// own, and a non-finite old `x` is caught the same way. DFTL writes no twist.
#[inline(always)]
pub fn component_sum<T: Lane>(v: V3<T>) -> T {
    v.x + v.y + v.z
}

/// 0 where `total` (a sum of [`component_sum`]s) is finite, NaN otherwise (`x − x`).
#[inline(always)]
#[allow(clippy::eq_op)] // x − x is the point: 0 for finite x, NaN for ±∞ and NaN.
pub fn not_finite_sum<T: Lane>(total: T) -> T {
    total - total
}

/// [`crate::math::sin_cos`] of each lane, with the bits it gives that lane: the same
/// operations written over the lanes (the quadrant's integer work too), so that the compiler
/// packs them; the lanes that `sin_cos` hands to libm (NaN, `|x| > 201`) are patched one by
/// one, and a zero lane keeps its sign.
#[inline(always)]
#[must_use]
pub fn sin_cos_in_lanes<const W: usize>(x: Wide<W>) -> (Wide<W>, Wide<W>) {
    let q = x * Wide::splat(core::f32::consts::FRAC_2_PI);
    // `q ∓ 0.5` as `q + (∓0.5)`: the same IEEE operation.
    let mut n = [0_i32; W];
    for (n, q) in n.iter_mut().zip(q.0) {
        let half = if q < 0.0 { -0.5 } else { 0.5 };
        *n = (q + half) as i32;
    }
    let mut m = Wide::splat(0.0);
    let (mut odd, mut half_turn) = ([0_u32; W], [0_u32; W]);
    for (((m, odd), half_turn), n) in m.0.iter_mut().zip(&mut odd).zip(&mut half_turn).zip(n) {
        *m = n as Real;
        *odd = lane_mask(n & 1 != 0);
        *half_turn = lane_mask(n & 2 != 0);
    }
    let [p0, p1, p2] = math::FRAC_PI_2_PARTS.map(Wide::splat);
    let r = ((x - m * p0) - m * p1) - m * p2;
    let z = r * r;
    let [s0, s1, s2] = math::SIN_COEFFICIENTS.map(Wide::splat);
    let [c0, c1, c2] = math::COS_COEFFICIENTS.map(Wide::splat);
    let sin = r + r * z * (s0 + z * (s1 + z * s2));
    let cos = (Wide::splat(1.0) - Wide::splat(0.5) * z) + z * z * (c0 + z * (c1 + z * c2));
    // The quadrant and the zero lanes as `sin_cos` picks them, as selects of whole lanes.
    let (odd, half_turn) = (WideMask(odd), WideMask(half_turn));
    let (s, c) = (Lane::select(odd, cos, sin), Lane::select(odd, -sin, cos));
    let (s, c) = (
        Lane::select(half_turn, -s, s),
        Lane::select(half_turn, -c, c),
    );
    // C's `sin(±0) = ±0`, as `sin_cos`.
    let zero = WideMask(lane_pairs(x.0, x.0, |x, _| lane_mask(x == 0.0)));
    let mut sin_out = Lane::select(zero, x, s).0;
    let mut cos_out = Lane::select(zero, Wide::splat(1.0), c).0;
    let beyond = lane_pairs(x.0, x.0, |x, _| {
        x.is_nan() || x.abs() > math::SIN_COS_REDUCED
    });
    if beyond.contains(&true) {
        for l in (0..W).filter(|&l| beyond[l]) {
            (sin_out[l], cos_out[l]) = libm::sincosf(x.0[l]);
        }
    }
    (Wide::new(sin_out), Wide::new(cos_out))
}

/// [`crate::math::atan2`] of each lane, with the bits it gives that lane: its branches as
/// selects of whole lanes, its one division packed.
#[inline(always)]
#[must_use]
pub fn atan2_in_lanes<const W: usize>(y: Wide<W>, x: Wide<W>) -> Wide<W> {
    let (ax, ay) = (x.abs(), y.abs());
    let steep = Lane::lt(ax, ay);
    let numerator = Lane::select(steep, ax, ay);
    let denominator = Lane::select(steep, ay, ax);
    let flat = WideMask(lane_pairs(denominator.0, denominator.0, |d, _| {
        lane_mask(d == 0.0)
    }));
    let t = Lane::select(flat, Wide::splat(0.0), numerator / denominator);
    // Each coefficient splat by itself: an array `map` is sometimes left out of line.
    let a = |k: usize| Wide::splat(math::ATAN_COEFFICIENTS[k]);
    let u = t * t;
    let u2 = u * u;
    let pairs = [
        a(0) + a(1) * u,
        a(2) + a(3) * u,
        a(4) + a(5) * u,
        a(6) + a(7) * u,
    ];
    let u4 = u2 * u2;
    let quads = [pairs[0] + pairs[1] * u2, pairs[2] + pairs[3] * u2];
    let p = (quads[0] + quads[1] * u4) + a(8) * (u4 * u4);
    let mut angle = t * p;
    angle = Lane::select(
        steep,
        Wide::splat(core::f32::consts::FRAC_PI_2) - angle,
        angle,
    );
    angle = Lane::select(
        sign_mask(x),
        Wide::splat(core::f32::consts::PI) - angle,
        angle,
    );
    Lane::select(sign_mask(y), -angle, angle)
}

/// Whether each lane's sign bit is set (`is_sign_negative`), as a whole-lane mask.
#[inline(always)]
fn sign_mask<const W: usize>(x: Wide<W>) -> WideMask<W> {
    WideMask(lane_pairs(x.0, x.0, |x, _| {
        ((x.to_bits() as i32) >> 31) as u32
    }))
}

/// [`crate::precision::Scalar::floor_and_parity`] of each lane, with its bits: the floor and
/// its parity in packed float and bit operations where `|x| < 2^22`, the scalar function in
/// the other lanes. The scalar's `as i32` and back, four times, was what the compiler most
/// often left unpacked in the twist's sweep.
#[inline(always)]
#[must_use]
pub fn floor_and_parity_in_lanes<const W: usize>(x: Wide<W>) -> (Wide<W>, WideMask<W>) {
    // `|x| < 2^22`: the floor in floats, exact; NaN and larger lanes as the scalar takes them
    // (`as` saturates), one by one.
    let rounded = rounded_small(x);
    let above = Lane::lt(x, rounded);
    let mut floor = Lane::select(above, rounded - Wide::splat(1.0), rounded);
    let mut odd = odd_mask(floor);
    let large = lane_pairs(x.0, x.0, |x, _| x.is_nan() || x.abs() >= SMALL_INTEGERS);
    if large.contains(&true) {
        for l in (0..W).filter(|&l| large[l]) {
            let (f, o) = crate::precision::Scalar::floor_and_parity(x.0[l]);
            floor.0[l] = f;
            odd.set(l, o);
        }
    }
    (floor, odd)
}

/// Below this magnitude, adding and subtracting [`ROUNDING`] rounds a float to an integer
/// exactly, and the integer sits in the low bits of the sum's mantissa.
const SMALL_INTEGERS: Real = 4_194_304.0; // 2^22
/// `1.5 · 2^23`: `x + ROUNDING` lies in `[2^23, 2^24)`, where the spacing of floats is 1, for
/// every `|x| < 2^22`; its mantissa is `x + 2^22`, rounded to the nearest integer (ties to
/// even).
const ROUNDING: Real = 12_582_912.0;

/// `x` rounded to the nearest integer, ties to even, for `|x| < 2^22` (other lanes: any
/// value): two packed additions.
#[inline(always)]
fn rounded_small<const W: usize>(x: Wide<W>) -> Wide<W> {
    (x + Wide::splat(ROUNDING)) - Wide::splat(ROUNDING)
}

/// Whether the integer `k` (`|k| < 2^22`) is odd: `k + 1.5 · 2^23`'s mantissa is
/// `k + 2^22`, whose lowest bit is `k`'s.
#[inline(always)]
fn odd_mask<const W: usize>(k: Wide<W>) -> WideMask<W> {
    let biased = k + Wide::splat(ROUNDING);
    WideMask(lane_pairs(biased.0, biased.0, |b, _| {
        lane_mask(b.to_bits() & 1 != 0)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{self, Libm};

    #[test]
    fn sin_cos_in_lanes_gives_each_lane_the_bits_of_sin_cos() {
        let specials = [
            0.0,
            -0.0,
            Real::NAN,
            Real::INFINITY,
            -201.0,
            201.0,
            201.1,
            -1.0e9,
        ];
        let mut checked = 0;
        let mut check = |x: [Real; 4]| {
            let (s, c) = sin_cos_in_lanes(Wide::new(x));
            for (l, x) in x.iter().enumerate() {
                let (sl, cl) = math::sin_cos(*x);
                assert_eq!(s.0[l].to_bits(), sl.to_bits(), "sin {x}");
                assert_eq!(c.0[l].to_bits(), cl.to_bits(), "cos {x}");
            }
            checked += 4;
        };
        for k in 0..100_000u32 {
            let x = (k as Real - 50_000.0) * 0.004_1;
            check([x, -x, x * 0.5, specials[k as usize % specials.len()]]);
        }
        assert_eq!(checked, 400_000);
    }

    #[test]
    fn atan2_in_lanes_gives_each_lane_the_bits_of_atan2() {
        let specials = [
            0.0,
            -0.0,
            Real::NAN,
            Real::INFINITY,
            -Real::INFINITY,
            Real::MIN_POSITIVE,
            -1.0e-40,
            3.0e38,
        ];
        let mut checked = 0;
        for k in 0..40_000u32 {
            let a = (k as Real - 20_000.0) * 0.000_37;
            let b = (k as Real * 0.618_034).sin() * 2.0;
            let special = specials[k as usize % specials.len()];
            let ys = [a, -b, special, b * 1.0e-3];
            let xs = [b, a, a, specials[(k as usize / 8) % specials.len()]];
            let angles = atan2_in_lanes(Wide::new(ys), Wide::new(xs));
            for l in 0..4 {
                let expected = math::atan2(ys[l], xs[l]);
                assert_eq!(
                    angles.0[l].to_bits(),
                    expected.to_bits(),
                    "{} {}",
                    ys[l],
                    xs[l]
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 160_000);
    }

    #[test]
    fn floor_and_parity_in_lanes_gives_each_lane_the_scalar_bits() {
        let specials = [
            Real::NAN,
            Real::INFINITY,
            -Real::INFINITY,
            -3.0e9,
            3.0e9,
            -0.0,
            4_194_303.5,
            -4_194_303.5,
            4_194_304.0,
            -4_194_305.0,
        ];
        for k in 0..20_000u32 {
            let x = (k as Real - 10_000.0) * 0.013_7;
            let xs = [x, -x, x + 0.5, specials[k as usize % specials.len()]];
            let (floor, odd) = floor_and_parity_in_lanes(Wide::new(xs));
            for (l, &x) in xs.iter().enumerate() {
                let (f, o) = crate::precision::Scalar::floor_and_parity(x);
                assert_eq!(floor.0[l].to_bits(), f.to_bits(), "{x}");
                assert_eq!(odd.get(l), o, "{x}");
            }
        }
    }

    #[test]
    fn lanes_match_the_scalar_helpers_bit_for_bit() {
        let q = math::quat_from_axis_angle::<Libm>(Vec3::new(0.0, 0.6, 0.8), 1.1);
        let v = Vec3::new(0.3, -1.2, 2.0);
        let r: Vec3 = Q::<Real>::from(q).rotate(v.into()).into();
        assert_eq!(r, math::rotate(q, v));
        let p: Quat = Q::<Real>::from(q)
            .product(q.into())
            .normalize::<Libm>()
            .into();
        assert_eq!(p, math::quat_normalize::<Libm>(math::quat_mul(q, q)));
        let wide = Q::<Wide<4>>::splat(q).rotate(V3::splat(v));
        assert_eq!(wide.y.0, [r.y; 4]);
        let m = Lane::lt(Wide::<4>::new([1.0, -1.0, 2.0, 0.0]), Wide::splat(0.5));
        assert_eq!(m.to_bools(), [false, true, false, true]);
    }
}
