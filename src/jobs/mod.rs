//! Render jobs, the work the front ends share (the `lambert` binary, and
//! the Python package): one image (`image`, with a time budget or adaptive
//! sampling), a part of one (`tile`), turntable frames (`turntable`), and
//! the queries beyond the first hit over files (`query`). Each
//! opens the device, renders and writes, tells a `ProgressSink` what it is
//! doing as it goes, and returns a report for its caller to print; the
//! caller parses options and loads the scene. Also the f64 oracle's scene
//! and a plain GPU render, which `diff` and the benchmarks share.

use std::sync::Arc;
use std::time::Duration;

use web_time::Instant;

use crate::camera::View;
use crate::error::{Error, Result};
use crate::gpu::AdapterRequest;
use crate::output::Rendered;
use crate::progress::{Progress, ProgressSink};
use crate::render::{DeviceChoice, Renderer, open_gpu};
use crate::scene::{Accel, Intersect, RenderSettings, Scene};

mod image;
mod options;
mod query;
mod tile;
mod turntable;

pub use image::{
    BudgetPlan, BudgetReport, BvhSummary, ImageJob, ImageReport, Sampled, Sampling, render_image,
    render_view,
};
pub use options::RenderOverrides;
pub use query::{
    INSIDE_WINDING, PointQuery, QueryJob, QueryKind, QueryReport, RayQuery, Sign, distances,
    inside, run_query, signed_distances,
};
// The point file is a file format beside the ray file (crate::rays).
pub use crate::rays::{POINT_BYTES, parse_points, read_points};
pub use tile::{Band, TileJob, TileReport, render_band, render_tile};
pub use turntable::{
    FrameReport, TurntableJob, TurntableReport, frame_path, frame_paths, render_turntable,
};

/// The f64 oracle's version of `scene`: the watertight test, in double
/// precision, is the reference every variant and device is measured against.
pub fn oracle_scene(scene: &Scene) -> Scene {
    let mut oracle = scene.clone();
    oracle.intersect = Intersect::Watertight;
    oracle
}

/// Renders `scene` as `view` sees it on the GPU (any adapter, lavapipe
/// included), showing no progress.
pub fn render_gpu(scene: &Scene, view: &View, request: &AdapterRequest) -> Result<Rendered> {
    let mut renderer = open_gpu(scene, request)?;
    Ok(renderer.render(view, &Progress::hidden())?.0)
}

/// `render_gpu` through the GPU's ray queries (`--accel hardware`), or an
/// error saying why not where the device has none: what a comparison of
/// the hardware path (`lambert diff --compare hardware-cpu`) renders, which
/// must not compare the compute BVH in its place.
pub fn render_hardware(scene: &Scene, view: &View, request: &AdapterRequest) -> Result<Rendered> {
    let mut scene = scene.clone();
    scene.accel = Accel::Hardware;
    let mut renderer = open_gpu(&scene, request)?;
    if let Some(note) = renderer.accel_note() {
        return Err(Error::Gpu(note.to_string()));
    }
    Ok(renderer.render(view, &Progress::hidden())?.0)
}

/// Seconds as the reports print them: `1.234 s`.
pub fn seconds(d: Duration) -> String {
    format!("{:.3} s", d.as_secs_f64())
}

/// A line for the user, if the caller shows them.
fn say(sink: Option<&dyn ProgressSink>, text: &str) {
    if let Some(sink) = sink {
        sink.line(text);
    }
}

/// A renderer for `scene` on the device `choice` asks for, the note of a
/// fallback to the CPU path said; and how long opening took (the upload).
/// A GPU keeps its own copy of the scene: the host's goes with the last
/// `Arc` the caller holds.
fn open(
    scene: Arc<Scene>,
    choice: DeviceChoice,
    request: &AdapterRequest,
    sink: Option<&dyn ProgressSink>,
) -> Result<(Renderer, Duration)> {
    let start = Instant::now();
    let (renderer, note) = Renderer::open(scene, choice, request)?;
    let upload = start.elapsed();
    if let Some(note) = note {
        say(sink, &note);
    }
    Ok((renderer, upload))
}

/// `open` for `scene` rendered with `settings`, and the renderer's
/// description for the user.
fn open_with(
    scene: Scene,
    settings: &RenderSettings,
    choice: DeviceChoice,
    request: &AdapterRequest,
    sink: Option<&dyn ProgressSink>,
) -> Result<(Renderer, Duration, String)> {
    let (renderer, upload) = open(
        Arc::new(scene.with_settings(settings)),
        choice,
        request,
        sink,
    )?;
    let device = renderer.describe();
    Ok((renderer, upload, device))
}
