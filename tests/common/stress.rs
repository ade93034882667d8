//! Geometry helpers and probes of the numerical stress tests
//! (tests/stress.rs, tests/stress_edge_cases.rs; tests/hardware_rays.rs
//! runs the probes on the hardware path).

use glam::{DVec3, Vec3};
use lambert::Scene;
use lambert::cpu;
use lambert::layout::{Hit, NO_HIT, Ray, Triangle};
use lambert::probe::{Rng, edge_aimed_rays, icosphere};
use lambert::scene::Intersect;

use super::{asset, scene, scene_of};

pub fn triangle(v: [Vec3; 3]) -> Triangle {
    Triangle {
        v0: v[0].to_array(),
        v1: v[1].to_array(),
        v2: v[2].to_array(),
        ..Default::default()
    }
}

pub fn with_intersect(scene: &Scene, intersect: Intersect) -> Scene {
    let settings = lambert::scene::RenderSettings {
        intersect,
        ..scene.default_settings()
    };
    scene.clone().with_settings(&settings)
}

pub fn ray(origin: Vec3, dir: Vec3) -> Ray {
    Ray {
        origin: origin.to_array(),
        tmin: 0.0,
        dir: dir.to_array(),
        tmax: f32::INFINITY,
    }
}

pub fn misses(hits: &[Hit]) -> usize {
    hits.iter().filter(|h| h.prim == NO_HIT).count()
}

/// A named mesh: vertices and triangles as vertex indices.
pub type NamedMesh = (&'static str, Vec<DVec3>, Vec<[u32; 3]>);

/// The closed meshes of the leak test, as f64 vertices and faces, about 20
/// units across.
pub fn closed_meshes() -> Vec<NamedMesh> {
    let (ico_v, ico_f) = icosphere(10.0, 3);
    let cube = lambert::loading::load_obj(
        &asset("scenes/meshes/cube.obj"),
        lambert::loading::NormalMode::Face,
    )
    .unwrap();
    let bunny = lambert::loading::load_obj(
        &asset("scenes/meshes/bunny_lowres.obj"),
        lambert::loading::NormalMode::Face,
    )
    .unwrap();
    let scale = |m: lambert::loading::Mesh, size: f64| {
        let lo = m.positions.iter().fold(DVec3::MAX, |a, &b| a.min(b));
        let hi = m.positions.iter().fold(DVec3::MIN, |a, &b| a.max(b));
        let k = size / (hi - lo).max_element();
        let centre = 0.5 * (lo + hi);
        let v = m.positions.iter().map(|&p| (p - centre) * k).collect();
        (v, m.triangles)
    };
    let (cube_v, cube_f) = scale(cube, 20.0);
    let (bunny_v, bunny_f) = scale(bunny, 20.0);
    vec![
        ("icosphere", ico_v, ico_f),
        ("cube", cube_v, cube_f),
        ("bunny_lowres", bunny_v, bunny_f),
    ]
}

/// Where the leak test moves them.
pub const OFFSETS: [[f64; 3]; 3] = [[0.0; 3], [1.5e5, 1.2e3, -2.2e5], [1e6, 1e6, 1e6]];

/// The leak test's cases: each closed mesh at each offset (its name, the
/// offset, its scene) with its edge-aimed rays from inside, every one of
/// which the f64 oracle hits (checked here).
pub fn leak_cases(rng: &mut Rng) -> Vec<(&'static str, DVec3, Scene, Vec<Ray>)> {
    let mut cases = Vec::new();
    for (name, vertices, faces) in closed_meshes() {
        for offset in OFFSETS {
            let offset = DVec3::from(offset);
            let v32: Vec<Vec3> = vertices.iter().map(|&v| (v + offset).as_vec3()).collect();
            let triangles: Vec<Triangle> = faces
                .iter()
                .map(|f| triangle(f.map(|i| v32[i as usize])))
                .collect();
            let scene = scene_of(triangles, vec![]);
            let rays = edge_aimed_rays(&v32, &faces, rng);
            let oracle = cpu::trace_rays_f64(&scene, &rays, false);
            assert_eq!(
                oracle.iter().filter(|h| h.prim == NO_HIT).count(),
                0,
                "{name} at {offset}: the f64 oracle leaks"
            );
            cases.push((name, offset, scene, rays));
        }
    }
    cases
}

/// Triangles at random scales from 1e-8 to 1e8, each placed at a random
/// distance of up to a few times its size from the origin.
pub fn random_scale_triangles(rng: &mut Rng, n: usize) -> Vec<Triangle> {
    (0..n)
        .map(|_| {
            let scale = 10f64.powf(rng.range(-8.0, 8.0));
            let centre = rng.direction() * scale * rng.range(0.0, 4.0);
            triangle(
                [0, 1, 2]
                    .map(|_| (centre + rng.direction() * scale * rng.range(0.2, 1.0)).as_vec3()),
            )
        })
        .collect()
}

/// A ray at a random interior point of each triangle, from its front.
pub fn rays_at_fronts(triangles: &[Triangle], rng: &mut Rng) -> Vec<Ray> {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = [t.v0, t.v1, t.v2].map(|v| Vec3::from(v).as_dvec3());
            let n = (b - a).cross(c - a).normalize();
            let (u, v) = (rng.range(0.1, 0.45), rng.range(0.1, 0.45));
            let p = a + u * (b - a) + v * (c - a);
            let size = (b - a).length().max((c - a).length());
            let origin = p + n * size;
            ray(origin.as_vec3(), (p - origin).as_vec3())
        })
        .collect()
}

/// Four rays spawned from each hit of `primary` in `scene` as shading
/// spawns them (the hit point, its error bound and the offset along the
/// normal facing the incoming ray), in random directions on that side,
/// and the primitive each left.
pub fn spawned_rays(scene: &Scene, primary: &[Ray], rng: &mut Rng) -> (Vec<Ray>, Vec<u32>) {
    let kernel = cpu::f32::Kernel::new(scene);
    let hits = cpu::trace_rays(scene, primary, false);
    let mut spawned = Vec::new();
    let mut sources = Vec::new();
    for (r, h) in primary.iter().zip(&hits) {
        if h.prim == NO_HIT {
            continue;
        }
        let surface =
            kernel.surface_at(&cpu::f32::Ray::from_query(r), &cpu::f32::Hit::from_query(h));
        let n = surface.geometric_normal;
        let origin = cpu::f32::offset_ray_origin(surface.position, surface.error, n);
        for _ in 0..4 {
            let mut d = rng.direction().as_vec3();
            if d.dot(n) < 0.0 {
                d = -d;
            }
            spawned.push(ray(origin, d));
            sources.push(h.prim);
        }
    }
    (spawned, sources)
}

/// A quad scaled by `scale` and moved by `translate`, lit at 60° by a
/// directional light, seen from above at an angle; shadows on.
pub fn lit_plane(scale: f64, translate: [f64; 3], intersect: Intersect) -> Scene {
    let at = |p: [f64; 3]| {
        format!(
            "[{:e}, {:e}, {:e}]",
            p[0] * scale + translate[0],
            p[1] * scale + translate[1],
            p[2] * scale + translate[2]
        )
    };
    let s = scene(&format!(
        "[camera]\neye = {}\nlook_at = {}\nvfov = 40.0\nwidth = 48\nheight = 48\n\
         [[mesh]]\nobj = \"meshes/quad.obj\"\nscale = {:e}\ntranslate = {}\nalbedo = 0.5\n\
         [[directional_light]]\ndirection = [0.0, -0.5, -0.8660254037844386]\nirradiance = 2.0\n",
        at([0.0, 1.0, 1.2]),
        at([0.0; 3]),
        4.0 * scale,
        at([0.0; 3]),
    ));
    let settings = lambert::scene::RenderSettings {
        intersect,
        ..s.default_settings()
    };
    s.with_settings(&settings)
}
