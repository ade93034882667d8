//! Images and their files: PNG (sRGB, 8-bit, for people), EXR and PFM
//! (linear f32, unclamped, for tools). Every file is written atomically.

use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};

use image::{ExtendedColorType, ImageEncoder};

use crate::error::{Error, Result};

/// Linear RGB, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<[f32; 3]>,
}

/// A render: the image and, per pixel, the primitive its camera ray hit
/// (`layout::NO_HIT` for a miss).
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    pub image: Image,
    pub prims: Vec<u32>,
    /// Per pixel, the variance of the mean luminance of its samples (the
    /// squared standard error; 0 at 1 sample per pixel).
    pub variance: Vec<f32>,
}

impl Image {
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        self.rgb[(y * self.width + x) as usize]
    }

    /// 8-bit sRGB: clamp to [0, 1], sRGB transfer curve, round.
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.rgb
            .iter()
            .flat_map(|p| p.map(linear_to_srgb8))
            .collect()
    }

    /// `to_srgb8` with an opaque alpha: what a viewer shows (a canvas's
    /// ImageData, the window's frame), the bytes the PNG writer writes.
    pub fn to_rgba8(&self) -> Vec<u8> {
        self.to_srgb8()
            .chunks(3)
            .flat_map(|rgb| [rgb[0], rgb[1], rgb[2], 255])
            .collect()
    }

    /// The PNG that `save` writes, as bytes.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        self.encode_png()
            .map_err(|e| Error::Usage(format!("encoding PNG: {e}")))
    }

    /// Writes PNG, EXR or PFM, chosen by the extension, atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let bytes = match extension.as_deref() {
            Some("png") => self.encode_png(),
            Some("exr") => self.encode_exr(),
            Some("pfm") => Ok(self.encode_pfm()),
            _ => {
                return Err(Error::Usage(format!(
                    "{}: unknown image format; use .png, .exr or .pfm",
                    path.display()
                )));
            }
        }
        .map_err(|e| Error::Usage(format!("{}: cannot encode: {e}", path.display())))?;
        write_atomically(path, &bytes)
    }

    fn encode_png(&self) -> image::ImageResult<Vec<u8>> {
        encode_rgb8(self.width, self.height, &self.to_srgb8())
    }

    fn encode_exr(&self) -> image::ImageResult<Vec<u8>> {
        let mut bytes = Cursor::new(Vec::new());
        image::codecs::openexr::OpenExrEncoder::new(&mut bytes).write_image(
            bytemuck::cast_slice(&self.rgb),
            self.width,
            self.height,
            ExtendedColorType::Rgb32F,
        )?;
        Ok(bytes.into_inner())
    }

    /// Portable float map: little-endian (negative scale), rows bottom to top.
    fn encode_pfm(&self) -> Vec<u8> {
        let mut bytes = format!("PF\n{} {}\n-1.0\n", self.width, self.height).into_bytes();
        for row in self.rgb.chunks(self.width as usize).rev() {
            for value in row.iter().flatten() {
                bytes.extend_from_slice(&value.to_le_bytes());
            }
        }
        bytes
    }
}

/// An EXR's first flat layer at its largest resolution, as linear RGB
/// (`.layer_data.channel_data.pixels.1`, rows top to bottom) with its
/// attributes: what render parts and environment maps are read as. The
/// caller checks the header first: the decoder allocates what it claims.
pub type ExrRgb = exr::image::PixelImage<(usize, Vec<[f32; 3]>), exr::image::RgbChannels>;

/// `bytes` decoded as an `ExrRgb`.
pub fn decode_exr_rgb(bytes: &[u8]) -> std::result::Result<ExrRgb, exr::error::Error> {
    use exr::prelude::*;
    read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, _| (size.width(), vec![[0.0f32; 3]; size.area()]),
            |(width, pixels): &mut (usize, Vec<[f32; 3]>),
             p: Vec2<usize>,
             (r, g, b): (f32, f32, f32)| { pixels[p.y() * *width + p.x()] = [r, g, b] },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
}

pub fn linear_to_srgb8(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let encoded = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (encoded * 255.0).round() as u8
}

fn encode_rgb8(width: u32, height: u32, rgb: &[u8]) -> image::ImageResult<Vec<u8>> {
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes).write_image(
        rgb,
        width,
        height,
        ExtendedColorType::Rgb8,
    )?;
    Ok(bytes)
}

/// PNG bytes of 8-bit RGB pixels, rows from the top.
pub fn encode_png_rgb8(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>> {
    encode_rgb8(width, height, rgb).map_err(|e| Error::Usage(format!("encoding PNG: {e}")))
}

/// Temporary files being written, removed by `remove_temporaries` when a
/// signal ends the process mid-write.
static TEMPORARIES: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Removes every temporary file still being written: the CLI's SIGINT,
/// SIGTERM and SIGHUP handler calls it before exiting. Holds the registry
/// until the process exits, so no rename can complete behind it.
pub fn remove_temporaries_and_exit(code: i32) -> ! {
    let guard = registry();
    for path in guard.iter() {
        let _ = std::fs::remove_file(path);
    }
    std::process::exit(code)
}

/// Where writing `path` lands: symlinks followed (a dangling one to the
/// file it names), so that the link stays and its target is replaced.
fn resolve_target(path: &Path) -> Result<PathBuf> {
    let mut target = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&target) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&target).map_err(|e| Error::io(&target, e))?;
                target = match target.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            _ => return Ok(target),
        }
    }
    Err(Error::Usage(format!(
        "{}: too many levels of symbolic links",
        path.display()
    )))
}

/// The folder a new file at `target` goes in.
fn folder_of(target: &Path) -> &Path {
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Whether `target` exists and is neither a regular file nor a folder (a
/// device, a FIFO, a socket): such a target is written directly.
fn is_special(target: &Path) -> bool {
    std::fs::metadata(target).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Makes ready to write `path` before any work is done: its folder is
/// created when missing (the one rule for every output, --plot's folder
/// included), and must take a new file; a folder at `path` is an error.
pub fn prepare_output(path: &Path) -> Result<()> {
    prepare_output_for(path, &[])
}

/// `prepare_output`, refusing an output that is one of `inputs`: an output
/// is never written over a file the command reads (a symlink or a hard
/// link to one included).
pub fn prepare_output_for(path: &Path, inputs: &[&Path]) -> Result<()> {
    refuse_input(path, inputs)?;
    let target = resolve_target(path)?;
    if target.is_dir() {
        return Err(Error::Usage(format!(
            "{}: is a folder, not a file",
            path.display()
        )));
    }
    if is_special(&target) {
        return Ok(());
    }
    let folder = folder_of(&target);
    std::fs::create_dir_all(folder).map_err(|e| Error::io(folder, e))?;
    let created = create_temporary(&target, "probe").map(|(probe, _)| {
        let _ = std::fs::remove_file(&probe);
        unregister(&probe);
    });
    created.map_err(|e| {
        Error::Usage(format!(
            "{}: cannot write in {}: {e}",
            path.display(),
            folder.display()
        ))
    })?;
    Ok(())
}

/// An error where the output `path` is one of `inputs`.
pub fn refuse_input(path: &Path, inputs: &[&Path]) -> Result<()> {
    match inputs.iter().find(|input| same_file(path, input)) {
        Some(input) => Err(Error::Usage(format!(
            "{}: the output is one of the inputs ({}); name another output file",
            path.display(),
            input.display()
        ))),
        None => Ok(()),
    }
}

/// Whether `a` and `b` name one file: the same device and inode where both
/// exist (symlinks followed, hard links seen), else the same absolute path
/// with symlinks resolved as far as they exist.
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        use std::os::unix::fs::MetadataExt;
        return (ma.dev(), ma.ino()) == (mb.dev(), mb.ino());
    }
    match (canonical(a), canonical(b)) {
        (Some(a), Some(b)) => a == b,
        _ => false,
    }
}

/// `path` made absolute, with symlinks resolved in its longest existing
/// prefix (a file not yet written has no canonical path of its own).
fn canonical(path: &Path) -> Option<PathBuf> {
    let target = resolve_target(path).ok()?;
    if let Ok(full) = std::fs::canonicalize(&target) {
        return Some(full);
    }
    let folder = std::fs::canonicalize(folder_of(&target)).ok()?;
    Some(folder.join(target.file_name()?))
}

fn registry() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner())
}

fn unregister(path: &Path) {
    registry().retain(|p| p != path);
}

/// How many names `create_temporary` tries before it gives up: each is
/// 64 random bits, so a second collision means something else is wrong.
const TEMPORARY_TRIES: usize = 8;

/// Creates a new file beside `target`, `.NAME.PID.RANDOM.kind`, with
/// O_EXCL (`create_new`), registered for `remove_temporaries_and_exit`.
/// The pid alone is not unique: two containers both run lambert as pid 1
/// and may write to one shared folder; the random part tells them apart,
/// and O_EXCL means a name already taken is never opened (another name is
/// tried), so no writer's bytes land in another's file.
fn create_temporary(target: &Path, kind: &str) -> std::io::Result<(PathBuf, std::fs::File)> {
    use std::hash::{BuildHasher, Hasher};
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = target
        .file_name()
        .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name"))?;
    let mut last = None;
    for _ in 0..TEMPORARY_TRIES {
        // RandomState's keys come from the OS's random source once per
        // process; the time and a counter vary them within one.
        let mut hasher = std::collections::hash_map::RandomState::new().build_hasher();
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        hasher.write_u128(now);
        hasher.write_u32(std::process::id());
        hasher.write_u64(COUNTER.fetch_add(1, Ordering::Relaxed));
        let path = folder_of(target).join(format!(
            ".{}.{}.{:016x}.{kind}",
            name.to_string_lossy(),
            std::process::id(),
            hasher.finish()
        ));
        // Registered before it exists, so that a signal between its
        // creation and its registration cannot leave it behind.
        registry().push(path.clone());
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
        {
            Ok(file) => return Ok((path, file)),
            Err(e) => {
                // Not ours to remove: another writer's, or nothing.
                unregister(&path);
                if e.kind() != std::io::ErrorKind::AlreadyExists {
                    return Err(e);
                }
                last = Some(e);
            }
        }
    }
    Err(last.expect("at least one try"))
}

/// Writes `bytes` to `path` atomically: a temporary file beside its target
/// (symlinks followed), then a rename over it, so that a failure or a
/// signal leaves any previous file untouched and no partial or temporary
/// file behind, and of two writers at once one complete file wins. A
/// device or FIFO is written directly, as a shell redirection would.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let target = resolve_target(path)?;
    if is_special(&target) {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .open(&target)
            .map_err(|e| Error::io(path, e))?;
        return file
            .write_all(bytes)
            .and_then(|_| file.flush())
            .map_err(|e| Error::io(path, e));
    }
    let (temporary, mut file) = create_temporary(&target, "tmp").map_err(|e| Error::io(path, e))?;
    let written = file.write_all(bytes).and_then(|_| file.sync_all());
    drop(file);
    // The registry is held across the rename, so that a signal's cleanup
    // cannot run between the rename and the unregistering.
    let mut live = registry();
    let result = written.and_then(|_| std::fs::rename(&temporary, &target));
    live.retain(|p| p != &temporary);
    drop(live);
    if let Err(e) = result {
        let _ = std::fs::remove_file(&temporary);
        return Err(Error::io(path, e));
    }
    Ok(())
}
