//! `GpuRenderer`: a scene resident on the device, the steps that put it
//! there, and the uniform each call writes from its view.

use std::ops::Range;
use std::sync::Weak;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use web_time::Instant;

use crate::camera::View;
use crate::error::{Error, Result};
use crate::layout::{ClosestPoint, Hit, LightAnswer, LightQuery, ListedHit, Params, Ray};
use crate::output::{Image, Rendered};
use crate::progress::Progress;
use crate::scene::{Accel, Integrator, Intersect, Scene};

use super::bindings::fits_wavefront;
use super::device::Gpu;
use super::hardware::{Acceleration, AccelerationStats};
use super::pipelines::{Layouts, Pipelines, resident_constants};
use super::proximity::Proximity;
use super::query::Lists;
use super::render::Tiles;
use super::resident::{Host, Resident};
use super::shader::{HARDWARE_SOURCE, SHADER_SOURCE, specialisation};
use super::timer::GpuTimings;
use super::upload::{BvhStorage, SceneBuffers};
use super::wavefront::ShadowDispatch;

/// A scene resident on the device, rendered from any view: each render
/// call takes its `View` and writes the uniform from it and the scene's
/// part (`Resident`), so no call leaves state another reads. It keeps all
/// it renders with (the scene's part of the uniform, its placement), so
/// the host's scene may go once it is built.
///
/// Its parts, each in its own file with its own `impl`, reached only
/// through their methods: the device context (`Gpu`), the shader module
/// and its layouts (`Pipelines`), the scene's upload (`Resident`: its
/// buffers, the BVH, textures, the uniform), and one part per pass or
/// kernel family: the tile renders (`Tiles`, render.rs: the megakernel or
/// the `Wavefront`; progressive batches and the wavefront's pixel lists),
/// the ray queries and pixel lists (`Lists`, query.rs) and the geometric
/// queries (`Proximity`, proximity.rs). A pass reads the others through
/// `Host`.
///
/// Under `--accel hardware` (where the device has ray queries), the scene's
/// acceleration structures (`hardware.rs`) are part of the upload: the
/// resident bind groups hold their group (group 2 of every pipeline), and
/// the shader module is the ray-query one.
///
/// When each is built (the rule): what every call needs when the renderer
/// is opened (`new`): the device context, the scene's upload (with its
/// acceleration structures), the shader module, the tile's buffers and the
/// timer. Every pipeline on the first
/// use of its pass, by its `prepare_*` (which a caller may call first to
/// leave the compile out of a timing): the megakernel's `render` pipeline
/// or the wavefront's passes and lists (`prepare_render`), the wavefront's
/// pixel-list pass, `trace_rays`'s pipelines (`prepare_trace`),
/// `render_pixel_list`'s, and the geometric queries' (each on its first
/// query; the winding tree on the first winding query).
pub struct GpuRenderer {
    gpu: Gpu,
    pipelines: Pipelines,
    resident: Resident,
    tiles: Tiles,
    lists: Lists,
    proximity: Proximity,
    /// How a render traces its shadow rays (the tests set either).
    pub shadow_dispatch: ShadowDispatch,
    /// Bytes of the scene's buffers on the device.
    pub device_bytes: u64,
    /// The arrays that lie, whole or in part, in the high binding of the
    /// scene's words (none where they fit one binding).
    pub split_arrays: Vec<&'static str>,
    /// Where the shader reads the BVH from.
    pub bvh_storage: BvhStorage,
    pub upload_time: Duration,
    /// The resident scene's placement: `trace_rays` takes world rays.
    pub placement: crate::placement::Placement,
    /// Under `--accel hardware`, what was built; None where the rays go
    /// through the compute BVH.
    acceleration_stats: Option<AccelerationStats>,
    /// Why `--accel hardware` traces through the compute BVH instead.
    accel_note: Option<String>,
}

impl GpuRenderer {
    /// Uploads `scene` with a shader specialised to it.
    pub fn new(gpu: Gpu, scene: &Scene) -> Result<GpuRenderer> {
        pollster::block_on(GpuRenderer::open(gpu, scene))
    }

    /// `new`, awaited rather than blocking (the web's: a browser runs the
    /// device's callbacks only between its tasks).
    pub async fn open(gpu: Gpu, scene: &Scene) -> Result<GpuRenderer> {
        let storage = BvhStorage::for_scene(&gpu, scene);
        GpuRenderer::build(gpu, scene, specialisation(scene), storage).await
    }

    /// `new` with the BVH in the given storage rather than the adapter's
    /// (the tests check both on one adapter).
    pub fn with_bvh_storage(gpu: Gpu, scene: &Scene, storage: BvhStorage) -> Result<GpuRenderer> {
        pollster::block_on(GpuRenderer::build(
            gpu,
            scene,
            specialisation(scene),
            storage,
        ))
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
        pollster::block_on(GpuRenderer::build(gpu, scene, constants, storage))
    }

    async fn build(
        gpu: Gpu,
        scene: &Scene,
        constants: Vec<(&'static str, f64)>,
        storage: BvhStorage,
    ) -> Result<GpuRenderer> {
        let start = Instant::now();
        let (acceleration, accel_note) = match scene.accel {
            Accel::Hardware => Acceleration::for_scene(&gpu, scene).await?,
            _ => (None, None),
        };
        let device = &gpu.device;
        let buffers = SceneBuffers::upload(&gpu, scene, storage).await?;
        let mut constants = resident_constants(constants, &buffers, storage, scene, &gpu);
        if let Some(acceleration) = &acceleration {
            constants.push(acceleration.constant());
        }
        let lights = scene.lights.len().min(u32::MAX as usize) as u32;
        let path = scene.integrator == Integrator::Path;
        let tiles = Tiles::new(&gpu, lights, path);
        let layouts = Layouts::new(device);

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let resident = Resident::new(
            device,
            scene,
            &layouts,
            &buffers,
            tiles.targets(),
            acceleration.as_ref().map(|a| a.group().clone()),
        );
        let source = match acceleration {
            Some(_) => HARDWARE_SOURCE,
            None => SHADER_SOURCE,
        };
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lambert shader"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        if let Some(e) = scope.pop().await {
            return Err(Error::Gpu(format!("uploading the scene: {e}")));
        }
        gpu.wait().await?;
        let shadow_dispatch = ShadowDispatch::for_scene(
            scene,
            gpu.options.shadow_dispatch.as_deref(),
            &gpu.limits,
            acceleration.is_some(),
        )?;
        Ok(GpuRenderer {
            gpu,
            pipelines: Pipelines::new(
                module,
                constants,
                layouts,
                acceleration.as_ref().map(|a| a.layout().clone()),
            ),
            acceleration_stats: acceleration.map(|a| a.stats),
            accel_note,
            resident,
            tiles,
            lists: Lists::default(),
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

    /// Whether its rays go through ray queries (`--accel hardware` on a
    /// device that has them): the acceleration structures built, if so.
    pub fn ray_queries(&self) -> Option<&AccelerationStats> {
        self.acceleration_stats.as_ref()
    }

    /// Why a scene that asked for `--accel hardware` traces through the
    /// compute BVH instead (the device has no ray queries, or the scene
    /// exceeds their limits), for the front end to say.
    pub fn accel_note(&self) -> Option<&str> {
        self.accel_note.as_deref()
    }

    /// The uniform of a render of `view` (camera, size, spp, seed): the
    /// scene's part as uploaded, the view's from `view`.
    pub(super) fn uniform(&self, view: &View) -> Params {
        self.resident.uniform(self.placement.offset, view)
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

    /// Renders the scene as `view` sees it, tile by tile, reading each
    /// back before the next.
    pub fn render(&mut self, view: &View, progress: &Progress) -> Result<(Rendered, GpuTimings)> {
        pollster::block_on(self.render_async(view, progress))
    }

    /// `render`, awaited rather than blocking.
    pub async fn render_async(
        &mut self,
        view: &View,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        self.render_rows_async(view, 0..view.camera.height, progress)
            .await
    }

    /// Renders rows `rows` of `view`'s image alone (a part of it), tile by
    /// tile; fails rather than return a picture whose loops the driver
    /// cut short (`Tiles::render_rows`).
    pub fn render_rows(
        &mut self,
        view: &View,
        rows: std::ops::Range<u32>,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        pollster::block_on(self.render_rows_async(view, rows, progress))
    }

    async fn render_rows_async(
        &mut self,
        view: &View,
        rows: std::ops::Range<u32>,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        let params = self.uniform(view);
        self.prepare_render_async().await?;
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        let dispatch = self.shadow_dispatch;
        self.tiles
            .render_rows(host, dispatch, &params, rows, progress)
            .await
    }

    /// Builds the passes a render runs if not built yet: the megakernel's
    /// pipeline, or the wavefront (so that timing a render can leave the
    /// compile out).
    pub fn prepare_render(&mut self) -> Result<()> {
        pollster::block_on(self.prepare_render_async())
    }

    async fn prepare_render_async(&mut self) -> Result<()> {
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        self.tiles.prepare(host, self.shadow_dispatch).await
    }

    /// Whether this renderer renders in the wavefront, as `shadow_dispatch`
    /// asks. Each of its dispatches takes every sample of the tile's pixels
    /// a megakernel dispatch would, in one submission: an earlier version
    /// that dispatched each sample's passes and waited took 152 s rather
    /// than 19 over the sampling tests.
    pub fn is_wavefront(&self) -> bool {
        self.shadow_dispatch == ShadowDispatch::Wavefront
    }

    /// Side of the tiles `render` dispatches for `view`.
    pub fn tile_side(&self, view: &View) -> u32 {
        self.tiles.tile_side(self.shadow_dispatch, view.spp)
    }

    /// Number of tiles `render` dispatches for `view`.
    pub fn tile_count(&self, view: &View) -> u64 {
        let side = self.tile_side(view);
        let camera = &view.camera;
        camera.width.div_ceil(side) as u64 * camera.height.div_ceil(side) as u64
    }

    /// Adds samples `samples` of `view` (of its `spp`) to `sums` (one per
    /// pixel, row by row: colour sums and squared luminance, as the shader
    /// keeps them), which hold samples `0..samples.start`. When
    /// `samples.end` is the view's spp, returns the finished image: the
    /// shader's means, bit for bit the image `render` returns.
    pub fn add_samples(
        &mut self,
        view: &View,
        samples: Range<u32>,
        sums: &mut [[f32; 4]],
    ) -> Result<Option<Image>> {
        self.add_samples_or_cancel(view, samples, sums, &AtomicBool::new(false))
    }

    /// `add_samples`, stopped before its next tile once `cancel` is set
    /// (then `sums` are as they were, and None comes back).
    pub fn add_samples_or_cancel(
        &mut self,
        view: &View,
        samples: Range<u32>,
        sums: &mut [[f32; 4]],
        cancel: &AtomicBool,
    ) -> Result<Option<Image>> {
        pollster::block_on(self.add_samples_async(view, samples, sums, cancel))
    }

    /// `add_samples_or_cancel`, awaited rather than blocking.
    pub async fn add_samples_async(
        &mut self,
        view: &View,
        samples: Range<u32>,
        sums: &mut [[f32; 4]],
        cancel: &AtomicBool,
    ) -> Result<Option<Image>> {
        let params = self.uniform(view);
        let (width, height, spp) = (params.width, params.height, params.spp);
        crate::camera::check_batch((width, height, spp), &samples, sums.len())
            .map_err(Error::Usage)?;
        if samples == (0..spp) {
            let (rendered, _) = self.render_async(view, &Progress::hidden()).await?;
            return Ok(Some(rendered.image));
        }
        self.prepare_render_async().await?;
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        let dispatch = self.shadow_dispatch;
        self.tiles
            .add_samples(host, dispatch, &params, samples, sums, cancel)
            .await
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
        let timer = self.tiles.timer();
        pollster::block_on(self.lists.trace(host, timer, rays, any_hit, intersect))
    }

    /// Builds the `trace_rays` pipeline for closest or any hit with the
    /// given ray/triangle test, if not built yet.
    pub fn prepare_trace(&mut self, any_hit: bool, intersect: Intersect) -> Result<()> {
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        pollster::block_on(self.lists.prepare_trace(host, any_hit, intersect))
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
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        pollster::block_on(async {
            if self.shadow_dispatch == ShadowDispatch::Wavefront {
                let lists = &self.lists;
                return (self.tiles)
                    .render_list_wavefront(host, lists, &params, pixels)
                    .await;
            }
            self.lists.prepare_pixel_list(host).await?;
            let (lists, dispatch) = (&self.lists, ShadowDispatch::Megakernel);
            (self.tiles)
                .until_whole(host, dispatch, params.spp, async |tiles| {
                    let step = tiles.samples_per_dispatch(dispatch).min(params.spp);
                    lists.render_pixel_list(host, &params, pixels, step).await
                })
                .await
        })
    }

    /// The path integrator's light functions (`sample_emitter`,
    /// `emitter_pdf`, `environment_radiance`, `environment_pdf`) on each
    /// of `queries`, in the scene's local frame: what tests compare with
    /// the CPU twin's.
    pub fn probe_lights(&mut self, queries: &[LightQuery]) -> Result<Vec<LightAnswer>> {
        let host = Host::new(&self.gpu, &self.pipelines, &self.resident);
        pollster::block_on(self.lists.probe_lights(host, queries))
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
        pollster::block_on(proximity.closest_points(host, points, margins, max_distance))
    }

    /// `cpu::winding_numbers` on the device: the same tree (uploaded on the
    /// first call) walked in the same order.
    pub fn winding_numbers(&mut self, points: &[[f32; 3]]) -> Result<Vec<f32>> {
        let (host, proximity) = self.proximity();
        pollster::block_on(proximity.winding_numbers(host, points))
    }

    /// `cpu::count_intersections` on the device (`pad`: the CPU's
    /// `box_pad`).
    pub fn count_intersections(&mut self, rays: &[Ray], pad: f32) -> Result<Vec<u32>> {
        let (host, proximity) = self.proximity();
        pollster::block_on(proximity.count_intersections(host, rays, pad))
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
        pollster::block_on(proximity.list_intersections(host, rays, pad))
    }

    /// Turns shadows on or off (the viewer's key): the uniform's flag,
    /// the HAS_SHADOWS override (where the shader is specialised) and the
    /// shadow dispatch, the pipelines built on them rebuilt on next use.
    /// The scene's buffers stay: the same image as a renderer opened on
    /// the scene with that setting.
    pub fn set_shadows(&mut self, on: bool) -> Result<()> {
        let params = self.resident.scene_params();
        if params.shadows == on as u32 {
            return Ok(());
        }
        let lights = params.num_lights;
        self.resident.set_shadows(on);
        self.set_constant("HAS_SHADOWS", on && lights > 0);
        self.choose_shadow_dispatch()
    }

    /// Switches the integrator (the viewer's key) and a path's depth: the
    /// PATH_TRACE override and the shadow dispatch, the pipelines built
    /// on them rebuilt on next use; the scene's buffers stay.
    pub fn set_integrator(&mut self, integrator: Integrator, max_depth: u32) -> Result<()> {
        self.resident.set_max_depth(max_depth);
        self.set_constant("PATH_TRACE", integrator == Integrator::Path);
        self.tiles.set_path(integrator == Integrator::Path);
        self.choose_shadow_dispatch()
    }

    /// Whether samples are path traced (the PATH_TRACE override).
    fn path_traced(&self) -> bool {
        self.constant_on("PATH_TRACE")
    }

    /// Whether the boolean override `name` is on.
    fn constant_on(&self, name: &str) -> bool {
        let constants = &self.pipelines.constants;
        constants.iter().any(|&(n, v)| n == name && v != 0.0)
    }

    /// Sets a boolean override, and drops the pipelines built on the old.
    fn set_constant(&mut self, name: &str, on: bool) {
        let constants = &mut self.pipelines.constants;
        if let Some((_, flag)) = constants.iter_mut().find(|(n, _)| *n == name) {
            *flag = on as u32 as f64;
        }
        self.tiles.forget_pipelines();
        self.lists.forget_pipelines();
    }

    /// The shadow dispatch for the uniform's shadows and lights and the
    /// integrator (each integrator has its own wavefront).
    fn choose_shadow_dispatch(&mut self) -> Result<()> {
        let params = self.resident.scene_params();
        let path = self.path_traced();
        self.shadow_dispatch = ShadowDispatch::for_lights(
            path,
            self.constant_on("HAS_TEXTURES"),
            params.shadows != 0,
            params.num_lights,
            self.gpu.options.shadow_dispatch.as_deref(),
            &self.gpu.limits,
            fits_wavefront(&self.gpu.limits, path, self.acceleration_stats.is_some()),
        )?;
        Ok(())
    }
}
