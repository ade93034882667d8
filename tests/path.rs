//! The path integrator (`--integrator path`): the same exposure as the
//! direct integrator where nothing reflects between surfaces, the GPU
//! against its CPU twin on the same random numbers, and its settings.

mod common;

use common::*;
use lambert::Scene;
use lambert::output::Rendered;
use lambert::scene::{Integrator, RenderSettings};

/// `scene` path traced with `spp` samples and at most `max_depth` surfaces.
fn path_traced(scene: &Scene, spp: u32, max_depth: u32) -> Scene {
    let mut settings = RenderSettings {
        integrator: Integrator::Path,
        max_depth,
        ..scene.default_settings()
    };
    settings.view.spp = spp;
    scene.clone().with_settings(&settings)
}

/// Largest difference of two images, relative to the larger value (values
/// under `floor` compared absolutely).
fn worst_relative(a: &Rendered, b: &Rendered, floor: f32) -> f32 {
    a.image
        .rgb
        .iter()
        .flatten()
        .zip(b.image.rgb.iter().flatten())
        .map(|(x, y)| (x - y).abs() / x.abs().max(y.abs()).max(floor))
        .fold(0.0, f32::max)
}

/// Two spheres on each other's far sides from the camera, apart, no
/// ambient: what the lights give one sphere cannot reach the other.
const CONVEX: &str = r#"
[camera]
eye = [0.0, 0.0, 8.0]
look_at = [0.0, 0.0, 0.0]
vfov = 40.0
width = 48
height = 32

[render]
background = [0.1, 0.2, 0.3]

[[sphere]]
center = [-1.3, 0.0, 0.0]
radius = 1.0
albedo = [0.8, 0.5, 0.2]

[[point_light]]
position = [-4.0, 3.0, 5.0]
intensity = [30.0, 30.0, 30.0]

[[directional_light]]
direction = [1.0, 0.5, 1.0]
irradiance = [0.6, 0.6, 0.5]
"#;

#[test]
fn path_tracing_changes_the_light_transport_not_the_exposure() {
    // One convex body: every bounce leaves the scene and brings back
    // nothing (no environment), so path tracing sees what the direct
    // integrator sees, light by light (each punctual light is taken at
    // every vertex, emitting π times its colour into albedo/π).
    let scene = scene(CONVEX);
    let direct = render_cpu(&scene);
    for max_depth in [1, 4] {
        let path = render_cpu(&path_traced(&scene, 1, max_depth));
        let worst = worst_relative(&direct, &path, 1e-3);
        assert!(
            worst < 1e-4,
            "max_depth {max_depth}: path differs from direct by {worst} (relative)"
        );
        assert_eq!(direct.prims, path.prims, "the same camera rays and hits");
    }
    // The background is what a camera ray that misses shows, as under
    // direct.
    let background = direct.image.rgb[0];
    assert_eq!(background, [0.1, 0.2, 0.3]);
}

#[test]
fn gpu_path_tracing_agrees_with_its_twin() {
    // The Cornell room lit by its point lights: light bounces between its
    // walls. Both paths draw the same random numbers; they part only
    // where rounding sends a path another way, which the image's mean
    // barely shows.
    let mut scene = path_traced(&load("cornell"), 4, 6);
    let mut view = scene.view().clone();
    view.camera = view.camera.resized(Some(64), Some(64)).unwrap();
    scene.view_mut().clone_from(&view);
    let gpu = render_gpu(&scene);
    let cpu = render_cpu(&scene);
    assert_eq!(gpu.prims, cpu.prims, "the same first hits");
    let mean = |r: &Rendered| r.image.rgb.iter().flatten().map(|&v| v as f64).sum::<f64>();
    let (g, c) = (mean(&gpu), mean(&cpu));
    assert!(
        (g - c).abs() <= 2e-3 * c,
        "image sums differ: GPU {g}, CPU {c}"
    );
    let close = gpu
        .image
        .rgb
        .iter()
        .zip(&cpu.image.rgb)
        .filter(|(a, b)| (0..3).all(|i| (a[i] - b[i]).abs() <= 1e-3 * a[i].abs().max(b[i].abs()).max(1e-2)))
        .count();
    let pixels = cpu.image.rgb.len();
    let differ = bits(&gpu).iter().zip(bits(&cpu)).filter(|(a, b)| **a != *b).count();
    println!("{close} of {pixels} pixels within 1e-3, {differ} values differ in bits; sums {g} {c}");
    assert!(
        close as f64 >= 0.98 * pixels as f64,
        "only {close} of {pixels} pixels agree within 1e-3"
    );
    // Bounced light is there: path tracing is brighter than direct light
    // alone in the room (the walls light each other).
    let direct = render_cpu(&{
        let mut s = load("cornell");
        s.view_mut().clone_from(&view);
        s
    });
    let ambient_free = mean(&direct);
    assert!(c > ambient_free, "no light bounced: {c} against {ambient_free}");
}

#[test]
fn the_integrator_and_depth_come_from_the_scene_file() {
    let text = CONVEX.replace(
        "[render]",
        "[render]\nintegrator = \"path\"\nmax_depth = 3",
    );
    let settings = scene(&text).default_settings();
    assert_eq!(settings.integrator, Integrator::Path);
    assert_eq!(settings.max_depth, 3);
    let defaults = scene(CONVEX).default_settings();
    assert_eq!(defaults.integrator, Integrator::Direct);
    assert_eq!(defaults.max_depth, lambert::scene::DEFAULT_MAX_DEPTH);
    for (bad, what) in [
        ("max_depth = 0", "max_depth 0"),
        ("max_depth = 65", "max_depth 65"),
        ("integrator = \"bidir\"", "bidir"),
    ] {
        let text = CONVEX.replace("[render]", &format!("[render]\n{bad}"));
        let error = Scene::from_toml(&text, &asset("scenes/inline.toml"))
            .expect_err(bad)
            .to_string();
        assert!(error.contains(what), "{bad}: {error}");
    }
}
