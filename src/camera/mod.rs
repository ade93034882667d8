//! Where rays start: the `[camera]` table, its basis in both precisions,
//! the camera framed on a model with none, a turntable's orbit, the
//! stratified sample grid, and the default light (placed by the camera).
//! Below the scene and both backends, which all read it.

use glam::DVec3;
use serde::Deserialize;

use crate::layout::{LIGHT_DIRECTIONAL, Light};
use crate::limits::{checked_point, validate_resolution, vector_text};

mod basis;
pub mod navigate;

/// The basis in single precision, as on the GPU.
#[allow(clippy::unnecessary_cast)]
pub mod f32 {
    super::basis::basis!(f32, glam::Vec3);
}

/// The basis in double precision, for the oracle.
#[allow(clippy::unnecessary_cast)]
pub mod f64 {
    super::basis::basis!(f64, glam::DVec3);
}

/// What one render looks at: the camera (image size included), samples
/// per pixel and the jitter's seed. A per-call setting, apart from the
/// scene's geometry, so that one resident scene renders at any size or spp;
/// a scene file's own is the scene's `view` field, its default.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    pub camera: Camera,
    /// Samples per pixel (1: the pixel centre).
    pub spp: u32,
    /// Seed of the sample jitter.
    pub seed: u32,
}

/// The `[camera]` table. Kept in f64 so the oracle can use it at full
/// precision; the f32 paths round it once.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub eye: [f64; 3],
    pub look_at: [f64; 3],
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Vertical field of view, degrees.
    pub vfov: f64,
    pub width: u32,
    pub height: u32,
}

pub fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

impl Camera {
    /// This camera with eye and look_at relative to `offset` (in f64):
    /// what the kernels' camera basis is built from, for geometry kept
    /// relative to a scene's offset.
    pub fn relative_to(&self, offset: DVec3) -> Camera {
        let local = |p: [f64; 3]| (DVec3::from(p) - offset).to_array();
        Camera {
            eye: local(self.eye),
            look_at: local(self.look_at),
            ..self.clone()
        }
    }

    /// This camera at another image size: with only one of width and
    /// height given, the other keeps the aspect ratio.
    pub fn resized(&self, width: Option<u32>, height: Option<u32>) -> Result<Camera, String> {
        let (w, h) = (self.width as f64, self.height as f64);
        let (width, height) = match (width, height) {
            (None, None) => return Ok(self.clone()),
            (Some(width), Some(height)) => (width, height),
            (Some(width), None) => (width, ((width as f64 * h / w).round() as u32).max(1)),
            (None, Some(height)) => (((height as f64 * w / h).round() as u32).max(1), height),
        };
        validate_resolution(width, height)?;
        Ok(Camera {
            width,
            height,
            ..self.clone()
        })
    }
}

/// Smallest sine of the angle between camera.up and the view direction:
/// closer, the camera's right vector (f × up) is mostly rounding. Any up
/// that passes gives the same camera as its part perpendicular to f.
pub const MIN_UP_SINE: f64 = 1e-6;

pub fn validate_camera(camera: &Camera) -> Result<(), String> {
    for (name, v) in [
        ("eye", camera.eye),
        ("look_at", camera.look_at),
        ("up", camera.up),
    ] {
        checked_point(&format!("camera.{name}"), v)?;
    }
    let eye = DVec3::from(camera.eye);
    let forward = DVec3::from(camera.look_at) - eye;
    if forward.length_squared() == 0.0 {
        return Err("camera.eye and camera.look_at are the same point".into());
    }
    let up = DVec3::from(camera.up);
    if up.length_squared() == 0.0 {
        return Err("camera.up is the zero vector".into());
    }
    let sine = forward.normalize().cross(up.normalize()).length();
    if sine < MIN_UP_SINE {
        return Err(format!(
            "camera.up = {} is parallel to the view direction (look_at − eye): the angle between them must be at least {MIN_UP_SINE:e} rad",
            vector_text(DVec3::from(camera.up))
        ));
    }
    if !(camera.vfov > 0.0 && camera.vfov < 180.0) {
        return Err(format!(
            "camera.vfov = {} must be in (0, 180) degrees",
            camera.vfov
        ));
    }
    validate_resolution(camera.width, camera.height).map_err(|e| format!("camera: {e}"))
}

/// `camera` checked in the precision the renderer uses: its eye and
/// look_at moved into the local frame of a scene at `offset` and rounded
/// to f32, as every kernel's basis is built (`f32::CameraBasis`). Two
/// points apart in f64 can round to one in f32 (a view direction of zero:
/// every pixel NaN, rendered black), and an up barely off the view
/// direction can become parallel to it.
pub fn validate_camera_f32(camera: &Camera, offset: DVec3) -> Result<(), String> {
    let local = camera.relative_to(offset);
    let rounded = |p: [f64; 3]| DVec3::from(p).as_vec3();
    if rounded(local.eye) == rounded(local.look_at) {
        let frame = if offset == DVec3::ZERO {
            String::new()
        } else {
            format!(" relative to the scene's centre {}", vector_text(offset))
        };
        return Err(format!(
            "camera.eye = {} and camera.look_at = {} are the same point in f32, the precision \
             the renderer uses{frame}; move look_at further from eye",
            vector_text(DVec3::from(camera.eye)),
            vector_text(DVec3::from(camera.look_at))
        ));
    }
    let basis = f32::CameraBasis::new(&local);
    if ![basis.right, basis.up, basis.forward]
        .iter()
        .all(|v| v.is_finite())
    {
        return Err(format!(
            "camera.up = {} is parallel to the view direction (look_at − eye) in f32, the \
             precision the renderer uses",
            vector_text(DVec3::from(camera.up))
        ));
    }
    Ok(())
}

/// A model rendered alone: its resolution unless its camera's aspect ratio
/// or --width/--height say otherwise.
pub const DEFAULT_WIDTH: u32 = 1024;
pub const DEFAULT_HEIGHT: u32 = 768;
/// Field of view of the camera framed on a model with none.
pub const FRAMED_VFOV_DEG: f64 = 40.0;

/// The camera framed on a model with none: looking at the centre of its
/// bounding box from the front-right and above (along (1, 0.75, 2) from
/// it, +Y up), at the distance where the box's bounding sphere just fits
/// the narrower field of view, with a 5% margin. A flat model (`flat`: its
/// plane's unit normal, `flat_normal`) that this direction would see
/// within 30° of its plane, or edge-on, is seen from 60° off it instead, on
/// the same side, so that the image shows its face rather than a sliver.
pub fn frame_camera(&(lo, hi): &(DVec3, DVec3), flat: Option<DVec3>) -> Camera {
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-6);
    let aspect = DEFAULT_WIDTH as f64 / DEFAULT_HEIGHT as f64;
    let half_v = (FRAMED_VFOV_DEG / 2.0).to_radians();
    let half_h = (half_v.tan() * aspect).atan();
    let distance = 1.05 * radius / half_v.min(half_h).sin();
    let mut direction = DVec3::new(1.0, 0.75, 2.0).normalize();
    let mut up = DVec3::from(default_up());
    if let Some(normal) = flat {
        let off_plane = direction.dot(normal);
        if off_plane.abs() < 0.5 {
            // The default direction's part in the plane keeps the view's
            // heading; where it has none off the plane, its front side.
            let along = (direction - off_plane * normal).normalize();
            let side = if off_plane < 0.0 { -1.0 } else { 1.0 };
            let (sin, cos) = 60f64.to_radians().sin_cos();
            direction = side * sin * normal + cos * along;
            // A plane tilted so that this looks straight down +Y (or up
            // it) keeps its heading as the image's up instead.
            if direction.cross(up).length() < 0.1 {
                up = along;
            }
        }
    }
    let eye = centre + distance * direction;
    Camera {
        eye: eye.to_array(),
        look_at: centre.to_array(),
        up: up.to_array(),
        vfov: FRAMED_VFOV_DEG,
        width: DEFAULT_WIDTH,
        height: DEFAULT_HEIGHT,
    }
}

/// Most a flat model's points stray from its plane, as a fraction of its
/// size: a sheet this thin still shows as a sliver edge-on.
pub const FLAT_THICKNESS: f64 = 0.02;

/// The unit normal of the plane `points` lie in (to within
/// `FLAT_THICKNESS` of their extent), or None when they span a volume or
/// a line. `points` gives them afresh for each of its passes: the plane
/// is the one through a, the point farthest from the first point, b, the
/// farthest from a, and the point farthest from the line ab.
pub fn flat_normal<I: Iterator<Item = DVec3>>(points: impl Fn() -> I) -> Option<DVec3> {
    let farthest = |from: DVec3, measure: &dyn Fn(DVec3) -> f64| {
        points().fold((from, 0.0), |(best, d), p| {
            let m = measure(p - from);
            if m > d { (p, m) } else { (best, d) }
        })
    };
    let start = points().next()?;
    let (a, _) = farthest(start, &|v| v.length_squared());
    let (b, size) = farthest(a, &|v| v.length_squared());
    let size = size.sqrt();
    let line = b - a;
    let (c, _) = farthest(a, &|v| line.cross(v).length_squared());
    let normal = line.cross(c - a);
    // A line, or a point: no plane to see it from.
    if normal.length() <= 1e-9 * size * size {
        return None;
    }
    let normal = normal.normalize();
    let thickness = points().fold(0.0f64, |t, p| t.max((p - a).dot(normal).abs()));
    (thickness <= FLAT_THICKNESS * size).then_some(normal)
}

/// The camera of frame `frame` of `frames`, orbiting look_at about up.
pub fn orbit(camera: &Camera, frame: u32, frames: u32) -> Camera {
    let centre = DVec3::from(camera.look_at);
    let axis = DVec3::from(camera.up).normalize();
    let angle = std::f64::consts::TAU * frame as f64 / frames as f64;
    let eye =
        centre + glam::DQuat::from_axis_angle(axis, angle) * (DVec3::from(camera.eye) - centre);
    Camera {
        eye: eye.to_array(),
        ..camera.clone()
    }
}

/// The light of a model with none: directional, irradiance 1, shining
/// from behind the camera's right shoulder (from the camera, 30% to its
/// right and 50% up), so that what the camera sees is lit.
pub fn default_light(camera: &Camera) -> Light {
    let basis = f64::CameraBasis::new(camera);
    directional_light(basis.forward - 0.3 * basis.right - 0.5 * basis.up, [1.0; 3])
}

/// A directional light travelling along `direction` (finite, non-zero,
/// as the caller checked) with `irradiance`; the shader takes the way to
/// the light.
pub fn directional_light(direction: DVec3, irradiance: [f32; 3]) -> Light {
    Light {
        vector: (-direction.normalize()).as_vec3().to_array(),
        kind: LIGHT_DIRECTIONAL,
        color: irradiance,
        ..Light::default()
    }
}

/// Columns of the stratified sample grid: the largest divisor of `spp` not
/// above its square root, so that the grid is as square as `spp` allows and
/// every cell holds one sample.
pub fn strata_columns(spp: u32) -> u32 {
    (1..=spp.isqrt().max(1))
        .rev()
        .find(|d| spp.is_multiple_of(*d))
        .unwrap_or(1)
}

/// A progressive render's batch of samples `samples` of a `(width,
/// height, spp)` view, added to `pixels` sums: a non-empty range within
/// the view's samples, and one sum for each pixel.
pub fn check_batch(
    (width, height, spp): (u32, u32, u32),
    samples: &std::ops::Range<u32>,
    pixels: usize,
) -> Result<(), String> {
    if samples.is_empty() || samples.end > spp {
        return Err(format!(
            "samples {}..{} of a view of {spp} samples per pixel: a batch is a non-empty range within them",
            samples.start, samples.end
        ));
    }
    if pixels != width as usize * height as usize {
        return Err(format!("{pixels} sums for a {width}×{height} view"));
    }
    Ok(())
}
