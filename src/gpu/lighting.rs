//! The overrides that compile the path integrator's light lookups out of
//! a scene without them (its emitters' table, environment and uniform are
//! uploaded with the scene's other arrays, src/gpu/upload.rs).

use crate::scene::Scene;

/// The overrides of `scene`'s lights: HAS_ENVIRONMENT, HAS_EMITTERS.
pub fn lighting_specialisation(scene: &Scene) -> [(&'static str, f64); 2] {
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    [
        ("HAS_ENVIRONMENT", flag(scene.environment().is_some())),
        ("HAS_EMITTERS", flag(!scene.emitters().entries.is_empty())),
    ]
}
