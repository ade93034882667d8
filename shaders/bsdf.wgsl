// Stage: the BSDF. In branch `mat`, only its parameters, which
// `material_at` (shaders/material.wgsl) fills; the BSDF engineer's file,
// with the BSDF itself, replaces this one. CPU twin: src/cpu/bsdf.rs.

// What the BSDF reads at a surface point: the base colour (linear RGB),
// metalness, perceptual roughness (α = roughness²) and the material kind
// (MATERIAL_LAMBERT, MATERIAL_METALLIC_ROUGHNESS).
struct BsdfParams {
    base_color: vec3<f32>,
    metallic: f32,
    roughness: f32,
    kind: u32,
}
