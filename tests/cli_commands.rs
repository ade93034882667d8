//! The `lambert` binary's commands and options across the board: the CPU kernel variable, lights and ambient, outputs never over inputs, `-q`, turntable names, diff heatmaps, bench's scenes, info's tree statistics.

mod common;

use std::path::{Path, PathBuf};

use common::args::{CHEAPEST_BENCH, trace_args, turntable_args};
use common::cli::*;
use common::{lambert, lambert_command, s};

/// `LAMBERT_CPU_KERNEL` is read by the binary, not the library: `info`
/// reports the kernel it names (or the widest narrower one the CPU has),
/// the packets' narrower one where it differs, and the wider ones as not
/// chosen; a name that is no kernel's leaves the
/// widest.
#[test]
fn the_cpu_kernel_variable_reaches_the_cli() {
    use lambert::cpu::{CPU_KERNEL_ENV, CpuKernel};
    let info = |value: &str| {
        let out = lambert_command()
            .arg("info")
            .env(CPU_KERNEL_ENV, value)
            .output()
            .unwrap();
        assert!(out.status.success(), "{out:?}");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let text = info("Portable");
    assert!(text.contains(", portable kernel"), "{text}");
    let best = CpuKernel::detect();
    if best > CpuKernel::Portable {
        let wider = format!("{} kernel: available, not chosen", best.name());
        assert!(text.contains(&wider), "{text}");
    }
    let text = info("no such kernel");
    assert!(
        text.contains(&format!(", {} kernel", best.name())),
        "{text}"
    );
    // The packets' own kernel, where it differs (AVX-512 on Intel).
    let packets = format!(
        "coherent rays' packets: {} kernel",
        best.narrow_on_intel().name()
    );
    assert_eq!(
        text.contains(&packets),
        best.narrow_on_intel() != best,
        "{text}"
    );
    assert_eq!(
        CpuKernel::narrowed_to(Some("AVX-512")),
        best.min(CpuKernel::Avx512)
    );
    assert_eq!(
        CpuKernel::narrowed_to(Some("avx2+fma")),
        best.min(CpuKernel::Avx2Fma)
    );
    assert_eq!(CpuKernel::narrowed_to(None), best);
}

/// A headless machine's commands print no line that says "error" unless
/// something failed (Mesa's device-select layer printed two about
/// XDG_RUNTIME_DIR), and `info` names the CPU kernel in use.
#[test]
fn successful_commands_print_no_error_lines() {
    let (case, scene) = Case::lit_sphere();
    let out = case.path("out.png");
    let runs = [
        vec!["info"],
        vec!["render", s(&scene), "-o", s(&out), "--device", "gpu"],
        vec!["render", s(&scene), "-o", s(&out)],
    ];
    for args in runs {
        // As on a headless CI machine.
        let output = lambert_command()
            .env_remove("XDG_RUNTIME_DIR")
            .env_remove("WAYLAND_DISPLAY")
            .args(&args)
            .output()
            .unwrap();
        assert!(output.status.success(), "{args:?}: {output:?}");
        let text = String::from_utf8_lossy(&output.stdout).to_string()
            + &String::from_utf8_lossy(&output.stderr);
        for line in text.lines() {
            assert!(
                !line.to_lowercase().contains("error"),
                "{args:?} printed {line:?}"
            );
        }
        if args == ["info"] {
            // The kernel the CLI chose from the environment, as it reads it.
            let asked = std::env::var(lambert::cpu::CPU_KERNEL_ENV).ok();
            let kernel = lambert::cpu::CpuKernel::narrowed_to(asked.as_deref()).name();
            assert!(text.contains(&format!("{kernel} kernel")), "{text}");
        }
    }
}

/// A glTF quad of albedo 0.5 in the plane z = 0, facing +z (where the
/// framed camera looks from), with `lights` as KHR_lights_punctual lights
/// placed at the given positions.
fn quad_gltf(case: &Case, name: &str, lights: &[([f64; 3], f64)]) -> PathBuf {
    let mut bytes = Vec::new();
    for v in [
        [-1.0f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ] {
        bytes.extend(v.iter().flat_map(|c| c.to_le_bytes()));
    }
    bytes.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(case.path(&format!("{name}.bin")), &bytes).unwrap();
    let light_defs: Vec<String> = lights
        .iter()
        .map(|(_, i)| format!(r#"{{"type": "point", "intensity": {i}}}"#))
        .collect();
    let light_nodes: Vec<String> = lights
        .iter()
        .enumerate()
        .map(|(i, (p, _))| {
            format!(
                r#"{{"translation": [{}, {}, {}], "extensions": {{"KHR_lights_punctual": {{"light": {i}}}}}}}"#,
                p[0], p[1], p[2]
            )
        })
        .collect();
    let roots: Vec<String> = (0..=lights.len()).map(|i| i.to_string()).collect();
    let extensions = if lights.is_empty() {
        String::new()
    } else {
        format!(
            r#""extensionsUsed": ["KHR_lights_punctual"], "extensions": {{"KHR_lights_punctual": {{"lights": [{}]}}}},"#,
            light_defs.join(", ")
        )
    };
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, {extensions}
        "buffers": [{{"uri": "{name}.bin", "byteLength": 60}}],
        "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 12}}],
        "accessors": [
            {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]}},
            {{"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
        "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.5, 0.5, 1.0]}}}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
        "nodes": [{{"mesh": 0}}{}],
        "scenes": [{{"nodes": [{}]}}], "scene": 0}}"#,
        light_nodes
            .iter()
            .map(|n| format!(", {n}"))
            .collect::<String>(),
        roots.join(", ")
    );
    case.file(&format!("{name}.gltf"), &json)
}

/// Renders `model` (3×3, CPU) with `extra` options and returns the centre
/// pixel, whose camera ray passes through the model's centre.
fn centre_pixel(case: &Case, model: &Path, extra: &[&str]) -> [f32; 3] {
    let out = case.path("centre.exr");
    let mut args = vec!["render", s(model), "-o", s(&out), "--device", "cpu"];
    args.extend(["--width", "3", "--height", "3"]);
    args.extend(extra);
    let output = lambert(&args);
    assert!(output.status.success(), "{args:?}: {output:?}");
    image::open(&out).unwrap().to_rgb32f().get_pixel(1, 1).0
}

/// Issue 28 item 2: a file's lights are the scene's lights (no ambient
/// added to them); the default ambient belongs to a model with no light;
/// --ambient sets it for any render.
#[test]
fn a_models_own_lights_get_no_ambient_and_ambient_sets_it() {
    let case = Case::new();
    // Behind the quad: the face the camera sees faces away from it.
    let behind = quad_gltf(&case, "behind", &[([0.0, 0.0, -2.0], 4.0)]);
    assert_eq!(centre_pixel(&case, &behind, &[]), [0.0; 3]);
    let info = lambert(&["info", s(&behind)]);
    assert!(String::from_utf8_lossy(&info.stdout).contains("ambient: [0.0, 0.0, 0.0]"));
    // In front, 2 away: E = 4/2² = 1 candela's worth along the normal, so
    // 0.5 × 1/π (the glTF BRDF's diffuse lobe is albedo/π).
    let front = quad_gltf(&case, "front", &[([0.0, 0.0, 2.0], 4.0)]);
    for c in centre_pixel(&case, &front, &[]) {
        assert!((c - 0.5 / std::f32::consts::PI).abs() < 1e-4, "{c}");
    }
    // --ambient on the file's lights: albedo × ambient, per channel.
    let lit = centre_pixel(&case, &behind, &["--ambient", "0.2,0.3,0.4"]);
    for (c, e) in lit.iter().zip([0.1, 0.15, 0.2]) {
        assert!((c - e).abs() < 1e-6, "{lit:?}");
    }
    assert_eq!(
        centre_pixel(&case, &behind, &["--ambient", "0.2"]),
        centre_pixel(&case, &behind, &["--ambient", "0.2,0.2,0.2"])
    );

    // No lights: the default light and the default ambient 0.1, which
    // --ambient replaces.
    let bare = quad_gltf(&case, "bare", &[]);
    let info = lambert(&["info", s(&bare)]);
    assert!(String::from_utf8_lossy(&info.stdout).contains("ambient: [0.1, 0.1, 0.1]"));
    let default = centre_pixel(&case, &bare, &[]);
    assert_eq!(default, centre_pixel(&case, &bare, &["--ambient", "0.1"]));
    let without = centre_pixel(&case, &bare, &["--ambient", "0"]);
    for (d, w) in default.iter().zip(without) {
        assert!((d - w - 0.05).abs() < 1e-6, "{default:?} {without:?}");
    }

    // A TOML scene's render.ambient is overridden too (no light: ambient alone).
    let scene = case.file(
        "ambient.toml",
        &format!("{CAMERA}{SPHERE}[render]\nambient = [0.5, 0.5, 0.5]\n"),
    );
    let out = case.path("toml.exr");
    let render = |extra: &[&str]| {
        let mut args = vec!["render", s(&scene), "-o", s(&out), "--device", "cpu"];
        args.extend(extra);
        assert!(lambert(&args).status.success());
        image::open(&out).unwrap().to_rgb32f().get_pixel(8, 6).0
    };
    let [full, half] = [render(&[]), render(&["--ambient", "0.25"])];
    assert!(full[0] > 0.0);
    assert_eq!(full.map(|c| c / 2.0), half);

    // Bad values are refused by the option's parser.
    for bad in ["-1", "1,2", "nan", "a,b,c"] {
        let output = lambert(&["render", s(&bare), "-o", s(&out), "--ambient", bad]);
        assert_eq!(output.status.code(), Some(2), "{bad}: {output:?}");
    }
}

/// Issue 28 item 15: no command writes its output over one of its inputs
/// (by name, through a symlink or a hard link); it says so and writes
/// nothing.
#[test]
fn no_output_is_written_over_an_input() {
    let case = Case::new();
    let scene_text = format!("{CAMERA}{SPHERE}{LIGHT}");
    let scene = case.file("scene.toml", &scene_text);
    let obj = case.file("tri.obj", TRIANGLE_OBJ);
    let ray: Vec<u8> = [0.25f32, 0.25, 1.0, 0.0, 0.0, 0.0, -1.0, f32::INFINITY]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let rays = case.path("rays.bin");
    std::fs::write(&rays, &ray).unwrap();
    // Image names for the scene file, as a user's link might give them.
    let scene_png = case.path("scene.png");
    std::os::unix::fs::symlink(&scene, &scene_png).unwrap();
    let scene_exr = case.path("scene.exr");
    std::fs::hard_link(&scene, &scene_exr).unwrap();
    let obj_bin = case.path("obj.bin");
    std::os::unix::fs::symlink(&obj, &obj_bin).unwrap();
    let cpu = ["--device", "cpu"];
    let runs: Vec<(Vec<&str>, &Path)> = vec![
        (
            [&["render", s(&scene), "-o", s(&scene_png)][..], &cpu].concat(),
            &scene_png,
        ),
        (
            [&["render", s(&scene), "-o", s(&scene_exr)][..], &cpu].concat(),
            &scene_exr,
        ),
        (
            vec!["render", s(&scene), "--tile", "0/2", "-o", s(&scene_exr)],
            &scene_exr,
        ),
        (
            vec![
                "diff",
                s(&scene),
                "--compare",
                "cpu-oracle",
                "--heatmap",
                s(&scene_png),
            ],
            &scene_png,
        ),
        ([&trace_args(&obj, &rays, &rays)[..], &cpu].concat(), &rays),
        (trace_args(&obj, &rays, &obj_bin), &obj_bin),
        (vec!["camera-rays", s(&scene), "-o", s(&scene)], &scene),
    ];
    for (args, output) in runs {
        let out = lambert(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let expected_code = if args[0] == "diff" { 2 } else { 1 };
        assert_eq!(out.status.code(), Some(expected_code), "{args:?}: {stderr}");
        assert!(
            stderr.contains("the output is one of the inputs") && stderr.contains(s(output)),
            "{args:?}: {stderr}"
        );
        assert_eq!(std::fs::read_to_string(&scene).unwrap(), scene_text);
        assert_eq!(std::fs::read_to_string(&obj).unwrap(), TRIANGLE_OBJ);
        assert_eq!(std::fs::read(&rays).unwrap(), ray);
    }
    // A turntable whose later frame would land on the scene: refused before
    // the first frame is written.
    let frames = case.path("scene.{}.png");
    let frame1 = case.path("scene.1.png");
    std::os::unix::fs::symlink(&scene, &frame1).unwrap();
    let out = lambert(&turntable_args(&scene, "2", &frames));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("the output is one of the inputs"),
        "{stderr}"
    );
    assert!(!case.path("scene.0.png").exists());
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), scene_text);
}

/// Issue 28 item 16: `-q` is accepted by every command, before or after
/// its name, and silences notes (the CPU-fallback note of `trace`
/// included) but not results or errors.
#[test]
fn quiet_is_accepted_everywhere_and_silences_notes() {
    let (case, scene) = Case::lit_sphere();
    let obj = case.file("tri.obj", TRIANGLE_OBJ);
    let rays = case.path("rays.bin");
    let hits = case.path("hits.bin");
    let (part0, part1) = (case.path("part0.exr"), case.path("part1.exr"));
    let merged = case.path("merged.png");
    let camera_rays = ["camera-rays", s(&scene), "-o", s(&rays)];
    let trace = trace_args(&obj, &rays, &hits);
    let parts = [
        ["render", s(&scene), "--tile", "0/2", "-o", s(&part0)],
        ["render", s(&scene), "--tile", "1/2", "-o", s(&part1)],
    ];
    let merge = ["merge", s(&part0), s(&part1), "-o", s(&merged)];
    let diff = ["diff", s(&scene), "--compare", "cpu-oracle"];
    // Without -q each says something on stderr (trace: the note that no
    // hardware GPU was found, here where there is none, and its report).
    for args in [&camera_rays[..], &trace, &parts[0], &parts[1], &merge] {
        let out = lambert(args);
        assert!(out.status.success(), "{args:?}: {out:?}");
        assert!(!out.stderr.is_empty(), "{args:?}");
    }
    for args in [
        &camera_rays[..],
        &trace,
        &parts[0],
        &parts[1],
        &merge,
        &diff,
    ] {
        for quiet in [
            [&["-q"][..], args].concat(),
            [args, &["--quiet"][..]].concat(),
        ] {
            let out = lambert(&quiet);
            assert!(out.status.success(), "{quiet:?}: {out:?}");
            assert_eq!(String::from_utf8_lossy(&out.stderr), "", "{quiet:?}");
        }
    }
    // The result still goes to stdout, and an error is still an error.
    let out = lambert(&[&diff[..], &["-q"][..]].concat());
    assert!(String::from_utf8_lossy(&out.stdout).contains("pixels compared"));
    let out = lambert(&["-q", "merge", s(&part0), "-o", s(&merged)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.starts_with("error: "),
        "{stderr}"
    );
}

/// Issue 28 item 16: every placeholder of a turntable pattern is filled.
#[test]
fn turntable_fills_every_placeholder() {
    let (case, scene) = Case::lit_sphere();
    let pattern = case.path("f{}/frame_{:03}.png");
    let out = lambert(&[&turntable_args(&scene, "2", &pattern)[..], &["-q"]].concat());
    assert!(out.status.success(), "{out:?}");
    for frame in 0..2 {
        let path = case.path(&format!("f{frame}/frame_{frame:03}.png"));
        assert!(path.exists(), "{} missing", path.display());
    }
    assert!(!case.path("f{}").exists() && !case.path("f0/frame_{:03}.png").exists());
    let frames = lambert::jobs::frame_path(Path::new("a_{}_{:02}_{}.exr"), 7).unwrap();
    assert_eq!(frames, Path::new("a_7_07_7.exr"));
}

/// Issue 28 item 16: `diff --heatmap` writes every image format `render`
/// does, and its help says so.
#[test]
fn diff_heatmap_writes_png_exr_and_pfm() {
    let (case, scene) = Case::lit_sphere();
    for ext in ["png", "exr", "pfm"] {
        let heatmap = case.path(&format!("heat.{ext}"));
        let out = lambert(&[
            "diff",
            s(&scene),
            "--compare",
            "cpu-oracle",
            "--heatmap",
            s(&heatmap),
        ]);
        assert!(out.status.success(), "{ext}: {out:?}");
        assert!(std::fs::metadata(&heatmap).unwrap().len() > 0);
    }
    let help = String::from_utf8_lossy(&lambert(&["diff", "--help"]).stdout).into_owned();
    let line = help
        .lines()
        .skip_while(|l| !l.contains("--heatmap"))
        .take(3)
        .collect::<String>();
    assert!(
        [".png", ".exr", ".pfm"].iter().all(|f| line.contains(f)),
        "{line}"
    );
}

/// Issue 28 item 16: `lambert bench` outside the repository finds the
/// bundled scenes its help promises (beside the executable), and its
/// errors read as every other command's.
#[test]
fn bench_finds_the_bundled_scenes_from_any_folder() {
    let case = Case::new();
    let json = case.path("points.json");
    let out = lambert_command()
        .current_dir(case.dir.path())
        .args(CHEAPEST_BENCH)
        .args(["-q", "--json", s(&json)])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");
    let points: Vec<serde_json::Value> =
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    for scene in ["edge_cases", "spheres", "triangle_oblique"] {
        assert!(points.iter().any(|p| p["scene"] == scene), "{scene}");
    }
    let missing = case.path("missing.obj");
    let out = lambert_command()
        .current_dir(case.dir.path())
        .args(["bench", "--device", "cpu", s(&missing)])
        .output()
        .unwrap();
    expect_failure(&out, &["missing.obj: no such file"]);
    assert!(String::from_utf8_lossy(&out.stderr).starts_with("error: "));
}

/// `lambert info MODEL` prints both trees' statistics as `validate` measures
/// them (issue 29 item 1).
#[test]
fn info_prints_the_trees_statistics() {
    let path = common::asset("scenes/meshes/bunny_lowres.obj");
    let info = lambert(&["info", s(&path)]);
    assert!(info.status.success(), "{info:?}");
    let stdout = String::from_utf8_lossy(&info.stdout);
    let scene = lambert::Scene::load(&path).unwrap();
    let bvh = scene
        .bvh()
        .validate(scene.triangles(), scene.spheres())
        .unwrap();
    let nodes = lambert::cwbvh::compress(scene.bvh());
    let compressed = lambert::cwbvh::validate(&nodes, scene.bvh()).unwrap();
    assert!(bvh.nodes > 1 && bvh.leaves > bvh.nodes, "{bvh}");
    for line in [
        format!("  BVH (CPU): {bvh}\n"),
        format!("  compressed BVH (GPU): {compressed}\n"),
    ] {
        assert!(stdout.contains(&line), "expected '{line}' in: {stdout}");
    }
}
