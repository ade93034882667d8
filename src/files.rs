//! The one rule for every file lambert reads: a regular file (after
//! symlinks), read up to a size cap. A FIFO would block the read forever
//! and `/dev/zero` would fill memory; both report a size of 0, so the cap
//! bounds the read itself as well as being checked against the size first.

use std::fs::File;
use std::io::{ErrorKind, Read};
use std::path::Path;

use crate::error::{Error, Result};

/// The most lambert reads of one model file (OBJ, PLY, glTF and its
/// buffers), a gunzipped `.ply.gz`, or an EXR part.
pub const MAX_MODEL_BYTES: u64 = 4 << 30;
/// The most lambert reads of a ray or hit file: a billion rays.
pub const MAX_RAY_BYTES: u64 = 32 << 30;
/// The most lambert reads of a TOML scene or an MTL file: text written by
/// hand or by an exporter, never this large.
pub const MAX_TEXT_BYTES: u64 = 256 << 20;
/// The most an image file's compressed bytes expand, with a margin:
/// deflate's limit is about 1032 to 1, RLE's 64 to 1. A part file's or an
/// environment map's header that claims more pixels than its bytes could
/// hold at this is refused before its pixels are allocated.
pub const MAX_EXPANSION: u64 = 1100;

/// Opens `path` if it is a regular file of at most `cap` bytes; returns
/// the file and its size.
pub fn open_capped(path: &Path, cap: u64) -> Result<(File, u64)> {
    // Checked before opening: opening a FIFO blocks until a writer comes.
    check(
        path,
        &std::fs::metadata(path).map_err(|e| Error::io(path, e))?,
        cap,
    )?;
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    // And again on what was opened, in case the path changed meanwhile.
    let size = check(path, &file.metadata().map_err(|e| Error::io(path, e))?, cap)?;
    Ok((file, size))
}

/// The bytes of `path`, a regular file of at most `cap` bytes.
pub fn read_capped(path: &Path, cap: u64) -> Result<Vec<u8>> {
    let (file, size) = open_capped(path, cap)?;
    read_bounded(file, path, cap, size, "")
}

/// `read_capped` as UTF-8 text.
pub fn read_text_capped(path: &Path, cap: u64) -> Result<String> {
    String::from_utf8(read_capped(path, cap)?).map_err(|_| {
        Error::io(
            path,
            std::io::Error::new(ErrorKind::InvalidData, "not UTF-8 text"),
        )
    })
}

/// The gunzipped `bytes` of `path` (a `.gz` file), refused past `cap`
/// bytes: a small gzip file can unpack to far more than memory holds.
pub fn gunzip_capped(bytes: &[u8], path: &Path, cap: u64) -> Result<Vec<u8>> {
    let decoder = flate2::read::MultiGzDecoder::new(bytes);
    read_bounded(decoder, path, cap, 0, "unpacks to ").map_err(|e| match e {
        Error::Io { source, .. } if source.kind() != ErrorKind::FileTooLarge => {
            Error::scene(path, format!("not a readable gzip file: {source}"))
        }
        e => e,
    })
}

/// Reads `reader` to its end, at most `cap` bytes; `expected` is a size
/// hint, `what` what a reader past the cap does ("unpacks to ").
fn read_bounded(
    reader: impl Read,
    path: &Path,
    cap: u64,
    expected: u64,
    what: &str,
) -> Result<Vec<u8>> {
    let mut bytes = Vec::with_capacity(expected.min(cap) as usize);
    reader
        .take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > cap {
        return Err(too_large(path, &format!("{what}more than"), cap));
    }
    Ok(bytes)
}

/// Why `path` (after symlinks) is not a regular file, in the words a file
/// lambert reads is refused with ("not found", "not a regular file (a
/// directory)"); None when it is one. For the files a model names (its
/// images), which are checked when it loads and read later.
pub fn not_regular(path: &Path) -> Option<String> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => None,
        Ok(meta) => Some(not_regular_text(&meta)),
        Err(e) if e.kind() == ErrorKind::NotFound => Some("not found".into()),
        Err(e) => Some(format!("not readable ({e})")),
    }
}

fn not_regular_text(meta: &std::fs::Metadata) -> String {
    format!("not a regular file ({})", kind_of(meta))
}

/// Refuses anything but a regular file within the cap; returns its size.
fn check(path: &Path, meta: &std::fs::Metadata, cap: u64) -> Result<u64> {
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            ErrorKind::IsADirectory
        } else {
            ErrorKind::InvalidInput
        };
        let message = not_regular_text(meta);
        return Err(Error::io(path, std::io::Error::new(kind, message)));
    }
    if meta.len() > cap {
        return Err(too_large(
            path,
            &format!("{} bytes, more than", meta.len()),
            cap,
        ));
    }
    Ok(meta.len())
}

/// `size`: how large the file is, as a phrase ending in a comparison.
fn too_large(path: &Path, size: &str, cap: u64) -> Error {
    let message = format!(
        "{size} the {} that lambert reads of one file",
        bytes_text(cap)
    );
    Error::io(path, std::io::Error::new(ErrorKind::FileTooLarge, message))
}

/// A size in the largest binary unit it is a whole number of.
fn bytes_text(bytes: u64) -> String {
    let units = [(30, "GiB"), (20, "MiB"), (10, "KiB")];
    match units
        .iter()
        .find(|(shift, _)| bytes.is_multiple_of(1 << shift))
    {
        Some((shift, unit)) if bytes > 0 => format!("{} {unit}", bytes >> shift),
        _ => format!("{bytes} bytes"),
    }
}

/// What a file that is not a regular file is, in words.
#[cfg(unix)]
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else {
        "not a file"
    }
}

/// What a file that is not a regular file is, in words: elsewhere than
/// Unix, the standard library tells only folders apart.
#[cfg(not(unix))]
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    if meta.is_dir() {
        "a directory"
    } else {
        "not a file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cap_bounds_the_read_and_names_itself() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("five.bin");
        std::fs::write(&path, b"12345").unwrap();
        assert_eq!(read_capped(&path, 5).unwrap(), b"12345");
        let message = read_capped(&path, 4).unwrap_err().to_string();
        let expected = "five.bin: 5 bytes, more than the 4 bytes that lambert reads of one file";
        assert!(message.contains(expected), "{message}");
        // /dev/zero reports a size of 0: the read itself stops at the cap.
        let zero = File::open("/dev/zero").unwrap();
        let message = read_bounded(zero, &path, 2048, 0, "")
            .unwrap_err()
            .to_string();
        let expected = "five.bin: more than the 2 KiB that lambert reads of one file";
        assert!(message.contains(expected), "{message}");
    }
}
