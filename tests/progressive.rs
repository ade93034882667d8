//! A render refined a few samples at a time (`Renderer::add_samples`, the
//! viewer's) ends with the very image one render of the same view makes,
//! on both paths, whatever the batches; and a batch that does not follow
//! on is refused.

mod common;

use std::sync::Arc;

use common::{load, open_gpu};
use lambert::camera::View;
use lambert::gpu::GpuRenderer;
use lambert::output::Image;
use lambert::render::{Progressive, Renderer};

/// The cornell box, small, at `spp` (a 2×3 grid of strata at 6: the
/// stratification depends on spp, so batches must keep the whole view's).
/// Several tiles wide and high at any spp (a GPU tile is at most 256
/// pixels a side, 128 at 6 spp), so that the GPU's sums of one tile must
/// be carried to its next batch past the others.
fn small_view(spp: u32) -> (Arc<lambert::Scene>, View) {
    let mut scene = load("cornell");
    scene.view_mut().camera.width = 517;
    scene.view_mut().camera.height = 263;
    scene.view_mut().spp = spp;
    scene.view_mut().seed = 7;
    let view = scene.view().clone();
    (Arc::new(scene), view)
}

fn bits(image: &Image) -> Vec<u32> {
    image.rgb.iter().flatten().map(|c| c.to_bits()).collect()
}

/// Adds the view's samples in batches of `batches` (cycling) and returns
/// each image after each batch.
fn progressive(renderer: &mut Renderer, view: &View, batches: &[u32]) -> Vec<Image> {
    let mut progressive = Progressive::new(view.clone());
    let mut images = Vec::new();
    for &count in batches.iter().cycle() {
        if progressive.is_finished() {
            break;
        }
        renderer.add_samples(&mut progressive, count).unwrap();
        images.push(progressive.image());
    }
    images
}

fn check_batches_equal_one_render(mut renderer: Renderer, path: &str) {
    // 3 spp: where a wavefront renders few samples (shadows apart), its
    // passes must carry the sums alike.
    let cases = [
        (6, &[1u32][..]),
        (6, &[2, 1, 3]),
        (1, &[1]),
        (6, &[6]),
        (3, &[1]),
    ];
    for (spp, batches) in cases {
        let (_, view) = small_view(spp);
        let (whole, _) = renderer.render(&view, None).unwrap();
        let images = progressive(&mut renderer, &view, batches);
        let last = images.last().unwrap();
        assert_eq!(
            bits(last),
            bits(&whole.image),
            "{path}: spp {spp} in batches {batches:?} differs from one render"
        );
        // The frames before are the means so far: they converge to it.
        if images.len() > 1 {
            assert_ne!(
                bits(&images[0]),
                bits(last),
                "{path}: the first frame is already final"
            );
        }
    }
}

#[test]
fn cpu_batches_equal_one_render_bit_for_bit() {
    let (scene, _) = small_view(1);
    check_batches_equal_one_render(Renderer::Cpu(scene), "CPU");
}

#[test]
fn gpu_batches_equal_one_render_bit_for_bit() {
    let (scene, _) = small_view(1);
    let gpu = GpuRenderer::new(open_gpu(), &scene).unwrap();
    check_batches_equal_one_render(Renderer::Gpu(Box::new(gpu)), "GPU");
}

#[test]
fn a_frame_is_the_mean_of_the_samples_so_far() {
    // One sample of a 4-spp view, on the CPU: the mean of one sample is
    // that sample, which a 4-spp render's pixel averages with three more.
    let (scene, view) = small_view(4);
    let mut renderer = Renderer::Cpu(scene);
    let images = progressive(&mut renderer, &view, &[1]);
    assert_eq!(images.len(), 4);
    let (whole, _) = renderer.render(&view, None).unwrap();
    let mean_of_frames: Vec<f32> = (0..whole.image.rgb.len() * 3)
        .map(|i| {
            // Frame k's image is the mean of k + 1 samples: recover each
            // sample and average them, as the render does.
            let at = |k: usize| images[k].rgb[i / 3][i % 3];
            let sample = |k: usize| at(k) * (k + 1) as f32 - at(k.max(1) - 1) * k as f32;
            (0..4).map(sample).sum::<f32>() / 4.0
        })
        .collect();
    let rendered: Vec<f32> = whole.image.rgb.iter().flatten().copied().collect();
    for (a, b) in mean_of_frames.iter().zip(&rendered) {
        assert!((a - b).abs() <= 1e-5 * b.abs().max(1.0), "{a} vs {b}");
    }
}

#[test]
fn a_batch_past_the_views_samples_or_of_another_size_is_refused() {
    let (scene, view) = small_view(4);
    let pixels = (view.camera.width * view.camera.height) as usize;
    let mut sums = vec![[0.0f32; 4]; pixels];
    let error = lambert::cpu::add_samples(&scene, &view, 3..5, &mut sums).unwrap_err();
    assert!(error.contains("samples 3..5 of a view of 4"), "{error}");
    let error = lambert::cpu::add_samples(&scene, &view, 2..2, &mut sums).unwrap_err();
    assert!(error.contains("non-empty"), "{error}");
    let mut short = vec![[0.0f32; 4]; pixels - 1];
    let error = lambert::cpu::add_samples(&scene, &view, 0..1, &mut short).unwrap_err();
    assert!(error.contains("sums for a 517×263 view"), "{error}");
    let mut gpu = GpuRenderer::new(open_gpu(), &scene).unwrap();
    let error = gpu
        .add_samples(&view, 0..5, &mut sums)
        .unwrap_err()
        .to_string();
    assert!(error.contains("samples 0..5 of a view of 4"), "{error}");
}
