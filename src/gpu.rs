//! The GPU path: adapter choice, scene upload, and tiled dispatch of
//! `shaders/trace.wgsl` through wgpu.

use std::borrow::Cow;
use std::sync::{Arc, Mutex, mpsc};
use std::time::{Duration, Instant};

use wgpu::util::DeviceExt;

use crate::cpu::f32::CameraBasis;
use crate::error::{Error, Result};
use crate::layout::{
    CompressedNode, Hit, LIGHT_DIRECTIONAL, LIGHT_POINT, NO_HIT, Params, PrimBlock, Ray, Sphere,
    Triangle, TriangleNormals,
};
use crate::output::{Image, Rendered};
use crate::progress::Progress;
use crate::scene::{Accel, Camera, Intersect, Scene};

/// The kernel's source, validated by naga in tests/shaders.rs.
pub const SHADER_SOURCE: &str = crate::shader_source::SOURCE;

/// Side of the square tile one dispatch renders: small enough that no
/// dispatch runs long enough for a GPU watchdog to kill it.
pub const TILE: u32 = 256;
/// The `render` entry point's workgroup (x, y) in pixels
/// (`RENDER_WORKGROUP_X`/`_Y` in trace.wgsl), measured on lavapipe against
/// 16×16 and 64×1 (docs/bvh.md).
const RENDER_WORKGROUP: [u32; 2] = [8, 8];
/// Invocations per workgroup of every entry point (`WORKGROUP_INVOCATIONS`
/// in trace.wgsl, which sizes the traversal stacks in workgroup memory by
/// it).
pub const WORKGROUP_INVOCATIONS: u32 = 64;
const _: () = assert!(RENDER_WORKGROUP[0] * RENDER_WORKGROUP[1] == WORKGROUP_INVOCATIONS);

/// Which adapter to use: `--adapter`, `--backend`, or wgpu's own
/// `WGPU_ADAPTER_NAME` and `WGPU_BACKEND` when those are unset.
#[derive(Clone, Debug, Default)]
pub struct AdapterRequest {
    /// Case-insensitive substring of the adapter's name.
    pub name: Option<String>,
    /// vulkan, metal, dx12 or gl.
    pub backend: Option<String>,
}

impl AdapterRequest {
    fn name_filter(&self) -> Option<String> {
        self.name
            .clone()
            .or_else(|| std::env::var("WGPU_ADAPTER_NAME").ok())
            .map(|n| n.to_lowercase())
    }

    /// True when the user named an adapter, which then may be a software one.
    pub fn names_adapter(&self) -> bool {
        self.name_filter().is_some()
    }

    /// The backends asked for, if any were: `--backend`, else wgpu's
    /// `WGPU_BACKEND` (a comma-separated list), each name checked alike.
    fn backends(&self) -> Result<Option<wgpu::Backends>> {
        let parse = |name: &str, source: &str| match name.trim().to_lowercase().as_str() {
            "vulkan" | "vk" => Ok(wgpu::Backends::VULKAN),
            "metal" | "mtl" => Ok(wgpu::Backends::METAL),
            "dx12" | "d3d12" => Ok(wgpu::Backends::DX12),
            "gl" | "gles" | "opengl" => Ok(wgpu::Backends::GL),
            other => Err(Error::Usage(format!(
                "unknown backend '{other}'{source}: use vulkan, metal, dx12 or gl"
            ))),
        };
        match self.backend.as_deref() {
            Some(name) => parse(name, "").map(Some),
            None => match std::env::var("WGPU_BACKEND") {
                Ok(list) => list
                    .split(',')
                    .try_fold(wgpu::Backends::empty(), |all, name| {
                        Ok(all | parse(name, " in WGPU_BACKEND")?)
                    })
                    .map(Some),
                Err(_) => Ok(None),
            },
        }
    }

    /// Whether the adapter's name matches `--adapter`/`WGPU_ADAPTER_NAME`.
    pub fn matches(&self, info: &wgpu::AdapterInfo) -> bool {
        self.name_filter()
            .is_none_or(|f| info.name.to_lowercase().contains(&f))
    }

    /// What was asked for, in words, for "no adapter" messages.
    pub fn describe_request(&self) -> Result<String> {
        let mut parts = Vec::new();
        if let Some(name) = self.name_filter() {
            parts.push(format!("whose name contains '{name}'"));
        }
        if let Some(backends) = self.backends()? {
            let names: Vec<&str> = [
                (wgpu::Backends::VULKAN, "Vulkan"),
                (wgpu::Backends::METAL, "Metal"),
                (wgpu::Backends::DX12, "DX12"),
                (wgpu::Backends::GL, "GL"),
            ]
            .iter()
            .filter(|(b, _)| backends.contains(*b))
            .map(|(_, name)| *name)
            .collect();
            parts.push(format!("on {}", names.join(" or ")));
        }
        Ok(parts.join(" "))
    }

    /// Whether Vulkan is among the backends asked for (lavapipe can help).
    pub fn wants_vulkan(&self) -> Result<bool> {
        Ok(self
            .backends()?
            .is_none_or(|b| b.contains(wgpu::Backends::VULKAN)))
    }
}

/// Every adapter wgpu finds for the requested backends. Unless a backend is
/// named, GL is only tried when Vulkan, Metal and DX12 offer nothing: its
/// headless start-up is slow and noisy.
pub fn enumerate_adapters(request: &AdapterRequest) -> Result<Vec<wgpu::Adapter>> {
    let find = |backends| {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        pollster::block_on(instance.enumerate_adapters(backends))
    };
    match request.backends()? {
        Some(backends) => Ok(find(backends)),
        None => {
            let primary = find(wgpu::Backends::PRIMARY);
            Ok(if primary.is_empty() {
                find(wgpu::Backends::SECONDARY)
            } else {
                primary
            })
        }
    }
}

fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
}

fn is_software(info: &wgpu::AdapterInfo) -> bool {
    info.device_type == wgpu::DeviceType::Cpu
}

/// Mesa's llvmpipe, as lavapipe (Vulkan) or through GL: it cuts loops short
/// after 65535 iterations an invocation group (the shader's
/// `loops_completed`).
fn is_llvmpipe(info: &wgpu::AdapterInfo) -> bool {
    info.name.to_lowercase().contains("llvmpipe") || info.driver.to_lowercase().contains("llvmpipe")
}

/// Where the shader reads the BVH's nodes and leaf blocks from
/// (`BVH_TEXELS` in trace.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhStorage {
    /// Storage buffers, split over two bindings when large: what hardware
    /// GPUs get.
    Buffers,
    /// rgba32uint textures read with `textureLoad`: what llvmpipe gets. It
    /// fetches a texel for its 8 SIMD lanes with vector instructions, where
    /// a storage-buffer load whose address differs between lanes is a loop
    /// over them, a branch per word (docs/bvh.md).
    Texels,
}

impl BvhStorage {
    /// The storage that measured fastest on this kind of adapter, where
    /// `scene`'s BVH fits it: a tree too large for the device's textures
    /// is read from buffers.
    pub fn for_scene(gpu: &Gpu, scene: &Scene) -> BvhStorage {
        let fits = |texels: usize| {
            let max = gpu.limits.max_texture_dimension_2d as usize;
            TEXELS_PER_ROW as usize <= max && texels.div_ceil(TEXELS_PER_ROW as usize) <= max
        };
        let words = |bytes: usize| bytes / 16;
        let nodes = words(scene.bvh.nodes.len() * size_of::<CompressedNode>());
        let blocks = words(std::mem::size_of_val(scene.bvh.blocks.as_slice()));
        if is_llvmpipe(&gpu.info) && fits(nodes) && fits(blocks) {
            BvhStorage::Texels
        } else {
            BvhStorage::Buffers
        }
    }
}

/// Texels in a row of a BVH texture (`TEXEL_ROW_BITS` in trace.wgsl): a
/// power of two, so that the shader splits a texel index into (x, y) with a
/// mask and a shift.
pub const TEXELS_PER_ROW: u32 = 4096;

/// Samples a dispatch adds to each pixel on llvmpipe: the bundled scenes'
/// pixels ran out of loop iterations from about 192 (a 3,674-triangle
/// bunny, two lights); a heavier scene halves it as often as it needs.
const LLVMPIPE_SAMPLES_PER_DISPATCH: u32 = 32;

/// `LAMBERT_GPU_MAX_BUFFER_BYTES`: a cap on the buffer and binding sizes
/// lambert requests from the adapter (`Gpu::open_limited`).
pub const MAX_BUFFER_ENV: &str = "LAMBERT_GPU_MAX_BUFFER_BYTES";

fn max_buffer_bytes_from_env() -> Result<Option<u64>> {
    match std::env::var(MAX_BUFFER_ENV) {
        Err(_) => Ok(None),
        Ok(v) => {
            v.trim().parse().map(Some).map_err(|_| {
                Error::Usage(format!("{MAX_BUFFER_ENV}={v}: expected a number of bytes"))
            })
        }
    }
}

/// An open device and queue.
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    errors: Arc<Mutex<Option<String>>>,
}

impl Gpu {
    /// Opens the best adapter matching `request`: hardware before software,
    /// Vulkan/Metal/DX12 before GL. With `hardware_only`, software
    /// rasterisers such as lavapipe do not count.
    pub fn open(request: &AdapterRequest, hardware_only: bool) -> Result<Gpu> {
        Gpu::open_limited(request, hardware_only, max_buffer_bytes_from_env()?)
    }

    /// `open`, requesting at most `max_buffer_bytes` per buffer and per
    /// storage binding (when given) instead of all the adapter offers: what
    /// a smaller GPU would do, for tests and for sharing a device.
    pub fn open_limited(
        request: &AdapterRequest,
        hardware_only: bool,
        max_buffer_bytes: Option<u64>,
    ) -> Result<Gpu> {
        let adapters = enumerate_adapters(request)?;
        let filter = request.name_filter();
        let rank = |info: &wgpu::AdapterInfo| {
            let kind = match info.device_type {
                wgpu::DeviceType::DiscreteGpu => 0,
                wgpu::DeviceType::IntegratedGpu => 1,
                wgpu::DeviceType::VirtualGpu => 2,
                wgpu::DeviceType::Cpu => 3,
                wgpu::DeviceType::Other => 4,
            };
            (kind, info.backend == wgpu::Backend::Gl)
        };
        let chosen = adapters
            .iter()
            .filter(|a| {
                let info = a.get_info();
                filter
                    .as_ref()
                    .is_none_or(|f| info.name.to_lowercase().contains(f))
                    && !(hardware_only && is_software(&info))
            })
            .min_by_key(|a| rank(&a.get_info()));
        let Some(adapter) = chosen else {
            let available: Vec<String> = adapters.iter().map(|a| describe(&a.get_info())).collect();
            let wanted = match (&filter, hardware_only) {
                (Some(f), _) => format!("no adapter whose name contains '{f}'"),
                (None, true) => "no hardware GPU adapter".to_string(),
                (None, false) => "no GPU adapter".to_string(),
            };
            let available = if available.is_empty() {
                "none (install Mesa's lavapipe: apt-get install mesa-vulkan-drivers)".to_string()
            } else {
                available.join(", ")
            };
            return Err(Error::Gpu(format!(
                "{wanted}; adapters available: {available}"
            )));
        };
        let info = adapter.get_info();
        // The adapter's real limits, not wgpu's conservative defaults: large
        // scenes need big storage bindings.
        let mut limits = adapter.limits();
        if let Some(max) = max_buffer_bytes {
            limits.max_buffer_size = limits.max_buffer_size.min(max);
            limits.max_storage_buffer_binding_size =
                limits.max_storage_buffer_binding_size.min(max);
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lambert"),
            // GPU time of each dispatch, where the adapter can measure it.
            required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| Error::Gpu(format!("cannot open {}: {e}", describe(&info))))?;
        // wgpu's default handler panics; keep the error and report it instead.
        let errors = Arc::new(Mutex::new(None));
        let slot = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            slot.lock().unwrap().get_or_insert(e.to_string());
        }));
        // A lost device (a driver reset, a removed GPU, `destroy`) is an
        // error with the driver's reason at the next wait, not a hang.
        let slot = errors.clone();
        let name = describe(&info);
        device.set_device_lost_callback(move |reason, message| {
            slot.lock()
                .unwrap_or_else(|e| e.into_inner())
                .get_or_insert(format!(
                    "the device {name} was lost ({reason:?}): {message}"
                ));
        });
        Ok(Gpu {
            device,
            queue,
            info,
            limits,
            errors,
        })
    }

    pub fn describe(&self) -> String {
        describe(&self.info)
    }

    /// A software rasteriser such as lavapipe.
    pub fn is_software(&self) -> bool {
        is_software(&self.info)
    }

    fn check_errors(&self) -> Result<()> {
        match self.errors.lock().unwrap().take() {
            Some(e) => Err(Error::Gpu(e)),
            None => Ok(()),
        }
    }

    fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the device: {e}")))?;
        self.check_errors()
    }

    /// Maps the first `len` bytes of `buffer` (MAP_READ) once the queue's
    /// work is done, hands them to `read`, and unmaps; `what` names the
    /// data in errors.
    fn read_mapped<T>(
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

    /// Largest storage binding, bytes.
    fn binding_limit(&self) -> u64 {
        self.limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
    }

    /// A storage buffer of `bytes`, which may be at most `max_bytes` long.
    fn storage_buffer(&self, label: &str, bytes: &[u8], max_bytes: u64) -> Result<wgpu::Buffer> {
        if bytes.len() as u64 > max_bytes {
            return Err(Error::GpuLimit(format!(
                "the scene's {label} take {} bytes, {} more than the {max_bytes} bytes {} can \
                 bind for them (max_buffer_size {}, max_storage_buffer_binding_size {})",
                bytes.len(),
                bytes.len() as u64 - max_bytes,
                self.describe(),
                self.limits.max_buffer_size,
                self.limits.max_storage_buffer_binding_size
            )));
        }
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE,
            }))
    }

    /// An array that may exceed one storage binding: one buffer, bound as
    /// two ranges (see TRIANGLES_PER_BINDING in the shader).
    fn split_buffer(&self, label: &str, bytes: &[u8], stride: u64) -> Result<SplitBuffer> {
        let limit = self.binding_limit();
        let len = bytes.len() as u64;
        // Whole elements in the low range, and an offset every device
        // accepts (a multiple of 256 elements is a multiple of 256 bytes);
        // the high range holds the rest, up to one binding more.
        let per_binding = (limit / stride) / 256 * 256;
        let max_bytes = (per_binding * stride + limit).min(self.limits.max_buffer_size);
        let buffer = self.storage_buffer(label, bytes, max_bytes)?;
        if len <= limit {
            return Ok(SplitBuffer {
                buffer,
                per_binding: u32::MAX,
                low: len,
            });
        }
        Ok(SplitBuffer {
            buffer,
            per_binding: per_binding as u32,
            low: per_binding * stride,
        })
    }
}

impl Gpu {
    /// `bytes` (whole 16-byte texels) as an rgba32uint texture of
    /// `TEXELS_PER_ROW` texels a row, texel i at (i % row, i / row).
    /// `BvhStorage::for_scene` checks first that they fit.
    fn texel_texture(&self, label: &str, bytes: &[u8]) -> Result<wgpu::Texture> {
        const TEXEL: usize = 16;
        // No bytes: the placeholder of the storage not in use, one texel.
        let row = if bytes.is_empty() {
            1
        } else {
            TEXELS_PER_ROW as usize
        };
        let texels = (bytes.len() / TEXEL).max(1);
        let rows = texels.div_ceil(row);
        let max = self.limits.max_texture_dimension_2d as usize;
        if rows > max || row > max {
            return Err(Error::GpuLimit(format!(
                "{label}: {} bytes need a texture of {row} × {rows} texels; {} allows {max} × {max}",
                bytes.len(),
                self.describe()
            )));
        }
        let texture = self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: row as u32,
                height: rows as u32,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Uint,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        // Whole rows straight from `bytes`, then the last one padded.
        let write = |y: usize, data: &[u8], height: usize| {
            self.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: y as u32,
                        z: 0,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                data,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some((row * TEXEL) as u32),
                    rows_per_image: Some(height as u32),
                },
                wgpu::Extent3d {
                    width: row as u32,
                    height: height as u32,
                    depth_or_array_layers: 1,
                },
            )
        };
        let full = bytes.len() / (row * TEXEL);
        if full > 0 {
            write(0, &bytes[..full * row * TEXEL], full);
        }
        let rest = &bytes[full * row * TEXEL..];
        if !rest.is_empty() {
            let mut last = vec![0u8; row * TEXEL];
            last[..rest.len()].copy_from_slice(rest);
            write(full, &last, 1);
        }
        Ok(texture)
    }
}

/// A buffer bound as a low range and, when split, a high one.
struct SplitBuffer {
    buffer: wgpu::Buffer,
    /// Elements in the low binding (u32::MAX: all of them).
    per_binding: u32,
    /// Bytes in the low binding.
    low: u64,
}

impl SplitBuffer {
    fn low_binding(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: 0,
            size: wgpu::BufferSize::new(self.low),
        })
    }

    /// The rest; unsplit, the low range again (bound, never read).
    fn high_binding(&self) -> wgpu::BindingResource<'_> {
        if self.buffer.size() == self.low {
            return self.low_binding();
        }
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: self.low,
            size: wgpu::BufferSize::new(self.buffer.size() - self.low),
        })
    }
}

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
struct Timer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    period: f64,
}

impl Timer {
    fn new(gpu: &Gpu) -> Option<Timer> {
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

    fn writes(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }
    }

    fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..2, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.staging, 0, 16);
    }

    /// The pass's device time, once its submission has completed.
    fn read(&self, gpu: &Gpu) -> Result<Duration> {
        let ticks = gpu.read_mapped(&self.staging, 16, "timestamps", |bytes| {
            let t: &[u64] = bytemuck::cast_slice(bytes);
            t[1].saturating_sub(t[0])
        })?;
        Ok(Duration::from_nanos((ticks as f64 * self.period) as u64))
    }
}

/// Most lights a render traces the shadow rays of apart (the shader's
/// `shadow_blocked` has a bit of a pixel's word each; the queue holds a
/// ray for each light of each tile pixel, `SHADOW_QUERY_BYTES`).
pub const MAX_LIGHTS_APART: u32 = 8;

/// Bytes of the shader's `ShadowQuery` (a queued shadow ray; GPU-only,
/// checked against naga's layout in tests/shaders.rs).
pub const SHADOW_QUERY_BYTES: u64 = 48;

/// How a render traces its shadow rays: in the `render` megakernel, each
/// invocation after its own primary hit, or apart (`render_primary`
/// queues them, `render_shadows` traces the queue side by side,
/// `render_shade` shades; the same image, bit for bit). Apart measured
/// faster on lavapipe (docs/bvh.md): the default wherever shadows are
/// traced and there are at most `MAX_LIGHTS_APART` lights, for renders
/// at one sample per pixel (`shadows_apart`).
/// LAMBERT_SHADOW_DISPATCH=megakernel|apart chooses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowDispatch {
    Megakernel,
    Apart,
}

impl ShadowDispatch {
    /// Apart where it applies, unless LAMBERT_SHADOW_DISPATCH says
    /// otherwise.
    fn for_scene(scene: &Scene) -> Result<ShadowDispatch> {
        let applies =
            scene.shadows && (1..=MAX_LIGHTS_APART as usize).contains(&scene.lights.len());
        match std::env::var("LAMBERT_SHADOW_DISPATCH").as_deref() {
            Err(_) | Ok("apart") if applies => Ok(ShadowDispatch::Apart),
            Err(_) | Ok("apart") | Ok("megakernel") => Ok(ShadowDispatch::Megakernel),
            Ok(other) => Err(Error::Usage(format!(
                "LAMBERT_SHADOW_DISPATCH={other:?}: use \"megakernel\" or \"apart\""
            ))),
        }
    }
}

/// The three passes of a render with its shadow rays apart, and their
/// buffers.
struct SplitShadows {
    primary: wgpu::ComputePipeline,
    shadows: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    count: wgpu::Buffer,
}

/// A scene resident on the device: buffers and pipeline are built once;
/// a new camera only rewrites the uniform.
pub struct GpuRenderer {
    gpu: Gpu,
    module: wgpu::ShaderModule,
    constants: Vec<(&'static str, f64)>,
    scene_layout: wgpu::BindGroupLayout,
    image_layout: wgpu::BindGroupLayout,
    rays_layout: wgpu::BindGroupLayout,
    pixels_layout: wgpu::BindGroupLayout,
    pixel_list_pipeline: Option<wgpu::ComputePipeline>,
    /// Built on first use, as are the trace pipelines: a ray query never
    /// compiles the render entry point, nor a render the query's.
    render_pipeline: Option<wgpu::ComputePipeline>,
    /// The passes of a render with its shadow rays apart, built on first
    /// use where `shadow_dispatch` asks for them.
    split: Option<SplitShadows>,
    /// How a render traces its shadow rays (the tests set either).
    pub shadow_dispatch: ShadowDispatch,
    scene_group: wgpu::BindGroup,
    image_group: wgpu::BindGroup,
    /// `trace_rays` pipelines, built on first use: by any hit or closest
    /// hit, then by ray/triangle test.
    trace_pipelines: [[Option<wgpu::ComputePipeline>; 3]; 2],
    params: Params,
    params_buffer: wgpu::Buffer,
    color_texture: wgpu::Texture,
    prim_texture: wgpu::Texture,
    color_staging: wgpu::Buffer,
    prim_staging: wgpu::Buffer,
    /// The shader's flag that the driver cut its loops short, and its
    /// readback.
    loop_status: wgpu::Buffer,
    loop_status_staging: wgpu::Buffer,
    /// Samples one dispatch adds to a pixel: few enough that no invocation
    /// trips llvmpipe's loop limit (`loops_completed` in the shader);
    /// halved whenever one still does.
    samples_per_dispatch: u32,
    /// Bytes of the scene's buffers on the device.
    pub device_bytes: u64,
    /// The arrays split over two bindings ("triangles" also stands for
    /// their normals).
    pub split_arrays: Vec<&'static str>,
    /// Where the shader reads the BVH from.
    pub bvh_storage: BvhStorage,
    timer: Option<Timer>,
    /// Device time of the last `trace_rays` (its dispatches, summed), where
    /// timestamps work.
    trace_device_time: Option<Duration>,
    /// `run_list`'s input, output and readback buffers, by label.
    list_buffers: std::cell::RefCell<std::collections::HashMap<&'static str, wgpu::Buffer>>,
    pub upload_time: Duration,
    /// The resident scene's placement: `trace_rays` takes world rays.
    pub placement: crate::placement::Placement,
}

/// Bytes per row of a texture copy: wgpu requires a multiple of 256.
pub fn padded_bytes_per_row(width: u32, bytes_per_pixel: u32) -> u32 {
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    (width * bytes_per_pixel).div_ceil(align) * align
}

/// The uniform for `scene` seen from `camera`: the f32 reference's basis, so
/// both paths shoot the very same rays.
pub fn params_for(scene: &Scene, camera: &Camera) -> Params {
    let basis = CameraBasis::new(&scene.local_camera(camera));
    Params {
        eye: basis.eye.to_array(),
        width: basis.width,
        right: basis.right.to_array(),
        height: basis.height,
        up: basis.up.to_array(),
        tan_half_x: basis.tan_half_x,
        forward: basis.forward.to_array(),
        tan_half_y: basis.tan_half_y,
        background: scene.background,
        num_triangles: scene.triangles.len() as u32,
        ambient: scene.ambient,
        num_spheres: scene.spheres.len() as u32,
        tile_origin: [0, 0],
        num_lights: scene.lights.len() as u32,
        shadows: scene.shadows as u32,
        spp: scene.spp,
        seed: scene.seed,
        strata_x: crate::scene::strata_columns(scene.spp),
        sample_begin: 0,
        sample_end: scene.spp,
        canary_loops: 2,
        _pad0: 0,
        _pad1: 0,
    }
}

/// At least one element: wgpu rejects empty storage bindings. Borrows the
/// scene's own memory otherwise, so that upload makes no host copy.
fn non_empty<T: bytemuck::Pod + Default>(items: &[T]) -> Cow<'_, [u8]> {
    if items.is_empty() {
        Cow::Owned(bytemuck::bytes_of(&T::default()).to_vec())
    } else {
        Cow::Borrowed(bytemuck::cast_slice(items))
    }
}

enum BindingKind {
    Uniform,
    Storage,
    StorageWrite,
    Image(wgpu::TextureFormat),
    /// A read-only rgba32uint texture (`BvhStorage::Texels`).
    Texels,
}

fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    bindings: &[(u32, BindingKind)],
) -> wgpu::BindGroupLayout {
    let buffer = |ty| wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    let entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
        .iter()
        .map(|(binding, kind)| wgpu::BindGroupLayoutEntry {
            binding: *binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: match kind {
                BindingKind::Uniform => buffer(wgpu::BufferBindingType::Uniform),
                BindingKind::Storage => {
                    buffer(wgpu::BufferBindingType::Storage { read_only: true })
                }
                BindingKind::StorageWrite => {
                    buffer(wgpu::BufferBindingType::Storage { read_only: false })
                }
                BindingKind::Image(format) => wgpu::BindingType::StorageTexture {
                    access: wgpu::StorageTextureAccess::WriteOnly,
                    format: *format,
                    view_dimension: wgpu::TextureViewDimension::D2,
                },
                BindingKind::Texels => wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Uint,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
            },
            count: None,
        })
        .collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// A render tile's bind group: the colour and primitive textures at
/// bindings 0 and 1, and `buffers` at theirs.
fn tile_bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    [color, prim]: [&wgpu::Texture; 2],
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let (color, prim) = (
        color.create_view(&Default::default()),
        prim.create_view(&Default::default()),
    );
    let mut entries = vec![
        wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::TextureView(&color),
        },
        wgpu::BindGroupEntry {
            binding: 1,
            resource: wgpu::BindingResource::TextureView(&prim),
        },
    ];
    entries.extend(
        buffers
            .iter()
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: buffer.as_entire_binding(),
            }),
    );
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry_point: &str,
    layouts: &[&wgpu::BindGroupLayout],
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().copied().map(Some).collect();
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry_point),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry_point),
        layout: Some(&pipeline_layout),
        module,
        entry_point: Some(entry_point),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            zero_initialize_workgroup_memory: false,
        },
        cache: None,
    })
}

impl GpuRenderer {
    /// Uploads `scene` with a shader specialised to it.
    pub fn new(gpu: Gpu, scene: &Scene) -> Result<GpuRenderer> {
        let storage = BvhStorage::for_scene(&gpu, scene);
        GpuRenderer::build(gpu, scene, specialisation(scene), storage)
    }

    /// `new` with the BVH in the given storage rather than the adapter's
    /// (the tests check both on one adapter).
    pub fn with_bvh_storage(gpu: Gpu, scene: &Scene, storage: BvhStorage) -> Result<GpuRenderer> {
        GpuRenderer::build(gpu, scene, specialisation(scene), storage)
    }

    /// Uploads `scene` with the full shader: every feature compiled in, only
    /// the acceleration and the intersection test chosen. The benchmarks
    /// measure what specialisation saves against it.
    pub fn with_full_shader(gpu: Gpu, scene: &Scene) -> Result<GpuRenderer> {
        let constants = specialisation(scene)
            .into_iter()
            .filter(|(name, _)| matches!(*name, "USE_BVH" | "INTERSECT"))
            .collect();
        let storage = BvhStorage::for_scene(&gpu, scene);
        GpuRenderer::build(gpu, scene, constants, storage)
    }

    fn build(
        gpu: Gpu,
        scene: &Scene,
        constants: Vec<(&'static str, f64)>,
        storage: BvhStorage,
    ) -> Result<GpuRenderer> {
        let start = Instant::now();
        let device = &gpu.device;
        let params = params_for(scene, &scene.camera);
        let params_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        // A scene within the binding limits may still not fit the device's
        // memory, which wgpu reports as an out-of-memory error.
        let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let limit = gpu.binding_limit();
        let triangles =
            gpu.split_buffer("triangles", &non_empty::<Triangle>(&scene.triangles), 48)?;
        let normals =
            gpu.split_buffer("normals", &non_empty::<TriangleNormals>(&scene.normals), 48)?;
        let compressed = crate::cwbvh::compress(&scene.bvh);
        let texels = storage == BvhStorage::Texels;
        // The storage not used gets a placeholder, bound and never read.
        let (buffer_nodes, buffer_blocks): (&[CompressedNode], &[PrimBlock]) = if texels {
            (&[], &[])
        } else {
            (&compressed, &scene.bvh.blocks)
        };
        let (texel_nodes, texel_blocks): (&[u8], &[u8]) = if texels {
            (
                bytemuck::cast_slice(&compressed),
                bytemuck::cast_slice(&scene.bvh.blocks),
            )
        } else {
            (&[], &[])
        };
        let node_texture = gpu.texel_texture("BVH node texels", texel_nodes)?;
        let block_texture = gpu.texel_texture("BVH leaf block texels", texel_blocks)?;
        let nodes = gpu.split_buffer(
            "BVH nodes",
            &non_empty(buffer_nodes),
            std::mem::size_of::<CompressedNode>() as u64,
        )?;
        let spheres = gpu.storage_buffer("spheres", &non_empty::<Sphere>(&scene.spheres), limit)?;
        let materials = gpu.storage_buffer("materials", &non_empty(&scene.materials), limit)?;
        let lights = gpu.storage_buffer("lights", &non_empty(&scene.lights), limit)?;
        let blocks = gpu.split_buffer(
            "BVH leaf blocks",
            &non_empty(buffer_blocks),
            std::mem::size_of::<PrimBlock>() as u64,
        )?;
        drop(compressed);
        let device_bytes = [
            &triangles.buffer,
            &normals.buffer,
            &nodes.buffer,
            &spheres,
            &materials,
            &lights,
            &blocks.buffer,
        ]
        .iter()
        .map(|b| b.size())
        .sum::<u64>()
            + [&node_texture, &block_texture]
                .iter()
                .map(|t| 16 * t.width() as u64 * t.height() as u64)
                .sum::<u64>();
        if let Some(e) = pollster::block_on(memory.pop()) {
            return Err(Error::GpuLimit(format!(
                "the scene's {device_bytes} bytes of GPU data (triangles {}, BVH nodes {}, leaf \
                 blocks {}) do not fit in the memory of {}: {e}",
                triangles.buffer.size(),
                nodes.buffer.size(),
                blocks.buffer.size(),
                gpu.describe()
            )));
        }
        let split_arrays = [
            ("triangles", &triangles),
            ("BVH nodes", &nodes),
            ("BVH leaf blocks", &blocks),
        ]
        .iter()
        .filter(|(_, b)| b.per_binding != u32::MAX)
        .map(|(name, _)| *name)
        .collect();
        let mut constants = constants;
        constants.push(("TRIANGLES_PER_BINDING", triangles.per_binding as f64));
        constants.push(("NODES_PER_BINDING", nodes.per_binding as f64));
        constants.push(("BLOCKS_PER_BINDING", blocks.per_binding as f64));
        constants.push(("BVH_TEXELS", texels as u32 as f64));
        constants.push(("RENDER_WORKGROUP_X", RENDER_WORKGROUP[0] as f64));
        constants.push(("RENDER_WORKGROUP_Y", RENDER_WORKGROUP[1] as f64));
        let (stack_entries, spills) = crate::cwbvh::short_stack(
            scene.bvh.depth(),
            gpu.limits.max_compute_workgroup_storage_size,
        );
        constants.push(("STACK_ENTRIES", stack_entries as f64));
        constants.push(("STACK_SPILLS", spills as u32 as f64));

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
        let color_texture = texture("color", wgpu::TextureFormat::Rgba32Float);
        let prim_texture = texture("prim", wgpu::TextureFormat::R32Uint);
        let staging = |label, bytes_per_pixel| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (padded_bytes_per_row(TILE, bytes_per_pixel) * TILE) as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            })
        };
        let color_staging = staging("color readback", 16);
        let prim_staging = staging("prim readback", 4);
        let tile_sums = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tile sums"),
            size: (TILE * TILE * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let loop_status = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("loop status"),
            size: 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let loop_status_staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("loop status readback"),
            size: 4,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });

        let scene_layout = bind_group_layout(
            device,
            "scene",
            &[
                (0, BindingKind::Uniform),
                (1, BindingKind::Storage),
                (2, BindingKind::Storage),
                (3, BindingKind::Storage),
                (4, BindingKind::Storage),
                (5, BindingKind::Storage),
                (6, BindingKind::Storage),
                (7, BindingKind::Storage),
                (8, BindingKind::Storage),
                (9, BindingKind::Storage),
                (10, BindingKind::Storage),
                (11, BindingKind::Storage),
                (12, BindingKind::StorageWrite),
                (13, BindingKind::Texels),
                (14, BindingKind::Texels),
            ],
        );
        let image_layout = bind_group_layout(
            device,
            "image tile",
            &[
                (0, BindingKind::Image(wgpu::TextureFormat::Rgba32Float)),
                (1, BindingKind::Image(wgpu::TextureFormat::R32Uint)),
                (6, BindingKind::StorageWrite),
            ],
        );
        let rays_layout = bind_group_layout(
            device,
            "rays",
            &[(2, BindingKind::Storage), (3, BindingKind::StorageWrite)],
        );
        let pixels_layout = bind_group_layout(
            device,
            "pixel list",
            &[(4, BindingKind::Storage), (5, BindingKind::StorageWrite)],
        );
        let node_view = node_texture.create_view(&Default::default());
        let block_view = block_texture.create_view(&Default::default());
        let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        let entries = [
            entry(0, params_buffer.as_entire_binding()),
            entry(1, triangles.low_binding()),
            entry(2, normals.low_binding()),
            entry(3, spheres.as_entire_binding()),
            entry(4, materials.as_entire_binding()),
            entry(5, lights.as_entire_binding()),
            entry(6, nodes.low_binding()),
            entry(7, blocks.low_binding()),
            entry(8, triangles.high_binding()),
            entry(9, normals.high_binding()),
            entry(10, nodes.high_binding()),
            entry(11, blocks.high_binding()),
            entry(12, loop_status.as_entire_binding()),
            entry(13, wgpu::BindingResource::TextureView(&node_view)),
            entry(14, wgpu::BindingResource::TextureView(&block_view)),
        ];

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let scene_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &scene_layout,
            entries: &entries,
        });
        let image_group = tile_bind_group(
            device,
            "image tile",
            &image_layout,
            [&color_texture, &prim_texture],
            &[(6, &tile_sums)],
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("trace.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SHADER_SOURCE.into()),
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!("uploading the scene: {e}")));
        }
        gpu.wait()?;
        let timer = Timer::new(&gpu);
        let shadow_dispatch = ShadowDispatch::for_scene(scene)?;
        let samples_per_dispatch = if is_llvmpipe(&gpu.info) {
            LLVMPIPE_SAMPLES_PER_DISPATCH
        } else {
            u32::MAX
        };
        Ok(GpuRenderer {
            gpu,
            module,
            constants,
            scene_layout,
            image_layout,
            rays_layout,
            pixels_layout,
            render_pipeline: None,
            split: None,
            shadow_dispatch,
            pixel_list_pipeline: None,
            scene_group,
            image_group,
            trace_pipelines: Default::default(),
            params,
            params_buffer,
            color_texture,
            prim_texture,
            color_staging,
            prim_staging,
            loop_status,
            loop_status_staging,
            samples_per_dispatch,
            device_bytes,
            split_arrays,
            bvh_storage: storage,
            timer,
            trace_device_time: None,
            list_buffers: Default::default(),
            upload_time: start.elapsed(),
            placement: scene.placement(),
        })
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// Points the resident scene's camera elsewhere; uploads nothing else.
    pub fn set_camera(&mut self, scene: &Scene, camera: &Camera) {
        // The counts are the uploaded scene's: the host's copy may have
        // released its geometry (`Scene::release_geometry`).
        self.params = Params {
            num_triangles: self.params.num_triangles,
            num_spheres: self.params.num_spheres,
            ..params_for(scene, camera)
        };
    }

    /// Renders tile by tile, reading each back before the next.
    pub fn render(&mut self, progress: &Progress) -> Result<(Rendered, GpuTimings)> {
        self.render_rows(0..self.params.height, progress)
    }

    /// Renders rows `rows` of the image alone (a part of it), tile by tile.
    /// If the driver cut the shader's loops short anywhere (checked once,
    /// after the last tile), renders again with half as many samples per
    /// dispatch, down to one, then fails rather than return a wrong
    /// picture.
    pub fn render_rows(
        &mut self,
        rows: std::ops::Range<u32>,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        self.prepare_render()?;
        loop {
            let result = self.render_rows_once(&rows, progress)?;
            if !self.loops_were_cut()? {
                return Ok(result);
            }
            self.fewer_samples_per_dispatch()?;
        }
    }

    fn render_rows_once(
        &mut self,
        rows: &std::ops::Range<u32>,
        progress: &Progress,
    ) -> Result<(Rendered, GpuTimings)> {
        let width = self.params.width;
        let height = rows.len() as u32;
        let mut rgb = vec![[0.0f32; 3]; width as usize * height as usize];
        let mut prims = vec![0u32; width as usize * height as usize];
        let mut variance = vec![0.0f32; width as usize * height as usize];
        let mut timings = GpuTimings::default();
        let side = self.tile_side();
        for tile_y in rows.clone().step_by(side as usize) {
            for tile_x in (0..width).step_by(side as usize) {
                let tile_width = side.min(width - tile_x);
                let tile_height = side.min(rows.end - tile_y);
                let start = Instant::now();
                let device_time = self.render_tile(tile_x, tile_y, tile_width, tile_height)?;
                timings.render += start.elapsed();
                if let Some(t) = device_time {
                    *timings.device.get_or_insert(Duration::ZERO) += t;
                }

                let start = Instant::now();
                self.read_tile(tile_width, tile_height, |row, colors, ids| {
                    let offset = ((tile_y - rows.start + row) * width + tile_x) as usize;
                    let n = tile_width as usize;
                    for (i, src) in colors.chunks(4).enumerate() {
                        rgb[offset + i] = [src[0], src[1], src[2]];
                        variance[offset + i] = src[3];
                    }
                    prims[offset..offset + n].copy_from_slice(ids);
                })?;
                timings.readback += start.elapsed();
                progress.inc(1);
            }
        }
        Ok((
            Rendered {
                image: Image { width, height, rgb },
                prims,
                variance,
            },
            timings,
        ))
    }

    /// Side of the tiles `render` dispatches: TILE at 1 sample per pixel
    /// per dispatch, smaller as they grow, so that a dispatch traces about
    /// as many camera rays (TILE²) at any spp.
    pub fn tile_side(&self) -> u32 {
        let samples = self.params.spp.min(self.samples_per_dispatch());
        let side = TILE / samples.isqrt().max(1);
        let step = RENDER_WORKGROUP[0].max(RENDER_WORKGROUP[1]);
        side.next_multiple_of(step).clamp(step, TILE)
    }

    /// Renders one tile, its samples over as many dispatches as
    /// `samples_per_dispatch` asks. Returns the device time where
    /// timestamps work.
    fn render_tile(&mut self, x: u32, y: u32, width: u32, height: u32) -> Result<Option<Duration>> {
        let spp = self.params.spp;
        let step = self.samples_per_dispatch().min(spp);
        let mut device_time = None;
        for begin in (0..spp).step_by(step as usize) {
            self.params.sample_begin = begin;
            self.params.sample_end = (begin + step).min(spp);
            if let Some(t) = self.dispatch_tile(x, y, width, height)? {
                *device_time.get_or_insert(Duration::ZERO) += t;
            }
        }
        Ok(device_time)
    }

    /// Samples a render dispatch adds to a pixel: one with the shadow rays
    /// apart (each sample's passes in turn).
    fn samples_per_dispatch(&self) -> u32 {
        if self.shadows_apart() {
            1
        } else {
            self.samples_per_dispatch
        }
    }

    /// Whether this render traces its shadow rays apart: as
    /// `shadow_dispatch` asks, at one sample per pixel. With more, each
    /// sample would be a dispatch of its own, waited on: the sampling
    /// tests' high-spp renders took 152 s rather than 19.
    pub fn shadows_apart(&self) -> bool {
        self.shadow_dispatch == ShadowDispatch::Apart && self.params.spp == 1
    }

    /// Halves `samples_per_dispatch` after the driver cut loops short.
    fn fewer_samples_per_dispatch(&mut self) -> Result<()> {
        let step = self.samples_per_dispatch().min(self.params.spp);
        if step <= 1 {
            return Err(Error::Gpu(format!(
                "{} cut the shader's loops short even at one sample per pixel per dispatch \
                 (Mesa's llvmpipe ends loops after 65535 iterations an invocation group): \
                 this scene is too complex for this adapter; use --device cpu",
                self.gpu.describe()
            )));
        }
        self.samples_per_dispatch = step / 2;
        Ok(())
    }

    /// Whether any invocation since the last call found its loops cut short
    /// (the shader's `report_cut_loops`); clears the flag.
    fn loops_were_cut(&self) -> Result<bool> {
        let gpu = &self.gpu;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.loop_status, 0, &self.loop_status_staging, 0, 4);
        encoder.clear_buffer(&self.loop_status, 0, None);
        gpu.queue.submit([encoder.finish()]);
        gpu.read_mapped(&self.loop_status_staging, 4, "loop status", |bytes| {
            bytemuck::cast_slice::<u8, u32>(bytes)[0] != 0
        })
    }

    /// Number of tiles `render` dispatches for the current camera.
    pub fn tile_count(&self) -> u64 {
        let side = self.tile_side();
        self.params.width.div_ceil(side) as u64 * self.params.height.div_ceil(side) as u64
    }

    /// Renders one tile; returns its device time where timestamps work.
    fn dispatch_tile(
        &mut self,
        x: u32,
        y: u32,
        width: u32,
        height: u32,
    ) -> Result<Option<Duration>> {
        self.params.tile_origin = [x, y];
        let gpu = &self.gpu;
        gpu.queue
            .write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let [wx, wy] = RENDER_WORKGROUP;
        if let (true, Some(split)) = (self.shadows_apart(), &self.split) {
            encoder.clear_buffer(&split.count, 0, None);
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render tile, shadows apart"),
                timestamp_writes: self.timer.as_ref().map(Timer::writes),
            });
            pass.set_bind_group(0, &self.scene_group, &[]);
            pass.set_bind_group(1, &split.group, &[]);
            pass.set_pipeline(&split.primary);
            pass.dispatch_workgroups(width.div_ceil(wx), height.div_ceil(wy), 1);
            pass.set_pipeline(&split.shadows);
            pass.dispatch_workgroups((width * height).div_ceil(WORKGROUP_INVOCATIONS), 1, 1);
            pass.set_pipeline(&split.shade);
            pass.dispatch_workgroups(width.div_ceil(wx), height.div_ceil(wy), 1);
        } else {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render tile"),
                timestamp_writes: self.timer.as_ref().map(Timer::writes),
            });
            pass.set_pipeline(self.render_pipeline.as_ref().expect("prepared"));
            pass.set_bind_group(0, &self.scene_group, &[]);
            pass.set_bind_group(1, &self.image_group, &[]);
            pass.dispatch_workgroups(width.div_ceil(wx), height.div_ceil(wy), 1);
        }
        if let Some(timer) = &self.timer {
            timer.resolve(&mut encoder);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait()?;
        self.timer.as_ref().map(|t| t.read(gpu)).transpose()
    }

    /// Copies the tile's textures to the staging buffers (rows padded as
    /// wgpu requires), maps them and hands each row to `row_sink`.
    fn read_tile(
        &self,
        width: u32,
        height: u32,
        mut row_sink: impl FnMut(u32, &[f32], &[u32]),
    ) -> Result<()> {
        let gpu = &self.gpu;
        let color_row = padded_bytes_per_row(TILE, 16);
        let prim_row = padded_bytes_per_row(TILE, 4);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let extent = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        for (texture, buffer, row_bytes) in [
            (&self.color_texture, &self.color_staging, color_row),
            (&self.prim_texture, &self.prim_staging, prim_row),
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

    fn build_pipeline(
        &self,
        entry_point: &str,
        output_layout: &wgpu::BindGroupLayout,
        constants: &[(&str, f64)],
    ) -> Result<wgpu::ComputePipeline> {
        let scope = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = compute_pipeline(
            &self.gpu.device,
            &self.module,
            entry_point,
            &[&self.scene_layout, output_layout],
            constants,
        );
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!(
                "building the {entry_point} pipeline: {e}"
            )));
        }
        self.gpu.wait()?;
        Ok(pipeline)
    }

    /// Builds the render pipeline if not built yet (so that timing a render
    /// can leave the compile out).
    pub fn prepare_render(&mut self) -> Result<()> {
        if self.shadows_apart() {
            if self.split.is_none() {
                self.split = Some(self.build_split()?);
            }
        } else if self.render_pipeline.is_none() {
            let pipeline = self.build_pipeline("render", &self.image_layout, &self.constants)?;
            self.render_pipeline = Some(pipeline);
        }
        Ok(())
    }

    /// The passes and buffers of a render with its shadow rays apart.
    fn build_split(&self) -> Result<SplitShadows> {
        let device = &self.gpu.device;
        let layout = bind_group_layout(
            device,
            "image tile, shadows apart",
            &[
                (0, BindingKind::Image(wgpu::TextureFormat::Rgba32Float)),
                (1, BindingKind::Image(wgpu::TextureFormat::R32Uint)),
                (7, BindingKind::StorageWrite),
                (8, BindingKind::StorageWrite),
                (9, BindingKind::StorageWrite),
                (10, BindingKind::StorageWrite),
            ],
        );
        let pixels = (TILE * TILE) as u64;
        let lights = (self.params.num_lights as u64).max(1);
        let buffer = |label, size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let hits = buffer("primary hits", pixels * std::mem::size_of::<Hit>() as u64);
        let queue = buffer("shadow queue", pixels * lights * SHADOW_QUERY_BYTES);
        let count = buffer("shadow count", 4);
        let blocked = buffer("shadow blocked", pixels * 4);
        let group = tile_bind_group(
            device,
            "image tile, shadows apart",
            &layout,
            [&self.color_texture, &self.prim_texture],
            &[(7, &hits), (8, &queue), (9, &count), (10, &blocked)],
        );
        let mut from_queue = self.constants.clone();
        from_queue.push(("SHADOWS_FROM_QUEUE", 1.0));
        Ok(SplitShadows {
            primary: self.build_pipeline("render_primary", &layout, &self.constants)?,
            shadows: self.build_pipeline("render_shadows", &layout, &self.constants)?,
            shade: self.build_pipeline("render_shade", &layout, &from_queue)?,
            group,
            count,
        })
    }

    /// Builds the `trace_rays` pipeline for closest or any hit with the
    /// given ray/triangle test, if not built yet.
    pub fn prepare_trace(&mut self, any_hit: bool, intersect: Intersect) -> Result<()> {
        let (a, i) = (any_hit as usize, intersect.shader_value() as usize);
        if self.trace_pipelines[a][i].is_none() {
            let mut constants: Vec<(&str, f64)> = self
                .constants
                .iter()
                .filter(|(name, _)| *name != "INTERSECT")
                .copied()
                .collect();
            constants.push(("INTERSECT", intersect.shader_value() as f64));
            constants.push(("ANY_HIT", if any_hit { 1.0 } else { 0.0 }));
            let pipeline = self.build_pipeline("trace_rays", &self.rays_layout, &constants)?;
            self.trace_pipelines[a][i] = Some(pipeline);
        }
        Ok(())
    }

    /// Traces `rays` (world coordinates, as in a ray file) against the
    /// resident scene with the ray/triangle test `intersect`: closest hits,
    /// or with `any_hit` the first hit each ray finds. Misses come back as
    /// t = +inf, prim = NO_HIT.
    pub fn trace_rays(
        &mut self,
        rays: &[Ray],
        any_hit: bool,
        intersect: Intersect,
    ) -> Result<Vec<Hit>> {
        let local = self.placement.localize(rays);
        let mut hits = self.trace_local_rays(&local.rays, any_hit, intersect)?;
        local.to_world(&mut hits);
        Ok(hits)
    }

    /// `trace_rays` for rays already in the scene's local frame
    /// (`Placement::local_ray`), hits in that frame.
    pub fn trace_local_rays(
        &mut self,
        rays: &[Ray],
        any_hit: bool,
        intersect: Intersect,
    ) -> Result<Vec<Hit>> {
        self.prepare_trace(any_hit, intersect)?;
        let pipeline = self.trace_pipelines[any_hit as usize][intersect.shader_value() as usize]
            .as_ref()
            .expect("prepared");
        let (hits, device): (Vec<Hit>, _) =
            self.run_list(pipeline, &self.rays_layout, 2, rays, 1 << 20, None, true)?;
        self.trace_device_time = device;
        if self.loops_were_cut()? {
            return Err(Error::Gpu(format!(
                "{} cut the shader's loops short on a ray of this query (Mesa's llvmpipe \
                 ends loops after 65535 iterations an invocation group): use --device cpu",
                self.gpu.describe()
            )));
        }
        Ok(hits
            .into_iter()
            .map(|h| if h.prim == NO_HIT { Hit::MISS } else { h })
            .collect())
    }

    /// Renders the listed pixels with the current sampling (adaptive
    /// sampling's later passes): mean colour and variance of the mean.
    pub fn render_pixel_list(&mut self, pixels: &[[u32; 2]]) -> Result<Vec<[f32; 4]>> {
        if self.pixel_list_pipeline.is_none() {
            let pipeline =
                self.build_pipeline("render_pixel_list", &self.pixels_layout, &self.constants)?;
            self.pixel_list_pipeline = Some(pipeline);
        }
        loop {
            let pipeline = self.pixel_list_pipeline.as_ref().expect("built");
            let step = self.samples_per_dispatch.min(self.params.spp);
            // As many samples per dispatch as a full tile at 1 spp.
            let batch =
                ((TILE * TILE) / step).max(RENDER_WORKGROUP[0] * RENDER_WORKGROUP[1]) as usize;
            let (results, _) = self.run_list(
                pipeline,
                &self.pixels_layout,
                4,
                pixels,
                batch,
                Some(step),
                false,
            )?;
            if !self.loops_were_cut()? {
                return Ok(results);
            }
            self.fewer_samples_per_dispatch()?;
        }
    }

    /// Runs a one-invocation-per-item entry point over `inputs` (bound at
    /// `binding`, outputs at `binding + 1`), `batch` items per dispatch so
    /// that no dispatch runs long; with `step`, the scene's samples that
    /// many at a time, a dispatch each. With `timed`, also returns the
    /// dispatches' device time, summed, where timestamps work (reading it
    /// back waits on each dispatch's queries).
    fn run_list<I: bytemuck::Pod, O: bytemuck::Pod>(
        &self,
        pipeline: &wgpu::ComputePipeline,
        layout: &wgpu::BindGroupLayout,
        binding: u32,
        inputs: &[I],
        batch: usize,
        step: Option<u32>,
        timed: bool,
    ) -> Result<(Vec<O>, Option<Duration>)> {
        const LIST_WORKGROUP: usize = WORKGROUP_INVOCATIONS as usize;
        let timer = self.timer.as_ref().filter(|_| timed);
        let mut device = timer.map(|_| Duration::ZERO);
        let gpu = &self.gpu;
        let batch = batch.min(inputs.len()).max(1);
        use wgpu::BufferUsages as U;
        let out_bytes = (batch * size_of::<O>()) as u64;
        let mut cache = self.list_buffers.borrow_mut();
        let [in_buffer, out_buffer, staging] = [
            (
                "list input",
                (batch * size_of::<I>()) as u64,
                U::STORAGE | U::COPY_DST,
            ),
            ("list output", out_bytes, U::STORAGE | U::COPY_SRC),
            ("list readback", out_bytes, U::COPY_DST | U::MAP_READ),
        ]
        .map(|(label, size, usage)| {
            // Kept between calls and grown as needed: creating them anew
            // cost lavapipe a sixth of a million-ray query.
            let kept = cache.get(label).filter(|b| b.size() >= size).cloned();
            kept.unwrap_or_else(|| {
                let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                });
                cache.insert(label, buffer.clone());
                buffer
            })
        });
        drop(cache);
        let mut outputs = Vec::with_capacity(inputs.len());
        for chunk in inputs.chunks(batch) {
            let in_len = std::mem::size_of_val(chunk) as u64;
            let out_len = (chunk.len() * size_of::<O>()) as u64;
            gpu.queue
                .write_buffer(&in_buffer, 0, bytemuck::cast_slice(chunk));
            // Bound to the batch's length: the shader stops at arrayLength.
            let range = |buffer, size| {
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(size),
                })
            };
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("list"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding,
                        resource: range(&in_buffer, in_len),
                    },
                    wgpu::BindGroupEntry {
                        binding: binding + 1,
                        resource: range(&out_buffer, out_len),
                    },
                ],
            });
            let spp = self.params.spp;
            let step = step.unwrap_or(spp);
            for begin in (0..spp).step_by(step as usize) {
                let params = Params {
                    sample_begin: begin,
                    sample_end: (begin + step).min(spp),
                    ..self.params
                };
                gpu.queue
                    .write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&params));
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("list"),
                        timestamp_writes: timer.map(Timer::writes),
                    });
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, &self.scene_group, &[]);
                    pass.set_bind_group(1, &group, &[]);
                    pass.dispatch_workgroups(chunk.len().div_ceil(LIST_WORKGROUP) as u32, 1, 1);
                }
                if let Some(timer) = timer {
                    timer.resolve(&mut encoder);
                }
                gpu.queue.submit([encoder.finish()]);
                gpu.wait()?;
                if let (Some(timer), Some(total)) = (timer, &mut device) {
                    *total += timer.read(gpu)?;
                }
            }
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&out_buffer, 0, &staging, 0, out_len);
            gpu.queue.submit([encoder.finish()]);
            gpu.read_mapped(&staging, out_len, "results", |bytes| {
                outputs.extend_from_slice(bytemuck::cast_slice::<u8, O>(bytes))
            })?;
        }
        Ok((outputs, device))
    }

    /// Device time of the last `trace_rays`, from timestamp queries (None
    /// where the adapter has none).
    pub fn trace_device_time(&self) -> Option<Duration> {
        self.trace_device_time
    }
}

/// Pipeline-overridable constants that strip what `scene` does not use.
pub fn specialisation(scene: &Scene) -> Vec<(&'static str, f64)> {
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    let has_light = |kind| scene.lights.iter().any(|l| l.kind == kind);
    vec![
        ("HAS_TRIANGLES", flag(!scene.triangles.is_empty())),
        ("HAS_SPHERES", flag(!scene.spheres.is_empty())),
        (
            "HAS_SHADOWS",
            flag(scene.shadows && !scene.lights.is_empty()),
        ),
        ("HAS_POINT_LIGHTS", flag(has_light(LIGHT_POINT))),
        ("HAS_DIRECTIONAL_LIGHTS", flag(has_light(LIGHT_DIRECTIONAL))),
        ("USE_BVH", flag(scene.accel == Accel::Bvh)),
        ("INTERSECT", scene.intersect.shader_value() as f64),
    ]
}
