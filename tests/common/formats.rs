//! Helpers of the model-format tests (tests/formats.rs, tests/formats_gltf.rs,
//! tests/stl.rs, tests/defects.rs).

use std::path::{Path, PathBuf};

use lambert::loading::{Mesh, NormalMode, load_mesh};

use super::{asset, error_of, write};

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

/// Writes each case (a file name, its bytes, what its error says) to
/// `dir` and checks that loading it fails within `seconds`, with an error
/// that names the file and says what the case expects.
pub fn assert_load_errors<'a>(
    dir: &Path,
    cases: impl IntoIterator<Item = (&'a str, Vec<u8>, &'a str)>,
    seconds: u64,
) {
    for (name, bytes, expected) in cases {
        let path = write(dir, name, bytes);
        let start = std::time::Instant::now();
        let message = error_of(&path);
        assert!(message.contains(name), "{name}: {message}");
        assert!(
            message.contains(expected),
            "{name}: expected '{expected}' in: {message}"
        );
        assert!(
            start.elapsed().as_secs() < seconds,
            "{name} took {:?}",
            start.elapsed()
        );
    }
}

/// A folder holding `files` (name, text), and the mesh of the last (an
/// OBJ, say, after its MTL) loaded with face normals.
pub fn load_written(files: &[(&str, &str)]) -> (tempfile::TempDir, Mesh) {
    let dir = tempfile::tempdir().unwrap();
    let paths: Vec<PathBuf> = files
        .iter()
        .map(|(name, text)| write(dir.path(), name, text))
        .collect();
    let mesh = load_mesh(paths.last().unwrap(), NormalMode::Face).unwrap();
    (dir, mesh)
}
