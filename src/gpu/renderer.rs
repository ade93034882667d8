//! `GpuRenderer`: a scene resident on the device, the steps that put it
//! there, and the uniform each call writes from its view.

use std::sync::Weak;
use std::time::{Duration, Instant};

use crate::camera::View;
use crate::error::{Error, Result};
use crate::layout::{ClosestPoint, Hit, ListedHit, Params, Ray};
use crate::scene::{Intersect, Scene};

use super::adapter::is_llvmpipe;
use super::device::Gpu;
use super::pipelines::{Layouts, Pipelines, resident_constants};
use super::proximity::Proximity;
use super::query::Lists;
use super::readback::TileTargets;
use super::render::LLVMPIPE_SAMPLES_PER_DISPATCH;
use super::resident::{Host, Resident};
use super::shader::{SHADER_SOURCE, specialisation};
use super::timer::Timer;
use super::upload::{BvhStorage, SceneBuffers};
use super::wavefront::{ShadowDispatch, Wavefront};

/// A scene resident on the device, rendered from any view: each render
/// call takes its `View` and writes the uniform from it and the scene's
/// part (`Resident`), so no call leaves state another reads. It keeps all
/// it renders with (the scene's part of the uniform, its placement), so
/// the host's scene may go once it is built.
///
/// Its parts, and when each is built (the rule): what every call needs is
/// built when the renderer is opened (`new`): the device context (`Gpu`),
/// the scene's upload and bind groups (`Resident`: buffers, the BVH,
/// textures, the uniform), the shader module and its layouts
/// (`Pipelines`), the tile's buffers (`TileTargets`) and the timer. Each
/// pass or kernel family is built on its first use, by its `prepare_*`
/// (which a caller may call first to leave the compile out of a timing):
/// the megakernel's `render` pipeline or the `Wavefront`
/// (`prepare_render`), the wavefront's pixel-list pass, `trace_rays`'s
/// pipelines (`prepare_trace`), `render_pixel_list`'s, and the geometric
/// queries' (`proximity.rs`; the winding tree on the first winding query).
pub struct GpuRenderer {
    pub(super) gpu: Gpu,
    pub(super) pipelines: Pipelines,
    pub(super) resident: Resident,
    pub(super) tile: TileTargets,
    /// Samples one dispatch adds to a pixel: few enough that no invocation
    /// trips llvmpipe's loop limit (`loops_completed` in the shader);
    /// halved whenever one still does.
    pub(super) samples_per_dispatch: u32,
    pub(super) timer: Option<Timer>,
    /// The megakernel's pipeline, built on its first render.
    pub(super) megakernel: Option<wgpu::ComputePipeline>,
    /// The wavefront's passes, built on the first wavefront render.
    pub(super) wavefront: Option<Wavefront>,
    pub(super) lists: Lists,
    proximity: Proximity,
    /// How a render traces its shadow rays (the tests set either).
    pub shadow_dispatch: ShadowDispatch,
    /// Bytes of the scene's buffers on the device.
    pub device_bytes: u64,
    /// The arrays split over two bindings.
    pub split_arrays: Vec<&'static str>,
    /// Where the shader reads the BVH from.
    pub bvh_storage: BvhStorage,
    pub upload_time: Duration,
    /// The resident scene's placement: `trace_rays` takes world rays.
    pub placement: crate::placement::Placement,
}

impl GpuRenderer {
    /// Uploads `scene` with a shader specialised to it.
    pub fn new(gpu: Gpu, scene: &Scene) -> Result<GpuRenderer> {
        let storage = BvhStorage::for_scene(&gpu, scene);
        GpuRenderer::build(gpu, scene, specialisation(scene), storage)
    }

    /// `new` with the BVH in the given storage rather than the adapter's
    /// (the tests check both on one adapter).
    pub fn with_bvh_storage(gpu: Gpu, scene: &Scene, storage: BvhStorage) -> Result<GpuRenderer> {
        GpuRenderer::build(gpu, scene, specialisation(scene), storage)
    }

    /// Uploads `scene` with the full shader: every feature compiled in, only
    /// the acceleration and the intersection test chosen. The benchmarks
    /// measure what specialisation saves against it.
    pub fn with_full_shader(gpu: Gpu, scene: &Scene) -> Result<GpuRenderer> {
        let constants = specialisation(scene)
            .into_iter()
            .filter(|(name, _)| matches!(*name, "USE_BVH" | "INTERSECT"))
            .collect();
        let storage = BvhStorage::for_scene(&gpu, scene);
        GpuRenderer::build(gpu, scene, constants, storage)
    }

    fn build(
        gpu: Gpu,
        scene: &Scene,
        constants: Vec<(&'static str, f64)>,
        storage: BvhStorage,
    ) -> Result<GpuRenderer> {
        let start = Instant::now();
        let device = &gpu.device;
        let buffers = SceneBuffers::upload(&gpu, scene, storage)?;
        let constants = resident_constants(constants, &buffers, storage, scene, &gpu);
        let tile = TileTargets::new(device);
        let layouts = Layouts::new(device);

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let resident = Resident::new(device, scene, &layouts, &buffers, &tile);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lambert shader"),
            source: wgpu::ShaderSource::Wgsl(SHADER_SOURCE.into()),
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!("uploading the scene: {e}")));
        }
        gpu.wait()?;
        let timer = Timer::new(&gpu);
        let shadow_dispatch = ShadowDispatch::for_scene(
            scene,
            gpu.options.shadow_dispatch.as_deref(),
            gpu.limits.max_storage_buffer_binding_size as u64,
        )?;
        let samples_per_dispatch = if is_llvmpipe(&gpu.info) {
            LLVMPIPE_SAMPLES_PER_DISPATCH
        } else {
            u32::MAX
        };
        Ok(GpuRenderer {
            gpu,
            pipelines: Pipelines::new(module, constants, layouts),
            resident,
            tile,
            samples_per_dispatch,
            timer,
            wavefront: None,
            lists: Lists::default(),
            megakernel: None,
            proximity: Default::default(),
            shadow_dispatch,
            device_bytes: buffers.device_bytes,
            split_arrays: buffers.split_arrays(),
            bvh_storage: storage,
            upload_time: start.elapsed(),
            placement: scene.placement(),
        })
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// The uniform of a render of `view` (camera, size, spp, seed): the
    /// scene's part as uploaded, the view's from `view`.
    pub(super) fn uniform(&self, view: &View) -> Params {
        self.resident.uniform(self.placement.offset, view)
    }

    /// Lights in the resident scene.
    pub(super) fn scene_lights(&self) -> u32 {
        self.resident.scene_params().num_lights
    }

    /// Spheres in the resident scene (the geometric queries are over
    /// triangles).
    pub fn sphere_count(&self) -> u32 {
        self.resident.scene_params().num_spheres
    }

    /// Where a winding query finds the scene's winding tree (the engine
    /// sets it when it opens the renderer from an `Arc<Scene>`).
    pub fn set_winding_source(&mut self, scene: Weak<Scene>) {
        self.proximity.set_winding_source(scene);
    }

    /// What a pass reads of the renderer's other parts.
    pub(super) fn host(&self) -> Host<'_> {
        Host::new(&self.gpu, &self.pipelines, &self.resident)
    }

    /// Traces `rays` (world coordinates, as in a ray file) against the
    /// resident scene with the ray/triangle test `intersect`: closest hits,
    /// or with `any_hit` the first hit each ray finds. Misses come back as
    /// t = +inf, prim = NO_HIT.
    pub fn trace_rays(
        &mut self,
        rays: &[Ray],
        any_hit: bool,
        intersect: Intersect,
    ) -> Result<Vec<Hit>> {
        let local = self.placement.localize(rays);
        let mut hits = self.trace_local_rays(&local.rays, any_hit, intersect)?;
        local.to_world(&mut hits);
        Ok(hits)
    }

    /// `trace_rays` for rays already in the scene's local frame
    /// (`Placement::local_ray`), hits in that frame.
    pub fn trace_local_rays(
        &mut self,
        rays: &[Ray],
        any_hit: bool,
        intersect: Intersect,
    ) -> Result<Vec<Hit>> {
        self.prepare_trace(any_hit, intersect)?;
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        let timer = self.timer.as_ref();
        self.lists.trace(host, timer, rays, any_hit, intersect)
    }

    /// Builds the `trace_rays` pipeline for closest or any hit with the
    /// given ray/triangle test, if not built yet.
    pub fn prepare_trace(&mut self, any_hit: bool, intersect: Intersect) -> Result<()> {
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        self.lists.prepare_trace(host, any_hit, intersect)
    }

    /// Device time of the last `trace_rays`, from timestamp queries (None
    /// where the adapter has none).
    pub fn trace_device_time(&self) -> Option<Duration> {
        self.lists.trace_device_time()
    }

    /// Renders the listed pixels with `view`'s spp and seed (adaptive
    /// sampling's later passes): mean colour and variance of the mean. In
    /// the wavefront where the render is (`is_wavefront`), else in one
    /// pass; the same bits either way.
    pub fn render_pixel_list(&mut self, view: &View, pixels: &[[u32; 2]]) -> Result<Vec<[f32; 4]>> {
        let params = self.uniform(view);
        if self.is_wavefront() {
            return self.render_list_wavefront(&params, pixels);
        }
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        self.lists.prepare_pixel_list(host)?;
        loop {
            let step = self.samples_per_dispatch.min(params.spp);
            let results = self
                .lists
                .render_pixel_list(self.host(), &params, pixels, step)?;
            if !self.loops_were_cut()? {
                return Ok(results);
            }
            self.fewer_samples_per_dispatch(params.spp)?;
        }
    }

    /// The geometric queries' part, and what it reads of the others.
    fn proximity(&mut self) -> (Host<'_>, &mut Proximity) {
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        (host, &mut self.proximity)
    }

    /// `cpu::closest_points` on the device (`margins`: each point's cull
    /// margin, the CPU's `query_margin`).
    pub fn closest_points(
        &mut self,
        points: &[[f32; 3]],
        margins: &[f32],
        max_distance: f32,
    ) -> Result<Vec<ClosestPoint>> {
        let (host, proximity) = self.proximity();
        proximity.closest_points(host, points, margins, max_distance)
    }

    /// `cpu::winding_numbers` on the device: the same tree (uploaded on the
    /// first call) walked in the same order.
    pub fn winding_numbers(&mut self, points: &[[f32; 3]]) -> Result<Vec<f32>> {
        let (host, proximity) = self.proximity();
        proximity.winding_numbers(host, points)
    }

    /// `cpu::count_intersections` on the device (`pad`: the CPU's
    /// `box_pad`).
    pub fn count_intersections(&mut self, rays: &[Ray], pad: f32) -> Result<Vec<u32>> {
        let (host, proximity) = self.proximity();
        proximity.count_intersections(host, rays, pad)
    }

    /// `cpu::list_intersections` on the device, each ray's hits in the
    /// order the traversal found them (the engine sorts them); a ray whose
    /// crossings alone exceed one binding is `Error::GpuLimit`.
    pub fn list_intersections(
        &mut self,
        rays: &[Ray],
        pad: f32,
    ) -> Result<(Vec<u64>, Vec<ListedHit>)> {
        let (host, proximity) = self.proximity();
        proximity.list_intersections(host, rays, pad)
    }
}
