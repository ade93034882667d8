//! The scene's upload as the passes see it: `Resident` (the bind groups
//! over the scene's buffers, the uniform and its scene part, the shader's
//! loop flag), the uniform of a view, and `Host`, what a pass reads of the
//! renderer's parts.

use glam::DVec3;
use wgpu::util::DeviceExt;

use crate::camera::View;
use crate::camera::f32::CameraBasis;
use crate::camera::strata_columns;
use crate::error::Result;
use crate::layout::Params;
use crate::scene::Scene;

use super::bindings::{ACCELERATION, IMAGE_TILE, SCENE};
use super::device::Gpu;
use super::pipelines::{Layouts, Pipelines};
use super::readback::{LoopStatus, TileTargets};
use super::upload::SceneBuffers;

/// The bind groups every pass binds (the scene's buffers live on in
/// them), the uniform, the scene's part of it and the shader's loop flag.
pub(super) struct Resident {
    scene_group: wgpu::BindGroup,
    /// Group 2 under `--accel hardware`: the acceleration structures.
    acceleration_group: Option<wgpu::BindGroup>,
    image_group: wgpu::BindGroup,
    params_buffer: wgpu::Buffer,
    /// The uniform's scene part (its counts, background, ambient); the
    /// view's part zero, each render call's to fill.
    scene_params: Params,
    loop_status: LoopStatus,
}

impl Resident {
    /// The uniform (the scene's part), the loop flag, and the bind groups
    /// over `buffers` and `tile` (in the caller's error scope).
    pub fn new(
        device: &wgpu::Device,
        scene: &Scene,
        layouts: &Layouts,
        buffers: &SceneBuffers,
        tile: &TileTargets,
        acceleration_group: Option<wgpu::BindGroup>,
    ) -> Resident {
        let params = scene_params(scene);
        let params_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let loop_status = LoopStatus::new(device);
        let scene_group = scene_bind_group(
            device,
            layouts,
            buffers,
            &params_buffer,
            &loop_status.texture,
        );
        let image_group = IMAGE_TILE.bind_group(
            device,
            IMAGE_TILE.label,
            &layouts.image,
            vec![
                ("out_prim", tile.prim.as_entire_binding()),
                ("tile_sums", tile.sums.as_entire_binding()),
            ],
        );
        Resident {
            scene_group,
            acceleration_group,
            image_group,
            params_buffer,
            scene_params: params,
            loop_status,
        }
    }

    /// Binds the scene's groups in `pass`: group 0, and under `--accel
    /// hardware` group 2 (the acceleration structures).
    pub fn bind_scene(&self, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_bind_group(SCENE.group, &self.scene_group, &[]);
        if let Some(group) = &self.acceleration_group {
            pass.set_bind_group(ACCELERATION.group, group, &[]);
        }
    }

    /// The megakernel's group 1: the tile's buffers.
    pub fn image_group(&self) -> &wgpu::BindGroup {
        &self.image_group
    }

    /// Whether any invocation since the last call found its loops cut
    /// short (the shader's `report_cut_loops`); clears the flag.
    pub async fn loops_were_cut(&self, gpu: &Gpu) -> Result<bool> {
        self.loop_status.were_cut(gpu).await
    }

    /// The uniform of a render of `view` (camera, size, spp, seed): the
    /// scene's part as uploaded, the view's from `view` (the geometry
    /// relative to `offset`).
    pub fn uniform(&self, offset: DVec3, view: &View) -> Params {
        with_view(self.scene_params, offset, view)
    }

    /// Uploads the uniform `params` with `samples` (of its spp) as the
    /// next dispatch's: a pixel list's samples, a dispatch at a time.
    pub fn write_samples(&self, gpu: &Gpu, params: &Params, samples: std::ops::Range<u32>) {
        let params = Params {
            sample_begin: samples.start,
            sample_end: samples.end,
            ..*params
        };
        self.write_uniform(gpu, &params);
    }

    /// Uploads `params` as the uniform of the next dispatch.
    pub fn write_uniform(&self, gpu: &Gpu, params: &Params) {
        gpu.queue
            .write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(params));
    }

    /// The uniform's scene part alone: all the queries read.
    pub fn scene_params(&self) -> &Params {
        &self.scene_params
    }

    /// Shadows on or off in the uniform's scene part (each call's uniform
    /// starts from it).
    pub fn set_shadows(&mut self, on: bool) {
        self.scene_params.shadows = on as u32;
    }

    /// A path's most surfaces in the uniform's scene part.
    pub fn set_max_depth(&mut self, max_depth: u32) {
        self.scene_params.max_depth = max_depth;
    }
}

/// The uniform's part that `scene` sets.
fn scene_params(scene: &Scene) -> Params {
    Params {
        background: scene.background,
        num_triangles: scene.triangles.len() as u32,
        ambient: scene.ambient,
        num_spheres: scene.spheres.len() as u32,
        num_lights: scene.lights.len() as u32,
        shadows: scene.shadows as u32,
        canary_loops: 2,
        max_depth: scene.max_depth,
        ..bytemuck::Zeroable::zeroed()
    }
}

/// `params` seen from `view` (the geometry relative to `offset`): the f32
/// reference's basis, so both paths shoot the very same rays.
fn with_view(params: Params, offset: DVec3, view: &View) -> Params {
    let basis = CameraBasis::new(&view.camera.relative_to(offset));
    Params {
        eye: basis.eye.to_array(),
        width: basis.width,
        right: basis.right.to_array(),
        height: basis.height,
        up: basis.up.to_array(),
        tan_half_x: basis.tan_half_x,
        forward: basis.forward.to_array(),
        tan_half_y: basis.tan_half_y,
        tile_origin: [0, 0],
        spp: view.spp,
        seed: view.seed,
        strata_x: strata_columns(view.spp),
        sample_begin: 0,
        sample_end: view.spp,
        cone_spread: crate::texture::cone_spread(basis.tan_half_y, basis.height, view.spp),
        ..params
    }
}

/// What a pass reads of the renderer's other parts: the device context,
/// the shader module, the scene's upload (bind group, uniform, loop flag).
#[derive(Clone, Copy)]
pub(super) struct Host<'a> {
    gpu: &'a Gpu,
    pipelines: &'a Pipelines,
    resident: &'a Resident,
}

impl<'a> Host<'a> {
    pub fn new(gpu: &'a Gpu, pipelines: &'a Pipelines, resident: &'a Resident) -> Host<'a> {
        Host {
            gpu,
            pipelines,
            resident,
        }
    }

    pub fn gpu(&self) -> &Gpu {
        self.gpu
    }

    /// Binds the scene's groups in `pass` (`Resident::bind_scene`).
    pub fn bind_scene(&self, pass: &mut wgpu::ComputePass<'_>) {
        self.resident.bind_scene(pass)
    }

    /// The uniform's scene part alone: all the queries read.
    pub fn scene_params(&self) -> &Params {
        self.resident.scene_params()
    }

    /// The megakernel's group 1: the tile's buffers.
    pub fn image_group(&self) -> &wgpu::BindGroup {
        self.resident.image_group()
    }

    /// Uploads `params` as the uniform of the next dispatch.
    pub fn write_uniform(&self, params: &Params) {
        self.resident.write_uniform(self.gpu, params)
    }

    /// Uploads the uniform `params` with `samples` (of its spp) as the
    /// next dispatch's.
    pub fn write_samples(&self, params: &Params, samples: std::ops::Range<u32>) {
        self.resident.write_samples(self.gpu, params, samples)
    }

    /// The shader's bind group layouts.
    pub fn layouts(&self) -> &Layouts {
        &self.pipelines.layouts
    }

    /// The overrides specialising the shader to the resident scene.
    pub fn constants(&self) -> &[(&'static str, f64)] {
        &self.pipelines.constants
    }

    /// Builds `entry` with the scene's group and `layout`, specialised to
    /// the resident scene.
    pub async fn build(
        &self,
        entry: &str,
        layout: &wgpu::BindGroupLayout,
    ) -> Result<wgpu::ComputePipeline> {
        self.build_with(entry, layout, self.constants()).await
    }

    /// `build` with other overrides.
    pub async fn build_with(
        &self,
        entry: &str,
        layout: &wgpu::BindGroupLayout,
        constants: &[(&str, f64)],
    ) -> Result<wgpu::ComputePipeline> {
        self.pipelines
            .build(self.gpu, entry, layout, constants)
            .await
    }

    /// Whether any invocation since the last call found its loops cut
    /// short; clears the flag.
    pub async fn loops_were_cut(&self) -> Result<bool> {
        self.resident.loops_were_cut(self.gpu).await
    }
}

/// Group 0: the uniform, the scene's words (low and high ranges) and
/// where its arrays start, the loop flag, the BVH's texels and the
/// lighting uniform.
fn scene_bind_group(
    device: &wgpu::Device,
    layouts: &Layouts,
    buffers: &SceneBuffers,
    params_buffer: &wgpu::Buffer,
    loop_status: &wgpu::Texture,
) -> wgpu::BindGroup {
    let view = |texture: &wgpu::Texture| texture.create_view(&Default::default());
    let [node_view, block_view, triangle_view, status_view] = [
        &buffers.node_texture,
        &buffers.block_texture,
        &buffers.triangle_texture,
        loop_status,
    ]
    .map(view);
    let entries = vec![
        ("params", params_buffer.as_entire_binding()),
        ("scene_words", buffers.words.low_binding()),
        ("arrays", buffers.arrays.as_entire_binding()),
        ("scene_words_hi", buffers.words.high_binding()),
        (
            "loop_status",
            wgpu::BindingResource::TextureView(&status_view),
        ),
        (
            "bvh_node_texels",
            wgpu::BindingResource::TextureView(&node_view),
        ),
        (
            "bvh_block_texels",
            wgpu::BindingResource::TextureView(&block_view),
        ),
        (
            "triangle_texels",
            wgpu::BindingResource::TextureView(&triangle_view),
        ),
        ("lighting", buffers.lighting.as_entire_binding()),
    ];
    SCENE.bind_group(device, SCENE.label, &layouts.scene, entries)
}
