//! What the harness's threads and the page's single thread share to step strands in lanes:
//! the lanes' widths and their square root ([`VectorSqrt`]). The core's block paths give the
//! bits of its per-strand path; this keeps them so.

use hairsim_core::dftl::RECOMMENDED_LANES;
use hairsim_core::{Math, Real};

/// Lanes of the DFTL blocks.
pub const DFTL_LANES: usize = RECOMMENDED_LANES;
/// Lanes of the rod's blocks (`hairsim_core::pipeline::rod::step_block`).
pub const ROD_LANES: usize = 4;

/// The backend `M` with the hardware's square root, which the compiler can vectorise
/// (`libm::sqrtf` is a scalar `sqrtss` on x86-64 and a software loop on `wasm32`, where
/// `f32::sqrt` is one `f32.sqrt`, or one `f32x4.sqrt` for four lanes with `simd128`).
/// [`Math::sqrt`] is correctly rounded in every backend and so is `f32::sqrt`: the same bits;
/// the trigonometry stays `M`'s.
#[derive(Clone, Copy, Debug, Default)]
pub struct VectorSqrt<M>(std::marker::PhantomData<M>);

impl<M: Math> Math for VectorSqrt<M> {
    const NAME: &'static str = M::NAME;
    const PLAIN_TRIGONOMETRY: bool = M::PLAIN_TRIGONOMETRY;
    #[inline(always)]
    fn sqrt(x: Real) -> Real {
        x.sqrt()
    }
    #[inline(always)]
    fn sin_cos(x: Real) -> (Real, Real) {
        M::sin_cos(x)
    }
    #[inline(always)]
    fn atan2(y: Real, x: Real) -> Real {
        M::atan2(y, x)
    }
}
