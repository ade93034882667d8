//! A part of one image (`lambert render --tile I/N`): a band of its rows,
//! rendered exactly as in the whole image and written as an EXR part file
//! for `merge`.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::open;
use crate::error::Result;
use crate::gpu::AdapterRequest;
use crate::parts::{Tile, settings_hash, write_part};
use crate::progress::ProgressSink;
use crate::render::DeviceChoice;
use crate::scene::{RenderSettings, Scene};

/// One part to render and write.
pub struct TileJob<'a> {
    pub tile: Tile,
    pub output: &'a Path,
    pub device: DeviceChoice,
    pub adapter: &'a AdapterRequest,
}

/// What `render_tile` did.
pub struct TileReport {
    pub output: PathBuf,
    pub tile: Tile,
    /// The image's rows this part holds.
    pub rows: Range<u32>,
    pub width: u32,
    pub height: u32,
    /// `Renderer::describe` of the device it rendered on.
    pub device: String,
    /// Rendering and writing the part.
    pub elapsed: Duration,
}

/// Renders `job.tile`'s rows of `scene` with `settings` and writes them.
pub fn render_tile(
    scene: Scene,
    settings: &RenderSettings,
    job: &TileJob,
    sink: Option<&dyn ProgressSink>,
) -> Result<TileReport> {
    let view = settings.view.clone();
    let rows = job.tile.rows(view.camera.height)?;
    let scene = Arc::new(scene.with_settings(settings));
    let (mut renderer, _) = open(Arc::clone(&scene), job.device, job.adapter, sink)?;
    let device = if renderer.is_cpu() { "cpu" } else { "gpu" };
    let hash = settings_hash(&scene, &view, device);
    // A GPU has its own copy of the geometry now: the host's can go.
    drop(scene);
    let start = Instant::now();
    let (rendered, _) = renderer.render_rows(&view, rows.clone(), sink)?;
    write_part(
        job.output,
        &rendered.image,
        job.tile,
        view.camera.height,
        rows.clone(),
        &hash,
    )?;
    Ok(TileReport {
        output: job.output.to_path_buf(),
        tile: job.tile,
        rows,
        width: view.camera.width,
        height: view.camera.height,
        device: renderer.describe(),
        elapsed: start.elapsed(),
    })
}
