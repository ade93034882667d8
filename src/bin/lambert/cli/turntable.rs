//! `lambert render --turntable N`: its options checked, then the job
//! (`jobs::render_turntable`) and its report.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::{RenderArgs, load_for};
use crate::progress_bar;
use lambert::error::{Error, Result};
use lambert::jobs::{TurntableJob, frame_paths, render_turntable, seconds};

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
    let paths = frame_paths(&args.output, range.clone())?;
    for path in &paths {
        lambert::output::refuse_input(path, &[&args.input.scene])?;
    }
    let outputs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
    let (scene, settings) = load_for(&args.input, &outputs, quiet)?;
    let job = TurntableJob {
        pattern: &args.output,
        frames,
        range,
        device: args.input.device.into(),
        adapter: &args.input.adapter.request(),
    };
    let report = render_turntable(scene, &settings, &job, progress_bar::unless_quiet(quiet))?;
    if !quiet {
        eprintln!(
            "{} of {} frames, {} per frame on average (render and readback; the scene was uploaded once)",
            report.written.len(),
            report.frames,
            seconds(report.mean_frame_time())
        );
    }
    Ok(ExitCode::SUCCESS)
}
