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
use crate::limits::MAX_COORDINATE;
use crate::output::write_atomically;
use crate::scene::Scene;

const RAY_BYTES: usize = 32;
const FIELDS: [&str; 8] = ["ox", "oy", "oz", "tmin", "dx", "dy", "dz", "tmax"];
/// Range of direction lengths the f32 tests handle: |d|² and 1/d stay finite
/// and normal in f32.
pub const MIN_DIRECTION: f64 = 1e-18;
pub const MAX_DIRECTION: f64 = 1e18;

/// Reads and validates a ray file: one bulk read straight into the rays.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>> {
    use std::io::Read;
    let (mut file, length) = crate::files::open_capped(path, crate::files::MAX_RAY_BYTES)?;
    let length = length as usize;
    check_ray_bytes(length, path)?;
    let mut rays = vec![Ray::default(); length / RAY_BYTES];
    file.read_exact(bytemuck::cast_slice_mut(&mut rays))
        .map_err(|e| Error::io(path, e))?;
    // A file that grew since its length was read is not a ray file we know.
    if file.read(&mut [0u8]).map_err(|e| Error::io(path, e))? != 0 {
        return Err(Error::Usage(format!(
            "{}: the file grew while it was read",
            path.display()
        )));
    }
    validate_rays(&rays)
        .map_err(|bad| Error::Usage(format!("{}: {}", path.display(), bad.in_file())))?;
    Ok(rays)
}

fn check_ray_bytes(length: usize, path: &Path) -> Result<()> {
    if !length.is_multiple_of(RAY_BYTES) {
        return Err(Error::Usage(format!(
            "{}: {length} bytes is not a whole number of rays ({RAY_BYTES} bytes each: 8 \
             little-endian f32 ox oy oz tmin dx dy dz tmax); {} bytes left over",
            path.display(),
            length % RAY_BYTES
        )));
    }
    Ok(())
}

/// A point file's record: little-endian f32 x, y, z.
pub const POINT_BYTES: usize = 12;
const AXES: [&str; 3] = ["x", "y", "z"];

/// Reads and checks a point file: every coordinate finite and within
/// `MAX_COORDINATE`, the first bad one named by point, byte offset and axis.
pub fn read_points(path: &Path) -> Result<Vec<[f32; 3]>> {
    let bytes = crate::files::read_capped(path, crate::files::MAX_RAY_BYTES)?;
    parse_points(&bytes, path)
}

/// Decodes a point file's bytes; `path` names it in errors.
pub fn parse_points(bytes: &[u8], path: &Path) -> Result<Vec<[f32; 3]>> {
    if !bytes.len().is_multiple_of(POINT_BYTES) {
        return Err(Error::Usage(format!(
            "{}: {} bytes is not a whole number of points ({POINT_BYTES} bytes each: 3 \
             little-endian f32 x y z); {} bytes left over",
            path.display(),
            bytes.len(),
            bytes.len() % POINT_BYTES
        )));
    }
    // A copy rather than a cast: `bytes` may be unaligned.
    let points: Vec<[f32; 3]> = bytemuck::pod_collect_to_vec(bytes);
    let bad = |c: &f32| !(c.is_finite() && (*c as f64).abs() <= MAX_COORDINATE);
    if let Some(i) = points.iter().position(|p| p.iter().any(bad)) {
        let axis = points[i].iter().position(bad).expect("a bad coordinate");
        return Err(Error::Usage(format!(
            "{}: point {i} (byte offset {}): {} is {:?}; coordinates must be finite and within ±{MAX_COORDINATE:e}",
            path.display(),
            i * POINT_BYTES,
            AXES[axis],
            points[i][axis]
        )));
    }
    Ok(points)
}

/// Decodes a ray file's bytes; `path` names it in errors.
pub fn parse_rays(bytes: &[u8], path: &Path) -> Result<Vec<Ray>> {
    check_ray_bytes(bytes.len(), path)?;
    // The file is little-endian f32s in the struct's order, as every target
    // wgpu runs on is; a copy rather than a cast, as `bytes` may be unaligned.
    let rays: Vec<Ray> = bytemuck::pod_collect_to_vec(bytes);
    validate_rays(&rays)
        .map_err(|bad| Error::Usage(format!("{}: {}", path.display(), bad.in_file())))?;
    Ok(rays)
}

/// The first ray `validate_rays` refused, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct BadRay {
    pub index: usize,
    pub problem: String,
}

impl BadRay {
    /// The message for a ray file: the ray's byte offset too.
    pub fn in_file(&self) -> String {
        format!(
            "ray {} (byte offset {}): {}",
            self.index,
            self.index * RAY_BYTES,
            self.problem
        )
    }
}

impl std::fmt::Display for BadRay {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ray {}: {}", self.index, self.problem)
    }
}

/// Every value finite except tmax, which may be +inf; a direction of length
/// within [MIN_DIRECTION, MAX_DIRECTION]; tmin ≤ tmax. The error names the
/// first bad ray and the field; nothing is allocated unless one is bad.
pub fn validate_rays(rays: &[Ray]) -> Result<(), BadRay> {
    use rayon::prelude::*;
    const CHUNK: usize = 8192;
    // In parallel chunks, and the first bad ray reported (not just any one).
    let chunk = rays
        .par_chunks(CHUNK)
        .position_first(|chunk| !chunk.iter().all(ray_is_valid));
    match chunk {
        None => Ok(()),
        Some(c) => {
            let index = c * CHUNK
                + rays[c * CHUNK..]
                    .iter()
                    .position(|r| !ray_is_valid(r))
                    .expect("a bad ray in the chunk");
            Err(bad_ray(&rays[index], index))
        }
    }
}

/// What is wrong with `rays[index]`, which `ray_is_valid` refused.
pub fn bad_ray(ray: &Ray, index: usize) -> BadRay {
    BadRay {
        index,
        problem: ray_problem(ray).expect("an invalid ray"),
    }
}

/// Whether `validate_rays` accepts `ray` (without building a message).
#[inline]
pub fn ray_is_valid(ray: &Ray) -> bool {
    // `&`, not `&&`: no branch per test, so the checks of packed rays
    // vectorise (a query checks every ray as it reads it).
    let [ox, oy, oz] = ray.origin;
    let [dx, dy, dz] = ray.dir;
    let finite = ox.is_finite()
        & oy.is_finite()
        & oz.is_finite()
        & dx.is_finite()
        & dy.is_finite()
        & dz.is_finite();
    finite & direction_length_is_valid(ray.dir) & bounds_are_valid(ray.tmin, ray.tmax)
}

/// Whether a direction's length is within [MIN_DIRECTION, MAX_DIRECTION]
/// (its coordinates finite or not: `ray_is_valid` checks that).
#[inline]
pub fn direction_length_is_valid(dir: [f32; 3]) -> bool {
    let [x, y, z] = dir.map(f64::from);
    let squared = x * x + y * y + z * z;
    (squared >= MIN_DIRECTION * MIN_DIRECTION) & (squared <= MAX_DIRECTION * MAX_DIRECTION)
}

/// Whether every direction whose longest axis (in magnitude) lies within
/// [shortest, longest] has a valid length (`direction_length_is_valid`):
/// its length lies within [longest axis, √3 · longest axis]. A check of
/// many rays at once, which may refuse some valid ones near the limits
/// (check those one by one).
#[inline]
pub fn direction_lengths_are_valid(shortest: f32, longest: f32) -> bool {
    (shortest as f64 >= MIN_DIRECTION) & (longest as f64 * 3f64.sqrt() <= MAX_DIRECTION)
}

/// Whether a ray's bounds are valid: tmin finite, tmax finite or +∞,
/// tmin ≤ tmax.
#[inline]
pub fn bounds_are_valid(tmin: f32, tmax: f32) -> bool {
    tmin.is_finite() & (tmax.is_finite() | (tmax == f32::INFINITY)) & (tmin <= tmax)
}

#[inline]
fn ray_problem(ray: &Ray) -> Option<String> {
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
    let finite = values[..7].iter().all(|v| v.is_finite())
        && (ray.tmax.is_finite() || ray.tmax == f32::INFINITY);
    if !finite {
        let (value, field) = values
            .iter()
            .zip(FIELDS)
            .find(|(v, field)| !(v.is_finite() || (*field == "tmax" && **v == f32::INFINITY)))
            .expect("a field is not finite");
        return Some(format!(
            "{field} is {value}; only tmax may be infinite (+inf), and nothing NaN"
        ));
    }
    let [x, y, z] = ray.dir.map(f64::from);
    let squared = x * x + y * y + z * z;
    if !(MIN_DIRECTION * MIN_DIRECTION..=MAX_DIRECTION * MAX_DIRECTION).contains(&squared) {
        let length = squared.sqrt();
        return Some(format!(
            "the direction (dx, dy, dz) has length {length:e}; it must be between \
             {MIN_DIRECTION:e} and {MAX_DIRECTION:e} (f32 squares of it must not under- or overflow)"
        ));
    }
    if ray.tmin > ray.tmax {
        return Some(format!(
            "tmin = {} is greater than tmax = {}",
            ray.tmin, ray.tmax
        ));
    }
    None
}

/// A ray file's bytes: the layout struct is exactly the file's 8 floats,
/// and the file is little-endian, as is every target wgpu runs on.
pub fn rays_to_bytes(rays: &[Ray]) -> &[u8] {
    bytemuck::cast_slice(rays)
}

/// A hit file's bytes (the same reasoning as `rays_to_bytes`).
pub fn hits_to_bytes(hits: &[Hit]) -> &[u8] {
    bytemuck::cast_slice(hits)
}

pub fn write_rays(path: &Path, rays: &[Ray]) -> Result<()> {
    write_atomically(path, rays_to_bytes(rays))
}

pub fn write_hits(path: &Path, hits: &[Hit]) -> Result<()> {
    write_atomically(path, hits_to_bytes(hits))
}

/// Reads a hit file.
pub fn read_hits(path: &Path) -> Result<Vec<Hit>> {
    let bytes = crate::files::read_capped(path, crate::files::MAX_RAY_BYTES)?;
    if !bytes.len().is_multiple_of(16) {
        return Err(Error::Usage(format!(
            "{}: {} bytes is not a whole number of 16-byte hits",
            path.display(),
            bytes.len()
        )));
    }
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

/// The camera rays of `scene`'s default view through its pixel centres,
/// row by row from the top: the same rays `render` shoots at spp = 1 (unit
/// direction, tmin 0, tmax +inf).
pub fn camera_rays(scene: &Scene) -> Vec<Ray> {
    camera_rays_for(scene, &scene.view.camera)
}

/// `camera_rays` through another camera (another image size, say).
pub fn camera_rays_for(scene: &Scene, camera: &crate::camera::Camera) -> Vec<Ray> {
    let mut kernel = cpu::f32::Kernel::new(scene);
    kernel.camera = cpu::f32::CameraBasis::new(&scene.local_camera(camera));
    let (width, height) = (camera.width, camera.height);
    (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let ray = kernel.camera_ray(x as f32 + 0.5, y as f32 + 0.5);
            Ray {
                // A ray file's rays are in world coordinates.
                origin: (ray.origin.as_dvec3() + scene.offset).as_vec3().to_array(),
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
