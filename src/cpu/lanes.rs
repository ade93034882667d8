//! Vectors of lanes that a leaf's blocks of triangles are tested in, each
//! lane's arithmetic the same IEEE operations in the same order: glam's
//! 4-lane vectors (one block), and for a leaf's two blocks side by side
//! `Ymm` (one AVX register, f32 on x86) or `Pair` (two 4-lane vectors).
//! The closest-point test is written once over `Lanes`
//! (closest/stage.rs), so every width gives the same bits.

use std::ops::{Add, BitAnd, Div, Mul, Sub};

/// What a block test asks of its lanes.
pub trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    type Scalar: Copy;
    type Mask: Copy + BitAnd<Output = Self::Mask>;
    /// The lanes as an array, the first block's first.
    type Array: AsRef<[Self::Scalar]>;

    fn splat(x: Self::Scalar) -> Self;
    /// `a` where a > b, else `b` (SSE's `maxps`: `b` where either is NaN).
    fn greater(self, b: Self) -> Self;
    /// `a` where a < b, else `b` (SSE's `minps`).
    fn lesser(self, b: Self) -> Self;
    fn gt(self, b: Self) -> Self::Mask;
    fn lt(self, b: Self) -> Self::Mask;
    fn le(self, b: Self) -> Self::Mask;
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    fn any(mask: Self::Mask) -> bool;
    fn to_lanes(self) -> Self::Array;
}

/// glam's 4-lane vectors, their own operations (`max` and `min` are
/// `maxps`'s and `minps`'s select on x86, in f32 and f64 alike).
macro_rules! glam_lanes {
    ($vec:ty, $real:ty, $mask:ty) => {
        impl Lanes for $vec {
            type Scalar = $real;
            type Mask = $mask;
            type Array = [$real; 4];

            #[inline(always)]
            fn splat(x: $real) -> Self {
                <$vec>::splat(x)
            }
            #[inline(always)]
            fn greater(self, b: Self) -> Self {
                self.max(b)
            }
            #[inline(always)]
            fn lesser(self, b: Self) -> Self {
                self.min(b)
            }
            #[inline(always)]
            fn gt(self, b: Self) -> $mask {
                self.cmpgt(b)
            }
            #[inline(always)]
            fn lt(self, b: Self) -> $mask {
                self.cmplt(b)
            }
            #[inline(always)]
            fn le(self, b: Self) -> $mask {
                self.cmple(b)
            }
            #[inline(always)]
            fn select(mask: $mask, a: Self, b: Self) -> Self {
                <$vec>::select(mask, a, b)
            }
            #[inline(always)]
            fn any(mask: $mask) -> bool {
                mask.any()
            }
            #[inline(always)]
            fn to_lanes(self) -> [$real; 4] {
                self.to_array()
            }
        }
    };
}
glam_lanes!(glam::Vec4, f32, glam::BVec4A);
glam_lanes!(glam::DVec4, f64, glam::BVec4);

/// Two 4-lane vectors side by side: eight lanes where no 8-lane register
/// is (f64, and f32 off x86), each operation on both halves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair<V>(pub V, pub V);

/// A `Pair`'s comparisons, each half's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairMask<M>(M, M);

impl<M: BitAnd<Output = M>> BitAnd for PairMask<M> {
    type Output = PairMask<M>;
    #[inline(always)]
    fn bitand(self, b: PairMask<M>) -> PairMask<M> {
        PairMask(self.0 & b.0, self.1 & b.1)
    }
}

macro_rules! pair_op {
    ($trait:ident, $method:ident) => {
        impl<V: Lanes> $trait for Pair<V> {
            type Output = Pair<V>;
            #[inline(always)]
            fn $method(self, b: Pair<V>) -> Pair<V> {
                Pair(self.0.$method(b.0), self.1.$method(b.1))
            }
        }
    };
}
pair_op!(Add, add);
pair_op!(Sub, sub);
pair_op!(Mul, mul);
pair_op!(Div, div);

impl<V: Lanes<Scalar = S, Array = [S; 4]>, S: Copy> Lanes for Pair<V> {
    type Scalar = S;
    type Mask = PairMask<V::Mask>;
    type Array = [S; 8];

    #[inline(always)]
    fn splat(x: S) -> Self {
        Pair(V::splat(x), V::splat(x))
    }
    #[inline(always)]
    fn greater(self, b: Self) -> Self {
        Pair(self.0.greater(b.0), self.1.greater(b.1))
    }
    #[inline(always)]
    fn lesser(self, b: Self) -> Self {
        Pair(self.0.lesser(b.0), self.1.lesser(b.1))
    }
    #[inline(always)]
    fn gt(self, b: Self) -> Self::Mask {
        PairMask(self.0.gt(b.0), self.1.gt(b.1))
    }
    #[inline(always)]
    fn lt(self, b: Self) -> Self::Mask {
        PairMask(self.0.lt(b.0), self.1.lt(b.1))
    }
    #[inline(always)]
    fn le(self, b: Self) -> Self::Mask {
        PairMask(self.0.le(b.0), self.1.le(b.1))
    }
    #[inline(always)]
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self {
        Pair(V::select(mask.0, a.0, b.0), V::select(mask.1, a.1, b.1))
    }
    #[inline(always)]
    fn any(mask: Self::Mask) -> bool {
        V::any(mask.0) | V::any(mask.1)
    }
    #[inline(always)]
    fn to_lanes(self) -> [S; 8] {
        let ([a, b, c, d], [e, f, g, h]) = (self.0.to_lanes(), self.1.to_lanes());
        [a, b, c, d, e, f, g, h]
    }
}

#[cfg(target_arch = "x86_64")]
pub use ymm::Ymm;

/// Eight f32 lanes in one AVX register.
#[cfg(target_arch = "x86_64")]
mod ymm {
    use super::Lanes;
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, Div, Mul, Sub};

    /// Eight f32 lanes in one AVX register. Every operation is an AVX
    /// instruction: a `Ymm` is made (`join`) only where the CPU has AVX
    /// (the AVX2 and AVX-512 kernels, `Scalar::has_wide`), and operated
    /// on only inlined into their code (`with_simd`), where each is one
    /// instruction.
    #[derive(Clone, Copy, Debug)]
    pub struct Ymm(__m256);

    /// A `Ymm`'s comparisons: all bits set where true.
    #[derive(Clone, Copy, Debug)]
    pub struct YmmMask(__m256);

    impl Ymm {
        /// The lanes of `low` and then of `high`.
        ///
        /// # Safety
        /// The CPU has AVX.
        #[inline(always)]
        pub unsafe fn join(low: &[f32; 4], high: &[f32; 4]) -> Ymm {
            // SAFETY: the caller vouches for AVX; each pointer is to 4 f32.
            Ymm(unsafe { _mm256_loadu2_m128(high.as_ptr(), low.as_ptr()) })
        }
    }

    // SAFETY of every `unsafe` below: a `Ymm` exists only where the CPU
    // has AVX (`join`).
    macro_rules! ymm_op {
        ($trait:ident, $method:ident, $intrinsic:ident) => {
            impl $trait for Ymm {
                type Output = Ymm;
                #[inline(always)]
                fn $method(self, b: Ymm) -> Ymm {
                    Ymm(unsafe { $intrinsic(self.0, b.0) })
                }
            }
        };
    }
    ymm_op!(Add, add, _mm256_add_ps);
    ymm_op!(Sub, sub, _mm256_sub_ps);
    ymm_op!(Mul, mul, _mm256_mul_ps);
    ymm_op!(Div, div, _mm256_div_ps);

    impl BitAnd for YmmMask {
        type Output = YmmMask;
        #[inline(always)]
        fn bitand(self, b: YmmMask) -> YmmMask {
            YmmMask(unsafe { _mm256_and_ps(self.0, b.0) })
        }
    }

    impl Lanes for Ymm {
        type Scalar = f32;
        type Mask = YmmMask;
        type Array = [f32; 8];

        #[inline(always)]
        fn splat(x: f32) -> Self {
            Ymm(unsafe { _mm256_set1_ps(x) })
        }
        /// maxps: the second operand unless the first is greater.
        #[inline(always)]
        fn greater(self, b: Self) -> Self {
            Ymm(unsafe { _mm256_max_ps(self.0, b.0) })
        }
        #[inline(always)]
        fn lesser(self, b: Self) -> Self {
            Ymm(unsafe { _mm256_min_ps(self.0, b.0) })
        }
        #[inline(always)]
        fn gt(self, b: Self) -> YmmMask {
            YmmMask(unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, b.0) })
        }
        #[inline(always)]
        fn lt(self, b: Self) -> YmmMask {
            YmmMask(unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, b.0) })
        }
        #[inline(always)]
        fn le(self, b: Self) -> YmmMask {
            YmmMask(unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, b.0) })
        }
        #[inline(always)]
        fn select(mask: YmmMask, a: Self, b: Self) -> Self {
            Ymm(unsafe { _mm256_blendv_ps(b.0, a.0, mask.0) })
        }
        #[inline(always)]
        fn any(mask: YmmMask) -> bool {
            unsafe { _mm256_movemask_ps(mask.0) != 0 }
        }
        #[inline(always)]
        fn to_lanes(self) -> [f32; 8] {
            let mut lanes = [0.0; 8];
            unsafe { _mm256_storeu_ps(lanes.as_mut_ptr(), self.0) };
            lanes
        }
    }
}
