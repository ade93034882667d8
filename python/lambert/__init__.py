"""lambert: ray queries and renders on numpy arrays, on the GPU or the CPU.

A :class:`Scene` is built once (its BVH, and its upload to each device it
is used on) and then queried any number of times, from any thread::

    import numpy as np, lambert
    scene = lambert.Scene.from_arrays(vertices, faces)
    hits = scene.intersect(origins, directions)       # dict of numpy arrays
    depth = hits["t"].reshape(h, w)

Hits follow Embree's conventions: ``t`` (inf on a miss), ``prim_id`` (the
face row, -1 on a miss), barycentrics ``u``, ``v`` with
P = (1-u-v)·v0 + u·v1 + v·v2, and ``normal``, the unnormalised geometric
normal (v1-v0)×(v2-v0). Triangles are watertight: no ray passes between
two that share an edge. See docs/python.md.
"""

import os

# Mesa's device-select Vulkan layer prints "error: XDG_RUNTIME_DIR is
# invalid or not set" twice on a headless machine while listing adapters;
# it only reorders them, which lambert ranks itself. Switched off as the
# CLI does (src/bin/lambert/main.rs), before the native module makes any wgpu
# instance, unless the user steers it.
if "MESA_VK_DEVICE_SELECT" not in os.environ and "NODEVICE_SELECT" not in os.environ:
    os.environ["NODEVICE_SELECT"] = "1"

import numpy as np  # noqa: E402

from . import _lambert  # noqa: E402
from ._errors import (  # noqa: E402
    LambertError,
    LambertFileNotFoundError,
    LambertNotADirectoryError,
    LambertOSError,
    LambertPermissionError,
    LambertRuntimeError,
    LambertTypeError,
    LambertValueError,
)
from ._examples import example_path  # noqa: E402
from ._image import Camera, Image, merge, to_srgb, write_image  # noqa: E402
from ._image import _point  # noqa: E402
from ._options import _colour, _number, progress_callback, render_choices, sampling, tile_pair  # noqa: E402

__all__ = [
    "RAY_DTYPE",
    "Camera",
    "Image",
    "LambertError",
    "LambertFileNotFoundError",
    "LambertNotADirectoryError",
    "LambertOSError",
    "LambertPermissionError",
    "LambertRuntimeError",
    "LambertTypeError",
    "LambertValueError",
    "Scene",
    "example_path",
    "merge",
    "open3d",
    "to_srgb",
    "trimesh",
    "write_image",
]

#: The record layout of a ray file (docs/ray-query.md): little-endian
#: float32 ox oy oz tmin dx dy dz tmax, 32 bytes a ray. An array of it goes
#: straight into :meth:`Scene.intersect` and :meth:`Scene.occluded`, e.g.
#: ``np.fromfile("rays.bin", dtype=lambert.RAY_DTYPE)``.
RAY_DTYPE = np.dtype(
    [(name, "<f4") for name in ("ox", "oy", "oz", "tmin", "dx", "dy", "dz", "tmax")]
)

_DEVICES = ("auto", "gpu", "cpu")


def _floats(name, array):
    """An (N, 3) float32 or float64 array, converted only if it is neither."""
    a = np.asarray(array)
    if a.dtype.kind not in "fiu" or a.dtype.kind == "c":
        raise LambertValueError(f"{name} must be a real-valued (N, 3) array, not {a.dtype}")
    if a.dtype not in (np.float32, np.float64):
        a = a.astype(np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise LambertValueError(f"{name} has shape {a.shape}; it must be (N, 3)")
    return a


def _bound(name, value, n):
    """tmin or tmax: a Python float, or a (N,) float32 or float64 array
    (float64 is kept for float64 origins, traced from f64)."""
    a = np.asarray(value)
    if a.dtype.kind not in "fiub":
        raise LambertValueError(f"{name} must be a number or a (N,) array, not {a.dtype}")
    if a.ndim == 0:
        return float(a)
    if a.ndim != 1 or a.shape[0] != n:
        raise LambertValueError(f"{name} has shape {a.shape}; give a scalar or one value per ray ({n},)")
    return a if a.dtype == np.float64 else a.astype(np.float32, copy=False)


def _name(name, value):
    """A choice given by name (a str; the native module checks which)."""
    if not isinstance(value, str):
        raise LambertTypeError(f"{name} must be a str, not {type(value).__name__}")
    return value


def _device(device):
    """``device``: "auto", "gpu" or "cpu"."""
    if _name("device", device) not in _DEVICES:
        raise LambertValueError(f'device="{device}": use "auto", "gpu" or "cpu"')
    return device


def _max_distance(value):
    """A closest-point query's reach: a number ≥ 0, inf for no limit."""
    try:
        d = float(value)
    except (TypeError, ValueError):
        raise LambertTypeError(f"max_distance must be a number, not {type(value).__name__}") from None
    if not d >= 0.0:
        raise LambertValueError(f"max_distance = {d}: must be a number ≥ 0 (inf for no limit)")
    return d


def _albedo(albedo):
    """One colour for the whole mesh: a number (grey) or (r, g, b)."""
    if albedo is None:
        return None
    a = np.asarray(albedo, dtype=np.float64)
    if a.shape not in ((), (1,), (3,)):
        raise LambertValueError(
            f"albedo has shape {a.shape}; give one colour for the whole mesh, a number or shape (3,) "
            "(a colour per face, shape (F, 3), is not supported)"
        )
    return [float(c) for c in np.broadcast_to(a, (3,))]


def _query(origins, directions, tmin, tmax):
    """(origins, directions, tmin, tmax) as the native module takes them:
    RAY_DTYPE records become an (N, 8) float32 view and directions None."""
    if directions is None:
        records = np.asarray(origins)
        if records.dtype != RAY_DTYPE:
            raise LambertValueError(
                "with no directions, the first argument must be an array of lambert.RAY_DTYPE "
                f"records, not {records.dtype}"
            )
        if not (np.isscalar(tmin) and tmin == 0.0 and np.isscalar(tmax) and tmax == np.inf):
            raise LambertValueError("ray records carry their own tmin and tmax; do not pass them too")
        records = np.ascontiguousarray(records.reshape(-1))
        return records.view(np.float32).reshape(-1, 8), None, 0.0, 0.0
    o = _floats("origins", origins)
    d = _floats("directions", directions)
    if o.shape[0] != d.shape[0]:
        raise LambertValueError(f"{o.shape[0]} origins but {d.shape[0]} directions")
    return o, d, _bound("tmin", tmin, o.shape[0]), _bound("tmax", tmax, o.shape[0])


def _native_property(name, doc=None):
    """A read-only property of :class:`Scene`: its native scene's ``name``."""
    return property(lambda self: getattr(self._native, name), doc=doc)


class Scene:
    """Triangles (and, from a scene file, spheres, materials, lights and a
    camera), resident for queries and renders (docs/python.md).

    Build one with :meth:`from_arrays` (vertices (V, 3) of any float
    dtype, faces (F, 3) of any integer dtype) or :meth:`load` (a scene
    TOML or a model file: .obj, .ply, .gltf, .glb, .stl)::

        scene = lambert.Scene.load(lambert.example_path("bunny"))
        image = scene.render(320, 240, spp=4)     # lambert.Image, (240, 320, 3) float32

    Renders, as ``lambert render`` does, bit for bit:

    - :meth:`render` → :class:`Image`, (H, W, 3) float32 linear RGB, with
      the CLI's choices (camera, spp, seed, target_error, time_budget,
      ambient, shadows, integrator, max_depth, environment, tile);
    - :meth:`camera_rays` → (origins, directions), (W·H, 3) float32 each;
    - :meth:`add_point_light`, :meth:`add_directional_light`,
      :meth:`add_spot_light`: lights as the TOML format names them.

    Ray queries (origins and directions (N, 3), any float dtype, or
    RAY_DTYPE records; tmin, tmax scalars or (N,)):

    - :meth:`intersect` → dict: ``t`` (N,) float32, ``prim_id`` (N,)
      int64, ``u``, ``v`` (N,) float32, ``normal`` (N, 3) float32;
    - :meth:`occluded` → (N,) bool;
    - :meth:`count_intersections` → (N,) int32; :meth:`list_intersections`
      → dict of ``ray_splits`` (N + 1,) int64 and one row a crossing.

    Point queries (points (N, 3), any float dtype):

    - :meth:`closest_points` → dict: ``point`` (N, 3) float32,
      ``prim_id`` int64, ``u``, ``v``, ``distance`` float32;
    - :meth:`distance`, :meth:`signed_distance`, :meth:`winding_number` →
      (N,) float32; :meth:`contains` → (N,) bool.

    ``device``: "auto" (a hardware GPU, else the CPU path), "gpu" (any
    adapter, lavapipe included) or "cpu". Tracing releases the GIL;
    several threads may query one Scene at once. Bad arguments raise
    :class:`LambertError` subclasses that are also ValueError, TypeError,
    OSError or RuntimeError, naming the argument.
    """

    __slots__ = ("_native", "__weakref__")

    def __init__(self, native):
        if not isinstance(native, _lambert.NativeScene):
            raise LambertTypeError("use Scene.from_arrays(vertices, faces) or Scene.load(path)")
        self._native = native

    @classmethod
    def from_arrays(cls, vertices, faces, albedo=None):
        """A mesh from a (V, 3) vertex array of any float dtype and a (F, 3)
        face array of any integer dtype; triangle i is faces[i]. Raises
        ValueError naming the row of a NaN, infinite or huge coordinate (over
        1e9) or an index out of range. With a framed camera and a default
        light, as ``lambert render model.obj`` uses."""
        v = np.asarray(vertices)
        if v.dtype.kind not in "fiu":
            raise LambertValueError(f"vertices must be a float array, not {v.dtype}")
        f = np.asarray(faces)
        # An empty list is float64 to numpy; the no-triangles error below fits it better.
        if f.dtype.kind not in "iu" and f.size:
            raise LambertValueError(f"faces must be an integer array, not {f.dtype}")
        if v.ndim != 2 or v.shape[1] != 3:
            raise LambertValueError(f"vertices has shape {v.shape}; it must be (V, 3)")
        if f.ndim != 2 or f.shape[1] != 3:
            raise LambertValueError(f"faces has shape {f.shape}; it must be (F, 3)")
        if f.dtype == np.uint64 and f.size and f.max() > np.iinfo(np.int64).max:
            row = int(np.argmax(f.max(axis=1) > np.iinfo(np.int64).max))
            raise LambertValueError(f"faces row {row} = {f[row].tolist()}: index out of range")
        native = _lambert.NativeScene.from_arrays(
            v.astype(np.float64, copy=False), f.astype(np.int64, copy=False), _albedo(albedo)
        )
        return cls(native)

    @classmethod
    def load(cls, path, camera=None):
        """A scene TOML file, or any model file the CLI reads alone (.obj,
        .ply, .ply.gz, .gltf, .glb, .stl); ``camera``: a glTF file's camera
        by name (the CLI's ``--camera``; None: its first). Raises
        LambertFileNotFoundError (an OSError) for a file that cannot be
        read, LambertValueError (naming file and line or field) for bad
        content."""
        if not isinstance(path, (str, os.PathLike)):
            raise LambertTypeError(f"path must be a str or os.PathLike, not {type(path).__name__}")
        if camera is not None and not isinstance(camera, str):
            raise LambertTypeError(f"camera must be a glTF camera's name (str), not {type(camera).__name__}")
        return cls(_lambert.NativeScene.load(os.fspath(path), camera))

    def intersect(self, origins, directions=None, tmin=0.0, tmax=np.inf, *, device="auto",
                  intersect="watertight", _t64=False):
        """Closest hits of rays (origins and directions (N, 3) of any float
        dtype; tmin and tmax scalars or (N,) arrays; or one array of
        RAY_DTYPE records). Returns a dict of numpy arrays: ``t`` float32
        (inf on a miss), ``prim_id`` int64 (-1 on a miss), ``u``, ``v``
        float32, ``normal`` float32 (N, 3). Hits count where
        tmin < t < tmax; t is along the ray as given. float64 origins keep
        their precision far from the origin; where float32 limits a ray's
        hits, a RuntimeWarning names it."""
        # _t64 (the trimesh drop-in's): t as float64, the traced t plus the
        # origin's move in f64 unrounded, for locations as precise as the trace.
        o, d, lo, hi = _query(origins, directions, tmin, tmax)
        return self._native.trace(o, d, lo, hi, _device(device), _name("intersect", intersect), False, bool(_t64))

    def occluded(self, origins, directions=None, tmin=0.0, tmax=np.inf, *, device="auto",
                 intersect="watertight"):
        """(N,) bool: whether anything lies on each ray with tmin < t < tmax
        (shadow rays: the first hit found ends the search)."""
        o, d, lo, hi = _query(origins, directions, tmin, tmax)
        return self._native.trace(o, d, lo, hi, _device(device), _name("intersect", intersect), True, False)

    def closest_points(self, points, max_distance=np.inf, *, device="auto"):
        """The closest point of the scene's triangles to each of ``points``
        ((N, 3), any float dtype) within ``max_distance``. Returns a dict:
        ``point`` (N, 3) float32, ``prim_id`` int64 (-1 where nothing lies
        within max_distance), ``u``, ``v`` float32 (the point is
        (1-u-v)·v0 + u·v1 + v·v2, as ``intersect``'s), ``distance`` float32
        (inf beyond max_distance). Of triangles at the same distance (a
        point nearest an edge or vertex they share), one is reported.
        float64 points keep their precision far from the origin (``point``
        is float32: take a far location from prim_id, u and v on the
        float64 vertices); where float32 points are too coarse for the
        scene, a RuntimeWarning names the first. So for every point query."""
        p = _floats("points", points)
        return _lambert.closest_points(self._native, p, _max_distance(max_distance), _device(device))

    def distance(self, points, *, device="auto"):
        """(N,) float32: the distance from each point to the nearest triangle."""
        return _lambert.point_values(self._native, _floats("points", points), "distance", "winding", _device(device))

    def signed_distance(self, points, method="winding", *, device="auto"):
        """(N,) float32: the distance to the nearest triangle, negative
        inside. ``method="winding"``: inside where the generalized winding
        number is at least 0.5 in magnitude (closed meshes facing either
        way, and meshes with holes or self-intersections get
        a sensible inside; on the CPU path a closed mesh's sign is taken
        from each point's closest point, the same answer for little more
        than the distance's time: docs/ray-query.md); ``"parity"``: inside
        where a ray from the point crosses the surface an odd number of
        times (watertight meshes)."""
        if method not in ("winding", "parity"):
            raise LambertValueError(f'method={method!r}: use "winding" or "parity"')
        return _lambert.point_values(self._native, _floats("points", points), "signed_distance", method, _device(device))

    def winding_number(self, points, *, device="auto"):
        """(N,) float32: the generalized winding number of the triangles
        about each point (1 inside a closed, outward-facing mesh, -1 facing
        in, 0 outside; within 1e-2 at 1% of the diagonal from the surface,
        fractional near holes)."""
        return _lambert.point_values(self._native, _floats("points", points), "winding_number", "winding", _device(device))

    def contains(self, points, *, device="auto"):
        """(N,) bool: whether each point is inside (|winding number| ≥ 0.5:
        the inside of a closed mesh facing either way)."""
        return _lambert.contains(self._native, _floats("points", points), _device(device))

    def count_intersections(self, origins, directions=None, tmin=0.0, tmax=np.inf, *, device="auto"):
        """(N,) int32: how many times each ray crosses the triangles within
        tmin < t < tmax (rays as for :meth:`intersect`, float64 origins
        traced from f64); a crossing through an edge or vertex that
        triangles share counts once."""
        o, d, lo, hi = _query(origins, directions, tmin, tmax)
        return _lambert.crossings(self._native, o, d, lo, hi, _device(device), False)

    def list_intersections(self, origins, directions=None, tmin=0.0, tmax=np.inf, *, device="auto"):
        """Every crossing of each ray within tmin < t < tmax, sorted by t
        along each ray. Returns a dict: ``ray_splits`` (N + 1,) int64 (ray
        i's crossings are rows ray_splits[i]:ray_splits[i+1]), ``ray_ids``
        int64, ``t`` float32, ``prim_id`` int64, ``u``, ``v`` float32."""
        o, d, lo, hi = _query(origins, directions, tmin, tmax)
        return _lambert.crossings(self._native, o, d, lo, hi, _device(device), True)

    def camera_rays(self, width=None, height=None, *, camera=None):
        """(origins, directions), each (width·height, 3) float32: the
        camera's rays through pixel centres, row-major from the top (unit
        directions), as ``lambert camera-rays`` writes them and ``render``
        shoots at 1 spp. ``camera``: a :class:`Camera`, a glTF camera's
        name, or None (the scene's). Give one of width and height to keep
        the aspect ratio."""
        return _lambert.camera_rays(self._native, render_choices(width, height, camera=camera))

    def render(self, width=None, height=None, *, camera=None, spp=None, target_error=None, max_spp=256,
               time_budget=None, seed=None, ambient=None, shadows=None, integrator=None, max_depth=None,
               environment=None, environment_strength=1.0, environment_rotation=0.0, device="auto",
               progress=None, tile=None):
        """The image, an :class:`Image`: (H, W, 3) float32 linear RGB,
        bit for bit what ``lambert render`` writes with the same choices.

        - ``width``, ``height``: the size (None: the scene's; one alone
          keeps the camera's aspect ratio).
        - ``camera``: a :class:`Camera`, a glTF camera's name (the CLI's
          ``--camera``), or None (the scene's).
        - ``spp``: stratified samples per pixel (None: the scene's
          render.spp, else 1); ``seed``: of the sample jitter.
        - ``target_error``: adaptive sampling until each pixel's standard
          error is below it (at most ``max_spp``); ``time_budget``: as many
          samples as fit in that many seconds.
        - ``ambient`` (a number or (r, g, b)), ``shadows`` (bool): over
          the scene's.
        - ``integrator``: "direct" or "path" (None: the scene's); under
          "path", ``max_depth`` surfaces a path at most.
        - ``environment``: an equirectangular .hdr or .exr file, or a
          colour (r, g, b) (one number: grey), with
          ``environment_strength`` and ``environment_rotation`` (degrees
          about +Y): the CLI's ``--environment*``, replacing the scene's.
        - ``device``: "auto", "gpu" or "cpu".
        - ``progress``: True (a tqdm bar if tqdm is installed, else a text
          bar on stderr) or a callable ``progress(done, total, unit)``.
        - ``tile``: (k, n), part k of n (k from 0): only that band of rows,
          an Image whose ``part`` :func:`merge` reads (``lambert render
          --tile k/n``).
        """
        choices = render_choices(
            width, height, camera=camera, spp=spp, seed=seed, ambient=ambient, shadows=shadows,
            integrator=integrator, max_depth=max_depth, environment=environment,
            environment_strength=environment_strength, environment_rotation=environment_rotation,
        )
        tile = tile_pair(tile)
        budget, target, limit = sampling(spp, target_error, max_spp, time_budget, tile)
        image, part = _lambert.render(
            self._native, choices, budget, target, limit, _device(device), progress_callback(progress), tile
        )
        return Image(image, part=part, scene=self._native)

    def add_point_light(self, position, intensity):
        """Adds a point light, as a TOML ``[[point_light]]``: at world
        ``position`` (x, y, z), of ``intensity`` (a number or (r, g, b);
        irradiance at distance r is intensity / r², the lecture's units).
        A model file's default light and its ambient go, as when the file
        brings lights of its own. Returns the scene."""
        self._native = _lambert.with_light(
            self._native, "point", _point("position", position), None, _colour("intensity", intensity), None
        )
        return self

    def add_directional_light(self, direction, irradiance):
        """Adds a directional light, as a TOML ``[[directional_light]]``:
        travelling along ``direction``, of ``irradiance`` (a number or
        (r, g, b)). Returns the scene."""
        self._native = _lambert.with_light(
            self._native, "directional", None, _point("direction", direction),
            _colour("irradiance", irradiance), None,
        )
        return self

    def add_spot_light(self, position, direction, intensity, inner_angle_deg=0.0, outer_angle_deg=45.0):
        """Adds a spot light, as a TOML ``[[spot_light]]``: at
        ``position``, pointing along ``direction``, ``intensity`` on its
        axis, full within ``inner_angle_deg`` of it and none beyond
        ``outer_angle_deg`` (KHR_lights_punctual's falloff between).
        Returns the scene."""
        angles = (_number("inner_angle_deg", inner_angle_deg), _number("outer_angle_deg", outer_angle_deg))
        self._native = _lambert.with_light(
            self._native, "spot", _point("position", position), _point("direction", direction),
            _colour("intensity", intensity), angles,
        )
        return self

    def device(self, device="auto"):
        """What ``device`` resolves to for this scene, e.g. "GPU: llvmpipe
        (Vulkan, software)" or "CPU reference path (8 threads)"."""
        return self._native.device_name(_device(device))

    triangle_count = _native_property("triangle_count", "int: how many triangles the scene has (its faces' rows).")
    sphere_count = _native_property("sphere_count", "int: how many spheres the scene has (a scene TOML's [[sphere]]s).")
    bounds = _native_property("bounds", "((xmin, ymin, zmin), (xmax, ymax, zmax)), or None when empty.")
    camera = _native_property(
        "camera",
        "dict: the scene's camera: eye, look_at, up (3-tuples of float), vfov (degrees), width, height (int).",
    )

    def __repr__(self):
        return f"<lambert.Scene: {self.triangle_count} triangles, {self.sphere_count} spheres>"


# After Scene: the drop-ins build on it. trimesh and Open3D themselves are
# imported only where a drop-in needs them, so `import lambert` works
# without them.
from . import open3d, trimesh  # noqa: E402
