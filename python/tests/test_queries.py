"""Hits from the binding against the CLI's on the same rays, bit for bit."""

import os

import numpy as np
import pytest

import lambert
from conftest import MESHES, SCENES, read_obj, random_rays, records

MESH_NAMES = ["bunny_lowres.obj", "dragon_res4.obj", "cube.obj", "fan.obj"]
DEVICES = ["cpu", "gpu"]


def assert_same_hits(hits, cli_hits):
    prim = cli_hits["prim"].astype(np.int64)
    prim[prim == 0xFFFFFFFF] = -1
    np.testing.assert_array_equal(hits["prim_id"], prim)
    np.testing.assert_array_equal(hits["t"], cli_hits["t"])
    np.testing.assert_array_equal(hits["u"], cli_hits["u"])
    np.testing.assert_array_equal(hits["v"], cli_hits["v"])


@pytest.mark.parametrize("name", MESH_NAMES)
@pytest.mark.parametrize("device", DEVICES)
def test_hits_equal_the_cli_on_every_mesh(name, device, trace_cli):
    path = os.path.join(MESHES, name)
    scene = lambert.Scene.load(path)
    o, d = random_rays(scene, 3000, seed=len(name))
    co, cd = scene.camera_rays(96, 64)
    o, d = np.concatenate([o, co]), np.concatenate([d, cd])
    rays = records(o, d)
    expected = trace_cli(path, rays, device)
    assert (expected["prim"] != 0xFFFFFFFF).sum() > len(rays) // 10, "the rays must hit something"
    # As arrays (float64, converted once) and as records (float32, viewed).
    assert_same_hits(scene.intersect(o.astype(np.float32), d.astype(np.float32), device=device), expected)
    assert_same_hits(scene.intersect(rays, device=device), expected)
    any_hit = trace_cli(path, rays, device, any_hit=True)
    np.testing.assert_array_equal(scene.occluded(rays, device=device), any_hit["prim"] != 0xFFFFFFFF)


@pytest.mark.parametrize("name", ["bunny_lowres.obj", "dragon_res4.obj"])
def test_from_arrays_is_the_model_file(name):
    path = os.path.join(MESHES, name)
    v, f = read_obj(path)
    from_file = lambert.Scene.load(path)
    # Any float and integer dtypes.
    from_arrays = lambert.Scene.from_arrays(v.astype(np.float32), f.astype(np.uint32))
    assert from_arrays.triangle_count == from_file.triangle_count == len(f)
    o, d = random_rays(from_file, 5000, seed=3)
    a, b = from_file.intersect(o, d, device="cpu"), from_arrays.intersect(o, d, device="cpu")
    for key in ("t", "prim_id", "u", "v", "normal"):
        np.testing.assert_array_equal(a[key], b[key])
    # The same framed camera, up to the float32 rounding of the vertices given.
    for key, value in from_file.camera.items():
        np.testing.assert_allclose(from_arrays.camera[key], value, rtol=1e-6, atol=1e-6)


def test_hit_fields_follow_embree_conventions():
    v = np.array([[0, 0, 0], [2, 0, 0], [0, 3, 0]], dtype=np.float64)
    scene = lambert.Scene.from_arrays(v, np.array([[0, 1, 2]], dtype=np.int16))
    o = np.array([[0.5, 0.75, 4.0], [5.0, 5.0, 4.0]])
    d = np.array([[0.0, 0.0, -2.0], [0.0, 0.0, -1.0]])
    for device in DEVICES:
        h = scene.intersect(o, d, device=device)
        assert h["t"].dtype == np.float32 and h["u"].dtype == np.float32 and h["v"].dtype == np.float32
        assert h["prim_id"].dtype == np.int64 and h["normal"].dtype == np.float32
        assert h["normal"].shape == (2, 3)
        # t in units of the direction given (|d| = 2): the plane is 4 away.
        assert h["t"][0] == 2.0 and h["prim_id"][0] == 0
        # P = (1-u-v) v0 + u v1 + v v2.
        p = (1 - h["u"][0] - h["v"][0]) * v[0] + h["u"][0] * v[1] + h["v"][0] * v[2]
        np.testing.assert_allclose(p, [0.5, 0.75, 0.0], atol=1e-6)
        np.testing.assert_array_equal(h["normal"][0], [0, 0, 6])  # (v1-v0) x (v2-v0)
        assert h["t"][1] == np.inf and h["prim_id"][1] == -1


def test_tmin_and_tmax_as_scalars_and_per_ray():
    v = np.array([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], dtype=np.float64)
    scene = lambert.Scene.from_arrays(v, [[0, 1, 2]])
    o = np.tile([0.0, 0.0, 5.0], (4, 1))
    d = np.tile([0.0, 0.0, -1.0], (4, 1))
    # The plane is at t = 5; hits count where tmin < t < tmax.
    tmin = np.array([0.0, 5.0, 4.9, 0.0])
    tmax = np.array([np.inf, np.inf, 5.1, 4.9])
    for device in DEVICES:
        h = scene.intersect(o, d, tmin, tmax, device=device)
        np.testing.assert_array_equal(h["prim_id"], [0, -1, 0, -1])
        np.testing.assert_array_equal(scene.occluded(o, d, tmin, tmax, device=device), [True, False, True, False])
        np.testing.assert_array_equal(scene.intersect(o, d, tmax=4.0, device=device)["prim_id"], [-1] * 4)


def test_ray_files_go_straight_in(tmp_path, cli):
    scene_path = os.path.join(SCENES, "bunny.toml")
    cli("camera-rays", scene_path, "-o", str(tmp_path / "rays.bin"), "--width", "40", "--height", "30")
    rays = np.fromfile(tmp_path / "rays.bin", dtype=lambert.RAY_DTYPE)
    scene = lambert.Scene.load(scene_path)
    o, d = scene.camera_rays(40, 30)
    assert o.dtype == np.float32 and o.shape == (1200, 3)
    np.testing.assert_array_equal(o, np.stack([rays["ox"], rays["oy"], rays["oz"]], axis=1))
    np.testing.assert_array_equal(d, np.stack([rays["dx"], rays["dy"], rays["dz"]], axis=1))
    a, b = scene.intersect(rays, device="cpu"), scene.intersect(o, d, device="cpu")
    np.testing.assert_array_equal(a["t"], b["t"])
    # One of width and height keeps the camera's aspect ratio.
    cam = scene.camera
    o2, _ = scene.camera_rays(width=cam["width"] * 2)
    assert len(o2) == cam["width"] * 2 * cam["height"] * 2


def test_an_empty_query_gives_empty_arrays():
    scene = lambert.Scene.load(os.path.join(MESHES, "cube.obj"))
    h = scene.intersect(np.zeros((0, 3)), np.zeros((0, 3)), device="cpu")
    assert h["t"].shape == (0,) and h["normal"].shape == (0, 3)
    assert scene.occluded(np.zeros((0, 3)), np.zeros((0, 3)), device="cpu").shape == (0,)


def test_intersect_options_reach_both_devices():
    scene = lambert.Scene.load(os.path.join(MESHES, "dragon_res4.obj"))
    o, d = random_rays(scene, 4000, seed=9)
    for name in ("watertight", "moller-trumbore", "seed"):
        cpu = scene.intersect(o, d, device="cpu", intersect=name)
        gpu = scene.intersect(o, d, device="gpu", intersect=name)
        np.testing.assert_array_equal(cpu["prim_id"], gpu["prim_id"])
    # The seed test is another test: it gives other distances than watertight.
    a = scene.intersect(o, d, device="cpu", intersect="seed")["t"]
    b = scene.intersect(o, d, device="cpu", intersect="watertight")["t"]
    assert not np.array_equal(a, b)
