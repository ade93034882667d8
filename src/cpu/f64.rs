//! Double precision, the oracle: the kernel (`kernel!`, kernel.rs) with
//! `Real = f64`, and its `Scalar` (src/cpu/precision.rs), portable
//! throughout: no SIMD variants (the trait's defaults, which the stages
//! never ask for: `has_ymm_boxes` and `has_vector_sort` are false).
//! Nothing else is defined here (tests/architecture_rules.rs checks it).

super::kernel::kernel!(f64);

impl Scalar for Real {
    #[inline(always)]
    fn greater_of(a: Vec4, b: Vec4) -> Vec4 {
        Vec4::select(a.cmpgt(b), a, b)
    }

    #[inline(always)]
    fn lesser_of(a: Vec4, b: Vec4) -> Vec4 {
        Vec4::select(a.cmplt(b), a, b)
    }

    type Wide = crate::cpu::lanes::Pair<Vec4>;

    fn has_wide(_: crate::cpu::CpuKernel) -> bool {
        true
    }

    #[inline(always)]
    unsafe fn wide_vertices(low: &PrimBlock, high: &PrimBlock) -> [[Self::Wide; 3]; 3] {
        std::array::from_fn(|i| {
            std::array::from_fn(|k| crate::cpu::lanes::Pair(vec4(low.v[i][k]), vec4(high.v[i][k])))
        })
    }

    /// The low 26 of the 52 stored mantissa bits cleared: the oracle's
    /// twin of the f32 split (27 and 26 bits, each product exact).
    #[inline(always)]
    fn high_half(x: Real) -> Real {
        Real::from_bits(x.to_bits() & !((1u64 << 26) - 1))
    }
}
