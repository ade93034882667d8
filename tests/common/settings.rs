//! Scenes with a render setting changed, as the jobs render them.

use lambert::Scene;
use lambert::scene::{Accel, RenderSettings};

/// `scene` traced by testing every primitive (the BVH's reference).
pub fn brute_force(scene: &Scene) -> Scene {
    let settings = RenderSettings {
        accel: Accel::BruteForce,
        ..scene.default_settings()
    };
    scene.clone().with_settings(&settings)
}
