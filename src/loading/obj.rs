//! Wavefront OBJ loading, with the `Kd` of its MTL materials.
//!
//! A small parser of our own rather than tobj: errors must name the file and
//! line at fault, and the triangle order must be exactly the file's (polygons
//! fan-triangulated as (v0,v1,v2), (v0,v2,v3), …), because primitive ids in
//! `lambert trace` output are defined by it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::{Mesh, NormalMode, area_weighted_normals, check_coordinate};
use crate::error::{Error, Result};

/// Reads an OBJ file and the MTL files it names.
pub fn load_obj(path: &Path, mode: NormalMode) -> Result<Mesh> {
    let text = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_obj(&String::from_utf8_lossy(&text), path, mode)
}

/// The materials of an OBJ's MTL files, by name, as they are named.
#[derive(Default)]
pub struct Materials {
    index: HashMap<String, u32>,
    albedo: Vec<[f32; 3]>,
}

/// Reads `mtl` (relative to the OBJ's folder) into `materials`: `newmtl
/// NAME` and its `Kd r g b` (linear RGB); everything else is ignored. A
/// missing file is a warning; a malformed `Kd` an error at its line.
fn load_mtl(mtl: &Path, materials: &mut Materials, warnings: &mut Vec<String>) -> Result<()> {
    let bytes = match std::fs::read(mtl) {
        Ok(b) => b,
        Err(e) => {
            warnings.push(format!(
                "{}: material library not read ({e}); its faces get the default albedo",
                mtl.display()
            ));
            return Ok(());
        }
    };
    parse_mtl(&String::from_utf8_lossy(&bytes), mtl, materials)
}

/// Parses MTL text into `materials` (`load_mtl`'s rules); `mtl` names it
/// in errors.
pub fn parse_mtl(text: &str, mtl: &Path, materials: &mut Materials) -> Result<()> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut current: Option<u32> = None;
    for (index, line) in text.lines().enumerate() {
        let fail = |message: String| Error::Line {
            path: mtl.to_path_buf(),
            line: index + 1,
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
                let mut kd = [0.0f32; 3];
                for (i, slot) in kd.iter_mut().enumerate() {
                    let token = tokens
                        .next()
                        .ok_or_else(|| fail(format!("Kd needs 3 numbers (r g b), found {i}")))?;
                    let v: f32 = token
                        .parse()
                        .map_err(|_| fail(format!("Kd: '{token}' is not a number")))?;
                    if !v.is_finite() || v < 0.0 {
                        return Err(fail(format!("Kd: {token} must be finite and non-negative")));
                    }
                    *slot = v;
                }
                materials.albedo[id as usize] = kd;
            }
            _ => {}
        }
    }
    Ok(())
}

/// The MTL files an `mtllib` statement names, relative to the OBJ's folder.
fn mtl_paths<'a>(obj: &Path, tokens: impl Iterator<Item = &'a str>) -> Vec<PathBuf> {
    let folder = obj.parent().unwrap_or(Path::new("."));
    tokens.map(|t| folder.join(t)).collect()
}

/// A face corner: position index and, if given, normal index.
type Corner = (u32, Option<u32>);

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
    // A UTF-8 byte-order mark (some Windows exporters write one) is not
    // part of the first statement.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for (index, line) in text.lines().enumerate() {
        let line_number = index + 1;
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
                    load_mtl(&mtl, &mut materials, &mut mesh.warnings)?;
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
                    return Err(fail(format!(
                        "a face needs at least 3 vertices, this one has {}",
                        corners.len()
                    )));
                }
                for k in 1..corners.len() - 1 {
                    let fan = [corners[0], corners[k], corners[k + 1]];
                    mesh.triangles.push(fan.map(|c| c.0));
                    corner_normals.push(fan.map(|c| c.1));
                    mesh.face_materials.push(current);
                }
            }
            // Names, groups, materials, texture coordinates, lines, points:
            // nothing a Lambertian triangle renderer uses.
            _ => {}
        }
    }
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
    let position = resolve_index(
        parts.next().unwrap_or(""),
        positions,
        ("vertex", "vertices"),
    )?;
    let _texture = parts.next();
    let normal = match parts.next() {
        Some(n) if !n.is_empty() => Some(resolve_index(n, normals, ("normal", "normals"))?),
        _ => None,
    };
    Ok((position, normal))
}

/// `what`: the element's name, singular and plural.
fn resolve_index(token: &str, count: usize, (what, plural): (&str, &str)) -> Result<u32, String> {
    let i: i64 = token
        .parse()
        .map_err(|_| format!("'{token}' is not a {what} index"))?;
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || resolved < 0 || resolved >= count as i64 {
        let defined = if count == 1 { what } else { plural };
        return Err(format!(
            "{what} index {i} is out of range: {count} {defined} defined before this line"
        ));
    }
    Ok(resolved as u32)
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
