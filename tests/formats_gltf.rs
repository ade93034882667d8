//! Model formats (issue 17): glTF and GLB: hierarchy, cameras, lights, materials, buffers, malformed files.

mod common;

use std::path::{Path, PathBuf};

use common::formats::*;
use common::*;
use glam::DVec3;
use lambert::Scene;
use lambert::loading::{NormalMode, load_mesh};

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
    // Candela in the lecture's units: ÷ π (docs/rendering.md, "Light units").
    let expected = glam::Vec3::new(40.0, 36.0, 32.0) / std::f32::consts::PI;
    assert!((glam::Vec3::from(point.color) - expected).length() < 1e-5);
    let sun = scene
        .lights()
        .iter()
        .find(|l| l.kind == lambert::layout::LIGHT_DIRECTIONAL)
        .unwrap();
    let to_light = DVec3::new(0.0, 60f64.to_radians().sin(), 60f64.to_radians().cos());
    assert!((glam::Vec3::from(sun.vector).as_dvec3() - to_light).length() < 1e-6);
    assert!(
        (glam::Vec3::from(sun.color) - glam::Vec3::new(0.75, 0.75, 0.9) / std::f32::consts::PI)
            .length()
            < 1e-6
    );

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
    // What lambert's model lacks is a warning: range, textures,
    // non-triangle modes; a second node places the mesh again. A spot light
    // is read, with the spec's default cones (0 and π/4) about the node's −Z.
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
    assert_eq!(scene.lights().len(), 2);
    let spot = scene.lights()[0];
    assert_eq!(spot.kind, lambert::layout::LIGHT_SPOT);
    assert_eq!(spot.direction, [0.0, 0.0, -1.0]);
    assert_eq!(
        (spot.cos_inner, spot.cos_outer),
        (1.0, 45f32.to_radians().cos())
    );
    assert_eq!(scene.lights()[1].vector, [0.0, 0.0, 4.0]);
    assert_eq!(
        scene.lights()[1].color,
        [(3.0 / std::f64::consts::PI) as f32; 3]
    );
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
