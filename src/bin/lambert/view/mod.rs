//! `lambert view`: a window showing the ray-traced image of a scene,
//! refined a sample per pixel each frame (docs/viewer.md). The window and
//! its input live here (`app`), the render thread in `worker`, the camera
//! moves in the library's `camera::navigate` (the web viewer's too),
//! showing a frame in `present`.

mod app;
mod present;
mod worker;

use std::path::PathBuf;
use std::process::ExitCode;

use lambert::error::{Error, Result};
use lambert::gpu::AdapterRequest;
use lambert::render::DeviceChoice;
use lambert::scene::Scene;

/// What the command line asks of the viewer.
pub struct Settings {
    /// The file the scene came from (`R`, `1`–`9` read its cameras again).
    pub path: PathBuf,
    pub scene: Scene,
    pub device: DeviceChoice,
    pub request: AdapterRequest,
    /// Samples per pixel of the whole sequence, one a frame.
    pub spp: u32,
    /// `--frames N`: exit once the `spp` (= N) frames are in, after
    /// writing `screenshot`.
    pub frames: bool,
    /// Where `--frames` and `S` write (`S`: lambert-view-NNN.png when
    /// not given).
    pub screenshot: Option<PathBuf>,
    pub quiet: bool,
}

/// Opens the window and runs until it closes (or `--frames` are done).
pub fn view(settings: Settings) -> Result<ExitCode> {
    check_display()?;
    let event_loop = winit::event_loop::EventLoop::<worker::Report>::with_user_event()
        .build()
        .map_err(|e| {
            // winit's text starts with the source line it failed on.
            let text = e.to_string();
            let why = text
                .strip_prefix("os error at ")
                .and_then(|t| t.split_once(": "))
                .map_or(text.as_str(), |(_, why)| why);
            let display = std::env::var("DISPLAY").unwrap_or_default();
            Error::Usage(format!(
                "lambert view: cannot open a window on display {display:?}: {why}"
            ))
        })?;
    let mut app = app::App::new(settings, event_loop.create_proxy());
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::Usage(format!("lambert view: the window failed: {e}")))?;
    app.outcome()
}

/// A window needs a display: on Linux and the BSDs an X server (Wayland
/// desktops offer theirs, XWayland).
fn check_display() -> Result<()> {
    if cfg!(any(target_os = "macos", target_os = "windows")) {
        return Ok(());
    }
    let set = |name| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    if set("DISPLAY") {
        return Ok(());
    }
    let why = if set("WAYLAND_DISPLAY") {
        "WAYLAND_DISPLAY is set but DISPLAY is not (lambert view needs XWayland)"
    } else {
        "DISPLAY is not set"
    };
    Err(Error::Usage(format!(
        "lambert view: no display to open a window on ({why}); run it in a desktop session, or headless under Xvfb (xvfb-run lambert view …), or use lambert render"
    )))
}
