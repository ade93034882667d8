#!/usr/bin/env python3
"""Two or more builds of the Python extension in one process, their calls
alternating, on the same rays (docs/benchmarks.md, the eleventh session).

    python benches/python_ab.py OLD_DIR NEW_DIR [MORE_DIR ...] [--query intersect|intersect64|occluded]
                                [--calls 30] [--model MODEL.obj]

Each DIR holds a `lambert/` package (a copy of an installed one: the
extension and its Python files). They are imported under names of their
own, so each keeps its own extension. Prints, for each build after the
first, the median over the pairs of calls side by side of its call's time
over the first build's (below 1: faster), then each build's median time.
A host whose speed changes in spells of seconds moves both calls of a
pair alike, which separate processes do not.
"""

import argparse
import importlib
import os
import shutil
import statistics
import sys
import tempfile
import time

import numpy as np

from python_bench import default_model  # benches/, beside this script


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("builds", nargs="+", help="directories holding a lambert/ package")
    parser.add_argument("--query", choices=["intersect", "intersect64", "occluded"], default="intersect")
    parser.add_argument("--calls", type=int, default=30)
    parser.add_argument("--model", default=default_model())
    parser.add_argument("--side", type=int, default=1024)
    args = parser.parse_args()
    if len(args.builds) < 2:
        parser.error("give at least two builds")

    with tempfile.TemporaryDirectory() as root:
        for i, build in enumerate(args.builds):
            shutil.copytree(os.path.join(build, "lambert"), os.path.join(root, f"lambert_{i}"))
        sys.path.insert(0, root)
        modules = [importlib.import_module(f"lambert_{i}") for i in range(len(args.builds))]
        compare(args, [m.Scene.load(args.model) for m in modules])


def compare(args, scenes):
    o, d = scenes[0].camera_rays(args.side, args.side)
    o32, d32 = np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32)
    o64, d64 = o32.astype(np.float64), d32.astype(np.float64)

    def call(scene):
        if args.query == "intersect":
            return scene.intersect(o32, d32, device="cpu")
        if args.query == "intersect64":
            return scene.intersect(o64, d64, device="cpu")
        return scene.occluded(o32, d32, device="cpu")

    for scene in scenes:
        call(scene)
    times = [[] for _ in scenes]
    for r in range(args.calls):
        # Each build first as often as last.
        order = list(range(len(scenes)))
        for k in order if r % 2 == 0 else reversed(order):
            start = time.perf_counter()
            out = call(scenes[k])
            times[k].append(time.perf_counter() - start)
            del out

    for build, t in zip(args.builds[1:], times[1:]):
        ratios = sorted(b / a for a, b in zip(times[0], t))
        q = len(ratios) // 4
        print(f"{build}: {statistics.median(ratios):.4f} of {args.builds[0]}'s time "
              f"(quartiles {ratios[q]:.4f}, {ratios[-1 - q]:.4f})")
    for build, t in zip(args.builds, times):
        print(f"{build}: median {statistics.median(t) * 1e3:.2f} ms, fastest {min(t) * 1e3:.2f} ms")


if __name__ == "__main__":
    sys.exit(main())
