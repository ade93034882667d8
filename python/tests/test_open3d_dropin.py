"""lambert.open3d.RaycastingScene where Open3D code and Open3D's answers
are the reference (issue 44): inside on closed meshes facing either way,
directions of any finite length, Open3D's ``.numpy()`` idiom on numpy
input, and the advice a GPU error gives in Python's terms."""

import os
import subprocess

import numpy as np
import pytest

import lambert
from conftest import LAMBERT, open3d_scenes


def sphere(centre=(0.0, 0.0, 0.0), radius=1.0, rings=24, segments=32):
    """A closed, outward-facing latitude-longitude sphere: (vertices, faces)."""
    theta = np.linspace(0, np.pi, rings + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    vertices = np.concatenate([[[0, 0, 1]], ring, [[0, 0, -1]]]) * radius + centre
    faces = []
    for j in range(segments):
        k = (j + 1) % segments
        faces.append([0, 1 + j, 1 + k])
        last = 1 + (rings - 2) * segments
        faces.append([len(vertices) - 1, last + k, last + j])
        for i in range(rings - 2):
            a, b = 1 + i * segments + j, 1 + i * segments + k
            c, d = a + segments, b + segments
            faces += [[a, c, d], [a, d, b]]
    return vertices.astype(np.float32), np.array(faces, dtype=np.uint32)


def reversed_faces(faces):
    return np.ascontiguousarray(faces[:, ::-1])


def points_off(vertices, faces, n, seed, clearance=0.02):
    """Random points over the mesh's box and beyond, none within
    `clearance` of its surface (where rounding may pick either side)."""
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    points = ((lo + hi) / 2 + (rng.random((n, 3)) - 0.5) * 1.5 * (hi - lo)).astype(np.float32)
    distance = lambert.Scene.from_arrays(vertices, faces).distance(points, device="cpu")
    return points[distance > clearance * np.linalg.norm(hi - lo)]


@pytest.mark.parametrize("facing", ["out", "in"])
def test_inside_of_a_closed_sphere_is_open3ds_facing_either_way(facing):
    vertices, faces = sphere()
    if facing == "in":
        faces = reversed_faces(faces)
    theirs, ours = open3d_scenes(vertices, faces)
    points = points_off(vertices, faces, 3000, seed=1)
    expected = theirs.compute_signed_distance(points).numpy()
    assert (expected < 0).sum() > 300
    got = ours.compute_signed_distance(points)
    np.testing.assert_array_equal(np.signbit(got), expected < 0)
    np.testing.assert_allclose(np.abs(got), np.abs(expected), rtol=1e-5, atol=1e-6)
    np.testing.assert_array_equal(ours.compute_occupancy(points), theirs.compute_occupancy(points).numpy())
    # The native API's rule is the same: |winding number| >= 0.5.
    scene = lambert.Scene.from_arrays(vertices, faces)
    np.testing.assert_array_equal(scene.contains(points, device="cpu"), expected < 0)


def test_two_bodies_one_facing_in_are_inside_as_open3d_says():
    # As trimesh's multibody.stl: two closed bodies apart, one facing in.
    left_v, left_f = sphere(centre=(-1.2, 0.0, 0.0))
    right_v, right_f = sphere(centre=(1.2, 0.0, 0.0), radius=0.8)
    vertices = np.concatenate([left_v, right_v])
    faces = np.concatenate([left_f, reversed_faces(right_f) + len(left_v)])
    theirs, ours = open3d_scenes(vertices, faces)
    points = points_off(vertices, faces, 4000, seed=2)
    expected = theirs.compute_occupancy(points).numpy()
    assert expected[points[:, 0] > 0].sum() > 50, "points inside the body facing in"
    np.testing.assert_array_equal(ours.compute_occupancy(points), expected)
    np.testing.assert_array_equal(np.signbit(ours.compute_signed_distance(points)),
                                  theirs.compute_signed_distance(points).numpy() < 0)


def box_scene():
    """lambert's drop-in over the cube [-1, 1]³."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float32)
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], dtype=np.uint32)
    scene = lambert.open3d.RaycastingScene(device="cpu")
    scene.add_triangles(corners, faces)
    return scene


@pytest.mark.parametrize("length", [1e-30, 1e-8, 1.0, 1e20])
def test_any_finite_direction_length_is_traced_with_t_in_its_units(length):
    # From x = -3 along +x through the cube [-1, 1]³: crossings at 2 and 4
    # units of distance, so at t = 2 / length and 4 / length.
    scene = box_scene()
    rays = np.array([[-3, 0.1, 0.2, length, 0, 0]], dtype=np.float32)
    np.testing.assert_array_equal(scene.count_intersections(rays), [2])
    t = np.float32(2) / np.float32(length)
    np.testing.assert_allclose(scene.cast_rays(rays)["t_hit"], [t], rtol=1e-6)
    listed = scene.list_intersections(rays)
    np.testing.assert_allclose(listed["t_hit"], [t, 2 * t], rtol=1e-6)
    np.testing.assert_array_equal(listed["ray_splits"], [0, 2])
    # tnear and tfar are in the same units.
    np.testing.assert_array_equal(scene.test_occlusions(rays, tfar=float(t) * 0.9), [False])
    np.testing.assert_array_equal(scene.test_occlusions(rays, tfar=float(t) * 1.1), [True])
    np.testing.assert_array_equal(scene.test_occlusions(rays, tnear=float(t) * 2.1), [False])


def test_untraceable_rays_miss_and_keep_their_rows():
    scene = box_scene()
    rays = np.array([[np.nan, 0, 0, 1, 0, 0],      # a NaN origin
                     [-3, 0.1, 0.2, 0, 0, 0],      # no direction
                     [-3, 0.1, 0.2, 1, np.inf, 0],  # an infinite one
                     [-3, 0.1, 0.2, 1, 0, 0]], dtype=np.float32)
    np.testing.assert_array_equal(scene.count_intersections(rays), [0, 0, 0, 2])
    ans = scene.cast_rays(rays)
    np.testing.assert_array_equal(ans["t_hit"], [np.inf, np.inf, np.inf, 2])
    np.testing.assert_array_equal(ans["primitive_ids"][:3], [lambert.open3d.INVALID_ID] * 3)
    listed = scene.list_intersections(rays)
    np.testing.assert_array_equal(listed["ray_splits"], [0, 0, 0, 0, 2])
    np.testing.assert_array_equal(listed["ray_ids"], [3, 3])


def test_an_error_names_the_callers_row_after_untraceable_rays():
    scene = box_scene()
    # Row 0 is untraceable (a miss); row 1 is the first the native check
    # refuses (tnear above tfar), and is named by the caller's row.
    rays = np.array([[np.nan, 0, 0, 1, 0, 0], [-3, 0.1, 0.2, 1, 0, 0]], dtype=np.float32)
    with pytest.raises(ValueError, match=r"^ray 1: tmin = 2 is greater than tmax = 1"):
        scene.test_occlusions(rays, tnear=2.0, tfar=1.0)


def test_open3d_code_runs_unchanged_on_numpy_rays():
    # Open3D's tutorials: scene.cast_rays(rays)["t_hit"].numpy().
    scene = box_scene()
    rays = np.array([[-3, 0.1, 0.2, 1, 0, 0], [-3, 5, 0, 1, 0, 0]], dtype=np.float32)
    t = scene.cast_rays(rays)["t_hit"].numpy()
    assert type(t) is np.ndarray and t.dtype == np.float32
    np.testing.assert_array_equal(t, [2, np.inf])
    assert type(scene.count_intersections(rays).numpy()) is np.ndarray
    assert type(scene.list_intersections(rays)["t_hit"].numpy()) is np.ndarray
    assert type(scene.test_occlusions(rays).numpy()) is np.ndarray
    points = np.array([[0, 0, 0], [3, 0, 0]], dtype=np.float32)
    np.testing.assert_array_equal(scene.compute_occupancy(points).numpy(), [1, 0])
    np.testing.assert_array_equal(scene.compute_signed_distance(points).numpy(), [-1, 2])
    assert type(scene.compute_distance(points).numpy()) is np.ndarray
    assert type(scene.compute_closest_points(points)["points"].numpy()) is np.ndarray
    # Still numpy arrays for numpy code.
    assert isinstance(t, np.ndarray) and np.isinf(scene.cast_rays(rays)["t_hit"]).tolist() == [False, True]


def stacked_triangles(layers):
    """`layers` copies of one triangle that a ray down the z axis misses
    within their box: it tests every copy, more loop iterations than
    llvmpipe lets an invocation group run."""
    vertices = np.array([[-1, -1, 0], [0.9, -1, 0], [-1, 0.9, 0]], dtype=np.float32)
    return vertices, np.zeros((layers, 3), dtype=np.int64) + [0, 1, 2]


def test_a_gpu_error_gives_its_advice_in_each_front_ends_terms(tmp_path):
    vertices, faces = stacked_triangles(300_000)
    scene = lambert.Scene.from_arrays(vertices, faces)
    origins = np.tile([[0.0, 0.0, 1.0]], (64, 1))
    directions = np.tile([[0.0, 0.0, -1.0]], (64, 1))
    if "llvmpipe" not in scene.device("gpu"):
        pytest.skip(f"the loop limit is llvmpipe's; the GPU here is {scene.device('gpu')}")
    with pytest.raises(RuntimeError) as e:
        scene.intersect(origins, directions, device="gpu")
    message = str(e.value)
    assert "cut the shader's loops short" in message and message.endswith('use device="cpu"'), message
    assert "--device" not in message
    # The CLI's words for the same error.
    mesh = tmp_path / "stack.obj"
    mesh.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in vertices) + "f 1 2 3\n" * len(faces))
    rays = np.zeros(64, dtype=lambert.RAY_DTYPE)
    rays["oz"], rays["dz"], rays["tmax"] = 1, -1, np.inf
    rays.tofile(tmp_path / "rays.bin")
    done = subprocess.run([LAMBERT, "trace", "--obj", str(mesh), "--rays", str(tmp_path / "rays.bin"),
                           "-o", str(tmp_path / "hits.bin"), "--device", "gpu", "-q"],
                          capture_output=True, text=True, env=dict(os.environ, NODEVICE_SELECT="1"))
    assert done.returncode != 0
    assert "cut the shader's loops short" in done.stderr and "use --device cpu" in done.stderr, done.stderr
    assert 'device="cpu"' not in done.stderr
