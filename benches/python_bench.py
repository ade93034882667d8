#!/usr/bin/env python3
"""The Python binding against `lambert trace` and against embreex and
trimesh, in one process, on the same rays (docs/benchmarks.md).

    python benches/python_bench.py [MODEL.obj ...] [--json out.json]

Defaults to ../shared/models/dragon.obj (the 871k-triangle Stanford
dragon) when it exists, else the bundled bunny. For each model: its
framed camera's rays at 1024x1024 and as many incoherent rays (random
origins in the bounding sphere, random directions), closest hits, on the
CPU path and on the GPU (lavapipe here: --device gpu). Times are medians
of --runs runs after one warm-up; `lambert trace --warmup` reports its own
trace time for the same ray file. trimesh's intersector is timed on a
hundredth of the rays (it is far slower) and scaled.
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import lambert

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAMBERT = os.environ.get(
    "LAMBERT", os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "lambert")
)


def cpu_name():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def default_model():
    """The full dragon from ../shared when it is there, else the bundled
    dragon_res4."""
    shared = os.path.join(ROOT, "..", "shared", "models", "dragon.obj")
    return shared if os.path.exists(shared) else os.path.join(ROOT, "assets", "scenes", "meshes", "dragon_res4.obj")


def median_time(runs, f):
    f()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def load_mesh(path):
    """Vertices and faces in file order (no merging, no reordering)."""
    import trimesh

    mesh = trimesh.load(path, process=False, force="mesh")
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64), mesh


def incoherent_rays(scene, n, seed=1):
    lo, hi = (np.array(b, dtype=np.float64) for b in scene.bounds)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    rng = np.random.default_rng(seed)
    o = centre + radius * (rng.random((n, 3)) * 2 - 1) * 0.6
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return o.astype(np.float32), d.astype(np.float32)


def trace_cli(model, o, d, device, runs):
    """`lambert trace`'s own trace time (median) for these rays."""
    rays = np.zeros(len(o), dtype=lambert.RAY_DTYPE)
    for i, k in enumerate(("ox", "oy", "oz")):
        rays[k] = o[:, i]
    for i, k in enumerate(("dx", "dy", "dz")):
        rays[k] = d[:, i]
    rays["tmax"] = np.inf
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "rays.bin")
        rays.tofile(path)
        times = []
        for _ in range(runs):
            out = subprocess.run(
                [LAMBERT, "trace", "--obj", model, "--rays", path, "-o", os.path.join(tmp, "hits.bin"),
                 "--device", device, "--warmup", "--json", "-q"],
                check=True, capture_output=True, text=True,
            ).stdout
            report = json.loads(out)
            times.append(report["trace_seconds"])
        hits = np.fromfile(os.path.join(tmp, "hits.bin"), dtype=[("t", "<f4"), ("prim", "<u4"), ("u", "<f4"), ("v", "<f4")])
    return statistics.median(times), report, hits


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("models", nargs="*")
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--side", type=int, default=1024, help="camera rays: side x side")
    parser.add_argument("--json")
    parser.add_argument("--no-gpu", action="store_true")
    args = parser.parse_args()
    models = args.models or [
        p for p in [os.path.join(ROOT, "..", "shared", "models", "dragon.obj")] if os.path.exists(p)
    ] or [os.path.join(ROOT, "assets", "scenes", "meshes", "bunny.obj")]

    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        rtcore_scene = None
    try:
        import trimesh.ray.ray_triangle as ray_triangle
    except ImportError:
        ray_triangle = None

    print(f"machine: {cpu_name()}, {os.cpu_count()} threads; Python {platform.python_version()}")
    results = []
    for model in models:
        v, f, mesh = load_mesh(model)
        start = time.perf_counter()
        scene = lambert.Scene.from_arrays(v, f)
        build = time.perf_counter() - start
        print(f"\n{os.path.basename(model)}: {len(f)} triangles; Scene.from_arrays {build:.2f} s")
        embree = None
        if rtcore_scene is not None:
            embree = rtcore_scene.EmbreeScene()
            TriangleMesh(scene=embree, vertices=v.astype(np.float32), indices=f.astype(np.int32))
        ray_sets = {
            "camera": scene.camera_rays(args.side, args.side),
            "incoherent": incoherent_rays(scene, args.side * args.side),
        }
        devices = ["cpu"] + ([] if args.no_gpu else ["gpu"])
        for name, (o, d) in ray_sets.items():
            n = len(o)
            row = {"model": os.path.basename(model), "triangles": len(f), "rays": name, "count": n}
            for device in devices:
                hits = scene.intersect(o, d, device=device)
                ours = median_time(args.runs, lambda: scene.intersect(o, d, device=device))
                cli, report, cli_hits = trace_cli(model, o, d, device, max(1, args.runs // 2))
                cli_prim = cli_hits["prim"].astype(np.int64)
                cli_prim[cli_prim == 0xFFFFFFFF] = -1
                same = np.array_equal(cli_hits["t"], hits["t"]) and np.array_equal(cli_prim, hits["prim_id"])
                row[device] = {
                    "binding_seconds": ours, "trace_cli_seconds": cli, "overhead": ours / cli - 1,
                    "binding_mrays": n / ours / 1e6, "same_hits_as_cli": bool(same),
                    "device": report["device"],
                }
                print(f"  {name:10} {device}: binding {ours * 1e3:8.1f} ms ({n / ours / 1e6:6.2f} Mrays/s), "
                      f"lambert trace {cli * 1e3:8.1f} ms: {100 * (ours / cli - 1):+5.1f}%; hits identical: {same}")
            if embree is not None:
                o32, d32 = o.astype(np.float32), d.astype(np.float32)
                e = median_time(args.runs, lambda: embree.run(o32, d32, output=1))
                eh = embree.run(o32, d32, output=1)
                ours = scene.intersect(o, d, device="cpu")
                prim_same = np.mean(eh["primID"].astype(np.int64) == ours["prim_id"])
                both = (eh["primID"] >= 0) & (ours["prim_id"] >= 0)
                t_rel = np.abs(eh["tfar"][both] - ours["t"][both]) / np.maximum(ours["t"][both], 1e-30)
                row["embreex"] = {"seconds": e, "mrays": n / e / 1e6, "same_prim": float(prim_same),
                                  "t_rel_max": float(t_rel.max()) if both.any() else 0.0}
                print(f"  {name:10} embreex: {e * 1e3:8.1f} ms ({n / e / 1e6:6.2f} Mrays/s); lambert cpu/embreex time "
                      f"{row['cpu']['binding_seconds'] / e:.2f}x; same primitive on {100 * prim_same:.4f}% of rays, "
                      f"max relative t difference {row['embreex']['t_rel_max']:.1e}")
            if ray_triangle is not None:
                k = max(1, n // 100)
                tri = ray_triangle.RayMeshIntersector(mesh)
                tm = median_time(1, lambda: tri.intersects_first(o[:k], d[:k])) * n / k
                row["trimesh"] = {"seconds": tm, "mrays": n / tm / 1e6}
                print(f"  {name:10} trimesh (ray_triangle, scaled from {k} rays): {tm:8.2f} s ({n / tm / 1e6:6.3f} Mrays/s)")
            results.append(row)
    if args.json:
        with open(args.json, "w") as out:
            json.dump({"machine": cpu_name(), "results": results}, out, indent=2)


if __name__ == "__main__":
    sys.exit(main())
