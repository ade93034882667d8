//! Texture sampling, the twin of shaders/texture.wgsl, function by
//! function with the same names, bit for bit: each float operation rounds
//! on its own (Rust neither fuses nor reassociates; the shader's `rounded`
//! stops its compiler doing so), and the rest is integer arithmetic
//! (docs/textures.md). The f64 oracle samples in f64 throughout, from
//! the texture coordinates on.
//!
//! Written once for both precisions: `kernel!` (kernel.rs) expands it
//! into `cpu::f32` and `cpu::f64`, whose `Real` and vector types it takes;
//! its items here are the single-precision ones; the macro is in
//! stage.rs.

pub(super) mod stage;

pub use super::f32::{
    Textures, difference_of_products, fixed_to_float, interpolate_uv, log2_fixed, rounded,
    texel_position, wrap_coordinate, wrap_texel,
};
