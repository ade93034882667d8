//! `lambert render --turntable N`: frames orbiting the camera's look_at,
//! the scene uploaded once, named by a pattern.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use super::{RenderArgs, check_output_path, print_warnings, seconds};
use lambert::camera::orbit;
use lambert::error::{Error, Result};
use lambert::jobs::frame_path;
use lambert::render::Renderer;

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
        lambert::output::refuse_input(&frame_path(&args.output, frame)?, &[&args.scene])?;
    }
    check_output_path(&frame_path(&args.output, *range.start())?, &[&args.scene])?;
    let mut scene = args.options.load(&args.scene)?;
    print_warnings(&scene, quiet);
    let (mut renderer, note) = Renderer::open(&scene, args.device.into(), &args.adapter.request())?;
    if let Some(note) = note.filter(|_| !quiet) {
        eprintln!("{note}");
    }
    if !quiet {
        eprintln!("rendering {frames} frames on {}", renderer.describe());
    }
    if !renderer.is_cpu() {
        scene.release_geometry();
    }
    let mut view = scene.view();
    let mut total = Duration::ZERO;
    let rendered_frames = range.clone().count() as u32;
    for frame in range {
        view.camera = orbit(&scene.camera, frame, frames);
        let start = Instant::now();
        let (rendered, _) = renderer.render(&scene, &view, None)?;
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
