//! Defects found by trying unusual but valid inputs (issue 22), far from the origin (issue 28 item 3): meshes, rays and scenes at 1e6 to 1e19.

mod common;

use common::args::trace_args;
use common::data::ray;
use common::*;
use lambert::layout::{NO_HIT, Ray};

/// An icosphere of radius 1 about `centre` (f64, as a loader reads it):
/// the scene's arrays and its triangles for the reference.
fn far_icosphere(centre: glam::DVec3) -> (lambert::Scene, Vec<[glam::DVec3; 3]>) {
    let (vertices, faces) = lambert::probe::icosphere(1.0, 2);
    let world: Vec<glam::DVec3> = vertices.iter().map(|&v| v + centre).collect();
    let arrays: Vec<[f64; 3]> = world.iter().map(|v| v.to_array()).collect();
    let rows: Vec<[i64; 3]> = faces.iter().map(|f| f.map(i64::from)).collect();
    let scene = lambert::Scene::from_arrays(&arrays, &rows, None).unwrap();
    let triangles = faces.iter().map(|f| f.map(|i| world[i as usize])).collect();
    (scene, triangles)
}

/// An icosphere of radius 1 about `centre` as an OBJ file's text.
fn icosphere_obj(centre: glam::DVec3, subdivisions: u32) -> String {
    let (vertices, faces) = lambert::probe::icosphere(1.0, subdivisions);
    let mut obj = String::new();
    for v in &vertices {
        let p = *v + centre;
        obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for f in &faces {
        obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    obj
}

/// The nearest hit of a ray on f64 triangles: Möller–Trumbore in f64 about
/// the ray's origin (the reference; f64 at 1e8 holds 1.5e-8).
fn reference_t(o: glam::DVec3, d: glam::DVec3, triangles: &[[glam::DVec3; 3]]) -> Option<f64> {
    triangles
        .iter()
        .filter_map(|[a, b, c]| {
            let (e1, e2, s) = (*b - *a, *c - *a, o - *a);
            let p = d.cross(e2);
            let det = e1.dot(p);
            let (u, q) = (s.dot(p) / det, s.cross(e1));
            let v = d.dot(q) / det;
            let t = e2.dot(q) / det;
            (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
        })
        .min_by(f64::total_cmp)
}

/// Rays from 1.5 to 4 units off the sphere's centre towards points within
/// 0.8 of it (so each hits), in f64.
fn rays_near(centre: glam::DVec3, count: usize) -> Vec<(glam::DVec3, glam::DVec3)> {
    let mut rng = lambert::probe::Rng(28);
    (0..count)
        .map(|_| {
            let origin = centre + rng.direction() * (1.5 + 2.5 * rng.unit());
            let target = centre + rng.direction() * 0.8 * rng.unit();
            (origin, target - origin)
        })
        .collect()
}

/// The local rays of the CPU path, traced (`trace_rays_each` in
/// `RayFrame::Local`).
fn trace_local_cpu(scene: &lambert::Scene, rays: &[Ray]) -> Vec<lambert::layout::Hit> {
    use lambert::cpu::{CpuKernel, QueryOptions, QueryRays, RayFrame, trace_rays_each};
    let hits = std::sync::Mutex::new(vec![lambert::layout::Hit::MISS; rays.len()]);
    let options = QueryOptions {
        any_hit: false,
        intersect: scene.default_settings().intersect,
        cpu_kernel: CpuKernel::active(),
        normals: false,
    };
    let rays = QueryRays::Slice(rays);
    trace_rays_each(scene, rays, options, RayFrame::Local, &|chunk| {
        let mut all = hits.lock().unwrap();
        all[chunk.start..chunk.start + chunk.hits.len()].copy_from_slice(chunk.hits);
    });
    hits.into_inner().unwrap()
}

/// Issue 28 item 3: an icosphere of radius 1 at 1e6 and 1e8 traces as one
/// at the origin: rays given in f64 (the Python package's way:
/// `Placement::local_ray`, hits back with their shift) hit within 1e-5 of
/// its size of an f64 reference, on both paths; rays given in f32 (a ray
/// file) hit where their own f32 numbers say, on both paths.
#[test]
fn meshes_far_from_the_origin_trace_as_at_the_origin() {
    use glam::DVec3;
    let size = 2.0;
    for centre in [
        DVec3::ZERO,
        DVec3::splat(1e6),
        DVec3::new(1e8, -1e8, 1e8),
        DVec3::new(1e8 + 0.3, 2.5e7, -7e7),
    ] {
        let (scene, triangles) = far_icosphere(centre);
        let placement = scene.placement();
        let world = rays_near(centre, 500);
        let (local, shifts): (Vec<Ray>, Vec<f64>) = world
            .iter()
            .map(|&(o, d)| placement.local_ray(o, d, 0.0, f64::INFINITY))
            .unzip();
        let mut gpu = lambert::gpu::GpuRenderer::new(open_gpu(), &scene).unwrap();
        let gpu_hits = gpu
            .trace_local_rays(&local, false, scene.default_settings().intersect)
            .unwrap();
        for (what, hits) in [("CPU", trace_local_cpu(&scene, &local)), ("GPU", gpu_hits)] {
            let mut worst = 0.0f64;
            for (i, ((o, d), (hit, shift))) in
                world.iter().zip(hits.iter().zip(&shifts)).enumerate()
            {
                let hit = lambert::placement::world_hit(*hit, *shift);
                let want = reference_t(*o, *d, &triangles).expect("every ray is aimed inside");
                assert_ne!(hit.prim, NO_HIT, "{what}, centre {centre}: ray {i} misses");
                let error = (*d * (hit.t as f64 - want)).length();
                worst = worst.max(error);
                assert!(
                    error <= 1e-5 * size,
                    "{what}, centre {centre}: ray {i} hits {error:e} from the reference"
                );
            }
            println!("{what}, centre {centre}: f64 rays hit within {worst:.2e} of the reference");
        }
        // The same rays rounded to f32, as a ray file holds them: traced as
        // given, world in, world out.
        let f32_rays: Vec<Ray> = world
            .iter()
            .map(|(o, d)| Ray {
                origin: o.as_vec3().to_array(),
                tmin: 0.0,
                dir: d.as_vec3().to_array(),
                tmax: f32::INFINITY,
            })
            .collect();
        for (what, hits) in [
            ("CPU", trace_cpu(&scene, &f32_rays, false)),
            (
                "GPU",
                gpu.trace_rays(&f32_rays, false, scene.default_settings().intersect)
                    .unwrap(),
            ),
        ] {
            for (i, (ray, hit)) in f32_rays.iter().zip(&hits).enumerate() {
                let [o, d] = [ray.origin, ray.dir].map(|v| glam::Vec3::from(v).as_dvec3());
                let Some(want) = reference_t(o, d, &triangles) else {
                    assert_eq!(hit.prim, NO_HIT, "{what}, centre {centre}: f32 ray {i}");
                    continue;
                };
                assert_ne!(
                    hit.prim, NO_HIT,
                    "{what}, centre {centre}: f32 ray {i} misses"
                );
                let error = (d * (hit.t as f64 - want)).length();
                assert!(
                    error <= 1e-5 * size,
                    "{what}, centre {centre}: f32 ray {i} hits {error:e} from the reference"
                );
            }
        }
    }
}

/// A ray starting 1e19 away hits, on both paths, in the oracle and from
/// the CLI; rays whose f32 origins cannot hold a position near a mesh at
/// 1e8, or whose hits lie beyond f32's t, are named in a warning.
#[test]
fn rays_from_far_away_hit_and_imprecise_ones_are_named() {
    use glam::DVec3;
    let (scene, triangles) = far_icosphere(DVec3::ZERO);
    let rays = [
        ray([0.1, 0.2, 1e19], [0.0, 0.0, -1.0]),
        ray([-1e19, 0.3, -0.2], [1.0, 0.0, 0.0]),
        ray([0.0, 0.0, 3e38], [0.0, 0.0, -1e-18]),
    ];
    let oracle = lambert::cpu::trace_rays_f64(&scene, &rays, false);
    let as_f64 = |hits: Vec<lambert::layout::Hit>| {
        hits.iter()
            .map(|h| (h.prim, h.t as f64))
            .collect::<Vec<_>>()
    };
    for (what, hits) in [
        ("oracle", oracle.iter().map(|h| (h.prim, h.t)).collect()),
        ("CPU", as_f64(trace_cpu(&scene, &rays, false))),
        ("GPU", as_f64(trace_gpu(&scene, &rays, false))),
    ] {
        for (i, r) in rays[..2].iter().enumerate() {
            let [o, d] = [r.origin, r.dir].map(|v| glam::Vec3::from(v).as_dvec3());
            let want = reference_t(o, d, &triangles).unwrap();
            let (prim, t) = hits[i];
            assert_ne!(prim, NO_HIT, "{what}: ray {i} from 1e19 misses");
            assert!(
                ((t - want) / want).abs() < 1e-7,
                "{what}: ray {i}: t {t} for {want}"
            );
        }
        // Its t would be 3e56: beyond f32, so a miss, and a warning says so.
        if what != "oracle" {
            assert_eq!(hits[2].0, NO_HIT, "{what}: a t beyond f32");
        }
    }
    let warnings = scene.placement().ray_warnings(&rays);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].starts_with("ray 2: ") && warnings[0].contains("beyond f32's largest t"),
        "{warnings:?}"
    );

    // From the CLI: the mesh as an OBJ file, at 1e8, and a ray file with a
    // ray from 1e19 away and one from near the mesh, whose f32 origin
    // is only known to 8 units.
    let dir = tempfile::tempdir().unwrap();
    let obj_path = dir.path().join("far.obj");
    std::fs::write(&obj_path, icosphere_obj(DVec3::new(1e8, 0.0, 0.0), 2)).unwrap();
    let rays = [
        ray([1e8, 0.25, 1e19], [0.0, 0.0, -1.0]),
        ray([1e8, 0.0, 3.0], [0.0, 0.0, -1.0]),
    ];
    let rays_path = dir.path().join("rays.bin");
    lambert::rays::write_rays(&rays_path, &rays).unwrap();
    for device in ["cpu", "gpu"] {
        let hits_path = dir.path().join(format!("hits-{device}.bin"));
        let out = lambert(
            &[
                &trace_args(&obj_path, &rays_path, &hits_path)[..],
                &["--device", device],
            ]
            .concat(),
        );
        assert!(out.status.success(), "{device}: {}", stderr(&out));
        let hits = lambert::rays::read_hits(&hits_path).unwrap();
        // 1e19 − 1 in f32 is 1e19: the sphere's near side.
        assert_ne!(hits[0].prim, NO_HIT, "{device}: the ray from 1e19 misses");
        assert!(
            ((hits[0].t as f64 - 1e19) / 1e19).abs() < 1e-7,
            "{device}: {}",
            hits[0].t
        );
        assert_ne!(
            hits[1].prim, NO_HIT,
            "{device}: the ray from 3 units off misses"
        );
        assert!((hits[1].t - 2.0).abs() < 0.05, "{device}: t {}", hits[1].t);
        let text = stderr(&out);
        assert!(
            text.contains("warning: ray 1: its origin [1e8, 0, 3] is given in f32, which spaces values 8 apart"),
            "{device}: {text}"
        );
        assert!(!text.contains("ray 0"), "{device}: {text}");
    }
}

/// A scene translated to 1e8 renders as at the origin, on both paths.
#[test]
fn a_scene_at_1e8_renders_as_at_the_origin() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("ico.obj"),
        icosphere_obj(glam::DVec3::ZERO, 3),
    )
    .unwrap();
    let at = |t: [f64; 3]| {
        let p = |x: [f64; 3]| format!("[{}, {}, {}]", x[0] + t[0], x[1] + t[1], x[2] + t[2]);
        let text = format!(
            "[camera]\neye = {}\nlook_at = {}\nvfov = 40.0\nwidth = 48\nheight = 48\n\
             [[mesh]]\nfile = \"ico.obj\"\ntranslate = {}\n\
             [[point_light]]\nposition = {}\nintensity = 20.0\n",
            p([0.5, 0.8, 4.0]),
            p([0.0; 3]),
            p([0.0; 3]),
            p([2.0, 3.0, 4.0]),
        );
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, text).unwrap();
        lambert::Scene::load(&path).unwrap()
    };
    let (near, far) = (at([0.0; 3]), at([1e8, -3e7, 1e8]));
    assert_eq!(near.offset(), glam::DVec3::ZERO);
    for (what, a, b) in [
        ("CPU", render_cpu(&near), render_cpu(&far)),
        ("GPU", render_gpu(&near), render_gpu(&far)),
    ] {
        let stats = lambert::diff::compare(&a, &b, &Default::default()).unwrap();
        println!("{what}: at 1e8 against the origin\n{stats}");
        assert!(stats.passed, "{what}: at 1e8 against the origin\n{stats}");
    }
}
