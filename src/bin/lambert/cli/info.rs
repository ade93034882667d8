//! `lambert info`: the adapters and CPU kernels, or what a model holds.

use std::path::Path;
use std::process::ExitCode;

use super::AdapterArgs;
use lambert::cpu;
use lambert::error::{Error, Result};
use lambert::gpu;
use lambert::scene::Scene;

/// `lambert info MODEL`.
pub(super) fn model_info(path: &Path, camera: Option<&str>) -> Result<ExitCode> {
    let scene = Scene::load_with_camera(path, camera)?;
    println!("{}", path.display());
    println!("  triangles: {}", scene.triangles().len());
    if !scene.spheres().is_empty() {
        println!("  spheres: {}", scene.spheres().len());
    }
    if let Some(b) = scene.bvh().bounds() {
        // The BVH's bounds are local (relative to the offset): world ones
        // are printed, and the centre the geometry is kept relative to.
        let world = |p: glam::Vec3| lambert::limits::vector_text(p.as_dvec3() + scene.offset());
        let centre = if scene.offset() == glam::DVec3::ZERO {
            String::new()
        } else {
            format!(
                " (kept in f32 relative to the centre {})",
                lambert::limits::vector_text(scene.offset())
            )
        };
        println!("  bounds: {} to {}{centre}", world(b.min), world(b.max));
    }
    // The trees checked as they are measured: a failure is a builder's bug,
    // reported rather than printed as statistics.
    let invalid = |e: lambert::bvh::Invalid| Error::scene(path, format!("{e} (a bug in lambert)"));
    let bvh = scene
        .bvh()
        .validate(scene.triangles(), scene.spheres())
        .map_err(invalid)?;
    println!("  BVH (CPU): {bvh}");
    let compressed = lambert::cwbvh::compress(scene.bvh());
    let compressed = lambert::cwbvh::validate(&compressed, scene.bvh()).map_err(invalid)?;
    println!("  compressed BVH (GPU): {compressed}");
    let smooth = !scene.normals().is_empty();
    println!(
        "  normals: {}",
        if smooth {
            "smooth (the file's)"
        } else {
            "face"
        }
    );
    println!(
        "  vertex colours: {}",
        match scene.colored_triangles() {
            0 => "none".to_string(),
            n => format!("yes, on {n} of {} triangles", scene.triangles().len()),
        }
    );
    println!("  materials: {}", scene.materials().len());
    for (i, m) in scene.materials().iter().enumerate().take(32) {
        let [r, g, b, a] = m.base_color;
        let mut line = format!("    {i}: base colour [{r}, {g}, {b}], alpha {a}");
        if m.alpha_mode == lambert::layout::ALPHA_MASK {
            line += &format!(", alpha mode MASK (cut-off {})", m.alpha_cutoff);
        } else {
            line += ", alpha mode OPAQUE";
        }
        if m.emission != [0.0; 3] {
            let [r, g, b] = m.emission;
            line += &format!(", emissive [{r}, {g}, {b}]");
        }
        if m.kind == lambert::layout::MATERIAL_METALLIC_ROUGHNESS {
            line += &format!(", metallic {}, roughness {}", m.metallic, m.roughness);
            if m.metallic_roughness_texture != lambert::layout::NO_TEXTURE {
                line += " (× the metallic-roughness texture)";
            }
        } else {
            line += ", Lambert";
        }
        if m.normal_texture != lambert::layout::NO_TEXTURE {
            line += &format!(", normal map (scale {})", m.normal_scale);
        }
        println!("{line}");
    }
    let textures = scene.textures().images();
    println!("  textures: {}", textures.len());
    for (t, image) in textures.iter().enumerate() {
        // Which materials read it, and as what.
        let users: Vec<String> = scene
            .materials()
            .iter()
            .enumerate()
            .flat_map(|(i, m)| {
                [
                    (m.base_color_texture, "base colour"),
                    (m.emissive_texture, "emissive"),
                    (m.alpha_texture, "alpha"),
                    (m.metallic_roughness_texture, "metallic-roughness"),
                    (m.normal_texture, "normal"),
                ]
                .into_iter()
                .filter(|&(slot, _)| {
                    slot != lambert::layout::NO_TEXTURE
                        && scene.textures().image_of_slot(slot) == Some(t)
                })
                .map(move |(_, role)| format!("{i} ({role})"))
            })
            .collect();
        println!(
            "    {t}: {}, {}×{} {}, {} mip levels, used by material{} {}",
            image.name,
            image.width,
            image.height,
            image.format,
            image.level_count,
            if users.len() == 1 { "" } else { "s" },
            users.join(", ")
        );
    }
    let emissive = scene
        .materials()
        .iter()
        .filter(|m| m.emission != [0.0; 3])
        .count();
    println!("  emissive materials: {emissive}");
    let c = &scene.view().camera;
    let v = |a: [f64; 3]| lambert::limits::vector_text(glam::DVec3::from(a));
    println!(
        "  camera: eye {}, look_at {}, up {}, vfov {:.4}°, {}×{}",
        v(c.eye),
        v(c.look_at),
        v(c.up),
        c.vfov,
        c.width,
        c.height
    );
    println!("  lights: {}", scene.lights().len());
    for light in scene.lights() {
        let vector = lambert::limits::vector_text(glam::Vec3::from(light.vector).as_dvec3());
        let color = lambert::limits::vector_text(glam::Vec3::from(light.color).as_dvec3());
        if light.kind == lambert::layout::LIGHT_POINT {
            println!("    point at {vector}, intensity {color}");
        } else if light.kind == lambert::layout::LIGHT_SPOT {
            let direction =
                lambert::limits::vector_text(glam::Vec3::from(light.direction).as_dvec3());
            let angle = |cos: f32| cos.clamp(-1.0, 1.0).acos().to_degrees();
            println!(
                "    spot at {vector} pointing {direction}, intensity {color}, cones {:.2}° to \
                 {:.2}°",
                angle(light.cos_inner),
                angle(light.cos_outer)
            );
        } else {
            println!("    directional towards {vector} (from the surface), irradiance {color}");
        }
    }
    if let Some(e) = scene.environment() {
        let what = match (&e.map, e.file()) {
            (Some(map), Some(file)) => {
                format!("{} ({} × {} texels)", file.display(), map.width, map.height)
            }
            _ => format!("colour {:?}", e.color),
        };
        println!(
            "  environment (path integrator only): {what}, strength {}, turned {}° about +Y",
            e.spec.strength, e.spec.rotation_deg
        );
    }
    let table = scene.emitters();
    println!(
        "  emitters (path integrator): {} ({} emissive triangles)",
        table.entries.len(),
        table.uniform.num_triangle_emitters
    );
    // f32 values, printed as f32 (0.1, not 0.10000000149011612).
    println!("  ambient: {:?}", scene.ambient());
    for warning in scene.warnings() {
        println!("  warning: {warning}");
    }
    Ok(ExitCode::SUCCESS)
}

pub(super) fn info(args: &AdapterArgs) -> Result<ExitCode> {
    let request = args.request();
    let all = gpu::enumerate_adapters(&request)?;
    let none_at_all = all.is_empty();
    let adapters: Vec<_> = all
        .into_iter()
        .filter(|a| request.matches(&a.get_info()))
        .collect();
    let kernel = cpu::CpuKernel::active();
    println!(
        "CPU path: {} threads, {} kernel",
        rayon::current_num_threads(),
        kernel.name()
    );
    let packets = kernel.narrow_on_intel();
    if packets != kernel {
        println!(
            "  coherent rays' packets: {} kernel (512-bit instructions slow an Intel core)",
            packets.name()
        );
    }
    for other in cpu::CpuKernel::ALL {
        if let Some(missing) = other.missing() {
            println!(
                "  {} kernel: not on this CPU (needs {missing})",
                other.name()
            );
        } else if other > kernel {
            println!(
                "  {} kernel: available, not chosen (LAMBERT_CPU_KERNEL)",
                other.name()
            );
        }
    }
    if adapters.is_empty() {
        let wanted = request.describe_request()?;
        let wanted = if wanted.is_empty() {
            String::new()
        } else {
            format!(" {wanted}")
        };
        if none_at_all && request.wants_vulkan()? && cfg!(target_os = "linux") {
            println!(
                "no GPU adapters{wanted} (for a software one, install Mesa's lavapipe: apt-get install mesa-vulkan-drivers)"
            );
        } else {
            println!("no GPU adapters{wanted}");
        }
    }
    for adapter in adapters {
        let info = adapter.get_info();
        let limits = adapter.limits();
        println!("adapter: {}", info.name);
        println!(
            "  backend: {:?}, type: {:?}",
            info.backend, info.device_type
        );
        println!("  driver: {} {}", info.driver, info.driver_info);
        println!(
            "  limits: storage binding {} MiB, buffer {} MiB, texture 2D {} px, workgroup invocations {}",
            limits.max_storage_buffer_binding_size >> 20,
            limits.max_buffer_size >> 20,
            limits.max_texture_dimension_2d,
            limits.max_compute_invocations_per_workgroup
        );
        println!(
            "  timestamp queries: {}",
            adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY)
        );
        println!(
            "  ray queries (--accel hardware): {}",
            gpu::offers_ray_queries(&adapter)
        );
        if let Some(why) = gpu::cannot_run(&adapter) {
            println!("  cannot run lambert: {why}");
        }
    }
    Ok(ExitCode::SUCCESS)
}
