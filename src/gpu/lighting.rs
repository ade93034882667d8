//! The path integrator's lights on the device: the emitters' table, the
//! environment's pixels and CDFs (placeholders where the scene has none)
//! and the lighting uniform, group 0's bindings 20 to 23, and the
//! overrides that compile their lookups out of a scene without them.

use wgpu::util::DeviceExt;

use crate::error::Result;
use crate::layout::Emitter;
use crate::scene::Scene;

use super::device::{Gpu, non_empty};

/// Bindings 20 to 23 (`Scene::emitters`, `Scene::environment`).
pub(super) struct LightingBuffers {
    emitters: wgpu::Buffer,
    environment: wgpu::Buffer,
    environment_cdf: wgpu::Buffer,
    lighting: wgpu::Buffer,
}

impl LightingBuffers {
    pub fn upload(gpu: &Gpu, scene: &Scene) -> Result<LightingBuffers> {
        let limit = gpu.binding_limit();
        let table = scene.emitters();
        let map = scene.environment().and_then(|e| e.map.as_ref());
        let (pixels, cdf): (&[[f32; 4]], &[f32]) = map.map_or((&[], &[]), |m| (&m.pixels, &m.cdf));
        Ok(LightingBuffers {
            emitters: gpu.storage_buffer(
                "emitters",
                &non_empty::<Emitter>(&table.entries),
                limit,
            )?,
            environment: gpu.storage_buffer("environment", &non_empty(pixels), limit)?,
            environment_cdf: gpu.storage_buffer("environment CDF", &non_empty(cdf), limit)?,
            lighting: gpu
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("lighting"),
                    contents: bytemuck::bytes_of(&table.uniform),
                    usage: wgpu::BufferUsages::UNIFORM,
                }),
        })
    }

    /// Their bytes on the device.
    pub fn device_bytes(&self) -> u64 {
        [
            &self.emitters,
            &self.environment,
            &self.environment_cdf,
            &self.lighting,
        ]
        .iter()
        .map(|b| b.size())
        .sum()
    }

    /// Their entries of the scene's bind group, by the shader's names.
    pub fn entries(&self) -> [(&'static str, wgpu::BindingResource<'_>); 4] {
        [
            ("emitters", self.emitters.as_entire_binding()),
            ("environment", self.environment.as_entire_binding()),
            ("environment_cdf", self.environment_cdf.as_entire_binding()),
            ("lighting", self.lighting.as_entire_binding()),
        ]
    }
}

/// The overrides of `scene`'s lights: HAS_ENVIRONMENT, HAS_EMITTERS.
pub fn lighting_specialisation(scene: &Scene) -> [(&'static str, f64); 2] {
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    [
        ("HAS_ENVIRONMENT", flag(scene.environment().is_some())),
        ("HAS_EMITTERS", flag(!scene.emitters().entries.is_empty())),
    ]
}
