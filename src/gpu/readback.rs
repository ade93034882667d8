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
    pub async fn were_cut(&self, gpu: &Gpu) -> Result<bool> {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.buffer, 0, &self.staging, 0, 4);
        encoder.clear_buffer(&self.buffer, 0, None);
        gpu.queue.submit([encoder.finish()]);
        gpu.read_mapped(&self.staging, 4, "loop status", |bytes| {
            bytemuck::cast_slice::<u8, u32>(bytes)[0] != 0
        })
        .await
    }
}
