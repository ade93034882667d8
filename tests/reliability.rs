//! Reliability (issue 21): fuzz findings, signals, concurrent writers, a full disk, the GPU's limits.

mod common;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use common::args::render_args;
use common::{lambert_command, s, temporaries};
use lambert::inputs::Input;

fn fuzz_dir(kind: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz")
        .join(kind)
}

/// The files of `fuzz/<kind>/<target>/`, each with its target.
fn fuzz_files(kind: &str) -> Vec<(Input, PathBuf)> {
    let mut files = Vec::new();
    for input in Input::ALL {
        let Ok(entries) = std::fs::read_dir(fuzz_dir(kind).join(input.name())) else {
            continue;
        };
        for entry in entries.flatten() {
            files.push((input, entry.path()));
        }
    }
    files.sort_by(|a, b| a.1.cmp(&b.1));
    files
}

/// Every input the fuzz harness found a panic, a hang or a runaway
/// allocation with is now a clear error naming the file, within the
/// harness's one second.
#[test]
fn fuzz_findings_are_clear_errors() {
    let findings = fuzz_files("regressions");
    assert!(findings.len() >= 5, "{findings:?}");
    for (input, path) in findings {
        let bytes = std::fs::read(&path).unwrap();
        let start = Instant::now();
        let result = std::panic::catch_unwind(|| input.parse(&bytes, &path));
        let elapsed = start.elapsed();
        let result = result.unwrap_or_else(|_| panic!("{}: panicked", path.display()));
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if name.starts_with("accepted-") {
            result.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        } else {
            let message = result.expect_err(&name).to_string();
            assert!(
                message.contains(&path.display().to_string()),
                "{name}: the message does not name the file: {message}"
            );
        }
        assert!(elapsed < Duration::from_secs(1), "{name}: took {elapsed:?}");
    }
}

/// What the glTF and part findings are refused with: the reason, not a panic.
#[test]
fn findings_say_what_is_wrong() {
    let error = |name: &str| {
        let path = fuzz_dir("regressions").join("gltf").join(name);
        let bytes = std::fs::read(&path).unwrap();
        Input::Gltf.parse(&bytes, &path).unwrap_err().to_string()
    };
    let e = error("crash-position-accessor-out-of-range.gltf");
    assert!(
        e.contains("attribute POSITION names accessor 7, but the file has 2 accessors"),
        "{e}"
    );
    let e = error("crash-signed-short-indices.gltf");
    assert!(e.contains("indices accessor 1 holds Scalar I16"), "{e}");
    let e = error("crash-byte-stride-below-element.gltf");
    assert!(
        e.contains(
            "POSITION accessor 0: its buffer view 0 has byteStride 8, less than one element"
        ),
        "{e}"
    );
    let e = error("crash-glb-length-below-header.glb");
    assert!(e.contains("its GLB header declares 0 bytes"), "{e}");
    let path = fuzz_dir("regressions").join("part/memory-huge-band-in-a-small-file.exr");
    let e = Input::Part
        .parse(&std::fs::read(&path).unwrap(), &path)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("claims 1610612736 bytes of pixels, more than its 550 bytes"),
        "{e}"
    );
    for cyclic in ["slow-node-cycle.gltf", "memory-shared-children.gltf"] {
        let e = error(cyclic);
        assert!(e.contains("is reached twice from the scene's roots"), "{e}");
    }
}

/// Images the gltf crate's validation lets through but its `Image::source`
/// unwraps (found by `scripts/fuzz --short`): a warning naming the image,
/// and the model loads with its material's factor.
#[test]
fn images_without_a_source_are_warnings_not_panics() {
    for (name, why) in [
        (
            "accepted-image-buffer-view-without-mime-type.gltf",
            "image 0: it has a bufferView but no mimeType",
        ),
        (
            "accepted-image-without-uri-or-buffer-view.gltf",
            "image 0: it has neither a bufferView nor a uri",
        ),
    ] {
        let path = fuzz_dir("regressions").join("gltf").join(name);
        let scene = lambert::Scene::load(&path).unwrap();
        let warnings = scene.warnings().join("\n");
        assert!(warnings.contains(why), "{name}: {warnings}");
    }
}

/// The saved corpus (the harness's seeds) still parses without a panic,
/// and its valid seeds still load: the corpus exercises the parsers' real
/// paths, not only their first error.
#[test]
fn the_fuzz_corpus_parses() {
    let corpus = fuzz_files("corpus");
    let mut loaded = std::collections::BTreeMap::<&str, usize>::new();
    for (input, path) in &corpus {
        let bytes = std::fs::read(path).unwrap();
        let result = std::panic::catch_unwind(|| input.parse(&bytes, path));
        let result = result.unwrap_or_else(|_| panic!("{}: panicked", path.display()));
        if result.is_ok() {
            *loaded.entry(input.name()).or_default() += 1;
        }
    }
    // The TOML seeds name meshes beside them, which the harness's path
    // does not have; every other target has valid seeds.
    for input in Input::ALL.iter().filter(|i| **i != Input::Toml) {
        assert!(
            loaded.get(input.name()).is_some_and(|n| *n > 0),
            "{}: {loaded:?}",
            input.name()
        );
    }
}

// ---- writes -----------------------------------------------------------------

const SCENE: &str = "[camera]\neye = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\n\
width = 16\nheight = 12\n[render]\nbackground = [0.2, 0.3, 0.5]\n\
[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n\
[[point_light]]\nposition = [0.0, 2.0, 3.0]\nintensity = 10.0\n";

/// SCENE at `width`×`height`, with background `background`, in `dir`.
fn scene_file(dir: &Path, name: &str, width: u32, height: u32, background: f32) -> PathBuf {
    let path = dir.join(name);
    let text = SCENE
        .replace(
            "width = 16\nheight = 12",
            &format!("width = {width}\nheight = {height}"),
        )
        .replace("[0.2, 0.3, 0.5]", &format!("[{background}, 0.3, 0.5]"));
    std::fs::write(&path, text).unwrap();
    path
}

/// The binary with Mesa's device-select layer off (it warns on lavapipe).
fn lambert() -> std::process::Command {
    let mut command = lambert_command();
    command.env("NODEVICE_SELECT", "1");
    command
}

/// SIGINT or SIGTERM at any moment of a merge (reading the parts, then
/// writing the image) leaves no temporary file and the previous output
/// whole.
#[test]
fn signals_during_merge_leave_the_previous_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = scene_file(d, "big.toml", 2048, 2048, 0.2);
    let parts: Vec<PathBuf> = (0..2).map(|i| d.join(format!("part{i}.exr"))).collect();
    for (i, part) in parts.iter().enumerate() {
        let tile = format!("{i}/2");
        let args = [
            "render",
            s(&scene),
            "-o",
            s(part),
            "--device",
            "cpu",
            "--tile",
            &tile,
            "-q",
        ];
        let out = lambert().args(args).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let output = d.join("out.pfm");
    let whole = 18 + 2048 * 2048 * 12;
    let mut interrupted = 0;
    for (round, delay_ms) in [5u64, 20, 40, 80, 120, 160, 220, 300].iter().enumerate() {
        std::fs::write(&output, "previous").unwrap();
        let child = lambert()
            .args(["merge", s(&parts[0]), s(&parts[1]), "-o", s(&output)])
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let (success, bytes) = common::signals::interrupt(child, round, *delay_ms, d, &output);
        interrupted += common::previous_or_whole(success, &bytes, whole, *delay_ms) as usize;
    }
    assert!(
        interrupted > 0,
        "no merge was interrupted before its output"
    );
}

/// Renders of different scenes to one file at the same moment leave one
/// of the complete images, byte for byte, never a mixture, and no
/// temporary file.
#[test]
fn concurrent_renders_to_one_output_leave_one_whole_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let writers = 3;
    let scenes: Vec<PathBuf> = (0..writers)
        .map(|i| scene_file(d, &format!("s{i}.toml"), 384, 384, 0.1 + 0.3 * i as f32))
        .collect();
    let references: Vec<Vec<u8>> = scenes
        .iter()
        .enumerate()
        .map(|(i, scene)| {
            let out = d.join(format!("reference{i}.pfm"));
            let status = lambert()
                .args(["render", s(scene), "-o", s(&out), "--device", "cpu", "-q"])
                .status()
                .unwrap();
            assert!(status.success());
            std::fs::read(out).unwrap()
        })
        .collect();
    assert!(references[0] != references[1]);
    let output = d.join("out.pfm");
    let mut winners = std::collections::BTreeSet::new();
    for round in 0..6 {
        let children: Vec<_> = scenes
            .iter()
            .map(|scene| {
                lambert()
                    .args(render_args(scene, &output, "cpu"))
                    .arg("-q")
                    .spawn()
                    .unwrap()
            })
            .collect();
        for mut child in children {
            assert!(child.wait().unwrap().success(), "round {round}");
        }
        let bytes = std::fs::read(&output).unwrap();
        let winner = references.iter().position(|r| *r == bytes);
        assert!(
            winner.is_some(),
            "round {round}: the output is no writer's whole image"
        );
        winners.extend(winner);
        assert!(temporaries(d).is_empty(), "{:?}", temporaries(d));
    }
    // Which writer's rename lands last is the scheduler's choice.
    let _ = writeln_stderr(&format!(
        "concurrent writers: images of writers {winners:?} won"
    ));
}

fn writeln_stderr(line: &str) -> std::io::Result<()> {
    use std::io::Write;
    writeln!(std::io::stderr(), "{line}")
}

/// A write that fails for lack of space (a 1 MiB tmpfs, mounted in a
/// private mount namespace) is an error naming the file, and leaves the
/// previous output and no temporary file.
#[test]
fn a_full_disk_leaves_the_previous_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = scene_file(d, "scene.toml", 512, 512, 0.2);
    let small = d.join("small");
    std::fs::create_dir(&small).unwrap();
    let output = small.join("out.pfm");
    // Everything that needs the mount runs inside the namespace.
    let script = format!(
        "mount -t tmpfs -o size=1m tmpfs '{dir}' || exit 90
         printf previous > '{out}'
         '{lambert}' render '{scene}' -o '{out}' --device cpu -q
         echo \"status=$?\"
         echo \"previous=$(cat '{out}')\"
         echo \"files=$(ls -A '{dir}' | tr '\\n' ' ')\"",
        dir = s(&small),
        out = s(&output),
        lambert = env!("CARGO_BIN_EXE_lambert"),
        scene = s(&scene),
    );
    let out = std::process::Command::new("unshare")
        .args(["-rm", "sh", "-c", &script])
        .env("NODEVICE_SELECT", "1")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(90) || !out.status.success() && stdout.is_empty() {
        let _ = writeln_stderr(&format!(
            "skipped: the full-disk case needs a tmpfs mount (root or user namespaces): {stderr}"
        ));
        return;
    }
    assert!(stdout.contains("status=1\n"), "{stdout}\n{stderr}");
    assert!(stdout.contains("previous=previous\n"), "{stdout}\n{stderr}");
    assert!(stdout.contains("files=out.pfm \n"), "{stdout}\n{stderr}");
    assert!(
        stderr.contains("out.pfm") && stderr.contains("No space left on device"),
        "{stderr}"
    );
}

// ---- the GPU's limits and a lost device --------------------------------------

/// A cap on what lambert requests: lavapipe then behaves as a GPU whose
/// buffers and bindings hold 64 KiB.
const SMALL_GPU: u64 = 1 << 16;

/// A scene larger than the adapter's buffer and binding limits is an error
/// that says what does not fit and by how much.
#[test]
fn a_scene_beyond_the_gpu_limits_says_what_and_by_how_much() {
    use lambert::gpu::{AdapterRequest, Gpu, GpuRenderer};
    let scene = common::load("bunny");
    // On lavapipe the triangles lie in textures with the BVH; their
    // shading normals, as many bytes, in a buffer.
    let bytes = scene.normals().len() * 48;
    let gpu = Gpu::open_limited(&AdapterRequest::default(), false, Some(SMALL_GPU))
        .expect("a GPU adapter (lavapipe: apt-get install mesa-vulkan-drivers)");
    assert_eq!(gpu.limits.max_buffer_size, SMALL_GPU);
    let Err(error) = GpuRenderer::new(gpu, &scene) else {
        panic!("the bunny fits in 64 KiB buffers");
    };
    assert!(matches!(error, lambert::Error::GpuLimit(_)), "{error:?}");
    let message = error.to_string();
    // The scene's words hold every read-only array: the message names
    // each with its size, and the limit.
    assert!(
        message.contains("the scene's arrays take")
            && message.contains(&format!("triangle normals {bytes} bytes"))
            && message.contains(&format!("more than the {SMALL_GPU} bytes")),
        "{message}"
    );
    assert!(message.contains("max_buffer_size 65536"), "{message}");
    // The full limits take it.
    assert!(GpuRenderer::new(common::open_gpu(), &scene).is_ok());
}

/// Through the CLI: `--device gpu` fails with that message and writes
/// nothing; `--device auto` renders on the CPU path with a note.
#[test]
fn too_large_for_the_gpu_fails_or_falls_back_to_the_cpu() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::asset("scenes/bunny.toml");
    let output = dir.path().join("out.png");
    let run = |device: &str| {
        lambert()
            .args(["render", s(&scene), "-o", s(&output), "--device", device])
            .args(["--adapter", "llvmpipe", "--width", "32", "--height", "32"])
            .env(lambert::gpu::MAX_BUFFER_ENV, SMALL_GPU.to_string())
            .output()
            .unwrap()
    };
    let out = run("gpu");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("triangle normals 176448 bytes")
            && stderr.contains("more than the 65536 bytes"),
        "{stderr}"
    );
    assert!(!output.exists());
    let out = run("auto");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("triangle normals 176448 bytes"), "{stderr}");
    assert!(
        stderr.contains("note: using the CPU path instead"),
        "{stderr}"
    );
    assert!(stderr.contains("CPU reference path"), "{stderr}");
    assert!(output.exists());
}

/// A validation error (here: a tile buffer beyond the capped buffer size)
/// is an error with wgpu's message, exit status 1 and no image.
#[test]
fn a_validation_error_is_an_error_with_the_adapters_message() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("out.png");
    let out = lambert()
        .args([
            "render",
            s(&common::asset("scenes/spheres.toml")),
            "-o",
            s(&output),
        ])
        .args(["--device", "gpu", "--width", "32", "--height", "32"])
        .env(lambert::gpu::MAX_BUFFER_ENV, SMALL_GPU.to_string())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("error: GPU: ") && stderr.contains("Validation Error"),
        "{stderr}"
    );
    assert!(!output.exists());
    assert!(temporaries(dir.path()).is_empty());
}

/// A device lost mid-work (destroyed here: what a driver reset or a
/// removed GPU looks like to wgpu) is an error that says so, within
/// seconds: no hang, and no image.
#[test]
fn a_lost_device_is_an_error_not_a_hang() {
    use lambert::gpu::GpuRenderer;
    let scene = common::load("spheres");
    let mut renderer = GpuRenderer::new(common::open_gpu(), &scene).expect("scene uploads");
    let view = scene.view().clone();
    renderer.gpu().device.destroy();
    let (sender, receiver) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let result = renderer.render(&view, &lambert::progress::Progress::hidden());
        let _ = sender.send(result.map(|_| ()).map_err(|e| e.to_string()));
    });
    let result = receiver
        .recv_timeout(Duration::from_secs(60))
        .expect("the render hung on a lost device");
    let message = result.expect_err("a render on a destroyed device succeeded");
    assert!(message.starts_with("GPU: "), "{message}");
    assert!(message.contains("lost"), "{message}");
    let _ = writeln_stderr(&format!("a destroyed device's render: {message}"));
}

/// Once a scene is on the GPU, its host copy of the geometry can go (the
/// render jobs let it go after the upload): the GPU renderer keeps none of
/// it, and renders from another camera, at more samples and adaptive
/// sampling's pixel lists are the same without it.
#[test]
fn a_gpu_render_does_not_need_the_hosts_geometry() {
    use lambert::render::{DeviceChoice, Renderer};
    use std::sync::Arc;
    for name in ["bunny", "spheres", "cornell"] {
        let mut scene = common::load(name);
        (
            scene.view_mut().camera.width,
            scene.view_mut().camera.height,
        ) = (64, 48);
        scene.view_mut().spp = 2;
        let view = scene.view().clone();
        let scene = Arc::new(scene);
        let host = Arc::downgrade(&scene);
        let (mut renderer, _) =
            Renderer::open(Arc::clone(&scene), DeviceChoice::Gpu, &Default::default())
                .expect("opens");
        let (before, _) = renderer.render(&view, None).expect("renders");
        let pixels = [[0, 0], [view.camera.width / 2, view.camera.height / 2]];
        let list = renderer
            .render_pixel_list(&view, &pixels)
            .expect("pixel list");
        assert!(scene.primitive_count() > 0);
        drop(scene);
        assert!(
            host.upgrade().is_none(),
            "{name}: the GPU renderer holds the host's scene"
        );
        let (after, _) = renderer
            .render(&view, None)
            .expect("renders without the geometry");
        assert_eq!(before, after, "{name}");
        assert_eq!(
            list,
            renderer
                .render_pixel_list(&view, &pixels)
                .expect("pixel list")
        );
        // And from another camera, at another sample count: only the view
        // changes, not the scene.
        let mut moved = view.clone();
        moved.camera.eye[0] += 0.5;
        moved.spp = 3;
        let (moved_image, _) = renderer.render(&moved, None).expect("renders");
        let mut reference = common::load(name);
        *reference.view_mut() = moved.clone();
        let (fresh, _) =
            Renderer::open(Arc::new(reference), DeviceChoice::Gpu, &Default::default())
                .expect("opens")
                .0
                .render(&moved, None)
                .expect("renders");
        assert_eq!(moved_image, fresh, "{name} from another camera");
    }
}

/// Every model in the fuzz corpus and regressions that parses makes a BVH,
/// and a compressed one, that `validate` accepts: what the harness checks
/// of each input it makes.
#[test]
fn fuzz_models_build_valid_trees() {
    let mut checked = 0;
    for (input, path) in fuzz_files("corpus")
        .into_iter()
        .chain(fuzz_files("regressions"))
    {
        let bytes = std::fs::read(&path).unwrap();
        let Ok(Some(scene)) = input.model_scene(&bytes, &path) else {
            continue;
        };
        let bvh = &scene.bvh();
        bvh.validate(scene.triangles(), scene.spheres())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        lambert::cwbvh::validate(&lambert::cwbvh::compress(bvh), bvh)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        checked += 1;
    }
    assert!(checked >= 10, "only {checked} models built a scene");
}
