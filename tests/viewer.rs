//! `lambert view` as a person uses it: under Xvfb (an X server with no
//! screen) with lavapipe, driven by real X input events (xdotool's XTEST
//! drags, keys and wheel), its window read back from the X server (xwd).
//! The test command installs xvfb, xdotool and x11-apps (scripts/test);
//! without them these tests fail on CI (CI set) and say they were skipped
//! elsewhere.

mod common;

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

use common::{asset, lambert, lambert_command, s};
use glam::{DQuat, DVec3};

/// Long enough for a loaded machine building in parallel.
const PATIENCE: Duration = Duration::from_secs(60);

/// A child process killed when the test ends, however it ends.
struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// One X server at a time: a server ending unlinks its socket after its
/// lock, so one started meanwhile on the freed number lost its socket.
static ONE_SERVER: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// An X server of its own for one test: its display, e.g. ":7". (Fields
/// drop in order: the server ends before the next may start.)
struct Xvfb {
    display: String,
    server: Child,
    _turn: std::sync::MutexGuard<'static, ()>,
}

impl Drop for Xvfb {
    /// SIGTERM, so that the server removes its socket and lock.
    fn drop(&mut self) {
        let _ = Command::new("kill")
            .arg(self.server.id().to_string())
            .status();
        let _ = self.server.wait();
    }
}

/// The tools these tests need, or None (skipped) where they are missing
/// and CI is not set; on CI their absence fails the test.
fn xvfb() -> Option<Xvfb> {
    let missing: Vec<&str> = ["Xvfb", "xdotool", "xwd"]
        .into_iter()
        .filter(|tool| {
            Command::new("sh")
                .args(["-c", &format!("command -v {tool}")])
                .output()
                .is_ok_and(|o| !o.status.success())
        })
        .collect();
    if !missing.is_empty() {
        let message = format!(
            "the viewer's tests need {} (apt-get install xvfb xdotool x11-apps; scripts/test installs them)",
            missing.join(", ")
        );
        if std::env::var_os("CI").is_some() {
            panic!("{message}");
        }
        eprintln!("skipped: {message}");
        return None;
    }
    let turn = ONE_SERVER.lock().unwrap_or_else(|e| e.into_inner());
    // -displayfd: the server picks a free display and writes its number.
    let mut server = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "640x480x24",
            "-nolisten",
            "tcp",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("Xvfb starts");
    let mut line = String::new();
    BufReader::new(server.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let number: u32 = line.trim().parse().expect("Xvfb names its display");
    let x = Xvfb {
        display: format!(":{number}"),
        server,
        _turn: turn,
    };
    // Until a client gets through (other suites may start servers too).
    let deadline = Instant::now() + PATIENCE;
    while !Command::new("xdotool")
        .arg("getmouselocation")
        .env("DISPLAY", &x.display)
        .output()
        .is_ok_and(|o| o.status.success())
    {
        assert!(
            Instant::now() < deadline,
            "Xvfb {} takes no client",
            x.display
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    Some(x)
}

/// Lines a pipe gives, as they come.
fn lines(pipe: impl Read + Send + 'static) -> Receiver<String> {
    let (sender, receiver) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(pipe).lines().map_while(Result::ok) {
            if sender.send(line).is_err() {
                return;
            }
        }
    });
    receiver
}

/// The first line from `lines` that `wanted` accepts (failing after
/// PATIENCE), and the lines before it.
fn wait_for(lines: &Receiver<String>, what: &str, wanted: impl Fn(&str) -> bool) -> String {
    let deadline = Instant::now() + PATIENCE;
    let mut seen = Vec::new();
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        match lines.recv_timeout(left) {
            Ok(line) if wanted(&line) => return line,
            Ok(line) => seen.push(line),
            Err(_) => panic!("no {what} within {PATIENCE:?}; lines seen: {seen:?}"),
        }
    }
}

/// xdotool's output on `x`.
fn xdotool(x: &Xvfb, args: &[&str]) -> String {
    let output = Command::new("xdotool")
        .args(args)
        .env("DISPLAY", &x.display)
        .output()
        .expect("xdotool runs");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A running `lambert view` and its X server.
struct Viewer {
    x: Xvfb,
    process: Killed,
    stdout: Receiver<String>,
    stderr: Receiver<String>,
    window: String,
}

impl Viewer {
    fn start(x: Xvfb, args: &[&str]) -> Viewer {
        Viewer::start_with(x, args, &[])
    }

    /// `start`, with environment variables set. A first connection to a
    /// fresh Xvfb is now and then refused on this machine (shared with
    /// other suites' servers) though xdotool's got through: a viewer that
    /// says it cannot open a window is started again, twice at most.
    fn start_with(x: Xvfb, args: &[&str], env: &[(&str, &str)]) -> Viewer {
        let spawn = || {
            let mut child = lambert_command()
                .arg("view")
                .args(args)
                .envs(env.iter().copied())
                .env("DISPLAY", &x.display)
                .env_remove("WAYLAND_DISPLAY")
                .stdin(Stdio::null())
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("lambert view starts");
            let stdout = lines(child.stdout.take().unwrap());
            let stderr = lines(child.stderr.take().unwrap());
            (Killed(child), stdout, stderr)
        };
        let mut attempt = 1;
        let (window, (process, stdout, stderr)) = 'started: loop {
            let (mut process, stdout, stderr) = spawn();
            let deadline = Instant::now() + PATIENCE;
            loop {
                let found = xdotool(&x, &["search", "--name", "^lambert view"]);
                if let Some(id) = found.lines().next() {
                    break 'started (id.to_string(), (process, stdout, stderr));
                }
                if let Some(status) = process.0.try_wait().unwrap() {
                    let errors: Vec<String> = stderr.try_iter().collect();
                    let refused = errors.iter().any(|e| e.contains("cannot open a window"));
                    assert!(
                        refused && attempt < 3,
                        "lambert view exited ({status}) before its window showed: {errors:?}"
                    );
                    eprintln!("attempt {attempt}: {errors:?}; again");
                    attempt += 1;
                    break;
                }
                assert!(Instant::now() < deadline, "no window within {PATIENCE:?}");
                std::thread::sleep(Duration::from_millis(100));
            }
        };
        let viewer = Viewer {
            x,
            process,
            stdout,
            stderr,
            window,
        };
        // No window manager runs: give the window the keyboard, and the
        // pointer over it for the wheel.
        let window = viewer.window.clone();
        viewer.xdotool(&["windowfocus", &window]);
        viewer.xdotool(&["mousemove", "--window", &window, "5", "5"]);
        viewer
    }

    fn xdotool(&self, args: &[&str]) -> String {
        xdotool(&self.x, args)
    }

    /// Presses a key (an X keysym: "c", "S", "Escape") as a keyboard would.
    fn key(&self, key: &str) {
        self.xdotool(&["key", key]);
    }

    /// Drags with mouse button `button` from (x, y) by (dx, dy), in steps.
    fn drag(&self, button: &str, (x, y): (i32, i32), (dx, dy): (i32, i32)) {
        let w = &self.window;
        let at = |x: i32, y: i32| {
            ["mousemove", "--window", w, &x.to_string(), &y.to_string()].map(String::from)
        };
        let mut args: Vec<String> = at(x, y).to_vec();
        args.extend(["mousedown".to_string(), button.to_string()]);
        for step in 1..=3 {
            args.extend(at(x + dx * step / 3, y + dy * step / 3));
        }
        args.extend(["mouseup".to_string(), button.to_string()]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        self.xdotool(&args);
    }

    /// `C`: the camera the viewer prints.
    fn camera(&self) -> toml::Table {
        self.key("c");
        let mut text = String::new();
        wait_for(&self.stdout, "[camera] table", |l| l == "[camera]");
        for _ in 0..6 {
            text += &wait_for(&self.stdout, "camera line", |_| true);
            text += "\n";
        }
        text.parse().expect("the camera printed is TOML")
    }

    /// `s` until the screenshot holds every one of the view's
    /// samples (`spp`): the image the window settles on.
    fn converged_screenshot(&self, spp: u32) {
        let deadline = Instant::now() + PATIENCE;
        loop {
            self.key("s");
            let line = wait_for(&self.stderr, "screenshot line", |l| l.starts_with("wrote "));
            if line.ends_with(&format!("({spp} spp)")) {
                // The last frame came before the line: let it be shown.
                std::thread::sleep(Duration::from_millis(500));
                return;
            }
            assert!(Instant::now() < deadline, "not converged: {line}");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// The window's pixels as the X server holds them (xwd), RGB.
    fn screen(&self) -> (u32, u32, Vec<u8>) {
        let output = Command::new("xwd")
            .args(["-silent", "-id", &self.window])
            .env("DISPLAY", &self.x.display)
            .output()
            .expect("xwd runs");
        assert!(output.status.success(), "xwd failed");
        parse_xwd(&output.stdout)
    }

    /// Escape, and the exit status.
    fn quit(self) -> std::process::ExitStatus {
        self.quit_with("Escape")
    }

    /// `key` (Escape or q), and the exit status.
    fn quit_with(mut self, key: &str) -> std::process::ExitStatus {
        self.key(key);
        let deadline = Instant::now() + PATIENCE;
        loop {
            if let Some(status) = self.process.0.try_wait().unwrap() {
                return status;
            }
            assert!(Instant::now() < deadline, "{key} did not close the viewer");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// An XWD dump's pixels (ZPixmap, 24 or 32 bits a pixel, as Xvfb's
/// depth-24 screen writes them) as RGB.
fn parse_xwd(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let field = |i: usize| u32::from_be_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    let (header, format) = (field(0) as usize, field(2));
    let (width, height) = (field(4), field(5));
    let (byte_order, bits_per_pixel, bytes_per_line) = (field(7), field(11), field(12) as usize);
    let masks = [field(13 + 1), field(13 + 2), field(13 + 3)];
    let colours = field(19) as usize;
    assert_eq!(format, 2, "a ZPixmap dump");
    assert_eq!(bits_per_pixel, 32, "32 bits a pixel");
    let pixels = &bytes[header + 12 * colours..];
    let mut rgb = Vec::with_capacity(width as usize * height as usize * 3);
    for y in 0..height as usize {
        for x in 0..width as usize {
            let p: [u8; 4] = pixels[y * bytes_per_line + 4 * x..][..4]
                .try_into()
                .unwrap();
            let value = if byte_order == 0 {
                u32::from_le_bytes(p)
            } else {
                u32::from_be_bytes(p)
            };
            rgb.extend(masks.map(|m| ((value & m) >> m.trailing_zeros()) as u8));
        }
    }
    (width, height, rgb)
}

/// A PNG's pixels, RGB.
fn png(path: &Path) -> (u32, u32, Vec<u8>) {
    let image = image::open(path).expect("a PNG").to_rgb8();
    (image.width(), image.height(), image.into_raw())
}

fn cornell() -> PathBuf {
    asset("scenes/cornell.toml")
}

/// `scenes/cornell.toml` with its `[camera]` table replaced by `camera`,
/// written to `dir` (its meshes found where they are).
fn cornell_with_camera(dir: &Path, camera: &toml::Table) -> PathBuf {
    let mut scene: toml::Table = std::fs::read_to_string(cornell()).unwrap().parse().unwrap();
    scene.insert("camera".into(), toml::Value::Table(camera.clone()));
    let meshes = asset("scenes/meshes");
    let text = toml::to_string(&scene)
        .unwrap()
        .replace("\"meshes/", &format!("\"{}/", meshes.display()));
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn vector(camera: &toml::Table, key: &str) -> DVec3 {
    let values: Vec<f64> = camera[key]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_float().unwrap())
        .collect();
    DVec3::from_slice(&values)
}

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

#[test]
fn a_drag_orbits_and_the_camera_printed_renders_what_the_window_shows() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let (width, height, spp) = (120, 90, 2);
    let viewer = Viewer::start(
        x,
        &[
            s(&cornell()),
            "--width",
            "120",
            "--height",
            "90",
            "--spp",
            "2",
            "--device",
            "gpu",
            "--screenshot",
            s(&shot),
        ],
    );
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
    let viewer = Viewer::start(
        x,
        &[
            s(&cornell()),
            "--width",
            "80",
            "--height",
            "60",
            "--spp",
            "1",
            "--device",
            "cpu",
        ],
    );
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
