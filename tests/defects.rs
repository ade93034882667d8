//! Defects found by trying unusual but valid inputs (issue 22): each test failed before its fix.

mod common;

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::args::{render_args, trace_args};
use common::data::ray;
use common::formats::assert_has;
use common::signals::interrupt;
use common::*;
use lambert::layout::{NO_HIT, Ray, Triangle};

const SCENE: &str = "[camera]\neye = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 16\nheight = 12\n\
[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n\
[[point_light]]\nposition = [0.0, 2.0, 3.0]\nintensity = 10.0\n";

fn scene_file(dir: &Path) -> PathBuf {
    let path = dir.join("scene.toml");
    std::fs::write(&path, SCENE).unwrap();
    path
}

/// diff's statistics stay meaningful when a value is not finite: counted,
/// and left out of the maximum, RMSE and PSNR rather than making them
/// infinite or NaN.
#[test]
fn diff_statistics_count_non_finite_pixels_apart() {
    use lambert::diff::{Tolerance, compare};
    use lambert::output::{Image, Rendered};
    let image = |rgb: Vec<[f32; 3]>| Rendered {
        image: Image {
            width: rgb.len() as u32,
            height: 1,
            rgb,
        },
        prims: vec![0; 3],
        variance: vec![0.0; 3],
    };
    let a = image(vec![[0.5; 3], [f32::NAN, 0.0, 0.0], [0.25; 3]]);
    let b = image(vec![[0.5; 3], [0.1, 0.0, 0.0], [0.5, 0.25, 0.25]]);
    let stats = compare(&a, &b, &Tolerance::default()).unwrap();
    assert_eq!(stats.non_finite, 1);
    assert_eq!(stats.beyond_tolerance, 2);
    assert_eq!(stats.max_abs, 0.25);
    assert!(stats.rmse.is_finite() && stats.rmse > 0.0);
    assert!(stats.psnr_db.is_some_and(f64::is_finite));
    assert!(!stats.passed);
    let text = stats.to_string();
    assert!(text.contains("not finite           1"), "{text}");
    assert!(!text.contains("identical"), "{text}");
    let json = serde_json::to_value(&stats).unwrap();
    assert_eq!(json["max_abs"], 0.25);
}

/// Spheres beyond the radius whose near side is found are refused, and
/// the oracle no longer calls a hit on the far side agreement.
#[test]
fn large_spheres_are_refused_and_the_oracle_sees_wrong_distances() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.toml");
    std::fs::write(
        &path,
        SCENE.replace(
            "center = [0.0, 0.0, 0.0]\nradius = 1.0",
            "center = [0.0, 0.0, -5e8]\nradius = 5e8",
        ),
    )
    .unwrap();
    let out = lambert(&["render", s(&path), "-o", s(&dir.path().join("x.png"))]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("sphere[0].radius"),
        "{}",
        stderr(&out)
    );

    use lambert::cpu::f64::Hit as OracleHit;
    let hit = |t: f32| lambert::layout::Hit {
        t,
        prim: 0,
        u: 0.0,
        v: 0.0,
    };
    let oracle = [OracleHit {
        t: 5.0,
        prim: 0,
        u: 0.0,
        v: 0.0,
    }; 2];
    let agreement = lambert::rays::Agreement::measure(&[hit(2e9), hit(5.0000005)], &oracle);
    assert_eq!((agreement.same, agreement.other_distance), (1, 1));
}

/// A ray whose direction is tiny but accepted (length 1e-18) hits through
/// the BVH as through brute force, on both paths and in the oracle.
#[test]
fn tiny_directions_hit_through_the_bvh() {
    let triangle = Triangle {
        v0: [-1.0, -1.0, 0.0],
        v1: [1.0, -1.0, 0.0],
        v2: [0.0, 1.0, 0.0],
        ..Default::default()
    };
    let sphere = lambert::layout::Sphere {
        center: [10.0, 0.0, 0.0],
        radius: 1.0,
        ..Default::default()
    };
    let scene = scene_of(vec![triangle], vec![sphere]);
    let rays = [
        ray([0.0, 0.0, 5.0], [0.0, 0.0, -1e-18]),
        ray([0.0, 0.0, 5.0], [1e-19, 0.0, -1e-18]),
        ray([10.0, 0.0, 5.0], [0.0, 0.0, -1e-18]),
        ray([0.0, 0.0, 5.0], [0.0, 0.0, -1e-17]),
    ];
    let expect = [(0, 5e18), (0, 5e18), (1, 4e18), (0, 5e17)];
    let oracle = lambert::cpu::trace_rays_f64(&scene, &rays, false);
    for (what, hits) in [
        ("CPU", trace_cpu(&scene, &rays, false)),
        ("GPU", trace_gpu(&scene, &rays, false)),
    ] {
        for (i, (hit, (prim, t))) in hits.iter().zip(expect).enumerate() {
            assert_eq!(hit.prim, prim, "{what}: ray {i}");
            assert!(
                (hit.t as f64 / t - 1.0).abs() < 1e-6,
                "{what}: ray {i} at {}",
                hit.t
            );
            assert_eq!(oracle[i].prim, prim, "oracle: ray {i}");
        }
    }
    let brute = common::brute_force(&scene);
    let brute_hits = trace_cpu(&brute, &rays, false);
    assert!(brute_hits.iter().all(|h| h.prim != NO_HIT));
}

/// What `path` is, not following a link.
fn file_type(path: &Path) -> std::fs::FileType {
    std::fs::symlink_metadata(path).unwrap().file_type()
}

/// Renders `scene` to `link`, a symlink, on the CPU: it succeeds and the
/// link stays a link.
fn render_through_link(scene: &Path, link: &Path) {
    let out = lambert(&render_args(scene, link, "cpu"));
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        std::fs::symlink_metadata(link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
}

/// Outputs that are not regular files: a symlink keeps pointing where it
/// did and its target gets the image, a dangling one creates its target,
/// a FIFO is written into, not replaced; and a device that fails the
/// write (as /dev/full would) is an error, not a replaced node.
#[test]
fn outputs_follow_links_and_write_into_fifos() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = scene_file(d);

    std::fs::write(d.join("real.pfm"), "old").unwrap();
    std::os::unix::fs::symlink("real.pfm", d.join("link.pfm")).unwrap();
    render_through_link(&scene, &d.join("link.pfm"));
    assert!(
        std::fs::read(d.join("real.pfm"))
            .unwrap()
            .starts_with(b"PF\n16 12\n")
    );

    std::os::unix::fs::symlink("sub/target.png", d.join("dangling.png")).unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    render_through_link(&scene, &d.join("dangling.png"));
    image::open(d.join("sub/target.png")).unwrap();

    let fifo = d.join("fifo.pfm");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).unwrap())
    };
    let out = lambert(&["render", s(&scene), "-o", s(&fifo), "--device", "cpu"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let bytes = reader.join().unwrap();
    assert!(bytes.starts_with(b"PF\n16 12\n"), "{} bytes", bytes.len());
    assert!(file_type(&fifo).is_fifo());
    assert!(temporaries(d).is_empty(), "{:?}", temporaries(d));

    // A device that fails the write, as /dev/full does (a copy of it here:
    // making device nodes needs root, which CI has).
    let full = d.join("full.pfm");
    let made = Command::new("mknod")
        .arg(&full)
        .args(["c", "1", "7"])
        .status()
        .unwrap()
        .success();
    if !made {
        use std::io::Write;
        let _ = writeln!(
            std::io::stderr(),
            "skipped: the /dev/full case needs root to make a device node"
        );
        return;
    }
    let out = lambert(&["render", s(&scene), "-o", s(&full), "--device", "cpu"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("full.pfm"), "{}", stderr(&out));
    assert!(file_type(&full).is_char_device());
    assert!(temporaries(d).is_empty(), "{:?}", temporaries(d));
}

/// SIGINT or SIGTERM at any moment of a render and its write (a PFM,
/// written in one piece, used to leave its temporary file) leaves no
/// temporary file and the previous output whole.
#[test]
fn signals_leave_no_temporary_file_and_the_previous_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = d.join("big.toml");
    std::fs::write(
        &scene,
        SCENE.replace("width = 16\nheight = 12", "width = 2048\nheight = 2048"),
    )
    .unwrap();
    let output = d.join("out.pfm");
    std::fs::write(&output, "previous").unwrap();
    let mut interrupted = 0;
    for (round, delay_ms) in [50u64, 150, 300, 450, 600, 800, 1000, 1300]
        .iter()
        .enumerate()
    {
        let child = lambert_command()
            .args(render_args(&scene, &output, "cpu"))
            .arg("-q")
            .spawn()
            .unwrap();
        let (success, bytes) = interrupt(child, round, *delay_ms, d, &output);
        if previous_or_whole(success, &bytes, 18 + 2048 * 2048 * 12, *delay_ms) {
            interrupted += 1;
        } else {
            std::fs::write(&output, "previous").unwrap();
        }
    }
    assert!(interrupted > 0, "no run was interrupted");
}

/// The output folder is made ready before the work: a missing one is
/// created (the rule for every output), one that cannot exist fails at
/// once, before any rendering.
#[test]
fn output_folders_are_checked_before_the_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = scene_file(d);
    let nested = d.join("new/deeper/out.png");
    let out = lambert(&["render", s(&scene), "-o", s(&nested), "--device", "cpu"]);
    assert!(out.status.success(), "{}", stderr(&out));
    image::open(&nested).unwrap();

    std::fs::write(d.join("file"), "").unwrap();
    for args in [
        vec!["render", s(&scene), "-o", "file/out.png", "--device", "cpu"],
        vec![
            "bench",
            "--time-vs-error",
            s(&scene),
            "--json",
            "file/b.json",
            "--spp-list",
            "1",
        ],
        vec!["camera-rays", s(&scene), "-o", "file/rays.bin"],
    ] {
        let out = lambert_in(d, &args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let text = stderr(&out);
        assert!(text.contains("file"), "{args:?}: {text}");
        assert!(
            !text.contains("rendering on") && !text.contains("RMSE"),
            "{args:?} worked first: {text}"
        );
        assert!(String::from_utf8_lossy(&out.stdout).is_empty(), "{args:?}");
    }
}

/// bench outside the repository says what it lacks, before any table
/// (with no inputs it finds the bundled ones from the executable: issue 28
/// item 16, tests/cli_commands.rs).
#[test]
fn bench_says_what_it_needs() {
    let dir = tempfile::tempdir().unwrap();
    let out = lambert_in(dir.path(), &["bench", "missing.obj"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty());
    assert!(
        stderr(&out).contains("missing.obj: no such file"),
        "{}",
        stderr(&out)
    );
}

/// diff: 0 agree, 1 differ, 2 error (as diff(1)); nonsense tolerances are
/// errors.
#[test]
fn diff_errors_exit_2_and_nonsense_options_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path());
    let out = lambert(&["diff", s(&dir.path().join("missing.toml"))]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    for (option, value) in [
        ("--tol-abs", "NaN"),
        ("--tol-abs", "-1"),
        ("--tol-rel", "inf"),
        ("--max-bad", "-0.5"),
        ("--max-bad", "1.5"),
        ("--max-prim-mismatch", "NaN"),
    ] {
        let arg = format!("{option}={value}");
        let out = lambert(&["diff", s(&scene), &arg]);
        assert_eq!(out.status.code(), Some(2), "{arg}: {}", stderr(&out));
        assert!(stderr(&out).contains(option), "{arg}: {}", stderr(&out));
    }
    let out = lambert(&["diff", s(&scene), "--compare", "cpu-oracle"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

/// -q prints nothing but errors, the fallback note included; trace does
/// not call its work rendering.
#[test]
fn quiet_is_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path());
    let out = lambert_command()
        .args([
            "render",
            s(&scene),
            "-o",
            s(&dir.path().join("x.png")),
            "-q",
        ])
        .env("WGPU_ADAPTER_NAME", "no such adapter")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(stderr(&out), "");
    let obj = dir.path().join("t.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let rays = dir.path().join("r.bin");
    lambert::rays::write_rays(
        &rays,
        &[Ray {
            origin: [0.2, 0.2, 1.0],
            tmin: 0.0,
            dir: [0.0, 0.0, -1.0],
            tmax: f32::INFINITY,
        }],
    )
    .unwrap();
    let out = lambert_command()
        .args(trace_args(&obj, &rays, &dir.path().join("h.bin")))
        .env("WGPU_ADAPTER_NAME", "no such adapter")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stderr(&out).contains("rendering"), "{}", stderr(&out));
}

/// OBJ: a byte-order mark is not part of the first statement; messages say
/// "vertices" and print vectors as the user writes them; a transformed
/// vertex beyond range names the mesh entry.
#[test]
fn obj_byte_order_marks_and_messages() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let plain = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 2 4 3\n";
    std::fs::write(d.join("plain.obj"), plain).unwrap();
    std::fs::write(d.join("bom.obj"), format!("\u{feff}{plain}")).unwrap();
    let load = |name: &str| {
        lambert::loading::load_obj(&d.join(name), lambert::loading::NormalMode::Face).unwrap()
    };
    let (a, b) = (load("plain.obj"), load("bom.obj"));
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.triangles, b.triangles);

    std::fs::write(d.join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let err = lambert::loading::load_obj(&d.join("bad.obj"), lambert::loading::NormalMode::Face)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("2 vertices defined") && err.contains(":3"),
        "{err}"
    );

    let scene = d.join("s.toml");
    std::fs::write(
        &scene,
        SCENE.to_string()
            + "[[mesh]]\nobj = \"plain.obj\"\nscale = 1e8\ntranslate = [9.5e8, 0.0, 0.0]\n",
    )
    .unwrap();
    let err = lambert::Scene::load(&scene).unwrap_err().to_string();
    assert_has(&err, &["mesh[0] (plain.obj): vertex 2 at [1, 0, 0]"]);
    assert!(!err.contains("DVec3"), "{err}");
}

/// info honours --adapter, suggests lavapipe only where it would help,
/// and WGPU_BACKEND names are checked as --backend's are.
#[test]
fn info_filters_and_backend_names() {
    let out = lambert(&["info", "--adapter", "no such adapter"]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(!text.contains("adapter: "), "{text}");
    assert!(
        text.contains("no GPU adapters whose name contains 'no such adapter'"),
        "{text}"
    );
    assert!(
        !text.contains("lavapipe"),
        "lavapipe is installed here: {text}"
    );
    let out = lambert(&["info", "--backend", "metal"]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    if cfg!(not(target_os = "macos")) {
        assert!(
            text.contains("no GPU adapters on Metal") && !text.contains("lavapipe"),
            "{text}"
        );
    }
    let out = lambert_command()
        .arg("info")
        .env("WGPU_BACKEND", "bogus")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert_has(&stderr(&out), &["unknown backend 'bogus' in WGPU_BACKEND"]);
}

/// The up vector's threshold is stated, and just past it renders as the
/// default up does.
#[test]
fn the_up_vector_threshold_is_stated() {
    let dir = tempfile::tempdir().unwrap();
    let tilted = |angle: f64| {
        let path = dir.path().join(format!("up{angle}.toml"));
        // The view direction is −z; up leans from it by `angle` toward +y.
        let up = format!("up = [0.0, {}, {}]\n", angle.sin(), -angle.cos());
        std::fs::write(&path, SCENE.replacen("vfov", &format!("{up}vfov"), 1)).unwrap();
        path
    };
    let out = lambert(&[
        "render",
        s(&tilted(5e-7)),
        "-o",
        s(&dir.path().join("a.png")),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("at least 1e-6 rad"),
        "{}",
        stderr(&out)
    );
    let near = lambert::Scene::load(&tilted(1e-5)).unwrap();
    let default = lambert::Scene::load(&scene_file(dir.path())).unwrap();
    let (a, b) = (render_cpu(&near), render_cpu(&default));
    assert_eq!(a.prims, b.prims);
}
