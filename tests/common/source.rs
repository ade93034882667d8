//! Reading src/'s code as text for tests/architecture.rs: its files, its
//! code without comments and strings, the paths it names, and the cycles
//! of a graph.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

pub const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Files under `dir` (recursively) whose names end with `suffix`, as paths
/// relative to the crate root.
pub fn files(dir: &str, suffix: &str) -> Vec<PathBuf> {
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

pub fn line_count(path: &Path) -> usize {
    std::fs::read_to_string(Path::new(ROOT).join(path))
        .unwrap()
        .lines()
        .count()
}

/// `text` without comments (line, doc and block) and string literals, so
/// that only code is searched for `crate::` paths; the newlines of what it
/// drops stay, so that every line keeps its number.
pub fn code_only(text: &str) -> String {
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

pub fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// A `crate::` path: where it is written (a char index: the `crate::`, or
/// the member of a group) and its segments after `crate`.
pub type CratePath = (usize, Vec<String>);

/// The paths of a use tree or path starting at `chars[*i]` (just after a
/// `crate::`, or at a group's member, written at `at`), each as its
/// segments, prefixed by `prefix`; a group (`{a, b::c}`) gives one path
/// per member.
pub fn paths(
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
pub fn crate_paths(code: &str) -> Vec<Vec<String>> {
    crate_paths_at(code).into_iter().map(|(_, p)| p).collect()
}

/// `crate_paths`, each with the line (from 1) it is written on.
pub fn crate_paths_at(code: &str) -> Vec<CratePath> {
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
pub fn crate_paths_found(chars: &[char]) -> Vec<CratePath> {
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

pub fn code_find(chars: &[char], from: usize, needle: &str) -> Option<usize> {
    let needle: Vec<char> = needle.chars().collect();
    (from..chars.len().saturating_sub(needle.len() - 1))
        .find(|&k| chars[k..k + needle.len()] == needle[..])
}

/// The graph's cycles: its strongly connected components of more than one
/// module (Tarjan's algorithm), each sorted.
pub fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
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

/// Every Rust file of src/, with its text.
pub fn source_files() -> Vec<(PathBuf, String)> {
    files("src", ".rs")
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(Path::new(ROOT).join(&path)).unwrap();
            (path, text)
        })
        .collect()
}

/// Fails listing `problems` under `what`, if there are any.
pub fn assert_none(problems: &[String], what: &str) {
    assert!(problems.is_empty(), "{what}:\n{}", problems.join("\n"));
}
