//! `--accel hardware` (docs/hardware-rays.md): the scene in the GPU's
//! ray-tracing units, through wgpu's experimental ray queries. With
//! `features` (what the device is opened with), the one module of the GPU
//! layer that names that API: whether a device can trace with it
//! (`unsupported`), and the scene's acceleration structures
//! (`Acceleration`: BLASes, the TLAS over them, and the bind group the
//! ray-query module reads them through, `ACCELERATION`), built once when a
//! renderer is opened and kept by it. How primitives go into them: `plan`.

mod plan;

use std::time::Duration;

use web_time::Instant;

use wgpu::util::DeviceExt;

use crate::error::{Error, Result};
use crate::layout::{FLAG_MASKED, Sphere, Triangle};
use crate::scene::Scene;

use super::bindings::{ACCELERATION, unmet_hardware_limits};
use super::device::Gpu;
use super::features::RAY_QUERY;
use super::options::RAY_QUERY_GEOMETRY_ENV;
use plan::{BlasPlan, Kind, Limits, Plan, Run};

/// Whether `adapter` offers ray queries (a device opened on it for
/// `--accel hardware` has them).
pub fn offers_ray_queries(adapter: &wgpu::Adapter) -> bool {
    adapter.features().contains(RAY_QUERY)
}

/// Why `gpu` cannot trace with ray queries, if it cannot: the device has
/// no ray queries (it was opened without them, or its adapter has none),
/// or too few bindings for the ray-query module.
fn unsupported(gpu: &Gpu) -> Option<String> {
    if !gpu.device.features().contains(RAY_QUERY) {
        return Some(format!(
            "{} has no ray queries (wgpu's EXPERIMENTAL_RAY_QUERY: Vulkan's VK_KHR_ray_query, \
             which Mesa's lavapipe has from Mesa 24.1)",
            gpu.describe()
        ));
    }
    unmet_hardware_limits(&gpu.limits)
        .map(|why| format!("{} cannot run the ray-query kernel: {why}", gpu.describe()))
}

/// How the driver gets the scene's triangles (`LAMBERT_RAY_QUERY_GEOMETRY`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TriangleGeometry {
    /// Triangles, tested in the hardware (opaque ones never reach the
    /// shader): the fast path of RT units.
    Triangles,
    /// Each triangle's box, padded (`box_pad`), the triangle tested in the
    /// shader by the compute path's own test: the hardware only traverses.
    /// For drivers whose own tests leak: lavapipe's slab test is not
    /// conservative, so rays aimed at a shared vertex or edge escape
    /// between triangles (docs/hardware-rays.md, "Bugs met").
    Boxes,
}

impl TriangleGeometry {
    /// Its value of the variable.
    pub fn name(self) -> &'static str {
        match self {
            TriangleGeometry::Triangles => "triangles",
            TriangleGeometry::Boxes => "boxes",
        }
    }

    /// The variable's choice, else boxes on llvmpipe (lavapipe) and
    /// triangles on every other driver.
    pub fn for_gpu(gpu: &Gpu) -> Result<TriangleGeometry> {
        let all = [TriangleGeometry::Triangles, TriangleGeometry::Boxes];
        match gpu.options.ray_query_geometry.as_deref().map(str::trim) {
            Some(value) => all.into_iter().find(|g| g.name() == value).ok_or_else(|| {
                Error::Usage(format!(
                    "{RAY_QUERY_GEOMETRY_ENV}={value}: expected triangles or boxes"
                ))
            }),
            None if gpu.is_llvmpipe() => Ok(TriangleGeometry::Boxes),
            None => Ok(TriangleGeometry::Triangles),
        }
    }
}

/// Bytes of a triangle as the BLAS reads it: the scene's `Triangle`, whose
/// vertices lie 16 bytes apart (each a vec3 and a word the BLAS skips).
const VERTEX_STRIDE: u64 = 16;
const _: () = assert!(size_of::<Triangle>() as u64 == 3 * VERTEX_STRIDE);

/// Bytes of a box: min and max corners, three f32 each.
const BOX_STRIDE: u64 = wgpu::AABB_GEOMETRY_MIN_STRIDE;

/// What was built, for reports and the docs' figures.
#[derive(Clone, Copy, Debug)]
pub struct AccelerationStats {
    pub triangles: TriangleGeometry,
    pub blases: usize,
    /// Geometries over all BLASes (runs of one opacity, and sphere boxes).
    pub geometries: usize,
    /// Wall time of the build (uploads, BLASes, TLAS, waiting for them).
    pub build_time: Duration,
}

impl AccelerationStats {
    /// Whether crossing counts and lists go through ray queries: where the
    /// triangles are boxes, each tested by the shader's crossing test, which
    /// counts an edge once by lambert's rule (shaders/hardware_trace.wgsl,
    /// `every_hit`). The hardware's own triangles reach the shader only
    /// where its test hits them, which on an edge need not be the triangle
    /// the rule counts, so there they walk the compute BVH.
    pub fn serves_crossings(&self) -> bool {
        self.triangles == TriangleGeometry::Boxes
    }
}

/// The scene's acceleration structures and the bind group over them (the
/// BLASes live on through the TLAS's instances, the TLAS and the runs'
/// table through the group).
pub(super) struct Acceleration {
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
    pub stats: AccelerationStats,
}

impl Acceleration {
    /// `scene`'s structures on `gpu`, or, where the device has no ray
    /// queries or the scene exceeds their limits, none and the note of why
    /// its rays go through the compute BVH instead (never a wrong answer:
    /// the BVH is the CPU path's twin). Fails only where the device does.
    pub async fn for_scene(
        gpu: &Gpu,
        scene: &Scene,
    ) -> Result<(Option<Acceleration>, Option<String>)> {
        let note = |why: String| {
            Some(format!(
                "--accel hardware: {why}\nnote: tracing through the compute BVH instead"
            ))
        };
        if let Some(why) = unsupported(gpu) {
            return Ok((None, note(why)));
        }
        let triangles = TriangleGeometry::for_gpu(gpu)?;
        match plan_for(gpu, scene, triangles) {
            Ok(plan) => Ok((
                Some(Acceleration::build(gpu, scene, &plan, triangles).await?),
                None,
            )),
            Err(why) => Ok((None, note(why))),
        }
    }

    /// Builds the planned structures on `gpu` (which `unsupported` passed).
    async fn build(
        gpu: &Gpu,
        scene: &Scene,
        plan: &Plan,
        triangles: TriangleGeometry,
    ) -> Result<Acceleration> {
        let start = Instant::now();
        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pad = box_pad(scene);
        let blases: Vec<wgpu::Blas> = plan
            .blases
            .iter()
            .map(|blas| build_blas(gpu, scene, blas, pad))
            .collect();
        let mut tlas = device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("scene TLAS"),
            max_instances: blases.len().max(1) as u32,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        // Identity transforms: the BLASes hold the scene's local frame.
        const IDENTITY: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        for (i, (blas, planned)) in blases.iter().zip(&plan.blases).enumerate() {
            tlas[i] = Some(wgpu::TlasInstance::new(
                blas,
                IDENTITY,
                planned.first_run,
                0xff,
            ));
        }
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.build_acceleration_structures([], [&tlas]);
        gpu.queue.submit([encoder.finish()]);
        let runs = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hardware_runs"),
            contents: bytemuck::cast_slice(&with_one(&plan.run_bases)),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let layout = ACCELERATION.layout(device);
        let group = ACCELERATION.bind_group(
            device,
            ACCELERATION.label,
            &layout,
            vec![
                (
                    "scene_tlas",
                    wgpu::BindingResource::AccelerationStructure(&tlas),
                ),
                ("hardware_runs", runs.as_entire_binding()),
            ],
        );
        if let Some(e) = scope.pop().await {
            return Err(Error::Gpu(format!(
                "building the acceleration structures: {e}"
            )));
        }
        gpu.wait().await?;
        Ok(Acceleration {
            layout,
            group,
            stats: AccelerationStats {
                triangles,
                blases: plan.blases.len(),
                geometries: plan.blases.iter().map(|b| b.runs.len()).sum(),
                build_time: start.elapsed(),
            },
        })
    }

    /// The ray-query module's override: whether the triangles are boxes
    /// (then every committed hit is one the shader generated).
    pub fn constant(&self) -> (&'static str, f64) {
        let boxes = self.stats.triangles == TriangleGeometry::Boxes;
        ("HARDWARE_TRIANGLE_BOXES", boxes as u32 as f64)
    }

    /// The layout of group 2 of every pipeline of the ray-query module.
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// Group 2: the TLAS and the runs' table.
    pub fn group(&self) -> &wgpu::BindGroup {
        &self.group
    }
}

/// `plan` for `scene` within `gpu`'s limits: a BLAS's triangles (or
/// boxes) also within one buffer, which the build reads them from.
fn plan_for(
    gpu: &Gpu,
    scene: &Scene,
    triangles: TriangleGeometry,
) -> std::result::Result<Plan, String> {
    let masks = scene.has_alpha_mask();
    let masked: Vec<bool> = scene
        .triangles
        .iter()
        .map(|t| masks && t.flags & FLAG_MASKED != 0)
        .collect();
    let per_buffer = gpu.limits.max_buffer_size / size_of::<Triangle>() as u64;
    let limits = Limits {
        blas_primitives: (gpu.limits.max_blas_primitive_count as u64).min(per_buffer) as u32,
        blas_geometries: gpu.limits.max_blas_geometry_count,
        instances: gpu.limits.max_tlas_instance_count,
    };
    let boxes = triangles == TriangleGeometry::Boxes;
    plan::plan(&masked, boxes, scene.spheres.len() as u32, limits).map_err(|why| {
        format!(
            "the scene does not fit {}'s ray queries: {why}",
            gpu.describe()
        )
    })
}

/// `values`, or one zero where there are none (a binding is never empty).
fn with_one(values: &[u32]) -> Vec<u32> {
    if values.is_empty() {
        vec![0]
    } else {
        values.to_vec()
    }
}

/// Builds one planned BLAS in a submission of its own, so that its input
/// (a copy of its triangles, or its primitives' boxes, padded by `pad`)
/// goes once it is built.
fn build_blas(gpu: &Gpu, scene: &Scene, planned: &BlasPlan, pad: f32) -> wgpu::Blas {
    let device = &gpu.device;
    let first = planned.runs[0].first;
    let end = planned.runs.last().map_or(first, |r| r.first + r.count);
    let flags = |run: &Run| match run.opaque {
        true => wgpu::AccelerationStructureGeometryFlags::OPAQUE,
        false => wgpu::AccelerationStructureGeometryFlags::empty(),
    };
    let create = |sizes| {
        device.create_blas(
            &wgpu::CreateBlasDescriptor {
                label: Some("scene BLAS"),
                flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                update_mode: wgpu::AccelerationStructureUpdateMode::Build,
            },
            sizes,
        )
    };
    let input = |contents: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("BLAS input"),
            contents,
            usage: wgpu::BufferUsages::BLAS_INPUT,
        })
    };
    let mut encoder = device.create_command_encoder(&Default::default());
    let (first_id, end_id) = (first as usize, end as usize);
    let blas = if planned.kind == Kind::Triangles {
        let sizes: Vec<_> = planned
            .runs
            .iter()
            .map(|run| wgpu::BlasTriangleGeometrySizeDescriptor {
                vertex_format: wgpu::VertexFormat::Float32x3,
                vertex_count: 3 * run.count,
                index_format: None,
                index_count: None,
                flags: flags(run),
            })
            .collect();
        let blas = create(wgpu::BlasGeometrySizeDescriptors::Triangles {
            descriptors: sizes.clone(),
        });
        let vertices = input(bytemuck::cast_slice(&scene.triangles[first_id..end_id]));
        let geometries = planned
            .runs
            .iter()
            .zip(&sizes)
            .map(|(run, size)| wgpu::BlasTriangleGeometry {
                size,
                vertex_buffer: &vertices,
                first_vertex: 3 * (run.first - first),
                vertex_stride: VERTEX_STRIDE,
                index_buffer: None,
                first_index: None,
                transform_buffer: None,
                transform_buffer_offset: None,
            })
            .collect();
        let entry = wgpu::BlasBuildEntry {
            blas: &blas,
            geometry: wgpu::BlasGeometries::TriangleGeometries(geometries),
        };
        encoder.build_acceleration_structures([&entry], []);
        blas
    } else {
        let sizes: Vec<_> = planned
            .runs
            .iter()
            .map(|run| wgpu::BlasAABBGeometrySizeDescriptor {
                primitive_count: run.count,
                flags: flags(run),
            })
            .collect();
        let blas = create(wgpu::BlasGeometrySizeDescriptors::AABBs {
            descriptors: sizes.clone(),
        });
        let boxes: Vec<[f32; 6]> = if planned.kind == Kind::Spheres {
            let base = scene.triangles.len();
            let spheres = &scene.spheres[first_id - base..end_id - base];
            spheres.iter().map(|s| sphere_box(s, pad)).collect()
        } else {
            let triangles = &scene.triangles[first_id..end_id];
            triangles.iter().map(|t| triangle_box(t, pad)).collect()
        };
        let boxes = input(bytemuck::cast_slice(&boxes));
        let geometries = planned
            .runs
            .iter()
            .zip(&sizes)
            .map(|(run, size)| wgpu::BlasAabbGeometry {
                size,
                stride: BOX_STRIDE,
                aabb_buffer: &boxes,
                primitive_offset: ((run.first - first) as u64 * BOX_STRIDE) as u32,
            })
            .collect();
        let entry = wgpu::BlasBuildEntry {
            blas: &blas,
            geometry: wgpu::BlasGeometries::AabbGeometries(geometries),
        };
        encoder.build_acceleration_structures([&entry], []);
        blas
    };
    gpu.queue.submit([encoder.finish()]);
    blas
}

/// How far every box reaches beyond its primitive, the same for all: 2⁻¹⁶
/// of the scene's largest coordinate (its local frame). A box only
/// decides which primitives the shader tests (a wider one costs a test, a
/// narrower one a hit), and a driver's slab test rounds each distance
/// relative to the ray's origin and the box's planes, not to the box's
/// size: lavapipe's misses a box whose face a ray grazes by a few units
/// of roundoff of those coordinates. This margin covers sixteen times the
/// error of a ray from anywhere in the scene's bounds.
fn box_pad(scene: &Scene) -> f32 {
    let triangles = scene.triangles.iter().flat_map(|t| [t.v0, t.v1, t.v2]);
    let spheres = scene
        .spheres
        .iter()
        .map(|s| s.center.map(|c| c.abs() + s.radius));
    let largest = triangles
        .chain(spheres)
        .flatten()
        .fold(0f32, |m, c| m.max(c.abs()));
    largest * (-16f32).exp2()
}

/// A box `pad` beyond `low..high` on every side, rounded outward.
fn padded(low: [f32; 3], high: [f32; 3], pad: f32) -> [f32; 6] {
    let low = low.map(|v| (v - pad).next_down());
    let high = high.map(|v| (v + pad).next_up());
    [low[0], low[1], low[2], high[0], high[1], high[2]]
}

fn triangle_box(t: &Triangle, pad: f32) -> [f32; 6] {
    let low = std::array::from_fn(|a| t.v0[a].min(t.v1[a]).min(t.v2[a]));
    let high = std::array::from_fn(|a| t.v0[a].max(t.v1[a]).max(t.v2[a]));
    padded(low, high, pad)
}

/// A sphere's box: the rounded centre ± radius, one step of f32 outward,
/// then `pad` (the sphere test's own roundoff is far below it).
fn sphere_box(s: &Sphere, pad: f32) -> [f32; 6] {
    let low = s.center.map(|c| (c - s.radius).next_down());
    let high = s.center.map(|c| (c + s.radius).next_up());
    padded(low, high, pad)
}
