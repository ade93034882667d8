//! What the CLI tests share: a scene's parts as TOML, a folder of inputs, and a failure's checks.

use std::path::PathBuf;
use std::process::Output;

use super::{lambert, s};

pub const CAMERA: &str = "\n[camera]\neye = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 16\nheight = 12\n";

pub const SPHERE: &str = "[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";
pub const LIGHT: &str = "[[point_light]]\nposition = [0.0, 2.0, 3.0]\nintensity = 10.0\n";
pub const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

pub struct Case {
    pub dir: tempfile::TempDir,
}

impl Case {
    pub fn new() -> Case {
        Case {
            dir: tempfile::tempdir().unwrap(),
        }
    }

    /// A case whose scene.toml (returned) is a lit sphere in view.
    pub fn lit_sphere() -> (Case, PathBuf) {
        let case = Case::new();
        let scene = case.file("scene.toml", &format!("{CAMERA}{SPHERE}{LIGHT}"));
        (case, scene)
    }

    pub fn file(&self, name: &str, text: &str) -> PathBuf {
        let path = self.dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// Renders `scene` on the CPU path and expects a failure naming `expected`.
    pub fn fails(&self, scene: &str, expected: &[&str]) {
        let scene_path = self.file("scene.toml", scene);
        let out = self.path("out.png");
        let output = lambert(&["render", s(&scene_path), "-o", s(&out), "--device", "cpu"]);
        expect_failure(&output, expected);
        assert!(!out.exists(), "a failed render wrote an image");
    }
}

pub fn expect_failure(output: &Output, expected: &[&str]) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!("{stderr}");
    assert!(
        !output.status.success(),
        "expected failure, got success; stderr:\n{stderr}"
    );
    assert_eq!(output.status.code(), Some(1), "stderr:\n{stderr}");
    assert!(!stderr.contains("panicked"), "panic:\n{stderr}");
    for e in expected {
        assert!(stderr.contains(e), "stderr lacks '{e}':\n{stderr}");
    }
}
