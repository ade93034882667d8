//! Wavefront OBJ loading, with the `Kd` of its MTL materials.
//!
//! A small parser of our own rather than tobj: errors must name the file and
//! line at fault, and the triangle order must be exactly the file's (polygons
//! fan-triangulated as (v0,v1,v2), (v0,v2,v3), …), because primitive ids in
//! `lambert trace` output are defined by it.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::{Mesh, NormalMode, area_weighted_normals, check_coordinate};
use crate::error::{Error, Result};

/// Reads an OBJ file and the MTL files it names.
pub fn load_obj(path: &Path, mode: NormalMode) -> Result<Mesh> {
    let text = crate::files::read_capped(path, crate::files::MAX_MODEL_BYTES)?;
    parse_obj(&String::from_utf8_lossy(&text), path, mode)
}

/// The materials of an OBJ's MTL files, by name, as they are named.
#[derive(Default)]
pub struct Materials {
    index: HashMap<String, u32>,
    albedo: Vec<[f32; 3]>,
    /// What was read but not understood, each naming its file and line.
    warnings: Vec<String>,
}

/// The statements of OBJ or MTL text, each with the number of the line it
/// starts on: a line ending in `\` continues on the next (the OBJ spec),
/// joined as one line. A UTF-8 byte-order mark (some Windows exporters
/// write one) is not part of the first statement.
fn statements(text: &str) -> impl Iterator<Item = (usize, Cow<'_, str>)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text.lines().enumerate();
    std::iter::from_fn(move || {
        let (index, first) = lines.next()?;
        let mut statement = Cow::Borrowed(first);
        while let Some(head) = statement.trim_end().strip_suffix('\\') {
            let head = head.to_string();
            let Some((_, next)) = lines.next() else {
                statement = Cow::Owned(head);
                break;
            };
            statement = Cow::Owned(format!("{head} {next}"));
        }
        Some((index + 1, statement))
    })
}

/// Reads `mtl` (relative to the OBJ's folder) into `materials`: `newmtl
/// NAME` and its `Kd` (`parse_mtl`); everything else is ignored. A file
/// that cannot be read (missing, not a regular file, too large) is a
/// warning; a malformed `Kd` an error at its line.
fn load_mtl(mtl: &Path, materials: &mut Materials) -> Result<()> {
    let bytes = match crate::files::read_capped(mtl, crate::files::MAX_TEXT_BYTES) {
        Ok(b) => b,
        // Missing, a FIFO, a device, too large: the faces can still render.
        Err(e) => {
            let reason = match e {
                Error::Io { source, .. } => source.to_string(),
                e => e.to_string(),
            };
            materials.warnings.push(format!(
                "{}: material library not read ({reason}); its faces get the default albedo",
                mtl.display()
            ));
            return Ok(());
        }
    };
    parse_mtl(&String::from_utf8_lossy(&bytes), mtl, materials)
}

/// Parses MTL text into `materials` (`load_mtl`'s rules); `mtl` names it
/// in errors. `Kd r [g b]` is linear RGB (g and b repeat r if omitted, as
/// the spec says), `Kd xyz X [Y Z]` CIE XYZ; `Kd spectral` is a warning.
pub fn parse_mtl(text: &str, mtl: &Path, materials: &mut Materials) -> Result<()> {
    let mut current: Option<u32> = None;
    for (line_number, line) in statements(text) {
        let fail = |message: String| Error::Line {
            path: mtl.to_path_buf(),
            line: line_number,
            message,
        };
        let line = line.split('#').next().unwrap_or("");
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("newmtl") => {
                let name = tokens
                    .next()
                    .ok_or_else(|| fail("newmtl needs a material name".into()))?;
                let id = materials.albedo.len() as u32;
                materials.albedo.push([0.8; 3]);
                // A later definition of a name wins, as in most readers.
                materials.index.insert(name.to_string(), id);
                current = Some(id);
            }
            Some("Kd") => {
                let id = current.ok_or_else(|| fail("Kd before any newmtl".into()))?;
                let mut tokens = tokens.peekable();
                let space = tokens.next_if(|t| matches!(*t, "xyz" | "spectral"));
                if space == Some("spectral") {
                    materials.warnings.push(format!(
                        "{}:{line_number}: Kd spectral is not supported; the material gets \
                         the default albedo",
                        mtl.display()
                    ));
                    continue;
                }
                let kd = parse_colour(tokens).map_err(fail)?;
                materials.albedo[id as usize] = if space == Some("xyz") {
                    let (rgb, clamped) = xyz_to_linear_srgb(kd);
                    if clamped {
                        materials.warnings.push(format!(
                            "{}:{line_number}: Kd xyz {kd:?} lies outside sRGB; its negative \
                             components are clamped to 0",
                            mtl.display()
                        ));
                    }
                    rgb
                } else {
                    kd.map(|c| c as f32)
                };
            }
            _ => {}
        }
    }
    Ok(())
}

/// `r [g b]`: one number repeated, or three; each finite and non-negative.
fn parse_colour<'a>(tokens: impl Iterator<Item = &'a str>) -> Result<[f64; 3], String> {
    let mut values = Vec::with_capacity(3);
    for token in tokens.take(3) {
        let v: f64 = token
            .parse()
            .map_err(|_| format!("Kd: '{token}' is not a number"))?;
        if !v.is_finite() || v < 0.0 {
            return Err(format!("Kd: {token} must be finite and non-negative"));
        }
        values.push(v);
    }
    match values[..] {
        [v] => Ok([v; 3]),
        [r, g, b] => Ok([r, g, b]),
        _ => Err(format!(
            "Kd needs 1 or 3 numbers (r [g b]), found {}",
            values.len()
        )),
    }
}

/// CIE XYZ to linear sRGB (IEC 61966-2-1's D65 matrix), negative
/// components clamped to 0; whether that clamped a colour outside sRGB's
/// gamut.
fn xyz_to_linear_srgb([x, y, z]: [f64; 3]) -> ([f32; 3], bool) {
    let rgb = [
        3.2404542 * x - 1.5371385 * y - 0.4985314 * z,
        -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
        0.0556434 * x - 0.2040259 * y + 1.0572252 * z,
    ];
    // The matrix's seven digits leave a primary's other components a few
    // 1e-8 from 0: rounding, not a colour outside the gamut.
    let rounding = 1e-5 * rgb.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    let clamped = rgb.iter().any(|&c| c < -rounding);
    (rgb.map(|c| c.max(0.0) as f32), clamped)
}

/// The MTL files an `mtllib` statement names, relative to the OBJ's folder.
fn mtl_paths<'a>(obj: &Path, tokens: impl Iterator<Item = &'a str>) -> Vec<PathBuf> {
    let folder = obj.parent().unwrap_or(Path::new("."));
    tokens.map(|t| folder.join(t)).collect()
}

/// A face corner: position index and, if given, normal index (None
/// inside where it names a normal that is not defined).
type Corner = (u32, Option<Option<u32>>);

/// Faces of one kind skipped or changed: how many, and the first's line.
#[derive(Default)]
struct Skipped {
    count: usize,
    first_line: usize,
}

impl Skipped {
    fn add(&mut self, line: usize) {
        if self.count == 0 {
            self.first_line = line;
        }
        self.count += 1;
    }

    /// One warning for the kind, `what` saying what the faces were.
    fn warn(&self, path: &Path, what: &str, warnings: &mut Vec<String>) {
        if self.count > 0 {
            let faces = if self.count == 1 { "face" } else { "faces" };
            warnings.push(format!(
                "{}:{}: {} {faces} {what} (the first on this line)",
                path.display(),
                self.first_line,
                self.count
            ));
        }
    }
}

/// Parses OBJ text; `path` names it in errors and anchors its `mtllib`s.
pub fn parse_obj(text: &str, path: &Path, mode: NormalMode) -> Result<Mesh> {
    let mut mesh = Mesh::default();
    let mut materials = Materials::default();
    let mut uses_materials = false;
    let mut current: Option<u32> = None;
    let mut unknown: Vec<String> = Vec::new();
    let mut vertex_normals: Vec<DVec3> = Vec::new();
    let mut corner_normals: Vec<[Option<u32>; 3]> = Vec::new();
    let mut corners: Vec<Corner> = Vec::new();
    let mut short_faces = Skipped::default();
    let mut unknown_normals = Skipped::default();
    for (line_number, line) in statements(text) {
        let fail = |message: String| Error::Line {
            path: path.to_path_buf(),
            line: line_number,
            message,
        };
        let line = line.split('#').next().unwrap_or("");
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("v") => mesh
                .positions
                .push(parse_vector(&mut tokens).map_err(fail)?),
            Some("vn") => vertex_normals.push(parse_vector(&mut tokens).map_err(fail)?),
            Some("mtllib") => {
                for mtl in mtl_paths(path, tokens) {
                    load_mtl(&mtl, &mut materials)?;
                }
            }
            Some("usemtl") => {
                uses_materials = true;
                let name = tokens.next().unwrap_or("");
                current = materials.index.get(name).copied();
                if current.is_none() && !unknown.iter().any(|n| n == name) {
                    unknown.push(name.to_string());
                    mesh.warnings.push(format!(
                        "{}:{line_number}: unknown material '{name}'; its faces get the default albedo",
                        path.display()
                    ));
                }
            }
            Some("f") => {
                corners.clear();
                for token in tokens {
                    corners.push(
                        parse_corner(token, mesh.positions.len(), vertex_normals.len())
                            .map_err(fail)?,
                    );
                }
                if corners.len() < 3 {
                    short_faces.add(line_number);
                    continue;
                }
                if corners.iter().any(|c| c.1 == Some(None)) {
                    unknown_normals.add(line_number);
                    corners.iter_mut().for_each(|c| c.1 = None);
                }
                for k in 1..corners.len() - 1 {
                    let fan = [corners[0], corners[k], corners[k + 1]];
                    mesh.triangles.push(fan.map(|c| c.0));
                    corner_normals.push(fan.map(|c| c.1.flatten()));
                    mesh.face_materials.push(current);
                }
            }
            // Counted for the message of a file without triangles.
            Some("l" | "p") => mesh.skipped_lines += 1,
            // Names, groups, texture coordinates: nothing a Lambertian
            // triangle renderer uses.
            _ => {}
        }
    }
    mesh.warnings.append(&mut materials.warnings);
    short_faces.warn(
        path,
        "with fewer than 3 vertices skipped",
        &mut mesh.warnings,
    );
    unknown_normals.warn(
        path,
        "naming normals that are not defined (no such vn): those normals are dropped and \
         computed ones used",
        &mut mesh.warnings,
    );
    if mode == NormalMode::Smooth {
        mesh.file_normals = !corner_normals.is_empty()
            && corner_normals.iter().all(|c| c.iter().all(Option::is_some));
        mesh.normals = Some(smooth_normals(&mesh, &vertex_normals, &corner_normals));
    }
    if uses_materials {
        mesh.materials = materials.albedo;
    } else {
        mesh.face_materials.clear();
    }
    Ok(mesh)
}

fn parse_vector<'a>(tokens: &mut impl Iterator<Item = &'a str>) -> Result<DVec3, String> {
    let mut v = [0.0; 3];
    for (i, slot) in v.iter_mut().enumerate() {
        let token = tokens
            .next()
            .ok_or_else(|| format!("expected 3 coordinates, found {i}"))?;
        let x: f64 = token
            .parse()
            .map_err(|_| format!("'{token}' is not a number"))?;
        *slot = check_coordinate(x, token)?;
    }
    Ok(DVec3::from(v))
}

/// `i`, `i/t`, `i//n` or `i/t/n`, with 1-based or negative (relative) indices.
fn parse_corner(token: &str, positions: usize, normals: usize) -> Result<Corner, String> {
    let mut parts = token.split('/');
    let i = parse_index(parts.next().unwrap_or(""), "vertex")?;
    let position = resolve_index(i, positions).ok_or_else(|| {
        let defined = if positions == 1 { "vertex" } else { "vertices" };
        format!("vertex index {i} is out of range: {positions} {defined} defined before this line")
    })?;
    let _texture = parts.next();
    // A normal index past the normals is a quirk, not broken geometry:
    // the face is shaded with computed normals instead.
    let normal = match parts.next() {
        Some(n) if !n.is_empty() => Some(resolve_index(parse_index(n, "normal")?, normals)),
        _ => None,
    };
    Ok((position, normal))
}

/// `what`: the element's name.
fn parse_index(token: &str, what: &str) -> Result<i64, String> {
    token
        .parse()
        .map_err(|_| format!("'{token}' is not a {what} index"))
}

/// A 1-based or negative index among `count` elements, 0-based; None
/// where there is no such element.
fn resolve_index(i: i64, count: usize) -> Option<u32> {
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    (i != 0 && resolved >= 0 && resolved < count as i64).then_some(resolved as u32)
}

fn smooth_normals(
    mesh: &Mesh,
    vertex_normals: &[DVec3],
    corner_normals: &[[Option<u32>; 3]],
) -> Vec<[DVec3; 3]> {
    let needs_computed = corner_normals.iter().any(|c| c.iter().any(Option::is_none));
    let area_weighted = if needs_computed {
        area_weighted_normals(mesh)
    } else {
        Vec::new()
    };
    mesh.triangles
        .iter()
        .zip(corner_normals)
        .map(|(tri, normals)| {
            if let [Some(a), Some(b), Some(c)] = *normals {
                [a, b, c].map(|i| vertex_normals[i as usize])
            } else {
                tri.map(|i| area_weighted[i as usize])
            }
        })
        .collect()
}
