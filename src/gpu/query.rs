//! Ray queries, pixel lists and the lights' probe: one invocation per
//! item, in batches. Their part of a renderer (`Lists`): the `trace_rays`,
//! `render_pixel_list` and `probe_lights` pipelines, each built on its
//! first use, and the buffers kept between calls.

use std::cell::RefCell;
use std::collections::HashMap;
use std::time::Duration;

use crate::error::{Error, Result};
use crate::layout::{Hit, LightAnswer, LightQuery, NO_HIT, Params, Ray, WORKGROUP_INVOCATIONS};
use crate::scene::Intersect;

use super::bindings::leading_bytes;
use super::pipelines::ListLayout;
use super::resident::Host;
use super::timer::Timer;
use super::{RENDER_WORKGROUP, TILE};

/// The list passes' part of a renderer.
#[derive(Default)]
pub(super) struct Lists {
    /// `trace_rays` pipelines: by any hit or closest hit, then by
    /// ray/triangle test.
    trace: [[Option<wgpu::ComputePipeline>; 3]; 2],
    pixel_list: Option<wgpu::ComputePipeline>,
    light_probe: Option<wgpu::ComputePipeline>,
    /// The list passes' input, output and readback buffers, by label
    /// (`buffers`).
    buffers: RefCell<HashMap<&'static str, wgpu::Buffer>>,
    /// Device time of the last `trace_rays` (its dispatches, summed), where
    /// timestamps work.
    trace_device_time: Option<Duration>,
}

impl Lists {
    /// Drops the pipelines built so far (the shader's overrides changed);
    /// the kept buffers stay.
    pub fn forget_pipelines(&mut self) {
        self.trace = Default::default();
        self.pixel_list = None;
        self.light_probe = None;
    }

    /// Builds the `trace_rays` pipeline for closest or any hit with the
    /// given ray/triangle test, if not built yet.
    pub async fn prepare_trace(
        &mut self,
        host: Host<'_>,
        any_hit: bool,
        intersect: Intersect,
    ) -> Result<()> {
        let (a, i) = (any_hit as usize, intersect.shader_value() as usize);
        if self.trace[a][i].is_none() {
            let mut constants: Vec<(&str, f64)> = host
                .constants()
                .iter()
                .filter(|(name, _)| *name != "INTERSECT")
                .copied()
                .collect();
            constants.push(("INTERSECT", intersect.shader_value() as f64));
            constants.push(("ANY_HIT", if any_hit { 1.0 } else { 0.0 }));
            let layout = &host.layouts().rays.layout;
            let pipeline = host.build_with("trace_rays", layout, &constants).await?;
            self.trace[a][i] = Some(pipeline);
        }
        Ok(())
    }

    /// Traces `rays` in the scene's local frame (`prepare_trace` first),
    /// timed with `timer` where there is one: hits in that frame, misses
    /// as `Hit::MISS`.
    pub async fn trace(
        &mut self,
        host: Host<'_>,
        timer: Option<&Timer>,
        rays: &[Ray],
        any_hit: bool,
        intersect: Intersect,
    ) -> Result<Vec<Hit>> {
        let pipeline = self.trace[any_hit as usize][intersect.shader_value() as usize]
            .as_ref()
            .expect("prepared");
        let list = &host.layouts().rays;
        let (hits, device): (Vec<Hit>, _) = self
            .run_list(host, timer, pipeline, list, rays, 1 << 20, None)
            .await?;
        self.trace_device_time = device;
        if host.loops_were_cut().await? {
            return Err(Error::LoopsCut(format!(
                "{} cut the shader's loops short on a ray of this query (Mesa's llvmpipe \
                 ends loops after 65535 iterations an invocation group)",
                host.gpu().describe()
            )));
        }
        Ok(hits
            .into_iter()
            .map(|h| if h.prim == NO_HIT { Hit::MISS } else { h })
            .collect())
    }

    /// Device time of the last `trace`, from timestamp queries (None
    /// where the adapter has none).
    pub fn trace_device_time(&self) -> Option<Duration> {
        self.trace_device_time
    }

    /// Builds the `render_pixel_list` pipeline if not built yet.
    pub async fn prepare_pixel_list(&mut self, host: Host<'_>) -> Result<()> {
        if self.pixel_list.is_none() {
            let layout = &host.layouts().pixels.layout;
            self.pixel_list = Some(host.build("render_pixel_list", layout).await?);
        }
        Ok(())
    }

    /// The listed pixels rendered in one pass with the view's uniform
    /// `params`, `step` samples a dispatch (`prepare_pixel_list` first):
    /// mean colour and variance of the mean.
    pub async fn render_pixel_list(
        &self,
        host: Host<'_>,
        params: &Params,
        pixels: &[[u32; 2]],
        step: u32,
    ) -> Result<Vec<[f32; 4]>> {
        let pipeline = self.pixel_list.as_ref().expect("prepared");
        let list = &host.layouts().pixels;
        // As many samples per dispatch as a full tile at 1 spp.
        let batch = ((TILE * TILE) / step).max(RENDER_WORKGROUP[0] * RENDER_WORKGROUP[1]) as usize;
        let sampling = Some((params, step));
        let (results, _) = self
            .run_list(host, None, pipeline, list, pixels, batch, sampling)
            .await?;
        Ok(results)
    }

    /// The lights stage's functions on `queries` (`probe_lights`, which
    /// tests compare with the CPU twin), its pipeline built on first use.
    pub async fn probe_lights(
        &mut self,
        host: Host<'_>,
        queries: &[LightQuery],
    ) -> Result<Vec<LightAnswer>> {
        let list = &host.layouts().light_probe;
        if self.light_probe.is_none() {
            self.light_probe = Some(host.build("probe_lights", &list.layout).await?);
        }
        let pipeline = self.light_probe.as_ref().expect("built");
        let (answers, _) = self
            .run_list(host, None, pipeline, list, queries, 1 << 16, None)
            .await?;
        Ok(answers)
    }

    /// A list pass's input (written by the host, read by the shader),
    /// output (written by the shader) and readback buffers, of at least
    /// `input` and `output` bytes: kept between calls and grown as needed,
    /// since creating them anew cost lavapipe a sixth of a million-ray
    /// query.
    pub fn buffers(&self, host: Host<'_>, input: u64, output: u64) -> [wgpu::Buffer; 3] {
        use wgpu::BufferUsages as U;
        let mut cache = self.buffers.borrow_mut();
        [
            ("list input", input, U::STORAGE | U::COPY_DST),
            ("list output", output, U::STORAGE | U::COPY_SRC),
            ("list readback", output, U::COPY_DST | U::MAP_READ),
        ]
        .map(|(label, size, usage)| {
            let kept = cache.get(label).filter(|b| b.size() >= size).cloned();
            kept.unwrap_or_else(|| {
                let buffer = host.gpu().device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                });
                cache.insert(label, buffer.clone());
                buffer
            })
        })
    }

    /// Runs a one-invocation-per-item entry point over `inputs` (bound at
    /// `list`'s first binding, outputs at its second), `batch` items per
    /// dispatch so that no dispatch runs long; with `sampling` (a view's
    /// uniform and a step), its samples that many at a time, a dispatch
    /// each, else one dispatch with the scene's uniform. With `timer`, also
    /// returns the dispatches' device time, summed, where timestamps work
    /// (reading it back waits on each dispatch's queries).
    #[allow(clippy::too_many_arguments)]
    async fn run_list<I: bytemuck::Pod, O: bytemuck::Pod>(
        &self,
        host: Host<'_>,
        timer: Option<&Timer>,
        pipeline: &wgpu::ComputePipeline,
        list: &ListLayout,
        inputs: &[I],
        batch: usize,
        sampling: Option<(&Params, u32)>,
    ) -> Result<(Vec<O>, Option<Duration>)> {
        const LIST_WORKGROUP: usize = WORKGROUP_INVOCATIONS as usize;
        let table = list.table;
        let [input, output] = table.entries else {
            unreachable!("a list's bindings are its input and its output")
        };
        let mut device = timer.map(|_| Duration::ZERO);
        let gpu = host.gpu();
        let batch = batch.min(inputs.len()).max(1);
        let [in_buffer, out_buffer, staging] = self.buffers(
            host,
            (batch * size_of::<I>()) as u64,
            (batch * size_of::<O>()) as u64,
        );
        let mut outputs = Vec::with_capacity(inputs.len());
        for chunk in inputs.chunks(batch) {
            let in_len = std::mem::size_of_val(chunk) as u64;
            let out_len = (chunk.len() * size_of::<O>()) as u64;
            gpu.queue
                .write_buffer(&in_buffer, 0, bytemuck::cast_slice(chunk));
            let group = table.bind_group(
                &gpu.device,
                "list",
                &list.layout,
                vec![
                    (input.name, leading_bytes(&in_buffer, in_len)),
                    (output.name, leading_bytes(&out_buffer, out_len)),
                ],
            );
            let (params, spp, step) = match sampling {
                Some((params, step)) => (params, params.spp, step),
                None => (host.scene_params(), 1, 1),
            };
            for begin in (0..spp).step_by(step as usize) {
                host.write_samples(params, begin..(begin + step).min(spp));
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("list"),
                        timestamp_writes: timer.map(Timer::writes),
                    });
                    pass.set_pipeline(pipeline);
                    host.bind_scene(&mut pass);
                    pass.set_bind_group(table.group, &group, &[]);
                    pass.dispatch_workgroups(chunk.len().div_ceil(LIST_WORKGROUP) as u32, 1, 1);
                }
                if let Some(timer) = timer {
                    timer.resolve(&mut encoder);
                }
                gpu.queue.submit([encoder.finish()]);
                gpu.wait().await?;
                if let (Some(timer), Some(total)) = (timer, &mut device) {
                    *total += timer.read(gpu).await?;
                }
            }
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&out_buffer, 0, &staging, 0, out_len);
            gpu.queue.submit([encoder.finish()]);
            gpu.read_mapped(&staging, out_len, "results", |bytes| {
                outputs.extend_from_slice(bytemuck::cast_slice::<u8, O>(bytes))
            })
            .await?;
        }
        Ok((outputs, device))
    }
}
