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

import operator
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

__all__ = ["RAY_DTYPE", "Scene", "open3d", "trimesh", "write_image"]

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
        raise ValueError(f"{name} must be a real-valued (N, 3) array, not {a.dtype}")
    if a.dtype not in (np.float32, np.float64):
        a = a.astype(np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} has shape {a.shape}; it must be (N, 3)")
    return a


def _bound(name, value, n):
    """tmin or tmax: a Python float, or a (N,) float32 or float64 array
    (float64 is kept for float64 origins, traced from f64)."""
    a = np.asarray(value)
    if a.dtype.kind not in "fiub":
        raise ValueError(f"{name} must be a number or a (N,) array, not {a.dtype}")
    if a.ndim == 0:
        return float(a)
    if a.ndim != 1 or a.shape[0] != n:
        raise ValueError(f"{name} has shape {a.shape}; give a scalar or one value per ray ({n},)")
    return a if a.dtype == np.float64 else a.astype(np.float32, copy=False)


def _count(name, value):
    """A width, height or sample count: None, or a whole number that fits
    (the native module says what range it takes)."""
    if value is None:
        return None
    try:
        n = operator.index(value)
    except TypeError:
        raise TypeError(f"{name} must be a whole number, not {type(value).__name__}") from None
    if n < 0:
        raise ValueError(f"{name} = {n}: must be a positive whole number")
    if n > 0xFFFFFFFF:
        raise ValueError(f"{name} = {n} is too large")
    return n


def _max_distance(value):
    """A closest-point query's reach: a number ≥ 0, inf for no limit."""
    try:
        d = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"max_distance must be a number, not {type(value).__name__}") from None
    if not d >= 0.0:
        raise ValueError(f"max_distance = {d}: must be a number ≥ 0 (inf for no limit)")
    return d


def _albedo(albedo):
    """One colour for the whole mesh: a number (grey) or (r, g, b)."""
    if albedo is None:
        return None
    a = np.asarray(albedo, dtype=np.float64)
    if a.shape not in ((), (1,), (3,)):
        raise ValueError(
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
            raise ValueError(
                "with no directions, the first argument must be an array of lambert.RAY_DTYPE "
                f"records, not {records.dtype}"
            )
        if not (np.isscalar(tmin) and tmin == 0.0 and np.isscalar(tmax) and tmax == np.inf):
            raise ValueError("ray records carry their own tmin and tmax; do not pass them too")
        records = np.ascontiguousarray(records.reshape(-1))
        return records.view(np.float32).reshape(-1, 8), None, 0.0, 0.0
    o = _floats("origins", origins)
    d = _floats("directions", directions)
    if o.shape[0] != d.shape[0]:
        raise ValueError(f"{o.shape[0]} origins but {d.shape[0]} directions")
    return o, d, _bound("tmin", tmin, o.shape[0]), _bound("tmax", tmax, o.shape[0])


def _native_property(name, doc=None):
    """A read-only property of :class:`Scene`: its native scene's ``name``."""
    return property(lambda self: getattr(self._native, name), doc=doc)


class Scene:
    """Triangles (and, from a scene file, spheres, materials, lights and a
    camera), resident for queries and renders.

    Build one with :meth:`from_arrays` or :meth:`load`. Tracing releases the
    GIL; several threads may query one Scene at once.
    """

    __slots__ = ("_native", "__weakref__")

    def __init__(self, native):
        if not isinstance(native, _lambert.NativeScene):
            raise TypeError("use Scene.from_arrays(vertices, faces) or Scene.load(path)")
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
            raise ValueError(f"vertices must be a float array, not {v.dtype}")
        f = np.asarray(faces)
        # An empty list is float64 to numpy; the no-triangles error below fits it better.
        if f.dtype.kind not in "iu" and f.size:
            raise ValueError(f"faces must be an integer array, not {f.dtype}")
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices has shape {v.shape}; it must be (V, 3)")
        if f.ndim != 2 or f.shape[1] != 3:
            raise ValueError(f"faces has shape {f.shape}; it must be (F, 3)")
        if f.dtype == np.uint64 and f.size and f.max() > np.iinfo(np.int64).max:
            row = int(np.argmax(f.max(axis=1) > np.iinfo(np.int64).max))
            raise ValueError(f"faces row {row} = {f[row].tolist()}: index out of range")
        native = _lambert.NativeScene.from_arrays(
            v.astype(np.float64, copy=False), f.astype(np.int64, copy=False), _albedo(albedo)
        )
        return cls(native)

    @classmethod
    def load(cls, path):
        """A scene TOML file, or any model file the CLI reads alone (.obj,
        .ply, .ply.gz, .gltf, .glb, .stl). Raises OSError for a file that cannot
        be read, ValueError (naming file and line or field) for bad content."""
        return cls(_lambert.NativeScene.load(os.fspath(path)))

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
        return self._native.trace(o, d, lo, hi, device, intersect, False, bool(_t64))

    def occluded(self, origins, directions=None, tmin=0.0, tmax=np.inf, *, device="auto",
                 intersect="watertight"):
        """(N,) bool: whether anything lies on each ray with tmin < t < tmax
        (shadow rays: the first hit found ends the search)."""
        o, d, lo, hi = _query(origins, directions, tmin, tmax)
        return self._native.trace(o, d, lo, hi, device, intersect, True, False)

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
        return _lambert.closest_points(self._native, p, _max_distance(max_distance), device)

    def distance(self, points, *, device="auto"):
        """(N,) float32: the distance from each point to the nearest triangle."""
        return _lambert.point_values(self._native, _floats("points", points), "distance", "winding", device)

    def signed_distance(self, points, method="winding", *, device="auto"):
        """(N,) float32: the distance to the nearest triangle, negative
        inside. ``method="winding"``: inside where the generalized winding
        number is at least 0.5 in magnitude (closed meshes facing either
        way, and meshes with holes or self-intersections get
        a sensible inside); ``"parity"``: inside where a ray from the point
        crosses the surface an odd number of times (watertight meshes)."""
        if method not in ("winding", "parity"):
            raise ValueError(f'method={method!r}: use "winding" or "parity"')
        return _lambert.point_values(self._native, _floats("points", points), "signed_distance", method, device)

    def winding_number(self, points, *, device="auto"):
        """(N,) float32: the generalized winding number of the triangles
        about each point (1 inside a closed, outward-facing mesh, -1 facing
        in, 0 outside; within 1e-2 at 1% of the diagonal from the surface,
        fractional near holes)."""
        return _lambert.point_values(self._native, _floats("points", points), "winding_number", "winding", device)

    def contains(self, points, *, device="auto"):
        """(N,) bool: whether each point is inside (|winding number| ≥ 0.5:
        the inside of a closed mesh facing either way)."""
        return _lambert.contains(self._native, _floats("points", points), device)

    def count_intersections(self, origins, directions=None, tmin=0.0, tmax=np.inf, *, device="auto"):
        """(N,) int32: how many times each ray crosses the triangles within
        tmin < t < tmax (rays as for :meth:`intersect`, float64 origins
        traced from f64); a crossing through an edge or vertex that
        triangles share counts once."""
        o, d, lo, hi = _query(origins, directions, tmin, tmax)
        return _lambert.crossings(self._native, o, d, lo, hi, device, False)

    def list_intersections(self, origins, directions=None, tmin=0.0, tmax=np.inf, *, device="auto"):
        """Every crossing of each ray within tmin < t < tmax, sorted by t
        along each ray. Returns a dict: ``ray_splits`` (N + 1,) int64 (ray
        i's crossings are rows ray_splits[i]:ray_splits[i+1]), ``ray_ids``
        int64, ``t`` float32, ``prim_id`` int64, ``u``, ``v`` float32."""
        o, d, lo, hi = _query(origins, directions, tmin, tmax)
        return _lambert.crossings(self._native, o, d, lo, hi, device, True)

    def camera_rays(self, width=None, height=None):
        """(origins, directions), each (width·height, 3) float32: the scene
        camera's rays through pixel centres, row-major from the top (unit
        directions). Give one of width and height to keep the aspect ratio."""
        return self._native.camera_rays(_count("width", width), _count("height", height))

    def render(self, width=None, height=None, spp=1, device="auto", integrator=None, max_depth=None):
        """The image, (H, W, 3) float32 linear RGB, ``spp`` stratified
        samples per pixel. ``integrator``: "direct" (Lambert shading from
        the scene's lights with shadows) or "path" (path tracing: physically
        based materials, area lights, the environment, bounced light, at
        most ``max_depth`` surfaces a path); None: the scene's own
        (render.integrator, else "direct")."""
        return self._native.render(
            _count("width", width),
            _count("height", height),
            _count("spp", spp),
            device,
            integrator,
            _count("max_depth", max_depth),
        )

    def device(self, device="auto"):
        """What ``device`` resolves to for this scene, e.g. "GPU: llvmpipe
        (Vulkan, software)" or "CPU reference path (8 threads)"."""
        return self._native.device_name(device)

    triangle_count = _native_property("triangle_count")
    sphere_count = _native_property("sphere_count")
    bounds = _native_property("bounds", "((xmin, ymin, zmin), (xmax, ymax, zmax)), or None when empty.")
    camera = _native_property("camera", "The scene's camera: eye, look_at, up, vfov (degrees), width, height.")

    def __repr__(self):
        return f"<lambert.Scene: {self.triangle_count} triangles, {self.sphere_count} spheres>"


def write_image(path, image):
    """Writes a linear-RGB (H, W, 3) image as .png (8-bit sRGB), .exr or .pfm
    (float32), chosen by the extension, atomically: a failed write leaves no
    partial file and any previous one untouched."""
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"image has shape {a.shape}; it must be (H, W, 3)")
    path = os.fspath(path)
    # A file where a folder of the path should be: the native write would
    # fail creating the folder, with the OS's bare "File exists".
    folder = os.path.dirname(os.path.abspath(path))
    while not os.path.exists(folder):
        folder = os.path.dirname(folder)
    if not os.path.isdir(folder):
        raise NotADirectoryError(f"{path}: cannot write there: {folder} is not a folder")
    _lambert.write_image(path, np.ascontiguousarray(a, dtype=np.float32))


# After Scene: the drop-ins build on it. trimesh and Open3D themselves are
# imported only where a drop-in needs them, so `import lambert` works
# without them.
from . import open3d, trimesh  # noqa: E402
