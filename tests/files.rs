//! Inputs are regular files read with a size cap; a model without triangles is one error (issue 28).
// Items 7 and 13 of issue 28. Each run of the binary has a deadline: a
// regression here is a hang, which must fail the test rather than stall
// the suite.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::args::trace_args;
use common::{lambert_with_deadline as lambert, s, write};

/// Runs lambert, expecting a failure whose message holds `expected`.
fn fails(args: &[&str], expected: &str) {
    let (code, _, stderr) = lambert(args);
    assert!(
        code.is_some_and(|c| c != 0),
        "{args:?}: exit {code:?}; {stderr}"
    );
    assert!(
        stderr.contains(expected),
        "{args:?}: expected '{expected}' in: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

fn fifo(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    let made = Command::new("mkfifo").arg(&path).status().unwrap();
    assert!(made.success());
    path
}

/// A file of `size` bytes that takes no space: its metadata alone says
/// it is too large.
fn sparse(dir: &Path, name: &str, size: u64) -> PathBuf {
    let path = dir.join(name);
    std::fs::File::create(&path).unwrap().set_len(size).unwrap();
    path
}

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
const CAMERA: &str = "[camera]\neye = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 8\nheight = 8\n";

/// `mtllib` naming a FIFO, `/dev/zero`, a folder or an over-cap file:
/// each a warning naming it and what it is, and the model still loads
/// (as a missing MTL file does).
#[test]
fn material_libraries_that_are_not_regular_files_are_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fifo(d, "pipe.mtl");
    std::fs::create_dir(d.join("folder.mtl")).unwrap();
    sparse(d, "huge.mtl", 300 << 20);
    let obj = write(
        d,
        "m.obj",
        format!("mtllib pipe.mtl /dev/zero folder.mtl huge.mtl\n{TRIANGLE}"),
    );
    let (code, stdout, stderr) = lambert(&["info", s(&obj)]);
    assert_eq!(code, Some(0), "{stdout}{stderr}");
    assert!(stdout.contains("triangles: 1"), "{stdout}");
    for expected in [
        "pipe.mtl: material library not read (not a regular file (a FIFO))",
        "/dev/zero: material library not read (not a regular file (a character device))",
        "folder.mtl: material library not read (not a regular file (a directory))",
        "huge.mtl: material library not read (314572800 bytes, more than the 256 MiB that \
         lambert reads of one file)",
    ] {
        assert!(
            stdout.contains(expected),
            "expected '{expected}' in: {stdout}"
        );
    }
}

/// Every kind of input, given as a FIFO, a device or a folder, is refused
/// at once with its name and what it is.
#[test]
fn every_input_must_be_a_regular_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("out.png");
    for name in [
        "m.obj", "m.ply", "m.ply.gz", "m.gltf", "m.glb", "m.stl", "s.toml",
    ] {
        let pipe = fifo(d, name);
        let what = format!("{name}: not a regular file (a FIFO)");
        fails(&["info", s(&pipe)], &what);
        fails(&["render", s(&pipe), "-o", s(&out)], &what);
    }
    std::fs::create_dir(d.join("folder.obj")).unwrap();
    fails(
        &["info", s(&d.join("folder.obj"))],
        "folder.obj: not a regular file (a directory)",
    );
    // A scene naming a device (through a link) as its mesh.
    let link = d.join("zero.obj");
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    let scene = write(
        d,
        "device.toml",
        format!("{CAMERA}[[mesh]]\nfile = {:?}\n", s(&link)),
    );
    fails(
        &["info", s(&scene)],
        "zero.obj: not a regular file (a character device)",
    );
    // A glTF buffer that is a FIFO.
    let buffer = fifo(d, "buffer.bin");
    let gltf = write(
        d,
        "b.gltf",
        r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "buffer.bin", "byteLength": 36}]}"#,
    );
    fails(
        &["info", s(&gltf)],
        &format!("buffer 0: {}: not a regular file (a FIFO)", s(&buffer)),
    );
    // Ray files and parts.
    let rays = fifo(d, "rays.bin");
    let obj = write(d, "t.obj", TRIANGLE);
    fails(
        &trace_args(&obj, &rays, &d.join("hits.bin")),
        "rays.bin: not a regular file (a FIFO)",
    );
    let part = fifo(d, "part.exr");
    fails(
        &["merge", s(&part), "-o", s(&out)],
        "part.exr: not a regular file (a FIFO)",
    );
}

/// A file larger than its cap is refused from its size, before a byte is
/// read, naming the file and the cap.
#[test]
fn files_over_the_cap_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let big = sparse(d, "big.obj", (4 << 30) + 1);
    fails(
        &["info", s(&big)],
        "big.obj: 4294967297 bytes, more than the 4 GiB that lambert reads of one file",
    );
    let scene = sparse(d, "big.toml", (256 << 20) + 1);
    fails(
        &["info", s(&scene)],
        "big.toml: 268435457 bytes, more than the 256 MiB",
    );
}

/// A gzip bomb: the gunzipped size is bounded as the read is, not only
/// the file's.
#[test]
fn gunzipped_size_is_capped() {
    use std::io::Write;
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    gz.write_all(&vec![0u8; 1 << 20]).unwrap();
    let gz = gz.finish().unwrap();
    let path = Path::new("bomb.ply.gz");
    let message = lambert::files::gunzip_capped(&gz, path, 1 << 16)
        .unwrap_err()
        .to_string();
    assert_eq!(
        message,
        "bomb.ply.gz: unpacks to more than the 64 KiB that lambert reads of one file"
    );
    assert_eq!(
        lambert::files::gunzip_capped(&gz, path, 1 << 20)
            .unwrap()
            .len(),
        1 << 20
    );
}

/// A model without triangles (nothing, only points, only lines) is one
/// error in every format, naming the file and what it held, from a
/// render, `info` and a TOML scene alike.
#[test]
fn no_triangles_is_one_error_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("out.png");
    let ply_header = |vertices: usize, edges: usize| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n\
             property float z\nelement face 0\nproperty list uchar int vertex_indices\n\
             element edge {edges}\nproperty int vertex1\nproperty int vertex2\nend_header\n"
        )
    };
    // One triangle's worth of positions, the buffer of the glTF files.
    let positions: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    write(d, "positions.bin", positions);
    let gltf = |mode: &str| {
        let mesh = if mode.is_empty() {
            String::new()
        } else {
            format!(
                r#", "nodes": [{{"mesh": 0}}], "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "mode": {mode}}}]}}],
                "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}}],
                "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
                "buffers": [{{"byteLength": 36, "uri": "positions.bin"}}]"#
            )
        };
        let nodes = if mode.is_empty() { "[]" } else { "[0]" };
        format!(r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": {nodes}}}]{mesh}}}"#)
    };
    let cases = [
        ("empty.obj", String::new(), "0 points, 0 lines skipped"),
        (
            "points.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1 2 3\n".into(),
            "3 points, 1 lines skipped",
        ),
        (
            "lines.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3 1\n".into(),
            "3 points, 2 lines skipped",
        ),
        (
            "short.obj",
            "v 0 0 0\nv 1 0 0\nf 1 2\n".into(),
            "2 points, 0 lines skipped",
        ),
        (
            "faceless.ply",
            format!("{}0 0 0\n1 0 0\n0 1 0\n0 1\n", ply_header(3, 1)),
            "3 points, 1 lines skipped",
        ),
        ("nothing.ply", ply_header(0, 0), "0 points, 0 lines skipped"),
        ("points.gltf", gltf("0"), "3 points, 1 lines skipped"),
        ("lines.gltf", gltf("1"), "3 points, 1 lines skipped"),
        ("nomesh.gltf", gltf(""), "0 points, 0 lines skipped"),
    ];
    for (name, text, counts) in cases {
        let path = write(d, name, text);
        let expected = format!("{}: no triangles ({counts})", s(&path));
        fails(&["render", s(&path), "-o", s(&out)], &expected);
        fails(&["info", s(&path)], &expected);
        let scene = write(
            d,
            "scene.toml",
            format!("{CAMERA}[[mesh]]\nfile = {name:?}\n"),
        );
        fails(&["render", s(&scene), "-o", s(&out)], &expected);
    }
    assert!(!out.exists());
}
