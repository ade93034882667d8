//! What the Python package's renders share with the CLI in the library
//! (issue 49): `RenderOverrides` (a render's choices over a scene's own),
//! lights added to a loaded scene, and parts joined in memory
//! (`parts::assemble`) as `lambert merge` joins files.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use lambert::camera::Camera;
use lambert::gpu::AdapterRequest;
use lambert::jobs::{RenderOverrides, render_band};
use lambert::layout::LIGHT_POINT;
use lambert::parts::{Part, Tile, assemble};
use lambert::render::{DeviceChoice, Renderer};
use lambert::scene::Scene;

const BOX: &str = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv 0 1.5 0\n\
                   f 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 1 3 2\nf 1 4 3\n";

fn model(dir: &Path) -> PathBuf {
    let path = dir.join("pyramid.obj");
    std::fs::write(&path, BOX).unwrap();
    path
}

fn name(option: &str) -> String {
    format!("<{option}>")
}

#[test]
fn a_light_given_to_a_model_replaces_its_default_light_and_ambient() {
    let dir = tempfile::tempdir().unwrap();
    let mut scene = Scene::load(&model(dir.path())).unwrap();
    assert_eq!(scene.lights().len(), 1);
    assert!(scene.ambient()[0] > 0.0);
    scene
        .add_point_light("light", [0.0, 4.0, 0.0], [5.0, 4.0, 3.0])
        .unwrap();
    scene
        .add_point_light("light", [1.0, 4.0, 0.0], [1.0; 3])
        .unwrap();
    // Both given lights, the default one gone, no ambient.
    assert_eq!(scene.lights().len(), 2);
    assert_eq!(scene.lights()[0].kind, LIGHT_POINT);
    assert_eq!(scene.lights()[0].color, [5.0, 4.0, 3.0]);
    assert_eq!(scene.ambient(), [0.0; 3]);
    let bad = scene
        .add_directional_light("light", [0.0; 3], [1.0; 3])
        .unwrap_err();
    assert!(bad.to_string().contains("light.direction"), "{bad}");
    let bad = scene
        .add_point_light("light", [0.0, f64::NAN, 0.0], [1.0; 3])
        .unwrap_err();
    assert!(bad.to_string().contains("light.position"), "{bad}");
    let bad = scene
        .add_spot_light("light", [0.0; 3], [0.0, -1.0, 0.0], [1.0; 3], [50.0, 40.0])
        .unwrap_err();
    assert!(bad.to_string().contains("cone angles"), "{bad}");
    assert_eq!(scene.lights().len(), 2);
}

#[test]
fn overrides_apply_a_camera_at_the_view_s_size_and_name_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let mut scene = Scene::load(&model(dir.path())).unwrap();
    let mut settings = scene.default_settings();
    let camera = Camera {
        eye: [0.0, 2.0, 6.0],
        look_at: [0.0, 0.5, 0.0],
        up: [0.0, 1.0, 0.0],
        vfov: 30.0,
        width: 1,
        height: 1,
    };
    let overrides = RenderOverrides {
        camera: Some(camera.clone()),
        width: Some(64),
        spp: Some(3),
        seed: Some(9),
        ambient: Some([0.5; 3]),
        shadows: Some(false),
        ..RenderOverrides::default()
    };
    overrides.apply(&mut scene, &mut settings, &name).unwrap();
    let view = &settings.view;
    assert_eq!((view.camera.eye, view.camera.vfov), (camera.eye, 30.0));
    // The model's 1024 × 768 kept as an aspect ratio at width 64.
    assert_eq!((view.camera.width, view.camera.height), (64, 48));
    assert_eq!((view.spp, view.seed), (3, 9));
    assert_eq!(settings.ambient, [0.5; 3]);
    assert!(!settings.shadows);
    for (overrides, words) in [
        (
            RenderOverrides {
                spp: Some(0),
                ..RenderOverrides::default()
            },
            "<spp = 0",
        ),
        (
            RenderOverrides {
                camera: Some(Camera {
                    look_at: camera.eye,
                    ..camera.clone()
                }),
                ..RenderOverrides::default()
            },
            "<camera>: camera.eye and camera.look_at are the same point",
        ),
        (
            RenderOverrides {
                max_depth: Some(0),
                ..RenderOverrides::default()
            },
            "<max_depth 0",
        ),
    ] {
        let mut settings = scene.default_settings();
        let e = overrides
            .apply(&mut scene, &mut settings, &name)
            .unwrap_err();
        assert!(e.to_string().contains(words), "{e}");
    }
}

#[test]
fn bands_assembled_in_memory_equal_the_whole_render() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(&model(dir.path())).unwrap();
    let mut settings = scene.default_settings();
    RenderOverrides {
        width: Some(40),
        spp: Some(2),
        ..RenderOverrides::default()
    }
    .apply_settings(&scene, &mut settings, &name)
    .unwrap();
    let request = AdapterRequest::default();
    let (mut renderer, _) = Renderer::open(
        Arc::new(scene.clone().with_settings(&settings)),
        DeviceChoice::Cpu,
        &request,
    )
    .unwrap();
    let whole = renderer.render(&settings.view, None).unwrap().0.image;
    let mut parts = Vec::new();
    for index in (0..3).rev() {
        let tile = Tile { index, count: 3 };
        let band = render_band(
            scene.clone(),
            &settings,
            tile,
            DeviceChoice::Cpu,
            &request,
            None,
        )
        .unwrap();
        assert_eq!(band.rows, tile.rows(30).unwrap());
        let name = PathBuf::from(format!("tile {index}"));
        parts.push(Part::new(name, band.image, tile, band.height, band.hash).unwrap());
    }
    let merged = assemble(&parts).unwrap();
    assert_eq!(
        (merged.width, merged.height, merged.rgb),
        (whole.width, whole.height, whole.rgb)
    );
    // Refused as merge refuses files: one missing, or a band of the wrong height.
    let e = assemble(&parts[1..]).unwrap_err();
    assert!(e.to_string().contains("parts missing: 2/3"), "{e}");
    let band = render_band(
        scene,
        &settings,
        Tile { index: 0, count: 3 },
        DeviceChoice::Cpu,
        &request,
        None,
    )
    .unwrap();
    let e = Part::new(
        "short".into(),
        band.image,
        Tile { index: 0, count: 2 },
        30,
        band.hash,
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("not part 0/2"), "{e}");
}
