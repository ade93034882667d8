//! A device with ray queries for the hardware path's tests
//! (tests/hardware_rays.rs, tests/hardware_path.rs): this process's,
//! where its adapter has them (a real RT GPU, or a system Mesa ≥ 24.1);
//! else the private lavapipe that scripts/mesa-rt unpacks into the target
//! directory (Mesa 25 from Debian's bookworm-backports), in a child
//! process of the test binary, since the Vulkan loader and the dynamic
//! linker read their variables once per process. The rest of the suite
//! keeps the system's Mesa.

use std::path::PathBuf;
use std::process::Command;

use lambert::gpu::{AdapterRequest, Gpu};

/// Set in the child process: it must find ray queries, not spawn again.
const CHILD_ENV: &str = "LAMBERT_RAY_QUERY_CHILD";

/// The private lavapipe's prefix: `mesa-rt` in the target directory
/// (this binary is `<target>/<profile>/deps/<test>`).
pub fn private_mesa() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    let target = exe
        .ancestors()
        .nth(3)
        .expect("<target>/<profile>/deps/<test>");
    target.join("mesa-rt")
}

/// The variables that point the Vulkan loader at the private lavapipe
/// alone (its ICD file) and the linker at its libraries (in Debian's
/// multiarch directory, as scripts/mesa-rt unpacks them).
pub fn private_mesa_env(prefix: &std::path::Path) -> [(&'static str, String); 2] {
    let libs = prefix.join(format!("usr/lib/{}-linux-gnu", std::env::consts::ARCH));
    let path = match std::env::var("LD_LIBRARY_PATH") {
        Ok(old) if !old.is_empty() => format!("{}:{old}", libs.display()),
        _ => libs.display().to_string(),
    };
    let icd = prefix.join("usr/share/vulkan/icd.d/lvp_icd.json");
    [
        ("VK_DRIVER_FILES", icd.display().to_string()),
        ("LD_LIBRARY_PATH", path),
    ]
}

/// A device opened with ray queries, for the test named `test` (its
/// function's name). None where the test ran elsewhere or cannot run:
/// - this process's adapter has them: the device;
/// - else, with the private lavapipe unpacked: the test again in a child
///   process on it (its output shown, its failure this test's), and None;
/// - else None, saying why, outside CI; under CI (CI=true) a failure,
///   since scripts/test installs the private lavapipe there.
pub fn ray_query_gpu(test: &str) -> Option<Gpu> {
    let request = AdapterRequest {
        ray_queries: true,
        ..AdapterRequest::default()
    };
    let gpu = Gpu::open(&request, false).ok();
    if let Some(gpu) = gpu.filter(|g| g.device.features().contains(RAY_QUERY)) {
        return Some(gpu);
    }
    if std::env::var_os(CHILD_ENV).is_some() {
        panic!(
            "the private lavapipe ({}) offers no ray queries",
            private_mesa().display()
        );
    }
    let prefix = private_mesa();
    if prefix.join("usr/share/vulkan/icd.d/lvp_icd.json").is_file() {
        run_in_child(test, &prefix);
        return None;
    }
    let why = format!(
        "{test}: no adapter with ray queries (Mesa ≥ 24.1's lavapipe or an RT GPU), \
         and no private lavapipe at {} (scripts/mesa-rt unpacks one)",
        prefix.display()
    );
    if std::env::var("CI").as_deref() == Ok("true") {
        panic!("{why}: under CI the hardware path's tests must run");
    }
    println!("skipped: {why}");
    None
}

const RAY_QUERY: wgpu::Features = wgpu::Features::EXPERIMENTAL_RAY_QUERY;

/// One child at a time: each runs lavapipe on every core.
static ONE_CHILD: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Runs test `test` of this binary alone in a child process on the
/// lavapipe at `prefix`, printing its output; panics if it fails.
fn run_in_child(test: &str, prefix: &std::path::Path) {
    let _turn = ONE_CHILD.lock().unwrap_or_else(|e| e.into_inner());
    let exe = std::env::current_exe().expect("the test binary's path");
    let output = Command::new(exe)
        .args([test, "--exact", "--nocapture", "--test-threads=1"])
        .envs(private_mesa_env(prefix))
        .env(CHILD_ENV, "1")
        .env("NODEVICE_SELECT", "1")
        .output()
        .expect("the test binary runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    println!(
        "{test} ran on the private lavapipe ({}):\n{text}",
        prefix.display()
    );
    assert!(
        output.status.success(),
        "{test} failed on the private lavapipe"
    );
    assert!(
        text.contains("1 passed"),
        "{test}: the child process ran no test"
    );
}
