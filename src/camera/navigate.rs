//! The viewers' camera moves (orbit, pan, dolly, fly, frame) and the
//! camera as a `[camera]` table: pure functions of the camera, in f64,
//! kept by a `Reach` within what a scene file accepts of a camera; `lambert
//! view`'s window and the web page's viewer (web/) move alike.

use glam::{DQuat, DVec3};

use super::{Camera, MIN_UP_SINE, frame_camera};
use crate::limits::{MAX_COORDINATE, MAX_LOCAL_COORDINATE};

/// Samples per pixel of a viewer's sequence when nothing else gives them:
/// the converged image is `render --spp 1024`'s.
pub const INTERACTIVE_SPP: u32 = 1024;

/// Where the camera may go: eye and look_at within MAX_LOCAL_COORDINATE of
/// the scene's offset on each axis and within MAX_COORDINATE (what a scene
/// file accepts, so that `c`'s table renders), and the eye at least
/// `min_distance` from look_at (so that a notch back always moves it).
#[derive(Clone, Copy, Debug)]
pub struct Reach {
    lo: DVec3,
    hi: DVec3,
    offset: DVec3,
    min_distance: f64,
}

/// The closest the eye comes to look_at, as a fraction of the scene's size.
const MIN_DISTANCE_OF_SIZE: f64 = 1e-6;
/// ... and of look_at's own magnitude (4,500 of f64's steps there), so
/// that the view direction, eye − look_at, is right to 2e-4 rad: a
/// fraction of a pixel.
const MIN_DISTANCE_OF_POSITION: f64 = 1e-12;
/// ... and of look_at's distance from the scene's offset: the renderer
/// takes the camera in f32 in the scene's frame, where eye and look_at
/// must stay about a thousand of f32's steps apart (2^-13) for the view
/// direction to hold to a fraction of a pixel, and not become one point.
const MIN_DISTANCE_OF_LOCAL_POSITION: f64 = 1.0 / 8192.0;

impl Reach {
    /// About `offset`, for a scene `size` across.
    pub fn new(offset: DVec3, size: f64) -> Reach {
        // A hair inside the limits: world − offset, rounded, stays within.
        let local = MAX_LOCAL_COORDINATE * (1.0 - 1e-9);
        let world = DVec3::splat(MAX_COORDINATE * (1.0 - 1e-9));
        // A scene of one point has no size: a unit then.
        let size = if size > 0.0 && size.is_finite() {
            size
        } else {
            1.0
        };
        let min_distance = MIN_DISTANCE_OF_SIZE * size;
        Reach {
            lo: (offset - local).max(-world),
            hi: (offset + local).min(world),
            offset,
            min_distance,
        }
    }

    /// The closest the eye may come to `look_at`.
    fn min_distance(&self, look_at: DVec3) -> f64 {
        self.min_distance
            .max(MIN_DISTANCE_OF_POSITION * look_at.abs().max_element())
            .max(MIN_DISTANCE_OF_LOCAL_POSITION * (look_at - self.offset).abs().max_element())
    }

    /// `camera` moved back within reach (`before` where the move left
    /// the eye no direction from look_at, or no finite place).
    pub fn keep(&self, camera: Camera, before: &Camera) -> Camera {
        let (eye, look_at) = (DVec3::from(camera.eye), DVec3::from(camera.look_at));
        let offset = eye - look_at;
        if !offset.is_finite() || offset.length_squared() == 0.0 {
            return before.clone();
        }
        self.place(camera, look_at, offset.normalize(), offset.length(), before)
    }

    /// The camera with look_at in the box (less a margin for the eye's
    /// least distance) and the eye `distance` from it along `direction`,
    /// that distance kept between the least and the box's wall.
    fn place(
        &self,
        camera: Camera,
        look_at: DVec3,
        direction: DVec3,
        distance: f64,
        before: &Camera,
    ) -> Camera {
        if !look_at.is_finite() || !direction.is_finite() || distance.is_nan() {
            return before.clone();
        }
        let margin = self.min_distance(look_at.clamp(self.lo, self.hi));
        let look_at = look_at.clamp(self.lo + margin, self.hi - margin);
        // The farthest the eye may go along `direction` inside the box.
        let room = (0..3)
            .filter(|&i| direction[i] != 0.0)
            .map(|i| {
                let wall = if direction[i] > 0.0 {
                    self.hi[i]
                } else {
                    self.lo[i]
                };
                (wall - look_at[i]) / direction[i]
            })
            .fold(f64::INFINITY, f64::min);
        let distance = distance.clamp(margin, room.max(margin));
        Camera {
            eye: (look_at + direction * distance)
                .clamp(self.lo, self.hi)
                .to_array(),
            look_at: look_at.to_array(),
            ..camera
        }
    }
}

/// Orbit: a drag the window's height long turns the camera half a turn
/// (π / height radians a pixel), about `up` for a sideways drag and about
/// the camera's right for an upward one.
pub fn orbit(camera: &Camera, dx: f64, dy: f64, window_height: u32, reach: &Reach) -> Camera {
    let per_pixel = std::f64::consts::PI / window_height.max(1) as f64;
    let centre = DVec3::from(camera.look_at);
    let up = DVec3::from(camera.up).normalize();
    let offset = DVec3::from(camera.eye) - centre;
    let turned = DQuat::from_axis_angle(up, -dx * per_pixel) * offset;
    let right = (-turned).cross(up).normalize();
    let tilted = DQuat::from_axis_angle(right, -dy * per_pixel) * turned;
    // Never over the pole (the camera would turn upside down) nor onto it
    // (up must stay apart from the view direction).
    let side = |v: DVec3| v.normalize().cross(up);
    let offset =
        if side(tilted).length() > 1000.0 * MIN_UP_SINE && side(tilted).dot(side(turned)) > 0.0 {
            tilted
        } else {
            turned
        };
    let orbited = Camera {
        eye: (centre + offset).to_array(),
        ..camera.clone()
    };
    reach.keep(orbited, camera)
}

/// The camera's right and true up (unit vectors), and its distance to
/// look_at.
fn frame_of(camera: &Camera) -> (DVec3, DVec3, DVec3, f64) {
    let offset = DVec3::from(camera.look_at) - DVec3::from(camera.eye);
    let forward = offset.normalize();
    let right = forward.cross(DVec3::from(camera.up)).normalize();
    (forward, right, right.cross(forward), offset.length())
}

/// Both eye and look_at moved by `by` (look_at stopped at the reach's
/// walls, the eye kept at its distance).
fn moved(camera: &Camera, by: DVec3, reach: &Reach) -> Camera {
    let (forward, _, _, distance) = frame_of(camera);
    let look_at = DVec3::from(camera.look_at) + by;
    reach.place(camera.clone(), look_at, -forward, distance, camera)
}

/// Pan: the point at look_at's depth under the cursor follows it.
pub fn pan(camera: &Camera, dx: f64, dy: f64, window_height: u32, reach: &Reach) -> Camera {
    let (_, right, up, distance) = frame_of(camera);
    let pixel = 2.0 * distance * (camera.vfov.to_radians() / 2.0).tan() / window_height as f64;
    moved(camera, (-dx * right + dy * up) * pixel, reach)
}

/// Dolly: each notch of the wheel towards the scene brings the eye 10%
/// closer to look_at (away for notches back), as far as `reach` allows.
pub fn dolly(camera: &Camera, notches: f64, reach: &Reach) -> Camera {
    let (forward, _, _, distance) = frame_of(camera);
    let look_at = DVec3::from(camera.look_at);
    // 0 or ∞ for a wild count: the reach's least or farthest distance.
    let distance = distance * 0.9f64.powf(notches);
    reach.place(camera.clone(), look_at, -forward, distance, camera)
}

/// Fly: a step of 5% of the distance to look_at along the camera's
/// forward (W, S), right (D, A) or up (E, Q), look_at moving alike, up to
/// the reach's walls.
pub fn fly(camera: &Camera, key: char, reach: &Reach) -> Option<Camera> {
    let (forward, right, up, distance) = frame_of(camera);
    let direction = match key {
        'w' => forward,
        's' => -forward,
        'd' => right,
        'a' => -right,
        'e' => up,
        'q' => -up,
        _ => return None,
    };
    Some(moved(camera, direction * 0.05 * distance, reach))
}

/// The camera framed on the box `bounds` (as a model with no camera of
/// its own is framed; `flat`, a flat model's normal), at the window's size,
/// within reach.
pub fn frame(
    bounds: (DVec3, DVec3),
    flat: Option<DVec3>,
    width: u32,
    height: u32,
    reach: &Reach,
) -> Camera {
    let framed = Camera {
        width,
        height,
        ..frame_camera(&bounds, flat)
    };
    reach.keep(framed.clone(), &framed)
}

/// The camera as a scene file's `[camera]` table (docs/scene-format.md):
/// numbers printed to the last bit, so that pasting it renders the same
/// picture.
pub fn camera_toml(camera: &Camera) -> String {
    let v = |p: [f64; 3]| format!("[{:?}, {:?}, {:?}]", p[0], p[1], p[2]);
    format!(
        "[camera]\neye = {}\nlook_at = {}\nup = {}\nvfov = {:?}\nwidth = {}\nheight = {}\n",
        v(camera.eye),
        v(camera.look_at),
        v(camera.up),
        camera.vfov,
        camera.width,
        camera.height
    )
}
