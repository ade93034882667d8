//! Inside tests from the side of each point's closest point
//! (`bvh::Sides`, issue 48 item 4) against the winding number they stand
//! for: the same answer on closed meshes (a sphere, a box of many flat
//! triangles, a torus, nested and inward-facing spheres, spheres that
//! cross, the bundled models) at random points and at points on and very
//! near the surface; open meshes keep the winding number; signed
//! distances keep their distances bit for bit.

use std::sync::Arc;

use lambert::jobs::{self, Sign};
use lambert::layout::Triangle;
use lambert::render::Renderer;
use lambert::scene::Scene;

mod common;

use common::data::{Lcg, quad_grid, sphere_mesh, tri};

/// A closed torus about the z axis (radii big and small), facing out.
fn torus(big: f32, small: f32, around: usize, across: usize) -> Vec<Triangle> {
    let vertex = |i: usize, j: usize| {
        let u = 2.0 * std::f32::consts::PI * (i % around) as f32 / around as f32;
        let v = 2.0 * std::f32::consts::PI * (j % across) as f32 / across as f32;
        let ring = big + small * v.cos();
        [ring * u.cos(), ring * u.sin(), small * v.sin()]
    };
    quad_grid(around, across, vertex)
}

/// The box [−1, 1]³, each face an n × n grid of squares cut in two (many
/// flat triangles that meet at vertices and edges), facing out.
fn grid_box(n: usize) -> Vec<Triangle> {
    let mut out = Vec::new();
    let at = |k: usize| -1.0 + 2.0 * k as f32 / n as f32;
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let point = |i: usize, j: usize| {
                let mut p = [0.0; 3];
                p[axis] = side;
                p[(axis + 1) % 3] = at(i);
                p[(axis + 2) % 3] = at(j);
                p
            };
            for i in 0..n {
                for j in 0..n {
                    let (a, b, c, d) = (
                        point(i, j),
                        point(i + 1, j),
                        point(i + 1, j + 1),
                        point(i, j + 1),
                    );
                    // (axis+1, axis+2, axis) is right-handed: facing +axis.
                    if side > 0.0 {
                        out.extend([tri(a, b, c), tri(a, c, d)]);
                    } else {
                        out.extend([tri(a, c, b), tri(a, d, c)]);
                    }
                }
            }
        }
    }
    out
}

fn flipped(triangles: Vec<Triangle>) -> Vec<Triangle> {
    triangles
        .into_iter()
        .map(|t| tri(t.v0, t.v2, t.v1))
        .collect()
}

fn cpu(scene: Scene) -> Renderer {
    Renderer::Cpu(Arc::new(scene))
}

/// Random points over 1.5× the triangles' box, and points on and near the
/// surface: on random triangles' interiors, on their vertices, and off
/// them along their normals by 1e-7 to 1e-2 of the box's size, either way.
fn points(triangles: &[Triangle], random: usize, near: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut rng = Lcg(seed);
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for t in triangles {
        for v in [t.v0, t.v1, t.v2] {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
    }
    let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f32::max);
    let mut out: Vec<[f32; 3]> = (0..random)
        .map(|_| {
            std::array::from_fn(|k| {
                let (c, h) = ((lo[k] + hi[k]) / 2.0, (hi[k] - lo[k]) * 0.75);
                c + (2.0 * rng.next() - 1.0) * h
            })
        })
        .collect();
    for i in 0..near {
        let t = &triangles[(rng.next() * triangles.len() as f32) as usize % triangles.len()];
        let (a, b, c) = (
            glam::Vec3::from(t.v0),
            glam::Vec3::from(t.v1),
            glam::Vec3::from(t.v2),
        );
        let (mut u, mut v) = (rng.next(), rng.next());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let on = match i % 4 {
            0 => a,
            _ => a + (b - a) * u + (c - a) * v,
        };
        let normal = (b - a).cross(c - a).normalize_or_zero();
        let offset = [0.0, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2][i % 7] * size;
        let sign = if rng.next() < 0.5 { -1.0 } else { 1.0 };
        out.push((on + normal * (sign * offset)).to_array());
    }
    out
}

/// Checks the inside test and the signed distance on `scene` against the
/// winding number at `points`; returns how many points the sides decided.
fn check(name: &str, scene: Scene, points: &[[f32; 3]]) -> usize {
    let mut r = cpu(scene);
    let by_winding: Vec<bool> = r
        .winding_numbers(points)
        .unwrap()
        .iter()
        .map(|w| w.abs() >= jobs::INSIDE_WINDING)
        .collect();
    let inside = jobs::inside(&mut r, points, Sign::Winding).unwrap();
    for (i, (a, b)) in inside.iter().zip(&by_winding).enumerate() {
        assert_eq!(
            a, b,
            "{name}: point {i} {:?}: sides say {a}, winding {b}",
            points[i]
        );
    }
    let distances = jobs::distances(&mut r, points).unwrap();
    let signed = jobs::signed_distances(&mut r, points, Sign::Winding).unwrap();
    for i in 0..points.len() {
        assert_eq!(
            signed[i].abs().to_bits(),
            distances[i].to_bits(),
            "{name}: point {i}"
        );
        assert_eq!(
            signed[i].is_sign_negative(),
            by_winding[i],
            "{name}: point {i}"
        );
    }
    match r.bounds_solid() {
        Ok(_) => {
            let closest = r.closest_points(points, f32::INFINITY).unwrap();
            let sides = r.solid_inside(points, &closest).unwrap();
            sides.iter().filter(|s| s.is_some()).count()
        }
        Err(_) => 0,
    }
}

/// The pieces and the triangles in none, of a closed mesh.
fn counts(triangles: Vec<Triangle>) -> (usize, usize) {
    cpu(Scene::from_triangles(triangles))
        .bounds_solid()
        .unwrap()
}

#[test]
fn closed_meshes_take_the_winding_numbers_inside_from_their_sides() {
    let meshes: Vec<(&str, Vec<Triangle>)> = vec![
        ("sphere", sphere_mesh([0.1, -0.2, 0.3], 1.0, 24, 48)),
        ("box", grid_box(6)),
        ("torus", torus(1.0, 0.35, 48, 24)),
        ("inward sphere", flipped(sphere_mesh([0.0; 3], 1.0, 16, 32))),
    ];
    for (name, triangles) in meshes {
        let (pieces, apart) = counts(triangles.clone());
        assert_eq!((pieces, apart), (1, 0), "{name}");
        let p = points(&triangles, 6000, 3000, 7);
        let decided = check(name, Scene::from_triangles(triangles), &p);
        // The random points and those off the surface by 1e-3 or more: the
        // sides decide nearly all; on and very near it, the winding number.
        assert!(
            decided > 6000,
            "{name}: the sides decided {decided} of {}",
            p.len()
        );
    }
}

#[test]
fn nested_and_crossing_closed_meshes_label_each_piece() {
    // One sphere in another, both facing out: 2 inside the inner one.
    let mut nested = sphere_mesh([0.0; 3], 1.0, 24, 48);
    nested.extend(sphere_mesh([0.1, 0.0, 0.0], 0.5, 16, 32));
    assert_eq!(counts(nested.clone()), (2, 0));
    // A hollow shell: the inner sphere faces in.
    let mut hollow = sphere_mesh([0.0; 3], 1.0, 24, 48);
    hollow.extend(flipped(sphere_mesh([0.1, 0.0, 0.0], 0.5, 16, 32)));
    // Two spheres that cross: the triangles along their crossing circle
    // are left out, and the parts of each sphere inside the other are
    // pieces of their own.
    let mut crossing = sphere_mesh([0.0; 3], 0.6, 24, 48);
    crossing.extend(sphere_mesh([0.5, 0.05, 0.0], 0.6, 24, 48));
    let (pieces, apart) = counts(crossing.clone());
    assert!(
        pieces >= 4 && apart > 0,
        "{pieces} pieces, {apart} triangles apart"
    );
    for (name, triangles) in [
        ("nested", nested),
        ("hollow", hollow),
        ("crossing", crossing),
    ] {
        let p = points(&triangles, 6000, 3000, 11);
        let decided = check(name, Scene::from_triangles(triangles), &p);
        assert!(decided > 5000, "{name}: the sides decided {decided}");
    }
}

#[test]
fn the_bundled_models_agree_with_their_winding_numbers() {
    for (file, random, near) in [
        ("cube.obj", 4000, 2000),
        ("dragon_res4.obj", 6000, 3000),
        ("bunny_lowres.obj", 4000, 2000),
        ("boxes.glb", 4000, 2000),
    ] {
        let path = common::asset(&format!("scenes/meshes/{file}"));
        let scene = Scene::from_model(&path, None).unwrap();
        let triangles = scene.triangles().to_vec();
        let offset = scene.offset();
        // World points: the triangles are in the scene's local frame.
        let world: Vec<[f32; 3]> = points(&triangles, random, near, 3)
            .iter()
            .map(|p| std::array::from_fn(|k| (f64::from(p[k]) + offset[k]) as f32))
            .collect();
        let closed = cpu(Scene::from_model(&path, None).unwrap()).bounds_solid();
        let decided = check(file, scene, &world);
        eprintln!(
            "{file}: {closed:?}, the sides decided {decided} of {}",
            world.len()
        );
        if closed.is_ok() {
            assert!(decided > random / 2, "{file}: the sides decided {decided}");
        }
    }
}

#[test]
fn open_meshes_keep_the_winding_number() {
    let mut open = sphere_mesh([0.0; 3], 1.0, 12, 24);
    open.remove(40);
    let r = cpu(Scene::from_triangles(open.clone()));
    let why = r.bounds_solid().unwrap_err();
    assert!(why.contains("hole"), "{why}");
    let p = points(&open, 2000, 1000, 5);
    assert_eq!(
        check("open sphere", Scene::from_triangles(open.clone()), &p),
        0
    );
    // A lone flat square: open too.
    let square = vec![
        tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]),
        tri([0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
    ];
    assert!(cpu(Scene::from_triangles(square)).bounds_solid().is_err());
}

#[test]
fn a_mesh_with_zero_area_triangles_still_agrees() {
    // A sphere with zero-area triangles added along its edges (as the
    // full dragon has, making its edges look shared by four): they are
    // left out and the rest decides.
    let mut triangles = sphere_mesh([0.0; 3], 1.0, 16, 32);
    let extra: Vec<Triangle> = triangles
        .iter()
        .step_by(37)
        .map(|t| tri(t.v0, t.v1, t.v1))
        .collect();
    triangles.extend(extra);
    let (pieces, apart) = counts(triangles.clone());
    assert_eq!(pieces, 1);
    assert!(apart > 0);
    let p = points(&triangles, 4000, 2000, 9);
    let decided = check("sphere with slivers", Scene::from_triangles(triangles), &p);
    assert!(decided > 4000, "the sides decided {decided}");
}

/// `lambert query inside` and `signed-distance` say on stderr which way
/// they took the signs: from the closest points' sides on a closed mesh
/// (with its pieces), from winding numbers on an open one (naming the
/// edge); nothing with --quiet.
#[test]
fn lambert_query_says_which_way_it_took_the_signs() {
    use common::{lambert, s, stderr, write};
    let dir = tempfile::tempdir().unwrap();
    let points: Vec<u8> = [[0.1f32, 0.2, 0.3], [5.0, 0.0, 0.0], [0.0, -0.4, 0.1]]
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let points = write(dir.path(), "points.bin", points);
    let out = dir.path().join("out.bin");
    for (mesh, expected) in [
        (
            "cube.obj",
            "inside from the side of each point's closest point (the mesh is closed: 1 piece(s), 0 triangle(s)",
        ),
        (
            "quad.obj",
            "inside from winding numbers: the mesh is not closed: the edge",
        ),
    ] {
        let obj = common::asset(&format!("scenes/meshes/{mesh}"));
        for what in ["inside", "signed-distance"] {
            let args = [
                "query",
                what,
                "--obj",
                s(&obj),
                "--points",
                s(&points),
                "-o",
                s(&out),
            ];
            let run = lambert(&[&args[..], &["--device", "cpu"]].concat());
            let text = stderr(&run);
            assert!(
                run.status.success() && text.contains(expected),
                "{mesh} {what}: {text}"
            );
            let quiet = lambert(&[&args[..], &["--device", "cpu", "--quiet"]].concat());
            assert!(
                !stderr(&quiet).contains("inside from"),
                "{}",
                stderr(&quiet)
            );
        }
    }
}
