//! Geometry helpers of the numerical stress tests (tests/stress.rs, tests/stress_edge_cases.rs).

use glam::Vec3;
use lambert::Scene;
use lambert::layout::{Hit, NO_HIT, Ray, Triangle};
use lambert::scene::Intersect;

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
