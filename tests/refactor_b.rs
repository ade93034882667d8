//! Issue 45, item 1 and the gpu folder's last import circle: the GPU host's
//! files import each other in no circle, the wavefront has one name
//! (`ShadowDispatch::Wavefront`, and `wavefront` for
//! LAMBERT_SHADOW_DISPATCH), and a render's view is an argument of each
//! call, so that calls with other views in between change nothing.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use common::{assert_contains_all, open_gpu, scene};
use lambert::camera::View;
use lambert::gpu::{AdapterRequest, Gpu, GpuOptions, GpuRenderer, ShadowDispatch};
use lambert::output::Rendered;
use lambert::progress::Progress;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The sibling files a Rust source names through `super::` (`super::a::X`,
/// `use super::{a::X, b::{Y, Z}}`), out of `siblings`; comments skipped.
fn super_imports(source: &str, siblings: &BTreeSet<String>) -> BTreeSet<String> {
    let code: String = source
        .lines()
        .map(|line| line.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");
    let mut names = BTreeSet::new();
    for (at, _) in code.match_indices("super::") {
        let rest = &code[at + "super::".len()..];
        // A group reaches its closing brace; a path, its first name.
        let text = if rest.starts_with('{') {
            let mut depth = 0;
            let end = rest
                .char_indices()
                .find(|&(_, c)| {
                    depth += match c {
                        '{' => 1,
                        '}' => -1,
                        _ => 0,
                    };
                    depth == 0
                })
                .map_or(rest.len(), |(i, _)| i);
            &rest[..end]
        } else {
            rest.split(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .next()
                .unwrap_or("")
        };
        let mut word = String::new();
        let mut chars = text.chars().peekable();
        while let Some(c) = chars.next() {
            if c.is_alphanumeric() || c == '_' {
                word.push(c);
                continue;
            }
            if c == ':' && chars.peek() == Some(&':') && siblings.contains(&word) {
                names.insert(word.clone());
            }
            word.clear();
        }
        if siblings.contains(&word) && !rest.starts_with('{') && text.ends_with(&word) {
            // `super::a` alone names the file too.
            names.insert(word);
        }
    }
    names
}

/// A circle in `graph`, as its files in order, if there is one.
fn find_circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|n| n == node) {
            let mut circle = path[at..].to_vec();
            circle.push(node.to_string());
            return Some(circle);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(circle) = visit(next, graph, path, done) {
                return Some(circle);
            }
        }
        path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|node| visit(node, graph, &mut Vec::new(), &mut done))
}

/// The files of a folder module (`src/gpu/`) by their imports of each
/// other: `adapter.rs` and `device.rs` took each other's names until the
/// options both carry moved to `options.rs`.
fn gpu_import_graph() -> BTreeMap<String, BTreeSet<String>> {
    let dir = root().join("src/gpu");
    let mut sources = BTreeMap::new();
    for entry in std::fs::read_dir(&dir).expect("src/gpu") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "rs") {
            let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
            sources.insert(stem, std::fs::read_to_string(&path).expect("readable"));
        }
    }
    sources.remove("mod");
    let siblings: BTreeSet<String> = sources.keys().cloned().collect();
    sources
        .iter()
        .map(|(name, text)| {
            let mut imports = super_imports(text, &siblings);
            imports.remove(name);
            (name.clone(), imports)
        })
        .collect()
}

#[test]
fn the_gpu_files_import_each_other_in_no_circle() {
    let graph = gpu_import_graph();
    assert!(
        graph["device"].contains("adapter") && graph["renderer"].contains("upload"),
        "the import reader finds the files' imports: {graph:?}"
    );
    if let Some(circle) = find_circle(&graph) {
        panic!("src/gpu imports in a circle: {}", circle.join(" -> "));
    }
}

#[test]
fn the_circle_check_finds_a_circle_and_reads_groups() {
    let siblings: BTreeSet<String> = ["a", "b", "c"].map(String::from).into();
    let imports = super_imports(
        "use super::{X, a::{Y, Z}};\n// super::c::W, a comment\nfn f() { super::b::g() }",
        &siblings,
    );
    assert_eq!(imports, ["a", "b"].map(String::from).into());
    let edges = |pairs: &[(&str, &str)]| {
        let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (from, to) in pairs {
            graph
                .entry(from.to_string())
                .or_default()
                .insert(to.to_string());
        }
        graph
    };
    assert_eq!(find_circle(&edges(&[("a", "b"), ("b", "c")])), None);
    assert_eq!(
        find_circle(&edges(&[("a", "b"), ("b", "c"), ("c", "b")])),
        Some(["b", "c", "b"].map(String::from).to_vec())
    );
}

/// A small scene with shadows (the wavefront applies): two balls on a
/// floor (a large sphere), one point light.
fn shadowed_scene() -> lambert::Scene {
    scene(
        "[camera]\neye = [0.0, 1.5, 4.0]\nlook_at = [0.0, 0.3, 0.0]\nvfov = 45.0\n\
         width = 40\nheight = 28\n\
         [[sphere]]\ncenter = [-0.5, 0.5, 0.0]\nradius = 0.5\n\
         [[sphere]]\ncenter = [0.7, 0.3, 0.4]\nradius = 0.3\n\
         [[sphere]]\ncenter = [0.0, -100.0, 0.0]\nradius = 100.0\n\
         [[point_light]]\nposition = [1.0, 3.0, 2.0]\nintensity = [8.0, 8.0, 8.0]\n",
    )
}

fn gpu_with_dispatch(chosen: &str) -> Gpu {
    let request = AdapterRequest {
        options: GpuOptions {
            shadow_dispatch: Some(chosen.to_string()),
            ..GpuOptions::default()
        },
        ..AdapterRequest::default()
    };
    Gpu::open(&request, false).expect("an adapter (lavapipe on CI)")
}

/// LAMBERT_SHADOW_DISPATCH takes the wavefront's one name; the old
/// `apart` is refused, naming the values it takes.
#[test]
fn the_shadow_dispatch_variable_names_the_wavefront() {
    let scene = shadowed_scene();
    let wavefront = GpuRenderer::new(gpu_with_dispatch("wavefront"), &scene).unwrap();
    assert_eq!(wavefront.shadow_dispatch, ShadowDispatch::Wavefront);
    assert!(wavefront.is_wavefront());
    let mega = GpuRenderer::new(gpu_with_dispatch("megakernel"), &scene).unwrap();
    assert_eq!(mega.shadow_dispatch, ShadowDispatch::Megakernel);
    let Err(error) = GpuRenderer::new(gpu_with_dispatch("apart"), &scene) else {
        panic!("LAMBERT_SHADOW_DISPATCH=apart was taken");
    };
    let error = error.to_string();
    assert_contains_all(
        &error,
        &[
            "LAMBERT_SHADOW_DISPATCH=\"apart\"",
            "\"megakernel\" or \"wavefront\"",
        ],
    );
}

/// The wavefront's old names are gone from the code and the docs.
#[test]
fn the_wavefront_has_one_name() {
    let old = [
        "ShadowDispatch::Apart",
        "SplitShadows",
        "shadows_apart",
        "SHADOWS_APART",
        "build_split",
        "pipelines.split",
        "render_list_apart",
        "megakernel|apart",
        "shadow_rays_apart_render",
    ];
    let mut files = vec![root().join("README.md")];
    for dir in ["src", "src/gpu", "docs", "tests", "examples", "scripts"] {
        for entry in std::fs::read_dir(root().join(dir)).expect("folder") {
            let path = entry.expect("entry").path();
            if path.is_file() && path.file_name().is_some_and(|n| n != "refactor_b.rs") {
                files.push(path);
            }
        }
    }
    let mut found = Vec::new();
    for file in files {
        let Ok(text) = std::fs::read_to_string(&file) else {
            continue;
        };
        for name in old.iter().filter(|name| text.contains(*name)) {
            found.push(format!("{}: {name}", file.display()));
        }
    }
    assert!(found.is_empty(), "old names of the wavefront:\n{found:#?}");
}

fn bits(r: &Rendered) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let rgb = r.image.rgb.iter().flatten().map(|c| c.to_bits()).collect();
    let variance = r.variance.iter().map(|v| v.to_bits()).collect();
    (rgb, variance, r.prims.clone())
}

fn list_bits(results: &[[f32; 4]]) -> Vec<u32> {
    results.iter().flatten().map(|c| c.to_bits()).collect()
}

/// Each call renders the view it is given: on one renderer, renders, pixel
/// lists and progressive batches of other views in between change no bit
/// of any of them against a renderer that made only that call, in the
/// wavefront and in the megakernel; and the ray queries after them hit
/// alike.
#[test]
fn each_render_call_renders_the_view_it_is_given() {
    let scene = shadowed_scene();
    let first = View {
        spp: 1,
        seed: 3,
        ..scene.view().clone()
    };
    let mut second = View {
        spp: 5,
        seed: 11,
        ..scene.view().clone()
    };
    second.camera.eye = [2.0, 2.5, 3.0];
    second.camera.width = 23;
    second.camera.height = 17;
    let pixels: Vec<[u32; 2]> = (0..23 * 17).step_by(5).map(|i| [i % 23, i / 23]).collect();
    let rays = lambert::rays::camera_rays(&scene);
    let hidden = Progress::hidden();
    for dispatch in [ShadowDispatch::Wavefront, ShadowDispatch::Megakernel] {
        let fresh = || {
            let mut renderer = GpuRenderer::new(open_gpu(), &scene).unwrap();
            renderer.shadow_dispatch = dispatch;
            renderer
        };
        let alone_first = fresh().render(&first, &hidden).unwrap().0;
        let alone_second = fresh().render(&second, &hidden).unwrap().0;
        let alone_list = fresh().render_pixel_list(&second, &pixels).unwrap();
        let alone_hits = fresh()
            .trace_rays(&rays, false, scene.default_settings().intersect)
            .unwrap();

        let mut shared = fresh();
        let label = format!("{dispatch:?}");
        assert_eq!(
            bits(&shared.render(&first, &hidden).unwrap().0),
            bits(&alone_first),
            "{label}"
        );
        let mut sums = vec![[0.0f32; 4]; 23 * 17];
        assert!(
            shared
                .add_samples(&second, 0..2, &mut sums)
                .unwrap()
                .is_none()
        );
        let list = shared.render_pixel_list(&second, &pixels).unwrap();
        assert_eq!(
            list_bits(&list),
            list_bits(&alone_list),
            "{label}: the pixel list"
        );
        let again = shared.render(&first, &hidden).unwrap().0;
        assert_eq!(
            bits(&again),
            bits(&alone_first),
            "{label}: the first view again"
        );
        let finished = shared.add_samples(&second, 2..5, &mut sums).unwrap();
        let rgb: Vec<u32> = finished
            .expect("the last batch")
            .rgb
            .iter()
            .flatten()
            .map(|c| c.to_bits())
            .collect();
        assert_eq!(
            rgb,
            bits(&alone_second).0,
            "{label}: the batches end as one render"
        );
        let hits = shared
            .trace_rays(&rays, false, scene.default_settings().intersect)
            .unwrap();
        let hit_bits = |hits: &[lambert::layout::Hit]| -> Vec<[u32; 2]> {
            hits.iter().map(|h| [h.t.to_bits(), h.prim]).collect()
        };
        assert_eq!(
            hit_bits(&hits),
            hit_bits(&alone_hits),
            "{label}: the rays' hits"
        );
        assert_eq!(
            shared.tile_count(&second),
            fresh().tile_count(&second),
            "{label}"
        );
    }
}
