//! What the CPU twin's stages take from the precision they are expanded
//! in: the trait `Scalar`, implemented for f32 (src/cpu/f32.rs) and f64
//! (src/cpu/f64.rs). The stages (`kernel!`, kernel.rs) name nothing else
//! that a precision's module defines by hand: they call these as
//! `<Real as Scalar>::greater_of(…)`, and a precision that lacks one, or
//! gives it another signature, does not compile.

use super::lanes::Lanes;
use super::simd::CpuKernel;
use crate::layout::{BVH_WIDTH, BvhNode, PrimBlock};

/// The kernel's own items in a precision that `Scalar` names: the types
/// its functions take and give, and the portable slab test its SIMD
/// variant defaults to. `kernel!` implements it for the `Real` it expands
/// the stages in (its `Vec4`, `Ray`, `Slabs`, `BoxHits`, `TraversalStack`
/// and `intersect_boxes`).
pub trait KernelItems: Copy {
    type Vec4;
    type Ray;
    type Slabs;
    type BoxHits;
    type Stack;

    /// The kernel's portable slab test of a node's eight child boxes.
    fn intersect_boxes(ray: &Self::Ray, slabs: &Self::Slabs, node: &BvhNode) -> Self::BoxHits;
}

/// A precision the CPU kernel computes in, with what differs by it: f32,
/// the reference the GPU is diffed against, or f64, the oracle. The
/// shader's NaN-ignoring selects, the split of `two_square`, and the SIMD
/// variants of two hot stages with whether this process runs them. A
/// SIMD variant gives its portable original's results bit for bit
/// (tests/bvh.rs and src/cpu/f32.rs test them against each other). A
/// precision with none (f64; f32 off x86) keeps the defaults: `has_…`
/// false, so that the stages take the portable originals and never call
/// the variants (the slab test's is the portable one; the ordering's
/// panics).
///
/// The implementations' functions are `#[inline(always)]` where the
/// stages call them in hot code, and the defaults are not (as the free
/// functions they replace were not): a call through the trait compiles
/// to what a call of a free function did.
pub trait Scalar: KernelItems {
    /// `a` where a > b, else `b` (a NaN in either yields `b`): the
    /// shader's `select(b, a, a > b)`, lane by lane.
    fn greater_of(a: Self::Vec4, b: Self::Vec4) -> Self::Vec4;

    /// `a` where a < b, else `b` (a NaN in either yields `b`).
    fn lesser_of(a: Self::Vec4, b: Self::Vec4) -> Self::Vec4;

    /// `x` with the low half of its mantissa cleared: a high half whose
    /// square and product with the rest (`x − high_half`) are exact in
    /// this precision (Dekker's split for `two_square`, by mask rather
    /// than by the multiply of Veltkamp's, which a fused multiply-add
    /// would spoil).
    fn high_half(x: Self) -> Self;

    /// A leaf's two blocks' eight lanes, side by side, for closest points
    /// (`closest_point_lanes`): f32's one AVX register on x86, else two
    /// 4-lane vectors.
    type Wide: Lanes<Scalar = Self>;

    /// Whether `kernel` has the instructions of `Wide`'s operations (f32's
    /// are AVX's on x86, which the portable kernel lacks).
    fn has_wide(kernel: CpuKernel) -> bool;

    /// The vertices of blocks `low` and `high` (per vertex, per axis),
    /// `low`'s lanes first.
    ///
    /// # Safety
    /// `has_wide` holds for a kernel this CPU runs (fastest inlined into
    /// that kernel's code; elsewhere each operation is a call).
    unsafe fn wide_vertices(low: &PrimBlock, high: &PrimBlock) -> [[Self::Wide; 3]; 3];

    /// Whether this process runs `intersect_boxes_ymm`.
    fn has_ymm_boxes() -> bool {
        false
    }

    /// `intersect_boxes` with each row of eight planes in one 8-lane
    /// register: the same IEEE operations lane for lane, so the same
    /// result (by default, the portable `intersect_boxes` itself).
    ///
    /// # Safety
    /// `has_ymm_boxes()` must hold (the CPU has AVX2 and FMA).
    unsafe fn intersect_boxes_ymm(
        ray: &Self::Ray,
        slabs: &Self::Slabs,
        node: &BvhNode,
    ) -> Self::BoxHits {
        Self::intersect_boxes(ray, slabs, node)
    }

    /// Whether this process runs `push_sorted_zmm`.
    fn has_vector_sort() -> bool {
        false
    }

    /// `visit`'s ordering of the entered children (one or more) in vector
    /// registers: what `push_sorted` pushes and returns, for any number of
    /// them.
    ///
    /// # Safety
    /// `has_vector_sort()` must hold (the CPU has AVX-512).
    unsafe fn push_sorted_zmm(
        _stack: &mut Self::Stack,
        _sp: &mut usize,
        _t: &[Self; BVH_WIDTH],
        _children: &[u32; BVH_WIDTH],
        _entered: u32,
    ) -> u32 {
        unreachable!("no vector ordering of children in this precision (has_vector_sort is false)")
    }
}
