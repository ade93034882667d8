//! Speed of the geometric queries on a model: closest points, winding
//! numbers and parity on the CPU path, alternating rounds, points spread
//! uniformly over 1.5× the model's box (issue 32's measure), and the same
//! on the GPU for fewer points, checked equal to the CPU's bit for bit.
//!
//! cargo run --release --example proximity_speed -- MODEL [POINTS] [GPU_POINTS]

use std::sync::Arc;
use std::time::Instant;

use lambert::Scene;
use lambert::render::{DeviceChoice, Renderer};

fn main() -> lambert::Result<()> {
    let mut args = std::env::args().skip(1);
    let model = args
        .next()
        .expect("usage: proximity_speed MODEL [POINTS] [GPU_POINTS]");
    let n: usize = args
        .next()
        .map_or(1_000_000, |a| a.parse().expect("points"));
    let gpu_n: usize = args
        .next()
        .map_or(20_000, |a| a.parse().expect("GPU points"));
    let scene = Arc::new(Scene::load(std::path::Path::new(&model))?);
    let b = scene.bvh().bounds().expect("a model with triangles");
    let (c, h) = (b.centre(), (b.max - b.min) * 0.75);
    // A fixed sequence (an LCG), so that every run queries the same points.
    let mut state: u64 = 1;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / ((1u64 << 24) as f32) * 2.0 - 1.0
    };
    let points: Vec<[f32; 3]> = (0..n)
        .map(|_| {
            [
                c.x + h.x * uniform(),
                c.y + h.y * uniform(),
                c.z + h.z * uniform(),
            ]
        })
        .collect();
    let mut cpu = Renderer::Cpu(Arc::clone(&scene));
    println!(
        "{model}: {} triangles, {n} points, {}",
        scene.triangles().len(),
        cpu.describe()
    );
    let start = Instant::now();
    cpu.winding_numbers(&points[..1])?;
    println!(
        "winding tree built in {:.3} s",
        start.elapsed().as_secs_f64()
    );
    let rate = |count: usize, start: Instant| count as f64 / start.elapsed().as_secs_f64() / 1e6;
    for round in 0..3 {
        let t = Instant::now();
        cpu.closest_points(&points, f32::INFINITY)?;
        let closest = rate(n, t);
        let t = Instant::now();
        cpu.winding_numbers(&points)?;
        let winding = rate(n, t);
        let t = Instant::now();
        cpu.parity_inside(&points)?;
        let parity = rate(n, t);
        println!(
            "round {round}: closest {closest:.3} M/s, winding {winding:.3} M/s, parity {parity:.3} M/s"
        );
    }
    let (mut gpu, _) = Renderer::open(Arc::clone(&scene), DeviceChoice::Gpu, &Default::default())?;
    let some = &points[..gpu_n.min(n)];
    gpu.closest_points(&some[..1], f32::INFINITY)?;
    gpu.winding_numbers(&some[..1])?;
    let t = Instant::now();
    let closest = gpu.closest_points(some, f32::INFINITY)?;
    let closest_rate = rate(some.len(), t);
    let t = Instant::now();
    let winding = gpu.winding_numbers(some)?;
    let winding_rate = rate(some.len(), t);
    println!(
        "{}: {} points, closest {closest_rate:.4} M/s, winding {winding_rate:.4} M/s",
        gpu.describe(),
        some.len()
    );
    assert_eq!(
        closest,
        cpu.closest_points(some, f32::INFINITY)?,
        "GPU and CPU closest points differ"
    );
    let bits = |w: Vec<f32>| w.into_iter().map(f32::to_bits).collect::<Vec<_>>();
    assert_eq!(
        bits(winding),
        bits(cpu.winding_numbers(some)?),
        "GPU and CPU winding numbers differ"
    );
    Ok(())
}
