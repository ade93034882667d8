//! Scenes and files the lights' tests share: environment maps written with
//! the `image` crate, a floor lit by an emissive quad, punctual lights and
//! a map, and uniform numbers in f32.

use std::path::Path;

use lambert::Scene;
use lambert::layout::{LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT, Light, Material, Triangle};
use lambert::lighting::{EnvironmentSource, EnvironmentSpec};
use lambert::probe::Rng;

/// Uniform in [0, 1) in f32 (an f64 in [0, 1) may round to 1.0).
pub fn unit_f32(rng: &mut Rng) -> f32 {
    (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32
}

/// A unit vector uniform over the sphere.
pub fn unit_vector(rng: &mut Rng) -> [f32; 3] {
    let z = rng.range(-1.0, 1.0);
    let phi = rng.range(0.0, std::f64::consts::TAU);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let v = glam::DVec3::new(r * phi.cos(), r * phi.sin(), z).normalize();
    v.as_vec3().to_array()
}

fn rgb_image(width: u32, height: u32, rgb: &[[f32; 3]]) -> image::Rgb32FImage {
    image::Rgb32FImage::from_fn(width, height, |x, y| {
        image::Rgb(rgb[(y * width + x) as usize])
    })
}

/// Writes `rgb` (row 0 first) as an OpenEXR file.
pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) {
    rgb_image(width, height, rgb)
        .save(path)
        .expect("EXR written");
}

/// Writes `rgb` (row 0 first) as a Radiance HDR file.
pub fn write_hdr(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let pixels: Vec<image::Rgb<f32>> = rgb.iter().map(|&p| image::Rgb(p)).collect();
    image::codecs::hdr::HdrEncoder::new(file)
        .encode(&pixels, width as usize, height as usize)
        .expect("HDR written");
}

/// The map at `path` with `strength` and `rotation_deg`, as a spec.
pub fn map_spec(path: &Path, strength: f64, rotation_deg: f64) -> EnvironmentSpec {
    EnvironmentSpec::new(
        EnvironmentSource::Image(path.to_path_buf()),
        strength,
        rotation_deg,
        |key| key.to_string(),
    )
    .unwrap()
}

/// A constant environment of `color` × `strength`.
pub fn color_spec(color: [f32; 3], strength: f64) -> EnvironmentSpec {
    EnvironmentSpec::new(EnvironmentSource::Color(color), strength, 0.0, |key| {
        key.to_string()
    })
    .unwrap()
}

fn triangle(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3], material: u32) -> Triangle {
    Triangle {
        v0,
        v1,
        v2,
        material,
        ..Default::default()
    }
}

/// A floor from −2 to 2 on x and z at y = 0 (grey, material 0): triangles
/// 0 and 1. Its bounding sphere's radius is 2√2.
pub fn floor() -> Scene {
    Scene::from_triangles(vec![
        triangle([-2.0, 0.0, -2.0], [-2.0, 0.0, 2.0], [2.0, 0.0, 2.0], 0),
        triangle([-2.0, 0.0, -2.0], [2.0, 0.0, 2.0], [2.0, 0.0, -2.0], 0),
    ])
}

/// An emissive material of radiance `emission`.
pub fn emissive(emission: [f32; 3]) -> Material {
    let mut material = Material::from_albedo([0.0; 3]);
    material.emission = emission;
    material
}

/// `floor` with a quad light of radiance `emission` at y = 1, from −0.5 to
/// 0.5 on x and 0 to 0.5 on z (triangles 2 and 3, material 1), and a
/// small one of radiance 4 at y = 0.5 (triangle 4, material 2).
pub fn floor_with_quad(emission: [f32; 3]) -> Scene {
    let mut scene = floor();
    scene.materials_mut().push(emissive(emission));
    scene.materials_mut().push(emissive([4.0; 3]));
    scene.add_triangles([
        triangle([-0.5, 1.0, 0.0], [0.5, 1.0, 0.0], [0.5, 1.0, 0.5], 1),
        triangle([-0.5, 1.0, 0.0], [0.5, 1.0, 0.5], [-0.5, 1.0, 0.5], 1),
        triangle([1.0, 0.5, 1.0], [1.2, 0.5, 1.0], [1.0, 0.5, 1.2], 2),
    ]);
    scene.rebuild_bvh();
    scene
}

pub fn point_light(position: [f32; 3], color: [f32; 3]) -> Light {
    Light {
        vector: position,
        kind: LIGHT_POINT,
        color,
        ..Default::default()
    }
}

/// A directional light towards unit `to_light`.
pub fn directional_light(to_light: [f32; 3], color: [f32; 3]) -> Light {
    Light {
        vector: to_light,
        kind: LIGHT_DIRECTIONAL,
        color,
        ..Default::default()
    }
}

/// A spot light at `position` pointing along unit `direction`, full within
/// `inner_deg` of it, none beyond `outer_deg`.
pub fn spot_light(
    position: [f32; 3],
    direction: [f32; 3],
    color: [f32; 3],
    inner_deg: f64,
    outer_deg: f64,
) -> Light {
    Light {
        vector: position,
        kind: LIGHT_SPOT,
        color,
        direction,
        cos_inner: inner_deg.to_radians().cos() as f32,
        cos_outer: outer_deg.to_radians().cos() as f32,
    }
}

/// A map of `width` × `height` texels, dim (0.05 to 1.05, from `seed`)
/// but for one bright texel (50 × 1, 2, 3) at `bright`, written to `path`.
pub fn bright_texel_map(
    path: &Path,
    width: u32,
    height: u32,
    bright: (u32, u32),
    seed: u64,
) -> Vec<[f32; 3]> {
    let mut rng = Rng(seed);
    let rgb: Vec<[f32; 3]> = (0..width * height)
        .map(|i| {
            if (i % width, i / width) == bright {
                [50.0, 100.0, 150.0]
            } else {
                std::array::from_fn(|_| rng.range(0.05, 1.05) as f32)
            }
        })
        .collect();
    write_exr(path, width, height, &rgb);
    rgb
}
