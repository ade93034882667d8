//! Interrupting the binary mid-run, for the tests of what a signal leaves.

use std::path::Path;
use std::process::{Child, Command};
use std::time::Duration;

use super::temporaries;

/// Sends `child` SIGINT (even rounds) or SIGTERM (odd ones) `delay_ms`
/// after its start, waits for it and checks that it left no temporary file
/// in `dir`; returns whether it succeeded and the bytes `output` holds.
pub fn interrupt(
    mut child: Child,
    round: usize,
    delay_ms: u64,
    dir: &Path,
    output: &Path,
) -> (bool, Vec<u8>) {
    std::thread::sleep(Duration::from_millis(delay_ms));
    let signal = if round.is_multiple_of(2) {
        "-INT"
    } else {
        "-TERM"
    };
    Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    let status = child.wait().unwrap();
    assert!(
        temporaries(dir).is_empty(),
        "after {delay_ms} ms: {:?}",
        temporaries(dir)
    );
    (status.success(), std::fs::read(output).unwrap())
}
