//! The code's shape read from its own files: file sizes, no cycle among the modules, and each import against the layer table.
// docs/architecture.md says what each module is for and where it belongs.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// No Rust file in src/ or python/src may be longer (docs/architecture.md).
const MAX_RUST_LINES: usize = 800;
/// No shader file may be longer.
const MAX_SHADER_LINES: usize = 600;

/// Rust files allowed past MAX_RUST_LINES, each with its line count when
/// it was listed (none may grow): none since issue 29's splits.
const OVERSIZED_RUST: &[(&str, usize)] = &[];
/// Shaders allowed past MAX_SHADER_LINES: none since the split by stage.
const OVERSIZED_SHADERS: &[(&str, usize)] = &[];

/// Files under `dir` (recursively) whose names end with `suffix`, as paths
/// relative to the crate root.
fn files(dir: &str, suffix: &str) -> Vec<PathBuf> {
    fn walk(dir: &Path, suffix: &str, found: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                walk(&path, suffix, found);
            } else if path.to_string_lossy().ends_with(suffix) {
                found.push(path);
            }
        }
    }
    let mut found = Vec::new();
    walk(&Path::new(ROOT).join(dir), suffix, &mut found);
    found.sort();
    found
        .into_iter()
        .map(|p| p.strip_prefix(ROOT).unwrap().to_path_buf())
        .collect()
}

fn line_count(path: &Path) -> usize {
    std::fs::read_to_string(Path::new(ROOT).join(path))
        .unwrap()
        .lines()
        .count()
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
    assert!(problems.is_empty(), "{}", problems.join("\n"));
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

// ---- the module graph -------------------------------------------------------

/// `text` without comments (line, doc and block) and string literals, so
/// that only code is searched for `crate::` paths; the newlines of what it
/// drops stay, so that every line keeps its number.
fn code_only(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let newlines = |out: &mut String, dropped: &[char]| {
        out.extend(dropped.iter().filter(|&&c| c == '\n'));
    };
    let mut i = 0;
    while i < chars.len() {
        let next = chars.get(i + 1).copied();
        match chars[i] {
            '/' if next == Some('/') => {
                while i < chars.len() && chars[i] != '\n' {
                    i += 1;
                }
            }
            '/' if next == Some('*') => {
                let start = i;
                i += 2;
                while i + 1 < chars.len() && !(chars[i] == '*' && chars[i + 1] == '/') {
                    i += 1;
                }
                i += 2;
                newlines(&mut out, &chars[start..i.min(chars.len())]);
            }
            'r' if (next == Some('"') || next == Some('#'))
                && !(i > 0 && is_ident(chars[i - 1])) =>
            {
                // A raw string, r#"…"#: ends at a quote and as many #.
                let hashes = chars[i + 1..].iter().take_while(|&&c| c == '#').count();
                if chars.get(i + 1 + hashes) != Some(&'"') {
                    out.push('r');
                    i += 1;
                    continue;
                }
                let start = i;
                i += hashes + 2;
                let close: Vec<char> = std::iter::once('"')
                    .chain(std::iter::repeat_n('#', hashes))
                    .collect();
                while i < chars.len() && !chars[i..].starts_with(&close) {
                    i += 1;
                }
                i += close.len();
                out.push_str("\"\"");
                newlines(&mut out, &chars[start..i.min(chars.len())]);
            }
            '"' => {
                let start = i;
                i += 1;
                while i < chars.len() && chars[i] != '"' {
                    i += if chars[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("\"\"");
                newlines(&mut out, &chars[start..i.min(chars.len())]);
            }
            // A char literal ('"' among them), not a lifetime.
            '\'' if chars.get(i + 2) == Some(&'\'') => i += 3,
            '\'' if next == Some('\\') => {
                i += 2;
                while i < chars.len() && chars[i] != '\'' {
                    i += 1;
                }
                i += 1;
            }
            c => {
                out.push(c);
                i += 1;
            }
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// A `crate::` path: where it is written (a char index: the `crate::`, or
/// the member of a group) and its segments after `crate`.
type CratePath = (usize, Vec<String>);

/// The paths of a use tree or path starting at `chars[*i]` (just after a
/// `crate::`, or at a group's member, written at `at`), each as its
/// segments, prefixed by `prefix`; a group (`{a, b::c}`) gives one path
/// per member.
fn paths(
    chars: &[char],
    i: &mut usize,
    at: usize,
    prefix: Vec<String>,
    found: &mut Vec<CratePath>,
) {
    let skip_space = |i: &mut usize| {
        while *i < chars.len() && chars[*i].is_whitespace() {
            *i += 1;
        }
    };
    let mut path = prefix;
    loop {
        skip_space(i);
        if chars.get(*i) == Some(&'{') {
            *i += 1;
            loop {
                skip_space(i);
                match chars.get(*i) {
                    Some('}') => {
                        *i += 1;
                        return;
                    }
                    Some(',') => *i += 1,
                    None => return,
                    _ => paths(chars, i, *i, path.clone(), found),
                }
            }
        }
        let start = *i;
        while *i < chars.len() && is_ident(chars[*i]) {
            *i += 1;
        }
        let segment: String = chars[start..*i].iter().collect();
        if !segment.is_empty() {
            path.push(segment);
        }
        skip_space(i);
        if chars.get(*i) == Some(&':') && chars.get(*i + 1) == Some(&':') {
            *i += 2;
        } else {
            found.push((at, path));
            // Past the rest of this member (`as name`, `*`) to `,` or `}`.
            while *i < chars.len() && !matches!(chars[*i], ',' | '}' | ';' | '{') {
                if !(chars[*i].is_whitespace() || is_ident(chars[*i]) || chars[*i] == '*') {
                    return;
                }
                *i += 1;
            }
            return;
        }
    }
}

/// Every `crate::…` path in `code`, as segments after `crate`.
fn crate_paths(code: &str) -> Vec<Vec<String>> {
    crate_paths_at(code).into_iter().map(|(_, p)| p).collect()
}

/// `crate_paths`, each with the line (from 1) it is written on.
fn crate_paths_at(code: &str) -> Vec<CratePath> {
    let mut line = 1;
    let mut counted = 0;
    let chars: Vec<char> = code.chars().collect();
    let mut found = crate_paths_found(&chars);
    for (at, _) in &mut found {
        line += chars[counted..*at].iter().filter(|&&c| c == '\n').count();
        counted = *at;
        *at = line;
    }
    found
}

/// The `crate::` paths of `chars`, each at the char index it is written at.
fn crate_paths_found(chars: &[char]) -> Vec<CratePath> {
    let mut found = Vec::new();
    let mut i = 0;
    while let Some(at) = code_find(chars, i, "crate::") {
        let before = at.checked_sub(1).map(|b| chars[b]);
        i = at + "crate::".len();
        if before.is_some_and(|c| is_ident(c) || c == '$') {
            continue;
        }
        paths(chars, &mut i, at, Vec::new(), &mut found);
    }
    found
}

fn code_find(chars: &[char], from: usize, needle: &str) -> Option<usize> {
    let needle: Vec<char> = needle.chars().collect();
    (from..chars.len().saturating_sub(needle.len() - 1))
        .find(|&k| chars[k..k + needle.len()] == needle[..])
}

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

/// The graph's cycles: its strongly connected components of more than one
/// module (Tarjan's algorithm), each sorted.
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct Tarjan<'a> {
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        found: Vec<Vec<String>>,
    }
    impl<'a> Tarjan<'a> {
        fn visit(&mut self, v: &'a str) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            self.on_stack.insert(v);
            for w in self.graph.get(v).into_iter().flatten() {
                let w = w.as_str();
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let low = self.low[v].min(self.low[w]);
                    self.low.insert(v, low);
                } else if self.on_stack.contains(w) {
                    let low = self.low[v].min(self.index[w]);
                    self.low.insert(v, low);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = Vec::new();
                loop {
                    let w = self.stack.pop().unwrap();
                    self.on_stack.remove(w);
                    component.push(w.to_string());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort();
                    self.found.push(component);
                }
            }
        }
    }
    let mut t = Tarjan {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        found: Vec::new(),
    };
    for v in graph.keys() {
        if !t.index.contains_key(v.as_str()) {
            t.visit(v);
        }
    }
    t.found.sort();
    t.found
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
    assert!(
        found.is_empty(),
        "modules that reach each other:\n{}",
        text.join("\n")
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

/// Every Rust file of src/, with its text.
fn source_files() -> Vec<(PathBuf, String)> {
    files("src", ".rs")
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(Path::new(ROOT).join(&path)).unwrap();
            (path, text)
        })
        .collect()
}

/// Every module of src/ imports only what its layer allows.
#[test]
fn every_import_keeps_to_the_layers() {
    let files = source_files();
    assert!(files.len() > 20, "found only {} files", files.len());
    let problems = layer_violations(&files);
    assert!(
        problems.is_empty(),
        "imports against the layers (docs/architecture.md):\n{}",
        problems.join("\n")
    );
}

/// The layer check names the file, line and import of each import upward,
/// between the backends, of an unknown name, and a module with no layer;
/// and passes what the table allows.
#[test]
fn the_layer_check_catches_imports_against_the_table() {
    let file = |path: &str, text: &str| (PathBuf::from(path), text.to_string());
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
    let reads = environment_reads(&files);
    assert!(
        reads.is_empty(),
        "environment variables read in the library (read them in the front ends and pass them in):\n{}",
        reads.join("\n")
    );
}

/// The check finds a read in the library's code, not in a comment, a string
/// or the binary's code.
#[test]
fn the_environment_check_finds_reads() {
    let file = |path: &str, text: &str| (PathBuf::from(path), text.to_string());
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

// ---- no source fragments ----------------------------------------------------

/// No file of src/ pastes a `.rs` file into another with `include!`: every
/// Rust file is a module of its own, which tools (rust-analyzer, this
/// file's checks) can place; code written once for both precisions is a
/// macro that each precision's module expands (src/cpu/kernel.rs). The
/// check itself finds such an include in code, not in a comment or a
/// string, nor an `include_str!` of a shader.
#[test]
fn no_rust_file_is_included_into_another() {
    let includes = |files: &[(PathBuf, String)]| {
        let mut found = Vec::new();
        for (path, text) in files {
            let lines: Vec<&str> = text.lines().collect();
            for (i, line) in code_only(text).lines().enumerate() {
                let pasted = line.match_indices("include!(").any(|(at, _)| {
                    !line[..at].ends_with(|c: char| is_ident(c)) && lines[i].contains(".rs\"")
                });
                if pasted {
                    found.push(format!("{}:{}", path.display(), i + 1));
                }
            }
        }
        found
    };
    let file = |path: &str, text: &str| (PathBuf::from(path), text.to_string());
    let planted = includes(&[file(
        "src/cpu/f32.rs",
        "// include!(\"kernel.rs\");\nconst S: &str = include_str!(\"../../shaders/a.wgsl\");\nlet s = \"include!(\\\"x.rs\\\")\";\ninclude!(\"kernel.rs\");",
    )]);
    assert_eq!(planted, ["src/cpu/f32.rs:4"]);
    let found = includes(&source_files());
    assert!(
        found.is_empty(),
        "`.rs` files pasted in with include! (make them modules, docs/architecture.md):\n{}",
        found.join("\n")
    );
}

// ---- settings in their place -------------------------------------------------

/// The `pub` fields of `struct Scene` in `text` (src/scene/mod.rs's code):
/// its fields are the crate's, read through methods; what a render may
/// change is a `RenderSettings`.
fn public_scene_fields(text: &str) -> Vec<String> {
    let code = code_only(text);
    let Some(start) = code.find("pub struct Scene {") else {
        return vec!["no `pub struct Scene {` found".into()];
    };
    let body = &code[start..];
    let body = &body[..body.find("\n}").unwrap_or(body.len())];
    body.lines()
        .skip(1)
        .map(str::trim)
        .filter(|line| line.starts_with("pub ") || line.starts_with("pub(super)"))
        .map(|line| line.trim_end_matches(',').to_string())
        .collect()
}

#[test]
fn the_scene_has_no_public_field() {
    let text = std::fs::read_to_string(Path::new(ROOT).join("src/scene/mod.rs")).unwrap();
    let public = public_scene_fields(&text);
    assert!(
        public.is_empty(),
        "src/scene/mod.rs: `Scene` has public fields (make them pub(crate) and add a method):\n{}",
        public.join("\n")
    );
}

#[test]
fn the_field_check_finds_public_fields() {
    let text = "/// pub view: View\npub struct Scene {\n    /// pub x\n    pub view: View,\n    \
                pub(crate) spp: u32,\n    pub shadows: bool,\n}\npub struct Other {\n    pub a: u8,\n}\n";
    assert_eq!(
        public_scene_fields(text),
        ["pub view: View", "pub shadows: bool"]
    );
}

/// `file:line` of each `Renderer::Gpu` or `Renderer::Cpu` in the code of
/// the front ends' files (the binary's, the Python extension's): they ask
/// a `Renderer` through its methods.
fn renderer_variants_named(files: &[(PathBuf, String)]) -> Vec<String> {
    let mut found = Vec::new();
    for (path, text) in files {
        for (i, line) in code_only(text).lines().enumerate() {
            if line.contains("Renderer::Gpu") || line.contains("Renderer::Cpu") {
                found.push(format!("{}:{}", path.display(), i + 1));
            }
        }
    }
    found
}

#[test]
fn no_front_end_names_the_renderers_variants() {
    let front_ends: Vec<(PathBuf, String)> = files("src/bin", ".rs")
        .into_iter()
        .chain(files("python/src", ".rs"))
        .map(|path| {
            let text = std::fs::read_to_string(Path::new(ROOT).join(&path)).unwrap();
            (path, text)
        })
        .collect();
    assert!(front_ends.len() > 10, "front ends not found");
    let named = renderer_variants_named(&front_ends);
    assert!(
        named.is_empty(),
        "front ends match on Renderer's variants (use its methods):\n{}",
        named.join("\n")
    );
}

#[test]
fn the_variant_check_finds_them_in_code_only() {
    let file = |path: &str, text: &str| (PathBuf::from(path), text.to_string());
    let named = renderer_variants_named(&[
        file(
            "python/src/lib.rs",
            "// Renderer::Cpu\nlet s = \"Renderer::Gpu\";\nlet r = Renderer::Cpu(scene);",
        ),
        file(
            "src/bin/lambert/view/app.rs",
            "match r {\n    Renderer::Gpu(g) => g,\n}",
        ),
    ]);
    assert_eq!(
        named,
        ["python/src/lib.rs:3", "src/bin/lambert/view/app.rs:2"]
    );
}
