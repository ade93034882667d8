//! Images decoded to 8-bit RGBA, from a file (read as every file is:
//! regular, size-capped) or from bytes a model carries. Only PNG and JPEG,
//! the formats glTF allows; anything else is refused with a message the
//! caller turns into a warning.

use std::io::Cursor;

use crate::files::read_capped;
use crate::loading::material::ImageSource;

/// The most lambert reads of one image file.
pub const MAX_IMAGE_BYTES: u64 = 512 << 20;
/// The widest and tallest image lambert decodes: its texel coordinates in
/// 1/256 steps stay exact in f32 (docs/textures.md).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// An image as 8-bit RGBA rows, top row first; `format` is what it was
/// ("PNG", "JPEG"), for `lambert info`.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedImage {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub format: &'static str,
}

/// The image `source` holds, or why not, in words that name it (the file,
/// or the model's name for embedded bytes).
pub fn decode_image(source: &ImageSource) -> Result<DecodedImage, String> {
    let (bytes, name) = match source {
        ImageSource::File(path) => (
            read_capped(path, MAX_IMAGE_BYTES).map_err(|e| e.to_string())?,
            path.display().to_string(),
        ),
        ImageSource::Embedded { bytes, name } => (bytes.clone(), name.clone()),
    };
    decode_bytes(&bytes).map_err(|why| format!("{name}: {why}"))
}

fn decode_bytes(bytes: &[u8]) -> Result<DecodedImage, String> {
    let format = match image::guess_format(bytes) {
        Ok(image::ImageFormat::Png) => ("PNG", image::ImageFormat::Png),
        Ok(image::ImageFormat::Jpeg) => ("JPEG", image::ImageFormat::Jpeg),
        Ok(other) => return Err(format!("a {other:?} image (lambert reads PNG and JPEG)")),
        Err(_) => return Err("not a PNG or JPEG image".into()),
    };
    let mut reader = image::ImageReader::with_format(Cursor::new(bytes), format.1);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    // RGBA8 of the largest image, and the decoder's own buffers beside it.
    limits.max_alloc = Some(2 * 4 * (MAX_TEXTURE_SIDE as u64).pow(2));
    reader.limits(limits);
    let image = reader
        .decode()
        .map_err(|e| format!("not a readable {} image: {e}", format.0))?;
    let rgba = image.into_rgba8();
    Ok(DecodedImage {
        width: rgba.width(),
        height: rgba.height(),
        rgba: rgba.into_raw(),
        format: format.0,
    })
}
