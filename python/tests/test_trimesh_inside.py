"""lambert.trimesh's inside on closed meshes facing either way (issue 44,
item 3): the sign of ``ProximityQuery.signed_distance`` is trimesh's
``mesh.contains`` (its ray test), whichever way the faces point."""

import numpy as np
import pytest
import trimesh

import lambert.trimesh
from conftest import reference_module


def two_bodies_one_facing_in():
    """As trimesh's multibody.stl: two closed spheres apart, the second's
    faces reversed."""
    a = trimesh.creation.icosphere(subdivisions=3)
    b = trimesh.creation.icosphere(subdivisions=3, radius=0.7)
    b.apply_translation([2.5, 0, 0])
    faces = np.concatenate([a.faces, b.faces[:, ::-1] + len(a.vertices)])
    return trimesh.Trimesh(np.concatenate([a.vertices, b.vertices]), faces, process=False)


@pytest.mark.parametrize("facing", ["out", "in", "one body in"])
def test_signed_distance_is_positive_where_trimesh_contains(facing):
    # trimesh's ray test runs over its R-tree of triangles.
    reference_module("rtree", needed_by="trimesh's contains")
    sphere = trimesh.creation.icosphere(subdivisions=3)
    mesh = {"out": sphere,
            "in": trimesh.Trimesh(sphere.vertices, sphere.faces[:, ::-1], process=False),
            "one body in": two_bodies_one_facing_in()}[facing]
    assert mesh.is_watertight
    rng = np.random.default_rng(4)
    lo, hi = mesh.bounds
    points = lo - 0.2 + rng.random((3000, 3)) * (hi - lo + 0.4)
    sd = lambert.trimesh.ProximityQuery(mesh, device="cpu").signed_distance(points)
    clear = np.abs(sd) > 1e-3
    expected = mesh.contains(points)
    assert expected[clear].sum() > 200
    np.testing.assert_array_equal((sd > 0)[clear], expected[clear])
