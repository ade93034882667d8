//! A synthetic scene of millions of triangles, too large for one storage
//! binding on lavapipe (128 MiB), rendered on the GPU and the CPU path.
//!
//! cargo run --release --example large_scene -- [SUBDIVISIONS] [SIZE]
//! (9 subdivisions of an icosahedron: 5,242,880 triangles.)

use std::time::Instant;

use glam::{DVec3, Vec3};
use lambert::camera::Camera;
use lambert::diff::{Tolerance, compare};
use lambert::gpu::{AdapterRequest, Gpu, GpuRenderer};
use lambert::layout::{LIGHT_DIRECTIONAL, Light};
use lambert::progress::Progress;
use lambert::{Scene, cpu, probe};

fn main() -> lambert::Result<()> {
    let mut args = std::env::args().skip(1);
    let subdivisions: u32 = args.next().map_or(9, |a| a.parse().expect("subdivisions"));
    let size: u32 = args.next().map_or(1024, |a| a.parse().expect("size"));

    let start = Instant::now();
    let (vertices, faces) = probe::icosphere(1.0, subdivisions);
    // Ripples make the surface non-trivial to trace and shade.
    let bumpy =
        |v: DVec3| v * (1.0 + 0.03 * (25.0 * v.x).sin() * (25.0 * v.y).cos() * (25.0 * v.z).sin());
    let vertices: Vec<Vec3> = vertices.into_iter().map(|v| bumpy(v).as_vec3()).collect();
    let triangles = probe::triangles(&vertices, &faces);
    drop((vertices, faces));
    let generated = start.elapsed();
    let mut scene = Scene::from_triangles(triangles);
    scene.view_mut().camera = Camera {
        eye: [0.0, 0.6, 3.2],
        look_at: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        vfov: 40.0,
        width: size,
        height: size,
    };
    scene.lights_mut().push(Light {
        vector: Vec3::new(0.5, 0.7, 0.5).normalize().to_array(),
        kind: LIGHT_DIRECTIONAL,
        color: [2.5; 3],
        ..Light::default()
    });
    let settings = lambert::scene::RenderSettings {
        ambient: [0.05; 3],
        shadows: true,
        ..scene.default_settings()
    };
    let scene = scene.with_settings(&settings);
    println!(
        "{} triangles: generated in {:.2} s, BVH ({} nodes) built in {:.2} s",
        scene.triangles().len(),
        generated.as_secs_f64(),
        scene.bvh().nodes.len(),
        scene.bvh().build_time.as_secs_f64()
    );

    let gpu = Gpu::open(&AdapterRequest::default(), false)?;
    let limit = gpu.limits.max_storage_buffer_binding_size;
    let start = Instant::now();
    let mut renderer = GpuRenderer::new(gpu, &scene)?;
    println!(
        "GPU {}: uploaded {:.1} MiB ({:.1} bytes per triangle) in {:.2} s; one binding holds {} MiB, arrays split over two: {:?}",
        renderer.gpu().describe(),
        renderer.device_bytes as f64 / (1 << 20) as f64,
        renderer.device_bytes as f64 / scene.triangles().len() as f64,
        start.elapsed().as_secs_f64(),
        limit >> 20,
        renderer.split_arrays
    );
    renderer.prepare_render()?;
    let start = Instant::now();
    let (gpu_image, _) = renderer.render(scene.view(), &Progress::hidden())?;
    let gpu_time = start.elapsed();
    let start = Instant::now();
    let cpu_image = cpu::render(
        &scene,
        scene.view(),
        cpu::Precision::F32,
        &Progress::hidden(),
    );
    let cpu_time = start.elapsed();
    println!(
        "{size}x{size}: GPU {:.2} s, CPU path {:.2} s",
        gpu_time.as_secs_f64(),
        cpu_time.as_secs_f64()
    );
    let stats = compare(&gpu_image, &cpu_image, &Tolerance::default())?;
    println!("GPU vs CPU:\n{stats}");
    gpu_image
        .image
        .save(std::path::Path::new("large_scene.png"))?;
    println!("wrote large_scene.png");
    Ok(())
}
