//! The winding number's documented bound (within 1e-2 of the exact f64 sum
//! at points 1% of the diagonal or more from the surface; docs/python.md,
//! docs/ray-query.md), on a bumpy closed mesh and on stacked coincident
//! layers, and the inside rule on closed meshes of either orientation.

mod common;

use std::sync::Arc;

use common::data::{Lcg, d3, winding_f64};
use glam::DVec3;
use lambert::jobs::{Sign, inside, signed_distances};
use lambert::layout::Triangle;
use lambert::render::Renderer;
use lambert::scene::Scene;

fn tri(v0: DVec3, v1: DVec3, v2: DVec3) -> Triangle {
    Triangle {
        v0: v0.as_vec3().to_array(),
        v1: v1.as_vec3().to_array(),
        v2: v2.as_vec3().to_array(),
        ..Default::default()
    }
}

/// The first point where `a` and `b` disagree, if any.
fn first_difference(points: &[[f32; 3]], a: &[bool], b: &[bool]) -> Option<([f32; 3], bool, bool)> {
    (0..points.len())
        .find(|&i| a[i] != b[i])
        .map(|i| (points[i], a[i], b[i]))
}

fn reversed(triangles: &[Triangle]) -> Vec<Triangle> {
    triangles
        .iter()
        .map(|t| Triangle {
            v1: t.v2,
            v2: t.v1,
            ..*t
        })
        .collect()
}

/// A closed, outward-facing sphere about `centre` (radius about `r`), its
/// radius waved by `amplitude` (k bumps a half turn) and jittered by
/// `noise`: a surface curved at many scales, as a scanned model is.
fn bumpy_sphere(centre: DVec3, r: f64, amplitude: f64, k: f64, noise: f64) -> Vec<Triangle> {
    let (rings, segments) = (150, 200);
    let mut rng = Lcg(3);
    let vertex: Vec<Vec<DVec3>> = (0..=rings)
        .map(|i| {
            let theta = std::f64::consts::PI * i as f64 / rings as f64;
            (0..segments)
                .map(|j| {
                    let phi = std::f64::consts::TAU * j as f64 / segments as f64;
                    let wave = amplitude * (k * theta).sin() * ((k + 2.0) * phi).cos();
                    let radius = r * (1.0 + wave + noise * (rng.next_f64() - 0.5));
                    centre
                        + radius
                            * DVec3::new(
                                theta.sin() * phi.cos(),
                                theta.sin() * phi.sin(),
                                theta.cos(),
                            )
                })
                .collect()
        })
        .collect();
    let mut out = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let next = (j + 1) % segments;
            let (a, b, c, d) = (
                vertex[i][j],
                vertex[i + 1][j],
                vertex[i + 1][next],
                vertex[i][next],
            );
            out.push(tri(a, b, c));
            out.push(tri(a, c, d));
        }
    }
    out
}

fn cpu(triangles: Vec<Triangle>) -> Renderer {
    Renderer::Cpu(Arc::new(Scene::from_triangles(triangles)))
}

/// The worst error of the winding numbers against the exact sum, and how
/// many points were checked, over `count` random points in the cube
/// [lo, hi]³ at least 1% of the mesh's diagonal from its surface.
fn worst_error(triangles: &[Triangle], lo: f64, hi: f64, count: usize) -> (f64, [f32; 3], usize) {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for t in triangles {
        for v in [t.v0, t.v1, t.v2] {
            min = min.min(d3(v));
            max = max.max(d3(v));
        }
    }
    let near = 0.01 * (max - min).length();
    let mut renderer = cpu(triangles.to_vec());
    let mut rng = Lcg(5);
    let points: Vec<[f32; 3]> = (0..count).map(|_| rng.point_f64(lo, hi)).collect();
    let closest = renderer.closest_points(&points, f32::INFINITY).unwrap();
    let points: Vec<[f32; 3]> = points
        .into_iter()
        .zip(closest)
        .filter(|(_, c)| f64::from(c.distance) >= near)
        .map(|(p, _)| p)
        .collect();
    let w = renderer.winding_numbers(&points).unwrap();
    let mut worst = (0.0, [0.0; 3]);
    for (p, w) in points.iter().zip(w) {
        let error = (f64::from(w) - winding_f64(d3(*p), triangles)).abs();
        if error > worst.0 {
            worst = (error, *p);
        }
    }
    (worst.0, worst.1, points.len())
}

#[test]
fn winding_numbers_on_a_bumpy_closed_mesh_keep_the_bound() {
    // Bumps of half the radius: the far field of a first-order dipole at
    // 4 radii erred by 2.4e-2 here.
    let triangles = bumpy_sphere(DVec3::new(0.2, -0.1, 0.3), 1.0, 0.5, 8.0, 0.05);
    let (worst, at, checked) = worst_error(&triangles, -1.4, 1.8, 2000);
    assert!(checked > 1500, "{checked} points checked");
    assert!(worst < 1e-2, "error {worst} at {at:?}");
}

#[test]
fn stacked_coincident_layers_do_not_add_up_their_errors() {
    for layers in [10, 20_000] {
        let (a, b, c, d) = (
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        );
        let triangles: Vec<Triangle> = (0..layers)
            .flat_map(|_| [tri(a, b, c), tri(a, c, d)])
            .collect();
        let count = if layers > 1000 { 300 } else { 2000 };
        let (worst, at, checked) = worst_error(&triangles, -1.0, 2.0, count);
        assert!(checked > count * 9 / 10, "{checked} points checked");
        // 3.3 with 20,000 layers before each sum carried its rounding error.
        assert!(worst < 1e-2, "{layers} layers: error {worst} at {at:?}");
    }
}

/// Random points of the cube [-2, 2]³ (none lands on a surface closely
/// enough for rounding to pick its side).
fn random_points(count: usize) -> Vec<[f32; 3]> {
    let mut rng = Lcg(9);
    (0..count).map(|_| rng.point_f64(-2.0, 2.0)).collect()
}

#[test]
fn inside_is_the_same_on_closed_meshes_facing_in_or_out() {
    let outward = bumpy_sphere(DVec3::ZERO, 1.0, 0.1, 3.0, 0.0);
    let points = random_points(2000);
    let by_parity = inside(&mut cpu(outward.clone()), &points, Sign::Parity).unwrap();
    assert!(by_parity.iter().filter(|&&i| i).count() > 80);
    for (facing, triangles) in [("out", outward.clone()), ("in", reversed(&outward))] {
        let mut renderer = cpu(triangles);
        for sign in Sign::ALL {
            let found = inside(&mut renderer, &points, sign).unwrap();
            assert_eq!(
                first_difference(&points, &found, &by_parity),
                None,
                "facing {facing}, by {}: (point, inside, by parity facing out)",
                sign.name()
            );
        }
        let sdf = signed_distances(&mut renderer, &points, Sign::Winding).unwrap();
        for (d, inside) in sdf.iter().zip(&by_parity) {
            assert_eq!(d.is_sign_negative(), *inside);
        }
    }
}

#[test]
fn two_bodies_one_facing_in_are_both_inside_as_by_parity() {
    // As trimesh's multibody.stl: two closed bodies apart, one facing in.
    let left = bumpy_sphere(DVec3::new(-1.0, 0.0, 0.0), 0.8, 0.1, 3.0, 0.0);
    let right = reversed(&bumpy_sphere(DVec3::new(1.0, 0.0, 0.0), 0.8, 0.1, 3.0, 0.0));
    let mut renderer = cpu([left, right].concat());
    let points = random_points(2000);
    let by_winding = inside(&mut renderer, &points, Sign::Winding).unwrap();
    let by_parity = inside(&mut renderer, &points, Sign::Parity).unwrap();
    assert_eq!(
        first_difference(&points, &by_winding, &by_parity),
        None,
        "(point, inside by winding, by parity)"
    );
    let right_inside = points
        .iter()
        .zip(&by_winding)
        .filter(|(p, inside)| **inside && p[0] > 0.0)
        .count();
    assert!(
        right_inside > 50,
        "{right_inside} inside the body facing in"
    );
}

#[test]
fn the_gpu_carries_the_rounding_errors_as_the_cpu_does() {
    // Where the carried errors count: a driver that folded (a + b) − a to
    // b would sum plainly, and differ.
    let (a, b, c) = (
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.3, 1.0, 0.2),
    );
    let triangles: Vec<Triangle> = (0..3000).map(|_| tri(a, b, c)).collect();
    let scene = Arc::new(Scene::from_triangles(triangles));
    let (mut gpu, _) = Renderer::open(
        Arc::clone(&scene),
        lambert::render::DeviceChoice::Gpu,
        &Default::default(),
    )
    .unwrap_or_else(|e| {
        panic!("GPU tests need a wgpu adapter ({e}): sudo apt-get install mesa-vulkan-drivers")
    });
    let points = random_points(500);
    assert_eq!(
        gpu.winding_numbers(&points).unwrap(),
        cpu(scene.triangles().to_vec())
            .winding_numbers(&points)
            .unwrap()
    );
}
