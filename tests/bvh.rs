//! The BVH: its structure, and traversal against brute force on both paths.

mod common;

use common::*;
use glam::Vec3;
use lambert::Scene;
use lambert::cpu::f32::{Kernel, Ray, ray_shear};
use lambert::layout::{BVH_WIDTH, NO_HIT, Sphere, Triangle};
use proptest::prelude::*;

/// The wide tree's invariants (`Bvh::validate`) and the compressed tree's
/// (`cwbvh::validate`), whose statistics agree with the wide tree's.
fn check_structure(scene: &Scene) {
    let bvh = &scene.bvh();
    let stats = bvh
        .validate(scene.triangles(), scene.spheres())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        (stats.nodes, stats.leaves, stats.depth),
        (bvh.nodes.len(), bvh.leaf_count(), bvh.depth())
    );
    let compressed = lambert::cwbvh::compress(bvh);
    let cstats = lambert::cwbvh::validate(&compressed, bvh).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        (cstats.nodes, cstats.leaves, cstats.depth),
        (stats.nodes, stats.leaves, stats.depth)
    );
    assert_eq!(
        (cstats.leaf_min, cstats.leaf_max),
        (stats.leaf_min, stats.leaf_max)
    );
}

fn triangle(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
    Triangle {
        v0: a,
        v1: b,
        v2: c,
        ..Default::default()
    }
}

fn sphere(center: [f32; 3], radius: f32) -> Sphere {
    Sphere {
        center,
        radius,
        ..Default::default()
    }
}

/// Closest hits through the BVH and by brute force agree (prim and t) for
/// each ray; any-hit agrees on occlusion.
fn check_rays(scene: &Scene, rays: &[Ray]) {
    let brute = common::brute_force(scene);
    let (fast, slow) = (Kernel::new(scene), Kernel::new(&brute));
    let mut hits = 0;
    for ray in rays {
        let (a, b) = (fast.trace_closest(*ray), slow.trace_closest(*ray));
        // Two primitives within rounding of the same t (on a shared edge, or
        // where a box's entry distance rounds past a hit) may be taken in
        // either order; beyond that, the hits must be the same.
        assert!(
            (a.t - b.t).abs() <= 1e-5 * b.t.abs(),
            "BVH t {} vs brute force t {} for {ray:?}",
            a.t,
            b.t
        );
        if a.prim != b.prim {
            let t_other = fast.intersect_primitive(ray, &ray_shear(ray.dir), a.prim).0;
            assert!(
                (t_other - b.t).abs() <= 1e-5 * b.t.abs(),
                "prim {} vs {} for {ray:?}",
                a.prim,
                b.prim
            );
        }
        assert_eq!(
            fast.trace_any(*ray),
            slow.trace_any(*ray),
            "any-hit differs for {ray:?}"
        );
        hits += (a.prim != NO_HIT) as usize;
    }
    assert!(hits > 0, "no ray hit anything: the test checks nothing");
}

/// Deterministic rays from around `centre` towards points near it.
fn random_rays(seed: u64, n: usize, centre: [f32; 3], spread: f32) -> Vec<Ray> {
    // SplitMix64: reproducible without another dependency.
    let mut state = seed;
    let mut unit = move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| {
            let o = [0, 1, 2].map(|a| centre[a] + spread * (2.0 * unit() - 1.0));
            let target = [0, 1, 2].map(|a| centre[a] + 0.5 * spread * (2.0 * unit() - 1.0));
            let dir = glam::Vec3::from(target) - glam::Vec3::from(o);
            Ray {
                origin: o.into(),
                tmin: 0.0,
                dir,
                tmax: lambert::layout::FAR,
            }
        })
        .collect()
}

#[test]
fn bundled_scenes_build_valid_trees_and_trace_like_brute_force() {
    for name in ["cornell", "spheres", "bunny", "dragon", "edge_cases"] {
        let s = load(name);
        check_structure(&s);
        let root = s.bvh().bounds().expect("a non-empty scene");
        let centre = root.centre().to_array();
        let spread = (root.max - root.min).max_element();
        check_rays(&s, &random_rays(7, 2000, centre, spread));
        println!(
            "{name}: {} nodes, depth {}, SAH cost {:.2}",
            s.bvh().nodes.len(),
            s.bvh().depth(),
            s.bvh().sah_cost()
        );
    }
}

#[test]
fn degenerate_inputs_build_and_trace() {
    let t = triangle([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let cases: Vec<(&str, Vec<Triangle>)> = vec![
        ("one triangle", vec![t]),
        ("identical triangles", vec![t; 1000]),
        // Zero areas make every SAH split cost the same, so the builder takes
        // the first bin each time: far deeper than the stack allows, unless
        // it falls back to median splits near the depth limit.
        (
            "zero-area triangles",
            (0..2000)
                .map(|i| {
                    let x = i as f32 * 0.001;
                    triangle([x, 0.0, 0.0], [x + 0.5, 0.0, 0.0], [x + 1.0, 0.0, 0.0])
                })
                .chain(std::iter::once(t))
                .collect(),
        ),
        (
            "flat scene",
            (0..400)
                .map(|i| {
                    let (x, y) = ((i % 20) as f32, (i / 20) as f32);
                    triangle([x, y, 0.0], [x + 1.0, y, 0.0], [x, y + 1.0, 0.0])
                })
                .collect(),
        ),
    ];
    for (what, triangles) in cases {
        let s = scene_of(triangles, vec![]);
        check_structure(&s);
        // Rays from in front of the z = 0 plane, aimed at it.
        let rays: Vec<Ray> = random_rays(3, 500, [0.5, 0.5, 3.0], 2.0)
            .into_iter()
            .map(|mut r| {
                r.dir.z = -r.dir.z.abs() - 0.5;
                r
            })
            .collect();
        check_rays(&s, &rays);
        println!("{what}: depth {}", s.bvh().depth());
    }
}

/// A corrupted tree fails validation with an error naming the node, the
/// slot and what is wrong: a leaf's box that does not hold its primitives,
/// a primitive in two leaves, one in none, and a compressed child box that
/// does not contain the exact one.
#[test]
fn validate_names_what_is_wrong_in_a_corrupted_tree() {
    use lambert::layout::{CompressedNode, LEAF_BIT, leaf_range};
    let scene = scene_of(
        (0..400)
            .map(|i| {
                let (x, y) = ((i % 20) as f32, (i / 20) as f32);
                triangle([x, y, 0.0], [x + 1.0, y, 0.0], [x, y + 1.0, 0.0])
            })
            .collect(),
        vec![],
    );
    let error = |bvh: &lambert::bvh::Bvh| {
        bvh.validate(scene.triangles(), scene.spheres())
            .expect_err("a corrupted tree passed")
            .to_string()
    };
    // Every leaf as (node, slot, first block, blocks).
    let leaves: Vec<(usize, usize, usize, usize)> = scene
        .bvh()
        .nodes
        .iter()
        .enumerate()
        .flat_map(|(i, n)| n.children.iter().enumerate().map(move |(s, &c)| (i, s, c)))
        .filter(|&(_, _, c)| c != u32::MAX && c & LEAF_BIT != 0)
        .map(|(i, s, c)| {
            let (first, count) = leaf_range(c);
            (i, s, first as usize, count as usize)
        })
        .collect();
    let used = |b: &lambert::layout::PrimBlock| b.prims.iter().filter(|&&p| p != NO_HIT).count();

    // A leaf's box shrunk to its minimum along x.
    let (node, slot, first, _) = leaves[0];
    let mut bvh = scene.bvh().clone();
    bvh.nodes[node].bounds[1][slot] = bvh.nodes[node].bounds[0][slot];
    let p = bvh.blocks[first].prims[0];
    let message = error(&bvh);
    assert!(
        message.starts_with(&format!(
            "BVH node {node}: slot {slot}: primitive {p}'s box"
        )) && message.contains("outside the leaf's box"),
        "{message}"
    );

    // The first leaf's first primitive copied over a lane of the last leaf.
    let (node, slot, last, _) = *leaves.last().unwrap();
    let mut bvh = scene.bvh().clone();
    let (from, mut to) = (bvh.blocks[first], bvh.blocks[last]);
    to.prims[0] = from.prims[0];
    for k in 0..3 {
        for a in 0..3 {
            to.v[k][a][0] = from.v[k][a][0];
        }
    }
    bvh.blocks[last] = to;
    let message = error(&bvh);
    assert!(
        message.starts_with(&format!(
            "BVH node {node}: slot {slot}: primitive {p} is also in node {} slot {}",
            leaves[0].0, leaves[0].1
        )),
        "{message}"
    );

    // A primitive dropped from a one-block leaf of two or more.
    let &(_, _, block, _) = leaves
        .iter()
        .find(|&&(_, _, first, count)| count == 1 && used(&scene.bvh().blocks[first]) >= 2)
        .expect("a one-block leaf of two primitives or more");
    let mut bvh = scene.bvh().clone();
    let lane = used(&bvh.blocks[block]) - 1;
    let dropped = bvh.blocks[block].prims[lane];
    bvh.blocks[block].prims[lane] = NO_HIT;
    for k in 0..3 {
        for a in 0..3 {
            bvh.blocks[block].v[k][a][lane] = 0.0;
        }
    }
    assert_eq!(
        error(&bvh),
        format!("BVH: primitive {dropped} is in no leaf")
    );

    // A compressed child's box shrunk to its minimum along x.
    let mut nodes = lambert::cwbvh::compress(scene.bvh());
    lambert::cwbvh::validate(&nodes, scene.bvh()).expect("the compressed tree is valid");
    let slot = (0..BVH_WIDTH)
        .find(|&s| CompressedNode::byte(nodes[0].child_meta, s) != 0)
        .unwrap();
    let min = CompressedNode::byte(nodes[0].q[0], slot);
    let row = &mut nodes[0].q[1][slot / 4];
    *row = *row & !(0xff << (8 * (slot % 4))) | min << (8 * (slot % 4));
    let message = lambert::cwbvh::validate(&nodes, scene.bvh())
        .expect_err("a shrunk compressed box passed")
        .to_string();
    assert!(
        message.starts_with(&format!(
            "compressed BVH node 0: slot {slot}: the quantised box"
        )) && message.contains("does not contain the exact one"),
        "{message}"
    );
}

proptest! {
    #![proptest_config(proptest_config(32, "bvh"))]
    #[test]
    fn random_scenes_trace_like_brute_force(
        tris in prop::collection::vec(prop::array::uniform9(-5.0f32..5.0), 1..300),
        spheres in prop::collection::vec((prop::array::uniform3(-5.0f32..5.0), 0.05f32..1.0), 0..20),
        seed in 0u64..1000,
    ) {
        let triangles = tris.iter().map(|v| triangle([v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]])).collect();
        let spheres = spheres.iter().map(|&(c, r)| sphere(c, r)).collect();
        let s = scene_of(triangles, spheres);
        check_structure(&s);
        check_rays(&s, &random_rays(seed, 200, [0.0; 3], 8.0));
    }
}

#[test]
fn gpu_bvh_and_brute_force_render_the_same_image() {
    for name in ["cornell", "bunny", "spheres", "edge_cases"] {
        let s = load(name);
        let brute = common::brute_force(&s);
        let (a, b) = (render_gpu(&s), render_gpu(&brute));
        // edge_cases aims its centre row and column exactly along shared
        // edges, where two triangles tie on t: brute force takes the lower
        // id, the BVH the first it visits. Those 2·65 pixels may differ in id
        // (not in colour); everywhere else the default bound holds.
        let ties = if name == "edge_cases" {
            130.0 / 4225.0
        } else {
            0.0
        };
        let tolerance = lambert::diff::Tolerance {
            max_prim_mismatch_fraction: lambert::diff::Tolerance::default()
                .max_prim_mismatch_fraction
                + ties,
            ..Default::default()
        };
        let stats = lambert::diff::compare(&a, &b, &tolerance).unwrap();
        println!("{name}: GPU BVH vs GPU brute force\n{stats}");
        assert!(stats.passed, "{name}:\n{stats}");
        // The BVH path on the GPU also matches the CPU reference's BVH path.
        let stats =
            lambert::diff::compare(&a, &render_cpu(&s), &lambert::diff::Tolerance::default())
                .unwrap();
        assert!(stats.passed, "{name} GPU vs CPU through the BVH:\n{stats}");
    }
}

/// The slab test in one 8-lane register (x86 with AVX2 and FMA, which node
/// visits take where the CPU has them) gives what the portable two halves
/// give, bit for bit: entry distances of every lane and the entered mask,
/// for random rays and boxes, and for rays with zero, tiny, infinite or NaN
/// components, a shortened tmax and a tmin past some boxes. Must run where
/// CI runs: on a CPU without AVX2 it fails rather than passing untested,
/// unless LAMBERT_NO_YMM_TEST says the machine is known to lack it.
#[test]
fn slab_test_in_one_register_equals_the_portable_one() {
    use lambert::cpu::Scalar;
    use lambert::cpu::f32::{intersect_boxes, ray_slabs};
    use lambert::layout::{BvhNode, leaf_ref};
    if !<f32 as Scalar>::has_ymm_boxes() {
        assert!(
            std::env::var_os("LAMBERT_NO_YMM_TEST").is_some(),
            "this CPU lacks AVX2 or FMA: set LAMBERT_NO_YMM_TEST=1 to skip"
        );
        return;
    }
    let mut rays = random_rays(21, 3000, [0.0; 3], 4.0);
    let boxes = random_rays(22, 3000, [0.0; 3], 2.0);
    let odd = [0.0, -0.0, 1e-30, -1e-20, f32::INFINITY, f32::NAN, 1.0];
    for (i, &x) in odd.iter().enumerate() {
        for (j, &y) in odd.iter().enumerate() {
            let origin = Vec3::new(odd[(i + j) % odd.len()].min(3.0), -2.5, 0.25);
            rays.push(Ray {
                origin,
                tmin: 0.0,
                dir: Vec3::new(x, 1.0, y),
                tmax: lambert::layout::FAR,
            });
        }
    }
    for (i, ray) in rays.iter_mut().enumerate() {
        if i % 3 == 1 {
            ray.tmax = 1.5;
        }
        if i % 5 == 2 {
            ray.tmin = 0.75;
        }
    }
    let mut entered = 0;
    for (i, ray) in rays.iter().enumerate() {
        let mut node = BvhNode::EMPTY;
        // Up to eight boxes from random points, some slots left empty.
        for slot in (0..BVH_WIDTH).filter(|s| (i + s) % 6 != 0) {
            let b = &boxes[(i * 8 + slot) % boxes.len()];
            let (p, q) = (b.origin, b.origin + b.dir * 0.3);
            let leaf = leaf_ref(slot as u32, 1);
            node.set_child(slot, leaf, p.min(q).to_array(), p.max(q).to_array());
        }
        let slabs = ray_slabs(ray);
        let portable = intersect_boxes(ray, &slabs, &node);
        // SAFETY: has_ymm_boxes() holds.
        let ymm = unsafe { <f32 as Scalar>::intersect_boxes_ymm(ray, &slabs, &node) };
        assert_eq!(portable.entered, ymm.entered, "entered boxes for {ray:?}");
        assert_eq!(
            portable.t.map(f32::to_bits),
            ymm.t.map(f32::to_bits),
            "entry distances for {ray:?}"
        );
        entered += portable.entered.count_ones();
    }
    assert!(entered > 100, "too few boxes entered: {entered}");
}

/// The 8-lane slab test against a plain f64 one, box by box: entry distance
/// within rounding where both see a hit, and never a miss where the exact
/// test sees the ray pass through the box's interior; finite rays miss empty
/// slots; a ray lying in a face's plane, parallel to it, still enters.
#[test]
fn slab_test_of_eight_boxes_matches_a_plain_one() {
    use lambert::cpu::f32::{intersect_boxes, ray_slabs};
    use lambert::layout::{BvhNode, FAR, leaf_ref};
    let rays = random_rays(11, 4000, [0.0; 3], 4.0);
    let boxes = random_rays(12, 4000, [0.0; 3], 2.0);
    let mut entered = 0;
    for (i, ray) in rays.iter().enumerate() {
        let mut node = BvhNode::EMPTY;
        // Seven boxes from random points; slot 7 stays empty.
        for slot in 0..7 {
            let b = &boxes[(i * 7 + slot) % boxes.len()];
            let (p, q) = (b.origin, b.origin + b.dir * 0.3);
            let leaf = leaf_ref(slot as u32, 1);
            node.set_child(slot, leaf, p.min(q).to_array(), p.max(q).to_array());
        }
        let boxes = intersect_boxes(ray, &ray_slabs(ray), &node);
        assert_eq!(
            boxes.entered & 128,
            0,
            "an empty slot was entered by {ray:?}"
        );
        for slot in 0..7 {
            let t_slot = boxes.t[slot];
            let hit = boxes.entered & (1 << slot) != 0;
            let (lo, hi) = node.child_bounds(slot);
            let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
            let (mut near, mut far) = (ray.tmin as f64, ray.tmax as f64);
            for a in 0..3 {
                let (t0, t1) = ((lo[a] as f64 - o[a]) / d[a], (hi[a] as f64 - o[a]) / d[a]);
                near = near.max(t0.min(t1));
                far = far.min(t0.max(t1));
            }
            // The per-ray offsets are moved outward by 8 units of roundoff
            // of origin / direction: an entry may come that much early.
            let offset = (0..3).map(|a| (o[a] / d[a]).abs()).fold(0.0, f64::max);
            if near < far * (1.0 - 1e-5) {
                entered += 1;
                assert!(hit, "slot {slot} missed, exact: hit, {ray:?}");
                assert!(
                    (t_slot as f64 - near).abs() <= 1e-5 * near.abs().max(1e-3) + 1e-6 * offset,
                    "slot {slot}: {t_slot} vs exact {near} for {ray:?}"
                );
            } else if near > far * (1.0 + 1e-5) {
                assert!(!hit, "slot {slot} entered, exact: miss, {ray:?}");
            }
        }
    }
    assert!(entered > 100, "too few rays entered a box: {entered}");
    // Parallel to the z slab of a unit box: outside it, the ray misses;
    // along its face z = 1 (the plane's distance near 0, the other's huge),
    // it enters at x = 0.
    let mut node = BvhNode::EMPTY;
    node.set_child(0, leaf_ref(0, 1), [0.0; 3], [1.0; 3]);
    for (z, dir) in [(1.5, 0.0), (-0.5, 0.0), (1.5, -0.0), (-1e-3, -0.0)] {
        let ray = Ray {
            origin: Vec3::new(-1.0, 0.5, z),
            tmin: 0.0,
            dir: Vec3::new(1.0, 0.0, dir),
            tmax: FAR,
        };
        let boxes = intersect_boxes(&ray, &ray_slabs(&ray), &node);
        assert_eq!(
            boxes.entered & 1,
            0,
            "parallel ray outside the box: {ray:?}"
        );
    }
    for dir in [Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, -0.0)] {
        let ray = Ray {
            origin: Vec3::new(-1.0, 0.5, 1.0),
            tmin: 0.0,
            dir,
            tmax: FAR,
        };
        let boxes = intersect_boxes(&ray, &ray_slabs(&ray), &node);
        assert_eq!(boxes.entered & 1, 1, "grazing ray with direction {dir:?}");
        assert!(
            (boxes.t[0] - 1.0).abs() < 1e-6,
            "grazing ray with direction {dir:?} enters at {}",
            boxes.t[0]
        );
    }
}

/// Random small triangles, enough that incoherent rays through their BVH
/// are traced eight at a time, with prefetching, rather than two.
fn soup() -> Scene {
    let soup = scene_of(
        random_rays(9, 400_000, [0.0; 3], 1.0)
            .iter()
            .map(|r| {
                let (p, d) = (r.origin, 0.01 * r.dir);
                triangle(
                    p.into(),
                    (p + d).into(),
                    (p + Vec3::new(d.y, d.z, d.x)).into(),
                )
            })
            .collect(),
        Vec::new(),
    );
    let bvh_bytes = soup.bvh().device_bytes();
    assert!(
        bvh_bytes > lambert::cpu::LARGE_BVH_BYTES,
        "{bvh_bytes} bytes"
    );
    soup
}

/// Random rays from around `scene`'s bounds, as a ray query.
fn query_rays(scene: &Scene, seed: u64, n: usize) -> Vec<lambert::layout::Ray> {
    let root = scene.bvh().bounds().expect("a non-empty scene");
    let spread = (root.max - root.min).max_element();
    random_rays(seed, n, root.centre().to_array(), spread)
        .iter()
        .map(|r| lambert::layout::Ray {
            origin: r.origin.to_array(),
            tmin: r.tmin,
            dir: r.dir.to_array(),
            tmax: r.tmax,
        })
        .collect()
}

/// Every SIMD kernel this CPU runs gives the portable kernel's hits and
/// pixels bit for bit: camera and random rays, closest and any hit, through
/// BVHs small and larger than cache (each of `trace_rays`' chunk kinds).
/// A kernel the CPU lacks is skipped, saying so.
#[test]
fn every_cpu_kernel_equals_the_portable_one() {
    use lambert::cpu::{CpuKernel, Precision, render_with, trace_rays_with};
    use std::io::Write;
    let scenes = [
        ("bunny", load("bunny")),
        ("spheres", load("spheres")),
        ("soup", soup()),
    ];
    for kernel in CpuKernel::ALL {
        if let Some(missing) = kernel.missing() {
            // Straight to stderr: the harness hides eprintln! of a passing test.
            let _ = writeln!(
                std::io::stderr(),
                "skipped: the {} kernel needs {missing}, which this CPU lacks",
                kernel.name()
            );
            continue;
        }
        for (name, scene) in &scenes {
            let camera = lambert::rays::camera_rays(scene);
            for (rays, what) in [(query_rays(scene, 5, 5001), "random"), (camera, "camera")] {
                for any_hit in [false, true] {
                    let portable = trace_rays_with(
                        scene,
                        &rays,
                        any_hit,
                        scene.default_settings().intersect,
                        CpuKernel::Portable,
                    );
                    let simd = trace_rays_with(
                        scene,
                        &rays,
                        any_hit,
                        scene.default_settings().intersect,
                        kernel,
                    );
                    for (i, (a, b)) in portable.iter().zip(&simd).enumerate() {
                        assert_eq!(
                            (a.prim, a.t.to_bits(), a.u.to_bits(), a.v.to_bits()),
                            (b.prim, b.t.to_bits(), b.u.to_bits(), b.v.to_bits()),
                            "{name}, {what} ray {i}, any_hit {any_hit}: {} kernel",
                            kernel.name()
                        );
                    }
                }
            }
            if *name != "soup" {
                let hidden = lambert::progress::Progress::hidden();
                let portable = render_with(
                    scene,
                    scene.view(),
                    Precision::F32,
                    &hidden,
                    CpuKernel::Portable,
                );
                let simd = render_with(scene, scene.view(), Precision::F32, &hidden, kernel);
                assert_eq!(
                    portable.prims,
                    simd.prims,
                    "{name}: {} kernel",
                    kernel.name()
                );
                assert_eq!(
                    bits(&portable),
                    bits(&simd),
                    "{name}: {} kernel",
                    kernel.name()
                );
            }
        }
    }
}

/// `cpu::trace_rays` traces two or eight rays at a time per thread, a node
/// visit each in turn; every ray must get exactly the hit it gets alone.
#[test]
fn interleaved_ray_queries_equal_single_ray_traces() {
    for (name, scene) in [
        ("bunny", load("bunny")),
        ("spheres", load("spheres")),
        ("soup", soup()),
    ] {
        let kernel = Kernel::new(&scene);
        // An odd count over several chunks, so that lanes run dry unevenly.
        let rays = query_rays(&scene, 5, 5001);
        for any_hit in [false, true] {
            let hits = lambert::cpu::trace_rays(&scene, &rays, any_hit);
            let mut hit_count = 0;
            for (ray, hit) in rays.iter().zip(&hits) {
                let alone = kernel.trace(Ray::from_query(ray), any_hit);
                assert_eq!(hit.prim, alone.prim, "{name}: {ray:?}");
                if alone.prim != NO_HIT {
                    assert_eq!((hit.t, hit.u, hit.v), (alone.t, alone.u, alone.v));
                    hit_count += 1;
                }
            }
            assert!(hit_count > 100, "{name}: only {hit_count} rays hit");
        }
    }
}

/// A ray with a NaN or infinite component (a degenerate triangle's NaN
/// normal makes one) can pass the slab test of an empty slot's inverted
/// box; traversal must still never enter an empty slot, and answer as brute
/// force does, on both paths. Without the `occupied` mask the CPU path
/// panics here (the NaN and all-infinite directions reach an empty slot);
/// the GPU's robust buffer access would hide its out-of-bounds read, so its
/// half checks that both paths agree, relying on IEEE NaN and infinity
/// behaviour, which WGSL permits an implementation to skip but every
/// adapter we run on has.
#[test]
fn rays_with_nan_or_infinite_components_trace_like_brute_force() {
    let t = triangle([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let far_t = triangle([5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]);
    let sphere = sphere([0.0, 3.0, 0.0], 0.5);
    let scene = scene_of(vec![t, far_t], vec![sphere]);
    assert_ne!(
        scene.bvh().nodes[0].occupied,
        0b1111,
        "the root has no empty slot"
    );
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let query = |origin: [f32; 3], dir: [f32; 3], tmin: f32, tmax: f32| lambert::layout::Ray {
        origin,
        tmin,
        dir,
        tmax,
    };
    let down = [0.0, 0.0, -1.0];
    let rays = vec![
        query([0.2, 0.2, 1.0], [nan; 3], 0.0, inf),
        query([0.2, 0.2, 1.0], [nan, 0.0, -1.0], 0.0, inf),
        query([nan; 3], down, 0.0, inf),
        query([0.2, 0.2, nan], down, 0.0, inf),
        query([inf, 0.2, 1.0], down, 0.0, inf),
        query([0.2, 0.2, inf], down, 0.0, inf),
        query([0.2, 0.2, 1.0], [0.0, 0.0, -inf], 0.0, inf),
        query([0.2, 0.2, 1.0], [inf; 3], 0.0, inf),
        query([0.2, 0.2, 1.0], [-inf; 3], 0.0, inf),
        query([0.2, 0.2, 1.0], [0.0; 3], 0.0, inf),
        query([0.2, 0.2, 1.0], down, nan, inf),
        query([0.2, 0.2, 1.0], down, 0.0, nan),
        // A finite ray that hits, so that the comparison is not all misses.
        query([0.2, 0.2, 1.0], down, 0.0, inf),
    ];
    let brute = common::brute_force(&scene);
    let expected = |any_hit| {
        let prims = hit_prims(&trace_cpu(&brute, &rays, any_hit));
        assert_eq!(prims.last(), Some(&0), "the finite ray hits triangle 0");
        prims
    };
    assert_both_paths_give(&scene, &rays, expected, "BVH vs brute force");
}

fn hit_prims(hits: &[lambert::layout::Hit]) -> Vec<u32> {
    hits.iter().map(|h| h.prim).collect()
}

/// `scene` gives `rays` the primitives `expected(any_hit)` on the CPU and
/// the GPU path, for closest and for any hits.
fn assert_both_paths_give(
    scene: &Scene,
    rays: &[lambert::layout::Ray],
    expected: impl Fn(bool) -> Vec<u32>,
    what: &str,
) {
    for any_hit in [false, true] {
        let expected = expected(any_hit);
        let cpu = hit_prims(&trace_cpu(scene, rays, any_hit));
        assert_eq!(cpu, expected, "{what}: CPU, any_hit {any_hit}");
        let gpu = hit_prims(&trace_gpu(scene, rays, any_hit));
        assert_eq!(gpu, expected, "{what}: GPU, any_hit {any_hit}");
    }
}

/// The 4-lane watertight test of a leaf block gives each lane exactly what
/// the one-triangle test gives (t, u and v bit for bit), as the shader's
/// and the CPU's blocks rely on; lanes that hold no triangle never hit.
#[test]
fn block_test_matches_the_one_triangle_test_bit_for_bit() {
    use lambert::cpu::f32::{intersect_triangle_block, intersect_triangle_watertight};
    use lambert::layout::{FAR, PrimBlock};
    let rays = random_rays(21, 3000, [0.0; 3], 3.0);
    // Random points near the centre, as vertices.
    let points: Vec<Vec3> = random_rays(22, 3000 * 12, [0.0; 3], 1.5)
        .iter()
        .map(|r| r.origin)
        .collect();
    let mut hits = 0;
    for (i, ray) in rays.iter().enumerate() {
        let p = |l: usize, k: usize| points[i * 12 + l * 3 + k];
        let triangles: Vec<Triangle> = (0..4)
            .map(|l| triangle(p(l, 0).into(), p(l, 1).into(), p(l, 2).into()))
            .collect();
        // On odd rays lane 3 is primitive 3 beyond the triangles (a sphere).
        let n = if i % 2 == 0 { 4 } else { 3 };
        let block = PrimBlock::new(&[0, 1, 2, 3], &triangles[..n]);
        let shear = ray_shear(ray.dir);
        let lanes = intersect_triangle_block(ray, &shear, &block);
        for (lane, t) in lanes.t.to_array().into_iter().enumerate() {
            let expected = if lane < n {
                let [a, b, c] = [0, 1, 2].map(|k| p(lane, k));
                intersect_triangle_watertight(ray, &shear, a, b, c)
            } else {
                (FAR, 0.0, 0.0)
            };
            assert_eq!(t.to_bits(), expected.0.to_bits(), "lane {lane} t, {ray:?}");
            if expected.0 != FAR {
                let (u, v) = lanes.uv(lane);
                assert_eq!(
                    (u.to_bits(), v.to_bits()),
                    (expected.1.to_bits(), expected.2.to_bits()),
                    "lane {lane} u, v, {ray:?}"
                );
                hits += 1;
            }
        }
    }
    assert!(hits > 200, "only {hits} lanes hit: the test checks little");
}

/// Traversal takes hits only from a block's triangle lanes: vertices in an
/// empty or a sphere lane (zero in a real block; a GPU that fuses
/// multiply-adds can find a hit in those) must not count, on either path.
/// Here they are made a large triangle in front of everything.
#[test]
fn block_lanes_that_hold_no_triangle_never_hit() {
    let t = triangle([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let u = triangle([0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 2.0, 0.0]);
    let sphere = sphere([3.0, 0.5, 0.0], 0.5);
    for (what, spheres) in [("empty lane", vec![]), ("sphere lane", vec![sphere])] {
        let scene = scene_of(vec![t, u], spheres);
        assert_eq!(scene.bvh().blocks.len(), 1, "{what}: one block");
        let rays: Vec<lambert::layout::Ray> = random_rays(31, 400, [0.5, 0.5, 3.0], 2.0)
            .iter()
            .map(|r| lambert::layout::Ray {
                origin: r.origin.to_array(),
                tmin: 0.0,
                dir: [r.dir.x, r.dir.y, -r.dir.z.abs() - 0.5],
                tmax: f32::INFINITY,
            })
            .collect();
        let mut doctored = scene.clone();
        let mut bvh = doctored.bvh().clone();
        let block = &mut bvh.blocks[0];
        let cover = [[-50.0, -50.0, 1.0], [50.0, -50.0, 1.0], [0.0, 50.0, 1.0]];
        for (k, vertex) in cover.iter().enumerate() {
            for (a, &x) in vertex.iter().enumerate() {
                block.v[k][a][2] = x;
                block.v[k][a][3] = x;
            }
        }
        doctored.replace_bvh(bvh);
        let expected = |any_hit| {
            let prims = hit_prims(&trace_cpu(&scene, &rays, any_hit));
            assert!(prims.iter().any(|&p| p != NO_HIT), "{what}: nothing hit");
            prims
        };
        assert_both_paths_give(&doctored, &rays, expected, what);
    }
}
