//! The ray-query interface (docs/ray-query.md): ray files in, hit files out,
//! and how a set of hits agrees with the f64 oracle's.
//!
//! RAYS.bin: little-endian f32, 8 per ray: ox oy oz tmin dx dy dz tmax.
//! HITS.bin: 16 bytes per ray: f32 t (+inf on a miss), u32 primitive
//! (0xFFFFFFFF on a miss), f32 u, f32 v.

use std::path::Path;

use serde::Serialize;

use crate::cpu;
use crate::error::{Error, Result};
use crate::layout::{Hit, NO_HIT, Ray};
use crate::output::write_atomically;
use crate::scene::Scene;

const RAY_BYTES: usize = 32;
const FIELDS: [&str; 8] = ["ox", "oy", "oz", "tmin", "dx", "dy", "dz", "tmax"];
/// Range of direction lengths the f32 tests handle: |d|² and 1/d stay finite
/// and normal in f32.
pub const MIN_DIRECTION: f64 = 1e-18;
pub const MAX_DIRECTION: f64 = 1e18;

/// Reads and validates a ray file.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_rays(&bytes, path)
}

/// Decodes a ray file's bytes; `path` names it in errors.
pub fn parse_rays(bytes: &[u8], path: &Path) -> Result<Vec<Ray>> {
    let fail = |message: String| Error::Usage(format!("{}: {message}", path.display()));
    if !bytes.len().is_multiple_of(RAY_BYTES) {
        return Err(fail(format!(
            "{} bytes is not a whole number of rays ({RAY_BYTES} bytes each: 8 little-endian f32 \
             ox oy oz tmin dx dy dz tmax); {} bytes left over",
            bytes.len(),
            bytes.len() % RAY_BYTES
        )));
    }
    let rays: Vec<Ray> = bytes
        .chunks_exact(RAY_BYTES)
        .map(|chunk| {
            let f: [f32; 8] = std::array::from_fn(|i| {
                f32::from_le_bytes(chunk[4 * i..4 * i + 4].try_into().unwrap())
            });
            Ray {
                origin: [f[0], f[1], f[2]],
                tmin: f[3],
                dir: [f[4], f[5], f[6]],
                tmax: f[7],
            }
        })
        .collect();
    validate_rays(&rays).map_err(fail)?;
    Ok(rays)
}

/// Every value finite except tmax, which may be +inf; a direction of length
/// within [MIN_DIRECTION, MAX_DIRECTION]; tmin ≤ tmax. The message names the first bad ray, its byte offset and
/// the field.
pub fn validate_rays(rays: &[Ray]) -> Result<(), String> {
    for (i, ray) in rays.iter().enumerate() {
        let values = [
            ray.origin[0],
            ray.origin[1],
            ray.origin[2],
            ray.tmin,
            ray.dir[0],
            ray.dir[1],
            ray.dir[2],
            ray.tmax,
        ];
        let at = format!("ray {i} (byte offset {})", i * RAY_BYTES);
        for (value, field) in values.iter().zip(FIELDS) {
            let allowed = value.is_finite() || (field == "tmax" && *value == f32::INFINITY);
            if !allowed {
                return Err(format!(
                    "{at}: {field} is {value}; only tmax may be infinite (+inf), and nothing NaN"
                ));
            }
        }
        let length = glam::Vec3::from(ray.dir).as_dvec3().length();
        if !(MIN_DIRECTION..=MAX_DIRECTION).contains(&length) {
            return Err(format!(
                "{at}: the direction (dx, dy, dz) has length {length:e}; it must be between \
                 {MIN_DIRECTION:e} and {MAX_DIRECTION:e} (f32 squares of it must not under- or overflow)"
            ));
        }
        if ray.tmin > ray.tmax {
            return Err(format!(
                "{at}: tmin = {} is greater than tmax = {}",
                ray.tmin, ray.tmax
            ));
        }
    }
    Ok(())
}

pub fn rays_to_bytes(rays: &[Ray]) -> Vec<u8> {
    // The layout struct is exactly the file's 8 floats; the file is
    // little-endian, as is every target wgpu runs on.
    bytemuck::cast_slice(rays).to_vec()
}

pub fn hits_to_bytes(hits: &[Hit]) -> Vec<u8> {
    bytemuck::cast_slice(hits).to_vec()
}

pub fn write_rays(path: &Path, rays: &[Ray]) -> Result<()> {
    write_atomically(path, &rays_to_bytes(rays))
}

pub fn write_hits(path: &Path, hits: &[Hit]) -> Result<()> {
    write_atomically(path, &hits_to_bytes(hits))
}

/// Reads a hit file.
pub fn read_hits(path: &Path) -> Result<Vec<Hit>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if bytes.len() % 16 != 0 {
        return Err(Error::Usage(format!(
            "{}: {} bytes is not a whole number of 16-byte hits",
            path.display(),
            bytes.len()
        )));
    }
    Ok(bytes
        .chunks_exact(16)
        .map(|c| Hit {
            t: f32::from_le_bytes(c[0..4].try_into().unwrap()),
            prim: u32::from_le_bytes(c[4..8].try_into().unwrap()),
            u: f32::from_le_bytes(c[8..12].try_into().unwrap()),
            v: f32::from_le_bytes(c[12..16].try_into().unwrap()),
        })
        .collect())
}

/// The camera rays of `scene` through its pixel centres, row by row from the
/// top: the same rays `render` shoots at spp = 1 (unit direction, tmin 0,
/// tmax +inf).
pub fn camera_rays(scene: &Scene) -> Vec<Ray> {
    let kernel = cpu::f32::Kernel::new(scene);
    let (width, height) = (scene.camera.width, scene.camera.height);
    (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let ray = kernel.camera_ray(x as f32 + 0.5, y as f32 + 0.5);
            Ray {
                origin: ray.origin.to_array(),
                tmin: 0.0,
                dir: ray.dir.to_array(),
                tmax: f32::INFINITY,
            }
        })
        .collect()
}

/// Relative distance error beyond which a hit on the oracle's primitive
/// still disagrees with it (f32 triangle hits err by about 1e-7).
pub const AGREE_T_REL: f64 = 1e-4;

/// How one set of hits agrees with the f64 oracle's.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Agreement {
    pub rays: usize,
    /// Same primitive at the same distance (within AGREE_T_REL), or both
    /// miss.
    pub same: usize,
    /// Same primitive, but a distance off by more than AGREE_T_REL (a
    /// sphere's far side for its near one, say).
    pub other_distance: usize,
    /// Hit where the oracle misses.
    pub false_hits: usize,
    /// Miss where the oracle hits.
    pub false_misses: usize,
    /// Both hit, different primitives.
    pub other_primitive: usize,
    /// |t − t_oracle| / t_oracle over rays that hit the same primitive.
    pub t_rel_error_median: f64,
    pub t_rel_error_p99: f64,
    pub t_rel_error_max: f64,
}

impl Agreement {
    pub fn measure(hits: &[Hit], oracle: &[cpu::f64::Hit]) -> Agreement {
        assert_eq!(hits.len(), oracle.len(), "one hit per ray on both sides");
        let mut a = Agreement {
            rays: hits.len(),
            ..Agreement::default()
        };
        let mut errors = Vec::new();
        for (h, o) in hits.iter().zip(oracle) {
            match (h.prim == NO_HIT, o.prim == NO_HIT) {
                (true, true) => a.same += 1,
                (false, true) => a.false_hits += 1,
                (true, false) => a.false_misses += 1,
                (false, false) if h.prim != o.prim => a.other_primitive += 1,
                (false, false) => {
                    let error = ((h.t as f64 - o.t) / o.t).abs();
                    if error <= AGREE_T_REL {
                        a.same += 1;
                    } else {
                        a.other_distance += 1;
                    }
                    errors.push(error);
                }
            }
        }
        errors.sort_by(f64::total_cmp);
        let quantile = |q: f64| {
            if errors.is_empty() {
                0.0
            } else {
                errors[((errors.len() - 1) as f64 * q).round() as usize]
            }
        };
        a.t_rel_error_median = quantile(0.5);
        a.t_rel_error_p99 = quantile(0.99);
        a.t_rel_error_max = quantile(1.0);
        a
    }

    pub fn same_fraction(&self) -> f64 {
        self.same as f64 / self.rays.max(1) as f64
    }
}

impl std::fmt::Display for Agreement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "against the f64 oracle: {} of {} rays agree ({:.4}%)",
            self.same,
            self.rays,
            100.0 * self.same_fraction()
        )?;
        writeln!(
            f,
            "  false hits {}, false misses {}, other primitive {}, same primitive at another distance {}",
            self.false_hits, self.false_misses, self.other_primitive, self.other_distance
        )?;
        write!(
            f,
            "  relative t error: median {:.2e}, p99 {:.2e}, max {:.2e}",
            self.t_rel_error_median, self.t_rel_error_p99, self.t_rel_error_max
        )
    }
}

/// Distance between two f32 values in units in the last place.
pub fn ulp_distance(a: f32, b: f32) -> u32 {
    let key = |x: f32| {
        let bits = x.to_bits() as i32;
        if bits < 0 { i32::MIN - bits } else { bits }
    };
    (key(a) as i64 - key(b) as i64)
        .unsigned_abs()
        .min(u32::MAX as u64) as u32
}
