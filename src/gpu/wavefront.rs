//! The wavefront: a render with its shadow rays traced apart from the
//! camera rays (`render_primary`, or `render_list_primary` over a pixel
//! list, then `render_shadows` and `render_resolve`: every sample of a
//! dispatch at once, in one submission), its pipelines, the lists between
//! its passes and their bind groups; and `ShadowDispatch`, which of the
//! two renders a renderer runs.

use crate::error::{Error, Result};
use crate::layout::WORKGROUP_INVOCATIONS;
use crate::scene::Scene;

use super::bindings::{WAVEFRONT, fits_wavefront};
use super::device::Gpu;
use super::options::SHADOW_DISPATCH_ENV;
use super::path_wave::path_wave_bytes;
use super::readback::TileTargets;
use super::resident::Host;
use super::{SHADOW_QUERY_BYTES, WAVE_RAYS, WAVE_SHADING_BYTES, WAVE_SHADOW_RAYS};

/// How a render traces its shadow rays: in the `render` megakernel, each
/// invocation after its own primary hit, or in the wavefront
/// (`render_primary` traces a dispatch's camera rays, shades their hits
/// but for their shadows and queues their shadow rays, `render_shadows`
/// traces the queue side by side, `render_resolve` adds up the pixels
/// that waited on them; the same image, bit for bit, at any spp and any
/// number of lights).
/// LAMBERT_SHADOW_DISPATCH=megakernel|wavefront chooses (`GpuOptions`);
/// unset, the wavefront wherever it applies: on a quiet machine it
/// measured faster than the megakernel at every spp (lavapipe, the dragon,
/// one point light, device time: 0.73× at 1 spp, 0.98× at 4, 0.95× at 16,
/// 0.90× at 64; docs/bvh.md). Under the path integrator, the megakernel
/// runs `path_radiance` whole, the wavefront a pass a bounce
/// (gpu::path_wave); unset, the megakernel, or the wavefront where the
/// scene has textures (`path_dispatch`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowDispatch {
    Megakernel,
    Wavefront,
}

impl ShadowDispatch {
    /// `Wavefront` where it applies, unless `chosen`
    /// (LAMBERT_SHADOW_DISPATCH) says otherwise: for the direct
    /// integrator, where shadows are traced and a queue for the scene's
    /// lights fits one storage binding; for the path integrator, the path
    /// wavefront (gpu::path_wave) where its buffers fit one. Either only
    /// where the adapter binds its passes' storage buffers.
    pub(super) fn for_scene(
        scene: &Scene,
        chosen: Option<&str>,
        limits: &wgpu::Limits,
        hardware: bool,
    ) -> Result<ShadowDispatch> {
        let lights = scene.lights.len().min(u32::MAX as usize) as u32;
        let path = scene.integrator == crate::scene::Integrator::Path;
        let textured = scene.has_textures();
        let bound = fits_wavefront(limits, path, hardware);
        ShadowDispatch::for_lights(path, textured, scene.shadows, lights, chosen, limits, bound)
    }

    /// `for_scene` from the integrator, whether the scene has textures and
    /// the uniform's shadows and light count (what `GpuRenderer::set_shadows`
    /// has). The wavefront applies only where its lists fit one binding and
    /// its passes' bindings fit the adapter's limits (`bound`: WebGPU's
    /// default 8 storage buffers a stage hold the megakernel's, not the
    /// wavefront's; `fits_wavefront`).
    pub(super) fn for_lights(
        path: bool,
        textured: bool,
        shadows: bool,
        lights: u32,
        chosen: Option<&str>,
        limits: &wgpu::Limits,
        bound: bool,
    ) -> Result<ShadowDispatch> {
        let max_binding = limits.max_storage_buffer_binding_size;
        let (applies, unset) = if path {
            (
                bound && path_wave_bytes() <= max_binding,
                path_dispatch(textured),
            )
        } else {
            let queue = wave_queue_bytes(lights) <= max_binding;
            (
                bound && shadows && lights > 0 && queue,
                ShadowDispatch::Wavefront,
            )
        };
        match chosen {
            None if applies => Ok(unset),
            Some("wavefront") if applies => Ok(ShadowDispatch::Wavefront),
            None | Some("wavefront") | Some("megakernel") => Ok(ShadowDispatch::Megakernel),
            Some(other) => Err(Error::Usage(format!(
                "{SHADOW_DISPATCH_ENV}={other:?}: use \"megakernel\" or \"wavefront\""
            ))),
        }
    }
}

/// The path integrator's dispatch where LAMBERT_SHADOW_DISPATCH is unset,
/// as measured on lavapipe (docs/benchmarks.md): the megakernel for an
/// untextured scene (the wavefront took 1.06–1.12× its time on
/// cornell_area.toml and dragon_cornell.toml), the wavefront for a textured
/// one, whose megakernel carries every texture fetch of every bounce in one
/// function (the wavefront took 0.56–0.75× its time on textured.glb).
fn path_dispatch(textured: bool) -> ShadowDispatch {
    if textured {
        ShadowDispatch::Wavefront
    } else {
        ShadowDispatch::Megakernel
    }
}

/// Camera rays a wavefront dispatch takes with `lights` lights:
/// `WAVE_RAYS`, fewer where their shadow rays would pass
/// `WAVE_SHADOW_RAYS`, a workgroup's at the least.
pub(super) fn wave_budget(lights: u32) -> u32 {
    (WAVE_SHADOW_RAYS / lights.max(1)).clamp(WORKGROUP_INVOCATIONS, WAVE_RAYS)
}

/// `wave_counts` (shadow rays queued, pixels listed) and `wave_workgroups`
/// (the indirect dispatches of `render_shadows`, then `render_resolve`)
/// as each tile starts them: the lists empty, each dispatch 0 × 1 × 1.
const EMPTY_COUNTS: [u32; 2] = [0; 2];
const EMPTY_WORKGROUPS: [u32; 6] = [0, 1, 1, 0, 1, 1];
/// Where `render_resolve`'s dispatch lies in `wave_workgroups`.
const RESOLVE_WORKGROUPS_OFFSET: u64 = 12;
/// Bytes of a `resolve_pixels` entry (pixel, first sample to resolve).
const RESOLVE_PIXEL_BYTES: u64 = 8;

/// Bytes of a wavefront dispatch's shadow queue: a ray for each light of
/// each camera ray.
fn wave_queue_bytes(lights: u32) -> u64 {
    wave_budget(lights) as u64 * lights.max(1) as u64 * SHADOW_QUERY_BYTES
}

/// The wavefront's passes, the lists between them, and the tile's bind
/// groups. Built on a renderer's first wavefront render; the pixel list's
/// first pass on its first pixel list.
pub(super) struct Wavefront {
    /// The first pass of a dispatch of one sample a pixel, and of several.
    primary: wgpu::ComputePipeline,
    primary_samples: wgpu::ComputePipeline,
    /// The first pass over a pixel list, built on first use.
    list_primary: Option<wgpu::ComputePipeline>,
    shadows: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    buffers: WaveBuffers,
    /// The tile's group 1, for the primary pass and the indirect ones.
    tile_groups: [wgpu::BindGroup; 2],
}

/// The wavefront's lists between its passes, and the layout that binds
/// them.
struct WaveBuffers {
    layout: wgpu::BindGroupLayout,
    shading: wgpu::Buffer,
    queue: wgpu::Buffer,
    resolve_pixels: wgpu::Buffer,
    counts: wgpu::Buffer,
    workgroups: wgpu::Buffer,
    /// What the indirect passes bind at `wave_workgroups`: a dispatch may
    /// not bind the buffer it is dispatched by.
    unused: wgpu::Buffer,
}

impl Wavefront {
    /// The passes and lists of a wavefront over `lights` lights, writing
    /// `tile`'s buffers.
    pub async fn new(host: Host<'_>, tile: &TileTargets, lights: u32) -> Result<Wavefront> {
        let device = &host.gpu().device;
        let layout = WAVEFRONT.layout(device);
        let rays = wave_budget(lights) as u64;
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        let none = wgpu::BufferUsages::empty();
        let shading = buffer("wave shading", rays * WAVE_SHADING_BYTES, none);
        let queue = buffer("shadow queue", wave_queue_bytes(lights), none);
        let resolve_pixels = buffer("resolve pixels", rays * RESOLVE_PIXEL_BYTES, none);
        let bytes = |words: &[u32]| std::mem::size_of_val(words) as u64;
        let counts = buffer(
            "wave counts",
            bytes(&EMPTY_COUNTS),
            wgpu::BufferUsages::COPY_DST,
        );
        let workgroups = buffer(
            "wave workgroups",
            bytes(&EMPTY_WORKGROUPS),
            wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::INDIRECT,
        );
        let unused = buffer("wave workgroups, unused", bytes(&EMPTY_WORKGROUPS), none);
        // A tile's render binds no pixel list: one entry, never read.
        let no_list = buffer("no pixel list", RESOLVE_PIXEL_BYTES, none);
        let buffers = WaveBuffers {
            layout,
            shading,
            queue,
            resolve_pixels,
            counts,
            workgroups,
            unused,
        };
        let tile_groups = buffers.groups(
            device,
            [
                tile.prim.as_entire_binding(),
                tile.sums.as_entire_binding(),
                no_list.as_entire_binding(),
            ],
        );
        let build = |entry| host.build(entry, &buffers.layout);
        Ok(Wavefront {
            primary: build("render_primary").await?,
            primary_samples: build("render_primary_samples").await?,
            list_primary: None,
            shadows: build("render_shadows").await?,
            resolve: build("render_resolve").await?,
            buffers,
            tile_groups,
        })
    }

    /// Builds the pixel list's first pass if not built yet.
    pub async fn prepare_list(&mut self, host: Host<'_>) -> Result<()> {
        if self.list_primary.is_none() {
            let pipeline = host
                .build("render_list_primary", &self.buffers.layout)
                .await?;
            self.list_primary = Some(pipeline);
        }
        Ok(())
    }

    /// Records one dispatch of the wavefront over the tile's `workgroups`,
    /// `samples` samples a pixel.
    pub fn dispatch_tile(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        samples: u32,
        workgroups: [u32; 3],
    ) {
        let primary = if samples == 1 {
            &self.primary
        } else {
            &self.primary_samples
        };
        self.dispatch(gpu, pass, primary, &self.tile_groups, workgroups);
    }

    /// The wavefront's group 1 over a pixel list, with `prim`, `sums` and
    /// `list` at `out_prim`, `tile_sums` and `pixel_list` (for
    /// `dispatch_list`).
    pub fn list_groups(
        &self,
        device: &wgpu::Device,
        bindings: [wgpu::BindingResource<'_>; 3],
    ) -> [wgpu::BindGroup; 2] {
        self.buffers.groups(device, bindings)
    }

    /// Records one dispatch of the wavefront over a pixel list bound in
    /// `groups` (`list_groups`); `prepare_list` first.
    pub fn dispatch_list(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        groups: &[wgpu::BindGroup; 2],
        workgroups: u32,
    ) {
        let primary = self.list_primary.as_ref().expect("prepare_list first");
        self.dispatch(gpu, pass, primary, groups, [workgroups, 1, 1]);
    }

    /// Records one dispatch of the wavefront: `primary` over `workgroups`
    /// with `group`, then the shadow rays and the listed pixels, dispatched
    /// indirectly with `indirect_group`; the lists emptied first.
    fn dispatch(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        primary: &wgpu::ComputePipeline,
        [group, indirect_group]: &[wgpu::BindGroup; 2],
        [x, y, z]: [u32; 3],
    ) {
        let lists = &self.buffers;
        gpu.queue
            .write_buffer(&lists.counts, 0, bytemuck::cast_slice(&EMPTY_COUNTS));
        gpu.queue.write_buffer(
            &lists.workgroups,
            0,
            bytemuck::cast_slice(&EMPTY_WORKGROUPS),
        );
        pass.set_bind_group(WAVEFRONT.group, group, &[]);
        pass.set_pipeline(primary);
        pass.dispatch_workgroups(x, y, z);
        // An invocation a queued shadow ray (the primary pass counts the
        // workgroups).
        pass.set_pipeline(&self.shadows);
        pass.set_bind_group(WAVEFRONT.group, indirect_group, &[]);
        pass.dispatch_workgroups_indirect(&lists.workgroups, 0);
        // An invocation a pixel the primary pass listed.
        pass.set_pipeline(&self.resolve);
        pass.dispatch_workgroups_indirect(&lists.workgroups, RESOLVE_WORKGROUPS_OFFSET);
    }
}

impl WaveBuffers {
    /// The wavefront's group 1 with `prim`, `sums` and `list` at
    /// `out_prim`, `tile_sums` and `pixel_list`: for the primary pass,
    /// then for the indirect ones.
    fn groups(
        &self,
        device: &wgpu::Device,
        [prim, sums, list]: [wgpu::BindingResource<'_>; 3],
    ) -> [wgpu::BindGroup; 2] {
        [&self.workgroups, &self.unused].map(|workgroups| {
            WAVEFRONT.bind_group(
                device,
                WAVEFRONT.label,
                &self.layout,
                vec![
                    ("out_prim", prim.clone()),
                    ("tile_sums", sums.clone()),
                    ("pixel_list", list.clone()),
                    ("wave_shading", self.shading.as_entire_binding()),
                    ("shadow_queue", self.queue.as_entire_binding()),
                    ("wave_counts", self.counts.as_entire_binding()),
                    ("wave_workgroups", workgroups.as_entire_binding()),
                    ("resolve_pixels", self.resolve_pixels.as_entire_binding()),
                ],
            )
        })
    }
}
