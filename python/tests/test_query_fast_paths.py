"""The CPU path's per-chunk loops for the usual arrays (packed float32 or
float64 rows, scalar tmin and tmax) against its general loop (any other
layout): the same hits, bit for bit, and the same precision warnings,
which are now noted chunk by chunk as the rays are read."""

import warnings

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

import lambert  # noqa: E402

# More rays than one of the kernel's chunks (256), so that several chunks
# (and the short last one) are read.
N = 2500
COLUMNS = ("t", "prim_id", "u", "v", "normal")


def sphere_scene(place):
    mesh = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    mesh.apply_translation(np.array(place, dtype=np.float64))
    return lambert.Scene.from_arrays(mesh.vertices, mesh.faces), mesh.centroid


def rays_near_and_far(centre, seed):
    """float64 rays from 1.5 to 60 units of the sphere (the far ones moved
    into the scene's frame along the ray), most towards it."""
    rng = np.random.default_rng(seed)
    away = rng.normal(size=(N, 3))
    distance = rng.uniform(1.5, 60.0, size=(N, 1))
    o = centre + distance * away / np.linalg.norm(away, axis=1)[:, None]
    d = centre + 1.5 * (rng.random((N, 3)) - 0.5) - o
    return o, d


def general(a):
    """The same values in a layout that the per-chunk loops do not take."""
    return np.asfortranarray(a)


def same(a, b):
    for column in COLUMNS:
        assert a[column].dtype == b[column].dtype, column
        assert np.array_equal(a[column], b[column], equal_nan=True), column


@pytest.mark.parametrize("place", [[0.0, 0.0, 0.0], [1e6, -0.7e6, 0.3e6]])
@pytest.mark.parametrize("origins", [np.float32, np.float64])
@pytest.mark.parametrize("directions", [np.float32, np.float64])
@pytest.mark.parametrize("bounds", ["none", "scalar", "per ray"])
def test_packed_rows_hit_as_the_general_layout(place, origins, directions, bounds):
    scene, centre = sphere_scene(place)
    o, d = rays_near_and_far(centre, seed=11)
    o, d = o.astype(origins), d.astype(directions)
    kwargs = {}
    if bounds == "scalar":
        # Directions run to points by the sphere: hits lie at t of 0.3 to
        # 1, so these bounds cut some of them.
        kwargs = {"tmin": 0.5, "tmax": 0.9}
    elif bounds == "per ray":
        rng = np.random.default_rng(12)
        kwargs = {"tmin": rng.uniform(0.0, 0.6, N), "tmax": rng.uniform(0.7, 2.0, N)}
    with warnings.catch_warnings():
        # float32 origins at 1e6 are coarse (warned, and checked below).
        warnings.simplefilter("ignore")
        fast = scene.intersect(o, d, device="cpu", **kwargs)
        slow = scene.intersect(general(o), general(d), device="cpu", **kwargs)
        hit = scene.occluded(o, d, device="cpu", **kwargs)
        hit_slow = scene.occluded(general(o), general(d), device="cpu", **kwargs)
    same(fast, slow)
    assert np.array_equal(hit, hit_slow)
    # Not a vacuous comparison: most rays hit, and some miss.
    assert 0.1 * N < np.count_nonzero(fast["prim_id"] >= 0) < N


def near_then_far(centre, seed):
    """`rays_near_and_far`'s rays, the first 1500 from within 2 units of
    the sphere's centre (so whole chunks of them stay where they are, and
    run through the per-chunk loops at once) and the rest as drawn (far
    ones moved, near ones not)."""
    o, d = rays_near_and_far(centre, seed)
    near = slice(0, 1500)
    away = o[near] - centre
    o[near] = centre + 2.0 * away / np.linalg.norm(away, axis=1)[:, None]
    d[near] = centre + 1.5 * (np.random.default_rng(seed + 1).random((1500, 3)) - 0.5) - o[near]
    return o, d


@pytest.mark.parametrize("place", [[0.0, 0.0, 0.0], [1e6, -0.7e6, 0.3e6]])
@pytest.mark.parametrize("origins", [np.float32, np.float64])
@pytest.mark.parametrize("directions", [np.float32, np.float64])
def test_chunks_of_near_rays_hit_as_the_general_layout(place, origins, directions):
    scene, centre = sphere_scene(place)
    o, d = near_then_far(centre, seed=21)
    o, d = o.astype(origins), d.astype(directions)
    for t64 in (False, True):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fast = scene.intersect(o, d, device="cpu", _t64=t64)
            slow = scene.intersect(general(o), general(d), device="cpu", _t64=t64)
        same(fast, slow)
    assert 0.1 * N < np.count_nonzero(fast["prim_id"][:1500] >= 0) < 1500


# A ray that is invalid as f32 holds it, among near ones: a NaN or an
# infinite coordinate, a direction too short or too long (also one whose
# length is within the limits though its longest axis is not), an
# origin beyond f32's range.
BAD = {
    "nan direction": lambda o, d: d.__setitem__((300, 1), np.nan),
    "infinite origin": lambda o, d: o.__setitem__((300, 2), np.inf),
    "zero direction": lambda o, d: d.__setitem__(300, 0.0),
    "short direction": lambda o, d: d.__setitem__(300, [4e-19, 4e-19, 0.0]),
    "long direction": lambda o, d: d.__setitem__(300, [1e18, 1e18, 0.0]),
    "origin beyond float32": lambda o, d: o.__setitem__((300, 0), 1e39),
}


@pytest.mark.parametrize("bad", sorted(BAD))
@pytest.mark.parametrize("origins", [np.float32, np.float64])
@pytest.mark.parametrize("directions", [np.float32, np.float64])
def test_an_invalid_ray_among_near_ones_is_named_as_the_general_layout(bad, origins, directions):
    scene, centre = sphere_scene([0.0, 0.0, 0.0])
    o, d = near_then_far(centre, seed=22)
    with np.errstate(over="ignore"):
        o, d = o.astype(origins), d.astype(directions)
        BAD[bad](o, d)
    with pytest.raises(ValueError) as packed:
        scene.intersect(o, d, device="cpu")
    with pytest.raises(ValueError) as slow:
        scene.intersect(general(o), general(d), device="cpu")
    assert str(packed.value) == str(slow.value)
    assert "300" in str(packed.value)


def test_a_valid_ray_beyond_the_chunks_quick_bounds_is_traced():
    """A direction whose longest axis is under the shortest allowed length
    while its length is not: the per-chunk bound refuses the chunk, and
    the general loop then accepts the ray (no error, hits as the general
    layout's)."""
    scene, centre = sphere_scene([0.0, 0.0, 0.0])
    o, d = near_then_far(centre, seed=23)
    d[300] = 1.2e-18 / np.sqrt(3.0)
    assert np.abs(d[300]).max() < 1e-18 <= np.linalg.norm(d[300])
    same(scene.intersect(o, d, device="cpu"), scene.intersect(general(o), general(d), device="cpu"))


@pytest.mark.parametrize("layout", ["packed", "general", "records"])
def test_coarse_float32_origins_are_warned_of_chunk_by_chunk(layout):
    # A sphere at 1e8 seen from around the world's origin: float32 holds
    # those origins finely enough for their distance, but rays 1100 and
    # 2400 (in the second and third chunks) start 6 units from the sphere,
    # where it spaces values 8 apart.
    scene, centre = sphere_scene([1e8, 0.4e8, -0.9e8])
    rng = np.random.default_rng(13)
    o = 100.0 * (rng.random((N, 3)) - 0.5)
    d = centre - o
    o[[1100, 2400]] = centre + [6.0, 0.0, 0.0]
    d[[1100, 2400]] = [-1.0, 0.0, 0.0]
    o, d = o.astype(np.float32), d.astype(np.float32)
    if layout == "records":
        from conftest import records

        query = (records(o, d),)
    else:
        query = (o, d) if layout == "packed" else (general(o), general(d))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene.intersect(*query, device="cpu")
    texts = [str(w.message) for w in caught]
    assert len(texts) == 1, texts
    assert texts[0].startswith("ray 1100 (and 1 more like it): its origin"), texts


@pytest.mark.parametrize("layout", ["packed", "general"])
def test_hits_beyond_float32_t_are_warned_of_once_each(layout):
    scene, centre = sphere_scene([0.0, 0.0, 0.0])
    o, d = rays_near_and_far(centre, seed=14)
    # Rays 7 and 2000: directions so short that the sphere lies beyond
    # float32's largest t.
    for i in (7, 2000):
        o[i] = [1e37, 0.0, 0.0]
        d[i] = [-1e-3, 0.0, 0.0]
    query = (o, d) if layout == "packed" else (general(o), general(d))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hits = scene.intersect(*query, device="cpu")
    texts = [str(w.message) for w in caught]
    assert len(texts) == 1, texts
    assert texts[0].startswith("ray 7 (and 1 more like it): the scene lies up to t ="), texts
    assert hits["prim_id"][7] == -1 and hits["prim_id"][2000] == -1
