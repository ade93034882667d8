//! Model formats (issue 17): PLY, OBJ with MTL, glTF/GLB, the `file` key, a model file alone.

mod common;

use std::path::{Path, PathBuf};

use common::*;
use glam::DVec3;
use lambert::Scene;
use lambert::loading::{NormalMode, load_mesh};

fn meshes(name: &str) -> PathBuf {
    asset(&format!("scenes/meshes/{name}"))
}

/// Asserts that `text` contains each of `parts`.
fn assert_has(text: &str, parts: &[&str]) {
    for part in parts {
        assert!(text.contains(part), "lacks '{part}': {text}");
    }
}

/// The one warning `mesh` has.
fn only_warning(mesh: &lambert::loading::Mesh) -> &str {
    assert_eq!(mesh.warnings.len(), 1, "{:?}", mesh.warnings);
    &mesh.warnings[0]
}

/// The bunny scene with its mesh read from `file` (relative to
/// assets/scenes), through the `file` key.
fn bunny_from(file: &str) -> Scene {
    let text = std::fs::read_to_string(asset("scenes/bunny.toml"))
        .unwrap()
        .replace(
            "obj = \"meshes/bunny_lowres.obj\"",
            &format!("file = \"{file}\""),
        );
    assert!(text.contains(file));
    scene(&text)
}

#[test]
fn ply_and_obj_give_the_same_image_bit_for_bit_on_both_paths() {
    let obj = bunny_from("meshes/bunny_lowres.obj");
    for ply in [
        "meshes/bunny_lowres.ply",
        "meshes/bunny_lowres_ascii.ply.gz",
    ] {
        let ply = bunny_from(ply);
        assert_eq!(obj.triangles(), ply.triangles());
        assert_eq!(obj.normals(), ply.normals(), "smooth normals");
        assert_eq!(bits(&render_cpu(&obj)), bits(&render_cpu(&ply)));
        assert_eq!(bits(&render_gpu(&obj)), bits(&render_gpu(&ply)));
    }
}

#[test]
fn ply_encodings_types_and_lists() {
    let dir = tempfile::tempdir().unwrap();
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\ncomment two triangles as a quad\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\n\
             element edge 1\nproperty int vertex1\nproperty int vertex2\n\
             element face 1\nproperty list ushort short vertex_index\nproperty list uchar float texcoord\nend_header\n"
        )
    };
    let vertices = [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut ascii = header("ascii");
    for v in vertices {
        ascii += &format!("{} {} {} 0 0 1 255\n", v[0], v[1], v[2]);
    }
    ascii += "0 1\n4 0 1 2 3 2 0.5 0.5\n";
    let mut big = header("binary_big_endian").into_bytes();
    let mut little = header("binary_little_endian").into_bytes();
    for (out, be) in [(&mut big, true), (&mut little, false)] {
        let f = |x: f32| if be { x.to_be_bytes() } else { x.to_le_bytes() };
        for v in vertices {
            for c in v.into_iter().chain([0.0, 0.0, 1.0]) {
                out.extend(f(c));
            }
            out.push(255);
        }
        let i32b = |x: i32| if be { x.to_be_bytes() } else { x.to_le_bytes() };
        out.extend(i32b(0));
        out.extend(i32b(1));
        let u16b = |x: u16| if be { x.to_be_bytes() } else { x.to_le_bytes() };
        out.extend(u16b(4));
        for i in [0i16, 1, 2, 3] {
            out.extend(if be { i.to_be_bytes() } else { i.to_le_bytes() });
        }
        out.push(2);
        out.extend(f(0.5));
        out.extend(f(0.5));
    }
    for (name, bytes) in [
        ("a.ply", ascii.into_bytes()),
        ("be.ply", big),
        ("le.ply", little),
    ] {
        let path = write(dir.path(), name, bytes);
        let mesh = load_mesh(&path, NormalMode::Smooth).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]], "{name}");
        assert_eq!(mesh.positions[2], DVec3::new(1.0, 1.0, 0.0), "{name}");
        assert!(mesh.file_normals, "{name}");
        assert_eq!(mesh.normals.unwrap()[1], [DVec3::Z; 3], "{name}");
    }
}

#[test]
fn malformed_ply_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let ok_header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let binary_header = |vertices: u64| {
        format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let mut truncated = binary_header(3).into_bytes();
    truncated.extend([0u8; 36]);
    truncated.extend([3u8, 0, 0, 0, 0]);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("not.ply", b"plx\nformat ascii 1.0\n".to_vec(), "not.ply:1: not a PLY file"),
        ("format.ply", b"ply\nformat binary_middle_endian 1.0\nend_header\n".to_vec(), "format.ply:2: unknown format line"),
        ("noend.ply", b"ply\nformat ascii 1.0\nelement vertex 1\n".to_vec(), "no end_header"),
        ("type.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n".to_vec(), "type.ply:4: unknown property type 'quad'"),
        ("range.ply", format!("{ok_header}0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n").into_bytes(), "range.ply:13: face 0: vertex index 3 is out of range"),
        ("nan.ply", format!("{ok_header}0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").into_bytes(), "nan.ply:11: vertex 1: coordinate NaN must be finite"),
        ("huge.ply", format!("{ok_header}0 0 0\n1 1e30 0\n0 1 0\n3 0 1 2\n").into_bytes(), "vertex 1: coordinate 1000000000000000000000000000000 must be finite"),
        ("word.ply", format!("{ok_header}0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n").into_bytes(), "word.ply:11: vertex 1: 'x' is not a number"),
        ("short.ply", format!("{ok_header}0 0 0\n1 0 0\n").into_bytes(), "only 2 lines follow"),
        ("truncated.ply", truncated, "face 0: the file ends inside it"),
        ("claims.ply", { let mut b = binary_header(4_000_000_000).into_bytes(); b.extend([0u8; 64]); b }, "declares 4000000000 'vertex' elements"),
        ("points.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n".to_vec(), "points.ply: no triangles (1 points, 0 lines skipped)"),
        ("noxyz.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0\n".to_vec(), "no 'z' property"),
        ("two.ply", format!("{ok_header}0 0 0\n1 0 0\n0 1 0\n2 0 1\n").into_bytes(), "a face needs at least 3 vertices"),
        ("gz.ply.gz", b"not gzip".to_vec(), "not a readable gzip file"),
    ];
    for (name, bytes, expected) in cases {
        let path = write(dir.path(), name, bytes);
        let start = std::time::Instant::now();
        let message = error_of(&path);
        assert!(message.contains(name), "{name}: {message}");
        assert!(
            message.contains(expected),
            "{name}: expected '{expected}' in: {message}"
        );
        assert!(
            start.elapsed().as_secs() < 5,
            "{name} took {:?}",
            start.elapsed()
        );
    }
}

/// Issue 28 item 11: a face element declared before the vertex element
/// loads (indices are checked once every element is read); an ascii line
/// with more values than the header declares (VCGLib writes them) reads
/// the declared ones with one warning naming the first line; elements and
/// properties lambert does not read are named in one warning.
#[test]
fn ply_faces_first_extra_values_and_unread_properties() {
    let dir = tempfile::tempdir().unwrap();
    let faces_first = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement face 1\nproperty list uchar int vertex_indices\n\
             element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
        )
    };
    let ascii = faces_first("ascii") + "3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n";
    let mut binary = faces_first("binary_little_endian").into_bytes();
    binary.push(3);
    for i in [0i32, 1, 2] {
        binary.extend(i.to_le_bytes());
    }
    for c in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        binary.extend(c.to_le_bytes());
    }
    // 64-bit integers (trimesh reads them): a vertex id, skipped, and the
    // indices.
    let mut wide = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty int64 id\n\
                     property float x\nproperty float y\nproperty float z\n\
                     element face 1\nproperty list uchar uint64 vertex_indices\nend_header\n"
        .to_vec();
    for (id, v) in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        .iter()
        .enumerate()
    {
        wide.extend((-(id as i64)).to_be_bytes());
        for c in v {
            wide.extend(c.to_be_bytes());
        }
    }
    wide.push(3);
    for i in [0u64, 1, 2] {
        wide.extend(i.to_be_bytes());
    }
    let mesh = load_mesh(&write(dir.path(), "wide.ply", wide), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(mesh.positions[2], DVec3::Y);

    for (name, bytes) in [("first.ply", ascii.into_bytes()), ("first-le.ply", binary)] {
        let mesh = load_mesh(&write(dir.path(), name, bytes), NormalMode::Face).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2]], "{name}");
        assert_eq!(mesh.positions[1], DVec3::X, "{name}");
        assert!(mesh.warnings.is_empty(), "{name}: {:?}", mesh.warnings);
    }
    // An index past the vertices is still an error, at the face's line.
    let beyond = faces_first("ascii") + "3 0 1 3\n0 0 0\n1 0 0\n0 1 0\n";
    let message = error_of(&write(dir.path(), "beyond.ply", beyond));
    assert!(
        message.contains(
            "beyond.ply:10: face 0: vertex index 3 is out of range: the file has 3 vertices"
        ),
        "{message}"
    );

    let surplus = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                   element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                   0 0 0\n1 0 0 0.5 0.5\n0 1 0 1 1\n3 0 1 2 6 0 0 1 0 0 1\n";
    let mesh = load_mesh(&write(dir.path(), "surplus.ply", surplus), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(mesh.positions[2], DVec3::Y);
    assert_has(
        only_warning(&mesh),
        &[
            "surplus.ply:11: vertex 1: 5 values on the line, the header declares 3",
            "ignored (on 3 lines in all)",
        ],
    );

    let extra = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                 property uchar red\nelement face 1\nproperty list uchar int vertex_indices\nproperty uchar flags\n\
                 element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n\
                 0 0 0 255\n1 0 0 255\n0 1 0 255\n3 0 1 2 7\n0 1\n";
    let mesh = load_mesh(&write(dir.path(), "extra.ply", extra), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_has(
        only_warning(&mesh),
        &["extra.ply: ignored", "vertex red, face flags, element edge"],
    );
}

#[test]
fn obj_materials_from_mtl_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "colours.mtl",
        "# made by hand\nnewmtl red.paint-1\nKd 0.8 0.1 0.1\nnewmtl blue\nKa 0 0 0\nKd 0.1 0.1 0.9\n",
    );
    write(
        d,
        "boxes.obj",
        "mtllib colours.mtl missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nusemtl red.paint-1\nf 2 4 3\nusemtl blue\nf 1 3 2\nusemtl nonesuch\nf 2 3 4\n",
    );
    let mesh = load_mesh(&d.join("boxes.obj"), NormalMode::Face).unwrap();
    assert_eq!(mesh.face_materials, vec![None, Some(0), Some(1), None]);
    assert_eq!(albedos(&mesh), vec![[0.8, 0.1, 0.1], [0.1, 0.1, 0.9]]);
    let warnings = mesh.warnings.join("\n");
    assert!(warnings.contains("missing.mtl"), "{warnings}");
    assert!(
        warnings.contains("boxes.obj:11: unknown material 'nonesuch'"),
        "{warnings}"
    );

    let camera = "[camera]\neye = [0.5, 0.5, 3.0]\nlook_at = [0.5, 0.5, 0.0]\nvfov = 40.0\nwidth = 8\nheight = 8\n[render]\nambient = 1.0\nshadows = false\n";
    let scene_at = |extra: &str| {
        let text = format!("{camera}[[mesh]]\nfile = \"boxes.obj\"\n{extra}");
        Scene::from_toml(&text, &d.join("s.toml")).unwrap()
    };
    let s = scene_at("");
    let albedo = |t: usize| s.materials()[s.triangles()[t].material as usize].albedo();
    assert_eq!(
        [albedo(0), albedo(1), albedo(2), albedo(3)],
        [[0.8; 3], [0.8, 0.1, 0.1], [0.1, 0.1, 0.9], [0.8; 3]]
    );
    assert_eq!(s.warnings().len(), 2);
    let overridden = scene_at("albedo = [0.2, 0.3, 0.4]\n");
    assert!(
        overridden
            .triangles()
            .iter()
            .all(|t| overridden.materials()[t.material as usize].albedo() == [0.2, 0.3, 0.4])
    );
    // Per-face materials on both paths: ambient 1 shows each face's albedo.
    let (gpu, cpu) = (render_gpu(&s), render_cpu(&s));
    assert_eq!(gpu.prims, cpu.prims);
    let stats = lambert::diff::compare(&gpu, &cpu, &Default::default()).unwrap();
    assert!(stats.passed, "{stats}");
    let reds = cpu
        .image
        .rgb
        .iter()
        .filter(|p| **p == [0.8, 0.1, 0.1])
        .count();
    assert!(reds > 0, "no pixel shows the red material");

    for (mtl, expected) in [
        (
            "newmtl a\nKd 0.5 0.5\n",
            "bad.mtl:2: Kd needs 1 or 3 numbers (r [g b]), found 2",
        ),
        (
            "newmtl a\nKd 0.5 x 0.5\n",
            "bad.mtl:2: Kd: 'x' is not a number",
        ),
        (
            "newmtl a\nKd 0.5 -1 0.5\n",
            "bad.mtl:2: Kd: -1 must be finite and non-negative",
        ),
        ("Kd 1 1 1\n", "bad.mtl:1: Kd before any newmtl"),
    ] {
        write(d, "bad.mtl", mtl);
        write(
            d,
            "bad.obj",
            "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        let message = error_of(&d.join("bad.obj"));
        assert!(message.contains(expected), "{message}");
    }
}

#[test]
fn gltf_hierarchy_camera_lights_and_materials() {
    let path = meshes("boxes.glb");
    let g = lambert::loading::gltf::load_scene(&path, NormalMode::Face).unwrap();
    assert_eq!(g.mesh.triangles.len(), 12 + 2);
    // The box: scaled 1.5 by its node, raised 0.75, then turned 30° about
    // y and moved 0.5 along x by its parent.
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let corner = DVec3::new(0.75, 1.5, 0.75);
    let expected = DVec3::new(
        corner.x * c + corner.z * s + 0.5,
        corner.y,
        -corner.x * s + corner.z * c,
    );
    assert!(
        g.mesh
            .positions
            .iter()
            .any(|p| (*p - expected).length() < 1e-6),
        "no box corner at {expected}"
    );
    assert_eq!(albedos(&g.mesh), vec![[0.8, 0.1, 0.1], [0.6, 0.6, 0.6]]);
    let camera = &g.cameras[0];
    assert_eq!(camera.name.as_deref(), Some("view"));
    let pitch = (2.0f64).atan2(7.0);
    assert!((camera.eye - DVec3::new(0.0, 2.5, 7.0)).length() < 1e-6);
    assert!((camera.forward - DVec3::new(0.0, -pitch.sin(), -pitch.cos())).length() < 1e-6);
    assert!((camera.yfov_deg - 40.0).abs() < 1e-4);
    assert!((camera.aspect_ratio.unwrap() - 4.0 / 3.0).abs() < 1e-6);

    let scene = Scene::load(&path).unwrap();
    assert_eq!(
        (scene.view().camera.width, scene.view().camera.height),
        (1024, 768)
    );
    assert_eq!(scene.lights().len(), 2);
    let point = scene
        .lights()
        .iter()
        .find(|l| l.kind == lambert::layout::LIGHT_POINT)
        .unwrap();
    assert_eq!(point.vector, [-3.0, 4.0, 3.0]);
    assert_eq!(point.color, [40.0, 36.0, 32.0]);
    let sun = scene
        .lights()
        .iter()
        .find(|l| l.kind == lambert::layout::LIGHT_DIRECTIONAL)
        .unwrap();
    let to_light = DVec3::new(0.0, 60f64.to_radians().sin(), 60f64.to_radians().cos());
    assert!((glam::Vec3::from(sun.vector).as_dvec3() - to_light).length() < 1e-6);
    assert!((glam::Vec3::from(sun.color) - glam::Vec3::new(0.75, 0.75, 0.9)).length() < 1e-6);

    let mut small = scene.clone();
    small.view_mut().camera.width = 64;
    small.view_mut().camera.height = 48;
    let (gpu, cpu) = (render_gpu(&small), render_cpu(&small));
    let stats = lambert::diff::compare(&gpu, &cpu, &Default::default()).unwrap();
    assert!(stats.passed, "{stats}");
    assert!(cpu.prims.iter().any(|&p| p < 12) && cpu.prims.iter().any(|&p| p == 12 || p == 13));
}

#[test]
fn gltf_in_a_toml_scene_brings_geometry_only() {
    let text = "[camera]\neye = [0.0, 8.0, 0.1]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 50.0\nwidth = 8\nheight = 8\n\
                [[mesh]]\nfile = \"meshes/BOXES.GLB\"\nscale = 2.0\n[[point_light]]\nposition = [0.0, 5.0, 0.0]\nintensity = 1.0\n";
    // The extension is matched case-insensitively; the file itself is boxes.glb.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("meshes")).unwrap();
    std::fs::copy(meshes("boxes.glb"), dir.path().join("meshes/BOXES.GLB")).unwrap();
    let s = Scene::from_toml(text, &dir.path().join("s.toml")).unwrap();
    assert_eq!(s.lights().len(), 1);
    assert_eq!(s.view().camera.vfov, 50.0);
    assert_eq!(s.triangles().len(), 14);
    let max_x = s
        .triangles()
        .iter()
        .flat_map(|t| [t.v0[0], t.v1[0], t.v2[0]])
        .fold(f32::MIN, f32::max);
    assert_eq!(max_x, 6.0, "scale = 2 applies to glTF geometry");
}

/// Writes a .gltf whose JSON is `json` with one buffer of `buffer` bytes
/// as a data URI (or `uri` as given).
fn gltf_file(dir: &Path, name: &str, json: serde_json::Value) -> PathBuf {
    write(dir, name, serde_json::to_vec(&json).unwrap())
}

/// `doc` with each key of `extra` set (replacing what it had).
fn merged(mut doc: serde_json::Value, extra: serde_json::Value) -> serde_json::Value {
    for (k, v) in extra.as_object().unwrap() {
        doc[k] = v.clone();
    }
    doc
}

fn triangle_gltf(
    buffer_uri: &str,
    byte_length: usize,
    count: usize,
    extra: serde_json::Value,
) -> serde_json::Value {
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"uri": buffer_uri, "byteLength": byte_length}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}]
    });
    merged(doc, extra)
}

#[test]
fn gltf_data_uris_external_buffers_and_malformed_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let floats: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    use base64_like::encode;
    let data_uri = format!("data:application/octet-stream;base64,{}", encode(&floats));
    let ok = gltf_file(
        d,
        "ok.gltf",
        triangle_gltf(&data_uri, 36, 3, serde_json::json!({})),
    );
    assert_eq!(
        load_mesh(&ok, NormalMode::Face).unwrap().triangles,
        vec![[0, 1, 2]]
    );
    write(d, "tri.bin", &floats);
    let external = gltf_file(
        d,
        "external.gltf",
        triangle_gltf("tri.bin", 36, 3, serde_json::json!({})),
    );
    assert_eq!(
        load_mesh(&external, NormalMode::Face)
            .unwrap()
            .positions
            .len(),
        3
    );

    let cases = [
        (
            write(d, "json.gltf", "{\"asset\": "),
            "json.gltf: not a readable glTF file",
        ),
        (
            gltf_file(
                d,
                "missing.gltf",
                triangle_gltf("nothere.bin", 36, 3, serde_json::json!({})),
            ),
            "reading buffer 0 (\"nothere.bin\"): ",
        ),
        (
            gltf_file(
                d,
                "short.gltf",
                triangle_gltf(
                    &format!(
                        "data:application/octet-stream;base64,{}",
                        encode(&floats[..24])
                    ),
                    36,
                    3,
                    serde_json::json!({}),
                ),
            ),
            "buffer 0 (its data URI) holds 24 bytes, but its byteLength is 36",
        ),
        (
            gltf_file(
                d,
                "beyond.gltf",
                triangle_gltf(&data_uri, 36, 4, serde_json::json!({})),
            ),
            "accessor 0 (4 elements) reaches beyond its buffer view 0",
        ),
        (
            gltf_file(
                d,
                "draco.gltf",
                triangle_gltf(
                    &data_uri,
                    36,
                    3,
                    serde_json::json!({"extensionsUsed": ["KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"]}),
                ),
            ),
            "requires the extension KHR_draco_mesh_compression",
        ),
        (
            gltf_file(
                d,
                "points.gltf",
                triangle_gltf(
                    &data_uri,
                    36,
                    3,
                    serde_json::json!({"meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 0}]}]}),
                ),
            ),
            "no triangles",
        ),
        (
            gltf_file(
                d,
                "index.gltf",
                triangle_gltf(
                    &data_uri,
                    36,
                    3,
                    serde_json::json!({"nodes": [{"mesh": 5}]}),
                ),
            ),
            "invalid glTF: nodes[0].mesh: ",
        ),
    ];
    // What lambert's model lacks is a warning: spot lights, range,
    // textures, non-triangle modes; a second node places the mesh again.
    let warned = gltf_file(
        d,
        "warned.gltf",
        triangle_gltf(
            &data_uri,
            36,
            3,
            serde_json::json!({
                "extensionsUsed": ["KHR_lights_punctual"],
                "extensions": {"KHR_lights_punctual": {"lights": [
                    {"name": "spot", "type": "spot", "intensity": 2.0, "spot": {}},
                    {"name": "lamp", "type": "point", "intensity": 3.0, "range": 10.0}
                ]}},
                "nodes": [
                    {"mesh": 0, "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 5.0, 0.0, 0.0, 1.0]},
                    {"extensions": {"KHR_lights_punctual": {"light": 0}}},
                    {"translation": [0.0, 0.0, 4.0], "extensions": {"KHR_lights_punctual": {"light": 1}}},
                    {"mesh": 1}
                ],
                "scenes": [{"nodes": [0, 1, 2, 3]}],
                "meshes": [
                    {"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]},
                    {"primitives": [{"attributes": {"POSITION": 0}, "mode": 1}]}
                ],
                "materials": [{"name": "painted", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
                "textures": [{"source": 0}],
                "images": [{"uri": "paint.png"}]
            }),
        ),
    );
    let scene = Scene::load(&warned).unwrap();
    let warnings = scene.warnings().join("\n");
    for expected in [
        "light spot: a spot light, skipped",
        "light lamp: its range is ignored",
        "image 0: ",
        "paint.png is not found; the materials using it keep their factors",
        "mode Lines skipped",
    ] {
        assert!(
            warnings.contains(expected),
            "lacks '{expected}': {warnings}"
        );
    }
    assert_eq!(scene.lights().len(), 1);
    assert_eq!(scene.lights()[0].vector, [0.0, 0.0, 4.0]);
    assert_eq!(scene.lights()[0].color, [3.0; 3]);
    // The node's matrix (column-major) moved the triangle 5 along x.
    assert_eq!(scene.triangles()[0].v1, [6.0, 0.0, 0.0]);

    for (path, expected) in cases {
        let message = error_of(&path);
        assert!(
            message.contains(expected),
            "{}: expected '{expected}' in: {message}",
            path.display()
        );
        assert!(
            message.contains(&*path.file_name().unwrap().to_string_lossy()),
            "{message}"
        );
        assert!(!message.contains("invalid glTF: invalid glTF"), "{message}");
    }
}

/// A glTF of one tetrahedron (four vertices, u16 indices wound so that
/// every face's geometric normal faces out), with `extra` merged in (its
/// nodes, materials, …).
fn tetrahedron_gltf(extra: serde_json::Value) -> serde_json::Value {
    let mut bytes: Vec<u8> = [
        0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0,
    ]
    .iter()
    .flat_map(|f| f.to_le_bytes())
    .collect();
    bytes.extend(
        [0u16, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3]
            .iter()
            .flat_map(|i| i.to_le_bytes()),
    );
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64_like::encode(&bytes)
    );
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"uri": uri, "byteLength": 72}],
        "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}
        ]
    });
    merged(doc, extra)
}

/// Issue 28 item 5: a mirroring node (negative determinant) flips its
/// triangles' winding, as the spec's clockwise front faces ask, so that
/// geometric normals still face out; a matrix or two mirrors alike.
#[test]
fn gltf_mirrored_nodes_keep_their_normals_facing_out() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "scale.gltf",
            serde_json::json!([{"mesh": 0, "scale": [-1.0, 1.0, 1.0]}]),
            true,
        ),
        (
            "matrix.gltf",
            serde_json::json!([{"mesh": 0, "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -2.0, 0.0, 3.0, 0.0, 0.0, 1.0]}]),
            true,
        ),
        (
            "twice.gltf",
            serde_json::json!([{"scale": [-1.0, 1.0, 1.0], "children": [1]}, {"mesh": 0, "scale": [1.0, -1.0, 1.0]}]),
            false,
        ),
    ];
    for (name, nodes, mirrored) in cases {
        let path = gltf_file(
            dir.path(),
            name,
            tetrahedron_gltf(serde_json::json!({"nodes": nodes})),
        );
        let mesh = load_mesh(&path, NormalMode::Face).unwrap();
        assert_eq!(mesh.triangles.len(), 4, "{name}");
        let centre = mesh.positions.iter().sum::<DVec3>() / 4.0;
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let outward = (a + b + c) / 3.0 - centre;
            assert!(
                (b - a).cross(c - a).dot(outward) > 0.0,
                "{name}: triangle {t:?} faces in"
            );
        }
        // The first face (0, 2, 1) keeps its first corner; a mirror swaps the others.
        let expected = if mirrored { [0, 1, 2] } else { [0, 2, 1] };
        assert_eq!(mesh.triangles[0], expected, "{name}");
    }
}

/// Issue 28 item 5: a rotation that is not a unit quaternion is
/// normalised (as trimesh, Blender and three.js do) with one warning
/// naming the node; one of length 0 is an error.
#[test]
fn gltf_rotations_are_normalised_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let load = |name: &str, rotation: [f64; 4]| {
        let nodes = serde_json::json!([{"mesh": 0, "name": "spun", "rotation": rotation}]);
        let path = gltf_file(
            dir.path(),
            name,
            tetrahedron_gltf(serde_json::json!({"nodes": nodes})),
        );
        Scene::load(&path).map(|_| load_mesh(&path, NormalMode::Face).unwrap())
    };
    for (unit, scaled) in [
        ([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 2.0]),
        ([0.0, 0.0, h, h], [0.0, 0.0, 2.0 * h, 2.0 * h]),
    ] {
        let unit_mesh = load("unit.gltf", unit).unwrap();
        assert!(unit_mesh.warnings.is_empty(), "{:?}", unit_mesh.warnings);
        let mesh = load("scaled.gltf", scaled).unwrap();
        for (p, q) in mesh.positions.iter().zip(&unit_mesh.positions) {
            assert!((*p - *q).length() < 1e-6, "{scaled:?}: {p} for {q}");
        }
        assert_has(
            only_warning(&mesh),
            &[
                "scaled.gltf",
                "node 0 'spun'",
                "has length 2.0000, not 1",
                "normalised",
            ],
        );
    }
    // A quarter turn about z takes x to y.
    let turned = load("turned.gltf", [0.0, 0.0, 2.0 * h, 2.0 * h]).unwrap();
    assert!((turned.positions[1] - DVec3::Y).length() < 1e-6);
    let message = load("zero.gltf", [0.0; 4]).unwrap_err().to_string();
    assert_has(
        &message,
        &["zero.gltf", "node 0 'spun'", "cannot be normalised"],
    );
}

/// Issue 28 items 5 and 18: a negative baseColorFactor component is
/// clamped to 0 with a warning (it would be negative radiance). Issue 30
/// item 4: emission (emissiveFactor × KHR_materials_emissive_strength) is
/// read, and rendered, so it is no longer a warning.
#[test]
fn gltf_negative_colours_are_clamped_and_emission_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let material =
        |m: u32| serde_json::json!({"attributes": {"POSITION": 0}, "indices": 1, "material": m});
    let path = gltf_file(
        dir.path(),
        "lit.gltf",
        tetrahedron_gltf(serde_json::json!({
            "extensionsUsed": ["KHR_materials_emissive_strength"],
            "meshes": [{"primitives": [material(0), material(1), material(2), material(1)]}],
            "materials": [
                {"name": "paint", "pbrMetallicRoughness": {"baseColorFactor": [-0.5, 0.25, 2.0, 1.0]}},
                {"name": "lamp", "emissiveFactor": [1.0, 0.5, 0.0],
                 "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 5.0}}},
                {"name": "glow", "emissiveFactor": [0.0, 0.0, 1.0]}
            ]
        })),
    );
    let mesh = load_mesh(&path, NormalMode::Face).unwrap();
    assert_eq!(albedos(&mesh), vec![[0.0, 0.25, 2.0], [1.0; 3], [1.0; 3]]);
    let emissive: Vec<[f32; 3]> = mesh.materials.iter().map(|m| m.emissive).collect();
    assert_eq!(emissive, vec![[0.0; 3], [5.0, 2.5, 0.0], [0.0, 0.0, 1.0]]);
    assert_eq!(mesh.warnings.len(), 1, "{:?}", mesh.warnings);
    let clamped = &mesh.warnings[0];
    assert_has(
        clamped,
        &["lit.gltf", "material paint", "-0.5", "clamped to 0"],
    );
    // A material without emission or a negative colour: no warning.
    let plain = gltf_file(
        dir.path(),
        "plain.gltf",
        tetrahedron_gltf(serde_json::json!({
            "meshes": [{"primitives": [material(0)]}],
            "materials": [{"name": "paint", "emissiveFactor": [0.0, 0.0, 0.0]}]
        })),
    );
    let warnings = load_mesh(&plain, NormalMode::Face).unwrap().warnings;
    assert!(warnings.is_empty(), "{warnings:?}");
}

/// Issue 28 item 6: accessors and buffer views the gltf crate would read
/// past (or panic on: a byteStride below the element's size) are errors
/// that name the file and the accessor, never a panic.
#[test]
fn gltf_malformed_accessors_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let json = |extra: serde_json::Value| tetrahedron_gltf(extra);
    let positions = |extra: serde_json::Value| {
        let accessor = serde_json::json!({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                                          "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]});
        merged(accessor, extra)
    };
    let indices =
        serde_json::json!({"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"});
    let views = |first: serde_json::Value| serde_json::json!([first, {"buffer": 0, "byteOffset": 48, "byteLength": 24}]);
    let cases = [
        (
            "stride.gltf",
            json(
                serde_json::json!({"bufferViews": views(serde_json::json!({"buffer": 0, "byteLength": 48, "byteStride": 8}))}),
            ),
            "POSITION accessor 0: its buffer view 0 has byteStride 8, less than one element (12 bytes)",
        ),
        (
            "normal-stride.gltf",
            json(serde_json::json!({
                "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 2}, "indices": 1}]}],
                "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24},
                                {"buffer": 0, "byteLength": 48, "byteStride": 4}],
                "accessors": [positions(serde_json::json!({})), indices, positions(serde_json::json!({"bufferView": 2}))]
            })),
            "NORMAL accessor 2: its buffer view 2 has byteStride 4",
        ),
        (
            "view.gltf",
            json(
                serde_json::json!({"bufferViews": views(serde_json::json!({"buffer": 0, "byteOffset": 40, "byteLength": 48}))}),
            ),
            "accessor 0: buffer view 0 ends beyond its buffer (72 bytes)",
        ),
        (
            "offset.gltf",
            json(
                serde_json::json!({"accessors": [positions(serde_json::json!({"byteOffset": 4})), indices]}),
            ),
            "accessor 0 (4 elements) reaches beyond its buffer view 0 (48 bytes)",
        ),
        (
            "empty.gltf",
            json(
                serde_json::json!({"accessors": [positions(serde_json::json!({"count": 0})), indices]}),
            ),
            "accessor 0 has count 0",
        ),
        (
            "sparse.gltf",
            json(
                serde_json::json!({"accessors": [positions(serde_json::json!({"sparse": {
                "count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 0}}})), indices]}),
            ),
            "accessor 0 is sparse",
        ),
        (
            "type.gltf",
            json(
                serde_json::json!({"accessors": [positions(serde_json::json!({"componentType": 5123})), indices]}),
            ),
            "POSITION accessor 0 holds Vec3 U16",
        ),
        (
            "float-indices.gltf",
            json(
                serde_json::json!({"accessors": [positions(serde_json::json!({})),
                {"bufferView": 1, "componentType": 5126, "count": 6, "type": "SCALAR"}]}),
            ),
            "indices accessor 1 holds Scalar F32",
        ),
        (
            "index.gltf",
            json(
                serde_json::json!({"accessors": [positions(serde_json::json!({"count": 3, "max": [1.0, 1.0, 0.0]})), indices]}),
            ),
            "index 3 is out of range (3 vertices)",
        ),
    ];
    for (name, doc, expected) in cases {
        let path = gltf_file(d, name, doc);
        let result = std::panic::catch_unwind(|| load_mesh(&path, NormalMode::Face));
        let message = match result {
            Err(_) => panic!("{name}: panicked"),
            Ok(Ok(_)) => panic!("{name}: loaded"),
            Ok(Err(e)) => e.to_string(),
        };
        assert!(message.contains(name), "{name}: {message}");
        assert!(
            message.contains(expected),
            "{name}: expected '{expected}' in: {message}"
        );
    }
    // A normalized flag on floats means nothing (the spec allows it on
    // integers only): read as the floats they are.
    let normalized = gltf_file(
        d,
        "normalized.gltf",
        json(
            serde_json::json!({"accessors": [positions(serde_json::json!({"normalized": true})), indices]}),
        ),
    );
    assert_eq!(
        load_mesh(&normalized, NormalMode::Face)
            .unwrap()
            .triangles
            .len(),
        4
    );
}

/// Base64 for the data-URI test, written out rather than a dependency.
mod base64_like {
    pub fn encode(bytes: &[u8]) -> String {
        const TABLE: &[u8; 64] =
            b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in bytes.chunks(3) {
            let b = [
                chunk[0],
                *chunk.get(1).unwrap_or(&0),
                *chunk.get(2).unwrap_or(&0),
            ];
            let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
            for i in 0..4 {
                if i <= chunk.len() {
                    out.push(TABLE[(n >> (18 - 6 * i) & 63) as usize] as char);
                } else {
                    out.push('=');
                }
            }
        }
        out
    }
}

/// `lambert render MODEL` for every format, with no scene file: a framed
/// camera or the file's, a light, never a black picture; `--camera` picks
/// a glTF camera by name; an unknown extension names the supported ones.
#[test]
fn a_model_file_alone_renders() {
    let dir = tempfile::tempdir().unwrap();
    for model in [
        "bunny_lowres.obj",
        "bunny_lowres.ply",
        "bunny_lowres_ascii.ply.gz",
        "boxes.glb",
    ] {
        let out = dir.path().join(format!("{model}.png"));
        let output = lambert_command()
            .args([
                "render",
                meshes(model).to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--width",
                "64",
            ])
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "{model}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let image = image::open(&out).unwrap().to_rgb8();
        assert_eq!(image.width(), 64);
        assert_eq!(image.height(), 48, "{model}: the aspect ratio is kept");
        let lit = image
            .pixels()
            .filter(|p| p.0.iter().any(|&c| c > 40))
            .count();
        assert!(lit > 64 * 48 / 10, "{model}: only {lit} lit pixels");
    }
    let output = lambert_command()
        .args([
            "render",
            meshes("boxes.glb").to_str().unwrap(),
            "-o",
            "x.png",
            "--camera",
            "nonesuch",
        ])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let text = String::from_utf8_lossy(&output.stderr);
    assert!(
        text.contains("no perspective camera named 'nonesuch' (the file has 'view')"),
        "{text}"
    );
    // STL is read since issue 30; a 3DS file is not.
    let other = write(dir.path(), "model.3ds", "MM");
    let message = Scene::load(&other).unwrap_err().to_string();
    assert!(
        message.contains(".obj, .ply, .ply.gz, .gltf, .glb and .stl"),
        "{message}"
    );
    let output = lambert_command()
        .args(["info", meshes("boxes.glb").to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&output.stdout);
    for expected in [
        "triangles: 14",
        "materials: 2",
        "lights: 2",
        "eye [0, 2.5, 7]",
    ] {
        assert!(text.contains(expected), "info lacks {expected}: {text}");
    }
}

/// OBJ's `\` line continuation (the OBJ spec): a statement across lines
/// reads as one, and errors after it still name the right line.
#[test]
fn obj_line_continuation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = "v 0 0 \\\n0\nv 1 0 0\r\nv 0 1 0\nv 1 1 0\nf 1 \\\r\n 2 \\ \n3\nf 2 4 3\n";
    let mesh = load_mesh(&write(d, "c.obj", text), NormalMode::Face).unwrap();
    assert_eq!(mesh.positions[0], DVec3::ZERO);
    assert_eq!(mesh.positions.len(), 4);
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [1, 3, 2]]);
    assert!(mesh.warnings.is_empty(), "{:?}", mesh.warnings);
    let bad = write(d, "bad.obj", format!("{text}v 0 0 x\n"));
    let message = error_of(&bad);
    assert!(
        message.contains("bad.obj:10: 'x' is not a number"),
        "{message}"
    );
    // A continuation on the last line ends the statement there.
    let last = write(d, "last.obj", format!("{text}f 1 2 4 \\"));
    assert_eq!(
        load_mesh(&last, NormalMode::Face).unwrap().triangles.len(),
        3
    );
}

/// Faces that other readers load with a note: fewer than 3 vertices
/// (skipped), normals that are not defined (dropped for computed ones);
/// one warning per kind, with the count and the first line.
#[test]
fn obj_short_faces_and_undefined_normals_are_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let quad = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.5\n";
    let short = write(d, "short.obj", format!("{quad}f 1 2\nf 1 2 3\nf 4\nf\n"));
    let mesh = load_mesh(&short, NormalMode::Smooth).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(
        mesh.warnings,
        vec![format!(
            "{}:5: 3 faces with fewer than 3 vertices skipped (the first on this line)",
            short.display()
        )]
    );

    let faces = |second: &str, third: &str| {
        format!("{quad}vn 0 0 1\nf 1//1 2//1 3//1\nf {second}\nf {third}\n")
    };
    let named = write(d, "named.obj", faces("2//2 4//2 3//2", "2//1 4//-3 3//1"));
    let plain = write(d, "plain.obj", faces("2 4 3", "2 4 3"));
    let mesh = load_mesh(&named, NormalMode::Smooth).unwrap();
    let reference = load_mesh(&plain, NormalMode::Smooth).unwrap();
    assert_eq!(mesh.triangles, reference.triangles);
    assert_eq!(mesh.normals, reference.normals);
    assert_eq!(mesh.normals.as_ref().unwrap()[0], [DVec3::Z; 3]);
    assert!(!mesh.file_normals);
    assert_eq!(mesh.warnings.len(), 1, "{:?}", mesh.warnings);
    assert!(
        mesh.warnings[0].starts_with(&format!(
            "{}:7: 2 faces naming normals that are not defined",
            named.display()
        )),
        "{:?}",
        mesh.warnings
    );
    // No vn at all: the face loads, with computed normals.
    let none = write(d, "none.obj", format!("{quad}f 1//1 2//1 3//1\n"));
    let mesh = load_mesh(&none, NormalMode::Smooth).unwrap();
    assert_eq!(mesh.triangles.len(), 1);
    assert!(mesh.warnings[0].contains("none.obj:5: 1 face naming normals"));
    // A normal index that is not a number is still an error.
    let word = write(d, "word.obj", format!("{quad}f 1//x 2//1 3//1\n"));
    assert!(error_of(&word).contains("word.obj:5: 'x' is not a normal index"));
}

/// MTL colours as the spec writes them: `Kd r` (g and b repeat r),
/// `Kd xyz X [Y Z]` (CIE XYZ, converted to linear sRGB), `Kd spectral`
/// (a warning, the default albedo); negative values stay refused.
#[test]
fn mtl_grey_xyz_and_spectral_colours() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "m.mtl",
        "newmtl grey\nKd 0.5\nnewmtl spectral\nKd spectral green.rfl 0.8\n\
         newmtl white\nKd xyz 0.95047 1.0 1.08883\nnewmtl red\nKd xyz 0.4124564 0.2126729 0.0193339\n\
         newmtl greyxyz\nKd xyz 0.2\nnewmtl beyond\nKd xyz 1 0 0\n",
    );
    let names = ["grey", "spectral", "white", "red", "greyxyz", "beyond"];
    let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for name in names {
        obj += &format!("usemtl {name}\nf 1 2 3\n");
    }
    let mesh = load_mesh(&write(d, "m.obj", obj), NormalMode::Face).unwrap();
    let m = &albedos(&mesh);
    assert_eq!(m[0], [0.5; 3]);
    assert_eq!(m[1], [0.8; 3]);
    let close = |a: [f32; 3], b: [f32; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-4);
    assert!(close(m[2], [1.0; 3]), "D65 white: {:?}", m[2]);
    assert!(close(m[3], [1.0, 0.0, 0.0]), "sRGB red: {:?}", m[3]);
    // Y = Z = X: equal XYZ is not grey in sRGB (D65 white is not X=Y=Z).
    assert!(m[4][0] > m[4][1] && m[4][1] > m[4][2], "{:?}", m[4]);
    assert!(m[5][1] == 0.0 && m[5][0] > 3.0, "{:?}", m[5]);
    let warnings = mesh.warnings.join("\n");
    assert!(
        warnings.contains("m.mtl:4: Kd spectral is not supported"),
        "{warnings}"
    );
    assert!(warnings.contains("m.mtl:12: Kd xyz"), "{warnings}");
    assert_eq!(mesh.warnings.len(), 2, "{warnings}");

    for (mtl, expected) in [
        (
            "newmtl a\nKd -0.5\n",
            "n.mtl:2: Kd: -0.5 must be finite and non-negative",
        ),
        (
            "newmtl a\nKd xyz 0.5 -1\n",
            "n.mtl:2: Kd: -1 must be finite and non-negative",
        ),
        (
            "newmtl a\nKd xyz\n",
            "n.mtl:2: Kd needs 1 or 3 numbers (r [g b]), found 0",
        ),
    ] {
        write(d, "n.mtl", mtl);
        let obj = write(
            d,
            "n.obj",
            "mtllib n.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        let message = error_of(&obj);
        assert!(message.contains(expected), "{message}");
    }
}

/// A TOML mesh scaled by a negative factor on one or three axes is
/// mirrored: its faces keep facing out (two corners swapped, and their
/// normals with them); on two axes it is a rotation and nothing swaps.
#[test]
fn toml_mirrored_meshes_keep_their_normals_facing_out() {
    let dir = tempfile::tempdir().unwrap();
    // A tetrahedron whose faces all face out.
    std::fs::write(
        dir.path().join("tet.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nf 1//1 3//1 2//1\nf 1//1 2//1 4//1\nf 1//1 4//1 3//1\nf 2//1 3//1 4//1\n",
    )
    .unwrap();
    for (scale, mirrored) in [
        ("[-1.0, 1.0, 1.0]", true),
        ("[1.0, -2.0, 1.0]", true),
        ("-1.0", true),
        ("[-1.0, -1.0, 1.0]", false),
        ("1.0", false),
    ] {
        let text = format!(
            "[camera]\neye = [3.0, 3.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 8\nheight = 8\n\
             [[mesh]]\nfile = \"tet.obj\"\nnormals = \"smooth\"\nscale = {scale}\n\
             [[point_light]]\nposition = [0.0, 5.0, 0.0]\nintensity = 1.0\n"
        );
        let s = Scene::from_toml(&text, &dir.path().join("s.toml")).unwrap();
        assert_eq!(s.triangles().len(), 4, "{scale}");
        let v = |p: [f32; 3]| DVec3::from(p.map(f64::from));
        let corners: Vec<DVec3> = s
            .triangles()
            .iter()
            .flat_map(|t| [v(t.v0), v(t.v1), v(t.v2)])
            .collect();
        let centre = corners.iter().sum::<DVec3>() / corners.len() as f64;
        for t in s.triangles() {
            let [a, b, c] = [v(t.v0), v(t.v1), v(t.v2)];
            let outward = (a + b + c) / 3.0 - centre;
            assert!(
                (b - a).cross(c - a).dot(outward) > 0.0,
                "{scale}: {t:?} faces in"
            );
        }
        // The first face (1, 3, 2) keeps its first corner; a mirror swaps the others.
        let first = &s.triangles()[0];
        let expected_v1 = if mirrored { v(first.v2) } else { v(first.v1) };
        assert_eq!(v(first.v0), DVec3::ZERO, "{scale}");
        assert!(
            expected_v1.x == 0.0 && expected_v1.z == 0.0,
            "{scale}: {first:?}"
        );
        assert_eq!(s.normals().len(), 4, "{scale}: smooth normals kept");
    }
}

/// The RGB of each material's base colour.
fn albedos(mesh: &lambert::loading::Mesh) -> Vec<[f32; 3]> {
    mesh.materials
        .iter()
        .map(|m| [m.base_color[0], m.base_color[1], m.base_color[2]])
        .collect()
}
