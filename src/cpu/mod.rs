//! The CPU reference path: the shader's algorithm in Rust, run in parallel
//! with rayon. `f32` is the reference the GPU is diffed against; `f64` is the
//! same code in double precision, the oracle that measures both.

mod all_hits;
pub mod aov;
mod bsdf;
pub mod closest;
/// Single precision, as on the GPU.
#[allow(clippy::unnecessary_cast)]
pub mod f32;
/// Double precision: the oracle.
#[allow(clippy::unnecessary_cast)]
pub mod f64;
mod fetch;
mod integrator;
mod intersect;
mod kernel;
mod lanes;
mod layout;
mod lights;
mod material;
mod math;
mod packet;
mod precision;
mod prefetch;
mod proximity;
mod query;
mod render;
mod rows;
mod sample;
mod shade;
mod simd;
pub mod texture;
mod traverse;
mod traverse_cpu;
pub mod winding;

pub use precision::Scalar;
pub use prefetch::{LARGE_BVH_BYTES, prefetch_rows};
pub use proximity::{
    box_pad, closest_points, closest_points_with, count_intersections, list_intersections,
    solid_inside, sort_hits, spatial_order, winding_numbers,
};
pub use query::{
    Filled, QueryKernel, QueryOptions, QueryRays, RayFrame, SharedOut, TracedChunk, trace_rays,
    trace_rays_as, trace_rays_each, trace_rays_f64, trace_rays_gpu_twin, trace_rays_with,
    traces_in_packets,
};
pub use render::{
    add_samples, add_samples_or_cancel, render, render_gpu_twin, render_pixel_list, render_rows,
    render_with,
};
pub use rows::pack_rays;
pub use simd::{CPU_KERNEL_ENV, CpuKernel, with_simd};

/// Which precision the CPU path computes in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    F32,
    F64,
}
