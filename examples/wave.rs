//! The wavefront render (shadow rays apart) against the megakernel and
//! against its rays traced alone, in one process: the scene loaded once,
//! then rounds in which each takes its turn (device time from timestamp
//! queries, and on Linux the process's CPU time, which on lavapipe is the
//! work itself and is disturbed far less than wall or device time when
//! other processes share the machine; medians and ranges).
//!
//! cargo run --release --example wave -- SCENE.toml [ROUNDS] [SPP] [path [SIDE]]
//!
//! With `path`, the scene path traced (its max_depth) at SIDE² (default:
//! the scene's size): the path integrator's wavefront against its
//! megakernel, no rays alone (a path's rays are not the camera's).
//!
//! "Rays alone" are the scene's camera rays (closest hit) and the shadow
//! rays of their hits towards its first light (any hit), as `lambert
//! bench` traces them (`trace_rays`); at 1 spp the render traces the same
//! camera rays and, with one light, about as many shadow rays (it spawns
//! one where the shading normal faces the light, bench where the geometric
//! one does).

use std::time::Duration;

use lambert::Scene;
use lambert::gpu::{AdapterRequest, ShadowDispatch};
use lambert::progress::Progress;
use lambert::scene::{Integrator, RenderSettings};

fn main() -> lambert::Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .expect("usage: wave SCENE.toml [ROUNDS] [SPP] [path [SIDE]]");
    let rounds: usize = args.next().map_or(5, |a| a.parse().expect("rounds"));
    let mut scene = Scene::load(std::path::Path::new(&path))?;
    if let Some(spp) = args.next() {
        scene.view_mut().spp = spp.parse().expect("spp");
    }
    let path_traced = args.next().is_some_and(|a| a == "path");
    if path_traced {
        let settings = RenderSettings {
            integrator: Integrator::Path,
            ..scene.default_settings()
        };
        scene = scene.with_settings(&settings);
        if let Some(side) = args.next() {
            let side = Some(side.parse().expect("side"));
            let camera = scene.view().camera.resized(side, side).expect("side");
            scene.view_mut().camera = camera;
        }
    }
    // The rays alone where they are what the render traces.
    let turns = if path_traced { 2 } else { 3 };
    let request = AdapterRequest::default().with_environment(|v| std::env::var(v).ok());
    let mut gpu = lambert::render::open_gpu(&scene, &request)?;
    // The rays alone on a renderer of their own: a ray query's timestamps
    // after a render on the same one read as microseconds on lavapipe
    // (not understood yet; the hits were right).
    let mut tracer = lambert::render::open_gpu(&scene, &request)?;
    let primary = lambert::rays::camera_rays(&scene);
    let shadow = if path_traced {
        Vec::new()
    } else {
        let hits = lambert::cpu::trace_rays(&scene, &primary, false);
        lambert::bench::shadow_rays(&scene, &primary, &hits)
    };
    println!(
        "{path}: {}x{} at {} spp, {} camera rays, {} shadow rays traced alone; {}",
        scene.view().camera.width,
        scene.view().camera.height,
        scene.view().spp,
        primary.len(),
        shadow.len(),
        gpu.gpu().describe()
    );
    let hidden = Progress::hidden();
    let mut times: [Vec<Duration>; 3] = Default::default();
    let mut cpu_times: [Vec<Duration>; 3] = Default::default();
    // One warm-up of each (pipelines built), not counted.
    for round in 0..=rounds {
        for turn in 0..turns {
            let which = (turn + round) % turns;
            let cpu_before = process_cpu_time();
            let t = if which < 2 {
                gpu.shadow_dispatch =
                    [ShadowDispatch::Wavefront, ShadowDispatch::Megakernel][which];
                gpu.render(scene.view(), &hidden)?.1.device
            } else {
                tracer.trace_rays(&primary, false, scene.default_settings().intersect)?;
                let p = tracer.trace_device_time();
                tracer.trace_rays(&shadow, true, scene.default_settings().intersect)?;
                p.zip(tracer.trace_device_time()).map(|(p, s)| p + s)
            };
            let t = t.expect("timestamp queries on this adapter");
            let cpu = process_cpu_time().zip(cpu_before).map(|(a, b)| a - b);
            if round > 0 {
                times[which].push(t);
                cpu_times[which].extend(cpu);
            }
        }
    }
    report("device time", &mut times);
    if cpu_times[0].len() == rounds {
        report("CPU time", &mut cpu_times);
    }
    Ok(())
}

/// Each renderer's median and range, and its median over the rays alone'
/// (where they were traced).
fn report(what: &str, times: &mut [Vec<Duration>; 3]) {
    let median = |v: &[Duration]| v[v.len() / 2].as_secs_f64();
    times.iter_mut().for_each(|t| t.sort());
    let alone = if times[2].is_empty() {
        f64::NAN
    } else {
        median(&times[2])
    };
    println!("{what}:");
    for (name, t) in ["wavefront", "megakernel", "rays alone"]
        .iter()
        .zip(times.iter())
        .filter(|(_, t)| !t.is_empty())
    {
        let m = median(t);
        let ratio = if alone.is_nan() {
            String::new()
        } else {
            format!(", {:.2}x the rays alone", m / alone)
        };
        println!(
            "  {name:<11} {m:.3} s ({:.3}–{:.3}){ratio}",
            t[0].as_secs_f64(),
            t[t.len() - 1].as_secs_f64(),
        );
    }
}

/// The process's user and system time, all threads (Linux: /proc/self/stat,
/// in clock ticks of 10 ms); None elsewhere.
fn process_cpu_time() -> Option<Duration> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces), from field 3.
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks: u64 = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
    Some(Duration::from_millis(ticks * 10))
}
