//! The `lambert` binary as a user meets it: outputs, and clear errors (never a panic) for bad input.

mod common;

use common::args::{render_args, trace_args, turntable_args};
use common::cli::*;
use common::{lambert, s};

#[test]
fn renders_png_exr_and_pfm() {
    let (case, scene) = Case::lit_sphere();
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
        &lambert(
            &[
                &render_args(&scene, &out, "gpu")[..],
                &["--backend", "glide"],
            ]
            .concat(),
        ),
        &["unknown backend 'glide'"],
    );
    expect_failure(
        &lambert(
            &[
                &render_args(&scene, &out, "gpu")[..],
                &["--adapter", "no-such-adapter"],
            ]
            .concat(),
        ),
        &["no adapter whose name contains 'no-such-adapter'"],
    );
}

#[test]
fn diff_reports_statistics_and_json() {
    let (case, scene) = Case::lit_sphere();
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
        let out = lambert(
            &[
                &trace_args(&obj, &rays_path, &hits_path)[..],
                &["--device", device, "--oracle", "--warmup", "--json"],
            ]
            .concat(),
        );
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
        let hits = case.path("hits.bin");
        let out = lambert(&[&trace_args(&obj, rays, &hits)[..], &["--device", "cpu"]].concat());
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
    let (case, scene) = Case::lit_sphere();
    let pattern = case.path("frames/frame_{:04}.png");
    let out = lambert(&turntable_args(&scene, "3", &pattern));
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
    let (case, scene) = Case::lit_sphere();
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
