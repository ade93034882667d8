"""Shared fixtures: the repository's assets and the `lambert` binary the
hits are compared with (built by scripts/test before pytest runs)."""

import importlib
import json
import os
import subprocess

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MESHES = os.path.join(ROOT, "assets", "scenes", "meshes")
SCENES = os.path.join(ROOT, "assets", "scenes")
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
LAMBERT = os.environ.get("LAMBERT", os.path.join(TARGET, "release", "lambert"))
SHARED_MODELS = os.path.join(os.path.dirname(ROOT), "shared", "models")
HIT_DTYPE = np.dtype([("t", "<f4"), ("prim", "<u4"), ("u", "<f4"), ("v", "<f4")])


@pytest.fixture(scope="session")
def cli():
    """Runs the lambert binary; returns its stdout."""
    if not os.path.exists(LAMBERT):
        pytest.fail(f"{LAMBERT} is missing: build it with cargo build --release")

    def run(*args, env=None):
        full_env = dict(os.environ, NODEVICE_SELECT="1", **(env or {}))
        done = subprocess.run([LAMBERT, *args], capture_output=True, text=True, env=full_env)
        if done.returncode != 0:
            raise AssertionError(f"lambert {' '.join(args)} failed: {done.stderr}")
        return done.stdout

    return run


def read_obj(path):
    """Vertices and triangles of a triangles-only OBJ, in file order."""
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                vertices.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = [int(p.split("/")[0]) for p in parts[1:]]
                idx = [i - 1 if i > 0 else len(vertices) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    faces.append([idx[0], idx[k], idx[k + 1]])
    return np.array(vertices), np.array(faces)


def random_rays(scene, n, seed):
    """Rays from around the scene's bounding box in random directions."""
    lo, hi = (np.array(b, dtype=np.float64) for b in scene.bounds)
    centre, size = (lo + hi) / 2, np.linalg.norm(hi - lo)
    rng = np.random.default_rng(seed)
    o = centre + size * (rng.random((n, 3)) - 0.5)
    d = rng.normal(size=(n, 3))
    return o, d


def records(o, d, tmin=0.0, tmax=np.inf):
    import lambert

    r = np.zeros(len(o), dtype=lambert.RAY_DTYPE)
    for i, k in enumerate(("ox", "oy", "oz")):
        r[k] = o[:, i]
    for i, k in enumerate(("dx", "dy", "dz")):
        r[k] = d[:, i]
    r["tmin"], r["tmax"] = tmin, tmax
    return r


@pytest.fixture(scope="session")
def trace_cli(cli, tmp_path_factory):
    """`lambert trace` on a ray-record array; returns its HIT_DTYPE hits."""

    def trace(mesh, rays, device="cpu", any_hit=False):
        tmp = tmp_path_factory.mktemp("trace")
        rays.tofile(tmp / "rays.bin")
        args = ["trace", "--obj", mesh, "--rays", str(tmp / "rays.bin"), "-o", str(tmp / "hits.bin"),
                "--device", device, "-q"]
        cli(*args, *(["--any-hit"] if any_hit else []))
        return np.fromfile(tmp / "hits.bin", dtype=HIT_DTYPE)

    return trace


def reference_module(name, needed_by=None):
    """A test-only reference (open3d, igl; scipy and rtree for trimesh's
    proximity, `needed_by` saying what uses it) that scripts/test-python
    installs: skips without it, except under CI (CI=true), where its absence
    fails, so that the comparison never silently stops running."""
    why = f", which {needed_by} needs," if needed_by else ""
    try:
        return importlib.import_module(name)
    except ImportError as e:
        if os.environ.get("CI", "").lower() in ("true", "1"):
            pytest.fail(f"{name}{why} is not importable under CI ({e}): scripts/test-python installs it")
        pytest.skip(f"{name}{why} is not installed (scripts/test-python installs it)")


def open3d_scenes(vertices, faces):
    """Open3D's RaycastingScene of the mesh and lambert's drop-in one (CPU),
    for the comparisons: (theirs, ours)."""
    import lambert

    o3d = reference_module("open3d")
    theirs = o3d.t.geometry.RaycastingScene()
    theirs.add_triangles(o3d.core.Tensor(vertices), o3d.core.Tensor(faces))
    ours = lambert.open3d.RaycastingScene(device="cpu")
    ours.add_triangles(vertices, faces)
    return theirs, ours


QUERY_DEVICES = ["cpu", "gpu"]
