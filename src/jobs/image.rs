//! One image (`lambert render`): at the view's spp, within a time budget
//! (a timed 1-spp pilot chooses the spp) or adaptively (`--target-error`);
//! written to a file, with a report of where the time went.

use std::path::{Path, PathBuf};
use std::time::Duration;

use web_time::Instant;

use super::{open_with, say};
use crate::adaptive::{AdaptiveReport, AdaptiveSettings, render_adaptive};
use crate::bvh::Bvh;
use crate::camera::View;
use crate::cpu::aov::{Aov, render_aovs};
use crate::error::Result;
use crate::gpu::{AccelerationStats, AdapterRequest};
use crate::limits::MAX_SPP;
use crate::output::Rendered;
use crate::progress::ProgressSink;
use crate::render::{DeviceChoice, RenderTimings, Renderer};
use crate::scene::{RenderSettings, Scene};

/// How many samples each pixel gets.
#[derive(Clone, Copy, Debug)]
pub enum Sampling {
    /// The view's spp.
    Fixed,
    /// As many as fit in this many seconds (the pilot's included).
    Budget(f64),
    /// More where a pixel's standard error is above `target_error`, up to
    /// `max_spp`, from the view's spp when above 1, else 4.
    Adaptive { target_error: f64, max_spp: u32 },
}

/// A render's image and what its sampling found.
pub struct Sampled {
    pub rendered: Rendered,
    pub timings: RenderTimings,
    /// Samples traced in all (primary rays).
    pub samples: f64,
    pub budget: Option<BudgetReport>,
    pub adaptive: Option<AdaptiveReport>,
}

/// What a time budget chose and what it expects.
#[derive(Clone, Copy, Debug)]
pub struct BudgetReport {
    pub budget: f64,
    pub plan: BudgetPlan,
    /// RMSE expected from sampling noise; unknown at 1 spp.
    pub expected_rmse: Option<f64>,
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
fn spp_for_budget(renderer: &mut Renderer, view: &View, budget: f64) -> Result<BudgetPlan> {
    let pilot = View {
        spp: 1,
        ..view.clone()
    };
    let (_, t) = renderer.render(&pilot, None)?;
    let per_sample = (t.render + t.readback).as_secs_f64().max(1e-6);
    let spp = ((budget - per_sample) / per_sample)
        .floor()
        .clamp(1.0, MAX_SPP as f64) as u32;
    Ok(BudgetPlan { per_sample, spp })
}

/// Renders `renderer`'s scene as `view` sees it, with `sampling`'s
/// samples; progress and the budget's choice on `sink`.
pub fn render_view(
    renderer: &mut Renderer,
    view: &View,
    sampling: Sampling,
    sink: Option<&dyn ProgressSink>,
) -> Result<Sampled> {
    let mut view = view.clone();
    let mut budget = None;
    if let Sampling::Budget(seconds) = sampling {
        let plan = spp_for_budget(renderer, &view, seconds)?;
        say(
            sink,
            &format!(
                "time budget {seconds} s: a 1-spp pass takes {:.3} s, so {} spp",
                plan.per_sample, plan.spp
            ),
        );
        view.spp = plan.spp;
        budget = Some((seconds, plan));
    }
    let samples = view.camera.width as f64 * view.camera.height as f64 * view.spp as f64;
    let Sampling::Adaptive {
        target_error,
        max_spp,
    } = sampling
    else {
        let (rendered, timings) = renderer.render(&view, sink)?;
        let budget = budget.map(|(budget, plan)| BudgetReport {
            budget,
            plan,
            expected_rmse: (view.spp > 1).then(|| mean_variance(&rendered).sqrt()),
        });
        return Ok(Sampled {
            rendered,
            timings,
            samples,
            budget,
            adaptive: None,
        });
    };
    let settings = AdaptiveSettings {
        target_error,
        // The view's samples, when it asks for more than one.
        base_spp: if view.spp > 1 { view.spp } else { 4 },
        max_spp,
    };
    let start = Instant::now();
    let (rendered, report) = render_adaptive(renderer, &view, settings)?;
    Ok(Sampled {
        rendered,
        timings: RenderTimings {
            render: start.elapsed(),
            readback: Duration::ZERO,
            device: None,
        },
        samples: report.total_samples as f64,
        budget: None,
        adaptive: Some(report),
    })
}

fn mean_variance(rendered: &Rendered) -> f64 {
    rendered.variance.iter().map(|&v| v as f64).sum::<f64>() / rendered.variance.len() as f64
}

/// One image to render and write.
pub struct ImageJob<'a> {
    pub output: &'a Path,
    pub device: DeviceChoice,
    pub adapter: &'a AdapterRequest,
    pub sampling: Sampling,
    /// First-hit outputs written beside the image (`Aov::path_beside`).
    pub aovs: &'a [Aov],
}

/// The scene's BVH as the report gives it, taken before a GPU render lets
/// the host's copy go.
#[derive(Clone, Copy, Debug)]
pub struct BvhSummary {
    pub nodes: usize,
    pub depth: usize,
    pub sah_cost: f64,
    pub build_time: Duration,
    pub device_bytes: usize,
}

impl BvhSummary {
    fn of(bvh: &Bvh) -> BvhSummary {
        BvhSummary {
            nodes: bvh.nodes.len(),
            depth: bvh.depth(),
            sah_cost: bvh.sah_cost(),
            build_time: bvh.build_time,
            device_bytes: bvh.device_bytes(),
        }
    }
}

/// What `render_image` did.
pub struct ImageReport {
    pub output: PathBuf,
    /// `Renderer::describe` of the device it rendered on.
    pub device: String,
    pub width: u32,
    pub height: u32,
    pub primitives: usize,
    pub bvh: BvhSummary,
    /// Under `--accel hardware`, the acceleration structures the GPU's
    /// ray queries traced (None where the rays went through a BVH).
    pub ray_queries: Option<AccelerationStats>,
    /// Opening the device and uploading the scene.
    pub upload: Duration,
    pub timings: RenderTimings,
    pub write: Duration,
    /// Samples traced in all (primary rays).
    pub samples: f64,
    pub budget: Option<BudgetReport>,
    pub adaptive: Option<AdaptiveReport>,
    /// The first-hit outputs written, and how long they took.
    pub aovs: Vec<PathBuf>,
    pub aov_time: Duration,
}

impl ImageReport {
    /// Primary rays per second of the render stage, in millions.
    pub fn mrays_per_second(&self) -> f64 {
        self.samples / self.timings.render.as_secs_f64() / 1e6
    }

    /// Primary rays per second of GPU time, in millions, where the adapter
    /// times itself.
    pub fn device_mrays_per_second(&self) -> Option<f64> {
        let device = self.timings.device?;
        Some(self.samples / device.as_secs_f64() / 1e6)
    }
}

/// Renders `scene` with `settings` (its view among them) as `job` asks
/// and writes the image.
pub fn render_image(
    scene: Scene,
    settings: &RenderSettings,
    job: &ImageJob,
    sink: Option<&dyn ProgressSink>,
) -> Result<ImageReport> {
    // Taken before a GPU lets the host's geometry go.
    let primitives = scene.primitive_count();
    let bvh = BvhSummary::of(&scene.bvh);
    let view = settings.view.clone();
    // On the host's copy, before a GPU lets it go.
    let start = Instant::now();
    let scene = scene.with_settings(settings);
    let aovs = render_aovs(&scene, &view, job.aovs);
    let aov_time = start.elapsed();
    let (mut renderer, upload, device) = open_with(scene, settings, job.device, job.adapter, sink)?;
    say(sink, &format!("rendering on {device}"));
    let sampled = render_view(&mut renderer, &view, job.sampling, sink)?;
    let start = Instant::now();
    sampled.rendered.image.save(job.output)?;
    let mut aov_paths = Vec::new();
    for (aov, image) in job.aovs.iter().zip(&aovs) {
        let path = aov.path_beside(job.output);
        image.save(&path)?;
        aov_paths.push(path);
    }
    Ok(ImageReport {
        output: job.output.to_path_buf(),
        device,
        width: view.camera.width,
        height: view.camera.height,
        primitives,
        bvh,
        ray_queries: renderer.ray_queries(),
        upload,
        timings: sampled.timings,
        write: start.elapsed(),
        samples: sampled.samples,
        budget: sampled.budget,
        adaptive: sampled.adaptive,
        aovs: aov_paths,
        aov_time,
    })
}
