//! The shader module, its bind group layouts, and how a pass builds its
//! compute pipelines from them (each pass keeps its own, built on its first
//! use: a ray query never compiles the render entry point, nor a render the
//! query's).

use crate::error::{Error, Result};
use crate::scene::Scene;

use super::RENDER_WORKGROUP;
use super::bindings::{BindingTable, IMAGE_TILE, LIGHT_PROBE, PIXEL_LIST, RAYS, SCENE};
use super::device::Gpu;
use super::upload::{BvhStorage, SceneBuffers};

/// The bind group layouts every renderer builds, one per binding table
/// (the wavefront builds its own with its passes).
pub(super) struct Layouts {
    pub scene: wgpu::BindGroupLayout,
    pub image: wgpu::BindGroupLayout,
    pub rays: ListLayout,
    pub pixels: ListLayout,
    pub light_probe: ListLayout,
}

/// The layout of a list pass's group, with the table `run_list` binds its
/// input and output by.
pub(super) struct ListLayout {
    pub table: &'static BindingTable,
    pub layout: wgpu::BindGroupLayout,
}

impl Layouts {
    pub fn new(device: &wgpu::Device) -> Layouts {
        Layouts {
            scene: SCENE.layout(device),
            image: IMAGE_TILE.layout(device),
            rays: ListLayout {
                table: &RAYS,
                layout: RAYS.layout(device),
            },
            pixels: ListLayout {
                table: &PIXEL_LIST,
                layout: PIXEL_LIST.layout(device),
            },
            light_probe: ListLayout {
                table: &LIGHT_PROBE,
                layout: LIGHT_PROBE.layout(device),
            },
        }
    }
}

/// The shader module, the overrides specialising it to the resident scene,
/// and its layouts: what every pass builds its pipelines from (each pass
/// keeps its own).
pub(super) struct Pipelines {
    pub module: wgpu::ShaderModule,
    pub constants: Vec<(&'static str, f64)>,
    pub layouts: Layouts,
    /// Group 2 of the ray-query module's pipelines (`--accel hardware`),
    /// which every pass binds then (`Host::bind_scene`).
    pub acceleration: Option<wgpu::BindGroupLayout>,
}

impl Pipelines {
    pub fn new(
        module: wgpu::ShaderModule,
        constants: Vec<(&'static str, f64)>,
        layouts: Layouts,
        acceleration: Option<wgpu::BindGroupLayout>,
    ) -> Pipelines {
        Pipelines {
            module,
            constants,
            layouts,
            acceleration,
        }
    }

    /// `entry_point` with the scene at group 0, `output_layout` at 1, and
    /// in the ray-query module the acceleration structures at 2.
    pub async fn build(
        &self,
        gpu: &Gpu,
        entry_point: &str,
        output_layout: &wgpu::BindGroupLayout,
        constants: &[(&str, f64)],
    ) -> Result<wgpu::ComputePipeline> {
        let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut layouts = vec![&self.layouts.scene, output_layout];
        layouts.extend(&self.acceleration);
        let pipeline =
            compute_pipeline(&gpu.device, &self.module, entry_point, &layouts, constants);
        if let Some(e) = scope.pop().await {
            return Err(Error::Gpu(format!(
                "building the {entry_point} pipeline: {e}"
            )));
        }
        gpu.wait().await?;
        Ok(pipeline)
    }
}

/// `specialisation`'s overrides (or some of them) and those the upload
/// decides: where the scene's words are split, where the BVH is read from, the
/// workgroup's shape and the traversal stack's size.
pub(super) fn resident_constants(
    mut constants: Vec<(&'static str, f64)>,
    buffers: &SceneBuffers,
    storage: BvhStorage,
    scene: &Scene,
    gpu: &Gpu,
) -> Vec<(&'static str, f64)> {
    constants.push(("WORDS_PER_BINDING", buffers.words.per_binding as f64));
    constants.push(("BVH_TEXELS", (storage == BvhStorage::Texels) as u32 as f64));
    constants.push(("RENDER_WORKGROUP_X", RENDER_WORKGROUP[0] as f64));
    constants.push(("RENDER_WORKGROUP_Y", RENDER_WORKGROUP[1] as f64));
    constants.push(("TILE", super::TILE as f64));
    let (stack_entries, spills) = crate::cwbvh::short_stack(
        scene.bvh.depth(),
        gpu.limits.max_compute_workgroup_storage_size,
    );
    constants.push(("STACK_ENTRIES", stack_entries as f64));
    constants.push(("STACK_SPILLS", spills as u32 as f64));
    constants.push(("CPU_THREADS", gpu.cpu_threads() as f64));
    constants
}

pub(super) fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry_point: &str,
    layouts: &[&wgpu::BindGroupLayout],
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().copied().map(Some).collect();
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry_point),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry_point),
        layout: Some(&pipeline_layout),
        module,
        entry_point: Some(entry_point),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            zero_initialize_workgroup_memory: false,
        },
        cache: None,
    })
}
