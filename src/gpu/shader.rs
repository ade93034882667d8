//! The shader's source and the overrides that specialise it: the one place
//! the host reads `shaders/` from.

use crate::layout::{LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT};
use crate::scene::{Integrator, Scene};

/// The kernel's source, validated by naga in tests/shaders.rs.
pub const SHADER_SOURCE: &str = crate::shader_source::SOURCE;

/// The kernel tracing through ray queries (`--accel hardware`).
pub const HARDWARE_SOURCE: &str = crate::shader_source::HARDWARE_SOURCE;

/// Pipeline-overridable constants that strip what `scene` does not use.
pub fn specialisation(scene: &Scene) -> Vec<(&'static str, f64)> {
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    let has_light = |kind| scene.lights.iter().any(|l| l.kind == kind);
    let mut constants = vec![
        ("HAS_TRIANGLES", flag(!scene.triangles.is_empty())),
        ("HAS_SPHERES", flag(!scene.spheres.is_empty())),
        (
            "HAS_SHADOWS",
            flag(scene.shadows && !scene.lights.is_empty()),
        ),
        ("HAS_POINT_LIGHTS", flag(has_light(LIGHT_POINT))),
        ("HAS_DIRECTIONAL_LIGHTS", flag(has_light(LIGHT_DIRECTIONAL))),
        ("HAS_SPOT_LIGHTS", flag(has_light(LIGHT_SPOT))),
        ("HAS_ALPHA_MASK", flag(scene.has_alpha_mask())),
        ("HAS_TEXTURES", flag(scene.has_textures())),
        ("HAS_ATTRIBUTES", flag(!scene.attributes.is_empty())),
        // Tangents are kept for every triangle once one material has a
        // normal texture.
        ("HAS_NORMAL_MAPS", flag(!scene.tangents.is_empty())),
        // Normals are kept for every triangle once one mesh is smooth.
        ("HAS_SMOOTH", flag(!scene.normals.is_empty())),
        ("USE_BVH", flag(scene.accel.traverses_bvh())),
        ("PATH_TRACE", flag(scene.integrator == Integrator::Path)),
        ("INTERSECT", scene.intersect.shader_value() as f64),
    ];
    constants.extend(super::lighting::lighting_specialisation(scene));
    constants
}
