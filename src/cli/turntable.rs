//! `lambert render --turntable N`: frames orbiting the camera's look_at,
//! the scene uploaded once, named by a pattern.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use super::{RenderArgs, check_output_path, print_warnings, seconds};
use crate::error::{Error, Result};
use crate::render::Renderer;
use crate::scene::Camera;

/// `--frames A-B` (or `A`) of `frames`: inclusive, within 0..frames.
pub(super) fn frame_range(text: &str, frames: u32) -> Result<std::ops::RangeInclusive<u32>> {
    let usage = || {
        Error::Usage(format!(
            "--frames {text}: expected A-B (or A), with 0 ≤ A ≤ B < {frames}"
        ))
    };
    let (a, b) = text.split_once('-').unwrap_or((text, text));
    let (a, b): (u32, u32) = (
        a.trim().parse().map_err(|_| usage())?,
        b.trim().parse().map_err(|_| usage())?,
    );
    if a > b || b >= frames {
        return Err(usage());
    }
    Ok(a..=b)
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

/// The camera of frame `frame` of `frames`, orbiting look_at about up.
fn orbit(camera: &Camera, frame: u32, frames: u32) -> Camera {
    let centre = glam::DVec3::from(camera.look_at);
    let axis = glam::DVec3::from(camera.up).normalize();
    let angle = std::f64::consts::TAU * frame as f64 / frames as f64;
    let eye = centre
        + glam::DQuat::from_axis_angle(axis, angle) * (glam::DVec3::from(camera.eye) - centre);
    Camera {
        eye: eye.to_array(),
        ..camera.clone()
    }
}

pub(super) fn turntable(args: &RenderArgs, frames: u32, quiet: bool) -> Result<ExitCode> {
    if frames == 0 {
        return Err(Error::Usage("--turntable needs at least 1 frame".into()));
    }
    let range = match &args.frames {
        Some(text) => frame_range(text, frames)?,
        None => 0..=frames - 1,
    };
    // Every frame's name is checked before the first is rendered.
    for frame in range.clone() {
        crate::output::refuse_input(&frame_path(&args.output, frame)?, &[&args.scene])?;
    }
    check_output_path(&frame_path(&args.output, *range.start())?, &[&args.scene])?;
    let mut scene = args.options.load(&args.scene)?;
    print_warnings(&scene, quiet);
    let (mut renderer, note) = Renderer::open(&scene, args.device, &args.adapter.request())?;
    if let Some(note) = note.filter(|_| !quiet) {
        eprintln!("{note}");
    }
    if !quiet {
        eprintln!("rendering {frames} frames on {}", renderer.describe());
    }
    if !renderer.is_cpu() {
        scene.release_geometry();
    }
    let start_camera = scene.camera.clone();
    let mut total = Duration::ZERO;
    let rendered_frames = range.clone().count() as u32;
    for frame in range {
        scene.camera = orbit(&start_camera, frame, frames);
        let start = Instant::now();
        let (rendered, _) = renderer.render(&scene, false)?;
        let elapsed = start.elapsed();
        total += elapsed;
        let path = frame_path(&args.output, frame)?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        rendered.image.save(&path)?;
        if !quiet {
            eprintln!("frame {frame}: {} ({})", seconds(elapsed), path.display());
        }
    }
    if !quiet {
        eprintln!(
            "{rendered_frames} of {frames} frames, {} per frame on average (render and readback; the scene was uploaded once)",
            seconds(total / rendered_frames)
        );
    }
    Ok(ExitCode::SUCCESS)
}
