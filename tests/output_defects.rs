//! Issue 44's defects of outputs, part hashes, temporaries, degenerate
//! cameras and the command line's smaller rules: each test builds its
//! own scenes in a temporary folder.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::args::{CHEAPEST_BENCH, render_args, turntable_args};
use common::{lambert, s, stderr, write};
use lambert::Scene;
use lambert::output::Image;

const CAMERA: &str = "\n[camera]\neye = [0.5, 0.5, 3.0]\nlook_at = [0.5, 0.5, 0.0]\nvfov = 40.0\nwidth = 16\nheight = 12\n";

const LIGHT: &str = "[[point_light]]\nposition = [0.0, 2.0, 3.0]\nintensity = 10.0\n";

/// A unit quad with texture coordinates, its MTL naming `texture` as
/// map_Kd.
fn textured_quad(texture: &str) -> (String, String) {
    let obj = "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
               vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3 4/4\n";
    let mtl = format!("newmtl m\nKd 1 1 1\nmap_Kd {texture}\n");
    (obj.to_string(), mtl)
}

/// A 2×2 PNG of one grey level.
fn write_png(path: &Path, grey: f32) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    Image {
        width: 2,
        height: 2,
        rgb: vec![[grey; 3]; 4],
    }
    .save(path)
    .unwrap();
}

/// A folder holding a room: `room.toml` reading `meshes/quad.obj`, whose
/// MTL `meshes/quad.mtl` names the texture `meshes/tex/grid.png`.
fn room() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let meshes = dir.path().join("meshes");
    std::fs::create_dir_all(&meshes).unwrap();
    let (obj, mtl) = textured_quad("tex/grid.png");
    write(&meshes, "quad.obj", obj);
    write(&meshes, "quad.mtl", mtl);
    write_png(&meshes.join("tex/grid.png"), 0.5);
    let scene = format!("{CAMERA}{LIGHT}[[mesh]]\nfile = \"meshes/quad.obj\"\n");
    let path = write(dir.path(), "room.toml", scene);
    (dir, path)
}

/// The run failed, saying the output is one of the scene's inputs, and
/// `input` holds the bytes it held before.
fn refused_as_input(output: &Output, input: &Path, before: &[u8]) {
    let text = stderr(output);
    assert!(
        !output.status.success(),
        "wrote over {}: {text}",
        input.display()
    );
    assert!(
        text.contains("the output is one of the inputs"),
        "no word of the input: {text}"
    );
    assert_eq!(
        std::fs::read(input).unwrap(),
        before,
        "{} changed",
        input.display()
    );
}

#[test]
fn no_output_replaces_a_mesh_an_mtl_or_a_texture_the_scene_reads() {
    let (dir, scene) = room();
    let meshes = dir.path().join("meshes");
    let texture = meshes.join("tex/grid.png");
    let quad = meshes.join("quad.obj");
    let mtl = meshes.join("quad.mtl");
    let rays = dir.path().join("rays.bin");
    let made = lambert(&["camera-rays", s(&scene), "-o", s(&rays)]);
    assert!(made.status.success(), "{}", stderr(&made));
    let cases: Vec<(Vec<&str>, &Path)> = vec![
        // The model alone: its texture, named by its MTL.
        (
            vec!["render", s(&quad), "-o", s(&texture), "--device", "cpu"],
            &texture,
        ),
        (
            vec!["render", s(&scene), "-o", s(&texture), "--device", "cpu"],
            &texture,
        ),
        (vec!["diff", s(&scene), "--heatmap", s(&texture)], &texture),
        (
            vec![
                "view",
                s(&scene),
                "--frames",
                "1",
                "--screenshot",
                s(&texture),
            ],
            &texture,
        ),
        (vec!["camera-rays", s(&scene), "-o", s(&quad)], &quad),
        (vec!["camera-rays", s(&scene), "-o", s(&mtl)], &mtl),
        (
            [&CHEAPEST_BENCH[..], &["--json", s(&mtl), s(&scene)]].concat(),
            &mtl,
        ),
        (
            vec![
                "trace",
                "--scene",
                s(&scene),
                "--rays",
                s(&rays),
                "-o",
                s(&quad),
            ],
            &quad,
        ),
    ];
    for (args, input) in cases {
        let before = std::fs::read(input).unwrap();
        let output = lambert(&args);
        println!("{args:?}");
        refused_as_input(&output, input, &before);
    }
}

#[test]
fn no_output_replaces_a_gltf_file_s_buffer() {
    let dir = tempfile::tempdir().unwrap();
    let positions: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let buffer = write(dir.path(), "tri.bin", &positions);
    let gltf = r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"uri": "tri.bin", "byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}]}"#;
    let model = write(dir.path(), "tri.gltf", gltf);
    let output = lambert(&["camera-rays", s(&model), "-o", s(&buffer)]);
    refused_as_input(&output, &buffer, &positions);
}

#[test]
fn turntable_and_part_outputs_are_refused_over_a_texture() {
    let (dir, scene) = room();
    let texture = dir.path().join("meshes/tex/grid.png");
    let before = std::fs::read(&texture).unwrap();
    let pattern = dir.path().join("meshes/tex/{}.png");
    // Frame 0 of 2 would be …/tex/0.png; make it the texture through a link.
    std::os::unix::fs::symlink(&texture, dir.path().join("meshes/tex/0.png")).unwrap();
    let output = lambert(&turntable_args(&scene, "2", &pattern));
    refused_as_input(&output, &texture, &before);
    let exr = dir.path().join("meshes/tex/grid.exr");
    write(
        &dir.path().join("meshes"),
        "quad.mtl",
        textured_quad("tex/grid.exr").1,
    );
    std::fs::write(&exr, b"texture bytes").unwrap();
    let output = lambert(&[
        "render",
        s(&scene),
        "--tile",
        "0/2",
        "-o",
        s(&exr),
        "--device",
        "cpu",
    ]);
    refused_as_input(&output, &exr, b"texture bytes");
}

/// A scene's part hash (the CPU path's).
fn hash_of(scene: &Path) -> String {
    let scene = Scene::load(scene).expect("test scene loads");
    lambert::parts::settings_hash(&scene, scene.view(), "cpu")
}

#[test]
fn a_part_hash_changes_with_a_texture_s_pixels() {
    let (dir, scene) = room();
    let before = hash_of(&scene);
    // The same size, other pixels.
    write_png(&dir.path().join("meshes/tex/grid.png"), 0.25);
    assert_ne!(
        hash_of(&scene),
        before,
        "the texture's pixels are not hashed"
    );
}

#[test]
fn parts_of_a_far_scene_whose_mesh_moved_do_not_merge() {
    let dir = tempfile::tempdir().unwrap();
    let far = 1.0e6;
    // A directional light: a point light's position, kept relative to the
    // scene's centre, would move in the local frame and change the hash.
    let scene = |shift: f64| {
        let obj: String = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
            .iter()
            .map(|[x, y]| format!("v {} {} 0\n", far + x + shift, y))
            .chain(["f 1 2 3 4\n".to_string()])
            .collect();
        let name = format!("quad{shift}.obj");
        write(dir.path(), &name, obj);
        let text = format!(
            "[camera]\neye = [{e}, 0.5, 3.0]\nlook_at = [{e}, 0.5, 0.0]\nvfov = 40.0\n\
             width = 16\nheight = 12\n\
             [[directional_light]]\ndirection = [0.0, -1.0, -1.0]\nirradiance = 1.0\n\
             [[mesh]]\nfile = \"{name}\"\n",
            e = far + 0.5
        );
        write(dir.path(), &format!("scene{shift}.toml"), text)
    };
    let (here, moved) = (scene(0.0), scene(0.3));
    assert_ne!(
        hash_of(&here),
        hash_of(&moved),
        "a mesh moved 0.3 units gives the same hash"
    );
    // And merge refuses the two parts.
    let parts: Vec<PathBuf> = [(&here, 0), (&moved, 1)]
        .iter()
        .map(|(scene, i)| {
            let part = dir.path().join(format!("part{i}.exr"));
            let tile = format!("{i}/2");
            let output = lambert(&[
                "render",
                s(scene),
                "--tile",
                &tile,
                "-o",
                s(&part),
                "--device",
                "cpu",
            ]);
            assert!(output.status.success(), "{}", stderr(&output));
            part
        })
        .collect();
    let merged = dir.path().join("merged.png");
    let output = lambert(&["merge", s(&parts[0]), s(&parts[1]), "-o", s(&merged)]);
    assert!(!output.status.success(), "parts of two scenes merged");
    assert!(stderr(&output).contains("not parts of one render"));
    assert!(!merged.exists());
}

#[test]
fn a_temporary_of_another_writer_with_this_pid_is_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.pfm");
    // What another container's lambert, also this pid, is writing now
    // under the name a pid-only temporary would take.
    let theirs = dir
        .path()
        .join(format!(".out.pfm.{}.tmp", std::process::id()));
    std::fs::write(&theirs, b"another writer's bytes").unwrap();
    let image = Image {
        width: 3,
        height: 2,
        rgb: vec![[0.25, 0.5, 0.75]; 6],
    };
    image.save(&out).expect("the write succeeds");
    assert_eq!(
        std::fs::read(&theirs).unwrap(),
        b"another writer's bytes",
        "the other writer's temporary was opened"
    );
    // Ours is whole, and no temporary of ours stayed behind.
    let written = std::fs::read(&out).unwrap();
    assert!(written.starts_with(b"PF\n3 2\n"));
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

#[test]
fn temporaries_of_one_process_have_distinct_random_names() {
    // Two threads writing one output at once: each its own temporary,
    // each write whole.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.pfm");
    std::thread::scope(|scope| {
        for grey in [0.25f32, 0.75] {
            let out = &out;
            scope.spawn(move || {
                for _ in 0..50 {
                    Image {
                        width: 64,
                        height: 64,
                        rgb: vec![[grey; 3]; 64 * 64],
                    }
                    .save(out)
                    .expect("every write succeeds");
                }
            });
        }
    });
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["out.pfm"]);
}

/// Loads scene text from a temporary folder: its error, if any.
fn scene_error(text: &str) -> Option<String> {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "tri.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let path = write(dir.path(), "scene.toml", text);
    Scene::load(&path).err().map(|e| e.to_string())
}

#[test]
fn a_camera_degenerate_in_f32_is_an_error_naming_eye_and_look_at() {
    for (eye, look_at) in [
        ("[0.5, 5, 0.25000001]", "[0.5, 5, 0.25]"),
        ("[3.00000001, 1, 2]", "[3.0, 1, 2]"),
        ("[100000, 0, 7]", "[100000.001, 0, 7]"),
    ] {
        let text = format!(
            "[camera]\neye = {eye}\nlook_at = {look_at}\nvfov = 40.0\nwidth = 8\nheight = 8\n\
             {LIGHT}[[mesh]]\nfile = \"tri.obj\"\n"
        );
        let message =
            scene_error(&text).unwrap_or_else(|| panic!("eye {eye}, look_at {look_at} loaded"));
        assert!(
            message.contains("camera.eye") && message.contains("camera.look_at"),
            "{message}"
        );
        assert!(message.contains("f32"), "{message}");
    }
    // Apart in f32: no error.
    let text = format!(
        "[camera]\neye = [0.5, 5, 0.2501]\nlook_at = [0.5, 5, 0.25]\nvfov = 40.0\nwidth = 8\n\
         height = 8\n{LIGHT}[[mesh]]\nfile = \"tri.obj\"\n"
    );
    assert_eq!(scene_error(&text), None);
}

#[test]
fn turntable_frames_that_name_one_file_are_refused_before_rendering() {
    let (dir, scene) = room();
    let pattern = dir.path().join("d{}/../same.png");
    let output = lambert(&turntable_args(&scene, "3", &pattern));
    let text = stderr(&output);
    assert!(!output.status.success(), "{text}");
    assert!(text.contains("frames 0 and 1"), "{text}");
    assert!(!dir.path().join("same.png").exists());
}

#[test]
fn a_range_of_frames_says_how_many_of_how_many() {
    let (dir, scene) = room();
    let pattern = dir.path().join("f{}.png");
    let output = lambert(
        &[
            &turntable_args(&scene, "4", &pattern)[..],
            &["--frames", "0-2"],
        ]
        .concat(),
    );
    let text = stderr(&output);
    assert!(output.status.success(), "{text}");
    assert!(text.contains("rendering 3 of 4 frames"), "{text}");
}

#[test]
fn an_adapter_that_cannot_run_the_kernel_is_refused_in_words_and_auto_falls_back() {
    let (dir, scene) = room();
    let out = dir.path().join("out.png");
    // GL (Mesa's llvmpipe through EGL): wgpu's GL backend is refused.
    let gpu = lambert(&[&render_args(&scene, &out, "gpu")[..], &["--backend", "gl"]].concat());
    let text = stderr(&gpu);
    assert!(!gpu.status.success(), "{text}");
    assert!(!text.contains("Too many bindings"), "{text}");
    assert!(
        text.contains("cannot run lambert") && text.contains("GL backend"),
        "GL's adapter not found or not refused in words (GL tests need Mesa's \
         libegl-mesa0): {text}"
    );
    assert!(!out.exists());
    // `info` says so of the adapter.
    let info = lambert(&["info", "--backend", "gl"]);
    let listed = String::from_utf8_lossy(&info.stdout);
    assert!(listed.contains("cannot run lambert"), "{listed}");
    // Named, a software adapter is auto's choice: it falls back instead.
    let auto = lambert(&[
        "render",
        s(&scene),
        "-o",
        s(&out),
        "--backend",
        "gl",
        "--adapter",
        "llvmpipe",
    ]);
    let text = stderr(&auto);
    assert!(auto.status.success(), "{text}");
    assert!(text.contains("using the CPU path instead"), "{text}");
    assert!(out.exists());
}

#[test]
fn info_prints_a_far_model_s_bounds_in_world_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let model = write(
        dir.path(),
        "far.obj",
        "v 3000000 0 0\nv 3000001 0 0\nv 3000000 1 0\nf 1 2 3\n",
    );
    let output = lambert(&["info", s(&model)]);
    assert!(output.status.success(), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    let bounds = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("bounds:"))
        .unwrap_or_else(|| panic!("no bounds: {stdout}"));
    assert!(
        bounds.contains("[3000000, 0, 0] to [3000001, 1, 0]"),
        "{bounds}"
    );
    assert!(bounds.contains("centre [3000000.5, 0.5, 0]"), "{bounds}");
}

/// Runs `lambert render` of a fresh room with `options`: its status and
/// stderr.
fn render_with(options: &[&str]) -> (bool, String) {
    let (dir, scene) = room();
    let out = dir.path().join("out.png");
    let mut args = vec!["render", s(&scene), "-o", s(&out), "--device", "cpu"];
    args.extend(options);
    let output = lambert(&args);
    (output.status.success(), stderr(&output))
}

#[test]
fn spp_with_a_time_budget_and_max_spp_alone_are_refused_in_words() {
    let (ok, text) = render_with(&["--time-budget", "0.2", "--spp", "4"]);
    assert!(!ok, "{text}");
    assert!(
        text.contains("--time-budget")
            && text.contains("--spp")
            && text.contains("cannot be used with"),
        "{text}"
    );
    let (ok, text) = render_with(&["--max-spp", "8"]);
    assert!(!ok, "{text}");
    assert!(text.contains("--target-error"), "{text}");
    let (ok, text) = render_with(&["--max-spp", "8", "--target-error", "0.5"]);
    assert!(ok, "{text}");
}

/// Waits until process `pid` catches SIGHUP, SIGINT and SIGTERM (its
/// handlers installed: a signal before would kill it outright), from
/// Linux's /proc/PID/status.
fn wait_for_signal_handlers(pid: u32) {
    let wanted = (1u64 << 0) | (1 << 1) | (1 << 14); // signals 1, 2 and 15
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    loop {
        let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
        let caught = status
            .lines()
            .find_map(|l| l.strip_prefix("SigCgt:"))
            .and_then(|mask| u64::from_str_radix(mask.trim(), 16).ok())
            .unwrap_or(0);
        if caught & wanted == wanted {
            // And a moment for the chained handler after ctrlc's.
            std::thread::sleep(std::time::Duration::from_millis(100));
            return;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "process {pid} installed no signal handlers in 20 s"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

#[test]
fn sigterm_exits_143_and_sigint_130() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "[camera]\neye = [0.5, 0.5, 3.0]\nlook_at = [0.5, 0.5, 0.0]\nvfov = 40.0\n\
         width = 1024\nheight = 1024\n[render]\nspp = 256\n\
         [[sphere]]\ncenter = [0.5, 0.5, 0.0]\nradius = 1.0\n{LIGHT}"
    );
    let scene = write(dir.path(), "slow.toml", text);
    let out = dir.path().join("out.pfm");
    for (signal, code) in [("-TERM", 143), ("-INT", 130), ("-HUP", 129)] {
        let mut child = common::lambert_command()
            .args(["render", s(&scene), "-o", s(&out), "--device", "cpu", "-q"])
            .spawn()
            .unwrap();
        wait_for_signal_handlers(child.id());
        let killed = std::process::Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "kill {signal}: {status:?}");
    }
}

/// `lambert bench --time-vs-error` of `scenes` at its cheapest, with
/// `--plot plot`.
fn bench_plot(scenes: &[&Path], plot: &Path) -> Output {
    let mut args = CHEAPEST_BENCH.to_vec();
    args.extend(["--plot", s(plot)]);
    args.extend(scenes.iter().map(|p| s(p)));
    lambert(&args)
}

#[test]
fn time_vs_error_plots_of_two_scenes_of_one_name_are_both_kept() {
    let dir = tempfile::tempdir().unwrap();
    let scenes: Vec<PathBuf> = ["a", "b"]
        .iter()
        .map(|folder| {
            let folder = dir.path().join(folder);
            std::fs::create_dir_all(&folder).unwrap();
            let text =
                format!("{CAMERA}{LIGHT}[[sphere]]\ncenter = [0.5, 0.5, 0.0]\nradius = 0.5\n");
            write(&folder, "scene.toml", text)
        })
        .collect();
    let plot = dir.path().join("plots");
    let output = bench_plot(&[&scenes[0], &scenes[1]], &plot);
    assert!(output.status.success(), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    for name in ["a_scene", "b_scene"] {
        assert!(
            plot.join(format!("time_vs_error_{name}.png")).exists(),
            "no plot of {name}: {:?}",
            std::fs::read_dir(&plot).unwrap().collect::<Vec<_>>()
        );
    }
    assert!(
        stdout.contains("a/scene:") && stdout.contains("b/scene:"),
        "{stdout}"
    );
    // --plot naming a file says what --plot wants.
    let file = write(dir.path(), "plot.png", "not a folder");
    let output = bench_plot(&[&scenes[0]], &file);
    let text = stderr(&output);
    assert!(!output.status.success());
    assert!(
        text.contains("not a folder") && text.contains("--plot"),
        "{text}"
    );
}
