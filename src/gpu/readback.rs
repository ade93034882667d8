//! Getting results back from the device: mapped buffers, the render tile's
//! textures, and the shader's flag that the driver cut its loops short.

use std::sync::mpsc;

use crate::error::{Error, Result};

use super::TILE;
use super::device::Gpu;

impl Gpu {
    /// Maps the first `len` bytes of `buffer` (MAP_READ) once the queue's
    /// work is done, hands them to `read`, and unmaps; `what` names the
    /// data in errors.
    pub(super) fn read_mapped<T>(
        &self,
        buffer: &wgpu::Buffer,
        len: u64,
        what: &str,
        read: impl FnOnce(&[u8]) -> T,
    ) -> Result<T> {
        let (sender, receiver) = mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, ..len, move |r| {
            let _ = sender.send(r);
        });
        self.wait()?;
        let fail = |e: String| Error::Gpu(format!("reading back the {what}: {e}"));
        receiver
            .recv()
            .map_err(|e| fail(e.to_string()))?
            .map_err(|e| fail(e.to_string()))?;
        let result = {
            let mapped = buffer
                .get_mapped_range(..len)
                .map_err(|e| fail(e.to_string()))?;
            read(&mapped)
        };
        buffer.unmap();
        Ok(result)
    }
}

/// Bytes per row of a texture copy: wgpu requires a multiple of 256.
pub fn padded_bytes_per_row(width: u32, bytes_per_pixel: u32) -> u32 {
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    (width * bytes_per_pixel).div_ceil(align) * align
}

/// The textures a render tile is written to, and their readback buffers.
pub(super) struct TileTargets {
    pub color: wgpu::Texture,
    pub prim: wgpu::Texture,
    color_staging: wgpu::Buffer,
    prim_staging: wgpu::Buffer,
}

impl TileTargets {
    pub fn new(device: &wgpu::Device) -> TileTargets {
        let texture = |label, format| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: TILE,
                    height: TILE,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let staging = |label, bytes_per_pixel| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (padded_bytes_per_row(TILE, bytes_per_pixel) * TILE) as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            })
        };
        TileTargets {
            color: texture("color", wgpu::TextureFormat::Rgba32Float),
            prim: texture("prim", wgpu::TextureFormat::R32Uint),
            color_staging: staging("color readback", 16),
            prim_staging: staging("prim readback", 4),
        }
    }

    /// The colour and primitive textures, as bound at `out_color` and
    /// `out_prim`.
    pub fn views(&self) -> [wgpu::TextureView; 2] {
        [
            self.color.create_view(&Default::default()),
            self.prim.create_view(&Default::default()),
        ]
    }

    /// Copies the tile's textures to the staging buffers (rows padded as
    /// wgpu requires), maps them and hands each row to `row_sink`.
    pub fn read(
        &self,
        gpu: &Gpu,
        width: u32,
        height: u32,
        mut row_sink: impl FnMut(u32, &[f32], &[u32]),
    ) -> Result<()> {
        let color_row = padded_bytes_per_row(TILE, 16);
        let prim_row = padded_bytes_per_row(TILE, 4);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let extent = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        for (texture, buffer, row_bytes) in [
            (&self.color, &self.color_staging, color_row),
            (&self.prim, &self.prim_staging, prim_row),
        ] {
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row_bytes),
                        rows_per_image: Some(height),
                    },
                },
                extent,
            );
        }
        gpu.queue.submit([encoder.finish()]);

        let (sender, receiver) = mpsc::channel();
        for buffer in [&self.color_staging, &self.prim_staging] {
            let sender = sender.clone();
            buffer.map_async(wgpu::MapMode::Read, .., move |r| {
                let _ = sender.send(r);
            });
        }
        gpu.wait()?;
        for _ in 0..2 {
            receiver
                .recv()
                .map_err(|e| Error::Gpu(format!("readback: {e}")))?
                .map_err(|e| Error::Gpu(format!("readback: {e}")))?;
        }
        {
            let map = |buffer: &wgpu::Buffer| {
                buffer
                    .get_mapped_range(..)
                    .map_err(|e| Error::Gpu(format!("readback: {e}")))
            };
            let colors = map(&self.color_staging)?;
            let ids = map(&self.prim_staging)?;
            for row in 0..height {
                let c = (row * color_row) as usize;
                let p = (row * prim_row) as usize;
                row_sink(
                    row,
                    bytemuck::cast_slice(&colors[c..c + width as usize * 16]),
                    bytemuck::cast_slice(&ids[p..p + width as usize * 4]),
                );
            }
        }
        self.color_staging.unmap();
        self.prim_staging.unmap();
        Ok(())
    }
}

/// The shader's flag that the driver cut its loops short (`loop_status`),
/// and its readback.
pub(super) struct LoopStatus {
    pub buffer: wgpu::Buffer,
    staging: wgpu::Buffer,
}

impl LoopStatus {
    pub fn new(device: &wgpu::Device) -> LoopStatus {
        LoopStatus {
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("loop status"),
                size: 4,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            staging: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("loop status readback"),
                size: 4,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
        }
    }

    /// Whether any invocation since the last call found its loops cut short
    /// (the shader's `report_cut_loops`); clears the flag.
    pub fn were_cut(&self, gpu: &Gpu) -> Result<bool> {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.buffer, 0, &self.staging, 0, 4);
        encoder.clear_buffer(&self.buffer, 0, None);
        gpu.queue.submit([encoder.finish()]);
        gpu.read_mapped(&self.staging, 4, "loop status", |bytes| {
            bytemuck::cast_slice::<u8, u32>(bytes)[0] != 0
        })
    }
}
