//! The BSDF, the twin of shaders/bsdf.wgsl. In branch `mat`, only its
//! parameters, which `material_at` (material.rs) fills; the BSDF
//! engineer's file, with the BSDF itself, replaces this one. Written once
//! for both precisions: `kernel!` (kernel.rs) expands it into `cpu::f32`
//! and `cpu::f64`, whose `Real` and `Vec3` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! bsdf {
    () => {
        /// What the BSDF reads at a surface point: the base colour (linear
        /// RGB), metalness, perceptual roughness (α = roughness²) and the
        /// material kind (`MATERIAL_LAMBERT`, `MATERIAL_METALLIC_ROUGHNESS`).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct BsdfParams {
            pub base_color: Vec3,
            pub metallic: Real,
            pub roughness: Real,
            pub kind: u32,
        }
    };
}
pub(crate) use bsdf;
