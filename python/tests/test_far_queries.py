"""Point and crossing queries on meshes far from the origin (issue 44,
items 1 and 2; docs/python.md, "Far from the origin"): float64 points and
origins keep their precision at 1e6 and 1e8, on both devices, against
trimesh's own float64 answers; float32 ones too coarse for the scene get a
warning naming the first."""

import warnings

import numpy as np
import pytest

import trimesh  # noqa: E402  (scripts/test installs it)

import lambert  # noqa: E402
import lambert.trimesh  # noqa: E402

DEVICES = ["cpu", "gpu"]
# The place (f32 spaces values 0.5 apart there) and one where it
# spaces them 8 apart.
PLACES = {"1e6": [5e6, 4e6, 100.0], "1e8": [1e8, 0.4e8, -0.9e8]}


def offsets():
    """The issue's points about the centre, then points on shells inside
    and outside the unit sphere (none within 5e-3 of its surface)."""
    rng = np.random.default_rng(44)
    away = rng.normal(size=(60, 3))
    away /= np.linalg.norm(away, axis=1)[:, None]
    shells = away * np.resize([0.5, 0.95, 1.1, 1.7], 60)[:, None]
    return np.vstack([[[0.3, 0.1, 0.2], [1.2, 0.0, 0.0], [0.99, 0.0, 0.0]], shells])


def sphere_at(place):
    """A unit icosphere about `place` (its faces all more than 0.99 from
    the centre), and points about it in float64."""
    mesh = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    centre = np.array(place, dtype=np.float64)
    mesh.apply_translation(centre)
    return mesh, centre + offsets()


def inside():
    return np.linalg.norm(offsets(), axis=1) < 1.0


@pytest.mark.parametrize("device", DEVICES)
@pytest.mark.parametrize("place", PLACES)
def test_float64_points_answer_as_float64_does(device, place):
    mesh, points = sphere_at(PLACES[place])
    scene = lambert.Scene.from_arrays(mesh.vertices, mesh.faces)
    _, truth, _ = trimesh.proximity.closest_point(mesh, points)
    # The points: 0.622, 0.2 and about 0.01 from the surface.
    np.testing.assert_allclose(truth[:2], [0.6224, 0.2], atol=1e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # float64 points need no warning
        distance = scene.distance(points, device=device)
        signed = scene.signed_distance(points, device=device)
        parity = scene.signed_distance(points, method="parity", device=device)
        winding = scene.winding_number(points, device=device)
        contains = scene.contains(points, device=device)
        closest = scene.closest_points(points, device=device)
    np.testing.assert_allclose(distance, truth, atol=1e-5)
    sign = np.where(inside(), -1.0, 1.0)
    np.testing.assert_allclose(signed, sign * truth, atol=1e-5)
    np.testing.assert_allclose(parity, sign * truth, atol=1e-5)
    np.testing.assert_allclose(winding, inside().astype(np.float64), atol=1e-2)
    assert (contains == inside()).all()
    # The triangle and (u, v) found, evaluated in float64, are that near.
    corners = mesh.vertices[mesh.faces[closest["prim_id"]]]
    u, v = closest["u"].astype(np.float64)[:, None], closest["v"].astype(np.float64)[:, None]
    found = (1 - u - v) * corners[:, 0] + u * corners[:, 1] + v * corners[:, 2]
    np.testing.assert_allclose(np.linalg.norm(found - points, axis=1), truth, atol=1e-5)


@pytest.mark.parametrize("device", DEVICES)
@pytest.mark.parametrize("place", PLACES)
def test_trimesh_drop_in_is_within_1e7_far_from_the_origin(device, place):
    mesh, points = sphere_at(PLACES[place])
    closest, distance, _ = lambert.trimesh.ProximityQuery(mesh, device=device).on_surface(points)
    expected, expected_distance, _ = trimesh.proximity.closest_point(mesh, points)
    # As documented: within about 1e-7 of trimesh's on a mesh of size 1
    # (the same points as at the origin, up to 2.9e-7 apart there), the
    # distance always; the point too, but where another is as near (the
    # issue's third point, on an axis of the sphere's symmetry).
    np.testing.assert_allclose(distance, expected_distance, atol=1e-7)
    apart = np.linalg.norm(closest - expected, axis=1)
    assert (apart < 3e-7).sum() >= len(points) - 2, apart
    signed = lambert.trimesh.ProximityQuery(mesh, device=device).signed_distance(points)
    np.testing.assert_allclose(signed, np.where(inside(), 1.0, -1.0) * expected_distance, atol=2e-7)


def crossings(mesh, origins, directions):
    """trimesh's own float64 crossings, by ray, sorted by t."""
    from trimesh.ray.ray_triangle import RayMeshIntersector as Reference

    locations, index_ray, _ = Reference(mesh).intersects_location(origins, directions)
    t = np.einsum("ij,ij->i", locations - origins[index_ray], directions[index_ray])
    return [np.sort(t[index_ray == i]) for i in range(len(origins))]


@pytest.mark.parametrize("device", DEVICES)
@pytest.mark.parametrize("place", PLACES)
def test_float64_rays_count_and_list_their_crossings(device, place):
    mesh, _ = sphere_at(PLACES[place])
    centre = np.array(PLACES[place])
    scene = lambert.Scene.from_arrays(mesh.vertices, mesh.faces)
    # The ray (a grazing double hit at t = 5 from float32), and
    # rays from 5 units out through points within 0.6 of the centre.
    rng = np.random.default_rng(7)
    start = rng.normal(size=(40, 3))
    o = np.vstack([centre + [0.95, 0.0, -5.0], centre + 5 * start / np.linalg.norm(start, axis=1)[:, None]])
    target = np.vstack([centre + [0.95, 0.0, 0.0], centre + 0.6 * (rng.random((40, 3)) - 0.5)])
    d = (target - o) / np.linalg.norm(target - o, axis=1)[:, None]
    truth = crossings(mesh, o, d)
    assert len(truth[0]) == 2 and abs(truth[0][0] - 4.69) < 0.01
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # float64 origins need no warning
        counts = scene.count_intersections(o, d, device=device)
        listed = scene.list_intersections(o, d, device=device)
    assert counts.tolist() == [len(t) for t in truth]
    splits = listed["ray_splits"]
    for i, t in enumerate(truth):
        np.testing.assert_allclose(listed["t"][splits[i]:splits[i + 1]], t, atol=1e-5, err_msg=f"ray {i}")


@pytest.mark.parametrize("device", DEVICES)
def test_far_float32_points_and_rays_warn(device):
    mesh, points = sphere_at(PLACES["1e6"])
    scene = lambert.Scene.from_arrays(mesh.vertices, mesh.faces)
    p32 = points.astype(np.float32)
    n = len(p32) - 1
    for query in (scene.distance, scene.signed_distance, scene.winding_number, scene.contains,
                  scene.closest_points):
        with pytest.warns(RuntimeWarning, match=rf"point 0 \(and {n} more like it\): its position .* is given in f32"):
            query(p32, device=device)
    o = np.array([PLACES["1e6"]], dtype=np.float32) + np.float32([0.95, 0.0, -5.0])
    d = np.float32([[0.0, 0.0, 1.0]])
    for query in (scene.count_intersections, scene.list_intersections):
        with pytest.warns(RuntimeWarning, match=r"ray 0: its origin .* is given in f32"):
            query(o, d, device=device)
    # Near the origin, float32 holds them: no warning.
    near = lambert.Scene.from_arrays(mesh.vertices - PLACES["1e6"], mesh.faces)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        near.distance((points - PLACES["1e6"]).astype(np.float32), device=device)
        near.count_intersections(o - np.float32(PLACES["1e6"]), d, device=device)


def test_gpu_lists_more_crossings_than_one_binding_holds():
    """Item 6: 300,000 rays × 30 crossings (180 MB of listed crossings,
    beyond lavapipe's 128 MiB storage binding) are listed on the GPU in
    batches that fit, as the CPU path lists them."""
    vertices, faces = [], []
    for z in range(30):
        b = len(vertices)
        vertices += [[-1, -1, z], [1, -1, z], [1, 1, z], [-1, 1, z]]
        faces += [[b, b + 1, b + 2], [b, b + 2, b + 3]]
    scene = lambert.Scene.from_arrays(np.array(vertices, dtype=np.float64), np.array(faces))
    n = 300_000
    rng = np.random.default_rng(6)
    o = np.column_stack([rng.uniform(-0.9, 0.9, (n, 2)), np.full(n, -1.0)]).astype(np.float32)
    d = np.tile(np.float32([0, 0, 1]), (n, 1))
    gpu = scene.list_intersections(o, d, device="gpu")
    cpu = scene.list_intersections(o, d, device="cpu")
    assert len(cpu["t"]) == 30 * n
    for key in cpu:
        assert (gpu[key] == cpu[key]).all(), key
