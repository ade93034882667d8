//! Getting results back from the device: mapped buffers, the render tile's
//! buffers, and the shader's flag that the driver cut its loops short.

use crate::error::{Error, Result};

use super::TILE;
use super::device::Gpu;
use super::signal::signal;

impl Gpu {
    /// Maps the first `len` bytes of `buffer` (MAP_READ) once the queue's
    /// work is done, hands them to `read`, and unmaps; `what` names the
    /// data in errors.
    pub(super) async fn read_mapped<T>(
        &self,
        buffer: &wgpu::Buffer,
        len: u64,
        what: &str,
        read: impl FnOnce(&[u8]) -> T,
    ) -> Result<T> {
        let (sender, mapped) = signal();
        buffer.map_async(wgpu::MapMode::Read, ..len, move |r| sender.send(r));
        self.wait().await?;
        let fail = |e: String| Error::Gpu(format!("reading back the {what}: {e}"));
        mapped.await.map_err(|e| fail(e.to_string()))?;
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

/// The buffers a render tile is written to (`tile_sums`, `out_prim`:
/// pixel (x, y) at y · TILE + x), and their readback buffers.
pub(super) struct TileTargets {
    /// The pixels' sums between a tile's dispatches, their means after
    /// the last; copied both ways by a progressive render (`add_samples`).
    pub sums: wgpu::Buffer,
    pub prim: wgpu::Buffer,
    color_staging: wgpu::Buffer,
    prim_staging: wgpu::Buffer,
}

/// Bytes of a tile pixel's sums or mean (colour and squared luminance, or
/// colour and variance), and of its primitive.
pub(super) const SUMS_BYTES: u64 = 16;
const PRIM_BYTES: u64 = 4;

impl TileTargets {
    pub fn new(device: &wgpu::Device) -> TileTargets {
        let buffer = |label, bytes_per_pixel: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes_per_pixel * (TILE * TILE) as u64,
                usage,
                mapped_at_creation: false,
            })
        };
        let target = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let staging = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ;
        TileTargets {
            sums: buffer(
                "tile sums",
                SUMS_BYTES,
                target | wgpu::BufferUsages::COPY_DST,
            ),
            prim: buffer("prim", PRIM_BYTES, target),
            color_staging: buffer("color readback", SUMS_BYTES, staging),
            prim_staging: buffer("prim readback", PRIM_BYTES, staging),
        }
    }

    /// Copies the tile's first `height` rows (its means, after its last
    /// dispatch) to the staging buffers, maps them and hands the first
    /// `width` pixels of each row to `row_sink`.
    pub async fn read(
        &self,
        gpu: &Gpu,
        width: u32,
        height: u32,
        mut row_sink: impl FnMut(u32, &[f32], &[u32]),
    ) -> Result<()> {
        let rows = (height * TILE) as u64;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        for (buffer, staging, bytes) in [
            (&self.sums, &self.color_staging, SUMS_BYTES),
            (&self.prim, &self.prim_staging, PRIM_BYTES),
        ] {
            encoder.copy_buffer_to_buffer(buffer, 0, staging, 0, rows * bytes);
        }
        gpu.queue.submit([encoder.finish()]);

        let mapped = [
            (&self.color_staging, SUMS_BYTES),
            (&self.prim_staging, PRIM_BYTES),
        ]
        .map(|(buffer, bytes)| {
            let (sender, mapped) = signal();
            buffer.map_async(wgpu::MapMode::Read, ..rows * bytes, move |r| sender.send(r));
            mapped
        });
        gpu.wait().await?;
        for mapped in mapped {
            mapped
                .await
                .map_err(|e| Error::Gpu(format!("readback: {e}")))?;
        }
        {
            let map = |buffer: &wgpu::Buffer, bytes: u64| {
                buffer
                    .get_mapped_range(..rows * bytes)
                    .map_err(|e| Error::Gpu(format!("readback: {e}")))
            };
            let colors = map(&self.color_staging, SUMS_BYTES)?;
            let ids = map(&self.prim_staging, PRIM_BYTES)?;
            let colors: &[[f32; 4]] = bytemuck::cast_slice(&colors);
            let ids: &[u32] = bytemuck::cast_slice(&ids);
            for row in 0..height {
                let at = (row * TILE) as usize;
                row_sink(
                    row,
                    bytemuck::cast_slice(&colors[at..at + width as usize]),
                    &ids[at..at + width as usize],
                );
            }
        }
        self.color_staging.unmap();
        self.prim_staging.unmap();
        Ok(())
    }
}

/// The shader's flag that the driver cut its loops short (`loop_status`,
/// a one-texel r32uint storage texture), and its readback.
pub(super) struct LoopStatus {
    pub texture: wgpu::Texture,
    staging: wgpu::Buffer,
}

/// A flag's bytes, and what a row of a texture copy to a buffer is
/// aligned to.
const FLAG_BYTES: u32 = 4;
const ROW_ALIGNMENT: u64 = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as u64;

impl LoopStatus {
    pub fn new(device: &wgpu::Device) -> LoopStatus {
        LoopStatus {
            texture: device.create_texture(&wgpu::TextureDescriptor {
                label: Some("loop status"),
                size: wgpu::Extent3d {
                    width: 1,
                    height: 1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R32Uint,
                usage: wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            }),
            staging: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("loop status readback"),
                size: ROW_ALIGNMENT,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
        }
    }

    /// Whether any invocation since the last call found its loops cut short
    /// (the shader's `report_cut_loops`); clears the flag.
    pub async fn were_cut(&self, gpu: &Gpu) -> Result<bool> {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let extent = wgpu::Extent3d {
            width: 1,
            height: 1,
            depth_or_array_layers: 1,
        };
        encoder.copy_texture_to_buffer(
            self.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(ROW_ALIGNMENT as u32),
                    rows_per_image: None,
                },
            },
            extent,
        );
        gpu.queue.submit([encoder.finish()]);
        // Queued after the copy: the queue's writes go before the next
        // submission's commands.
        gpu.queue.write_texture(
            self.texture.as_image_copy(),
            &[0; FLAG_BYTES as usize],
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(FLAG_BYTES),
                rows_per_image: None,
            },
            extent,
        );
        gpu.read_mapped(&self.staging, FLAG_BYTES as u64, "loop status", |bytes| {
            bytemuck::cast_slice::<u8, u32>(bytes)[0] != 0
        })
        .await
    }
}
