//! Issue 30: materials and per-vertex data from every loader to the pixel
//! on both paths: vertex colours, alpha masks, emission, texture
//! coordinates, and the errors their malformed forms get.

mod common;

use std::path::{Path, PathBuf};

use common::data::{glb, one_mesh_glb};
use common::formats::load_written;
use common::*;
use lambert::Scene;
use lambert::layout::NO_HIT;
use lambert::loading::{AlphaMode, NormalMode, load_mesh};
use lambert::output::Rendered;

/// One vertex attribute of a quad: its bytes (four elements), and its
/// accessor's componentType, type and whether it is normalised.
struct Attribute {
    name: &'static str,
    bytes: Vec<u8>,
    component: u32,
    kind: &'static str,
    normalized: bool,
}

impl Attribute {
    /// An attribute of 32-bit floats.
    fn floats(name: &'static str, values: &[f32], kind: &'static str) -> Attribute {
        Attribute {
            name,
            bytes: floats(values),
            component: 5126,
            kind,
            normalized: false,
        }
    }
}

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// A GLB of the quad (−h, −h, z) … (h, h, z) facing +z (two triangles,
/// (0, 1, 2) and (0, 2, 3), corners counter-clockwise from the bottom
/// left), with `attributes` and material `material`.
fn quad_glb(h: f32, z: f32, attributes: &[Attribute], material: serde_json::Value) -> Vec<u8> {
    let mut bin = floats(&[-h, -h, z, h, -h, z, h, h, z, -h, h, z]);
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let mut views = vec![
        serde_json::json!({"buffer": 0, "byteLength": 48}),
        serde_json::json!({"buffer": 0, "byteOffset": 48, "byteLength": 12}),
    ];
    let mut accessors = vec![
        serde_json::json!({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                           "min": [-h, -h, z], "max": [h, h, z]}),
        serde_json::json!({"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}),
    ];
    let mut names = serde_json::Map::new();
    names.insert("POSITION".into(), 0.into());
    for a in attributes {
        // Each view starts on a 4-byte boundary, as the spec requires.
        bin.resize(bin.len().div_ceil(4) * 4, 0);
        let view = views.len();
        views.push(
            serde_json::json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": a.bytes.len()}),
        );
        bin.extend(&a.bytes);
        names.insert(a.name.into(), accessors.len().into());
        accessors.push(
            serde_json::json!({"bufferView": view, "componentType": a.component,
            "count": 4, "type": a.kind, "normalized": a.normalized}),
        );
    }
    let rest = serde_json::json!({
        "meshes": [{"primitives": [{"attributes": names, "indices": 1, "material": 0}]}],
        "materials": [material],
        "bufferViews": views,
        "accessors": accessors,
    });
    one_mesh_glb("KHR_materials_emissive_strength", rest, &bin)
}

/// The scene `body` (meshes, lights) under a camera at (0, 0, `eye_z`)
/// looking down −z, 32 × 32 pixels, in `dir`.
fn scene_in(dir: &Path, eye_z: f64, body: &str) -> Scene {
    let text = format!(
        "[camera]\neye = [0.0, 0.0, {eye_z}]\nlook_at = [0.0, 0.0, -10.0]\nvfov = 60.0\n\
         width = 32\nheight = 32\n{body}"
    );
    Scene::from_toml(&text, &dir.join("scene.toml")).unwrap()
}

/// Renders on both paths and checks them equal bit for bit (colours and
/// the primitive in every pixel); the CPU's render.
fn render_both(scene: &Scene, what: &str) -> Rendered {
    let cpu = render_cpu(scene);
    let gpu = render_gpu(scene);
    assert!(
        bits(&gpu) == bits(&cpu),
        "{what}: GPU and CPU colours differ"
    );
    assert_eq!(
        gpu.prims, cpu.prims,
        "{what}: GPU and CPU hit different primitives"
    );
    cpu
}

/// The pixel that (x, y, 0) falls in, seen from (0, 0, 3) (`scene_in`).
fn pixel_at(r: &Rendered, x: f32, y: f32) -> ([f32; 3], u32) {
    let half = 3.0 * (30f32).to_radians().tan();
    let column = ((x / half + 1.0) / 2.0 * 32.0) as u32;
    let row = ((1.0 - y / half) / 2.0 * 32.0) as u32;
    (
        r.image.pixel(column, row),
        r.prims[(row * 32 + column) as usize],
    )
}

fn close(a: [f32; 3], b: [f32; 3], tolerance: f32) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= tolerance)
}

const RED_GREEN_BLUE_WHITE: [[f32; 3]; 4] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
];

/// Item 2: an OBJ's `v x y z r g b` colours multiply its `Kd`, are
/// interpolated across each triangle, and render the same on both paths,
/// bit for bit; a scene's `albedo` replaces them.
#[test]
fn obj_vertex_colours_reach_the_pixel_on_both_paths() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut obj = String::from("mtllib m.mtl\n");
    for (corner, [r, g, b]) in [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
        .iter()
        .zip(RED_GREEN_BLUE_WHITE)
    {
        obj += &format!("v {} {} 0 {r} {g} {b}\n", corner[0], corner[1]);
    }
    obj += "usemtl half\nf 1 2 3 4\n";
    write(d, "coloured.obj", obj);
    write(d, "m.mtl", "newmtl half\nKd 0.5 0.5 0.5\n");
    let scene = scene_in(
        d,
        3.0,
        "[render]\nambient = 1.0\n[[mesh]]\nfile = \"coloured.obj\"\n",
    );
    assert_eq!(scene.colored_triangles(), 2);
    let image = render_both(&scene, "coloured quad");
    // Near each corner, half its colour (Kd 0.5); the middle of the
    // diagonal (corners 1 and 3), half of their mean.
    for ((x, y), [r, g, b]) in [(-0.9, -0.9), (0.9, -0.9), (0.9, 0.9), (-0.9, 0.9)]
        .iter()
        .zip(RED_GREEN_BLUE_WHITE)
    {
        let (rgb, _) = pixel_at(&image, *x, *y);
        assert!(
            close(rgb, [r / 2.0, g / 2.0, b / 2.0], 0.12),
            "near ({x}, {y}): {rgb:?}"
        );
    }
    let (centre, _) = pixel_at(&image, 0.01, 0.0);
    assert!(close(centre, [0.25, 0.0, 0.25], 0.05), "centre: {centre:?}");
    let grey = scene_in(
        d,
        3.0,
        "[render]\nambient = 1.0\n[[mesh]]\nfile = \"coloured.obj\"\nalbedo = 0.5\n",
    );
    let (rgb, _) = pixel_at(&render_cpu(&grey), -0.9, -0.9);
    assert_eq!(rgb, [0.5; 3], "albedo replaces the vertex colours");
}

/// Item 2: glTF COLOR_0 in each form the spec allows (RGB or RGBA; float,
/// unorm8, unorm16) gives the same linear colours, multiplying
/// baseColorFactor; PLY's uchar colours are sRGB-decoded, float ones kept.
#[test]
fn colours_of_every_format_and_type_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Per vertex: (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1); alpha 1, 0, 1, 0.
    let rgba: Vec<[f32; 4]> = RED_GREEN_BLUE_WHITE
        .iter()
        .enumerate()
        .map(|(i, [r, g, b])| [*r, *g, *b, (1 - i % 2) as f32])
        .collect();
    let flat = |n: usize| -> Vec<f32> { rgba.iter().flat_map(|c| c[..n].to_vec()).collect() };
    let unorm8 = |n: usize| -> Vec<u8> { flat(n).iter().map(|&x| (x * 255.0) as u8).collect() };
    let unorm16 = |n: usize| -> Vec<u8> {
        flat(n)
            .iter()
            .flat_map(|&x| ((x * 65535.0) as u16).to_le_bytes())
            .collect()
    };
    let material =
        serde_json::json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 1.0, 1.0, 1.0]}});
    for (name, bytes, component, kind) in [
        ("f32 rgb", floats(&flat(3)), 5126, "VEC3"),
        ("f32 rgba", floats(&flat(4)), 5126, "VEC4"),
        ("u8 rgb", unorm8(3), 5121, "VEC3"),
        ("u8 rgba", unorm8(4), 5121, "VEC4"),
        ("u16 rgb", unorm16(3), 5123, "VEC3"),
        ("u16 rgba", unorm16(4), 5123, "VEC4"),
    ] {
        let colour = Attribute {
            name: "COLOR_0",
            bytes,
            component,
            kind,
            normalized: component != 5126,
        };
        let path = write(d, "c.glb", quad_glb(1.0, 0.0, &[colour], material.clone()));
        let mesh = load_mesh(&path, NormalMode::Face).unwrap();
        let colors = mesh.colors.expect(name);
        let alpha = |i: usize| if kind == "VEC4" { rgba[i][3] } else { 1.0 };
        let vertex = |i: usize| {
            let [r, g, b] = RED_GREEN_BLUE_WHITE[i];
            [r, g, b, alpha(i)]
        };
        assert_eq!(
            colors,
            vec![
                [vertex(0), vertex(1), vertex(2)],
                [vertex(0), vertex(2), vertex(3)]
            ],
            "{name}"
        );
        assert_eq!(mesh.materials[0].base_color, [0.5, 1.0, 1.0, 1.0]);
    }

    let header = |props: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n{props}element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let uchar = header(
        "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n",
    ) + "0 0 0 255 128 0 51\n1 0 0 0 0 0 255\n0 1 0 255 255 255 255\n3 0 1 2\n";
    let mesh = load_mesh(&write(d, "u.ply", uchar), NormalMode::Face).unwrap();
    let colors = mesh.colors.expect("uchar colours");
    // sRGB 128 is linear 0.2158; alpha is linear (51 / 255 = 0.2).
    let [r, g, b, a] = colors[0][0];
    assert_eq!((r, b), (1.0, 0.0));
    assert!((g - 0.2158).abs() < 1e-4, "sRGB 128 decodes to {g}");
    assert!((a - 0.2).abs() < 1e-6, "alpha {a}");
    assert_eq!(colors[0][2], [1.0; 4]);
    assert_eq!(mesh.materials[0].base_color, [1.0; 4], "colours as given");
    let float = header("property float red\nproperty float green\nproperty float blue\n")
        + "0 0 0 0.5 0.25 0.125\n1 0 0 0 0 0\n0 1 0 1 1 1\n3 0 1 2\n";
    let mesh = load_mesh(&write(d, "f.ply", float), NormalMode::Face).unwrap();
    assert_eq!(
        mesh.colors.unwrap()[0][0],
        [0.5, 0.25, 0.125, 1.0],
        "float colours are linear"
    );
}

/// Item 2: texture coordinates from each source, stored in glTF's
/// convention (OBJ and PLY v flipped): OBJ `vt`, PLY `u v`, `s t`,
/// `texture_u texture_v` and a face `texcoord` list, glTF TEXCOORD_n (the
/// set the base colour texture names) as float and unorm.
#[test]
fn texture_coordinates_of_every_format_are_read() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0.125\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";
    let (dir, mesh) = load_written(&[("t.obj", obj)]);
    let d = dir.path();
    let expected = [[0.25, 0.875], [1.0, 1.0], [0.0, 0.0]];
    assert_eq!(mesh.uvs, Some(vec![expected]), "OBJ vt");
    let vertices = "0 0 0 0.25 0.125\n1 0 0 1 0\n0 1 0 0 1\n";
    for [u, v] in [["u", "v"], ["s", "t"], ["texture_u", "texture_v"]] {
        let ply = format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float {u}\nproperty float {v}\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n{vertices}3 0 1 2\n"
        );
        let mesh = load_mesh(&write(d, "t.ply", ply), NormalMode::Face).unwrap();
        assert_eq!(mesh.uvs, Some(vec![expected]), "PLY {u} {v}");
        assert!(mesh.warnings.is_empty(), "{:?}", mesh.warnings);
    }
    let ply = "ply\nformat ascii 1.0\ncomment TextureFile missing image.png\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 6 0.25 0.125 1 0 0 1\n";
    let mesh = load_mesh(&write(d, "l.ply", ply), NormalMode::Face).unwrap();
    assert_eq!(mesh.uvs, Some(vec![expected]), "PLY texcoord list");
    let warnings = mesh.warnings.join("\n");
    assert!(
        warnings.contains("TextureFile 'missing image.png' is not found"),
        "{warnings}"
    );

    let uvs = [0.25f32, 0.125, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
    let material = serde_json::json!({"pbrMetallicRoughness":
        {"baseColorTexture": {"index": 0, "texCoord": 1}}});
    for (bytes, component) in [
        (floats(&uvs), 5126),
        (uvs.iter().map(|&x| (x * 255.0) as u8).collect(), 5121),
        (
            uvs.iter()
                .flat_map(|&x| ((x * 65535.0) as u16).to_le_bytes())
                .collect(),
            5123,
        ),
    ] {
        // TEXCOORD_0 is a decoy: the texture reads set 1.
        let decoy = Attribute::floats("TEXCOORD_0", &[9.0; 8], "VEC2");
        let set = Attribute {
            name: "TEXCOORD_1",
            bytes,
            component,
            kind: "VEC2",
            normalized: component != 5126,
        };
        let mut json_material = material.clone();
        json_material["name"] = "tex".into();
        let bytes = quad_glb(1.0, 0.0, &[decoy, set], json_material);
        let mut doc = bytes.clone();
        // The texture and image are appended to the JSON by a re-encode.
        let path = write(d, "t.glb", {
            let json_len = u32::from_le_bytes(doc[12..16].try_into().unwrap()) as usize;
            let mut json: serde_json::Value =
                serde_json::from_slice(&doc[20..20 + json_len]).unwrap();
            let bin_start = 20 + json_len + 8;
            let bin = doc.split_off(bin_start);
            json["textures"] = serde_json::json!([{"source": 0}]);
            json["images"] = serde_json::json!([{"uri": "present.png"}]);
            glb(json, &bin)
        });
        write(d, "present.png", b"not decoded by the loader");
        let mesh = load_mesh(&path, NormalMode::Face).unwrap();
        let got = mesh.uvs.expect("TEXCOORD_1");
        // unorm8 and unorm16 hold 0.25 and 0.125 to within a step.
        let step = if component == 5121 {
            1.0 / 255.0
        } else {
            1.0 / 65535.0
        };
        let expected = [[0.25, 0.125], [1.0, 0.0], [1.0, 1.0]];
        for (corner, want) in got[0].iter().zip(expected) {
            for k in 0..2 {
                assert!(
                    (corner[k] - want[k]).abs() <= step,
                    "component {component}: {got:?}"
                );
            }
        }
        let texture = mesh.materials[0].base_color_texture.expect("its texture");
        let scene = Scene::load(&path).unwrap();
        let warnings = scene.warnings().join("\n");
        // Textures render now: this one's bytes are no image, which the
        // scene says, naming the image and the material (it keeps its
        // factor).
        assert!(
            warnings.contains(
                "present.png: not a PNG or JPEG image; material 'tex' keeps its colour without it"
            ),
            "{warnings}"
        );
        assert_eq!(
            mesh.images[texture.image as usize],
            lambert::loading::ImageSource::File(d.join("present.png"))
        );
    }
}

/// Item 4: an emissive surface renders its emission (emissiveFactor ×
/// KHR_materials_emissive_strength) in the dark, on both paths bit for
/// bit, and lights nothing else.
#[test]
fn emission_renders_in_the_dark() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let material = serde_json::json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]},
        "emissiveFactor": [0.5, 0.25, 1.0],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}}
    });
    write(d, "lamp.glb", quad_glb(0.5, 0.0, &[], material));
    write(
        d,
        "floor.obj",
        "v -2 -2 -1\nv 2 -2 -1\nv 2 2 -1\nv -2 2 -1\nf 1 2 3 4\n",
    );
    let scene = scene_in(
        d,
        3.0,
        "[[mesh]]\nfile = \"lamp.glb\"\n[[mesh]]\nfile = \"floor.obj\"\n",
    );
    let image = render_both(&scene, "emissive quad");
    assert!(
        bits(&render_gpu(&scene)) == bits(&image),
        "emission: GPU = CPU, bit for bit"
    );
    let (lamp, prim) = pixel_at(&image, 0.0, 0.0);
    assert_eq!(lamp, [1.0, 0.5, 2.0], "the emission, exactly");
    assert!(prim < 2, "the lamp's triangles");
    let (floor, prim) = pixel_at(&image, 1.5, 1.5);
    assert_eq!(
        (floor, prim >= 2),
        ([0.0; 3], true),
        "the floor is not lit by it"
    );
}

/// The mask scenes: a floor at z = 0, a quad at z = 1 of `alpha_mode`
/// whose alpha is 1 on its right corners and 0 on its left (COLOR_0), a
/// light above it; the camera at (0, 0, `eye_z`).
fn masked_scene(d: &Path, alpha_mode: &str, eye_z: f64) -> Scene {
    let colour = Attribute::floats(
        "COLOR_0",
        &[
            1.0, 1.0, 1.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0,
        ],
        "VEC4",
    );
    let material = serde_json::json!({"name": "leaf", "alphaMode": alpha_mode, "alphaCutoff": 0.5,
        "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.9, 0.2, 1.0]}});
    let model: PathBuf = write(
        d,
        &format!("{alpha_mode}.glb"),
        quad_glb(1.0, 1.0, &[colour], material),
    );
    write(
        d,
        "floor.obj",
        "v -3 -3 0\nv 3 -3 0\nv 3 3 0\nv -3 3 0\nf 1 2 3 4\n",
    );
    scene_in(
        d,
        eye_z,
        &format!(
            "[[mesh]]\nfile = \"floor.obj\"\n[[mesh]]\nfile = \"{}\"\n\
             [[point_light]]\nposition = [0.0, 0.0, 4.0]\nintensity = 16.0\n",
            model.file_name().unwrap().to_string_lossy()
        ),
    )
}

/// Item 3: a MASK quad is cut out where its alpha (baseColorFactor.a ×
/// COLOR_0 alpha, interpolated) falls below alphaCutoff: invisible to
/// camera rays, and shadow rays pass; where it is not cut out, it is seen
/// and casts its shadow. BLEND renders as MASK at 0.5, with a warning. GPU
/// and CPU agree bit for bit.
#[test]
fn alpha_masks_cut_out_for_camera_and_shadow_rays() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // From above (z = 6): the floor through the left half of the quad, the
    // quad on its right half.
    for mode in ["MASK", "BLEND"] {
        let scene = masked_scene(d, mode, 6.0);
        assert!(scene.has_alpha_mask());
        if mode == "BLEND" {
            let warnings = scene.warnings().join("\n");
            assert!(
                warnings.contains(
                    "material leaf: alphaMode BLEND is rendered as MASK with alphaCutoff 0.5"
                ),
                "{warnings}"
            );
        }
        let image = render_both(&scene, mode);
        let left = image.prims[16 * 32 + 13];
        let right = image.prims[16 * 32 + 19];
        assert!(
            left < 2,
            "{mode}: the floor (triangles 0, 1) through the cut-out: {left}"
        );
        assert!(
            (2..4).contains(&right),
            "{mode}: the quad where it is opaque: {right}"
        );
    }
    // From below the quad (z = 0.5, looking down at the floor): shadow rays
    // to the light pass the cut-out half, and not the opaque one.
    let masked = render_both(&masked_scene(d, "MASK", 0.5), "mask, shadows");
    let opaque = render_both(&masked_scene(d, "OPAQUE", 0.5), "opaque, shadows");
    let lum = |r: &Rendered, x: u32| r.image.pixel(x, 16)[0];
    assert!(lum(&masked, 12) > 0.0, "the floor under the cut-out is lit");
    assert_eq!(
        lum(&masked, 20),
        0.0,
        "the floor under the opaque half is not"
    );
    assert_eq!(lum(&opaque, 12), 0.0, "an opaque quad shadows it all");
    assert!(!masked_scene(d, "OPAQUE", 0.5).has_alpha_mask());
}

/// Item 3 for OBJ: `d < 1` is a blend (a mask at 0.5, with a warning);
/// `Tr` is skipped with a warning (MeshLab writes `Tr 1` for opaque, as
/// trimesh's models/fuze.obj.mtl has it); `Ke` is emission.
#[test]
fn mtl_alpha_and_emission() {
    let mtl =
        "newmtl glass\nKd 1 1 1\nd 0.25\nnewmtl meshlab\nTr 1.000000\nnewmtl lamp\nKe 1 0.5 0\n";
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glass\nf 1 2 3\nusemtl meshlab\nf 1 2 3\nusemtl lamp\nf 1 2 3\n";
    let (_dir, mesh) = load_written(&[("m.mtl", mtl), ("m.obj", obj)]);
    let m = &mesh.materials;
    assert_eq!(
        (m[0].base_color[3], m[0].alpha_mode),
        (0.25, AlphaMode::Blend)
    );
    assert_eq!(
        (m[1].base_color[3], m[1].alpha_mode),
        (1.0, AlphaMode::Opaque)
    );
    assert_eq!(
        (m[2].emissive, m[2].alpha_mode),
        ([1.0, 0.5, 0.0], AlphaMode::Opaque)
    );
    let warnings = mesh.warnings.join("\n");
    assert!(
        warnings.contains("m.mtl: material glass: its transparency"),
        "{warnings}"
    );
    assert!(warnings.contains("m.mtl:5: Tr is skipped"), "{warnings}");
    assert!(!warnings.contains("material meshlab"), "{warnings}");
}

/// Item 8: malformed colours and texture coordinates are errors naming the
/// file and the line, element or accessor at fault.
#[test]
fn malformed_colours_and_texture_coordinates_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let message = |path: &Path| load_mesh(path, NormalMode::Face).unwrap_err().to_string();
    // COLOR_0 as SCALAR, and as signed shorts.
    for (component, kind) in [(5126, "SCALAR"), (5122, "VEC4")] {
        let colour = Attribute {
            name: "COLOR_0",
            bytes: vec![0; 32],
            component,
            kind,
            normalized: true,
        };
        let path = write(
            d,
            "bad.glb",
            quad_glb(1.0, 0.0, &[colour], serde_json::json!({})),
        );
        let m = message(&path);
        for part in ["bad.glb", "mesh 0 primitive 0: COLOR_0 accessor 2"] {
            assert!(m.contains(part), "{kind} {component}: {m}");
        }
    }
    let path = write(
        d,
        "vt.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
    );
    let m = message(&path);
    assert!(
        m.contains("vt.obj:5: ") && m.contains("texture coordinate index 2 is out of range"),
        "{m}"
    );
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty int red\nproperty int green\nproperty int blue\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n";
    let m = message(&write(d, "c.ply", ply));
    assert!(
        m.contains("c.ply") && m.contains("vertex property 'red' is i32"),
        "{m}"
    );
}

/// Item 3: ray queries see what the camera sees: a hit in a cut-out is no
/// hit (docs/ray-query.md).
#[test]
fn ray_queries_pass_through_cut_outs() {
    let dir = tempfile::tempdir().unwrap();
    let scene = masked_scene(dir.path(), "MASK", 6.0);
    let ray = |x: f32| lambert::layout::Ray {
        origin: [x, 0.0, 6.0],
        tmin: 0.0,
        dir: [0.0, 0.0, -1.0],
        tmax: f32::INFINITY,
    };
    let rays = [ray(-0.8), ray(0.8)];
    let cpu = trace_cpu(&scene, &rays, false);
    let gpu = trace_gpu(&scene, &rays, false);
    assert_eq!(cpu, gpu);
    assert_eq!(
        (cpu[0].t, cpu[1].t),
        (6.0, 5.0),
        "the floor through the cut-out, the quad beside it"
    );
    assert_ne!(cpu[0].prim, NO_HIT);
}

/// Item 7: `lambert info MODEL` lists vertex colours, each material's alpha
/// mode, and the emissive materials.
#[test]
fn info_lists_colours_alpha_modes_and_emission() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = masked_scene(d, "MASK", 6.0);
    assert_eq!(scene.colored_triangles(), 2);
    let colour = Attribute::floats("COLOR_0", &[1.0; 12], "VEC3");
    let material = serde_json::json!({"emissiveFactor": [0.5, 0.25, 1.0]});
    let path = write(d, "lamp.glb", quad_glb(1.0, 0.0, &[colour], material));
    let info = lambert(&["info", s(&path)]);
    let out = String::from_utf8_lossy(&info.stdout);
    assert!(info.status.success(), "{}", stderr(&info));
    for line in [
        "vertex colours: yes, on 2 of 2 triangles",
        "0: base colour [1, 1, 1], alpha 1, alpha mode OPAQUE, emissive [0.5, 0.25, 1]",
        "emissive materials: 1",
    ] {
        assert!(out.contains(line), "lacks '{line}':\n{out}");
    }
    let info = lambert(&["info", s(&d.join("MASK.glb"))]);
    let out = String::from_utf8_lossy(&info.stdout);
    assert!(out.contains("alpha mode MASK (cut-off 0.5)"), "{out}");
    assert!(out.contains("emissive materials: 0"), "{out}");
}
