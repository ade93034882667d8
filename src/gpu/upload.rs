//! The scene's arrays on the device: one storage buffer of words (split
//! over two bindings when large) and the BVH's texel textures.

use wgpu::util::DeviceExt;

use crate::error::{Error, Result};
use crate::layout::{CompressedNode, SceneArrays};
use crate::scene::Scene;

use super::adapter::is_llvmpipe;
use super::device::Gpu;

/// Where the shader reads the BVH's nodes and leaf blocks from
/// (`BVH_TEXELS` in shaders/layout.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhStorage {
    /// The scene's words (a storage buffer, split over two bindings when
    /// large): what hardware GPUs get.
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
    /// Every read-only array, at the words `arrays` gives.
    pub words: SceneWords,
    /// `arrays` as the uniform the shader reads it from.
    pub arrays: wgpu::Buffer,
    pub node_texture: wgpu::Texture,
    pub block_texture: wgpu::Texture,
    /// The triangles, with `BvhStorage::Texels` (3 texels each).
    pub triangle_texture: wgpu::Texture,
    /// The path integrator's lighting uniform (binding 23).
    pub lighting: wgpu::Buffer,
    /// Bytes of all of them.
    pub device_bytes: u64,
}

/// Bytes of a word of `scene_words`.
const WORD: u64 = 16;

impl SceneBuffers {
    /// Uploads `scene`'s arrays, its BVH in `storage` (the triangles too:
    /// each either in the words or in texels, never both).
    pub async fn upload(gpu: &Gpu, scene: &Scene, storage: BvhStorage) -> Result<SceneBuffers> {
        // A scene within the binding limits may still not fit the device's
        // memory, which wgpu reports as an out-of-memory error.
        let memory = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let texels = storage == BvhStorage::Texels;
        let compressed = crate::cwbvh::compress(&scene.bvh);
        // Each in one place only: [texels, words].
        let place = |bytes: &[u8]| -> [usize; 2] {
            if texels {
                [bytes.len(), 0]
            } else {
                [0, bytes.len()]
            }
        };
        let triangles: &[u8] = bytemuck::cast_slice(&scene.triangles);
        let nodes: &[u8] = bytemuck::cast_slice(&compressed);
        let blocks: &[u8] = bytemuck::cast_slice(&scene.bvh.blocks);
        let [in_texels, in_words] = place(triangles);
        let triangle_texture = gpu.texel_texture("triangle texels", &triangles[..in_texels])?;
        let triangle_words = &triangles[..in_words];
        let [in_texels, in_words] = place(nodes);
        let node_texture = gpu.texel_texture("BVH node texels", &nodes[..in_texels])?;
        let node_words = &nodes[..in_words];
        let [in_texels, in_words] = place(blocks);
        let block_texture = gpu.texel_texture("BVH leaf block texels", &blocks[..in_texels])?;
        let block_words = &blocks[..in_words];
        let table = scene.emitters();
        let map = scene.environment().and_then(|e| e.map.as_ref());
        let (pixels, cdf): (&[[f32; 4]], &[f32]) = map.map_or((&[], &[]), |m| (&m.pixels, &m.cdf));
        let mut arrays = SceneArrays::default();
        let words = gpu.scene_words(&mut [
            ("triangles", triangle_words, &mut arrays.triangles),
            (
                "triangle normals",
                bytemuck::cast_slice(&scene.normals),
                &mut arrays.normals,
            ),
            (
                "triangle attributes",
                bytemuck::cast_slice(&scene.attributes),
                &mut arrays.attributes,
            ),
            (
                "triangle tangents",
                bytemuck::cast_slice(&scene.tangents),
                &mut arrays.tangents,
            ),
            ("BVH nodes", node_words, &mut arrays.nodes),
            ("BVH leaf blocks", block_words, &mut arrays.blocks),
            (
                "spheres",
                bytemuck::cast_slice(&scene.spheres),
                &mut arrays.spheres,
            ),
            (
                "materials",
                bytemuck::cast_slice(&scene.materials),
                &mut arrays.materials,
            ),
            (
                "lights",
                bytemuck::cast_slice(&scene.lights),
                &mut arrays.lights,
            ),
            (
                "textures",
                bytemuck::cast_slice(scene.textures.words()),
                &mut arrays.textures,
            ),
            (
                "emitters",
                bytemuck::cast_slice(&table.entries),
                &mut arrays.emitters,
            ),
            (
                "environment",
                bytemuck::cast_slice(pixels),
                &mut arrays.environment,
            ),
            (
                "environment CDF",
                bytemuck::cast_slice(cdf),
                &mut arrays.environment_cdf,
            ),
        ])?;
        drop(compressed);
        let uniform = |label, contents: &[u8]| {
            gpu.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage: wgpu::BufferUsages::UNIFORM,
                })
        };
        let arrays_buffer = uniform("scene arrays", bytemuck::bytes_of(&arrays));
        let lighting = uniform("lighting", bytemuck::bytes_of(&table.uniform));
        let device_bytes = [&words.buffer, &arrays_buffer, &lighting]
            .iter()
            .map(|b| b.size())
            .sum::<u64>()
            + [&node_texture, &block_texture, &triangle_texture]
                .iter()
                .map(|t| 16 * t.width() as u64 * t.height() as u64)
                .sum::<u64>();
        if let Some(e) = memory.pop().await {
            return Err(Error::GpuLimit(format!(
                "the scene's {device_bytes} bytes of GPU data ({}) do not fit in the memory of {}: {e}",
                words.sizes(),
                gpu.describe()
            )));
        }
        Ok(SceneBuffers {
            words,
            arrays: arrays_buffer,
            node_texture,
            block_texture,
            triangle_texture,
            lighting,
            device_bytes,
        })
    }

    /// The arrays that lie, whole or in part, in the high binding.
    pub fn split_arrays(&self) -> Vec<&'static str> {
        self.words.split_arrays.clone()
    }
}

/// The scene's read-only arrays in one buffer of 16-byte words, bound as a
/// low range and, when it passes one binding, a high one
/// (`WORDS_PER_BINDING` in the shader).
pub(super) struct SceneWords {
    pub buffer: wgpu::Buffer,
    /// Words in the low binding (u32::MAX: all of them).
    pub per_binding: u32,
    /// Bytes in the low binding.
    low: u64,
    /// Each array's name and bytes, for messages.
    arrays: Vec<(&'static str, u64)>,
    /// The arrays that lie in the high binding, whole or in part.
    split_arrays: Vec<&'static str>,
}

impl SceneWords {
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

    /// The arrays' sizes, for messages: "triangles 4800 bytes, …".
    fn sizes(&self) -> String {
        SceneWords::describe(&self.arrays)
    }

    fn describe(arrays: &[(&'static str, u64)]) -> String {
        arrays
            .iter()
            .filter(|(_, bytes)| *bytes > 0)
            .map(|(name, bytes)| format!("{name} {bytes} bytes"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl Gpu {
    /// `arrays` (name, bytes, where to write its first word) in one buffer
    /// of 16-byte words, each array from a whole word; bound as two ranges
    /// where they pass one binding (see WORDS_PER_BINDING in the shader).
    fn scene_words(&self, arrays: &mut [(&'static str, &[u8], &mut u32)]) -> Result<SceneWords> {
        let limit = self.binding_limit();
        let mut words = 0u64;
        for (_, bytes, first) in arrays.iter_mut() {
            **first = u32::try_from(words).unwrap_or(u32::MAX);
            words += (bytes.len() as u64).div_ceil(WORD);
        }
        // One word at the least: a binding is never empty.
        let len = words.max(1) * WORD;
        // The low range a multiple of 256 bytes, an offset every device
        // accepts; the high range holds the rest, up to one binding more.
        let low = if len <= limit { len } else { limit / 256 * 256 };
        let max_bytes = (low + limit).min(self.limits.max_buffer_size);
        let sizes: Vec<(&'static str, u64)> = arrays
            .iter()
            .map(|(name, bytes, _)| (*name, bytes.len() as u64))
            .collect();
        if len > max_bytes || words > u32::MAX as u64 {
            let named = SceneWords::describe(&sizes);
            return Err(Error::GpuLimit(format!(
                "the scene's arrays take {len} bytes ({named}), {} more than the {max_bytes} bytes {} \
                 can bind for them in two bindings (max_buffer_size {}, \
                 max_storage_buffer_binding_size {})",
                len.saturating_sub(max_bytes),
                self.describe(),
                self.limits.max_buffer_size,
                self.limits.max_storage_buffer_binding_size
            )));
        }
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene words"),
            size: len,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut split_arrays = Vec::new();
        for (name, bytes, first) in arrays.iter() {
            let offset = **first as u64 * WORD;
            if !bytes.is_empty() {
                self.queue.write_buffer(&buffer, offset, bytes);
                if offset + bytes.len() as u64 > low {
                    split_arrays.push(*name);
                }
            }
        }
        Ok(SceneWords {
            buffer,
            per_binding: if len == low {
                u32::MAX
            } else {
                (low / WORD) as u32
            },
            low,
            arrays: sizes,
            split_arrays,
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
