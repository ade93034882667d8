//! The limits every layer checks against (coordinates, sphere radius,
//! image size, samples per pixel) and the checks themselves, in one place
//! at the bottom of the library so that loaders, the camera and the scene
//! take them from here rather than from each other.

use glam::DVec3;

/// World coordinates beyond this magnitude are rejected: f64 itself spaces
/// them 1/8 apart there. Geometry far from the origin is kept relative to
/// the scene's offset (`placement`), so precision does not set this limit.
pub const MAX_COORDINATE: f64 = 1e15;

/// Geometry, lights and the camera beyond this distance (per axis) from
/// the scene's offset are rejected: the f32 edge tests take fourth powers
/// of lengths and would overflow.
pub const MAX_LOCAL_COORDINATE: f64 = 1e9;

/// Largest sphere radius. The hit distance no longer errs with the radius
/// (`intersect_sphere` keeps |o − c|² − r² exact to a few ulps of itself:
/// five units off a sphere of this radius, t is right to 1e-7), but f32
/// holds points on a larger sphere's surface no closer than 1/16 unit.
pub const MAX_SPHERE_RADIUS: f64 = 1e6;
/// Largest image side, in pixels.
pub const MAX_SIDE: u32 = 65_536;
/// Largest image, in pixels (16K × 16K): 5 GiB of host buffers.
pub const MAX_PIXELS: u64 = 1 << 28;

/// Most samples per pixel a render may ask for.
pub const MAX_SPP: u32 = 4096;

/// The most surfaces a path may hit (`--max-depth`): a path's loop runs
/// within one GPU invocation, whose time a driver may bound.
pub const MAX_MAX_DEPTH: u32 = 64;

/// `max_depth` from 1 (direct light alone) to `MAX_MAX_DEPTH`.
pub fn validate_max_depth(max_depth: u32) -> Result<(), String> {
    if (1..=MAX_MAX_DEPTH).contains(&max_depth) {
        Ok(())
    } else {
        Err(format!(
            "max_depth {max_depth} is outside 1 to {MAX_MAX_DEPTH}"
        ))
    }
}

/// Checks a sample count.
pub fn validate_spp(spp: u32) -> Result<(), String> {
    if spp == 0 || spp > MAX_SPP {
        return Err(format!("spp = {spp} must be between 1 and {MAX_SPP}"));
    }
    Ok(())
}

/// Checks an image size against what memory and tiling can serve.
pub fn validate_resolution(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("resolution {width}×{height} has a zero side"));
    }
    if width > MAX_SIDE || height > MAX_SIDE || width as u64 * height as u64 > MAX_PIXELS {
        return Err(format!(
            "resolution {width}×{height} is beyond the supported maximum \
             ({MAX_SIDE} per side, {MAX_PIXELS} pixels in all)"
        ));
    }
    Ok(())
}

/// A world point `field` as given, if finite and within MAX_COORDINATE.
pub fn checked_point(field: &str, v: [f64; 3]) -> Result<[f64; 3], String> {
    if v.iter().all(|c| c.is_finite() && c.abs() <= MAX_COORDINATE) {
        Ok(v)
    } else {
        Err(format!(
            "{field} = {v:?} must be finite with magnitude at most {MAX_COORDINATE:e}"
        ))
    }
}

/// A vector as a user writes it: [x, y, z].
pub fn vector_text(v: DVec3) -> String {
    let number = |x: f64| {
        if x != 0.0 && !(1e-4..1e7).contains(&x.abs()) {
            format!("{x:e}")
        } else {
            format!("{x}")
        }
    };
    format!("[{}, {}, {}]", number(v.x), number(v.y), number(v.z))
}
