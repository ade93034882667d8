#!/usr/bin/env python3
"""`Scene.intersect` and `Scene.occluded` against `lambert trace` on the
same rays, the CPU path, alternating (issue 48 item 3; docs/benchmarks.md).

    python benches/python_vs_trace.py [MODEL.obj] [--rounds 3] [--side 1024]

Defaults to ../shared/models/dragon.obj when it exists, else the bundled
dragon_res4. The model's framed camera rays (side x side) as C-contiguous
float32 and float64 arrays. Each round: `lambert trace --device cpu
--warmup` (its own trace time, median of 3 processes), then the binding's
intersect on float32 and on float64 arrays (medians of 7 calls in this
process, after a warm-up: conversion, checks and the output arrays
included), then `trace --any-hit` and `occluded` on float32 arrays.
Prints the trace's time over the binding's (1 = the CLI's speed), each
round's and, after the rounds, the median of each ratio over them (a
host that slows in spells moves single rounds by 10% either way).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np

import lambert
from python_bench import LAMBERT, cpu_name, default_model, median_time  # benches/, beside this script


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("model", nargs="?", default=default_model())
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--side", type=int, default=1024)
    args = parser.parse_args()

    scene = lambert.Scene.load(args.model)
    o, d = scene.camera_rays(args.side, args.side)
    o32, d32 = np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32)
    o64, d64 = o32.astype(np.float64), d32.astype(np.float64)
    rays = np.zeros(len(o32), dtype=lambert.RAY_DTYPE)
    for i, k in enumerate("xyz"):
        rays["o" + k] = o32[:, i]
        rays["d" + k] = d32[:, i]
    rays["tmax"] = np.inf
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "rays.bin")
        rays.tofile(path)

        def trace(any_hit):
            times = []
            for _ in range(3):
                out = subprocess.run(
                    [LAMBERT, "trace", "--obj", args.model, "--rays", path, "-o", os.path.join(tmp, "hits.bin"),
                     "--device", "cpu", "--warmup", "--json", "-q"] + (["--any-hit"] if any_hit else []),
                    check=True, capture_output=True, text=True,
                ).stdout
                times.append(json.loads(out)["trace_seconds"])
            return statistics.median(times)

        print(f"{os.path.basename(args.model)}, {len(o32)} camera rays, CPU path; {cpu_name()}, "
              f"{os.cpu_count()} threads")
        ratios = {"intersect float32": [], "intersect float64": [], "occluded float32": []}
        for r in range(args.rounds):
            closest = trace(False)
            f32 = median_time(7, lambda: scene.intersect(o32, d32, device="cpu"))
            f64 = median_time(7, lambda: scene.intersect(o64, d64, device="cpu"))
            any_hit = trace(True)
            occluded = median_time(7, lambda: scene.occluded(o32, d32, device="cpu"))
            f32_x, f64_x, occluded_x = closest / f32, closest / f64, any_hit / occluded
            print(f"round {r + 1}: trace {closest * 1e3:.1f} ms; intersect float32 {f32 * 1e3:.1f} ms "
                  f"({f32_x:.2f}x), float64 {f64 * 1e3:.1f} ms ({f64_x:.2f}x); "
                  f"trace --any-hit {any_hit * 1e3:.1f} ms, occluded float32 {occluded * 1e3:.1f} ms "
                  f"({occluded_x:.2f}x); load average {os.getloadavg()[0]:.1f}", flush=True)
            for name, ratio in zip(ratios, (f32_x, f64_x, occluded_x)):
                ratios[name].append(ratio)
        print("medians over the rounds: " + ", ".join(
            f"{name} {statistics.median(values):.2f}x" for name, values in ratios.items()))


if __name__ == "__main__":
    sys.exit(main())
