//! Geometric queries on the resident scene (closest points, winding
//! numbers, every hit along rays; shaders/entry_proximity.wgsl): points and
//! rays in the scene's local frame, answers in it (`proximity`, in the
//! engine, moves them). Buffers are kept between calls and grown as
//! needed, as `run_list`'s are; the winding tree is uploaded on the first
//! winding query, from the host's scene (`winding_source`).

use std::collections::HashMap;
use std::sync::Weak;

use crate::error::{Error, Result};
use crate::layout::{ClosestPoint, ListedHit, NO_HIT, Ray, WORKGROUP_INVOCATIONS};
use crate::scene::Scene;

use super::bindings::{PROXIMITY, leading_bytes, unmet_proximity_limits};
use super::resident::Host;

/// Items per dispatch at most: no dispatch runs long enough for a watchdog,
/// and the workgroup count stays within every device's limit
/// (`GpuRenderer::batch`: fewer where a binding holds fewer).
const BATCH: usize = 1 << 18;

/// The geometric queries' part of a renderer: their layout and pipelines
/// (each built on its first use), the buffers they keep between calls, and
/// the winding tree (uploaded on the first winding query).
#[derive(Default)]
pub(super) struct Proximity {
    layout: Option<wgpu::BindGroupLayout>,
    pipelines: HashMap<&'static str, wgpu::ComputePipeline>,
    /// By binding name (and "readback"), grown as needed.
    buffers: HashMap<&'static str, wgpu::Buffer>,
    /// The winding tree's nodes and triangle ids, once uploaded.
    winding: Option<(wgpu::Buffer, wgpu::Buffer)>,
    /// The host's scene, for its winding tree (set by the engine when it
    /// opens the renderer; the jobs let it go, and then no winding query
    /// runs on this renderer).
    winding_source: Option<Weak<Scene>>,
}

/// One binding's buffer and the bytes of it a dispatch binds.
type Bound<'a> = (&'static str, &'a wgpu::Buffer, u64);

impl Proximity {
    /// Where a winding query finds the scene's winding tree.
    pub fn set_winding_source(&mut self, scene: Weak<Scene>) {
        self.winding_source = Some(scene);
    }

    /// Items a dispatch takes, each binding `bytes` of one buffer (its
    /// largest): BATCH, or as many as the adapter's storage binding limit
    /// holds.
    fn batch(&self, host: Host<'_>, bytes: usize) -> usize {
        let fit = host.gpu().binding_limit() / bytes as u64;
        BATCH.min(fit as usize).max(1)
    }

    /// A kept buffer of at least `size` bytes (4 at least).
    fn kept_buffer(
        &mut self,
        host: Host<'_>,
        label: &'static str,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        let size = size.max(16).next_multiple_of(16);
        if let Some(b) = self.buffers.get(label).filter(|b| b.size() >= size) {
            return b.clone();
        }
        let buffer = host.gpu().device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        });
        self.buffers.insert(label, buffer.clone());
        buffer
    }

    fn storage(&mut self, host: Host<'_>, label: &'static str, bytes: &[u8]) -> wgpu::Buffer {
        use wgpu::BufferUsages as U;
        let buffer = self.kept_buffer(
            host,
            label,
            bytes.len() as u64,
            U::STORAGE | U::COPY_DST | U::COPY_SRC,
        );
        host.gpu().queue.write_buffer(&buffer, 0, bytes);
        buffer
    }

    /// Runs `entry` over `items` invocations with the named buffers bound
    /// (the rest of the table bound to a small placeholder).
    async fn dispatch_query(
        &mut self,
        host: Host<'_>,
        entry: &'static str,
        items: usize,
        bound: &[Bound<'_>],
    ) -> Result<()> {
        if self.layout.is_none() {
            if let Some(why) = unmet_proximity_limits(&host.gpu().limits) {
                return Err(Error::GpuLimit(format!(
                    "{} cannot run the geometric queries: {why}",
                    host.gpu().describe()
                )));
            }
            self.layout = Some(PROXIMITY.layout(&host.gpu().device));
        }
        if !self.pipelines.contains_key(entry) {
            let layout = self.layout.as_ref().expect("built");
            let pipeline = host.build(entry, layout).await?;
            self.pipelines.insert(entry, pipeline);
        }
        // The bindings this entry point does not use: each its own kept
        // buffer (one buffer under two bindings, one of them written,
        // would be refused).
        use wgpu::BufferUsages as U;
        let unused: Vec<(&str, wgpu::Buffer)> = PROXIMITY
            .entries
            .iter()
            .filter(|e| !bound.iter().any(|(name, ..)| *name == e.name))
            .map(|e| {
                (
                    e.name,
                    self.kept_buffer(host, e.name, 64, U::STORAGE | U::COPY_DST | U::COPY_SRC),
                )
            })
            .collect();
        let resources = PROXIMITY
            .entries
            .iter()
            .map(|e| {
                let (buffer, size) = match bound.iter().find(|(name, ..)| *name == e.name) {
                    Some(&(_, b, size)) => (b, size.max(4)),
                    None => (
                        &unused.iter().find(|(n, _)| *n == e.name).expect("kept").1,
                        64,
                    ),
                };
                (e.name, leading_bytes(buffer, size))
            })
            .collect();
        let layout = self.layout.as_ref().expect("built");
        let group = PROXIMITY.bind_group(&host.gpu().device, entry, layout, resources);
        let mut encoder = host
            .gpu()
            .device
            .create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(entry),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipelines[entry]);
            host.bind_scene(&mut pass);
            pass.set_bind_group(PROXIMITY.group, &group, &[]);
            pass.dispatch_workgroups(items.div_ceil(WORKGROUP_INVOCATIONS as usize) as u32, 1, 1);
        }
        host.gpu().queue.submit([encoder.finish()]);
        host.gpu().wait().await?;
        if host.loops_were_cut().await? {
            return Err(Error::LoopsCut(format!(
                "{} cut the shader's loops short in {entry} (Mesa's llvmpipe ends loops \
                 after 65535 iterations an invocation group)",
                host.gpu().describe()
            )));
        }
        Ok(())
    }

    /// The first `len` bytes of `buffer`, as `T`s.
    async fn read_back<T: bytemuck::Pod>(
        &mut self,
        host: Host<'_>,
        buffer: &wgpu::Buffer,
        len: u64,
    ) -> Result<Vec<T>> {
        use wgpu::BufferUsages as U;
        let staging = self.kept_buffer(host, "readback", len, U::COPY_DST | U::MAP_READ);
        let mut encoder = host
            .gpu()
            .device
            .create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, len);
        host.gpu().queue.submit([encoder.finish()]);
        host.gpu()
            .read_mapped(&staging, len, "query results", |bytes| {
                bytemuck::pod_collect_to_vec(bytes)
            })
            .await
    }

    /// Runs `entry` over `items` invocations with `inputs` bound and its
    /// output binding `output` a kept buffer of `len` bytes, and reads the
    /// output back as `T`s; returns the buffer too (a later pass binds
    /// it).
    async fn run_query<T: bytemuck::Pod>(
        &mut self,
        host: Host<'_>,
        entry: &'static str,
        items: usize,
        inputs: &[Bound<'_>],
        (output, len): (&'static str, u64),
    ) -> Result<(wgpu::Buffer, Vec<T>)> {
        use wgpu::BufferUsages as U;
        let buffer = self.kept_buffer(host, output, len, U::STORAGE | U::COPY_SRC | U::COPY_DST);
        let mut bound = inputs.to_vec();
        bound.push((output, &buffer, len));
        self.dispatch_query(host, entry, items, &bound).await?;
        let values = self.read_back(host, &buffer, len).await?;
        Ok((buffer, values))
    }

    /// `cpu::closest_points` on the device (`margins`: each point's cull
    /// margin, the CPU's `query_margin`).
    pub async fn closest_points(
        &mut self,
        host: Host<'_>,
        points: &[[f32; 3]],
        margins: &[f32],
        max_distance: f32,
    ) -> Result<Vec<ClosestPoint>> {
        let scalars = [max_distance * max_distance, 0.0, 0.0, 0.0];
        let mut out = Vec::with_capacity(points.len());
        let batch = self.batch(host, size_of::<ClosestPoint>());
        for (chunk, margins) in points.chunks(batch).zip(margins.chunks(batch)) {
            let input: Vec<[f32; 4]> = chunk
                .iter()
                .zip(margins)
                .map(|(p, &m)| [p[0], p[1], p[2], m])
                .collect();
            let points = self.storage(host, "query_points", bytemuck::cast_slice(&input));
            let scalars = self.storage(host, "query_scalars", bytemuck::cast_slice(&scalars));
            let len = (chunk.len() * size_of::<ClosestPoint>()) as u64;
            let (_, answers): (_, Vec<ClosestPoint>) = self
                .run_query(
                    host,
                    "closest_points",
                    chunk.len(),
                    &[
                        ("query_points", &points, (input.len() * 16) as u64),
                        ("query_scalars", &scalars, 16),
                    ],
                    ("closest_out", len),
                )
                .await?;
            out.extend(answers.into_iter().map(|a| {
                if a.prim == NO_HIT {
                    ClosestPoint::NONE
                } else {
                    a
                }
            }));
        }
        Ok(out)
    }

    /// `cpu::winding_numbers` on the device: the same tree (uploaded on the
    /// first call) walked in the same order.
    pub async fn winding_numbers(
        &mut self,
        host: Host<'_>,
        points: &[[f32; 3]],
    ) -> Result<Vec<f32>> {
        if self.winding.is_none() {
            let scene = self
                .winding_source
                .as_ref()
                .and_then(Weak::upgrade)
                .ok_or_else(|| {
                    Error::Gpu(
                        "winding numbers need the scene's winding tree, and this GPU renderer \
                         no longer has the host's scene: open it with Renderer::open or \
                         Renderers, keeping the scene"
                            .into(),
                    )
                })?;
            let tree = scene.bvh.winding_tree(scene.triangles.len());
            use wgpu::util::DeviceExt;
            let upload = |label, bytes: &[u8]| {
                host.gpu()
                    .device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents: if bytes.is_empty() { &[0; 4] } else { bytes },
                        usage: wgpu::BufferUsages::STORAGE,
                    })
            };
            let nodes = upload("winding nodes", bytemuck::cast_slice(&tree.nodes));
            let prims = upload("winding prims", bytemuck::cast_slice(&tree.prims));
            self.winding = Some((nodes, prims));
        }
        let (nodes, prims) = self.winding.clone().expect("uploaded");
        let mut out = Vec::with_capacity(points.len());
        // 16 bytes a point in, 4 out.
        for chunk in points.chunks(self.batch(host, 16)) {
            let input: Vec<[f32; 4]> = chunk.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect();
            let points = self.storage(host, "query_points", bytemuck::cast_slice(&input));
            let (_, answers) = self
                .run_query::<f32>(
                    host,
                    "winding_numbers",
                    chunk.len(),
                    &[
                        ("query_points", &points, (input.len() * 16) as u64),
                        ("winding_nodes", &nodes, nodes.size()),
                        ("winding_prims", &prims, prims.size()),
                    ],
                    ("winding_out", (chunk.len() * 4) as u64),
                )
                .await?;
            out.extend(answers);
        }
        Ok(out)
    }

    /// The crossing queries' `query_scalars`: the boxes' pad (the CPU's
    /// `box_pad`) second.
    fn crossing_scalars(&mut self, host: Host<'_>, pad: f32) -> wgpu::Buffer {
        let scalars = [0.0, pad, 0.0, 0.0];
        self.storage(host, "query_scalars", bytemuck::cast_slice(&scalars))
    }

    /// Each ray's count of crossings (`pad`: the CPU's `box_pad`).
    async fn count_chunk(
        &mut self,
        host: Host<'_>,
        rays: &[Ray],
        pad: f32,
    ) -> Result<(wgpu::Buffer, wgpu::Buffer, Vec<u32>)> {
        let rays_buffer = self.storage(host, "rays", bytemuck::cast_slice(rays));
        let scalars = self.crossing_scalars(host, pad);
        let (counts, n) = self
            .run_query::<u32>(
                host,
                "count_hits",
                rays.len(),
                &[
                    ("rays", &rays_buffer, (rays.len() * size_of::<Ray>()) as u64),
                    ("query_scalars", &scalars, 16),
                ],
                ("hit_counts", (rays.len() * 4) as u64),
            )
            .await?;
        Ok((rays_buffer, counts, n))
    }

    /// `cpu::count_intersections` on the device.
    pub async fn count_intersections(
        &mut self,
        host: Host<'_>,
        rays: &[Ray],
        pad: f32,
    ) -> Result<Vec<u32>> {
        let mut out = Vec::with_capacity(rays.len());
        for chunk in rays.chunks(self.batch(host, size_of::<Ray>())) {
            out.extend(self.count_chunk(host, chunk, pad).await?.2);
        }
        Ok(out)
    }

    /// `cpu::list_intersections` on the device, each ray's hits in the
    /// order the traversal found them (the engine sorts them): counts,
    /// their prefix sums, then a second pass that writes each ray's hits
    /// from its first slot, over runs of rays whose hits fit one binding.
    /// A ray whose crossings alone exceed one is `Error::GpuLimit` (auto
    /// takes the CPU path then).
    pub async fn list_intersections(
        &mut self,
        host: Host<'_>,
        rays: &[Ray],
        pad: f32,
    ) -> Result<(Vec<u64>, Vec<ListedHit>)> {
        let hit_bytes = size_of::<ListedHit>() as u64;
        // Hits one binding holds (each ray's first slot is a u32).
        let per_binding = (host.gpu().binding_limit() / hit_bytes).min(u32::MAX as u64);
        let mut splits = vec![0u64];
        let mut hits = Vec::new();
        let batch = self.batch(host, size_of::<Ray>());
        for (c, chunk) in rays.chunks(batch).enumerate() {
            let (rays_buffer, counts, n) = self.count_chunk(host, chunk, pad).await?;
            for &k in &n {
                splits.push(splits.last().expect("one") + k as u64);
            }
            let runs = binding_runs(&n, per_binding).map_err(|k| {
                Error::GpuLimit(format!(
                    "ray {}: its {} crossings take {} bytes, more than the {} bytes {} \
                     can bind (max_storage_buffer_binding_size {}); the CPU path lists them",
                    c * batch + k,
                    n[k],
                    n[k] as u64 * hit_bytes,
                    per_binding * hit_bytes,
                    host.gpu().describe(),
                    host.gpu().limits.max_storage_buffer_binding_size
                ))
            })?;
            for (range, total) in runs.into_iter().filter(|(_, total)| *total > 0) {
                // The whole chunk's rays are bound already; a run of them
                // is bound from its own first ray.
                let run = &chunk[range.clone()];
                let run_rays = if run.len() == chunk.len() {
                    rays_buffer.clone()
                } else {
                    self.storage(host, "rays", bytemuck::cast_slice(run))
                };
                let listed = self
                    .list_run(host, run, &run_rays, &counts, &n[range.clone()], total, pad)
                    .await?;
                let base = (c * batch + range.start) as u32;
                hits.extend(listed.into_iter().map(|h| ListedHit {
                    ray: h.ray + base,
                    ..h
                }));
            }
        }
        Ok((splits, hits))
    }

    /// The `total` hits of `run` (bound in `run_rays`), whose counts are
    /// `n`, ray indices from 0 (`counts`: the chunk's count buffer, its
    /// start rewritten with each ray's first slot).
    async fn list_run(
        &mut self,
        host: Host<'_>,
        run: &[Ray],
        run_rays: &wgpu::Buffer,
        counts: &wgpu::Buffer,
        n: &[u32],
        total: u64,
        pad: f32,
    ) -> Result<Vec<ListedHit>> {
        let firsts: Vec<u32> = n
            .iter()
            .scan(0u32, |first, &k| {
                let this = *first;
                *first += k;
                Some(this)
            })
            .collect();
        host.gpu()
            .queue
            .write_buffer(counts, 0, bytemuck::cast_slice(&firsts));
        let scalars = self.crossing_scalars(host, pad);
        let (_, listed) = self
            .run_query::<ListedHit>(
                host,
                "list_hits",
                run.len(),
                &[
                    ("rays", run_rays, std::mem::size_of_val(run) as u64),
                    ("query_scalars", &scalars, 16),
                    ("hit_counts", counts, (n.len() * 4) as u64),
                ],
                ("listed_hits", total * size_of::<ListedHit>() as u64),
            )
            .await?;
        Ok(listed)
    }
}

/// Consecutive runs of the rays whose crossing `counts` sum to at most
/// `per_binding` each (as many rays a run as fit), with their sums; or the
/// first ray whose count alone is more (which no run can list).
pub fn binding_runs(
    counts: &[u32],
    per_binding: u64,
) -> std::result::Result<Vec<(std::ops::Range<usize>, u64)>, usize> {
    let mut runs = Vec::new();
    let mut start = 0;
    while start < counts.len() {
        let (mut end, mut total) = (start, 0u64);
        while end < counts.len() && total + counts[end] as u64 <= per_binding {
            total += counts[end] as u64;
            end += 1;
        }
        if end == start {
            return Err(start);
        }
        runs.push((start..end, total));
        start = end;
    }
    Ok(runs)
}
