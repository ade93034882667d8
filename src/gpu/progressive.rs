//! A render refined a few samples at a time (the viewer's): samples
//! `[begin, end)` of the view added, tile by tile, to per-pixel sums the
//! caller keeps, exactly as `render` adds a tile's samples over its
//! dispatches, so that the last batch's means are `render`'s image bit for
//! bit.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::Result;
use crate::layout::Params;
use crate::output::Image;

use super::TILE;
use super::readback::SUMS_BYTES;
use super::render::Tiles;
use super::resident::Host;
use super::wavefront::ShadowDispatch;

impl Tiles {
    /// Adds samples `samples` (a batch checked against the view, not all
    /// of them) of the view's uniform `params` to `sums` (one per pixel,
    /// row by row: colour sums and squared luminance, as the shader keeps
    /// them), which hold samples `0..samples.start` (`prepare` first);
    /// stopped before its next tile once `cancel` is set (then `sums` are
    /// as they were, and None comes back). When `samples.end` is the
    /// view's spp, returns the finished image.
    pub async fn add_samples(
        &mut self,
        host: Host<'_>,
        dispatch: ShadowDispatch,
        params: &Params,
        samples: Range<u32>,
        sums: &mut [[f32; 4]],
        cancel: &AtomicBool,
    ) -> Result<Option<Image>> {
        // The sums change only once the batch's loops ran whole.
        let mut next = Vec::new();
        let image = self
            .until_whole(host, dispatch, params.spp, async |tiles| {
                next = sums.to_vec();
                tiles
                    .add_samples_once(host, dispatch, params, &samples, &mut next, cancel)
                    .await
            })
            .await?;
        if cancel.load(Ordering::Relaxed) {
            return Ok(None);
        }
        sums.copy_from_slice(&next);
        Ok(image)
    }

    async fn add_samples_once(
        &self,
        host: Host<'_>,
        dispatch: ShadowDispatch,
        params: &Params,
        samples: &Range<u32>,
        sums: &mut [[f32; 4]],
        cancel: &AtomicBool,
    ) -> Result<Option<Image>> {
        let (width, height) = (params.width, params.height);
        let finishing = samples.end == params.spp;
        let mut rgb = vec![[0.0f32; 3]; if finishing { sums.len() } else { 0 }];
        let gpu = host.gpu();
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tile sums readback"),
            size: TILE as u64 * TILE as u64 * SUMS_BYTES,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let side = self.tile_side(dispatch, params.spp);
        for tile_y in (0..height).step_by(side as usize) {
            for tile_x in (0..width).step_by(side as usize) {
                if cancel.load(Ordering::Relaxed) {
                    return Ok(None);
                }
                let tile_width = side.min(width - tile_x) as usize;
                let tile_height = side.min(height - tile_y);
                // The tile's rows in `tile_sums`, TILE pixels apart.
                let at = |row: u32| ((tile_y + row) * width + tile_x) as usize;
                let slot = |row: u32| (row * TILE) as usize;
                if samples.start > 0 {
                    let mut block = vec![[0.0f32; 4]; slot(tile_height)];
                    for row in 0..tile_height {
                        block[slot(row)..][..tile_width]
                            .copy_from_slice(&sums[at(row)..][..tile_width]);
                    }
                    let bytes = bytemuck::cast_slice(&block);
                    gpu.queue.write_buffer(&self.targets().sums, 0, bytes);
                }
                let extent = [tile_x, tile_y, tile_width as u32, tile_height];
                self.render_tile(host, dispatch, params, extent, samples.clone())
                    .await?;
                if finishing {
                    self.targets()
                        .read(gpu, extent[2], tile_height, |row, colors, _| {
                            for (i, src) in colors.chunks(4).enumerate() {
                                rgb[at(row) + i] = [src[0], src[1], src[2]];
                            }
                        })
                        .await?;
                    continue;
                }
                let len = slot(tile_height) as u64 * SUMS_BYTES;
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                encoder.copy_buffer_to_buffer(&self.targets().sums, 0, &staging, 0, len);
                gpu.queue.submit([encoder.finish()]);
                gpu.read_mapped(&staging, len, "tile sums", |bytes| {
                    let block: &[[f32; 4]] = bytemuck::cast_slice(bytes);
                    for row in 0..tile_height {
                        sums[at(row)..][..tile_width]
                            .copy_from_slice(&block[slot(row)..][..tile_width]);
                    }
                })
                .await?;
            }
        }
        Ok(finishing.then_some(Image { width, height, rgb }))
    }
}
