//! Numerical stress suite (docs/accuracy.md), edge cases: rays parallel to, in the plane of or at degenerate triangles, NaN and invalid rays, degenerate geometry.

mod common;

use common::stress::*;
use common::*;
use glam::Vec3;
use lambert::cpu;
use lambert::layout::{NO_HIT, Ray, Triangle};
use lambert::scene::Intersect;

#[test]
fn parallel_in_plane_and_degenerate_cases_give_no_false_hits() {
    let unit = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let z = Vec3::Z;
    let cases: Vec<(&str, Vec<Triangle>, Vec<Ray>)> = vec![
        (
            "ray in the triangle's plane (n·d = 0)",
            vec![triangle(unit)],
            vec![
                ray(Vec3::new(-1.0, 0.25, 0.0), Vec3::X),
                ray(Vec3::new(0.25, -1.0, 0.0), Vec3::Y),
                ray(Vec3::new(0.2, 0.2, 0.0), Vec3::new(1.0, 1.0, 0.0)),
            ],
        ),
        (
            "ray parallel above the plane",
            vec![triangle(unit)],
            vec![ray(Vec3::new(-1.0, 0.25, 1e-3), Vec3::X)],
        ),
        (
            "n·d within 1e-7 of 0, crossing the plane far outside",
            vec![triangle(unit)],
            vec![
                ray(Vec3::new(-1.0, 0.25, 1.0), Vec3::new(1.0, 0.0, -1e-7)),
                ray(Vec3::new(-1.0, 0.25, -1.0), Vec3::new(1.0, 0.0, 1e-7)),
            ],
        ),
        (
            "origin in the plane, leaving it",
            vec![triangle(unit)],
            vec![
                ray(Vec3::new(0.25, 0.25, 0.0), z),
                ray(Vec3::new(0.25, 0.25, 0.0), -z),
                ray(Vec3::new(0.25, 0.25, 0.0), Vec3::new(1.0, 0.0, 1.0)),
            ],
        ),
        (
            "zero-area, collinear and repeated-vertex triangles",
            vec![
                triangle([unit[0], unit[0], unit[0]]),
                triangle([unit[0], unit[1], Vec3::new(2.0, 0.0, 0.0)]),
                triangle([unit[0], unit[1], unit[1]]),
            ],
            vec![
                ray(Vec3::new(0.0, 0.0, 1.0), -z),
                ray(Vec3::new(0.5, 0.0, 1.0), -z),
                ray(Vec3::new(1.0, 0.0, 1.0), -z),
                ray(Vec3::new(-1.0, 0.0, 0.0), Vec3::X),
                ray(Vec3::new(0.5, 1.0, 0.0), -Vec3::Y),
            ],
        ),
    ];
    for (what, triangles, rays) in cases {
        let base = scene_of(triangles, vec![]);
        for intersect in Intersect::ALL {
            let scene = with_intersect(&base, intersect);
            for (path, hits) in [
                ("CPU", trace_cpu(&scene, &rays, false)),
                ("GPU", trace_gpu(&scene, &rays, false)),
            ] {
                for (r, h) in rays.iter().zip(&hits) {
                    assert_eq!(
                        h.prim,
                        NO_HIT,
                        "{what}: {} on {path} hits at t = {} with {r:?}",
                        intersect.name(),
                        h.t
                    );
                    assert!(h.t.is_infinite() && !h.u.is_nan() && !h.v.is_nan());
                }
            }
        }
        println!("{what}: no hits on either path, any variant");
    }
    // A nearly parallel ray that does cross the triangle still hits it.
    let scene = scene_of(vec![triangle(unit)], vec![]);
    let grazing = [ray(
        Vec3::new(-1.0, 0.25, 1e-7),
        Vec3::new(1.0, 0.0, -1e-7 / 1.25),
    )];
    for intersect in Intersect::ALL {
        let s = with_intersect(&scene, intersect);
        let oracle = cpu::trace_rays_f64(&s, &grazing, false)[0];
        assert_eq!(oracle.prim, 0, "the oracle misses the grazing ray");
        for hits in [
            trace_cpu(&s, &grazing, false),
            trace_gpu(&s, &grazing, false),
        ] {
            assert_eq!(
                hits[0].prim,
                0,
                "{} misses a grazing ray that crosses it",
                intersect.name()
            );
        }
    }
}

/// A ray with a NaN in its origin, direction or tmin (a shadow ray from a
/// degenerate triangle's NaN normal, say: the library's own rays are not
/// validated as a ray file is) misses on every path, closest and any hit.
/// The shader and the twin answer it before traversal, where the slab
/// test would enter every box (on an H200 a whole-tree walk of the dragon
/// took 0.39 s for one such ray); this checks that the shortcut keeps the
/// answer the traversal gives.
#[test]
fn nan_rays_miss_on_every_path() {
    let unit = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let scene = scene_of(
        vec![triangle(unit)],
        vec![lambert::layout::Sphere {
            center: [0.25, 0.25, -2.0],
            radius: 0.5,
            ..Default::default()
        }],
    );
    let good = ray(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z);
    let nan = f32::NAN;
    let rays = [
        good,
        Ray {
            origin: [0.25, nan, 1.0],
            ..good
        },
        Ray {
            dir: [0.0, 0.0, nan],
            ..good
        },
        Ray {
            dir: [nan; 3],
            ..good
        },
        Ray { tmin: nan, ..good },
    ];
    for any_hit in [false, true] {
        for (path, hits) in [
            ("CPU", trace_cpu(&scene, &rays, any_hit)),
            (
                "twin",
                cpu::trace_rays_gpu_twin(
                    &scene,
                    &rays,
                    any_hit,
                    scene.default_settings().intersect,
                ),
            ),
            ("GPU", trace_gpu(&scene, &rays, any_hit)),
        ] {
            assert_eq!(
                hits[0].prim, 0,
                "{path}: the valid ray must hit the triangle"
            );
            for (i, h) in hits.iter().enumerate().skip(1) {
                assert_eq!(
                    h.prim, NO_HIT,
                    "{path}, any_hit {any_hit}: NaN ray {i} hit {h:?}"
                );
            }
        }
    }
}

#[test]
fn invalid_rays_are_rejected_with_the_ray_and_field_named() {
    let good = ray(Vec3::ZERO, Vec3::Z);
    let path = std::path::Path::new("probe.rays");
    let bytes = |rays: &[Ray]| lambert::rays::rays_to_bytes(rays).to_vec();
    assert!(lambert::rays::parse_rays(&bytes(&[good]), path).is_ok());
    let cases: Vec<(Ray, &str)> = vec![
        (
            Ray {
                origin: [f32::NAN, 0.0, 0.0],
                ..good
            },
            "ox is NaN",
        ),
        (
            Ray {
                dir: [0.0, f32::INFINITY, 0.0],
                ..good
            },
            "dy is inf",
        ),
        (
            Ray {
                tmin: f32::NAN,
                ..good
            },
            "tmin is NaN",
        ),
        (
            Ray {
                tmax: f32::NAN,
                ..good
            },
            "tmax is NaN",
        ),
        (
            Ray {
                dir: [0.0; 3],
                ..good
            },
            "direction (dx, dy, dz) has length 0e0",
        ),
        // |d|² would underflow or overflow in f32: rejected, not missed.
        (
            Ray {
                dir: [1e-25, 0.0, 0.0],
                ..good
            },
            "direction (dx, dy, dz) has length 1",
        ),
        (
            Ray {
                dir: [0.0, 0.0, 1e20],
                ..good
            },
            "direction (dx, dy, dz) has length 1",
        ),
        (
            Ray {
                tmin: 2.0,
                tmax: 1.0,
                ..good
            },
            "tmin = 2 is greater than tmax = 1",
        ),
    ];
    for (bad, expected) in cases {
        let err = lambert::rays::parse_rays(&bytes(&[good, bad]), path)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("probe.rays")
                && err.contains("ray 1 (byte offset 32)")
                && err.contains(expected),
            "{err}"
        );
    }
    let err = lambert::rays::parse_rays(&bytes(&[good])[..30], path)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("30 bytes is not a whole number of rays"),
        "{err}"
    );
}

#[test]
fn degenerate_geometry_renders_without_nan_pixels() {
    let mut s = load("edge_cases");
    let extra = [
        triangle([Vec3::ZERO; 3]),
        triangle([Vec3::ZERO, Vec3::X, Vec3::X * 2.0]),
        triangle([Vec3::ZERO, Vec3::Y, Vec3::Y]),
    ];
    let material = s.triangles()[0].material;
    s.add_triangles(extra.iter().map(|t| Triangle { material, ..*t }));
    s.rebuild_bvh();
    for intersect in Intersect::ALL {
        let scene = with_intersect(&s, intersect);
        for (path, r) in [("CPU", render_cpu(&scene)), ("GPU", render_gpu(&scene))] {
            assert!(
                r.image.rgb.iter().flatten().all(|c| c.is_finite()),
                "{} on {path}: a pixel is not finite",
                intersect.name()
            );
        }
    }
}
