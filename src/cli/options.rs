//! Options several commands share: the adapter, the scene's settings, the
//! view and a render's light, and their value parsers.

use std::path::Path;

use clap::Args;

use crate::error::{Error, Result};
use crate::gpu::AdapterRequest;
use crate::scene::{Accel, Intersect, Scene, validate_spp};

#[derive(Args, Clone)]
pub(super) struct AdapterArgs {
    /// Adapter whose name contains this (case-insensitive); else WGPU_ADAPTER_NAME.
    #[arg(long)]
    adapter: Option<String>,
    /// vulkan, metal, dx12 or gl; else WGPU_BACKEND, else all.
    #[arg(long)]
    backend: Option<String>,
}

impl AdapterArgs {
    /// The request, completed from the environment: wgpu's own variables
    /// and lambert's GPU ones (the library reads none).
    pub(super) fn request(&self) -> AdapterRequest {
        AdapterRequest {
            name: self.adapter.clone(),
            backend: self.backend.clone(),
            ..Default::default()
        }
        .with_environment(|name| std::env::var(name).ok())
    }
}

/// Settings that override the scene file's.
#[derive(Args, Clone)]
pub(super) struct SceneOptions {
    #[arg(long, value_enum, default_value_t)]
    accel: Accel,
    /// Ray/triangle test [default: the scene's render.intersect, else watertight].
    #[arg(long, value_enum)]
    intersect: Option<Intersect>,
    /// Samples per pixel [default: the scene's render.spp, else 1].
    #[arg(long)]
    spp: Option<u32>,
    /// Seed of the sample jitter [default: the scene's render.seed, else 0].
    #[arg(long)]
    seed: Option<u32>,
    #[command(flatten)]
    view: ViewOptions,
}

/// The image size and a glTF file's camera.
#[derive(Args, Clone)]
pub(super) struct ViewOptions {
    /// Image width [default: the scene's; a model file's 1024]; with only
    /// one of --width and --height, the other keeps the aspect ratio.
    #[arg(long)]
    width: Option<u32>,
    /// Image height [default: the scene's; a model file's 768, or its
    /// glTF camera's aspect ratio].
    #[arg(long)]
    height: Option<u32>,
    /// A glTF file's camera, by name [default: its first perspective one].
    #[arg(long)]
    camera: Option<String>,
}

impl ViewOptions {
    pub(super) fn load(&self, path: &Path) -> Result<Scene> {
        let mut scene = Scene::load_with_camera(path, self.camera.as_deref())?;
        self.apply(&mut scene)?;
        Ok(scene)
    }

    pub(super) fn apply(&self, scene: &mut Scene) -> Result<()> {
        scene.camera = scene
            .camera
            .resized(self.width, self.height)
            .map_err(|e| Error::Usage(format!("--width/--height: {e}")))?;
        Ok(())
    }
}

impl SceneOptions {
    pub(super) fn load(&self, path: &Path) -> Result<Scene> {
        let mut scene = Scene::load_with_camera(path, self.view.camera.as_deref())?;
        self.apply(&mut scene)?;
        Ok(scene)
    }

    pub(super) fn apply(&self, scene: &mut Scene) -> Result<()> {
        scene.accel = self.accel;
        if let Some(intersect) = self.intersect {
            scene.intersect = intersect;
        }
        if let Some(spp) = self.spp {
            validate_spp(spp).map_err(|e| Error::Usage(format!("--{e}")))?;
            scene.spp = spp;
        }
        if let Some(seed) = self.seed {
            scene.seed = seed;
        }
        self.view.apply(scene)
    }
}

/// `SceneOptions`, and the light of a render.
#[derive(Args, Clone)]
pub(super) struct RenderOptions {
    /// Ambient light, R,G,B or one value for grey [default: a scene's
    /// render.ambient; a model file's 0.1 when it has no lights of its
    /// own, else 0].
    #[arg(long, value_name = "R[,G,B]", value_parser = ambient)]
    ambient: Option<[f32; 3]>,
    #[command(flatten)]
    scene: SceneOptions,
}

impl RenderOptions {
    pub(super) fn load(&self, path: &Path) -> Result<Scene> {
        let mut scene = self.scene.load(path)?;
        if let Some(ambient) = self.ambient {
            scene.ambient = ambient;
        }
        Ok(scene)
    }
}

/// `R,G,B` or one value for all three, each a finite number ≥ 0.
fn ambient(text: &str) -> std::result::Result<[f32; 3], String> {
    let values = text
        .split(',')
        .map(non_negative)
        .collect::<std::result::Result<Vec<f32>, String>>()?;
    match values[..] {
        [v] => Ok([v; 3]),
        [r, g, b] => Ok([r, g, b]),
        _ => Err(format!(
            "'{text}' is not R,G,B or one value (got {} values)",
            values.len()
        )),
    }
}

/// A finite number ≥ 0.
pub(super) fn non_negative(text: &str) -> std::result::Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("'{text}' is not a finite number ≥ 0")),
    }
}

/// A number from 0 to 1.
pub(super) fn fraction(text: &str) -> std::result::Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("'{text}' is not a fraction from 0 to 1")),
    }
}
