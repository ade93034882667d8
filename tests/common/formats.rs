//! Helpers of the model-format tests (tests/formats.rs, tests/formats_gltf.rs).

use std::path::PathBuf;

use super::asset;

pub fn meshes(name: &str) -> PathBuf {
    asset(&format!("scenes/meshes/{name}"))
}

/// Asserts that `text` contains each of `parts`.
pub fn assert_has(text: &str, parts: &[&str]) {
    for part in parts {
        assert!(text.contains(part), "lacks '{part}': {text}");
    }
}

/// The one warning `mesh` has.
pub fn only_warning(mesh: &lambert::loading::Mesh) -> &str {
    assert_eq!(mesh.warnings.len(), 1, "{:?}", mesh.warnings);
    &mesh.warnings[0]
}

/// The RGB of each material's base colour.
pub fn albedos(mesh: &lambert::loading::Mesh) -> Vec<[f32; 3]> {
    mesh.materials
        .iter()
        .map(|m| [m.base_color[0], m.base_color[1], m.base_color[2]])
        .collect()
}
