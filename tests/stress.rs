//! Numerical stress suite (docs/accuracy.md) on the CPU path and the GPU.
// Watertightness, self-intersection, edge cases, scale invariance,
// agreement with the f64 oracle, and GPU against CPU on ray sets. Every test
// prints its figures (`--nocapture`).

mod common;

use common::stress::*;
use common::*;
use glam::{DVec3, Vec3};
use lambert::Scene;
use lambert::cpu;
use lambert::layout::{Hit, NO_HIT, Ray, Triangle};
use lambert::probe::Rng;
use lambert::rays::{Agreement, ulp_distance};
use lambert::scene::Intersect;
use proptest::prelude::{prop, prop_assert, prop_assert_eq, prop_assume, proptest};

// ------------------------------------------------------------ watertightness

#[test]
fn watertight_meshes_do_not_leak() {
    let mut rng = Rng(11);
    let mut watertight_leaks = 0;
    println!("leaks (rays from inside that escape), BVH traversal:");
    println!(
        "{:<14} {:>22} {:>7} {:>16} {:>16}",
        "mesh", "offset", "rays", "variant", "CPU / GPU"
    );
    for (name, offset, scene, rays) in leak_cases(&mut rng) {
        for intersect in Intersect::ALL {
            let s = with_intersect(&scene, intersect);
            let cpu_leaks = misses(&trace_cpu(&s, &rays, false));
            let gpu_leaks = misses(&trace_gpu(&s, &rays, false));
            println!(
                "{name:<14} {:>22} {:>7} {:>16} {:>7} / {:<7}",
                format!("{offset}"),
                rays.len(),
                intersect.name(),
                cpu_leaks,
                gpu_leaks
            );
            if intersect == Intersect::Watertight {
                watertight_leaks += cpu_leaks + gpu_leaks;
            }
        }
    }
    assert_eq!(watertight_leaks, 0, "the watertight test let rays through");
}

// --------------------------------------------------------- self-intersection

#[test]
fn rays_spawned_from_hits_never_hit_their_own_triangle() {
    let mut rng = Rng(5);
    let triangles = random_scale_triangles(&mut rng, 3000);
    let base = scene_of(triangles.clone(), vec![]);
    let primary = rays_at_fronts(&triangles, &mut rng);
    println!("self-hits of spawned rays (3000 triangles, scales 1e-8..1e8, 4 rays each):");
    let mut default_self_hits = 0;
    for intersect in Intersect::ALL {
        let scene = with_intersect(&base, intersect);
        let (spawned, sources) = spawned_rays(&scene, &primary, &mut rng);
        assert!(
            spawned.len() > 4 * 2900,
            "too few primary hits: {}",
            spawned.len()
        );
        let count = |hits: Vec<Hit>| {
            hits.iter()
                .zip(&sources)
                .filter(|(h, s)| h.prim == **s)
                .count()
        };
        let cpu_self = count(trace_cpu(&scene, &spawned, false));
        let gpu_self = count(trace_gpu(&scene, &spawned, false));
        println!(
            "  {:<16} CPU {cpu_self} / GPU {gpu_self} of {}",
            intersect.name(),
            spawned.len()
        );
        if intersect == Intersect::default() {
            default_self_hits = cpu_self + gpu_self;
        }
    }
    assert_eq!(default_self_hits, 0, "spawned rays hit their own triangle");
}

#[test]
fn a_lit_plane_has_no_shadow_acne_at_any_scale() {
    // Every pixel on the plane is k·E·cos 60° = 0.5·2·0.5 exactly lit.
    let expected = 0.5f32;
    println!("shadow acne: plane pixels darker than k·E·cosθ");
    for (scale, translate) in [
        (1e-6, [0.0; 3]),
        (1e-3, [0.0; 3]),
        (1.0, [0.0; 3]),
        (1e3, [0.0; 3]),
        (1e6, [0.0; 3]),
        (1.0, [1e5, 1e5, 1e5]),
        (1e3, [1.5e5, 1.2e3, -2.2e5]),
    ] {
        for intersect in Intersect::ALL {
            let scene = lit_plane(scale, translate, intersect);
            for (path, image) in [("CPU", render_cpu(&scene)), ("GPU", render_gpu(&scene))] {
                let on_plane: Vec<f32> = image
                    .image
                    .rgb
                    .iter()
                    .zip(&image.prims)
                    .filter(|(_, p)| **p != NO_HIT)
                    .map(|(c, _)| c[1])
                    .collect();
                let acne = on_plane
                    .iter()
                    .filter(|&&v| (v - expected).abs() > 1e-5)
                    .count();
                assert!(on_plane.len() > 1000, "the camera misses the plane");
                if acne > 0 || intersect == Intersect::default() {
                    println!(
                        "  scale {scale:e}, translate {translate:?}, {} on {path}: {acne} of {}",
                        intersect.name(),
                        on_plane.len()
                    );
                }
                if intersect == Intersect::default() {
                    assert_eq!(
                        acne, 0,
                        "shadow acne at scale {scale}, translate {translate:?} on {path}"
                    );
                }
            }
        }
    }
}

// ----------------------------------------------------------- scale invariance

/// The spheres scene with every length multiplied by `scale`, then moved by
/// `translate`; point-light intensities scale by scale² so that irradiance
/// stays the same.
fn transformed_spheres(scale: f64, translate: f64) -> Scene {
    let mut s = load("spheres");
    let map = |p: [f32; 3]| p.map(|c| (c as f64 * scale + translate) as f32);
    let map64 = |p: [f64; 3]| p.map(|c| c * scale + translate);
    s.view_mut().camera.eye = map64(s.view().camera.eye);
    s.view_mut().camera.look_at = map64(s.view().camera.look_at);
    for t in s.triangles_mut() {
        t.v0 = map(t.v0);
        t.v1 = map(t.v1);
        t.v2 = map(t.v2);
    }
    for sp in s.spheres_mut() {
        sp.center = map(sp.center);
        sp.radius = (sp.radius as f64 * scale) as f32;
    }
    for l in s.lights_mut() {
        if l.kind == lambert::layout::LIGHT_POINT {
            l.vector = map(l.vector);
            l.color = l.color.map(|c| (c as f64 * scale * scale) as f32);
        }
    }
    s.rebuild_bvh();
    s
}

#[test]
fn scaled_and_translated_scenes_render_the_same_image() {
    let original = transformed_spheres(1.0, 0.0);
    let reference = render_cpu(&original);
    // Scaling alone (by powers far from 1) changes nothing but rounding:
    // at most 0.5% of pixels may differ by more than 1e-3 per channel, and
    // 0.5% hit another primitive.
    let scaled = lambert::diff::Tolerance {
        abs: 1e-3,
        rel: 1e-3,
        max_bad_fraction: 5e-3,
        max_prim_mismatch_fraction: 5e-3,
    };
    // A translation T puts every coordinate on a grid of spacing ~T·2⁻²⁴:
    // the scene itself moves by up to half of that, which no renderer can
    // undo. Where that is 1/1000 of the scene (T = 1e5, 12-unit floor),
    // silhouettes and shadow edges move by up to ~0.1 pixel: at most 2% of
    // pixels (those edges) may differ by more than 0.1 and 1% hit another
    // primitive, and the image as a whole stays within an RMSE of 0.05.
    let translated = lambert::diff::Tolerance {
        abs: 0.1,
        rel: 0.05,
        max_bad_fraction: 2e-2,
        max_prim_mismatch_fraction: 1e-2,
    };
    for (scale, translate) in [
        (1e-6, 0.0),
        (1e6, 0.0),
        (1.0, 1e5),
        (1e3, 1e5),
        (1e-6, 1e-1),
    ] {
        let scene = transformed_spheres(scale, translate);
        let grid = translate / scale * f64::EPSILON * (1u64 << 29) as f64;
        let (tolerance, rmse) = if grid < 1e-4 {
            (&scaled, 1e-3)
        } else {
            (&translated, 5e-2)
        };
        for (path, image) in [("CPU", render_cpu(&scene)), ("GPU", render_gpu(&scene))] {
            let stats = lambert::diff::compare(&image, &reference, tolerance).unwrap();
            println!(
                "scale {scale:e}, translate {translate:e} on {path}: {} pixels beyond {}, {} other primitive, RMSE {:.2e}",
                stats.beyond_tolerance, tolerance.abs, stats.prim_mismatches, stats.rmse
            );
            assert!(
                stats.passed && stats.rmse <= rmse,
                "scale {scale}, translate {translate} on {path}:\n{stats}"
            );
        }
    }
}

// ------------------------------------------------------------ against oracle

proptest! {
    #![proptest_config(proptest_config(256, "stress"))]
    /// Away from edges (barycentric band 1e-4) and grazing angles, every
    /// variant agrees with the oracle on hit or miss, and t within 1e-5
    /// relative plus what the origin's own magnitude allows (see below).
    #[test]
    fn each_variant_agrees_with_the_oracle_away_from_edges(
        v in prop::array::uniform9(-10.0f32..10.0),
        origin in prop::array::uniform3(-20.0f32..20.0),
        target in prop::array::uniform3(-10.0f32..10.0),
    ) {
        let t = Triangle { v0: [v[0], v[1], v[2]], v1: [v[3], v[4], v[5]], v2: [v[6], v[7], v[8]], ..Default::default() };
        let [a, b, c] = [t.v0, t.v1, t.v2].map(|p| Vec3::from(p).as_dvec3());
        let n = (b - a).cross(c - a);
        prop_assume!(n.length() > 1e-3);
        let r = ray(Vec3::from(origin), Vec3::from(target) - Vec3::from(origin));
        let d = Vec3::from(r.dir).as_dvec3();
        prop_assume!(d.length() > 1e-3);
        // Exact (f64) barycentrics of where the ray meets the plane.
        let o = Vec3::from(r.origin).as_dvec3();
        let cos = n.normalize().dot(d.normalize()).abs();
        prop_assume!(cos > 1e-3);
        let t_plane = n.dot(a - o) / n.dot(d);
        let p = o + t_plane * d;
        let area = |x: DVec3, y: DVec3, z: DVec3| (y - x).cross(z - x).dot(n) / n.length_squared();
        let bary = [area(p, b, c), area(a, p, c), area(a, b, p)];
        let margin = bary.iter().cloned().fold(f64::INFINITY, f64::min);
        let outside = bary.iter().cloned().fold(f64::INFINITY, |m, x| m.min(x.abs()));
        prop_assume!(outside > 1e-4 && t_plane.abs() > 1e-3);
        let expect_hit = margin > 0.0 && t_plane > 0.0;
        let base = scene_of(vec![t], vec![]);
        for intersect in Intersect::ALL {
            let s = with_intersect(&base, intersect);
            let h = trace_cpu(&s, &[r], false)[0];
            prop_assert_eq!(h.prim != NO_HIT, expect_hit, "{} disagrees with the oracle", intersect.name());
            if expect_hit {
                // f32 holds a point near the origin only to about ε·|o|, so
                // each variant's arithmetic (o − v, its products) may move
                // the hit by a few of those along the plane's normal: t by
                // that over cos·|d|. A hit close to an origin 20 units away
                // (t ~ 1e-3) cannot be right to 1e-5 of t alone.
                let near_origin = 4.0 * f32::EPSILON as f64 * o.length() / (cos * d.length());
                let error = (h.t as f64 - t_plane).abs();
                prop_assert!(
                    error <= 1e-5 * t_plane + near_origin,
                    "{}: t {} vs {} (error {:e}, allowed {:e} + {:e})",
                    intersect.name(), h.t, t_plane, error, 1e-5 * t_plane, near_origin
                );
            }
        }
    }
}

#[test]
fn gpu_and_cpu_agree_on_ray_sets_for_the_default_variant() {
    let mut rng = Rng(99);
    let mut total = 0;
    let mut same = 0;
    let mut worst_ulps = 0;
    let mut ulps = Vec::new();
    for name in ["bunny", "dragon", "cornell", "spheres"] {
        let scene = load(name);
        let root = scene.bvh().bounds().expect("a non-empty scene");
        let (lo, hi) = (root.min.as_dvec3(), root.max.as_dvec3());
        let size = (hi - lo).max_element();
        let rays: Vec<Ray> = (0..20_000)
            .map(|_| {
                let inside =
                    |rng: &mut Rng| lo + (hi - lo) * DVec3::new(rng.unit(), rng.unit(), rng.unit());
                let origin = inside(&mut rng) + rng.direction() * size;
                ray(origin.as_vec3(), (inside(&mut rng) - origin).as_vec3())
            })
            .collect();
        // The GPU's twin: the CPU path's own BVH visits children in another
        // order, and takes the other primitive where two tie on t (the
        // Cornell box's shared edges).
        let cpu_hits =
            cpu::trace_rays_gpu_twin(&scene, &rays, false, scene.default_settings().intersect);
        let gpu_hits = trace_gpu(&scene, &rays, false);
        let oracle = Agreement::measure(&gpu_hits, &cpu::trace_rays_f64(&scene, &rays, false));
        let mut scene_same = 0;
        for (c, g) in cpu_hits.iter().zip(&gpu_hits) {
            if c.prim == g.prim {
                scene_same += 1;
                if c.prim != NO_HIT {
                    let d = ulp_distance(c.t, g.t);
                    worst_ulps = worst_ulps.max(d);
                    ulps.push(d);
                }
            }
        }
        println!(
            "{name}: GPU and CPU hit the same primitive for {scene_same} of {} rays; GPU {oracle}",
            rays.len()
        );
        total += rays.len();
        same += scene_same;
    }
    ulps.sort();
    let p999 = ulps[(ulps.len() - 1) * 999 / 1000];
    println!(
        "all: {same} of {total} same primitive ({:.4}%); t differs by at most {worst_ulps} ULPs (99.9% within {p999})",
        100.0 * same as f64 / total as f64
    );
    assert!(
        same as f64 >= 0.9999 * total as f64,
        "GPU and CPU disagree on too many rays"
    );
    assert!(
        worst_ulps <= 16,
        "GPU and CPU t differ by {worst_ulps} ULPs"
    );
}

// ------------------------------------------------------ BVH on the GPU path

#[test]
fn gpu_bvh_traces_rays_like_gpu_brute_force() {
    let mut rng = Rng(3);
    for name in ["bunny", "cornell", "spheres", "edge_cases"] {
        let scene = load(name);
        let brute = common::brute_force(&scene);
        let root = scene.bvh().bounds().expect("a non-empty scene");
        let centre = root.centre().as_dvec3();
        let size = (root.max - root.min).max_element() as f64;
        let rays: Vec<Ray> = (0..5000)
            .map(|_| {
                let origin = centre + rng.direction() * size;
                let target = centre + rng.direction() * size * 0.3 * rng.unit();
                ray(origin.as_vec3(), (target - origin).as_vec3())
            })
            .collect();
        let (fast, slow) = (
            trace_gpu(&scene, &rays, false),
            trace_gpu(&brute, &rays, false),
        );
        let kernel = cpu::f32::Kernel::new(&scene);
        let mut ties = 0;
        for (r, (a, b)) in rays.iter().zip(fast.iter().zip(&slow)) {
            assert!(
                a.t == b.t || (a.t - b.t).abs() <= 1e-5 * b.t.abs(),
                "{name}: BVH t {} vs brute force {} for {r:?}",
                a.t,
                b.t
            );
            if a.prim != b.prim {
                // Another id only where both primitives are hit at that t
                // (a shared edge, or coplanar faces): either is the closest.
                let kr = cpu::f32::Ray::from_query(r);
                let shear = cpu::f32::ray_shear(kr.dir);
                let t_other = kernel.intersect_primitive(&kr, &shear, b.prim).0;
                assert!(
                    (t_other - a.t).abs() <= 1e-5 * a.t.abs(),
                    "{name}: BVH hits {} at {}, brute force {} at {}",
                    a.prim,
                    a.t,
                    b.prim,
                    b.t
                );
                ties += 1;
            }
        }
        let any_fast = trace_gpu(&scene, &rays, true);
        for (a, b) in any_fast.iter().zip(&slow) {
            assert_eq!(
                a.prim == NO_HIT,
                b.prim == NO_HIT,
                "{name}: any-hit disagrees with closest hit"
            );
        }
        println!("{name}: 5000 rays, GPU BVH = GPU brute force ({ties} ties on t)");
    }
}
