"""`lambert query` (docs/ray-query.md, "Closest points, distances and
crossings"): its files hold what the Python package returns, bit for bit,
on both devices; bad files and options are errors naming what is wrong,
and nothing is written then."""

import json
import os
import re
import subprocess

import numpy as np
import pytest

import lambert
from conftest import LAMBERT, MESHES, QUERY_DEVICES, records

MESH = os.path.join(MESHES, "bunny_lowres.obj")
CLOSEST_DTYPE = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("prim", "<u4"), ("u", "<f4"), ("v", "<f4"),
                          ("distance", "<f4"), ("reserved", "<u4")])
LISTED_DTYPE = np.dtype([("ray", "<u4"), ("prim", "<u4"), ("t", "<f4"), ("u", "<f4"), ("v", "<f4")])


@pytest.fixture(scope="module")
def bunny():
    scene = lambert.Scene.load(MESH)
    lo, hi = (np.array(b) for b in scene.bounds)
    rng = np.random.default_rng(8)
    points = (lo + (rng.random((3000, 3)) - 0.25) * 1.5 * (hi - lo)).astype(np.float32)
    o = (lo + rng.random((2000, 3)) * (hi - lo)).astype(np.float32)
    d = rng.normal(size=(2000, 3)).astype(np.float32)
    return scene, points, o, d


def run(*args):
    env = dict(os.environ, NODEVICE_SELECT="1")
    return subprocess.run([LAMBERT, *args], capture_output=True, text=True, env=env)


def query(cli, tmp_path, what, input_args, device, *extra):
    out = tmp_path / f"{what}.bin"
    cli("query", what, "--obj", MESH, *input_args, "-o", str(out), "--device", device, "-q", *extra)
    return out


@pytest.mark.parametrize("device", QUERY_DEVICES)
def test_point_queries_write_what_python_returns(cli, tmp_path, bunny, device):
    scene, points, _, _ = bunny
    points.tofile(tmp_path / "points.bin")
    given = ["--points", str(tmp_path / "points.bin")]
    reach = 0.01
    # Python's answers first: the CLI's files must hold them.
    expected = scene.closest_points(points, max_distance=reach, device=device)
    closest = np.fromfile(query(cli, tmp_path, "closest", given, device, "--max-distance", str(reach)),
                          dtype=CLOSEST_DTYPE)
    assert len(closest) == len(points)
    prim = closest["prim"].astype(np.int64)
    np.testing.assert_array_equal(np.where(prim == 0xFFFFFFFF, -1, prim), expected["prim_id"])
    point = np.stack([closest["x"], closest["y"], closest["z"]], axis=1)
    np.testing.assert_array_equal(point, expected["point"])
    np.testing.assert_array_equal(closest["distance"], expected["distance"])
    assert (closest["reserved"] == 0).all()
    assert 0 < (expected["prim_id"] >= 0).sum() < len(points)
    distance = np.fromfile(query(cli, tmp_path, "distance", given, device), dtype="<f4")
    np.testing.assert_array_equal(distance, scene.distance(points, device=device))
    for method in ("winding", "parity"):
        sd = np.fromfile(query(cli, tmp_path, "signed-distance", given, device, "--method", method), dtype="<f4")
        np.testing.assert_array_equal(sd, scene.signed_distance(points, method=method, device=device))
    inside = np.fromfile(query(cli, tmp_path, "inside", given, device), dtype=np.uint8)
    np.testing.assert_array_equal(inside, scene.contains(points, device=device).astype(np.uint8))
    assert 0 < inside.sum() < len(points)


@pytest.mark.parametrize("device", QUERY_DEVICES)
def test_ray_queries_write_what_python_returns(cli, tmp_path, bunny, device):
    scene, _, o, d = bunny
    r = records(o, d, 0.0, np.inf)
    r.tofile(tmp_path / "rays.bin")
    given = ["--rays", str(tmp_path / "rays.bin")]
    # Python's answers first: the CLI's files must hold them.
    expected_counts = scene.count_intersections(o, d, device=device)
    expected = scene.list_intersections(o, d, device=device)
    counts = np.fromfile(query(cli, tmp_path, "count", given, device), dtype="<u4")
    np.testing.assert_array_equal(counts, expected_counts)
    listed = np.fromfile(query(cli, tmp_path, "list", given, device), dtype=LISTED_DTYPE)
    np.testing.assert_array_equal(listed["ray"], expected["ray_ids"])
    for mine, theirs in (("prim", "prim_id"), ("t", "t"), ("u", "u"), ("v", "v")):
        np.testing.assert_array_equal(listed[mine], expected[theirs])
    assert counts.sum() == len(listed) > 0


def test_the_report_says_what_was_done(tmp_path, bunny):
    _, points, _, _ = bunny
    points.tofile(tmp_path / "points.bin")
    done = run("query", "inside", "--obj", MESH, "--points", str(tmp_path / "points.bin"), "-o",
               str(tmp_path / "in.bin"), "--device", "cpu", "--json")
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["queries"] == report["records"] == len(points)
    assert 0 < report["found"] < len(points)
    assert "inside of 3000 points" in done.stderr


BAD = [
    (lambda p: p.write_bytes(b"\0" * 13), "13 bytes is not a whole number of points"),
    (lambda p: np.array([[0, 0, 0], [0, np.nan, 0]], dtype="<f4").tofile(p), r"point 1 \(byte offset 12\): y is NaN"),
    (lambda p: np.array([[0, 0, 1e30]], dtype="<f4").tofile(p), r"point 0 \(byte offset 0\): z is 1e30"),
]


@pytest.mark.parametrize("write, message", BAD)
def test_a_bad_point_file_is_an_error_naming_the_point_and_nothing_is_written(tmp_path, write, message):
    write(tmp_path / "points.bin")
    out = tmp_path / "out.bin"
    done = run("query", "distance", "--obj", MESH, "--points", str(tmp_path / "points.bin"), "-o", str(out))
    assert done.returncode != 0
    assert re.search(message, done.stderr), done.stderr
    assert "points.bin" in done.stderr
    assert not out.exists()


def test_bad_options_are_refused_before_any_work(tmp_path, bunny):
    _, points, o, d = bunny
    points.tofile(tmp_path / "points.bin")
    records(o, d).tofile(tmp_path / "rays.bin")
    p, r = str(tmp_path / "points.bin"), str(tmp_path / "rays.bin")
    out = str(tmp_path / "out.bin")
    cases = [
        (["distance", "--points", p, "--max-distance", "1"], "--max-distance does not apply"),
        (["closest", "--points", p, "--method", "parity"], "--method does not apply"),
        (["closest", "--points", p, "--max-distance=-1"], "not a finite number"),
        (["closest", "--points", p, "--max-distance", "nan"], "not a finite number"),
        (["count", "--points", p], "--points (it takes --rays)"),
        (["list"], "give --rays"),
        (["closest"], "give --points"),
        (["inside", "--rays", r], "--rays (it takes --points)"),
    ]
    for args, message in cases:
        done = run("query", args[0], "--obj", MESH, *args[1:], "-o", out)
        assert done.returncode != 0 and message in done.stderr, (args, done.stderr)
        assert not os.path.exists(out)
    # Never over an input.
    done = run("query", "distance", "--obj", MESH, "--points", p, "-o", p)
    assert done.returncode != 0 and "the output is one of the inputs" in done.stderr
    assert np.array_equal(np.fromfile(p, dtype="<f4").reshape(-1, 3), points)
    done = run("query", "distance", "--obj", MESH, "--points", p, "-o", MESH)
    assert done.returncode != 0 and "the output is one of the inputs" in done.stderr
