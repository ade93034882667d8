"""A drop-in for Open3D's ``open3d.t.geometry.RaycastingScene``, traced by
lambert on the GPU or the CPU path.

Switch with one line::

    scene = lambert.open3d.RaycastingScene()     # was o3d.t.geometry.RaycastingScene()
    mesh_id = scene.add_triangles(mesh)          # or add_triangles(vertices, triangles)
    ans = scene.cast_rays(rays)                  # (..., 6) rays: ox oy oz dx dy dz

The methods, their arguments and defaults, the result keys, shapes and
dtypes are Open3D's (0.20): ``add_triangles``, ``cast_rays``,
``test_occlusions``, ``count_intersections``, ``list_intersections``,
``compute_closest_points``, ``compute_distance``,
``compute_signed_distance``, ``compute_occupancy``, ``INVALID_ID``, and
``create_rays_pinhole`` (Open3D's own, when Open3D is installed). Arrays in
are numpy arrays or, when Open3D is installed, its tensors; results come
back as Open3D tensors where the input was one, else as numpy arrays
that also have Open3D's ``.numpy()`` (a plain view of themselves), so
that Open3D's idiom ``scene.cast_rays(np_rays)["t_hit"].numpy()`` runs
unchanged and numpy code keeps its arrays. Barycentrics are Open3D's and
Embree's, which are lambert's: the point is (1-u-v)·v0 + u·v1 + v·v2.

Where it differs from Open3D:

- Inside (``compute_signed_distance``, ``compute_occupancy``) is where the
  generalized winding number is at least 0.5 in magnitude
  (``method="winding"``, the default), which agrees with Open3D's ray
  parity on closed meshes whose bodies do not overlap, facing out or in
  (where two bodies facing the same way overlap it is inside, parity
  outside), and stays sensible on meshes with holes or
  self-intersections; give
  ``method="parity"`` for a parity count as Open3D does. ``nsamples`` is
  checked as Open3D checks it (odd, at least 1) but needs no votes: the
  winding number has no edge cases, and lambert's watertight crossings
  count an edge or vertex once.
- ``list_intersections`` lists each ray's crossings sorted by t (Open3D's
  come in traversal order), and a crossing through an edge or vertex that
  triangles share counts once, in ``count_intersections`` too.
- Hits count where t > 0 (Open3D's tnear = 0 includes t = 0).
- Any finite non-zero direction is traced, however long or short (1e-30
  or 1e20): one of a length outside 1e-6 to 1e6 is normalised in float64
  and t given back in units of its length, as Open3D's. A ray with a non-finite value or a zero direction
  misses; a ray the native checks refuse (an origin too far from the
  scene) is a ``ValueError`` naming its row in ``rays.reshape(-1, 6)``;
  so is a query point with a non-finite coordinate.
- On an empty scene, closest points have ``INVALID_ID`` ids and distances
  are inf (Open3D gives the distance to the origin).
- ``nthreads`` is accepted and ignored: lambert uses all cores (rayon's
  pool), or the GPU. ``device``: lambert's ``"auto"``, ``"gpu"`` or
  ``"cpu"`` (an Open3D ``Device`` maps CPU to ``"cpu"``, SYCL to ``"gpu"``).
- Vertices may be any float dtype and triangles any integer dtype (Open3D
  takes float32 and uint32 only); vertices are rounded to float32 as
  Open3D stores them.
"""

import numpy as np

from . import Scene
from ._errors import LambertTypeError, LambertValueError

__all__ = ["INVALID_ID", "RaycastingScene"]

#: Open3D's id for no geometry or primitive (Embree's RTC_INVALID_GEOMETRY_ID).
INVALID_ID = 0xFFFFFFFF


#: Direction lengths traced as given; shorter or longer ones are normalised
#: in float64 first (f32 squares of them would under- or overflow).
_USUAL_LENGTH = (1e-6, 1e6)


def _is_tensor(x):
    """Whether `x` is an Open3D tensor (without importing Open3D)."""
    return type(x).__module__.startswith("open3d") and hasattr(x, "numpy")


def _numpy(x, name, last):
    """`x` as a numpy array whose last axis has `last` values, and whether
    it was an Open3D tensor."""
    tensor = _is_tensor(x)
    a = x.numpy() if tensor else np.asarray(x)
    if a.dtype.kind not in "fiu":
        raise LambertValueError(f"{name} must be a real-valued (..., {last}) array, not {a.dtype}")
    if a.ndim < 2 or a.shape[-1] != last:
        raise LambertValueError(f"{name} has shape {a.shape}; it must be (..., {last}) with at least 2 dims")
    return a, tensor


class Result(np.ndarray):
    """A result array for numpy input: numpy's, with Open3D's
    ``Tensor.numpy()``, so that code written for Open3D runs unchanged."""

    def numpy(self):
        """This array as a plain numpy array (a view), as Open3D's."""
        return self.view(np.ndarray)


def _out(values, tensor):
    """A result as numpy (with ``.numpy()``), or as an Open3D tensor where
    the input was one."""
    if not tensor:
        if isinstance(values, dict):
            return {k: v.view(Result) for k, v in values.items()}
        return values.view(Result)
    import open3d

    if isinstance(values, dict):
        return {k: open3d.core.Tensor.from_numpy(np.ascontiguousarray(v)) for k, v in values.items()}
    return open3d.core.Tensor.from_numpy(np.ascontiguousarray(values))


def _device(device):
    """lambert's device for a string or an Open3D Device."""
    if isinstance(device, str) and device in ("auto", "gpu", "cpu"):
        return device
    kind = str(device).split(":")[0].upper()
    if kind == "CPU":
        return "cpu"
    if kind in ("SYCL", "CUDA"):
        return "gpu"
    raise LambertValueError(f'device={device!r}: use "auto", "gpu", "cpu" or an Open3D CPU or SYCL device')


def _check_nsamples(nsamples):
    if not (isinstance(nsamples, (int, np.integer)) and nsamples >= 1 and nsamples % 2 == 1):
        raise LambertValueError(f"nsamples must be odd and >= 1 but is {nsamples}")


class RaycastingScene:
    """Open3D's RaycastingScene over lambert (see the module's docstring
    for where it differs). Each ``add_triangles`` call adds one geometry,
    numbered from 0; the scene is built on the first query after it."""

    INVALID_ID = INVALID_ID

    def __init__(self, nthreads=0, device="auto"):
        self._device = _device(device)
        self._vertices = []
        self._triangles = []
        # First primitive of each geometry in the combined scene, and the total.
        self._starts = np.zeros(1, dtype=np.int64)
        self._built = None

    def add_triangles(self, vertex_positions=None, triangle_indices=None, *, mesh=None):
        """Adds a triangle mesh, ``(vertex_positions, triangle_indices)``
        ((V, 3) floats, (F, 3) integers) or an Open3D ``TriangleMesh`` (of
        ``open3d.t.geometry`` or the legacy ``open3d.geometry``); returns
        its geometry id."""
        if mesh is None and triangle_indices is None:
            mesh = vertex_positions
        if mesh is not None:
            if hasattr(mesh, "vertex") and hasattr(mesh, "triangle"):
                vertex_positions, triangle_indices = mesh.vertex.positions, mesh.triangle.indices
            elif hasattr(mesh, "vertices") and hasattr(mesh, "triangles"):
                vertex_positions, triangle_indices = mesh.vertices, mesh.triangles
            else:
                raise LambertTypeError(f"add_triangles takes (vertex_positions, triangle_indices) or a mesh, "
                                f"not {type(mesh).__name__}")
        v, _ = _numpy(vertex_positions, "vertex_positions", 3)
        f, _ = _numpy(triangle_indices, "triangle_indices", 3)
        if v.ndim != 2 or f.ndim != 2:
            raise LambertValueError(f"vertex_positions {v.shape} and triangle_indices {f.shape} must be (N, 3)")
        if f.dtype.kind not in "iu" and f.size:
            raise LambertValueError(f"triangle_indices must be integers, not {f.dtype}")
        v = v.astype(np.float32)
        if not np.isfinite(v).all():
            row = int(np.flatnonzero(~np.isfinite(v).all(axis=1))[0])
            raise LambertValueError(f"vertex_positions row {row} = {v[row].tolist()}: not finite")
        f = f.astype(np.int64)
        if f.size and (f.min() < 0 or f.max() >= len(v)):
            row = int(np.flatnonzero(((f < 0) | (f >= len(v))).any(axis=1))[0])
            raise LambertValueError(f"triangle_indices row {row} = {f[row].tolist()}: index out of range "
                             f"({len(v)} vertices)")
        self._vertices.append(v)
        self._triangles.append(f)
        self._starts = np.append(self._starts, self._starts[-1] + len(f))
        self._built = None
        return len(self._triangles) - 1

    def _combined(self):
        """The combined lambert Scene, vertices and faces (numbered across
        the geometries in order), or None while there are no triangles."""
        if self._built is None and self._starts[-1] > 0:
            first = np.cumsum([0] + [len(v) for v in self._vertices[:-1]])
            faces = np.concatenate([f + k for f, k in zip(self._triangles, first)])
            vertices = np.concatenate(self._vertices)
            self._built = (Scene.from_arrays(vertices, faces), vertices, faces)
        return self._built

    @property
    def _scene(self):
        built = self._combined()
        return None if built is None else built[0]

    def _ids(self, prim):
        """Geometry and primitive ids (uint32, INVALID_ID for -1) of lambert's prim ids."""
        hit = prim >= 0
        geometry = np.searchsorted(self._starts, prim, side="right") - 1
        local = prim - self._starts[np.clip(geometry, 0, None)]
        return (np.where(hit, geometry, INVALID_ID).astype(np.uint32),
                np.where(hit, local, INVALID_ID).astype(np.uint32))

    def _rays(self, rays):
        """Flat origins, directions to trace (normalised in float64 where
        their length is out of the usual, so that any finite non-zero
        length traces), the caller's direction lengths in units of the
        traced ones' (the caller's t is the traced t over it), the
        result shape and whether they came as a tensor; None for the
        directions when nothing can be hit (an empty scene). A ray that
        cannot be traced (a non-finite value, a zero direction) becomes
        one with an empty t interval, which the native queries answer as
        a miss: every ray keeps its row, so that an error names the
        caller's."""
        a, tensor = _numpy(rays, "rays", 6)
        shape = a.shape[:-1]
        flat = a.reshape(-1, 6)
        o = flat[:, :3].astype(np.float32)
        d = flat[:, 3:].astype(np.float64)
        with np.errstate(invalid="ignore", over="ignore"):
            # Scaled by the largest component first: no square over- or underflows.
            scale = np.abs(d).max(axis=1)
            unit = d / scale[:, None]
            norm = np.sqrt((unit * unit).sum(axis=1))
            length = scale * norm
            unit /= norm[:, None]
        ok = np.isfinite(flat).all(axis=1) & np.isfinite(o).all(axis=1) & (scale > 0)
        # Directions of an ordinary length are traced as given (the native
        # queries' bits); only the others need the normalising.
        usual = ok & (length >= _USUAL_LENGTH[0]) & (length <= _USUAL_LENGTH[1])
        traced = np.where(usual[:, None], d, unit)
        length[usual] = 1
        o[~ok] = 0
        traced[~ok] = (1, 0, 0)
        length[~ok] = 1
        if self._scene is None:
            traced = None
        return o, traced, length, ok, shape, tensor

    def _points(self, query_points):
        a, tensor = _numpy(query_points, "query_points", 3)
        return a.reshape(-1, 3).astype(np.float32, copy=False), a.shape[:-1], tensor

    def cast_rays(self, rays, nthreads=0):
        """The first hit of each ray: ``t_hit`` (inf on a miss),
        ``geometry_ids``, ``primitive_ids`` (uint32, INVALID_ID on a miss),
        ``primitive_uvs`` (..., 2) and ``primitive_normals`` (..., 3, unit,
        zero on a miss)."""
        o, d, length, ok, shape, tensor = self._rays(rays)
        n = len(o)
        t = np.full(n, np.inf, dtype=np.float32)
        prim = np.full(n, -1, dtype=np.int64)
        uv = np.zeros((n, 2), dtype=np.float32)
        normal = np.zeros((n, 3), dtype=np.float32)
        if d is not None:
            hits = self._scene.intersect(o, d, 0.0, np.where(ok, np.inf, 0.0), device=self._device)
            t = (hits["t"] / length).astype(np.float32)
            prim = hits["prim_id"]
            uv = np.stack([hits["u"], hits["v"]], axis=-1)
            ng = hits["normal"]
            with np.errstate(invalid="ignore", divide="ignore"):
                unit = ng / np.sqrt((ng * ng).sum(axis=1, dtype=np.float32))[:, None]
            normal = np.where(prim[:, None] >= 0, unit, 0).astype(np.float32)
        geometry, primitive = self._ids(prim)
        return _out({"t_hit": t.reshape(shape), "geometry_ids": geometry.reshape(shape),
                     "primitive_ids": primitive.reshape(shape),
                     "primitive_uvs": uv.reshape(shape + (2,)),
                     "primitive_normals": normal.reshape(shape + (3,))}, tensor)

    def test_occlusions(self, rays, tnear=0.0, tfar=np.inf, nthreads=0):
        """(...) bool: whether anything lies on each ray with tnear < t < tfar."""
        o, d, length, ok, shape, tensor = self._rays(rays)
        hit = np.zeros(len(o), dtype=bool)
        if d is not None:
            # tnear and tfar in the caller's units, as the traced rays' t.
            with np.errstate(invalid="ignore", over="ignore"):
                lo, hi = float(tnear) * length, float(tfar) * length
            hit = self._scene.occluded(o, d, np.where(ok, lo, 0.0), np.where(ok, hi, 0.0),
                                       device=self._device)
        return _out(hit.reshape(shape), tensor)

    def count_intersections(self, rays, nthreads=0):
        """(...) int32: how many times each ray crosses the triangles."""
        o, d, _, ok, shape, tensor = self._rays(rays)
        count = np.zeros(len(o), dtype=np.int32)
        if d is not None:
            count = self._scene.count_intersections(o, d, 0.0, np.where(ok, np.inf, 0.0),
                                                    device=self._device)
        return _out(count.reshape(shape), tensor)

    def list_intersections(self, rays, nthreads=0):
        """Every crossing: ``ray_splits`` (rays + 1,), ``ray_ids``,
        ``t_hit``, ``geometry_ids``, ``primitive_ids`` (uint32) and
        ``primitive_uvs`` (hits, 2), each ray's crossings sorted by t."""
        o, d, length, ok, _, tensor = self._rays(rays)
        listed = {"ray_splits": np.zeros(len(o) + 1, dtype=np.int64),
                  "ray_ids": np.zeros(0, dtype=np.int64), "t": np.zeros(0, dtype=np.float32),
                  "prim_id": np.zeros(0, dtype=np.int64), "u": np.zeros(0, dtype=np.float32),
                  "v": np.zeros(0, dtype=np.float32)}
        if d is not None:
            listed = self._scene.list_intersections(o, d, 0.0, np.where(ok, np.inf, 0.0),
                                                    device=self._device)
        geometry, primitive = self._ids(listed["prim_id"])
        t = (listed["t"] / length[listed["ray_ids"]]).astype(np.float32)
        return _out({"ray_splits": listed["ray_splits"].astype(np.uint32),
                     "ray_ids": listed["ray_ids"].astype(np.uint32),
                     "t_hit": t, "geometry_ids": geometry, "primitive_ids": primitive,
                     "primitive_uvs": np.stack([listed["u"], listed["v"]], axis=-1)}, tensor)

    def compute_closest_points(self, query_points, nthreads=0):
        """The closest point on the triangles to each query point:
        ``points`` (..., 3), ``geometry_ids``, ``primitive_ids`` (uint32),
        ``primitive_uvs`` (..., 2), ``primitive_normals`` (..., 3, unit)."""
        p, shape, tensor = self._points(query_points)
        n = len(p)
        points = np.zeros((n, 3), dtype=np.float32)
        prim = np.full(n, -1, dtype=np.int64)
        uv = np.zeros((n, 2), dtype=np.float32)
        normal = np.zeros((n, 3), dtype=np.float32)
        built = self._combined()
        if built is not None:
            scene, vertices, faces = built
            found = scene.closest_points(p, device=self._device)
            points, prim = found["point"], found["prim_id"]
            uv = np.stack([found["u"], found["v"]], axis=-1)
            # The triangle's unit normal, as Open3D gives it (in float32).
            tri = vertices[faces[prim]]
            ng = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            with np.errstate(invalid="ignore", divide="ignore"):
                normal = ng / np.sqrt((ng * ng).sum(axis=1))[:, None]
        geometry, primitive = self._ids(prim)
        return _out({"points": points.reshape(shape + (3,)), "geometry_ids": geometry.reshape(shape),
                     "primitive_ids": primitive.reshape(shape), "primitive_uvs": uv.reshape(shape + (2,)),
                     "primitive_normals": normal.reshape(shape + (3,))}, tensor)

    def compute_distance(self, query_points, nthreads=0):
        """(...) float32: the distance from each query point to the triangles."""
        p, shape, tensor = self._points(query_points)
        scene = self._scene
        d = np.full(len(p), np.inf, dtype=np.float32) if scene is None else scene.distance(p, device=self._device)
        return _out(d.reshape(shape), tensor)

    def compute_signed_distance(self, query_points, nthreads=0, nsamples=1, *, method="winding"):
        """(...) float32: the distance to the triangles, negative inside
        (see the module's docstring for ``method``)."""
        _check_nsamples(nsamples)
        p, shape, tensor = self._points(query_points)
        scene = self._scene
        if scene is None:
            d = np.full(len(p), np.inf, dtype=np.float32)
        else:
            d = scene.signed_distance(p, method=method, device=self._device)
        return _out(d.reshape(shape), tensor)

    def compute_occupancy(self, query_points, nthreads=0, nsamples=1, *, method="winding"):
        """(...) float32: 1 where a query point is inside, else 0."""
        _check_nsamples(nsamples)
        p, shape, tensor = self._points(query_points)
        scene = self._scene
        if scene is None:
            inside = np.zeros(len(p), dtype=bool)
        elif method == "winding":
            inside = scene.contains(p, device=self._device)
        else:
            # The sign bit: a point on the surface has distance -0.0 inside.
            inside = np.signbit(scene.signed_distance(p, method=method, device=self._device))
        return _out(inside.astype(np.float32).reshape(shape), tensor)

    @staticmethod
    def create_rays_pinhole(*args, **kwargs):
        """Open3D's own ``RaycastingScene.create_rays_pinhole`` (rays for a
        pinhole camera, as an Open3D tensor); needs Open3D."""
        import open3d

        return open3d.t.geometry.RaycastingScene.create_rays_pinhole(*args, **kwargs)
