//! The GPU's compressed BVH (src/cwbvh.rs) against its CPU twin, bit for bit.
// `cpu::trace_rays_gpu_twin`: closest and any hit, from storage buffers and
// from textures; quantised boxes lose no hit, at any scale or offset; trees
// as deep as the builder allows trace within the stack, its short part
// spilling.

mod common;

use common::*;
use glam::{DVec3, Vec3};
use lambert::Scene;
use lambert::cpu;
use lambert::cwbvh::{MIN_WORKGROUP_BYTES, short_stack};
use lambert::gpu::{BvhStorage, GpuRenderer};
use lambert::layout::{Hit, NO_HIT, Ray, Triangle};
use lambert::probe::Rng;

/// (rays whose primitive differs, rays with the same primitive but other
/// bits of t, u or v).
fn mismatches(a: &[Hit], b: &[Hit]) -> (usize, usize) {
    let prims = a.iter().zip(b).filter(|(x, y)| x.prim != y.prim).count();
    let bits = a
        .iter()
        .zip(b)
        .filter(|(x, y)| {
            x.prim == y.prim
                && [(x.t, y.t), (x.u, y.u), (x.v, y.v)]
                    .iter()
                    .any(|(p, q)| p.to_bits() != q.to_bits())
        })
        .count();
    (prims, bits)
}

/// Rays from around the scene's box towards points inside it.
fn random_rays(scene: &Scene, rng: &mut Rng, n: usize) -> Vec<Ray> {
    let root = scene.bvh().bounds().expect("a non-empty scene");
    let (lo, hi) = (root.min.as_dvec3(), root.max.as_dvec3());
    let size = (hi - lo).max_element();
    (0..n)
        .map(|_| {
            let inside =
                |rng: &mut Rng| lo + (hi - lo) * DVec3::new(rng.unit(), rng.unit(), rng.unit());
            let origin = inside(rng) + rng.direction() * size;
            let dir = inside(rng) - origin;
            Ray {
                origin: origin.as_vec3().to_array(),
                tmin: 0.0,
                dir: dir.as_vec3().to_array(),
                tmax: f32::INFINITY,
            }
        })
        .collect()
}

#[test]
fn gpu_hits_equal_the_twins_bit_for_bit() {
    let mut rng = Rng(18);
    for name in ["dragon", "bunny", "cornell", "spheres", "edge_cases"] {
        let scene = load(name);
        let mut rays = lambert::rays::camera_rays(&scene);
        rays.extend(random_rays(&scene, &mut rng, 20_000));
        for storage in [BvhStorage::Buffers, BvhStorage::Texels] {
            let mut renderer =
                GpuRenderer::with_bvh_storage(open_gpu(), &scene, storage).expect("scene uploads");
            for any_hit in [false, true] {
                let gpu = renderer
                    .trace_rays(&rays, any_hit, scene.default_settings().intersect)
                    .expect("GPU trace");
                let twin = cpu::trace_rays_gpu_twin(
                    &scene,
                    &rays,
                    any_hit,
                    scene.default_settings().intersect,
                );
                let hits = twin.iter().filter(|h| h.prim != NO_HIT).count();
                println!(
                    "{name}, {storage:?}, any hit {any_hit}: {} rays, {hits} hits, GPU vs twin (other primitive, other bits) {:?}",
                    rays.len(),
                    mismatches(&gpu, &twin)
                );
                assert!(hits > 0, "{name}: nothing hit");
                assert_eq!(
                    mismatches(&gpu, &twin),
                    (0, 0),
                    "{name}, {storage:?}, any hit {any_hit}"
                );
            }
        }
    }
}

/// Every closest hit the twin finds is brute force's: the same t, bit for
/// bit (ties on t may pick another primitive). Brute force also tests
/// triangles smaller than the rounding of their coordinates relative to
/// the ray's origin, where the watertight test's fused multiply-adds can
/// report a hit nowhere near them; such hits (the point o + t·d off the
/// triangle's box) are left out, and a BVH rightly culls them.
fn assert_twin_is_exact(name: &str, scene: &Scene, rays: &[Ray]) {
    let brute = common::brute_force(scene);
    let twin = cpu::trace_rays_gpu_twin(scene, rays, false, scene.default_settings().intersect);
    let truth = cpu::trace_rays(&brute, rays, false);
    let on_triangle = |ray: &Ray, hit: &Hit| {
        let t = &scene.triangles()[hit.prim as usize];
        let p = Vec3::from(ray.origin) + hit.t * Vec3::from(ray.dir);
        let (lo, hi) = (
            Vec3::from(t.v0).min(t.v1.into()).min(t.v2.into()),
            Vec3::from(t.v0).max(t.v1.into()).max(t.v2.into()),
        );
        let slack = (hi - lo).max_element() * 1e-3;
        p.cmpge(lo - slack).all() && p.cmple(hi + slack).all()
    };
    let (mut hits, mut bogus) = (0, 0);
    for (i, (a, b)) in twin.iter().zip(&truth).enumerate() {
        if b.prim != NO_HIT && !on_triangle(&rays[i], b) {
            bogus += 1;
            continue;
        }
        hits += (b.prim != NO_HIT) as usize;
        assert_eq!(
            a.t.to_bits(),
            b.t.to_bits(),
            "{name}: ray {i} {:?}: twin {a:?}, brute force {b:?}",
            rays[i]
        );
    }
    println!(
        "{name}: {} rays, {hits} hits, twin = brute force ({bogus} brute-force hits off their triangle left out)",
        rays.len()
    );
    assert!(hits > rays.len() / 20, "{name}: too few hits to tell");
}

fn triangle(a: Vec3, b: Vec3, c: Vec3) -> Triangle {
    Triangle {
        v0: a.to_array(),
        v1: b.to_array(),
        v2: c.to_array(),
        ..Triangle::default()
    }
}

/// A grid of small triangles of side `size` around `offset`: quantising
/// their boxes on a grid far from the origin is where rounding would bite.
fn grid_at(offset: Vec3, size: f32, n: usize) -> Vec<Triangle> {
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let p = offset + Vec3::new(i as f32, j as f32, ((i * 7 + j * 3) % 5) as f32) * size;
            triangles.push(triangle(p, p + Vec3::X * size, p + Vec3::Y * size));
            triangles.push(triangle(
                p + Vec3::X * size,
                p + Vec3::new(size, size, 0.0),
                p + Vec3::Y * size,
            ));
        }
    }
    triangles
}

#[test]
fn quantised_boxes_lose_no_hit_at_any_scale_or_offset() {
    let mut rng = Rng(7);
    for (offset, size) in [
        (Vec3::ZERO, 1.0),
        // Steps of 4 ULPs at 1e6: the grid's origin is far from the box.
        (Vec3::splat(1e6), 0.25),
        (Vec3::new(-3e5, 2e5, 7e4), 0.25),
        (Vec3::splat(1e-6), 1e-9),
        (Vec3::new(1e12, -1e12, 0.0), 1e7),
    ] {
        let scene = scene_of(grid_at(offset, size, 40), vec![]);
        let name = format!("grid of side {size} at {offset}");
        assert_twin_is_exact(&name, &scene, &random_rays(&scene, &mut rng, 4000));
        let rays = random_rays(&scene, &mut rng, 4000);
        let gpu = trace_gpu(&scene, &rays, false);
        let twin =
            cpu::trace_rays_gpu_twin(&scene, &rays, false, scene.default_settings().intersect);
        assert_eq!(mismatches(&gpu, &twin), (0, 0), "{name}: GPU vs twin");
    }
}

#[test]
fn trees_as_deep_as_the_builder_makes_trace_within_the_stack() {
    // Clusters of triangles shrinking by half towards a point, one scale
    // per cluster: the SAH splits off one scale at a time, a deep tree.
    const SCALES: i32 = 80;
    let mut triangles = Vec::new();
    for k in 0..SCALES * 8 {
        let s = 0.5f32.powi(k / 8);
        let p = Vec3::new(s, (k % 4) as f32 * s * 0.25, (k % 8 / 4) as f32 * s * 0.1);
        triangles.push(triangle(p, p + Vec3::X * s * 0.2, p + Vec3::Y * s * 0.2));
    }
    let scene = scene_of(triangles, vec![]);
    let depth = scene.bvh().depth();
    println!("depth {depth} (limit {})", lambert::bvh::MAX_DEPTH);
    assert!(depth >= 10, "the tree is only {depth} levels deep");
    // Rays at each scale from a few times its size away, so that every
    // triangle they may hit is large next to the rounding of its
    // coordinates relative to the ray's origin.
    let mut rng = Rng(11);
    let rays: Vec<Ray> = (0..SCALES * 100)
        .map(|i| {
            let s = 0.5f32.powi(i / 100);
            let target = Vec3::new(
                s * (1.0 + 0.25 * rng.unit() as f32),
                s * 0.25 * rng.unit() as f32,
                0.0,
            );
            let origin = target + (Vec3::Z + rng.direction().as_vec3() * 0.5) * 4.0 * s;
            Ray {
                origin: origin.to_array(),
                tmin: 0.0,
                dir: (target - origin).to_array(),
                tmax: f32::INFINITY,
            }
        })
        .collect();
    // Deeper than the short stack holds: its oldest entries spill (on the
    // twin too, which is checked against brute force).
    let (entries, spills) = short_stack(depth, MIN_WORKGROUP_BYTES);
    assert!(spills, "{depth} levels fit {entries} entries");
    assert_twin_is_exact("deep tree", &scene, &rays);
    assert_short_stacks_agree("deep tree", &scene, &rays);
}

#[test]
fn a_short_stack_that_spills_traces_as_a_whole_one() {
    // The bunny's tree (4 levels) needs 3 entries: random rays, which
    // push the most, through a short stack of 1 and of 2 spill often.
    let scene = load("bunny");
    let rays = random_rays(&scene, &mut Rng(7), 20_000);
    assert_short_stacks_agree("bunny", &scene, &rays);
}

/// The GPU's hits through the adapter's short stack, and through one of 1
/// and of 2 entries (the device's workgroup memory lowered), equal the
/// twin's, closest and any hit; so do the twin's through such stacks.
fn assert_short_stacks_agree(name: &str, scene: &Scene, rays: &[Ray]) {
    let depth = scene.bvh().depth();
    let nodes = lambert::cwbvh::compress(scene.bvh());
    for any_hit in [false, true] {
        let twin =
            cpu::trace_rays_gpu_twin(scene, rays, any_hit, scene.default_settings().intersect);
        for entries in [1, 2] {
            let mut kernel = cpu::f32::Kernel::new(scene);
            kernel.compressed = Some(&nodes);
            kernel.stack_entries = entries;
            for (i, (ray, whole)) in rays.iter().zip(&twin).enumerate() {
                let hit = kernel.trace(cpu::f32::Ray::from_query(ray), any_hit);
                assert!(
                    hit.prim == whole.prim && (hit.prim == NO_HIT || hit.t == whole.t),
                    "{name}: ray {i}, twin with {entries} short-stack entries {hit:?}, whole {whole:?}"
                );
            }
        }
        for entries in [None, Some(1), Some(2)] {
            let mut gpu = open_gpu();
            if let Some(entries) = entries {
                gpu.limits.max_compute_workgroup_storage_size =
                    entries * 8 * lambert::layout::WORKGROUP_INVOCATIONS;
            }
            let shape = short_stack(depth, gpu.limits.max_compute_workgroup_storage_size);
            if entries.is_some() {
                assert!(shape.1, "{name}: {depth} levels fit a stack of {shape:?}");
            }
            let hits = GpuRenderer::new(gpu, scene)
                .expect("scene uploads")
                .trace_rays(rays, any_hit, scene.default_settings().intersect)
                .expect("GPU trace");
            println!("{name}: short stack {shape:?}, any hit {any_hit}: GPU vs twin");
            assert_eq!(
                mismatches(&hits, &twin),
                (0, 0),
                "{name}, short stack {shape:?}, any hit {any_hit}: GPU vs twin"
            );
        }
    }
}

#[test]
fn a_tree_too_large_for_the_devices_textures_is_read_from_buffers() {
    let scene = load("bunny");
    let rays = lambert::rays::camera_rays(&scene);
    let twin = cpu::trace_rays_gpu_twin(&scene, &rays, false, scene.default_settings().intersect);
    let default = GpuRenderer::new(open_gpu(), &scene).expect("scene uploads");
    println!("default storage on this adapter: {:?}", default.bvh_storage);
    // Textures of fewer texels a row than TEXELS_PER_ROW hold no tree.
    let mut gpu = open_gpu();
    gpu.limits.max_texture_dimension_2d = lambert::gpu::TEXELS_PER_ROW / 2;
    let mut renderer = GpuRenderer::new(gpu, &scene).expect("scene uploads");
    assert_eq!(renderer.bvh_storage, BvhStorage::Buffers);
    let hits = renderer
        .trace_rays(&rays, false, scene.default_settings().intersect)
        .expect("GPU trace");
    assert_eq!(mismatches(&hits, &twin), (0, 0));
}
