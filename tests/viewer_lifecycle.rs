//! The viewer's camera range and its lifecycle (issue 44, items 19 and
//! 20): its navigation kept within what a scene file accepts (the
//! functions themselves, and `lambert view` driven under Xvfb), one wheel
//! click one notch, a failed screenshot survived, a window destroyed or
//! quit ending it promptly, `r` without a reparse, `l` without a second
//! scene, and `render.spp` honoured.

mod common;
#[path = "common/viewer.rs"]
mod viewer;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use common::{lambert, s};
use glam::DVec3;
use lambert::camera::Camera;
use lambert::camera::navigate::{self, Reach};
use lambert::scene::Scene;
use viewer::{PATIENCE, Viewer, vector, wait_for, xvfb};

/// A scene of one sphere at `centre` (radius 1) seen from `camera`, with
/// a light and `extra` lines: what a `[camera]` table pasted in makes.
fn sphere_scene(centre: DVec3, camera: &str, extra: &str) -> String {
    let [x, y, z] = centre.to_array();
    format!(
        "{camera}\n{extra}\n[[sphere]]\ncenter = [{x:?}, {y:?}, {z:?}]\nradius = 1.0\n\n\
         [[point_light]]\nposition = [{:?}, {:?}, {:?}]\nintensity = [50.0, 50.0, 50.0]\n",
        x + 3.0,
        y + 4.0,
        z + 5.0
    )
}

/// `camera` as the viewer prints it, pasted into the sphere's scene: the
/// scene as loaded, or why it is refused.
fn pasted(centre: DVec3, camera: &Camera) -> Result<Scene, String> {
    let text = sphere_scene(centre, &navigate::camera_toml(camera), "");
    Scene::from_toml(&text, Path::new("pasted.toml")).map_err(|e| e.to_string())
}

fn distance(camera: &Camera) -> f64 {
    (DVec3::from(camera.eye) - DVec3::from(camera.look_at)).length()
}

/// Each camera of a walk is finite and accepted by the scene format.
fn check(centre: DVec3, camera: &Camera, what: &str) {
    let finite = camera
        .eye
        .iter()
        .chain(&camera.look_at)
        .all(|c| c.is_finite());
    assert!(finite, "{what}: {camera:?}");
    assert!(distance(camera) > 0.0, "{what}: the eye is on look_at");
    if let Err(e) = pasted(centre, camera) {
        panic!("{what}: the camera printed is refused: {e}");
    }
}

/// Near the origin, and far from it (a scene offset of 3e14).
const CENTRES: [DVec3; 2] = [DVec3::ZERO, DVec3::new(3e14, -2e14, 1e14)];

fn start(centre: DVec3) -> (Camera, Reach) {
    let camera = format!(
        "[camera]\neye = [{:?}, {:?}, {:?}]\nlook_at = [{:?}, {:?}, {:?}]\nvfov = 40.0\nwidth = 160\nheight = 120",
        centre.x,
        centre.y,
        centre.z + 5.0,
        centre.x,
        centre.y,
        centre.z
    );
    let scene = Scene::from_toml(&sphere_scene(centre, &camera, ""), Path::new("s.toml")).unwrap();
    (scene.view().camera.clone(), scene.reach())
}

#[test]
fn hundreds_of_notches_each_way_keep_the_camera_in_the_scene_formats_range() {
    for centre in CENTRES {
        let (file, reach) = start(centre);
        let mut camera = file.clone();
        for notch in 0..600 {
            camera = navigate::dolly(&camera, 1.0, &reach);
            check(centre, &camera, &format!("notch {notch} in"));
        }
        // The least distance is a fraction of the scene's size (2 across),
        // well clear of f64's spacing at look_at, and a notch back moves
        // the eye again.
        let nearest = distance(&camera);
        assert!(nearest >= 1e-6, "{nearest}");
        // Near the origin, a millionth of the scene's size (its box's
        // diagonal, 2√3) it is.
        if centre == DVec3::ZERO {
            assert!((nearest - 2e-6 * 3f64.sqrt()).abs() < 1e-12, "{nearest}");
        }
        let back = navigate::dolly(&camera, -1.0, &reach);
        assert!(
            (distance(&back) / nearest - 1.0 / 0.9).abs() < 1e-3,
            "a notch back from {nearest} moved the eye to {}",
            distance(&back)
        );
        for notch in 0..600 {
            camera = navigate::dolly(&camera, -1.0, &reach);
            check(centre, &camera, &format!("notch {notch} out"));
        }
        let farthest = distance(&camera);
        assert!(farthest > 1e8, "{farthest}");
        let closer = navigate::dolly(&camera, 1.0, &reach);
        assert!(
            distance(&closer) < farthest,
            "a notch in did not move the eye"
        );
        // Wild counts at once (an overflowing wheel) stay in range too.
        for notches in [1e6, -1e6, 1e300, -1e300, f64::INFINITY, f64::NEG_INFINITY] {
            check(
                centre,
                &navigate::dolly(&file, notches, &reach),
                &format!("{notches} notches"),
            );
        }
        let unchanged = navigate::dolly(&file, f64::NAN, &reach);
        assert_eq!(unchanged.eye, file.eye, "NaN notches moved the eye");
    }
}

#[test]
fn flying_panning_and_orbiting_far_out_stay_in_range() {
    for centre in CENTRES {
        let (mut camera, reach) = start(centre);
        for _ in 0..400 {
            camera = navigate::dolly(&camera, -1.0, &reach);
        }
        for key in ['w', 's', 'a', 'd', 'e', 'q'] {
            for step in 0..300 {
                camera = navigate::fly(&camera, key, &reach).unwrap();
                check(centre, &camera, &format!("{key} step {step}"));
            }
        }
        for step in 0..200 {
            camera = navigate::pan(&camera, 5000.0, -3000.0, 120, &reach);
            check(centre, &camera, &format!("pan {step}"));
            camera = navigate::orbit(&camera, 17.0, 9.0, 120, &reach);
            check(centre, &camera, &format!("orbit {step}"));
        }
        // Close in, flying keeps the least distance.
        for _ in 0..400 {
            camera = navigate::dolly(&camera, 1.0, &reach);
        }
        for step in 0..300 {
            camera = navigate::fly(&camera, 'w', &reach).unwrap();
            check(centre, &camera, &format!("close, w step {step}"));
        }
    }
}

/// A sphere scene file in `dir` with a 160×120 camera 5 from it, and
/// `extra` lines (a `[render]` table).
fn sphere_file(dir: &Path, extra: &str, eye_z: f64) -> PathBuf {
    let camera = format!(
        "[camera]\neye = [0.0, 0.0, {eye_z:?}]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 160\nheight = 120"
    );
    let path = dir.join("sphere.toml");
    std::fs::write(&path, sphere_scene(DVec3::ZERO, &camera, extra)).unwrap();
    path
}

fn camera_distance(camera: &toml::Table) -> f64 {
    (vector(camera, "eye") - vector(camera, "look_at")).length()
}

#[test]
fn one_wheel_click_is_one_notch_and_hundreds_keep_a_camera_render_accepts() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = sphere_file(dir.path(), "", 5.0);
    let args = [s(&scene), "--spp", "1", "--device", "cpu"];
    let viewer = Viewer::start(x, &args);
    let file = viewer.camera();
    viewer.xdotool(&["click", "4"]);
    let closer = viewer.camera();
    let ratio = camera_distance(&closer) / camera_distance(&file);
    assert!(
        (ratio - 0.9).abs() < 1e-12,
        "one click moved the eye by {ratio}, not 0.9"
    );
    viewer.xdotool(&["click", "--repeat", "3", "--delay", "20", "5"]);
    let back = viewer.camera();
    let ratio = camera_distance(&back) / camera_distance(&closer);
    assert!(
        (ratio - 0.9f64.powi(-3)).abs() < 1e-9,
        "three clicks back: {ratio}"
    );

    viewer.xdotool(&["click", "--repeat", "400", "--delay", "1", "4"]);
    let nearest = camera_distance(&viewer.camera());
    assert!(nearest > 0.0 && nearest.is_finite(), "{nearest}");
    viewer.xdotool(&["click", "--repeat", "300", "--delay", "1", "5"]);
    let far = viewer.camera();
    assert!(camera_distance(&far) > 1e6, "{far:?}");
    // What `c` printed renders.
    let mut table: toml::Table = std::fs::read_to_string(&scene).unwrap().parse().unwrap();
    table.insert("camera".into(), toml::Value::Table(far));
    let pasted = dir.path().join("pasted.toml");
    std::fs::write(&pasted, toml::to_string(&table).unwrap()).unwrap();
    let image = dir.path().join("far.png");
    let render = lambert(&["render", s(&pasted), "-o", s(&image), "--device", "cpu"]);
    assert!(render.status.success(), "{}", common::stderr(&render));
    assert!(viewer.quit().success());
}

/// The window's title.
fn title(viewer: &Viewer) -> String {
    viewer
        .xdotool(&["getwindowname", &viewer.window])
        .trim()
        .to_string()
}

/// Waits until the title satisfies `wanted`.
fn wait_for_title(viewer: &Viewer, what: &str, wanted: impl Fn(&str) -> bool) -> String {
    let deadline = Instant::now() + PATIENCE;
    loop {
        let title = title(viewer);
        if wanted(&title) {
            return title;
        }
        assert!(Instant::now() < deadline, "no {what} in the title: {title}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Waits (PATIENCE at most) for the viewer to exit: its status.
fn exit_of(viewer: &mut Viewer, what: &str) -> std::process::ExitStatus {
    viewer.exit_status(&format!("{what} did not end the viewer"))
}

#[test]
fn a_screenshot_that_cannot_be_written_is_reported_and_the_viewer_goes_on() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("shots");
    std::fs::create_dir(&folder).unwrap();
    let shot = folder.join("shot.png");
    let scene = sphere_file(dir.path(), "", 5.0);
    let args = [
        s(&scene),
        "--spp",
        "2",
        "--device",
        "cpu",
        "--screenshot",
        s(&shot),
    ];
    let mut viewer = Viewer::start(x, &args);
    wait_for_title(&viewer, "a frame", |t| t.contains(" spp"));
    std::fs::remove_dir(&folder).unwrap();
    viewer.key("s");
    let line = wait_for(&viewer.stderr, "the screenshot's error", |l| {
        l.starts_with("error:")
    });
    assert!(line.contains("screenshot not written"), "{line}");
    let title = wait_for_title(&viewer, "the error", |t| {
        t.contains("screenshot not written")
    });
    assert!(title.contains("lambert view"), "{title}");
    std::thread::sleep(Duration::from_millis(300));
    assert!(
        viewer.process.0.try_wait().unwrap().is_none(),
        "the viewer ended on a screenshot it could not write"
    );
    // Room again: the next `s` writes, and the title's error goes.
    std::fs::create_dir(&folder).unwrap();
    viewer.key("s");
    wait_for(&viewer.stderr, "the screenshot", |l| {
        l.starts_with("wrote ")
    });
    assert!(shot.exists());
    wait_for_title(&viewer, "no error", |t| !t.contains("error"));
    assert!(viewer.quit().success());
}

#[test]
fn a_window_destroyed_by_the_window_manager_ends_the_viewer() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = sphere_file(dir.path(), "", 5.0);
    let mut viewer = Viewer::start(x, &[s(&scene), "--spp", "1", "--device", "cpu"]);
    wait_for_title(&viewer, "a frame", |t| t.contains(" spp"));
    let window = viewer.window.clone();
    // XDestroyWindow from another client: no close request comes first.
    viewer.xdotool(&["windowclose", &window]);
    let status = exit_of(&mut viewer, "the window destroyed");
    assert!(status.success(), "{status}");
}

#[test]
fn escape_cancels_the_frame_in_flight() {
    // Frames long enough to catch in flight, on the CPU path and lavapipe.
    for (device, side) in [("cpu", "3000"), ("gpu", "600")] {
        let Some(x) = xvfb() else { return };
        let dir = tempfile::tempdir().unwrap();
        let scene = sphere_file(dir.path(), "", 5.0);
        let size = ["--width", side, "--height", side];
        let args = [&[s(&scene), "--device", device, "--spp", "64"][..], &size].concat();
        let mut viewer = Viewer::start(x, &args);
        // The second frame's time: the first's includes building pipelines.
        let second = wait_for_title(&viewer, "the second frame", |t| t.contains("2/64 spp"));
        let frame_ms: f64 = second
            .split(" ms/frame")
            .next()
            .and_then(|t| t.rsplit(" — ").next())
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("no frame time in {second}"));
        // The third frame is under way.
        let pressed = Instant::now();
        viewer.key("Escape");
        let status = exit_of(&mut viewer, "Escape");
        let took = pressed.elapsed().as_secs_f64() * 1e3;
        assert!(status.success(), "{device}: {status}");
        assert!(
            took < 0.5 * frame_ms + 300.0,
            "{device}: Escape took {took:.0} ms to end the viewer, a frame {frame_ms:.0} ms"
        );
    }
}

#[test]
fn r_returns_to_the_camera_loaded_without_reading_the_file_again() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = sphere_file(dir.path(), "", 5.0);
    let viewer = Viewer::start(x, &[s(&scene), "--spp", "1", "--device", "cpu"]);
    let loaded = viewer.camera();
    viewer.xdotool(&["click", "4"]);
    // The file changes under the viewer: `r` is still the camera loaded.
    sphere_file(dir.path(), "", 9.0);
    viewer.key("r");
    assert_eq!(viewer.camera(), loaded);
    assert!(viewer.quit().success());
}

/// The process's memory, bytes: resident now (VmRSS) and at its peak
/// (VmHWM).
fn memory(viewer: &Viewer) -> [u64; 2] {
    let status =
        std::fs::read_to_string(format!("/proc/{}/status", viewer.process.0.id())).unwrap();
    ["VmRSS:", "VmHWM:"].map(|key| {
        let line = status.lines().find(|l| l.starts_with(key)).unwrap();
        let kib: u64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
        kib * 1024
    })
}

/// A binary STL of `n` small triangles in a row.
fn stl(path: &Path, n: u32) {
    let mut bytes = vec![0u8; 80];
    bytes.extend(n.to_le_bytes());
    for i in 0..n {
        let x = i as f32 * 1e-3;
        let corners = [[x, 0.0, 0.0], [x + 1e-3, 0.0, 0.0], [x, 1.0, 0.0]];
        let floats = [0.0f32, 0.0, 1.0]
            .into_iter()
            .chain(corners.into_iter().flatten());
        bytes.extend(floats.flat_map(f32::to_le_bytes));
        bytes.extend([0, 0]);
    }
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn l_toggles_shadows_without_a_second_copy_of_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("strip.stl");
    let triangles = 400_000u32;
    stl(&model, triangles);
    // The triangles alone, of a copy of the scene (its BVH comes on top).
    let copy = triangles as u64 * std::mem::size_of::<lambert::layout::Triangle>() as u64;
    // On lavapipe the device's copy is host memory too: the peak shows
    // two scenes held at once.
    for device in ["cpu", "gpu"] {
        let Some(x) = xvfb() else { return };
        let size = ["--width", "160", "--height", "120", "--spp", "1"];
        let args = [&[s(&model), "--device", device][..], &size].concat();
        let viewer = Viewer::start(x, &args);
        wait_for_title(&viewer, "the frame", |t| t.contains("1/1 spp, done"));
        let before = memory(&viewer);
        viewer.key("l");
        wait_for(&viewer.stderr, "the shadows line", |l| l == "shadows off");
        wait_for_title(&viewer, "the frame", |t| t.contains("1/1 spp, done"));
        let after = memory(&viewer);
        for (i, what) in ["resident", "peak"].into_iter().enumerate() {
            assert!(
                after[i] < before[i] + copy / 2,
                "{device}, shadows off: {} MiB {what}, from {} MiB (a copy of the triangles is {} MiB)",
                after[i] >> 20,
                before[i] >> 20,
                copy >> 20
            );
        }
        assert!(viewer.quit().success());
    }
}

#[test]
fn the_viewer_refines_to_the_scenes_render_spp_as_its_help_says() {
    let help = lambert(&["view", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout).into_owned();
    assert!(
        help.contains("[default: the scene's render.spp, else 1024]"),
        "{help}"
    );
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = sphere_file(dir.path(), "[render]\nspp = 3", 5.0);
    let viewer = Viewer::start(x, &[s(&scene), "--device", "cpu"]);
    wait_for_title(&viewer, "3 spp, done", |t| t.contains("— 3/3 spp, done"));
    assert!(viewer.quit().success());
}

#[test]
fn a_cancelled_batch_adds_nothing_and_the_next_starts_from_the_first_sample() {
    use lambert::render::{Progressive, Renderer};
    use std::sync::Arc;
    use std::sync::atomic::AtomicBool;
    let mut scene = common::load("cornell");
    scene.view_mut().camera.width = 300;
    scene.view_mut().camera.height = 200;
    scene.view_mut().spp = 4;
    let view = scene.view().clone();
    let scene = Arc::new(scene);
    let gpu = lambert::gpu::GpuRenderer::new(common::open_gpu(), &scene).unwrap();
    for mut renderer in [
        Renderer::Cpu(Arc::clone(&scene)),
        Renderer::Gpu(Box::new(gpu)),
    ] {
        let mut progressive = Progressive::new(view.clone());
        renderer.add_samples(&mut progressive, 1).unwrap();
        let cancelled = AtomicBool::new(true);
        let added = renderer
            .add_samples_or_cancel(&mut progressive, 2, &cancelled)
            .unwrap();
        assert!(
            !added,
            "{}: a cancelled batch says it added",
            renderer.describe()
        );
        assert_eq!(progressive.samples(), 0, "{}", renderer.describe());
        // Started again, its batches make the render's image.
        for count in [1, 3] {
            assert!(
                renderer
                    .add_samples_or_cancel(&mut progressive, count, &AtomicBool::new(false))
                    .unwrap()
            );
        }
        let (rendered, _) = renderer.render(&view, None).unwrap();
        assert_eq!(
            progressive.image().rgb,
            rendered.image.rgb,
            "{}",
            renderer.describe()
        );
    }
}
