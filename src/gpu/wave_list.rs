//! Adaptive sampling's later passes (a list of pixels, the view's spp
//! samples of each) in the wavefront: `render_list_primary` over a batch
//! of the list, then the wavefront's shadow and resolve passes, in one
//! submission a dispatch, the same bits as the megakernel's
//! `render_pixel_list`.

use crate::error::Result;
use crate::layout::{Params, WORKGROUP_INVOCATIONS};

use super::bindings::leading_bytes;
use super::query::Lists;
use super::readback::SUMS_BYTES;
use super::render::Tiles;
use super::resident::Host;
use super::wavefront::ShadowDispatch;

/// Bytes of a listed pixel (x, y).
const PIXEL_BYTES: u64 = 8;

impl Tiles {
    /// `render_pixel_list` in the wavefront, the view's uniform `params`
    /// (`lists` keeps the buffers): each listed pixel's mean colour and the
    /// variance of its mean.
    pub async fn render_list_wavefront(
        &mut self,
        host: Host<'_>,
        lists: &Lists,
        params: &Params,
        pixels: &[[u32; 2]],
    ) -> Result<Vec<[f32; 4]>> {
        self.prepare_wavefront_list(host).await?;
        self.until_whole(host, ShadowDispatch::Wavefront, params.spp, async |tiles| {
            tiles
                .render_list_wavefront_once(host, lists, params, pixels)
                .await
        })
        .await
    }

    async fn render_list_wavefront_once(
        &self,
        host: Host<'_>,
        lists: &Lists,
        params: &Params,
        pixels: &[[u32; 2]],
    ) -> Result<Vec<[f32; 4]>> {
        let gpu = host.gpu();
        let spp = params.spp;
        let step = self
            .samples_per_dispatch(ShadowDispatch::Wavefront)
            .min(spp);
        // As many camera rays a dispatch as the wavefront's lists hold.
        let batch = (self.wave_budget() / step) as usize;
        let batch = batch.min(pixels.len()).max(1);
        let [list, sums, staging] =
            lists.buffers(host, batch as u64 * PIXEL_BYTES, batch as u64 * SUMS_BYTES);
        let prim = self.targets().prim.as_entire_binding();
        let mut results = Vec::with_capacity(pixels.len());
        for chunk in pixels.chunks(batch) {
            let n = chunk.len() as u64;
            gpu.queue
                .write_buffer(&list, 0, bytemuck::cast_slice(chunk));
            let bindings = [
                prim.clone(),
                leading_bytes(&sums, n * SUMS_BYTES),
                leading_bytes(&list, n * PIXEL_BYTES),
            ];
            let groups = match self.path_wave() {
                Some(path_wave) => path_wave.list_groups(&gpu.device, bindings),
                None => self
                    .wavefront()
                    .expect("prepared")
                    .list_groups(&gpu.device, bindings),
            };
            let workgroups = n.div_ceil(WORKGROUP_INVOCATIONS as u64) as u32;
            for begin in (0..spp).step_by(step as usize) {
                host.write_samples(params, begin..(begin + step).min(spp));
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("pixel list, wavefront"),
                        timestamp_writes: None,
                    });
                    host.bind_scene(&mut pass);
                    match self.path_wave() {
                        Some(path_wave) => path_wave.dispatch_list(
                            gpu,
                            &mut pass,
                            &groups,
                            workgroups,
                            params.max_depth,
                        ),
                        None => {
                            let wavefront = self.wavefront().expect("prepared");
                            wavefront.dispatch_list(gpu, &mut pass, &groups, workgroups)
                        }
                    }
                }
                gpu.queue.submit([encoder.finish()]);
                gpu.wait().await?;
            }
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&sums, 0, &staging, 0, n * SUMS_BYTES);
            gpu.queue.submit([encoder.finish()]);
            gpu.read_mapped(&staging, n * SUMS_BYTES, "pixel list results", |bytes| {
                results.extend_from_slice(bytemuck::cast_slice::<u8, [f32; 4]>(bytes))
            })
            .await?;
        }
        Ok(results)
    }
}
