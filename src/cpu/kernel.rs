// The CPU twin of shaders/trace.wgsl, function by function with the same
// names. Included twice by src/cpu/mod.rs: once with `Real = f32` (the
// reference the GPU is diffed against) and once with `Real = f64` (the
// oracle). The including module defines `Real`, `Vec3` and `add_ulps`.

use crate::bvh::MAX_DEPTH;
use crate::layout::{FLAG_SMOOTH, LIGHT_POINT, NO_HIT};
use crate::scene::{Accel, Camera, Scene};

/// Widens a box's exit distance by 2·gamma(3) (pbrt-v4), as in the shader.
const BOX_SLACK: Real = 1.0000004;

/// "No hit yet" distance, as in the shader.
pub const FAR: Real = Real::MAX;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub tmin: Real,
    pub dir: Vec3,
    pub tmax: Real,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: Real,
    pub prim: u32,
    pub u: Real,
    pub v: Real,
}

pub struct Surface {
    pub position: Vec3,
    pub geometric_normal: Vec3,
    pub shading_normal: Vec3,
    pub albedo: Vec3,
}

pub fn miss() -> Hit {
    Hit {
        t: FAR,
        prim: NO_HIT,
        u: 0.0,
        v: 0.0,
    }
}

fn vec3(v: [f32; 3]) -> Vec3 {
    Vec3::new(v[0] as Real, v[1] as Real, v[2] as Real)
}

fn vec3_f64(v: [f64; 3]) -> Vec3 {
    Vec3::new(v[0] as Real, v[1] as Real, v[2] as Real)
}

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

/// A scene seen from one camera: what the shader's bindings hold.
pub struct Kernel<'a> {
    pub camera: CameraBasis,
    pub scene: &'a Scene,
    background: Vec3,
    ambient: Vec3,
}

impl<'a> Kernel<'a> {
    pub fn new(scene: &'a Scene) -> Kernel<'a> {
        Kernel {
            camera: CameraBasis::new(&scene.camera),
            scene,
            background: vec3(scene.background),
            ambient: vec3(scene.ambient),
        }
    }

    /// Pinhole camera; `pixel` in pixel units, row 0 at the top.
    pub fn camera_ray(&self, pixel_x: Real, pixel_y: Real) -> Ray {
        let c = &self.camera;
        let sx = (2.0 * pixel_x / c.width as Real - 1.0) * c.tan_half_x;
        let sy = (1.0 - 2.0 * pixel_y / c.height as Real) * c.tan_half_y;
        let dir = (c.forward + sx * c.right + sy * c.up).normalize();
        Ray {
            origin: c.eye,
            tmin: 0.0,
            dir,
            tmax: FAR,
        }
    }

    /// (t, u, v) of primitive `prim` (triangles first, then spheres).
    pub fn intersect_primitive(&self, ray: &Ray, prim: u32) -> (Real, Real, Real) {
        let triangles = &self.scene.triangles;
        if (prim as usize) < triangles.len() {
            let tri = &triangles[prim as usize];
            return intersect_triangle(ray, vec3(tri.v0), vec3(tri.v1), vec3(tri.v2));
        }
        let sphere = &self.scene.spheres[prim as usize - triangles.len()];
        (intersect_sphere(ray, vec3(sphere.center), sphere.radius as Real), 0.0, 0.0)
    }

    /// Tests `prim`; if it is hit nearer than ray.tmax, makes it the hit and
    /// shortens the ray. Returns whether it did.
    pub fn record_hit(&self, ray: &mut Ray, hit: &mut Hit, prim: u32) -> bool {
        let (t, u, v) = self.intersect_primitive(ray, prim);
        if t < ray.tmax {
            ray.tmax = t;
            *hit = Hit { t, prim, u, v };
            return true;
        }
        false
    }

    /// Closest hit through the BVH, nearer child first; with `any_hit`, the
    /// first hit found.
    pub fn trace_bvh(&self, ray_in: Ray, any_hit: bool) -> Hit {
        let nodes = &self.scene.bvh.nodes;
        let mut ray = ray_in;
        let mut hit = miss();
        let inv_dir = ray.dir.recip();
        let mut stack = [(0u32, 0.0 as Real); MAX_DEPTH];
        let mut sp = 0;
        let t_root = intersect_box(&ray, inv_dir, &nodes[0]);
        if t_root < ray.tmax {
            stack[0] = (0, t_root);
            sp = 1;
        }
        while sp > 0 {
            sp -= 1;
            let (index, t_entry) = stack[sp];
            if t_entry >= ray.tmax {
                continue;
            }
            let node = &nodes[index as usize];
            if node.count > 0 {
                for &prim in &self.scene.bvh.prims[node.first as usize..(node.first + node.count) as usize] {
                    if self.record_hit(&mut ray, &mut hit, prim) && any_hit {
                        return hit;
                    }
                }
                continue;
            }
            let left = node.first;
            let t_left = intersect_box(&ray, inv_dir, &nodes[left as usize]);
            let t_right = intersect_box(&ray, inv_dir, &nodes[left as usize + 1]);
            let left_first = t_left <= t_right;
            let (t_near, t_far) = (t_left.min(t_right), t_left.max(t_right));
            if t_far < ray.tmax {
                stack[sp] = (if left_first { left + 1 } else { left }, t_far);
                sp += 1;
            }
            if t_near < ray.tmax {
                stack[sp] = (if left_first { left } else { left + 1 }, t_near);
                sp += 1;
            }
        }
        hit
    }

    /// Every primitive in turn: the reference the BVH is tested against.
    pub fn trace_brute_force(&self, ray_in: Ray, any_hit: bool) -> Hit {
        let mut ray = ray_in;
        let mut hit = miss();
        for prim in 0..self.scene.primitive_count() as u32 {
            if self.record_hit(&mut ray, &mut hit, prim) && any_hit {
                return hit;
            }
        }
        hit
    }

    pub fn trace(&self, ray_in: Ray, any_hit: bool) -> Hit {
        let mut ray = ray_in;
        ray.tmax = ray.tmax.min(FAR);
        match self.scene.accel {
            Accel::Bvh => self.trace_bvh(ray, any_hit),
            Accel::BruteForce => self.trace_brute_force(ray, any_hit),
        }
    }

    pub fn trace_closest(&self, ray: Ray) -> Hit {
        self.trace(ray, false)
    }

    /// Any hit in (tmin, tmax): stops at the first blocker.
    pub fn trace_any(&self, ray: Ray) -> bool {
        self.trace(ray, true).prim != NO_HIT
    }

    pub fn surface_at(&self, ray: &Ray, hit: &Hit) -> Surface {
        let scene = self.scene;
        let num_triangles = scene.triangles.len() as u32;
        if hit.prim < num_triangles {
            let tri = &scene.triangles[hit.prim as usize];
            let (v0, v1, v2) = (vec3(tri.v0), vec3(tri.v1), vec3(tri.v2));
            let w = 1.0 - hit.u - hit.v;
            let position = w * v0 + hit.u * v1 + hit.v * v2;
            let geometric = face_forward((v1 - v0).cross(v2 - v0).normalize(), ray.dir);
            let mut shading = geometric;
            if tri.flags & FLAG_SMOOTH != 0 {
                let ns = &scene.normals[hit.prim as usize];
                let corner = |n: [f32; 4]| Vec3::new(n[0] as Real, n[1] as Real, n[2] as Real);
                let interpolated =
                    w * corner(ns.n0) + hit.u * corner(ns.n1) + hit.v * corner(ns.n2);
                if interpolated.dot(interpolated) > 0.0 {
                    shading = face_forward(interpolated.normalize(), ray.dir);
                }
            }
            return Surface {
                position,
                geometric_normal: geometric,
                shading_normal: shading,
                albedo: vec3(scene.materials[tri.material as usize].albedo),
            };
        }
        let sphere = &scene.spheres[(hit.prim - num_triangles) as usize];
        let center = vec3(sphere.center);
        let outward = (ray.origin + hit.t * ray.dir - center).normalize();
        let position = center + (sphere.radius as Real) * outward;
        let normal = face_forward(outward, ray.dir);
        Surface {
            position,
            geometric_normal: normal,
            shading_normal: normal,
            albedo: vec3(scene.materials[sphere.material as usize].albedo),
        }
    }

    /// Lambert: ambient·k + Σ k·E·max(0, n·l)·visible, linear RGB.
    pub fn shade(&self, ray: &Ray, hit: &Hit) -> Vec3 {
        if hit.prim == NO_HIT {
            return self.background;
        }
        let surface = self.surface_at(ray, hit);
        let mut color = self.ambient * surface.albedo;
        let origin = offset_ray_origin(surface.position, surface.geometric_normal);
        for light in &self.scene.lights {
            let light_vector = vec3(light.vector);
            let (to_light, irradiance, shadow_ray) = if light.kind == LIGHT_POINT {
                let d = light_vector - surface.position;
                let distance_squared = d.dot(d);
                let s = light_vector - origin;
                let shadow_length = s.length();
                (
                    d / distance_squared.sqrt(),
                    vec3(light.color) / distance_squared,
                    Ray {
                        origin,
                        tmin: 0.0,
                        dir: s / shadow_length,
                        tmax: shadow_length,
                    },
                )
            } else {
                (
                    light_vector,
                    vec3(light.color),
                    Ray {
                        origin,
                        tmin: 0.0,
                        dir: light_vector,
                        tmax: FAR,
                    },
                )
            };
            let cos_theta = surface.shading_normal.dot(to_light);
            if cos_theta <= 0.0 || irradiance == Vec3::ZERO {
                continue;
            }
            if self.scene.shadows && self.trace_any(shadow_ray) {
                continue;
            }
            color += surface.albedo * irradiance * cos_theta;
        }
        color
    }

    /// One pixel at its centre: colour and the primitive the camera ray hit.
    pub fn render_pixel(&self, x: u32, y: u32) -> (Vec3, u32) {
        let ray = self.camera_ray(x as Real + 0.5, y as Real + 0.5);
        let hit = self.trace_closest(ray);
        (self.shade(&ray, &hit), hit.prim)
    }
}

/// The lecture's test: plane hit t = n·(a − o)/(n·d), then three edge tests
/// that must all agree in sign. Returns (t, u, v); t = FAR on a miss.
pub fn intersect_triangle(ray: &Ray, a: Vec3, b: Vec3, c: Vec3) -> (Real, Real, Real) {
    let n = (b - a).cross(c - a);
    let n_dot_d = n.dot(ray.dir);
    if n_dot_d == 0.0 {
        return (FAR, 0.0, 0.0);
    }
    let t = n.dot(a - ray.origin) / n_dot_d;
    if !(t > ray.tmin && t < ray.tmax) {
        return (FAR, 0.0, 0.0);
    }
    let p = ray.origin + t * ray.dir;
    let e0 = (b - a).cross(p - a).dot(n);
    let e1 = (c - b).cross(p - b).dot(n);
    let e2 = (a - c).cross(p - c).dot(n);
    let inside =
        (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
    if !inside {
        return (FAR, 0.0, 0.0);
    }
    let nn = n.dot(n);
    (t, e2 / nn, e0 / nn)
}

/// Nearest root of |o + t·d − c|² = r² inside (tmin, tmax); FAR on a miss.
pub fn intersect_sphere(ray: &Ray, center: Vec3, radius: Real) -> Real {
    let oc = ray.origin - center;
    let a = ray.dir.dot(ray.dir);
    let b = oc.dot(ray.dir);
    let c = oc.dot(oc) - radius * radius;
    let f = oc - (b / a) * ray.dir;
    let discriminant = a * (radius * radius - f.dot(f));
    if discriminant < 0.0 {
        return FAR;
    }
    let q = -b - sign_nonzero(b) * discriminant.sqrt();
    let t0 = c / q;
    let t1 = q / a;
    let near = t0.min(t1);
    let far = t0.max(t1);
    if near > ray.tmin && near < ray.tmax {
        return near;
    }
    if far > ray.tmin && far < ray.tmax {
        return far;
    }
    FAR
}

/// Distance at which the ray enters the node's box within (tmin, tmax), or
/// FAR. Comparisons, not min/max, so that a NaN slab is ignored as on the GPU.
pub fn intersect_box(ray: &Ray, inv_dir: Vec3, node: &crate::layout::BvhNode) -> Real {
    let t0 = (vec3(node.min) - ray.origin) * inv_dir;
    let t1 = (vec3(node.max) - ray.origin) * inv_dir;
    let mut t_near = ray.tmin;
    let mut t_far = ray.tmax;
    for axis in 0..3 {
        let swap = t0[axis] > t1[axis];
        let near = if swap { t1[axis] } else { t0[axis] };
        let far = if swap { t0[axis] } else { t1[axis] } * BOX_SLACK;
        if near > t_near {
            t_near = near;
        }
        if far < t_far {
            t_far = far;
        }
    }
    if t_near <= t_far { t_near } else { FAR }
}

fn sign_nonzero(x: Real) -> Real {
    if x < 0.0 { -1.0 } else { 1.0 }
}

fn face_forward(n: Vec3, dir: Vec3) -> Vec3 {
    if n.dot(dir) > 0.0 { -n } else { n }
}

/// Ray Tracing Gems ch. 6: move p off its surface along n by a few ULPs of p
/// (or a fixed amount near the origin).
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    let offset = |p: Real, n: Real| -> Real {
        if p.abs() < 1.0 / 32.0 {
            p + (1.0 / 65536.0) * n
        } else {
            let of_i = (256.0 * n) as i32;
            add_ulps(p, if p < 0.0 { -of_i } else { of_i })
        }
    };
    Vec3::new(offset(p.x, n.x), offset(p.y, n.y), offset(p.z, n.z))
}
