//! Render work the front ends share (the `lambert` binary, and the Python
//! package where it needs it): the f64 oracle's scene, a GPU render, the
//! time budget's pilot, and a turntable's frame names (its cameras:
//! `camera::orbit`).

use std::path::{Path, PathBuf};

use crate::camera::View;
use crate::error::{Error, Result};
use crate::gpu::{AdapterRequest, Gpu, GpuRenderer};
use crate::limits::MAX_SPP;
use crate::output::Rendered;
use crate::progress::Progress;
use crate::render::Renderer;
use crate::scene::{Intersect, Scene};

/// The f64 oracle's version of `scene`: the watertight test, in double
/// precision, is the reference every variant and device is measured against.
pub fn oracle_scene(scene: &Scene) -> Scene {
    let mut oracle = scene.clone();
    oracle.intersect = Intersect::Watertight;
    oracle
}

/// Renders on the GPU (any adapter, lavapipe included), showing no progress.
pub fn render_gpu(scene: &Scene, request: &AdapterRequest) -> Result<Rendered> {
    let mut renderer = GpuRenderer::new(Gpu::open(request, false)?, scene)?;
    Ok(renderer.render(&Progress::hidden())?.0)
}

/// What a time budget's pilot found.
#[derive(Clone, Copy, Debug)]
pub struct BudgetPlan {
    /// Seconds one sample per pixel takes (render and readback).
    pub per_sample: f64,
    /// Samples per pixel that fit in the rest of the budget.
    pub spp: u32,
}

/// Samples per pixel that fit in `budget` seconds, from a timed 1-spp pilot
/// render (whose time counts against the budget).
pub fn spp_for_budget(
    renderer: &mut Renderer,
    scene: &Scene,
    view: &View,
    budget: f64,
) -> Result<BudgetPlan> {
    let pilot = View {
        spp: 1,
        ..view.clone()
    };
    let (_, t) = renderer.render(scene, &pilot, None)?;
    let per_sample = (t.render + t.readback).as_secs_f64().max(1e-6);
    let spp = ((budget - per_sample) / per_sample)
        .floor()
        .clamp(1.0, MAX_SPP as f64) as u32;
    Ok(BudgetPlan { per_sample, spp })
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
