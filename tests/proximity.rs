//! The geometric queries (closest points, winding numbers, every hit
//! along rays) against brute-force f64 references over every triangle.

use std::sync::Arc;

use glam::DVec3;
use lambert::layout::{ClosestPoint, NO_HIT, Ray, Sphere, Triangle};
use lambert::render::Renderer;
use lambert::scene::Scene;

mod common;

use common::data::{Lcg, d3, ray, sphere_mesh, tri, winding_f64};

fn cpu(triangles: Vec<Triangle>) -> Renderer {
    Renderer::Cpu(Arc::new(Scene::from_triangles(triangles)))
}

/// The exact (f64) nearest point of a triangle: the projection where it
/// falls inside, else the nearest point of the three edges.
fn closest_f64(p: DVec3, t: &Triangle) -> (f64, DVec3) {
    let (a, b, c) = (d3(t.v0), d3(t.v1), d3(t.v2));
    let n = (b - a).cross(c - a);
    let mut best = (f64::INFINITY, a);
    if n.length_squared() > 0.0 {
        let q = p - n * (p - a).dot(n) / n.length_squared();
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(s, e)| (e - s).cross(q - s).dot(n) >= 0.0);
        if inside {
            best = ((p - q).length(), q);
        }
    }
    for (s, e) in [(a, b), (a, c), (b, c)] {
        let d = e - s;
        let t = if d.length_squared() > 0.0 {
            ((p - s).dot(d) / d.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let q = s + d * t;
        if (p - q).length() < best.0 {
            best = ((p - q).length(), q);
        }
    }
    best
}

/// A soup of random triangles in [−1, 1]³, degenerate ones among them.
fn soup(seed: u64, n: usize) -> Vec<Triangle> {
    let mut rng = Lcg(seed);
    let mut triangles: Vec<Triangle> = (0..n)
        .map(|_| {
            let a = rng.point(-1.0, 1.0);
            let b = [
                a[0] + rng.range(-0.3, 0.3),
                a[1] + rng.range(-0.3, 0.3),
                a[2] + rng.range(-0.3, 0.3),
            ];
            let c = [
                a[0] + rng.range(-0.3, 0.3),
                a[1] + rng.range(-0.3, 0.3),
                a[2] + rng.range(-0.3, 0.3),
            ];
            tri(a, b, c)
        })
        .collect();
    // Degenerate: a repeated vertex, collinear vertices, a point.
    triangles.push(tri([0.5, 0.5, 0.5], [0.5, 0.5, 0.5], [0.7, 0.5, 0.5]));
    triangles.push(tri([-0.5, 0.2, 0.1], [-0.3, 0.4, 0.1], [-0.1, 0.6, 0.1]));
    triangles.push(tri([0.1, -0.9, 0.3], [0.1, -0.9, 0.3], [0.1, -0.9, 0.3]));
    triangles
}

fn check_closest(
    triangles: &[Triangle],
    points: &[[f32; 3]],
    answers: &[ClosestPoint],
    scale: f64,
) {
    for (i, (p, a)) in points.iter().zip(answers).enumerate() {
        let p = d3(*p);
        let exact = triangles
            .iter()
            .map(|t| closest_f64(p, t).0)
            .fold(f64::INFINITY, f64::min);
        assert_ne!(a.prim, NO_HIT, "point {i}");
        let tol = 1e-5 * scale;
        assert!(
            (a.distance as f64 - exact).abs() <= tol,
            "point {i}: distance {} against {exact}",
            a.distance
        );
        // The triangle named is (one of) the nearest, and the point and
        // (u, v) lie on it where the distance says.
        let t = &triangles[a.prim as usize];
        assert!(
            (closest_f64(p, t).0 - exact).abs() <= tol,
            "point {i}: triangle {} is not the nearest",
            a.prim
        );
        let (u, v) = (a.u as f64, a.v as f64);
        let on = d3(t.v0) * (1.0 - u - v) + d3(t.v1) * u + d3(t.v2) * v;
        assert!(
            (on - d3(a.point)).length() <= tol,
            "point {i}: (u, v) = ({u}, {v}) is not the point"
        );
        assert!(
            ((d3(a.point) - p).length() - exact).abs() <= tol,
            "point {i}: the point is not at the distance"
        );
    }
}

#[test]
fn closest_points_match_brute_force_on_random_soups() {
    for seed in 1..4 {
        let triangles = soup(seed, 300);
        let mut renderer = cpu(triangles.clone());
        let mut rng = Lcg(seed + 100);
        let mut points: Vec<[f32; 3]> = (0..500).map(|_| rng.point(-1.5, 1.5)).collect();
        // Far points, and points on vertices and edges.
        points.extend([[40.0, -30.0, 20.0], [-1e4, 3.0, 2.0]]);
        for t in triangles.iter().take(50) {
            points.push(t.v1);
            points.push([
                0.5 * (t.v0[0] + t.v2[0]),
                0.5 * (t.v0[1] + t.v2[1]),
                0.5 * (t.v0[2] + t.v2[2]),
            ]);
        }
        let answers = renderer.closest_points(&points, f32::INFINITY).unwrap();
        let scale = |p: &[f32; 3]| d3(*p).abs().max_element().max(1.5);
        for (p, a) in points.iter().zip(&answers) {
            check_closest(
                &triangles,
                std::slice::from_ref(p),
                std::slice::from_ref(a),
                scale(p),
            );
        }
    }
}

/// Four triangles about `c` in its plane z = c.z, out to c ± x and c ± y,
/// counter-clockwise from +x.
fn fan(c: [f32; 3]) -> Vec<Triangle> {
    let ring =
        [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]].map(|[x, y]| [c[0] + x, c[1] + y, c[2]]);
    (0..4).map(|k| tri(c, ring[k], ring[(k + 1) % 4])).collect()
}

#[test]
fn a_point_on_a_shared_vertex_goes_to_the_lowest_triangle() {
    // A fan of four triangles about the origin, listed so that the lowest id
    // is not the first the traversal would meet.
    let mut triangles = fan([0.0, 0.0, 0.0]);
    triangles.extend(soup(9, 40).into_iter().map(|t| Triangle {
        v0: t.v0.map(|x| x + 5.0),
        v1: t.v1.map(|x| x + 5.0),
        v2: t.v2.map(|x| x + 5.0),
        ..t
    }));
    let mut renderer = cpu(triangles);
    let answers = renderer
        .closest_points(
            &[
                [0.0, 0.0, 0.5],
                [0.0, 0.0, -2.0],
                [0.5, 0.0, 1.0],
                [0.0, 0.5, 0.0],
            ],
            f32::INFINITY,
        )
        .unwrap();
    // Above the centre vertex: all four at distance 0.5; the lowest is 0.
    assert_eq!((answers[0].prim, answers[0].distance), (0, 0.5));
    assert_eq!(answers[0].point, [0.0; 3]);
    assert_eq!((answers[1].prim, answers[1].distance), (0, 2.0));
    // Above the edge shared by triangles 0 and 3 (the +x spoke): 0.
    assert_eq!(answers[2].prim, 0);
    assert_eq!(answers[2].distance, 1.0);
    // On the edge shared by 0 and 1 (the +y spoke): 0, at distance 0.
    assert_eq!((answers[3].prim, answers[3].distance), (0, 0.0));
}

#[test]
fn max_distance_cuts_off_and_an_empty_scene_finds_nothing() {
    let mut renderer = cpu(vec![tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])]);
    let points = [[0.2, 0.2, 1.0], [0.2, 0.2, 3.0], [0.2, 0.2, 2.0]];
    let answers = renderer.closest_points(&points, 2.0).unwrap();
    assert_eq!((answers[0].prim, answers[0].distance), (0, 1.0));
    assert_eq!(answers[1], ClosestPoint::NONE);
    // Exactly at max_distance counts.
    assert_eq!((answers[2].prim, answers[2].distance), (0, 2.0));
    let mut empty = cpu(Vec::new());
    assert_eq!(
        empty.closest_points(&points, f32::INFINITY).unwrap(),
        vec![ClosestPoint::NONE; 3]
    );
    assert_eq!(empty.winding_numbers(&points).unwrap(), vec![0.0; 3]);
    assert_eq!(
        empty
            .count_intersections(&[ray([0.0; 3], [0.0, 0.0, 1.0])])
            .unwrap(),
        vec![0]
    );
}

#[test]
fn winding_numbers_are_one_inside_zero_outside_and_match_the_exact_sum() {
    let mut triangles = sphere_mesh([0.3, -0.2, 0.1], 1.0, 40, 60);
    // A second closed sphere beside it, so that the tree has far nodes.
    triangles.extend(sphere_mesh([3.0, 0.0, 0.0], 0.5, 30, 40));
    let mut renderer = cpu(triangles.clone());
    let mut rng = Lcg(7);
    let points: Vec<[f32; 3]> = (0..400).map(|_| rng.point(-2.0, 4.0)).collect();
    let w = renderer.winding_numbers(&points).unwrap();
    for (p, &w) in points.iter().zip(&w) {
        let exact = winding_f64(d3(*p), &triangles);
        assert!(
            (w as f64 - exact).abs() < 5e-3,
            "{p:?}: {w} against {exact}"
        );
        let inside = (d3(*p) - DVec3::new(0.3, -0.2, 0.1)).length() < 0.98
            || (d3(*p) - DVec3::new(3.0, 0.0, 0.0)).length() < 0.48;
        let outside = (d3(*p) - DVec3::new(0.3, -0.2, 0.1)).length() > 1.02
            && (d3(*p) - DVec3::new(3.0, 0.0, 0.0)).length() > 0.52;
        if inside {
            assert!((w - 1.0).abs() < 5e-3, "{p:?} inside: {w}");
        }
        if outside {
            assert!(w.abs() < 5e-3, "{p:?} outside: {w}");
        }
    }
}

#[test]
fn a_mesh_with_a_hole_still_has_a_sensible_inside() {
    let mut triangles = sphere_mesh([0.0; 3], 1.0, 20, 30);
    // A hole at the north pole: the first ring of triangles gone.
    triangles.drain(0..30);
    let mut renderer = cpu(triangles.clone());
    let w = renderer
        .winding_numbers(&[
            [0.0, 0.0, 0.0],
            [0.0, 0.0, -0.8],
            [0.0, 0.0, 3.0],
            [0.0, 0.0, 1.0],
        ])
        .unwrap();
    assert!(w[0] > 0.9 && w[1] > 0.9, "inside: {w:?}");
    assert!(w[2].abs() < 0.05, "outside: {w:?}");
    // In the hole itself: about half.
    assert!((w[3] - 0.5).abs() < 0.1, "in the hole: {w:?}");
    for (i, p) in [[0.0f32, 0.0, 0.0], [0.0, 0.0, -0.8], [0.0, 0.0, 3.0]]
        .iter()
        .enumerate()
    {
        assert!((w[i] as f64 - winding_f64(d3(*p), &triangles)).abs() < 5e-3);
    }
}

#[test]
fn counts_through_a_closed_mesh_are_even_from_outside_and_odd_from_inside() {
    let triangles = sphere_mesh([0.0; 3], 1.0, 12, 16);
    let mut renderer = cpu(triangles);
    let mut rng = Lcg(3);
    let mut rays = Vec::new();
    let mut inside = Vec::new();
    for _ in 0..2000 {
        let o = rng.point(-1.5, 1.5);
        let d = rng.point(-1.0, 1.0);
        if d3(d).length() < 0.1 {
            continue;
        }
        inside.push(d3(o).length() < 0.9);
        rays.push(ray(o, d));
    }
    // Rays through the poles and along the mesh's vertices and edges.
    for j in 0..16 {
        let phi = 2.0 * std::f32::consts::PI * j as f32 / 16.0;
        rays.push(ray([0.0, 0.0, 0.0], [phi.cos(), phi.sin(), 0.0]));
        inside.push(true);
    }
    rays.push(ray([0.0, 0.0, -3.0], [0.0, 0.0, 1.0]));
    inside.push(false);
    let counts = renderer.count_intersections(&rays).unwrap();
    let list = renderer.list_intersections(&rays).unwrap();
    for (i, (&n, &inside)) in counts.iter().zip(&inside).enumerate() {
        let expected_odd = inside;
        if inside || d3(rays[i].origin).length() > 1.1 {
            assert_eq!(
                n % 2 == 1,
                expected_odd,
                "ray {i}: {n} crossings: {:?}",
                rays[i]
            );
        }
        let hits = &list.hits[list.ray_splits[i] as usize..list.ray_splits[i + 1] as usize];
        assert_eq!(hits.len() as u32, n, "ray {i}");
        assert!(
            hits.windows(2).all(|w| w[0].t <= w[1].t),
            "ray {i}: not sorted"
        );
        assert!(hits.iter().all(|h| h.ray == i as u32));
    }
    // Through both poles: two crossings.
    assert_eq!(*counts.last().unwrap(), 2);
    let parity = renderer
        .parity_inside(&[[0.0, 0.1, 0.2], [0.0, 0.0, 3.0], [0.5, -0.5, 0.0]])
        .unwrap();
    assert_eq!(parity, vec![true, false, true]);
}

#[test]
fn an_edge_or_a_vertex_crossed_counts_once() {
    // A square of two triangles (diagonal from (0,0) to (1,1)), and a fan
    // of four about (3, 0.5).
    let mut triangles = vec![
        tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]),
        tri([0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
    ];
    triangles.extend(fan([3.0, 0.5, 0.0]));
    let mut renderer = cpu(triangles);
    let rays = [
        ray([0.5, 0.5, 1.0], [0.0, 0.0, -1.0]), // the diagonal's midpoint
        ray([0.25, 0.25, -1.0], [0.0, 0.0, 1.0]), // from the back
        ray([3.0, 0.5, 1.0], [0.0, 0.0, -1.0]), // the fan's centre
        ray([3.5, 0.5, 1.0], [0.0, 0.0, -1.0]), // a spoke
        ray([0.3, 0.3, 1.0], [0.1, 0.1, -1.0]), // slanted, along the diagonal
    ];
    let counts = renderer.count_intersections(&rays).unwrap();
    assert_eq!(counts, vec![1, 1, 1, 1, 1]);
    let list = renderer.list_intersections(&rays).unwrap();
    assert_eq!(list.ray_splits, vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(list.hits[0].t, 1.0);
}

#[test]
fn queries_far_from_the_origin_answer_as_near_it() {
    let near = sphere_mesh([0.0; 3], 1.0, 12, 16);
    let shift = [1024.0f32, -2048.0, 512.0];
    let far: Vec<Triangle> = near
        .iter()
        .map(|t| {
            let m = |v: [f32; 3]| std::array::from_fn(|a| v[a] + shift[a]);
            tri(m(t.v0), m(t.v1), m(t.v2))
        })
        .collect();
    let mut a = cpu(near.clone());
    let mut b = cpu(far.clone());
    let points = [[0.1, 0.2, 0.3], [2.0, 0.0, 0.0], [0.0, -3.0, 1.0]];
    let moved: Vec<[f32; 3]> = points
        .iter()
        .map(|p| std::array::from_fn(|k| p[k] + shift[k]))
        .collect();
    let (ca, cb) = (
        a.closest_points(&points, f32::INFINITY).unwrap(),
        b.closest_points(&moved, f32::INFINITY).unwrap(),
    );
    for (x, y) in ca.iter().zip(&cb) {
        // Within the rounding of the shifted vertices (f32 spaces values
        // 2.4e-4 apart at 2048).
        assert!(
            (x.distance - y.distance).abs() < 1e-3,
            "{} {}",
            x.distance,
            y.distance
        );
        let back: Vec<f32> = (0..3).map(|k| y.point[k] - shift[k]).collect();
        assert!(
            (0..3).all(|k| (back[k] - x.point[k]).abs() < 1e-3),
            "{back:?} {:?}",
            x.point
        );
    }
    let (wa, wb) = (
        a.winding_numbers(&points).unwrap(),
        b.winding_numbers(&moved).unwrap(),
    );
    assert!(
        (wa[0] - 1.0).abs() < 1e-3 && (wb[0] - 1.0).abs() < 0.05,
        "{wa:?} {wb:?}"
    );
    // A point beyond f32's reach of the scene is refused, named.
    let error = b
        .closest_points(&[[0.0; 3], [1e10, 0.0, 0.0]], f32::INFINITY)
        .unwrap_err()
        .to_string();
    assert!(error.contains("point 1"), "{error}");
}

#[test]
fn bad_inputs_are_refused_with_the_first_bad_one_named() {
    let mut renderer = cpu(sphere_mesh([0.0; 3], 1.0, 6, 8));
    let e = renderer
        .closest_points(
            &[
                [0.0; 3],
                [0.0; 3],
                [f32::NAN, 0.0, 0.0],
                [f32::INFINITY, 0.0, 0.0],
            ],
            1.0,
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("point 2") && e.contains("not finite"), "{e}");
    let e = renderer
        .winding_numbers(&[[0.0, f32::NEG_INFINITY, 0.0]])
        .unwrap_err()
        .to_string();
    assert!(e.contains("point 0"), "{e}");
    let e = renderer
        .parity_inside(&[[0.0; 3], [0.0, 0.0, f32::NAN]])
        .unwrap_err()
        .to_string();
    assert!(e.contains("point 1"), "{e}");
    for bad in [-1.0, f32::NAN] {
        let e = renderer
            .closest_points(&[[0.0; 3]], bad)
            .unwrap_err()
            .to_string();
        assert!(e.contains("max_distance"), "{e}");
    }
    let mut r = ray([0.0; 3], [0.0, 0.0, 0.0]);
    let e = renderer
        .count_intersections(&[ray([0.0; 3], [1.0, 0.0, 0.0]), r])
        .unwrap_err()
        .to_string();
    assert!(e.contains("ray 1"), "{e}");
    r.dir = [1.0, 0.0, 0.0];
    r.tmin = f32::NAN;
    let e = renderer.list_intersections(&[r]).unwrap_err().to_string();
    assert!(e.contains("ray 0") && e.contains("tmin"), "{e}");
    // Spheres: the queries are over triangles.
    let mut with_sphere = Renderer::Cpu(Arc::new(common::scene_of(
        vec![tri([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])],
        vec![Sphere {
            center: [0.0, 0.0, 3.0],
            radius: 1.0,
            ..Default::default()
        }],
    )));
    for e in [
        with_sphere.closest_points(&[[0.0; 3]], 1.0).map(|_| ()),
        with_sphere.winding_numbers(&[[0.0; 3]]).map(|_| ()),
        with_sphere
            .count_intersections(&[ray([0.0; 3], [0.0, 0.0, 1.0])])
            .map(|_| ()),
    ] {
        let e = e.unwrap_err().to_string();
        assert!(e.contains("1 sphere"), "{e}");
    }
}

#[test]
fn the_four_lane_closest_point_is_the_scalar_one_bit_for_bit() {
    use lambert::cpu::closest::{closest_point_block, closest_point_triangle};
    use lambert::layout::PrimBlock;
    let triangles = soup(5, 400);
    let mut rng = Lcg(11);
    for chunk in triangles.chunks(4) {
        let ids: Vec<u32> = (0..chunk.len() as u32).collect();
        let block = PrimBlock::new(&ids, chunk);
        for _ in 0..20 {
            let p = glam::Vec3::from(rng.point(-2.0, 2.0));
            let (d2, u, v, q) = closest_point_block(p, &block);
            for (lane, t) in chunk.iter().enumerate() {
                let (sq, sd2, su, sv) =
                    closest_point_triangle(p, t.v0.into(), t.v1.into(), t.v2.into());
                let lane_q = [q[0][lane], q[1][lane], q[2][lane]];
                assert_eq!(
                    (d2[lane].to_bits(), u[lane].to_bits(), v[lane].to_bits()),
                    (sd2.to_bits(), su.to_bits(), sv.to_bits()),
                    "{p} {t:?}"
                );
                assert_eq!(lane_q.map(f32::to_bits), sq.to_array().map(f32::to_bits));
            }
        }
    }
}

/// A closest-point query started from any triangle as its hint (as
/// `closest_points` starts each from its neighbour's answer) finds what
/// it finds with none, bit for bit, ties included.
#[test]
fn a_hint_changes_no_closest_point() {
    use lambert::cpu::closest::closest_point;
    // Shared vertices and edges (a tessellated sphere) make ties.
    let mut triangles = sphere_mesh([0.0; 3], 1.0, 12, 16);
    triangles.extend(soup(9, 200));
    let scene = Scene::from_triangles(triangles.clone());
    let mut rng = Lcg(21);
    let mut queue = Vec::new();
    let mut points: Vec<[f32; 3]> = (0..300).map(|_| rng.point(-2.5, 2.5)).collect();
    // On vertices, where several triangles are equally near.
    points.extend(triangles.iter().take(40).map(|t| t.v0));
    for p in points {
        let p = glam::Vec3::from(p);
        let plain = closest_point(
            scene.bvh(),
            triangles.len(),
            p,
            f32::INFINITY,
            1e-5,
            None,
            &mut queue,
            false,
        );
        for prim in (0..triangles.len()).step_by(37) {
            let t = &triangles[prim];
            let hint = Some((prim as u32, [t.v0, t.v1, t.v2].map(glam::Vec3::from)));
            let hinted = closest_point(
                scene.bvh(),
                triangles.len(),
                p,
                f32::INFINITY,
                1e-5,
                hint,
                &mut queue,
                false,
            );
            assert_eq!(hinted, plain, "{p} from triangle {prim}");
        }
        // Within a max distance the hint may lie beyond: still the same.
        let t = &triangles[0];
        let hint = Some((0, [t.v0, t.v1, t.v2].map(glam::Vec3::from)));
        assert_eq!(
            closest_point(
                scene.bvh(),
                triangles.len(),
                p,
                0.01,
                1e-5,
                hint,
                &mut queue,
                false
            ),
            closest_point(
                scene.bvh(),
                triangles.len(),
                p,
                0.01,
                1e-5,
                None,
                &mut queue,
                false
            ),
        );
    }
}

/// The same queries on the GPU (lavapipe here) and the CPU path.
fn both(triangles: Vec<Triangle>) -> (Renderer, Renderer) {
    let scene = Arc::new(Scene::from_triangles(triangles));
    let (gpu, _) = Renderer::open(
        Arc::clone(&scene),
        lambert::render::DeviceChoice::Gpu,
        &Default::default(),
    )
    .unwrap_or_else(|e| {
        panic!("GPU tests need a wgpu adapter ({e}): sudo apt-get install mesa-vulkan-drivers")
    });
    (gpu, Renderer::Cpu(scene))
}

#[test]
fn gpu_and_cpu_answer_every_query_bit_for_bit() {
    let mut triangles = soup(21, 500);
    triangles.extend(sphere_mesh([0.2, 0.1, -0.3], 0.8, 16, 24));
    let (mut gpu, mut cpu) = both(triangles.clone());
    let mut rng = Lcg(77);
    let mut points: Vec<[f32; 3]> = (0..3000).map(|_| rng.point(-1.6, 1.6)).collect();
    points.extend(triangles.iter().take(200).map(|t| t.v2));
    points.push([30.0, -20.0, 10.0]);
    for max_distance in [f32::INFINITY, 0.05] {
        let g = gpu.closest_points(&points, max_distance).unwrap();
        let c = cpu.closest_points(&points, max_distance).unwrap();
        let misses = c.iter().filter(|a| a.prim == NO_HIT).count();
        assert!(
            max_distance.is_infinite() || misses > 100,
            "{misses} beyond the cut-off"
        );
        for (i, (g, c)) in g.iter().zip(&c).enumerate() {
            assert_eq!(
                bytemuck::bytes_of(g),
                bytemuck::bytes_of(c),
                "point {i} {:?}: GPU {g:?}, CPU {c:?}",
                points[i]
            );
        }
    }
    let g = gpu.winding_numbers(&points).unwrap();
    let c = cpu.winding_numbers(&points).unwrap();
    for (i, (g, c)) in g.iter().zip(&c).enumerate() {
        assert_eq!(g.to_bits(), c.to_bits(), "point {i}: GPU {g}, CPU {c}");
    }
    let rays: Vec<Ray> = (0..3000)
        .map(|_| ray(rng.point(-1.6, 1.6), rng.point(-1.0, 1.0)))
        .chain((0..24).map(|j| {
            let phi = 2.0 * std::f32::consts::PI * j as f32 / 24.0;
            ray([0.2, 0.1, -0.3], [phi.cos(), phi.sin(), 0.0])
        }))
        .collect();
    assert_eq!(
        gpu.count_intersections(&rays).unwrap(),
        cpu.count_intersections(&rays).unwrap()
    );
    let (g, c) = (
        gpu.list_intersections(&rays).unwrap(),
        cpu.list_intersections(&rays).unwrap(),
    );
    assert_eq!(g.ray_splits, c.ray_splits);
    assert!(c.hits.len() > 1000, "{} hits", c.hits.len());
    for (i, (g, c)) in g.hits.iter().zip(&c.hits).enumerate() {
        assert_eq!(
            bytemuck::bytes_of(g),
            bytemuck::bytes_of(c),
            "hit {i}: GPU {g:?}, CPU {c:?}"
        );
    }
    assert_eq!(
        gpu.parity_inside(&points).unwrap(),
        cpu.parity_inside(&points).unwrap()
    );
}

#[test]
fn the_gpu_refuses_what_the_cpu_refuses_and_answers_an_empty_scene() {
    // The CPU renderer holds the scene, which winding queries need.
    let (mut gpu, _cpu) = both(Vec::new());
    let points = [[0.0, 0.0, 1.0], [2.0, 0.0, 0.0]];
    assert_eq!(
        gpu.closest_points(&points, f32::INFINITY).unwrap(),
        vec![ClosestPoint::NONE; 2]
    );
    assert_eq!(gpu.winding_numbers(&points).unwrap(), vec![0.0; 2]);
    assert_eq!(
        gpu.count_intersections(&[ray([0.0; 3], [0.0, 0.0, 1.0])])
            .unwrap(),
        vec![0]
    );
    let e = gpu
        .closest_points(&[[f32::NAN, 0.0, 0.0]], 1.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("point 0"), "{e}");
}
