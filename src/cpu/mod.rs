//! The CPU reference path: the shader's algorithm in Rust, run in parallel
//! with rayon. `f32` is the reference the GPU is diffed against; `f64` is the
//! same code in double precision, the oracle that measures both.

use rayon::prelude::*;

use crate::output::{Image, Rendered};
use crate::progress::Progress;
use crate::scene::Scene;

/// Single precision, as on the GPU.
#[allow(clippy::unnecessary_cast)]
pub mod f32 {
    pub type Real = f32;
    pub type Vec3 = glam::Vec3;

    /// Steps `x` by `k` units in the last place (Ray Tracing Gems ch. 6).
    fn add_ulps(x: Real, k: i32) -> Real {
        Real::from_bits((x.to_bits() as i32).wrapping_add(k) as u32)
    }

    include!("kernel.rs");
}

/// Double precision: the oracle.
#[allow(clippy::unnecessary_cast)]
pub mod f64 {
    pub type Real = f64;
    pub type Vec3 = glam::DVec3;

    fn add_ulps(x: Real, k: i32) -> Real {
        Real::from_bits((x.to_bits() as i64).wrapping_add(k as i64) as u64)
    }

    include!("kernel.rs");
}

/// Which precision the CPU path computes in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    F32,
    F64,
}

/// Renders every pixel at its centre; rows run in parallel.
pub fn render(scene: &Scene, precision: Precision, progress: &Progress) -> Rendered {
    let (width, height) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut rgb = vec![[0.0f32; 3]; width * height];
    let mut prims = vec![0u32; width * height];
    let kernel32 = f32::Kernel::new(scene);
    let kernel64 = f64::Kernel::new(scene);
    rgb.par_chunks_mut(width)
        .zip(prims.par_chunks_mut(width))
        .enumerate()
        .for_each(|(y, (rgb_row, prim_row))| {
            for x in 0..width {
                let (color, prim) = match precision {
                    Precision::F32 => {
                        let (c, p) = kernel32.render_pixel(x as u32, y as u32);
                        (c.to_array(), p)
                    }
                    Precision::F64 => {
                        let (c, p) = kernel64.render_pixel(x as u32, y as u32);
                        (c.as_vec3().to_array(), p)
                    }
                };
                rgb_row[x] = color;
                prim_row[x] = prim;
            }
            progress.inc(1);
        });
    Rendered {
        image: Image {
            width: width as u32,
            height: height as u32,
            rgb,
        },
        prims,
    }
}
