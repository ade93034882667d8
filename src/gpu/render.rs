//! The render passes: tile by tile, in the `render` megakernel or in the
//! wavefront (`wavefront.rs`), each tile read back before the next; the
//! view rendered is each call's argument.

use std::time::{Duration, Instant};

use crate::camera::View;
use crate::error::{Error, Result};
use crate::layout::{Params, WORKGROUP_INVOCATIONS};
use crate::output::{Image, Rendered};
use crate::progress::Progress;

use super::bindings::{IMAGE_TILE, SCENE};
use super::timer::{GpuTimings, Timer};
use super::wavefront::{ShadowDispatch, Wavefront, wave_budget};
use super::{GpuRenderer, RENDER_WORKGROUP, TILE};

/// Samples a dispatch adds to each pixel on llvmpipe: the bundled scenes'
/// pixels ran out of loop iterations from about 192 (a 3,674-triangle
/// bunny, two lights); a heavier scene halves it as often as it needs.
pub(super) const LLVMPIPE_SAMPLES_PER_DISPATCH: u32 = 32;

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

impl GpuRenderer {
    /// Renders the scene as `view` sees it, tile by tile, reading each
    /// back before the next.
    pub fn render(&mut self, view: &View, progress: &Progress) -> Result<(Rendered, GpuTimings)> {
        self.render_rows(view, 0..view.camera.height, progress)
    }

    /// Renders rows `rows` of `view`'s image alone (a part of it), tile by
    /// tile. If the driver cut the shader's loops short anywhere (checked
    /// once, after the last tile), renders again with half as many samples
    /// per dispatch, down to one, then fails rather than return a wrong
    /// picture.
    pub fn render_rows(
        &mut self,
        view: &View,
        rows: std::ops::Range<u32>,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        let params = self.uniform(view);
        self.prepare_render()?;
        loop {
            let result = self.render_rows_once(&params, &rows, progress)?;
            if !self.loops_were_cut()? {
                return Ok(result);
            }
            self.fewer_samples_per_dispatch(params.spp)?;
        }
    }

    fn render_rows_once(
        &mut self,
        params: &Params,
        rows: &std::ops::Range<u32>,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        let width = params.width;
        let height = rows.len() as u32;
        let mut rgb = vec![[0.0f32; 3]; width as usize * height as usize];
        let mut prims = vec![0u32; width as usize * height as usize];
        let mut variance = vec![0.0f32; width as usize * height as usize];
        let mut timings = GpuTimings::default();
        let side = self.tile_side_for(params.spp);
        for tile_y in rows.clone().step_by(side as usize) {
            for tile_x in (0..width).step_by(side as usize) {
                let tile_width = side.min(width - tile_x);
                let tile_height = side.min(rows.end - tile_y);
                let start = Instant::now();
                let samples = 0..params.spp;
                let extent = [tile_x, tile_y, tile_width, tile_height];
                let device_time = self.render_tile(params, extent, samples)?;
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

    /// Side of the tiles `render` dispatches for `view`: TILE at 1 sample
    /// per pixel per dispatch, smaller as they grow, so that a dispatch
    /// traces about as many camera rays (TILE²) at any spp; in the
    /// wavefront no larger than its buffers take (`wave_budget`: smaller
    /// with many lights).
    pub fn tile_side(&self, view: &View) -> u32 {
        self.tile_side_for(view.spp)
    }

    pub(super) fn tile_side_for(&self, spp: u32) -> u32 {
        let samples = spp.min(self.samples_per_dispatch());
        let step = RENDER_WORKGROUP[0].max(RENDER_WORKGROUP[1]);
        let side = (TILE / samples.isqrt().max(1))
            .next_multiple_of(step)
            .clamp(step, TILE);
        if self.is_wavefront() {
            let fits = (wave_budget(self.scene_lights()) / samples).isqrt() / step * step;
            return side.min(fits.max(step));
        }
        side
    }

    /// Number of tiles `render` dispatches for `view`.
    pub fn tile_count(&self, view: &View) -> u64 {
        let side = self.tile_side(view);
        let camera = &view.camera;
        camera.width.div_ceil(side) as u64 * camera.height.div_ceil(side) as u64
    }

    /// Renders samples `samples` of one tile (`[x, y, width, height]`; all
    /// of them, or a progressive render's next few, added to the tile's
    /// sums) of the view `params` holds, over as many dispatches as
    /// `samples_per_dispatch` asks. Returns the device time where
    /// timestamps work.
    pub(super) fn render_tile(
        &mut self,
        params: &Params,
        extent: [u32; 4],
        samples: std::ops::Range<u32>,
    ) -> Result<Option<Duration>> {
        let step = self.samples_per_dispatch().min(params.spp);
        let mut device_time = None;
        for begin in samples.clone().step_by(step as usize) {
            let dispatch = Params {
                sample_begin: begin,
                sample_end: (begin + step).min(samples.end),
                tile_origin: [extent[0], extent[1]],
                tile_size: [extent[2], extent[3]],
                ..*params
            };
            if let Some(t) = self.dispatch_tile(&dispatch)? {
                *device_time.get_or_insert(Duration::ZERO) += t;
            }
        }
        Ok(device_time)
    }

    /// Samples a render dispatch adds to a pixel; in the wavefront, no
    /// more than leave a workgroup's pixels within its buffers.
    pub(super) fn samples_per_dispatch(&self) -> u32 {
        if self.is_wavefront() {
            let budget = wave_budget(self.scene_lights());
            self.samples_per_dispatch
                .min(budget / WORKGROUP_INVOCATIONS)
        } else {
            self.samples_per_dispatch
        }
    }

    /// Whether this render is the wavefront, as `shadow_dispatch` asks.
    /// Each of its dispatches takes every sample of the tile's pixels a
    /// megakernel dispatch would, in one submission: an earlier version
    /// that dispatched each sample's passes and waited took 152 s rather
    /// than 19 over the sampling tests.
    pub fn is_wavefront(&self) -> bool {
        self.shadow_dispatch == ShadowDispatch::Wavefront
    }

    /// Halves `samples_per_dispatch` after the driver cut loops short in a
    /// render of `spp` samples per pixel.
    pub(super) fn fewer_samples_per_dispatch(&mut self, spp: u32) -> Result<()> {
        let step = self.samples_per_dispatch().min(spp);
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
        self.resident.loops_were_cut(&self.gpu)
    }

    /// Renders one tile with the uniform `params` (its tile and samples
    /// set); returns its device time where timestamps work.
    fn dispatch_tile(&mut self, params: &Params) -> Result<Option<Duration>> {
        let [width, height] = params.tile_size;
        let gpu = &self.gpu;
        let resident = &self.resident;
        resident.write_uniform(gpu, params);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let workgroups = tile_workgroups(width, height, gpu.cpu_threads());
        if let (true, Some(wavefront)) = (self.is_wavefront(), &self.wavefront) {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render tile, wavefront"),
                timestamp_writes: self.timer.as_ref().map(Timer::writes),
            });
            pass.set_bind_group(SCENE.group, resident.scene_group(), &[]);
            let samples = params.sample_end - params.sample_begin;
            wavefront.dispatch_tile(gpu, &mut pass, samples, workgroups);
        } else {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render tile"),
                timestamp_writes: self.timer.as_ref().map(Timer::writes),
            });
            let [groups_x, groups_y, layers] = workgroups;
            pass.set_pipeline(self.megakernel.as_ref().expect("prepared"));
            pass.set_bind_group(SCENE.group, resident.scene_group(), &[]);
            pass.set_bind_group(IMAGE_TILE.group, resident.image_group(), &[]);
            pass.dispatch_workgroups(groups_x, groups_y, layers);
        }
        if let Some(timer) = &self.timer {
            timer.resolve(&mut encoder);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait()?;
        self.timer.as_ref().map(|t| t.read(gpu)).transpose()
    }

    /// Builds the passes a render runs if not built yet: the megakernel's
    /// pipeline, or the wavefront (so that timing a render can leave the
    /// compile out).
    pub fn prepare_render(&mut self) -> Result<()> {
        if self.is_wavefront() {
            if self.wavefront.is_none() {
                let lights = self.scene_lights();
                let wavefront = Wavefront::new(&self.gpu, &self.pipelines, &self.tile, lights)?;
                self.wavefront = Some(wavefront);
            }
        } else if self.megakernel.is_none() {
            let host = self.host();
            let pipeline = host.build("render", &host.layouts().image)?;
            self.megakernel = Some(pipeline);
        }
        Ok(())
    }
}
