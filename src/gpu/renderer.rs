//! `GpuRenderer`: a scene resident on the device, and the steps that put
//! it there.

use std::time::{Duration, Instant};

use glam::DVec3;
use wgpu::util::DeviceExt;

use crate::camera::f32::CameraBasis;
use crate::camera::{View, strata_columns};
use crate::error::{Error, Result};
use crate::layout::Params;
use crate::scene::Scene;

use super::adapter::is_llvmpipe;
use super::bindings::{IMAGE_TILE, SCENE};
use super::device::Gpu;
use super::pipelines::{Layouts, Pipelines, resident_constants};
use super::query::ListState;
use super::readback::{LoopStatus, TileTargets};
use super::render::{LLVMPIPE_SAMPLES_PER_DISPATCH, ShadowDispatch};
use super::shader::{SHADER_SOURCE, specialisation};
use super::timer::Timer;
use super::upload::{BvhStorage, SceneBuffers};

/// A scene resident on the device: buffers and pipeline are built once;
/// a new view only rewrites the uniform. It keeps all it renders with (the
/// scene's uniform, its placement), so the host's scene may go once it is
/// built; it starts at the scene's default view (`Scene::view`).
pub struct GpuRenderer {
    pub(super) gpu: Gpu,
    pub(super) pipelines: Pipelines,
    pub(super) resident: Resident,
    pub(super) tile: TileTargets,
    /// The uniform as the next dispatch writes it.
    pub(super) params: Params,
    /// Samples one dispatch adds to a pixel: few enough that no invocation
    /// trips llvmpipe's loop limit (`loops_completed` in the shader);
    /// halved whenever one still does.
    pub(super) samples_per_dispatch: u32,
    pub(super) timer: Option<Timer>,
    pub(super) lists: ListState,
    pub(super) proximity: super::proximity::ProximityState,
    /// How a render traces its shadow rays (the tests set either).
    pub shadow_dispatch: ShadowDispatch,
    /// Bytes of the scene's buffers on the device.
    pub device_bytes: u64,
    /// The arrays split over two bindings.
    pub split_arrays: Vec<&'static str>,
    /// Where the shader reads the BVH from.
    pub bvh_storage: BvhStorage,
    pub upload_time: Duration,
    /// The resident scene's placement: `trace_rays` takes world rays.
    pub placement: crate::placement::Placement,
}

/// The bind groups every pass binds (the scene's buffers live on in
/// them), the uniform and the shader's loop flag.
pub(super) struct Resident {
    pub scene_group: wgpu::BindGroup,
    pub image_group: wgpu::BindGroup,
    pub params_buffer: wgpu::Buffer,
    pub loop_status: LoopStatus,
}

/// The uniform for `scene` seen from `view`.
fn params_for(scene: &Scene, view: &View) -> Params {
    let scene_params = Params {
        background: scene.background,
        num_triangles: scene.triangles.len() as u32,
        ambient: scene.ambient,
        num_spheres: scene.spheres.len() as u32,
        num_lights: scene.lights.len() as u32,
        shadows: scene.shadows as u32,
        canary_loops: 2,
        ..bytemuck::Zeroable::zeroed()
    };
    with_view(scene_params, scene.offset, view)
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

impl GpuRenderer {
    /// Uploads `scene` with a shader specialised to it.
    pub fn new(gpu: Gpu, scene: &Scene) -> Result<GpuRenderer> {
        let storage = BvhStorage::for_scene(&gpu, scene);
        GpuRenderer::build(gpu, scene, specialisation(scene), storage)
    }

    /// `new` with the BVH in the given storage rather than the adapter's
    /// (the tests check both on one adapter).
    pub fn with_bvh_storage(gpu: Gpu, scene: &Scene, storage: BvhStorage) -> Result<GpuRenderer> {
        GpuRenderer::build(gpu, scene, specialisation(scene), storage)
    }

    /// Uploads `scene` with the full shader: every feature compiled in, only
    /// the acceleration and the intersection test chosen. The benchmarks
    /// measure what specialisation saves against it.
    pub fn with_full_shader(gpu: Gpu, scene: &Scene) -> Result<GpuRenderer> {
        let constants = specialisation(scene)
            .into_iter()
            .filter(|(name, _)| matches!(*name, "USE_BVH" | "INTERSECT"))
            .collect();
        let storage = BvhStorage::for_scene(&gpu, scene);
        GpuRenderer::build(gpu, scene, constants, storage)
    }

    fn build(
        gpu: Gpu,
        scene: &Scene,
        constants: Vec<(&'static str, f64)>,
        storage: BvhStorage,
    ) -> Result<GpuRenderer> {
        let start = Instant::now();
        let device = &gpu.device;
        let params = params_for(scene, &scene.view);
        let params_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let buffers = SceneBuffers::upload(&gpu, scene, storage)?;
        let constants = resident_constants(constants, &buffers, storage, scene, &gpu);
        let tile = TileTargets::new(device);
        let loop_status = LoopStatus::new(device);
        let layouts = Layouts::new(device);

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let scene_group = scene_bind_group(
            device,
            &layouts,
            &buffers,
            [&params_buffer, &loop_status.buffer],
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
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lambert shader"),
            source: wgpu::ShaderSource::Wgsl(SHADER_SOURCE.into()),
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!("uploading the scene: {e}")));
        }
        gpu.wait()?;
        let timer = Timer::new(&gpu);
        let shadow_dispatch = ShadowDispatch::for_scene(
            scene,
            gpu.options.shadow_dispatch.as_deref(),
            gpu.limits.max_storage_buffer_binding_size as u64,
        )?;
        let samples_per_dispatch = if is_llvmpipe(&gpu.info) {
            LLVMPIPE_SAMPLES_PER_DISPATCH
        } else {
            u32::MAX
        };
        Ok(GpuRenderer {
            gpu,
            pipelines: Pipelines::new(module, constants, layouts),
            resident: Resident {
                scene_group,
                image_group,
                params_buffer,
                loop_status,
            },
            tile,
            params,
            samples_per_dispatch,
            timer,
            lists: ListState::default(),
            proximity: Default::default(),
            shadow_dispatch,
            device_bytes: buffers.device_bytes,
            split_arrays: buffers.split_arrays(),
            bvh_storage: storage,
            upload_time: start.elapsed(),
            placement: scene.placement(),
        })
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// Sets the view (camera, size, spp, seed) the resident scene is
    /// rendered from; uploads nothing else (the scene's own part of the
    /// uniform stays the one uploaded).
    pub fn set_view(&mut self, view: &View) {
        self.params = with_view(self.params, self.placement.offset, view);
    }

    /// Turns shadows on or off (the viewer's key): the uniform's flag,
    /// the HAS_SHADOWS override (where the shader is specialised) and the
    /// shadow dispatch, the pipelines built on them rebuilt on next use.
    /// The scene's buffers stay: the same image as a renderer opened on
    /// the scene with that setting.
    pub fn set_shadows(&mut self, on: bool) -> Result<()> {
        if self.params.shadows == on as u32 {
            return Ok(());
        }
        let lights = self.params.num_lights;
        self.shadow_dispatch = ShadowDispatch::for_lights(
            on,
            lights,
            self.gpu.options.shadow_dispatch.as_deref(),
            self.gpu.limits.max_storage_buffer_binding_size,
        )?;
        self.params.shadows = on as u32;
        let p = &mut self.pipelines;
        if let Some((_, flag)) = p.constants.iter_mut().find(|(n, _)| *n == "HAS_SHADOWS") {
            *flag = (on && lights > 0) as u32 as f64;
        }
        p.render = None;
        p.split = None;
        p.pixel_list = None;
        p.trace = Default::default();
        Ok(())
    }
}

/// Group 0: the uniform, the scene's arrays (low and high ranges), the
/// loop flag and the BVH's texels.
fn scene_bind_group(
    device: &wgpu::Device,
    layouts: &Layouts,
    buffers: &SceneBuffers,
    [params_buffer, loop_status]: [&wgpu::Buffer; 2],
) -> wgpu::BindGroup {
    let node_view = buffers.node_texture.create_view(&Default::default());
    let block_view = buffers.block_texture.create_view(&Default::default());
    let triangle_view = buffers.triangle_texture.create_view(&Default::default());
    SCENE.bind_group(
        device,
        SCENE.label,
        &layouts.scene,
        vec![
            ("params", params_buffer.as_entire_binding()),
            ("triangles", buffers.triangles.low_binding()),
            ("triangle_normals", buffers.normals.low_binding()),
            ("spheres", buffers.spheres.as_entire_binding()),
            ("materials", buffers.materials.as_entire_binding()),
            ("lights", buffers.lights.as_entire_binding()),
            ("bvh_nodes", buffers.nodes.low_binding()),
            ("bvh_blocks", buffers.blocks.low_binding()),
            ("triangles_hi", buffers.triangles.high_binding()),
            ("triangle_normals_hi", buffers.normals.high_binding()),
            ("bvh_nodes_hi", buffers.nodes.high_binding()),
            ("bvh_blocks_hi", buffers.blocks.high_binding()),
            ("loop_status", loop_status.as_entire_binding()),
            ("triangle_attributes", buffers.attributes.low_binding()),
            ("triangle_attributes_hi", buffers.attributes.high_binding()),
            ("textures", buffers.textures.as_entire_binding()),
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
        ],
    )
}
