//! Criterion benches of the CPU pieces, and of our BVH builder against
//! obvhs's BVH2 builders.
//!
//!     cargo bench --bench bvh                 # everything
//!     cargo bench --bench bvh -- cpu/         # our CPU pieces only
//!     cargo bench --bench bvh -- 'build/dragon_res4'
//!
//! Groups:
//! - `cpu`: `Bvh::build` on the largest model (the full dragon), and
//!   `cpu::trace_rays` with primary rays on the smallest (dragon_res4).
//! - `build/<model>`: our `Bvh::build` against obvhs presets (convert +
//!   build + reorder into our layout).
//! - `trace/<model>`: 512x512 primary rays through our own CPU traversal on
//!   each tree, so the difference is the tree's quality alone.
//!
//! `LAMBERT_BENCH_MODELS=dragon_res4,dragon` restricts the ladder.
//! The SAH costs and the rest of the table come from `--bench bvh_compare`.

mod common;

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use lambert::bvh::Bvh;
use lambert::{bench, cpu, rays};

const TRACE_SIZE: u32 = 512;

fn cpu_pieces(c: &mut Criterion) {
    let mut group = c.benchmark_group("cpu");
    group.sample_size(10);

    let (name, path) = common::largest();
    let scene = bench::scene_for_obj(&path, TRACE_SIZE).expect("load model");
    group.measurement_time(Duration::from_secs(10));
    group.throughput(Throughput::Elements(scene.triangles().len() as u64));
    group.bench_function(BenchmarkId::new("bvh_build", &name), |b| {
        b.iter(|| Bvh::build(black_box(scene.triangles()), black_box(scene.spheres())))
    });

    let (name, path) = common::smallest();
    let scene = bench::scene_for_obj(&path, 1024).expect("load model");
    let camera_rays = rays::camera_rays(&scene);
    group.measurement_time(Duration::from_secs(5));
    group.throughput(Throughput::Elements(camera_rays.len() as u64));
    group.bench_function(BenchmarkId::new("trace_primary_1024", &name), |b| {
        b.iter(|| cpu::trace_rays(&scene, black_box(&camera_rays), false))
    });
    group.finish();
}

fn builders(c: &mut Criterion) {
    for (name, path) in common::ladder() {
        let mut scene = bench::scene_for_obj(&path, TRACE_SIZE).expect("load model");
        let tris = scene.triangles().len();
        let big = tris > 300_000;
        // Criterion times a subset of the presets (bvh_compare has them all):
        // obvhs's fast, medium and slow, and medium with leaves collapsed
        // under our SAH constants. The slow preset (spatial pre-splits) takes
        // seconds on the full dragon, so there it is traced but not timed.
        let presets: Vec<_> = common::presets()
            .into_iter()
            .filter(|(label, _)| {
                [
                    "obvhs-fast",
                    "obvhs-medium",
                    "obvhs-slow",
                    "obvhs-medium-ct1",
                ]
                .contains(label)
            })
            .collect();
        let timed_presets: Vec<_> = presets
            .iter()
            .filter(|(label, _)| !(big && *label == "obvhs-slow"))
            .collect();

        let mut group = c.benchmark_group(format!("build/{name}"));
        group.sample_size(10);
        group.warm_up_time(Duration::from_secs(1));
        group.measurement_time(Duration::from_secs(if big { 8 } else { 3 }));
        group.throughput(Throughput::Elements(tris as u64));
        group.bench_function("ours", |b| {
            b.iter(|| Bvh::build(black_box(scene.triangles()), black_box(scene.spheres())))
        });
        for (label, params) in timed_presets {
            group.bench_function(*label, |b| {
                b.iter(|| common::build_obvhs(black_box(scene.triangles()), *params).0)
            });
        }
        group.finish();

        let camera_rays = rays::camera_rays(&scene);
        let mut trees = vec![("ours".to_string(), scene.bvh().clone())];
        for (label, params) in &presets {
            trees.push((
                label.to_string(),
                common::build_obvhs(scene.triangles(), *params).0,
            ));
        }
        let reference = cpu::trace_rays(&scene, &camera_rays, false);

        let mut group = c.benchmark_group(format!("trace/{name}"));
        group.sample_size(10);
        group.warm_up_time(Duration::from_secs(1));
        group.measurement_time(Duration::from_secs(if big { 5 } else { 2 }));
        group.throughput(Throughput::Elements(camera_rays.len() as u64));
        for (label, bvh) in trees {
            scene.replace_bvh(bvh);
            // Quick check: the converted tree finds the same hits.
            let a = common::agreement(&reference, &cpu::trace_rays(&scene, &camera_rays, false));
            assert!(
                a.differ * 1000 <= a.rays,
                "{name} {label}: {a:?} disagree with our tree"
            );
            group.bench_function(&label, |b| {
                b.iter(|| cpu::trace_rays(&scene, black_box(&camera_rays), false))
            });
        }
        group.finish();
    }
}

criterion_group!(benches, cpu_pieces, builders);
criterion_main!(benches);
