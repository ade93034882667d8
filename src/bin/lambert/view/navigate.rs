//! The viewer's camera moves (orbit, pan, dolly, fly, frame) and the
//! camera as a `[camera]` table: pure functions of the camera, in f64.

use glam::{DQuat, DVec3};

use lambert::camera::{Camera, MIN_UP_SINE, frame_camera};

/// Orbit: a drag the window's height long turns the camera half a turn
/// (π / height radians a pixel), about `up` for a sideways drag and about
/// the camera's right for an upward one.
pub fn orbit(camera: &Camera, dx: f64, dy: f64, window_height: u32) -> Camera {
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
    Camera {
        eye: (centre + offset).to_array(),
        ..camera.clone()
    }
}

/// The camera's right and true up (unit vectors), and its distance to
/// look_at.
fn frame_of(camera: &Camera) -> (DVec3, DVec3, DVec3, f64) {
    let offset = DVec3::from(camera.look_at) - DVec3::from(camera.eye);
    let forward = offset.normalize();
    let right = forward.cross(DVec3::from(camera.up)).normalize();
    (forward, right, right.cross(forward), offset.length())
}

/// Both eye and look_at moved by `by`.
fn moved(camera: &Camera, by: DVec3) -> Camera {
    Camera {
        eye: (DVec3::from(camera.eye) + by).to_array(),
        look_at: (DVec3::from(camera.look_at) + by).to_array(),
        ..camera.clone()
    }
}

/// Pan: the point at look_at's depth under the cursor follows it.
pub fn pan(camera: &Camera, dx: f64, dy: f64, window_height: u32) -> Camera {
    let (_, right, up, distance) = frame_of(camera);
    let pixel = 2.0 * distance * (camera.vfov.to_radians() / 2.0).tan() / window_height as f64;
    moved(camera, (-dx * right + dy * up) * pixel)
}

/// Dolly: each notch of the wheel towards the scene brings the eye 10%
/// closer to look_at (away for notches back).
pub fn dolly(camera: &Camera, notches: f64) -> Camera {
    let centre = DVec3::from(camera.look_at);
    let offset = DVec3::from(camera.eye) - centre;
    Camera {
        eye: (centre + offset * 0.9f64.powf(notches)).to_array(),
        ..camera.clone()
    }
}

/// Fly: a step of 5% of the distance to look_at along the camera's
/// forward (W, S), right (D, A) or up (E, Q), look_at moving alike.
pub fn fly(camera: &Camera, key: char) -> Option<Camera> {
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
    Some(moved(camera, direction * 0.05 * distance))
}

/// The camera framed on the box `bounds` (as a model with no camera of
/// its own is framed; `flat`, a flat model's normal), at the window's size.
pub fn frame(bounds: (DVec3, DVec3), flat: Option<DVec3>, width: u32, height: u32) -> Camera {
    Camera {
        width,
        height,
        ..frame_camera(&bounds, flat)
    }
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
