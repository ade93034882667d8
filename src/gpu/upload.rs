//! The scene's arrays on the device: storage buffers (split over two
//! bindings when large) and the BVH's texel textures.

use wgpu::util::DeviceExt;

use crate::error::{Error, Result};
use crate::layout::{
    CompressedNode, PrimBlock, Sphere, Triangle, TriangleAttributes, TriangleNormals,
    TriangleTangents,
};
use crate::scene::Scene;

use super::adapter::is_llvmpipe;
use super::device::{Gpu, non_empty};
use super::lighting::LightingBuffers;

/// Where the shader reads the BVH's nodes and leaf blocks from
/// (`BVH_TEXELS` in shaders/layout.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhStorage {
    /// Storage buffers, split over two bindings when large: what hardware
    /// GPUs get.
    Buffers,
    /// rgba32uint read-only storage textures: what llvmpipe gets. It
    /// fetches a texel for its 8 SIMD lanes with vector instructions, where
    /// a storage-buffer load whose address differs between lanes is a loop
    /// over them, a branch per word; and a storage texture, unlike a sampled
    /// one, has no mip level to look up for each lane (docs/bvh.md).
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
        let triangles = words(std::mem::size_of_val(scene.triangles.as_slice()));
        if is_llvmpipe(&gpu.info) && fits(nodes) && fits(blocks) && fits(triangles) {
            BvhStorage::Texels
        } else {
            BvhStorage::Buffers
        }
    }
}

/// Texels in a row of a BVH texture (`TEXEL_ROW_BITS` in shaders/layout.wgsl): a
/// power of two, so that the shader splits a texel index into (x, y) with a
/// mask and a shift.
pub const TEXELS_PER_ROW: u32 = 4096;

/// The scene's arrays on the device, as the scene bind group binds them.
pub(super) struct SceneBuffers {
    pub triangles: SplitBuffer,
    pub normals: SplitBuffer,
    pub attributes: SplitBuffer,
    pub nodes: SplitBuffer,
    pub blocks: SplitBuffer,
    pub spheres: wgpu::Buffer,
    pub materials: wgpu::Buffer,
    pub lights: wgpu::Buffer,
    pub node_texture: wgpu::Texture,
    pub block_texture: wgpu::Texture,
    /// The triangles, with `BvhStorage::Texels` (3 texels each).
    pub triangle_texture: wgpu::Texture,
    /// `texture::TextureStore::words`.
    pub textures: wgpu::Buffer,
    /// `Scene::tangents` (a placeholder where no material has a normal
    /// texture); one binding, as it is kept only for normal-mapped scenes.
    pub tangents: wgpu::Buffer,
    /// The path integrator's lights (bindings 20 to 23).
    pub lighting: LightingBuffers,
    /// Bytes of all of them.
    pub device_bytes: u64,
}

impl SceneBuffers {
    /// Uploads `scene`'s arrays, its BVH in `storage` (the other storage
    /// gets a placeholder, bound and never read).
    pub async fn upload(gpu: &Gpu, scene: &Scene, storage: BvhStorage) -> Result<SceneBuffers> {
        // A scene within the binding limits may still not fit the device's
        // memory, which wgpu reports as an out-of-memory error.
        let memory = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let limit = gpu.binding_limit();
        let texels = storage == BvhStorage::Texels;
        // In one place only: texels or buffer.
        let (buffer_triangles, texel_triangles): (&[Triangle], &[u8]) = if texels {
            (&[], bytemuck::cast_slice(&scene.triangles))
        } else {
            (&scene.triangles, &[])
        };
        let triangles = gpu.split_buffer("triangles", &non_empty(buffer_triangles), 48)?;
        let triangle_texture = gpu.texel_texture("triangle texels", texel_triangles)?;
        let normals =
            gpu.split_buffer("normals", &non_empty::<TriangleNormals>(&scene.normals), 48)?;
        let attributes = gpu.split_buffer(
            "triangle attributes",
            &non_empty::<TriangleAttributes>(&scene.attributes),
            size_of::<TriangleAttributes>() as u64,
        )?;
        let compressed = crate::cwbvh::compress(&scene.bvh);
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
        let textures = gpu.storage_buffer(
            "textures",
            bytemuck::cast_slice(scene.textures.words()),
            limit,
        )?;
        let tangents = gpu.storage_buffer(
            "triangle tangents",
            &non_empty::<TriangleTangents>(&scene.tangents),
            limit,
        )?;
        let blocks = gpu.split_buffer(
            "BVH leaf blocks",
            &non_empty(buffer_blocks),
            std::mem::size_of::<PrimBlock>() as u64,
        )?;
        drop(compressed);
        let lighting = LightingBuffers::upload(gpu, scene)?;
        let device_bytes = lighting.device_bytes()
            + [
                &triangles.buffer,
                &normals.buffer,
                &attributes.buffer,
                &nodes.buffer,
                &spheres,
                &materials,
                &lights,
                &textures,
                &tangents,
                &blocks.buffer,
            ]
            .iter()
            .map(|b| b.size())
            .sum::<u64>()
            + [&node_texture, &block_texture, &triangle_texture]
                .iter()
                .map(|t| 16 * t.width() as u64 * t.height() as u64)
                .sum::<u64>();
        if let Some(e) = memory.pop().await {
            return Err(Error::GpuLimit(format!(
                "the scene's {device_bytes} bytes of GPU data (triangles {}, BVH nodes {}, leaf \
                 blocks {}) do not fit in the memory of {}: {e}",
                triangles.buffer.size(),
                nodes.buffer.size(),
                blocks.buffer.size(),
                gpu.describe()
            )));
        }
        Ok(SceneBuffers {
            triangles,
            normals,
            attributes,
            nodes,
            blocks,
            spheres,
            materials,
            lights,
            node_texture,
            block_texture,
            triangle_texture,
            textures,
            tangents,
            lighting,
            device_bytes,
        })
    }

    /// The arrays split over two bindings.
    pub fn split_arrays(&self) -> Vec<&'static str> {
        [
            ("triangles", &self.triangles),
            ("triangle normals", &self.normals),
            ("triangle attributes", &self.attributes),
            ("BVH nodes", &self.nodes),
            ("BVH leaf blocks", &self.blocks),
        ]
        .iter()
        .filter(|(_, b)| b.per_binding != u32::MAX)
        .map(|(name, _)| *name)
        .collect()
    }
}

/// A buffer bound as a low range and, when split, a high one.
pub(super) struct SplitBuffer {
    pub buffer: wgpu::Buffer,
    /// Elements in the low binding (u32::MAX: all of them).
    pub per_binding: u32,
    /// Bytes in the low binding.
    low: u64,
}

impl SplitBuffer {
    pub fn low_binding(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: 0,
            size: wgpu::BufferSize::new(self.low),
        })
    }

    /// The rest; unsplit, the low range again (bound, never read).
    pub fn high_binding(&self) -> wgpu::BindingResource<'_> {
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

impl Gpu {
    /// A storage buffer of `bytes`, which may be at most `max_bytes` long.
    pub(super) fn storage_buffer(
        &self,
        label: &str,
        bytes: &[u8],
        max_bytes: u64,
    ) -> Result<wgpu::Buffer> {
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

    /// `bytes` (whole 16-byte texels) as an rgba32uint storage texture of
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
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST,
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
