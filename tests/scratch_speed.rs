use lambert::scene::Scene;
use std::sync::Arc;
use std::time::Instant;
#[test]
#[ignore]
fn speed() {
    let scene =
        Arc::new(Scene::load(std::path::Path::new("/work/shared/models/dragon_res2.obj")).unwrap());
    let b = scene.bvh.bounds().unwrap();
    let (c, h) = (b.centre(), (b.max - b.min) * 0.75);
    let mut s: u64 = 1;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 40) as f32) / ((1u64 << 24) as f32) * 2.0 - 1.0
    };
    let n = 3000;
    let points: Vec<glam::Vec3> = (0..n)
        .map(|_| glam::Vec3::new(c.x + h.x * rnd(), c.y + h.y * rnd(), c.z + h.z * rnd()))
        .collect();
    let radius = scene.placement().radius as f32;
    println!("bounds {:?} radius {radius}", b);
    let t = Instant::now();
    let mut q = Vec::new();
    for p in &points {
        let m = lambert::cpu::closest::query_margin(p.abs().max_element(), radius);
        lambert::cpu::closest::closest_point(
            &scene.bvh,
            scene.triangles.len(),
            *p,
            f32::INFINITY,
            m,
            &mut q,
        );
    }
    let e = t.elapsed().as_secs_f64();
    let (nodes, leaves) = lambert::cpu::closest::DBG.with(|c| c.get());
    println!(
        "{:.1} us/query, nodes {:.1} blocks {:.1} per query",
        e / n as f64 * 1e6,
        nodes as f64 / n as f64,
        leaves as f64 / n as f64
    );
}
