//! Model files, one loader per format behind `load_mesh`: OBJ (with MTL
//! materials), PLY (ascii and binary, optionally gzipped) and glTF 2.0
//! (`.gltf` and `.glb`, whose cameras and lights `gltf::load_scene` also
//! reads) and STL (binary and ASCII). Every loader numbers triangles in file order, polygons
//! fan-triangulated as (v0,v1,v2), (v0,v2,v3), …, so that the same
//! triangles from any format are the same primitives.

pub mod gltf;
pub mod material;
mod mtl_brdf;
pub mod obj;
pub mod ply;
pub mod stl;
pub mod tangents;

use std::path::Path;

use glam::DVec3;
use serde::Deserialize;

use crate::error::{Error, Result};
pub use material::{AlphaMode, Brdf, ImageSource, MaterialDesc, TextureUse};

pub use obj::{load_obj, parse_obj};

/// How a mesh's shading normals are chosen (`normals = "face" | "smooth"`).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum NormalMode {
    /// The geometric normal of each triangle.
    #[default]
    Face,
    /// The file's normals (OBJ `vn`, PLY `nx ny nz`, glTF NORMAL) where
    /// every corner of a face has one, else area-weighted vertex normals.
    Smooth,
}

/// A triangle mesh, in f64 as parsed (a glTF file's already placed by its
/// nodes' transforms), with the materials its file gives its faces.
#[derive(Debug, Default)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    /// Position indices, three per triangle, in file order.
    pub triangles: Vec<[u32; 3]>,
    /// Per-triangle corner normals (unnormalised), for smooth meshes.
    pub normals: Option<Vec<[DVec3; 3]>>,
    /// Per triangle, an index into `materials`, or None for the format's
    /// default; empty when the file names no materials.
    pub face_materials: Vec<Option<u32>>,
    /// The materials the file defines.
    pub materials: Vec<MaterialDesc>,
    /// The images the materials' textures name (`TextureUse::image`).
    pub images: Vec<ImageSource>,
    /// Per triangle, its corners' texture coordinates (glTF's convention,
    /// see `material`), when the file gives them.
    pub uvs: Option<Vec<[[f32; 2]; 3]>>,
    /// Per triangle, its corners' tangents (xyz) and bitangent signs (w),
    /// glTF TANGENT's convention (`tangents`), where the file gives them
    /// (glTF TANGENT with NORMAL, in every primitive).
    pub tangents: Option<Vec<[[f32; 4]; 3]>>,
    /// Per triangle, its corners' linear RGBA colours (glTF COLOR_0, PLY
    /// `red green blue [alpha]`, OBJ `v x y z r g b`), when the file gives
    /// them; they multiply the base colour.
    pub colors: Option<Vec<[[f32; 4]; 3]>>,
    /// What was read but ignored or not found, each naming the file.
    pub warnings: Vec<String>,
    /// The files read for it: the model file and those it names (MTL
    /// files, glTF buffers); its images' are in `images`.
    pub files: Vec<std::path::PathBuf>,
    /// Whether `normals` are the file's own at every corner (not computed).
    pub file_normals: bool,
    /// Vertices read but not in `positions` (a glTF file's point and line
    /// primitives), for the message of a file without triangles.
    pub unused_points: usize,
    /// Line and point elements read but not rendered (OBJ `l` and `p`,
    /// PLY edges, glTF point and line primitives), likewise.
    pub skipped_lines: usize,
}

/// Where the line that `bytes` begins ends, and where the next one
/// begins: every text format's lines end at `\n`, `\r\n` or a lone `\r`
/// (classic Mac OS files, which some CAD exporters still write).
pub(crate) fn line_end(bytes: &[u8]) -> (usize, usize) {
    match bytes.iter().position(|&b| b == b'\n' || b == b'\r') {
        None => (bytes.len(), bytes.len()),
        Some(end) if bytes[end..].starts_with(b"\r\n") => (end, end + 2),
        Some(end) => (end, end + 1),
    }
}

/// The lines of `bytes` as `line_end` ends them (as `str::lines`: no
/// empty last line after a final ending).
pub(crate) fn byte_lines(mut bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    std::iter::from_fn(move || {
        if bytes.is_empty() {
            return None;
        }
        let (end, next) = line_end(bytes);
        let line = &bytes[..end];
        bytes = &bytes[next..];
        Some(line)
    })
}

/// `byte_lines` of text.
pub(crate) fn text_lines(text: &str) -> impl Iterator<Item = &str> {
    // Line endings are ASCII, so every line is whole UTF-8.
    byte_lines(text.as_bytes()).map(|line| std::str::from_utf8(line).unwrap_or_default())
}

/// The one answer for a model without triangles, whatever its format:
/// an error, rather than a picture of nothing or a camera framed on no
/// bounds.
pub fn require_triangles(mesh: &Mesh, path: &Path) -> Result<()> {
    if mesh.triangles.is_empty() {
        return Err(Error::scene(
            path,
            format!(
                "no triangles ({} points, {} lines skipped)",
                mesh.positions.len() + mesh.unused_points,
                mesh.skipped_lines
            ),
        ));
    }
    Ok(())
}

/// The model formats, chosen by file extension (case-insensitive).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Obj,
    Ply,
    /// `.ply.gz`
    PlyGz,
    Gltf,
    Glb,
    /// Binary or ASCII STL.
    Stl,
}

pub const SUPPORTED: &str = ".obj, .ply, .ply.gz, .gltf, .glb and .stl";

impl Format {
    pub fn of(path: &Path) -> Result<Format> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        let format = if name.ends_with(".obj") {
            Format::Obj
        } else if name.ends_with(".ply.gz") {
            Format::PlyGz
        } else if name.ends_with(".ply") {
            Format::Ply
        } else if name.ends_with(".gltf") {
            Format::Gltf
        } else if name.ends_with(".glb") {
            Format::Glb
        } else if name.ends_with(".stl") {
            Format::Stl
        } else {
            return Err(Error::Usage(format!(
                "{}: not a model format lambert reads; use {SUPPORTED}",
                path.display()
            )));
        };
        Ok(format)
    }

    pub fn is_gltf(self) -> bool {
        matches!(self, Format::Gltf | Format::Glb)
    }
}

/// Loads any model file: its geometry and materials (a glTF file's default
/// scene, placed by its nodes; its cameras and lights are
/// `gltf::load_scene`'s). A file without triangles is an error
/// (`require_triangles`).
pub fn load_mesh(path: &Path, mode: NormalMode) -> Result<Mesh> {
    let mut mesh = match Format::of(path)? {
        Format::Obj => load_obj(path, mode)?,
        Format::Ply | Format::PlyGz => ply::load_ply(path, mode)?,
        Format::Stl => stl::load_stl(path, mode)?,
        // `gltf::load_scene` requires triangles itself: a model scene
        // reads glTF files through it alone.
        Format::Gltf | Format::Glb => return Ok(gltf::load_scene(path, mode)?.mesh),
    };
    require_triangles(&mesh, path)?;
    mesh.files.insert(0, path.to_path_buf());
    Ok(mesh)
}

/// A model file's bytes as `path`'s name says they are (a `.ply.gz`
/// gunzipped first): its geometry and materials, and a glTF file's cameras
/// and lights; what `Scene::from_model` reads, and the web's dropped file
/// (which names it). Files it refers to (MTL, external buffers, images) are
/// read relative to `path`. A file without triangles is an error.
pub fn parse_model(bytes: &[u8], path: &Path, mode: NormalMode) -> Result<gltf::GltfScene> {
    let mesh = match Format::of(path)? {
        Format::Obj => parse_obj(&String::from_utf8_lossy(bytes), path, mode)?,
        Format::Ply => ply::parse_ply(bytes, path, mode)?,
        Format::PlyGz => {
            let cap = crate::files::MAX_MODEL_BYTES;
            let bytes = crate::files::gunzip_capped(bytes, path, cap)?;
            ply::parse_ply(&bytes, path, mode)?
        }
        Format::Stl => stl::parse_stl(bytes, path, mode)?,
        // `gltf::parse_scene` requires triangles itself.
        Format::Gltf | Format::Glb => return gltf::parse_scene(bytes, path, mode),
    };
    require_triangles(&mesh, path)?;
    Ok(gltf::GltfScene {
        mesh,
        ..Default::default()
    })
}

/// Corner normals of every triangle: the given per-vertex normals where
/// there are some (`vertex_normals`, one per position), else area-weighted
/// vertex normals.
pub fn vertex_normals(mesh: &Mesh, vertex_normals: Option<&[DVec3]>) -> Vec<[DVec3; 3]> {
    let computed;
    let per_vertex = match vertex_normals {
        Some(n) => n,
        None => {
            computed = area_weighted_normals(mesh);
            &computed
        }
    };
    corner_values(&mesh.triangles, per_vertex)
}

/// Per position, the sum of its triangles' unnormalised normals (twice
/// their areas times their unit normals).
pub fn area_weighted_normals(mesh: &Mesh) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; mesh.positions.len()];
    for tri in &mesh.triangles {
        let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        for i in tri {
            normals[*i as usize] += n;
        }
    }
    normals
}

/// Checks a coordinate read from a model file: finite, and within the
/// magnitude the f32 tests support.
/// `text` is the coordinate as the file wrote it.
pub fn check_coordinate(x: f64, text: &str) -> std::result::Result<f64, String> {
    if !x.is_finite() || x.abs() > crate::limits::MAX_COORDINATE {
        return Err(format!(
            "coordinate {text} must be finite with magnitude at most {:e}",
            crate::limits::MAX_COORDINATE
        ));
    }
    Ok(x)
}

/// A per-vertex attribute at each triangle's corners.
pub fn corner_values<T: Copy>(triangles: &[[u32; 3]], per_vertex: &[T]) -> Vec<[T; 3]> {
    triangles
        .iter()
        .map(|tri| tri.map(|i| per_vertex[i as usize]))
        .collect()
}

/// An sRGB-encoded value in [0, 1] decoded to linear (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}
