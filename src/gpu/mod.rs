//! The GPU path: adapter choice, scene upload, and tiled dispatch of
//! the shader (`shaders/*.wgsl`, composed in `shader_source`) through wgpu, split by concern:
//!
//! - `options`: the front ends' options and their variables' names;
//! - `adapter`: which adapter a request asks for, and the choice;
//! - `device`: the open device, its limits and errors;
//! - `upload`: the scene's buffers and the BVH's storage;
//! - `lighting`: the path integrator's lights' buffers and overrides;
//! - `bindings`: the bind group tables, checked against the shader;
//! - `shader`: the shader's source and its specialisation;
//! - `features`: what a device is opened with (timestamp queries, and the
//!   ray queries of `--accel hardware`);
//! - `hardware`: `--accel hardware`, the scene's acceleration structures
//!   for ray queries (wgpu's experimental API is named there and in
//!   `features` alone);
//! - `pipelines`: the shader module, its overrides and layouts;
//! - `renderer`: `GpuRenderer`, a scene resident on the device: its
//!   parts, and when each is built;
//! - `resident`: the scene's upload as the passes see it (bind groups,
//!   the uniform of a view), and `Host`, what a pass reads of the others;
//! - `render`: the tile renders' part (`Tiles`: the megakernel, or the
//!   wavefront), tile by tile, of the view each call is given;
//! - `wavefront`: the wavefront (shadow rays traced apart from the camera
//!   rays): its passes, lists and bind groups, and `ShadowDispatch`;
//! - `path_wave`: the path integrator's wavefront (a pass a bounce);
//! - `wave_list`: adaptive sampling's pixel lists in the wavefront;
//! - `progressive`: a render's samples added a few at a time (the viewer);
//! - `query`: ray queries and pixel lists (`Lists`);
//! - `proximity`: closest points, winding numbers, every hit along rays
//!   (`Proximity`);
//! - `timer` and `readback`: timestamps, and getting results back.

mod adapter;
pub mod bindings;
mod device;
mod features;
mod hardware;
mod lighting;
mod options;
mod path_wave;
mod pipelines;
mod progressive;
mod proximity;
mod query;
mod readback;
mod render;
mod renderer;
mod resident;
mod shader;
mod signal;
mod timer;
mod upload;
mod wave_list;
mod wavefront;

pub use adapter::{AdapterRequest, Presenting, cannot_run, enumerate_adapters};
pub use device::Gpu;
pub use hardware::{AccelerationStats, TriangleGeometry, offers_ray_queries};
pub use options::{GpuOptions, MAX_BUFFER_ENV, RAY_QUERY_GEOMETRY_ENV, SHADOW_DISPATCH_ENV};
pub use proximity::binding_runs;
pub use renderer::GpuRenderer;
pub use shader::{HARDWARE_SOURCE, SHADER_SOURCE, specialisation};
pub use timer::GpuTimings;
pub use upload::{BvhStorage, TEXELS_PER_ROW};
pub use wavefront::ShadowDispatch;

/// Side of the square tile one dispatch renders: small enough that no
/// dispatch runs long enough for a GPU watchdog to kill it.
pub const TILE: u32 = 256;
/// The `render` entry point's workgroup (x, y) in pixels
/// (`RENDER_WORKGROUP_X`/`_Y` in shaders/layout.wgsl), measured on lavapipe against
/// 16×16 and 64×1 (docs/bvh.md).
const RENDER_WORKGROUP: [u32; 2] = [8, 8];
// The render workgroup is every entry point's (`layout::WORKGROUP_INVOCATIONS`).
const _: () =
    assert!(RENDER_WORKGROUP[0] * RENDER_WORKGROUP[1] == crate::layout::WORKGROUP_INVOCATIONS);

/// Camera rays a dispatch of the wavefront render takes
/// at most: as many as the megakernel's largest tile dispatch (a 256²
/// tile at 3 samples per pixel: `GpuRenderer::tile_side` rounds up), whose
/// tiles it shares.
pub const WAVE_RAYS: u32 = 3 * TILE * TILE;
/// Shadow rays a wavefront dispatch queues at most where it has more than
/// a few lights: 8 lights of each pixel of a 1-spp tile; more lights
/// shrink its tile and its samples in turn, so no dispatch traces more
/// than a megakernel tile with as many lights.
pub const WAVE_SHADOW_RAYS: u32 = TILE * TILE * 8;

/// Bytes of the shader's `ShadowQuery` (a queued shadow ray) and
/// `WaveShading` (a camera ray's shading but for its shadows): GPU-only,
/// checked against naga's layout in tests/shaders.rs.
pub const SHADOW_QUERY_BYTES: u64 = 48;
pub const WAVE_SHADING_BYTES: u64 = 32;
/// Bytes of the shader's `PathRecord` (a path between its vertices, in
/// the path integrator's wavefront), checked as `ShadowQuery` is.
pub const PATH_RECORD_BYTES: u64 = 96;
/// Paths a dispatch of the path integrator's wavefront takes at most (its
/// records 18 MiB, within WebGPU's 128 MiB binding): as many as the
/// direct integrator's wavefront's camera rays, whose tiles it shares.
pub const PATH_WAVE_PATHS: u32 = WAVE_RAYS;
