//! The environment: light from every direction at infinity, a constant
//! colour or an equirectangular map (Radiance `.hdr` or OpenEXR `.exr`),
//! with a strength and a turn about +Y. Maps follow Mitsuba 3's
//! conventions (src/emitters/envmap.cpp; docs/rendering.md, "The
//! environment"): a direction d in the map's frame reads
//! u = atan2(d.x, −d.z)/2π (wrapped into [0, 1)), v = acos(d.y)/π, row 0
//! straight up; columns are texel-centred and periodic (column j's centre
//! at u = (j + ½)/W), rows are corner-aligned (row i at v = i/(H − 1)),
//! and the radiance between them bilinear.
//!
//! Sampling: a piecewise-constant distribution over the cells between
//! neighbouring texels (the bilinear patches), each weighted by its mean
//! luminance times its solid angle, so every direction whose radiance is
//! not 0 has a pdf that is not 0.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use super::distribution::cdf_2d;
use crate::error::{Error, Result};
use crate::files::{MAX_EXPANSION, read_capped};

/// The most lambert reads of an environment map file.
pub const MAX_ENVIRONMENT_BYTES: u64 = 1 << 30;
/// The widest and tallest map lambert decodes (as textures).
const MAX_ENVIRONMENT_SIDE: u32 = 16384;

/// What an environment is made of.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentSource {
    /// A constant radiance, linear RGB.
    Color([f32; 3]),
    /// An equirectangular map: a `.hdr` or `.exr` file.
    Image(PathBuf),
}

/// An environment as a scene file or `--environment` gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentSpec {
    pub source: EnvironmentSource,
    /// Multiplies the radiance (finite, ≥ 0).
    pub strength: f32,
    /// The map turned about +Y by this many degrees, as Mitsuba's
    /// `to_world = rotate([0, 1, 0], angle)`: a direction d in the world
    /// reads the map at R⁻¹·d.
    pub rotation_deg: f64,
}

impl EnvironmentSpec {
    /// The spec, its colour, strength and rotation checked; `name` gives
    /// the name errors call a key by (`"strength"` → `environment.strength`
    /// in a scene file, an option's name on the command line).
    pub fn new(
        source: EnvironmentSource,
        strength: f64,
        rotation_deg: f64,
        name: impl Fn(&str) -> String,
    ) -> Result<EnvironmentSpec, String> {
        if !(strength.is_finite() && strength >= 0.0 && strength <= f32::MAX as f64) {
            return Err(format!(
                "{} = {strength} must be finite and non-negative",
                name("strength")
            ));
        }
        if !rotation_deg.is_finite() {
            return Err(format!(
                "{} = {rotation_deg} must be finite",
                name("rotation_deg")
            ));
        }
        if let EnvironmentSource::Color(c) = source
            && !c.iter().all(|v| v.is_finite() && *v >= 0.0)
        {
            return Err(format!(
                "{} = {c:?} must be finite and non-negative",
                name("color")
            ));
        }
        Ok(EnvironmentSpec {
            source,
            strength: strength as f32,
            rotation_deg,
        })
    }

    /// The environment in words, for messages: its file or its colour.
    pub fn describe(&self) -> String {
        match &self.source {
            EnvironmentSource::Color(c) => format!("the environment (colour {c:?})"),
            EnvironmentSource::Image(path) => format!("the environment ({})", path.display()),
        }
    }
}

/// A map as the kernels read it: pixels (linear RGB × strength, row 0
/// straight up; a one-row file stored twice, so that rows span θ from 0 to
/// π) and the CDFs of its cells (`distribution::cdf_2d`: `height − 1` rows
/// of `width` cells).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
    pub cdf: Vec<f32>,
}

/// A loaded environment (see the module's comment).
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    pub spec: EnvironmentSpec,
    /// The constant radiance × strength (zero with a map).
    pub color: [f32; 3],
    pub map: Option<EnvironmentMap>,
    /// cos and sin of the rotation, rounded once from f64.
    pub rotation: [f32; 2],
    /// ∫ L dω over the sphere, L the mean of the three channels: the
    /// power's share of the environment is π r² times this (pbrt-v4's
    /// `ImageInfiniteLight::Phi`).
    pub radiance_integral: f64,
}

/// Rec. 709 luminance, Mitsuba's weight for a map's sampling.
fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

fn mean(c: [f32; 3]) -> f64 {
    (c[0] as f64 + c[1] as f64 + c[2] as f64) / 3.0
}

impl Environment {
    /// The environment `spec` gives: its map read (capped), decoded and
    /// its distribution built. Errors name the file.
    pub fn load(spec: &EnvironmentSpec) -> Result<Environment> {
        let radians = spec.rotation_deg.to_radians();
        let rotation = [radians.cos() as f32, radians.sin() as f32];
        let (color, map, radiance_integral) = match &spec.source {
            EnvironmentSource::Color(c) => {
                let color = c.map(|v| v * spec.strength);
                (color, None, 4.0 * std::f64::consts::PI * mean(color))
            }
            EnvironmentSource::Image(path) => {
                let bytes = read_capped(path, MAX_ENVIRONMENT_BYTES)?;
                let (map, integral) = EnvironmentMap::parse(&bytes, path, spec.strength)?;
                ([0.0; 3], Some(map), integral)
            }
        };
        Ok(Environment {
            spec: spec.clone(),
            color,
            map,
            rotation,
            radiance_integral,
        })
    }

    /// The file it was read from, if any.
    pub fn file(&self) -> Option<&Path> {
        match &self.spec.source {
            EnvironmentSource::Image(path) => Some(path),
            EnvironmentSource::Color(_) => None,
        }
    }
}

impl EnvironmentMap {
    /// The map in `bytes` (a `.hdr` or `.exr` file's, which `path` names
    /// in errors) × strength, and ∫ L dω of its channels' mean.
    pub fn parse(bytes: &[u8], path: &Path, strength: f32) -> Result<(EnvironmentMap, f64)> {
        let (width, height, rgb) = decode(path, bytes)?;
        Ok(EnvironmentMap::new(width, height, &rgb, strength))
    }

    /// The map of `rgb` (`width` × `height`, row 0 straight up) × strength,
    /// and ∫ L dω of its channels' mean.
    fn new(width: u32, height: u32, rgb: &[[f32; 3]], strength: f32) -> (EnvironmentMap, f64) {
        let (w, h) = (width as usize, height as usize);
        // One row spans all of θ when stored twice.
        let rows: Vec<&[[f32; 3]]> = if h == 1 {
            vec![rgb, rgb]
        } else {
            rgb.chunks(w).collect()
        };
        let pixels: Vec<[f32; 4]> = rows
            .iter()
            .flat_map(|row| row.iter())
            .map(|c| [c[0] * strength, c[1] * strength, c[2] * strength, 0.0])
            .collect();
        let stored_h = rows.len();
        let cells = stored_h - 1;
        let pixel = |i: usize, j: usize| {
            let p = pixels[i * w + j % w];
            [p[0], p[1], p[2]]
        };
        let corners = |i: usize, j: usize, f: fn([f32; 3]) -> f64| {
            (f(pixel(i, j)) + f(pixel(i, j + 1)) + f(pixel(i + 1, j)) + f(pixel(i + 1, j + 1)))
                / 4.0
        };
        let pi = std::f64::consts::PI;
        let mut weights = Vec::with_capacity(cells * w);
        let mut integral = 0.0;
        for i in 0..cells {
            // The band's solid angle over 2π/W: cos θᵢ − cos θᵢ₊₁.
            let band =
                (pi * i as f64 / cells as f64).cos() - (pi * (i + 1) as f64 / cells as f64).cos();
            for j in 0..w {
                weights.push(corners(i, j, luminance) * band);
                integral += corners(i, j, mean) * band * 2.0 * pi / w as f64;
            }
        }
        let map = EnvironmentMap {
            width,
            height: stored_h as u32,
            pixels,
            cdf: cdf_2d(&weights, cells, w),
        };
        (map, integral)
    }
}

/// A `.hdr` or `.exr` file's pixels as linear RGB, row 0 first, or why
/// not, naming `path`. Negative values are read as 0; a value that is not
/// finite is refused.
/// An EXR's header and chunks checked before its pixels are decoded: one
/// flat part, its pixels and tiles within what its bytes can expand to,
/// every chunk within the file.
fn check_exr_layers(bytes: &[u8]) -> std::result::Result<(), String> {
    let mut read = Cursor::new(bytes);
    let meta = exr::meta::MetaData::read_from_buffered(&mut read, false)
        .map_err(|e| format!("not a readable OpenEXR image: {e}"))?;
    let [header] = meta.headers.as_slice() else {
        return Err(format!(
            "has {} parts; an environment map has one",
            meta.headers.len()
        ));
    };
    if header.deep {
        return Err("a deep image; an environment map is flat".into());
    }
    // A tile's buffer is sized by the header before a pixel is read (a
    // 500-byte file claimed 64 × 16,056,384-pixel tiles: 1.1 GB): held,
    // as the whole image is, to what the file's bytes can expand to.
    let bytes_per_pixel = header.channels.bytes_per_pixel as u64;
    let (chunk_header, size_at) = match header.blocks {
        exr::meta::BlockDescription::Tiles(tiles) => {
            let tile_bytes = tiles.tile_size.area() as u64 * bytes_per_pixel;
            if tile_bytes > MAX_EXPANSION * bytes.len() as u64 {
                return Err(format!(
                    "its header claims tiles of {tile_bytes} bytes, more than its {} bytes \
                     can hold (the file is truncated or corrupt)",
                    bytes.len()
                ));
            }
            // A tile chunk: tile x, y, level x, level y, then its size.
            (20, 16)
        }
        // A scanline chunk: its first line's y, then its size.
        exr::meta::BlockDescription::ScanLines => (8, 4),
    };
    let pixel_bytes = header.layer_size.area() as u64 * bytes_per_pixel;
    if pixel_bytes > MAX_EXPANSION * bytes.len() as u64 {
        return Err(format!(
            "its header claims {pixel_bytes} bytes of pixels, more than its {} bytes can hold \
             (the file is truncated or corrupt)",
            bytes.len()
        ));
    }
    // Every chunk the offset table names must lie within the file: the
    // exr crate allocates what a chunk's size field claims before it finds
    // the bytes missing (a corrupt 500-byte RLE file asked for 1.1 GB).
    let corrupt = |what: String| {
        format!("not a readable OpenEXR image: {what} (the file is truncated or corrupt)")
    };
    let word = |at: usize, n: usize| bytes.get(at..at + n);
    let table = read.position() as usize;
    for chunk in 0..header.chunk_count {
        let entry = word(table + 8 * chunk, 8)
            .ok_or_else(|| corrupt(format!("its offset table ends before chunk {chunk}")))?;
        let offset = u64::from_le_bytes(entry.try_into().expect("8 bytes")) as usize;
        let size = word(offset.saturating_add(size_at), 4)
            .map(|w| i32::from_le_bytes(w.try_into().expect("4 bytes")))
            .ok_or_else(|| corrupt(format!("chunk {chunk} starts past its end")))?;
        let end = (offset + chunk_header).checked_add(usize::try_from(size).unwrap_or(usize::MAX));
        if !end.is_some_and(|end| end <= bytes.len()) {
            return Err(corrupt(format!(
                "chunk {chunk} claims {size} bytes past its end"
            )));
        }
    }
    Ok(())
}

fn decode(path: &Path, bytes: &[u8]) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    let fail = |message: String| Error::scene(path, message);
    let (name, format) = match image::guess_format(bytes) {
        Ok(image::ImageFormat::Hdr) => ("Radiance HDR", image::ImageFormat::Hdr),
        Ok(image::ImageFormat::OpenExr) => ("OpenEXR", image::ImageFormat::OpenExr),
        _ => {
            return Err(fail(
                "not a Radiance HDR (.hdr) or OpenEXR (.exr) image, the environment maps \
                 lambert reads"
                    .into(),
            ));
        }
    };
    let unreadable = |e: image::ImageError| fail(format!("not a readable {name} image: {e}"));
    let reader = || {
        let mut reader = image::ImageReader::with_format(Cursor::new(bytes), format);
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_ENVIRONMENT_SIDE);
        limits.max_image_height = Some(MAX_ENVIRONMENT_SIDE);
        limits.max_alloc = Some(4 << 30);
        reader.limits(limits);
        reader
    };
    // The header first: a small file may claim a huge image, whose pixels
    // the decoder would allocate before reading one.
    if format == image::ImageFormat::OpenExr {
        check_exr_layers(bytes).map_err(fail)?;
    }
    let (width, height) = reader().into_dimensions().map_err(unreadable)?;
    let claimed = 12 * width as u64 * height as u64;
    if width == 0 || height == 0 {
        return Err(fail(format!(
            "a {name} image of {width} × {height} pixels: none to light with"
        )));
    }
    if claimed > MAX_EXPANSION * bytes.len() as u64 {
        return Err(fail(format!(
            "its header claims {width} × {height} pixels, {claimed} bytes, more than its {} \
             bytes can hold",
            bytes.len()
        )));
    }
    // An EXR through the exr crate itself, as `parts` reads, at its data
    // window's size (which the image crate's may not report).
    let (width, height, pixels) = if format == image::ImageFormat::OpenExr {
        let layer = crate::output::decode_exr_rgb(bytes)
            .map_err(|e| fail(format!("not a readable OpenEXR image: {e}")))?
            .layer_data;
        let (w, h) = (layer.size.width(), layer.size.height());
        let side = |v: usize| {
            u32::try_from(v)
                .ok()
                .filter(|&v| (1..=MAX_ENVIRONMENT_SIDE).contains(&v))
        };
        let (Some(w), Some(h)) = (side(w), side(h)) else {
            return Err(fail(format!(
                "its pixels are {w} × {h}: an environment map's sides are 1 to \
                 {MAX_ENVIRONMENT_SIDE}"
            )));
        };
        (w, h, layer.channel_data.pixels.1)
    } else {
        let image = reader().decode().map_err(unreadable)?.into_rgb32f();
        (width, height, image.pixels().map(|p| p.0).collect())
    };
    let mut rgb = Vec::with_capacity((width * height) as usize);
    for (i, p) in pixels.iter().enumerate() {
        if !p.iter().all(|v| v.is_finite()) {
            return Err(fail(format!(
                "pixel ({}, {}) is {p:?}: an environment's radiance must be finite",
                i as u32 % width,
                i as u32 / width,
            )));
        }
        rgb.push(p.map(|v| v.max(0.0)));
    }
    Ok((width, height, rgb))
}
