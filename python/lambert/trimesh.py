"""Drop-ins for trimesh's ray intersector and proximity queries, traced by
lambert.

Switch with one line each::

    mesh.ray = lambert.trimesh.RayMeshIntersector(mesh)
    closest, distance, triangle_id = lambert.trimesh.ProximityQuery(mesh).on_surface(points)

The methods take and return what ``trimesh.ray.ray_pyembree``'s do. Unlike
Embree's, no ray passes between two triangles that share an edge. Multiple
hits are found by raising each ray's tmin past its last hit rather than by
moving its origin, so rounding never makes a ray hit the same triangle
twice; hits within trimesh's own step (1e-6 of the mesh's scale) beyond the
last one are the same point of the surface (a shared edge or vertex) and
count once, as in trimesh.
"""

import numpy as np

from . import Scene
from ._errors import LambertValueError

__all__ = ["ProximityQuery", "RayMeshIntersector"]


def _rays(ray_origins, ray_directions, mesh):
    """float64 origins and unit directions, and which rays are traceable
    (finite, with a non-zero direction, and a mesh with triangles); trimesh
    reports the others as misses rather than raising."""
    o = np.array(ray_origins, dtype=np.float64).reshape(-1, 3)
    d = np.array(ray_directions, dtype=np.float64).reshape(-1, 3)
    if o.shape != d.shape:
        raise LambertValueError("Ray origin and direction don't match!")
    with np.errstate(invalid="ignore", divide="ignore"):
        length = np.linalg.norm(d, axis=1)
        d = d / length[:, None]
    ok = np.isfinite(o).all(axis=1) & np.isfinite(d).all(axis=1) & (length > 0)
    # An empty mesh is no Scene (from_arrays refuses it): every ray misses.
    ok &= len(mesh.faces) > 0
    return o, d, ok


class _Cached:
    """A lambert Scene of a trimesh mesh, built on first use and rebuilt
    if the mesh changes."""

    def __init__(self, geometry, device="auto"):
        self.mesh = geometry
        self.device = device
        self._built = None

    @property
    def _scene(self):
        key = hash(self.mesh)
        if self._built is None or self._built[0] != key:
            self._built = (key, Scene.from_arrays(self.mesh.vertices, self.mesh.faces))
        return self._built[1]


class RayMeshIntersector(_Cached):
    """Ray queries on a ``trimesh.Trimesh``, on lambert's GPU path or its
    CPU path (``device="auto"`` takes a GPU when there is a hardware one).
    The scene is built on first use and rebuilt if the mesh changes."""

    def intersects_first(self, ray_origins, ray_directions):
        """(n,) int: the index of the first triangle each ray hits, -1 for none."""
        o, d, ok = _rays(ray_origins, ray_directions, self.mesh)
        prim = np.full(len(o), -1, dtype=np.int64)
        if ok.any():
            prim[ok] = self._scene.intersect(o[ok], d[ok], device=self.device)["prim_id"]
        return prim

    def intersects_any(self, ray_origins, ray_directions):
        """(n,) bool: whether each ray hits the mesh."""
        o, d, ok = _rays(ray_origins, ray_directions, self.mesh)
        hit = np.zeros(len(o), dtype=bool)
        if ok.any():
            hit[ok] = self._scene.occluded(o[ok], d[ok], device=self.device)
        return hit

    def intersects_id(self, ray_origins, ray_directions, multiple_hits=True, max_hits=100,
                      return_locations=False):
        """(index_tri, index_ray[, locations]): the triangles each ray hits
        (every hit along it with ``multiple_hits``, at most ``max_hits``),
        ordered as trimesh's: all first hits, then all second hits, and so on."""
        o, d, ok = _rays(ray_origins, ray_directions, self.mesh)
        tris, rays, locations = [], [], []
        live = np.flatnonzero(ok)
        step = max(1e-8, 1e-6 * float(self.mesh.scale)) if len(live) else 0.0
        # t and tmin in float64: a sensor far from the mesh has a long t
        # that float32 would round by more than the mesh's precision.
        tmin = np.zeros(len(live), dtype=np.float64)
        for _ in range(max_hits if multiple_hits else 1):
            if len(live) == 0:
                break
            hits = self._scene.intersect(o[live], d[live], tmin, device=self.device, _t64=True)
            hit = hits["prim_id"] >= 0
            live, t = live[hit], hits["t"][hit]
            tris.append(hits["prim_id"][hit])
            rays.append(live)
            locations.append(o[live] + d[live] * t[:, None])
            # The next hit lies beyond this one on the same ray (hits count
            # where t > tmin), past the other triangles at this edge or vertex.
            tmin = t + step
        index_tri = np.concatenate(tris) if tris else np.zeros(0, dtype=np.int64)
        index_ray = np.concatenate(rays) if rays else np.zeros(0, dtype=np.int64)
        if return_locations:
            loc = np.concatenate(locations) if locations else np.zeros((0, 3))
            return index_tri, index_ray, loc
        return index_tri, index_ray

    def intersects_location(self, ray_origins, ray_directions, multiple_hits=True):
        """(locations, index_ray, index_tri): where the rays hit the mesh."""
        index_tri, index_ray, locations = self.intersects_id(
            ray_origins, ray_directions, multiple_hits=multiple_hits, return_locations=True
        )
        return locations, index_ray, index_tri

    def contains_points(self, points):
        """(n,) bool: whether each point lies inside the (closed) mesh, by
        trimesh's own ray-parity test over this intersector."""
        from trimesh.ray.ray_util import contains_points

        if len(self.mesh.faces) == 0:
            # Nothing is inside an empty mesh (trimesh's test needs bounds).
            return np.zeros(len(np.asarray(points, dtype=np.float64).reshape(-1, 3)), dtype=bool)
        return contains_points(self, points)


def _points(points):
    """float64 (n, 3) points, as trimesh's proximity functions take them."""
    p = np.asanyarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise LambertValueError("points must be (n,3)!")
    return p


class ProximityQuery(_Cached):
    """trimesh's ``ProximityQuery`` (``mesh.nearest``) on lambert's closest
    points, on its GPU path or its CPU path (``device="auto"`` takes a
    GPU when there is a hardware one).

    Where it differs from trimesh:

    - ``on_surface``: the closest point is found in float32 and returned
      as (1-u-v)·v0 + u·v1 + v·v2 of the triangle found, evaluated in
      float64 (trimesh's is float64 throughout): on a mesh of size 1 it is
      within about 1e-7 of trimesh's, far from the origin too (the points
      go in as float64, moved into the mesh's frame before float32). Of triangles equally near (a point
      nearest an edge or vertex they share) one is reported; trimesh
      prefers the one whose normal faces the point most.
    - ``signed_distance`` signs by the generalized winding number (inside
      where it is at least 0.5 in magnitude) rather than by the closest
      triangle's normal and ray parity: meshes with holes or
      self-intersections get a sensible inside, and on a closed mesh it
      is positive where ``mesh.contains`` (trimesh's ray test) says
      inside, whichever way the faces point (trimesh's own, signing by
      normals that point in, disagrees with its ``contains`` there). The sign is trimesh's: positive inside, negative
      outside; the distance is ``on_surface``'s, in float64.
    - ``vertex`` is trimesh's own (a k-d tree over the vertices, which
      needs scipy): lambert has no nearest-vertex query.
    - A point with a non-finite coordinate is a ``ValueError`` naming its
      row; on a mesh with no faces ``on_surface`` and ``signed_distance``
      raise ``ValueError`` too (trimesh's fail on an empty array).
    """

    def on_surface(self, points):
        """(closest (n, 3) float64, distance (n,) float64, triangle_id (n,)
        int64): the closest point of the mesh to each point."""
        p = _points(points)
        found = self._scene.closest_points(p, device=self.device)
        triangle_id = found["prim_id"]
        corners = np.asarray(self.mesh.vertices, dtype=np.float64)[np.asarray(self.mesh.faces)[triangle_id]]
        u, v = found["u"].astype(np.float64), found["v"].astype(np.float64)
        closest = (1 - u - v)[:, None] * corners[:, 0] + u[:, None] * corners[:, 1] + v[:, None] * corners[:, 2]
        return closest, np.linalg.norm(p - closest, axis=1), triangle_id

    def signed_distance(self, points):
        """(n,) float64: the distance to the mesh, positive inside (trimesh's sign)."""
        p = _points(points)
        distance = self.on_surface(p)[1]
        return np.where(self._scene.contains(p, device=self.device), distance, -distance)

    def vertex(self, points):
        """(distance (n,) float64, vertex_id (n,) int): the nearest vertex
        to each point, by trimesh's own k-d tree."""
        return self.mesh.kdtree.query(points)
