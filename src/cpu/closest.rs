//! Closest points, the twin of shaders/closest.wgsl: the nearest point of
//! a triangle to a point (`closest_point_triangle`, its arithmetic written
//! out operation by operation as in the shader, so both round alike), the
//! distance of a box (`box_distance2`), the order of candidates (`better`)
//! and the traversal (`closest_point`). The CPU walks its own 256-byte
//! nodes nearest first, the GPU its compressed ones: `better` is a total
//! order (distance, then primitive id) and both traversals visit every box
//! that could hold a candidate as good as the best so far
//! (`cull_bound`), so they find the same answer, bit for bit.
//!
//! Written once for both precisions: `kernel!` (kernel.rs) expands it
//! into `cpu::f32` and `cpu::f64`, whose `Real` and vector types it takes;
//! its items here are the single-precision ones; the macro is in
//! stage.rs.

pub(super) mod stage;

pub use super::f32::{
    BoxQueue, Nearest, better, box_distance2, closest_on_segment, closest_point,
    closest_point_block, closest_point_triangle, cull_bound, dot3, query_margin,
};
