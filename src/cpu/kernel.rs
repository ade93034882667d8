//! The CPU twin of the shader (shaders/*.wgsl), function by function with
//! the same names, stage by stage in modules of the same names
//! (docs/bvh.md, docs/shaders.md), the texture sampler, closest points and
//! winding numbers included. Each stage module holds a macro of its items,
//! written once for both precisions; `kernel!` expands them all into the
//! module that invokes it: src/cpu/f32.rs (`Real = f32`, the reference
//! the GPU is diffed against) and src/cpu/f64.rs (`Real = f64`, the
//! oracle, so f64 end to end). A macro
//! rather than generic functions over a trait of both precisions keeps the
//! hot code as it was written, operation for operation and inlining for
//! inlining, in each.
//!
//! What differs by precision the stages take from one place: the trait
//! `Scalar` (src/cpu/precision.rs), which each precision's module
//! implements for its `Real`, and which the stages call by the trait's
//! name, `<Real as Scalar>::greater_of(…)`: `greater_of` and `lesser_of`
//! (the shader's NaN-ignoring selects), `high_half` (the split of
//! `two_square`), `intersect_boxes_ymm` with `has_ymm_boxes`
//! (`intersect_boxes` in one 8-lane register, and whether the CPU can run
//! it) and `push_sorted_zmm` with `has_vector_sort` (the ordering of
//! entered children in vector registers); the SIMD variants with the
//! kernel's types they take and the portable slab test (`KernelItems`,
//! which `kernel!` implements).
//! So a stage names nothing that the invoking module defines by hand
//! (tests/architecture_rules.rs checks that the precisions' modules
//! define nothing beside `kernel!` and their `Scalar`), and a precision
//! that lacks one of them does not compile.

/// The kernel in the invoking module, in single or double precision:
/// `Real` the scalar (`f32` or `f64`), `Vec2`, `Vec3` and `Vec4` glam's
/// vectors of it, `CameraBasis` the camera's basis in it
/// (`camera::f32::CameraBasis` or `camera::f64::CameraBasis`). The invoking
/// module implements `Scalar` for `Real`.
macro_rules! kernel {
    (f32) => {
        crate::cpu::kernel::kernel!(f32, glam::Vec2, glam::Vec3, glam::Vec4);
    };
    (f64) => {
        crate::cpu::kernel::kernel!(f64, glam::DVec2, glam::DVec3, glam::DVec4);
    };
    ($real:ident, $vec2:ty, $vec3:ty, $vec4:ty) => {
        use crate::cpu::precision::{KernelItems, Scalar};
        pub type Real = $real;
        pub type Vec2 = $vec2;
        pub type Vec3 = $vec3;
        pub type Vec4 = $vec4;
        pub use crate::camera::$real::CameraBasis;
        crate::cpu::layout::layout!();
        crate::cpu::math::math!();
        crate::cpu::bsdf::bsdf!();
        crate::cpu::fetch::fetch!();
        crate::cpu::intersect::intersect!();
        crate::cpu::traverse::traverse!();
        crate::cpu::traverse_cpu::traverse_cpu!();
        crate::cpu::all_hits::all_hits!();
        crate::cpu::shade::shade!();
        crate::cpu::lights::lights!();
        crate::cpu::sample::sample!();
        crate::cpu::texture::stage::texture!();
        crate::cpu::material::material!();
        crate::cpu::closest::stage::closest!();
        crate::cpu::winding::stage::winding!();
        crate::cpu::integrator::integrator!();

        impl KernelItems for Real {
            type Vec4 = Vec4;
            type Ray = Ray;
            type Slabs = Slabs;
            type BoxHits = BoxHits;
            type Stack = TraversalStack;

            #[inline(always)]
            fn intersect_boxes(ray: &Ray, slabs: &Slabs, node: &BvhNode) -> BoxHits {
                intersect_boxes(ray, slabs, node)
            }
        }
    };
}
pub(crate) use kernel;
