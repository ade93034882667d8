//! Adaptive sampling's later passes (a list of pixels, `params.spp` more
//! samples of each) as a wavefront: `render_list_primary` over a batch of
//! the list, then the tile render's shadow and resolve passes, in one
//! submission a dispatch, the same bits as `render_pixel_list`.

use crate::error::Result;
use crate::layout::WORKGROUP_INVOCATIONS;

use super::GpuRenderer;
use super::bindings::{SCENE, leading_bytes};
use super::readback::SUMS_BYTES;
use super::render::wave_budget;

/// Bytes of a listed pixel (x, y).
const PIXEL_BYTES: u64 = 8;

impl GpuRenderer {
    /// `render_pixel_list` with its shadow rays apart: each listed pixel's
    /// mean colour and the variance of its mean.
    pub(super) fn render_list_apart(&mut self, pixels: &[[u32; 2]]) -> Result<Vec<[f32; 4]>> {
        self.prepare_render()?;
        if self
            .pipelines
            .split
            .as_ref()
            .expect("prepared")
            .list_primary
            .is_none()
        {
            let p = &self.pipelines;
            let layout = &p.split.as_ref().expect("prepared").buffers.layout;
            let pipeline = p.build(&self.gpu, "render_list_primary", layout, &p.constants)?;
            self.pipelines
                .split
                .as_mut()
                .expect("prepared")
                .list_primary = Some(pipeline);
        }
        loop {
            let results = self.render_list_apart_once(pixels)?;
            if !self.loops_were_cut()? {
                return Ok(results);
            }
            self.fewer_samples_per_dispatch()?;
        }
    }

    fn render_list_apart_once(&self, pixels: &[[u32; 2]]) -> Result<Vec<[f32; 4]>> {
        let gpu = &self.gpu;
        let split = self.pipelines.split.as_ref().expect("prepared");
        let primary = split.list_primary.as_ref().expect("built");
        let spp = self.params.spp;
        let step = self.samples_per_dispatch().min(spp);
        // As many camera rays a dispatch as the wavefront's lists hold.
        let batch = (wave_budget(self.params.num_lights) / step) as usize;
        let batch = batch.min(pixels.len()).max(1);
        let [list, sums, staging] =
            self.list_buffers(batch as u64 * PIXEL_BYTES, batch as u64 * SUMS_BYTES);
        let mut results = Vec::with_capacity(pixels.len());
        for chunk in pixels.chunks(batch) {
            let n = chunk.len() as u64;
            gpu.queue
                .write_buffer(&list, 0, bytemuck::cast_slice(chunk));
            let group = |indirect| {
                split.buffers.bind_group(
                    &gpu.device,
                    [
                        self.tile.prim.as_entire_binding(),
                        leading_bytes(&sums, n * SUMS_BYTES),
                        leading_bytes(&list, n * PIXEL_BYTES),
                    ],
                    indirect,
                )
            };
            let groups = [group(false), group(true)];
            let workgroups = n.div_ceil(WORKGROUP_INVOCATIONS as u64) as u32;
            for begin in (0..spp).step_by(step as usize) {
                self.upload_samples(begin..(begin + step).min(spp));
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("pixel list, shadows apart"),
                        timestamp_writes: None,
                    });
                    pass.set_bind_group(SCENE.group, &self.resident.scene_group, &[]);
                    split.dispatch(
                        gpu,
                        &mut pass,
                        primary,
                        [&groups[0], &groups[1]],
                        [workgroups, 1, 1],
                    );
                }
                gpu.queue.submit([encoder.finish()]);
                gpu.wait()?;
            }
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&sums, 0, &staging, 0, n * SUMS_BYTES);
            gpu.queue.submit([encoder.finish()]);
            gpu.read_mapped(&staging, n * SUMS_BYTES, "pixel list results", |bytes| {
                results.extend_from_slice(bytemuck::cast_slice::<u8, [f32; 4]>(bytes))
            })?;
        }
        Ok(results)
    }
}
