//! A render refined a few samples at a time (the viewer's): samples
//! `[begin, end)` of the view added, tile by tile, to per-pixel sums the
//! caller keeps, exactly as `render` adds a tile's samples over its
//! dispatches, so that the last batch's means are `render`'s image bit for
//! bit.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::camera::View;
use crate::error::{Error, Result};
use crate::layout::Params;
use crate::output::Image;
use crate::progress::Progress;

use super::readback::SUMS_BYTES;
use super::{GpuRenderer, TILE};

impl GpuRenderer {
    /// Adds samples `samples` of `view` (of its `spp`) to `sums`
    /// (one per pixel, row by row: colour sums and squared luminance, as
    /// the shader keeps them), which hold samples `0..samples.start`.
    /// When `samples.end` is the view's spp, returns the finished image:
    /// the shader's means, bit for bit the image `render` returns.
    pub fn add_samples(
        &mut self,
        view: &View,
        samples: Range<u32>,
        sums: &mut [[f32; 4]],
    ) -> Result<Option<Image>> {
        self.add_samples_or_cancel(view, samples, sums, &AtomicBool::new(false))
    }

    /// `add_samples`, stopped before its next tile once `cancel` is set
    /// (then `sums` are as they were, and None comes back).
    pub fn add_samples_or_cancel(
        &mut self,
        view: &View,
        samples: Range<u32>,
        sums: &mut [[f32; 4]],
        cancel: &AtomicBool,
    ) -> Result<Option<Image>> {
        let params = self.uniform(view);
        let (width, height, spp) = (params.width, params.height, params.spp);
        crate::camera::check_batch((width, height, spp), &samples, sums.len())
            .map_err(Error::Usage)?;
        if samples == (0..spp) {
            let (rendered, _) = self.render(view, &Progress::hidden())?;
            return Ok(Some(rendered.image));
        }
        self.prepare_render()?;
        loop {
            // The sums change only once the batch's loops ran whole.
            let mut next = sums.to_vec();
            let image = self.add_samples_once(&params, &samples, &mut next, cancel)?;
            if cancel.load(Ordering::Relaxed) {
                return Ok(None);
            }
            if !self.loops_were_cut()? {
                sums.copy_from_slice(&next);
                return Ok(image);
            }
            self.fewer_samples_per_dispatch(spp)?;
        }
    }

    fn add_samples_once(
        &mut self,
        params: &Params,
        samples: &Range<u32>,
        sums: &mut [[f32; 4]],
        cancel: &AtomicBool,
    ) -> Result<Option<Image>> {
        let (width, height) = (params.width, params.height);
        let finishing = samples.end == params.spp;
        let mut rgb = vec![[0.0f32; 3]; if finishing { sums.len() } else { 0 }];
        let staging = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tile sums readback"),
            size: TILE as u64 * TILE as u64 * SUMS_BYTES,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let side = self.tile_side_for(params.spp);
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
                    self.gpu.queue.write_buffer(&self.tile.sums, 0, bytes);
                }
                let extent = [tile_x, tile_y, tile_width as u32, tile_height];
                self.render_tile(params, extent, samples.clone())?;
                if finishing {
                    self.tile
                        .read(&self.gpu, extent[2], tile_height, |row, colors, _| {
                            for (i, src) in colors.chunks(4).enumerate() {
                                rgb[at(row) + i] = [src[0], src[1], src[2]];
                            }
                        })?;
                    continue;
                }
                let len = slot(tile_height) as u64 * SUMS_BYTES;
                let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
                encoder.copy_buffer_to_buffer(&self.tile.sums, 0, &staging, 0, len);
                self.gpu.queue.submit([encoder.finish()]);
                self.gpu.read_mapped(&staging, len, "tile sums", |bytes| {
                    let block: &[[f32; 4]] = bytemuck::cast_slice(bytes);
                    for row in 0..tile_height {
                        sums[at(row)..][..tile_width]
                            .copy_from_slice(&block[slot(row)..][..tile_width]);
                    }
                })?;
            }
        }
        Ok(finishing.then_some(Image { width, height, rgb }))
    }
}
