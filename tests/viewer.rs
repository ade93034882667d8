//! `lambert view` as a person uses it: under Xvfb (an X server with no
//! screen) with lavapipe, driven by real X input events (xdotool's XTEST
//! drags, keys and wheel), its window read back from the X server (xwd).
//! The test command installs xvfb, xdotool and x11-apps (scripts/test);
//! without them these tests fail on CI (CI set) and say they were skipped
//! elsewhere.

mod common;
#[path = "common/viewer.rs"]
mod viewer;

use std::path::Path;
use std::time::{Duration, Instant};

use common::{asset, lambert, lambert_command, s};
use glam::{DQuat, DVec3};
use viewer::{PATIENCE, Viewer, cornell, cornell_with_camera, png, vector, wait_for, xvfb};

#[test]
fn frames_then_screenshot_is_render_spp_n_bit_for_bit() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let size = ["--width", "64", "--height", "48"];
    for device in ["gpu", "cpu"] {
        let shot = dir.path().join(format!("view-{device}.png"));
        let rendered = dir.path().join(format!("render-{device}.png"));
        let viewer = lambert_command()
            .args([
                "view",
                s(&cornell()),
                "--frames",
                "5",
                "--screenshot",
                s(&shot),
            ])
            .args(size)
            .args(["--device", device])
            .env("DISPLAY", &x.display)
            .output()
            .unwrap();
        assert!(viewer.status.success(), "{}", common::stderr(&viewer));
        let render = lambert(&[
            "render",
            s(&cornell()),
            "--spp",
            "5",
            "-o",
            s(&rendered),
            "--device",
            device,
            "--width",
            "64",
            "--height",
            "48",
        ]);
        assert!(render.status.success(), "{}", common::stderr(&render));
        assert_eq!(
            std::fs::read(&shot).unwrap(),
            std::fs::read(&rendered).unwrap(),
            "{device}: view --frames 5 differs from render --spp 5"
        );
    }
}

/// `lambert view` of `scene` at `width`×`height`, `spp` and `device`.
fn view_args<'a>(
    scene: &'a Path,
    width: &'a str,
    height: &'a str,
    spp: &'a str,
    device: &'a str,
) -> Vec<&'a str> {
    vec![
        s(scene),
        "--width",
        width,
        "--height",
        height,
        "--spp",
        spp,
        "--device",
        device,
    ]
}

#[test]
fn a_drag_orbits_and_the_camera_printed_renders_what_the_window_shows() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let (width, height, spp) = (120, 90, 2);
    let cornell = cornell();
    let args = [
        view_args(&cornell, "120", "90", "2", "gpu"),
        vec!["--screenshot", s(&shot)],
    ];
    let viewer = Viewer::start(x, &args.concat());
    let before = viewer.camera();
    // 30 pixels to the right: a third of the height, a sixth of a turn.
    viewer.drag("1", (40, 45), (30, 0));
    let after = viewer.camera();
    for key in ["look_at", "up", "vfov", "width", "height"] {
        assert_eq!(before[key], after[key], "{key} moved in an orbit");
    }
    let (look_at, up) = (vector(&before, "look_at"), vector(&before, "up"));
    let angle = -30.0 * std::f64::consts::PI / height as f64;
    let expected = look_at + DQuat::from_axis_angle(up, angle) * (vector(&before, "eye") - look_at);
    let eye = vector(&after, "eye");
    assert!(
        (eye - expected).length() < 1e-9 * expected.length(),
        "after a 30-pixel drag the eye is at {eye}, expected {expected} (orbited by {angle} rad)"
    );

    // What the window settles on is what `render` makes of that camera.
    viewer.converged_screenshot(spp);
    let on_screen = viewer.screen();
    let rendered = dir.path().join("rendered.png");
    let scene = cornell_with_camera(dir.path(), &after);
    let render = lambert(&[
        "render",
        s(&scene),
        "--spp",
        "2",
        "-o",
        s(&rendered),
        "--device",
        "gpu",
    ]);
    assert_eq!((png(&rendered).0, png(&rendered).1), (width, height));
    assert_shows(
        viewer,
        on_screen,
        &shot,
        render,
        &rendered,
        "of the camera C printed",
    );
}

#[test]
fn keys_and_wheel_move_the_camera_as_listed() {
    let Some(x) = xvfb() else { return };
    let cornell = cornell();
    let viewer = Viewer::start(x, &view_args(&cornell, "80", "60", "1", "cpu"));
    let file = viewer.camera();
    let distance = |c: &toml::Table| (vector(c, "eye") - vector(c, "look_at")).length();
    // A notch of the wheel towards the scene: 10% closer. (winit 0.30 on
    // X11 reports a wheel button's press and its release alike, so
    // xdotool's click, which is both, moves one or two notches.)
    viewer.xdotool(&["click", "4"]);
    let closer = viewer.camera();
    let notches = (distance(&closer) / distance(&file)).ln() / 0.9f64.ln();
    assert!(
        [1.0, 2.0].iter().any(|n| (notches - n).abs() < 1e-9),
        "the wheel moved the eye {notches} notches: {closer:?}"
    );
    // W flies forward 5% of the distance, look_at along.
    viewer.key("w");
    let flown = viewer.camera();
    let step = vector(&flown, "look_at") - vector(&closer, "look_at");
    assert!(
        (step.length() - 0.05 * distance(&closer)).abs() < 1e-9,
        "{flown:?}"
    );
    // R: back to the file's camera.
    viewer.key("r");
    assert_eq!(viewer.camera(), file);
    // L: shadows off, said on stderr.
    viewer.key("l");
    wait_for(&viewer.stderr, "shadows line", |l| l == "shadows off");
    // A resized window renders at its new size.
    let window = viewer.window.clone();
    viewer.xdotool(&["windowsize", &window, "100", "70"]);
    let deadline = Instant::now() + PATIENCE;
    while viewer.camera()["width"].as_integer() != Some(100) {
        assert!(
            Instant::now() < deadline,
            "the resize did not reach the view"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    assert_eq!(viewer.camera()["height"].as_integer(), Some(70));
    // H lists the keys on stdout.
    viewer.key("h");
    wait_for(&viewer.stdout, "key list", |l| {
        l.contains("orbit about the look-at point")
    });
    // q quits where no mouse button is held (with one, it flies down).
    assert!(viewer.quit_with("q").success());
}

#[test]
fn with_no_gpu_adapter_the_cpu_path_renders_and_the_cpu_shows_it() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    // No Vulkan driver: no adapter, and no surface for the window.
    let no_gpu = [("VK_ICD_FILENAMES", "/nonexistent/icd.json")];
    let scene = cornell();
    let args = [s(&scene), "--width", "72", "--height", "40", "--spp", "3"];
    let viewer = Viewer::start_with(
        x,
        &[&args[..], &["--screenshot", s(&shot)]].concat(),
        &no_gpu,
    );
    wait_for(&viewer.stderr, "the CPU path's note", |l| {
        l.starts_with("rendering on the CPU path") && l.contains("shown by the CPU")
    });
    viewer.converged_screenshot(3);
    let on_screen = viewer.screen();
    let rendered = dir.path().join("rendered.png");
    let render_args: Vec<&str> = ["render"].into_iter().chain(args).collect();
    let render = lambert(&[&render_args[..], &["-o", s(&rendered), "--device", "cpu"]].concat());
    assert_shows(viewer, on_screen, &shot, render, &rendered, "--spp 3");
}

/// The screenshot Shift+S saved and the window's pixels are those of
/// `lambert render` (its run and its image, `what` it rendered); Escape
/// then ends the viewer well.
fn assert_shows(
    viewer: Viewer,
    on_screen: (u32, u32, Vec<u8>),
    shot: &Path,
    render: std::process::Output,
    rendered: &Path,
    what: &str,
) {
    assert!(render.status.success(), "{}", common::stderr(&render));
    let rendered = png(rendered);
    assert!(
        png(shot) == rendered,
        "Shift+S's screenshot differs from render {what}"
    );
    assert!(
        on_screen == rendered,
        "the window shows other pixels than render {what}"
    );
    assert!(viewer.quit().success());
}

#[test]
fn f_frames_the_model_and_number_keys_choose_its_gltf_cameras() {
    let Some(x) = xvfb() else { return };
    let model = asset("scenes/meshes/boxes.glb");
    let args = [
        s(&model),
        "--width",
        "64",
        "--height",
        "48",
        "--spp",
        "1",
        "--device",
        "cpu",
    ];
    let viewer = Viewer::start(x, &args);
    let file = viewer.camera();
    viewer.key("f");
    let framed = viewer.camera();
    assert_ne!(framed["eye"], file["eye"], "f did not move the camera");
    assert_eq!(framed["vfov"].as_float(), Some(40.0));
    // 1: the file's first camera (its eye at (0, 2.5, 7)), at the window's size.
    viewer.key("1");
    let first = viewer.camera();
    assert_eq!(vector(&first, "eye"), DVec3::new(0.0, 2.5, 7.0));
    assert_eq!(first, file);
    viewer.key("9");
    wait_for(&viewer.stderr, "no camera 9", |l| {
        l.contains("there is no camera 9")
    });
    assert!(viewer.quit().success());
}

#[test]
fn with_no_display_it_says_so_in_one_line_and_fails() {
    let output = lambert_command()
        .args(["view", s(&cornell())])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = common::stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("no display") && stderr.contains("DISPLAY is not set"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}
