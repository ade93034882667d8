//! Adaptive sampling (`lambert render --target-error E`): a first pass at a
//! few samples per pixel, then more samples only where a pixel's standard
//! error (from the spread of its own samples) is still above E, or whose
//! neighbour's is, doubling until every pixel is below E or at the cap.

use serde::Serialize;

use crate::camera::View;
use crate::error::Result;
use crate::limits::MAX_SPP;
use crate::output::Rendered;
use crate::render::Renderer;

const LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

#[derive(Clone, Copy, Debug)]
pub struct AdaptiveSettings {
    /// Standard error of a pixel's mean luminance to reach.
    pub target_error: f64,
    /// Samples every pixel gets first (at least 2, to estimate a spread; 4
    /// or more is better: with 2, both often land on one side of an edge).
    pub base_spp: u32,
    /// Most samples any pixel gets.
    pub max_spp: u32,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct AdaptiveReport {
    /// Pixels given more samples, per pass after the first.
    pub refined_per_pass: Vec<usize>,
    pub total_samples: u64,
    /// The sample cap used (the requested one, clamped to [base, MAX_SPP]).
    pub max_spp: u32,
    pub mean_spp: f64,
    /// √(mean over pixels of the variance of each pixel's mean): the RMSE
    /// the sampling noise alone is expected to leave.
    pub expected_rmse: f64,
    /// Pixels still above the target at the sample cap.
    pub above_target: usize,
}

/// Pixels above the target variance and their 8 neighbours: a pixel whose
/// few samples all fell on one side of an edge shows no spread, but its
/// neighbour across the edge does.
fn refine_list(variance: &[f32], width: u32, target_variance: f64) -> Vec<u32> {
    let height = variance.len() as u32 / width;
    let mut marked = vec![false; variance.len()];
    for (i, &v) in variance.iter().enumerate() {
        if v as f64 > target_variance {
            let (x, y) = (i as u32 % width, i as u32 / width);
            for ny in y.saturating_sub(1)..=(y + 1).min(height - 1) {
                for nx in x.saturating_sub(1)..=(x + 1).min(width - 1) {
                    marked[(ny * width + nx) as usize] = true;
                }
            }
        }
    }
    (0..variance.len() as u32)
        .filter(|&i| marked[i as usize])
        .collect()
}

fn luminance(c: [f32; 3]) -> f64 {
    (0..3).map(|i| (c[i] * LUMINANCE[i]) as f64).sum()
}

/// Renders `renderer`'s scene adaptively, seen from `view`; each pass
/// sets its own sample count and seed on a copy of the view.
pub fn render_adaptive(
    renderer: &mut Renderer,
    view: &View,
    settings: AdaptiveSettings,
) -> Result<(Rendered, AdaptiveReport)> {
    let base = settings.base_spp.clamp(2, MAX_SPP);
    let max_spp = settings.max_spp.clamp(base, MAX_SPP);
    let target_variance = settings.target_error * settings.target_error;
    let seed = view.seed;
    let mut pass_view = View {
        spp: base,
        ..view.clone()
    };
    let (mut rendered, _) = renderer.render(&pass_view, None)?;
    let pixels = rendered.prims.len();
    // Per pixel: samples so far, and the sum of squared deviations of
    // luminance about the mean (Chan et al.'s M2), to merge passes exactly.
    let mut samples = vec![base; pixels];
    let mut m2: Vec<f64> = rendered
        .variance
        .iter()
        .map(|&v| v as f64 * base as f64 * (base - 1) as f64)
        .collect();
    let mut report = AdaptiveReport::default();
    let width = view.camera.width;
    let mut spp = base;
    let mut pass = 1u32;
    while spp < max_spp {
        let extra = spp.min(max_spp - spp);
        // A pass of one sample would take the pixel centre, not a random
        // point: stop short of the cap rather than bias the mean.
        if extra < 2 {
            break;
        }
        let list = refine_list(&rendered.variance, width, target_variance);
        if list.is_empty() {
            break;
        }
        report.refined_per_pass.push(list.len());
        pass_view.spp = extra;
        // Another seed per pass: its samples are independent of the others.
        pass_view.seed = seed.wrapping_add(pass.wrapping_mul(0x9e37_79b9));
        let coords: Vec<[u32; 2]> = list.iter().map(|&i| [i % width, i / width]).collect();
        let results = renderer.render_pixel_list(&pass_view, &coords)?;
        for (&i, r) in list.iter().zip(&results) {
            let i = i as usize;
            let (na, nb) = (samples[i] as f64, extra as f64);
            let color_a = rendered.image.rgb[i];
            let color_b = [r[0], r[1], r[2]];
            let delta = luminance(color_b) - luminance(color_a);
            let m2_b = r[3] as f64 * nb * (nb - 1.0);
            let n = na + nb;
            m2[i] += m2_b + delta * delta * na * nb / n;
            rendered.image.rgb[i] = std::array::from_fn(|c| {
                ((color_a[c] as f64 * na + color_b[c] as f64 * nb) / n) as f32
            });
            samples[i] += extra;
            rendered.variance[i] = (m2[i] / ((n - 1.0) * n)) as f32;
        }
        spp += extra;
        pass += 1;
    }
    report.max_spp = max_spp;
    report.total_samples = samples.iter().map(|&n| n as u64).sum();
    report.mean_spp = report.total_samples as f64 / pixels as f64;
    report.expected_rmse =
        (rendered.variance.iter().map(|&v| v as f64).sum::<f64>() / pixels as f64).sqrt();
    report.above_target = rendered
        .variance
        .iter()
        .filter(|&&v| v as f64 > target_variance)
        .count();
    Ok((rendered, report))
}
