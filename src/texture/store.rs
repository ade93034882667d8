//! Every texture of a scene in one array of 32-bit words, the form both
//! paths read (docs/textures.md):
//!
//! - words 0..256: the sRGB table, 8-bit sRGB → linear in 1/`LINEAR_ONE`;
//! - once some image holds data rather than colour (normal and
//!   metallic-roughness maps), the linear table, 8-bit value v → v/255 in
//!   1/`LINEAR_ONE`, where the first such image was added;
//! - per image, its mip levels, 4 words each: the level's first texel
//!   word, width, height, 0;
//! - the texels, one word each, RGBA8 (RGB encoded as its table says, A
//!   linear), rows top first;
//! - per texture use (`TextureSlot`), `SLOT_WORDS` words: the UV transform,
//!   texel area, where its image's levels are, its sampler. A material
//!   names a use by the word where it starts (`layout::NO_TEXTURE` for none).

use bytemuck::{Pod, Zeroable};

use super::decode::DecodedImage;
use crate::loading::material::{Filter, TextureUse, Wrap};

/// Linear 1.0 in the store's fixed point (15 bits: a bilinear sum of four
/// texels, weights in 1/65536, stays within a u32; docs/textures.md).
pub const LINEAR_ONE: u32 = 1 << 15;
/// Words of the sRGB table at the start of the store.
pub const SRGB_TABLE_WORDS: u32 = 256;
/// Words of one `TextureSlot`.
pub const SLOT_WORDS: u32 = (std::mem::size_of::<TextureSlot>() / 4) as u32;

/// One use of an image, as the shader reads it (shaders/texture.wgsl,
/// `texture_slot` word offsets).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TextureSlot {
    /// Row-major 2×3 UV transform (`TextureUse::transform`).
    pub transform: [f32; 6],
    /// Texels per unit of UV area: |det| of the transform × width × height.
    pub texel_area: f32,
    /// Word of the image's first level entry.
    pub levels: u32,
    /// wrap u (bits 0–1), wrap v (2–3), bilinear magnify (4), bilinear
    /// minify (5), mipmaps (6), level count (8–15).
    pub flags: u32,
    /// Word of the table its image's RGB bytes decode through: 0, the sRGB
    /// table, for colour; the linear table for data (`Encoding::Linear`).
    pub table: u32,
}

/// How an image's RGB bytes encode their values: colour (base colour,
/// emission) is sRGB, as glTF and MTL say; data (normal vectors,
/// metalness, roughness) is linear, v/255.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    Srgb,
    Linear,
}

/// One mip level's entry (4 words).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TextureLevel {
    pub texels: u32,
    pub width: u32,
    pub height: u32,
    pub _pad: u32,
}

/// An 8-bit sRGB value as linear light in 1/`LINEAR_ONE` (the table both
/// paths read, so the decode is identical on both).
pub fn linear_from_srgb(s: u8) -> u32 {
    let c = s as f64 / 255.0;
    let linear = if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    };
    (linear * LINEAR_ONE as f64).round() as u32
}

fn srgb_table() -> [u32; 256] {
    std::array::from_fn(|s| linear_from_srgb(s as u8))
}

/// An 8-bit linear value v as v/255 in 1/`LINEAR_ONE` (as alpha decodes).
fn linear_table() -> [u32; 256] {
    std::array::from_fn(|v| (v as u32 * LINEAR_ONE + 127) / 255)
}

/// The 8-bit value whose decoded value (in `table`, increasing) is nearest.
fn encode_nearest(table: &[u32; 256], linear: u32) -> u8 {
    let above = table.partition_point(|&t| t < linear).min(255);
    if above > 0 && linear - table[above - 1] <= table[above].saturating_sub(linear) {
        (above - 1) as u8
    } else {
        above as u8
    }
}

/// The source indices a coarser level's index `i` averages: 2i and 2i+1,
/// and 2i+2 for the last one of an odd size (no source texel is dropped).
fn footprint(i: u32, size: u32) -> std::ops::Range<u32> {
    if size == 1 {
        return 0..1;
    }
    let end = if size % 2 == 1 && i == size / 2 - 1 {
        2 * i + 3
    } else {
        2 * i + 2
    };
    2 * i..end
}

/// The mip chain of an RGBA8 image (RGB sRGB, A linear) down to 1×1, each
/// level as (width, height, packed texels): a box filter of the level
/// above, averaged in linear light and re-encoded to 8-bit sRGB.
pub fn mip_chain(width: u32, height: u32, rgba: &[u8]) -> Vec<(u32, u32, Vec<u32>)> {
    encoded_mip_chain(width, height, rgba, Encoding::Srgb)
}

/// `mip_chain` of an image whose RGB is encoded as `encoding` says:
/// averaged as the values they decode to, re-encoded the same way.
fn encoded_mip_chain(
    width: u32,
    height: u32,
    rgba: &[u8],
    encoding: Encoding,
) -> Vec<(u32, u32, Vec<u32>)> {
    let table = match encoding {
        Encoding::Srgb => srgb_table(),
        Encoding::Linear => linear_table(),
    };
    let top: Vec<u32> = rgba
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let mut levels = vec![(width, height, top)];
    while let Some(&(w, h, ref above)) = levels.last() {
        if w == 1 && h == 1 {
            break;
        }
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let mut texels = Vec::with_capacity((nw * nh) as usize);
        for y in 0..nh {
            for x in 0..nw {
                let mut sum = [0u32; 4];
                let mut n = 0;
                for sy in footprint(y, h) {
                    for sx in footprint(x, w) {
                        let t = above[(sy * w + sx) as usize];
                        for (c, s) in sum.iter_mut().enumerate().take(3) {
                            *s += table[((t >> (8 * c)) & 255) as usize];
                        }
                        sum[3] += t >> 24;
                        n += 1;
                    }
                }
                let mean = |s: u32| (s + n / 2) / n;
                texels.push(
                    encode_nearest(&table, mean(sum[0])) as u32
                        | (encode_nearest(&table, mean(sum[1])) as u32) << 8
                        | (encode_nearest(&table, mean(sum[2])) as u32) << 16
                        | mean(sum[3]) << 24,
                );
            }
        }
        levels.push((nw, nh, texels));
    }
    levels
}

/// One image of the store, as `lambert info` lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredImage {
    /// The file, or where embedded bytes came from.
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// "PNG" or "JPEG".
    pub format: &'static str,
    /// The word of its first level entry.
    pub levels: u32,
    pub level_count: u32,
    /// Colour (sRGB) or data (linear).
    pub encoding: Encoding,
}

/// A scene's textures as the shader reads them (see the module's words).
#[derive(Clone, Debug)]
pub struct TextureStore {
    words: Vec<u32>,
    images: Vec<StoredImage>,
    slots: usize,
    /// The word where the linear table starts, once an image needs it.
    linear_table: Option<u32>,
}

/// No textures: the sRGB table alone (never an empty binding).
impl Default for TextureStore {
    fn default() -> TextureStore {
        TextureStore {
            words: srgb_table().to_vec(),
            images: Vec::new(),
            slots: 0,
            linear_table: None,
        }
    }
}

impl TextureStore {
    /// Adds `image` (called `name`), a colour image (sRGB), with its mip
    /// chain; returns its index for `slot`.
    pub fn add_image(&mut self, image: &DecodedImage, name: String) -> u32 {
        self.add_encoded_image(image, name, Encoding::Srgb)
    }

    /// `add_image` of an image encoded as `encoding` says.
    pub fn add_encoded_image(
        &mut self,
        image: &DecodedImage,
        name: String,
        encoding: Encoding,
    ) -> u32 {
        if encoding == Encoding::Linear && self.linear_table.is_none() {
            self.linear_table = Some(self.words.len() as u32);
            self.words.extend(linear_table());
        }
        let levels = encoded_mip_chain(image.width, image.height, &image.rgba, encoding);
        let first = self.words.len() as u32;
        let mut texel_word = self.words.len() + 4 * levels.len();
        for (w, h, texels) in &levels {
            self.words.extend([texel_word as u32, *w, *h, 0]);
            texel_word += texels.len();
        }
        for (_, _, texels) in levels.iter() {
            self.words.extend(texels);
        }
        self.images.push(StoredImage {
            name,
            width: image.width,
            height: image.height,
            format: image.format,
            levels: first,
            level_count: levels.len() as u32,
            encoding,
        });
        self.images.len() as u32 - 1
    }

    /// Adds a use of image `image` (an index `add_image` returned) with
    /// `texture`'s sampler and transform (its `image` field, the model's
    /// index, is not read); returns the word where it starts, the value a
    /// material's texture slot holds.
    pub fn slot(&mut self, image: u32, texture: &TextureUse) -> u32 {
        let stored = &self.images[image as usize];
        let (levels, count, width, height) = (
            stored.levels,
            stored.level_count,
            stored.width,
            stored.height,
        );
        let table = match stored.encoding {
            Encoding::Srgb => 0,
            Encoding::Linear => self.linear_table.expect("added with its linear image"),
        };
        let [[a, b, c], [d, e, f]] = texture.transform;
        let wrap = |w: Wrap| match w {
            Wrap::Repeat => 0,
            Wrap::MirroredRepeat => 1,
            Wrap::ClampToEdge => 2,
        };
        let linear = |f: Filter| (f == Filter::Linear) as u32;
        let sampler = texture.sampler;
        let slot = TextureSlot {
            transform: [a, b, c, d, e, f],
            texel_area: ((a as f64 * e as f64 - b as f64 * d as f64).abs()
                * width as f64
                * height as f64) as f32,
            levels,
            flags: wrap(sampler.wrap_u)
                | wrap(sampler.wrap_v) << 2
                | linear(sampler.magnify) << 4
                | linear(sampler.minify) << 5
                | (sampler.mipmaps as u32) << 6
                | count << 8,
            table,
        };
        let start = self.words.len() as u32;
        self.words.extend_from_slice(bytemuck::cast_slice(&[slot]));
        self.slots += 1;
        start
    }

    /// The words both paths read.
    pub fn words(&self) -> &[u32] {
        &self.words
    }

    /// Whether any material uses a texture.
    pub fn has_slots(&self) -> bool {
        self.slots > 0
    }

    /// The images added, in order.
    pub fn images(&self) -> &[StoredImage] {
        &self.images
    }

    /// The mean linear RGB of the image the slot starting at word `slot`
    /// reads: its coarsest mip level (1×1, averaged in linear light), the
    /// emitters' table's estimate of a textured emitter's power.
    pub fn mean_color(&self, slot: u32) -> [f64; 3] {
        let word = |at: u32| self.words[at as usize];
        let count = (word(slot + 8) >> 8) & 255;
        let level = word(slot + 7) + 4 * (count - 1);
        let (first, texels) = (word(level), word(level + 1) * word(level + 2));
        let mut sum = [0.0; 3];
        for t in first..first + texels {
            for (c, s) in sum.iter_mut().enumerate() {
                *s += word((word(t) >> (8 * c)) & 255) as f64 / LINEAR_ONE as f64;
            }
        }
        sum.map(|s| s / texels as f64)
    }

    /// The image (an index into `images`) the slot starting at word `slot`
    /// reads.
    pub fn image_of_slot(&self, slot: u32) -> Option<usize> {
        let levels = *self.words.get(slot as usize + 7)?;
        self.images.iter().position(|i| i.levels == levels)
    }
}
