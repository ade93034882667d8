"""Closest points, distances, signed distances, winding numbers, inside
tests and crossings against brute-force float64 references (every point
against every triangle: tests/reference.py), on closed meshes and on
meshes with holes, on both devices (the GPU's results equal the CPU's bit
for bit), for every array layout, and every bad input a ValueError that
names it."""

import os
import threading

import numpy as np
import pytest

import lambert
import reference as ref
from conftest import MESHES, QUERY_DEVICES, read_obj
from test_layouts import layouts, layouts1

DEVICES = QUERY_DEVICES


def open_box():
    """The box with one face (two triangles) taken away: a hole."""
    v, f = ref.box_mesh()
    return v, f[2:]


def soup():
    """Random triangles, some long and thin, one of zero area, and two
    sharing an edge: no surface, every region of the closest-point test."""
    rng = np.random.default_rng(11)
    v = rng.normal(size=(60, 3))
    f = rng.integers(0, 60, size=(30, 3))
    v = np.concatenate([v, [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [0, -1, 0]]])
    f = np.concatenate([f, [[60, 61, 62], [60, 61, 63], [61, 60, 64]]])
    return v, f


MESH_FACTORIES = {
    "box": ref.box_mesh,
    "sphere": ref.sphere_mesh,
    "open box": open_box,
    "soup": soup,
    "bunny": lambda: read_obj(os.path.join(MESHES, "bunny_lowres.obj")),
    "dragon (holes)": lambda: read_obj(os.path.join(MESHES, "dragon_res4.obj")),
}
CLOSED = {"box", "sphere", "bunny"}


@pytest.fixture(scope="module", params=list(MESH_FACTORIES))
def mesh(request):
    v, f = MESH_FACTORIES[request.param]()
    lo, hi = v.min(axis=0), v.max(axis=0)
    rng = np.random.default_rng(7)
    # Points over 1.5 times the box, some on the surface and at vertices.
    centre, size = (lo + hi) / 2, hi - lo
    points = centre + (rng.random((400, 3)) - 0.5) * 1.5 * size
    on_surface = v[f[:20]].mean(axis=1)
    points = np.concatenate([points, on_surface, v[:10]])
    return request.param, v, f, lambert.Scene.from_arrays(v, f), points


def scale(v):
    return float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))


@pytest.mark.parametrize("device", DEVICES)
def test_closest_points_are_the_brute_force_ones(mesh, device):
    name, v, f, scene, points = mesh
    d_ref, prim_ref, point_ref, all_d = ref.closest_points(v, f, points)
    got = scene.closest_points(points, device=device)
    assert got["point"].dtype == np.float32 and got["point"].shape == (len(points), 3)
    assert got["prim_id"].dtype == np.int64 and got["distance"].dtype == np.float32
    assert got["u"].dtype == np.float32 and got["v"].dtype == np.float32
    tol = 4e-6 * scale(v)
    np.testing.assert_allclose(got["distance"], d_ref, rtol=1e-5, atol=tol, err_msg=name)
    # The triangle reported is one of the nearest: its own distance is the
    # least (ties at a shared edge or vertex may name either).
    prim = got["prim_id"]
    assert (prim >= 0).all()
    np.testing.assert_allclose(all_d[np.arange(len(points)), prim], d_ref, rtol=1e-5, atol=tol, err_msg=name)
    unique = np.sort(all_d, axis=1)[:, 1] - d_ref > 1e-5 * scale(v)
    assert unique.sum() > len(points) // 10
    np.testing.assert_array_equal(prim[unique], prim_ref[unique], err_msg=name)
    np.testing.assert_allclose(got["point"][unique], point_ref[unique], atol=10 * tol, err_msg=name)
    # u and v are the point's weights on its triangle, as intersect's are.
    tri = v[f[prim]]
    u, w = got["u"].astype(np.float64), got["v"].astype(np.float64)
    at = (1 - u - w)[:, None] * tri[:, 0] + u[:, None] * tri[:, 1] + w[:, None] * tri[:, 2]
    np.testing.assert_allclose(at, got["point"], atol=10 * tol, err_msg=name)
    assert ((u >= -1e-6) & (w >= -1e-6) & (u + w <= 1 + 1e-6)).all()


@pytest.mark.parametrize("device", DEVICES)
def test_max_distance_leaves_farther_points_without_a_triangle(mesh, device):
    name, v, f, scene, points = mesh
    d_ref = ref.closest_points(v, f, points)[0]
    reach = float(np.median(d_ref))
    got = scene.closest_points(points, max_distance=reach, device=device)
    clear = np.abs(d_ref - reach) > 1e-4 * scale(v)
    beyond = got["prim_id"] < 0
    np.testing.assert_array_equal(beyond[clear], (d_ref > reach)[clear], err_msg=name)
    assert np.isinf(got["distance"][beyond]).all()
    near = scene.closest_points(points, device=device)
    np.testing.assert_array_equal(got["distance"][~beyond], near["distance"][~beyond])
    np.testing.assert_array_equal(got["prim_id"][~beyond], near["prim_id"][~beyond])
    nothing = scene.closest_points(points, max_distance=0.0, device=device)
    assert (nothing["prim_id"][d_ref > 1e-3] == -1).all()


@pytest.mark.parametrize("device", DEVICES)
def test_distance_is_the_closest_points_distance(mesh, device):
    _, _, _, scene, points = mesh
    d = scene.distance(points, device=device)
    assert d.dtype == np.float32 and d.shape == (len(points),)
    np.testing.assert_array_equal(d, scene.closest_points(points, device=device)["distance"])


@pytest.mark.parametrize("device", DEVICES)
def test_winding_numbers_are_the_brute_force_ones(mesh, device):
    name, v, f, scene, points = mesh
    w_ref = ref.winding_numbers(v, f, points)
    w = scene.winding_number(points, device=device)
    assert w.dtype == np.float32
    # Away from the surface (the fast approximation's error grows near it).
    d_ref = ref.closest_points(v, f, points)[0]
    away = d_ref > 1e-2 * scale(v)
    np.testing.assert_allclose(w[away], w_ref[away], atol=1e-2, err_msg=name)


@pytest.mark.parametrize("device", DEVICES)
def test_inside_is_a_winding_number_of_a_half_or_more(mesh, device):
    name, v, f, scene, points = mesh
    w_ref = ref.winding_numbers(v, f, points)
    inside = scene.contains(points, device=device)
    assert inside.dtype == bool
    # Off the surface (on it, the exact sum itself is ambiguous) and off
    # the threshold, |w| = 0.5 (a soup's winding numbers go negative too).
    d_ref = ref.closest_points(v, f, points)[0]
    clear = (np.abs(np.abs(w_ref) - 0.5) > 0.05) & (d_ref > 1e-3 * scale(v))
    np.testing.assert_array_equal(inside[clear], (np.abs(w_ref) >= 0.5)[clear], err_msg=name)
    np.testing.assert_array_equal(inside, np.abs(scene.winding_number(points, device=device)) >= 0.5)
    if name in CLOSED:
        assert 0 < inside.sum() < len(points)


@pytest.mark.parametrize("device", DEVICES)
@pytest.mark.parametrize("method", ["winding", "parity"])
def test_signed_distance_is_the_distance_negative_inside(mesh, device, method):
    name, v, f, scene, points = mesh
    sd = scene.signed_distance(points, method=method, device=device)
    assert sd.dtype == np.float32
    d = scene.distance(points, device=device)
    np.testing.assert_array_equal(np.abs(sd), d, err_msg=name)
    if method == "winding":
        np.testing.assert_array_equal(np.signbit(sd), scene.contains(points, device=device), err_msg=name)
    if name in CLOSED:
        # On a closed mesh both methods agree with the exact winding number
        # wherever a point is clear of the surface.
        w_ref = ref.winding_numbers(v, f, points)
        clear = d > 1e-4
        np.testing.assert_array_equal((sd < 0)[clear], (w_ref >= 0.5)[clear], err_msg=f"{name} {method}")


def test_a_hole_gets_a_sensible_inside_by_winding_number():
    v, f = open_box()
    scene = lambert.Scene.from_arrays(v, f)
    # The box's centre is inside (winding 5/6) though a face is missing;
    # points outside, far from the hole and beside it, are outside.
    points = np.array([[0, 0, 0], [0, 0, 0.5], [5, 0, 0], [-3, 0, 0], [0, 0, -3]], dtype=np.float64)
    np.testing.assert_array_equal(scene.contains(points), [True, True, False, False, False])
    sd = scene.signed_distance(points)
    assert sd[0] == pytest.approx(-1.0) and sd[2] == pytest.approx(4.0)


def random_rays(v, n, seed):
    """From around the mesh's box (twice its size) towards points within
    it: most cross the mesh."""
    rng = np.random.default_rng(seed)
    lo, hi = v.min(axis=0), v.max(axis=0)
    o = (lo + hi) / 2 + (rng.random((n, 3)) - 0.5) * 2 * (hi - lo)
    target = (lo + hi) / 2 + (rng.random((n, 3)) - 0.5) * 0.8 * (hi - lo)
    return o, target - o


@pytest.mark.parametrize("device", DEVICES)
def test_crossings_are_the_brute_force_ones(mesh, device):
    name, v, f, scene, _ = mesh
    o, d = random_rays(v, 300, seed=3)
    expected = ref.crossings(v, f, o, d)
    counts = scene.count_intersections(o, d, device=device)
    assert counts.dtype == np.int32 and counts.shape == (len(o),)
    np.testing.assert_array_equal(counts, [len(e) for e in expected], err_msg=name)
    assert counts.sum() > len(o) // 2
    listed = scene.list_intersections(o, d, device=device)
    splits = listed["ray_splits"]
    assert splits.dtype == np.int64 and splits.shape == (len(o) + 1,) and splits[0] == 0
    np.testing.assert_array_equal(np.diff(splits), counts)
    for key, dtype in [("ray_ids", np.int64), ("t", np.float32), ("prim_id", np.int64), ("u", np.float32),
                       ("v", np.float32)]:
        assert listed[key].dtype == dtype and listed[key].shape == (splits[-1],), key
    for i, hits in enumerate(expected):
        rows = slice(splits[i], splits[i + 1])
        assert (listed["ray_ids"][rows] == i).all()
        t = listed["t"][rows]
        assert (np.diff(t) >= 0).all(), f"ray {i}: not sorted by t"
        assert sorted(listed["prim_id"][rows]) == sorted(h[1] for h in hits), f"{name} ray {i}"
        np.testing.assert_allclose(t, [h[0] for h in hits], rtol=1e-5, atol=1e-6)
        order = np.argsort([h[1] for h in hits])
        mine = np.argsort(listed["prim_id"][rows])
        np.testing.assert_allclose(listed["u"][rows][mine], np.array([h[2] for h in hits])[order], atol=1e-4)
        np.testing.assert_allclose(listed["v"][rows][mine], np.array([h[3] for h in hits])[order], atol=1e-4)


@pytest.mark.parametrize("device", DEVICES)
def test_crossings_keep_to_tmin_and_tmax(mesh, device):
    name, v, f, scene, _ = mesh
    o, d = random_rays(v, 200, seed=4)
    tmin, tmax = 0.3, 1.7
    expected = ref.crossings(v, f, o, d, tmin, tmax)
    counts = scene.count_intersections(o, d, tmin, tmax, device=device)
    np.testing.assert_array_equal(counts, [len(e) for e in expected], err_msg=name)
    listed = scene.list_intersections(o, d, tmin, tmax, device=device)
    assert ((listed["t"] > tmin) & (listed["t"] < tmax)).all()
    # Records carry their own bounds, as intersect's do.
    from conftest import records

    np.testing.assert_array_equal(scene.count_intersections(records(o, d, tmin, tmax), device=device), counts)


@pytest.mark.parametrize("device", DEVICES)
def test_a_ray_through_a_shared_edge_or_vertex_crosses_once(device):
    v, f = ref.box_mesh()
    scene = lambert.Scene.from_arrays(v, f)
    # Through the middle of each face: its diagonal is the edge two triangles share.
    o = np.array([[0, 0, -5], [0, 0, -5], [-5, 0, 0], [-5, -5, -5]], dtype=np.float64)
    d = np.array([[0, 0, 1], [1e-9, 1e-9, 1], [1, 0, 0], [1, 1, 1]], dtype=np.float64)
    counts = scene.count_intersections(o, d, device=device)
    np.testing.assert_array_equal(counts, [2, 2, 2, 2])
    listed = scene.list_intersections(o, d, device=device)
    np.testing.assert_allclose(listed["t"], np.tile([4.0, 6.0], 4), rtol=1e-6)


def test_the_gpu_gives_the_cpus_results_bit_for_bit(mesh):
    name, v, f, scene, points = mesh
    cpu = scene.closest_points(points, device="cpu")
    gpu = scene.closest_points(points, device="gpu")
    for key in cpu:
        np.testing.assert_array_equal(gpu[key], cpu[key], err_msg=f"{name}: closest {key}")
    for method in ("winding", "parity"):
        np.testing.assert_array_equal(scene.signed_distance(points, method=method, device="gpu"),
                                      scene.signed_distance(points, method=method, device="cpu"), err_msg=method)
    np.testing.assert_array_equal(scene.winding_number(points, device="gpu"),
                                  scene.winding_number(points, device="cpu"))
    o, d = random_rays(v, 300, seed=5)
    np.testing.assert_array_equal(scene.count_intersections(o, d, device="gpu"),
                                  scene.count_intersections(o, d, device="cpu"))
    cpu, gpu = scene.list_intersections(o, d, device="cpu"), scene.list_intersections(o, d, device="gpu")
    for key in cpu:
        np.testing.assert_array_equal(gpu[key], cpu[key], err_msg=f"{name}: list {key}")


@pytest.mark.parametrize("device", DEVICES)
def test_every_layout_of_points_gives_the_c_order_results(device):
    v, f = read_obj(os.path.join(MESHES, "bunny_lowres.obj"))
    scene = lambert.Scene.from_arrays(v, f)
    rng = np.random.default_rng(9)
    points = (v.min(axis=0) + rng.random((5000, 3)) * (v.max(axis=0) - v.min(axis=0))).astype(np.float32)
    closest = scene.closest_points(points, device=device)
    sd = scene.signed_distance(points, device=device)
    inside = scene.contains(points, device=device)
    for name, p in layouts(points):
        got = scene.closest_points(p, device=device)
        for key in closest:
            np.testing.assert_array_equal(got[key], closest[key], err_msg=f"{name}: {key}")
        np.testing.assert_array_equal(scene.signed_distance(p, device=device), sd, err_msg=name)
        np.testing.assert_array_equal(scene.contains(p, device=device), inside, err_msg=name)
    one = np.broadcast_to(points[:1], points.shape)
    np.testing.assert_array_equal(scene.distance(one, device=device),
                                  np.full(len(points), closest["distance"][0]))


@pytest.mark.parametrize("device", DEVICES)
def test_every_layout_of_rays_gives_the_c_order_crossings(device):
    v, f = read_obj(os.path.join(MESHES, "bunny_lowres.obj"))
    scene = lambert.Scene.from_arrays(v, f)
    o, d = random_rays(v, 3000, seed=6)
    o, d = o.astype(np.float32), d.astype(np.float32)
    counts = scene.count_intersections(o, d, device=device)
    listed = scene.list_intersections(o, d, device=device)
    for (name, lo), (_, ld) in zip(layouts(o), layouts(d)):
        np.testing.assert_array_equal(scene.count_intersections(lo, ld, device=device), counts, err_msg=name)
        got = scene.list_intersections(lo, ld, device=device)
        for key in listed:
            np.testing.assert_array_equal(got[key], listed[key], err_msg=f"{name}: {key}")
    tmax = np.full(len(o), 0.5, dtype=np.float32)
    expected = scene.count_intersections(o, d, 0.0, 0.5, device=device)
    for name, t in layouts1(tmax):
        np.testing.assert_array_equal(scene.count_intersections(o, d, 0.0, t, device=device), expected, err_msg=name)


def test_no_points_and_no_rays_give_empty_results():
    v, f = ref.box_mesh()
    scene = lambert.Scene.from_arrays(v, f)
    none = np.zeros((0, 3))
    assert scene.closest_points(none)["point"].shape == (0, 3)
    assert scene.signed_distance(none).shape == (0,)
    assert scene.contains(none).shape == (0,)
    assert scene.count_intersections(none, none).shape == (0,)
    assert scene.list_intersections(none, none)["ray_splits"].tolist() == [0]


BAD_POINTS = [
    ([[0, 0, 0], [np.nan, 0, 0]], "points row 1"),
    ([[0, 0, 0], [0, 0, 0], [0, np.inf, 0]], "points row 2"),
    ([[1e300, 0, 0]], "points row 0"),
    ([[0, 0]], r"shape \(1, 2\); it must be \(N, 3\)"),
    ([0, 0, 0], r"shape \(3,\); it must be \(N, 3\)"),
    (np.zeros((2, 2, 3)), r"it must be \(N, 3\)"),
    (np.array([["a", "b", "c"]]), "real-valued"),
    (np.zeros((1, 3), dtype=complex), "real-valued"),
]


@pytest.mark.parametrize("points, message", BAD_POINTS)
@pytest.mark.parametrize("query", ["closest_points", "distance", "signed_distance", "contains", "winding_number"])
def test_bad_points_are_a_value_error_naming_them(points, message, query):
    v, f = ref.box_mesh()
    scene = lambert.Scene.from_arrays(v, f)
    with pytest.raises(ValueError, match=message):
        getattr(scene, query)(np.asarray(points), device="cpu")


def test_bad_options_are_value_errors_naming_them():
    v, f = ref.box_mesh()
    scene = lambert.Scene.from_arrays(v, f)
    p = np.zeros((2, 3))
    with pytest.raises(ValueError, match="method='inside'"):
        scene.signed_distance(p, method="inside")
    for bad in (-1.0, np.nan):
        with pytest.raises(ValueError, match="max_distance"):
            scene.closest_points(p, max_distance=bad)
    with pytest.raises(TypeError, match="max_distance"):
        scene.closest_points(p, max_distance="far")
    for query in ("closest_points", "distance", "signed_distance", "contains"):
        with pytest.raises(ValueError, match='device="tpu"'):
            getattr(scene, query)(p, device="tpu")
    with pytest.raises(ValueError, match="2 origins but 3 directions"):
        scene.count_intersections(p, np.ones((3, 3)))
    with pytest.raises(ValueError, match="ray 1: dy is NaN"):
        scene.count_intersections(p, [[1, 0, 0], [0, np.nan, 0]])
    with pytest.raises(ValueError, match="ray 0: the direction"):
        scene.list_intersections(p, np.zeros((2, 3)))
    with pytest.raises(ValueError, match="tmin"):
        scene.list_intersections(p, np.ones((2, 3)), tmin=[0.0, 1.0, 2.0])


def test_a_scene_without_triangles_is_a_value_error(tmp_path):
    (tmp_path / "ball.toml").write_text("[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 8\nheight = 8\n"
                                        "[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n")
    scene = lambert.Scene.load(tmp_path / "ball.toml")
    assert scene.triangle_count == 0 and scene.sphere_count == 1
    p = np.zeros((1, 3))
    for query in ("closest_points", "distance", "signed_distance", "contains", "winding_number"):
        with pytest.raises(ValueError, match="no triangles"):
            getattr(scene, query)(p, device="cpu")
    with pytest.raises(ValueError, match="no triangles"):
        scene.count_intersections(p, np.ones((1, 3)), device="cpu")
    # Triangles and spheres: the queries are over triangles alone.
    scene = lambert.Scene.load(os.path.join(os.path.dirname(MESHES), "spheres.toml"))
    assert scene.triangle_count and scene.sphere_count
    for query in ("closest_points", "signed_distance", "contains"):
        with pytest.raises(ValueError, match="sphere"):
            getattr(scene, query)(p, device="cpu")


def test_queries_run_in_threads_at_once_with_the_gil_released():
    v, f = read_obj(os.path.join(MESHES, "dragon_res4.obj"))
    scene = lambert.Scene.from_arrays(v, f)
    rng = np.random.default_rng(2)
    points = v.min(axis=0) + rng.random((20000, 3)) * (v.max(axis=0) - v.min(axis=0))
    expected = scene.signed_distance(points, device="cpu")
    results, ticks = [None] * 3, []
    stop = threading.Event()

    def tick():
        # Python code runs while the queries do: the GIL is free.
        while not stop.is_set():
            ticks.append(1)
            stop.wait(0.001)

    def query(i):
        results[i] = scene.signed_distance(points, device="cpu")

    ticker = threading.Thread(target=tick)
    ticker.start()
    workers = [threading.Thread(target=query, args=(i,)) for i in range(3)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    stop.set()
    ticker.join()
    for r in results:
        np.testing.assert_array_equal(r, expected)
    assert len(ticks) > 3
