//! Issue 48, item 1: the CPU ray query runs a kernel specialised for what
//! the scene holds (`f32::Kernel::features`: no alpha masks, no spheres,
//! the watertight test compiles those checks out), and the generic kernel
//! (`cpu::trace_rays_as` with `QueryKernel::Generic`, every check at run time) is the portable
//! original it must equal, bit for bit, on every CPU kernel this machine
//! runs, for camera and random rays, closest and any hit, through BVHs
//! small and larger than cache.

mod common;

use common::brute_force;
use common::data::{soup, unit};
use glam::Vec3;
use lambert::Scene;
use lambert::cpu::f32::{
    ALL_FEATURES, FEATURE_ALPHA, FEATURE_OTHER_TESTS, FEATURE_SPHERES, Kernel,
};
use lambert::cpu::{CpuKernel, LARGE_BVH_BYTES, QueryKernel, trace_rays_as, trace_rays_with};
use lambert::layout::{FAR, Hit, Ray, Sphere};
use lambert::probe::Rng;
use lambert::scene::Intersect;

/// `n` rays from around `scene`'s box towards points inside it.
fn random_rays(scene: &Scene, seed: u64, n: usize) -> Vec<Ray> {
    let root = scene.bvh().bounds().expect("a non-empty scene");
    let (centre, spread) = (root.centre(), (root.max - root.min).max_element());
    let mut rng = Rng(seed);
    let mut around = |scale: f32| {
        centre + scale * spread * (Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) - 0.5)
    };
    (0..n)
        .map(|_| {
            let origin = around(2.0);
            let dir = around(0.5) - origin;
            Ray {
                origin: origin.to_array(),
                tmin: 0.0,
                dir: dir.to_array(),
                tmax: FAR,
            }
        })
        .collect()
}

/// A pinhole camera's `side` × `side` rays, row by row, from in front of
/// `scene`'s box across it (coherent: neighbours nearly parallel).
fn camera_rays(scene: &Scene, side: usize) -> Vec<Ray> {
    let root = scene.bvh().bounds().expect("a non-empty scene");
    let (centre, spread) = (root.centre(), (root.max - root.min).max_element());
    let eye = centre + Vec3::new(0.1, 0.2, 1.5) * spread;
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

fn key(hit: &Hit) -> (u32, u32, u32, u32) {
    (hit.prim, hit.t.to_bits(), hit.u.to_bits(), hit.v.to_bits())
}

/// The scenes, what `features` must say of each, and the triangle test to
/// trace them with.
fn scenes() -> Vec<(&'static str, Scene, u8, Intersect)> {
    let small = common::scene_of(soup(1, 3000), Vec::new());
    let large = common::scene_of(soup(2, 60_000), Vec::new());
    let bytes = large.bvh().device_bytes();
    assert!(bytes > LARGE_BVH_BYTES, "{bytes} bytes: not beyond cache");
    let mut rng = Rng(3);
    let spheres = (0..60)
        .map(|_| Sphere {
            center: [unit(&mut rng), unit(&mut rng), unit(&mut rng)],
            radius: 0.02 + 0.05 * unit(&mut rng),
            ..Default::default()
        })
        .collect();
    let with_spheres = common::scene_of(soup(4, 3000), spheres);
    let masked = Scene::load(&common::asset("scenes/meshes/textured.obj")).expect("bundled mesh");
    vec![
        ("small soup", small.clone(), 0, Intersect::Watertight),
        ("large soup", large, 0, Intersect::Watertight),
        (
            "spheres",
            with_spheres,
            FEATURE_SPHERES,
            Intersect::Watertight,
        ),
        ("alpha-masked", masked, FEATURE_ALPHA, Intersect::Watertight),
        (
            "Möller–Trumbore",
            small,
            FEATURE_OTHER_TESTS,
            Intersect::MollerTrumbore,
        ),
    ]
}

/// Each scene's features are what it holds: a variant chosen for a scene
/// that lacks a check it needs would give wrong hits.
#[test]
fn features_name_what_the_scene_holds() {
    for (name, scene, features, intersect) in scenes() {
        let mut kernel = Kernel::new(&scene);
        kernel.intersect = intersect;
        assert_eq!(kernel.features(), features, "{name}");
        assert_eq!(features & !ALL_FEATURES, 0, "{name}");
    }
}

/// The specialised kernel (chosen by `trace_rays_with`) gives the generic
/// kernel's hits bit for bit, on every CPU kernel this machine runs, for
/// camera and random rays (coherent and incoherent chunks), closest and
/// any hit.
#[test]
fn specialised_kernels_equal_the_generic_one() {
    use std::io::Write;
    for (name, scene, _, intersect) in scenes() {
        let camera = camera_rays(&scene, 96);
        let random = random_rays(&scene, 5, 4000);
        for cpu_kernel in CpuKernel::ALL {
            if let Some(missing) = cpu_kernel.missing() {
                let _ = writeln!(
                    std::io::stderr(),
                    "skipped: the {} kernel needs {missing}",
                    cpu_kernel.name()
                );
                continue;
            }
            for (rays, what) in [(&camera, "camera"), (&random, "random")] {
                for any_hit in [false, true] {
                    let generic = trace_rays_as(
                        &scene,
                        rays,
                        any_hit,
                        intersect,
                        cpu_kernel,
                        QueryKernel::Generic,
                    );
                    let special = trace_rays_with(&scene, rays, any_hit, intersect, cpu_kernel);
                    let hits = generic.iter().filter(|h| h.prim != u32::MAX).count();
                    assert!(hits > rays.len() / 20, "{name}, {what}: {hits} hits");
                    for (i, (a, b)) in generic.iter().zip(&special).enumerate() {
                        assert_eq!(
                            key(a),
                            key(b),
                            "{name}, {what} ray {i}, any_hit {any_hit}, {} kernel",
                            cpu_kernel.name()
                        );
                    }
                }
            }
        }
    }
}

/// Where the scene holds spheres or alpha masks, the query's closest hits
/// name the primitives that testing every primitive names (the BVH's
/// reference): spheres are hit and cut-outs are passed through, as a
/// variant that compiled them out would not.
#[test]
fn spheres_and_masks_are_traced_by_the_query() {
    for (name, scene, features, intersect) in scenes() {
        if features & (FEATURE_SPHERES | FEATURE_ALPHA) == 0 {
            continue;
        }
        let rays = random_rays(&scene, 7, 4000);
        let bvh = trace_rays_with(&scene, &rays, false, intersect, CpuKernel::active());
        let reference = lambert::cpu::trace_rays(&brute_force(&scene), &rays, false);
        let differ = bvh
            .iter()
            .zip(&reference)
            .filter(|(a, b)| a.prim != b.prim)
            .count();
        // Only rays through shared edges may name the other triangle.
        assert!(
            differ <= 2,
            "{name}: {differ} of {} rays differ",
            rays.len()
        );
        if features & FEATURE_SPHERES != 0 {
            let triangles = scene.triangles().len() as u32;
            let on_spheres = bvh
                .iter()
                .filter(|h| h.prim != u32::MAX && h.prim >= triangles)
                .count();
            assert!(on_spheres > 100, "{name}: {on_spheres} sphere hits");
        }
    }
}
