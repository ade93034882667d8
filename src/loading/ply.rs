//! PLY (the Stanford repository's format): ascii, binary_little_endian and
//! binary_big_endian, gzipped when the name ends in `.gz`.
//!
//! A reader of our own rather than ply-rs-bw: it reads the two elements a
//! renderer needs straight into the mesh (ply-rs-bw builds a map of
//! properties per element, and allocates for the counts a header claims),
//! checks every count against what the file can hold before allocating,
//! and names the element, line or byte at fault.
//!
//! `vertex` gives `x y z` (float or double, or any other numeric type) and,
//! when present, `nx ny nz`; `face` gives a `vertex_indices` or
//! `vertex_index` list of any integer types, fan-triangulated in file order
//! as OBJ's polygons are, in either order of the two elements. Other
//! elements and properties are read past, named in one warning.

use std::path::Path;

use glam::DVec3;

use super::material::{ImageSource, MaterialDesc, TextureUse};
use super::{Mesh, NormalMode, check_coordinate, corner_values, vertex_normals};
use crate::error::{Error, Result};

mod attributes;
use attributes::{Attributes, COLOUR_NAMES, colour};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    /// 64-bit integers: not in the original spec; trimesh reads them.
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "int64" => Scalar::I64,
            "uint64" => Scalar::U64,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Debug)]
struct Property {
    name: String,
    /// For a list: the type of its count.
    count: Option<Scalar>,
    value: Scalar,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

impl Element {
    /// The fewest bytes one element takes in a binary file.
    fn min_bytes(&self) -> usize {
        self.properties
            .iter()
            .map(|p| p.count.unwrap_or(p.value).size())
            .sum()
    }

    fn property(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name)
    }
}

/// Reads a PLY file (gunzipped first when its name ends in `.gz`).
pub fn load_ply(path: &Path, mode: NormalMode) -> Result<Mesh> {
    let raw = crate::files::read_capped(path, crate::files::MAX_MODEL_BYTES)?;
    let gzipped = path.to_string_lossy().to_lowercase().ends_with(".gz");
    let bytes = if gzipped {
        crate::files::gunzip_capped(&raw, path, crate::files::MAX_MODEL_BYTES)?
    } else {
        raw
    };
    parse_ply(&bytes, path, mode)
}

/// Parses PLY bytes; `path` names them in errors.
pub fn parse_ply(bytes: &[u8], path: &Path, mode: NormalMode) -> Result<Mesh> {
    let (encoding, elements, body, header_lines, texture_file) = parse_header(bytes, path)?;
    let vertex = elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| Error::scene(path, "no vertex element in the header"))?;
    let face = elements.iter().position(|e| e.name == "face");
    let fail = |message: String| Error::scene(path, message);
    for name in ["x", "y", "z"] {
        if elements[vertex].property(name).is_none() {
            return Err(fail(format!("the vertex element has no '{name}' property")));
        }
        if elements[vertex].properties[elements[vertex].property(name).unwrap()]
            .count
            .is_some()
        {
            return Err(fail(format!("vertex property '{name}' is a list")));
        }
    }
    let indices = match face {
        Some(f) => {
            let element = &elements[f];
            let index = element
                .property("vertex_indices")
                .or_else(|| element.property("vertex_index"))
                .ok_or_else(|| {
                    fail("the face element has no vertex_indices or vertex_index list".into())
                })?;
            let property = &element.properties[index];
            if property.count.is_none() || !property.value.is_integer() {
                return Err(fail(format!(
                    "face property '{}' must be a list of integers",
                    property.name
                )));
            }
            Some(index)
        }
        None => None,
    };
    let attributes = Attributes::of(&elements, vertex, face).map_err(fail)?;
    // Every count checked against what the rest of the file can hold,
    // before anything is allocated for it.
    match encoding {
        Encoding::Ascii => {
            let lines = super::byte_lines(body)
                .filter(|l| !l.iter().all(u8::is_ascii_whitespace))
                .count();
            let claimed: usize = elements
                .iter()
                .map(|e| e.count)
                .fold(0, usize::saturating_add);
            if claimed > lines {
                return Err(fail(format!(
                    "the header declares {claimed} elements, but only {lines} lines follow it"
                )));
            }
        }
        _ => {
            let needed = elements
                .iter()
                .map(|e| e.count.saturating_mul(e.min_bytes()))
                .fold(0, usize::saturating_add);
            if needed > body.len() {
                let e = elements
                    .iter()
                    .max_by_key(|e| e.count.saturating_mul(e.min_bytes()))
                    .unwrap();
                return Err(fail(format!(
                    "the header declares {} '{}' elements, which need at least {needed} bytes in all, but {} follow the header",
                    e.count,
                    e.name,
                    body.len()
                )));
            }
        }
    }

    let mut reader = Reader {
        encoding,
        body,
        at: 0,
        line: header_lines,
        path,
        tokens: Vec::new(),
        token: 0,
        surplus: None,
    };
    let mut mesh = Mesh::default();
    let mut normals: Vec<DVec3> = Vec::new();
    let normal_slots = ["nx", "ny", "nz"].map(|n| elements[vertex].property(n));
    let has_normals = normal_slots.iter().all(Option::is_some);
    let xyz = ["x", "y", "z"].map(|n| elements[vertex].property(n).unwrap());
    let mut values: Vec<f64> = Vec::new();
    let mut list: Vec<i64> = Vec::new();
    let mut face_uvs: Vec<f32> = Vec::new();
    // The first face whose texcoord list does not fit its corners.
    let mut bad_texcoord: Option<(usize, usize, usize)> = None;
    // Per vertex: colours and texture coordinates; per triangle: the
    // face's colours and texture coordinates.
    let mut vertex_colors: Vec<[f32; 4]> = Vec::new();
    let mut vertex_uvs: Vec<[f32; 2]> = Vec::new();
    let mut triangle_colors: Vec<[[f32; 4]; 3]> = Vec::new();
    let mut triangle_uvs: Vec<[[f32; 2]; 3]> = Vec::new();
    // Faces read before the vertices (a header may declare them first):
    // the largest index among them, the face and where it was, checked
    // once the vertices are counted.
    let mut unresolved: Option<(i64, usize, Location)> = None;
    for (e, element) in elements.iter().enumerate() {
        if e == vertex {
            mesh.positions.reserve(element.count);
        }
        // A binary element without properties takes no bytes: its count,
        // however large, is nothing to read (looping over it could take
        // minutes, as the byte check above cannot bound it).
        if element.properties.is_empty() && encoding != Encoding::Ascii {
            continue;
        }
        for i in 0..element.count {
            reader.begin_element()?;
            let what = || format!("{} {i}", element.name);
            values.clear();
            list.clear();
            face_uvs.clear();
            for (p, property) in element.properties.iter().enumerate() {
                match property.count {
                    None => values.push(reader.scalar(property.value, &what)?),
                    Some(count_type) => {
                        let count = reader.scalar(count_type, &what)?;
                        if !(0.0..=1e9).contains(&count) || count.fract() != 0.0 {
                            return Err(reader
                                .error(format!("{}: list length {count} is not a count", what())));
                        }
                        let keep = Some(e) == face && Some(p) == indices;
                        let keep_uvs = Some(e) == face && Some(p) == attributes.face_uvs;
                        for _ in 0..count as usize {
                            let v = reader.scalar(property.value, &what)?;
                            if keep {
                                list.push(v as i64);
                            } else if keep_uvs {
                                face_uvs.push(v as f32);
                            }
                        }
                        values.push(f64::NAN);
                    }
                }
            }
            reader.end_element(&what);
            if e == vertex {
                let mut p = [0.0; 3];
                for (axis, &slot) in xyz.iter().enumerate() {
                    let v = values[slot];
                    p[axis] = check_coordinate(v, &v.to_string())
                        .map_err(|m| reader.error(format!("{}: {m}", what())))?;
                }
                mesh.positions.push(DVec3::from(p));
                if has_normals {
                    normals.push(DVec3::from(normal_slots.map(|s| values[s.unwrap()])));
                }
                if let Some(slots) = &attributes.vertex_colors {
                    vertex_colors.push(colour(slots, &values));
                }
                if let Some([u, v]) = attributes.vertex_uvs {
                    vertex_uvs.push([values[u] as f32, 1.0 - values[v] as f32]);
                }
            } else if Some(e) == face {
                if list.len() < 3 {
                    return Err(reader.error(format!(
                        "{}: a face needs at least 3 vertices, this one has {}",
                        what(),
                        list.len()
                    )));
                }
                let count = mesh.positions.len() as i64;
                let read_vertices = e > vertex;
                if let Some(bad) = list
                    .iter()
                    .find(|&&v| v < 0 || (read_vertices && v >= count))
                {
                    return Err(reader.error(out_of_range(&what(), *bad, count)));
                }
                let largest = list.iter().copied().max().unwrap_or(0);
                if !read_vertices && unresolved.is_none_or(|(v, _, _)| largest > v) {
                    unresolved = Some((largest, i, reader.location()));
                }
                if attributes.face_uvs.is_some() && face_uvs.len() != 2 * list.len() {
                    bad_texcoord.get_or_insert((i, face_uvs.len(), list.len()));
                    face_uvs.clear();
                    face_uvs.resize(2 * list.len(), 0.0);
                }
                let uv = |k: usize| [face_uvs[2 * k], 1.0 - face_uvs[2 * k + 1]];
                let face_colour = attributes.face_colors.as_ref().map(|s| colour(s, &values));
                for k in 1..list.len() - 1 {
                    mesh.triangles
                        .push([list[0], list[k], list[k + 1]].map(|v| v as u32));
                    if attributes.face_uvs.is_some() {
                        triangle_uvs.push([uv(0), uv(k), uv(k + 1)]);
                    }
                    if let Some(c) = face_colour {
                        triangle_colors.push([c; 3]);
                    }
                }
            }
        }
    }
    let count = mesh.positions.len() as i64;
    if let Some((bad, i, at)) = unresolved.filter(|(v, _, _)| *v >= count) {
        return Err(reader.error_at(at, out_of_range(&format!("face {i}"), bad, count)));
    }
    mesh.skipped_lines = elements
        .iter()
        .filter(|e| e.name == "edge")
        .map(|e| e.count)
        .sum();
    mesh.warnings.extend(reader.surplus_warning());
    mesh.warnings
        .extend(ignored(&elements, vertex, face, &attributes, path));
    if let Some((i, count, corners)) = bad_texcoord {
        mesh.warnings.push(format!(
            "{}: face {i}: texcoord holds {count} numbers for {corners} corners (2 a corner); \
             such faces read texture coordinates (0, 0)",
            path.display()
        ));
    }
    // Vertex colours win over face colours (as MeshLab shows them).
    if attributes.vertex_colors.is_some() {
        mesh.colors = Some(corner_values(&mesh.triangles, &vertex_colors));
    } else if attributes.face_colors.is_some() {
        mesh.colors = Some(triangle_colors);
    }
    if attributes.vertex_uvs.is_some() {
        mesh.uvs = Some(corner_values(&mesh.triangles, &vertex_uvs));
    } else if attributes.face_uvs.is_some() {
        mesh.uvs = Some(triangle_uvs);
    }
    let texture = texture_file.and_then(|name| {
        let file = path.parent().unwrap_or(Path::new(".")).join(&name);
        if let Some(why) = crate::files::not_regular(&file) {
            mesh.warnings.push(format!(
                "{}: its TextureFile '{name}' is {why} ({}); the faces keep their colours",
                path.display(),
                file.display()
            ));
            return None;
        }
        mesh.images.push(ImageSource::File(file));
        Some(TextureUse {
            image: 0,
            sampler: Default::default(),
            transform: super::material::IDENTITY_UV_TRANSFORM,
        })
    });
    // Colours or a texture as given: one white material, not the default
    // grey.
    if mesh.colors.is_some() || texture.is_some() {
        mesh.materials = vec![MaterialDesc {
            base_color_texture: texture,
            ..MaterialDesc::default()
        }];
        mesh.face_materials = vec![Some(0); mesh.triangles.len()];
    }
    if mode == NormalMode::Smooth {
        let given = has_normals.then_some(&normals[..]);
        mesh.file_normals = has_normals;
        mesh.normals = Some(vertex_normals(&mesh, given));
    }
    Ok(mesh)
}

fn out_of_range(what: &str, index: i64, count: i64) -> String {
    format!(
        "{what}: vertex index {index} is out of range: the file has {count} vertices (indices from 0)"
    )
}

/// One warning naming the elements and properties the file has that
/// lambert does not read (colours, texture coordinates, edges, …).
fn ignored(
    elements: &[Element],
    vertex: usize,
    face: Option<usize>,
    attributes: &Attributes,
    path: &Path,
) -> Option<String> {
    let mut skipped = Vec::new();
    for (e, element) in elements.iter().enumerate() {
        let used: Vec<&str> = if e == vertex {
            let mut used = vec!["x", "y", "z", "nx", "ny", "nz"];
            if attributes.vertex_colors.is_some() {
                used.extend(COLOUR_NAMES);
            }
            if let Some(slots) = attributes.vertex_uvs {
                used.extend(slots.map(|p| element.properties[p].name.as_str()));
            }
            used
        } else if Some(e) == face {
            let mut used = vec!["vertex_indices", "vertex_index"];
            if attributes.face_colors.is_some() {
                used.extend(COLOUR_NAMES);
            }
            if attributes.face_uvs.is_some() {
                used.push("texcoord");
            }
            used
        } else {
            skipped.push(format!("element {}", element.name));
            continue;
        };
        let names: Vec<&str> = element
            .properties
            .iter()
            .map(|p| p.name.as_str())
            .filter(|name| !used.contains(name))
            .collect();
        if !names.is_empty() {
            skipped.push(format!("{} {}", element.name, names.join(" ")));
        }
    }
    (!skipped.is_empty()).then(|| {
        format!(
            "{}: ignored (lambert reads vertex x y z nx ny nz, colours and texture coordinates, \
             and face vertex_indices, texcoord and colours): {}",
            path.display(),
            skipped.join(", ")
        )
    })
}

/// The encoding, the elements, the body, the header's line count, and the
/// image a `comment TextureFile NAME` line names.
type Header<'a> = (Encoding, Vec<Element>, &'a [u8], usize, Option<String>);

fn parse_header<'a>(bytes: &'a [u8], path: &Path) -> Result<Header<'a>> {
    let mut at = 0;
    let mut line_number = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut texture_file = None;
    // Whether the lines end in a lone CR (classic Mac OS).
    let mut lone_cr = false;
    loop {
        if at >= bytes.len() {
            return Err(Error::scene(path, "the header has no end_header line"));
        }
        let start = at;
        let (end, next) = super::line_end(&bytes[start..]);
        let raw = &bytes[start..start + end];
        at = start + next;
        line_number += 1;
        let fail = |message: String| Error::Line {
            path: path.to_path_buf(),
            line: line_number,
            message,
        };
        let text = std::str::from_utf8(raw).map_err(|_| fail("the header is not text".into()))?;
        if line_number == 1 {
            if text.trim() != "ply" {
                return Err(fail("not a PLY file: the first line must be 'ply'".into()));
            }
            lone_cr = &bytes[start + end..at] == b"\r";
            continue;
        }
        let mut tokens = text.split_whitespace();
        match tokens.next() {
            Some("format") => {
                encoding = Some(match (tokens.next(), tokens.next()) {
                    (Some("ascii"), Some("1.0")) => Encoding::Ascii,
                    (Some("binary_little_endian"), Some("1.0")) => Encoding::LittleEndian,
                    (Some("binary_big_endian"), Some("1.0")) => Encoding::BigEndian,
                    _ => {
                        return Err(fail(format!(
                            "unknown format line '{text}': use ascii, binary_little_endian or binary_big_endian 1.0"
                        )));
                    }
                });
            }
            Some("element") => {
                let (Some(name), Some(count)) = (tokens.next(), tokens.next()) else {
                    return Err(fail("an element line needs a name and a count".into()));
                };
                let count: usize = count
                    .parse()
                    .map_err(|_| fail(format!("element '{name}': '{count}' is not a count")))?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            Some("property") => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| fail("a property before any element".into()))?;
                let words: Vec<&str> = tokens.collect();
                let scalar = |name: &str| {
                    Scalar::parse(name)
                        .ok_or_else(|| fail(format!("unknown property type '{name}'")))
                };
                let property = match words.as_slice() {
                    ["list", count, value, name] => Property {
                        name: name.to_string(),
                        count: Some(scalar(count)?),
                        value: scalar(value)?,
                    },
                    [value, name] if *value != "list" => Property {
                        name: name.to_string(),
                        count: None,
                        value: scalar(value)?,
                    },
                    _ => return Err(fail(format!("malformed property line '{text}'"))),
                };
                if let Some(count) = property.count
                    && !count.is_integer()
                {
                    return Err(fail(format!(
                        "list '{}': its count must be an integer type",
                        property.name
                    )));
                }
                element.properties.push(property);
            }
            Some("end_header") => {
                // A binary body may begin with a \n byte: no part of a
                // lone CR ending.
                if lone_cr {
                    at = start + end + 1;
                }
                break;
            }
            // MeshLab's convention; the name may hold spaces.
            Some("comment") if tokens.next() == Some("TextureFile") => {
                let name = text.trim().splitn(3, char::is_whitespace).nth(2);
                texture_file = name.map(|n| n.trim().to_string()).filter(|n| !n.is_empty());
            }
            Some("comment" | "obj_info") | None => {}
            Some(other) => return Err(fail(format!("unknown header line '{other}'"))),
        }
    }
    let encoding = encoding.ok_or_else(|| Error::scene(path, "the header has no format line"))?;
    Ok((encoding, elements, &bytes[at..], line_number, texture_file))
}

/// Reads values from the body: whitespace-separated numbers, one element
/// a line (ascii), or packed bytes (binary).
struct Reader<'a> {
    encoding: Encoding,
    body: &'a [u8],
    at: usize,
    /// Ascii: the line last read, counted in the whole file.
    line: usize,
    path: &'a Path,
    tokens: Vec<&'a str>,
    token: usize,
    /// Ascii: lines with more values than the header declares, the first
    /// one's location and message, and how many there were.
    surplus: Option<(Location, String, usize)>,
}

/// Where an element was read: its line (ascii) and byte of the body.
#[derive(Clone, Copy, Debug)]
struct Location {
    line: usize,
    at: usize,
}

impl<'a> Reader<'a> {
    fn location(&self) -> Location {
        Location {
            line: self.line,
            at: self.at,
        }
    }

    fn error(&self, message: String) -> Error {
        self.error_at(self.location(), message)
    }

    fn error_at(&self, location: Location, message: String) -> Error {
        match self.encoding {
            Encoding::Ascii => Error::Line {
                path: self.path.to_path_buf(),
                line: location.line,
                message,
            },
            _ => Error::scene(
                self.path,
                format!("byte {} of the body: {message}", location.at),
            ),
        }
    }

    /// The warning for lines with more values than declared, if any.
    fn surplus_warning(&self) -> Option<String> {
        let (location, message, lines) = self.surplus.as_ref()?;
        let also = match lines {
            1 => String::new(),
            n => format!(" (on {n} lines in all)"),
        };
        Some(format!(
            "{}:{}: {message}; the extra values are ignored{also}",
            self.path.display(),
            location.line
        ))
    }

    /// Ascii: takes the next non-blank line's tokens.
    fn begin_element(&mut self) -> Result<()> {
        if self.encoding != Encoding::Ascii {
            return Ok(());
        }
        loop {
            if self.at >= self.body.len() {
                return Err(
                    self.error("the file ends before every element the header declares".into())
                );
            }
            let (end, next) = super::line_end(&self.body[self.at..]);
            let raw = &self.body[self.at..self.at + end];
            self.at += next;
            self.line += 1;
            let text = std::str::from_utf8(raw).map_err(|_| self.error("not text".into()))?;
            self.tokens = text.split_whitespace().collect();
            self.token = 0;
            if !self.tokens.is_empty() {
                return Ok(());
            }
        }
    }

    /// Ascii: values past the declared ones are ignored (VCGLib writes
    /// such lines), with one warning for the file.
    fn end_element(&mut self, what: &dyn Fn() -> String) {
        if self.encoding == Encoding::Ascii && self.token != self.tokens.len() {
            match &mut self.surplus {
                Some((_, _, lines)) => *lines += 1,
                None => {
                    let message = format!(
                        "{}: {} values on the line, the header declares {}",
                        what(),
                        self.tokens.len(),
                        self.token
                    );
                    self.surplus = Some((self.location(), message, 1));
                }
            }
        }
    }

    fn scalar(&mut self, kind: Scalar, what: &dyn Fn() -> String) -> Result<f64> {
        if self.encoding == Encoding::Ascii {
            let Some(token) = self.tokens.get(self.token).copied() else {
                return Err(
                    self.error(format!("{}: fewer values than the header declares", what()))
                );
            };
            self.token += 1;
            let value: f64 = token
                .parse()
                .map_err(|_| self.error(format!("{}: '{token}' is not a number", what())))?;
            if kind.is_integer() && value.fract() != 0.0 {
                return Err(self.error(format!("{}: '{token}' is not an integer", what())));
            }
            return Ok(value);
        }
        let size = kind.size();
        let Some(raw) = self.body.get(self.at..self.at + size) else {
            return Err(self.error(format!("{}: the file ends inside it (truncated)", what())));
        };
        self.at += size;
        let mut b = [0u8; 8];
        b[..size].copy_from_slice(raw);
        if self.encoding == Encoding::BigEndian {
            b[..size].reverse();
        }
        Ok(match kind {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::I64 => i64::from_le_bytes(b) as f64,
            Scalar::U64 => u64::from_le_bytes(b) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
}
