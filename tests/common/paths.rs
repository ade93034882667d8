//! Path tracing's test helpers: a scene path traced, a bundled scene
//! made small, and the bound within which the GPU's path-traced image is
//! its CPU twin's (docs/rendering.md, "GPU and CPU").

use lambert::Scene;
use lambert::output::Rendered;
use lambert::scene::{Integrator, RenderSettings};

use super::{bits, load, render_cpu, render_gpu};

/// `scene` path traced with `spp` samples and at most `max_depth` surfaces.
pub fn path_traced(scene: &Scene, spp: u32, max_depth: u32) -> Scene {
    let mut settings = RenderSettings {
        integrator: Integrator::Path,
        max_depth,
        ..scene.default_settings()
    };
    settings.view.spp = spp;
    scene.clone().with_settings(&settings)
}

/// The GPU's path-traced image against its twin's, on the same random
/// numbers: they part only where rounding sends a path another way (a
/// shadow ray grazing an edge, a roulette draw at its threshold), which
/// the image barely shows: the same first hits, image sums within 1e-5
/// relative, and 99% of pixels within 1e-3.
pub fn assert_agrees_with_twin(scene: &Scene) -> (f64, f64) {
    assert_within_twin_bound(&render_gpu(scene), &render_cpu(scene))
}

/// `assert_agrees_with_twin` of images already rendered.
pub fn assert_within_twin_bound(gpu: &Rendered, cpu: &Rendered) -> (f64, f64) {
    assert_eq!(gpu.prims, cpu.prims, "the same first hits");
    let sum = |r: &Rendered| r.image.rgb.iter().flatten().map(|&v| v as f64).sum::<f64>();
    let (g, c) = (sum(gpu), sum(cpu));
    let close = gpu
        .image
        .rgb
        .iter()
        .zip(&cpu.image.rgb)
        .filter(|(a, b)| {
            (0..3).all(|i| (a[i] - b[i]).abs() <= 1e-3 * a[i].abs().max(b[i].abs()).max(1e-2))
        })
        .count();
    let pixels = cpu.image.rgb.len();
    let differ = bits(gpu)
        .iter()
        .zip(bits(cpu))
        .filter(|(a, b)| **a != *b)
        .count();
    println!(
        "{close} of {pixels} pixels within 1e-3, {differ} values differ in bits; sums {g} {c}"
    );
    assert!(
        (g - c).abs() <= 1e-5 * c,
        "image sums differ: GPU {g}, CPU {c}"
    );
    assert!(
        close as f64 >= 0.99 * pixels as f64,
        "only {close} of {pixels} pixels agree within 1e-3"
    );
    (g, c)
}

/// `name`'s scene at `side`².
pub fn small(name: &str, side: u32) -> Scene {
    let mut scene = load(name);
    let mut view = scene.view().clone();
    view.camera = view.camera.resized(Some(side), Some(side)).unwrap();
    scene.view_mut().clone_from(&view);
    scene
}

/// One sphere lit by one point light, no ambient, before a camera (the
/// scene the integrators must show alike).
pub const ONE_LIGHT: &str = r#"
[render]
background = [0.1, 0.2, 0.3]

[[sphere]]
center = [-1.3, 0.0, 0.0]
radius = 1.0
albedo = [0.8, 0.5, 0.2]

[[point_light]]
position = [-4.0, 3.0, 5.0]
intensity = [30.0, 30.0, 30.0]

"#;
