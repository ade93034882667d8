//! The CPU path's render drivers: whole images, rows, the GPU's twin and
//! adaptive sampling's pixel lists, rows in parallel with rayon.

use rayon::prelude::*;

use super::packet::render_row;
use super::simd::{check_runs, with_simd};
use super::{CpuKernel, Precision, Scalar, f32, f64};
use crate::camera::View;
use crate::layout;
use crate::output::{Image, Rendered};
use crate::progress::Progress;
use crate::scene::Scene;

/// One pixel in the chosen precision: colour, first primitive, variance of
/// the mean luminance.
#[inline(always)]
fn pixel(
    kernel32: &f32::Kernel,
    kernel64: &f64::Kernel,
    precision: Precision,
    x: u32,
    y: u32,
) -> ([::core::primitive::f32; 3], u32, ::core::primitive::f32) {
    match precision {
        Precision::F32 => {
            let (c, p, v) = kernel32.render_pixel(x, y);
            (c.to_array(), p, v)
        }
        Precision::F64 => {
            let (c, p, v) = kernel64.render_pixel(x, y);
            (c.as_vec3().to_array(), p, v as ::core::primitive::f32)
        }
    }
}

/// Renders every pixel of `view`'s image of `scene` with its samples;
/// rows run in parallel.
pub fn render(scene: &Scene, view: &View, precision: Precision, progress: &Progress) -> Rendered {
    render_with(scene, view, precision, progress, CpuKernel::active())
}

/// Renders rows `rows` of `view`'s image of `scene` alone (a part of it).
pub fn render_rows(
    scene: &Scene,
    view: &View,
    precision: Precision,
    rows: std::ops::Range<u32>,
    progress: &Progress,
) -> Rendered {
    render_rows_with(
        scene,
        view,
        precision,
        rows,
        progress,
        CpuKernel::active(),
        None,
    )
}

/// `render` with a given CPU kernel (one this CPU runs).
pub fn render_with(
    scene: &Scene,
    view: &View,
    precision: Precision,
    progress: &Progress,
    cpu_kernel: CpuKernel,
) -> Rendered {
    render_rows_with(
        scene,
        view,
        precision,
        0..view.camera.height,
        progress,
        cpu_kernel,
        None,
    )
}

/// The GPU's twin: renders in single precision tracing the GPU's
/// compressed BVH as the shader does (`f32::Kernel::trace_compressed`), so
/// that a GPU/CPU difference is one of arithmetic, never of traversal
/// order. What `lambert diff` and the tests compare the GPU with.
pub fn render_gpu_twin(scene: &Scene, view: &View, progress: &Progress) -> Rendered {
    let nodes = crate::cwbvh::compress(&scene.bvh);
    render_rows_with(
        scene,
        view,
        Precision::F32,
        0..view.camera.height,
        progress,
        CpuKernel::Portable,
        Some(&nodes),
    )
}

/// The twin's short stack: a WebGPU device's (the GPU's own where its
/// workgroup memory is the minimum), spilling where the GPU's would.
pub(super) fn twin_stack_entries(scene: &Scene) -> usize {
    crate::cwbvh::short_stack(scene.bvh.depth(), crate::cwbvh::MIN_WORKGROUP_BYTES).0
}

/// The single-precision kernel of `view` on `cpu_kernel`, tracing the
/// GPU's compressed nodes where given.
fn kernel32<'a>(
    scene: &'a Scene,
    view: &View,
    cpu_kernel: CpuKernel,
    compressed: Option<&'a [layout::CompressedNode]>,
) -> f32::Kernel<'a> {
    let mut kernel = f32::Kernel::with_view(scene, view, cpu_kernel.ymm_boxes());
    kernel.compressed = compressed;
    kernel.stack_entries = twin_stack_entries(scene);
    kernel
}

/// A progressive render's next samples on the CPU path (the twin of
/// `GpuRenderer::add_samples`): samples `samples` of `view` added to each
/// pixel's sums (colour, squared luminance; row by row), which hold
/// samples `0..samples.start`; once they are the last, the image `render`
/// makes, bit for bit (the same kernel, its loop split).
pub fn add_samples(
    scene: &Scene,
    view: &View,
    samples: std::ops::Range<u32>,
    sums: &mut [[::core::primitive::f32; 4]],
) -> Result<Option<Image>, String> {
    let never = std::sync::atomic::AtomicBool::new(false);
    add_samples_or_cancel(scene, view, samples, sums, &never)
}

/// `add_samples`, whose rows not yet begun are skipped once `cancel` is
/// set: then `sums` hold part of the batch, and None comes back.
pub fn add_samples_or_cancel(
    scene: &Scene,
    view: &View,
    samples: std::ops::Range<u32>,
    sums: &mut [[::core::primitive::f32; 4]],
    cancel: &std::sync::atomic::AtomicBool,
) -> Result<Option<Image>, String> {
    use std::sync::atomic::Ordering;
    let c = &view.camera;
    crate::camera::check_batch((c.width, c.height, view.spp), &samples, sums.len())?;
    let cpu_kernel = CpuKernel::active();
    check_runs(cpu_kernel);
    let width = view.camera.width as usize;
    let kernel = kernel32(scene, view, cpu_kernel, None);
    sums.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        if cancel.load(Ordering::Relaxed) {
            return;
        }
        // SAFETY: checked above.
        unsafe {
            with_simd(
                cpu_kernel,
                #[inline(always)]
                || {
                    for (x, s) in row.iter_mut().enumerate() {
                        let before = (glam::Vec3::new(s[0], s[1], s[2]), s[3]);
                        let samples = samples.clone();
                        let ((sum, squares), _) =
                            kernel.add_samples(x as u32, y as u32, samples, before);
                        *s = [sum.x, sum.y, sum.z, squares];
                    }
                },
            )
        }
    });
    let mean = |s: &[::core::primitive::f32; 4]| {
        let (mean, _) = kernel.pixel_mean((glam::Vec3::new(s[0], s[1], s[2]), s[3]));
        mean.to_array()
    };
    if cancel.load(Ordering::Relaxed) {
        return Ok(None);
    }
    Ok((samples.end == view.spp).then(|| Image {
        width: view.camera.width,
        height: view.camera.height,
        rgb: sums.par_iter().map(mean).collect(),
    }))
}

fn render_rows_with(
    scene: &Scene,
    view: &View,
    precision: Precision,
    rows: std::ops::Range<u32>,
    progress: &Progress,
    cpu_kernel: CpuKernel,
    compressed: Option<&[layout::CompressedNode]>,
) -> Rendered {
    check_runs(cpu_kernel);
    let first_row = rows.start as usize;
    let (width, height) = (view.camera.width as usize, rows.len());
    let mut rgb = vec![[0.0; 3]; width * height];
    let mut prims = vec![0u32; width * height];
    let mut variance = vec![0.0; width * height];
    let kernel32 = kernel32(scene, view, cpu_kernel, compressed);
    let kernel64 = f64::Kernel::with_view(scene, view, <f64::Real as Scalar>::has_ymm_boxes());
    // Camera rays in packets (packet.rs), the single ray's hits bit for
    // bit, where the scene is triangles alone under the watertight test;
    // not for the oracle, nor the GPU's twin (it traverses the GPU's
    // nodes).
    let packets = precision == Precision::F32
        && compressed.is_none()
        && kernel32.features() == 0
        && scene.accel.traverses_bvh();
    let cpu_kernel = match packets {
        true => cpu_kernel.narrow_on_intel(),
        false => cpu_kernel,
    };
    rgb.par_chunks_mut(width)
        .zip(prims.par_chunks_mut(width))
        .zip(variance.par_chunks_mut(width))
        .enumerate()
        .for_each(|(row, ((rgb_row, prim_row), variance_row))| {
            let y = first_row + row;
            // SAFETY: checked above.
            unsafe {
                with_simd(
                    cpu_kernel,
                    #[inline(always)]
                    || {
                        if packets {
                            let ymm = cpu_kernel.ymm_boxes();
                            render_row(
                                &kernel32,
                                y as u32,
                                width,
                                view.spp,
                                ymm,
                                |x, (c, p, v)| {
                                    rgb_row[x] = c.to_array();
                                    prim_row[x] = p;
                                    variance_row[x] = v;
                                },
                            );
                            return;
                        }
                        for x in 0..width {
                            let (c, p, v) =
                                pixel(&kernel32, &kernel64, precision, x as u32, y as u32);
                            rgb_row[x] = c;
                            prim_row[x] = p;
                            variance_row[x] = v;
                        }
                    },
                )
            };
            progress.inc(1);
        });
    Rendered {
        image: Image {
            width: width as u32,
            height: height as u32,
            rgb,
        },
        prims,
        variance,
    }
}

/// Renders the listed pixels only (adaptive sampling's later passes):
/// mean colour and variance of the mean over `view`'s samples, as
/// `render_pixel_list` on the GPU.
pub fn render_pixel_list(
    scene: &Scene,
    view: &View,
    pixels: &[[u32; 2]],
) -> Vec<[::core::primitive::f32; 4]> {
    let kernel32 = f32::Kernel::with_view(scene, view, <f32::Real as Scalar>::has_ymm_boxes());
    let kernel64 = f64::Kernel::with_view(scene, view, <f64::Real as Scalar>::has_ymm_boxes());
    pixels
        .par_iter()
        .map(|&[x, y]| {
            // SAFETY: the active kernel runs on this CPU.
            let (c, _, v) = unsafe {
                with_simd(
                    CpuKernel::active(),
                    #[inline(always)]
                    || pixel(&kernel32, &kernel64, Precision::F32, x, y),
                )
            };
            [c[0], c[1], c[2], v]
        })
        .collect()
}
