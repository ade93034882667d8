//! Textured scenes through full renders, on both paths: hand-computed
//! pixels of a textured plane (bilinear, nearest, each wrap mode, the sRGB
//! decode), the mip level a receding checkerboard reads, the bundled
//! textured model from OBJ and from glTF, and GPU = CPU bit for bit.

mod common;

use std::path::Path;

use common::*;
use lambert::Scene;

/// Writes `name`.gltf (with `name`.bin and `name`.png) into `dir`: one
/// mesh of `positions`, glTF `uvs` and `triangles`, its material's base
/// colour texture `image` sampled with `sampler` (glTF JSON).
fn write_gltf(
    dir: &Path,
    name: &str,
    positions: &[[f32; 3]],
    uvs: &[[f32; 2]],
    triangles: &[u16],
    image: &image::RgbaImage,
    sampler: &str,
) {
    image.save(dir.join(format!("{name}.png"))).unwrap();
    let mut bin: Vec<u8> = bytemuck::cast_slice(positions).to_vec();
    bin.extend_from_slice(bytemuck::cast_slice(uvs));
    bin.extend_from_slice(bytemuck::cast_slice(triangles));
    bin.resize(bin.len().next_multiple_of(4), 0);
    std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
    let (p, u, t) = (12 * positions.len(), 8 * uvs.len(), 2 * triangles.len());
    let lo = |i| positions.iter().map(|q| q[i]).fold(f32::INFINITY, f32::min);
    let hi = |i| {
        positions
            .iter()
            .map(|q| q[i])
            .fold(f32::NEG_INFINITY, f32::max)
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],
        "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}},"metallicFactor":0}}}}],
        "textures":[{{"sampler":0,"source":0}}],"samplers":[{sampler}],"images":[{{"uri":"{name}.png"}}],
        "buffers":[{{"byteLength":{},"uri":"{name}.bin"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{p}}},{{"buffer":0,"byteOffset":{p},"byteLength":{u}}},
            {{"buffer":0,"byteOffset":{},"byteLength":{t}}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},
            {{"bufferView":1,"componentType":5126,"count":{},"type":"VEC2"}},
            {{"bufferView":2,"componentType":5123,"count":{},"type":"SCALAR"}}]}}"#,
        bin.len(),
        p + u,
        positions.len(),
        lo(0),
        lo(1),
        lo(2),
        hi(0),
        hi(1),
        hi(2),
        uvs.len(),
        triangles.len()
    );
    std::fs::write(dir.join(format!("{name}.gltf")), json).unwrap();
}

/// The two renders' pixels differ nowhere, bit for bit (else how many do,
/// and the first).
fn assert_same_bits(a: &lambert::output::Rendered, b: &lambert::output::Rendered, what: &str) {
    assert_eq!(a.prims, b.prims, "{what}: the primitives differ");
    let differ: Vec<usize> = (0..a.image.rgb.len())
        .filter(|&i| a.image.rgb[i].map(f32::to_bits) != b.image.rgb[i].map(f32::to_bits))
        .collect();
    assert!(
        differ.is_empty(),
        "{what}: {} pixels differ, first {}: {:?} vs {:?}",
        differ.len(),
        differ[0],
        a.image.rgb[differ[0]],
        b.image.rgb[differ[0]]
    );
}

/// The CPU render that traverses as the GPU does (`lambert diff`'s).
fn gpu_twin(scene: &Scene) -> lambert::output::Rendered {
    lambert::cpu::render_gpu_twin(scene, scene.view(), &lambert::progress::Progress::hidden())
}

/// A scene of `model` in `dir`, lit by ambient 1 alone (so a pixel is its
/// base colour), seen by `camera` (TOML).
fn scene_of(dir: &Path, model: &str, camera: &str, spp: u32) -> Scene {
    let toml = format!(
        "[camera]\n{camera}\n[render]\nambient = [1.0, 1.0, 1.0]\nspp = {spp}\n\
         [[mesh]]\nfile = \"{model}\"\n"
    );
    let path = dir.join(format!("{model}.toml"));
    std::fs::write(&path, toml).unwrap();
    let scene = Scene::load(&path).unwrap();
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    scene
}

/// The unit square [-1, 1]² at z = 0 filling an 8×8 view head-on: pixel
/// (i, j) reads the texture at ((i + 0.5)/8, (j + 0.5)/8).
const HEAD_ON: &str = "eye = [0.0, 0.0, 1.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n\
                       vfov = 90.0\nwidth = 8\nheight = 8";

fn textured_plane(dir: &Path, name: &str, image: &image::RgbaImage, sampler: &str) -> Scene {
    let positions = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    // Shifted by 1/1024 (a quarter of the filter's 1/256 texel step): no
    // pixel centre falls on a step, where a hit's last bit would choose.
    let uvs = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]].map(|[u, v]| [u + SHIFT, v + SHIFT]);
    write_gltf(
        dir,
        name,
        &positions,
        &uvs,
        &[0, 1, 2, 0, 2, 3],
        image,
        sampler,
    );
    scene_of(dir, &format!("{name}.gltf"), HEAD_ON, 1)
}

fn sampler(filter: u32, wrap: u32) -> String {
    format!(r#"{{"magFilter":{filter},"minFilter":9987,"wrapS":{wrap},"wrapT":{wrap}}}"#)
}

const LINEAR: u32 = 9729;
const NEAREST: u32 = 9728;
const REPEAT: u32 = 10497;
const MIRRORED: u32 = 33648;
const CLAMP: u32 = 33071;

/// The plane's texture coordinates' offset.
const SHIFT: f32 = 1.0 / 1024.0;

/// sRGB 128 as linear light, in the store's 1/32768 steps.
const LINEAR_128: f32 = 7073.0 / 32768.0;

/// Pixels of a 2×1 texture, (255, 128, 0) then (0, 0, 255), across the
/// plane: each is the texels' linear values (sRGB decoded) weighted by
/// hand, per filter and wrap mode, on both paths.
#[test]
fn a_textured_plane_gives_hand_computed_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let texels = image::RgbaImage::from_fn(2, 1, |x, _| {
        image::Rgba(if x == 0 {
            [255, 128, 0, 255]
        } else {
            [0, 0, 255, 255]
        })
    });
    // The first texel's weight at pixel column i = 0..8: u = (i + 0.5)/8 is
    // 2u − 0.5 = (2i − 3)/8 texels from the first texel's centre.
    let bilinear = |wrap| -> [f32; 8] {
        std::array::from_fn(|i| {
            let p = (2.0 * i as f32 - 3.0) / 8.0 + 2.0 * SHIFT;
            match wrap {
                CLAMP => 1.0 - p.clamp(0.0, 1.0),
                // Left of the first centre the neighbour is the last
                // texel; right of the second, the first again.
                REPEAT if p < 0.0 => 1.0 + p,
                REPEAT if p > 1.0 => p - 1.0,
                // Mirrored: the first texel's mirror image on the left,
                // the second's on the right.
                MIRRORED if p < 0.0 => 1.0,
                MIRRORED if p > 1.0 => 0.0,
                _ => 1.0 - p,
            }
        })
    };
    let nearest: [f32; 8] = std::array::from_fn(|i| if i < 4 { 1.0 } else { 0.0 });
    for (filter, wrap, weights) in [
        (LINEAR, CLAMP, bilinear(CLAMP)),
        (LINEAR, REPEAT, bilinear(REPEAT)),
        (LINEAR, MIRRORED, bilinear(MIRRORED)),
        (NEAREST, REPEAT, nearest),
    ] {
        let scene = textured_plane(dir.path(), "plane", &texels, &sampler(filter, wrap));
        let (cpu, gpu) = (render_cpu(&scene), render_gpu(&scene));
        assert_same_bits(&cpu, &gpu, "textured plane, GPU vs CPU");
        for (path, r) in [("CPU", cpu), ("GPU", gpu)] {
            for j in 0..8 {
                for (i, w) in weights.iter().enumerate() {
                    let expected = [*w, w * LINEAR_128, 1.0 - w];
                    let got = r.image.pixel(i as u32, j);
                    // Within one 1/256 step of the weights.
                    assert!(
                        got.iter()
                            .zip(expected)
                            .all(|(g, e)| (g - e).abs() <= 1.001 / 256.0),
                        "{path}, filter {filter}, wrap {wrap}, pixel ({i}, {j}): {got:?}, \
                         expected {expected:?}"
                    );
                }
            }
        }
    }
}

/// A checkerboard of 1×1-unit squares on the ground, receding to 200
/// units: at 1 spp its far rows read the mip levels and come out near the
/// checker's mean (linear 0.5), not aliased; without mipmaps (minFilter
/// LINEAR) the same rows alias to a scatter of near-black and near-white.
#[test]
fn a_receding_checkerboard_reads_its_mip_levels() {
    let dir = tempfile::tempdir().unwrap();
    let checker = image::RgbaImage::from_fn(8, 8, |x, y| {
        let v = if (x + y) % 2 == 0 { 255 } else { 0 };
        image::Rgba([v, v, v, 255])
    });
    let positions = [
        [-100.0, 0.0, 0.0],
        [100.0, 0.0, 0.0],
        [100.0, 0.0, -200.0],
        [-100.0, 0.0, -200.0],
    ];
    // One texel a unit: the 8-texel image every 8 units.
    let uvs = positions.map(|p| [p[0] / 8.0, p[2] / 8.0]);
    let camera = "eye = [0.0, 1.0, 0.0]\nlook_at = [0.0, 0.8, -10.0]\nup = [0.0, 1.0, 0.0]\n\
                  vfov = 60.0\nwidth = 96\nheight = 96";
    let far_rows = |scene: &Scene| -> (f32, f32) {
        let r = render_cpu(scene);
        assert_same_bits(&gpu_twin(scene), &render_gpu(scene), "GPU vs its CPU twin");
        // The rows just below the horizon (row 46): 25 to 200 units away,
        // where a pixel spans from one to tens of squares.
        let values: Vec<f32> = (47..53)
            .flat_map(|y| (0..96).map(move |x| (x, y)))
            .map(|(x, y)| r.image.pixel(x, y)[0])
            .collect();
        let mean = values.iter().sum::<f32>() / values.len() as f32;
        let spread =
            (values.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / values.len() as f32).sqrt();
        (mean, spread)
    };
    let triangles = [0, 1, 2, 0, 2, 3];
    write_gltf(
        dir.path(),
        "mips",
        &positions,
        &uvs,
        &triangles,
        &checker,
        &sampler(LINEAR, REPEAT),
    );
    let (mean, spread) = far_rows(&scene_of(dir.path(), "mips.gltf", camera, 1));
    assert!(
        (mean - 0.5).abs() < 0.05 && spread < 0.05,
        "with mips: mean {mean}, spread {spread}"
    );
    let no_mips = r#"{"magFilter":9729,"minFilter":9729,"wrapS":10497,"wrapT":10497}"#;
    write_gltf(
        dir.path(),
        "flat",
        &positions,
        &uvs,
        &triangles,
        &checker,
        no_mips,
    );
    let (mean, spread) = far_rows(&scene_of(dir.path(), "flat.gltf", camera, 1));
    assert!(
        spread > 0.2,
        "without mips: mean {mean}, spread {spread}: not aliased?"
    );
}

/// The bundled textured scene from glTF and from OBJ + MTL (v flipped,
/// the transform as `-s`, alpha from `map_d`) renders alike, and each
/// renders the same bits on the GPU as on the CPU.
#[test]
fn the_bundled_textured_model_renders_alike_from_obj_and_gltf() {
    let glb = Scene::load(&asset("scenes/meshes/textured.glb")).unwrap();
    let obj = Scene::load(&asset("scenes/meshes/textured.obj")).unwrap();
    assert!(glb.warnings().is_empty(), "{:?}", glb.warnings());
    let (a, b) = (render_cpu(&glb), render_cpu(&obj));
    let stats = lambert::diff::compare(&a, &b, &lambert::diff::Tolerance::default()).unwrap();
    assert!(stats.passed, "glTF and OBJ differ:\n{stats}");
    // Textured: more than two colours on the ground, and the cut-out shows
    // the ground through the leaf's corners.
    let colours: std::collections::BTreeSet<[u32; 3]> =
        a.image.rgb.iter().map(|c| c.map(f32::to_bits)).collect();
    assert!(colours.len() > 50, "{} colours", colours.len());
    for (name, scene) in [("glTF", &glb), ("OBJ", &obj)] {
        assert_same_bits(&gpu_twin(scene), &render_gpu(scene), name);
    }
}

/// `lambert info MODEL` lists each texture: where it is from, its size and
/// format, its mip levels, and which materials read it as what.
#[test]
fn info_lists_the_textures_and_their_materials() {
    let obj = asset("scenes/meshes/textured.obj");
    let output = common::lambert(&["info", common::s(&obj)]);
    let out = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{}", common::stderr(&output));
    let dir = asset("scenes/meshes");
    for line in [
        "  textures: 3".to_string(),
        format!(
            "    0: {}, 64×64 PNG, 7 mip levels, used by material 0 (base colour)",
            dir.join("textured_grid.png").display()
        ),
        format!(
            "    2: {}, 32×32 PNG, 6 mip levels, used by material 1 (alpha)",
            dir.join("textured_leaf.png").display()
        ),
    ] {
        assert!(out.lines().any(|l| l == line), "no line {line:?} in\n{out}");
    }
}

/// The malformed corpus's texture cases load with a warning each, naming
/// the model, the image and what is wrong, and render with the factor
/// alone; the well-formed one (a PNG data URI) loads without.
#[test]
fn broken_images_are_warnings_and_the_model_renders() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/gltf");
    for (name, warning) in [
        ("texture-missing-image-file.gltf", "no-such-image.png"),
        (
            "texture-truncated-png.gltf",
            "image 0: not a readable PNG image: unexpected end of file; material 'm' keeps its \
             colour without it",
        ),
        (
            "texture-wrong-mime-data-uri.gltf",
            "image 0: a Gif image (lambert reads PNG and JPEG); material 'm' keeps its colour \
             without it",
        ),
        ("texture-png-data-uri.gltf", ""),
    ] {
        let scene = Scene::load(&dir.join(name)).unwrap();
        if warning.is_empty() {
            assert!(
                scene.warnings().is_empty(),
                "{name}: {:?}",
                scene.warnings()
            );
            assert_eq!(scene.textures().images().len(), 1, "{name}");
        } else {
            assert!(
                scene
                    .warnings()
                    .iter()
                    .any(|w| w.contains(name) && w.contains(warning)),
                "{name}: {:?}",
                scene.warnings()
            );
            assert!(scene.textures().images().is_empty(), "{name}");
            assert_eq!(
                scene.materials()[0].base_color_texture,
                lambert::layout::NO_TEXTURE
            );
        }
        render_cpu(&scene);
    }
}

/// Textures beyond the device's storage binding are the GpuLimit error,
/// naming them and by how much, as geometry is; `--device auto` then
/// renders on the CPU path.
#[test]
fn textures_beyond_the_gpu_limits_are_a_gpu_limit_error() {
    use lambert::gpu::{AdapterRequest, Gpu, GpuRenderer};
    const SMALL_GPU: u64 = 1 << 16;
    let dir = tempfile::tempdir().unwrap();
    let big = image::RgbaImage::from_fn(256, 256, |x, y| image::Rgba([x as u8, y as u8, 0, 255]));
    let scene = textured_plane(dir.path(), "big", &big, &sampler(LINEAR, REPEAT));
    let bytes = 4 * scene.textures().words().len() as u64;
    assert!(bytes > 4 * 256 * 256, "{bytes}");
    let gpu = Gpu::open_limited(&AdapterRequest::default(), false, Some(SMALL_GPU)).unwrap();
    let Err(error) = GpuRenderer::new(gpu, &scene) else {
        panic!("{bytes} bytes of textures fit in 64 KiB");
    };
    assert!(matches!(error, lambert::Error::GpuLimit(_)), "{error:?}");
    let message = error.to_string();
    assert!(
        message.contains(&format!("textures {bytes} bytes"))
            && message.contains(&format!("more than the {SMALL_GPU} bytes")),
        "{message}"
    );
    let output = dir.path().join("out.pfm");
    let out = common::lambert_command()
        .args(["render", common::s(&dir.path().join("big.gltf.toml"))])
        .args([
            "-o",
            common::s(&output),
            "--device",
            "auto",
            "--adapter",
            "llvmpipe",
        ])
        .env(lambert::gpu::MAX_BUFFER_ENV, SMALL_GPU.to_string())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", common::stderr(&out));
    assert!(output.exists());
}
