//! The hardware path (`--accel hardware`, docs/hardware-rays.md) against
//! the compute path and the CPU twin: hits, leaks, renders, alpha masks,
//! rays the hardware cannot take, the fallbacks and their notes, the
//! command line and the viewer. Each test needs a device with ray queries
//! (`common::hardware::ray_query_gpu`: on CI, Mesa 25's lavapipe, unpacked
//! privately by scripts/mesa-rt). Every test prints its figures.

mod common;
#[path = "common/viewer.rs"]
mod viewer;

use common::hardware::ray_query_gpu;
use common::stress::*;
use common::*;
use glam::{DVec3, Vec3};
use lambert::Scene;
use lambert::cpu;
use lambert::diff::{Tolerance, compare};
use lambert::gpu::{Gpu, GpuRenderer, ShadowDispatch, TriangleGeometry};
use lambert::layout::{Hit, NO_HIT, Ray};
use lambert::output::Rendered;
use lambert::probe::Rng;
use lambert::progress::Progress;
use lambert::render::Renderer;
use lambert::scene::{Accel, Integrator, Intersect, RenderSettings};
use std::sync::Arc;

/// `scene` as `accel` traces it.
fn with_accel(scene: &Scene, accel: Accel) -> Scene {
    let settings = RenderSettings {
        accel,
        ..scene.default_settings()
    };
    scene.clone().with_settings(&settings)
}

/// A renderer of `scene` through ray queries on `gpu`, which has them.
fn hardware(gpu: &Gpu, scene: &Scene) -> GpuRenderer {
    let renderer = GpuRenderer::new(gpu.clone(), &with_accel(scene, Accel::Hardware))
        .expect("the scene uploads");
    assert!(
        renderer.ray_queries().is_some(),
        "no ray queries: {:?}",
        renderer.accel_note()
    );
    renderer
}

/// A renderer of `scene` through the compute BVH on `gpu`.
fn compute(gpu: &Gpu, scene: &Scene) -> GpuRenderer {
    GpuRenderer::new(gpu.clone(), &with_accel(scene, Accel::Bvh)).expect("the scene uploads")
}

fn trace(renderer: &mut GpuRenderer, scene: &Scene, rays: &[Ray], any_hit: bool) -> Vec<Hit> {
    renderer
        .trace_rays(rays, any_hit, scene.default_settings().intersect)
        .expect("the trace runs")
}

/// How the hardware's closest hits compare with the CPU twin's.
#[derive(Debug, Default)]
struct Agreement {
    rays: usize,
    /// Both miss, or the same primitive with the same bits of (t, u, v).
    identical: usize,
    /// The same primitive, (t, u, v) the hardware's own: the exact test
    /// missed the triangle the hardware hit (the largest relative
    /// difference of t in `worst_t`).
    hardware_only: usize,
    /// Another primitive at a distance within TIE of the CPU's: a tie, as
    /// where rays run along a shared edge.
    ties: usize,
    /// A hit where the other misses, or another primitive farther than a
    /// tie: what the test fails on.
    disagree: Vec<String>,
    worst_t: f64,
}

/// Two hits at distances this close (relative) are a tie: either
/// primitive is the nearest, within the f32 rounding of either distance
/// (2⁻¹⁶, many ulps: a tie's two triangles round their shared point
/// differently).
const TIE: f64 = 1.0 / 65536.0;

fn agreement(hardware: &[Hit], cpu: &[Hit]) -> Agreement {
    let mut a = Agreement {
        rays: cpu.len(),
        ..Agreement::default()
    };
    for (i, (h, c)) in hardware.iter().zip(cpu).enumerate() {
        let relative = (h.t as f64 - c.t as f64).abs() / (c.t as f64).abs().max(1e-30);
        if h.prim == NO_HIT && c.prim == NO_HIT || h == c {
            a.identical += 1;
        } else if h.prim == c.prim && relative <= TIE {
            a.hardware_only += 1;
            a.worst_t = a.worst_t.max(relative);
        } else if h.prim != NO_HIT && c.prim != NO_HIT && relative <= TIE {
            a.ties += 1;
            a.worst_t = a.worst_t.max(relative);
        } else {
            a.disagree
                .push(format!("ray {i}: hardware {h:?}, CPU {c:?}"));
        }
    }
    a
}

/// Rays of every kind through `scene`'s bounds: its camera's, and random
/// ones from inside and around the bounds in random directions.
fn ray_set(scene: &Scene, rng: &mut Rng, random: usize) -> Vec<Ray> {
    let camera = &scene.view().camera;
    let camera = camera.resized(Some(camera.width.min(256)), None).unwrap();
    let mut rays = lambert::rays::camera_rays_for(scene, &camera);
    let (lo, hi) = bounds(scene);
    let centre = (lo + hi) * 0.5;
    let size = (hi - lo).max_element().max(1e-3);
    for _ in 0..random {
        let origin = centre + (DVec3::new(rng.unit(), rng.unit(), rng.unit()) - 0.5) * size * 1.5;
        rays.push(ray(origin.as_vec3(), rng.direction().as_vec3()));
    }
    rays
}

/// The scene's primitives' bounds (world frame).
fn bounds(scene: &Scene) -> (DVec3, DVec3) {
    let offset = scene.offset();
    let mut points: Vec<DVec3> = scene
        .triangles()
        .iter()
        .flat_map(|t| [t.v0, t.v1, t.v2])
        .map(|v| Vec3::from(v).as_dvec3() + offset)
        .collect();
    for s in scene.spheres() {
        let c = Vec3::from(s.center).as_dvec3() + offset;
        points.push(c - s.radius as f64);
        points.push(c + s.radius as f64);
    }
    let lo = points.iter().fold(DVec3::MAX, |a, &b| a.min(b));
    let hi = points.iter().fold(DVec3::MIN, |a, &b| a.max(b));
    (lo, hi)
}

const SCENES: [&str; 6] = [
    "scenes/bunny.toml",
    "scenes/spheres.toml",
    "scenes/cornell.toml",
    "scenes/edge_cases.toml",
    "scenes/dragon.toml",
    "scenes/meshes/textured.glb",
];

/// Closest and any hits through ray queries agree with the CPU twin's on
/// the bundled scenes (spheres, alpha masks, shared edges) and camera and
/// random rays: the same primitive with the same bits (the hardware's hit
/// refined by the exact test), or a tie within TIE; any hit: the same
/// rays blocked.
/// Both ways of giving the driver triangles are measured; the device's
/// default is held to it.
#[test]
fn hits_agree_with_the_cpu_twin() {
    let Some(gpu) = ray_query_gpu("hits_agree_with_the_cpu_twin") else {
        return;
    };
    let default = TriangleGeometry::for_gpu(&gpu).unwrap();
    for geometry in ["triangles", "boxes"] {
        let mut gpu = gpu.clone();
        gpu.options.ray_query_geometry = Some(geometry.to_string());
        let failures = hits_agree(&gpu);
        println!("{failures:#?}");
        if TriangleGeometry::for_gpu(&gpu).unwrap() == default {
            assert!(
                failures.is_empty(),
                "triangles as {geometry}: {failures:#?}"
            );
        }
    }
}

/// The comparison on `gpu`, its table printed: what disagrees.
fn hits_agree(gpu: &Gpu) -> Vec<String> {
    let what = gpu
        .options
        .ray_query_geometry
        .as_deref()
        .unwrap_or("default");
    println!("triangles given as {what}:");
    let mut rng = Rng(47);
    let mut failures = Vec::new();
    println!(
        "{:<28} {:>7} {:>9} {:>8} {:>6} {:>9} {:>10} {:>9}",
        "scene", "rays", "identical", "hw-only", "ties", "disagree", "worst Δt", "any-hit Δ"
    );
    for name in SCENES {
        let scene = Scene::load(&asset(name)).unwrap();
        let rays = ray_set(&scene, &mut rng, 20_000);
        let mut renderer = hardware(gpu, &scene);
        let a = agreement(
            &trace(&mut renderer, &scene, &rays, false),
            &cpu::trace_rays(&scene, &rays, false),
        );
        let blocked = |hits: Vec<Hit>| hits.iter().map(|h| h.prim != NO_HIT).collect::<Vec<_>>();
        let any_hw = blocked(trace(&mut renderer, &scene, &rays, true));
        let any_cpu = blocked(cpu::trace_rays(&scene, &rays, true));
        let any_differ = any_hw.iter().zip(&any_cpu).filter(|(h, c)| h != c).count();
        println!(
            "{name:<28} {:>7} {:>9} {:>8} {:>6} {:>9} {:>10.2e} {:>9}",
            a.rays,
            a.identical,
            a.hardware_only,
            a.ties,
            a.disagree.len(),
            a.worst_t,
            any_differ
        );
        failures.extend(a.disagree.iter().take(4).map(|d| format!("{name}: {d}")));
        if any_differ > 0 {
            failures.push(format!("{name}: {any_differ} any-hit queries differ"));
        }
    }
    failures
}

/// The stress suite's probes through ray queries: its leak probe (closed
/// meshes at three offsets, rays from inside aimed at every vertex and
/// edge; tests/stress.rs's seeds, so the same rays) and its
/// self-intersection probe (rays spawned from hits as shading spawns
/// them, over triangles at scales 1e-8 to 1e8). Hardware intersection is
/// not the watertight test: a leak here would be a defect of the path.
/// Both ways of giving the driver triangles are measured; the device's
/// default (`TriangleGeometry::for_gpu`: boxes on lavapipe, whose own
/// tests leak) must not leak.
#[test]
fn no_ray_leaks_through_ray_queries() {
    let Some(gpu) = ray_query_gpu("no_ray_leaks_through_ray_queries") else {
        return;
    };
    let default = TriangleGeometry::for_gpu(&gpu).unwrap();
    for geometry in ["triangles", "boxes"] {
        let mut gpu = gpu.clone();
        gpu.options.ray_query_geometry = Some(geometry.to_string());
        let (leaks, own) = probe_leaks(&gpu);
        if TriangleGeometry::for_gpu(&gpu).unwrap() == default {
            assert_eq!(leaks, 0, "rays leaked through ray queries ({geometry})");
            assert_eq!(own, 0, "spawned rays hit their own triangle ({geometry})");
        }
    }
}

/// The probes on `gpu`: rays that leaked, and spawned rays that hit
/// their own triangle.
fn probe_leaks(gpu: &Gpu) -> (usize, usize) {
    let what = gpu
        .options
        .ray_query_geometry
        .as_deref()
        .unwrap_or("default");
    println!(
        "leaks through ray queries, triangles given as {what} (rays from inside that escape):"
    );
    let mut rng = Rng(11);
    let mut leaks = 0;
    for (name, offset, scene, rays) in leak_cases(&mut rng) {
        let mut renderer = hardware(gpu, &scene);
        let closest = misses(&trace(&mut renderer, &scene, &rays, false));
        let any = misses(&trace(&mut renderer, &scene, &rays, true));
        println!(
            "  {name:<14} {:>22} {:>6} rays: {closest} closest, {any} any hit",
            format!("{offset}"),
            rays.len()
        );
        leaks += closest + any;
    }
    let mut rng = Rng(5);
    let triangles = random_scale_triangles(&mut rng, 3000);
    let scene = scene_of(triangles.clone(), vec![]);
    let primary = rays_at_fronts(&triangles, &mut rng);
    let (spawned, sources) = spawned_rays(&scene, &primary, &mut rng);
    let hits = trace(&mut hardware(gpu, &scene), &scene, &spawned, false);
    let own = hits
        .iter()
        .zip(&sources)
        .filter(|(h, s)| h.prim == **s)
        .count();
    println!("  self-hits of spawned rays: {own} of {}", spawned.len());
    (leaks, own)
}

/// The stress suite's lit plane at every scale and offset, its shadow
/// rays through ray queries: no pixel darker than k·E·cos θ.
#[test]
fn a_lit_plane_has_no_shadow_acne_through_ray_queries() {
    let Some(gpu) = ray_query_gpu("a_lit_plane_has_no_shadow_acne_through_ray_queries") else {
        return;
    };
    for (scale, translate) in [
        (1e-6, [0.0; 3]),
        (1.0, [0.0; 3]),
        (1e6, [0.0; 3]),
        (1.0, [1e5, 1e5, 1e5]),
        (1e3, [1.5e5, 1.2e3, -2.2e5]),
    ] {
        let scene = lit_plane(scale, translate, Intersect::default());
        let image = render(&mut hardware(&gpu, &scene), &scene);
        let on_plane: Vec<f32> = (image.image.rgb.iter().zip(&image.prims))
            .filter(|(_, p)| **p != NO_HIT)
            .map(|(c, _)| c[1])
            .collect();
        let acne = on_plane.iter().filter(|&&v| (v - 0.5).abs() > 1e-5).count();
        println!(
            "scale {scale:e}, translate {translate:?}: {acne} of {} acne",
            on_plane.len()
        );
        assert!(on_plane.len() > 1000, "the camera misses the plane");
        assert_eq!(
            acne, 0,
            "shadow acne at scale {scale}, translate {translate:?}"
        );
    }
}

fn render(renderer: &mut GpuRenderer, scene: &Scene) -> Rendered {
    renderer
        .render(scene.view(), &Progress::hidden())
        .expect("the render runs")
        .0
}

/// `scene` with `integrator` and `spp` samples a pixel, at most 160 pixels wide.
fn variant(scene: &Scene, integrator: Integrator, spp: u32) -> Scene {
    let mut settings = scene.default_settings();
    settings.integrator = integrator;
    settings.view.spp = spp;
    let width = settings.view.camera.width.min(160);
    settings.view.camera = settings.view.camera.resized(Some(width), None).unwrap();
    scene.clone().with_settings(&settings)
}

/// Renders through ray queries agree with the compute path's on the same
/// device, as `lambert diff` judges them (1e-4 + 1e-4 of the value, at
/// most 0.1% of pixels beyond it) but for the share of pixels whose camera
/// ray hits another primitive, allowed 1% here: where two primitives tie
/// at the same distance (coincident triangles, shared edges),
/// `hits_agree_with_the_cpu_twin` shows either may come first. Direct
/// light (megakernel and wavefront, whose shadow rays are queries that end
/// at the first hit), path tracing, alpha masks.
#[test]
fn renders_agree_with_the_compute_path() {
    let Some(gpu) = ray_query_gpu("renders_agree_with_the_compute_path") else {
        return;
    };
    println!(
        "{:<28} {:<22} {:>9} {:>11} {:>11}",
        "scene", "render", "PSNR dB", "beyond tol", "other prim"
    );
    for name in SCENES.iter().filter(|n| !n.contains("dragon")) {
        let loaded = Scene::load(&asset(name)).unwrap();
        // The wavefront shades as the direct integrator does: a path is
        // the megakernel's.
        let direct = [ShadowDispatch::Megakernel, ShadowDispatch::Wavefront];
        let mut variants = vec![(
            "direct",
            variant(&loaded, Integrator::Direct, 1),
            &direct[..],
        )];
        if name.contains("cornell") || name.contains("spheres") {
            let path = variant(&loaded, Integrator::Path, 4);
            variants.push(("path, 4 spp", path, &direct[..1]));
        }
        for (what, scene, dispatches) in variants {
            let mut hw = hardware(&gpu, &scene);
            let mut bvh = compute(&gpu, &scene);
            for &dispatch in dispatches {
                hw.shadow_dispatch = dispatch;
                bvh.shadow_dispatch = dispatch;
                let tolerance = Tolerance {
                    max_prim_mismatch_fraction: 0.01,
                    ..Tolerance::default()
                };
                let (a, b) = (render(&mut hw, &scene), render(&mut bvh, &scene));
                let stats = compare(&a, &b, &tolerance).unwrap();
                println!(
                    "{name:<28} {:<22} {:>9.1} {:>11} {:>11}",
                    format!("{what}, {dispatch:?}"),
                    stats.psnr_db.unwrap_or(f64::INFINITY),
                    stats.beyond_tolerance,
                    stats.prim_mismatches
                );
                assert!(stats.passed, "{name}, {what}, {dispatch:?}:\n{stats}");
            }
        }
    }
}

/// Crossing counts and lists through ray queries (where the triangles
/// are boxes; else through the compute BVH) are the CPU twin's, exactly:
/// the leak probe's rays from inside the closed meshes cross once each,
/// and the bunny's camera and random rays as often as on the CPU.
#[test]
fn crossings_agree_with_the_cpu_twin() {
    let Some(gpu) = ray_query_gpu("crossings_agree_with_the_cpu_twin") else {
        return;
    };
    let mut rng = Rng(11);
    let mut cases: Vec<(String, Scene, Vec<Ray>)> = leak_cases(&mut rng)
        .into_iter()
        .map(|(name, offset, scene, rays)| (format!("{name} at {offset}"), scene, rays))
        .collect();
    let bunny = load("bunny");
    let rays = ray_set(&bunny, &mut rng, 5000);
    cases.push(("bunny.toml".to_string(), bunny, rays));
    for geometry in ["boxes", "triangles"] {
        let mut gpu = gpu.clone();
        gpu.options.ray_query_geometry = Some(geometry.to_string());
        for (name, scene, rays) in &cases {
            let mut hw = Renderer::Gpu(Box::new(hardware(&gpu, scene)));
            let mut cpu = Renderer::Cpu(Arc::new(scene.clone()));
            let counts = hw.count_intersections(rays).unwrap();
            assert_eq!(
                counts,
                cpu.count_intersections(rays).unwrap(),
                "{name}, {geometry}"
            );
            let lists = hw.list_intersections(rays).unwrap();
            assert_eq!(
                lists,
                cpu.list_intersections(rays).unwrap(),
                "{name}, {geometry}"
            );
            let total: u64 = counts.iter().map(|&c| c as u64).sum();
            println!(
                "{name:<40} as {geometry:<9} {} rays, {total} crossings: the CPU's",
                rays.len()
            );
        }
    }
}

/// Rays that Vulkan's ray queries may not take (a NaN or an infinity,
/// tmin < 0 or > tmax, a zero direction) go through the compute BVH, and
/// extreme but valid ones (directions of 1e-30 or 1e30, tmax infinite or
/// NaN) through the hardware: every answer the CPU twin's.
#[test]
fn rays_the_hardware_cannot_take_are_answered_as_on_the_cpu() {
    let Some(gpu) = ray_query_gpu("rays_the_hardware_cannot_take_are_answered_as_on_the_cpu")
    else {
        return;
    };
    let scene = load("bunny");
    let (lo, hi) = bounds(&scene);
    let centre = ((lo + hi) * 0.5).as_vec3();
    let outside = centre + Vec3::new(0.0, 0.0, 3.0 * (hi - lo).max_element() as f32);
    let at = |origin: Vec3, tmin: f32, dir: Vec3, tmax: f32| Ray {
        origin: origin.to_array(),
        tmin,
        dir: dir.to_array(),
        tmax,
    };
    let toward = centre - outside;
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let rays = [
        at(outside, 0.0, toward, inf),
        at(outside, -2.0, toward, inf),
        at(centre, -inf, toward, inf),
        at(outside, 0.9, toward, 0.5),
        at(outside, nan, toward, inf),
        at(outside, 0.0, toward, nan),
        at(outside, inf, toward, inf),
        at(Vec3::new(nan, 0.0, 0.0), 0.0, toward, inf),
        at(Vec3::new(inf, 0.0, 0.0), 0.0, toward, inf),
        at(outside, 0.0, Vec3::new(0.0, nan, -1.0), inf),
        at(outside, 0.0, Vec3::new(0.0, 0.0, -inf), inf),
        at(outside, 0.0, Vec3::ZERO, inf),
        at(outside, 0.0, toward * 1e-30, inf),
        at(outside, 0.0, toward * 1e30, inf),
        at(outside, 0.0, toward * 1e-30, 1e29),
    ];
    let mut renderer = hardware(&gpu, &scene);
    for any_hit in [false, true] {
        let hw = trace(&mut renderer, &scene, &rays, any_hit);
        let cpu = cpu::trace_rays(&scene, &rays, any_hit);
        for (i, ((h, c), r)) in hw.iter().zip(&cpu).zip(&rays).enumerate() {
            let same = h == c
                || h.prim == NO_HIT && c.prim == NO_HIT
                || any_hit && (h.prim == NO_HIT) == (c.prim == NO_HIT);
            assert!(
                same,
                "ray {i} {r:?} (any hit: {any_hit}): hardware {h:?}, CPU {c:?}"
            );
        }
    }
}

/// `--accel hardware` on a device without ray queries (the system's
/// adapter, opened without them) traces through the compute BVH, says so,
/// and renders the compute path's bits; the engine hands its note on.
#[test]
fn without_ray_queries_the_compute_bvh_answers_with_a_note() {
    let scene = with_accel(&load("spheres"), Accel::Hardware);
    let mut renderer = GpuRenderer::new(open_gpu(), &scene).expect("the scene uploads");
    assert!(renderer.ray_queries().is_none());
    let note = renderer.accel_note().expect("a note").to_string();
    assert_contains_all(
        &note,
        &["--accel hardware: ", "has no ray queries", "compute BVH"],
    );
    let mut bvh = GpuRenderer::new(open_gpu(), &with_accel(&scene, Accel::Bvh)).unwrap();
    assert_eq!(
        bits(&render(&mut renderer, &scene)),
        bits(&render(&mut bvh, &scene))
    );
    // The engine opens the device without ray queries unless the scene
    // asks for them, so the note can come only from such a device here.
    let device = lambert::gpu::AdapterRequest::default();
    let opened = lambert::render::Renderer::open(
        std::sync::Arc::new(scene),
        lambert::render::DeviceChoice::Gpu,
        &device,
    );
    let (renderer, engine_note) = opened.expect("a GPU opens");
    if renderer.describe().ends_with(", ray queries") {
        assert_eq!(engine_note, None);
    } else {
        assert_contains_all(&engine_note.expect("the note"), &["has no ray queries"]);
    }
}

/// The command line through ray queries: `lambert trace --accel hardware`
/// writes the compute path's hits, `lambert diff --compare hardware-cpu`
/// passes, `render.accel = "hardware"` in a scene file is read, and a
/// geometric query on it says it goes through the compute BVH.
#[test]
fn the_command_line_traces_renders_and_compares_through_ray_queries() {
    let test = "the_command_line_traces_renders_and_compares_through_ray_queries";
    let Some(gpu) = ray_query_gpu(test) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene_path = asset("scenes/bunny.toml");
    let scene = load("bunny");
    let rays = ray_set(&scene, &mut Rng(3), 2000);
    let ray_file = dir.path().join("rays.bin");
    lambert::rays::write_rays(&ray_file, &rays).unwrap();
    let mut hits = Vec::new();
    for accel in ["hardware", "bvh"] {
        let out = dir.path().join(format!("{accel}.hits"));
        let output = lambert(&[
            "trace",
            "--scene",
            s(&scene_path),
            "--rays",
            s(&ray_file),
            "-o",
            s(&out),
            "--device",
            "gpu",
            "--accel",
            accel,
            "--json",
        ]);
        assert!(output.status.success(), "{}", stderr(&output));
        let report = String::from_utf8_lossy(&output.stdout).to_string();
        assert_eq!(
            report.contains(", ray queries"),
            accel == "hardware",
            "{report}"
        );
        hits.push(lambert::rays::read_hits(&out).unwrap());
    }
    let differ = hits[0].iter().zip(&hits[1]).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "hardware and BVH hits differ on the bunny");
    let output = lambert(&["diff", s(&scene_path), "--compare", "hardware-cpu"]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(String::from_utf8_lossy(&output.stdout).contains("PASS"));
    // The scene format's render.accel, and a query's note.
    let toml = std::fs::read_to_string(&scene_path).unwrap();
    let meshes = asset("scenes/meshes");
    let toml = toml.replace("\"meshes/", &format!("\"{}/", meshes.display()));
    let hardware_scene = dir.path().join("hardware.toml");
    std::fs::write(
        &hardware_scene,
        format!("{toml}\n").replacen("[render]", "[render]\naccel = \"hardware\"", 1),
    )
    .unwrap();
    let image = dir.path().join("image.png");
    let output = lambert(&[
        "render",
        s(&hardware_scene),
        "--device",
        "gpu",
        "-o",
        s(&image),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_contains_all(
        &stderr(&output),
        &["ray queries: ", "BLAS", ", ray queries"],
    );
    let counts = dir.path().join("counts.bin");
    let output = lambert(&[
        "query",
        "count",
        "--scene",
        s(&hardware_scene),
        "--rays",
        s(&ray_file),
        "-o",
        s(&counts),
        "--device",
        "gpu",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    // Crossings go through ray queries where the triangles are boxes.
    let boxes = TriangleGeometry::for_gpu(&gpu).unwrap() == TriangleGeometry::Boxes;
    let noted = stderr(&output).contains("crossing counts and lists go through the compute BVH");
    assert_eq!(noted, !boxes, "{}", stderr(&output));
}

/// `lambert view --accel hardware` (under Xvfb): frames refined through
/// ray queries, no note of a fallback, and the image `render --accel bvh`
/// makes, bit for bit (the bunny has no ties).
#[test]
fn the_viewer_renders_through_ray_queries() {
    let Some(_gpu) = ray_query_gpu("the_viewer_renders_through_ray_queries") else {
        return;
    };
    let Some(x) = viewer::xvfb() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = asset("scenes/bunny.toml");
    let (shot, rendered) = (dir.path().join("view.png"), dir.path().join("render.png"));
    let size = ["--width", "64", "--height", "48", "--device", "gpu"];
    let view = lambert_command()
        .args(["view", s(&scene), "--frames", "3", "--screenshot", s(&shot)])
        .args(["--accel", "hardware"])
        .args(size)
        .env("DISPLAY", &x.display)
        .output()
        .unwrap();
    assert!(view.status.success(), "{}", stderr(&view));
    assert!(!stderr(&view).contains("compute BVH"), "{}", stderr(&view));
    let render = lambert_command()
        .args([
            "render",
            s(&scene),
            "--spp",
            "3",
            "-o",
            s(&rendered),
            "--accel",
            "bvh",
        ])
        .args(size)
        .output()
        .unwrap();
    assert!(render.status.success(), "{}", stderr(&render));
    assert_eq!(
        std::fs::read(&shot).unwrap(),
        std::fs::read(&rendered).unwrap()
    );
}
