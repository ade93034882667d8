//! A part of one image (`lambert render --tile I/N`): a band of its rows,
//! rendered exactly as in the whole image and written as an EXR part file
//! for `merge`.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use web_time::Instant;

use super::open;
use crate::error::Result;
use crate::gpu::AdapterRequest;
use crate::output::Image;
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
    /// Opening the device, rendering and writing the part.
    pub elapsed: Duration,
}

/// A part rendered, not yet written.
pub struct Band {
    /// The part's rows of the image, `rows.len()` tall.
    pub image: Image,
    pub rows: Range<u32>,
    /// The whole image's height.
    pub height: u32,
    /// What the part records of its scene and settings (`settings_hash`).
    pub hash: String,
    /// `Renderer::describe` of the device it rendered on.
    pub device: String,
}

/// Renders `tile`'s rows of `scene` with `settings` on `device`, each
/// pixel exactly as in the whole image.
pub fn render_band(
    scene: Scene,
    settings: &RenderSettings,
    tile: Tile,
    device: DeviceChoice,
    adapter: &AdapterRequest,
    sink: Option<&dyn ProgressSink>,
) -> Result<Band> {
    let view = settings.view.clone();
    let rows = tile.rows(view.camera.height)?;
    let scene = Arc::new(scene.with_settings(settings));
    let (mut renderer, _) = open(Arc::clone(&scene), device, adapter, sink)?;
    let kind = if renderer.is_cpu() { "cpu" } else { "gpu" };
    let hash = settings_hash(&scene, &view, kind);
    // A GPU has its own copy of the geometry now: the host's can go.
    drop(scene);
    let (rendered, _) = renderer.render_rows(&view, rows.clone(), sink)?;
    Ok(Band {
        image: rendered.image,
        rows,
        height: view.camera.height,
        hash,
        device: renderer.describe(),
    })
}

/// Renders `job.tile`'s rows of `scene` with `settings` and writes them.
pub fn render_tile(
    scene: Scene,
    settings: &RenderSettings,
    job: &TileJob,
    sink: Option<&dyn ProgressSink>,
) -> Result<TileReport> {
    let start = Instant::now();
    let band = render_band(scene, settings, job.tile, job.device, job.adapter, sink)?;
    write_part(
        job.output,
        &band.image,
        job.tile,
        band.height,
        band.rows.clone(),
        &band.hash,
    )?;
    Ok(TileReport {
        output: job.output.to_path_buf(),
        tile: job.tile,
        rows: band.rows,
        width: band.image.width,
        height: band.height,
        device: band.device,
        elapsed: start.elapsed(),
    })
}
