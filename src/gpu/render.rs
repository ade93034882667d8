//! The render passes: tile by tile, in the `render` megakernel or as a
//! wavefront with the shadow rays apart (`render_primary`,
//! `render_shadows`, `render_resolve`: every sample of a dispatch at
//! once),
//! each tile read back before the next.

use std::time::{Duration, Instant};

use crate::error::{Error, Result};
use crate::layout::WORKGROUP_INVOCATIONS;
use crate::output::{Image, Rendered};
use crate::progress::Progress;
use crate::scene::Scene;

use super::bindings::{IMAGE_TILE, SCENE, SHADOWS_APART};
use super::device::SHADOW_DISPATCH_ENV;
use super::timer::{GpuTimings, Timer};
use super::{
    GpuRenderer, RENDER_WORKGROUP, SHADOW_QUERY_BYTES, TILE, WAVE_RAYS, WAVE_SHADING_BYTES,
    WAVE_SHADOW_RAYS,
};

/// Samples a dispatch adds to each pixel on llvmpipe: the bundled scenes'
/// pixels ran out of loop iterations from about 192 (a 3,674-triangle
/// bunny, two lights); a heavier scene halves it as often as it needs.
pub(super) const LLVMPIPE_SAMPLES_PER_DISPATCH: u32 = 32;

/// How a render traces its shadow rays: in the `render` megakernel, each
/// invocation after its own primary hit, or apart, the wavefront
/// (`render_primary` traces a dispatch's camera rays, shades their hits
/// but for their shadows and queues their shadow rays, `render_shadows`
/// traces the queue side by side, `render_resolve` adds up the pixels
/// that waited on them; the same image, bit for bit, at any spp and any
/// number of lights).
/// LAMBERT_SHADOW_DISPATCH=megakernel|apart chooses (`GpuOptions`);
/// unset, apart wherever it applies: on a quiet machine it measured
/// faster than the megakernel at every spp (lavapipe, the dragon, one
/// point light, device time: 0.73× at 1 spp, 0.98× at 4, 0.95× at 16,
/// 0.90× at 64; docs/bvh.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowDispatch {
    Megakernel,
    Apart,
}

impl ShadowDispatch {
    /// `Apart` where it applies (shadows traced, and a queue for the
    /// scene's lights no larger than `max_binding` bytes), unless
    /// `chosen` (LAMBERT_SHADOW_DISPATCH) says otherwise.
    pub(super) fn for_scene(
        scene: &Scene,
        chosen: Option<&str>,
        max_binding: u64,
    ) -> Result<ShadowDispatch> {
        let lights = scene.lights.len().min(u32::MAX as usize) as u32;
        ShadowDispatch::for_lights(scene.shadows, lights, chosen, max_binding)
    }

    /// `for_scene` from the uniform's shadows and light count (what
    /// `GpuRenderer::set_shadows` has).
    pub(super) fn for_lights(
        shadows: bool,
        lights: u32,
        chosen: Option<&str>,
        max_binding: u64,
    ) -> Result<ShadowDispatch> {
        let applies = shadows && lights > 0 && wave_queue_bytes(lights) <= max_binding;
        match chosen {
            None | Some("apart") if applies => Ok(ShadowDispatch::Apart),
            None | Some("apart") | Some("megakernel") => Ok(ShadowDispatch::Megakernel),
            Some(other) => Err(Error::Usage(format!(
                "{SHADOW_DISPATCH_ENV}={other:?}: use \"megakernel\" or \"apart\""
            ))),
        }
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

/// The workgroups of a render dispatch over a `width` × `height` tile, on
/// an adapter that runs a dispatch on `threads` CPU threads (the shader's
/// CPU_THREADS): every `threads`-th column of them in each of `threads`
/// layers, as the shader's `tile_pixel` takes them.
fn tile_workgroups(width: u32, height: u32, threads: u32) -> [u32; 3] {
    let [wx, wy] = RENDER_WORKGROUP;
    [
        width.div_ceil(wx).div_ceil(threads),
        height.div_ceil(wy),
        threads,
    ]
}

/// The passes of a render with its shadow rays apart, and their buffers.
pub(super) struct SplitShadows {
    /// The first pass of a dispatch of one sample a pixel, and of several.
    primary: wgpu::ComputePipeline,
    primary_samples: wgpu::ComputePipeline,
    /// The first pass over a pixel list, built on first use.
    pub list_primary: Option<wgpu::ComputePipeline>,
    shadows: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    pub buffers: WaveBuffers,
    /// The tile's group 1, for the primary pass and the indirect ones.
    group: wgpu::BindGroup,
    indirect_group: wgpu::BindGroup,
}

/// The wavefront's lists between its passes, and the layout that binds
/// them.
pub(super) struct WaveBuffers {
    pub layout: wgpu::BindGroupLayout,
    shading: wgpu::Buffer,
    queue: wgpu::Buffer,
    resolve_pixels: wgpu::Buffer,
    counts: wgpu::Buffer,
    workgroups: wgpu::Buffer,
    /// What the indirect passes bind at `wave_workgroups`: a dispatch may
    /// not bind the buffer it is dispatched by.
    unused: wgpu::Buffer,
}

impl WaveBuffers {
    /// The wavefront's group 1 with `prim`, `sums` and `list` at
    /// `out_prim`, `tile_sums` and `pixel_list`: for the primary pass
    /// (`indirect` false) or the indirect ones.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        [prim, sums, list]: [wgpu::BindingResource<'_>; 3],
        indirect: bool,
    ) -> wgpu::BindGroup {
        let workgroups = if indirect {
            &self.unused
        } else {
            &self.workgroups
        };
        SHADOWS_APART.bind_group(
            device,
            SHADOWS_APART.label,
            &self.layout,
            vec![
                ("out_prim", prim),
                ("tile_sums", sums),
                ("pixel_list", list),
                ("wave_shading", self.shading.as_entire_binding()),
                ("shadow_queue", self.queue.as_entire_binding()),
                ("wave_counts", self.counts.as_entire_binding()),
                ("wave_workgroups", workgroups.as_entire_binding()),
                ("resolve_pixels", self.resolve_pixels.as_entire_binding()),
            ],
        )
    }
}

impl SplitShadows {
    /// Records one dispatch of the wavefront: `primary` over `workgroups`
    /// with `group`, then the shadow rays and the listed pixels, dispatched
    /// indirectly with `indirect_group`; the lists emptied first.
    pub fn dispatch(
        &self,
        gpu: &super::device::Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        primary: &wgpu::ComputePipeline,
        [group, indirect_group]: [&wgpu::BindGroup; 2],
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
        pass.set_bind_group(SHADOWS_APART.group, group, &[]);
        pass.set_pipeline(primary);
        pass.dispatch_workgroups(x, y, z);
        // An invocation a queued shadow ray (the primary pass counts the
        // workgroups).
        pass.set_pipeline(&self.shadows);
        pass.set_bind_group(SHADOWS_APART.group, indirect_group, &[]);
        pass.dispatch_workgroups_indirect(&lists.workgroups, 0);
        // An invocation a pixel the primary pass listed.
        pass.set_pipeline(&self.resolve);
        pass.dispatch_workgroups_indirect(&lists.workgroups, RESOLVE_WORKGROUPS_OFFSET);
    }
}

impl GpuRenderer {
    /// Renders tile by tile, reading each back before the next.
    pub fn render(&mut self, progress: &Progress) -> Result<(Rendered, GpuTimings)> {
        self.render_rows(0..self.params.height, progress)
    }

    /// Renders rows `rows` of the image alone (a part of it), tile by tile.
    /// If the driver cut the shader's loops short anywhere (checked once,
    /// after the last tile), renders again with half as many samples per
    /// dispatch, down to one, then fails rather than return a wrong
    /// picture.
    pub fn render_rows(
        &mut self,
        rows: std::ops::Range<u32>,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        self.prepare_render()?;
        loop {
            let result = self.render_rows_once(&rows, progress)?;
            if !self.loops_were_cut()? {
                return Ok(result);
            }
            self.fewer_samples_per_dispatch()?;
        }
    }

    fn render_rows_once(
        &mut self,
        rows: &std::ops::Range<u32>,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        let width = self.params.width;
        let height = rows.len() as u32;
        let mut rgb = vec![[0.0f32; 3]; width as usize * height as usize];
        let mut prims = vec![0u32; width as usize * height as usize];
        let mut variance = vec![0.0f32; width as usize * height as usize];
        let mut timings = GpuTimings::default();
        let side = self.tile_side();
        for tile_y in rows.clone().step_by(side as usize) {
            for tile_x in (0..width).step_by(side as usize) {
                let tile_width = side.min(width - tile_x);
                let tile_height = side.min(rows.end - tile_y);
                let start = Instant::now();
                let samples = 0..self.params.spp;
                let device_time =
                    self.render_tile(tile_x, tile_y, tile_width, tile_height, samples)?;
                timings.render += start.elapsed();
                if let Some(t) = device_time {
                    *timings.device.get_or_insert(Duration::ZERO) += t;
                }

                let start = Instant::now();
                self.tile
                    .read(&self.gpu, tile_width, tile_height, |row, colors, ids| {
                        let offset = ((tile_y - rows.start + row) * width + tile_x) as usize;
                        let n = tile_width as usize;
                        for (i, src) in colors.chunks(4).enumerate() {
                            rgb[offset + i] = [src[0], src[1], src[2]];
                            variance[offset + i] = src[3];
                        }
                        prims[offset..offset + n].copy_from_slice(ids);
                    })?;
                timings.readback += start.elapsed();
                progress.inc(1);
            }
        }
        Ok((
            Rendered {
                image: Image { width, height, rgb },
                prims,
                variance,
            },
            timings,
        ))
    }

    /// Side of the tiles `render` dispatches: TILE at 1 sample per pixel
    /// per dispatch, smaller as they grow, so that a dispatch traces about
    /// as many camera rays (TILE²) at any spp; in the wavefront no larger
    /// than its buffers take (`wave_budget`: smaller with many lights).
    pub fn tile_side(&self) -> u32 {
        let samples = self.params.spp.min(self.samples_per_dispatch());
        let step = RENDER_WORKGROUP[0].max(RENDER_WORKGROUP[1]);
        let side = (TILE / samples.isqrt().max(1))
            .next_multiple_of(step)
            .clamp(step, TILE);
        if self.shadows_apart() {
            let fits = (wave_budget(self.params.num_lights) / samples).isqrt() / step * step;
            return side.min(fits.max(step));
        }
        side
    }

    /// Number of tiles `render` dispatches for the current camera.
    pub fn tile_count(&self) -> u64 {
        let side = self.tile_side();
        self.params.width.div_ceil(side) as u64 * self.params.height.div_ceil(side) as u64
    }

    /// Renders samples `samples` of one tile (all of them, or a
    /// progressive render's next few, added to the tile's sums), over as
    /// many dispatches as `samples_per_dispatch` asks. Returns the device
    /// time where timestamps work.
    pub(super) fn render_tile(
        &mut self,
        x: u32,
        y: u32,
        width: u32,
        height: u32,
        samples: std::ops::Range<u32>,
    ) -> Result<Option<Duration>> {
        let step = self.samples_per_dispatch().min(self.params.spp);
        let mut device_time = None;
        for begin in samples.clone().step_by(step as usize) {
            self.params.sample_begin = begin;
            self.params.sample_end = (begin + step).min(samples.end);
            if let Some(t) = self.dispatch_tile(x, y, width, height)? {
                *device_time.get_or_insert(Duration::ZERO) += t;
            }
        }
        Ok(device_time)
    }

    /// Samples a render dispatch adds to a pixel; in the wavefront, no
    /// more than leave a workgroup's pixels within its buffers.
    pub(super) fn samples_per_dispatch(&self) -> u32 {
        if self.shadows_apart() {
            let budget = wave_budget(self.params.num_lights);
            self.samples_per_dispatch
                .min(budget / WORKGROUP_INVOCATIONS)
        } else {
            self.samples_per_dispatch
        }
    }

    /// Whether this render is the wavefront (its shadow rays apart), as
    /// `shadow_dispatch` asks. Each of its dispatches takes every sample of
    /// the tile's pixels a megakernel dispatch would, in one submission:
    /// an earlier version that dispatched each sample's passes and waited
    /// took 152 s rather than 19 over the sampling tests.
    pub fn shadows_apart(&self) -> bool {
        self.shadow_dispatch == ShadowDispatch::Apart
    }

    /// Halves `samples_per_dispatch` after the driver cut loops short.
    pub(super) fn fewer_samples_per_dispatch(&mut self) -> Result<()> {
        let step = self.samples_per_dispatch().min(self.params.spp);
        if step <= 1 {
            return Err(Error::LoopsCut(format!(
                "{} cut the shader's loops short even at one sample per pixel per dispatch \
                 (Mesa's llvmpipe ends loops after 65535 iterations an invocation group): \
                 this scene is too complex for this adapter",
                self.gpu.describe()
            )));
        }
        self.samples_per_dispatch = step / 2;
        Ok(())
    }

    /// Whether any invocation since the last call found its loops cut short
    /// (the shader's `report_cut_loops`); clears the flag.
    pub(super) fn loops_were_cut(&self) -> Result<bool> {
        self.resident.loop_status.were_cut(&self.gpu)
    }

    /// Renders one tile; returns its device time where timestamps work.
    fn dispatch_tile(
        &mut self,
        x: u32,
        y: u32,
        width: u32,
        height: u32,
    ) -> Result<Option<Duration>> {
        self.params.tile_origin = [x, y];
        self.params.tile_size = [width, height];
        let gpu = &self.gpu;
        let resident = &self.resident;
        gpu.queue
            .write_buffer(&resident.params_buffer, 0, bytemuck::bytes_of(&self.params));
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let [groups_x, groups_y, layers] = tile_workgroups(width, height, gpu.cpu_threads());
        if let (true, Some(split)) = (self.shadows_apart(), &self.pipelines.split) {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render tile, shadows apart"),
                timestamp_writes: self.timer.as_ref().map(Timer::writes),
            });
            pass.set_bind_group(SCENE.group, &resident.scene_group, &[]);
            let primary = if self.params.sample_end - self.params.sample_begin == 1 {
                &split.primary
            } else {
                &split.primary_samples
            };
            split.dispatch(
                gpu,
                &mut pass,
                primary,
                [&split.group, &split.indirect_group],
                [groups_x, groups_y, layers],
            );
        } else {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render tile"),
                timestamp_writes: self.timer.as_ref().map(Timer::writes),
            });
            pass.set_pipeline(self.pipelines.render.as_ref().expect("prepared"));
            pass.set_bind_group(SCENE.group, &resident.scene_group, &[]);
            pass.set_bind_group(IMAGE_TILE.group, &resident.image_group, &[]);
            pass.dispatch_workgroups(groups_x, groups_y, layers);
        }
        if let Some(timer) = &self.timer {
            timer.resolve(&mut encoder);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait()?;
        self.timer.as_ref().map(|t| t.read(gpu)).transpose()
    }

    /// The passes and buffers of a render with its shadow rays apart.
    pub(super) fn build_split(&self) -> Result<SplitShadows> {
        let device = &self.gpu.device;
        let layout = SHADOWS_APART.layout(device);
        let lights = self.params.num_lights;
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
        let tile = |indirect| {
            buffers.bind_group(
                device,
                [
                    self.tile.prim.as_entire_binding(),
                    self.tile.sums.as_entire_binding(),
                    no_list.as_entire_binding(),
                ],
                indirect,
            )
        };
        let (group, indirect_group) = (tile(false), tile(true));
        let p = &self.pipelines;
        let (constants, layout) = (&p.constants, &buffers.layout);
        Ok(SplitShadows {
            primary: p.build(&self.gpu, "render_primary", layout, constants)?,
            primary_samples: p.build(&self.gpu, "render_primary_samples", layout, constants)?,
            list_primary: None,
            shadows: p.build(&self.gpu, "render_shadows", layout, constants)?,
            resolve: p.build(&self.gpu, "render_resolve", layout, constants)?,
            buffers,
            group,
            indirect_group,
        })
    }
}
