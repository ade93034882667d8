"""Every array layout numpy can hand over is read by its strides: the same
values in any order, stride or width give the C-order result, bit for bit."""

import os

import numpy as np
import pytest

import lambert
from conftest import MESHES, random_rays

DEVICES = ["cpu", "gpu"]


def layouts(a):
    """(name, array): the values of the (N, 3) array `a` in every layout a
    user can pass, as float32 and float64."""
    for dtype in (np.float32, np.float64):
        c = np.ascontiguousarray(a, dtype=dtype)
        name = np.dtype(dtype).name
        wide = np.zeros((len(c), 5), dtype=dtype)
        wide[:, 1:4] = c
        yield f"C {name}", c
        yield f"Fortran {name}", np.asfortranarray(c)
        # np.array([xs, ys, zs]).T, the common idiom.
        yield f"transposed {name}", np.array([c[:, 0], c[:, 1], c[:, 2]]).T
        yield f"rows reversed {name}", np.ascontiguousarray(c[::-1])[::-1]
        yield f"columns reversed {name}", np.ascontiguousarray(c[:, ::-1])[:, ::-1]
        yield f"every other row {name}", np.repeat(c, 2, axis=0)[::2]
        yield f"column slice {name}", wide[:, 1:4]
        yield f"Fortran column slice {name}", np.asfortranarray(wide)[:, 1:4]


def layouts1(a):
    """(name, array): the values of the (N,) array `a` in every 1-D layout."""
    for dtype in (np.float32, np.float64):
        c = np.ascontiguousarray(a, dtype=dtype)
        name = np.dtype(dtype).name
        yield f"C {name}", c
        yield f"reversed {name}", np.ascontiguousarray(c[::-1])[::-1]
        yield f"every other {name}", np.repeat(c, 2)[::2]
        yield f"column of a (N, 2) array {name}", np.stack([c, c], axis=1)[:, 1]


def test_the_layouts_are_what_they_say():
    a = np.arange(30.0).reshape(10, 3)
    for name, x in layouts(a):
        np.testing.assert_array_equal(x, a)
        assert x.flags.c_contiguous == name.startswith("C "), name
    for name, x in layouts1(a[:, 0]):
        np.testing.assert_array_equal(x, a[:, 0])
        assert x.flags.c_contiguous == name.startswith("C "), name


def assert_same(got, expected, what):
    for key in ("t", "prim_id", "u", "v", "normal"):
        np.testing.assert_array_equal(got[key], expected[key], err_msg=f"{what}: {key}")


@pytest.fixture(scope="module")
def dragon():
    scene = lambert.Scene.load(os.path.join(MESHES, "dragon_res4.obj"))
    # More rays than one chunk (4096), so that chunks past the first are read too.
    o, d = random_rays(scene, 9000, seed=28)
    return scene, o.astype(np.float32), d.astype(np.float32)


@pytest.mark.parametrize("device", DEVICES)
def test_every_layout_of_origins_and_directions_gives_the_c_order_hits(dragon, device):
    scene, o, d = dragon
    expected = scene.intersect(o, d, device=device)
    expected_any = scene.occluded(o, d, device=device)
    assert (expected["prim_id"] >= 0).sum() > len(o) // 10, "the rays must hit something"
    for name, lo in layouts(o):
        for dname, ld in [("C", d), (name, dict(layouts(d))[name])]:
            what = f"origins {name}, directions {dname}"
            assert_same(scene.intersect(lo, ld, device=device), expected, what)
            np.testing.assert_array_equal(scene.occluded(lo, ld, device=device), expected_any, err_msg=what)
    for name, ld in layouts(d):
        what = f"directions {name}"
        assert_same(scene.intersect(o, ld, device=device), expected, what)
        np.testing.assert_array_equal(scene.occluded(o, ld, device=device), expected_any, err_msg=what)


@pytest.mark.parametrize("device", DEVICES)
def test_every_layout_of_tmin_and_tmax_gives_the_c_order_hits(dragon, device):
    scene, o, d = dragon
    rng = np.random.default_rng(5)
    tmin = (rng.random(len(o)) * 0.5).astype(np.float32)
    tmax = (1.0 + rng.random(len(o)) * 2.0).astype(np.float32)
    expected = scene.intersect(o, d, tmin, tmax, device=device)
    expected_any = scene.occluded(o, d, tmin, tmax, device=device)
    # The bounds matter to these rays: without them the hits differ.
    assert not np.array_equal(expected["prim_id"], scene.intersect(o, d, device=device)["prim_id"])
    for (name, lo), (_, hi) in zip(layouts1(tmin), layouts1(tmax)):
        assert_same(scene.intersect(o, d, lo, hi, device=device), expected, f"tmin, tmax {name}")
        np.testing.assert_array_equal(scene.occluded(o, d, lo, hi, device=device), expected_any, err_msg=name)


@pytest.mark.parametrize("device", DEVICES)
def test_broadcast_origins_are_one_origin_for_every_ray(dragon, device):
    scene, o, d = dragon
    one = np.broadcast_to(o[:1], o.shape)
    assert one.strides[0] == 0
    assert_same(scene.intersect(one, d, device=device), scene.intersect(np.tile(o[:1], (len(o), 1)), d,
                                                                          device=device), "broadcast")


@pytest.mark.parametrize("device", DEVICES)
def test_every_layout_of_vertices_and_faces_is_the_same_mesh(dragon, device):
    from conftest import read_obj

    scene, o, d = dragon
    v, f = read_obj(os.path.join(MESHES, "dragon_res4.obj"))
    expected = lambert.Scene.from_arrays(v, f).intersect(o, d, device=device)
    assert (expected["prim_id"] >= 0).sum() > len(o) // 10
    for name, lv in layouts(v):
        if "float32" in name:
            continue  # vertices rounded to float32 are another mesh
        got = lambert.Scene.from_arrays(lv, f).intersect(o, d, device=device)
        assert_same(got, expected, f"vertices {name}")
    for dtype in (np.int32, np.uint16, np.int64, np.uint64):
        c = f.astype(dtype)
        wide = np.zeros((len(c), 4), dtype=dtype)
        wide[:, 1:] = c
        for name, lf in [("C", c), ("Fortran", np.asfortranarray(c)), ("transposed", np.array(c.T).T),
                         ("rows reversed", np.ascontiguousarray(c[::-1])[::-1]),
                         ("every other row", np.repeat(c, 2, axis=0)[::2]), ("column slice", wide[:, 1:])]:
            got = lambert.Scene.from_arrays(v, lf).intersect(o, d, device=device)
            assert_same(got, expected, f"faces {np.dtype(dtype).name} {name}")


def test_every_layout_of_records_gives_the_same_hits(dragon):
    from conftest import records

    scene, o, d = dragon
    r = records(o, d)
    expected = scene.intersect(r, device="cpu")
    for name, lr in [("reversed", np.ascontiguousarray(r[::-1])[::-1]), ("every other", np.repeat(r, 2)[::2])]:
        assert_same(scene.intersect(lr, device="cpu"), expected, f"records {name}")


def test_every_layout_of_an_image_writes_the_same_file(tmp_path):
    rng = np.random.default_rng(3)
    image = rng.random((6, 7, 3)).astype(np.float32)
    lambert.write_image(tmp_path / "c.pfm", image)
    expected = (tmp_path / "c.pfm").read_bytes()
    for k, layout in enumerate([np.asfortranarray(image), np.ascontiguousarray(image[::-1])[::-1],
                                image.astype(np.float64), np.repeat(image, 2, axis=1)[:, ::2],
                                np.ascontiguousarray(image.transpose(2, 0, 1)).transpose(1, 2, 0)]):
        lambert.write_image(tmp_path / f"{k}.pfm", layout)
        assert (tmp_path / f"{k}.pfm").read_bytes() == expected, k
