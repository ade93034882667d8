"""Every public function, sent bad shapes, dtypes, NaNs, huge sizes and
wrong types, raises one of lambert's exceptions (each also the built-in a
Python user expects), naming the argument; nothing panics across the FFI
boundary (pyo3's PanicException is a BaseException, not an Exception)."""

import numpy as np
import pytest

import lambert

TRIANGLE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float64)
RAYS = np.array([[0.2, 0.2, -1.0]]), np.array([[0.0, 0.0, 1.0]])
POINTS = np.array([[0.2, 0.2, 0.5]])


@pytest.fixture(scope="module")
def scene():
    return lambert.Scene.from_arrays(TRIANGLE, [[0, 1, 2]])


def camera(**changes):
    args = dict(eye=(0, 0, 3), look_at=(0, 0, 0), up=(0, 1, 0), vfov=40)
    args.update(changes)
    return lambert.Camera(**args)


V, T, F, N, P = (lambert.LambertValueError, lambert.LambertTypeError, lambert.LambertFileNotFoundError,
                 lambert.LambertNotADirectoryError, lambert.LambertPermissionError)

CASES = [
    # Scene.from_arrays and Scene.load
    ("from_arrays shape", lambda s: lambert.Scene.from_arrays(TRIANGLE[:, :2], [[0, 1, 2]]), V, "vertices"),
    ("from_arrays dtype", lambda s: lambert.Scene.from_arrays(TRIANGLE.astype(complex), [[0, 1, 2]]), V, "vertices"),
    ("from_arrays NaN", lambda s: lambert.Scene.from_arrays(TRIANGLE * np.nan, [[0, 1, 2]]), V, "vertices row 0"),
    ("from_arrays huge", lambda s: lambert.Scene.from_arrays(TRIANGLE * 1e300, [[0, 1, 2]]), V, "vertices row 1"),
    ("from_arrays index", lambda s: lambert.Scene.from_arrays(TRIANGLE, [[0, 1, 2**40]]), V, "faces row 0"),
    ("from_arrays faces dtype", lambda s: lambert.Scene.from_arrays(TRIANGLE, [["a", "b", "c"]]), V, "faces"),
    ("from_arrays albedo", lambda s: lambert.Scene.from_arrays(TRIANGLE, [[0, 1, 2]], albedo=[1, 2]), V, "albedo"),
    ("load missing", lambda s: lambert.Scene.load("/nonexistent/scene.toml"), F, "scene.toml"),
    ("load type", lambda s: lambert.Scene.load(42), T, "path"),
    ("load camera type", lambda s: lambert.Scene.load("x.glb", camera=3), T, "camera"),
    # Ray queries
    ("intersect shape", lambda s: s.intersect(np.zeros((2, 2)), np.zeros((2, 3))), V, "origins"),
    ("intersect dtype", lambda s: s.intersect(np.array([["a", "b", "c"]]), RAYS[1]), V, "origins"),
    ("intersect NaN", lambda s: s.intersect(RAYS[0] * np.nan, RAYS[1]), V, "ray 0"),
    ("intersect huge", lambda s: s.intersect(RAYS[0] * 1e300, RAYS[1]), V, "ray 0"),
    ("intersect counts", lambda s: s.intersect(np.zeros((2, 3)), RAYS[1]), V, "origins but"),
    ("intersect tmax shape", lambda s: s.intersect(*RAYS, tmax=np.ones(4)), V, "tmax"),
    ("intersect tmin type", lambda s: s.intersect(*RAYS, tmin="a"), V, "tmin"),
    ("intersect device", lambda s: s.intersect(*RAYS, device="tpu"), V, "device"),
    ("intersect test", lambda s: s.intersect(*RAYS, intersect="fast"), V, "intersect"),
    ("intersect test type", lambda s: s.intersect(*RAYS, intersect=1), T, "intersect"),
    ("intersect device type", lambda s: s.intersect(*RAYS, device=0), T, "device"),
    ("contains device type", lambda s: s.contains(POINTS, device=None), T, "device"),
    ("signed_distance method type", lambda s: s.signed_distance(POINTS, method=0), V, "method"),
    ("occluded NaN", lambda s: s.occluded(RAYS[0], RAYS[1] * np.nan), V, "ray 0"),
    ("count_intersections shape", lambda s: s.count_intersections(np.zeros(3), RAYS[1]), V, "origins"),
    ("list_intersections NaN", lambda s: s.list_intersections(RAYS[0], RAYS[1], tmax=np.nan), V, "tmax"),
    # Point queries
    ("closest_points shape", lambda s: s.closest_points(np.zeros((4, 2))), V, "points"),
    ("closest_points NaN", lambda s: s.closest_points(POINTS * np.nan), V, "points row 0"),
    ("closest_points huge", lambda s: s.closest_points(POINTS * 1e300), V, "points row 0"),
    ("closest_points reach", lambda s: s.closest_points(POINTS, max_distance="far"), T, "max_distance"),
    ("closest_points negative", lambda s: s.closest_points(POINTS, max_distance=-1), V, "max_distance"),
    ("distance dtype", lambda s: s.distance(np.array([[b"a", b"b", b"c"]])), V, "points"),
    ("signed_distance method", lambda s: s.signed_distance(POINTS, method="sign"), V, "method"),
    ("winding_number NaN", lambda s: s.winding_number(POINTS * np.nan), V, "points row 0"),
    ("contains shape", lambda s: s.contains(np.zeros((3,))), V, "points"),
    # Renders and camera rays
    ("render width type", lambda s: s.render("wide"), T, "width"),
    ("render width float", lambda s: s.render(10.5), T, "width"),
    ("render negative", lambda s: s.render(-4, 4), V, "width"),
    ("render huge", lambda s: s.render(10**6, 10**6, device="cpu"), V, "width"),
    ("render huge int", lambda s: s.render(2**70), V, "width"),
    ("render spp", lambda s: s.render(4, 4, spp=0), V, "spp"),
    ("render spp huge", lambda s: s.render(4, 4, spp=10**6), V, "spp"),
    ("render seed", lambda s: s.render(4, 4, seed=-1), V, "seed"),
    ("render ambient NaN", lambda s: s.render(4, 4, ambient=np.nan), V, "ambient"),
    ("render ambient shape", lambda s: s.render(4, 4, ambient=[1, 2]), V, "ambient"),
    ("render ambient type", lambda s: s.render(4, 4, ambient="grey"), T, "ambient"),
    ("render shadows", lambda s: s.render(4, 4, shadows="yes"), T, "shadows"),
    ("render integrator", lambda s: s.render(4, 4, integrator="bidirectional"), V, "integrator"),
    ("render integrator type", lambda s: s.render(4, 4, integrator=1), T, "integrator"),
    ("render max_depth", lambda s: s.render(4, 4, integrator="path", max_depth=0), V, "max_depth"),
    ("render target_error", lambda s: s.render(4, 4, target_error=np.nan), V, "target_error"),
    ("render max_spp", lambda s: s.render(4, 4, target_error=0.1, max_spp=1), V, "max_spp"),
    ("render time_budget", lambda s: s.render(4, 4, time_budget=-1), V, "time_budget"),
    ("render time_budget type", lambda s: s.render(4, 4, time_budget="1s"), T, "time_budget"),
    ("render both", lambda s: s.render(4, 4, time_budget=1, spp=4), V, "time_budget"),
    ("render environment missing", lambda s: s.render(4, 4, environment="/nonexistent/sky.exr"), F, "sky.exr"),
    ("render environment NaN", lambda s: s.render(4, 4, environment=(np.nan, 0, 0)), V, "environment"),
    ("render environment strength", lambda s: s.render(4, 4, environment=1, environment_strength=-1), V,
     "environment_strength"),
    ("render environment rotation", lambda s: s.render(4, 4, environment=1, environment_rotation=np.inf), V,
     "environment_rotation"),
    ("render strength alone", lambda s: s.render(4, 4, environment_strength=2), V, "environment"),
    ("render device", lambda s: s.render(4, 4, device="tpu"), V, "device"),
    ("render tile", lambda s: s.render(4, 4, tile=(4, 4)), V, "tile"),
    ("render tile type", lambda s: s.render(4, 4, tile="0/2"), T, "tile"),
    ("render tile rows", lambda s: s.render(4, 4, tile=(0, 5)), V, "tile"),
    ("render camera type", lambda s: s.render(4, 4, camera=(0, 0, 3)), T, "camera"),
    ("render camera name", lambda s: s.render(4, 4, camera="front"), V, "camera"),
    ("render camera NaN", lambda s: s.render(4, 4, camera=camera(eye=(np.nan, 0, 3))), V, "camera.eye"),
    ("render camera huge", lambda s: s.render(4, 4, camera=camera(eye=(1e300, 0, 3))), V, "camera.eye"),
    ("render camera vfov", lambda s: s.render(4, 4, camera=camera(vfov=180)), V, "vfov"),
    ("render camera up", lambda s: s.render(4, 4, camera=camera(up=(0, 0, 1))), V, "camera.up"),
    ("render progress", lambda s: s.render(4, 4, progress=3), T, "progress"),
    ("camera shape", lambda s: camera(eye=(0, 0)), V, "camera.eye"),
    ("camera type", lambda s: camera(eye="here"), T, "camera.eye"),
    ("camera vfov type", lambda s: camera(vfov="wide"), T, "vfov"),
    ("camera_rays huge", lambda s: s.camera_rays(10**6, 10**6), V, "width"),
    ("camera_rays camera", lambda s: s.camera_rays(4, camera=camera(look_at=(0, 0, 3))), V, "camera"),
    # Lights
    ("point light NaN", lambda s: s.add_point_light((np.nan, 0, 0), 1), V, "position"),
    ("point light huge", lambda s: s.add_point_light((1e300, 0, 0), 1), V, "position"),
    ("point light negative", lambda s: s.add_point_light((0, 0, 1), -1), V, "intensity"),
    ("point light shape", lambda s: s.add_point_light((0, 0), 1), V, "position"),
    ("directional light zero", lambda s: s.add_directional_light((0, 0, 0), 1), V, "direction"),
    ("directional light type", lambda s: s.add_directional_light("down", 1), T, "direction"),
    ("spot light cone", lambda s: s.add_spot_light((0, 0, 1), (0, 0, -1), 1, 50, 40), V, "cone"),
    ("spot light angle type", lambda s: s.add_spot_light((0, 0, 1), (0, 0, -1), 1, "wide"), T, "inner_angle_deg"),
    # Images
    ("write_image shape", lambda s: lambert.write_image("/tmp/x.png", np.zeros((4, 4))), V, "image"),
    ("write_image dtype", lambda s: lambert.write_image("/tmp/x.png", np.zeros((4, 4, 3), dtype=complex)), T,
     "image"),
    ("write_image format", lambda s: lambert.write_image("/tmp/lambert-x.bmp", np.zeros((4, 4, 3))), V, "bmp"),
    ("write_image folder", lambda s: lambert.write_image("/etc/passwd/x.png", np.zeros((4, 4, 3))), N, "passwd"),
    ("write_image empty", lambda s: lambert.write_image("/tmp/x.png", np.zeros((0, 4, 3))), V, "image"),
    ("write_image scene", lambda s: lambert.write_image("/tmp/x.png", np.zeros((1, 1, 3)), scene=3), T, "scene"),
    ("to_srgb shape", lambda s: lambert.to_srgb(np.zeros((4, 3))), V, "image"),
    ("to_srgb type", lambda s: lambert.to_srgb("image"), T, "image"),
    ("merge type", lambda s: lambert.merge(3), T, "parts"),
    ("merge empty", lambda s: lambert.merge([]), V, "parts"),
    ("merge array", lambda s: lambert.merge([np.zeros((4, 4, 3))]), T, "parts[0]"),
    ("merge missing file", lambda s: lambert.merge(["/nonexistent/part.exr"]), F, "part.exr"),
    ("merge not a part", lambda s: lambert.merge([__file__]), V, "test_error_classes.py"),
    ("device", lambda s: s.device("tpu"), V, "device"),
    ("device type", lambda s: s.device(1), T, "device"),
    # The drop-ins
    ("open3d add_triangles shape", lambda s: lambert.open3d.RaycastingScene().add_triangles(
        np.zeros((3, 2), dtype=np.float32), np.zeros((1, 3), dtype=np.uint32)), V, "vertex_positions"),
    ("open3d device", lambda s: lambert.open3d.RaycastingScene(device="tpu"), V, "device"),
]


@pytest.mark.parametrize("name, call, kind, words", CASES, ids=[c[0] for c in CASES])
def test_bad_input_raises_lambert_s_exception_naming_it(scene, name, call, kind, words):
    try:
        call(scene)
    except BaseException as e:  # noqa: B036: a PanicException must be seen, not escape
        assert type(e).__name__ != "PanicException", f"{name}: panicked: {e}"
        assert isinstance(e, kind), f"{name}: {type(e).__mro__} is not {kind.__name__}: {e}"
        assert isinstance(e, lambert.LambertError)
        assert words in str(e), f"{name}: {e!s} does not name {words!r}"
    else:
        pytest.fail(f"{name}: no exception")


def test_the_classes_are_the_builtins_too():
    assert issubclass(lambert.LambertValueError, ValueError)
    assert issubclass(lambert.LambertTypeError, TypeError)
    assert issubclass(lambert.LambertFileNotFoundError, FileNotFoundError)
    assert issubclass(lambert.LambertFileNotFoundError, lambert.LambertOSError)
    assert issubclass(lambert.LambertNotADirectoryError, NotADirectoryError)
    assert issubclass(lambert.LambertPermissionError, PermissionError)
    assert issubclass(lambert.LambertRuntimeError, RuntimeError)
    for cls in (lambert.LambertValueError, lambert.LambertTypeError, lambert.LambertOSError,
                lambert.LambertRuntimeError):
        assert issubclass(cls, lambert.LambertError)
