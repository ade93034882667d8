//! The tile renders' part of a renderer (`Tiles`): the tile's buffers,
//! the megakernel's pipeline or the wavefront (each built on its first
//! render), the timer and the samples a dispatch takes; rendered tile by
//! tile, each tile read back before the next, from the uniform of the view
//! each call is given.

use std::time::Duration;

use web_time::Instant;

use crate::error::{Error, Result};
use crate::layout::{Params, WORKGROUP_INVOCATIONS};
use crate::output::{Image, Rendered};
use crate::progress::Progress;

use super::bindings::IMAGE_TILE;
use super::device::Gpu;
use super::path_wave::PathWave;
use super::readback::TileTargets;
use super::resident::Host;
use super::timer::{GpuTimings, Timer};
use super::wavefront::{ShadowDispatch, Wavefront, wave_budget};
use super::{PATH_WAVE_PATHS, RENDER_WORKGROUP, TILE};

/// Samples a dispatch adds to each pixel on llvmpipe: the bundled scenes'
/// pixels ran out of loop iterations from about 192 (a 3,674-triangle
/// bunny, two lights); a heavier scene halves it as often as it needs.
const LLVMPIPE_SAMPLES_PER_DISPATCH: u32 = 32;

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

/// The tile renders' part of a renderer.
pub(super) struct Tiles {
    /// The buffers a tile is rendered into and read back from.
    targets: TileTargets,
    /// The megakernel's pipeline, built on its first render.
    megakernel: Option<wgpu::ComputePipeline>,
    /// The wavefront's passes, built on the first wavefront render: the
    /// direct integrator's, or the path integrator's (`path`).
    wavefront: Option<Wavefront>,
    path_wave: Option<PathWave>,
    /// Whether samples are path traced (the PATH_TRACE override).
    path: bool,
    timer: Option<Timer>,
    /// Samples one dispatch adds to a pixel: few enough that no invocation
    /// trips llvmpipe's loop limit (`loops_completed` in the shader);
    /// halved whenever one still does.
    samples_per_dispatch: u32,
    /// Lights in the resident scene (the wavefront's lists are sized by
    /// them).
    lights: u32,
}

impl Tiles {
    /// The tile's buffers and the timer, for a scene of `lights` lights,
    /// path traced or not.
    pub fn new(gpu: &Gpu, lights: u32, path: bool) -> Tiles {
        let samples_per_dispatch = if gpu.is_llvmpipe() {
            LLVMPIPE_SAMPLES_PER_DISPATCH
        } else {
            u32::MAX
        };
        Tiles {
            targets: TileTargets::new(&gpu.device),
            megakernel: None,
            wavefront: None,
            path_wave: None,
            path,
            timer: Timer::new(gpu),
            samples_per_dispatch,
            lights,
        }
    }

    /// The tile's buffers (the megakernel's group 1 binds them).
    pub fn targets(&self) -> &TileTargets {
        &self.targets
    }

    pub fn timer(&self) -> Option<&Timer> {
        self.timer.as_ref()
    }

    /// Drops the passes built so far (the shader's overrides changed):
    /// `prepare` builds them again.
    pub fn forget_pipelines(&mut self) {
        self.megakernel = None;
        self.wavefront = None;
        self.path_wave = None;
    }

    /// Whether samples are path traced (the integrator switched: its
    /// pipelines are forgotten already).
    pub fn set_path(&mut self, path: bool) {
        self.path = path;
    }

    /// The wavefront, once `prepare` built it.
    pub fn wavefront(&self) -> Option<&Wavefront> {
        self.wavefront.as_ref()
    }

    /// The path integrator's wavefront, once `prepare` built it.
    pub fn path_wave(&self) -> Option<&PathWave> {
        self.path_wave.as_ref()
    }

    /// Builds the wavefront and its pixel list's passes if not built
    /// yet.
    pub async fn prepare_wavefront_list(&mut self, host: Host<'_>) -> Result<()> {
        self.prepare(host, ShadowDispatch::Wavefront).await?;
        if let Some(path_wave) = self.path_wave.as_mut() {
            return path_wave.prepare_list(host).await;
        }
        let wavefront = self.wavefront.as_mut().expect("prepared");
        wavefront.prepare_list(host).await
    }

    /// Builds the passes a render in `dispatch` runs if not built yet: the
    /// megakernel's pipeline, or the wavefront (so that timing a render
    /// can leave the compile out).
    pub async fn prepare(&mut self, host: Host<'_>, dispatch: ShadowDispatch) -> Result<()> {
        match dispatch {
            ShadowDispatch::Wavefront if self.path => {
                if self.path_wave.is_none() {
                    self.path_wave = Some(PathWave::new(host, &self.targets).await?);
                }
            }
            ShadowDispatch::Wavefront if self.wavefront.is_none() => {
                self.wavefront = Some(Wavefront::new(host, &self.targets, self.lights).await?);
            }
            ShadowDispatch::Megakernel if self.megakernel.is_none() => {
                self.megakernel = Some(host.build("render", &host.layouts().image).await?);
            }
            _ => {}
        }
        Ok(())
    }

    /// Renders rows `rows` of the image of the view's uniform `params`
    /// (all or a part of it), tile by tile (`prepare` first). If the driver
    /// cut the shader's loops short anywhere (checked once, after the last
    /// tile), renders again with fewer samples per dispatch
    /// (`until_whole`).
    pub async fn render_rows(
        &mut self,
        host: Host<'_>,
        dispatch: ShadowDispatch,
        params: &Params,
        rows: std::ops::Range<u32>,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        self.until_whole(host, dispatch, params.spp, async |tiles| {
            tiles
                .render_rows_once(host, dispatch, params, &rows, progress)
                .await
        })
        .await
    }

    async fn render_rows_once(
        &self,
        host: Host<'_>,
        dispatch: ShadowDispatch,
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
        let side = self.tile_side(dispatch, params.spp);
        for tile_y in rows.clone().step_by(side as usize) {
            for tile_x in (0..width).step_by(side as usize) {
                let tile_width = side.min(width - tile_x);
                let tile_height = side.min(rows.end - tile_y);
                let start = Instant::now();
                let samples = 0..params.spp;
                let extent = [tile_x, tile_y, tile_width, tile_height];
                let device_time = self
                    .render_tile(host, dispatch, params, extent, samples)
                    .await?;
                timings.render += start.elapsed();
                if let Some(t) = device_time {
                    *timings.device.get_or_insert(Duration::ZERO) += t;
                }

                let start = Instant::now();
                self.targets
                    .read(host.gpu(), tile_width, tile_height, |row, colors, ids| {
                        let offset = ((tile_y - rows.start + row) * width + tile_x) as usize;
                        let n = tile_width as usize;
                        for (i, src) in colors.chunks(4).enumerate() {
                            rgb[offset + i] = [src[0], src[1], src[2]];
                            variance[offset + i] = src[3];
                        }
                        prims[offset..offset + n].copy_from_slice(ids);
                    })
                    .await?;
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

    /// Side of the tiles a render of `spp` samples a pixel dispatches:
    /// TILE at 1 sample per pixel per dispatch, smaller as they grow, so
    /// that a dispatch traces about as many camera rays (TILE²) at any spp;
    /// in the wavefront no larger than its buffers take (`wave_budget`:
    /// smaller with many lights).
    pub fn tile_side(&self, dispatch: ShadowDispatch, spp: u32) -> u32 {
        let samples = spp.min(self.samples_per_dispatch(dispatch));
        let step = RENDER_WORKGROUP[0].max(RENDER_WORKGROUP[1]);
        let side = (TILE / samples.isqrt().max(1))
            .next_multiple_of(step)
            .clamp(step, TILE);
        if dispatch == ShadowDispatch::Wavefront {
            let fits = (self.wave_budget() / samples).isqrt() / step * step;
            return side.min(fits.max(step));
        }
        side
    }

    /// Renders samples `samples` of one tile (`[x, y, width, height]`; all
    /// of them, or a progressive render's next few, added to the tile's
    /// sums) of the view `params` holds, over as many dispatches as
    /// `samples_per_dispatch` asks. Returns the device time where
    /// timestamps work.
    pub async fn render_tile(
        &self,
        host: Host<'_>,
        dispatch: ShadowDispatch,
        params: &Params,
        extent: [u32; 4],
        samples: std::ops::Range<u32>,
    ) -> Result<Option<Duration>> {
        let step = self.samples_per_dispatch(dispatch).min(params.spp);
        let mut device_time = None;
        for begin in samples.clone().step_by(step as usize) {
            let tile = Params {
                sample_begin: begin,
                sample_end: (begin + step).min(samples.end),
                tile_origin: [extent[0], extent[1]],
                tile_size: [extent[2], extent[3]],
                ..*params
            };
            if let Some(t) = self.dispatch_tile(host, dispatch, &tile).await? {
                *device_time.get_or_insert(Duration::ZERO) += t;
            }
        }
        Ok(device_time)
    }

    /// Samples a render dispatch adds to a pixel; in the wavefront, no
    /// more than leave a workgroup's pixels within its buffers.
    pub fn samples_per_dispatch(&self, dispatch: ShadowDispatch) -> u32 {
        match dispatch {
            ShadowDispatch::Wavefront => {
                let budget = self.wave_budget();
                self.samples_per_dispatch
                    .min(budget / WORKGROUP_INVOCATIONS)
            }
            ShadowDispatch::Megakernel => self.samples_per_dispatch,
        }
    }

    /// Camera rays (paths) a wavefront dispatch takes at most: the path
    /// integrator's, or the direct one's for the scene's lights.
    pub fn wave_budget(&self) -> u32 {
        if self.path {
            return PATH_WAVE_PATHS;
        }
        wave_budget(self.lights)
    }

    /// Runs `attempt` (a render of `spp` samples per pixel at the current
    /// samples per dispatch) until the driver cut none of the shader's
    /// loops short in it (checked once, after it): after an attempt it
    /// cut, again with half as many samples per dispatch, down to one,
    /// then fails rather than return a wrong picture.
    pub async fn until_whole<T>(
        &mut self,
        host: Host<'_>,
        dispatch: ShadowDispatch,
        spp: u32,
        mut attempt: impl AsyncFnMut(&Tiles) -> Result<T>,
    ) -> Result<T> {
        loop {
            let result = attempt(self).await?;
            if !host.loops_were_cut().await? {
                return Ok(result);
            }
            self.fewer_samples_per_dispatch(host.gpu(), dispatch, spp)?;
        }
    }

    /// Halves `samples_per_dispatch` after the driver cut loops short in a
    /// render of `spp` samples per pixel.
    fn fewer_samples_per_dispatch(
        &mut self,
        gpu: &Gpu,
        dispatch: ShadowDispatch,
        spp: u32,
    ) -> Result<()> {
        let step = self.samples_per_dispatch(dispatch).min(spp);
        if step <= 1 {
            return Err(Error::LoopsCut(format!(
                "{} cut the shader's loops short even at one sample per pixel per dispatch \
                 (Mesa's llvmpipe ends loops after 65535 iterations an invocation group): \
                 this scene is too complex for this adapter",
                gpu.describe()
            )));
        }
        self.samples_per_dispatch = step / 2;
        Ok(())
    }

    /// Renders one tile with the uniform `params` (its tile and samples
    /// set); returns its device time where timestamps work.
    async fn dispatch_tile(
        &self,
        host: Host<'_>,
        dispatch: ShadowDispatch,
        params: &Params,
    ) -> Result<Option<Duration>> {
        let [width, height] = params.tile_size;
        let gpu = host.gpu();
        host.write_uniform(params);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let workgroups = tile_workgroups(width, height, gpu.cpu_threads());
        if let (ShadowDispatch::Wavefront, Some(path_wave)) = (dispatch, &self.path_wave) {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render tile, path wavefront"),
                timestamp_writes: self.timer.as_ref().map(Timer::writes),
            });
            host.bind_scene(&mut pass);
            path_wave.dispatch_tile(gpu, &mut pass, params.max_depth, workgroups);
        } else if let (ShadowDispatch::Wavefront, Some(wavefront)) = (dispatch, &self.wavefront) {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render tile, wavefront"),
                timestamp_writes: self.timer.as_ref().map(Timer::writes),
            });
            host.bind_scene(&mut pass);
            let samples = params.sample_end - params.sample_begin;
            wavefront.dispatch_tile(gpu, &mut pass, samples, workgroups);
        } else {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render tile"),
                timestamp_writes: self.timer.as_ref().map(Timer::writes),
            });
            let [groups_x, groups_y, layers] = workgroups;
            pass.set_pipeline(self.megakernel.as_ref().expect("prepared"));
            host.bind_scene(&mut pass);
            pass.set_bind_group(IMAGE_TILE.group, host.image_group(), &[]);
            pass.dispatch_workgroups(groups_x, groups_y, layers);
        }
        if let Some(timer) = &self.timer {
            timer.resolve(&mut encoder);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait().await?;
        match &self.timer {
            Some(timer) => timer.read(gpu).await.map(Some),
            None => Ok(None),
        }
    }
}
