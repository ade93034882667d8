//! Peak host and device memory of loading and rendering a large scene, in
//! bytes per triangle (docs/benchmarks.md, "Memory").
//!
//! cargo run --release --example memory -- [MODEL…]
//!
//! With no MODEL: the Stanford dragon (871k triangles) from
//! ../shared/models/dragon.obj when it is there, and the 5M-triangle
//! scene of examples/large_scene.rs (an icosphere of 9 subdivisions).
//! Each scene is measured in its own process (this one, re-run per scene),
//! so that one's peak is not the next one's floor.
//!
//! Host heap bytes are counted by `lambert::memory::Counting`; the
//! resident set (RSS) is the kernel's, and includes what a software
//! adapter such as lavapipe allocates as "device" memory.

use std::path::{Path, PathBuf};
use std::time::Instant;

use lambert::gpu::{AdapterRequest, Gpu, GpuRenderer};
use lambert::progress::Progress;
use lambert::{Scene, cpu, memory, probe};

#[global_allocator]
static ALLOCATOR: memory::Counting = memory::Counting;

const SIZE: u32 = 512;

fn mib(bytes: u64) -> String {
    format!("{:.0} MiB", bytes as f64 / (1u64 << 20) as f64)
}

/// The bytes the render needs of the scene: its arrays as the GPU and the
/// CPU path read them.
fn scene_bytes(scene: &Scene) -> u64 {
    use std::mem::size_of_val;
    (size_of_val(&scene.triangles()[..])
        + size_of_val(&scene.normals()[..])
        + size_of_val(&scene.spheres()[..])
        + size_of_val(&scene.materials()[..])
        + size_of_val(&scene.lights()[..])
        + size_of_val(&scene.bvh().nodes[..])
        + size_of_val(&scene.bvh().blocks[..])) as u64
}

/// Heap bytes of the phase just run: (peak, live after), and the peak RSS.
struct Phase {
    name: &'static str,
    peak_heap: u64,
    live_heap: u64,
    peak_rss: u64,
    seconds: f64,
}

fn measure<T>(name: &'static str, phases: &mut Vec<Phase>, work: impl FnOnce() -> T) -> T {
    memory::reset_peak();
    memory::reset_resident_peak();
    let start = Instant::now();
    let result = work();
    let seconds = start.elapsed().as_secs_f64();
    phases.push(Phase {
        name,
        peak_heap: memory::peak() as u64,
        live_heap: memory::live() as u64,
        peak_rss: memory::resident().map_or(0, |r| r.1),
        seconds,
    });
    result
}

fn icosphere_scene() -> Scene {
    use lambert::layout::Triangle;
    let (vertices, faces) = probe::icosphere(1.0, 9);
    let triangles: Vec<Triangle> = faces
        .iter()
        .map(|f| {
            let [v0, v1, v2] = f.map(|i| vertices[i as usize].as_vec3().to_array());
            Triangle {
                v0,
                v1,
                v2,
                ..Default::default()
            }
        })
        .collect();
    drop((vertices, faces));
    let mut scene = Scene::from_triangles(triangles);
    // A sphere: never flat.
    scene.view_mut().camera =
        lambert::camera::frame_camera(&(glam::DVec3::splat(-1.0), glam::DVec3::ONE), None);
    let light = lambert::camera::default_light(&scene.view().camera);
    scene.lights_mut().push(light);
    scene
}

fn run(model: &str) -> lambert::Result<()> {
    let mut phases = Vec::new();
    let baseline = memory::live() as u64;
    let mut scene = measure("load", &mut phases, || {
        if model == "icosphere9" {
            Ok(icosphere_scene())
        } else {
            Scene::load(Path::new(model))
        }
    })?;
    scene.view_mut().camera.width = SIZE;
    scene.view_mut().camera.height = SIZE;
    let triangles = scene.triangles().len() as u64;
    let needed = scene_bytes(&scene);
    let after_load = memory::live() as u64 - baseline;
    measure("CPU render", &mut phases, || {
        cpu::render(
            &scene,
            scene.view(),
            cpu::Precision::F32,
            &Progress::hidden(),
        )
    });
    let gpu = Gpu::open(&AdapterRequest::default(), false)?;
    let adapter = gpu.describe();
    let mut renderer = measure("GPU upload", &mut phases, || GpuRenderer::new(gpu, &scene))?;
    let device_bytes = renderer.device_bytes;
    measure("GPU render", &mut phases, || {
        renderer.render(scene.view(), &Progress::hidden()).map(drop)
    })?;

    let name = Path::new(model)
        .file_name()
        .map_or(model.to_string(), |n| n.to_string_lossy().into_owned());
    println!("\n{name}: {triangles} triangles, {SIZE}×{SIZE} at 1 spp; adapter {adapter}");
    println!(
        "scene arrays the render reads: {} ({:.1} B/triangle); heap live after loading: {} \
         ({:.1} B/triangle, {:+.1}% of the arrays: Vec capacity and the scene's small fields)",
        mib(needed),
        needed as f64 / triangles as f64,
        mib(after_load),
        after_load as f64 / triangles as f64,
        100.0 * (after_load as f64 / needed as f64 - 1.0)
    );
    println!(
        "device buffers: {} ({:.1} B/triangle)",
        mib(device_bytes),
        device_bytes as f64 / triangles as f64
    );
    println!("| phase | time | peak heap | B/tri | heap live after | B/tri | peak RSS | B/tri |");
    println!("|---|---|---|---|---|---|---|---|");
    for p in &phases {
        let per = |b: u64| format!("{:.0}", b as f64 / triangles as f64);
        println!(
            "| {} | {:.2} s | {} | {} | {} | {} | {} | {} |",
            p.name,
            p.seconds,
            mib(p.peak_heap),
            per(p.peak_heap),
            mib(p.live_heap),
            per(p.live_heap),
            mib(p.peak_rss),
            per(p.peak_rss)
        );
    }
    Ok(())
}

fn main() -> lambert::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let [model] = &args[..] {
        return run(model);
    }
    let mut models = args;
    if models.is_empty() {
        let dragon = PathBuf::from("../shared/models/dragon.obj");
        if dragon.exists() {
            models.push(dragon.display().to_string());
        } else {
            eprintln!(
                "{}: not there; measuring the 5M-triangle scene only",
                dragon.display()
            );
        }
        models.push("icosphere9".into());
    }
    // One process per scene: peaks (heap and RSS) start from nothing.
    for model in models {
        let status = std::process::Command::new(std::env::current_exe().unwrap())
            .arg(&model)
            .status()
            .map_err(|e| lambert::Error::Usage(format!("re-running for {model}: {e}")))?;
        if !status.success() {
            return Err(lambert::Error::Usage(format!(
                "{model}: the measurement failed"
            )));
        }
    }
    Ok(())
}
