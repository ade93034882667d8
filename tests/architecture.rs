//! The code's shape read from its own files: file sizes (src, shaders, tests), no cycle among the modules or among the files, each import against the layer table, and docs/architecture.md's counts.
// docs/architecture.md says what each module is for and where it belongs.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

// Not `mod common`: these helpers are this file's alone.
#[path = "common/doc_counts.rs"]
mod doc_counts;
#[path = "common/file_graph.rs"]
mod file_graph;
#[path = "common/source.rs"]
mod source;

use source::*;

/// No Rust file in src/ or python/src may be longer (docs/architecture.md).
const MAX_RUST_LINES: usize = 800;
/// No shader file may be longer.
const MAX_SHADER_LINES: usize = 600;
/// No file of tests/ may be longer: a file holds the tests of one subject.
const MAX_TEST_LINES: usize = 800;

/// Rust files allowed past MAX_RUST_LINES, each with its line count when
/// it was listed (none may grow): none since issue 29's splits.
const OVERSIZED_RUST: &[(&str, usize)] = &[];
/// Shaders allowed past MAX_SHADER_LINES: none since the split by stage.
const OVERSIZED_SHADERS: &[(&str, usize)] = &[];

/// A made-up file for the checks' own tests: its path and text.
fn file(path: &str, text: &str) -> (PathBuf, String) {
    (PathBuf::from(path), text.to_string())
}

/// Files over `limit` lines that are not in `allowed`, or grown past the
/// count they are listed with.
fn oversized(paths: &[PathBuf], limit: usize, allowed: &[(&str, usize)]) -> Vec<String> {
    let mut problems = Vec::new();
    for path in paths {
        let lines = line_count(path);
        let name = path.to_string_lossy();
        match allowed.iter().find(|(listed, _)| *listed == name) {
            Some((_, listed)) if lines > *listed => problems.push(format!(
                "{name}: {lines} lines, more than the {listed} it is listed with (it is to shrink)"
            )),
            Some(_) => {}
            None if lines > limit => problems.push(format!("{name}: {lines} lines, over {limit}")),
            None => {}
        }
    }
    problems
}

/// What already holds: no source file over 800 lines and no shader over
/// 600, but for today's oversized files, which may not grow.
#[test]
fn no_file_is_over_its_size_limit_but_the_listed_ones() {
    let mut rust = files("src", ".rs");
    rust.extend(files("python/src", ".rs"));
    assert!(rust.len() > 20, "found only {rust:?}");
    let mut shaders = files("shaders", ".wgsl");
    shaders.extend(files("src", ".wgsl"));
    assert!(!shaders.is_empty(), "found no shader");
    let mut problems = oversized(&rust, MAX_RUST_LINES, OVERSIZED_RUST);
    problems.extend(oversized(&shaders, MAX_SHADER_LINES, OVERSIZED_SHADERS));
    assert_none(&problems, "files over their size limit");
}

/// The size check fails on what it is for.
#[test]
fn the_size_check_catches_new_and_grown_files() {
    let file = PathBuf::from("src/lib.rs");
    let lines = line_count(&file);
    assert_eq!(oversized(&[file.clone()], lines, &[]), Vec::<String>::new());
    assert_eq!(oversized(&[file.clone()], lines - 1, &[]).len(), 1);
    assert_eq!(
        oversized(&[file.clone()], 1, &[("src/lib.rs", lines - 1)]).len(),
        1
    );
    assert!(oversized(&[file], 1, &[("src/lib.rs", lines)]).is_empty());
}

/// The files of tests/ (its helpers in tests/common/ too) over `limit`.
fn oversized_tests(limit: usize) -> Vec<String> {
    let tests = files("tests", ".rs");
    assert!(tests.len() > 20, "found only {tests:?}");
    oversized(&tests, limit, &[])
}

/// No test file is over MAX_TEST_LINES lines: split one by subject.
#[test]
fn no_test_file_is_over_its_size_limit() {
    assert_none(
        &oversized_tests(MAX_TEST_LINES),
        "test files over their size limit",
    );
}

/// The test files' check names the longest file when the limit is one
/// line below it.
#[test]
fn the_test_size_check_catches_a_long_file() {
    let longest = files("tests", ".rs")
        .into_iter()
        .max_by_key(|p| line_count(p))
        .unwrap();
    let problems = oversized_tests(line_count(&longest) - 1);
    assert_eq!(problems.len(), 1, "{problems:?}");
    assert!(problems[0].starts_with(&*longest.to_string_lossy()));
}

// ---- the module graph -------------------------------------------------------

/// The library's top-level module a file of src/ belongs to (src/cpu/kernel.rs
/// is `cpu`); None for the crate root and the binary.
fn module_of(path: &Path) -> Option<String> {
    let rel = path.strip_prefix("src").ok()?;
    let first = rel.components().next()?.as_os_str().to_string_lossy();
    let name = first.trim_end_matches(".rs").to_string();
    (!matches!(name.as_str(), "lib" | "main" | "bin")).then_some(name)
}

/// The module graph of src/: each top-level module and the top-level
/// modules it names through `crate::` paths (itself left out).
fn module_graph() -> BTreeMap<String, BTreeSet<String>> {
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for path in files("src", ".rs") {
        let Some(module) = module_of(&path) else {
            continue;
        };
        let text = std::fs::read_to_string(Path::new(ROOT).join(&path)).unwrap();
        let imports = graph.entry(module.clone()).or_default();
        for segments in crate_paths(&code_only(&text)) {
            if let Some(target) = segments.first()
                && *target != module
            {
                imports.insert(target.clone());
            }
        }
    }
    // Names that are not modules (`crate::Scene`, `crate::Result`) are the
    // root's re-exports, not edges.
    let modules: BTreeSet<String> = graph.keys().cloned().collect();
    for imports in graph.values_mut() {
        imports.retain(|m| modules.contains(m));
    }
    graph
}

/// The parser reads every form of `crate::` path the code uses, and
/// nothing in comments or strings.
#[test]
fn crate_paths_are_read_from_code_only() {
    let code = code_only(
        "use crate::cpu::{self, Precision};\n\
         use crate::{bvh::Bvh, loading::{obj, ply::read as r}};\n\
         pub(crate) fn f() -> crate::Result<()> { crate::gpu::WORKGROUP; }\n\
         // use crate::comment::X;\n\
         /* crate::block */ let s = \"crate::string\"; let c = '\"';\n\
         let raw = r#\"crate::raw \" crate::raw\"#; let r = crate::rays::X;\n\
         macro_rules! m { () => { $crate::macro_path } }\n\
         use crate::scene::*;",
    );
    let firsts: Vec<String> = crate_paths(&code)
        .into_iter()
        .map(|p| p.join("::"))
        .collect();
    assert_eq!(
        firsts,
        [
            "cpu::self",
            "cpu::Precision",
            "bvh::Bvh",
            "loading::obj",
            "loading::ply::read",
            "Result",
            "gpu::WORKGROUP",
            "rays::X",
            "scene",
        ]
    );
}

/// Tarjan finds the cycles, and only them.
#[test]
fn cycles_are_found() {
    let graph: BTreeMap<String, BTreeSet<String>> = [
        ("a", &["b"][..]),
        ("b", &["c"][..]),
        ("c", &["a", "d"][..]),
        ("d", &[][..]),
        ("e", &["d"][..]),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.iter().map(|s| s.to_string()).collect()))
    .collect();
    assert_eq!(cycles(&graph), [["a", "b", "c"]]);
}

/// The library's modules import each other in one direction only
/// (docs/architecture.md); `--nocapture` prints the graph.
#[test]
fn the_module_graph_has_no_cycle() {
    let graph = module_graph();
    assert!(graph.len() > 10, "read only {graph:?}");
    for (module, imports) in &graph {
        println!(
            "{module} -> {}",
            Vec::from_iter(imports.iter().cloned()).join(", ")
        );
    }
    let found = cycles(&graph);
    let text: Vec<String> = found.iter().map(|c| c.join(" <-> ")).collect();
    assert_none(&text, "modules that reach each other");
}

// ---- the file graph ---------------------------------------------------------

/// No two files of src/ reach each other through their imports, within a
/// module's folder too (tests/common/file_graph.rs says what an edge is);
/// `--nocapture` prints the graph.
#[test]
fn the_file_graph_has_no_cycle() {
    let graph = file_graph::file_graph(&source_files());
    assert!(graph.len() > 50, "read only {graph:?}");
    for (file, imports) in &graph {
        println!(
            "{file} -> {}",
            Vec::from_iter(imports.iter().cloned()).join(", ")
        );
    }
    let found: Vec<String> = cycles(&graph)
        .into_iter()
        .map(|c| c.join(" <-> "))
        .collect();
    assert_none(&found, "files that reach each other");
}

/// The file graph follows each kind of path (crate, super, super::super,
/// self, a group, a re-export through a child's name, an include) to the
/// file that defines what it names, and finds the cycles they close,
/// naming the files; a parent and its children, a `mod tests` using its
/// file, an extern crate's or a std path, a comment close none.
#[test]
fn file_cycles_are_found_through_every_kind_of_path() {
    let graph = file_graph::file_graph(&[
        file(
            "src/lib.rs",
            "pub mod a; pub mod b; pub mod e; pub use b::Thing;",
        ),
        file("src/a/mod.rs", "mod x; mod y; pub use x::X;"),
        file(
            "src/a/x.rs",
            "use super::y::{Y, Z};\n// use crate::b;\nfn f() { super::X }",
        ),
        file(
            "src/a/y.rs",
            "fn f() -> crate::a::X { std::f32::MAX; glam::Vec3 }",
        ),
        file(
            "src/b.rs",
            "pub struct Thing; fn f() -> crate::Result<crate::a::X> {}",
        ),
        file(
            "src/e/mod.rs",
            "mod k; mod m; mod inc { include!(\"inc.rs\"); }\nmod tests { use super::*; }",
        ),
        file("src/e/k.rs", "pub fn g() { super::m::h() }"),
        file("src/e/m.rs", "use super::{k::g, inc};"),
        file(
            "src/e/inc.rs",
            "fn h() { super::super::b::Thing; self::i(); }",
        ),
        file("src/bin/tool/main.rs", "mod c; use lambert::b::Thing;"),
        file("src/bin/tool/c.rs", "use crate::c::d; fn d() {}"),
    ]);
    let edges = |f: &str| Vec::from_iter(graph[f].iter().map(String::as_str));
    assert!(edges("src/lib.rs").is_empty());
    assert!(edges("src/a/mod.rs").is_empty());
    assert_eq!(edges("src/a/x.rs"), ["src/a/y.rs"]);
    assert_eq!(edges("src/a/y.rs"), ["src/a/x.rs"]);
    assert_eq!(edges("src/b.rs"), ["src/a/x.rs"]);
    assert_eq!(edges("src/e/mod.rs"), ["src/e/inc.rs"]);
    assert_eq!(edges("src/e/k.rs"), ["src/e/m.rs"]);
    assert_eq!(edges("src/e/m.rs"), ["src/e/k.rs"]);
    assert_eq!(edges("src/e/inc.rs"), ["src/b.rs"]);
    assert!(edges("src/bin/tool/main.rs").is_empty());
    assert!(edges("src/bin/tool/c.rs").is_empty());
    assert_eq!(
        cycles(&graph),
        [["src/a/x.rs", "src/a/y.rs"], ["src/e/k.rs", "src/e/m.rs"]]
    );
}

// ---- the layers -------------------------------------------------------------

/// Each top-level module of the library and its layer (docs/architecture.md,
/// "Layers"): a module imports only from layers below its own or from its
/// own layer, and never one of FORBIDDEN. A new module must be placed here.
const LAYERS: &[(&str, u32)] = &[
    ("error", 0),
    ("files", 0),
    ("layout", 0),
    ("limits", 0),
    ("memory", 0),
    ("output", 0),
    ("progress", 0),
    ("shader_source", 0),
    ("camera", 1),
    ("bvh", 2),
    ("cwbvh", 2),
    ("diff", 2),
    ("loading", 2),
    ("placement", 2),
    ("lighting", 2),
    ("probe", 2),
    ("texture", 2),
    ("scene", 3),
    ("cpu", 4),
    ("gpu", 4),
    ("rays", 5),
    ("render", 5),
    ("proximity", 5),
    ("adaptive", 6),
    ("inputs", 6),
    ("jobs", 6),
    ("parts", 6),
    ("bench", 7),
];

/// Imports no layer allows: the backends are siblings.
const FORBIDDEN: &[(&str, &str)] = &[("cpu", "gpu"), ("gpu", "cpu")];

/// The crate root's re-exports, and the module each comes from.
const ROOT_REEXPORTS: &[(&str, &str)] =
    &[("Error", "error"), ("Result", "error"), ("Scene", "scene")];

fn layer_of(module: &str) -> Option<u32> {
    LAYERS.iter().find(|(m, _)| *m == module).map(|&(_, l)| l)
}

/// Every import against the table in `files` (each a path under src/ and
/// its text), as `file:line: import: why`.
fn layer_violations(files: &[(PathBuf, String)]) -> Vec<String> {
    let mut problems = Vec::new();
    for (path, text) in files {
        let Some(module) = module_of(path) else {
            continue;
        };
        let Some(layer) = layer_of(&module) else {
            problems.push(format!(
                "{}: module `{module}` has no layer in tests/architecture.rs's LAYERS (nor in docs/architecture.md)",
                path.display()
            ));
            continue;
        };
        for (line, segments) in crate_paths_at(&code_only(text)) {
            let import = format!("crate::{}", segments.join("::"));
            let first = segments.first().map_or("", String::as_str);
            let target = ROOT_REEXPORTS
                .iter()
                .find(|(name, _)| *name == first)
                .map_or(first, |&(_, m)| m);
            if target == module {
                continue;
            }
            let at = format!("{}:{line}: {import}", path.display());
            match layer_of(target) {
                None => problems.push(format!("{at}: `{first}` is no module in the layer table")),
                Some(l) if l > layer => problems.push(format!(
                    "{at}: `{module}` (layer {layer}) imports `{target}` (layer {l}), a layer above it"
                )),
                Some(_) if FORBIDDEN.contains(&(module.as_str(), target)) => problems.push(format!(
                    "{at}: `{module}` may not import `{target}` (the backends are siblings)"
                )),
                Some(_) => {}
            }
        }
    }
    problems
}

/// Every module of src/ imports only what its layer allows.
#[test]
fn every_import_keeps_to_the_layers() {
    let files = source_files();
    assert!(files.len() > 20, "found only {} files", files.len());
    assert_none(
        &layer_violations(&files),
        "imports against the layers (docs/architecture.md)",
    );
}

/// The layer check names the file, line and import of each import upward,
/// between the backends, of an unknown name, and a module with no layer;
/// and passes what the table allows.
#[test]
fn the_layer_check_catches_imports_against_the_table() {
    let problems = layer_violations(&[
        file(
            "src/cwbvh.rs",
            "use crate::layout::Ray;\n/* a\ncomment */ let n = crate::gpu::X;",
        ),
        file(
            "src/cpu/render.rs",
            "use crate::{\n    scene::Scene,\n    gpu::GpuRenderer,\n};",
        ),
        file("src/gpu/renderer.rs", "use crate::cpu::f32::CameraBasis;"),
        file(
            "src/loading/mod.rs",
            "fn f() -> crate::Result<crate::Scene> {}",
        ),
        file(
            "src/scene/mod.rs",
            "use crate::camera::Camera;\nuse crate::scene::x;\nlet s = \"crate::gpu\";",
        ),
        file("src/limits.rs", "use crate::nothing::X;"),
        file("src/newmod.rs", "use crate::error::Error;"),
        file("src/bin/lambert/main.rs", "use crate::cli;"),
    ]);
    assert_eq!(
        problems,
        [
            "src/cwbvh.rs:3: crate::gpu::X: `cwbvh` (layer 2) imports `gpu` (layer 4), a layer above it",
            "src/cpu/render.rs:3: crate::gpu::GpuRenderer: `cpu` may not import `gpu` (the backends are siblings)",
            "src/gpu/renderer.rs:1: crate::cpu::f32::CameraBasis: `gpu` may not import `cpu` (the backends are siblings)",
            "src/loading/mod.rs:1: crate::Scene: `loading` (layer 2) imports `scene` (layer 3), a layer above it",
            "src/limits.rs:1: crate::nothing::X: `nothing` is no module in the layer table",
            "src/newmod.rs: module `newmod` has no layer in tests/architecture.rs's LAYERS (nor in docs/architecture.md)",
        ]
    );
}

/// The layer table names every module of src/, and only those.
#[test]
fn the_layer_table_names_every_module() {
    let modules: BTreeSet<String> = module_graph().into_keys().collect();
    let table: BTreeSet<String> = LAYERS.iter().map(|(m, _)| m.to_string()).collect();
    assert_eq!(modules, table);
}

// ---- the environment --------------------------------------------------------

/// `file:line` of each read of an environment variable (`env::var`,
/// `var_os`, `vars`) in the code of the library's files: the front ends
/// (`src/bin/`) read them and pass them in as options.
fn environment_reads(files: &[(PathBuf, String)]) -> Vec<String> {
    let mut found = Vec::new();
    for (path, text) in files {
        if path.starts_with("src/bin") {
            continue;
        }
        for (i, line) in code_only(text).lines().enumerate() {
            if line.contains("env::var") {
                found.push(format!("{}:{}", path.display(), i + 1));
            }
        }
    }
    found
}

/// The library reads no environment variable (`LAMBERT_*`, wgpu's):
/// docs/architecture.md's rule.
#[test]
fn the_library_reads_no_environment_variable() {
    let files = source_files();
    assert_none(
        &environment_reads(&files),
        "environment variables read in the library (read them in the front ends and pass them in)",
    );
}

/// The check finds a read in the library's code, not in a comment, a string
/// or the binary's code.
#[test]
fn the_environment_check_finds_reads() {
    let reads = environment_reads(&[
        file(
            "src/cpu/simd.rs",
            "// std::env::var(\"X\")\nlet s = \"env::var\";\nlet v = std::env::var(\"X\");",
        ),
        file(
            "src/gpu/device.rs",
            "use std::env;\n\nlet v = env::var_os(\"Y\");",
        ),
        file("src/bin/lambert/main.rs", "let v = std::env::var(\"X\");"),
    ]);
    assert_eq!(reads, ["src/cpu/simd.rs:3", "src/gpu/device.rs:3"]);
}

// ---- the doc's counts -------------------------------------------------------

/// The modules `module`'s files import, the root's re-exports as the
/// modules they come from.
fn imports_of(module: &str, files: &[(PathBuf, String)]) -> BTreeSet<String> {
    let mut imports = BTreeSet::new();
    for (path, text) in files {
        if module_of(path).as_deref() != Some(module) {
            continue;
        }
        for segments in crate_paths(&code_only(text)) {
            let first = segments.first().map_or("", String::as_str);
            let target = ROOT_REEXPORTS
                .iter()
                .find(|(name, _)| *name == first)
                .map_or(first, |&(_, m)| m);
            if target != module && layer_of(target).is_some() {
                imports.insert(target.to_string());
            }
        }
    }
    imports
}

/// docs/architecture.md as the code says it should read.
fn regenerated_doc() -> (PathBuf, String, Result<String, Vec<String>>) {
    let path = Path::new(ROOT).join("docs/architecture.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    let sources = source_files();
    let lines_in = |p: &Path| {
        p.exists()
            .then(|| line_count(p.strip_prefix(ROOT).unwrap()))
    };
    let module_lines = |module: &str| {
        let own = lines_in(&Path::new(ROOT).join(format!("src/{module}.rs")));
        let folder: Vec<usize> = files(&format!("src/{module}"), ".rs")
            .iter()
            .map(|p| line_count(p))
            .collect();
        (own.is_some() || !folder.is_empty())
            .then(|| own.unwrap_or(0) + folder.iter().sum::<usize>())
    };
    let file_lines = |module: &str, name: &str| {
        let own = format!("{module}.rs");
        let path = if name == own {
            format!("src/{own}")
        } else {
            format!("src/{module}/{name}")
        };
        lines_in(&Path::new(ROOT).join(path))
    };
    let imports = |module: &str| imports_of(module, &sources);
    let code = doc_counts::Code {
        module_lines: &module_lines,
        file_lines: &file_lines,
        imports: &imports,
    };
    let regenerated = doc_counts::with_counts(&doc, &code);
    (path, doc, regenerated)
}

/// Every count docs/architecture.md's layer table states (each module's
/// lines, each file's it names) and each module's imports are the code's
/// today. With `LAMBERT_REGENERATE_DOCS=1` the check writes the doc with
/// them instead of failing:
/// `LAMBERT_REGENERATE_DOCS=1 cargo test --release --test architecture the_docs_counts`.
#[test]
fn the_docs_counts_are_the_codes() {
    let (path, doc, regenerated) = regenerated_doc();
    let regenerated =
        regenerated.unwrap_or_else(|e| panic!("docs/architecture.md: {}", e.join("\n")));
    if std::env::var_os("LAMBERT_REGENERATE_DOCS").is_some_and(|v| v == "1") {
        std::fs::write(&path, &regenerated).unwrap();
        return;
    }
    let drifted: Vec<String> = doc
        .lines()
        .zip(regenerated.lines())
        .filter(|(a, b)| a != b)
        .map(|(a, b)| format!("the doc:  {a}\nthe code: {b}"))
        .collect();
    assert_none(
        &drifted,
        "docs/architecture.md's counts drifted from the code; run\n  \
         LAMBERT_REGENERATE_DOCS=1 cargo test --release --test architecture the_docs_counts",
    );
}

/// The count check recomputes a module's total, each file it names (with a
/// thousands separator, words after a count kept) and the imports, leaves
/// other lines alone, and names a module or file the code lacks.
#[test]
fn the_docs_count_check_catches_drift() {
    let module_lines = |m: &str| (m != "gone").then_some(1234);
    let file_lines = |m: &str, f: &str| (f != "gone.rs").then_some(m.len() * 10 + f.len());
    let imports = |m: &str| BTreeSet::from_iter((m == "b").then(|| "a".to_string()));
    let code = doc_counts::Code {
        module_lines: &module_lines,
        file_lines: &file_lines,
        imports: &imports,
    };
    let doc = "Lines 800 | 600\n\
               | 0 | `a` | 7 | What a is, 5 | error |\n\
               | 1 | `b` | 1,000 (`b.rs` 9, `x/y.rs` 1,111 with names, `C` 3) | b | — |\n";
    assert_eq!(
        doc_counts::with_counts(doc, &code).unwrap(),
        "Lines 800 | 600\n\
         | 0 | `a` | 1,234 | What a is, 5 | — |\n\
         | 1 | `b` | 1,234 (`b.rs` 14, `x/y.rs` 16 with names, `C` 3) | b | a |\n"
    );
    assert_eq!(
        doc_counts::with_counts(
            "| 0 | `gone` | 1 | x | — |\n| 0 | `b` | 1 (`gone.rs` 2) | x | — |",
            &code
        ),
        Err(vec![
            "`gone`: no such module".to_string(),
            "`b`: no file `gone.rs`".to_string()
        ])
    );
}
