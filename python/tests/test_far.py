"""Meshes far from the origin (docs/python.md, "Far from the origin"):
float64 rays keep their precision there, on both devices; where float32
cannot, a warning names the ray."""

import warnings

import numpy as np
import pytest

import trimesh  # noqa: E402  (scripts/test installs it)
from trimesh.ray.ray_triangle import RayMeshIntersector as Reference  # noqa: E402

import lambert  # noqa: E402
import lambert.trimesh  # noqa: E402

DEVICES = ["cpu", "gpu"]
# Where f32 spaces values 0.06 and 8 apart; odd components so that no axis
# is special.
PLACES = {"1e6": [1e6, -0.7e6, 0.3e6], "1e8": [1e8, 0.4e8, -0.9e8]}


def sphere_at(place):
    mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
    mesh.apply_translation(np.array(place, dtype=np.float64))
    return mesh


def sensor_rays(centre, n, seed, distance=6.0):
    """float64 rays from `distance` of the centre (5 units from a sphere of
    radius 1) towards points within 0.6 of it: all hit, none grazes."""
    rng = np.random.default_rng(seed)
    away = rng.normal(size=(n, 3))
    o = centre + distance * away / np.linalg.norm(away, axis=1)[:, None]
    target = centre + 0.6 * (rng.random((n, 3)) - 0.5)
    return o, target - o


def by_ray(locations, index_ray, origins):
    """Each ray's hit locations, nearest its origin first."""
    out = {}
    for ray in np.unique(index_ray):
        here = locations[index_ray == ray]
        order = np.argsort(np.linalg.norm(here - origins[ray], axis=1))
        out[int(ray)] = here[order]
    return out


@pytest.mark.parametrize("device", DEVICES)
@pytest.mark.parametrize("place", PLACES)
@pytest.mark.parametrize("multiple_hits", [False, True])
def test_drop_in_locations_match_trimesh_far_from_the_origin(device, place, multiple_hits):
    mesh = sphere_at(PLACES[place])
    o, d = sensor_rays(mesh.centroid, 300, seed=len(place) + multiple_hits)
    ours = lambert.trimesh.RayMeshIntersector(mesh, device=device)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # float64 rays need no warning
        loc, ray, _ = ours.intersects_location(o, d, multiple_hits=multiple_hits)
    loc_ref, ray_ref, _ = Reference(mesh).intersects_location(o, d, multiple_hits=multiple_hits)
    hits, expected = by_ray(loc, ray, o), by_ray(loc_ref, ray_ref, o)
    assert len(expected) == len(o)
    assert hits.keys() == expected.keys()
    tolerance = 1e-5 * mesh.scale
    for r, where in expected.items():
        assert hits[r].shape == where.shape, f"ray {r}: {hits[r]} vs trimesh's {where}"
        error = np.abs(hits[r] - where).max()
        assert error < tolerance, f"ray {r}: {error} off trimesh's hit (allowed {tolerance})"


@pytest.mark.parametrize("device", DEVICES)
@pytest.mark.parametrize("origins", ["C", "F"])
def test_float64_rays_at_1e8_hit_as_at_the_origin(device, origins):
    mesh = sphere_at([0.0, 0.0, 0.0])
    far = np.array(PLACES["1e8"])
    o, d = sensor_rays(np.zeros(3), 2000, seed=7)
    at_origin = lambert.Scene.from_arrays(mesh.vertices, mesh.faces).intersect(o, d, device=device)
    scene = lambert.Scene.from_arrays(mesh.vertices + far, mesh.faces)
    o_far = o + far
    if origins == "F":
        o_far = np.asfortranarray(o_far)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hits = scene.intersect(o_far, d, device=device)
    assert (at_origin["prim_id"] >= 0).all()
    # Rays through a shared edge may name either triangle.
    assert np.mean(hits["prim_id"] == at_origin["prim_id"]) > 0.995
    assert (hits["prim_id"] >= 0).all()
    # t is along the ray as given, as precise as at the origin.
    np.testing.assert_allclose(hits["t"], at_origin["t"], rtol=1e-5)
    np.testing.assert_array_equal(scene.occluded(o_far, d, device=device), True)


@pytest.mark.parametrize("device", DEVICES)
def test_a_ray_from_1e19_away_hits(device):
    mesh = sphere_at(PLACES["1e6"])
    centre = mesh.centroid
    scene = lambert.Scene.from_arrays(mesh.vertices, mesh.faces)
    # From 1e19 away along +x, +y and a slant, back at the sphere.
    away = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.6, -0.48, 0.64]])
    o = centre + 1e19 * away
    d = -away
    hits = scene.intersect(o, d, device=device)
    assert (hits["prim_id"] >= 0).all()
    # t is along the ray as given, rounded once to float32.
    np.testing.assert_allclose(hits["t"], 1e19 - 1.0, rtol=1e-7)
    assert scene.occluded(o, d, device=device).all()
    # The drop-in's locations lie on the sphere to f64's precision at 1e19
    # (2048 apart there): float32's t would put them 1e12 off.
    loc, ray, _ = lambert.trimesh.RayMeshIntersector(mesh, device=device).intersects_location(
        o, d, multiple_hits=False
    )
    assert sorted(ray.tolist()) == [0, 1, 2]
    assert (np.linalg.norm(loc - centre, axis=1) < 1e4).all(), loc - centre


@pytest.mark.parametrize("device", DEVICES)
@pytest.mark.parametrize("layout", ["arrays", "records"])
def test_float32_origins_too_coarse_for_the_scene_warn(device, layout):
    mesh = sphere_at(PLACES["1e8"])
    scene = lambert.Scene.from_arrays(mesh.vertices, mesh.faces)
    o, d = sensor_rays(mesh.centroid, 50, seed=3)
    o32, d32 = o.astype(np.float32), d.astype(np.float32)
    # Ray 0 starts near the origin, where float32 holds it finely enough
    # for its distance: the first coarse one is ray 1.
    o32[0] = [0.0, 0.0, 0.0]
    d32[0] = (mesh.centroid / np.linalg.norm(mesh.centroid)).astype(np.float32)
    if layout == "records":
        from conftest import records

        query = (records(o32, d32),)
    else:
        query = (o32, d32)
    with pytest.warns(RuntimeWarning, match=r"ray 1 \(and 48 more like it\): its origin .* is given in f32"):
        scene.intersect(*query, device=device)
    with pytest.warns(RuntimeWarning, match=r"ray 1 \(and 48 more like it\)"):
        scene.occluded(*query, device=device)
    # The same rays in float64 need no warning.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene.intersect(o, d, device=device)


def test_a_hit_beyond_float32_t_warns():
    mesh = sphere_at([0.0, 0.0, 0.0])
    scene = lambert.Scene.from_arrays(mesh.vertices, mesh.faces)
    # A short direction: the sphere lies at t = 1e37 / 1e-3, beyond float32.
    o = np.array([[1e37, 0.0, 0.0], [5.0, 0.0, 0.0]])
    d = np.array([[-1e-3, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    with pytest.warns(RuntimeWarning, match=r"ray 0: the scene lies up to t = .* beyond f32's largest t"):
        hits = scene.intersect(o, d, device="cpu")
    assert hits["prim_id"][1] >= 0
