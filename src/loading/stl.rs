//! STL (stereolithography), binary and ASCII: a reader of our own. The
//! mesh-loader crate reads both, but takes the triangle count from the
//! file's size without a word, refuses a file whose size is off by a byte
//! without saying where, and gives no line or byte in its errors.
//!
//! Which encoding a file is in (the header says nothing reliable:
//! SolidWorks and others begin binary headers with `solid`):
//! 1. binary when the file is exactly 84 + 50·n bytes, n being the count
//!    at bytes 80..84 (as trimesh decides). Text cannot pass this by
//!    chance: four text bytes as a count are at least 0x09090909, 7.5 GB
//!    of facets, beyond the 4 GiB a model may be;
//! 2. else ASCII when it begins with `solid`, unless its ASCII reading
//!    fails or finds no facet and it holds bytes text does not (controls
//!    other than whitespace): then binary, a `solid` header with a wrong
//!    count;
//! 3. else binary with the size rule below, if it holds such bytes; a
//!    text file that does not begin with `solid` is an error.
//!
//! The size rule, for a binary file whose count disagrees with its size:
//! when the bytes after the 84-byte header are a whole number of 50-byte
//! facets, the size says how many (writers that stream leave the count 0);
//! else, when the count's facets fit, they are read and the bytes after
//! them ignored; else the file is truncated, an error. Both readings are a
//! warning naming the file, the count and the size; no count is allocated
//! for before the size has bounded it.
//!
//! Facet normals (binary and ASCII) are not read: the geometry's own
//! (the winding's) is used, as the other formats' faces are. The binary
//! attribute bytes (VisCAM and SolidView keep a colour there; Materialise
//! Magics another) are not read either. Identical positions are welded
//! (exact f64 equality, -0 = +0), so that smooth normals average across
//! facets; triangles keep file order, degenerate ones included (trimesh
//! counts them too).

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;

use super::{Mesh, NormalMode, check_coordinate, vertex_normals};
use crate::error::{Error, Result};

/// Bytes of a binary file's header and of its triangle count.
const HEADER_BYTES: usize = 84;
/// Bytes of one binary facet: a normal, three vertices, an attribute.
const FACET_BYTES: usize = 50;

/// Reads an STL file, binary or ASCII.
pub fn load_stl(path: &Path, mode: NormalMode) -> Result<Mesh> {
    let bytes = crate::files::read_capped(path, crate::files::MAX_MODEL_BYTES)?;
    parse_stl(&bytes, path, mode)
}

/// Parses STL bytes; `path` names them in errors.
pub fn parse_stl(bytes: &[u8], path: &Path, mode: NormalMode) -> Result<Mesh> {
    let declared = declared_count(bytes);
    let whole = |n: usize| {
        n.checked_mul(FACET_BYTES)
            .is_some_and(|b| b == bytes.len() - HEADER_BYTES)
    };
    let mut mesh = match declared {
        Some(n) if whole(n) => binary(bytes, path, n)?,
        _ if begins_with_solid(bytes) => {
            let text = ascii(bytes, path);
            // A binary file with a `solid` header and a wrong count: the
            // ASCII reading fails, or finds nothing (no line ends).
            let found = text.as_ref().is_ok_and(|m| !m.triangles.is_empty());
            match declared {
                Some(n) if !found && !is_text(bytes) => binary_by_size(bytes, path, n)?,
                _ => text?,
            }
        }
        Some(n) if !is_text(bytes) => binary_by_size(bytes, path, n)?,
        _ => {
            return Err(Error::scene(
                path,
                format!(
                    "not an STL file: it does not begin with 'solid' as ASCII STL does, and {}",
                    if declared.is_none() {
                        format!(
                            "its {} bytes are fewer than a binary STL's header ({HEADER_BYTES})",
                            bytes.len()
                        )
                    } else {
                        "it is text, which binary STL is not".to_string()
                    }
                ),
            ));
        }
    };
    if mode == NormalMode::Smooth {
        mesh.normals = Some(vertex_normals(&mesh, None));
    }
    Ok(mesh)
}

/// The triangle count at bytes 80..84, if the file is that long.
fn declared_count(bytes: &[u8]) -> Option<usize> {
    let count = bytes.get(80..HEADER_BYTES)?;
    Some(u32::from_le_bytes(count.try_into().unwrap()) as usize)
}

/// Whether the file begins (after a UTF-8 byte-order mark and blanks) with
/// the word `solid`, in any case.
fn begins_with_solid(bytes: &[u8]) -> bool {
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let start = text.iter().position(|b| !is_blank(*b));
    let rest = &text[start.unwrap_or(text.len())..];
    rest.len() >= 5
        && rest[..5].eq_ignore_ascii_case(b"solid")
        && rest.get(5).is_none_or(|b| is_blank(*b))
}

/// Whether every byte could be text: no control bytes but whitespace.
/// Binary STL has them (a count's top byte is 0 below 2^24 facets).
fn is_text(bytes: &[u8]) -> bool {
    !bytes.iter().any(|&b| b < 0x20 && !is_blank(b))
}

/// Positions welded as they are read: each distinct point once.
#[derive(Default)]
struct Welder {
    mesh: Mesh,
    index: HashMap<[u64; 3], u32>,
}

impl Welder {
    fn with_capacity(facets: usize) -> Welder {
        let mut w = Welder::default();
        w.mesh.triangles.reserve(facets);
        // A closed mesh has about half as many vertices as triangles.
        w.mesh.positions.reserve(facets / 2);
        w.index.reserve(facets / 2);
        w
    }

    fn vertex(&mut self, p: DVec3) -> u32 {
        // + 0.0 turns -0 into +0, so the two weld.
        let key = (p + 0.0).to_array().map(f64::to_bits);
        let positions = &mut self.mesh.positions;
        *self.index.entry(key).or_insert_with(|| {
            positions.push(p);
            positions.len() as u32 - 1
        })
    }
}

/// A binary file whose count, `declared`, disagrees with its size (the
/// size rule).
fn binary_by_size(bytes: &[u8], path: &Path, declared: usize) -> Result<Mesh> {
    let body = bytes.len() - HEADER_BYTES;
    let (fits, rest) = (body / FACET_BYTES, body % FACET_BYTES);
    let said = format!(
        "its binary STL header declares {declared} triangles ({} bytes in all), but the file has {} bytes",
        HEADER_BYTES as u64 + FACET_BYTES as u64 * declared as u64,
        bytes.len()
    );
    let (count, reading) = if rest == 0 {
        let reading = format!(", which hold {fits} facets exactly: read {fits}, as the size says");
        (fits, reading)
    } else if declared <= fits {
        let ignored = body - declared * FACET_BYTES;
        let reading = format!(": read {declared}; the {ignored} bytes after them are ignored");
        (declared, reading)
    } else {
        return Err(Error::scene(
            path,
            format!(
                "{said}: it is truncated, ending at byte {} inside facet {fits} (from 0)",
                bytes.len()
            ),
        ));
    };
    let mut mesh = binary(bytes, path, count)?;
    let warning = format!("{}: {said}{reading}", path.display());
    mesh.warnings.push(warning);
    Ok(mesh)
}

/// The first `count` facets of a binary file (the caller has checked that
/// the file holds them).
fn binary(bytes: &[u8], path: &Path, count: usize) -> Result<Mesh> {
    let mut welder = Welder::with_capacity(count);
    for (i, facet) in bytes[HEADER_BYTES..]
        .chunks_exact(FACET_BYTES)
        .take(count)
        .enumerate()
    {
        let mut triangle = [0; 3];
        for (k, corner) in triangle.iter_mut().enumerate() {
            let mut p = [0.0; 3];
            for (axis, x) in p.iter_mut().enumerate() {
                // After the facet's normal (12 bytes), 12 bytes a vertex.
                let at = 12 + 12 * k + 4 * axis;
                let value = f32::from_le_bytes(facet[at..at + 4].try_into().unwrap());
                // Checked, then checked again for the message: formatting
                // every value was a sixth of the load.
                *x = check_coordinate(value as f64, "").map_err(|_| {
                    let byte = HEADER_BYTES + FACET_BYTES * i + at;
                    let m = check_coordinate(value as f64, &value.to_string()).unwrap_err();
                    Error::scene(path, format!("byte {byte}: facet {i}, vertex {k}: {m}"))
                })?;
            }
            *corner = welder.vertex(DVec3::from(p));
        }
        welder.mesh.triangles.push(triangle);
    }
    Ok(welder.mesh)
}

/// The words of a text, each with its line (from 1).
struct Words<'a> {
    /// The lines not yet begun.
    rest: &'a [u8],
    /// What is left of the current line.
    line_rest: &'a [u8],
    line: usize,
}

impl<'a> Words<'a> {
    fn next(&mut self) -> Option<&'a [u8]> {
        loop {
            let start = self.line_rest.iter().position(|b| !is_blank(*b));
            if let Some(start) = start {
                let word = &self.line_rest[start..];
                let end = word.iter().position(|b| is_blank(*b)).unwrap_or(word.len());
                self.line_rest = &word[end..];
                return Some(&word[..end]);
            }
            if self.rest.is_empty() {
                return None;
            }
            let (end, next) = super::line_end(self.rest);
            self.line_rest = &self.rest[..end];
            self.rest = &self.rest[next..];
            self.line += 1;
        }
    }

    /// Skips the rest of the current line (a solid's name).
    fn skip_line(&mut self) {
        self.line_rest = &[];
    }
}

/// ASCII whitespace, and the vertical tab (which C's isspace counts).
fn is_blank(b: u8) -> bool {
    b.is_ascii_whitespace() || b == 0x0b
}

/// A word as quoted in a message (at most 40 characters).
fn quoted(word: &[u8]) -> String {
    let text = String::from_utf8_lossy(word);
    match text.char_indices().nth(40) {
        Some((end, _)) => format!("'{}…'", &text[..end]),
        None => format!("'{text}'"),
    }
}

/// An ASCII file: one or more `solid … endsolid` blocks of facets.
fn ascii(bytes: &[u8], path: &Path) -> Result<Mesh> {
    let mut text = Ascii {
        words: Words {
            rest: bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes),
            line_rest: &[],
            line: 0,
        },
        path,
    };
    let mut welder = Welder::default();
    let mut warnings = Vec::new();
    'solids: while let Some(word) = text.words.next() {
        if !is(word, "solid") {
            // Only after a first solid: the file began with one.
            warnings.push(format!(
                "{}:{}: {} after the last endsolid is ignored",
                path.display(),
                text.words.line,
                quoted(word)
            ));
            break;
        }
        text.words.skip_line();
        let solid_line = text.words.line;
        loop {
            let Some(word) = text.words.next() else {
                warnings.push(format!(
                    "{}:{solid_line}: the solid begun here has no endsolid; its facets are read",
                    path.display()
                ));
                break 'solids;
            };
            if is(word, "endsolid") {
                text.words.skip_line();
                break;
            }
            if !is(word, "facet") {
                let m = format!("expected 'facet' or 'endsolid', found {}", quoted(word));
                return Err(text.fail(m));
            }
            let triangle = text.facet(welder.mesh.triangles.len(), &mut welder)?;
            welder.mesh.triangles.push(triangle);
        }
    }
    welder.mesh.warnings = warnings;
    Ok(welder.mesh)
}

fn is(word: &[u8], keyword: &str) -> bool {
    word.eq_ignore_ascii_case(keyword.as_bytes())
}

/// An ASCII file being read.
struct Ascii<'a> {
    words: Words<'a>,
    path: &'a Path,
}

impl Ascii<'_> {
    /// An error at the current line.
    fn fail(&self, message: String) -> Error {
        Error::Line {
            path: self.path.to_path_buf(),
            line: self.words.line,
            message,
        }
    }

    /// The next word of facet `facet`, which must be `keyword`.
    fn expect(&mut self, facet: usize, keyword: &str, what: &str) -> Result<()> {
        let found = match self.words.next() {
            Some(w) if is(w, keyword) => return Ok(()),
            Some(w) => format!("found {}", quoted(w)),
            None => "the file ends inside it".to_string(),
        };
        Err(self.fail(format!(
            "facet {facet}: expected '{keyword}' {what}, {found}"
        )))
    }

    /// The rest of a facet, after its word `facet`: its corners, welded.
    fn facet(&mut self, facet: usize, welder: &mut Welder) -> Result<[u32; 3]> {
        self.expect(facet, "normal", "after 'facet'")?;
        // The normal's three values are not read (nor checked: some
        // writers put nan or -1.#IND there); the winding gives it.
        for _ in 0..3 {
            self.words.next();
        }
        self.expect(facet, "outer", "after the normal")?;
        self.expect(facet, "loop", "after 'outer'")?;
        let mut triangle = [0; 3];
        for (k, corner) in triangle.iter_mut().enumerate() {
            self.expect(facet, "vertex", &format!("(vertex {k} of 3)"))?;
            let what = format!("facet {facet}, vertex {k}");
            let mut p = [0.0; 3];
            for x in &mut p {
                let Some(w) = self.words.next() else {
                    return Err(self.fail(format!("{what}: the file ends inside it")));
                };
                let value = std::str::from_utf8(w)
                    .ok()
                    .and_then(|t| t.parse::<f64>().ok())
                    .ok_or_else(|| self.fail(format!("{what}: {} is not a number", quoted(w))))?;
                *x = check_coordinate(value, &String::from_utf8_lossy(w))
                    .map_err(|m| self.fail(format!("{what}: {m}")))?;
            }
            *corner = welder.vertex(DVec3::from(p));
        }
        self.expect(
            facet,
            "endloop",
            "after three vertices (STL facets are triangles)",
        )?;
        self.expect(facet, "endfacet", "after 'endloop'")?;
        Ok(triangle)
    }
}
