//! Rules of the code's shape that the refactors of issue 45 set: no `.rs`
//! file pasted into another, the CPU twin's precisions defining nothing
//! but their `Scalar`, `Scene`'s fields the crate's, and no front end
//! naming the renderer's variants (tests/architecture.rs has the layers,
//! sizes and cycles).

use std::path::{Path, PathBuf};

// Only some of its helpers are used here.
#[allow(dead_code)]
#[path = "common/source.rs"]
mod source;

use source::*;

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
    assert_none(
        &found,
        "`.rs` files pasted in with include! (make them modules, docs/architecture.md)",
    );
}

// ---- the twin's precisions ---------------------------------------------------

/// Each item that a precision's module (`text`, src/cpu/f32.rs or f64.rs)
/// defines at its top level beyond `kernel!`'s expansion, its `impl
/// Scalar for Real` and its `#[cfg(test)] mod tests`, as `path:line:
/// item`. The stages `kernel!` expands take what differs by precision
/// from the trait `Scalar` alone (src/cpu/kernel.rs): an item defined
/// here would be a name they could come to use unqualified, which the
/// other precision might not define.
fn precision_module_items(path: &str, text: &str) -> Vec<String> {
    let mut found = Vec::new();
    let mut depth = 0i64;
    let mut after_cfg_test = false;
    for (i, line) in code_only(text).lines().enumerate() {
        let item = line.trim();
        if depth == 0 && !item.is_empty() {
            let allowed = item.starts_with("super::kernel::kernel!(")
                || item == "impl Scalar for Real {"
                || item == "#[cfg(test)]"
                || (after_cfg_test && item == "mod tests {")
                || item == "}";
            if !allowed {
                found.push(format!("{path}:{}: {item}", i + 1));
            }
            after_cfg_test = item == "#[cfg(test)]";
        }
        let count = |brackets: &[char]| line.matches(brackets).count() as i64;
        depth += count(&['{', '(', '[']) - count(&['}', ')', ']']);
    }
    found
}

#[test]
fn the_precisions_define_nothing_but_their_scalar() {
    let mut found = Vec::new();
    for path in ["src/cpu/f32.rs", "src/cpu/f64.rs"] {
        let text = std::fs::read_to_string(Path::new(ROOT).join(path)).unwrap();
        assert!(
            text.contains("impl Scalar for Real {"),
            "{path}: no `impl Scalar for Real`"
        );
        found.extend(precision_module_items(path, &text));
    }
    assert_none(
        &found,
        "items in a precision's module beside its `impl Scalar` (put what differs by \
         precision in the trait, src/cpu/precision.rs, and the rest in a stage)",
    );
}

#[test]
fn the_precision_check_finds_items_beside_the_trait() {
    let text = "//! fn documented() {}\nsuper::kernel::kernel!(\n    f32,\n    glam::Vec2,\n);\n\
                impl Scalar for Real {\n    fn high_half(x: Real) -> Real {\n        x\n    }\n}\n\
                #[inline(always)]\nfn greater_of(a: Vec4, b: Vec4) -> Vec4 {\n    a\n}\n\
                pub use crate::camera::f32::CameraBasis;\nmod tests {}\n\
                #[cfg(test)]\nmod tests {\n    fn helper() {}\n}\n";
    assert_eq!(
        precision_module_items("src/cpu/f32.rs", text),
        [
            "src/cpu/f32.rs:11: #[inline(always)]",
            "src/cpu/f32.rs:12: fn greater_of(a: Vec4, b: Vec4) -> Vec4 {",
            "src/cpu/f32.rs:15: pub use crate::camera::f32::CameraBasis;",
            "src/cpu/f32.rs:16: mod tests {}",
        ]
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
    assert_none(
        &public,
        "src/scene/mod.rs: `Scene` has public fields (make them pub(crate) and add a method)",
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
    assert_none(
        &named,
        "front ends match on Renderer's variants (use its methods)",
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
