//! The viewer's `p` (path tracing on and off) on a model lit by its own
//! emission: the default light goes under `path` and comes back under
//! `direct`, as `lambert render --integrator` has it (issue 46, item 5;
//! `Scene::default_light_goes`, `Scene::lights_change_with`).

mod common;
#[path = "common/viewer.rs"]
mod viewer;

use std::path::{Path, PathBuf};

use common::{lambert, s};
use lambert::scene::{Integrator, RenderSettings, Scene};
use viewer::{Viewer, wait_for, xvfb};

/// A floor lit by an emissive panel above it (MTL `Ke`), in `dir`: a model
/// with no lights of its own, which gets the default light.
fn emissive_model(dir: &Path) -> PathBuf {
    std::fs::write(
        dir.join("lamp.mtl"),
        "newmtl floor\nKd 0.8 0.8 0.8\n\nnewmtl lamp\nKd 0 0 0\nKe 4 3 2\n",
    )
    .unwrap();
    let obj = dir.join("lamp.obj");
    std::fs::write(
        &obj,
        "mtllib lamp.mtl\n\
         v -2 0 -2\nv -2 0 2\nv 2 0 2\nv 2 0 -2\n\
         v -0.5 1.5 -0.5\nv 0.5 1.5 -0.5\nv 0.5 1.5 0.5\nv -0.5 1.5 0.5\n\
         usemtl floor\nf 1 2 3 4\nusemtl lamp\nf 5 6 7 8\n",
    )
    .unwrap();
    obj
}

#[test]
fn the_default_light_goes_under_path_and_comes_back_under_direct() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(&emissive_model(dir.path())).unwrap();
    let with = |integrator| RenderSettings {
        integrator,
        ..scene.default_settings()
    };
    let (to_path, to_direct) = (with(Integrator::Path), with(Integrator::Direct));
    let lights = scene.lights().to_vec();
    assert_eq!(lights.len(), 1, "the model gets the default light");
    assert!(scene.lights_change_with(Integrator::Path));
    assert!(!scene.lights_change_with(Integrator::Direct));

    let path = scene.with_settings(&to_path);
    assert!(path.lights().is_empty(), "path drops the default light");
    assert!(path.lights_change_with(Integrator::Direct));
    assert!(!path.lights_change_with(Integrator::Path));

    let direct = path.with_settings(&to_direct);
    assert_eq!(direct.lights(), &lights[..], "direct gives it back");
    assert!(direct.lights_change_with(Integrator::Path));

    // Lights edited by hand are the scene's own: nothing gives the
    // default one back over them, nor drops them.
    let mut path = direct.with_settings(&to_path);
    path.lights_mut().push(lights[0]);
    assert!(!path.lights_change_with(Integrator::Direct));
    let direct = path.with_settings(&to_direct);
    assert_eq!(direct.lights(), &lights[..]);
    assert!(!direct.lights_change_with(Integrator::Path));
    assert_eq!(direct.with_settings(&to_path).lights(), &lights[..]);
}

/// On the GPU (lavapipe) the default light's change takes the scene to the
/// device again; on the CPU path the renderer shares the new scene.
#[test]
fn p_renders_what_render_integrator_path_renders_and_back() {
    for device in ["gpu", "cpu"] {
        let Some(x) = xvfb() else { return };
        let dir = tempfile::tempdir().unwrap();
        let model = emissive_model(dir.path());
        let size = [
            "--width", "32", "--height", "24", "--spp", "4", "--device", device,
        ];
        let rendered = |integrator: &str| {
            let out = dir.path().join(format!("render-{integrator}.png"));
            let render = [
                "render",
                s(&model),
                "-o",
                s(&out),
                "--integrator",
                integrator,
            ];
            let run = lambert(&[&render[..], &size[..]].concat());
            assert!(run.status.success(), "{}", common::stderr(&run));
            std::fs::read(out).unwrap()
        };
        let (path, direct) = (rendered("path"), rendered("direct"));
        assert_ne!(path, direct);

        let shot = dir.path().join("shot.png");
        let args = [&[s(&model), "--screenshot", s(&shot)][..], &size[..]].concat();
        let viewer = Viewer::start(x, &args);
        for (integrator, expected) in [("path", &path), ("direct", &direct)] {
            viewer.key("p");
            let said = format!("integrator {integrator}");
            wait_for(&viewer.stderr, &said, |l| l == said);
            viewer.converged_screenshot(4);
            assert!(
                std::fs::read(&shot).unwrap() == *expected,
                "{device}: after p the viewer's {integrator} image is not \
                 `render --integrator {integrator}`'s"
            );
        }
        assert!(viewer.quit().success());
    }
}
