#!/usr/bin/env python3
"""Closest points and signed distances: lambert (CPU path and GPU) against
Open3D's RaycastingScene, in one process, on the same points
(docs/benchmarks.md, "Proximity queries").

    python benches/proximity_bench.py [MODEL.obj] [--points 1000000] [--rounds 4] [--json out.json]

Defaults to ../shared/models/dragon.obj (the 871k-triangle Stanford
dragon) when it exists, else the bundled dragon_res4. The points are
uniform over 1.5 times the model's bounding box (float32, seed 1). Each
round times every contender once, in turn (A, B, C, A, B, C, ...), so a
machine's load drifts over all of them alike; the figure is each one's
median over the rounds, after one untimed warm-up call (the BVH build,
the GPU upload and pipelines, Open3D's scene commit). Ratios are Open3D's
median time over lambert's: above 1, lambert is faster.

Open3D's signed distance signs by ray parity; lambert's by the winding
number (the default, timed here) or by parity (--parity adds it).
"""

import argparse
import json
import os
import statistics
import sys
import time

import numpy as np

import lambert
from python_bench import cpu_name, default_model  # benches/, beside this script


def load_mesh(path):
    """Vertices (float32, as Open3D stores them) and faces, in file order."""
    import trimesh

    mesh = trimesh.load(path, process=False, force="mesh")
    return np.asarray(mesh.vertices, dtype=np.float32), np.asarray(mesh.faces, dtype=np.uint32)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("model", nargs="?", default=default_model())
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--no-gpu", action="store_true", help="time the CPU path and Open3D only")
    parser.add_argument("--parity", action="store_true", help="also time lambert's parity signed distance")
    parser.add_argument("--no-open3d", action="store_true",
                        help="time lambert alone (to compare two builds of it, alternating processes)")
    parser.add_argument("--json", help="write the figures here")
    args = parser.parse_args()

    import open3d as o3d

    start = time.perf_counter()
    v, f = load_mesh(args.model)
    print(f"{os.path.basename(args.model)}: {len(f)} triangles, loaded in {time.perf_counter() - start:.1f} s",
          file=sys.stderr)
    lo, hi = v.min(axis=0), v.max(axis=0)
    rng = np.random.default_rng(1)
    points = ((lo + hi) / 2 + (rng.random((args.points, 3)) - 0.5) * 1.5 * (hi - lo)).astype(np.float32)

    scene = lambert.Scene.from_arrays(v, f)
    theirs = o3d.t.geometry.RaycastingScene()
    theirs.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(f))
    q = o3d.core.Tensor(points)

    devices = ["cpu"] + ([] if args.no_gpu else ["gpu"])
    contenders = {}
    for device in devices:
        contenders[f"lambert {device} closest"] = lambda d=device: scene.closest_points(points, device=d)
        contenders[f"lambert {device} signed"] = lambda d=device: scene.signed_distance(points, device=d)
        if args.parity:
            contenders[f"lambert {device} signed parity"] = (
                lambda d=device: scene.signed_distance(points, method="parity", device=d))
    if not args.no_open3d:
        contenders["open3d closest"] = lambda: theirs.compute_closest_points(q)
        contenders["open3d signed"] = lambda: theirs.compute_signed_distance(q)

    for name, run in contenders.items():
        start = time.perf_counter()
        run()
        print(f"warm-up {name}: {time.perf_counter() - start:.2f} s", file=sys.stderr)
    times = {name: [] for name in contenders}
    for r in range(args.rounds):
        for name, run in contenders.items():
            start = time.perf_counter()
            run()
            times[name].append(time.perf_counter() - start)
        print(f"round {r + 1}: " + ", ".join(f"{n} {t[-1]:.2f} s" for n, t in times.items()), file=sys.stderr)

    # The answers agree (distances to f32 rounding), so the race is fair.
    worst = None
    if not args.no_open3d:
        mine = scene.closest_points(points, device="cpu")["distance"]
        their = np.linalg.norm(theirs.compute_closest_points(q)["points"].numpy() - points, axis=1)
        worst = float(np.max(np.abs(mine - their)) / np.linalg.norm(hi - lo))

    median = {name: statistics.median(t) for name, t in times.items()}
    report = {
        "model": os.path.basename(args.model), "triangles": int(len(f)), "points": args.points,
        "rounds": args.rounds, "cpu": cpu_name(), "threads": os.cpu_count(),
        "gpu": scene.device("gpu") if "gpu" in devices else None,
        "open3d": o3d.__version__, "max_distance_difference_over_size": worst,
        "median_seconds": median,
        "mqueries_per_second": {n: args.points / t / 1e6 for n, t in median.items()},
        "times": times,
        "speedup_over_open3d": {},
    }
    for device in devices if not args.no_open3d else []:
        for what in ("closest", "signed"):
            report["speedup_over_open3d"][f"{device} {what}"] = median[f"open3d {what}"] / median[
                f"lambert {device} {what}"]
    print(f"{report['model']} ({len(f)} triangles), {args.points} points over 1.5x its box, "
          f"{args.rounds} alternating rounds, medians; {report['cpu']}, {report['threads']} threads")
    for name, t in median.items():
        print(f"  {name:32s} {t:8.3f} s  {args.points / t / 1e6:8.3f} M points/s")
    for name, ratio in report["speedup_over_open3d"].items():
        print(f"  lambert {name} vs Open3D: {ratio:.2f}x")
    if worst is not None:
        print(f"  largest distance difference from Open3D: {worst:.1e} of the model's size")
    if args.json:
        with open(args.json, "w") as out:
            json.dump(report, out, indent=2)


if __name__ == "__main__":
    main()
