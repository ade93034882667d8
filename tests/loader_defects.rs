//! Issue 44, items 5, 10, 11 and 12: what loaders made of real files —
//! textures naming a missing UV set, image paths that are folders or
//! devices, CR-only line endings, OBJ faces naming `vt` with none, MTL
//! image paths as MeshLab and Blender write them, `-clamp on`, and flat
//! models framed edge-on. Every input is made here, in a temporary folder.

mod common;

use std::path::Path;

use common::data::one_mesh_glb;
use common::*;
use lambert::Scene;
use lambert::layout::NO_HIT;
use lambert::loading::material::{ImageSource, Wrap};
use lambert::loading::{NormalMode, load_mesh};

/// A 2×2 PNG.
fn png() -> Vec<u8> {
    png_bytes(2, [200, 50, 50, 255])
}

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// A GLB of a unit quad facing +z with TEXCOORD_0 only, material
/// `material`, and one texture whose image is `image` (a JSON image
/// entry; `{"bufferView": 3, …}` is an embedded PNG).
fn quad_glb(material: serde_json::Value, image: serde_json::Value) -> Vec<u8> {
    let mut bin = floats(&[0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.]);
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    bin.extend(floats(&[0., 1., 1., 1., 1., 0., 0., 0.]));
    let png = png();
    let png_len = png.len();
    bin.extend(png);
    bin.resize(bin.len().div_ceil(4) * 4, 0);
    let rest = serde_json::json!({
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": 0, "TEXCOORD_0": 2},
            "indices": 1,
            "material": 0
        }]}],
        "materials": [material],
        "textures": [{"source": 0}],
        "images": [image],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12},
            {"buffer": 0, "byteOffset": 60, "byteLength": 32},
            {"buffer": 0, "byteOffset": 92, "byteLength": png_len}
        ],
        "buffers": [{"byteLength": bin.len()}]
    });
    one_mesh_glb("KHR_texture_transform", rest, &bin)
}

fn embedded() -> serde_json::Value {
    serde_json::json!({"bufferView": 3, "mimeType": "image/png"})
}

/// Item 5: a texture reading a TEXCOORD_n the primitive lacks (its
/// texCoord, or KHR_texture_transform's override; base colour or
/// emissive) is kept, read at (0, 0), with a warning naming the material,
/// the texture and the set; `lambert info` lists the texture and warns.
#[test]
fn a_texture_naming_a_missing_uv_set_is_kept_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (
            serde_json::json!({"name": "painted",
                "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 2}}}),
            "material painted: its baseColorTexture reads TEXCOORD_2 (texCoord)",
        ),
        (
            serde_json::json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
                "extensions": {"KHR_texture_transform": {"texCoord": 1}}}}}),
            "material 0: its baseColorTexture reads TEXCOORD_1 (its KHR_texture_transform \
             texCoord)",
        ),
        (
            serde_json::json!({"name": "glow", "emissiveFactor": [1, 1, 1],
                "emissiveTexture": {"index": 0, "texCoord": 3}}),
            "material glow: its emissiveTexture reads TEXCOORD_3 (texCoord)",
        ),
    ];
    for (i, (material, expected)) in cases.into_iter().enumerate() {
        let path = write(d, &format!("uv{i}.glb"), quad_glb(material, embedded()));
        let scene = Scene::load(&path).unwrap();
        let warnings = scene.warnings().join("\n");
        assert!(warnings.contains(expected), "{warnings}");
        assert!(
            warnings.contains("which mesh 0 primitive 0 (the first such) does not have"),
            "{warnings}"
        );
        assert_eq!(scene.textures().images().len(), 1, "case {i}: {warnings}");
        let out = lambert(&["info", s(&path)]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(stdout.contains("textures: 1"), "{stdout}");
        assert!(
            stdout.contains(&format!("warning: {}", path.display())),
            "{stdout}"
        );
        assert!(stdout.contains(expected), "{stdout}");
    }
}

/// Item 10: an image path that is a folder or a device says so (glTF
/// `uri`, MTL `map_Kd`, PLY `TextureFile`), as a scene's paths do; a
/// missing one is still "not found".
#[test]
fn image_paths_that_are_folders_or_devices_say_what_they_are() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (".", "is not a regular file (a directory)"),
        ("/dev/zero", "is not a regular file (a character device)"),
        ("absent.png", "is not found"),
    ];
    for (i, (name, expected)) in cases.into_iter().enumerate() {
        let material = serde_json::json!({
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}});
        let glb = write(
            d,
            &format!("m{i}.glb"),
            quad_glb(material, serde_json::json!({"uri": name})),
        );
        write(
            d,
            &format!("m{i}.mtl"),
            format!("newmtl a\nmap_Kd {name}\n"),
        );
        let obj = write(
            d,
            &format!("m{i}.obj"),
            format!(
                "mtllib m{i}.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl a\nf 1/1 2/1 3/1\n"
            ),
        );
        let ply = write(
            d,
            &format!("m{i}.ply"),
            format!(
                "ply\nformat ascii 1.0\ncomment TextureFile {name}\nelement vertex 3\n\
                 property float x\nproperty float y\nproperty float z\nproperty float u\n\
                 property float v\nelement face 1\nproperty list uchar int vertex_indices\n\
                 end_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n"
            ),
        );
        for path in [glb, obj, ply] {
            let warnings = load_mesh(&path, NormalMode::Face)
                .unwrap()
                .warnings
                .join("\n");
            assert!(
                warnings.contains(expected),
                "{}: {warnings}",
                path.display()
            );
        }
    }
}

/// Item 11: lone CR line endings (classic Mac OS) read as line breaks in
/// ASCII STL, OBJ, MTL and PLY (header and ascii body), as `\n` and
/// `\r\n` do.
#[test]
fn cr_only_line_endings_are_line_breaks() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cr = |text: &str| text.replace('\n', "\r");
    let stl = "solid mac\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
               vertex 0 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\n\
               vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid mac\n";
    let mesh = load_mesh(&write(d, "mac.stl", cr(stl)), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles.len(), 2);
    write(d, "mac.mtl", cr("newmtl red\nKd 1 0 0\n"));
    let obj = "mtllib mac.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl red\nf 1 2 3\nf 2 4 3\n";
    let mesh = load_mesh(&write(d, "mac.obj", cr(obj)), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles.len(), 2);
    assert_eq!(mesh.materials[0].base_color, [1.0, 0.0, 0.0, 1.0]);
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
               property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
               end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let mesh = load_mesh(&write(d, "mac.ply", cr(ply)), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    // And a binary PLY whose header lines end in CR alone.
    let mut binary = cr("ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
                         property float x\nproperty float y\nproperty float z\n\
                         element face 1\nproperty list uchar int vertex_indices\nend_header\n")
    .into_bytes();
    // Its first vertex's x begins with a \n byte: the body, not a CR LF.
    let x = f32::from_le_bytes([b'\n', 0, 0, 0]);
    binary.extend(floats(&[x, 0., 0., 1., 0., 0., 0., 1., 0.]));
    binary.push(3);
    binary.extend([0i32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    let mesh = load_mesh(&write(d, "macb.ply", binary), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(mesh.positions[0].x, x as f64);
}

/// Item 11: an OBJ whose faces name texture coordinates when it has no
/// `vt` (trimesh's cubevt.obj) loads, as trimesh reads it: the UVs are
/// dropped with one warning naming the file and the first such face.
#[test]
fn obj_faces_naming_vt_with_none_defined_drop_them_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let obj =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 2/2/1 4/4/1 3/3/1\n";
    let path = write(dir.path(), "cubevt.obj", obj);
    let mesh = load_mesh(&path, NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles.len(), 2);
    assert_eq!(mesh.uvs, None);
    let warnings = mesh.warnings.join("\n");
    assert!(
        warnings
            .contains("cubevt.obj:6: 2 faces naming texture coordinates where the file has no vt"),
        "{warnings}"
    );
}

/// Item 11: `map_Kd` paths as MeshLab and Blender write them — options
/// first, then the rest of the line as the name, runs of spaces kept, and
/// backslashes read as folder separators where the name as written is
/// not a file; `-clamp on` clamps (glTF's CLAMP_TO_EDGE), and is no
/// skipped option.
#[test]
fn mtl_image_paths_and_clamp_as_exporters_write_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("textures")).unwrap();
    write(&d.join("textures"), "grid.png", png());
    write(d, "my  two  spaces.png", png());
    write(d, "plain.png", png());
    let mtl = "newmtl back\nmap_Kd textures\\grid.png\n\
               newmtl spaced\nmap_Kd -s 1 1 1 -bm 0.5 my  two  spaces.png  \n\
               newmtl clamped\nmap_Kd -clamp on plain.png\n\
               newmtl repeated\nmap_Kd -clamp off plain.png\n";
    write(d, "e.mtl", mtl);
    let obj = "mtllib e.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n\
               usemtl back\nf 1/1 2/1 3/1\nusemtl spaced\nf 1/1 2/1 3/1\n\
               usemtl clamped\nf 1/1 2/1 3/1\nusemtl repeated\nf 1/1 2/1 3/1\n";
    let mesh = load_mesh(&write(d, "e.obj", obj), NormalMode::Face).unwrap();
    let warnings = mesh.warnings.join("\n");
    let image_of = |m: usize| {
        let texture = mesh.materials[m]
            .base_color_texture
            .unwrap_or_else(|| panic!("material {m} has its texture: {warnings}"));
        (mesh.images[texture.image as usize].clone(), texture.sampler)
    };
    let file = |p: &Path| ImageSource::File(p.to_path_buf());
    assert_eq!(image_of(0).0, file(&d.join("textures/grid.png")));
    assert_eq!(image_of(1).0, file(&d.join("my  two  spaces.png")));
    let (clamped, sampler) = image_of(2);
    assert_eq!(clamped, file(&d.join("plain.png")));
    assert_eq!(
        (sampler.wrap_u, sampler.wrap_v),
        (Wrap::ClampToEdge, Wrap::ClampToEdge)
    );
    let sampler = image_of(3).1;
    assert_eq!(
        (sampler.wrap_u, sampler.wrap_v),
        (Wrap::Repeat, Wrap::Repeat)
    );
    // -bm is skipped with its warning; -clamp is read.
    assert!(
        warnings.contains("texture options -bm skipped"),
        "{warnings}"
    );
    assert!(!warnings.contains("-clamp skipped"), "{warnings}");
    // The backslashed name, when neither reading is a file, names both.
    write(d, "b.mtl", "newmtl b\nmap_Kd maps\\none.png\n");
    let obj = "mtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl b\nf 1 2 3\n";
    let mesh = load_mesh(&write(d, "b.obj", obj), NormalMode::Face).unwrap();
    let warnings = mesh.warnings.join("\n");
    assert_contains_all(
        &warnings,
        &["image 'maps\\none.png' is not found", "maps/none.png"],
    );
}

/// Item 12: a flat model with no camera is framed from off its plane:
/// a square in each axis plane, and in a plane that holds the default
/// view direction (1, 0.75, 2), covers a good part of the image rather
/// than a sliver.
#[test]
fn flat_models_are_framed_from_off_their_plane() {
    let dir = tempfile::tempdir().unwrap();
    let edge_on = glam::DVec3::new(1.0, 0.75, 2.0).normalize();
    // The least part of the image each must cover: seen from 60° off its
    // plane, an axis-aligned square covers about a quarter of it; the
    // tilted one's larger bounding box frames it smaller.
    let planes = [
        ("xy", glam::DVec3::X, glam::DVec3::Y, 0.2),
        ("yz", glam::DVec3::Y, glam::DVec3::Z, 0.2),
        ("xz", glam::DVec3::X, glam::DVec3::Z, 0.2),
        (
            "edge-on",
            edge_on,
            edge_on.cross(glam::DVec3::Y).normalize(),
            0.1,
        ),
    ];
    let mut covered = Vec::new();
    for (name, a, b, least) in planes {
        let corners = [-a - b, a - b, a + b, -a + b].map(|p| 3.0 * p + glam::DVec3::splat(5.0));
        let mut obj: String = corners
            .iter()
            .map(|p| format!("v {} {} {}\n", p.x, p.y, p.z))
            .collect();
        obj += "f 1 2 3\nf 1 3 4\n";
        let path = write(dir.path(), &format!("{name}.obj"), obj);
        let mut scene = Scene::load(&path).unwrap();
        scene.view_mut().camera.width = 64;
        scene.view_mut().camera.height = 48;
        let image = render_cpu(&scene);
        let hit = image.prims.iter().filter(|&&p| p != NO_HIT).count();
        covered.push((name, hit as f64 / image.prims.len() as f64, least));
    }
    assert!(
        covered.iter().all(|&(_, fraction, least)| fraction > least),
        "the fraction of the image each square covers, and its least: {covered:?}"
    );
}

/// Item 11: `-clamp on` reaches the pixel. A quad whose u runs 0 to 4
/// over a red-then-blue image: repeated, as many pixels are red as blue;
/// clamped, past u = 1 they read the blue edge.
#[test]
fn mtl_clamp_on_clamps_in_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let image = image::RgbaImage::from_fn(2, 1, |x, _| {
        image::Rgba(if x == 0 {
            [255, 0, 0, 255]
        } else {
            [0, 0, 255, 255]
        })
    });
    image.save(d.join("rb.png")).unwrap();
    let obj = "mtllib q.mtl\nv 0 0 0\nv 4 0 0\nv 4 1 0\nv 0 1 0\n\
               vt 0 0\nvt 4 0\nvt 4 1\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3 4/4\n";
    let mut blue_share = Vec::new();
    for clamp in ["off", "on"] {
        write(
            d,
            "q.mtl",
            format!("newmtl m\nKd 1 1 1\nmap_Kd -clamp {clamp} rb.png\n"),
        );
        let mut scene = Scene::load(&write(d, "q.obj", obj)).unwrap();
        scene.view_mut().camera.width = 64;
        scene.view_mut().camera.height = 48;
        let image = render_cpu(&scene);
        let hit: Vec<[f32; 3]> = (0..image.prims.len())
            .filter(|&i| image.prims[i] != NO_HIT)
            .map(|i| image.image.rgb[i])
            .collect();
        let blue = hit.iter().filter(|c| c[2] > c[0]).count();
        blue_share.push(blue as f64 / hit.len() as f64);
    }
    assert!(
        (0.35..0.65).contains(&blue_share[0]) && blue_share[1] > 0.8,
        "blue pixels' share, repeated and clamped: {blue_share:?}"
    );
}
