//! Issue 45 item 3, settings in their place: a render's settings apart
//! from the scene (`RenderSettings`, which the jobs take), shadows toggled
//! on a resident renderer, and what the front ends ask of a `Renderer`
//! instead of matching on its variants.

mod common;

use std::sync::{Arc, Mutex};

use lambert::camera::View;
use lambert::gpu::GpuRenderer;
use lambert::jobs::{self, ImageJob, Sampling};
use lambert::layout::Ray;
use lambert::progress::Progress;
use lambert::render::{DeviceChoice, Renderer, Renderers};
use lambert::scene::{Accel, Intersect, RenderSettings, Scene};

/// `scene`'s settings at a small size, with shadows `shadows`.
fn small(scene: &Scene, shadows: bool) -> RenderSettings {
    let mut settings = scene.default_settings();
    settings.view.camera.width = 40;
    settings.view.camera.height = 30;
    settings.view.spp = 2;
    settings.shadows = shadows;
    settings
}

fn gpu_render(renderer: &mut GpuRenderer, view: &View) -> Vec<u32> {
    common::bits(
        &renderer
            .render(view, &Progress::hidden())
            .expect("GPU render")
            .0,
    )
}

/// A GPU renderer's shadows turned off and on again render, bit for bit,
/// as renderers opened with those settings (the scene never uploaded
/// again), with the specialised shader and the full one, whatever the
/// shadow dispatch; and the shadows do show.
#[test]
fn shadows_set_on_a_gpu_renderer_render_as_one_opened_with_them() {
    let gpu = common::open_gpu();
    for name in ["cornell", "spheres"] {
        let scene = common::load(name);
        let (on, off) = (small(&scene, true), small(&scene, false));
        let with = |settings: &RenderSettings| scene.clone().with_settings(settings);
        let opened = |settings: &RenderSettings, full: bool| {
            let scene = with(settings);
            let mut renderer = if full {
                GpuRenderer::with_full_shader(gpu.clone(), &scene)
            } else {
                GpuRenderer::new(gpu.clone(), &scene)
            }
            .expect("scene uploads");
            gpu_render(&mut renderer, &settings.view)
        };
        for full in [false, true] {
            let (lit, unlit) = (opened(&on, full), opened(&off, full));
            assert_ne!(lit, unlit, "{name}: shadows change nothing");
            let scene = with(&on);
            let mut renderer = if full {
                GpuRenderer::with_full_shader(gpu.clone(), &scene)
            } else {
                GpuRenderer::new(gpu.clone(), &scene)
            }
            .expect("scene uploads");
            let dispatch = renderer.shadow_dispatch;
            gpu_render(&mut renderer, &on.view);
            renderer.set_shadows(false).unwrap();
            assert_eq!(gpu_render(&mut renderer, &on.view), unlit, "{name}: off");
            renderer.set_shadows(true).unwrap();
            assert_eq!(renderer.shadow_dispatch, dispatch, "{name}");
            assert_eq!(gpu_render(&mut renderer, &on.view), lit, "{name}: on again");
        }
    }
}

/// `Renderer::set_shadows` on the CPU path renders as the scene with that
/// setting, and leaves the caller's scene as it was.
#[test]
fn shadows_set_on_the_cpu_path_render_as_the_scene_with_them() {
    let scene = common::load("cornell");
    let on = small(&scene, true);
    let shared = Arc::new(scene.clone().with_settings(&on));
    let mut renderer = Renderer::open_on(Arc::clone(&shared), None).unwrap();
    renderer.set_shadows(false).unwrap();
    let (image, _) = renderer.render(&on.view, None).unwrap();
    let off = small(&scene, false);
    assert_eq!(image, common::render_cpu(&scene.with_settings(&off)));
    assert!(
        shared.default_settings().shadows,
        "the caller's scene changed"
    );
    assert!(!renderer.shared_scene().unwrap().default_settings().shadows);
}

/// A scene's default settings are what it renders with, and a scene with
/// settings gives them back.
#[test]
fn default_settings_and_with_settings_agree() {
    let scene = common::load("spheres");
    let defaults = scene.default_settings();
    assert_eq!(&defaults.view, scene.view());
    assert_eq!(
        scene.clone().with_settings(&defaults).default_settings(),
        defaults
    );
    let other = RenderSettings {
        shadows: !defaults.shadows,
        ambient: [0.25, 0.5, 0.125],
        accel: Accel::BruteForce,
        intersect: Intersect::Seed,
        ..small(&scene, true)
    };
    let configured = scene.clone().with_settings(&other);
    assert_eq!(configured.default_settings(), other);
    assert_eq!(configured.ambient(), other.ambient);
    assert_eq!(configured.view(), &other.view);
    // The geometry is the scene's.
    assert_eq!(configured.triangles(), scene.triangles());
    assert_eq!(configured.spheres(), scene.spheres());
}

/// The image job renders with the settings it is given (size, spp,
/// ambient, shadows, intersection test), not the scene's own.
#[test]
fn the_image_job_renders_with_the_settings_it_is_given() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("image.pfm");
    let scene = common::load("cornell");
    let settings = RenderSettings {
        ambient: [0.2; 3],
        intersect: Intersect::MollerTrumbore,
        ..small(&scene, false)
    };
    assert_ne!(settings, scene.default_settings());
    let job = ImageJob {
        output: &output,
        device: DeviceChoice::Cpu,
        adapter: &Default::default(),
        sampling: Sampling::Fixed,
        aovs: &[],
    };
    let report = jobs::render_image(scene.clone(), &settings, &job, None).unwrap();
    assert_eq!((report.width, report.height), (40, 30));
    let expected = dir.path().join("expected.pfm");
    let rendered = common::render_cpu(&scene.with_settings(&settings));
    rendered.image.save(&expected).unwrap();
    assert_eq!(
        std::fs::read(&output).unwrap(),
        std::fs::read(&expected).unwrap()
    );
}

/// `Renderers::run` holds its lock only while a GPU works: on the CPU
/// path, another thread may take it while the work runs.
#[test]
fn renderers_run_lets_the_lock_go_on_the_cpu_path() {
    let scene = Arc::new(common::load("spheres"));
    let renderers = Mutex::new(Renderers::new(Arc::clone(&scene), Default::default()));
    let view = small(&scene, true).view;
    let (image, note) = Renderers::run(&renderers, DeviceChoice::Cpu, |renderer| {
        assert!(
            renderers.try_lock().is_ok(),
            "the lock is held on the CPU path"
        );
        assert!(renderer.is_cpu() && renderer.gpu().is_none());
        Ok(renderer.render(&view, None)?.0)
    })
    .unwrap();
    assert!(note.is_none());
    let expected = common::render_cpu(&(*scene).clone().with_settings(&small(&scene, true)));
    assert_eq!(image, expected);
}

/// `Renderer::trace_local` traces rays given in the scene's frame: where
/// that is the world's (no offset), the hits of `trace`, on either device.
#[test]
fn trace_local_is_trace_in_the_scenes_frame() {
    let scene = Arc::new(common::load("cornell"));
    assert_eq!(scene.offset(), glam::DVec3::ZERO);
    let rays: Vec<Ray> = lambert::rays::camera_rays(&scene)
        .into_iter()
        .step_by(7)
        .collect();
    let gpu = common::open_gpu();
    for mut renderer in [
        Renderer::open_on(Arc::clone(&scene), None).unwrap(),
        Renderer::open_on(Arc::clone(&scene), Some(&gpu)).unwrap(),
    ] {
        for any_hit in [false, true] {
            let world = renderer
                .trace(&rays, any_hit, Intersect::Watertight)
                .unwrap();
            let local = renderer
                .trace_local(&rays, any_hit, Intersect::Watertight)
                .unwrap();
            assert_eq!(local, world, "{}", renderer.describe());
        }
    }
}
