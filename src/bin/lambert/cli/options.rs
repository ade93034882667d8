//! Options several commands share: the adapter, the scene's settings, the
//! view and a render's light, their value parsers, and the command line's
//! names of the library's choices (the library knows nothing of clap).

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};

use lambert::bench::BenchDevices;
use lambert::error::Result;
use lambert::gpu::AdapterRequest;
use lambert::jobs::RenderOverrides;
use lambert::render::DeviceChoice;
use lambert::scene::{Accel, Integrator, Intersect, RenderSettings, Scene, environment_option};

/// `--device` of render, diff and trace: `DeviceChoice`.
#[derive(Clone, Copy, Default, ValueEnum)]
pub(super) enum Device {
    /// A hardware GPU if there is one (or the adapter named), else the CPU path.
    #[default]
    Auto,
    /// Any wgpu adapter, software ones such as lavapipe included.
    Gpu,
    /// The CPU reference path.
    Cpu,
}

impl From<Device> for DeviceChoice {
    fn from(device: Device) -> DeviceChoice {
        match device {
            Device::Auto => DeviceChoice::Auto,
            Device::Gpu => DeviceChoice::Gpu,
            Device::Cpu => DeviceChoice::Cpu,
        }
    }
}

/// `--device` of bench: `BenchDevices`.
#[derive(Clone, Copy, ValueEnum)]
pub(super) enum BenchDevice {
    /// The GPU adapter (any, lavapipe included) and the CPU path.
    Both,
    Gpu,
    Cpu,
}

impl From<BenchDevice> for BenchDevices {
    fn from(device: BenchDevice) -> BenchDevices {
        match device {
            BenchDevice::Both => BenchDevices::Both,
            BenchDevice::Gpu => BenchDevices::Gpu,
            BenchDevice::Cpu => BenchDevices::Cpu,
        }
    }
}

/// `--accel`: `Accel`.
#[derive(Clone, Copy, ValueEnum)]
pub(super) enum AccelArg {
    /// The BVH (8-wide; compressed on the GPU).
    Bvh,
    /// Every primitive tested: the reference.
    BruteForce,
    /// The GPU's ray-tracing units through ray queries (docs/hardware-rays.md);
    /// the BVH where the device has none, with a note, and on the CPU path.
    Hardware,
}

impl From<AccelArg> for Accel {
    fn from(accel: AccelArg) -> Accel {
        match accel {
            AccelArg::Bvh => Accel::Bvh,
            AccelArg::BruteForce => Accel::BruteForce,
            AccelArg::Hardware => Accel::Hardware,
        }
    }
}

/// `--intersect`: `Intersect`.
#[derive(Clone, Copy, ValueEnum)]
enum IntersectArg {
    /// The lecture's plane intersection and three edge tests.
    Seed,
    /// Möller–Trumbore.
    MollerTrumbore,
    /// Woop, Benthin and Wald (JCGT 2013): no ray passes between triangles
    /// that share an edge.
    Watertight,
}

impl From<IntersectArg> for Intersect {
    fn from(intersect: IntersectArg) -> Intersect {
        match intersect {
            IntersectArg::Seed => Intersect::Seed,
            IntersectArg::MollerTrumbore => Intersect::MollerTrumbore,
            IntersectArg::Watertight => Intersect::Watertight,
        }
    }
}

/// `--integrator`: `Integrator`.
#[derive(Clone, Copy, ValueEnum)]
enum IntegratorArg {
    /// The lecture's light: ambient + Σ k·I·(n·l) with shadow rays.
    Direct,
    /// Path tracing: physically based materials, area lights, the
    /// environment and bounced light.
    Path,
}

impl From<IntegratorArg> for Integrator {
    fn from(integrator: IntegratorArg) -> Integrator {
        match integrator {
            IntegratorArg::Direct => Integrator::Direct,
            IntegratorArg::Path => Integrator::Path,
        }
    }
}

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

/// What a render reads and where it renders, as `render` and `view` take
/// them.
#[derive(Args)]
pub(super) struct SceneArgs {
    /// A scene (.toml) or model file.
    pub scene: PathBuf,
    #[arg(long, value_enum, default_value_t)]
    pub device: Device,
    #[command(flatten)]
    pub options: RenderOptions,
    #[command(flatten)]
    pub adapter: AdapterArgs,
}

/// Settings that override the scene file's.
#[derive(Args, Clone)]
pub(super) struct SceneOptions {
    /// How rays find their hits [default: the scene's render.accel, else bvh].
    #[arg(long, value_enum)]
    accel: Option<AccelArg>,
    /// Ray/triangle test [default: the scene's render.intersect, else watertight].
    #[arg(long, value_enum)]
    intersect: Option<IntersectArg>,
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

/// The scene at `path` (with the glTF camera `camera`), and its default
/// settings for the options to override.
fn load_scene(path: &Path, camera: Option<&str>) -> Result<(Scene, RenderSettings)> {
    let scene = Scene::load_with_camera(path, camera)?;
    let settings = scene.default_settings();
    Ok((scene, settings))
}

impl ViewOptions {
    pub(super) fn load(&self, path: &Path) -> Result<(Scene, RenderSettings)> {
        let (mut scene, mut settings) = load_scene(path, self.camera.as_deref())?;
        let overrides = RenderOverrides {
            width: self.width,
            height: self.height,
            ..RenderOverrides::default()
        };
        overrides.apply(&mut scene, &mut settings, &flag)?;
        Ok((scene, settings))
    }
}

impl SceneOptions {
    /// The options as the library applies them.
    fn overrides(&self) -> RenderOverrides {
        RenderOverrides {
            accel: self.accel.map(Into::into),
            intersect: self.intersect.map(Into::into),
            spp: self.spp,
            seed: self.seed,
            width: self.view.width,
            height: self.view.height,
            ..RenderOverrides::default()
        }
    }

    pub(super) fn apply(&self, scene: &mut Scene, settings: &mut RenderSettings) -> Result<()> {
        self.overrides().apply(scene, settings, &flag)
    }
}

/// An option's name on the command line, for the library's errors.
fn flag(name: &str) -> String {
    format!("--{name}")
}

/// `SceneOptions`, and the light of a render.
#[derive(Args, Clone)]
pub(super) struct RenderOptions {
    /// Ambient light, R,G,B or one value for grey [default: a scene's
    /// render.ambient; a model file's 0.1 when it has no lights of its
    /// own, else 0].
    #[arg(long, value_name = "R[,G,B]", value_parser = ambient)]
    ambient: Option<[f32; 3]>,
    /// How light reaches the camera [default: the scene's
    /// render.integrator, else direct].
    #[arg(long, value_enum)]
    integrator: Option<IntegratorArg>,
    /// Under --integrator path, the most surfaces a path hits [default:
    /// the scene's render.max_depth, else 8].
    #[arg(long, value_name = "N")]
    max_depth: Option<u32>,
    /// Light from every direction at infinity, for the path integrator: an
    /// equirectangular .hdr or .exr map, or a colour R,G,B (one value:
    /// grey) [default: a scene's [environment]; a model file's none].
    #[arg(long, value_name = "FILE|R[,G,B]")]
    environment: Option<String>,
    /// The environment's radiance multiplied by this.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 1.0,
        requires = "environment"
    )]
    environment_strength: f64,
    /// The environment's map turned about +Y by this many degrees.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        requires = "environment"
    )]
    environment_rotation: f64,
    #[command(flatten)]
    scene: SceneOptions,
}

impl RenderOptions {
    /// `--spp`, if given.
    pub(super) fn spp(&self) -> Option<u32> {
        self.scene.spp
    }

    /// The scene with the options' light: `--ambient` in its settings,
    /// `--environment` (scene content, as a file's `[environment]`, read
    /// once here) replacing its own.
    pub(super) fn load(&self, path: &Path) -> Result<(Scene, RenderSettings)> {
        let (mut scene, mut settings) = load_scene(path, self.scene.view.camera.as_deref())?;
        let environment = self
            .environment
            .as_deref()
            .map(|text| {
                environment_option(text, self.environment_strength, self.environment_rotation)
            })
            .transpose()?;
        let overrides = RenderOverrides {
            ambient: self.ambient,
            integrator: self.integrator.map(Into::into),
            max_depth: self.max_depth,
            environment,
            ..self.scene.overrides()
        };
        overrides.apply(&mut scene, &mut settings, &flag)?;
        Ok((scene, settings))
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
