//! lambert: a GPU ray tracer (WGSL compute through wgpu) with a CPU reference
//! path that mirrors the shader function by function, and an f64 oracle.
//!
//! Where to look: `shaders/` (the kernel, by stage), `cpu::kernel` (its CPU
//! twin: intersection in `intersect_triangle`/`intersect_sphere`, shading in
//! `shade`), `gpu` (wgpu host code), `scene` and `loading` (input),
//! `output` (images), `diff` (comparisons), `rays` (ray queries), `jobs`
//! (render work the front ends share). The `lambert` binary (src/bin/lambert/)
//! is a front end of this library, built with the default `cli` feature.

pub mod adaptive;
pub mod bench;
pub mod bvh;
pub mod camera;
pub mod cpu;
pub mod cwbvh;
pub mod diff;
pub mod error;
pub mod files;
pub mod gpu;
pub mod inputs;
pub mod jobs;
pub mod layout;
pub mod lighting;
pub mod limits;
pub mod loading;
pub mod memory;
pub mod output;
pub mod parts;
pub mod placement;
pub mod probe;
pub mod progress;
pub mod proximity;
pub mod rays;
pub mod render;
pub mod scene;
pub mod shader_source;
pub mod texture;

pub use error::{Error, Result};
pub use scene::Scene;
