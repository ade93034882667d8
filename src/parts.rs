//! Images rendered in parts (`lambert render --tile I/N`) and assembled
//! again (`lambert merge`), exactly: a sample depends only on its pixel,
//! its index and the seed, so a part's pixels are the whole render's.
//!
//! A part is band I of N of the image's rows (row I·H/N up to (I+1)·H/N),
//! written as an OpenEXR file whose display window is the whole image and
//! whose data window is the band, with the part's index and count and a
//! hash of everything that changes pixels as attributes.

use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::camera::View;
use crate::error::{Error, Result};
use crate::output::{Image, write_atomically};
use crate::scene::Scene;

const ATTRIBUTE_PART: &str = "lambertPart";
const ATTRIBUTE_HASH: &str = "lambertSettings";

/// Which part of how many: `--tile I/N`, I from 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    pub index: u32,
    pub count: u32,
}

impl Tile {
    pub fn parse(text: &str) -> Result<Tile> {
        let usage = || {
            Error::Usage(format!(
                "--tile {text}: expected I/N, with 0 ≤ I < N (I from 0)"
            ))
        };
        let (i, n) = text.split_once('/').ok_or_else(usage)?;
        let (index, count): (u32, u32) = (
            i.trim().parse().map_err(|_| usage())?,
            n.trim().parse().map_err(|_| usage())?,
        );
        if count == 0 || index >= count {
            return Err(usage());
        }
        Ok(Tile { index, count })
    }

    /// The rows this part renders of an image `height` rows tall: bands of
    /// equal height (±1 row), so parts cost about the same where the
    /// image's work is spread evenly (for uneven scenes, choose N larger
    /// than the number of workers).
    pub fn rows(self, height: u32) -> Result<Range<u32>> {
        if self.count > height {
            return Err(Error::Usage(format!(
                "--tile {}/{}: the image has only {height} rows; N must be at most that",
                self.index, self.count
            )));
        }
        let at = |i: u32| (i as u64 * height as u64 / self.count as u64) as u32;
        Ok(at(self.index)..at(self.index + 1))
    }
}

/// FNV-1a, 64 bits: a stable fingerprint (not a secure hash) of the
/// scene and settings that change pixels.
struct Fingerprint(u64);

impl Fingerprint {
    fn add(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x100_0000_01b3);
        }
    }
}

/// The hash a part records: everything that reaches a pixel. The scene's
/// geometry and its offset (the geometry is stored relative to the
/// scene's centre, so a far scene moved whole keeps its local numbers and
/// differs only there), materials and tangent frames, texture texels
/// (the store's words: an image's pixels changed at the same size change
/// nothing else), lights,
/// background, ambient, shadows, intersection test and acceleration; the
/// view's camera, image size, samples and seed; and which path renders
/// (the GPU's pixels differ from the CPU's within tolerance, so parts of
/// the two do not mix).
pub fn settings_hash(scene: &Scene, view: &View, device: &str) -> String {
    let mut h = Fingerprint(0xcbf2_9ce4_8422_2325);
    for v in scene.offset.to_array() {
        h.add(&v.to_le_bytes());
    }
    h.add(bytemuck::cast_slice(scene.textures.words()));
    h.add(bytemuck::cast_slice(&scene.triangles));
    h.add(bytemuck::cast_slice(&scene.normals));
    h.add(bytemuck::cast_slice(&scene.attributes));
    // Empty but for normal-mapped scenes: other scenes' hashes as before.
    h.add(bytemuck::cast_slice(&scene.tangents));
    h.add(bytemuck::cast_slice(&scene.spheres));
    h.add(bytemuck::cast_slice(&scene.materials));
    h.add(bytemuck::cast_slice(&scene.lights));
    // Only a scene with an environment adds to it: other scenes' hashes as
    // before.
    if let Some(e) = &scene.environment {
        h.add(bytemuck::cast_slice(&e.color));
        h.add(bytemuck::cast_slice(&e.rotation));
        if let Some(map) = &e.map {
            h.add(bytemuck::cast_slice(&map.pixels));
        }
    }
    let c = &view.camera;
    for v in c.eye.iter().chain(&c.look_at).chain(&c.up).chain([&c.vfov]) {
        h.add(&v.to_le_bytes());
    }
    for v in [
        c.width,
        c.height,
        scene.shadows as u32,
        view.spp,
        view.seed,
        scene.intersect.shader_value(),
        scene.accel as u32,
    ] {
        h.add(&v.to_le_bytes());
    }
    h.add(bytemuck::cast_slice(&scene.background));
    h.add(bytemuck::cast_slice(&scene.ambient));
    h.add(device.as_bytes());
    format!("fnv1a64:{:016x}", h.0)
}

/// Writes `band` (rows `rows` of a `width` × `height` image) as part
/// `tile`, atomically.
pub fn write_part(
    path: &Path,
    band: &Image,
    tile: Tile,
    height: u32,
    rows: Range<u32>,
    hash: &str,
) -> Result<()> {
    use exr::meta::attribute::{AttributeValue, IntegerBounds, Text};
    use exr::prelude::*;
    let width = band.width as usize;
    let pixels = |p: Vec2<usize>| {
        let [r, g, b] = band.rgb[p.y() * width + p.x()];
        (r, g, b)
    };
    let mut attributes = LayerAttributes::named("");
    attributes.layer_name = None;
    attributes.layer_position = Vec2(0, rows.start as i32);
    attributes.software_name = Some(Text::from("lambert"));
    // One custom attribute in each of the crate's two maps (layer and
    // image): two in one HashMap were written in a different order from
    // run to run, so the same part differed in bytes.
    attributes.other.insert(
        Text::from(ATTRIBUTE_HASH),
        AttributeValue::Text(Text::from(hash)),
    );
    let layer = Layer::new(
        (width, rows.len()),
        attributes,
        Encoding::SMALL_LOSSLESS,
        SpecificChannels::rgb(pixels),
    );
    let mut image = exr::image::Image::from_layer(layer);
    image.attributes.display_window = IntegerBounds::new((0, 0), (width, height as usize));
    image.attributes.other.insert(
        Text::from(ATTRIBUTE_PART),
        AttributeValue::Text(Text::from(
            format!("{}/{}", tile.index, tile.count).as_str(),
        )),
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).map_err(|e| {
        crate::error::Error::Usage(format!("{}: cannot encode the part: {e}", path.display()))
    })?;
    write_atomically(path, bytes.get_ref())
}

/// A part as read back.
pub struct Part {
    path: PathBuf,
    tile: Tile,
    hash: String,
    width: u32,
    height: u32,
    rows: Range<u32>,
    rgb: Vec<[f32; 3]>,
}

fn read_part(path: &Path) -> Result<Part> {
    let bytes = crate::files::read_capped(path, crate::files::MAX_MODEL_BYTES)?;
    parse_part(&bytes, path)
}

/// Checks a part's header before its pixels are decoded: the decoder
/// allocates what the header claims, so a few corrupt bytes could otherwise
/// ask for gigabytes. Only the compressions lambert writes parts with (and
/// none, and RLE) are read, as their expansion is bounded.
fn check_part_header(bytes: &[u8], fail: &dyn Fn(String) -> Error) -> Result<()> {
    use exr::compression::Compression;
    let meta = exr::meta::MetaData::read_from_buffered(bytes, false)
        .map_err(|e| fail(format!("not a readable EXR part: {e}")))?;
    let [header] = meta.headers.as_slice() else {
        return Err(fail(format!(
            "has {} layers; a lambert part has one",
            meta.headers.len()
        )));
    };
    if !matches!(
        header.compression,
        Compression::Uncompressed | Compression::RLE | Compression::ZIP1 | Compression::ZIP16
    ) || header.deep
    {
        return Err(fail(format!(
            "its pixels are {} (deep: {}); lambert parts are ZIP-compressed flat images",
            header.compression, header.deep
        )));
    }
    let display = header.shared_attributes.display_window.size;
    let side = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
    crate::limits::validate_resolution(side(display.width()), side(display.height()))
        .and_then(|_| {
            crate::limits::validate_resolution(
                side(header.layer_size.width()),
                side(header.layer_size.height()),
            )
        })
        .map_err(|e| fail(format!("its image: {e}")))?;
    let pixel_bytes = header.layer_size.area() as u64 * header.channels.bytes_per_pixel as u64;
    if pixel_bytes > crate::files::MAX_EXPANSION * bytes.len() as u64 {
        return Err(fail(format!(
            "its header claims {pixel_bytes} bytes of pixels, more than its {} bytes can hold \
             (the file is truncated or corrupt)",
            bytes.len()
        )));
    }
    Ok(())
}

/// Decodes and checks a part file's bytes; `path` names it in errors.
pub fn parse_part(bytes: &[u8], path: &Path) -> Result<Part> {
    use exr::meta::attribute::AttributeValue;
    let fail = |m: String| crate::error::Error::Usage(format!("{}: {m}", path.display()));
    check_part_header(bytes, &fail)?;
    let image = crate::output::decode_exr_rgb(bytes)
        .map_err(|e| fail(format!("not a readable EXR part: {e}")))?;
    // Read back from either level: a single-layer file has one header.
    let text = |name: &str| {
        let key = exr::meta::attribute::Text::from(name);
        let found = image
            .attributes
            .other
            .get(&key)
            .or_else(|| image.layer_data.attributes.other.get(&key));
        match found {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            _ => Err(fail(format!(
                "not a lambert part (no {name} attribute): render it with --tile"
            ))),
        }
    };
    let tile = Tile::parse(&text(ATTRIBUTE_PART)?)
        .map_err(|_| fail("its part attribute is malformed".into()))?;
    let hash = text(ATTRIBUTE_HASH)?;
    let display = image.attributes.display_window;
    let layer = &image.layer_data;
    let (width, height) = (display.size.width() as u32, display.size.height() as u32);
    let y0 = layer.attributes.layer_position.y();
    let band_height = layer.size.height() as u32;
    let expected = tile
        .rows(height)
        .map_err(|_| fail("its part index does not fit its image".into()))?;
    if layer.size.width() as u32 != width
        || y0 < 0
        || (y0 as u32..y0 as u32 + band_height) != expected
    {
        return Err(fail(format!(
            "its pixels (rows {y0}.. of {band_height}) are not part {}/{} of a {width}×{height} image",
            tile.index, tile.count
        )));
    }
    Ok(Part {
        path: path.to_path_buf(),
        tile,
        hash,
        width,
        height,
        rows: expected,
        rgb: layer.channel_data.pixels.1.clone(),
    })
}

/// Assembles `paths` (every part of one render, once) into `output`
/// (.png, .exr or .pfm, written atomically). Refuses, naming the parts, a
/// missing, duplicated or overlapping part and parts of different scenes,
/// settings or image sizes; a refused merge writes nothing.
pub fn merge(paths: &[PathBuf], output: &Path) -> Result<Image> {
    if paths.is_empty() {
        return Err(Error::Usage("merge needs the part files".into()));
    }
    let parts: Vec<Part> = paths.iter().map(|p| read_part(p)).collect::<Result<_>>()?;
    let first = &parts[0];
    for part in &parts[1..] {
        let differs = if (part.width, part.height) != (first.width, first.height) {
            Some(format!(
                "{}×{} against {}×{}",
                part.width, part.height, first.width, first.height
            ))
        } else if part.tile.count != first.tile.count {
            Some(format!(
                "one of {} parts against one of {}",
                part.tile.count, first.tile.count
            ))
        } else if part.hash != first.hash {
            Some("another scene or other settings (spp, seed, device, …)".into())
        } else {
            None
        };
        if let Some(why) = differs {
            return Err(Error::Usage(format!(
                "{} and {} are not parts of one render: {why}",
                first.path.display(),
                part.path.display()
            )));
        }
    }
    let count = first.tile.count;
    let mut owner: Vec<Option<&Part>> = vec![None; count as usize];
    for part in &parts {
        if let Some(other) = owner[part.tile.index as usize] {
            return Err(Error::Usage(format!(
                "{} and {} are both part {}/{count} (duplicated or overlapping)",
                other.path.display(),
                part.path.display(),
                part.tile.index
            )));
        }
        owner[part.tile.index as usize] = Some(part);
    }
    let missing: Vec<String> = (0..count)
        .filter(|&i| owner[i as usize].is_none())
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(Error::Usage(format!(
            "parts missing: {} (given {} of {count})",
            missing.join(", "),
            parts.len()
        )));
    }
    let (width, height) = (first.width, first.height);
    let mut rgb = vec![[0.0f32; 3]; width as usize * height as usize];
    for part in &parts {
        let at = part.rows.start as usize * width as usize;
        rgb[at..at + part.rgb.len()].copy_from_slice(&part.rgb);
    }
    let image = Image { width, height, rgb };
    image.save(output)?;
    Ok(image)
}
