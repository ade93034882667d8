//! A model file's bytes as the scene and settings `lambert render` gives
//! it, and its render on the browser's device.

use std::path::Path;

use lambert::Scene;
use lambert::gpu::{Gpu, GpuRenderer};
use lambert::jobs::RenderOverrides;
use lambert::output::Image;
use lambert::progress::Progress;
use lambert::scene::RenderSettings;

/// The scene of a model file's bytes with the settings `lambert render
/// NAME` renders it with, the size and spp given where they are: the
/// file's own camera or the framed one, the default light where it has
/// none, the default seed (`RenderOverrides`, the CLI's one rule).
pub fn scene(
    bytes: &[u8],
    path: &Path,
    width: Option<u32>,
    height: Option<u32>,
    spp: Option<u32>,
) -> lambert::Result<(Scene, RenderSettings)> {
    let mut scene = Scene::from_model_bytes(bytes, path, None)?;
    let mut settings = scene.default_settings();
    let overrides = RenderOverrides {
        width,
        height,
        spp,
        ..RenderOverrides::default()
    };
    overrides.apply(&mut scene, &mut settings, &|name| name.to_string())?;
    Ok((scene.with_settings(&settings), settings))
}

/// `lambert render NAME --width W --height H --spp N`'s image.
pub async fn render(
    gpu: &Gpu,
    bytes: &[u8],
    path: &Path,
    width: Option<u32>,
    height: Option<u32>,
    spp: Option<u32>,
) -> lambert::Result<Image> {
    let (scene, settings) = scene(bytes, path, width, height, spp)?;
    let mut renderer = GpuRenderer::open(gpu.clone(), &scene).await?;
    drop(scene);
    let (rendered, _) = renderer
        .render_async(&settings.view, &Progress::hidden())
        .await?;
    Ok(rendered.image)
}
