// The ray-query module's layout (`--accel hardware`; src/shader_source.rs
// composes it first, shaders/layout.wgsl after it): the `enable` that only
// adapters with ray queries accept, its override and its bindings. The
// override is declared here, before shaders/layout.wgsl's override-sized
// workgroup arrays: naga 30 panics on a pipeline whose module declares an
// override used by a function after such an array (docs/hardware-rays.md).
enable wgpu_ray_query;

// Whether the scene's triangles are boxes (`TriangleGeometry::Boxes`):
// then every committed hit is one the shader generated.
override HARDWARE_TRIANGLE_BOXES: bool = false;

// Group 2, the ACCELERATION table (src/gpu/bindings.rs): the scene's TLAS,
// and the first primitive id of each geometry: geometry g of an instance
// whose custom index is c holds primitives hardware_runs[c + g] + its
// primitive index (src/gpu/hardware/plan.rs lays them out).
@group(2) @binding(0) var scene_tlas: acceleration_structure;
@group(2) @binding(1) var<storage, read> hardware_runs: array<u32>;
