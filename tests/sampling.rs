//! Anti-aliasing: stratified samples from a hash both paths share, and error falling as spp rises.

mod common;

use common::*;
use lambert::Scene;
use lambert::camera::strata_columns;
use lambert::cpu;
use lambert::diff::{Tolerance, compare};
use lambert::output::Rendered;
use lambert::progress::Progress;
use lambert::render::{DeviceChoice, Renderer};
use lambert::scene::Intersect;
use std::sync::Arc;

/// `scene` rendered adaptively from its own view on `device`.
fn adaptive_on(
    scene: &Scene,
    device: DeviceChoice,
    settings: lambert::adaptive::AdaptiveSettings,
) -> (lambert::output::Rendered, lambert::adaptive::AdaptiveReport) {
    let shared = Arc::new(scene.clone());
    let (mut renderer, _) = Renderer::open(shared, device, &Default::default()).unwrap();
    lambert::adaptive::render_adaptive(&mut renderer, scene.view(), settings).unwrap()
}

fn at_spp(scene: &Scene, spp: u32) -> Scene {
    let mut s = scene.clone();
    s.view_mut().spp = spp;
    s
}

#[test]
fn strata_form_a_full_grid() {
    for (spp, columns) in [
        (1, 1),
        (2, 1),
        (4, 2),
        (8, 2),
        (9, 3),
        (12, 3),
        (16, 4),
        (17, 1),
        (64, 8),
    ] {
        assert_eq!(strata_columns(spp), columns, "spp {spp}");
        assert_eq!(spp % strata_columns(spp), 0);
    }
}

#[test]
fn samples_stay_in_their_pixel_and_cover_its_cells() {
    let mut s = load("edge_cases");
    s.view_mut().spp = 16;
    let kernel = cpu::f32::Kernel::new(&s);
    for (x, y) in [(0, 0), (7, 3), (64, 64)] {
        let mut cells = [false; 16];
        for sample in 0..16 {
            let (px, py) = kernel.sample_position(x, y, sample);
            assert!(px >= x as f32 && px < x as f32 + 1.0 && py >= y as f32 && py < y as f32 + 1.0);
            let (cx, cy) = (
                ((px - x as f32) * 4.0) as usize,
                ((py - y as f32) * 4.0) as usize,
            );
            cells[cy * 4 + cx] = true;
        }
        assert!(
            cells.iter().all(|&c| c),
            "pixel ({x}, {y}): a stratum has no sample"
        );
    }
    // spp = 1 keeps the pixel centre.
    s.view_mut().spp = 1;
    assert_eq!(
        cpu::f32::Kernel::new(&s).sample_position(3, 5, 0),
        (3.5, 5.5)
    );
}

/// The f64 oracle's image of `scene` at 256 spp, with `seed` and
/// `intersect`: the reference the sampling tests measure error against.
fn reference_of(scene: &Scene, seed: u32, intersect: Intersect) -> Rendered {
    let mut reference = at_spp(scene, 256);
    reference.view_mut().seed = seed;
    let settings = lambert::scene::RenderSettings {
        intersect,
        ..reference.default_settings()
    };
    render_oracle(&reference.with_settings(&settings))
}

#[test]
fn error_falls_as_spp_rises_on_hard_edges() {
    // edge_cases and spheres: silhouettes and shadow edges everywhere.
    for name in ["edge_cases", "spheres"] {
        let scene = load(name);
        let reference = reference_of(&scene, 12345, Intersect::Watertight);
        let mut last = f64::INFINITY;
        for spp in [1, 4, 16, 64] {
            let image = render_cpu(&at_spp(&scene, spp));
            let rmse = compare(&image, &reference, &Tolerance::default())
                .unwrap()
                .rmse;
            println!("{name}: spp {spp:>2}: RMSE {rmse:.3e} against the 256-spp f64 reference");
            assert!(
                rmse < last,
                "{name}: RMSE at spp {spp} ({rmse}) is not below {last}"
            );
            last = rmse;
        }
    }
}

#[test]
fn gpu_and_cpu_agree_at_4_spp() {
    for name in ["edge_cases", "spheres", "bunny", "cornell"] {
        let scene = at_spp(&load(name), 4);
        let (gpu, cpu) = (render_gpu(&scene), render_cpu(&scene));
        let stats = compare(&gpu, &cpu, &Tolerance::default()).unwrap();
        println!("{name} at 4 spp, GPU vs CPU:\n{stats}");
        assert!(stats.passed, "{name}:\n{stats}");
    }
}

#[test]
fn specialised_and_full_shaders_render_the_same_image() {
    use lambert::gpu::GpuRenderer;
    for name in ["spheres", "bunny", "triangle_oblique"] {
        let scene = load(name);
        let mut full = GpuRenderer::with_full_shader(open_gpu(), &scene).unwrap();
        let full = full.render(scene.view(), &Progress::hidden()).unwrap().0;
        let stats = compare(&render_gpu(&scene), &full, &Tolerance::default()).unwrap();
        assert_eq!(
            stats.max_abs, 0.0,
            "{name}: specialisation changed the image\n{stats}"
        );
        assert_eq!(stats.prim_mismatches, 0);
    }
}

#[test]
fn adaptive_sampling_beats_uniform_at_the_same_sample_count() {
    use lambert::adaptive::AdaptiveSettings;
    for name in ["edge_cases", "spheres"] {
        let scene = load(name);
        let reference = reference_of(&scene, 777, scene.default_settings().intersect);
        let settings = AdaptiveSettings {
            target_error: 0.01,
            base_spp: 4,
            max_spp: 64,
        };
        let (cpu_image, report) = adaptive_on(&scene, DeviceChoice::Cpu, settings);
        let (gpu_image, gpu_report) = adaptive_on(&scene, DeviceChoice::Gpu, settings);
        // Same samples on both paths: the same pixels refined, the same image.
        assert_eq!(
            report.refined_per_pass, gpu_report.refined_per_pass,
            "{name}"
        );
        let stats = compare(&gpu_image, &cpu_image, &Tolerance::default()).unwrap();
        assert!(stats.passed, "{name}: adaptive GPU vs CPU\n{stats}");
        // Uniform sampling with at least as many samples in all.
        let uniform_spp = report.mean_spp.ceil() as u32;
        let uniform = render_cpu(&at_spp(&scene, uniform_spp));
        let adaptive_rmse = compare(&cpu_image, &reference, &Tolerance::default())
            .unwrap()
            .rmse;
        let uniform_rmse = compare(&uniform, &reference, &Tolerance::default())
            .unwrap()
            .rmse;
        println!(
            "{name}: adaptive {:.2} spp on average: RMSE {adaptive_rmse:.3e} (expected {:.3e}); uniform {uniform_spp} spp: RMSE {uniform_rmse:.3e}",
            report.mean_spp, report.expected_rmse
        );
        assert!(
            adaptive_rmse < uniform_rmse,
            "{name}: adaptive sampling is no better than uniform"
        );
    }
}

/// High spp on small and odd image sizes, up to the maximum, GPU against
/// CPU, uniform and adaptive. llvmpipe (lavapipe, CI's adapter) ends every
/// loop once an invocation group has run 65535 loop iterations: before the
/// samples were split over dispatches (and that limit checked by the
/// shader), the bunny's GPU pixels lost most of their light from about 192
/// spp, with no warning.
#[test]
fn high_spp_renders_agree_on_both_paths_at_every_size() {
    use lambert::adaptive::AdaptiveSettings;
    let bunny = load("bunny");
    let gpu = open_gpu();
    let mut renderer = lambert::gpu::GpuRenderer::new(gpu, &bunny).unwrap();
    let sizes = [(1, 1), (5, 3), (9, 17)];
    for (width, height) in sizes {
        for spp in [1, 7, 64, 192, 256, 1000, lambert::limits::MAX_SPP] {
            // 9×17 at the top spp costs the CPU path most; its smaller
            // neighbours cover the same per-pixel work.
            if width * height > 20 && spp > 256 {
                continue;
            }
            let mut scene = at_spp(&bunny, spp);
            scene.view_mut().camera.width = width;
            scene.view_mut().camera.height = height;
            let gpu_image = renderer
                .render(scene.view(), &Progress::hidden())
                .unwrap()
                .0;
            let cpu_image = render_cpu(&scene);
            let stats = compare(&gpu_image, &cpu_image, &Tolerance::default()).unwrap();
            assert!(
                stats.passed,
                "{width}×{height} at {spp} spp: GPU vs CPU\n{stats}"
            );
            assert_eq!(
                gpu_image.prims, cpu_image.prims,
                "{width}×{height} at {spp} spp"
            );
        }
    }
    let mut scene = bunny.clone();
    scene.view_mut().camera.width = 7;
    scene.view_mut().camera.height = 5;
    let settings = AdaptiveSettings {
        target_error: 1e-5,
        base_spp: 4,
        max_spp: 1024,
    };
    let (cpu_image, report) = adaptive_on(&scene, DeviceChoice::Cpu, settings);
    let (gpu_image, gpu_report) = adaptive_on(&scene, DeviceChoice::Gpu, settings);
    assert_eq!(report.refined_per_pass, gpu_report.refined_per_pass);
    assert!(report.refined_per_pass.len() >= 7, "{report:?}");
    let stats = compare(&gpu_image, &cpu_image, &Tolerance::default()).unwrap();
    assert!(stats.passed, "adaptive to 1024 spp: GPU vs CPU\n{stats}");
}
