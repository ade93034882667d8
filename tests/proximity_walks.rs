//! Issue 48, item 4: the CPU's point queries walk faster with the same
//! answers. Closest points go depth first, each node's children nearest
//! first, and must still find the best candidate by `better`'s total order
//! (the brute-force minimum, bit for bit) wherever the walk starts; winding
//! numbers take a leaf's triangles four at a time (`triangle_winding4`),
//! which must be `triangle_winding` lane for lane, bit for bit.

use glam::Vec3;
use lambert::Scene;
use lambert::cpu::closest::{better, closest_point, closest_point_triangle, query_margin};
use lambert::cpu::winding::{triangle_winding, triangle_winding4};
use lambert::cpu::{CpuKernel, Scalar, closest_points_with};
use lambert::layout::{LEAF_BIT, NO_HIT, Triangle, leaf_range};
use lambert::probe::Rng;

fn point(rng: &mut Rng, half: f64) -> Vec3 {
    Vec3::new(
        rng.range(-half, half) as f32,
        rng.range(-half, half) as f32,
        rng.range(-half, half) as f32,
    )
}

/// `n` small triangles around the cube of side 2 at the origin, and a
/// strip of triangles sharing edges and vertices (ties).
fn triangles(seed: u64, n: usize) -> Vec<Triangle> {
    let mut rng = Rng(seed);
    let mut out: Vec<Triangle> = (0..n)
        .map(|_| {
            let p = point(&mut rng, 1.0);
            let [v0, v1, v2] = [0; 3].map(|_| (p + point(&mut rng, 0.1)).to_array());
            Triangle {
                v0,
                v1,
                v2,
                ..Default::default()
            }
        })
        .collect();
    for i in 0..40 {
        let x = i as f32 * 0.05 - 1.0;
        let corner = |dx: f32, y: f32| [x + dx, y, 1.5];
        out.push(Triangle {
            v0: corner(0.0, 0.0),
            v1: corner(0.05, 0.0),
            v2: corner(0.0, 0.05),
            ..Default::default()
        });
        out.push(Triangle {
            v0: corner(0.05, 0.0),
            v1: corner(0.05, 0.05),
            v2: corner(0.0, 0.05),
            ..Default::default()
        });
    }
    out
}

/// Leaves' blocks one at a time, and where this CPU runs f32's `Wide`
/// (AVX on x86), a leaf's two blocks at once.
fn widths() -> impl Iterator<Item = bool> + Clone {
    let wide = <f32 as Scalar>::has_wide(CpuKernel::active());
    [false, true].into_iter().filter(move |&w| !w || wide)
}

/// The depth-first walk finds `better`'s minimum over every triangle, bit
/// for bit (point, distance, id, u, v), with and without a hint, a leaf's
/// blocks one at a time or two at once (`widths`), for points inside the
/// soup, far outside it and on the strip's shared vertices, through a BVH
/// of many levels.
#[test]
fn the_depth_first_walk_finds_the_brute_force_minimum() {
    let triangles = triangles(3, 20_000);
    let scene = Scene::from_triangles(triangles.clone());
    let radius = scene.placement().radius as f32;
    let mut rng = Rng(4);
    let mut points: Vec<Vec3> = (0..200).map(|_| point(&mut rng, 1.2)).collect();
    points.extend((0..100).map(|_| point(&mut rng, 6.0)));
    points.extend(triangles[20_000..].iter().map(|t| Vec3::from(t.v1)));
    let mut queue = Vec::new();
    for (i, &p) in points.iter().enumerate() {
        let mut best = (f32::INFINITY, NO_HIT, Vec3::ZERO, 0.0, 0.0);
        for (id, t) in triangles.iter().enumerate() {
            let (q, d2, u, v) = closest_point_triangle(p, t.v0.into(), t.v1.into(), t.v2.into());
            if better(d2, id as u32, best.0, best.1) {
                best = (d2, id as u32, q, u, v);
            }
        }
        let hint_id = (i * 7919) % triangles.len();
        let t = &triangles[hint_id];
        let hint = (hint_id as u32, [t.v0, t.v1, t.v2].map(Vec3::from));
        let margin = query_margin(p.abs().max_element(), radius);
        for (hint, wide) in [None, Some(hint)]
            .into_iter()
            .flat_map(|h| widths().map(move |w| (h, w)))
        {
            let found = closest_point(
                scene.bvh(),
                triangles.len(),
                p,
                f32::INFINITY,
                margin,
                hint,
                &mut queue,
                wide,
            )
            .expect("a nearest triangle");
            assert_eq!(
                (
                    found.prim,
                    found.d2.to_bits(),
                    found.u.to_bits(),
                    found.v.to_bits(),
                    found.point.to_array().map(f32::to_bits)
                ),
                (
                    best.1,
                    best.0.to_bits(),
                    best.3.to_bits(),
                    best.4.to_bits(),
                    best.2.to_array().map(f32::to_bits)
                ),
                "point {i} {p}, hint {hint:?}, wide {wide}"
            );
        }
    }
}

/// `closest_points` compiled for each CPU kernel this machine runs gives
/// the portable kernel's answers, bit for bit: points in the soup, far
/// outside it and on the strip's shared vertices, with and without a
/// largest distance (some points then find none).
#[test]
fn every_cpu_kernel_finds_the_portable_kernels_closest_points() {
    let triangles = triangles(5, 20_000);
    let scene = Scene::from_triangles(triangles.clone());
    let mut rng = Rng(6);
    let mut points: Vec<[f32; 3]> = (0..3000).map(|_| point(&mut rng, 1.2).to_array()).collect();
    points.extend((0..500).map(|_| point(&mut rng, 6.0).to_array()));
    points.extend(triangles[20_000..].iter().map(|t| t.v1));
    let mut compared = 0;
    for max_distance in [f32::INFINITY, 0.02] {
        let portable = closest_points_with(&scene, &points, max_distance, CpuKernel::Portable);
        assert!(portable.iter().any(|c| c.prim == NO_HIT) == max_distance.is_finite());
        for kernel in CpuKernel::ALL {
            if let Some(missing) = kernel.missing() {
                eprintln!("skipped: the {} kernel needs {missing}", kernel.name());
                continue;
            }
            let found = closest_points_with(&scene, &points, max_distance, kernel);
            for (i, (a, b)) in found.iter().zip(&portable).enumerate() {
                assert_eq!(
                    bytemuck::bytes_of(a),
                    bytemuck::bytes_of(b),
                    "point {i} {:?}, the {} kernel, max distance {max_distance}",
                    points[i],
                    kernel.name()
                );
            }
            compared += 1;
        }
    }
    assert!(compared >= 2);
}

/// Four lanes of `triangle_winding4` are four calls of `triangle_winding`,
/// bit for bit: random triangles and points, points on a corner (0), in a
/// triangle's plane, and behind and in front of it (every branch of the
/// arctangent).
#[test]
fn four_lane_windings_are_the_scalar_ones_bit_for_bit() {
    let triangles = triangles(5, 400);
    let mut rng = Rng(6);
    for group in triangles.chunks(4) {
        let mut points: Vec<Vec3> = (0..30).map(|_| point(&mut rng, 2.0)).collect();
        let t = &group[0];
        let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
        points.extend([a, (a + b + c) / 3.0, 2.0 * a - b, (a + b) / 2.0]);
        for p in points {
            let corners = |v: fn(&Triangle) -> [f32; 3]| {
                [0, 1, 2].map(|axis| glam::Vec4::from(std::array::from_fn(|k| v(&group[k])[axis])))
            };
            let lanes =
                triangle_winding4(p, [corners(|t| t.v0), corners(|t| t.v1), corners(|t| t.v2)])
                    .to_array();
            for (k, t) in group.iter().enumerate() {
                let scalar = triangle_winding(p, t.v0.into(), t.v1.into(), t.v2.into());
                assert_eq!(lanes[k].to_bits(), scalar.to_bits(), "{p} {t:?}");
            }
        }
    }
}

/// The f64 walk (the oracle) gives the same answers, bit for bit, with a
/// leaf's two blocks at once (`Scalar::Wide`: two 4-lane vectors) as one
/// at a time, ties on the strip's shared vertices included.
#[test]
fn the_f64_walk_gives_the_same_answers_two_blocks_at_once() {
    use lambert::cpu::f64;
    let triangles = triangles(7, 5_000);
    let scene = Scene::from_triangles(triangles.clone());
    let radius = scene.placement().radius;
    let mut rng = Rng(8);
    let mut points: Vec<Vec3> = (0..300).map(|_| point(&mut rng, 1.2)).collect();
    points.extend((0..100).map(|_| point(&mut rng, 6.0)));
    points.extend(triangles[5_000..].iter().map(|t| Vec3::from(t.v2)));
    let mut queue = f64::BoxQueue::new();
    let mut pairs = 0;
    for p in points {
        let p = p.as_dvec3();
        let margin = f64::query_margin(p.abs().max_element(), radius);
        let [one, two] = [false, true].map(|wide| {
            f64::closest_point(
                scene.bvh(),
                triangles.len(),
                p,
                f64::INFINITY,
                margin,
                None,
                &mut queue,
                wide,
            )
            .expect("a nearest triangle")
        });
        let bits = |n: f64::Nearest| {
            (
                n.prim,
                n.d2.to_bits(),
                n.u.to_bits(),
                n.v.to_bits(),
                n.point.to_array().map(f64::Real::to_bits),
            )
        };
        assert_eq!(bits(two), bits(one), "{p}");
        pairs += 1;
    }
    assert_eq!(pairs, 480);
    // Leaves of two blocks, which `wide` takes at once.
    let two_block_leaves = scene
        .bvh()
        .nodes
        .iter()
        .flat_map(|n| {
            (0..8)
                .filter(move |s| n.occupied & 1 << s != 0)
                .map(move |s| n.children[s])
        })
        .filter(|&c| c & LEAF_BIT != 0 && leaf_range(c).1 == 2)
        .count();
    assert!(
        two_block_leaves > 100,
        "{two_block_leaves} leaves of two blocks"
    );
}
