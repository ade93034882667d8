//! One-shot comparison of our binned-SAH builder with obvhs's BVH2 builders
//! over the model ladder: build time, SAH cost (our `Bvh::sah_cost` formula
//! on both trees), depth, and primary-ray speed through our own CPU
//! traversal (`cpu::trace_rays`) on each tree converted to our layout.
//! Prints a Markdown table.
//!
//!     cargo bench --bench bvh_compare
//!
//! Environment: `LAMBERT_BENCH_MODELS=dragon_res4,dragon` restricts the
//! ladder; `LAMBERT_BENCH_SIZE` sets the image side (default 1024, i.e.
//! 1024x1024 camera rays).

mod common;

use std::hint::black_box;
use std::time::{Duration, Instant};

use lambert::bvh::Bvh;
use lambert::{bench, cpu, rays};

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Times each of `jobs` `rounds` times, round-robin after one untimed
/// warm-up round, so that background load falls on all of them alike.
fn interleaved<J>(
    jobs: &mut [J],
    rounds: usize,
    mut run: impl FnMut(&mut J),
) -> Vec<Vec<Duration>> {
    for job in jobs.iter_mut() {
        run(job);
    }
    let mut times = vec![Vec::new(); jobs.len()];
    for _ in 0..rounds {
        for (job, t) in jobs.iter_mut().zip(&mut times) {
            let start = Instant::now();
            run(job);
            t.push(start.elapsed());
        }
    }
    times
}

enum Builder {
    Ours,
    Obvhs(obvhs::BvhBuildParams),
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else is understood.
    let size: u32 = std::env::var("LAMBERT_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1024);
    println!(
        "rayon threads: {}, camera rays: {size}x{size} (primary, closest hit, our CPU traversal)",
        rayon::current_num_threads()
    );
    println!("times: min and median over interleaved rounds after a warm-up round");
    println!();
    println!(
        "| model | triangles | builder | build ms min | build ms med | SAH cost | depth | nodes | leaves | prim refs | Mrays/s best | Mrays/s med | same prim / tie / differ |"
    );
    println!("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|");
    for (name, path) in common::ladder() {
        let mut scene = bench::scene_for_obj(&path, size).expect("load model");
        assert!(scene.spheres().is_empty(), "OBJ scenes have no spheres");
        let tris = scene.triangles().len();
        let big = tris > 300_000;
        let camera_rays = rays::camera_rays(&scene);

        let mut builders: Vec<(String, Builder)> =
            vec![("ours (binned SAH)".into(), Builder::Ours)];
        builders.extend(
            common::presets()
                .into_iter()
                .filter(|(label, _)| common::preset_fits(label, tris))
                .map(|(label, params)| (label.to_string(), Builder::Obvhs(params))),
        );
        let build = |b: &Builder| match b {
            Builder::Ours => Bvh::build(scene.triangles(), scene.spheres()),
            Builder::Obvhs(params) => common::build_obvhs(scene.triangles(), *params).0,
        };
        let mut trees: Vec<Bvh> = Vec::new();
        let build_times = interleaved(&mut builders, if big { 3 } else { 7 }, |(_, b)| {
            black_box(build(b));
        });
        for (_, b) in &builders {
            trees.push(build(b));
        }

        scene.replace_bvh(trees[0].clone());
        let reference = cpu::trace_rays(&scene, &camera_rays, false);
        // Agreement per tree (deterministic), then timed rounds.
        // (Every tree fits the traversal stack: `Bvh::from_binary` checks.)
        let mut facts = Vec::new();
        for bvh in &trees {
            scene.replace_bvh(bvh.clone());
            facts.push(common::agreement(
                &reference,
                &cpu::trace_rays(&scene, &camera_rays, false),
            ));
        }
        let mut trace_best = Vec::new();
        {
            // Round-robin over the trees after a warm-up round, as for builds
            // (the tree is moved into the scene, not copied, between runs).
            let mut per = vec![Vec::new(); trees.len()];
            let rounds = if big { 4 } else { 7 };
            for round in 0..=rounds {
                for i in 0..trees.len() {
                    scene.replace_bvh(std::mem::take(&mut trees[i]));
                    let start = Instant::now();
                    black_box(cpu::trace_rays(&scene, &camera_rays, false));
                    let t = start.elapsed();
                    trees[i] = scene.replace_bvh(Default::default());
                    if round > 0 {
                        per[i].push(t);
                    }
                }
            }
            for times in per {
                let min = *times.iter().min().unwrap();
                trace_best.push((min, median(times)));
            }
        }

        for (i, ((label, _), bvh)) in builders.iter().zip(&trees).enumerate() {
            let depth = bvh.depth();
            let (leaves, refs) = common::leaf_stats(bvh);
            let sah = bvh.sah_cost();
            let nodes = bvh.nodes.len();
            let bt = &build_times[i];
            let mrays = |t: Duration| camera_rays.len() as f64 / t.as_secs_f64() / 1e6;
            let (best, med) = trace_best[i];
            let agree = &facts[i];
            let speed = format!("{:.2} | {:.2}", mrays(best), mrays(med));
            let agree = format!("{} / {} / {}", agree.same_prim, agree.tie, agree.differ);
            println!(
                "| {name} | {tris} | {label} | {:.1} | {:.1} | {sah:.2} | {depth} | {nodes} | {leaves} | {refs} | {speed} | {agree} |",
                ms(*bt.iter().min().unwrap()),
                ms(median(bt.clone())),
            );
        }
    }
}
