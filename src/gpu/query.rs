//! Ray queries and pixel lists: one invocation per item, in batches.

use std::cell::RefCell;
use std::collections::HashMap;
use std::time::Duration;

use crate::camera::View;
use crate::error::{Error, Result};
use crate::layout::{Hit, NO_HIT, Params, Ray, WORKGROUP_INVOCATIONS};
use crate::scene::Intersect;

use super::bindings::{SCENE, leading_bytes};
use super::pipelines::ListLayout;
use super::timer::Timer;
use super::{GpuRenderer, RENDER_WORKGROUP, TILE};

/// What the list passes keep between calls.
#[derive(Default)]
pub(super) struct ListState {
    /// The list passes' input, output and readback buffers, by label
    /// (`list_buffers`).
    buffers: RefCell<HashMap<&'static str, wgpu::Buffer>>,
    /// Device time of the last `trace_rays` (its dispatches, summed), where
    /// timestamps work.
    trace_device_time: Option<Duration>,
}

impl GpuRenderer {
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
        let pipeline = self.pipelines.trace[any_hit as usize][intersect.shader_value() as usize]
            .as_ref()
            .expect("prepared");
        let list = &self.pipelines.layouts.rays;
        let (hits, device): (Vec<Hit>, _) =
            self.run_list(pipeline, list, rays, 1 << 20, None, true)?;
        self.lists.trace_device_time = device;
        if self.loops_were_cut()? {
            return Err(Error::LoopsCut(format!(
                "{} cut the shader's loops short on a ray of this query (Mesa's llvmpipe \
                 ends loops after 65535 iterations an invocation group)",
                self.gpu.describe()
            )));
        }
        Ok(hits
            .into_iter()
            .map(|h| if h.prim == NO_HIT { Hit::MISS } else { h })
            .collect())
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
        self.prepare_pixel_list()?;
        loop {
            let pipeline = self.pipelines.pixel_list.as_ref().expect("built");
            let list = &self.pipelines.layouts.pixels;
            let step = self.samples_per_dispatch.min(params.spp);
            // As many samples per dispatch as a full tile at 1 spp.
            let batch =
                ((TILE * TILE) / step).max(RENDER_WORKGROUP[0] * RENDER_WORKGROUP[1]) as usize;
            let sampling = Some((&params, step));
            let (results, _) = self.run_list(pipeline, list, pixels, batch, sampling, false)?;
            if !self.loops_were_cut()? {
                return Ok(results);
            }
            self.fewer_samples_per_dispatch(params.spp)?;
        }
    }

    /// A list pass's input (written by the host, read by the shader),
    /// output (written by the shader) and readback buffers, of at least
    /// `input` and `output` bytes: kept between calls and grown as needed,
    /// since creating them anew cost lavapipe a sixth of a million-ray
    /// query.
    pub(super) fn list_buffers(&self, input: u64, output: u64) -> [wgpu::Buffer; 3] {
        use wgpu::BufferUsages as U;
        let mut cache = self.lists.buffers.borrow_mut();
        [
            ("list input", input, U::STORAGE | U::COPY_DST),
            ("list output", output, U::STORAGE | U::COPY_SRC),
            ("list readback", output, U::COPY_DST | U::MAP_READ),
        ]
        .map(|(label, size, usage)| {
            let kept = cache.get(label).filter(|b| b.size() >= size).cloned();
            kept.unwrap_or_else(|| {
                let buffer = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
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

    /// Uploads the uniform `params` with `samples` (of its spp) as the
    /// next dispatch's: a pixel list's samples, a dispatch at a time.
    pub(super) fn upload_samples(&self, params: &Params, samples: std::ops::Range<u32>) {
        let params = Params {
            sample_begin: samples.start,
            sample_end: samples.end,
            ..*params
        };
        self.resident.write_uniform(&self.gpu, &params);
    }

    /// Device time of the last `trace_rays`, from timestamp queries (None
    /// where the adapter has none).
    pub fn trace_device_time(&self) -> Option<Duration> {
        self.lists.trace_device_time
    }

    /// Runs a one-invocation-per-item entry point over `inputs` (bound at
    /// `list`'s first binding, outputs at its second), `batch` items per
    /// dispatch so that no dispatch runs long; with `sampling` (a view's
    /// uniform and a step), its samples that many at a time, a dispatch
    /// each, else one dispatch with the scene's uniform. With `timed`, also
    /// returns the dispatches' device time, summed, where timestamps work
    /// (reading it back waits on each dispatch's queries).
    fn run_list<I: bytemuck::Pod, O: bytemuck::Pod>(
        &self,
        pipeline: &wgpu::ComputePipeline,
        list: &ListLayout,
        inputs: &[I],
        batch: usize,
        sampling: Option<(&Params, u32)>,
        timed: bool,
    ) -> Result<(Vec<O>, Option<Duration>)> {
        const LIST_WORKGROUP: usize = WORKGROUP_INVOCATIONS as usize;
        let table = list.table;
        let [input, output] = table.entries else {
            unreachable!("a list's bindings are its input and its output")
        };
        let timer = self.timer.as_ref().filter(|_| timed);
        let mut device = timer.map(|_| Duration::ZERO);
        let gpu = &self.gpu;
        let batch = batch.min(inputs.len()).max(1);
        let [in_buffer, out_buffer, staging] = self.list_buffers(
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
                None => (self.resident.scene_params(), 1, 1),
            };
            for begin in (0..spp).step_by(step as usize) {
                self.upload_samples(params, begin..(begin + step).min(spp));
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("list"),
                        timestamp_writes: timer.map(Timer::writes),
                    });
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(SCENE.group, self.resident.scene_group(), &[]);
                    pass.set_bind_group(table.group, &group, &[]);
                    pass.dispatch_workgroups(chunk.len().div_ceil(LIST_WORKGROUP) as u32, 1, 1);
                }
                if let Some(timer) = timer {
                    timer.resolve(&mut encoder);
                }
                gpu.queue.submit([encoder.finish()]);
                gpu.wait()?;
                if let (Some(timer), Some(total)) = (timer, &mut device) {
                    *total += timer.read(gpu)?;
                }
            }
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&out_buffer, 0, &staging, 0, out_len);
            gpu.queue.submit([encoder.finish()]);
            gpu.read_mapped(&staging, out_len, "results", |bytes| {
                outputs.extend_from_slice(bytemuck::cast_slice::<u8, O>(bytes))
            })?;
        }
        Ok((outputs, device))
    }
}
