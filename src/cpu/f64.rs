//! Double precision, the oracle: the kernel (`kernel!`, kernel.rs) with
//! `Real = f64`, portable throughout.

super::kernel::kernel!(f64, glam::DVec2, glam::DVec3, glam::DVec4);

/// `a` where a > b, else `b` (a NaN in either yields `b`).
#[inline(always)]
fn greater_of(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmpgt(b), a, b)
}

/// `a` where a < b, else `b` (a NaN in either yields `b`).
#[inline(always)]
fn lesser_of(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmplt(b), a, b)
}

/// The oracle takes the portable `intersect_boxes` everywhere.
pub fn has_ymm_boxes() -> bool {
    false
}

use super::simd::no_push_sorted_zmm as push_sorted_zmm;

/// Never runs (`has_ymm_boxes` is false).
///
/// # Safety
/// None needed: unsafe only as its single-precision twin is.
pub unsafe fn intersect_boxes_ymm(ray: &Ray, slabs: &Slabs, node: &BvhNode) -> BoxHits {
    intersect_boxes(ray, slabs, node)
}

/// `x` with the low 26 of its 52 stored mantissa bits cleared: the
/// oracle's twin of the f32 split (27 and 26 bits, each product exact).
#[inline(always)]
fn high_half(x: Real) -> Real {
    Real::from_bits(x.to_bits() & !((1u64 << 26) - 1))
}

pub use crate::camera::f64::CameraBasis;
