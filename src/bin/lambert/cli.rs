//! The `lambert` command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

use clap::{Args, Parser, Subcommand, ValueEnum};

mod benchmark;
mod info;
mod options;
mod query;
mod turntable;
mod view;

use options::{
    AccelArg, AdapterArgs, BenchDevice, Device, RenderOptions, SceneArgs, SceneOptions,
    ViewOptions, fraction, non_negative,
};

use crate::progress_bar;
use lambert::cpu::aov::Aov;
use lambert::cpu::{self, Precision};
use lambert::diff::{self, Tolerance};
use lambert::error::{Error, Result};
use lambert::jobs::{
    self, ImageJob, ImageReport, Sampling, TileJob, oracle_scene, render_gpu, seconds,
};
use lambert::layout::NO_HIT;
use lambert::limits::MAX_SPP;
use lambert::progress::Progress;
use lambert::rays;
use lambert::render::Renderer;
use lambert::scene::{Integrator, RenderSettings, Scene};

#[derive(Parser)]
#[command(
    name = "lambert",
    version,
    about = "A GPU ray tracer with a CPU reference path"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Print nothing but errors and results (no notes, warnings or progress).
    #[arg(short, long, global = true)]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to PNG (sRGB, 8-bit), EXR or PFM (linear f32).
    Render(RenderArgs),
    /// Render a scene on two paths and compare the images.
    Diff(DiffArgs),
    /// Trace a ray file against a scene or OBJ meshes and write the hits.
    Trace(TraceArgs),
    /// Write a scene's camera rays (pixel centres, row by row) as a ray file.
    CameraRays(CameraRaysArgs),
    /// Closest points, distances, signed distances or inside tests of a
    /// point file; or counts or lists of every crossing of a ray file.
    Query(query::QueryArgs),
    /// List adapters, backends and limits.
    Info(InfoArgs),
    /// Measure trace speed over a ladder of models, or run time against
    /// error over the settings (--time-vs-error).
    Bench(BenchArgs),
    /// Assemble the parts of a render (`render --tile I/N`) into one image.
    Merge(MergeArgs),
    /// Open a window showing the scene ray traced, refined progressively;
    /// move the camera with the mouse and keys (H lists them).
    View(view::ViewArgs),
}

#[derive(Args)]
struct MergeArgs {
    /// Every part file of one render (any order).
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// Output image: .png, .exr or .pfm.
    #[arg(short, long)]
    output: PathBuf,
}

#[derive(Args)]
struct InfoArgs {
    /// A scene or model file: print what it holds (triangles, bounds,
    /// materials, camera, lights, warnings) instead of the adapters.
    model: Option<PathBuf>,
    /// A glTF file's camera, by name.
    #[arg(long)]
    camera: Option<String>,
    #[command(flatten)]
    adapter: AdapterArgs,
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    input: SceneArgs,
    /// Output image: .png, .exr or .pfm.
    #[arg(short, long)]
    output: PathBuf,
    /// Render N frames orbiting camera.look_at about camera.up; the scene
    /// stays on the device and only the camera changes. The output name
    /// holds the frame number as {}, {:04} (zero-padded to 4) or similar.
    #[arg(long, value_name = "N")]
    turntable: Option<u32>,
    /// Adaptive sampling: add samples only to pixels whose standard error
    /// (of mean luminance) is above E, or whose neighbour's is, starting from
    /// the scene's spp (or --spp) when above 1, else 4, doubling up to
    /// --max-spp. Reports the error it expects.
    #[arg(long, value_name = "E")]
    target_error: Option<f64>,
    /// Cap on samples per pixel for --target-error (which it requires:
    /// other renders take --spp).
    #[arg(long, default_value_t = 256, requires = "target_error")]
    max_spp: u32,
    /// Spend about this many seconds: a 1-spp pilot render times a sample,
    /// then the image is rendered with as many samples per pixel as the
    /// rest of the budget allows (the scene's render.spp is not used; an
    /// explicit --spp conflicts with it). Reports the error it expects.
    #[arg(
        long,
        value_name = "SECONDS",
        conflicts_with_all = ["target_error", "spp"]
    )]
    time_budget: Option<f64>,
    /// First-hit outputs for a denoiser, written beside the image as
    /// NAME.albedo.exr, NAME.normal.exr, NAME.depth.exr (.pfm for a PFM
    /// image): a comma-separated list of albedo, normal, depth.
    #[arg(long, value_name = "LIST")]
    aov: Option<String>,
    /// Render only part I (from 0) of N of the image, as an EXR part file
    /// for `lambert merge` (bands of rows; see docs/distributed.md).
    #[arg(long, value_name = "I/N")]
    tile: Option<String>,
    /// With --turntable: only frames A to B (inclusive, from 0, as Slurm and
    /// Blender count), named as in a full run.
    #[arg(long, value_name = "A-B", requires = "turntable")]
    frames: Option<String>,
}

/// `lambert render --tile I/N`: renders the part and writes it.
fn render_part(args: &RenderArgs, tile_text: &str, quiet: bool) -> Result<ExitCode> {
    let tile = lambert::parts::Tile::parse(tile_text)?;
    let refuse = |what: &str, why: &str| Err(Error::Usage(format!("--tile with {what}: {why}")));
    if args.target_error.is_some() {
        return refuse(
            "--target-error",
            "adaptive sampling looks at neighbouring pixels, across part edges too, so parts would not merge into the single render; use --spp",
        );
    }
    if args.time_budget.is_some() {
        return refuse(
            "--time-budget",
            "each part would choose its own spp; use --spp",
        );
    }
    if args.turntable.is_some() {
        return refuse("--turntable", "split a turntable by --frames instead");
    }
    let is_exr = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        return Err(Error::Usage(format!(
            "{}: a part is an OpenEXR file; name it .exr (lambert merge writes any format)",
            args.output.display()
        )));
    }
    let (scene, settings) = load_for(&args.input, &[&args.output], quiet)?;
    let job = TileJob {
        tile,
        output: &args.output,
        device: args.input.device.into(),
        adapter: &args.input.adapter.request(),
    };
    let report = jobs::render_tile(scene, &settings, &job, progress_bar::unless_quiet(quiet))?;
    if !quiet {
        eprintln!(
            "wrote {}: part {}/{} (rows {} to {} of {}×{}) on {} in {}",
            report.output.display(),
            report.tile.index,
            report.tile.count,
            report.rows.start,
            report.rows.end - 1,
            report.width,
            report.height,
            report.device,
            seconds(report.elapsed)
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn merge(args: &MergeArgs, quiet: bool) -> Result<ExitCode> {
    let parts: Vec<&Path> = args.parts.iter().map(PathBuf::as_path).collect();
    check_output_path(&args.output, &parts)?;
    let image = lambert::parts::merge(&args.parts, &args.output)?;
    if !quiet {
        eprintln!(
            "wrote {} ({}×{}, from {} parts)",
            args.output.display(),
            image.width,
            image.height,
            args.parts.len()
        );
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(Clone, Copy, ValueEnum)]
enum Comparison {
    /// GPU (f32) against the CPU reference (f32).
    GpuCpu,
    /// GPU (f32) against the f64 oracle.
    GpuOracle,
    /// CPU reference (f32) against the f64 oracle.
    CpuOracle,
    /// GPU through its ray queries (`--accel hardware`; an error where the
    /// adapter has none) against the CPU reference (f32).
    HardwareCpu,
}

#[derive(Args)]
struct DiffArgs {
    scene: PathBuf,
    #[arg(long, value_enum, default_value = "gpu-cpu")]
    compare: Comparison,
    /// Write a picture of the differences: .png, .exr or .pfm.
    #[arg(long)]
    heatmap: Option<PathBuf>,
    /// Print the statistics as JSON.
    #[arg(long)]
    json: bool,
    /// Allowed channel difference: abs + rel·|value| (linear).
    #[arg(long, default_value_t = Tolerance::default().abs, value_parser = non_negative)]
    tol_abs: f32,
    #[arg(long, default_value_t = Tolerance::default().rel, value_parser = non_negative)]
    tol_rel: f32,
    /// Fraction of pixels allowed beyond the tolerance (0 to 1).
    #[arg(long, default_value_t = Tolerance::default().max_bad_fraction, value_parser = fraction)]
    max_bad: f64,
    /// Fraction of pixels allowed to hit a different primitive (0 to 1).
    #[arg(long, default_value_t = Tolerance::default().max_prim_mismatch_fraction, value_parser = fraction)]
    max_prim_mismatch: f64,
    #[command(flatten)]
    options: RenderOptions,
    #[command(flatten)]
    adapter: AdapterArgs,
}

#[derive(Args)]
#[command(group = clap::ArgGroup::new("geometry").required(true).args(["scene", "obj"]))]
struct TraceArgs {
    /// Scene file whose meshes and spheres the rays are traced against.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// OBJ files, in order (primitive ids run across them in this order).
    #[arg(long, num_args = 1..)]
    obj: Vec<PathBuf>,
    /// Ray file: 8 little-endian f32 per ray (ox oy oz tmin dx dy dz tmax).
    #[arg(long)]
    rays: PathBuf,
    /// Hit file: t (f32), primitive (u32), u, v (f32) per ray.
    #[arg(short, long)]
    output: PathBuf,
    #[arg(long, value_enum, default_value_t)]
    device: Device,
    /// Report whether each ray hits anything (the first hit found), not the closest.
    #[arg(long)]
    any_hit: bool,
    #[command(flatten)]
    options: SceneOptions,
    /// Also trace in f64 (watertight) and report agreement and t error.
    #[arg(long)]
    oracle: bool,
    /// Trace the rays once, untimed, before the timed trace, so that the
    /// figure is that of a warm query (caches, memory pages, allocator and
    /// driver state already set up), as in benchmarks that warm up first.
    #[arg(long)]
    warmup: bool,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    adapter: AdapterArgs,
}

#[derive(Args)]
struct BenchArgs {
    /// Scene files or OBJ models [default: the OBJ models in
    /// ../shared/models when present, else the bundled bunny_lowres and
    /// dragon_res4 (assets/scenes/meshes); with --time-vs-error, the
    /// bundled scenes edge_cases, spheres and triangle_oblique. The
    /// bundled files are looked for in the working folder, then the
    /// executable's and those above it (a checkout's target/release)].
    inputs: Vec<PathBuf>,
    /// Measure run time against error over spp, intersection test, device
    /// and precision, and the skips (BVH, specialisation).
    #[arg(long)]
    time_vs_error: bool,
    /// Write every measured point as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write plots (PNG and SVG) into this folder.
    #[arg(long)]
    plot: Option<PathBuf>,
    #[arg(long, value_enum, default_value = "both")]
    device: BenchDevice,
    /// How rays find their hits [default: each scene's render.accel, else
    /// bvh]; `hardware` measures the GPU's ray queries (docs/hardware-rays.md).
    #[arg(long, value_enum)]
    accel: Option<AccelArg>,
    /// Image side for OBJ models (pixels).
    #[arg(long, default_value_t = 1024)]
    size: u32,
    /// Timed runs per measurement (median), after one warm-up; fewer (at
    /// least one) where they would take more than 4 s.
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Samples per pixel to measure (--time-vs-error).
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16")]
    spp_list: Vec<u32>,
    /// Samples per pixel of the converged f64 reference [default: 4 × the largest of --spp-list].
    #[arg(long)]
    reference_spp: Option<u32>,
    /// With --time-vs-error: also name the cheapest measured setting whose RMSE is at most this.
    #[arg(long)]
    target_error: Option<f64>,
    #[command(flatten)]
    adapter: AdapterArgs,
}

#[derive(Args)]
struct CameraRaysArgs {
    scene: PathBuf,
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    view: ViewOptions,
}

/// `lambert diff`'s exit code for an error (as diff(1)): 1 means only that
/// the images differ.
pub const DIFF_ERROR: u8 = 2;

pub fn run() -> Result<ExitCode> {
    let cli = Cli::parse();
    let quiet = cli.quiet;
    match cli.command {
        Command::Render(args) => render(&args, quiet),
        Command::Diff(args) => diff(&args, quiet).or_else(|e| {
            eprintln!("error: {e}");
            Ok(ExitCode::from(DIFF_ERROR))
        }),
        Command::Trace(args) => trace(&args, quiet),
        Command::CameraRays(args) => camera_rays(&args, quiet),
        Command::Query(args) => query::query(&args, quiet),
        Command::Info(args) => match &args.model {
            Some(model) => info::model_info(model, args.camera.as_deref()),
            None => info::info(&args.adapter),
        },
        Command::Bench(args) => benchmark::bench(&args, quiet),
        Command::Merge(args) => merge(&args, quiet),
        Command::View(args) => view::run(args, quiet),
    }
}

/// Loading's warnings, each on its own line, and what the direct
/// integrator leaves out of the scene where it renders it (`rendered_by`;
/// None for no render).
fn print_warnings(scene: &Scene, rendered_by: Option<Integrator>, quiet: bool) {
    if !quiet {
        let ignored = (rendered_by == Some(Integrator::Direct))
            .then(|| scene.ignored_by_direct())
            .flatten();
        for warning in scene.warnings().iter().cloned().chain(ignored) {
            eprintln!("warning: {warning}");
        }
    }
}

/// `flag`'s `value`, which must be a positive `what` and cannot be
/// combined with a turntable.
fn check_positive_alone(value: f64, flag: &str, what: &str, turntable: bool) -> Result<()> {
    if !(value.is_finite() && value > 0.0) {
        return Err(Error::Usage(format!(
            "{flag} {value} must be a positive {what}"
        )));
    }
    if turntable {
        return Err(Error::Usage(format!(
            "{flag} and --turntable cannot be combined"
        )));
    }
    Ok(())
}

fn render(args: &RenderArgs, quiet: bool) -> Result<ExitCode> {
    let turntable = args.turntable.is_some();
    if let Some(target) = args.target_error {
        check_positive_alone(target, "--target-error", "number", turntable)?;
        if !(2..=MAX_SPP).contains(&args.max_spp) {
            return Err(Error::Usage(format!(
                "--max-spp {} must be between 2 and {MAX_SPP}",
                args.max_spp
            )));
        }
    }
    if let Some(budget) = args.time_budget {
        check_positive_alone(budget, "--time-budget", "number of seconds", turntable)?;
    }
    if let Some(tile) = &args.tile {
        return render_part(args, tile, quiet);
    }
    if let Some(frames) = args.turntable {
        return turntable::turntable(args, frames, quiet);
    }
    let aovs = match &args.aov {
        Some(list) => Aov::parse_list(list).map_err(|e| Error::Usage(format!("--aov: {e}")))?,
        None => Vec::new(),
    };
    let aov_paths: Vec<PathBuf> = aovs.iter().map(|a| a.path_beside(&args.output)).collect();
    let outputs: Vec<&Path> = std::iter::once(args.output.as_path())
        .chain(aov_paths.iter().map(PathBuf::as_path))
        .collect();
    let start = Instant::now();
    let (scene, settings) = load_for(&args.input, &outputs, quiet)?;
    let load = start.elapsed();
    let sampling = match (args.time_budget, args.target_error) {
        (Some(budget), _) => Sampling::Budget(budget),
        (None, Some(target_error)) => Sampling::Adaptive {
            target_error,
            max_spp: args.max_spp,
        },
        (None, None) => Sampling::Fixed,
    };
    let job = ImageJob {
        output: &args.output,
        device: args.input.device.into(),
        adapter: &args.input.adapter.request(),
        sampling,
        aovs: &aovs,
    };
    let report = jobs::render_image(scene, &settings, &job, progress_bar::unless_quiet(quiet))?;
    if !quiet {
        print_image_report(&report, job.sampling, load);
    }
    Ok(ExitCode::SUCCESS)
}

/// `lambert render`'s report of one image.
fn print_image_report(report: &ImageReport, sampling: Sampling, load: Duration) {
    if let Some(budget) = &report.budget {
        eprintln!(
            "time budget: {} spp; expected RMSE from sampling noise {}",
            budget.plan.spp,
            match budget.expected_rmse {
                Some(noise) => format!("{noise:.3e}"),
                None => "unknown at 1 spp".to_string(),
            }
        );
    }
    if let (Some(adaptive), Sampling::Adaptive { target_error, .. }) = (&report.adaptive, sampling)
    {
        eprintln!(
            "adaptive: {:.1} samples per pixel on average ({} samples); pixels refined per pass {:?}; {} pixels still above {} at {} spp; expected RMSE from sampling noise {:.3e}",
            adaptive.mean_spp,
            adaptive.total_samples,
            adaptive.refined_per_pass,
            adaptive.above_target,
            target_error,
            adaptive.max_spp,
            adaptive.expected_rmse
        );
    }
    let bvh = &report.bvh;
    eprintln!(
        "wrote {} ({}×{}, {} primitives)",
        report.output.display(),
        report.width,
        report.height,
        report.primitives
    );
    eprintln!(
        "BVH: {} nodes, depth {}, SAH cost {:.1}, built in {} (part of load), {:.1} MiB on the device",
        bvh.nodes,
        bvh.depth,
        bvh.sah_cost,
        seconds(bvh.build_time),
        bvh.device_bytes as f64 / (1 << 20) as f64
    );
    if let Some(rq) = &report.ray_queries {
        eprintln!(
            "ray queries: {} BLAS, {} geometries, triangles as {}, built in {} (part of upload)",
            rq.blases,
            rq.geometries,
            rq.triangles.name(),
            seconds(rq.build_time)
        );
    }
    let t = &report.timings;
    eprintln!(
        "time: load {}, upload {}, render {}, readback {}, write {}",
        seconds(load),
        seconds(report.upload),
        seconds(t.render),
        seconds(t.readback),
        seconds(report.write)
    );
    eprintln!(
        "{:.2} Mrays/s (primary rays, render stage)",
        report.mrays_per_second()
    );
    if let (Some(device), Some(rate)) = (t.device, report.device_mrays_per_second()) {
        eprintln!(
            "GPU time (timestamp queries): {}, {rate:.2} Mrays/s",
            seconds(device)
        );
    }
    if !report.aovs.is_empty() {
        let paths: Vec<String> = report
            .aovs
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        eprintln!(
            "first-hit outputs ({} on the CPU path): {}",
            seconds(report.aov_time),
            paths.join(", ")
        );
    }
}

/// `input`'s scene with its options applied to the scene's default
/// settings, for a command that writes `outputs`: `load_scene_for`.
fn load_for(input: &SceneArgs, outputs: &[&Path], quiet: bool) -> Result<(Scene, RenderSettings)> {
    load_scene_for(&input.scene, &input.options, outputs, quiet)
}

/// The scene at `path` with `options` applied to its default settings,
/// for a command that writes `outputs` (an image, a turntable's frames, a
/// screenshot, a heatmap, or none): the first output's name checked
/// (`check_output_path`: they share a folder) before the time a load
/// takes, then every output against the files the scene read; the
/// scene's warnings printed unless `quiet`.
fn load_scene_for(
    path: &Path,
    options: &RenderOptions,
    outputs: &[&Path],
    quiet: bool,
) -> Result<(Scene, RenderSettings)> {
    if let Some(first) = outputs.first() {
        check_output_path(first, &[path])?;
    }
    let (scene, settings) = options.load(path)?;
    for output in outputs {
        scene.check_output(output)?;
    }
    print_warnings(&scene, Some(settings.integrator), quiet);
    Ok((scene, settings))
}

/// An image output: a known format, writable, and none of `inputs`.
fn check_output_path(path: &Path, inputs: &[&Path]) -> Result<()> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("png" | "exr" | "pfm") => lambert::output::prepare_output_for(path, inputs),
        _ => Err(Error::Usage(format!(
            "{}: unknown image format; use .png, .exr or .pfm",
            path.display()
        ))),
    }
}

fn diff(args: &DiffArgs, quiet: bool) -> Result<ExitCode> {
    let heatmap: Vec<&Path> = args.heatmap.as_deref().into_iter().collect();
    let (scene, settings) =
        load_scene_for(&args.scene, &args.options, &heatmap, quiet || args.json)?;
    let scene = scene.with_settings(&settings);
    let tolerance = Tolerance {
        abs: args.tol_abs,
        rel: args.tol_rel,
        max_bad_fraction: args.max_bad,
        max_prim_mismatch_fraction: args.max_prim_mismatch,
    };
    let request = args.adapter.request();
    let view = &settings.view;
    let cpu = || cpu::render(&scene, view, Precision::F32, &Progress::hidden());
    let oracle = || {
        let oracle = oracle_scene(&scene);
        cpu::render(&oracle, view, Precision::F64, &Progress::hidden())
    };
    let (a, b) = match args.compare {
        // The CPU side traces the GPU's own BVH layout (its twin), so that
        // the two differ only where their arithmetic does.
        Comparison::GpuCpu => (
            render_gpu(&scene, view, &request)?,
            cpu::render_gpu_twin(&scene, view, &Progress::hidden()),
        ),
        Comparison::GpuOracle => (render_gpu(&scene, view, &request)?, oracle()),
        Comparison::CpuOracle => (cpu(), oracle()),
        Comparison::HardwareCpu => (
            jobs::render_hardware(&scene, view, &request)?,
            cpu::render_gpu_twin(&scene, view, &Progress::hidden()),
        ),
    };
    let stats = diff::compare(&a, &b, &tolerance)?;
    if let Some(path) = &args.heatmap {
        diff::heatmap(&a, &b, &tolerance).save(path)?;
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&stats).expect("stats serialise")
        );
    } else {
        println!("{stats}");
    }
    Ok(if stats.passed {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// What `lambert trace --json` prints.
#[derive(serde::Serialize)]
struct TraceReport {
    device: String,
    intersect: &'static str,
    any_hit: bool,
    rays: usize,
    hits: usize,
    /// Reading and checking the ray file.
    read_seconds: f64,
    /// The untimed warm-up trace's time, with --warmup.
    warmup_seconds: Option<f64>,
    trace_seconds: f64,
    /// Writing the hit file (atomically, synced to disk).
    write_seconds: f64,
    mrays_per_second: f64,
    oracle: Option<rays::Agreement>,
}

fn trace(args: &TraceArgs, quiet: bool) -> Result<ExitCode> {
    let inputs: Vec<&Path> = [&args.rays]
        .into_iter()
        .chain(&args.scene)
        .chain(&args.obj)
        .map(PathBuf::as_path)
        .collect();
    lambert::output::prepare_output_for(&args.output, &inputs)?;
    let start = Instant::now();
    let rays = rays::read_rays(&args.rays)?;
    let read_seconds = start.elapsed().as_secs_f64();
    let mut scene = match &args.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::from_objs(&args.obj)?,
    };
    scene.check_output(&args.output)?;
    let mut settings = scene.default_settings();
    args.options.apply(&mut scene, &mut settings)?;
    let intersect = settings.intersect;
    // Where a ray's f32 numbers limit its hits (docs/accuracy.md).
    if !quiet {
        for warning in scene.placement().ray_warnings(&rays) {
            eprintln!("warning: {warning}");
        }
    }
    let scene = Arc::new(scene.with_settings(&settings));
    let device = args.device.into();
    let (mut renderer, note) = Renderer::open(Arc::clone(&scene), device, &args.adapter.request())?;
    if let Some(note) = note.filter(|_| !quiet) {
        eprintln!("{note}");
    }
    renderer.prepare_trace(args.any_hit, intersect)?;
    let warmup_seconds = if args.warmup {
        let start = Instant::now();
        renderer.trace(&rays, args.any_hit, intersect)?;
        Some(start.elapsed().as_secs_f64())
    } else {
        None
    };
    let start = Instant::now();
    let hits = renderer.trace(&rays, args.any_hit, intersect)?;
    let elapsed = start.elapsed();
    let start = Instant::now();
    rays::write_hits(&args.output, &hits)?;
    let write_seconds = start.elapsed().as_secs_f64();
    let oracle = args.oracle.then(|| {
        let truth = cpu::trace_rays_f64(&oracle_scene(&scene), &rays, args.any_hit);
        rays::Agreement::measure(&hits, &truth)
    });
    let report = TraceReport {
        device: renderer.describe(),
        intersect: intersect.name(),
        any_hit: args.any_hit,
        rays: rays.len(),
        hits: hits.iter().filter(|h| h.prim != NO_HIT).count(),
        read_seconds,
        warmup_seconds,
        trace_seconds: elapsed.as_secs_f64(),
        write_seconds,
        mrays_per_second: rays.len() as f64 / elapsed.as_secs_f64() / 1e6,
        oracle,
    };
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).expect("report serialises")
        );
    }
    if !quiet {
        eprintln!(
            "traced {} rays ({}, {}) on {}: {} hit; {} ({:.2} Mrays/s); wrote {}; read {:.3} s, write {:.3} s",
            report.rays,
            report.intersect,
            if args.any_hit {
                "any hit"
            } else {
                "closest hit"
            },
            report.device,
            report.hits,
            seconds(elapsed),
            report.mrays_per_second,
            args.output.display(),
            read_seconds,
            write_seconds
        );
        if let Some(agreement) = &report.oracle {
            eprintln!("{agreement}");
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn camera_rays(args: &CameraRaysArgs, quiet: bool) -> Result<ExitCode> {
    lambert::output::prepare_output_for(&args.output, &[&args.scene])?;
    let (scene, settings) = args.view.load(&args.scene)?;
    scene.check_output(&args.output)?;
    let rays = rays::camera_rays_for(&scene, &settings.view.camera);
    rays::write_rays(&args.output, &rays)?;
    if !quiet {
        eprintln!(
            "wrote {} camera rays to {}",
            rays.len(),
            args.output.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}
