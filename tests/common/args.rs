//! The argument lists many CLI tests give the binary.

use std::path::Path;

use super::s;

/// `lambert render` of `scene` to `out` on `device`.
pub fn render_args<'a>(scene: &'a Path, out: &'a Path, device: &'a str) -> Vec<&'a str> {
    vec!["render", s(scene), "-o", s(out), "--device", device]
}

/// `lambert trace` of the model `obj` and the ray file `rays` to `hits`.
pub fn trace_args<'a>(obj: &'a Path, rays: &'a Path, hits: &'a Path) -> Vec<&'a str> {
    vec!["trace", "--obj", s(obj), "--rays", s(rays), "-o", s(hits)]
}

/// `lambert render` of `scene` as a turntable of `frames` frames named by
/// `pattern`, on the CPU.
pub fn turntable_args<'a>(scene: &'a Path, frames: &'a str, pattern: &'a Path) -> Vec<&'a str> {
    vec![
        "render",
        s(scene),
        "--turntable",
        frames,
        "-o",
        s(pattern),
        "--device",
        "cpu",
    ]
}

/// `lambert bench --time-vs-error` at its cheapest (one run of 1 spp
/// against a 1-spp reference, on the CPU); scenes and outputs follow.
pub const CHEAPEST_BENCH: [&str; 10] = [
    "bench",
    "--time-vs-error",
    "--device",
    "cpu",
    "--spp-list",
    "1",
    "--reference-spp",
    "1",
    "--runs",
    "1",
];
