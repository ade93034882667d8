//! The point and every-hit queries on a mesh far from the origin (issue
//! 44, items 1 and 2): f64 points and ray origins keep their precision at
//! 1e6 and 1e8, against an f64 brute force over the same triangles; where
//! f32 input cannot, a warning names it (the library and `lambert query`);
//! and the GPU's lists sized by the adapter's binding limit (item 6).

use std::borrow::Cow;
use std::sync::Arc;

use glam::DVec3;
use lambert::Error;
use lambert::gpu::{AdapterRequest, Gpu, GpuRenderer, binding_runs};
use lambert::jobs::{self, Sign};
use lambert::layout::Ray;
use lambert::placement::LocalRays;
use lambert::render::{DeviceChoice, Renderer, with_fallback};
use lambert::scene::Scene;

mod common;
use common::{lambert, s, stderr, write};

/// Where f32 spaces values 0.5 and 8 apart (the first place).
const PLACES: [[f64; 3]; 2] = [[5e6, 4e6, 100.0], [1e8, -0.7e8, 0.3e8]];

/// A unit sphere about `centre`: an octahedron's faces split `levels`
/// times, every vertex pushed onto the sphere, facing out; vertices in f64.
fn sphere(centre: DVec3, levels: u32) -> (Vec<DVec3>, Vec<[usize; 3]>) {
    let mut faces: Vec<[DVec3; 3]> = Vec::new();
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    for sx in [1.0, -1.0] {
        for sy in [1.0, -1.0] {
            for sz in [1.0, -1.0] {
                let (a, b, c) = (axes[0] * sx, axes[1] * sy, axes[2] * sz);
                // Counter-clockwise seen from outside.
                faces.push(if sx * sy * sz > 0.0 {
                    [a, b, c]
                } else {
                    [a, c, b]
                });
            }
        }
    }
    for _ in 0..levels {
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (
                    (a + b).normalize(),
                    (b + c).normalize(),
                    (c + a).normalize(),
                );
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    let vertices = faces.iter().flatten().map(|&v| centre + v).collect();
    let indices = (0..faces.len())
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    (vertices, indices)
}

/// The sphere of `sphere(…, 3)` about `place`: its centre, its triangles
/// in f64 (the references') and its scene.
fn far_sphere(place: [f64; 3]) -> (DVec3, Vec<[DVec3; 3]>, Arc<Scene>) {
    let centre = DVec3::from(place);
    let (vertices, faces) = sphere(centre, 3);
    let triangles = faces.iter().map(|f| f.map(|i| vertices[i])).collect();
    (centre, triangles, scene_of(&vertices, &faces))
}

fn scene_of(vertices: &[DVec3], faces: &[[usize; 3]]) -> Arc<Scene> {
    let v: Vec<[f64; 3]> = vertices.iter().map(|v| v.to_array()).collect();
    let f: Vec<[i64; 3]> = faces.iter().map(|f| f.map(|i| i as i64)).collect();
    Arc::new(Scene::from_arrays(&v, &f, None).expect("a valid mesh"))
}

/// The exact nearest distance from `p` to triangle abc.
fn triangle_distance(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let n = (b - a).cross(c - a);
    let q = p - n * (p - a).dot(n) / n.length_squared();
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(s, e)| (e - s).cross(q - s).dot(n) >= 0.0);
    if inside {
        return (p - q).length();
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|&(s, e)| {
            let t = ((p - s).dot(e - s) / (e - s).length_squared()).clamp(0.0, 1.0);
            (p - (s + (e - s) * t)).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Every t > 0 at which the ray crosses a triangle (Möller–Trumbore in
/// f64), sorted.
fn crossings(origin: DVec3, dir: DVec3, triangles: &[[DVec3; 3]]) -> Vec<f64> {
    let mut ts: Vec<f64> = triangles
        .iter()
        .filter_map(|&[a, b, c]| {
            let (e1, e2) = (b - a, c - a);
            let p = dir.cross(e2);
            let det = e1.dot(p);
            let s = origin - a;
            let u = s.dot(p) / det;
            let q = s.cross(e1);
            let v = dir.dot(q) / det;
            let t = e2.dot(q) / det;
            (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
        })
        .collect();
    ts.sort_by(f64::total_cmp);
    ts
}

/// The points about the centre, and some more on a shell about it
/// (inside and outside, none within 1e-3 of the surface).
fn offsets() -> Vec<DVec3> {
    let mut out = vec![
        DVec3::new(0.3, 0.1, 0.2),
        DVec3::new(1.2, 0.0, 0.0),
        DVec3::new(0.99, 0.0, 0.0),
    ];
    for i in 0..40 {
        let a = i as f64 * 2.399963;
        let z = 1.0 - (i as f64 + 0.5) / 20.0;
        let dir = DVec3::new(
            a.cos() * (1.0 - z * z).sqrt(),
            a.sin() * (1.0 - z * z).sqrt(),
            z,
        );
        out.push(dir * [0.5, 0.97, 1.05, 1.7][i % 4]);
    }
    out
}

fn renderers(scene: &Arc<Scene>) -> Vec<Renderer> {
    let gpu = Renderer::open(
        Arc::clone(scene),
        DeviceChoice::Gpu,
        &AdapterRequest::default(),
    )
    .expect("a GPU adapter (lavapipe: apt-get install mesa-vulkan-drivers)")
    .0;
    vec![Renderer::Cpu(Arc::clone(scene)), gpu]
}

/// Item 1: distances, signed distances, winding numbers, inside tests
/// (both ways) and closest points of f64 points, on both devices, as an
/// f64 brute force has them, at 1e6 and 1e8.
#[test]
fn f64_points_keep_their_precision_far_from_the_origin() {
    for place in PLACES {
        let (centre, triangles, scene) = far_sphere(place);
        let points: Vec<[f64; 3]> = offsets().iter().map(|&o| (centre + o).to_array()).collect();
        let truth: Vec<f64> = points
            .iter()
            .map(|&p| {
                let p = DVec3::from(p);
                triangles
                    .iter()
                    .map(|&t| triangle_distance(p, t))
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        // Inside the sphere mesh: its faces are all more than 0.99 from
        // the centre, and no point lies between 0.99 and 1.
        let inside: Vec<bool> = offsets().iter().map(|o| o.length() < 1.0).collect();
        for mut renderer in renderers(&scene) {
            let on = format!("{} at {place:?}", renderer.describe());
            let distance = jobs::distances(&mut renderer, &points).unwrap();
            let signed = jobs::signed_distances(&mut renderer, &points, Sign::Winding).unwrap();
            let winding = renderer.winding_numbers(&points).unwrap();
            let parity = renderer.parity_inside(&points).unwrap();
            let closest = renderer.closest_points(&points, f32::INFINITY).unwrap();
            for i in 0..points.len() {
                let what = format!("point {i} ({:?} from the centre) on {on}", offsets()[i]);
                assert!(
                    (distance[i] as f64 - truth[i]).abs() < 1e-5,
                    "{what}: distance {} where the truth is {}",
                    distance[i],
                    truth[i]
                );
                let sign = if inside[i] { -1.0 } else { 1.0 };
                assert!(
                    (signed[i] as f64 - sign * truth[i]).abs() < 1e-5,
                    "{what}: signed distance {}, truth {}",
                    signed[i],
                    sign * truth[i]
                );
                assert!(
                    (winding[i] - if inside[i] { 1.0 } else { 0.0 }).abs() < 1e-2,
                    "{what}: winding number {}",
                    winding[i]
                );
                assert_eq!(parity[i], inside[i], "{what}: parity");
                // The triangle and its (u, v) found, evaluated in f64.
                let [a, b, c] = triangles[closest[i].prim as usize];
                let (u, v) = (closest[i].u as f64, closest[i].v as f64);
                let on_surface = a * (1.0 - u - v) + b * u + c * v;
                let found = (on_surface - DVec3::from(points[i])).length();
                assert!(
                    (found - truth[i]).abs() < 1e-5,
                    "{what}: the closest point found is {found} away, truth {}",
                    truth[i]
                );
            }
        }
    }
}

/// Item 2: the crossings of rays given in f64, moved into the scene's
/// frame as `trace`'s (`Placement::local_ray`), counted and listed on
/// both devices as an f64 brute force has them: the kind of ray,
/// from centre + (0.95, 0.01, −5) along +z (off the sphere's edges in
/// y = 0), crosses twice, not grazes at t = 5.
#[test]
fn f64_rays_cross_far_meshes_where_f64_says() {
    for place in PLACES {
        let (centre, triangles, scene) = far_sphere(place);
        let placement = scene.placement();
        // The ray, and rays from 5 units out aimed within 0.9 of
        // the centre (none grazes).
        let mut rays = vec![(centre + DVec3::new(0.95, 0.01, -5.0), DVec3::Z)];
        for o in offsets().iter().skip(3) {
            let from = centre + o.normalize() * 5.0;
            rays.push((from, centre + o.normalize().cross(DVec3::Z) * 0.3 - from));
        }
        let truth: Vec<Vec<f64>> = rays
            .iter()
            .map(|&(o, d)| crossings(o, d, &triangles))
            .collect();
        assert_eq!(truth[0].len(), 2);
        let (local, shifts): (Vec<Ray>, Vec<f64>) = rays
            .iter()
            .map(|&(o, d)| placement.local_ray(o, d, 0.0, f64::INFINITY))
            .unzip();
        let local = LocalRays {
            rays: Cow::Owned(local),
            shifts,
        };
        for mut renderer in renderers(&scene) {
            let on = format!("{} at {place:?}", renderer.describe());
            let counts = renderer.count_local_intersections(&local).unwrap();
            let list = renderer.list_local_intersections(&local).unwrap();
            for (i, truth) in truth.iter().enumerate() {
                assert_eq!(counts[i] as usize, truth.len(), "ray {i} on {on}");
                let (from, to) = (list.ray_splits[i] as usize, list.ray_splits[i + 1] as usize);
                let ts: Vec<f32> = list.hits[from..to].iter().map(|h| h.t).collect();
                assert_eq!(
                    ts.len(),
                    truth.len(),
                    "ray {i} on {on}: {ts:?}, truth {truth:?}"
                );
                for (t, want) in ts.iter().zip(truth) {
                    assert!(
                        (*t as f64 - want).abs() < 1e-5 * want.max(1.0),
                        "ray {i} on {on}: t = {ts:?}, truth {truth:?}"
                    );
                }
            }
        }
    }
}

/// Far f32 points and rays are as precise as f32 holds them: the library
/// says so for each kind, naming the first and counting the rest; f32
/// input near a mesh at the origin gets no warning.
#[test]
fn far_f32_points_and_rays_are_warned_of() {
    let centre = DVec3::from(PLACES[0]);
    let (vertices, faces) = sphere(centre, 1);
    let placement = scene_of(&vertices, &faces).placement();
    let points: Vec<[f32; 3]> = offsets()
        .iter()
        .map(|&o| (centre + o).as_vec3().to_array())
        .collect();
    let warnings =
        placement.point_warnings(points.len(), |i| DVec3::from(points[i].map(f64::from)));
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    let expected = format!(
        "point 0 (and {} more like it): its position",
        points.len() - 1
    );
    assert!(warnings[0].starts_with(&expected), "{}", warnings[0]);
    assert!(
        warnings[0].contains("spaces values 0.5 apart"),
        "{}",
        warnings[0]
    );
    assert!(
        warnings[0].contains("give points in f64"),
        "{}",
        warnings[0]
    );
    let (vertices, faces) = sphere(DVec3::ZERO, 1);
    let near = scene_of(&vertices, &faces).placement();
    let points: Vec<[f32; 3]> = offsets().iter().map(|o| o.as_vec3().to_array()).collect();
    assert!(
        near.point_warnings(points.len(), |i| DVec3::from(points[i].map(f64::from)))
            .is_empty()
    );
}

/// The sphere at the place as an OBJ file, with a far f32 point
/// file and ray file about it.
fn far_files(dir: &std::path::Path) -> [std::path::PathBuf; 3] {
    let centre = DVec3::from(PLACES[0]);
    let (vertices, faces) = sphere(centre, 2);
    let mut obj = String::new();
    for v in &vertices {
        obj += &format!("v {} {} {}\n", v.x, v.y, v.z);
    }
    for f in &faces {
        obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    let points: Vec<f32> = offsets()
        .iter()
        .flat_map(|&o| (centre + o).as_vec3().to_array())
        .collect();
    let o = (centre + DVec3::new(0.95, 0.0, -5.0)).as_vec3();
    let rays = [o.x, o.y, o.z, 0.0, 0.0, 0.0, 1.0, f32::INFINITY];
    [
        write(dir, "sphere.obj", obj),
        write(dir, "points.bin", bytemuck::cast_slice::<f32, u8>(&points)),
        write(dir, "rays.bin", bytemuck::cast_slice::<f32, u8>(&rays)),
    ]
}

/// `lambert query distance` and `count` warn of far f32 input as `lambert
/// trace` does (and say nothing with --quiet).
#[test]
fn lambert_query_warns_of_far_f32_points_and_rays() {
    let dir = tempfile::tempdir().unwrap();
    let [obj, points, rays] = far_files(dir.path());
    let out = dir.path().join("out.bin");
    for (what, input, flag, expected) in [
        (
            "distance",
            &points,
            "--points",
            "warning: point 0 (and 42 more like it): its position [5000000.5",
        ),
        (
            "signed-distance",
            &points,
            "--points",
            "warning: point 0 (and 42 more like it)",
        ),
        (
            "count",
            &rays,
            "--rays",
            "warning: ray 0: its origin [5000001, 4000000, 95]",
        ),
        ("list", &rays, "--rays", "warning: ray 0: its origin"),
    ] {
        let args = [
            "query",
            what,
            "--obj",
            s(&obj),
            flag,
            s(input),
            "-o",
            s(&out),
        ];
        let run = lambert(&[&args[..], &["--device", "cpu"]].concat());
        let text = stderr(&run);
        assert!(run.status.success(), "{what}: {text}");
        assert!(text.contains(expected), "{what}: {text}");
        assert!(text.contains("give "), "{what}: {text}");
        let quiet = lambert(&[&args[..], &["--device", "cpu", "--quiet"]].concat());
        assert!(
            !stderr(&quiet).contains("warning"),
            "{what}: {}",
            stderr(&quiet)
        );
    }
}

/// `count` quads stacked along z (z = 0, 1, …), each two triangles over
/// [−1, 1]²: a ray along +z crosses `count` of them.
fn stack(count: usize) -> Arc<Scene> {
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for k in 0..count {
        let z = k as f64;
        let base = vertices.len();
        vertices.extend([
            [-1.0, -1.0, z],
            [1.0, -1.0, z],
            [1.0, 1.0, z],
            [-1.0, 1.0, z],
        ]);
        faces.push([base, base + 1, base + 2]);
        faces.push([base, base + 2, base + 3]);
    }
    let vertices: Vec<DVec3> = vertices.into_iter().map(DVec3::from).collect();
    scene_of(&vertices, &faces)
}

/// What lambert asks of the adapter: buffers and storage bindings of at
/// most 1 MiB (a render tile's), 52,428 listed crossings.
const SMALL_GPU: u64 = 1 << 20;

/// A GPU renderer of `scene` on an adapter whose buffers and storage
/// bindings hold at most SMALL_GPU bytes.
fn small_gpu(scene: &Scene) -> Renderer {
    let gpu = Gpu::open_limited(&AdapterRequest::default(), false, Some(SMALL_GPU))
        .expect("a GPU adapter (lavapipe: apt-get install mesa-vulkan-drivers)");
    Renderer::Gpu(Box::new(
        GpuRenderer::new(gpu, scene).expect("the scene fits"),
    ))
}

/// Rays along +z through the stack, from below it.
fn up_rays(n: usize) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let (x, y) = ((i % 61) as f32 / 61.0 - 0.49, (i % 53) as f32 / 53.0 - 0.51);
            Ray {
                origin: [x * 1.7, y * 1.9, -1.0],
                tmin: 0.0,
                dir: [0.0, 0.0, 1.0],
                tmax: f32::INFINITY,
            }
        })
        .collect()
}

/// Item 6: a list whose crossings are several times what one storage
/// binding holds (10,000 rays × 30 crossings, 6 MB, against 1 MiB) is
/// listed in runs that fit, as the CPU lists it.
#[test]
fn gpu_lists_are_batched_by_the_binding_limit() {
    let scene = stack(30);
    let rays = up_rays(10_000);
    let mut gpu = small_gpu(&scene);
    let mut cpu = Renderer::Cpu(Arc::clone(&scene));
    let expected = cpu.list_intersections(&rays).unwrap();
    assert_eq!(expected.hits.len(), 10_000 * 30);
    assert_eq!(gpu.list_intersections(&rays).unwrap(), expected);
    assert_eq!(
        gpu.count_intersections(&rays).unwrap(),
        cpu.count_intersections(&rays).unwrap()
    );
}

/// Item 6: the runs a GPU lists at once hold as many rays as one binding's
/// crossings allow; a ray whose crossings alone are more is named (and
/// `list_intersections` makes it the typed GPU-limit error).
#[test]
fn runs_fit_the_binding_and_a_ray_beyond_it_is_named() {
    assert_eq!(
        binding_runs(&[3, 4, 0, 2, 5, 1], 7),
        Ok(vec![(0..3, 7), (3..5, 7), (5..6, 1)])
    );
    assert_eq!(binding_runs(&[], 7), Ok(vec![]));
    assert_eq!(binding_runs(&[0, 0], 7), Ok(vec![(0..2, 0)]));
    assert_eq!(binding_runs(&[3, 8, 1], 7), Err(1));
}

/// Item 6: where a GPU query hits the GPU's limits (`Error::GpuLimit`),
/// auto answers on the CPU path with its note; `gpu` keeps the error.
#[test]
fn auto_takes_the_cpu_path_where_a_query_hits_the_gpu_limits() {
    let scene = stack(3);
    let rays = up_rays(5);
    let mut gpu = small_gpu(&scene);
    // The GPU's list, as a GPU beyond its limits answers it.
    let list = |r: &mut Renderer| match r {
        Renderer::Gpu(_) => Err(Error::GpuLimit("ray 0: its crossings take more".into())),
        Renderer::Cpu(_) => r.list_intersections(&rays),
    };
    let gpu_only = with_fallback(&mut gpu, DeviceChoice::Gpu, &scene, list);
    assert!(matches!(gpu_only, Err(Error::GpuLimit(_))), "{gpu_only:?}");
    let (listed, note) = with_fallback(&mut gpu, DeviceChoice::Auto, &scene, list).unwrap();
    let cpu = Renderer::Cpu(Arc::clone(&scene))
        .list_intersections(&rays)
        .unwrap();
    assert_eq!(listed, cpu);
    assert_eq!(listed.hits.len(), 5 * 3);
    let note = note.expect("auto's note");
    assert!(
        note.contains("ray 0: its crossings take more") && note.contains("using the CPU path"),
        "{note}"
    );
    // Answers the GPU gives need no note.
    let (_, note) = with_fallback(&mut gpu, DeviceChoice::Auto, &scene, |r| {
        r.count_intersections(&rays)
    })
    .unwrap();
    assert_eq!(note, None);
}
