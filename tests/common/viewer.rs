//! The viewer tests' helpers (tests/viewer.rs, tests/viewer_lifecycle.rs):
//! an Xvfb of a test's own, `lambert view` run under it and driven with
//! xdotool, its window read back with xwd.
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

use glam::DVec3;

use crate::common::{asset, lambert_command};

/// Long enough for a loaded machine building in parallel.
pub const PATIENCE: Duration = Duration::from_secs(60);

/// A child process killed when the test ends, however it ends.
pub struct Killed(pub Child);

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
pub struct Xvfb {
    pub display: String,
    server: Child,
    /// The server's stderr, for a failing test's message.
    log: tempfile::NamedTempFile,
    _turn: std::sync::MutexGuard<'static, ()>,
}

impl Xvfb {
    /// Whether a client (xdotool) gets through now.
    pub fn takes_client(&self) -> bool {
        Command::new("xdotool")
            .arg("getmouselocation")
            .env("DISPLAY", &self.display)
            .output()
            .is_ok_and(|o| o.status.success())
    }

    /// The server's state and the last of what it wrote to stderr.
    pub fn report(&mut self) -> String {
        let state = match self.server.try_wait() {
            Ok(Some(status)) => format!("ended ({status})"),
            _ => "running".to_string(),
        };
        let said = std::fs::read_to_string(self.log.path()).unwrap_or_default();
        let tail: Vec<&str> = said.lines().rev().take(8).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        format!("Xvfb {} {state}; it said: {tail:?}", self.display)
    }
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
pub fn xvfb() -> Option<Xvfb> {
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
    let log = tempfile::NamedTempFile::new().expect("a file for Xvfb's stderr");
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
            // No autorepeat: on a loaded machine xdotool's key release can
            // come half a second after its press, and the server's repeats
            // would press `c` twice (two camera tables, the second read
            // as the next one's).
            "-ardelay",
            "30000",
            // No reset when the last client leaves: xdotool's probes are
            // such clients, and a viewer connecting while the server
            // resets is refused (two loops of 300 probes at once: 15 and
            // 12 refused without this flag, none with it).
            "-noreset",
        ])
        .stdout(Stdio::piped())
        .stderr(log.reopen().expect("Xvfb's stderr file"))
        .spawn()
        .expect("Xvfb starts");
    let mut line = String::new();
    BufReader::new(server.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let number: u32 = line.trim().parse().expect("Xvfb names its display");
    let mut x = Xvfb {
        display: format!(":{number}"),
        server,
        log,
        _turn: turn,
    };
    // Until a client gets through (other suites may start servers too).
    let deadline = Instant::now() + PATIENCE;
    while !x.takes_client() {
        assert!(
            Instant::now() < deadline,
            "no client gets through: {}",
            x.report()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    Some(x)
}

/// Lines a pipe gives, as they come.
pub fn lines(pipe: impl Read + Send + 'static) -> Receiver<String> {
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
pub fn wait_for(lines: &Receiver<String>, what: &str, wanted: impl Fn(&str) -> bool) -> String {
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
pub fn xdotool(x: &Xvfb, args: &[&str]) -> String {
    let output = Command::new("xdotool")
        .args(args)
        .env("DISPLAY", &x.display)
        .output()
        .expect("xdotool runs");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A running `lambert view` and its X server.
pub struct Viewer {
    pub x: Xvfb,
    pub process: Killed,
    pub stdout: Receiver<String>,
    pub stderr: Receiver<String>,
    pub window: String,
}

impl Viewer {
    pub fn start(x: Xvfb, args: &[&str]) -> Viewer {
        Viewer::start_with(x, args, &[])
    }

    /// `start`, with environment variables set. A viewer connecting while
    /// xdotool's probe left the server, which then reset, was refused
    /// (once, on CI, three times in a row; the servers now run with
    /// `-noreset`). Should one still say it cannot open a window, it is
    /// started again after a pause, on a fresh server where the old one
    /// takes no client any more; four times at most, each refusal printed
    /// with the server's state.
    pub fn start_with(mut x: Xvfb, args: &[&str], env: &[(&str, &str)]) -> Viewer {
        let spawn = |display: &str| {
            let mut child = lambert_command()
                .arg("view")
                .args(args)
                .envs(env.iter().copied())
                .env("DISPLAY", display)
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
        const ATTEMPTS: u32 = 5;
        let mut attempt = 1;
        let (window, (process, stdout, stderr)) = 'started: loop {
            let (mut process, stdout, stderr) = spawn(&x.display);
            let deadline = Instant::now() + PATIENCE;
            loop {
                // Mapped, not only created: the pointer moved over it below
                // must be over a window that takes the wheel's clicks.
                let found = xdotool(&x, &["search", "--onlyvisible", "--name", "^lambert view"]);
                if let Some(id) = found.lines().next() {
                    break 'started (id.to_string(), (process, stdout, stderr));
                }
                if let Some(status) = process.0.try_wait().unwrap() {
                    let errors: Vec<String> = stderr.try_iter().collect();
                    let refused = errors.iter().any(|e| e.contains("cannot open a window"));
                    let server = x.report();
                    assert!(
                        refused && attempt < ATTEMPTS,
                        "lambert view exited ({status}) before its window showed: {errors:?}; {server}"
                    );
                    eprintln!("attempt {attempt}: {errors:?}; {server}; again");
                    attempt += 1;
                    std::thread::sleep(Duration::from_millis(500));
                    if !x.takes_client() {
                        drop(x);
                        x = xvfb().expect("the tools were there a moment ago");
                        eprintln!("a fresh server: {}", x.display);
                    }
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

    pub fn xdotool(&self, args: &[&str]) -> String {
        xdotool(&self.x, args)
    }

    /// Presses a key (an X keysym: "c", "S", "Escape") as a keyboard would.
    pub fn key(&self, key: &str) {
        self.xdotool(&["key", key]);
    }

    /// Drags with mouse button `button` from (x, y) by (dx, dy), in steps.
    pub fn drag(&self, button: &str, (x, y): (i32, i32), (dx, dy): (i32, i32)) {
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
    pub fn camera(&self) -> toml::Table {
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
    pub fn converged_screenshot(&self, spp: u32) {
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
    pub fn screen(&self) -> (u32, u32, Vec<u8>) {
        let output = Command::new("xwd")
            .args(["-silent", "-id", &self.window])
            .env("DISPLAY", &self.x.display)
            .output()
            .expect("xwd runs");
        assert!(output.status.success(), "xwd failed");
        parse_xwd(&output.stdout)
    }

    /// Escape, and the exit status.
    pub fn quit(self) -> std::process::ExitStatus {
        self.quit_with("Escape")
    }

    /// `key` (Escape or q), and the exit status.
    pub fn quit_with(mut self, key: &str) -> std::process::ExitStatus {
        self.key(key);
        self.exit_status(&format!("{key} did not close the viewer"))
    }

    /// Waits (PATIENCE at most, else fails saying `late`) for the viewer
    /// to exit: its status.
    pub fn exit_status(&mut self, late: &str) -> std::process::ExitStatus {
        let deadline = Instant::now() + PATIENCE;
        loop {
            if let Some(status) = self.process.0.try_wait().unwrap() {
                return status;
            }
            assert!(Instant::now() < deadline, "{late}");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

/// An XWD dump's pixels (ZPixmap, 24 or 32 bits a pixel, as Xvfb's
/// depth-24 screen writes them) as RGB.
pub fn parse_xwd(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
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
pub fn png(path: &Path) -> (u32, u32, Vec<u8>) {
    let image = image::open(path).expect("a PNG").to_rgb8();
    (image.width(), image.height(), image.into_raw())
}

pub fn cornell() -> PathBuf {
    asset("scenes/cornell.toml")
}

/// `scenes/cornell.toml` with its `[camera]` table replaced by `camera`,
/// written to `dir` (its meshes found where they are).
pub fn cornell_with_camera(dir: &Path, camera: &toml::Table) -> PathBuf {
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

pub fn vector(camera: &toml::Table, key: &str) -> DVec3 {
    let values: Vec<f64> = camera[key]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_float().unwrap())
        .collect();
    DVec3::from_slice(&values)
}
