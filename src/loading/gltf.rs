//! glTF 2.0 (`.gltf` with external or data-URI buffers, and `.glb`), with
//! the `gltf` crate: every mesh primitive of the default scene (else the
//! first), placed by its node's world transform; its cameras; and its
//! KHR_lights_punctual lights (point, spot and directional).

use std::path::Path;

use glam::{DMat4, DQuat, DVec3};

use super::material::MaterialDesc;
use super::{Mesh, NormalMode, check_coordinate, corner_values, vertex_normals};
use crate::error::{Error, Result};

mod materials;
use materials::{DEFAULT_BRDF, Images, material_desc, texture_coordinate_set};

/// Extensions lambert implements, so a file may require them.
const IMPLEMENTED: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
];

/// A perspective camera of the file, in world space.
#[derive(Clone, Debug)]
pub struct GltfCamera {
    pub name: Option<String>,
    pub eye: DVec3,
    /// The node's −Z, normalised.
    pub forward: DVec3,
    /// The node's +Y, normalised.
    pub up: DVec3,
    /// Vertical field of view, degrees.
    pub yfov_deg: f64,
    pub aspect_ratio: Option<f64>,
}

/// A KHR_lights_punctual light in the file's photometric units (colour ×
/// intensity): a point light (candela), a spot light (candela on its axis,
/// pointing along `direction`, with its cone half-angles in radians) or a
/// directional one (lux, travelling along `direction`). The scene stores
/// them in the lecture's units, ÷ π (docs/rendering.md, "Light units").
#[derive(Clone, Debug)]
pub enum GltfLight {
    Point {
        position: DVec3,
        intensity: [f64; 3],
    },
    Spot {
        position: DVec3,
        direction: DVec3,
        intensity: [f64; 3],
        inner_cone_angle: f64,
        outer_cone_angle: f64,
    },
    Directional {
        direction: DVec3,
        irradiance: [f64; 3],
    },
}

/// What a glTF file holds for lambert.
#[derive(Debug, Default)]
pub struct GltfScene {
    pub mesh: Mesh,
    pub cameras: Vec<GltfCamera>,
    pub lights: Vec<GltfLight>,
}

/// Reads `path`: geometry (smooth normals from NORMAL, or computed, with
/// `NormalMode::Smooth`), materials, cameras and lights.
pub fn load_scene(path: &Path, mode: NormalMode) -> Result<GltfScene> {
    let bytes = crate::files::read_capped(path, crate::files::MAX_MODEL_BYTES)?;
    let mut scene = parse_scene(&bytes, path, mode)?;
    scene.mesh.files.insert(0, path.to_path_buf());
    Ok(scene)
}

/// `load_scene` of a file's bytes (JSON or GLB); `path` names it in errors
/// and anchors its external buffers.
pub fn parse_scene(bytes: &[u8], path: &Path, mode: NormalMode) -> Result<GltfScene> {
    let fail = |message: String| Error::scene(path, message);
    // The crate subtracts the 12-byte header from a GLB's declared length
    // unchecked: an overflow panic in checked builds, a wrapped length in
    // its message otherwise.
    if let Some(header) = bytes.get(..12).filter(|h| h.starts_with(b"glTF")) {
        let length = u32::from_le_bytes([header[8], header[9], header[10], header[11]]) as usize;
        if length < 12 || length > bytes.len() {
            return Err(fail(format!(
                "its GLB header declares {length} bytes, but the file has {} (and a header \
                 takes 12)",
                bytes.len()
            )));
        }
    }
    // Required extensions first: the crate's own validation would call an
    // unknown one merely invalid.
    let unchecked = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| fail(format!("not a readable glTF file: {e}")))?;
    if let Some(missing) = unchecked
        .extensions_required()
        .find(|e| !IMPLEMENTED.contains(e))
    {
        return Err(fail(format!(
            "the file requires the extension {missing}, which lambert does not implement"
        )));
    }
    // gltf-json's validation reads each POSITION accessor before checking
    // that it exists, and panics on an index past the end: check first.
    let json = unchecked.document.as_json();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for (semantic, accessor) in &primitive.attributes {
                if accessor.value() >= json.accessors.len() {
                    return Err(fail(format!(
                        "mesh {m} primitive {p}: attribute {} names accessor {}, \
                         but the file has {} accessors",
                        semantic.to_string(),
                        accessor.value(),
                        json.accessors.len()
                    )));
                }
            }
        }
    }
    drop(unchecked);
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice(bytes).map_err(|e| match e {
        // The crate's own text starts with "invalid glTF:" too.
        gltf::Error::Validation(errors) => fail(format!(
            "invalid glTF: {}",
            errors
                .iter()
                .map(|(at, error)| format!("{at}: {error}"))
                .collect::<Vec<_>>()
                .join("; ")
        )),
        e => fail(format!("invalid glTF: {e}")),
    })?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffer_files = check_buffer_files(&document, base).map_err(fail)?;
    let buffers = read_buffers(&document, base, blob).map_err(fail)?;

    let mut scene = GltfScene::default();
    // Extensions a file may use without requiring (transmission, volume,
    // clearcoat, sheen, …): the file renders without them, and says so.
    for extension in document.extensions_used() {
        if !IMPLEMENTED.contains(&extension) {
            scene.mesh.warnings.push(format!(
                "{}: the file uses {extension}, which lambert ignores (docs/rendering.md, \
                 \"Materials\")",
                path.display()
            ));
        }
    }
    let Some(root) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    else {
        return Err(fail("the file has no scene".into()));
    };
    let mut normals: Vec<DVec3> = Vec::new();
    let mut all_normals = true;
    let mut default_material: Option<u32> = None;
    let mut material_ids: Vec<Option<u32>> = vec![None; document.materials().len()];
    let mut images = Images::new(&document, &buffers, path);
    // Per vertex (parallel to positions): COLOR_0 (white where a primitive
    // has none) and the texture coordinates its material's textures read.
    let mut vertex_colors: Vec<[f32; 4]> = Vec::new();
    let mut vertex_uvs: Vec<[f32; 2]> = Vec::new();
    let (mut any_colors, mut any_uvs) = (false, false);
    // Per vertex, TANGENT placed by its node: kept if every primitive has
    // it (and NORMAL, which the spec requires of given tangents).
    let mut vertex_tangents: Vec<[f32; 4]> = Vec::new();
    let mut all_tangents = true;
    let mut stack: Vec<(gltf::Node, DMat4)> = root.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    // Nodes in document order within each level, as the file lists them.
    stack.reverse();
    // The spec's node hierarchy is a set of trees; a node reached twice (a
    // cycle, or two parents) would otherwise be expanded exponentially.
    let mut visited = vec![false; document.nodes().len()];
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(fail(format!(
                "node {} is reached twice from the scene's roots: the node hierarchy \
                 must be a tree (no cycles, one parent per node)",
                node.index()
            )));
        }
        let local = local_transform(&node, path, &mut scene.mesh.warnings).map_err(fail)?;
        let world = parent * local;
        if !world.is_finite() {
            return Err(fail(format!(
                "node {}: its transform is not finite",
                node.index()
            )));
        }
        let children: Vec<_> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world));
        }
        if let Some(camera) = node.camera() {
            read_camera(&camera, &world, &mut scene, path);
        }
        if let Some(light) = node.light() {
            read_light(&light, &world, &mut scene, path);
        }
        let Some(mesh) = node.mesh() else { continue };
        let normal_matrix = glam::DMat3::from_mat4(world).inverse().transpose();
        // A mirroring transform turns counter-clockwise faces clockwise: the
        // spec makes those the front faces, so swapping two corners keeps
        // the geometric normals facing out.
        let mirrored = glam::DMat3::from_mat4(world).determinant() < 0.0;
        for primitive in mesh.primitives() {
            let what = format!("mesh {} primitive {}", mesh.index(), primitive.index());
            use gltf::mesh::Mode;
            let mode_kind = primitive.mode();
            if !matches!(
                mode_kind,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                scene.mesh.warnings.push(format!(
                    "{}: {what}: mode {mode_kind:?} skipped (lambert renders triangles)",
                    path.display()
                ));
                scene.mesh.skipped_lines += 1;
                scene.mesh.unused_points += primitive
                    .get(&gltf::Semantic::Positions)
                    .map_or(0, |a| a.count());
                continue;
            }
            let position_accessor = primitive
                .get(&gltf::Semantic::Positions)
                .ok_or_else(|| fail(format!("{what} has no POSITION")))?;
            use gltf::accessor::{DataType, Dimensions};
            let vec3 = [DataType::F32];
            check_accessor(&position_accessor, &buffers, Dimensions::Vec3, &vec3)
                .map_err(|m| fail(format!("{what}: POSITION {m}")))?;
            if let Some(indices) = primitive.indices() {
                let types = [DataType::U8, DataType::U16, DataType::U32];
                check_accessor(&indices, &buffers, Dimensions::Scalar, &types)
                    .map_err(|m| fail(format!("{what}: indices {m}")))?;
            }
            let material = primitive.material();
            let uv_set = texture_coordinate_set(
                &material,
                &primitive,
                &what,
                path,
                &mut scene.mesh.warnings,
            );
            let color_accessor = primitive.get(&gltf::Semantic::Colors(0));
            if let Some(c) = &color_accessor {
                let dimensions = match c.dimensions() {
                    Dimensions::Vec4 => Dimensions::Vec4,
                    _ => Dimensions::Vec3,
                };
                let types = [DataType::F32, DataType::U8, DataType::U16];
                check_accessor(c, &buffers, dimensions, &types)
                    .map_err(|m| fail(format!("{what}: COLOR_0 {m}")))?;
            }
            let uv_accessor = uv_set.and_then(|n| primitive.get(&gltf::Semantic::TexCoords(n)));
            if let Some(t) = &uv_accessor {
                let types = [DataType::F32, DataType::U8, DataType::U16];
                check_accessor(t, &buffers, Dimensions::Vec2, &types)
                    .map_err(|m| fail(format!("{what}: TEXCOORD_{} {m}", uv_set.unwrap_or(0))))?;
            }
            let normal_accessor = primitive.get(&gltf::Semantic::Normals);
            if let Some(n) = &normal_accessor {
                check_accessor(n, &buffers, Dimensions::Vec3, &vec3)
                    .map_err(|m| fail(format!("{what}: NORMAL {m}")))?;
            }
            let tangent_accessor = primitive.get(&gltf::Semantic::Tangents);
            if let Some(t) = &tangent_accessor {
                check_accessor(t, &buffers, Dimensions::Vec4, &vec3)
                    .map_err(|m| fail(format!("{what}: TANGENT {m}")))?;
            }
            let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let first = scene.mesh.positions.len() as u32;
            let positions: Vec<[f32; 3]> = reader
                .read_positions()
                .ok_or_else(|| fail(format!("{what}: POSITION cannot be read")))?
                .collect();
            for (i, p) in positions.iter().enumerate() {
                let q = world.transform_point3(DVec3::from(p.map(f64::from)));
                for x in q.to_array() {
                    check_coordinate(x, &x.to_string()).map_err(|m| {
                        fail(format!("{what}: vertex {i} (placed by its node): {m}"))
                    })?;
                }
                scene.mesh.positions.push(q);
            }
            match reader.read_normals() {
                Some(iter) if normal_accessor.is_some() => {
                    normals.extend(iter.map(|n| {
                        (normal_matrix * DVec3::from(n.map(f64::from))).normalize_or_zero()
                    }));
                }
                _ => {
                    all_normals = false;
                    normals.extend(std::iter::repeat_n(DVec3::ZERO, positions.len()));
                }
            }
            let count = positions.len() as u32;
            let same_count = |accessor: &gltf::Accessor, name: &str| {
                if accessor.count() == positions.len() {
                    Ok(())
                } else {
                    Err(fail(format!(
                        "{what}: {name} accessor {} has {} elements, POSITION {}",
                        accessor.index(),
                        accessor.count(),
                        positions.len()
                    )))
                }
            };
            match (reader.read_tangents(), &tangent_accessor) {
                (Some(iter), Some(accessor)) if normal_accessor.is_some() => {
                    same_count(accessor, "TANGENT")?;
                    let linear = glam::DMat3::from_mat4(world);
                    vertex_tangents.extend(iter.map(|t| placed_tangent(t, linear)));
                }
                _ => {
                    all_tangents = false;
                    vertex_tangents.extend(std::iter::repeat_n([0.0; 4], positions.len()));
                }
            }
            match (reader.read_colors(0), &color_accessor) {
                (Some(colors), Some(accessor)) => {
                    same_count(accessor, "COLOR_0")?;
                    any_colors = true;
                    vertex_colors.extend(colors.into_rgba_f32());
                }
                _ => vertex_colors.extend(std::iter::repeat_n([1.0; 4], positions.len())),
            }
            // A textured primitive keeps its textures even without the set
            // they read (reading (0, 0), with the warning above).
            any_uvs |= uv_set.is_some();
            match (uv_set.and_then(|n| reader.read_tex_coords(n)), &uv_accessor) {
                (Some(uvs), Some(accessor)) => {
                    same_count(accessor, "TEXCOORD")?;
                    vertex_uvs.extend(uvs.into_f32());
                }
                _ => vertex_uvs.extend(std::iter::repeat_n([0.0; 2], positions.len())),
            }
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..count).collect(),
            };
            if let Some(bad) = indices.iter().find(|&&i| i >= count) {
                return Err(fail(format!(
                    "{what}: index {bad} is out of range ({count} vertices)"
                )));
            }
            let corners = |i: usize| indices[i] + first;
            let mut triangles: Vec<[u32; 3]> = Vec::new();
            let mut push =
                |[a, b, c]: [u32; 3]| triangles.push(if mirrored { [a, c, b] } else { [a, b, c] });
            match mode_kind {
                Mode::Triangles => {
                    for t in 0..indices.len() / 3 {
                        push([corners(3 * t), corners(3 * t + 1), corners(3 * t + 2)]);
                    }
                }
                Mode::TriangleStrip => {
                    for t in 0..indices.len().saturating_sub(2) {
                        // As the glTF spec orders them: (i, i+1, i+2) for
                        // even i, (i, i+2, i+1) for odd, one winding.
                        let tri = if t % 2 == 0 {
                            [corners(t), corners(t + 1), corners(t + 2)]
                        } else {
                            [corners(t), corners(t + 2), corners(t + 1)]
                        };
                        push(tri);
                    }
                }
                _ => {
                    for t in 1..indices.len().saturating_sub(1) {
                        push([corners(0), corners(t), corners(t + 1)]);
                    }
                }
            }
            let id = match material.index() {
                Some(m) => *material_ids[m].get_or_insert_with(|| {
                    let desc =
                        material_desc(&material, path, &mut images, &mut scene.mesh.warnings);
                    scene.mesh.materials.push(desc);
                    (scene.mesh.materials.len() - 1) as u32
                }),
                None => *default_material.get_or_insert_with(|| {
                    // glTF's default material: base colour 1, opaque,
                    // metallic and roughness 1.
                    scene.mesh.materials.push(MaterialDesc {
                        name: "(default)".into(),
                        brdf: DEFAULT_BRDF,
                        ..MaterialDesc::default()
                    });
                    (scene.mesh.materials.len() - 1) as u32
                }),
            };
            scene
                .mesh
                .face_materials
                .extend(std::iter::repeat_n(Some(id), triangles.len()));
            scene.mesh.triangles.extend(triangles);
        }
    }
    super::require_triangles(&scene.mesh, path)?;
    scene.mesh.images = images.sources;
    scene.mesh.files = buffer_files;
    if any_colors {
        scene.mesh.colors = Some(corner_values(&scene.mesh.triangles, &vertex_colors));
    }
    if any_uvs {
        scene.mesh.uvs = Some(corner_values(&scene.mesh.triangles, &vertex_uvs));
    }
    if all_tangents {
        scene.mesh.tangents = Some(corner_values(&scene.mesh.triangles, &vertex_tangents));
    }
    if mode == NormalMode::Smooth {
        let given = all_normals.then_some(&normals[..]);
        scene.mesh.file_normals = all_normals;
        scene.mesh.normals = Some(vertex_normals(&scene.mesh, given));
    }
    Ok(scene)
}

/// A node's local matrix, in f64. A rotation that is not a unit quaternion
/// is normalised, as trimesh, Blender and three.js do (the crate's matrix
/// would scale and shear by it), with a warning when it is off by more
/// than the rounding of a written file.
fn local_transform(
    node: &gltf::Node,
    path: &Path,
    warnings: &mut Vec<String>,
) -> std::result::Result<DMat4, String> {
    let (translation, rotation, scale) = match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            return Ok(DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))));
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => (translation, rotation, scale),
    };
    let q = DQuat::from_array(rotation.map(f64::from));
    let length = q.length();
    if !(length > 0.0 && length.is_finite()) {
        return Err(format!(
            "{}: its rotation {rotation:?} has length {length}, which cannot be normalised",
            node_name(node)
        ));
    }
    if (length - 1.0).abs() > 1e-3 {
        warnings.push(format!(
            "{}: {}: its rotation {rotation:?} has length {length:.4}, not 1; normalised",
            path.display(),
            node_name(node)
        ));
    }
    Ok(DMat4::from_scale_rotation_translation(
        DVec3::from(scale.map(f64::from)),
        q / length,
        DVec3::from(translation.map(f64::from)),
    ))
}

/// `node 3 'Cube'`, or `node 3` when it has no name.
fn node_name(node: &gltf::Node) -> String {
    match node.name() {
        Some(name) => format!("node {} '{name}'", node.index()),
        None => format!("node {}", node.index()),
    }
}

/// A material's name, else its index.
fn material_name(material: &gltf::Material) -> String {
    material.name().map_or_else(
        || format!("{}", material.index().unwrap_or(0)),
        str::to_string,
    )
}

/// The file's buffers, read as `gltf::import_buffers` reads them, with
/// each error naming the buffer and the file it names.
fn read_buffers(
    document: &gltf::Document,
    base: &Path,
    mut blob: Option<Vec<u8>>,
) -> std::result::Result<Vec<gltf::buffer::Data>, String> {
    document
        .buffers()
        .map(|buffer| {
            let source = match buffer.source() {
                gltf::buffer::Source::Bin => "no uri: the GLB's binary chunk".to_string(),
                gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                    "its data URI".to_string()
                }
                gltf::buffer::Source::Uri(uri) => format!("{uri:?}"),
            };
            let what = format!("buffer {} ({source})", buffer.index());
            let data =
                gltf::buffer::Data::from_source_and_blob(buffer.source(), Some(base), &mut blob)
                    .map_err(|e| format!("reading {what}: {e}"))?;
            if data.len() < buffer.length() {
                return Err(format!(
                    "{what} holds {} bytes, but its byteLength is {}",
                    data.len(),
                    buffer.length()
                ));
            }
            Ok(data)
        })
        .collect()
}

/// Checks the files that buffers name before the crate reads them: it
/// panics on a URI whose percent-encoding is not UTF-8, and would read a
/// device or FIFO (`/dev/zero`, an absolute path being allowed) forever.
/// Returns the files.
fn check_buffer_files(
    document: &gltf::Document,
    base: &Path,
) -> std::result::Result<Vec<std::path::PathBuf>, String> {
    let mut files = Vec::new();
    for buffer in document.buffers() {
        let gltf::buffer::Source::Uri(uri) = buffer.source() else {
            continue;
        };
        let index = buffer.index();
        let file = if uri.contains(':') {
            // data: is decoded in memory; file: is a path as it stands.
            match uri
                .strip_prefix("file://")
                .or_else(|| uri.strip_prefix("file:"))
            {
                Some(rest) => rest.to_string(),
                None => continue,
            }
        } else {
            percent_decoded(uri).ok_or_else(|| {
                format!("buffer {index}: its uri {uri:?} is not percent-encoded UTF-8")
            })?
        };
        let file = base.join(file);
        if file.exists() {
            crate::files::open_capped(&file, crate::files::MAX_MODEL_BYTES)
                .map_err(|e| format!("buffer {index}: {e}"))?;
        }
        files.push(file);
    }
    Ok(files)
}

/// `%XX` escapes decoded, or None where the result is not UTF-8.
fn percent_decoded(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (
            bytes[i],
            bytes.get(i + 1).copied().and_then(hex),
            bytes.get(i + 2).copied().and_then(hex),
        ) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (b, _, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8(out).ok()
}

/// Checks what the crate's readers assume of an accessor: its element type
/// (they panic on another one) and its extent within its buffer.
fn check_accessor(
    accessor: &gltf::Accessor,
    buffers: &[gltf::buffer::Data],
    dimensions: gltf::accessor::Dimensions,
    types: &[gltf::accessor::DataType],
) -> std::result::Result<(), String> {
    if accessor.dimensions() != dimensions || !types.contains(&accessor.data_type()) {
        return Err(format!(
            "accessor {} holds {:?} {:?}; the glTF spec requires {dimensions:?} of {types:?}",
            accessor.index(),
            accessor.dimensions(),
            accessor.data_type()
        ));
    }
    if accessor.sparse().is_some() {
        return Err(format!(
            "accessor {} is sparse, which lambert does not read",
            accessor.index()
        ));
    }
    let Some(view) = accessor.view() else {
        return Err(format!("accessor {} has no buffer view", accessor.index()));
    };
    let buffer = &buffers[view.buffer().index()];
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|end| end > buffer.len()) {
        return Err(format!(
            "accessor {}: buffer view {} ends beyond its buffer ({} bytes)",
            accessor.index(),
            view.index(),
            buffer.len()
        ));
    }
    // The crate reads each element from a stride's bytes (a panic when
    // they are fewer), and the last one at (count - 1) × stride.
    let stride = view.stride().unwrap_or(accessor.size());
    if stride < accessor.size() {
        return Err(format!(
            "accessor {}: its buffer view {} has byteStride {stride}, less than one element \
             ({} bytes)",
            accessor.index(),
            view.index(),
            accessor.size()
        ));
    }
    let Some(last) = accessor.count().checked_sub(1) else {
        return Err(format!(
            "accessor {} has count 0 (the glTF spec requires at least 1)",
            accessor.index()
        ));
    };
    let needed = last.checked_mul(stride).and_then(|b| {
        b.checked_add(accessor.offset())?
            .checked_add(accessor.size())
    });
    if needed.is_none_or(|n| n > view.length()) {
        return Err(format!(
            "accessor {} ({} elements) reaches beyond its buffer view {} ({} bytes)",
            accessor.index(),
            accessor.count(),
            view.index(),
            view.length()
        ));
    }
    Ok(())
}

fn read_camera(camera: &gltf::Camera, world: &DMat4, scene: &mut GltfScene, path: &Path) {
    match camera.projection() {
        gltf::camera::Projection::Perspective(p) => scene.cameras.push(GltfCamera {
            name: camera.name().map(str::to_string),
            eye: world.transform_point3(DVec3::ZERO),
            forward: world.transform_vector3(DVec3::NEG_Z).normalize_or_zero(),
            up: world.transform_vector3(DVec3::Y).normalize_or_zero(),
            yfov_deg: f64::from(p.yfov()).to_degrees(),
            aspect_ratio: p.aspect_ratio().map(f64::from),
        }),
        gltf::camera::Projection::Orthographic(_) => scene.mesh.warnings.push(format!(
            "{}: camera {}: orthographic, skipped (lambert's camera is a pinhole)",
            path.display(),
            camera.name().unwrap_or("(unnamed)")
        )),
    }
}

fn read_light(
    light: &gltf::khr_lights_punctual::Light,
    world: &DMat4,
    scene: &mut GltfScene,
    path: &Path,
) {
    use gltf::khr_lights_punctual::Kind;
    let name = light.name().unwrap_or("(unnamed)");
    let power = light
        .color()
        .map(|c| f64::from(c) * f64::from(light.intensity()));
    if light.range().is_some() {
        scene.mesh.warnings.push(format!(
            "{}: light {name}: its range is ignored (lambert's lights fall off as 1/r² without a cut-off)",
            path.display()
        ));
    }
    let position = world.transform_point3(DVec3::ZERO);
    // Spot and directional lights point along their node's −Z.
    let direction = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
    scene.lights.push(match light.kind() {
        Kind::Point => GltfLight::Point {
            position,
            intensity: power,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => GltfLight::Spot {
            position,
            direction,
            intensity: power,
            inner_cone_angle: f64::from(inner_cone_angle),
            outer_cone_angle: f64::from(outer_cone_angle),
        },
        Kind::Directional => GltfLight::Directional {
            direction,
            irradiance: power,
        },
    });
}

/// A TANGENT placed by its node's linear map: the direction mapped as
/// surface vectors are, the bitangent sign flipped by a mirroring map
/// (which turns the frame's handedness).
fn placed_tangent(t: [f32; 4], linear: glam::DMat3) -> [f32; 4] {
    let d = (linear * DVec3::new(t[0].into(), t[1].into(), t[2].into())).normalize_or_zero();
    let w = if linear.determinant() < 0.0 {
        -t[3]
    } else {
        t[3]
    };
    [d.x as f32, d.y as f32, d.z as f32, w]
}
