//! The options a front end read from the environment for the GPU, and
//! their variables' names: what both the adapter's request and the open
//! device carry (in a file of their own, so neither imports the other).

use crate::error::{Error, Result};

/// `LAMBERT_GPU_MAX_BUFFER_BYTES`: a cap on the buffer and binding sizes
/// lambert requests from the adapter (`Gpu::open_limited`).
pub const MAX_BUFFER_ENV: &str = "LAMBERT_GPU_MAX_BUFFER_BYTES";

/// `LAMBERT_SHADOW_DISPATCH`: megakernel or wavefront
/// (`ShadowDispatch`; unset, the wavefront wherever it applies under the
/// direct integrator, the megakernel under the path integrator).
pub const SHADOW_DISPATCH_ENV: &str = "LAMBERT_SHADOW_DISPATCH";

/// `LAMBERT_RAY_QUERY_GEOMETRY`: how `--accel hardware` gives the driver
/// its triangles, `triangles` or `boxes` (`hardware::TriangleGeometry`;
/// unset, boxes on lavapipe and triangles elsewhere).
pub const RAY_QUERY_GEOMETRY_ENV: &str = "LAMBERT_RAY_QUERY_GEOMETRY";

/// Settings a front end found in the environment, as it found them: each
/// is parsed where it is used, so that a bad value fails only the work that
/// needs it.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// `MAX_BUFFER_ENV`: bytes, checked when a device is opened.
    pub max_buffer_bytes: Option<String>,
    /// `SHADOW_DISPATCH_ENV`, checked when a scene is uploaded.
    pub shadow_dispatch: Option<String>,
    /// `LLVMPIPE_THREADS_ENV`, Mesa's own: how many threads llvmpipe runs
    /// a dispatch on.
    pub llvmpipe_threads: Option<String>,
    /// `RAY_QUERY_GEOMETRY_ENV`, checked when a scene's acceleration
    /// structures are built.
    pub ray_query_geometry: Option<String>,
}

/// Mesa's variable for llvmpipe's thread count (its default: the CPUs).
pub const LLVMPIPE_THREADS_ENV: &str = "LP_NUM_THREADS";

impl GpuOptions {
    pub(super) fn max_buffer_bytes(&self) -> Result<Option<u64>> {
        match &self.max_buffer_bytes {
            None => Ok(None),
            Some(v) => v.trim().parse().map(Some).map_err(|_| {
                Error::Usage(format!("{MAX_BUFFER_ENV}={v}: expected a number of bytes"))
            }),
        }
    }
}
