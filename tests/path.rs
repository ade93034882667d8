//! The path integrator (`--integrator path`): the same exposure as the
//! direct integrator where nothing reflects between surfaces, the GPU
//! against its CPU twin on the same random numbers, and its settings.

mod common;

use common::paths::*;
use common::*;
use lambert::Scene;
use lambert::output::Rendered;
use lambert::scene::Integrator;

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

/// One sphere lit by one point light, no ambient.
fn one_light() -> String {
    camera_on_z(8.0, 40.0, 48, 32) + ONE_LIGHT
}

/// `one_light()` and a directional light.
fn convex() -> String {
    one_light() + DIRECTIONAL
}

const DIRECTIONAL: &str = r#"
[[directional_light]]
direction = [1.0, 0.5, 1.0]
irradiance = [0.6, 0.6, 0.5]
"#;

#[test]
fn path_tracing_changes_the_light_transport_not_the_exposure() {
    // One convex body: every bounce leaves the scene and brings back
    // nothing (no environment), so path tracing sees what the direct
    // integrator sees. Lit by one point light (picked with probability 1,
    // emitting π times its colour into albedo/π), the same image.
    let one_light = scene(&one_light());
    let direct = render_cpu(&one_light);
    for max_depth in [1, 4] {
        let path = render_cpu(&path_traced(&one_light, 1, max_depth));
        let worst = worst_relative(&direct, &path, 1e-3);
        assert!(
            worst < 1e-4,
            "max_depth {max_depth}: path differs from direct by {worst} (relative)"
        );
        assert_eq!(direct.prims, path.prims, "the same camera rays and hits");
    }
    // The background is what a camera ray that misses shows, as under
    // direct.
    assert_eq!(direct.image.rgb[0], [0.1, 0.2, 0.3]);

    // Two lights: one drawn by power at each vertex, so the same image on
    // average (the direct integrator's is exact at any spp).
    let two_lights = scene(&convex());
    let spp = 256;
    let mean = |r: &Rendered| r.image.rgb.iter().flatten().map(|&v| v as f64).sum::<f64>();
    let direct = mean(&render_cpu(&two_lights));
    let path = mean(&render_cpu(&path_traced(&two_lights, spp, 4)));
    assert!(
        (path - direct).abs() <= 0.01 * direct,
        "two lights: path's image sum {path}, direct's {direct}"
    );
}

#[test]
fn gpu_path_tracing_agrees_with_its_twin() {
    // The Cornell room lit by its point lights: light bounces between its
    // walls.
    let room = small("cornell", 64);
    let (_, c) = assert_agrees_with_twin(&path_traced(&room, 4, 6));
    // Bounced light is there: brighter than direct light (and ambient)
    // alone.
    let direct = render_cpu(&room);
    let direct_sum = direct
        .image
        .rgb
        .iter()
        .flatten()
        .map(|&v| v as f64)
        .sum::<f64>();
    assert!(c > direct_sum, "no light bounced: {c} against {direct_sum}");
    // The box lit by its ceiling light alone: area light sampling, MIS.
    assert_agrees_with_twin(&small("cornell_area", 48));
}

#[test]
fn the_integrator_and_depth_come_from_the_scene_file() {
    let text = convex().replace("[render]", "[render]\nintegrator = \"path\"\nmax_depth = 3");
    let settings = scene(&text).default_settings();
    assert_eq!(settings.integrator, Integrator::Path);
    assert_eq!(settings.max_depth, 3);
    let defaults = scene(&convex()).default_settings();
    assert_eq!(defaults.integrator, Integrator::Direct);
    assert_eq!(defaults.max_depth, lambert::scene::DEFAULT_MAX_DEPTH);
    for (bad, what) in [
        ("max_depth = 0", "max_depth 0"),
        ("max_depth = 65", "max_depth 65"),
        ("integrator = \"bidir\"", "bidir"),
    ] {
        let text = convex().replace("[render]", &format!("[render]\n{bad}"));
        let error = Scene::from_toml(&text, &asset("scenes/inline.toml"))
            .expect_err(bad)
            .to_string();
        assert!(error.contains(what), "{bad}: {error}");
    }
}

#[test]
fn a_model_lit_by_its_own_emission_loses_the_default_light_under_path() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    write(
        "lamp.mtl",
        "newmtl glow\nKd 0 0 0\nKe 4 4 4\nnewmtl wall\nKd 0.8 0.8 0.8\n",
    );
    write(
        "lamp.obj",
        "mtllib lamp.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\n\
         usemtl wall\nf 1 2 3 4\nusemtl glow\nf 1 5 6 2\n",
    );
    let model = Scene::load(&dir.path().join("lamp.obj")).unwrap();
    // Under direct, the model is lit as any model with no light of its
    // own: the default light and ambient.
    assert_eq!(model.lights().len(), 1);
    let direct = model.clone().with_settings(&model.default_settings());
    assert_eq!(direct.lights().len(), 1);
    // Under path, its emissive face is its light.
    let path = path_traced(&model, 1, 4);
    assert!(path.lights().is_empty(), "the default light stayed");
    // A model with no light of its own keeps the default one.
    write("plain.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
    let plain = Scene::load(&dir.path().join("plain.obj")).unwrap();
    assert_eq!(path_traced(&plain, 1, 4).lights().len(), 1);
}
