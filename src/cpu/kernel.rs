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
//! Beside the types it is given, the invoking module defines what differs
//! by precision: `greater_of` and `lesser_of` (the shader's NaN-ignoring
//! selects), `high_half` (the split of `two_square`), `intersect_boxes_ymm`
//! with `has_ymm_boxes` (`intersect_boxes` in one 8-lane register, and
//! whether the CPU can run it), `push_sorted_zmm` (the ordering of entered
//! children in vector registers) and `CameraBasis`.

/// The kernel in the invoking module, with `Real`, `Vec2`, `Vec3` and
/// `Vec4` the given scalar and glam vector types.
macro_rules! kernel {
    ($real:ty, $vec2:ty, $vec3:ty, $vec4:ty) => {
        pub type Real = $real;
        pub type Vec2 = $vec2;
        pub type Vec3 = $vec3;
        pub type Vec4 = $vec4;
        crate::cpu::layout::layout!();
        crate::cpu::math::math!();
        crate::cpu::fetch::fetch!();
        crate::cpu::intersect::intersect!();
        crate::cpu::traverse::traverse!();
        crate::cpu::traverse_cpu::traverse_cpu!();
        crate::cpu::all_hits::all_hits!();
        crate::cpu::shade::shade!();
        crate::cpu::lights::lights!();
        crate::cpu::sample::sample!();
        crate::cpu::texture::stage::texture!();
        crate::cpu::bsdf::bsdf!();
        crate::cpu::material::material!();
        crate::cpu::closest::stage::closest!();
        crate::cpu::winding::stage::winding!();
    };
}
pub(crate) use kernel;
