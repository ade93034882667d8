//! Issue 46, materials: glTF's metallic-roughness factors and texture,
//! normal maps with the file's tangents or MikkTSpace's, emissive
//! strength, MTL's specular terms and TOML's keys, as the scene stores
//! them, `material_at` (the CPU twin) reads them and `lambert info` lists
//! them.

mod common;

use std::path::Path;

use common::data::ray;
use common::formats::load_written;
use common::pbr::{Glb, UPRIGHT_UVS, one_primitive_glb, quad_primitive};
use common::*;
use glam::Vec3;
use lambert::Scene;
use lambert::cpu::f32::{Hit, Kernel, Ray, SurfaceMaterial};
use lambert::layout::{MATERIAL_LAMBERT, MATERIAL_METALLIC_ROUGHNESS, NO_HIT, NO_TEXTURE};
use lambert::loading::Brdf;
use lambert::texture::Encoding;
use serde_json::{Value, json};

/// A textured quad (`quad_primitive`) under `material`, which names
/// texture i for image i of `images` (4×4 PNGs of one colour each).
fn textured_quad(
    material: Value,
    images: &[[u8; 4]],
    uvs: [[f32; 2]; 4],
    tangent: Option<[f32; 4]>,
) -> Vec<u8> {
    let mut glb = Glb::default();
    let primitive = quad_primitive(&mut glb, uvs, tangent);
    let images = images.iter().map(|&rgba| glb.png(rgba)).collect();
    one_primitive_glb(glb, primitive, material, images, &[])
}

/// The scene of `bytes`, written as `name` in `dir`, loaded as a model.
fn model(dir: &Path, name: &str, bytes: Vec<u8>) -> Scene {
    Scene::load(&write(dir, name, bytes)).unwrap()
}

/// `material_at` (after `surface_at`) where the ray from `origin` along
/// `dir` first hits.
fn material_where(scene: &Scene, origin: [f32; 3], dir: [f32; 3]) -> SurfaceMaterial {
    let query = ray(origin, dir);
    let hit = lambert::cpu::trace_rays(scene, &[query], false)[0];
    assert_ne!(hit.prim, NO_HIT, "the ray from {origin:?} hits the model");
    let kernel = Kernel::new(scene);
    let (ray, hit) = (Ray::from_query(&query), Hit::from_query(&hit));
    let surface = kernel.surface_at(&ray, &hit);
    kernel.material_at(&ray, &hit, &surface)
}

fn assert_near(actual: Vec3, expected: Vec3, tolerance: f32, what: &str) {
    assert!(
        (actual - expected).length() <= tolerance,
        "{what}: {actual} is not within {tolerance} of {expected}"
    );
}

/// The RGB bytes of a normal map's texel holding tangent-space `n`.
fn normal_texel(n: [f32; 3]) -> [u8; 4] {
    let byte = |c: f32| ((c + 1.0) / 2.0 * 255.0).round() as u8;
    [byte(n[0]), byte(n[1]), byte(n[2]), 255]
}

/// glTF metallicFactor and roughnessFactor make a metallic-roughness
/// material; metallicRoughnessTexture scales them by its B and G read as
/// data (128 is 128/255, not sRGB's 0.216), so an image that is also a
/// base colour texture is stored twice, once as colour; the defaults
/// (no pbrMetallicRoughness, no material at all) are the spec's 1 and 1.
#[test]
fn gltf_metallic_and_roughness_reach_the_material() {
    let dir = tempfile::tempdir().unwrap();
    let material = json!({"name": "brushed", "pbrMetallicRoughness": {
        "metallicFactor": 0.6, "roughnessFactor": 0.8,
        "baseColorTexture": {"index": 0},
        "metallicRoughnessTexture": {"index": 0}}});
    let scene = model(
        dir.path(),
        "mr.glb",
        textured_quad(material, &[[0, 128, 255, 255]], UPRIGHT_UVS, None),
    );
    let m = scene.materials()[0];
    assert_eq!(m.kind, MATERIAL_METALLIC_ROUGHNESS);
    assert_eq!((m.metallic, m.roughness), (0.6, 0.8));
    assert_ne!(m.metallic_roughness_texture, NO_TEXTURE);
    let encodings: Vec<Encoding> = scene
        .textures()
        .images()
        .iter()
        .map(|i| i.encoding)
        .collect();
    assert_eq!(encodings, [Encoding::Srgb, Encoding::Linear]);

    let at = material_where(&scene, [0.2, 0.1, 3.0], [0.0, 0.0, -1.0]);
    assert_eq!(at.bsdf.kind, MATERIAL_METALLIC_ROUGHNESS);
    assert!((at.bsdf.metallic - 0.6).abs() < 1e-6, "{at:?}");
    assert!(
        (at.bsdf.roughness - 0.8 * 128.0 / 255.0).abs() < 1e-4,
        "{at:?}"
    );
    // The base colour texture is colour: sRGB 128 is linear 0.2158.
    assert!((at.bsdf.base_color.y - 0.2158).abs() < 1e-3, "{at:?}");
    assert_eq!(at.shading_normal, Vec3::Z, "no normal map: the surface's");

    for (name, material) in [
        ("bare", json!({"name": "bare"})),
        (
            "untextured",
            json!({"pbrMetallicRoughness": {"metallicFactor": 0.25}}),
        ),
    ] {
        let scene = model(
            dir.path(),
            &format!("{name}.glb"),
            textured_quad(material, &[], UPRIGHT_UVS, None),
        );
        let m = scene.materials()[0];
        let metallic = if name == "bare" { 1.0 } else { 0.25 };
        assert_eq!(
            (m.kind, m.metallic, m.roughness),
            (MATERIAL_METALLIC_ROUGHNESS, metallic, 1.0),
            "{name}"
        );
    }
    // A primitive without a material gets glTF's default material.
    let mut glb = Glb::default();
    let mut primitive = quad_primitive(&mut glb, UPRIGHT_UVS, None);
    primitive.as_object_mut().unwrap().remove("material");
    let bytes = glb.finish(json!({"scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}], "meshes": [{"primitives": [primitive]}]}));
    let mesh = lambert::loading::gltf::parse_scene(&bytes, Path::new("d.glb"), Default::default())
        .unwrap()
        .mesh;
    assert_eq!(
        mesh.materials[0].brdf,
        Brdf::MetallicRoughness {
            metallic: 1.0,
            roughness: 1.0
        }
    );
}

/// A normal map tilts the shading normal in the tangent frame: the file's
/// TANGENT where given, else MikkTSpace's, which for a quad whose image
/// lies upright on it is +x (u's way) with sign +1; scaled X and Y by
/// normalTexture.scale; turned with the surface seen from behind.
#[test]
fn normal_maps_tilt_the_shading_normal_in_the_tangent_frame() {
    let dir = tempfile::tempdir().unwrap();
    let material = |scale: f32| {
        json!({"pbrMetallicRoughness": {"metallicFactor": 0.0},
               "normalTexture": {"index": 0, "scale": scale}})
    };
    let tilted = normal_texel([0.6, 0.0, 0.8]);
    let down = [0.0, 0.0, -1.0];

    let generated = model(
        dir.path(),
        "generated.glb",
        textured_quad(material(1.0), &[tilted], UPRIGHT_UVS, None),
    );
    assert_eq!(generated.materials()[0].normal_scale, 1.0);
    assert_eq!(generated.tangents().len(), 2);
    for t in generated.tangents() {
        for corner in [t.t0, t.t1, t.t2] {
            assert_near(
                Vec3::from_slice(&corner),
                Vec3::X,
                1e-6,
                "generated tangent",
            );
            assert_eq!(corner[3], 1.0, "bitangent sign");
        }
    }
    // 8-bit texels: 2·128/255 − 1 is 0.004, not 0.
    let n = material_where(&generated, [0.2, 0.1, 3.0], down).shading_normal;
    assert_near(n, Vec3::new(0.6, 0.0, 0.8), 0.01, "tilted along +x");
    assert!((n.length() - 1.0).abs() < 1e-6);
    // From behind, the whole frame turns: the normal faces the ray.
    let back = material_where(&generated, [0.2, 0.1, -3.0], [0.0, 0.0, 1.0]).shading_normal;
    assert_near(back, -n, 1e-6, "from behind");

    let scaled = model(
        dir.path(),
        "scaled.glb",
        textured_quad(material(0.5), &[tilted], UPRIGHT_UVS, None),
    );
    let n = material_where(&scaled, [0.2, 0.1, 3.0], down).shading_normal;
    assert_near(n, Vec3::new(0.3, 0.0, 0.8).normalize(), 0.01, "scale 0.5");

    // The file's tangent, +y: the same texel tilts the normal along +y.
    let given = model(
        dir.path(),
        "given.glb",
        textured_quad(
            material(1.0),
            &[tilted],
            UPRIGHT_UVS,
            Some([0.0, 1.0, 0.0, 1.0]),
        ),
    );
    assert_eq!(given.tangents()[0].t1, [0.0, 1.0, 0.0, 1.0]);
    let n = material_where(&given, [0.2, 0.1, 3.0], down).shading_normal;
    assert_near(n, Vec3::new(0.0, 0.6, 0.8), 0.01, "the file's tangent");

    // A flat texel leaves the normal as it was.
    let flat = model(
        dir.path(),
        "flat.glb",
        textured_quad(
            material(1.0),
            &[normal_texel([0.0, 0.0, 1.0])],
            UPRIGHT_UVS,
            None,
        ),
    );
    let n = material_where(&flat, [-0.5, 0.3, 3.0], down).shading_normal;
    assert_near(n, Vec3::Z, 0.01, "flat texel");
}

/// MikkTSpace against the tangents of known layouts, and the normal map
/// tilting along each: the image turned a quarter on the quad (u up the
/// quad: tangent +y, the image's top towards −x = n × t, sign +1) and
/// mirrored (u towards −x, the image's top +y = −(n × t), sign −1).
#[test]
fn generated_tangents_follow_the_texture_layout() {
    let dir = tempfile::tempdir().unwrap();
    let material = json!({"normalTexture": {"index": 0}});
    // u = (y + 1)/2, v = (x + 1)/2.
    let turned = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]];
    // u = (1 − x)/2, v = (1 − y)/2.
    let mirrored = [[1.0, 1.0], [0.0, 1.0], [0.0, 0.0], [1.0, 0.0]];
    for (name, uvs, expected) in [
        ("turned", turned, [0.0, 1.0, 0.0, 1.0]),
        ("mirrored", mirrored, [-1.0, 0.0, 0.0, -1.0]),
    ] {
        let scene = model(
            dir.path(),
            &format!("{name}.glb"),
            textured_quad(
                material.clone(),
                &[normal_texel([0.6, 0.0, 0.8])],
                uvs,
                None,
            ),
        );
        for t in scene.tangents() {
            for corner in [t.t0, t.t1, t.t2] {
                let error = (glam::Vec4::from(corner) - glam::Vec4::from(expected)).length();
                assert!(error < 1e-6, "{name}: {corner:?}, expected {expected:?}");
            }
        }
        let tangent = Vec3::new(expected[0], expected[1], expected[2]);
        let n = material_where(&scene, [0.2, 0.1, 3.0], [0.0, 0.0, -1.0]).shading_normal;
        assert_near(n, 0.6 * tangent + 0.8 * Vec3::Z, 0.01, name);
    }
}

/// KHR_materials_emissive_strength multiplies emissiveFactor.
#[test]
fn emissive_strength_scales_the_emission() {
    let dir = tempfile::tempdir().unwrap();
    let material = json!({"emissiveFactor": [1.0, 0.5, 0.25],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}});
    let mut glb = Glb::default();
    let primitive = quad_primitive(&mut glb, UPRIGHT_UVS, None);
    let bytes = one_primitive_glb(
        glb,
        primitive,
        material,
        Vec::new(),
        &["KHR_materials_emissive_strength"],
    );
    let scene = model(dir.path(), "glow.glb", bytes);
    assert_eq!(scene.materials()[0].emission, [4.0, 2.0, 1.0]);
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
}

/// Extensions a file uses but lambert does not implement (and the file
/// does not require) are warnings naming them.
#[test]
fn unimplemented_material_extensions_are_named() {
    let mut glb = Glb::default();
    let primitive = quad_primitive(&mut glb, UPRIGHT_UVS, None);
    let bytes = one_primitive_glb(
        glb,
        primitive,
        json!({}),
        Vec::new(),
        &["KHR_materials_transmission", "KHR_materials_clearcoat"],
    );
    let mesh = lambert::loading::gltf::parse_scene(&bytes, Path::new("g.glb"), Default::default())
        .unwrap()
        .mesh;
    let warnings = mesh.warnings.join("\n");
    for name in ["KHR_materials_transmission", "KHR_materials_clearcoat"] {
        assert!(
            warnings.contains(&format!("uses {name}, which lambert ignores")),
            "{warnings}"
        );
    }
}

/// MTL's Ks/Ns/Pr/Pm by Blender's rule (docs/rendering.md): a highlight
/// (Ks > 0) or Pr/Pm makes a metallic-roughness material, roughness from
/// Pr else 1 − √(Ns/1000), metallic from Pm else 0; without them, or with
/// Ks 0, Lambert. Out-of-range values are errors at their line.
#[test]
fn mtl_specular_terms_map_to_metallic_and_roughness() {
    let mtl = "newmtl matte\nKd 0.5 0.5 0.5\n\
               newmtl black_ks\nKs 0 0 0\nNs 500\n\
               newmtl shiny\nKs 0.5 0.5 0.5\nNs 250\n\
               newmtl no_exponent\nKs 1\n\
               newmtl pbr\nNs 900\nPr 0.3\nPm 1\n\
               newmtl capped\nKs 0.04\nNs 4000\n";
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl matte\nf 1 2 3\n";
    let (_dir, mesh) = load_written(&[("m.mtl", mtl), ("m.obj", obj)]);
    let brdf = |metallic, roughness| Brdf::MetallicRoughness {
        metallic,
        roughness,
    };
    let brdfs: Vec<(&str, Brdf)> = mesh
        .materials
        .iter()
        .map(|m| (m.name.as_str(), m.brdf))
        .collect();
    assert_eq!(
        brdfs,
        [
            ("matte", Brdf::Lambert),
            ("black_ks", Brdf::Lambert),
            ("shiny", brdf(0.0, 0.5)),
            ("no_exponent", brdf(0.0, 1.0)),
            ("pbr", brdf(1.0, 0.3)),
            ("capped", brdf(0.0, 0.0)),
        ]
    );
    let scene = {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "m.mtl", mtl);
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl shiny\nf 1 2 3\n";
        Scene::load(&write(dir.path(), "m.obj", obj)).unwrap()
    };
    let shiny = scene.materials()[2];
    assert_eq!(
        (shiny.kind, shiny.metallic, shiny.roughness),
        (MATERIAL_METALLIC_ROUGHNESS, 0.0, 0.5)
    );
    assert_eq!(scene.materials()[0].kind, MATERIAL_LAMBERT);

    for (statement, message) in [
        ("Pm 1.5", "Pm needs a number in [0, 1]"),
        ("Pr x", "Pr needs a number in [0, 1]"),
        ("Ns -1", "Ns needs a number ≥ 0"),
        ("Ks 0.5 0.5", "Ks needs 1 or 3 numbers"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "m.mtl", format!("newmtl a\n{statement}\n"));
        let path = write(dir.path(), "m.obj", obj);
        let error = error_of(&path);
        assert!(
            error.contains("m.mtl:2") && error.contains(message),
            "{error}"
        );
    }
}

/// TOML `metallic` and `roughness` on a mesh or a sphere make its
/// materials metallic-roughness (a factor not given keeps Lambert's:
/// metallic 0, roughness 1); each must lie in [0, 1].
#[test]
fn toml_metallic_and_roughness_keys() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let camera = "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\n\
                  width = 8\nheight = 8\n";
    let toml = |body: &str| format!("{camera}{body}");
    let scene = Scene::from_toml(
        &toml(
            "[[mesh]]\nfile = \"t.obj\"\nroughness = 0.5\n\
             [[mesh]]\nfile = \"t.obj\"\n\
             [[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmetallic = 1.0\nroughness = 0.2\n",
        ),
        &dir.path().join("s.toml"),
    )
    .unwrap();
    let kinds: Vec<(u32, f32, f32)> = scene
        .materials()
        .iter()
        .map(|m| (m.kind, m.metallic, m.roughness))
        .collect();
    assert_eq!(
        kinds,
        [
            (MATERIAL_METALLIC_ROUGHNESS, 0.0, 0.5),
            (MATERIAL_LAMBERT, 0.0, 1.0),
            (MATERIAL_METALLIC_ROUGHNESS, 1.0, 0.2),
        ]
    );
    for (body, message) in [
        (
            "[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmetallic = 2.0\n",
            "sphere[0].metallic = 2 must be in [0, 1]",
        ),
        (
            "[[mesh]]\nfile = \"t.obj\"\nroughness = -0.1\n",
            "mesh[0].roughness = -0.1 must be in [0, 1]",
        ),
    ] {
        let error = Scene::from_toml(&toml(body), &dir.path().join("s.toml"))
            .unwrap_err()
            .to_string();
        assert!(error.contains(message), "{error}");
    }
}

/// `lambert info` lists each material's BRDF, its metallic-roughness and
/// normal textures, and which textures they read.
#[test]
fn info_lists_metallic_roughness_and_normal_maps() {
    let dir = tempfile::tempdir().unwrap();
    let material = json!({"pbrMetallicRoughness": {"metallicFactor": 0.6,
        "roughnessFactor": 0.8, "metallicRoughnessTexture": {"index": 0}},
        "normalTexture": {"index": 1, "scale": 0.5}});
    let path = write(
        dir.path(),
        "info.glb",
        textured_quad(
            material,
            &[[0, 128, 255, 255], [128, 128, 255, 255]],
            UPRIGHT_UVS,
            None,
        ),
    );
    let output = lambert(&["info", s(&path)]);
    assert!(output.status.success(), "{output:?}");
    let text = String::from_utf8_lossy(&output.stdout);
    assert_contains_all(
        &text,
        &[
            "metallic 0.6, roughness 0.8 (× the metallic-roughness texture)",
            "normal map (scale 0.5)",
            "used by material 0 (metallic-roughness)",
            "used by material 0 (normal)",
        ],
    );
}

/// A scene with normal and metallic-roughness maps (tangents uploaded in
/// the scene's words, data textures in the store) renders under the direct
/// integrator on the GPU as on the CPU, bit for bit, and as it would
/// without the maps: the direct integrator reads neither.
#[test]
fn normal_mapped_scenes_render_on_both_paths() {
    let dir = tempfile::tempdir().unwrap();
    let with_maps = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
        "metallicRoughnessTexture": {"index": 1}}, "normalTexture": {"index": 2}});
    let without = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}});
    let images = [
        [200, 150, 100, 255],
        [0, 60, 255, 255],
        normal_texel([0.6, 0.0, 0.8]),
    ];
    let mut renders = Vec::new();
    for (name, material) in [("maps", with_maps), ("plain", without)] {
        let mut scene = model(
            dir.path(),
            &format!("{name}.glb"),
            textured_quad(material, &images, UPRIGHT_UVS, None),
        );
        scene.view_mut().camera.width = 24;
        scene.view_mut().camera.height = 24;
        let has_maps = lambert::gpu::specialisation(&scene)
            .iter()
            .any(|&(name, value)| name == "HAS_NORMAL_MAPS" && value == 1.0);
        assert_eq!(has_maps, name == "maps");
        let (gpu, cpu) = (render_gpu(&scene), render_cpu(&scene));
        assert!(bits(&gpu) == bits(&cpu), "{name}: GPU and CPU differ");
        renders.push(bits(&cpu));
    }
    assert!(
        renders[0] == renders[1],
        "the direct integrator reads no maps"
    );
}
