//! The path integrator (`--integrator path`) through ray queries
//! (`--accel hardware`, docs/hardware-rays.md): every bounce's closest hit
//! and every light sample's shadow ray a ray query, against the compute
//! BVH's path on the same seed, and the viewer path tracing through them.
//! Each test needs a device with ray queries (`common::hardware`: on CI,
//! Mesa 25's lavapipe, unpacked privately by scripts/mesa-rt).

mod common;
#[path = "common/viewer.rs"]
mod viewer;

use common::hardware::ray_query_gpu;
use common::*;
use lambert::Scene;
use lambert::gpu::{Gpu, GpuRenderer};
use lambert::output::Rendered;
use lambert::progress::Progress;
use lambert::scene::{Accel, Integrator, RenderSettings};

/// A room lit by an area light under its ceiling alone (an emissive
/// quad, sampled as an emitter), holding a metallic sphere and a metallic
/// cube, path traced. No textures: lavapipe compiles the path kernel with
/// a textured material in minutes (docs/hardware-rays.md, "Renders"), so
/// alpha masks' candidate confirmation is tested under the direct
/// integrator (`renders_agree_with_the_compute_path`), which shares it.
const ROOM: &str = r#"
[camera]
eye = [0.0, 5.0, 15.0]
look_at = [0.0, 4.0, 0.0]
vfov = 45.0
width = 64
height = 64

[render]
integrator = "path"
max_depth = 6
spp = 8
seed = 7

[[mesh]] # floor
file = "meshes/quad.obj"
albedo = [0.75, 0.75, 0.75]
scale = 10.0

[[mesh]] # ceiling
file = "meshes/quad.obj"
albedo = [0.75, 0.75, 0.75]
scale = 10.0
translate = [0.0, 10.0, 0.0]

[[mesh]] # back wall
file = "meshes/quad.obj"
albedo = [0.75, 0.75, 0.75]
scale = 10.0
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 5.0, -5.0]

[[mesh]] # left wall
file = "meshes/quad.obj"
albedo = [0.75, 0.1, 0.1]
scale = 10.0
rotate_deg = [0.0, 0.0, 90.0]
translate = [-5.0, 5.0, 0.0]

[[mesh]] # the light: 3 × 3 units just under the ceiling
file = "meshes/quad.obj"
albedo = [0.0, 0.0, 0.0]
emission = [12.0, 10.0, 7.0]
scale = 3.0
translate = [0.0, 9.98, 0.0]

[[mesh]] # a metallic cube
file = "meshes/cube.obj"
albedo = [0.9, 0.7, 0.4]
metallic = 1.0
roughness = 0.3
scale = 2.5
rotate_deg = [0.0, 25.0, 0.0]
translate = [2.2, 1.25, -1.0]

[[sphere]] # a metallic sphere
center = [-2.0, 2.0, 0.0]
radius = 2.0
albedo = [0.95, 0.95, 0.95]
metallic = 1.0
roughness = 0.15
"#;

/// `ROOM` as `accel` traces it.
fn room(accel: Accel) -> Scene {
    let scene = scene(ROOM);
    let settings = RenderSettings {
        accel,
        ..scene.default_settings()
    };
    scene.with_settings(&settings)
}

fn render(gpu: &Gpu, scene: &Scene) -> Rendered {
    let mut renderer = GpuRenderer::new(gpu.clone(), scene).expect("the scene uploads");
    assert_eq!(
        renderer.ray_queries().is_some(),
        scene.default_settings().accel == Accel::Hardware,
        "{:?}",
        renderer.accel_note()
    );
    renderer
        .render(scene.view(), &Progress::hidden())
        .expect("the render runs")
        .0
}

fn sum(r: &Rendered) -> f64 {
    r.image.rgb.iter().flatten().map(|&v| v as f64).sum()
}

/// The stated bound (docs/hardware-rays.md, "Renders"): on the same seed
/// the two paths draw the same random numbers, so they part only where a
/// ray's answer does: a tie between two primitives at one distance, which
/// either traversal may order first (`hits_agree_with_the_cpu_twin` in
/// tests/hardware_rays.rs). The camera rays' first hits are the same in all
/// but at most 0.5% of pixels (none in this room on lavapipe), the image
/// sums within 1e-4 relative, and 99% of pixels within 1e-3.
const PRIM_MISMATCHES: f64 = 0.005;
const SUM_RELATIVE: f64 = 1e-4;
const PIXELS_CLOSE: f64 = 0.99;

#[test]
fn path_traced_renders_agree_with_the_compute_path() {
    let Some(gpu) = ray_query_gpu("path_traced_renders_agree_with_the_compute_path") else {
        return;
    };
    let (hw, bvh) = (room(Accel::Hardware), room(Accel::Bvh));
    assert_eq!(hw.default_settings().integrator, Integrator::Path);
    let (a, b) = (render(&gpu, &hw), render(&gpu, &bvh));
    let pixels = a.prims.len();
    let mismatched = a.prims.iter().zip(&b.prims).filter(|(x, y)| x != y).count();
    let (sa, sb) = (sum(&a), sum(&b));
    let close = a
        .image
        .rgb
        .iter()
        .zip(&b.image.rgb)
        .filter(|(x, y)| {
            (0..3).all(|i| (x[i] - y[i]).abs() <= 1e-3 * x[i].abs().max(y[i].abs()).max(1e-2))
        })
        .count();
    let identical = a
        .image
        .rgb
        .iter()
        .zip(&b.image.rgb)
        .filter(|(x, y)| x == y)
        .count();
    println!(
        "room, path traced, {} spp: {mismatched} of {pixels} first hits differ, \
         sums {sa} (ray queries) {sb} (compute BVH), relative {:.2e}, \
         {close} pixels within 1e-3, {identical} identical",
        hw.view().spp,
        (sa - sb).abs() / sb
    );
    // The room is what the test says it is: the light, the metal and the
    // masked quads are in view, and light bounced off them.
    assert!(sb > 0.0, "a black image");
    let mut in_view = b.prims.clone();
    in_view.sort_unstable();
    in_view.dedup();
    assert!(in_view.len() > 8, "too few primitives in view: {in_view:?}");
    assert!(
        mismatched as f64 <= PRIM_MISMATCHES * pixels as f64,
        "{mismatched} of {pixels} first hits differ"
    );
    assert!(
        (sa - sb).abs() <= SUM_RELATIVE * sb,
        "image sums differ: ray queries {sa}, compute BVH {sb}"
    );
    assert!(
        close as f64 >= PIXELS_CLOSE * pixels as f64,
        "only {close} of {pixels} pixels agree within 1e-3"
    );
}

/// `lambert view --integrator path --accel hardware` (under Xvfb): frames
/// path traced through ray queries, no note of a fallback, and the image
/// `render --integrator path --accel bvh --spp 2` makes.
#[test]
fn the_viewer_path_traces_through_ray_queries() {
    let Some(_gpu) = ray_query_gpu("the_viewer_path_traces_through_ray_queries") else {
        return;
    };
    let Some(x) = viewer::xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let meshes = asset("scenes/meshes");
    let text = ROOM.replace("\"meshes/", &format!("\"{}/", meshes.display()));
    let scene = dir.path().join("room.toml");
    std::fs::write(&scene, text).unwrap();
    let (shot, rendered) = (dir.path().join("view.png"), dir.path().join("render.png"));
    let common = ["--integrator", "path", "--device", "gpu"];
    let view = lambert_command()
        .args(["view", s(&scene), "--frames", "2", "--screenshot", s(&shot)])
        .args(["--accel", "hardware"])
        .args(common)
        .env("DISPLAY", &x.display)
        .output()
        .unwrap();
    assert!(view.status.success(), "{}", stderr(&view));
    assert!(!stderr(&view).contains("compute BVH"), "{}", stderr(&view));
    let render = lambert_command()
        .args(["render", s(&scene), "--spp", "2", "-o", s(&rendered)])
        .args(["--accel", "bvh"])
        .args(common)
        .output()
        .unwrap();
    assert!(render.status.success(), "{}", stderr(&render));
    let (w, h, a) = viewer::png(&shot);
    let (_, _, b) = viewer::png(&rendered);
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    println!(
        "viewer against render: {differ} of {} bytes differ",
        a.len()
    );
    assert_eq!((w, h), (64, 64));
    assert_eq!(a.len(), b.len());
    assert!(
        differ as f64 <= 0.01 * a.len() as f64,
        "{differ} of {} bytes differ",
        a.len()
    );
}
