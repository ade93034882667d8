//! `lambert bench`: the model ladder and --time-vs-error.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::BenchArgs;
use lambert::bench::{self, BenchDevices};
use lambert::error::{Error, Result};
use lambert::gpu::Gpu;
use lambert::limits::{MAX_SPP, validate_spp};

/// The inputs `args` names, or else `defaults`'s, checked against the
/// outputs.
fn inputs_or(
    args: &BenchArgs,
    defaults: impl FnOnce() -> Result<Vec<PathBuf>>,
) -> Result<Vec<PathBuf>> {
    let inputs = if args.inputs.is_empty() {
        defaults()?
    } else {
        args.inputs.clone()
    };
    check_inputs_and_outputs(&inputs, args)?;
    Ok(inputs)
}

pub(super) fn bench(args: &BenchArgs, quiet: bool) -> Result<ExitCode> {
    if args.time_vs_error {
        return bench_time_vs_error(args, quiet);
    }
    let inputs = inputs_or(args, || {
        let ladder = bench::default_inputs();
        if ladder.is_empty() {
            return Err(Error::Usage(
                "lambert bench needs models to trace: name scene (.toml) or model (.obj) files; \
                 by default it traces ../shared/models, or the bundled models of lambert's \
                 source tree (assets/scenes/meshes), and found neither from here or from the \
                 executable's folder"
                    .into(),
            ));
        }
        Ok(ladder)
    })?;
    let request = args.adapter.request();
    let mut rows = Vec::new();
    println!(
        "{:<18} {:>9} {:>11} {:>11} {:>8} {:>7} {:>6} {:>9} {:>8}  device",
        "model", "triangles", "primary", "shadow", "build", "SAH", "depth", "memory", "B/tri"
    );
    println!(
        "{:<18} {:>9} {:>11} {:>11} {:>8} {:>7} {:>6} {:>9} {:>8}",
        "", "", "Mrays/s", "Mrays/s", "s", "", "", "MiB", ""
    );
    for (input, name) in inputs.iter().zip(input_names(&inputs)) {
        let mut scene = bench::load_input(input, args.size)?;
        if let Some(accel) = args.accel {
            let mut settings = scene.default_settings();
            settings.accel = accel.into();
            scene = scene.with_settings(&settings);
        }
        let scene = std::sync::Arc::new(scene);
        check_scene_inputs(&scene, args)?;
        for row in bench::ladder_rows(&name, &scene, args.device.into(), &request, args.runs)? {
            println!(
                "{:<18} {:>9} {:>11.2} {:>11.2} {:>8.3} {:>7.1} {:>6} {:>9.1} {:>8.1}  {}",
                row.model,
                row.triangles,
                row.primary_mrays_per_s,
                row.shadow_mrays_per_s,
                row.bvh_build_seconds,
                row.sah_cost,
                row.bvh_depth,
                row.device_bytes as f64 / (1 << 20) as f64,
                row.device_bytes_per_triangle,
                row.device
            );
            rows.push(row);
        }
    }
    if let Some(path) = &args.json {
        write_json(path, &rows)?;
    }
    if let Some(dir) = &args.plot {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        crate::plot::ladder(&rows, &dir.join("time_per_ray"))?;
    }
    Ok(ExitCode::SUCCESS)
}

/// Before any work: every input exists, and every output (--json, --plot)
/// can be written.
fn check_inputs_and_outputs(inputs: &[PathBuf], args: &BenchArgs) -> Result<()> {
    if let Some(missing) = inputs.iter().find(|p| !p.exists()) {
        return Err(Error::Usage(format!("{}: no such file", missing.display())));
    }
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    if let Some(path) = &args.json {
        lambert::output::prepare_output_for(path, &inputs)?;
    }
    if let Some(dir) = &args.plot {
        if dir.exists() && !dir.is_dir() {
            return Err(Error::Usage(format!(
                "--plot {}: is a file, not a folder; --plot names the folder the plots are \
                 written into (time_per_ray.png, time_vs_error_NAME.png, …): name a new or \
                 existing folder",
                dir.display()
            )));
        }
        lambert::output::prepare_output_for(&dir.join("time_per_ray.png"), &inputs)?;
    }
    Ok(())
}

/// --json is none of the files `scene` was read from (a mesh, an MTL
/// file, a texture): checked once it is loaded, before anything is written.
fn check_scene_inputs(scene: &lambert::scene::Scene, args: &BenchArgs) -> Result<()> {
    match &args.json {
        Some(path) => scene.check_output(path),
        None => Ok(()),
    }
}

/// The bench inputs' names in tables, JSON and plots: each file's name
/// without extension, or, where two share one (`a/scene.toml` and
/// `b/scene.toml`), each path from the inputs' common folder without
/// extension (`a/scene`, `b/scene`), so that no plot replaces another and
/// no two results read alike.
fn input_names(paths: &[PathBuf]) -> Vec<String> {
    let stems: Vec<String> = paths
        .iter()
        .map(|p| {
            p.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        })
        .collect();
    let distinct = |names: &[String]| {
        names.iter().collect::<std::collections::HashSet<_>>().len() == names.len()
    };
    if distinct(&stems) {
        return stems;
    }
    let absolute: Vec<PathBuf> = paths
        .iter()
        .map(|p| std::path::absolute(p).unwrap_or_else(|_| p.clone()))
        .collect();
    let mut common: PathBuf = absolute[0].parent().unwrap_or(Path::new("")).to_path_buf();
    while !absolute.iter().all(|p| p.starts_with(&common)) && common.pop() {}
    let relative: Vec<String> = absolute
        .iter()
        .map(|p| {
            let from = p.strip_prefix(&common).unwrap_or(p);
            from.with_extension("").to_string_lossy().into_owned()
        })
        .collect();
    if distinct(&relative) {
        return relative;
    }
    // One file named twice: numbered in order.
    relative
        .iter()
        .enumerate()
        .map(|(i, name)| format!("{name}#{}", i + 1))
        .collect()
}

fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).expect("bench results serialise");
    lambert::output::write_atomically(path, text.as_bytes())
}

fn bench_time_vs_error(args: &BenchArgs, quiet: bool) -> Result<ExitCode> {
    bench::check_spp_list(&args.spp_list)?;
    let reference_spp = args
        .reference_spp
        .unwrap_or((4 * args.spp_list.iter().max().copied().unwrap_or(1)).min(MAX_SPP));
    validate_spp(reference_spp).map_err(|e| Error::Usage(format!("--reference-{e}")))?;
    let inputs = inputs_or(args, || {
        let tree = bench::source_tree().unwrap_or_default();
        let defaults: Vec<PathBuf> = ["edge_cases", "spheres", "triangle_oblique"]
            .iter()
            .map(|n| tree.join(format!("assets/scenes/{n}.toml")))
            .collect();
        if !defaults.iter().all(|p| p.exists()) {
            return Err(Error::Usage(
                "lambert bench --time-vs-error needs scenes to measure: name them; by default \
                 it measures the bundled scenes of lambert's source tree (assets/scenes), and \
                 found none from here or from the executable's folder"
                    .into(),
            ));
        }
        Ok(defaults)
    })?;
    let request = args.adapter.request();
    let devices = BenchDevices::from(args.device);
    let gpu = match devices {
        BenchDevices::Cpu => false,
        _ => match Gpu::open(&request, false) {
            Ok(_) => true,
            Err(e) if devices == BenchDevices::Both => {
                if !quiet {
                    eprintln!("{e}\nnote: measuring the CPU paths only");
                }
                false
            }
            Err(e) => return Err(e),
        },
    };
    let mut spp = args.spp_list.clone();
    spp.sort_unstable();
    spp.dedup();
    let knobs = bench::Knobs {
        spp,
        reference_spp,
        runs: args.runs,
        gpu,
    };
    let mut all = Vec::new();
    for (input, name) in inputs.iter().zip(input_names(&inputs)) {
        let scene = std::sync::Arc::new(bench::load_input(input, args.size)?);
        check_scene_inputs(&scene, args)?;
        let points = bench::time_vs_error(&name, &scene, &knobs, &request, &mut |line| {
            if !quiet {
                eprintln!("{line}")
            }
        })?;
        println!("{name}: Pareto front (fastest first)");
        let mut front: Vec<&bench::Point> = points.iter().filter(|p| p.on_pareto_front).collect();
        front.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
        for p in front {
            println!(
                "  {:?} {:<16} {:<8} spp {:>6.2} {:<11} {:<11} {:>9.4} s  RMSE {:.3e}  PSNR {}  leaks {}",
                p.path,
                p.intersect.name(),
                p.sampling,
                p.mean_spp,
                p.accel,
                p.shader,
                p.seconds,
                p.rmse,
                p.psnr_db
                    .map_or("inf".to_string(), |v| format!("{v:.1} dB")),
                p.leaks
            );
        }
        if let Some(target) = args.target_error {
            match bench::cheapest_within(&points, target) {
                Some(p) => println!(
                    "  cheapest within RMSE {target:e}: {:?} {} spp {} ({:.4} s, expected RMSE {:.3e})",
                    p.path,
                    p.intersect.name(),
                    p.spp,
                    p.seconds,
                    p.rmse
                ),
                None => println!("  no measured setting reaches RMSE {target:e}"),
            }
        }
        if let Some(dir) = &args.plot {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
            let stem = format!("time_vs_error_{}", name.replace(['/', '\\'], "_"));
            crate::plot::time_vs_error(&points, &dir.join(stem))?;
        }
        all.extend(points);
    }
    if let Some(path) = &args.json {
        write_json(path, &all)?;
    }
    Ok(ExitCode::SUCCESS)
}
