//! Running the `lambert` binary and the files its tests feed it.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// A command that runs the binary under test.
pub fn lambert_command() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lambert"))
}

/// Runs the binary with `args` to completion.
pub fn lambert(args: &[&str]) -> Output {
    lambert_in(Path::new("."), args)
}

/// Runs the binary with `args` in `dir`.
pub fn lambert_in(dir: &Path, args: &[&str]) -> Output {
    lambert_command()
        .current_dir(dir)
        .args(args)
        .output()
        .expect("lambert runs")
}

/// The binary's exit status, stdout and stderr; killed (and the test
/// failed) past 20 s, so that a regression to a hang fails rather than
/// stalls the suite.
pub fn lambert_with_deadline(args: &[&str]) -> (Option<i32>, String, String) {
    let mut child = lambert_command()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("lambert runs");
    let deadline = Instant::now() + Duration::from_secs(20);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if Instant::now() > deadline {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("lambert {args:?} still running after 20 s: killed");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let read = |mut pipe: Box<dyn Read>| {
        let mut text = String::new();
        pipe.read_to_string(&mut text).unwrap();
        text
    };
    let stdout = read(Box::new(child.stdout.take().unwrap()));
    let stderr = read(Box::new(child.stderr.take().unwrap()));
    (status.code(), stdout, stderr)
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A run's stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Writes `bytes` to `dir`/`name` and returns the path.
pub fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// Files in `dir` whose names mark them as lambert's temporaries.
pub fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp") || n.ends_with(".probe"))
        .collect()
}
