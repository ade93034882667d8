//! Arbitrary output variables (`--aov albedo,normal,depth`): what the first
//! surface of each camera ray shows, averaged over a pixel's samples, for
//! an external denoiser (Intel Open Image Denoise takes albedo and normal
//! beside the noisy image). Computed on the CPU path whichever device
//! renders the image: first hits are cheap beside a path-traced image, and
//! the CPU traces the very camera rays the GPU does.

use rayon::prelude::*;

use super::f32::Kernel;
use super::precision::Scalar;
use crate::camera::View;
use crate::layout::NO_HIT;
use crate::output::Image;
use crate::scene::Scene;

/// Samples a pixel's outputs average at most: their own stratified grid
/// over the pixel (a denoiser wants the edges antialiased as the image's
/// are, not the image's noise).
pub const AOV_SAMPLES: u32 = 16;

/// One output variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Aov {
    /// The first surface's base colour (texture × factor × vertex colour;
    /// linear RGB); 0 where the ray leaves the scene.
    Albedo,
    /// Its shading normal (normal-mapped, towards the camera), world
    /// axes, each component in [−1, 1]; 0 where the ray leaves.
    Normal,
    /// Its distance along the camera ray, in world units (all three
    /// channels); 0 where the ray leaves (as Mitsuba 3's depth output).
    Depth,
}

impl Aov {
    pub const ALL: [Aov; 3] = [Aov::Albedo, Aov::Normal, Aov::Depth];

    pub fn name(self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
        }
    }

    /// A comma-separated list of names (`albedo,normal,depth`), each once.
    pub fn parse_list(text: &str) -> Result<Vec<Aov>, String> {
        let mut aovs = Vec::new();
        for name in text.split(',').map(str::trim) {
            let aov = Aov::ALL
                .into_iter()
                .find(|a| a.name() == name)
                .ok_or_else(|| format!("'{name}' is not albedo, normal or depth"))?;
            if aovs.contains(&aov) {
                return Err(format!("'{name}' is listed twice"));
            }
            aovs.push(aov);
        }
        Ok(aovs)
    }

    /// Where this output of an image written to `output` goes: beside it,
    /// `NAME.albedo.exr` (`.pfm` for a PFM image; EXR for a PNG one, whose
    /// 8 bits hold neither normals nor depths).
    pub fn path_beside(self, output: &std::path::Path) -> std::path::PathBuf {
        let extension = match output.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("pfm") => "pfm",
            _ => "exr",
        };
        output.with_extension(format!("{}.{extension}", self.name()))
    }
}

/// `aovs` of `view`'s image of `scene`, in that order; rows in parallel.
pub fn render_aovs(scene: &Scene, view: &View, aovs: &[Aov]) -> Vec<Image> {
    let (width, height) = (view.camera.width, view.camera.height);
    let samples = View {
        spp: view.spp.min(AOV_SAMPLES),
        ..view.clone()
    };
    let kernel = Kernel::with_view(scene, &samples, <f32 as Scalar>::has_ymm_boxes());
    let rows: Vec<Vec<[[f32; 3]; 3]>> = (0..height)
        .into_par_iter()
        .map(|y| {
            (0..width)
                .map(|x| first_hits(&kernel, x, y, samples.spp))
                .collect()
        })
        .collect();
    aovs.iter()
        .map(|&aov| Image {
            width,
            height,
            rgb: rows
                .iter()
                .flatten()
                .map(|pixel| pixel[aov as usize])
                .collect(),
        })
        .collect()
}

/// A pixel's mean albedo, normal and depth over `spp` samples.
fn first_hits(kernel: &Kernel, x: u32, y: u32, spp: u32) -> [[f32; 3]; 3] {
    let mut sums = [glam::Vec3::ZERO; 3];
    for sample in 0..spp {
        let (px, py) = kernel.sample_position(x, y, sample);
        let ray = kernel.camera_ray(px, py);
        let hit = kernel.trace_closest(ray);
        if hit.prim == NO_HIT {
            continue;
        }
        let surface = kernel.surface_at(&ray, &hit);
        let material = kernel.material_at(&ray, &hit, &surface);
        sums[Aov::Albedo as usize] += material.bsdf.base_color;
        sums[Aov::Normal as usize] += material.shading_normal;
        sums[Aov::Depth as usize] += glam::Vec3::splat(hit.t);
    }
    sums.map(|s| (s / spp as f32).to_array())
}
