//! The `lambert` binary as a user meets it: outputs, and clear errors (never a panic) for bad input.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{lambert, lambert_command, s};

const CAMERA: &str = r#"
[camera]
eye = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
vfov = 40.0
width = 16
height = 12
"#;

const SPHERE: &str = "[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";
const LIGHT: &str = "[[point_light]]\nposition = [0.0, 2.0, 3.0]\nintensity = 10.0\n";
const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

struct Case {
    dir: tempfile::TempDir,
}

impl Case {
    fn new() -> Case {
        Case {
            dir: tempfile::tempdir().unwrap(),
        }
    }

    fn file(&self, name: &str, text: &str) -> PathBuf {
        let path = self.dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// Renders `scene` on the CPU path and expects a failure naming `expected`.
    fn fails(&self, scene: &str, expected: &[&str]) {
        let scene_path = self.file("scene.toml", scene);
        let out = self.path("out.png");
        let output = lambert(&["render", s(&scene_path), "-o", s(&out), "--device", "cpu"]);
        expect_failure(&output, expected);
        assert!(!out.exists(), "a failed render wrote an image");
    }
}

fn expect_failure(output: &Output, expected: &[&str]) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!("{stderr}");
    assert!(
        !output.status.success(),
        "expected failure, got success; stderr:\n{stderr}"
    );
    assert_eq!(output.status.code(), Some(1), "stderr:\n{stderr}");
    assert!(!stderr.contains("panicked"), "panic:\n{stderr}");
    for e in expected {
        assert!(stderr.contains(e), "stderr lacks '{e}':\n{stderr}");
    }
}

#[test]
fn renders_png_exr_and_pfm() {
    let case = Case::new();
    let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}{LIGHT}"));
    for ext in ["png", "exr", "pfm"] {
        let out = case.path(&format!("out.{ext}"));
        let output = lambert(&["render", s(&scene), "-o", s(&out), "--device", "cpu"]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{stderr}");
        for stage in ["load", "upload", "render", "readback", "write", "Mrays/s"] {
            assert!(
                stderr.contains(stage),
                "timing report lacks {stage}:\n{stderr}"
            );
        }
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
    }
    let png = image::open(case.path("out.png")).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (16, 12));
    let exr = image::open(case.path("out.exr")).unwrap().to_rgb32f();
    assert_eq!(exr.dimensions(), (16, 12));
    // PFM: 16·12 pixels of 3 little-endian f32 after a 3-line header.
    let pfm = std::fs::read(case.path("out.pfm")).unwrap();
    assert!(pfm.starts_with(b"PF\n16 12\n-1.0\n"));
    assert_eq!(pfm.len(), "PF\n16 12\n-1.0\n".len() + 16 * 12 * 12);
}

#[test]
fn png_is_srgb_encoded_and_exr_linear() {
    let case = Case::new();
    // Head-on directional light on a plane: linear value k·E = 0.2 everywhere.
    case.file(
        "quad.obj",
        "v -9 -9 0\nv 9 -9 0\nv 9 9 0\nv -9 9 0\nf 1 2 3 4\n",
    );
    let scene = case.file(
        "scene.toml",
        &format!("{CAMERA}[[mesh]]\nobj = \"quad.obj\"\nalbedo = 0.5\n[[directional_light]]\ndirection = [0.0, 0.0, -1.0]\nirradiance = 0.4\n"),
    );
    for ext in ["png", "exr"] {
        let out = case.path(&format!("out.{ext}"));
        assert!(
            lambert(&["render", s(&scene), "-o", s(&out), "--device", "cpu"])
                .status
                .success()
        );
    }
    // sRGB(0.2) = 1.055·0.2^(1/2.4) − 0.055 = 0.48453 → 123.56 → 124.
    let png = image::open(case.path("out.png")).unwrap().to_rgb8();
    assert!(
        png.pixels().all(|p| p.0 == [124, 124, 124]),
        "{:?}",
        png.get_pixel(0, 0)
    );
    let exr = image::open(case.path("out.exr")).unwrap().to_rgb32f();
    assert!(exr.pixels().all(|p| (p.0[0] - 0.2).abs() < 1e-6));
}

#[test]
fn a_failed_render_leaves_the_previous_output_untouched() {
    let case = Case::new();
    let out = case.file("out.png", "previous contents");
    let bad = case.file(
        "bad.toml",
        &format!("{CAMERA}[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = -1.0\n"),
    );
    expect_failure(
        &lambert(&["render", s(&bad), "-o", s(&out), "--device", "cpu"]),
        &["radius"],
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous contents");
    // No temporary file is left behind.
    assert_eq!(std::fs::read_dir(case.dir.path()).unwrap().count(), 2);
}

#[test]
fn missing_files() {
    let case = Case::new();
    let out = case.path("out.png");
    expect_failure(
        &lambert(&["render", "no/such/scene.toml", "-o", s(&out)]),
        &["no/such/scene.toml", "No such file"],
    );
    case.fails(
        &format!("{CAMERA}[[mesh]]\nobj = \"missing.obj\"\n"),
        &["missing.obj", "No such file"],
    );
}

#[test]
fn malformed_toml_names_the_line() {
    Case::new().fails(
        &format!("{CAMERA}\n[[sphere]]\ncenter = [0.0, 0.0\n"),
        &["scene.toml", "line 10"],
    );
}

#[test]
fn unknown_keys_and_wrong_lengths() {
    let case = Case::new();
    case.fails(
        &format!("{CAMERA}{SPHERE}colour = 1\n"),
        &["unknown field `colour`"],
    );
    case.fails(
        &format!("{CAMERA}{SPHERE}[render]\nfog = true\n"),
        &["unknown field `fog`"],
    );
    case.fails(
        &format!("{CAMERA}[[sphere]]\ncenter = [0.0, 0.0]\nradius = 1.0\n"),
        &["center", "length 3"],
    );
    case.fails(
        &format!("{CAMERA}{SPHERE}albedo = [0.1, 0.2]\n"),
        &["albedo", "a number or an array of 3 numbers"],
    );
}

#[test]
fn malformed_obj_names_file_and_line() {
    let case = Case::new();
    let scene = format!("{CAMERA}[[mesh]]\nobj = \"m.obj\"\n");
    for (obj, expected) in [
        ("v 0 0 0\nv 1 0 x\n", "m.obj:2: 'x' is not a number"),
        ("v 0 0 0\nv 1 0\n", "m.obj:2: expected 3 coordinates"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            "m.obj:4: vertex index 4 is out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n",
            "m.obj:4: vertex index -4 is out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            "m.obj:4: vertex index 0 is out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\n\nf 1 2\n",
            "m.obj: no triangles (2 points, 0 lines skipped)",
        ),
        ("v 0 0 nan\n", "m.obj:1: coordinate nan must be finite"),
        ("v 0 0 inf\n", "m.obj:1: coordinate inf must be finite"),
        (
            "v 0 0 1e39\n",
            "m.obj:1: coordinate 1e39 must be finite with magnitude at most",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/1/x\n",
            "m.obj:4: 'x' is not a normal index",
        ),
    ] {
        case.file("m.obj", obj);
        case.fails(&scene, &[expected]);
    }
}

#[test]
fn bad_numbers_in_the_scene() {
    let case = Case::new();
    case.file("t.obj", TRIANGLE_OBJ);
    for (extra, expected) in [
        (
            "[[sphere]]\ncenter = [nan, 0.0, 0.0]\nradius = 1.0\n",
            "sphere[1].center",
        ),
        (
            "[[sphere]]\ncenter = [inf, 0.0, 0.0]\nradius = 1.0\n",
            "sphere[1].center",
        ),
        (
            "[[sphere]]\ncenter = [1e300, 0.0, 0.0]\nradius = 1.0\n",
            "sphere[1].center",
        ),
        (
            "[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 0.0\n",
            "sphere[1].radius = 0 must be positive",
        ),
        (
            "[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = -2.0\n",
            "sphere[1].radius = -2 must be positive",
        ),
        (
            "[[mesh]]\nobj = \"t.obj\"\nscale = 1e30\n",
            "beyond the supported magnitude",
        ),
        ("[[mesh]]\nobj = \"t.obj\"\nscale = 0.0\n", "mesh[0].scale"),
        (
            "[[mesh]]\nobj = \"t.obj\"\nalbedo = -0.5\n",
            "mesh[0].albedo",
        ),
        (
            "[[point_light]]\nposition = [0.0, 0.0, nan]\nintensity = 1.0\n",
            "point_light[0].position",
        ),
        (
            "[[directional_light]]\ndirection = [0.0, 0.0, 0.0]\nirradiance = 1.0\n",
            "directional_light[0].direction",
        ),
    ] {
        case.fails(&format!("{CAMERA}{SPHERE}{extra}"), &[expected]);
    }
}

#[test]
fn bad_cameras_and_resolutions() {
    let case = Case::new();
    let camera = |eye: &str, look_at: &str, up: &str, vfov: &str, w: &str, h: &str| {
        format!(
            "[camera]\neye = {eye}\nlook_at = {look_at}\nup = {up}\nvfov = {vfov}\nwidth = {w}\nheight = {h}\n{SPHERE}"
        )
    };
    let (e, l, u) = ("[0.0, 0.0, 3.0]", "[0.0, 0.0, 0.0]", "[0.0, 1.0, 0.0]");
    case.fails(
        &camera(e, e, u, "40", "8", "8"),
        &["camera.eye and camera.look_at are the same point"],
    );
    case.fails(
        &camera(e, l, "[0.0, 0.0, 1.0]", "40", "8", "8"),
        &["camera.up", "parallel"],
    );
    case.fails(
        &camera(e, l, "[0.0, 0.0, 0.0]", "40", "8", "8"),
        &["camera.up is the zero vector"],
    );
    for vfov in ["0", "180", "-5", "nan", "400"] {
        case.fails(
            &camera(e, l, u, vfov, "8", "8"),
            &["camera.vfov", "(0, 180)"],
        );
    }
    case.fails(&camera(e, l, u, "40", "0", "8"), &["zero side"]);
    case.fails(
        &camera(e, l, u, "40", "100000", "100000"),
        &["beyond the supported maximum"],
    );
    case.fails(&camera(e, l, u, "40", "-1", "8"), &["width"]);
    case.fails(&camera(e, l, u, "40", "9999999999", "8"), &["width"]);
    case.fails(SPHERE, &["missing field `camera`"]);
}

#[test]
fn empty_scenes() {
    let case = Case::new();
    case.fails(CAMERA, &["the scene is empty"]);
    case.file("empty.obj", "# nothing\nv 0 0 0\n");
    case.fails(
        &format!("{CAMERA}[[mesh]]\nobj = \"empty.obj\"\n"),
        &["empty.obj: no triangles (1 points, 0 lines skipped)"],
    );
}

#[test]
fn bad_output_names_and_options() {
    let case = Case::new();
    let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}"));
    let out = case.path("out.jpg");
    expect_failure(
        &lambert(&["render", s(&scene), "-o", s(&out)]),
        &["out.jpg", "unknown image format"],
    );
    // A folder under a regular file cannot be made: refused before the work.
    std::fs::write(case.path("plain"), "").unwrap();
    let out = case.path("plain/dir/out.png");
    expect_failure(
        &lambert(&["render", s(&scene), "-o", s(&out), "--device", "cpu"]),
        &["plain/dir"],
    );
    let out = case.path("out.png");
    expect_failure(
        &lambert(&[
            "render",
            s(&scene),
            "-o",
            s(&out),
            "--device",
            "gpu",
            "--backend",
            "glide",
        ]),
        &["unknown backend 'glide'"],
    );
    expect_failure(
        &lambert(&[
            "render",
            s(&scene),
            "-o",
            s(&out),
            "--device",
            "gpu",
            "--adapter",
            "no-such-adapter",
        ]),
        &["no adapter whose name contains 'no-such-adapter'"],
    );
}

#[test]
fn diff_reports_statistics_and_json() {
    let case = Case::new();
    let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}{LIGHT}"));
    let heatmap = case.path("heat.png");
    let output = lambert(&["diff", s(&scene), "--json", "--heatmap", s(&heatmap)]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let stats: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(stats["pixels"], 16 * 12);
    assert_eq!(stats["passed"], true);
    for key in [
        "max_abs",
        "max_8bit_steps",
        "rmse",
        "psnr_db",
        "beyond_tolerance",
        "prim_mismatches",
    ] {
        assert!(stats.get(key).is_some(), "JSON lacks {key}");
    }
    assert_eq!(
        image::open(&heatmap).unwrap().to_rgb8().dimensions(),
        (16, 12)
    );

    // An impossible tolerance makes the same comparison fail, with exit 1.
    let output = lambert(&[
        "diff",
        s(&scene),
        "--compare",
        "cpu-oracle",
        "--tol-abs",
        "0",
        "--tol-rel",
        "0",
        "--max-bad",
        "0",
    ]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("FAIL"), "{stdout}");
}

#[test]
fn info_lists_adapters() {
    let output = lambert(&["info"]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success());
    assert!(
        stdout.contains("adapter:"),
        "no adapter listed (install mesa-vulkan-drivers):\n{stdout}"
    );
    assert!(stdout.contains("limits:"), "{stdout}");
}

#[test]
fn trace_writes_hits_in_the_documented_format() {
    let case = Case::new();
    let obj = case.file("tri.obj", TRIANGLE_OBJ);
    // One ray hits (0.25, 0.25) from z = 1 with a direction of length 2, one misses.
    let rays: Vec<f32> = vec![
        0.25,
        0.25,
        1.0,
        0.0,
        0.0,
        0.0,
        -2.0,
        f32::INFINITY, //
        5.0,
        5.0,
        1.0,
        0.0,
        0.0,
        0.0,
        -1.0,
        f32::INFINITY,
    ];
    let rays_path = case.path("rays.bin");
    std::fs::write(
        &rays_path,
        rays.iter()
            .flat_map(|f| f.to_le_bytes())
            .collect::<Vec<u8>>(),
    )
    .unwrap();
    for device in ["cpu", "gpu"] {
        let hits_path = case.path(&format!("hits_{device}.bin"));
        let out = lambert(&[
            "trace",
            "--obj",
            obj.to_str().unwrap(),
            "--rays",
            rays_path.to_str().unwrap(),
            "-o",
            hits_path.to_str().unwrap(),
            "--device",
            device,
            "--oracle",
            "--warmup",
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        // The warm-up trace is reported apart; the hits below are the timed
        // trace's.
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        for key in ["warmup_seconds", "trace_seconds"] {
            assert!(report[key].as_f64().unwrap() > 0.0, "{key} in {report}");
        }
        let bytes = std::fs::read(&hits_path).unwrap();
        assert_eq!(bytes.len(), 32);
        let f = |i: usize| f32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
        let u = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
        // t in units of |d|: the plane is 1 away, |d| = 2.
        assert_eq!((f(0), u(4)), (0.5, 0));
        assert!(
            (f(8) - 0.25).abs() < 1e-6 && (f(12) - 0.25).abs() < 1e-6,
            "u, v"
        );
        assert_eq!((f(16), u(20)), (f32::INFINITY, u32::MAX));
    }
}

#[test]
fn trace_rejects_bad_ray_files() {
    let case = Case::new();
    let obj = case.file("tri.obj", TRIANGLE_OBJ);
    let short = case.file("short.bin", "0123456789");
    let mut nan = vec![0u8; 32];
    nan[16..20].copy_from_slice(&f32::NAN.to_le_bytes());
    let nan_path = case.path("nan.bin");
    std::fs::write(&nan_path, nan).unwrap();
    for (rays, expected) in [
        (&short, "10 bytes is not a whole number of rays"),
        (&nan_path, "ray 0 (byte offset 0): dx is NaN"),
    ] {
        let out = lambert(&[
            "trace",
            "--obj",
            obj.to_str().unwrap(),
            "--rays",
            rays.to_str().unwrap(),
            "-o",
            case.path("hits.bin").to_str().unwrap(),
            "--device",
            "cpu",
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(
            stderr.contains(expected) && stderr.contains(rays.to_str().unwrap()),
            "{stderr}"
        );
        assert!(!case.path("hits.bin").exists(), "a failed trace wrote hits");
    }
}

#[test]
fn turntable_writes_numbered_frames() {
    let case = Case::new();
    let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}{LIGHT}"));
    let pattern = case.path("frames/frame_{:04}.png");
    let out = lambert(&[
        "render",
        scene.to_str().unwrap(),
        "--turntable",
        "3",
        "-o",
        pattern.to_str().unwrap(),
        "--device",
        "cpu",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for frame in 0..3 {
        assert!(case.path(&format!("frames/frame_{frame:04}.png")).exists());
    }
    assert!(String::from_utf8_lossy(&out.stderr).contains("per frame"));
}

#[test]
fn bench_time_vs_error_runs_end_to_end() {
    let case = Case::new();
    let json = case.path("points.json");
    let plots = case.path("plots");
    let out = lambert(&[
        "bench",
        "--time-vs-error",
        "assets/scenes/edge_cases.toml",
        "--spp-list",
        "1,4,16",
        "--runs",
        "1",
        "--json",
        json.to_str().unwrap(),
        "--plot",
        plots.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let points: Vec<serde_json::Value> =
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    for field in [
        "scene",
        "path",
        "intersect",
        "spp",
        "accel",
        "shader",
        "seconds",
        "rmse",
        "psnr_db",
        "max_error",
        "mismatched_primitives",
        "leaks",
        "on_pareto_front",
    ] {
        assert!(
            points.iter().all(|p| p.get(field).is_some()),
            "a point lacks {field}"
        );
    }
    // Three paths (GPU on lavapipe, CPU f32, CPU f64) × three tests × three spp,
    // plus brute force on each path, the full shader on the GPU, and four
    // adaptive targets on each f32 path.
    assert_eq!(points.len(), 3 * 3 * 3 + 3 + 1 + 2 * 4);
    assert!(points.iter().any(|p| p["on_pareto_front"] == true));
    // Error falls with spp for every path and test.
    for path in ["gpu-f32", "cpu-f32", "cpu-f64"] {
        for test in ["seed", "moller-trumbore", "watertight"] {
            let rmse: Vec<f64> = points
                .iter()
                .filter(|p| {
                    p["path"] == path
                        && p["intersect"] == test
                        && p["accel"] == "bvh"
                        && p["shader"] != "full"
                        && p["sampling"] == "uniform"
                })
                .map(|p| p["rmse"].as_f64().unwrap())
                .collect();
            assert_eq!(rmse.len(), 3);
            assert!(
                rmse[0] > rmse[1] && rmse[1] > rmse[2],
                "{path} {test}: {rmse:?}"
            );
        }
    }
    for ext in ["png", "svg"] {
        assert!(
            plots
                .join(format!("time_vs_error_edge_cases.{ext}"))
                .exists()
        );
    }
}

#[test]
fn time_budget_and_target_error_render_and_report() {
    let case = Case::new();
    let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}{LIGHT}"));
    let out_png = case.path("out.png");
    let render = |option: &str, value: &str| {
        let out = lambert(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out_png.to_str().unwrap(),
            "--device",
            "cpu",
            option,
            value,
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        (out.status.code(), stderr)
    };
    let (code, stderr) = render("--time-budget", "0.5");
    assert_eq!(code, Some(0), "{stderr}");
    assert!(out_png.exists());
    // A 16×12 image renders in far less than 0.5 s: many samples fit.
    let spp: u32 = stderr
        .lines()
        .find_map(|l| {
            l.strip_prefix("time budget: ")?
                .split(' ')
                .next()?
                .parse()
                .ok()
        })
        .unwrap_or_else(|| panic!("no spp reported:\n{stderr}"));
    assert!(spp > 1, "{stderr}");
    let (code, stderr) = render("--target-error", "0.01");
    assert!(
        code == Some(0) && stderr.contains("expected RMSE"),
        "{stderr}"
    );
    // A negative number is no value to clap (exit 2); the rest are ours (exit 1).
    for (option, value, expected) in [
        ("--time-budget", "-1", 2),
        ("--time-budget", "nan", 1),
        ("--target-error", "0", 1),
    ] {
        assert_eq!(render(option, value).0, Some(expected), "{option} {value}");
    }
}

/// `LAMBERT_CPU_KERNEL` is read by the binary, not the library: `info`
/// reports the kernel it names (or the widest narrower one the CPU has),
/// and the wider ones as not chosen; a name that is no kernel's leaves the
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
    let case = Case::new();
    let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}{LIGHT}"));
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
    // In front, 2 away: E = 4/2² = 1 along the normal, so 0.5 × 1.
    let front = quad_gltf(&case, "front", &[([0.0, 0.0, 2.0], 4.0)]);
    for c in centre_pixel(&case, &front, &[]) {
        assert!((c - 0.5).abs() < 1e-4, "{c}");
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
        (
            [
                &[
                    "trace",
                    "--obj",
                    s(&obj),
                    "--rays",
                    s(&rays),
                    "-o",
                    s(&rays),
                ][..],
                &cpu,
            ]
            .concat(),
            &rays,
        ),
        (
            vec![
                "trace",
                "--obj",
                s(&obj),
                "--rays",
                s(&rays),
                "-o",
                s(&obj_bin),
            ],
            &obj_bin,
        ),
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
    let out = lambert(&[
        "render",
        s(&scene),
        "--turntable",
        "2",
        "-o",
        s(&frames),
        "--device",
        "cpu",
    ]);
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
    let case = Case::new();
    let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}{LIGHT}"));
    let obj = case.file("tri.obj", TRIANGLE_OBJ);
    let rays = case.path("rays.bin");
    let hits = case.path("hits.bin");
    let (part0, part1) = (case.path("part0.exr"), case.path("part1.exr"));
    let merged = case.path("merged.png");
    let camera_rays = ["camera-rays", s(&scene), "-o", s(&rays)];
    let trace = [
        "trace",
        "--obj",
        s(&obj),
        "--rays",
        s(&rays),
        "-o",
        s(&hits),
    ];
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
    let case = Case::new();
    let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}{LIGHT}"));
    let pattern = case.path("f{}/frame_{:03}.png");
    let out = lambert(&[
        "render",
        s(&scene),
        "--turntable",
        "2",
        "-o",
        s(&pattern),
        "--device",
        "cpu",
        "-q",
    ]);
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
    let case = Case::new();
    let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}{LIGHT}"));
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
        .args([
            "bench",
            "--time-vs-error",
            "--device",
            "cpu",
            "--spp-list",
            "1",
        ])
        .args(["--runs", "1", "-q", "--json", s(&json)])
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
        .validate(&scene.triangles(), &scene.spheres())
        .unwrap();
    let nodes = lambert::cwbvh::compress(&scene.bvh());
    let compressed = lambert::cwbvh::validate(&nodes, &scene.bvh()).unwrap();
    assert!(bvh.nodes > 1 && bvh.leaves > bvh.nodes, "{bvh}");
    for line in [
        format!("  BVH (CPU): {bvh}\n"),
        format!("  compressed BVH (GPU): {compressed}\n"),
    ] {
        assert!(stdout.contains(&line), "expected '{line}' in: {stdout}");
    }
}
