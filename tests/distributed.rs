//! Tiled renders merged by `lambert merge` and turntable frame ranges equal single renders (issue 20).

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{lambert, s};

fn scene(name: &str) -> &'static str {
    // Leaked: a few short paths, for the argument lists' lifetimes.
    Box::leak(format!("{}/assets/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR")).into_boxed_str())
}

fn ok(out: Output, what: &str) {
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Renders `scene` in `count` parts and merges them to `out`.
fn parts_and_merge(
    dir: &Path,
    scene: &str,
    count: u32,
    extra: &[&str],
    out: &Path,
) -> Vec<PathBuf> {
    let mut parts = Vec::new();
    for i in 0..count {
        let part = dir.join(format!("part{i}.exr"));
        let tile = format!("{i}/{count}");
        let mut args = vec!["render", scene, "--tile", &tile, "-o", s(&part), "-q"];
        args.extend(extra);
        ok(lambert(&args), &tile);
        parts.push(part);
    }
    // Any order.
    let mut merge = vec!["merge".to_string()];
    merge.extend(parts.iter().rev().map(|p| s(p).to_string()));
    merge.extend(["-o".into(), s(out).into()]);
    ok(
        lambert(&merge.iter().map(String::as_str).collect::<Vec<_>>()),
        "merge",
    );
    parts
}

#[test]
fn merged_parts_equal_the_single_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (name, count, spp, device) in [
        ("spheres", 3, "1", "cpu"),
        ("bunny", 4, "3", "cpu"),
        ("cornell", 2, "2", "gpu"),
        ("edge_cases", 7, "1", "gpu"),
    ] {
        let extra = ["--spp", spp, "--device", device];
        for format in ["png", "exr"] {
            let merged = d.join(format!("{name}_merged.{format}"));
            let single = d.join(format!("{name}_single.{format}"));
            parts_and_merge(d, scene(name), count, &extra, &merged);
            let mut args = vec!["render", scene(name), "-o", s(&single), "-q"];
            args.extend(extra);
            ok(lambert(&args), "single");
            let what = format!("{name}, {count} parts, {spp} spp on the {device}, {format}");
            if format == "png" {
                assert!(
                    std::fs::read(&merged).unwrap() == std::fs::read(&single).unwrap(),
                    "{what}: PNGs differ"
                );
            } else {
                let read = |p: &Path| image::open(p).unwrap().to_rgb32f().into_raw();
                let (a, b) = (read(&merged), read(&single));
                assert_eq!(a.len(), b.len());
                assert!(
                    a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                    "{what}: values differ"
                );
            }
        }
    }
}

#[test]
fn bad_merges_are_refused_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("out.png");
    let parts = parts_and_merge(d, scene("spheres"), 3, &["--device", "cpu"], &out);
    std::fs::write(&out, "previous").unwrap();
    // One part of `scene` as `name` in the folder, with `extra` options.
    let part = |name: &str, scene_name: &str, tile: &str, extra: &[&str]| {
        let path = d.join(name);
        let mut args = vec![
            "render",
            scene(scene_name),
            "--tile",
            tile,
            "-o",
            s(&path),
            "-q",
        ];
        args.extend(extra);
        ok(lambert(&args), name);
        path
    };
    let cpu = ["--device", "cpu"];
    let other_spp = part(
        "other_spp.exr",
        "spheres",
        "1/3",
        &["--spp", "2", "--device", "cpu"],
    );
    let other_scene = part(
        "other_scene.exr",
        "bunny",
        "1/3",
        &["--device", "cpu", "--width", "200", "--height", "150"],
    );
    let other_count = part("other_count.exr", "spheres", "1/4", &cpu);
    let other_size = part(
        "other_size.exr",
        "spheres",
        "1/3",
        &["--device", "cpu", "--width", "100"],
    );
    let gpu_part = part("gpu.exr", "spheres", "1/3", &["--device", "gpu"]);
    let not_part = d.join("plain.exr");
    ok(
        lambert(&[
            "render",
            scene("spheres"),
            "-o",
            s(&not_part),
            "--device",
            "cpu",
            "-q",
        ]),
        "plain",
    );
    let [p0, p1, p2] = [&parts[0], &parts[1], &parts[2]].map(|p| s(p));
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (vec![p0, p2], vec!["parts missing: 1/3"]),
        (vec![p0, p1, p1, p2], vec!["part1.exr", "both part 1/3"]),
        (
            vec![p0, s(&other_spp), p2],
            vec!["other_spp.exr", "other settings"],
        ),
        (
            vec![p0, s(&other_scene), p2],
            vec!["other_scene.exr", "other settings"],
        ),
        (vec![p0, s(&gpu_part), p2], vec!["gpu.exr", "device"]),
        (
            vec![p0, s(&other_count), p2],
            vec!["other_count.exr", "one of 4 parts"],
        ),
        (
            vec![p0, s(&other_size), p2],
            vec!["other_size.exr", "100×75"],
        ),
        (
            vec![p0, s(&not_part), p2],
            vec!["plain.exr", "not a lambert part"],
        ),
    ];
    for (inputs, expected) in cases {
        let mut args = vec!["merge"];
        args.extend(&inputs);
        args.extend(["-o", s(&out)]);
        let output = lambert(&args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{inputs:?}: {stderr}");
        for e in expected {
            assert!(
                stderr.contains(e),
                "{inputs:?}: stderr lacks '{e}': {stderr}"
            );
        }
        assert_eq!(
            std::fs::read(&out).unwrap(),
            b"previous",
            "{inputs:?} touched the output"
        );
    }
    for (args, expected) in [
        (vec!["--tile", "3/3"], "0 ≤ I < N"),
        (vec!["--tile", "1/0"], "0 ≤ I < N"),
        (vec!["--tile", "x"], "expected I/N"),
        (vec!["--tile", "0/200"], "N must be at most"),
        (
            vec!["--tile", "0/2", "--target-error", "0.01"],
            "--target-error",
        ),
        (vec!["--tile", "0/2", "--time-budget", "1"], "--time-budget"),
    ] {
        let part = d.join("p.exr");
        let mut full = vec![
            "render",
            scene("spheres"),
            "-o",
            s(&part),
            "--device",
            "cpu",
        ];
        full.extend(&args);
        let output = lambert(&full);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    let output = lambert(&[
        "render",
        scene("spheres"),
        "--tile",
        "0/2",
        "-o",
        s(&d.join("p.png")),
    ]);
    assert!(String::from_utf8_lossy(&output.stderr).contains("name it .exr"));
}

#[test]
fn frame_ranges_render_only_their_frames_with_the_full_names() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let full = d.join("full/f_{:03}.png");
    let split = d.join("split/f_{:03}.png");
    let base = [
        "--turntable",
        "5",
        "--device",
        "cpu",
        "-q",
        "--width",
        "40",
        "--height",
        "30",
    ];
    let mut args = vec!["render", scene("spheres"), "-o", s(&full)];
    args.extend(base);
    ok(lambert(&args), "full");
    for range in ["0-1", "2", "3-4"] {
        let mut args = vec![
            "render",
            scene("spheres"),
            "-o",
            s(&split),
            "--frames",
            range,
        ];
        args.extend(base);
        ok(lambert(&args), range);
    }
    for frame in 0..5 {
        let name = format!("f_{frame:03}.png");
        assert_eq!(
            std::fs::read(d.join("full").join(&name)).unwrap(),
            std::fs::read(d.join("split").join(&name)).unwrap(),
            "{name}"
        );
    }
    let only = d.join("only/f_{:03}.png");
    let mut args = vec![
        "render",
        scene("spheres"),
        "-o",
        s(&only),
        "--frames",
        "3-4",
    ];
    args.extend(base);
    ok(lambert(&args), "3-4");
    let names: Vec<_> = std::fs::read_dir(d.join("only"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
    for bad in ["4-3", "0-5", "x", "-1"] {
        let mut args = vec!["render", scene("spheres"), "-o", s(&only), "--frames", bad];
        args.extend(base);
        let output = lambert(&args);
        assert!(
            output.status.code().is_some_and(|c| c != 0),
            "--frames {bad} accepted"
        );
    }
}

/// Issue 28 item 15: an output that is one of the parts (by name, through
/// a symlink or a hard link, or a name the glob of a second run picks up)
/// is refused, and nothing is written.
#[test]
fn merge_refuses_an_output_that_is_one_of_its_parts() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let all = d.join("part_all.exr");
    let parts = parts_and_merge(d, scene("spheres"), 3, &["--device", "cpu"], &all);
    let bytes: Vec<Vec<u8>> = parts.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let symlink = d.join("link.exr");
    std::os::unix::fs::symlink(&parts[1], &symlink).unwrap();
    let hard = d.join("hard.exr");
    std::fs::hard_link(&parts[2], &hard).unwrap();
    let dotted = d.join(".").join("part0.exr");
    let [p0, p1, p2] = [&parts[0], &parts[1], &parts[2]].map(|p| s(p));
    let merged_before = std::fs::read(&all).unwrap();
    for (inputs, output) in [
        (vec![p0, p1, p2], s(&parts[1])),
        (vec![p0, p1, p2], s(&symlink)),
        (vec![p0, p1, p2], s(&hard)),
        (vec![p0, p1, p2], s(&dotted)),
        // `merge part*.exr -o part_all.exr`, run a second time.
        (vec![p0, p1, p2, s(&all)], s(&all)),
    ] {
        let mut args = vec!["merge"];
        args.extend(&inputs);
        args.extend(["-o", output]);
        let out = lambert(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "-o {output}: {stderr}");
        assert!(
            stderr.starts_with("error: ")
                && stderr.contains("the output is one of the inputs")
                && stderr.contains(output),
            "-o {output}: {stderr}"
        );
        for (part, before) in parts.iter().zip(&bytes) {
            assert_eq!(&std::fs::read(part).unwrap(), before, "-o {output}");
        }
        assert_eq!(std::fs::read(&all).unwrap(), merged_before);
    }
    // A new output not among the parts is written as before.
    let fresh = d.join("fresh.exr");
    ok(
        lambert(&["merge", p0, p1, p2, "-o", s(&fresh), "-q"]),
        "fresh",
    );
    assert_eq!(std::fs::read(&fresh).unwrap(), merged_before);
}

/// The same part, rendered again, is the same file byte for byte (its
/// EXR attributes were once written in a random order).
#[test]
fn a_part_rendered_twice_is_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let mut first: Option<Vec<u8>> = None;
    for run in 0..6 {
        let path = dir.path().join(format!("part_{run}.exr"));
        let out = path.to_str().unwrap();
        ok(
            lambert(&[
                "render",
                scene("cornell"),
                "--device",
                "cpu",
                "--width",
                "32",
                "--height",
                "32",
                "--tile",
                "0/2",
                "-q",
                "-o",
                out,
            ]),
            "tile",
        );
        let bytes = std::fs::read(&path).unwrap();
        match &first {
            None => first = Some(bytes),
            Some(f) => assert!(*f == bytes, "run {run} wrote other bytes than run 0"),
        }
    }
}
