// The CPU twin of the shader (shaders/*.wgsl), function by function with
// the same names, stage by stage in files of the same names (docs/bvh.md).
// Included twice: by src/cpu/f32.rs with `Real = f32` (the reference the
// GPU is diffed against) and by src/cpu/f64.rs with `Real = f64` (the
// oracle). The including module defines `Real`, `Vec3`, `Vec4`,
// `greater_of` and `lesser_of` (the shader's NaN-ignoring selects), and
// `intersect_boxes_ymm` with `has_ymm_boxes` (`intersect_boxes` in one
// 8-lane register, and whether the CPU can run it), and `push_sorted_zmm`
// (the ordering of entered children in vector registers).

include!("layout.rs");
include!("fetch.rs");
include!("intersect.rs");
include!("traverse.rs");
include!("traverse_cpu.rs");
include!("all_hits.rs");
include!("shade.rs");
include!("sample.rs");
