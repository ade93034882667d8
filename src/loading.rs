//! Wavefront OBJ loading.
//!
//! A small parser of our own rather than tobj: errors must name the file and
//! line at fault, and the triangle order must be exactly the file's (polygons
//! fan-triangulated as (v0,v1,v2), (v0,v2,v3), …), because primitive ids in
//! `lambert trace` output are defined by it.

use std::path::Path;

use glam::DVec3;
use serde::Deserialize;

use crate::error::{Error, Result};

/// How a mesh's shading normals are chosen (`normals = "face" | "smooth"`).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum NormalMode {
    /// The geometric normal of each triangle.
    #[default]
    Face,
    /// The OBJ's `vn` normals where every corner of a face has one, else
    /// area-weighted vertex normals.
    Smooth,
}

/// A triangle mesh in object space, in f64 as parsed.
#[derive(Debug, Default)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    /// Position indices, three per triangle, in file order.
    pub triangles: Vec<[u32; 3]>,
    /// Per-triangle corner normals (unnormalised), for smooth meshes.
    pub normals: Option<Vec<[DVec3; 3]>>,
}

pub fn load_obj(path: &Path, mode: NormalMode) -> Result<Mesh> {
    let text = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_obj(&String::from_utf8_lossy(&text), path, mode)
}

/// A face corner: position index and, if given, normal index.
type Corner = (u32, Option<u32>);

pub fn parse_obj(text: &str, path: &Path, mode: NormalMode) -> Result<Mesh> {
    let mut mesh = Mesh::default();
    let mut vertex_normals: Vec<DVec3> = Vec::new();
    let mut corner_normals: Vec<[Option<u32>; 3]> = Vec::new();
    let mut corners: Vec<Corner> = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let line_number = index + 1;
        let fail = |message: String| Error::Obj {
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
                }
            }
            // Names, groups, materials, texture coordinates, lines, points:
            // nothing a Lambertian triangle renderer uses.
            _ => {}
        }
    }
    if mode == NormalMode::Smooth {
        mesh.normals = Some(smooth_normals(&mesh, &vertex_normals, &corner_normals));
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
        if !x.is_finite() || x.abs() > crate::scene::MAX_COORDINATE {
            return Err(format!(
                "coordinate {token} must be finite with magnitude at most {:e}",
                crate::scene::MAX_COORDINATE
            ));
        }
        *slot = x;
    }
    Ok(DVec3::from(v))
}

/// `i`, `i/t`, `i//n` or `i/t/n`, with 1-based or negative (relative) indices.
fn parse_corner(token: &str, positions: usize, normals: usize) -> Result<Corner, String> {
    let mut parts = token.split('/');
    let position = resolve_index(parts.next().unwrap_or(""), positions, "vertex")?;
    let _texture = parts.next();
    let normal = match parts.next() {
        Some(n) if !n.is_empty() => Some(resolve_index(n, normals, "normal")?),
        _ => None,
    };
    Ok((position, normal))
}

fn resolve_index(token: &str, count: usize, what: &str) -> Result<u32, String> {
    let i: i64 = token
        .parse()
        .map_err(|_| format!("'{token}' is not a {what} index"))?;
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || resolved < 0 || resolved >= count as i64 {
        return Err(format!(
            "{what} index {i} is out of range: {count} {what}s are defined before this line"
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
    let mut area_weighted = Vec::new();
    if needs_computed {
        // The unnormalised cross product is twice the area times the normal.
        area_weighted = vec![DVec3::ZERO; mesh.positions.len()];
        for tri in &mesh.triangles {
            let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
            let n = (b - a).cross(c - a);
            for i in tri {
                area_weighted[*i as usize] += n;
            }
        }
    }
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
