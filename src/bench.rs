//! Whole-render benchmarks (`lambert bench`): trace speed over a ladder of
//! models, and run time against error over the settings that trade one for
//! the other (docs/benchmarks.md).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use web_time::Instant;

use glam::Vec3;
use serde::Serialize;

use crate::adaptive::{AdaptiveSettings, render_adaptive};
use crate::camera::{Camera, View};
use crate::cpu::{self, Precision};
use crate::diff::{self, Tolerance};
use crate::error::{Error, Result};
use crate::gpu::{AdapterRequest, Gpu, GpuRenderer};
use crate::layout::{LIGHT_DIRECTIONAL, Light, NO_HIT, Ray};
use crate::output::Rendered;
use crate::probe;
use crate::progress::Progress;
use crate::render::{DeviceChoice, Renderer, open_gpu};
use crate::scene::{Accel, Intersect, Scene};

/// Time a measurement may take beyond its warm-up: slow points get fewer
/// timed runs (at least one), so that a large scene's sweep stays within
/// minutes.
const POINT_BUDGET: Duration = Duration::from_secs(4);

/// Median of up to `runs` timed calls after one timed warm-up (fewer when
/// they would exceed POINT_BUDGET).
pub fn median_time<T>(runs: usize, mut f: impl FnMut() -> Result<T>) -> Result<(Duration, T)> {
    let start = Instant::now();
    f()?;
    let warm_up = start.elapsed();
    let affordable = (POINT_BUDGET.as_secs_f64() / warm_up.as_secs_f64().max(1e-9)) as usize;
    let runs = runs.min(affordable).max(1);
    let mut times = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs {
        let start = Instant::now();
        last = Some(f()?);
        times.push(start.elapsed());
    }
    times.sort();
    Ok((times[times.len() / 2], last.expect("at least one run")))
}

/// A model loaded as a scene: framed by a camera looking at it from the
/// front (+z) and slightly above, lit by one directional light, shadows on.
pub fn scene_for_obj(path: &Path, size: u32) -> Result<Scene> {
    let mut scene = Scene::from_objs(&[path.to_path_buf()])?;
    let root = scene
        .bvh
        .bounds()
        .ok_or_else(|| Error::Usage(format!("{}: the model has no triangles", path.display())))?;
    let (lo, hi) = (root.min, root.max);
    let centre = (lo + hi) * 0.5;
    let radius = (hi - lo).length() * 0.5;
    let vfov: f32 = 30.0;
    let distance = radius / (vfov.to_radians() * 0.5).sin();
    let eye = centre + Vec3::new(0.0, 0.3, 1.0).normalize() * distance;
    scene.view.camera = Camera {
        eye: eye.as_dvec3().to_array(),
        look_at: centre.as_dvec3().to_array(),
        up: [0.0, 1.0, 0.0],
        vfov: vfov as f64,
        width: size,
        height: size,
    };
    scene.lights.push(Light {
        vector: Vec3::new(0.4, 0.8, 0.45).normalize().to_array(),
        kind: LIGHT_DIRECTIONAL,
        color: [3.0; 3],
        ..Light::default()
    });
    scene.ambient = [0.05; 3];
    scene.shadows = true;
    crate::camera::validate_camera(&scene.view.camera)
        .map_err(|e| Error::Usage(format!("{}: cannot frame the model: {e}", path.display())))?;
    Ok(scene)
}

/// A bench input: a scene file, or an OBJ framed by `scene_for_obj`.
pub fn load_input(path: &Path, size: u32) -> Result<Scene> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
    {
        scene_for_obj(path, size)
    } else {
        Scene::load(path)
    }
}

/// The source tree's root (the folder holding assets/scenes): the working
/// folder, else the executable's folder or one above it (target/release/
/// in a checkout), else where this binary was built from.
pub fn source_tree() -> Option<PathBuf> {
    let has_assets = |dir: &Path| dir.join("assets/scenes").is_dir();
    let exe = std::env::current_exe().ok();
    let from_exe = exe.iter().flat_map(|e| e.ancestors().skip(1));
    std::iter::once(Path::new("."))
        .chain(from_exe)
        .chain(std::iter::once(Path::new(env!("CARGO_MANIFEST_DIR"))))
        .find(|dir| has_assets(dir))
        .map(Path::to_path_buf)
}

/// The bundled models the ladder falls back on (in assets/scenes/meshes).
const BUNDLED_LADDER: [&str; 2] = ["bunny_lowres.obj", "dragon_res4.obj"];

/// `lambert bench`'s models when none are named: the OBJ models of
/// ../shared/models (from the working folder, else beside the source
/// tree), else the bundled ones of the source tree; empty where neither is
/// found.
pub fn default_inputs() -> Vec<PathBuf> {
    let tree = source_tree();
    let shared = std::iter::once(PathBuf::from("../shared/models"))
        .chain(tree.iter().map(|t| t.join("../shared/models")));
    for models in shared {
        let ladder = default_ladder(&models);
        if !ladder.is_empty() {
            return ladder;
        }
    }
    tree.map(|t| {
        BUNDLED_LADDER
            .iter()
            .map(|m| t.join("assets/scenes/meshes").join(m))
            .filter(|p| p.is_file())
            .collect()
    })
    .unwrap_or_default()
}

/// The default ladder: every OBJ model in `models` (normally
/// ../shared/models), smallest file first.
pub fn default_ladder(models: &Path) -> Vec<PathBuf> {
    let mut found: Vec<(u64, PathBuf)> = std::fs::read_dir(models)
        .into_iter()
        .flatten()
        .flatten()
        .map(|entry| entry.path())
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")))
        .filter_map(|p| Some((std::fs::metadata(&p).ok()?.len(), p)))
        .collect();
    found.sort();
    found.into_iter().map(|(_, p)| p).collect()
}

/// Which renderers a benchmark runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchDevices {
    /// The GPU adapter (any, lavapipe included) and the CPU path.
    Both,
    Gpu,
    Cpu,
}

impl BenchDevices {
    fn renderers(self, scene: &Arc<Scene>, request: &AdapterRequest) -> Result<Vec<Renderer>> {
        let devices = match self {
            BenchDevices::Both => &[DeviceChoice::Gpu, DeviceChoice::Cpu][..],
            BenchDevices::Gpu => &[DeviceChoice::Gpu],
            BenchDevices::Cpu => &[DeviceChoice::Cpu],
        };
        devices
            .iter()
            .map(|&device| Ok(Renderer::open(Arc::clone(scene), device, request)?.0))
            .collect()
    }
}

/// One model on one renderer.
#[derive(Clone, Debug, Serialize)]
pub struct LadderRow {
    pub model: String,
    pub triangles: usize,
    pub device: String,
    pub primary_rays: usize,
    pub primary_mrays_per_s: f64,
    pub shadow_rays: usize,
    pub shadow_mrays_per_s: f64,
    /// The same from the GPU's own timestamps (the dispatches alone, no
    /// upload or readback), where it has them; the median run's.
    pub primary_device_mrays_per_s: Option<f64>,
    pub shadow_device_mrays_per_s: Option<f64>,
    pub bvh_build_seconds: f64,
    pub bvh_nodes: usize,
    pub bvh_depth: usize,
    pub sah_cost: f64,
    /// Bytes of triangles, normals, BVH nodes and leaf blocks on the device.
    pub device_bytes: usize,
    pub device_bytes_per_triangle: f64,
}

/// Shadow rays of the primary hits towards the scene's first light, spawned
/// as `shade` spawns them.
pub fn shadow_rays(scene: &Scene, primary: &[Ray], hits: &[crate::layout::Hit]) -> Vec<Ray> {
    let kernel = cpu::f32::Kernel::new(scene);
    let Some(light) = scene.lights.first() else {
        return Vec::new();
    };
    primary
        .iter()
        .zip(hits)
        .filter(|(_, h)| h.prim != NO_HIT)
        .filter_map(|(r, h)| {
            let surface =
                kernel.surface_at(&cpu::f32::Ray::from_query(r), &cpu::f32::Hit::from_query(h));
            let origin = cpu::f32::offset_ray_origin(
                surface.position,
                surface.error,
                surface.geometric_normal,
            );
            let (dir, tmax) = if light.kind == LIGHT_DIRECTIONAL {
                (Vec3::from(light.vector), f32::INFINITY)
            } else {
                let d = Vec3::from(light.vector) - origin;
                (d / d.length(), d.length())
            };
            (surface.geometric_normal.dot(dir) > 0.0).then_some(Ray {
                origin: origin.to_array(),
                tmin: 0.0,
                dir: dir.to_array(),
                tmax,
            })
        })
        .collect()
}

/// Primary and shadow ray throughput of `scene` on each renderer.
pub fn ladder_rows(
    name: &str,
    scene: &Arc<Scene>,
    devices: BenchDevices,
    request: &AdapterRequest,
    runs: usize,
) -> Result<Vec<LadderRow>> {
    let primary = crate::rays::camera_rays(scene);
    let hits = cpu::trace_rays(scene, &primary, false);
    let shadow = shadow_rays(scene, &primary, &hits);
    let device_bytes = std::mem::size_of_val(scene.triangles.as_slice())
        + std::mem::size_of_val(scene.normals.as_slice())
        + scene.bvh.device_bytes();
    let mut rows = Vec::new();
    for mut renderer in devices.renderers(scene, request)? {
        renderer.prepare_trace(false, scene.intersect)?;
        renderer.prepare_trace(true, scene.intersect)?;
        let mut timed = |rays: &[Ray], any_hit: bool| {
            let mut device = Vec::new();
            let (wall, _) = median_time(runs, || {
                let hits = renderer.trace(rays, any_hit, scene.intersect);
                device.extend(renderer.trace_device_time());
                hits
            })?;
            // The warm-up's time left out, as the wall time leaves it.
            let mut device = device.split_off(1.min(device.len()));
            device.sort();
            let mrays = |t: std::time::Duration| rays.len() as f64 / t.as_secs_f64() / 1e6;
            Ok::<_, Error>((wall, device.get(device.len() / 2).map(|&t| mrays(t))))
        };
        let (t_primary, primary_device) = timed(&primary, false)?;
        let (t_shadow, shadow_device) = timed(&shadow, true)?;
        rows.push(LadderRow {
            model: name.to_string(),
            triangles: scene.triangles.len(),
            device: renderer.describe(),
            primary_rays: primary.len(),
            primary_mrays_per_s: primary.len() as f64 / t_primary.as_secs_f64() / 1e6,
            shadow_rays: shadow.len(),
            shadow_mrays_per_s: shadow.len() as f64 / t_shadow.as_secs_f64() / 1e6,
            primary_device_mrays_per_s: primary_device,
            shadow_device_mrays_per_s: shadow_device,
            bvh_build_seconds: scene.bvh.build_time.as_secs_f64(),
            bvh_nodes: scene.bvh.nodes.len(),
            bvh_depth: scene.bvh.depth(),
            sah_cost: scene.bvh.sah_cost(),
            device_bytes,
            device_bytes_per_triangle: device_bytes as f64 / scene.triangles.len().max(1) as f64,
        });
    }
    Ok(rows)
}

// ------------------------------------------------------------ time vs error

/// Where and in what precision a point renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Path32 {
    /// The GPU adapter, f32.
    GpuF32,
    /// The CPU reference, f32.
    CpuF32,
    /// The CPU oracle, f64.
    CpuF64,
}

/// One setting of the knobs, measured.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    pub scene: String,
    pub path: Path32,
    pub intersect: Intersect,
    pub spp: u32,
    pub accel: &'static str,
    /// "specialised" or "full" (GPU only; the CPU path has no variants).
    pub shader: &'static str,
    /// "uniform", or "adaptive" (spp is then the mean samples per pixel,
    /// rounded; `target_error` the threshold).
    pub sampling: &'static str,
    pub target_error: Option<f64>,
    pub mean_spp: f64,
    /// Median wall time of a render, seconds (GPU: dispatch and readback).
    pub seconds: f64,
    /// GPU time of the dispatches from timestamp queries (GPU path, where
    /// the adapter supports them; not for adaptive sampling's passes).
    pub gpu_seconds: Option<f64>,
    pub rmse: f64,
    pub psnr_db: Option<f64>,
    pub max_error: f32,
    pub mismatched_primitives: u64,
    /// Rays of the leak probe that escape, on this path with this test.
    pub leaks: usize,
    pub on_pareto_front: bool,
}

/// What `--time-vs-error` varies.
#[derive(Clone, Debug)]
pub struct Knobs {
    pub spp: Vec<u32>,
    pub reference_spp: u32,
    pub runs: usize,
    pub gpu: bool,
}

fn accel_name(accel: Accel) -> &'static str {
    match accel {
        Accel::Bvh => "bvh",
        Accel::BruteForce => "brute-force",
        Accel::Hardware => "hardware",
    }
}

/// Leak counts of each path and test on the probe meshes.
fn leaks(path: Path32, intersect: Intersect, request: &AdapterRequest) -> Result<usize> {
    let mut total = 0;
    for (triangles, rays) in probe::leak_probe() {
        let mut scene = Scene::from_triangles(triangles);
        scene.intersect = intersect;
        total += match path {
            Path32::CpuF32 => probe::count_misses(&cpu::trace_rays(&scene, &rays, false)),
            Path32::CpuF64 => cpu::trace_rays_f64(&scene, &rays, false)
                .iter()
                .filter(|h| h.prim == NO_HIT)
                .count(),
            Path32::GpuF32 => {
                let mut r = open_gpu(&scene, request)?;
                probe::count_misses(&r.trace_rays(&rays, false, scene.intersect)?)
            }
        };
    }
    Ok(total)
}

/// Renders `scene` at every setting of `knobs`, timing each and measuring
/// its error against a converged reference: the f64 oracle (watertight) at
/// `reference_spp` with another seed.
pub fn time_vs_error(
    name: &str,
    scene: &Arc<Scene>,
    knobs: &Knobs,
    request: &AdapterRequest,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Point>> {
    let mut reference_scene = Scene::clone(scene);
    reference_scene.intersect = Intersect::Watertight;
    let reference_view = View {
        spp: knobs.reference_spp,
        // Its own stream of samples: adaptive passes use seed + k·0x9e3779b9.
        seed: cpu::f32::pcg_hash(scene.view.seed ^ 0x5eed_5eed),
        ..scene.view.clone()
    };
    log(&format!(
        "{name}: reference = f64 oracle at {} spp",
        knobs.reference_spp
    ));
    let reference = cpu::render(
        &reference_scene,
        &reference_view,
        Precision::F64,
        &Progress::hidden(),
    );
    let tolerance = Tolerance::default();
    let mut paths = vec![Path32::CpuF32, Path32::CpuF64];
    if knobs.gpu {
        paths.insert(0, Path32::GpuF32);
    }
    let mut points = Vec::new();
    for &path in &paths {
        for intersect in Intersect::ALL {
            let leak_count = leaks(path, intersect, request)?;
            for &spp in &knobs.spp {
                let mut s = Scene::clone(scene);
                s.intersect = intersect;
                let view = View {
                    spp,
                    ..scene.view.clone()
                };
                let mut variants = vec![(Accel::Bvh, "specialised")];
                // The skips change time, not the image: measured once, at
                // the default test and the first spp of the list.
                if intersect == Intersect::Watertight && spp == knobs.spp[0] {
                    variants.push((Accel::BruteForce, "specialised"));
                    if path == Path32::GpuF32 {
                        variants.push((Accel::Bvh, "full"));
                    }
                }
                for (accel, shader) in variants {
                    s.accel = accel;
                    let (seconds, device, image) =
                        time_render(&s, &view, path, shader == "full", knobs.runs, request)?;
                    let stats = diff::compare(&image, &reference, &tolerance)?;
                    let point = Point {
                        scene: name.to_string(),
                        path,
                        intersect,
                        spp,
                        accel: accel_name(accel),
                        shader: if path == Path32::GpuF32 { shader } else { "-" },
                        sampling: "uniform",
                        target_error: None,
                        mean_spp: spp as f64,
                        seconds: seconds.as_secs_f64(),
                        gpu_seconds: device.map(|d| d.as_secs_f64()),
                        rmse: stats.rmse,
                        psnr_db: stats.psnr_db,
                        max_error: stats.max_abs,
                        mismatched_primitives: stats.prim_mismatches,
                        leaks: leak_count,
                        on_pareto_front: false,
                    };
                    log(&format!(
                        "  {:?} {:<16} spp {:>3} {:<11} {:<11} {:>9.4} s  RMSE {:.3e}",
                        point.path,
                        intersect.name(),
                        spp,
                        point.accel,
                        point.shader,
                        point.seconds,
                        point.rmse
                    ));
                    points.push(point);
                }
            }
        }
    }
    // Adaptive sampling against uniform, on the f32 paths with the default
    // test: thresholds at which the uniform points' errors lie.
    for &path in paths.iter().filter(|&&p| p != Path32::CpuF64) {
        let base = 4;
        let max_spp = 4 * knobs.spp.iter().max().copied().unwrap_or(1).max(base);
        for target in [0.04, 0.02, 0.01, 0.005] {
            let settings = AdaptiveSettings {
                target_error: target,
                base_spp: base,
                max_spp,
            };
            let device = match path {
                Path32::GpuF32 => DeviceChoice::Gpu,
                _ => DeviceChoice::Cpu,
            };
            let (mut renderer, _) = Renderer::open(Arc::clone(scene), device, request)?;
            let (seconds, (image, report)) = median_time(knobs.runs, || {
                render_adaptive(&mut renderer, &scene.view, settings)
            })?;
            let stats = diff::compare(&image, &reference, &tolerance)?;
            let point = Point {
                scene: name.to_string(),
                path,
                intersect: scene.intersect,
                spp: report.mean_spp.round() as u32,
                accel: accel_name(scene.accel),
                shader: if path == Path32::GpuF32 {
                    "specialised"
                } else {
                    "-"
                },
                sampling: "adaptive",
                target_error: Some(target),
                mean_spp: report.mean_spp,
                seconds: seconds.as_secs_f64(),
                gpu_seconds: None,
                rmse: stats.rmse,
                psnr_db: stats.psnr_db,
                max_error: stats.max_abs,
                mismatched_primitives: stats.prim_mismatches,
                leaks: leaks(path, scene.intersect, request)?,
                on_pareto_front: false,
            };
            log(&format!(
                "  {:?} adaptive E={target:<6} mean spp {:>6.2} {:>9.4} s  RMSE {:.3e} (expected {:.3e})",
                path, report.mean_spp, point.seconds, point.rmse, report.expected_rmse
            ));
            points.push(point);
        }
    }
    mark_pareto_front(&mut points);
    Ok(points)
}

/// Median wall time of a render of `scene` seen from `view`, the device
/// time of the last run (GPU with timestamp queries only), and its image.
fn time_render(
    scene: &Scene,
    view: &View,
    path: Path32,
    full_shader: bool,
    runs: usize,
    request: &AdapterRequest,
) -> Result<(Duration, Option<Duration>, Rendered)> {
    let cpu = |precision| {
        let (t, image) = median_time(runs, || {
            Ok(cpu::render(scene, view, precision, &Progress::hidden()))
        })?;
        Ok((t, None, image))
    };
    match path {
        Path32::GpuF32 => {
            let mut r = if full_shader {
                // `--device gpu`'s adapter, with the unspecialised shader.
                GpuRenderer::with_full_shader(Gpu::open(request, false)?, scene)?
            } else {
                open_gpu(scene, request)?
            };
            r.prepare_render()?;
            let (t, (image, timings)) = median_time(runs, || r.render(view, &Progress::hidden()))?;
            Ok((t, timings.device, image))
        }
        Path32::CpuF32 => cpu(Precision::F32),
        Path32::CpuF64 => cpu(Precision::F64),
    }
}

/// A point is on the front when no other point is both no slower and no
/// less accurate (by RMSE), and better in one of the two. RMSEs within 0.1%
/// count as equal: below that, settings differ by rounding, not accuracy.
pub fn mark_pareto_front(points: &mut [Point]) {
    let no_worse = |q: f64, p: f64| q <= p * 1.001;
    let dominated: Vec<bool> = points
        .iter()
        .map(|p| {
            points.iter().any(|q| {
                q.scene == p.scene
                    && q.seconds <= p.seconds
                    && no_worse(q.rmse, p.rmse)
                    && (q.seconds < p.seconds || q.rmse < p.rmse / 1.001)
            })
        })
        .collect();
    for (p, d) in points.iter_mut().zip(dominated) {
        p.on_pareto_front = !d;
    }
}

/// The cheapest measured setting whose error is at most `target` RMSE.
pub fn cheapest_within(points: &[Point], target: f64) -> Option<&Point> {
    points
        .iter()
        .filter(|p| p.rmse <= target)
        .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
}

pub fn check_spp_list(list: &[u32]) -> Result<()> {
    if list.is_empty() {
        return Err(Error::Usage("--spp-list needs at least one value".into()));
    }
    for &spp in list {
        crate::limits::validate_spp(spp).map_err(|e| Error::Usage(format!("--spp-list: {e}")))?;
    }
    Ok(())
}
