//! Comparing two renders of one scene (GPU against CPU, or either against the
//! f64 oracle): statistics, a pass/fail verdict and a heatmap. `lambert diff`
//! and the tests share this code. docs/accuracy.md justifies the tolerance.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::output::{Image, Rendered, linear_to_srgb8};

/// When two renders count as the same image.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Tolerance {
    /// A channel may differ by `abs + rel·max(|a|, |b|)` (linear units).
    pub abs: f32,
    pub rel: f32,
    /// Fraction of pixels allowed beyond that.
    pub max_bad_fraction: f64,
    /// Fraction of pixels whose camera rays may hit different primitives.
    pub max_prim_mismatch_fraction: f64,
}

impl Default for Tolerance {
    fn default() -> Self {
        Tolerance {
            abs: 1e-4,
            rel: 1e-4,
            max_bad_fraction: 1e-3,
            max_prim_mismatch_fraction: 1e-3,
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct DiffStats {
    pub pixels: u64,
    /// Pixels with a NaN or an infinity in either image: each counts as
    /// beyond tolerance, and none enters the other statistics.
    pub non_finite: u64,
    /// Largest channel difference, linear, over the finite pixels.
    pub max_abs: f32,
    /// Largest channel difference in 8-bit sRGB steps.
    pub max_8bit_steps: u8,
    pub rmse: f64,
    /// Against a peak of 1.0, over the finite pixels; None when those are
    /// identical.
    pub psnr_db: Option<f64>,
    pub beyond_tolerance: u64,
    pub prim_mismatches: u64,
    pub tolerance: Tolerance,
    pub passed: bool,
}

fn pixel_beyond(a: [f32; 3], b: [f32; 3], tol: &Tolerance) -> bool {
    a.iter().zip(&b).any(|(x, y)| {
        let d = (x - y).abs();
        // NaN in either image always counts: only a comparable, small d passes.
        d.partial_cmp(&(tol.abs + tol.rel * x.abs().max(y.abs())))
            .is_none_or(|o| o == std::cmp::Ordering::Greater)
    })
}

pub fn compare(a: &Rendered, b: &Rendered, tol: &Tolerance) -> Result<DiffStats> {
    let (ia, ib) = (&a.image, &b.image);
    if (ia.width, ia.height) != (ib.width, ib.height) {
        return Err(Error::Usage(format!(
            "cannot compare a {}×{} image with a {}×{} one",
            ia.width, ia.height, ib.width, ib.height
        )));
    }
    let mut max_abs = 0.0f32;
    let mut max_8bit_steps = 0u8;
    let mut squared = 0.0f64;
    let mut beyond_tolerance = 0;
    let mut non_finite = 0;
    for (pa, pb) in ia.rgb.iter().zip(&ib.rgb) {
        beyond_tolerance += pixel_beyond(*pa, *pb, tol) as u64;
        if !pa.iter().chain(pb).all(|c| c.is_finite()) {
            non_finite += 1;
            continue;
        }
        for (x, y) in pa.iter().zip(pb) {
            let d = (x - y).abs();
            max_abs = max_abs.max(d);
            max_8bit_steps = max_8bit_steps.max(linear_to_srgb8(*x).abs_diff(linear_to_srgb8(*y)));
            squared += (d as f64).powi(2);
        }
    }
    let pixels = ia.rgb.len() as u64;
    let finite = pixels - non_finite;
    let prim_mismatches = a.prims.iter().zip(&b.prims).filter(|(x, y)| x != y).count() as u64;
    let rmse = if finite > 0 {
        (squared / (3 * finite) as f64).sqrt()
    } else {
        0.0
    };
    let passed = beyond_tolerance as f64 <= tol.max_bad_fraction * pixels as f64
        && prim_mismatches as f64 <= tol.max_prim_mismatch_fraction * pixels as f64;
    Ok(DiffStats {
        pixels,
        non_finite,
        max_abs,
        max_8bit_steps,
        rmse,
        psnr_db: (rmse > 0.0).then(|| -20.0 * rmse.log10()),
        beyond_tolerance,
        prim_mismatches,
        tolerance: *tol,
        passed,
    })
}

/// A picture of the differences: grey from black (equal) to white (10⁰)
/// on a log scale from 10⁻⁷; red where a pixel is beyond tolerance; magenta
/// where the camera rays hit different primitives.
pub fn heatmap(a: &Rendered, b: &Rendered, tol: &Tolerance) -> Image {
    let rgb = a
        .image
        .rgb
        .iter()
        .zip(&b.image.rgb)
        .zip(a.prims.iter().zip(&b.prims))
        .map(|((pa, pb), (prim_a, prim_b))| {
            if prim_a != prim_b {
                return [1.0, 0.0, 1.0];
            }
            if pixel_beyond(*pa, *pb, tol) {
                return [1.0, 0.0, 0.0];
            }
            let d = pa
                .iter()
                .zip(pb)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f32::max);
            let level = if d > 0.0 {
                ((d.log10() + 7.0) / 7.0).clamp(0.02, 1.0)
            } else {
                0.0
            };
            [level; 3]
        })
        .collect();
    Image {
        width: a.image.width,
        height: a.image.height,
        rgb,
    }
}

impl std::fmt::Display for DiffStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let percent = |n: u64| 100.0 * n as f64 / self.pixels as f64;
        writeln!(f, "pixels compared      {}", self.pixels)?;
        let of_finite = if self.non_finite > 0 {
            writeln!(
                f,
                "not finite           {} ({:.4}%): NaN or infinity in either image",
                self.non_finite,
                percent(self.non_finite)
            )?;
            " (finite pixels)"
        } else {
            ""
        };
        writeln!(
            f,
            "max abs difference   {:.3e} linear, {} 8-bit steps{of_finite}",
            self.max_abs, self.max_8bit_steps
        )?;
        writeln!(f, "RMSE                 {:.3e}{of_finite}", self.rmse)?;
        match self.psnr_db {
            Some(p) => writeln!(f, "PSNR                 {p:.1} dB{of_finite}")?,
            None if self.non_finite > 0 => {
                writeln!(f, "PSNR                 inf (finite pixels identical)")?
            }
            None => writeln!(f, "PSNR                 inf (identical)")?,
        }
        writeln!(
            f,
            "beyond tolerance     {} ({:.4}%; allowed {:.4}%, tolerance {:.0e} + {:.0e}·|value|)",
            self.beyond_tolerance,
            percent(self.beyond_tolerance),
            100.0 * self.tolerance.max_bad_fraction,
            self.tolerance.abs,
            self.tolerance.rel
        )?;
        writeln!(
            f,
            "hit primitive differs {} ({:.4}%; allowed {:.4}%)",
            self.prim_mismatches,
            percent(self.prim_mismatches),
            100.0 * self.tolerance.max_prim_mismatch_fraction
        )?;
        write!(f, "{}", if self.passed { "PASS" } else { "FAIL" })
    }
}
