//! The lights stage on the GPU (lavapipe in CI) against its CPU twin, bit
//! for bit: `sample_emitter`, `emitter_pdf`, `environment_radiance` and
//! `environment_pdf` on random queries (the `probe_lights` entry point),
//! in a scene with every kind of emitter and a turned map, and in one with
//! a constant environment; the emitters' table and map uploaded to
//! group 0's bindings 20 to 23.

mod common;

use glam::{Vec2, Vec3};
use lambert::Scene;
use lambert::cpu::f32::Kernel;
use lambert::gpu::GpuRenderer;
use lambert::layout::{LightAnswer, LightQuery};
use lambert::probe::Rng;

use common::lights::{
    bright_texel_map, color_spec, directional_light, floor, floor_with_quad, map_spec, point_light,
    spot_light, unit_f32, unit_vector,
};

/// Random queries about `scene`: points over the floor, normals and
/// directions anywhere, primitives the scene's and one past them.
fn queries(scene: &Scene, n: usize, seed: u64) -> Vec<LightQuery> {
    let mut rng = Rng(seed);
    let prims = scene.triangles().len() as u32 + 1;
    (0..n)
        .map(|_| LightQuery {
            position: [
                rng.range(-1.5, 1.5) as f32,
                rng.range(0.0, 2.0) as f32,
                rng.range(-1.5, 1.5) as f32,
            ],
            u_pick: unit_f32(&mut rng),
            normal: unit_vector(&mut rng),
            hit_prim: (rng.next_u64() % prims as u64) as u32,
            dir: unit_vector(&mut rng),
            distance: rng.range(0.1, 3.0) as f32,
            u: [unit_f32(&mut rng), unit_f32(&mut rng)],
            _pad: [0; 2],
        })
        .collect()
}

/// The CPU twin's answer to `q`.
fn twin(kernel: &Kernel, q: &LightQuery) -> LightAnswer {
    let (position, dir) = (Vec3::from(q.position), Vec3::from(q.dir));
    let s = kernel.sample_emitter(position, Vec3::from(q.normal), q.u_pick, Vec2::from(q.u));
    LightAnswer {
        wi: s.wi.to_array(),
        distance: s.distance,
        radiance: s.radiance.to_array(),
        pdf: s.pdf,
        environment: kernel.environment_radiance(dir).to_array(),
        environment_pdf: kernel.environment_pdf(dir),
        emitter_pdf: kernel.emitter_pdf(position, q.hit_prim, dir, q.distance),
        delta: s.delta as u32,
        _pad: [0; 2],
    }
}

/// Every answer of the GPU is the twin's, bit for bit.
fn assert_gpu_is_twin(scene: &Scene, seed: u64) {
    let queries = queries(scene, 20_000, seed);
    let mut renderer = GpuRenderer::new(common::open_gpu(), scene).expect("scene uploads");
    let answers = renderer.probe_lights(&queries).expect("probe runs");
    let kernel = Kernel::new(scene);
    let bits = |a: &LightAnswer| bytemuck::cast::<LightAnswer, [u32; 16]>(*a);
    let mut differ = 0;
    // How often each of the answer's 16 words differs.
    let mut words = [0; 16];
    for (q, gpu) in queries.iter().zip(&answers) {
        let cpu = twin(&kernel, q);
        for (count, (g, c)) in words.iter_mut().zip(bits(gpu).iter().zip(bits(&cpu))) {
            *count += (*g != c) as u32;
        }
        if bits(gpu) != bits(&cpu) {
            if differ < 5 {
                eprintln!("{q:?}\n  GPU {gpu:?}\n  CPU {cpu:?}");
            }
            differ += 1;
        }
    }
    assert_eq!(
        differ,
        0,
        "{differ} of {} answers differ (by word: {words:?})",
        queries.len()
    );
    // The queries reach every kind of sample.
    let delta = answers
        .iter()
        .filter(|a| a.delta == 1 && a.pdf > 0.0)
        .count();
    let area = answers
        .iter()
        .filter(|a| a.delta == 0 && a.pdf > 0.0)
        .count();
    let hits = answers.iter().filter(|a| a.emitter_pdf > 0.0).count();
    assert!(
        delta > 100 && area > 1000 && hits > 1000,
        "{delta} {area} {hits}"
    );
}

#[test]
fn every_emitter_and_a_turned_map_on_the_gpu_are_the_twins() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sun.exr");
    bright_texel_map(&path, 24, 13, (5, 4), 11);
    let mut scene = floor_with_quad([1.0, 2.0, 3.0]);
    scene.lights_mut().extend([
        point_light([0.0, 3.0, 0.0], [3.0, 2.0, 1.0]),
        spot_light([1.0, 3.0, 0.0], [0.0, -1.0, 0.0], [5.0; 3], 20.0, 30.0),
        directional_light([0.0, 0.8, 0.6], [0.2, 0.3, 0.4]),
    ]);
    scene
        .set_environment(Some(&map_spec(&path, 0.05, 30.0)))
        .unwrap();
    assert_gpu_is_twin(&scene, 1);
}

#[test]
fn a_constant_environment_on_the_gpu_is_the_twins() {
    let mut scene = floor();
    scene.materials_mut()[0].emission = [0.5; 3];
    scene.lights_mut().push(spot_light(
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [2.0; 3],
        10.0,
        40.0,
    ));
    scene
        .set_environment(Some(&color_spec([0.3, 0.2, 0.1], 1.5)))
        .unwrap();
    assert_gpu_is_twin(&scene, 2);
}
