//! The path integrator's wavefront (gpu::path_wave, shaders/entry_paths.wgsl:
//! a pass a bounce over queues of live paths, shadow rays apart) against
//! its megakernel and its CPU twin: the same random numbers in the same
//! order, so the same image as the megakernel's, bit for bit, and the
//! twin's within the bound docs/rendering.md states; paths that end early
//! (escaping, roulette) and at max_depth; adaptive sampling's pixel lists
//! and progressive batches; and the choice of dispatch.

mod common;

use common::paths::*;
use common::*;
use lambert::Scene;
use lambert::gpu::{AdapterRequest, Gpu, GpuOptions, GpuRenderer, ShadowDispatch};
use lambert::output::Rendered;
use lambert::progress::Progress;
use lambert::scene::RenderSettings;

/// `scene` rendered on one GPU renderer in the path wavefront, then in the
/// megakernel.
fn wavefront_and_megakernel(scene: &Scene) -> (Rendered, Rendered) {
    let mut renderer = GpuRenderer::new(open_gpu(), scene).expect("scene uploads");
    let mut render = |dispatch| {
        renderer.shadow_dispatch = dispatch;
        let rendered = renderer.render(scene.view(), &Progress::hidden());
        rendered.expect("GPU render").0
    };
    let wave = render(ShadowDispatch::Wavefront);
    let mega = render(ShadowDispatch::Megakernel);
    (wave, mega)
}

/// The wavefront's image is the megakernel's, bit for bit, and the CPU
/// twin's within the stated bound; returns the wavefront's.
fn assert_wavefront_is_megakernel_and_twin(scene: &Scene, what: &str) -> Rendered {
    let (wave, mega) = wavefront_and_megakernel(scene);
    assert_eq!(wave.prims, mega.prims, "{what}: the same first hits");
    let differ = bits(&wave)
        .iter()
        .zip(bits(&mega))
        .filter(|(a, b)| **a != *b)
        .count();
    assert_eq!(
        differ, 0,
        "{what}: {differ} values differ from the megakernel's"
    );
    assert_within_twin_bound(&wave, &render_cpu(scene));
    wave
}

/// An open box (floor and back wall) with a rough GGX metal sphere, a
/// Lambert sphere, an emissive quad over them and a point light, under a
/// constant environment: paths escape, hit emitters (MIS against the
/// light sample) and reflect off the metal.
fn metal_emitter_environment() -> Scene {
    scene(&format!(
        r#"
{}
[render]
integrator = "path"
max_depth = 6
spp = 8

[environment]
color = [0.3, 0.35, 0.5]

[[mesh]] # floor
obj = "meshes/quad.obj"
albedo = [0.7, 0.7, 0.7]
scale = 6.0
translate = [0.0, -1.0, 0.0]

[[mesh]] # back wall
obj = "meshes/quad.obj"
albedo = [0.6, 0.3, 0.2]
scale = 6.0
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 2.0, -3.0]

[[mesh]] # an emissive panel, facing down
obj = "meshes/quad.obj"
albedo = [0.0, 0.0, 0.0]
emission = [6.0, 5.0, 4.0]
scale = 1.5
rotate_deg = [180.0, 0.0, 0.0]
translate = [0.5, 2.5, 0.0]

[[sphere]] # rough gold
center = [-0.9, 0.0, 0.0]
radius = 1.0
albedo = [1.0, 0.71, 0.29]
metallic = 1.0
roughness = 0.3

[[sphere]]
center = [1.3, -0.4, 0.6]
radius = 0.6
albedo = [0.2, 0.6, 0.3]

[[point_light]]
position = [3.0, 3.0, 4.0]
intensity = [8.0, 8.0, 8.0]
"#,
        camera_on_z(7.0, 45.0, 40, 32)
    ))
}

#[test]
fn the_path_wavefront_renders_the_area_lit_box_as_the_megakernel_and_twin() {
    // 16 spp, depth 8, the ceiling quad alone lighting the room.
    let image = assert_wavefront_is_megakernel_and_twin(&small("cornell_area", 40), "box");
    let lit = image.image.rgb.iter().filter(|p| p[0] > 0.0).count();
    assert!(
        lit > image.image.rgb.len() / 2,
        "the box is lit: {lit} pixels"
    );
}

#[test]
fn the_path_wavefront_renders_metal_emitters_and_an_environment_as_the_megakernel() {
    let scene = metal_emitter_environment();
    let image = assert_wavefront_is_megakernel_and_twin(&scene, "metal");
    // The corner sees the environment (camera rays that escape; the mean
    // of 8 samples rounded).
    let corner = image.image.rgb[0];
    for (c, e) in corner.iter().zip([0.3, 0.35, 0.5]) {
        assert!((c - e).abs() <= 1e-6, "corner {corner:?}");
    }
    // A path that escapes after a bounce brings the environment back: the
    // scene is brighter with it than without.
    let mut dark = scene.clone();
    dark.set_environment(None).unwrap();
    let sum = |r: &Rendered| r.image.rgb.iter().flatten().map(|&v| v as f64).sum::<f64>();
    let (wave_dark, _) = wavefront_and_megakernel(&dark);
    assert!(
        sum(&image) > sum(&wave_dark),
        "the environment lights nothing"
    );
    // Without shadows the shade pass adds each light sample's term itself
    // (no shadow ray): brighter, still the megakernel's image.
    let settings = RenderSettings {
        shadows: false,
        ..scene.default_settings()
    };
    let unshadowed = scene.with_settings(&settings);
    let lit = assert_wavefront_is_megakernel_and_twin(&unshadowed, "no shadows");
    assert!(sum(&lit) > sum(&image), "no shadow was cast");
}

#[test]
fn paths_that_end_early_and_at_max_depth_are_handled() {
    // max_depth 1 on a convex body lit by one point light, no
    // environment: every continuation escapes and brings nothing back, so
    // the wavefront shows the direct integrator's image (as the CPU twin
    // does, tests/path.rs).
    let one_sphere = scene(&(camera_on_z(8.0, 40.0, 32, 24) + ONE_LIGHT));
    let direct = render_gpu(&one_sphere);
    let (path, _) = wavefront_and_megakernel(&path_traced(&one_sphere, 1, 1));
    assert_eq!(direct.prims, path.prims);
    for (d, p) in direct.image.rgb.iter().zip(&path.image.rgb) {
        for c in 0..3 {
            let scale = d[c].abs().max(p[c].abs()).max(1e-3);
            assert!(
                (d[c] - p[c]).abs() <= 1e-4 * scale,
                "direct {d:?}, path {p:?}"
            );
        }
    }
    // The box, closed but for the camera's side: at depth 64 roulette ends
    // nearly every path before max_depth, at depth 2 every path that
    // survives ends there; each as the megakernel ends it.
    let room = small("cornell_area", 24);
    let mut sums = Vec::new();
    for max_depth in [2, 64] {
        let scene = path_traced(&room, 8, max_depth);
        let what = format!("max_depth {max_depth}");
        let image = assert_wavefront_is_megakernel_and_twin(&scene, &what);
        sums.push(
            image
                .image
                .rgb
                .iter()
                .flatten()
                .map(|&v| v as f64)
                .sum::<f64>(),
        );
    }
    assert!(sums[1] > sums[0], "more bounces, more light: {sums:?}");
}

#[test]
fn pixel_lists_and_progressive_batches_run_in_the_path_wavefront() {
    let scene = metal_emitter_environment();
    let mut renderer = GpuRenderer::new(open_gpu(), &scene).expect("scene uploads");
    let view = scene.view();
    let pixels: Vec<[u32; 2]> = (0..150).map(|i| [i % 40, (i * 7) % 32]).collect();
    let mut lists = Vec::new();
    let mut batches = Vec::new();
    for dispatch in [ShadowDispatch::Wavefront, ShadowDispatch::Megakernel] {
        renderer.shadow_dispatch = dispatch;
        lists.push(renderer.render_pixel_list(view, &pixels).unwrap());
        // The view's 8 samples in batches of 3, 3 and 2, as the viewer adds
        // them.
        let mut sums = vec![[0.0f32; 4]; 40 * 32];
        let mut image = None;
        for samples in [0..3, 3..6, 6..8] {
            image = renderer.add_samples(view, samples, &mut sums).unwrap();
        }
        batches.push(image.expect("the last batch finishes the image"));
    }
    let words = |v: &[[f32; 4]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(words(&lists[0]), words(&lists[1]), "pixel lists");
    assert!(
        lists[0].iter().any(|p| p[3] > 0.0),
        "variances of the means"
    );
    assert_eq!(batches[0].rgb, batches[1].rgb, "progressive batches");
    // And the whole render's image, which the batches add up to.
    let whole = render_gpu(&scene);
    assert_eq!(batches[0].rgb, whole.image.rgb);
}

/// LAMBERT_SHADOW_DISPATCH (`GpuOptions::shadow_dispatch`) chooses under
/// the path integrator too, with or without shadows; unset, the dispatch
/// docs/benchmarks.md measured faster.
#[test]
fn the_shadow_dispatch_variable_chooses_the_path_wavefront() {
    let scene = path_traced(&small("cornell_area", 8), 1, 4);
    let renderer = |chosen: Option<&str>| {
        let request = AdapterRequest {
            options: GpuOptions {
                shadow_dispatch: chosen.map(str::to_string),
                ..GpuOptions::default()
            },
            ..AdapterRequest::default()
        };
        let gpu = Gpu::open(&request, false).expect("an adapter (lavapipe on CI)");
        GpuRenderer::new(gpu, &scene).expect("scene uploads")
    };
    assert!(renderer(Some("wavefront")).is_wavefront());
    assert!(!renderer(Some("megakernel")).is_wavefront());
    assert_eq!(
        renderer(None).shadow_dispatch,
        ShadowDispatch::Megakernel,
        "unset: the megakernel, faster on lavapipe"
    );
    let textured = Scene::load(&asset("scenes/meshes/textured.glb")).expect("bundled model");
    let textured = path_traced(&textured, 1, 4);
    let gpu = Gpu::open(&AdapterRequest::default(), false).expect("an adapter (lavapipe on CI)");
    let renderer = GpuRenderer::new(gpu, &textured).expect("scene uploads");
    assert_eq!(
        renderer.shadow_dispatch,
        ShadowDispatch::Wavefront,
        "unset, a textured scene: the wavefront, faster on lavapipe"
    );
}

/// A textured model (base-colour textures, an alpha-masked leaf) under an
/// environment: the wavefront its scene's default dispatch, the
/// megakernel's image bit for bit and the twin's within the bound.
#[test]
fn the_path_wavefront_renders_a_textured_model_as_the_megakernel() {
    let model = Scene::load(&asset("scenes/meshes/textured.glb")).expect("bundled model");
    let mut settings = RenderSettings {
        integrator: lambert::scene::Integrator::Path,
        max_depth: 4,
        ..model.default_settings()
    };
    settings.view.spp = 2;
    settings.view.camera.width = 48;
    settings.view.camera.height = 32;
    let scene = model.with_settings(&settings);
    assert_wavefront_is_megakernel_and_twin(&scene, "textured.glb");
}
