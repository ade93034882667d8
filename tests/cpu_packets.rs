//! Issue 48, item 2: coherent rays traced in packets (src/cpu/packet.rs)
//! give the single-ray kernel's hits bit for bit, closest and any hits
//! (`cpu::trace_rays_as` with `QueryKernel::Single`, the portable original): t, primitive, u and
//! v, on every CPU kernel this machine runs, for camera rays, the shadow
//! rays of their hits, rays through shared vertices and duplicated
//! triangles (hits at the same distance, where the single ray keeps the
//! first it meets), rays that miss everything, packets whose rays diverge
//! or straddle an axis, and random packets (a proptest); and the CPU
//! render's images, whose camera rays go in packets. Scenes with
//! spheres, alpha masks or another triangle test and incoherent rays do
//! not take the packets (`cpu::traces_in_packets`).

mod common;

use common::data::{soup, unit};
use glam::Vec3;
use lambert::Scene;
use lambert::cpu::{CpuKernel, QueryKernel, trace_rays_as, trace_rays_with, traces_in_packets};
use lambert::layout::{FAR, Hit, NO_HIT, Ray, Sphere, Triangle};
use lambert::probe::Rng;
use lambert::scene::Intersect;
use proptest::prelude::*;

/// A `side` × `side` grid of unit quads in the plane z = 0 (two triangles
/// each, sharing edges and vertices), every triangle twice: each hit is
/// at the same distance on two primitives, and rays through grid points on
/// six.
fn doubled_grid(side: usize) -> Vec<Triangle> {
    let mut triangles = Vec::new();
    let p = |i: usize, j: usize| {
        [
            i as f32 - side as f32 / 2.0,
            j as f32 - side as f32 / 2.0,
            0.0,
        ]
    };
    for i in 0..side {
        for j in 0..side {
            for tri in [
                common::data::tri(p(i, j), p(i + 1, j), p(i + 1, j + 1)),
                common::data::tri(p(i, j), p(i + 1, j + 1), p(i, j + 1)),
            ] {
                triangles.push(tri);
                triangles.push(tri);
            }
        }
    }
    triangles
}

/// A pinhole camera's `side` × `side` rays, row by row, from `offset`
/// (times the box's size) off `scene`'s centre towards the box's middle
/// plane.
fn camera_rays(scene: &Scene, side: usize, offset: Vec3) -> Vec<Ray> {
    let root = scene.bvh().bounds().expect("a non-empty scene");
    let (centre, spread) = (root.centre(), (root.max - root.min).max_element());
    let eye = centre + offset * spread;
    (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side) as f32, (i / side) as f32);
            let target =
                centre + spread * Vec3::new(x / side as f32 - 0.5, 0.5 - y / side as f32, 0.0);
            Ray {
                origin: eye.to_array(),
                tmin: 0.0,
                dir: (target - eye).to_array(),
                tmax: FAR,
            }
        })
        .collect()
}

/// Rays from the closest hits of `camera` (moved a thousandth of the
/// scene's size back along their ray) towards `light`, ending there: the
/// shadow rays of a render, in pixel order.
fn shadow_rays(scene: &Scene, camera: &[Ray], light: Vec3) -> Vec<Ray> {
    let hits = trace_rays_as(
        scene,
        camera,
        false,
        Intersect::Watertight,
        CpuKernel::Portable,
        QueryKernel::Single,
    );
    camera
        .iter()
        .zip(&hits)
        .filter(|(_, h)| h.prim != NO_HIT)
        .map(|(ray, hit)| {
            let dir = Vec3::from(ray.dir);
            let point = Vec3::from(ray.origin) + dir * hit.t * 0.999;
            Ray {
                origin: point.to_array(),
                tmin: 0.0,
                dir: (light - point).to_array(),
                tmax: 1.0,
            }
        })
        .collect()
}

fn key(hit: &Hit) -> (u32, u32, u32, u32) {
    (hit.prim, hit.t.to_bits(), hit.u.to_bits(), hit.v.to_bits())
}

/// The CPU kernels this machine runs (those it cannot, named on stderr).
fn kernels() -> Vec<CpuKernel> {
    use std::io::Write;
    CpuKernel::ALL
        .into_iter()
        .filter(|k| match k.missing() {
            None => true,
            Some(missing) => {
                let _ = writeln!(
                    std::io::stderr(),
                    "skipped: the {} kernel needs {missing}",
                    k.name()
                );
                false
            }
        })
        .collect()
}

/// The packets' closest hits, and their any hits (each ray's first hit in
/// its own order), equal the single ray's, bit for bit, on every CPU
/// kernel; returns how many rays hit.
fn assert_same_hits(scene: &Scene, rays: &[Ray], what: &str) -> usize {
    assert!(
        traces_in_packets(scene, rays, Intersect::Watertight),
        "{what}: not traced in packets"
    );
    let mut hit_count = 0;
    for any_hit in [false, true] {
        for cpu_kernel in kernels() {
            let single = trace_rays_as(
                scene,
                rays,
                any_hit,
                Intersect::Watertight,
                cpu_kernel,
                QueryKernel::Single,
            );
            let packets = trace_rays_with(scene, rays, any_hit, Intersect::Watertight, cpu_kernel);
            for (i, (a, b)) in single.iter().zip(&packets).enumerate() {
                assert_eq!(
                    key(a),
                    key(b),
                    "{what}, ray {i}, {} kernel, any hit {any_hit}",
                    cpu_kernel.name()
                );
            }
            // And the portable original's, whichever kernel traced.
            let portable = trace_rays_as(
                scene,
                rays,
                any_hit,
                Intersect::Watertight,
                CpuKernel::Portable,
                QueryKernel::Single,
            );
            assert!(
                portable.iter().zip(&packets).all(|(a, b)| key(a) == key(b)),
                "{what}: the {} kernel's packets differ from the portable kernel, any hit {any_hit}",
                cpu_kernel.name()
            );
            let hits = single.iter().filter(|h| h.prim != NO_HIT).count();
            if any_hit {
                assert_eq!(hits, hit_count, "{what}: any hits against closest hits");
            }
            hit_count = hits;
        }
    }
    hit_count
}

#[test]
fn camera_and_shadow_rays_in_packets_equal_the_single_ray() {
    let small = common::scene_of(soup(1, 3000), Vec::new());
    let large = common::scene_of(soup(2, 60_000), Vec::new());
    for (name, scene) in [("small soup", &small), ("large soup", &large)] {
        // Straddling the x and y axes (packets of mixed octants go alone),
        // and from one side, all in one octant.
        for offset in [Vec3::new(0.1, 0.2, 1.5), Vec3::new(1.2, 0.9, 1.5)] {
            let camera = camera_rays(scene, 256, offset);
            let hits = assert_same_hits(scene, &camera, &format!("{name}, camera {offset}"));
            assert!(hits > camera.len() / 10, "{name}: {hits} camera hits");
            let shadow = shadow_rays(scene, &camera, Vec3::new(3.0, 4.0, 5.0));
            let blocked = assert_same_hits(scene, &shadow, &format!("{name}, shadow {offset}"));
            assert!(blocked > shadow.len() / 20, "{name}: {blocked} shadow hits");
        }
    }
}

/// Every hit of the doubled grid is a tie, and rays through its grid points
/// meet six triangles at one point: the packet must name the triangle the
/// single ray meets first (it traces such rays again alone).
#[test]
fn ties_are_resolved_as_the_single_ray_resolves_them() {
    let scene = common::scene_of(doubled_grid(16), Vec::new());
    let eye = Vec3::new(0.25, 0.5, 20.0);
    // Through every grid point, row by row, and between them.
    let mut rays = Vec::new();
    for j in 0..=16 {
        for step in 0..=32 {
            let i = step as f32 / 2.0;
            let target = Vec3::new(i - 8.0, j as f32 - 8.0, 0.0);
            rays.push(Ray {
                origin: eye.to_array(),
                tmin: 0.0,
                dir: (target - eye).to_array(),
                tmax: FAR,
            });
        }
    }
    let hits = assert_same_hits(&scene, &rays, "doubled grid");
    assert!(hits > rays.len() * 9 / 10, "{hits} hits");
    let camera = camera_rays(&scene, 128, Vec3::new(0.05, 0.1, 1.0));
    assert_same_hits(&scene, &camera, "doubled grid, camera");
}

/// Rays that miss everything (looking away from the scene, and past it)
/// miss in packets too.
#[test]
fn rays_that_miss_everything_miss_in_packets() {
    let scene = common::scene_of(soup(3, 2000), Vec::new());
    let away = camera_rays(&scene, 64, Vec3::new(0.1, 0.2, 1.5))
        .into_iter()
        .map(|r| Ray {
            dir: (-Vec3::from(r.dir)).to_array(),
            ..r
        })
        .collect::<Vec<_>>();
    assert_eq!(assert_same_hits(&scene, &away, "away"), 0);
    // Past the box's edge: tmax too short to reach it.
    let short = camera_rays(&scene, 64, Vec3::new(0.1, 0.2, 1.5))
        .into_iter()
        .map(|r| Ray { tmax: 0.5, ..r })
        .collect::<Vec<_>>();
    assert_eq!(assert_same_hits(&scene, &short, "short"), 0);
}

/// Packets whose rays part: neighbours alternating between two far-apart
/// directions (each packet's rays then go alone), and camera rays with a
/// few of them turned away in every packet.
#[test]
fn diverging_packets_equal_the_single_ray() {
    let scene = common::scene_of(soup(4, 4000), Vec::new());
    let camera = camera_rays(&scene, 128, Vec3::new(0.3, 0.2, 1.5));
    let alternating: Vec<Ray> = camera
        .iter()
        .enumerate()
        .map(|(i, r)| {
            if i % 2 == 0 {
                *r
            } else {
                Ray {
                    dir: (Vec3::from(r.dir) * Vec3::new(-1.0, 1.0, 1.0)).to_array(),
                    ..*r
                }
            }
        })
        .collect();
    // Coherent as a whole (most rays neighbour one of their own), so in
    // packets; each packet of them is not, and goes ray by ray.
    let mixed: Vec<Ray> = camera
        .iter()
        .enumerate()
        .map(|(i, r)| {
            if i % 16 == 5 {
                Ray {
                    dir: (-Vec3::from(r.dir)).to_array(),
                    ..*r
                }
            } else {
                *r
            }
        })
        .collect();
    assert_same_hits(&scene, &mixed, "one ray in 16 turned away");
    assert!(!traces_in_packets(
        &scene,
        &alternating,
        Intersect::Watertight
    ));
    for cpu_kernel in kernels() {
        let single = trace_rays_as(
            &scene,
            &alternating,
            false,
            Intersect::Watertight,
            cpu_kernel,
            QueryKernel::Single,
        );
        let with = trace_rays_with(
            &scene,
            &alternating,
            false,
            Intersect::Watertight,
            cpu_kernel,
        );
        assert!(single.iter().zip(&with).all(|(a, b)| key(a) == key(b)));
    }
}

/// Spheres, alpha masks, another triangle test and incoherent rays take
/// the single-ray kernel, and their hits (closest and any) are its.
#[test]
fn scenes_and_queries_packets_cannot_trace_go_ray_by_ray() {
    let plain = common::scene_of(soup(5, 3000), Vec::new());
    let mut rng = Rng(6);
    let spheres = (0..40)
        .map(|_| Sphere {
            center: [
                unit(&mut rng) - 0.5,
                unit(&mut rng) - 0.5,
                unit(&mut rng) - 0.5,
            ],
            radius: 0.02 + 0.05 * unit(&mut rng),
            ..Default::default()
        })
        .collect();
    let with_spheres = common::scene_of(soup(5, 3000), spheres);
    let masked = Scene::load(&common::asset("scenes/meshes/textured.obj")).expect("bundled mesh");
    let camera = |scene: &Scene| camera_rays(scene, 128, Vec3::new(0.1, 0.2, 1.5));
    assert!(traces_in_packets(
        &plain,
        &camera(&plain),
        Intersect::Watertight
    ));
    let cases = [
        ("spheres", &with_spheres, Intersect::Watertight),
        ("alpha masks", &masked, Intersect::Watertight),
        ("Möller–Trumbore", &plain, Intersect::MollerTrumbore),
    ];
    for ((name, scene, intersect), any_hit) in cases
        .into_iter()
        .flat_map(|case| [(case, false), (case, true)])
    {
        let rays = camera(scene);
        assert!(
            !traces_in_packets(scene, &rays, intersect),
            "{name}: in packets"
        );
        for cpu_kernel in kernels() {
            let single = trace_rays_as(
                scene,
                &rays,
                any_hit,
                intersect,
                cpu_kernel,
                QueryKernel::Single,
            );
            let with = trace_rays_with(scene, &rays, any_hit, intersect, cpu_kernel);
            assert!(
                single.iter().zip(&with).all(|(a, b)| key(a) == key(b)),
                "{name}"
            );
        }
    }
    // Random rays: incoherent, so ray by ray.
    let mut rng = Rng(7);
    let random: Vec<Ray> = (0..4096)
        .map(|_| {
            let mut point = || Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) - 0.5;
            let origin = 2.0 * point();
            Ray {
                origin: origin.to_array(),
                tmin: 0.0,
                dir: (point() - origin).to_array(),
                tmax: FAR,
            }
        })
        .collect();
    assert!(!traces_in_packets(&plain, &random, Intersect::Watertight));
}

/// The CPU render traces its camera rays in packets where the scene is
/// triangles alone: its image and variances are those of rendering each
/// pixel alone (`cpu::render_pixel_list`, `Kernel::render_pixel` pixel by
/// pixel), bit for bit, on every CPU kernel, several samples a pixel and a
/// width no multiple of the packet's (shadows on, point lights: the
/// bundled Cornell box; the dragon as a model file, its default light).
#[test]
fn renders_with_packets_equal_pixels_rendered_alone() {
    use lambert::cpu::{Precision, render_pixel_list, render_with};
    use lambert::progress::Progress;
    let cornell = Scene::load(&common::asset("scenes/cornell.toml")).expect("bundled scene");
    let dragon =
        Scene::load(&common::asset("scenes/meshes/dragon_res4.obj")).expect("bundled mesh");
    for (name, scene) in [("cornell", &cornell), ("dragon_res4", &dragon)] {
        let mut view = scene.view().clone();
        view.camera.width = 67;
        view.camera.height = 29;
        view.spp = 3;
        let pixels: Vec<[u32; 2]> = (0..view.camera.height)
            .flat_map(|y| (0..view.camera.width).map(move |x| [x, y]))
            .collect();
        let alone = render_pixel_list(scene, &view, &pixels);
        let lit = alone.iter().filter(|p| p[0] > 0.05).count();
        assert!(lit > pixels.len() / 20, "{name}: {lit} lit pixels");
        for cpu_kernel in kernels() {
            let rendered = render_with(
                scene,
                &view,
                Precision::F32,
                &Progress::hidden(),
                cpu_kernel,
            );
            for (i, (rgb, expected)) in rendered.image.rgb.iter().zip(&alone).enumerate() {
                let got = [rgb[0], rgb[1], rgb[2], rendered.variance[i]].map(f32::to_bits);
                assert_eq!(
                    got,
                    expected.map(f32::to_bits),
                    "{name}, pixel {i}, {} kernel",
                    cpu_kernel.name()
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(common::proptest_config(48, "cpu_packets"))]

    /// Random packets: 64 rays from around one point of a random soup's
    /// neighbourhood, within a random spread of one direction, some with a
    /// finite tmax; in packets, the single ray's hits (closest and any)
    /// bit for bit.
    #[test]
    fn random_packets_equal_the_single_ray(
        seed in 0u64..1000,
        eye in prop::array::uniform3(-2.0f32..2.0),
        look in prop::array::uniform3(-0.3f32..0.3),
        spread in 0.0f32..0.3,
        tmax in prop::option::of(0.5f32..4.0),
    ) {
        let scene = common::scene_of(soup(seed, 500), Vec::new());
        let eye = Vec3::from(eye) + Vec3::new(0.0, 0.0, 2.5);
        let base = Vec3::from(look) - eye;
        let mut rng = Rng(seed + 1);
        let rays: Vec<Ray> = (0..64)
            .map(|_| {
                let jitter = Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) - 0.5;
                Ray {
                    origin: eye.to_array(),
                    tmin: 0.0,
                    dir: (base + spread * jitter).to_array(),
                    tmax: tmax.unwrap_or(FAR),
                }
            })
            .collect();
        for any_hit in [false, true] {
            let single = trace_rays_as(&scene, &rays, any_hit, Intersect::Watertight, CpuKernel::Portable, QueryKernel::Single);
            for cpu_kernel in kernels() {
                let packets = trace_rays_with(&scene, &rays, any_hit, Intersect::Watertight, cpu_kernel);
                for (i, (a, b)) in single.iter().zip(&packets).enumerate() {
                    prop_assert_eq!(key(a), key(b), "ray {}, {} kernel, any hit {}", i, cpu_kernel.name(), any_hit);
                }
            }
        }
    }
}

/// AVX-512 narrows to AVX2 for packets on an Intel CPU (as Linux's
/// /proc/cpuinfo names its vendor) and nowhere else; no other kernel
/// narrows.
#[cfg(target_os = "linux")]
#[test]
fn avx512_narrows_to_avx2_on_intel_alone() {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").expect("/proc/cpuinfo");
    let intel = cpuinfo
        .lines()
        .find(|l| l.starts_with("vendor_id"))
        .is_some_and(|l| l.ends_with("GenuineIntel"));
    assert_eq!(CpuKernel::Portable.narrow_on_intel(), CpuKernel::Portable);
    assert_eq!(CpuKernel::Avx2Fma.narrow_on_intel(), CpuKernel::Avx2Fma);
    let narrowed = match intel {
        true => CpuKernel::Avx2Fma,
        false => CpuKernel::Avx512,
    };
    assert_eq!(CpuKernel::Avx512.narrow_on_intel(), narrowed);
}
