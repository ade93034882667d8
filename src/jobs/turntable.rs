//! Turntable frames (`lambert render --turntable N`): the camera orbiting
//! its look_at, the scene uploaded once, each frame written as it is done
//! under a name made from a pattern.

use std::collections::HashMap;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::time::Duration;

use web_time::Instant;

use super::{open_with, say, seconds};
use crate::camera::orbit;
use crate::error::{Error, Result};
use crate::gpu::AdapterRequest;
use crate::progress::ProgressSink;
use crate::render::DeviceChoice;
use crate::scene::{RenderSettings, Scene};

/// Frames to render and write.
pub struct TurntableJob<'a> {
    /// The frames' names, with the frame number as `{}` or `{:04}`.
    pub pattern: &'a Path,
    /// Frames in a whole turn.
    pub frames: u32,
    /// Those rendered here (`--frames A-B`), named as in a whole run.
    pub range: RangeInclusive<u32>,
    pub device: DeviceChoice,
    pub adapter: &'a AdapterRequest,
}

/// One frame written.
pub struct FrameReport {
    pub frame: u32,
    pub path: PathBuf,
    /// Render and readback.
    pub elapsed: Duration,
}

/// What `render_turntable` did.
pub struct TurntableReport {
    /// Frames in a whole turn.
    pub frames: u32,
    pub written: Vec<FrameReport>,
    /// `Renderer::describe` of the device it rendered on.
    pub device: String,
}

impl TurntableReport {
    /// Render and readback per frame, on average.
    pub fn mean_frame_time(&self) -> Duration {
        let total: Duration = self.written.iter().map(|f| f.elapsed).sum();
        total / self.written.len().max(1) as u32
    }
}

/// Renders `job`'s frames of `scene` with `settings`, orbiting their
/// camera, and writes each; says each frame on `sink` as it is written.
pub fn render_turntable(
    scene: Scene,
    settings: &RenderSettings,
    job: &TurntableJob,
    sink: Option<&dyn ProgressSink>,
) -> Result<TurntableReport> {
    let paths = frame_paths(job.pattern, job.range.clone())?;
    let mut view = settings.view.clone();
    let (mut renderer, _, device) = open_with(scene, settings, job.device, job.adapter, sink)?;
    let count = paths.len();
    let of = if count as u32 == job.frames {
        String::new()
    } else {
        format!(" of {}", job.frames)
    };
    say(sink, &format!("rendering {count}{of} frames on {device}"));
    let camera = view.camera.clone();
    let mut written = Vec::new();
    for (frame, path) in job.range.clone().zip(paths) {
        view.camera = orbit(&camera, frame, job.frames);
        let start = Instant::now();
        let (rendered, _) = renderer.render(&view, None)?;
        let elapsed = start.elapsed();
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        rendered.image.save(&path)?;
        say(
            sink,
            &format!("frame {frame}: {} ({})", seconds(elapsed), path.display()),
        );
        written.push(FrameReport {
            frame,
            path,
            elapsed,
        });
    }
    Ok(TurntableReport {
        frames: job.frames,
        written,
        device,
    })
}

/// The names of frames `range` of `pattern` (`frame_path`), refused where
/// two name one file (`d{}/../same.png`: every frame's `..` leads back to
/// one folder), which would leave one image where the report counts many.
pub fn frame_paths(pattern: &Path, range: RangeInclusive<u32>) -> Result<Vec<PathBuf>> {
    let mut seen: HashMap<PathBuf, u32> = HashMap::new();
    let mut paths = Vec::new();
    for frame in range {
        let path = frame_path(pattern, frame)?;
        if let Some(first) = seen.insert(lexically_absolute(&path)?, frame) {
            return Err(Error::Usage(format!(
                "{}: frames {first} and {frame} are both written to {}; the frame number must \
                 make each frame's file its own",
                pattern.display(),
                path.display()
            )));
        }
        paths.push(path);
    }
    Ok(paths)
}

/// `path` made absolute with `.` and `..` resolved by name: a frame's
/// folder need not exist yet, so the file system cannot resolve them.
fn lexically_absolute(path: &Path) -> Result<PathBuf> {
    use std::path::Component;
    let absolute = if path.is_absolute() {
        path.to_path_buf()
    } else {
        let here = std::env::current_dir().map_err(|e| Error::io(Path::new("."), e))?;
        here.join(path)
    };
    let mut normal = PathBuf::new();
    for part in absolute.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir => {
                normal.pop();
            }
            other => normal.push(other),
        }
    }
    Ok(normal)
}

/// `frames/frame_{:04}.png` with frame 7 → `frames/frame_0007.png`; every
/// placeholder is filled (`{}/f_{}.png` → `7/f_7.png`).
pub fn frame_path(pattern: &Path, frame: u32) -> Result<PathBuf> {
    let text = pattern.to_string_lossy();
    let mut filled = String::new();
    let mut rest = &text[..];
    let mut placeholders = 0;
    while let Some((open, close)) = rest
        .find('{')
        .and_then(|o| rest[o..].find('}').map(|c| (o, o + c)))
    {
        let width = frame_number_width(pattern, &rest[open + 1..close])?;
        filled.push_str(&format!("{}{frame:0width$}", &rest[..open]));
        rest = &rest[close + 1..];
        placeholders += 1;
    }
    if placeholders == 0 {
        return Err(Error::Usage(format!(
            "{}: --turntable needs a frame number in the output name, as {{}} or {{:04}}",
            pattern.display()
        )));
    }
    filled.push_str(rest);
    Ok(PathBuf::from(filled))
}

/// The digits of a frame number placeholder `{spec}`: `{}` none (as
/// many as it takes), `{:04}` or `{:4}` four, zero-padded.
fn frame_number_width(pattern: &Path, spec: &str) -> Result<usize> {
    match spec.strip_prefix(":0").or_else(|| spec.strip_prefix(':')) {
        None if spec.is_empty() => Ok(0),
        Some(w) => w.parse::<usize>().ok().filter(|&w| w <= 16).ok_or_else(|| {
            Error::Usage(format!(
                "{}: cannot read the frame number format {{{spec}}}; use {{}} or {{:0N}} with N at most 16",
                pattern.display()
            ))
        }),
        None => Err(Error::Usage(format!(
            "{}: cannot read the frame number format {{{spec}}}; use {{}} or {{:04}}",
            pattern.display()
        ))),
    }
}
