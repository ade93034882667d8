//! The path integrator's wavefront (shaders/entry_paths.wgsl): a
//! dispatch's camera rays (`path_begin`, or `path_list_begin` over a pixel
//! list), then a bounce at a time the shade, shadow and extend passes over
//! the live paths, each dispatched indirectly with the workgroups
//! `path_advance` counts, and last the pixels' sums (`path_resolve`, or
//! `path_list_resolve`); in one submission. Its pipelines, buffers and
//! bind groups.

use crate::error::Result;

use super::bindings::PATH_WAVE;
use super::device::Gpu;
use super::readback::TileTargets;
use super::resident::Host;
use super::{PATH_RECORD_BYTES, PATH_WAVE_PATHS, SHADOW_QUERY_BYTES};

/// `path_counts` as each dispatch starts it (nothing appended, the first
/// half of the queues live) and `path_workgroups` (no workgroups).
const EMPTY_COUNTS: [u32; 5] = [0; 5];
const EMPTY_WORKGROUPS: [u32; 6] = [0, 1, 1, 0, 1, 1];
/// Where the shadow pass's dispatch lies in `path_workgroups`.
const SHADOW_WORKGROUPS_OFFSET: u64 = 12;
/// Bytes of a queue entry (a path's index).
const QUEUE_ENTRY_BYTES: u64 = 4;

/// Bytes of the largest of the path wavefront's buffers (its records).
pub(super) fn path_wave_bytes() -> u64 {
    PATH_WAVE_PATHS as u64 * PATH_RECORD_BYTES
}

/// The path wavefront's passes, its buffers, and the tile's bind groups.
pub(super) struct PathWave {
    begin: wgpu::ComputePipeline,
    list_begin: Option<wgpu::ComputePipeline>,
    advance: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
    shadows: wgpu::ComputePipeline,
    extend: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    list_resolve: Option<wgpu::ComputePipeline>,
    buffers: PathBuffers,
    /// The tile's group 1: for `path_advance`, and for the other passes.
    tile_groups: [wgpu::BindGroup; 2],
}

struct PathBuffers {
    layout: wgpu::BindGroupLayout,
    records: wgpu::Buffer,
    queues: wgpu::Buffer,
    shadow_queue: wgpu::Buffer,
    counts: wgpu::Buffer,
    workgroups: wgpu::Buffer,
    /// What the indirect passes bind at `path_workgroups`: a dispatch may
    /// not bind the buffer it is dispatched by.
    unused: wgpu::Buffer,
}

impl PathWave {
    /// The passes and buffers of `PATH_WAVE_PATHS` paths a dispatch,
    /// writing `tile`'s buffers.
    pub async fn new(host: Host<'_>, tile: &TileTargets) -> Result<PathWave> {
        let device = &host.gpu().device;
        let paths = PATH_WAVE_PATHS as u64;
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        let none = wgpu::BufferUsages::empty();
        let bytes = |words: &[u32]| std::mem::size_of_val(words) as u64;
        let buffers = PathBuffers {
            layout: PATH_WAVE.layout(device),
            records: buffer("path records", paths * PATH_RECORD_BYTES, none),
            queues: buffer("path queues", 2 * paths * QUEUE_ENTRY_BYTES, none),
            shadow_queue: buffer("path shadow queue", paths * SHADOW_QUERY_BYTES, none),
            counts: buffer(
                "path counts",
                bytes(&EMPTY_COUNTS),
                wgpu::BufferUsages::COPY_DST,
            ),
            workgroups: buffer(
                "path workgroups",
                bytes(&EMPTY_WORKGROUPS),
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::INDIRECT,
            ),
            unused: buffer("path workgroups, unused", bytes(&EMPTY_WORKGROUPS), none),
        };
        // A tile's render binds no pixel list: one entry, never read.
        let no_list = buffer("no pixel list", 8, none);
        let tile_groups = buffers.groups(
            device,
            [
                tile.prim.as_entire_binding(),
                tile.sums.as_entire_binding(),
                no_list.as_entire_binding(),
            ],
        );
        let build = |entry| host.build(entry, &buffers.layout);
        Ok(PathWave {
            begin: build("path_begin").await?,
            list_begin: None,
            advance: build("path_advance").await?,
            shade: build("path_shade").await?,
            shadows: build("path_shadows").await?,
            extend: build("path_extend").await?,
            resolve: build("path_resolve").await?,
            list_resolve: None,
            buffers,
            tile_groups,
        })
    }

    /// Builds the pixel list's first and last passes if not built yet.
    pub async fn prepare_list(&mut self, host: Host<'_>) -> Result<()> {
        if self.list_begin.is_none() {
            self.list_begin = Some(host.build("path_list_begin", &self.buffers.layout).await?);
            self.list_resolve = Some(
                host.build("path_list_resolve", &self.buffers.layout)
                    .await?,
            );
        }
        Ok(())
    }

    /// The group 1 over a pixel list, with `prim`, `sums` and `list` at
    /// `out_prim`, `tile_sums` and `pixel_list` (for `dispatch_list`).
    pub fn list_groups(
        &self,
        device: &wgpu::Device,
        bindings: [wgpu::BindingResource<'_>; 3],
    ) -> [wgpu::BindGroup; 2] {
        self.buffers.groups(device, bindings)
    }

    /// Records one dispatch over the tile's `workgroups`, `max_depth`
    /// bounces at most.
    pub fn dispatch_tile(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        max_depth: u32,
        workgroups: [u32; 3],
    ) {
        let ends = [&self.begin, &self.resolve];
        self.dispatch(gpu, pass, ends, &self.tile_groups, workgroups, max_depth);
    }

    /// Records one dispatch over a pixel list bound in `groups`
    /// (`list_groups`), `workgroups` of its pixels; `prepare_list` first.
    pub fn dispatch_list(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        groups: &[wgpu::BindGroup; 2],
        workgroups: u32,
        max_depth: u32,
    ) {
        let ends =
            [&self.list_begin, &self.list_resolve].map(|p| p.as_ref().expect("prepare_list first"));
        self.dispatch(gpu, pass, ends, groups, [workgroups, 1, 1], max_depth);
    }

    /// Records a dispatch: `begin` over `workgroups`, the bounces (a path
    /// has `max_depth` + 1 vertices at most: the last adds its emission
    /// only), then `resolve` over `workgroups`; the counts emptied first.
    fn dispatch(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        [begin, resolve]: [&wgpu::ComputePipeline; 2],
        [advance_group, group]: &[wgpu::BindGroup; 2],
        [x, y, z]: [u32; 3],
        max_depth: u32,
    ) {
        let b = &self.buffers;
        gpu.queue
            .write_buffer(&b.counts, 0, bytemuck::cast_slice(&EMPTY_COUNTS));
        gpu.queue
            .write_buffer(&b.workgroups, 0, bytemuck::cast_slice(&EMPTY_WORKGROUPS));
        let advance = |pass: &mut wgpu::ComputePass<'_>| {
            pass.set_bind_group(PATH_WAVE.group, advance_group, &[]);
            pass.set_pipeline(&self.advance);
            pass.dispatch_workgroups(1, 1, 1);
            pass.set_bind_group(PATH_WAVE.group, group, &[]);
        };
        pass.set_bind_group(PATH_WAVE.group, group, &[]);
        pass.set_pipeline(begin);
        pass.dispatch_workgroups(x, y, z);
        advance(pass);
        for depth in 0..=max_depth {
            pass.set_pipeline(&self.shade);
            pass.dispatch_workgroups_indirect(&b.workgroups, 0);
            advance(pass);
            pass.set_pipeline(&self.shadows);
            pass.dispatch_workgroups_indirect(&b.workgroups, SHADOW_WORKGROUPS_OFFSET);
            if depth < max_depth {
                pass.set_pipeline(&self.extend);
                pass.dispatch_workgroups_indirect(&b.workgroups, 0);
            }
        }
        pass.set_pipeline(resolve);
        pass.dispatch_workgroups(x, y, z);
    }
}

impl PathBuffers {
    /// Group 1 with `prim`, `sums` and `list` at `out_prim`, `tile_sums`
    /// and `pixel_list`: for `path_advance`, then for the other passes.
    fn groups(
        &self,
        device: &wgpu::Device,
        [prim, sums, list]: [wgpu::BindingResource<'_>; 3],
    ) -> [wgpu::BindGroup; 2] {
        [&self.workgroups, &self.unused].map(|workgroups| {
            PATH_WAVE.bind_group(
                device,
                PATH_WAVE.label,
                &self.layout,
                vec![
                    ("out_prim", prim.clone()),
                    ("tile_sums", sums.clone()),
                    ("pixel_list", list.clone()),
                    ("shadow_queue", self.shadow_queue.as_entire_binding()),
                    ("path_records", self.records.as_entire_binding()),
                    ("path_queues", self.queues.as_entire_binding()),
                    ("path_counts", self.counts.as_entire_binding()),
                    ("path_workgroups", workgroups.as_entire_binding()),
                ],
            )
        })
    }
}
