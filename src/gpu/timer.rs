//! Where a render's time went: wall time and timestamp queries.

use std::time::Duration;

use crate::error::Result;

use super::device::Gpu;

/// Where the time of one GPU render went.
#[derive(Clone, Copy, Debug, Default)]
pub struct GpuTimings {
    /// Wall time of the dispatches (submit to completion).
    pub render: Duration,
    pub readback: Duration,
    /// Device time of the dispatches, from timestamp queries, where the
    /// adapter supports them.
    pub device: Option<Duration>,
}

/// Timestamp queries around each dispatch.
pub(super) struct Timer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    period: f64,
}

impl Timer {
    pub fn new(gpu: &Gpu) -> Option<Timer> {
        if !gpu
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
        {
            return None;
        }
        let buffer = |label, usage| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16,
                usage,
                mapped_at_creation: false,
            })
        };
        Some(Timer {
            queries: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("dispatch time"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolve: buffer(
                "timestamps",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            staging: buffer(
                "timestamps readback",
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            ),
            period: gpu.queue.get_timestamp_period() as f64,
        })
    }

    pub fn writes(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }
    }

    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..2, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.staging, 0, 16);
    }

    /// The pass's device time, once its submission has completed.
    pub async fn read(&self, gpu: &Gpu) -> Result<Duration> {
        let ticks = gpu
            .read_mapped(&self.staging, 16, "timestamps", |bytes| {
                let t: &[u64] = bytemuck::cast_slice(bytes);
                t[1].saturating_sub(t[0])
            })
            .await?;
        Ok(Duration::from_nanos((ticks as f64 * self.period) as u64))
    }
}
