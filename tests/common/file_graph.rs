//! The graph of src/'s files for tests/architecture.rs: an edge from a
//! file to each file whose items it names (a `crate::`, `super::` or
//! `self::` path, or a path through a child module), and to each file it
//! `include!`s.
//!
//! A path is resolved to the file of the deepest module it names; where
//! that file only re-exports the item (`pub use device::Gpu`), to the file
//! the re-export names, so that a folder's `mod.rs` is no hub every file
//! of the folder reaches through. A module's file and the files of its own
//! submodules are one unit toward each other: a parent declares its
//! children and re-exports or calls them, and children use their parent's
//! types, Rust's usual shape, not a circle; the check is among siblings
//! and across modules. An `include!`d file is part of its includer's module.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use super::source::{code_find, code_only, is_ident, paths};

/// The crate a file of src/ belongs to (its root file) and its path of
/// modules there: src/gpu/device.rs is `["gpu", "device"]` in src/lib.rs's
/// crate, src/bin/lambert/cli/info.rs `["cli", "info"]` in the binary's.
fn module_path(path: &Path) -> (PathBuf, Vec<String>) {
    let components: Vec<String> = path
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    let (root, dir) = if components.get(1).map(String::as_str) == Some("bin") {
        let dir = PathBuf::from_iter(&components[..3.min(components.len())]);
        (dir.join("main.rs"), dir)
    } else {
        (PathBuf::from("src/lib.rs"), PathBuf::from("src"))
    };
    if path == root {
        return (root, Vec::new());
    }
    let mut modules: Vec<String> = path
        .strip_prefix(&dir)
        .unwrap_or(path)
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    if modules.last().is_some_and(|m| m == "mod.rs") {
        modules.pop();
    } else if let Some(last) = modules.last_mut() {
        *last = last.trim_end_matches(".rs").to_string();
    }
    (root, modules)
}

/// The inline modules of `chars` (`mod tests { … }`): each one's name and
/// the char range of its body.
fn inline_modules(chars: &[char]) -> Vec<(String, usize, usize)> {
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(at) = code_find(chars, from, "mod ") {
        from = at + 4;
        if at > 0 && is_ident(chars[at - 1]) {
            continue;
        }
        let name: String = chars[from..].iter().take_while(|&&c| is_ident(c)).collect();
        let mut i = from + name.len();
        while i < chars.len() && chars[i].is_whitespace() {
            i += 1;
        }
        if name.is_empty() || chars.get(i) != Some(&'{') {
            continue;
        }
        let mut depth = 0;
        let start = i;
        while i < chars.len() {
            match chars[i] {
                '{' => depth += 1,
                '}' => depth -= 1,
                _ => {}
            }
            i += 1;
            if depth == 0 {
                break;
            }
        }
        found.push((name, start, i));
    }
    found
}

/// Where each file's code stands: its crate and module path, and its code
/// (a file that is `include!`d stands where its includer does, once for
/// each includer).
type Place = (PathBuf, Vec<String>, String);

/// The file a path of `crate`'s modules names (the deepest module it
/// names that is a file) and what follows that module's name; None where
/// the path names no module of the crate (an extern crate, a std path).
fn file_of<'a>(
    modules: &'a BTreeMap<(PathBuf, Vec<String>), PathBuf>,
    krate: &Path,
    path: &[String],
) -> Option<(&'a PathBuf, usize)> {
    (0..=path.len()).rev().find_map(|n| {
        modules
            .get(&(krate.to_path_buf(), path[..n].to_vec()))
            .map(|f| (f, n))
    })
}

/// The file graph of `files` (each a path under src/ and its text): each
/// file and the files it names, itself left out.
pub fn file_graph(files: &[(PathBuf, String)]) -> BTreeMap<String, BTreeSet<String>> {
    let code: BTreeMap<&PathBuf, String> = files.iter().map(|(p, t)| (p, code_only(t))).collect();
    // `include!("x.rs")` beside the includer; read from the text, as
    // code_only blanks strings, on a line that has code.
    let mut includes: BTreeMap<PathBuf, Vec<(PathBuf, usize)>> = BTreeMap::new();
    for (path, text) in files {
        let lines: Vec<&str> = text.lines().collect();
        let mut offset = 0;
        for (n, line) in code[path].lines().enumerate() {
            if let Some(column) = line.find("include!(\"")
                && let Some(name) = lines.get(n).and_then(|l| l.split('"').nth(1))
            {
                let included = path.parent().unwrap().join(name);
                let at = offset + line[..column].chars().count();
                includes
                    .entry(included)
                    .or_default()
                    .push((path.clone(), at));
            }
            offset += line.chars().count() + 1;
        }
    }
    let mut modules = BTreeMap::new();
    for (path, _) in files {
        if !includes.contains_key(path) {
            modules.insert(module_path(path), path.clone());
        }
    }
    // Each file's places: its own, or its includers' at the include.
    fn places(
        path: &PathBuf,
        code: &BTreeMap<&PathBuf, String>,
        includes: &BTreeMap<PathBuf, Vec<(PathBuf, usize)>>,
        depth: usize,
    ) -> Vec<(PathBuf, Vec<String>)> {
        match includes.get(path) {
            Some(by) if depth < 8 => by
                .iter()
                .flat_map(|(includer, at)| {
                    let chars: Vec<char> = code
                        .get(includer)
                        .map_or(Vec::new(), |c| c.chars().collect());
                    let inline = inline_modules(&chars);
                    places(includer, code, includes, depth + 1).into_iter().map(
                        move |(k, mut m)| {
                            m.extend(
                                inline
                                    .iter()
                                    .filter(|(_, s, e)| s < at && at < e)
                                    .map(|(n, _, _)| n.clone()),
                            );
                            (k, m)
                        },
                    )
                })
                .collect(),
            _ => vec![module_path(path)],
        }
    }
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (path, _) in files {
        let from = path.to_string_lossy().into_owned();
        let edges = graph.entry(from.clone()).or_default();
        for (included, by) in &includes {
            if by.iter().any(|(p, _)| p == path) {
                edges.insert(included.to_string_lossy().into_owned());
            }
        }
        for (krate, module) in places(path, &code, &includes, 0) {
            let place: Place = (krate.clone(), module.clone(), code[path].clone());
            for target in named_files(&place, &modules, &code, 0) {
                // A module's file and its submodules' files are one unit
                // toward each other (see above).
                let (target_krate, target_module) = module_path(&target);
                if target_krate == krate
                    && (target_module.starts_with(&module) || module.starts_with(&target_module))
                {
                    continue;
                }
                edges.insert(target.to_string_lossy().into_owned());
            }
        }
    }
    graph
}

/// The files the code of `place` names, re-exports followed.
fn named_files(
    (krate, module, code): &Place,
    modules: &BTreeMap<(PathBuf, Vec<String>), PathBuf>,
    code_of: &BTreeMap<&PathBuf, String>,
    depth: usize,
) -> Vec<PathBuf> {
    let chars: Vec<char> = code.chars().collect();
    let inline = inline_modules(&chars);
    let mut found = Vec::new();
    for (full, _) in module_paths(&chars, krate, module, &inline, modules) {
        if let Some((file, n)) = file_of(modules, krate, &full) {
            found.push(reexported(file, &full[n..], krate, modules, code_of, depth));
        }
    }
    found
}

/// Every path of `chars` that names a module of the crate, as a full path
/// of modules and items from the crate's root, with the char index where
/// it is written.
fn module_paths(
    chars: &[char],
    krate: &Path,
    module: &[String],
    inline: &[(String, usize, usize)],
    modules: &BTreeMap<(PathBuf, Vec<String>), PathBuf>,
) -> Vec<(Vec<String>, usize)> {
    // The module the code at `at` is in: the file's, and the inline ones
    // around `at`.
    let module_at = |at: usize| -> Vec<String> {
        let mut m = module.to_vec();
        m.extend(
            inline
                .iter()
                .filter(|(_, s, e)| *s < at && at < *e)
                .map(|(n, _, _)| n.clone()),
        );
        m
    };
    let mut anchors: Vec<String> = ["crate", "super", "self"].map(String::from).to_vec();
    // A child module's name starts a relative path (`device::Gpu`).
    for (k, m) in modules.keys() {
        if k == krate && m.len() == module.len() + 1 && m.starts_with(module) {
            anchors.push(m[module.len()].clone());
        }
    }
    let mut found = Vec::new();
    for anchor in anchors {
        let needle = format!("{anchor}::");
        let mut i = 0;
        while let Some(at) = code_find(chars, i, &needle) {
            i = at + needle.len();
            if at > 0 && (is_ident(chars[at - 1]) || matches!(chars[at - 1], ':' | '$')) {
                continue;
            }
            let mut written = Vec::new();
            let mut j = i;
            paths(chars, &mut j, at, Vec::new(), &mut written);
            for (_, segments) in written {
                let mut base = module_at(at);
                let rest: Vec<String> = match anchor.as_str() {
                    "crate" => {
                        base.clear();
                        segments
                    }
                    "super" => {
                        base.pop();
                        let ups = segments.iter().take_while(|s| *s == "super").count();
                        base.truncate(base.len().saturating_sub(ups));
                        segments[ups..].to_vec()
                    }
                    "self" => segments,
                    child => std::iter::once(child.to_string()).chain(segments).collect(),
                };
                base.extend(rest.into_iter().filter(|s| s != "self"));
                found.push((base, at));
            }
        }
    }
    found
}

/// The file that defines `item` (its first segment) of `file`: `file`
/// itself, or where `file`'s `use` of that name leads.
fn reexported(
    file: &PathBuf,
    item: &[String],
    krate: &Path,
    modules: &BTreeMap<(PathBuf, Vec<String>), PathBuf>,
    code_of: &BTreeMap<&PathBuf, String>,
    depth: usize,
) -> PathBuf {
    let (Some(name), Some(code)) = (item.first(), code_of.get(file)) else {
        return file.clone();
    };
    if depth > 8 {
        return file.clone();
    }
    let (_, module) = module_path(file);
    let chars: Vec<char> = code.chars().collect();
    let inline = inline_modules(&chars);
    module_paths(&chars, krate, &module, &inline, modules)
        .into_iter()
        .filter(|(full, _)| full.last() == Some(name) && full.len() > 1)
        .find_map(|(full, _)| {
            let (target, n) = file_of(modules, krate, &full)?;
            (target != file)
                .then(|| reexported(target, &full[n..], krate, modules, code_of, depth + 1))
        })
        .unwrap_or_else(|| file.clone())
}
