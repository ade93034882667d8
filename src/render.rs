//! Choosing where a scene renders (GPU through wgpu, or the CPU reference)
//! and rendering it there.

use std::time::{Duration, Instant};

use crate::camera::View;
use crate::cpu::{self, Precision};
use crate::error::{Error, Result};
use crate::gpu::{AdapterRequest, Gpu, GpuRenderer};
use crate::layout::{Hit, Ray};
use crate::output::Rendered;
use crate::progress::{Progress, ProgressSink};
use crate::scene::{Intersect, Scene};

/// Where to render (`--device`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DeviceChoice {
    /// A hardware GPU if there is one (or the adapter named), else the CPU path.
    #[default]
    Auto,
    /// Any wgpu adapter, software ones such as lavapipe included.
    Gpu,
    /// The CPU reference path.
    Cpu,
}

/// A scene resident on its device (GPU buffers and pipelines, or the CPU
/// path): render it again from another camera, or trace ray queries
/// against it, and nothing but the camera or the rays is uploaded.
pub enum Renderer {
    Gpu(Box<GpuRenderer>),
    Cpu,
}

/// Why `--device auto` took the CPU path.
fn fallback_note(error: &crate::Error) -> String {
    format!(
        "{error}\nnote: using the CPU path instead (--device gpu uses a software adapter such as lavapipe)"
    )
}

/// The renderers of one scene, each opened (and the scene uploaded to it)
/// once, on first use: what a long-lived scene (the Python package's)
/// keeps, so that `auto` and `gpu` share one GPU where they can.
pub struct Renderers {
    request: AdapterRequest,
    cpu: Renderer,
    gpu: Option<Renderer>,
    /// Whether `gpu` is a hardware adapter (`auto` uses it then).
    gpu_is_hardware: bool,
    /// Set once `auto` found no GPU to use: the note it gave.
    auto_fell_back: Option<String>,
}

impl Renderers {
    pub fn new(request: AdapterRequest) -> Renderers {
        Renderers {
            request,
            cpu: Renderer::Cpu,
            gpu: None,
            gpu_is_hardware: false,
            auto_fell_back: None,
        }
    }

    /// The renderer `choice` asks for, opening it if need be. The note, on
    /// the first fallback of `auto` to the CPU path only, says why.
    pub fn get(
        &mut self,
        scene: &Scene,
        choice: DeviceChoice,
    ) -> Result<(&mut Renderer, Option<String>)> {
        let named = self.request.names_adapter();
        match choice {
            DeviceChoice::Cpu => Ok((&mut self.cpu, None)),
            DeviceChoice::Gpu => {
                if self.gpu.is_none() {
                    self.open_gpu(scene, Gpu::open(&self.request, false)?)?;
                }
                Ok((self.gpu.as_mut().expect("opened"), None))
            }
            DeviceChoice::Auto => {
                if self.gpu.is_some() && (self.gpu_is_hardware || named) {
                    return Ok((self.gpu.as_mut().expect("opened"), None));
                }
                if self.auto_fell_back.is_some() {
                    return Ok((&mut self.cpu, None));
                }
                match Gpu::open(&self.request, !named).and_then(|gpu| self.open_gpu(scene, gpu)) {
                    Ok(()) => Ok((self.gpu.as_mut().expect("opened"), None)),
                    // No GPU, or a scene too large for it: the CPU path.
                    Err(e @ (Error::Gpu(_) | Error::GpuLimit(_))) => {
                        let note = fallback_note(&e);
                        self.auto_fell_back = Some(note.clone());
                        Ok((&mut self.cpu, Some(note)))
                    }
                    Err(e) => Err(e),
                }
            }
        }
    }

    fn open_gpu(&mut self, scene: &Scene, gpu: Gpu) -> Result<()> {
        self.gpu_is_hardware = !gpu.is_software();
        self.gpu = Some(Renderer::Gpu(Box::new(GpuRenderer::new(gpu, scene)?)));
        Ok(())
    }
}

/// Time spent in each stage of one render.
#[derive(Clone, Copy, Debug, Default)]
pub struct RenderTimings {
    pub render: Duration,
    pub readback: Duration,
    /// GPU time from timestamp queries, where the adapter supports them.
    pub device: Option<Duration>,
}

impl Renderer {
    /// Opens the device `choice` asks for and uploads `scene`. The string
    /// returned, if any, explains a fallback to the CPU path.
    pub fn open(
        scene: &Scene,
        choice: DeviceChoice,
        request: &AdapterRequest,
    ) -> Result<(Renderer, Option<String>)> {
        let gpu = match choice {
            DeviceChoice::Cpu => return Ok((Renderer::Cpu, None)),
            DeviceChoice::Gpu => Gpu::open(request, false)?,
            DeviceChoice::Auto => match Gpu::open(request, !request.names_adapter()) {
                Ok(gpu) => gpu,
                Err(e) => return Ok((Renderer::Cpu, Some(fallback_note(&e)))),
            },
        };
        match GpuRenderer::new(gpu, scene) {
            Ok(renderer) => Ok((Renderer::Gpu(Box::new(renderer)), None)),
            // A scene too large for the adapter still renders with auto.
            Err(Error::GpuLimit(e)) if choice == DeviceChoice::Auto => Ok((
                Renderer::Cpu,
                Some(format!("GPU: {e}\nnote: using the CPU path instead")),
            )),
            Err(e) => Err(e),
        }
    }

    pub fn is_cpu(&self) -> bool {
        matches!(self, Renderer::Cpu)
    }

    /// Device time of the last GPU `trace`, from timestamp queries.
    pub fn trace_device_time(&self) -> Option<std::time::Duration> {
        match self {
            Renderer::Gpu(r) => r.trace_device_time(),
            Renderer::Cpu => None,
        }
    }

    pub fn describe(&self) -> String {
        match self {
            Renderer::Gpu(r) => format!("GPU: {}", r.gpu().describe()),
            Renderer::Cpu => format!(
                "CPU reference path ({} threads)",
                rayon::current_num_threads()
            ),
        }
    }

    /// Renders `scene` as `view` sees it (any camera, size, spp or seed;
    /// `Scene::view` is the file's own), showing progress on `progress` if
    /// given.
    pub fn render(
        &mut self,
        scene: &Scene,
        view: &View,
        progress: Option<&dyn ProgressSink>,
    ) -> Result<(Rendered, RenderTimings)> {
        self.render_rows(scene, view, 0..view.camera.height, progress)
    }

    /// Renders rows `rows` of `view`'s image (a part of it: `--tile`),
    /// each pixel exactly as in the whole image.
    pub fn render_rows(
        &mut self,
        scene: &Scene,
        view: &View,
        rows: std::ops::Range<u32>,
        progress: Option<&dyn ProgressSink>,
    ) -> Result<(Rendered, RenderTimings)> {
        match self {
            Renderer::Gpu(renderer) => {
                renderer.set_view(scene, view);
                let progress = Progress::start(progress, renderer.tile_count(), "tiles");
                let (rendered, t) = renderer.render_rows(rows, &progress)?;
                progress.finish();
                Ok((
                    rendered,
                    RenderTimings {
                        render: t.render,
                        readback: t.readback,
                        device: t.device,
                    },
                ))
            }
            Renderer::Cpu => {
                let progress = Progress::start(progress, rows.len() as u64, "rows");
                let start = Instant::now();
                let rendered = cpu::render_rows(scene, view, Precision::F32, rows, &progress);
                progress.finish();
                Ok((
                    rendered,
                    RenderTimings {
                        render: start.elapsed(),
                        readback: Duration::ZERO,
                        device: None,
                    },
                ))
            }
        }
    }

    /// Renders the listed pixels with `view`'s spp and seed: mean colour
    /// and variance of the mean (adaptive sampling's later passes).
    pub fn render_pixel_list(
        &mut self,
        scene: &Scene,
        view: &View,
        pixels: &[[u32; 2]],
    ) -> Result<Vec<[f32; 4]>> {
        match self {
            Renderer::Gpu(renderer) => {
                renderer.set_view(scene, view);
                renderer.render_pixel_list(pixels)
            }
            Renderer::Cpu => Ok(cpu::render_pixel_list(scene, view, pixels)),
        }
    }

    /// Readies the device for `trace` (builds its pipeline).
    pub fn prepare_trace(&mut self, any_hit: bool, intersect: Intersect) -> Result<()> {
        match self {
            Renderer::Gpu(renderer) => renderer.prepare_trace(any_hit, intersect),
            Renderer::Cpu => Ok(()),
        }
    }

    /// Traces a ray query against `scene` (which must be the scene the
    /// engine was opened with) with the ray/triangle test `intersect`.
    pub fn trace(
        &mut self,
        scene: &Scene,
        rays: &[Ray],
        any_hit: bool,
        intersect: Intersect,
    ) -> Result<Vec<Hit>> {
        match self {
            Renderer::Gpu(renderer) => renderer.trace_rays(rays, any_hit, intersect),
            Renderer::Cpu => Ok(cpu::trace_rays_with(
                scene,
                rays,
                any_hit,
                intersect,
                cpu::CpuKernel::active(),
            )),
        }
    }
}
