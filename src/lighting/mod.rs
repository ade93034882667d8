//! The path integrator's lights, built on the host once per scene: the
//! emitters' table (every emissive triangle, every punctual light and the
//! environment, one alias table by power: pbrt-v4's `PowerLightSampler`)
//! and the environment (`environment.rs`). Both render paths read them:
//! the CPU twin from the scene, the GPU from group 0's bindings 20–23
//! (docs/rendering.md, "Lights").

mod alias;
mod distribution;
mod environment;

use alias::alias_table;
pub use environment::{
    Environment, EnvironmentMap, EnvironmentSource, EnvironmentSpec, MAX_ENVIRONMENT_BYTES,
};

use std::f64::consts::PI;

use crate::layout::{
    EMITTER_ENVIRONMENT, EMITTER_LIGHT, EMITTER_TRIANGLE, Emitter, FLAG_ATTRIBUTES,
    LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT, LIGHTING_ENVIRONMENT_IMAGE, Light, Lighting,
    Material, NO_TEXTURE, Triangle,
};
use crate::texture::TextureStore;

/// What of a scene its emitters are: its triangles with their materials
/// and textures, its punctual lights, its environment, and the radius of
/// a sphere bounding its geometry (a directional light's and the
/// environment's power are what crosses its disc).
pub struct SceneLights<'a> {
    pub triangles: &'a [Triangle],
    pub materials: &'a [Material],
    pub textures: &'a TextureStore,
    pub lights: &'a [Light],
    pub environment: Option<&'a Environment>,
    pub radius: f64,
}

/// The emitters' table and the lighting uniform: what `sample_emitter`,
/// `emitter_pdf` and the environment's lookups read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EmitterTable {
    /// Triangles first (by primitive id), then lights, then the
    /// environment; only those whose power is not 0.
    pub entries: Vec<Emitter>,
    pub uniform: Lighting,
}

/// Mean of the three channels: the power's measure (pbrt-v4's
/// `SampledSpectrum::Average`, which `PowerLightSampler` weighs by).
fn mean(c: [f64; 3]) -> f64 {
    (c[0] + c[1] + c[2]) / 3.0
}

fn wide(c: [f32; 3]) -> [f64; 3] {
    c.map(f64::from)
}

/// The power of `light`, treated as the path integrator treats punctual
/// lights: emitting π·color (docs/rendering.md, "Lights"), the intensity
/// I of a point light (Φ = 4π·I) or a spot (Φ = 2π·I·((1 − cos inner) +
/// (cos inner − cos outer)/3), its t² falloff integrated over the cone
/// between, as pbrt's `SpotLight::Phi` integrates its own), the
/// irradiance E of a directional one (Φ = π r²·E, pbrt's
/// `DistantLight::Phi`).
fn light_power(light: &Light, radius: f64) -> f64 {
    let emitted = PI * mean(wide(light.color));
    match light.kind {
        LIGHT_POINT => 4.0 * PI * emitted,
        LIGHT_SPOT => {
            let (inner, outer) = (light.cos_inner as f64, light.cos_outer as f64);
            2.0 * PI * emitted * ((1.0 - inner) + (inner - outer).max(0.0) / 3.0)
        }
        LIGHT_DIRECTIONAL => PI * radius * radius * emitted,
        _ => 0.0,
    }
}

/// The radiance (channels' mean) each material's triangles emit, for
/// their power: emission × its texture's mean where the texture is read.
fn material_radiance(materials: &[Material], textures: &TextureStore) -> Vec<[f64; 2]> {
    materials
        .iter()
        .map(|m| {
            let plain = mean(wide(m.emission));
            let textured = if m.emissive_texture == NO_TEXTURE {
                plain
            } else {
                let t = textures.mean_color(m.emissive_texture);
                mean(std::array::from_fn(|c| m.emission[c] as f64 * t[c]))
            };
            [plain, textured]
        })
        .collect()
}

/// The area of `tri`, in f64 from its f32 corners.
fn triangle_area(tri: &Triangle) -> f64 {
    let [a, b, c] = [tri.v0, tri.v1, tri.v2].map(|v| glam::DVec3::from(wide(v)));
    0.5 * (b - a).cross(c - a).length()
}

/// The emitters' table of `scene` (see `EmitterTable`). An emissive
/// triangle emits from both faces, as the camera sees it, so its power is
/// 2π·A·L (pbrt-v4's two-sided `DiffuseAreaLight::Phi`).
pub fn emitter_table(scene: &SceneLights) -> EmitterTable {
    let radiance = material_radiance(scene.materials, scene.textures);
    let mut emitters = Vec::new();
    let mut powers = Vec::new();
    for (prim, tri) in scene.triangles.iter().enumerate() {
        let [plain, textured] = radiance[tri.material as usize];
        let l = if tri.flags & FLAG_ATTRIBUTES != 0 {
            textured
        } else {
            plain
        };
        if l > 0.0 {
            emitters.push((EMITTER_TRIANGLE, prim as u32));
            powers.push(2.0 * PI * triangle_area(tri) * l);
        }
    }
    let triangles = emitters.len();
    for (i, light) in scene.lights.iter().enumerate() {
        emitters.push((EMITTER_LIGHT, i as u32));
        powers.push(light_power(light, scene.radius));
    }
    if let Some(environment) = scene.environment {
        emitters.push((EMITTER_ENVIRONMENT, 0));
        powers.push(PI * scene.radius * scene.radius * environment.radiance_integral);
    }
    // Nothing that gives no light: it could never be picked.
    let kept: Vec<usize> = (0..powers.len())
        .filter(|&i| powers[i] > 0.0 && powers[i].is_finite())
        .collect();
    let weights: Vec<f64> = kept.iter().map(|&i| powers[i]).collect();
    let bins = if weights.is_empty() {
        Vec::new()
    } else {
        alias_table(&weights)
    };
    let entries: Vec<Emitter> = kept
        .iter()
        .zip(&bins)
        .map(|(&i, bin)| Emitter {
            kind: emitters[i].0,
            index: emitters[i].1,
            pmf: bin.p as f32,
            q: bin.q as f32,
            alias_bin: bin.alias,
            ..Default::default()
        })
        .collect();
    let environment_pmf = entries
        .iter()
        .find(|e| e.kind == EMITTER_ENVIRONMENT)
        .map_or(0.0, |e| e.pmf);
    let mut uniform = Lighting {
        num_emitters: entries.len() as u32,
        num_triangle_emitters: kept.iter().filter(|&&i| i < triangles).count() as u32,
        environment_pmf,
        total_power: weights.iter().sum::<f64>() as f32,
        rotation_cos: 1.0,
        ..Default::default()
    };
    if let Some(environment) = scene.environment {
        uniform.environment_color = environment.color;
        [uniform.rotation_cos, uniform.rotation_sin] = environment.rotation;
        if let Some(map) = &environment.map {
            uniform.environment_width = map.width;
            uniform.environment_height = map.height;
            uniform.flags |= LIGHTING_ENVIRONMENT_IMAGE;
        }
    }
    EmitterTable { entries, uniform }
}
