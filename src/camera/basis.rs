//! The camera's basis, written once for both precisions: `basis!`
//! expands it into camera::f32 and camera::f64 with their `Real` and
//! `Vec3`. The kernels (src/cpu/sample.rs, shaders/sample.wgsl) turn a
//! pixel into a ray through it.

/// `CameraBasis` in the invoking module, with `Real` and `Vec3` the given
/// scalar and glam vector types.
macro_rules! basis {
    ($real:ty, $vec3:ty) => {
        use crate::camera::Camera;
        type Real = $real;
        type Vec3 = $vec3;

        /// The camera convention of docs/scene-format.md in this precision.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct CameraBasis {
            pub eye: Vec3,
            pub right: Vec3,
            pub up: Vec3,
            pub forward: Vec3,
            /// tan(vfov/2)·W/H
            pub tan_half_x: Real,
            /// tan(vfov/2)
            pub tan_half_y: Real,
            pub width: u32,
            pub height: u32,
        }

        impl CameraBasis {
            pub fn new(camera: &Camera) -> CameraBasis {
                let eye = vec3_f64(camera.eye);
                let forward = (vec3_f64(camera.look_at) - eye).normalize();
                let right = forward.cross(vec3_f64(camera.up)).normalize();
                let up = right.cross(forward);
                let tan_half_y = (camera.vfov.to_radians() * 0.5).tan() as Real;
                CameraBasis {
                    eye,
                    right,
                    up,
                    forward,
                    tan_half_x: tan_half_y * camera.width as Real / camera.height as Real,
                    tan_half_y,
                    width: camera.width,
                    height: camera.height,
                }
            }
        }

        fn vec3_f64(v: [f64; 3]) -> Vec3 {
            Vec3::new(v[0] as Real, v[1] as Real, v[2] as Real)
        }
    };
}
pub(crate) use basis;
