//! Adaptive sampling's later passes (a list of pixels, the view's spp
//! samples of each) in the wavefront: `render_list_primary` over a batch
//! of the list, then the wavefront's shadow and resolve passes, in one
//! submission a dispatch, the same bits as the megakernel's
//! `render_pixel_list`.

use crate::error::Result;
use crate::layout::{Params, WORKGROUP_INVOCATIONS};

use super::GpuRenderer;
use super::bindings::{SCENE, leading_bytes};
use super::readback::SUMS_BYTES;
use super::wavefront::wave_budget;

/// Bytes of a listed pixel (x, y).
const PIXEL_BYTES: u64 = 8;

impl GpuRenderer {
    /// `render_pixel_list` in the wavefront, the view's uniform `params`:
    /// each listed pixel's mean colour and the variance of its mean.
    pub(super) fn render_list_wavefront(
        &mut self,
        params: &Params,
        pixels: &[[u32; 2]],
    ) -> Result<Vec<[f32; 4]>> {
        self.prepare_render()?;
        let wavefront = self.wavefront.as_mut().expect("prepared");
        wavefront.prepare_list(&self.gpu, &self.pipelines)?;
        loop {
            let results = self.render_list_wavefront_once(params, pixels)?;
            if !self.loops_were_cut()? {
                return Ok(results);
            }
            self.fewer_samples_per_dispatch(params.spp)?;
        }
    }

    fn render_list_wavefront_once(
        &self,
        params: &Params,
        pixels: &[[u32; 2]],
    ) -> Result<Vec<[f32; 4]>> {
        let gpu = &self.gpu;
        let wavefront = self.wavefront.as_ref().expect("prepared");
        let spp = params.spp;
        let step = self.samples_per_dispatch().min(spp);
        // As many camera rays a dispatch as the wavefront's lists hold.
        let batch = (wave_budget(self.scene_lights()) / step) as usize;
        let batch = batch.min(pixels.len()).max(1);
        let [list, sums, staging] = self.lists.buffers(
            self.host(),
            batch as u64 * PIXEL_BYTES,
            batch as u64 * SUMS_BYTES,
        );
        let mut results = Vec::with_capacity(pixels.len());
        for chunk in pixels.chunks(batch) {
            let n = chunk.len() as u64;
            gpu.queue
                .write_buffer(&list, 0, bytemuck::cast_slice(chunk));
            let groups = wavefront.list_groups(
                &gpu.device,
                [
                    self.tile.prim.as_entire_binding(),
                    leading_bytes(&sums, n * SUMS_BYTES),
                    leading_bytes(&list, n * PIXEL_BYTES),
                ],
            );
            let workgroups = n.div_ceil(WORKGROUP_INVOCATIONS as u64) as u32;
            for begin in (0..spp).step_by(step as usize) {
                self.resident
                    .write_samples(gpu, params, begin..(begin + step).min(spp));
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("pixel list, wavefront"),
                        timestamp_writes: None,
                    });
                    pass.set_bind_group(SCENE.group, self.resident.scene_group(), &[]);
                    wavefront.dispatch_list(gpu, &mut pass, &groups, workgroups);
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
