"""lambert.trimesh.RayMeshIntersector against trimesh's own intersectors."""

import numpy as np
import pytest

import trimesh  # noqa: E402  (scripts/test installs it)

import lambert.trimesh  # noqa: E402
from conftest import reference_module  # noqa: E402


def meshes():
    yield trimesh.creation.icosphere(subdivisions=3)
    yield trimesh.creation.box(extents=[1.0, 2.0, 0.5])
    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3)
    yield torus


def rays(mesh, n, seed):
    """From outside the mesh's bounding sphere towards points near its centre."""
    rng = np.random.default_rng(seed)
    centre, size = mesh.bounds.mean(axis=0), mesh.scale
    away = rng.normal(size=(n, 3))
    o = centre + 2 * size * away / np.linalg.norm(away, axis=1)[:, None]
    target = centre + size * (rng.random((n, 3)) - 0.5) * 0.5
    return o, target - o


def reference(mesh):
    """trimesh's own: the Embree one where embreex is installed, else its
    pure-numpy one."""
    try:
        from trimesh.ray.ray_pyembree import RayMeshIntersector
    except ImportError:
        from trimesh.ray.ray_triangle import RayMeshIntersector
    return RayMeshIntersector(mesh)


@pytest.mark.parametrize("index", range(3))
def test_first_and_any_hits_match_trimesh(index):
    mesh = list(meshes())[index]
    ours, theirs = lambert.trimesh.RayMeshIntersector(mesh, device="cpu"), reference(mesh)
    o, d = rays(mesh, 3000, seed=index)
    first, expected = ours.intersects_first(o, d), theirs.intersects_first(o, d)
    assert (expected >= 0).sum() > 1000
    # Rays through a shared edge may name either triangle; none are missed.
    assert np.mean(first == expected) > 0.999
    np.testing.assert_array_equal(first >= 0, expected >= 0)
    np.testing.assert_array_equal(ours.intersects_any(o, d), theirs.intersects_any(o, d))


@pytest.mark.parametrize("index", range(3))
def test_every_hit_along_each_ray_matches_trimesh(index):
    mesh = list(meshes())[index]
    ours, theirs = lambert.trimesh.RayMeshIntersector(mesh, device="cpu"), reference(mesh)
    o, d = rays(mesh, 2000, seed=10 + index)
    tri, ray = ours.intersects_id(o, d)
    tri_ref, ray_ref = theirs.intersects_id(o, d)
    pairs, pairs_ref = set(zip(ray.tolist(), tri.tolist())), set(zip(ray_ref.tolist(), tri_ref.tolist()))
    assert len(pairs_ref) > 2000
    # The same (ray, triangle) hits, but for rays through shared edges.
    assert len(pairs ^ pairs_ref) <= 0.002 * len(pairs_ref), (len(pairs - pairs_ref), len(pairs_ref - pairs))
    # A closed mesh: every ray that hits enters and leaves.
    counts = np.bincount(ray, minlength=len(o))
    assert np.all(counts % 2 == 0)
    # Locations lie on their triangles' planes, as trimesh's do.
    locations, index_ray, index_tri = ours.intersects_location(o, d)
    plane = np.einsum("ij,ij->i", locations - mesh.triangles[index_tri, 0], mesh.face_normals[index_tri])
    assert np.abs(plane).max() < 1e-5 * mesh.scale
    # First hits only.
    tri1, ray1 = ours.intersects_id(o, d, multiple_hits=False)
    first = ours.intersects_first(o, d)
    np.testing.assert_array_equal(ray1, np.flatnonzero(first >= 0))
    np.testing.assert_array_equal(tri1, first[first >= 0])


def test_degenerate_rays_are_misses_as_in_trimesh():
    mesh = trimesh.creation.icosphere()
    ours = lambert.trimesh.RayMeshIntersector(mesh, device="cpu")
    o = np.array([[0, 0, 5.0], [0, 0, 5.0], [np.nan, 0, 5.0]])
    d = np.array([[0, 0, -1.0], [0, 0, 0.0], [0, 0, -1.0]])
    np.testing.assert_array_equal(ours.intersects_first(o, d) >= 0, [True, False, False])
    np.testing.assert_array_equal(ours.intersects_any(o, d), [True, False, False])


def test_contains_points_and_one_line_switch():
    mesh = trimesh.creation.icosphere(subdivisions=3)
    mesh.ray = lambert.trimesh.RayMeshIntersector(mesh, device="cpu")
    points = np.array([[0, 0, 0], [0.5, 0.2, 0.1], [2, 0, 0], [0, 1.5, 0]])
    np.testing.assert_array_equal(mesh.contains(points), [True, True, False, False])
    # trimesh's own API through the new intersector.
    locations, index_ray, _ = mesh.ray.intersects_location([[0, 0, 5]], [[0, 0, -1]])
    assert len(index_ray) == 2 and np.allclose(sorted(locations[:, 2]), [-1, 1], atol=2e-2)


def test_the_gpu_gives_the_cpu_hits():
    mesh = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3)
    o, d = rays(mesh, 2000, seed=4)
    cpu = lambert.trimesh.RayMeshIntersector(mesh, device="cpu").intersects_id(o, d)
    gpu = lambert.trimesh.RayMeshIntersector(mesh, device="gpu").intersects_id(o, d)
    np.testing.assert_array_equal(cpu[0], gpu[0])
    np.testing.assert_array_equal(cpu[1], gpu[1])


@pytest.mark.parametrize("vertices", [np.zeros((0, 3)), np.eye(3)])
@pytest.mark.parametrize("device", ["cpu", "gpu"])
def test_an_empty_mesh_misses_every_ray_as_in_trimesh(vertices, device):
    # trimesh's Embree intersector on a mesh without faces: every ray
    # misses, with empty hit lists (its rtree one and contains_points fail).
    mesh = trimesh.Trimesh(vertices=vertices, faces=np.zeros((0, 3), dtype=np.int64))
    ours = lambert.trimesh.RayMeshIntersector(mesh, device=device)
    o = np.array([[0.2, 0.2, 1.0], [0.0, 0.0, 5.0], [1.0, 2.0, 3.0]])
    d = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    first = ours.intersects_first(o, d)
    np.testing.assert_array_equal(first, [-1, -1, -1])
    assert first.dtype.kind == "i"
    hit = ours.intersects_any(o, d)
    assert hit.dtype == bool and not hit.any() and hit.shape == (3,)
    for multiple_hits in (True, False):
        tri, ray, loc = ours.intersects_id(o, d, multiple_hits=multiple_hits, return_locations=True)
        assert tri.shape == ray.shape == (0,) and tri.dtype == ray.dtype == np.int64
        assert loc.shape == (0, 3) and loc.dtype == np.float64
        loc, ray, tri = ours.intersects_location(o, d, multiple_hits=multiple_hits)
        assert loc.shape == (0, 3) and ray.shape == tri.shape == (0,)
    inside = ours.contains_points(o)
    assert inside.dtype == bool and inside.shape == (3,) and not inside.any()


@pytest.mark.parametrize("index", range(3))
def test_stl_files_load_as_trimesh_reads_them(index, tmp_path):
    # Binary and ASCII STL as trimesh writes them: trimesh's triangle count
    # and bounds, and, binary STL holding float32 as lambert's scenes do,
    # the very hits of the same triangles given as arrays.
    mesh = list(meshes())[index]
    for kind in ["stl", "stl_ascii"]:
        path = tmp_path / f"{kind}.stl"
        path.write_bytes(mesh.export(file_type=kind) if kind == "stl" else
                         mesh.export(file_type=kind).encode())
        scene = lambert.Scene.load(path)
        theirs = trimesh.load(path)
        assert scene.triangle_count == len(theirs.faces) == len(mesh.faces)
        assert np.allclose(scene.bounds, theirs.bounds, atol=1e-6)
    vertices = mesh.vertices.astype(np.float32).astype(np.float64)
    arrays = lambert.Scene.from_arrays(vertices, mesh.faces)
    o, d = rays(mesh, 500, seed=index)
    mine = lambert.Scene.load(tmp_path / "stl.stl").intersect(o, d, device="cpu")
    same = arrays.intersect(o, d, device="cpu")
    for column in ["t", "prim_id", "u", "v"]:
        assert np.array_equal(mine[column], same[column]), column


def open_mesh():
    """A torus with a band of faces removed: a mesh with a hole."""
    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3)
    keep = torus.triangles_center[:, 0] < 0.9
    return trimesh.Trimesh(torus.vertices, torus.faces[keep], process=False)


def needs_trimesh_proximity():
    """trimesh's proximity queries, the reference of lambert.trimesh's, need
    scipy (a k-d tree) and rtree: without them the test skips, or fails
    under CI, as the other references do."""
    for name in ("scipy", "rtree"):
        reference_module(name, needed_by="trimesh's proximity")


def proximity_points(mesh, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = mesh.bounds
    return (lo + hi) / 2 + (rng.random((n, 3)) - 0.5) * 1.5 * (hi - lo)


@pytest.mark.parametrize("index", range(4))
def test_closest_points_on_the_surface_match_trimesh(index):
    needs_trimesh_proximity()
    mesh = (list(meshes()) + [open_mesh()])[index]
    points = proximity_points(mesh, 500, seed=index)
    query = lambert.trimesh.ProximityQuery(mesh, device="cpu")
    closest, distance, triangle_id = query.on_surface(points)
    expected = trimesh.proximity.ProximityQuery(mesh).on_surface(points)
    assert closest.dtype == distance.dtype == np.float64 and closest.shape == (500, 3)
    np.testing.assert_allclose(distance, expected[1], rtol=1e-5, atol=1e-6 * mesh.scale)
    # The same point, but for a few equally near elsewhere; the same
    # triangle unless several are as near (a vertex or edge they share).
    near = np.linalg.norm(closest - expected[0], axis=1) < 1e-5 * mesh.scale
    assert near.mean() > 0.99
    assert (triangle_id == expected[2]).mean() > 0.5
    np.testing.assert_allclose(np.linalg.norm(closest - points, axis=1), distance, rtol=1e-12)


@pytest.mark.parametrize("index", range(4))
def test_signed_distance_has_trimeshs_sign(index):
    mesh = (list(meshes()) + [open_mesh()])[index]
    points = proximity_points(mesh, 500, seed=10 + index)
    sd = lambert.trimesh.ProximityQuery(mesh, device="cpu").signed_distance(points)
    assert sd.dtype == np.float64
    if mesh.is_watertight:
        needs_trimesh_proximity()
        expected = trimesh.proximity.signed_distance(mesh, points)
        clear = np.abs(expected) > 1e-6
        np.testing.assert_array_equal(np.sign(sd[clear]), np.sign(expected[clear]))
        np.testing.assert_allclose(np.abs(sd), np.abs(expected), rtol=1e-5, atol=1e-6 * mesh.scale)
        np.testing.assert_array_equal(sd[clear] > 0, mesh.contains(points)[clear])
    else:
        # Inside by winding number: the torus's tube still holds its middle.
        inside = lambert.Scene.from_arrays(mesh.vertices, mesh.faces).contains(points)
        np.testing.assert_array_equal(sd > 0, inside)
        assert inside.any()


def test_nearest_vertex_is_trimeshs():
    needs_trimesh_proximity()
    mesh = trimesh.creation.icosphere(subdivisions=2)
    points = proximity_points(mesh, 200, seed=3)
    distance, vertex_id = lambert.trimesh.ProximityQuery(mesh).vertex(points)
    expected = trimesh.proximity.ProximityQuery(mesh).vertex(points)
    np.testing.assert_array_equal(vertex_id, expected[1])
    np.testing.assert_allclose(distance, expected[0])


def test_proximity_on_bad_points_is_a_value_error():
    query = lambert.trimesh.ProximityQuery(trimesh.creation.box())
    with pytest.raises(ValueError, match=r"points must be \(n,3\)"):
        query.on_surface(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="points row 1"):
        query.signed_distance([[0, 0, 0], [np.nan, 0, 0]])
