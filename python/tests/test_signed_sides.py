"""Signed distances and inside tests on closed meshes take their sign from
each point's closest point (the side of the surface it lies, issue 48
item 4) and must give the winding number's answer (|w| >= 0.5), point for
point, with the distances bit for bit those of `distance`: closed meshes
(a box, a sphere, two nested spheres, two that cross, the bundled
models) and an open one, at random points and at points on and very near
the surface, in float32 and float64."""

import os

import numpy as np
import pytest

import lambert
import reference as ref
from conftest import MESHES, read_obj


def nested_spheres():
    """A sphere inside another, both facing out: 2 inside the inner one."""
    v, f = ref.sphere_mesh(3)
    return np.concatenate([v, 0.4 * v + 0.1]), np.concatenate([f, f + len(v)])


def crossing_spheres():
    """Two spheres that cross each other."""
    v, f = ref.sphere_mesh(3)
    return np.concatenate([v, v + [0.8, 0.1, 0.0]]), np.concatenate([f, f + len(v)])


def open_box():
    v, f = ref.box_mesh()
    return v, f[2:]


MESHES_CLOSED = {
    "box": ref.box_mesh,
    "sphere": lambda: ref.sphere_mesh(3),
    "nested spheres": nested_spheres,
    "crossing spheres": crossing_spheres,
    "dragon_res4": lambda: read_obj(os.path.join(MESHES, "dragon_res4.obj")),
    "cube": lambda: read_obj(os.path.join(MESHES, "cube.obj")),
    "open box": open_box,
}


def points(v, f, n, seed):
    """n random points over 1.5x the box, and n on and near the surface:
    on triangles and vertices, and off them along the normal by 1e-7 to
    1e-2 of the box's size, either way."""
    rng = np.random.default_rng(seed)
    v = np.asarray(v, dtype=np.float64)
    lo, hi = v.min(axis=0), v.max(axis=0)
    size = float(np.max(hi - lo))
    random = (lo + hi) / 2 + (rng.random((n, 3)) - 0.5) * 1.5 * (hi - lo)
    t = rng.integers(0, len(f), n)
    a, b, c = (v[f[t, k]] for k in range(3))
    uv = rng.random((n, 2))
    flip = uv.sum(axis=1) > 1
    uv[flip] = 1 - uv[flip]
    on = a + (b - a) * uv[:, :1] + (c - a) * uv[:, 1:]
    on[::5] = a[::5]
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    offsets = np.array([0.0, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2])[np.arange(n) % 7] * size
    near = on + normal * (offsets * rng.choice([-1.0, 1.0], n))[:, None]
    return np.concatenate([random, near])


@pytest.mark.parametrize("name", MESHES_CLOSED)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_signed_distance_signs_are_the_winding_numbers(name, dtype):
    v, f = MESHES_CLOSED[name]()
    scene = lambert.Scene.from_arrays(np.asarray(v, dtype=np.float32), np.asarray(f, dtype=np.uint32))
    p = points(v, f, 3000, 5).astype(dtype)
    w = scene.winding_number(p, device="cpu")
    by_winding = np.abs(w) >= 0.5
    signed = scene.signed_distance(p, device="cpu")
    distance = scene.distance(p, device="cpu")
    np.testing.assert_array_equal(np.abs(signed).view(np.uint32), distance.view(np.uint32))
    wrong = np.flatnonzero(np.signbit(signed) != by_winding)
    assert wrong.size == 0, f"{name}: {wrong.size} signs differ, first at {p[wrong[0]]} (w = {w[wrong[0]]})"
    np.testing.assert_array_equal(scene.contains(p, device="cpu"), by_winding)


def test_the_sides_decide_where_the_winding_number_is_far_from_a_half():
    """Between two nested spheres the closest surface is the inner one's
    and the point is in front of it, yet inside (w = 1): the sides must
    say so (each piece's own winding number in front, not "behind =
    inside")."""
    v, f = nested_spheres()
    scene = lambert.Scene.from_arrays(np.asarray(v, dtype=np.float32), np.asarray(f, dtype=np.uint32))
    centre = np.array([[0.1, 0.1, 0.1], [0.1, 0.1, 0.6], [2.0, 0.0, 0.0]], dtype=np.float32)
    np.testing.assert_allclose(scene.winding_number(centre, device="cpu"), [2, 1, 0], atol=0.01)
    assert list(np.signbit(scene.signed_distance(centre, device="cpu"))) == [True, True, False]
