//! Choosing where a scene renders (GPU through wgpu, or the CPU reference)
//! and rendering it there.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use web_time::Instant;

use crate::camera::View;
use crate::cpu::{self, Precision};
use crate::error::{Error, Result};
use crate::gpu::{AdapterRequest, Gpu, GpuRenderer, Presenting};
use crate::layout::{Hit, Ray};
use crate::output::{Image, Rendered};
use crate::progress::{Progress, ProgressSink};
use crate::scene::{Accel, Integrator, Intersect, RenderSettings, Scene};

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
/// path sharing the scene): render it again from another view, or trace
/// ray queries against it, and nothing but the view or the rays is
/// uploaded. The GPU renderer keeps its own copy of all it needs, so the
/// host's geometry may go once it is opened. The front ends ask it through
/// its methods, never naming its variants.
pub enum Renderer {
    Gpu(Box<GpuRenderer>),
    Cpu(Arc<Scene>),
}

/// Why `--device auto` took the CPU path.
fn fallback_note(error: &crate::Error) -> String {
    format!(
        "{error}\nnote: using the CPU path instead (--device gpu uses a software adapter such as lavapipe)"
    )
}

/// Why `--device auto` took the CPU path for what a GPU's limits could not
/// hold.
fn limit_note(error: &str) -> String {
    format!("GPU: {error}\nnote: using the CPU path instead")
}

/// Runs `work` on `renderer`, opened for `choice`; where that is auto and
/// the work hits a limit of its GPU (`Error::GpuLimit`: the scene fit, a
/// query's answers do not), runs it again on the CPU path sharing `scene`,
/// and returns auto's note of why with the answers.
pub fn with_fallback<T>(
    renderer: &mut Renderer,
    choice: DeviceChoice,
    scene: &Arc<Scene>,
    work: impl Fn(&mut Renderer) -> Result<T>,
) -> Result<(T, Option<String>)> {
    match work(renderer) {
        Err(Error::GpuLimit(e)) if choice == DeviceChoice::Auto && !renderer.is_cpu() => {
            let answers = work(&mut Renderer::Cpu(Arc::clone(scene)))?;
            Ok((answers, Some(limit_note(&e))))
        }
        done => done.map(|answers| (answers, None)),
    }
}

/// What `open_device` opened.
enum Opened {
    Gpu(Box<GpuRenderer>),
    /// The CPU path, with the note of `auto`'s fallback, if it fell back.
    Cpu(Option<String>),
}

/// The device of a GPU render: any adapter `request` matches (only
/// hardware ones with `hardware_only`), among those that can present to
/// the window if one is given.
fn open_gpu_device(
    request: &AdapterRequest,
    hardware_only: bool,
    presenting: Option<&Presenting>,
) -> Result<Gpu> {
    match presenting {
        Some(p) => Gpu::open_presenting(request, hardware_only, p),
        None => Gpu::open(request, hardware_only),
    }
}

/// The one policy of where a scene renders: `cpu` the CPU path; `gpu` any
/// adapter (`open_gpu`); `auto` a hardware adapter (or the one named),
/// else the CPU path with a note, as for a scene too large for the
/// adapter. With a window, only adapters that can present to it count.
fn open_device(
    scene: &Scene,
    choice: DeviceChoice,
    request: &AdapterRequest,
    presenting: Option<&Presenting>,
) -> Result<Opened> {
    let request = &with_ray_queries(scene, request);
    match choice {
        DeviceChoice::Cpu => Ok(Opened::Cpu(None)),
        DeviceChoice::Gpu => Ok(Opened::Gpu(Box::new(open_any_gpu(
            scene, request, presenting,
        )?))),
        DeviceChoice::Auto => {
            let gpu = match open_gpu_device(request, !request.names_adapter(), presenting) {
                Ok(gpu) => gpu,
                Err(e) => return Ok(Opened::Cpu(Some(fallback_note(&e)))),
            };
            match GpuRenderer::new(gpu, scene) {
                Ok(renderer) => Ok(Opened::Gpu(Box::new(renderer))),
                Err(Error::GpuLimit(e)) => Ok(Opened::Cpu(Some(limit_note(&e)))),
                Err(e) => Err(e),
            }
        }
    }
}

/// `scene` uploaded to a GPU as `--device gpu` opens one: any adapter,
/// software ones included, failing if none opens or the scene does not fit.
/// Also what the measurements and comparisons of the GPU itself use.
pub fn open_gpu(scene: &Scene, request: &AdapterRequest) -> Result<GpuRenderer> {
    open_any_gpu(scene, &with_ray_queries(scene, request), None)
}

/// `request`, asking for ray queries where `scene` is traced in them
/// (`--accel hardware`; otherwise the device is opened without them).
fn with_ray_queries(scene: &Scene, request: &AdapterRequest) -> AdapterRequest {
    AdapterRequest {
        ray_queries: scene.accel == Accel::Hardware,
        ..request.clone()
    }
}

/// The note of a GPU renderer that was asked for `--accel hardware` but
/// traces through the compute BVH (`GpuRenderer::accel_note`).
fn accel_note(renderer: &GpuRenderer) -> Option<String> {
    renderer.accel_note().map(str::to_string)
}

fn open_any_gpu(
    scene: &Scene,
    request: &AdapterRequest,
    presenting: Option<&Presenting>,
) -> Result<GpuRenderer> {
    GpuRenderer::new(open_gpu_device(request, false, presenting)?, scene)
}

/// The renderers of one scene, each opened (and the scene uploaded to it)
/// once, on first use: what a long-lived scene (the Python package's)
/// keeps, so that `auto` and `gpu` share one GPU where they can.
pub struct Renderers {
    scene: Arc<Scene>,
    request: AdapterRequest,
    cpu: Renderer,
    gpu: Option<Renderer>,
    /// Whether `gpu` is a hardware adapter (`auto` uses it then).
    gpu_is_hardware: bool,
    /// Set once `auto` took the CPU path.
    auto_fell_back: bool,
}

impl Renderers {
    pub fn new(scene: Arc<Scene>, request: AdapterRequest) -> Renderers {
        Renderers {
            cpu: Renderer::Cpu(Arc::clone(&scene)),
            scene,
            request,
            gpu: None,
            gpu_is_hardware: false,
            auto_fell_back: false,
        }
    }

    /// The integrator (and a path's depth) of the renders that follow, on
    /// every renderer: the scene's copy changed once (the CPU path's), the
    /// GPU's pipelines specialised again, its buffers kept.
    pub fn set_integrator(&mut self, integrator: Integrator, max_depth: u32) -> Result<()> {
        if self.scene.integrator == integrator && self.scene.max_depth == max_depth {
            return Ok(());
        }
        let scene = Arc::make_mut(&mut self.scene);
        let settings = RenderSettings {
            integrator,
            max_depth,
            ..scene.default_settings()
        };
        let lights = scene.lights.len();
        *scene =
            std::mem::replace(scene, Scene::from_triangles(Vec::new())).with_settings(&settings);
        self.cpu = Renderer::Cpu(Arc::clone(&self.scene));
        if self.scene.lights.len() != lights {
            // Another set of lights: uploaded again on the GPU's next use.
            self.gpu = None;
        } else if let Some(gpu) = &mut self.gpu {
            gpu.set_integrator(integrator, max_depth)?;
        }
        Ok(())
    }

    /// Runs `work` on the renderer `choice` asks for from `renderers`
    /// (opened if need be), holding its lock only while a GPU works: the
    /// CPU path runs on a renderer of its own sharing the scene, so that
    /// threads render and query at once. Returns `get`'s note too.
    pub fn run<T>(
        renderers: &Mutex<Renderers>,
        choice: DeviceChoice,
        work: impl FnOnce(&mut Renderer) -> Result<T>,
    ) -> Result<(T, Option<String>)> {
        let mut guard = renderers.lock().unwrap_or_else(|e| e.into_inner());
        let (renderer, note) = guard.get(choice)?;
        if !renderer.is_cpu() {
            return Ok((work(renderer)?, note));
        }
        let mut cpu = Renderer::Cpu(Arc::clone(&guard.scene));
        drop(guard);
        Ok((work(&mut cpu)?, note))
    }

    /// The renderer `choice` asks for, opening it if need be. The note, on
    /// the first fallback of `auto` to the CPU path only (or when a GPU
    /// opened for `--accel hardware` has no ray queries), says why.
    pub fn get(&mut self, choice: DeviceChoice) -> Result<(&mut Renderer, Option<String>)> {
        let named = self.request.names_adapter();
        match choice {
            DeviceChoice::Cpu => Ok((&mut self.cpu, None)),
            DeviceChoice::Gpu | DeviceChoice::Auto => {
                let usable = choice == DeviceChoice::Gpu || self.gpu_is_hardware || named;
                if self.gpu.is_some() && usable {
                    return Ok((self.gpu.as_mut().expect("opened"), None));
                }
                if choice == DeviceChoice::Auto && self.auto_fell_back {
                    return Ok((&mut self.cpu, None));
                }
                match open_device(&self.scene, choice, &self.request, None)? {
                    Opened::Gpu(mut renderer) => {
                        renderer.set_winding_source(Arc::downgrade(&self.scene));
                        self.gpu_is_hardware = !renderer.gpu().is_software();
                        let note = accel_note(&renderer);
                        let gpu = self.gpu.insert(Renderer::Gpu(renderer));
                        Ok((gpu, note))
                    }
                    Opened::Cpu(note) => {
                        self.auto_fell_back = true;
                        Ok((&mut self.cpu, note))
                    }
                }
            }
        }
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
    /// Opens the device `choice` asks for and uploads `scene` to it, or
    /// shares it with the CPU path. The string returned, if any, explains
    /// a fallback to the CPU path.
    pub fn open(
        scene: Arc<Scene>,
        choice: DeviceChoice,
        request: &AdapterRequest,
    ) -> Result<(Renderer, Option<String>)> {
        Renderer::open_presenting(scene, choice, request, None)
    }

    /// `open`, for a window (the viewer's): a GPU is one that can present
    /// to it, so that the image is shown on the device that renders it.
    pub fn open_presenting(
        scene: Arc<Scene>,
        choice: DeviceChoice,
        request: &AdapterRequest,
        presenting: Option<&Presenting>,
    ) -> Result<(Renderer, Option<String>)> {
        Ok(match open_device(&scene, choice, request, presenting)? {
            Opened::Gpu(mut renderer) => {
                // Winding queries build the scene's winding tree from it.
                renderer.set_winding_source(Arc::downgrade(&scene));
                let note = accel_note(&renderer);
                (Renderer::Gpu(renderer), note)
            }
            Opened::Cpu(note) => (Renderer::Cpu(scene), note),
        })
    }

    /// A renderer of `scene` on `gpu` (a device already open: the
    /// viewer's, for another scene), or with none on the CPU path sharing
    /// it.
    pub fn open_on(scene: Arc<Scene>, gpu: Option<&Gpu>) -> Result<Renderer> {
        match gpu {
            Some(gpu) => pollster::block_on(Renderer::open_on_gpu(scene, gpu)),
            None => Ok(Renderer::Cpu(scene)),
        }
    }

    /// `open_on` a GPU, awaited rather than blocking (the web's).
    pub async fn open_on_gpu(scene: Arc<Scene>, gpu: &Gpu) -> Result<Renderer> {
        let mut renderer = GpuRenderer::open(gpu.clone(), &scene).await?;
        renderer.set_winding_source(Arc::downgrade(&scene));
        Ok(Renderer::Gpu(Box::new(renderer)))
    }

    pub fn is_cpu(&self) -> bool {
        matches!(self, Renderer::Cpu(_))
    }

    /// The GPU it renders on; None on the CPU path.
    pub fn gpu(&self) -> Option<&Gpu> {
        match self {
            Renderer::Gpu(r) => Some(r.gpu()),
            Renderer::Cpu(_) => None,
        }
    }

    /// The scene the CPU path shares; None on a GPU (which keeps its own
    /// copy of what it renders).
    pub fn shared_scene(&self) -> Option<&Arc<Scene>> {
        match self {
            Renderer::Gpu(_) => None,
            Renderer::Cpu(scene) => Some(scene),
        }
    }

    /// Turns shadows on or off for the renders that follow: on a GPU its
    /// pipelines are specialised again (the scene stays uploaded); the
    /// CPU path changes its scene, in place where no one else holds it.
    pub fn set_shadows(&mut self, on: bool) -> Result<()> {
        match self {
            Renderer::Gpu(renderer) => renderer.set_shadows(on),
            Renderer::Cpu(scene) => {
                if scene.shadows != on {
                    Arc::make_mut(scene).shadows = on;
                }
                Ok(())
            }
        }
    }

    /// Switches the integrator (and a path's depth) for the renders that
    /// follow, as `set_shadows` switches shadows.
    pub fn set_integrator(&mut self, integrator: Integrator, max_depth: u32) -> Result<()> {
        match self {
            Renderer::Gpu(renderer) => renderer.set_integrator(integrator, max_depth),
            Renderer::Cpu(scene) => {
                if scene.integrator != integrator || scene.max_depth != max_depth {
                    let scene = Arc::make_mut(scene);
                    scene.integrator = integrator;
                    scene.max_depth = max_depth;
                }
                Ok(())
            }
        }
    }

    /// The acceleration structures its rays go through where they go
    /// through the GPU's ray queries (`--accel hardware`), else None.
    pub fn ray_queries(&self) -> Option<crate::gpu::AccelerationStats> {
        match self {
            Renderer::Gpu(r) => r.ray_queries().copied(),
            Renderer::Cpu(_) => None,
        }
    }

    /// Where this renderer traces through ray queries (`--accel
    /// hardware`) but `what` does not (the geometric queries walk the
    /// compute BVH): the note saying so, for the front end to print.
    pub fn bvh_note(&self, what: &str) -> Option<String> {
        match self {
            Renderer::Gpu(r) if r.ray_queries().is_some() => Some(format!(
                "note: --accel hardware: {what} go through the compute BVH \
                 (docs/hardware-rays.md, \"Fallbacks\")"
            )),
            _ => None,
        }
    }

    /// Device time of the last GPU `trace`, from timestamp queries.
    pub fn trace_device_time(&self) -> Option<std::time::Duration> {
        match self {
            Renderer::Gpu(r) => r.trace_device_time(),
            Renderer::Cpu(_) => None,
        }
    }

    pub fn describe(&self) -> String {
        match self {
            Renderer::Gpu(r) if r.ray_queries().is_some() => {
                format!("GPU: {}, ray queries", r.gpu().describe())
            }
            Renderer::Gpu(r) => format!("GPU: {}", r.gpu().describe()),
            Renderer::Cpu(_) => format!(
                "CPU reference path ({} threads)",
                rayon::current_num_threads()
            ),
        }
    }

    /// Renders the scene as `view` sees it (any camera, size, spp or seed;
    /// `Scene::view` is the file's own), showing progress on `progress` if
    /// given.
    pub fn render(
        &mut self,
        view: &View,
        progress: Option<&dyn ProgressSink>,
    ) -> Result<(Rendered, RenderTimings)> {
        self.render_rows(view, 0..view.camera.height, progress)
    }

    /// Renders rows `rows` of `view`'s image (a part of it: `--tile`),
    /// each pixel exactly as in the whole image.
    pub fn render_rows(
        &mut self,
        view: &View,
        rows: std::ops::Range<u32>,
        progress: Option<&dyn ProgressSink>,
    ) -> Result<(Rendered, RenderTimings)> {
        match self {
            Renderer::Gpu(renderer) => {
                let progress = Progress::start(progress, renderer.tile_count(view), "tiles");
                let (rendered, t) = renderer.render_rows(view, rows, &progress)?;
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
            Renderer::Cpu(scene) => {
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
    pub fn render_pixel_list(&mut self, view: &View, pixels: &[[u32; 2]]) -> Result<Vec<[f32; 4]>> {
        match self {
            Renderer::Gpu(renderer) => renderer.render_pixel_list(view, pixels),
            Renderer::Cpu(scene) => Ok(cpu::render_pixel_list(scene, view, pixels)),
        }
    }

    /// Adds the next `count` samples of `progressive`'s view (fewer when
    /// fewer are left) on this renderer's device.
    pub fn add_samples(&mut self, progressive: &mut Progressive, count: u32) -> Result<()> {
        self.add_samples_or_cancel(progressive, count, &AtomicBool::new(false))
            .map(|_| ())
    }

    /// `add_samples`, stopped between tiles (rows on the CPU path) once
    /// another thread sets `cancel`: then `progressive` starts again from
    /// its first sample and this returns false. (A batch of all the view's
    /// samples at once is a plain GPU render, which stops only at its end.)
    pub fn add_samples_or_cancel(
        &mut self,
        progressive: &mut Progressive,
        count: u32,
        cancel: &AtomicBool,
    ) -> Result<bool> {
        pollster::block_on(self.add_samples_async(progressive, count, cancel))
    }

    /// `add_samples_or_cancel`, awaited rather than blocking (the web's).
    pub async fn add_samples_async(
        &mut self,
        progressive: &mut Progressive,
        count: u32,
        cancel: &AtomicBool,
    ) -> Result<bool> {
        let view = &progressive.view;
        let start = progressive.samples;
        let samples = start..start.saturating_add(count).min(view.spp);
        let finished = match self {
            Renderer::Gpu(renderer) => {
                renderer
                    .add_samples_async(view, samples.clone(), &mut progressive.sums, cancel)
                    .await?
            }
            Renderer::Cpu(scene) => cpu::add_samples_or_cancel(
                scene,
                view,
                samples.clone(),
                &mut progressive.sums,
                cancel,
            )
            .map_err(Error::Usage)?,
        };
        if cancel.load(Ordering::Relaxed) {
            // The sums hold part of the batch.
            *progressive = Progressive::new(progressive.view.clone());
            return Ok(false);
        }
        progressive.samples = samples.end;
        progressive.finished = finished;
        Ok(true)
    }

    /// Readies the device for `trace` (builds its pipeline).
    pub fn prepare_trace(&mut self, any_hit: bool, intersect: Intersect) -> Result<()> {
        match self {
            Renderer::Gpu(renderer) => renderer.prepare_trace(any_hit, intersect),
            Renderer::Cpu(_) => Ok(()),
        }
    }

    /// `trace` for rays already in the scene's local frame
    /// (`Placement::local_ray`), hits in that frame.
    pub fn trace_local(
        &mut self,
        rays: &[Ray],
        any_hit: bool,
        intersect: Intersect,
    ) -> Result<Vec<Hit>> {
        match self {
            Renderer::Gpu(renderer) => renderer.trace_local_rays(rays, any_hit, intersect),
            Renderer::Cpu(scene) => {
                let mut hits = vec![Hit::MISS; rays.len()];
                let out = cpu::SharedOut::new(&mut hits);
                let options = cpu::QueryOptions {
                    any_hit,
                    intersect,
                    cpu_kernel: cpu::CpuKernel::active(),
                    normals: false,
                };
                let rays = cpu::QueryRays::Slice(rays);
                cpu::trace_rays_each(scene, rays, options, cpu::RayFrame::Local, &|chunk| {
                    // SAFETY: chunks are disjoint and within `hits`.
                    unsafe {
                        std::ptr::copy_nonoverlapping(
                            chunk.hits.as_ptr(),
                            out.at(chunk.start),
                            chunk.hits.len(),
                        )
                    }
                });
                Ok(hits)
            }
        }
    }

    /// Traces a ray query against the scene with the ray/triangle test
    /// `intersect`.
    pub fn trace(&mut self, rays: &[Ray], any_hit: bool, intersect: Intersect) -> Result<Vec<Hit>> {
        match self {
            Renderer::Gpu(renderer) => renderer.trace_rays(rays, any_hit, intersect),
            Renderer::Cpu(scene) => Ok(cpu::trace_rays_with(
                scene,
                rays,
                any_hit,
                intersect,
                cpu::CpuKernel::active(),
            )),
        }
    }
}

/// Every crossing of a list of rays (`Renderer::list_intersections`): ray
/// i's are `hits[ray_splits[i] .. ray_splits[i + 1]]`, sorted by t, then
/// triangle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IntersectionList {
    /// N + 1 offsets into `hits`.
    pub ray_splits: Vec<u64>,
    pub hits: Vec<crate::layout::ListedHit>,
}

/// A render refined a few samples at a time (`Renderer::add_samples`; the
/// viewer's): per pixel, the sums of the first `samples()` of the view's
/// `spp` stratified samples, in the order `render` adds them, so that
/// once all are added `image()` is bit for bit `Renderer::render(view)`'s
/// image.
pub struct Progressive {
    view: View,
    samples: u32,
    /// Colour sums and squared luminance, row by row.
    sums: Vec<[f32; 4]>,
    /// The renderer's own means, once every sample is in.
    finished: Option<Image>,
}

impl Progressive {
    pub fn new(view: View) -> Progressive {
        let pixels = view.camera.width as usize * view.camera.height as usize;
        Progressive {
            view,
            samples: 0,
            sums: vec![[0.0; 4]; pixels],
            finished: None,
        }
    }

    pub fn view(&self) -> &View {
        &self.view
    }

    /// Samples per pixel added so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Whether every one of the view's samples is in.
    pub fn is_finished(&self) -> bool {
        self.samples == self.view.spp
    }

    /// The image so far: each pixel's mean over the samples added (black
    /// before any), and once all are, the renderer's image itself.
    pub fn image(&self) -> Image {
        if let Some(image) = &self.finished {
            return image.clone();
        }
        let n = self.samples.max(1) as f32;
        Image {
            width: self.view.camera.width,
            height: self.view.camera.height,
            rgb: self
                .sums
                .iter()
                .map(|s| [s[0] / n, s[1] / n, s[2] / n])
                .collect(),
        }
    }
}
