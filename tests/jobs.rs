//! Render jobs called as a library (`lambert::jobs`): their reports, the files they write and the lines they say as they go.

mod common;

use std::sync::{Arc, Mutex};

use lambert::camera::View;
use lambert::jobs::{self, ImageJob, Sampling, TurntableJob};
use lambert::progress::{ProgressBar, ProgressSink};
use lambert::render::{DeviceChoice, Renderer};

/// Keeps a job's lines; draws no bar.
#[derive(Default)]
struct Lines(Mutex<Vec<String>>);

struct NoBar;

impl ProgressBar for NoBar {
    fn inc(&self, _units: u64) {}
    fn finish(&self) {}
}

impl ProgressSink for Lines {
    fn start(&self, _total: u64, _unit: &str) -> Box<dyn ProgressBar> {
        Box::new(NoBar)
    }

    fn line(&self, text: &str) {
        self.0.lock().unwrap().push(text.to_string());
    }
}

fn small(name: &str) -> lambert::Scene {
    let mut scene = common::load(name);
    (
        scene.view_mut().camera.width,
        scene.view_mut().camera.height,
    ) = (16, 12);
    scene
}

/// An image job on the CPU path, writing `output`, no first-hit outputs.
fn cpu_image_job(output: &std::path::Path, sampling: Sampling) -> ImageJob<'_> {
    ImageJob {
        output,
        device: DeviceChoice::Cpu,
        adapter: &DEFAULT_ADAPTER,
        sampling,
        aovs: &[],
    }
}

static DEFAULT_ADAPTER: std::sync::LazyLock<lambert::gpu::AdapterRequest> =
    std::sync::LazyLock::new(Default::default);

#[test]
fn a_turntable_job_writes_its_frames_and_says_each() {
    let dir = tempfile::tempdir().unwrap();
    let pattern = dir.path().join("f_{:02}.png");
    let job = TurntableJob {
        pattern: &pattern,
        frames: 4,
        range: 1..=2,
        device: DeviceChoice::Cpu,
        adapter: &Default::default(),
    };
    let lines = Lines::default();
    let scene = small("spheres");
    let settings = scene.default_settings();
    let report = jobs::render_turntable(scene, &settings, &job, Some(&lines)).unwrap();
    let frames: Vec<u32> = report.written.iter().map(|f| f.frame).collect();
    assert_eq!(frames, [1, 2]);
    assert_eq!(report.frames, 4);
    for frame in &report.written {
        assert!(frame.path.is_file(), "{}", frame.path.display());
    }
    assert_eq!(report.written[0].path, dir.path().join("f_01.png"));
    let lines = lines.0.into_inner().unwrap();
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert_eq!(
        lines[0],
        format!("rendering 2 of 4 frames on {}", report.device)
    );
    assert!(lines[1].starts_with("frame 1: ") && lines[1].ends_with("f_01.png)"));
    assert!(lines[2].starts_with("frame 2: ") && lines[2].ends_with("f_02.png)"));
}

#[test]
fn an_image_job_reports_what_its_sampling_chose() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("image.pfm");
    let budget = 0.2;
    let job = cpu_image_job(&output, Sampling::Budget(budget));
    let lines = Lines::default();
    let scene = small("spheres");
    let settings = scene.default_settings();
    let report = jobs::render_image(scene, &settings, &job, Some(&lines)).unwrap();
    assert!(output.is_file());
    let chosen = report.budget.expect("a budget's report").plan.spp;
    assert_eq!(report.samples, (16 * 12 * chosen) as f64);
    assert_eq!((report.width, report.height), (16, 12));
    let lines = lines.0.into_inner().unwrap();
    assert_eq!(lines[0], format!("rendering on {}", report.device));
    assert!(
        lines[1].starts_with(&format!("time budget {budget} s: a 1-spp pass takes "))
            && lines[1].ends_with(&format!(", so {chosen} spp")),
        "{lines:?}"
    );

    let job = ImageJob {
        sampling: Sampling::Adaptive {
            target_error: 1e-6,
            max_spp: 16,
        },
        ..job
    };
    let scene = small("spheres");
    let mut settings = scene.default_settings();
    settings.view.spp = 1;
    let report = jobs::render_image(scene, &settings, &job, None).unwrap();
    let adaptive = report.adaptive.expect("an adaptive report");
    // From 4 samples (the scene asks for 1), refined where above the target.
    assert!(!adaptive.refined_per_pass.is_empty(), "{adaptive:?}");
    assert_eq!(report.samples, adaptive.total_samples as f64);
    assert!(adaptive.total_samples > 16 * 12 * 4, "{adaptive:?}");
}

/// What Python's render does: another size and spp as a view of the same
/// scene, through the job code, equal to a scene loaded with them.
#[test]
fn a_view_renders_as_a_scene_with_its_settings() {
    let scene = common::load("spheres");
    let view = View {
        spp: 3,
        ..small("spheres").view().clone()
    };
    let mut renderer = Renderer::Cpu(Arc::new(scene));
    let sampled = jobs::render_view(&mut renderer, &view, Sampling::Fixed, None).unwrap();
    let mut reference = small("spheres");
    reference.view_mut().spp = 3;
    assert_eq!(sampled.rendered, common::render_cpu(&reference));
    assert_eq!(sampled.samples, (16 * 12 * 3) as f64);
}

#[test]
fn an_image_job_writes_the_first_hits_outputs_beside_its_image() {
    use lambert::cpu::aov::Aov;
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("image.png");
    let job = ImageJob {
        aovs: &Aov::ALL,
        ..cpu_image_job(&output, Sampling::Fixed)
    };
    let scene = small("spheres");
    let settings = scene.default_settings();
    let camera = settings.view.camera.clone();
    let report = jobs::render_image(scene.clone(), &settings, &job, None).unwrap();
    let names: Vec<String> = report
        .aovs
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        ["image.albedo.exr", "image.normal.exr", "image.depth.exr"]
    );
    let read = |name: &str| image::open(dir.path().join(name)).unwrap().into_rgb32f();
    let (albedo, normal, depth) = (
        read("image.albedo.exr"),
        read("image.normal.exr"),
        read("image.depth.exr"),
    );
    assert_eq!(albedo.dimensions(), (camera.width, camera.height));
    // The centre pixel's camera ray hits a sphere (the scene's first hit
    // there, as the render's): its albedo is the sphere's, its normal a
    // unit vector facing the camera, its depth the hit's distance.
    let rendered = lambert::cpu::render(
        &scene,
        scene.view(),
        lambert::cpu::Precision::F32,
        &lambert::progress::Progress::hidden(),
    );
    let (x, y) = (camera.width / 2, camera.height / 2);
    let prim = rendered.prims[(y * camera.width + x) as usize];
    assert_ne!(prim, lambert::layout::NO_HIT, "the centre shows a sphere");
    let n = normal.get_pixel(x, y).0;
    let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    assert!((length - 1.0).abs() < 0.05, "normal {n:?}");
    let d = depth.get_pixel(x, y).0;
    assert!(d[0] > 0.0 && d[0] == d[1] && d[1] == d[2], "depth {d:?}");
    assert!(albedo.get_pixel(x, y).0.iter().any(|&c| c > 0.0));
    // A corner that misses everything is 0 in all three.
    let sky = rendered
        .prims
        .iter()
        .position(|&p| p == lambert::layout::NO_HIT);
    if let Some(i) = sky {
        let (sx, sy) = (i as u32 % camera.width, i as u32 / camera.width);
        assert_eq!(depth.get_pixel(sx, sy).0, [0.0; 3]);
    }
}
