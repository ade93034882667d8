"""Brute-force float64 references for the proximity and crossing queries:
every point against every triangle, in numpy, written from the textbook
formulas rather than from lambert's code."""

import numpy as np


def _on_segment(p, s0, s1):
    """The point of segment s0 s1 nearest p, and its parameter (0 at s0)."""
    e = s1 - s0
    ee = (e * e).sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(ee > 0, ((p - s0) * e).sum(-1) / ee, 0.0)
    t = np.clip(t, 0.0, 1.0)
    return s0 + t[..., None] * e, t


def closest_on_triangles(p, a, b, c):
    """The point of each triangle (a, b, c) nearest each p (all (..., 3)
    broadcast together) and its weights u (of b) and v (of c): the
    projection onto the plane where it falls inside the triangle, else the
    nearest of the three edges' nearest points (so degenerate triangles
    are their edges)."""
    ab, ac = b - a, c - a
    n = np.cross(ab, ac)
    nn = (n * n).sum(-1)
    # Barycentrics of the projection, by areas against the normal.
    with np.errstate(invalid="ignore", divide="ignore"):
        ap = p - a
        u_in = (np.cross(ap, ac) * n).sum(-1) / nn
        v_in = (np.cross(ab, ap) * n).sum(-1) / nn
    inside = (nn > 0) & (u_in >= 0) & (v_in >= 0) & (u_in + v_in <= 1)
    candidates = []
    q_ab, t_ab = _on_segment(p, a, b)
    candidates.append((q_ab, t_ab, 0 * t_ab))
    q_ac, t_ac = _on_segment(p, a, c)
    candidates.append((q_ac, 0 * t_ac, t_ac))
    q_bc, t_bc = _on_segment(p, b, c)
    candidates.append((q_bc, 1 - t_bc, t_bc))
    point, u, v = candidates[0]
    best = ((point - p) ** 2).sum(-1)
    for q, cu, cv in candidates[1:]:
        d = ((q - p) ** 2).sum(-1)
        nearer = d < best
        point = np.where(nearer[..., None], q, point)
        u, v, best = np.where(nearer, cu, u), np.where(nearer, cv, v), np.where(nearer, d, best)
    projection = a + np.nan_to_num(u_in)[..., None] * ab + np.nan_to_num(v_in)[..., None] * ac
    point = np.where(inside[..., None], projection, point)
    u, v = np.where(inside, u_in, u), np.where(inside, v_in, v)
    return point, u, v


def closest_points(vertices, faces, points, chunk=64):
    """(distance, prim, point, all_distances) of each point: the nearest
    triangle by brute force, and the distance to every triangle (for ties)."""
    v = np.asarray(vertices, dtype=np.float64)
    tri = v[np.asarray(faces)]
    a, b, c = (tri[None, :, k] for k in range(3))
    out_d, out_prim, out_point, everything = [], [], [], []
    p = np.asarray(points, dtype=np.float64)
    for start in range(0, len(p), chunk):
        q = p[start:start + chunk, None, :]
        point, _, _ = closest_on_triangles(q, a, b, c)
        d = np.linalg.norm(point - q, axis=-1)
        prim = d.argmin(axis=1)
        rows = np.arange(len(q))
        out_d.append(d[rows, prim])
        out_prim.append(prim)
        out_point.append(point[rows, prim])
        everything.append(d)
    return (np.concatenate(out_d), np.concatenate(out_prim), np.concatenate(out_point),
            np.concatenate(everything))


def winding_numbers(vertices, faces, points, chunk=64):
    """The generalized winding number (Jacobson et al. 2013) of each point:
    the triangles' solid angles (Van Oosterom and Strackee) over 4π."""
    v = np.asarray(vertices, dtype=np.float64)
    tri = v[np.asarray(faces)]
    out = []
    p = np.asarray(points, dtype=np.float64)
    for start in range(0, len(p), chunk):
        q = p[start:start + chunk, None, :]
        a, b, c = tri[None, :, 0] - q, tri[None, :, 1] - q, tri[None, :, 2] - q
        la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
        det = (a * np.cross(b, c)).sum(-1)
        den = la * lb * lc + (a * b).sum(-1) * lc + (b * c).sum(-1) * la + (c * a).sum(-1) * lb
        out.append(2 * np.arctan2(det, den).sum(axis=1) / (4 * np.pi))
    return np.concatenate(out)


def crossings(vertices, faces, origins, directions, tmin=0.0, tmax=np.inf):
    """Every crossing of each ray with each triangle (Möller and Trumbore
    in f64): a list per ray of (t, prim, u, v), sorted by t."""
    v = np.asarray(vertices, dtype=np.float64)
    tri = v[np.asarray(faces)]
    v0, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    result = []
    for o, d in zip(np.asarray(origins, dtype=np.float64), np.asarray(directions, dtype=np.float64)):
        pvec = np.cross(d, e2)
        det = (e1 * pvec).sum(-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            inv = 1.0 / det
            s = o - v0
            u = (s * pvec).sum(-1) * inv
            qvec = np.cross(s, e1)
            w = (qvec * d).sum(-1) * inv
            t = (qvec * e2).sum(-1) * inv
        hit = (det != 0) & (u >= 0) & (w >= 0) & (u + w <= 1) & (t > tmin) & (t < tmax)
        idx = np.flatnonzero(hit)
        order = np.argsort(t[idx], kind="stable")
        result.append([(t[i], i, u[i], w[i]) for i in idx[order]])
    return result


def box_mesh(lo=(-1, -1, -1), hi=(1, 1, 1)):
    """A closed box, 12 triangles facing outwards."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.float64)
    vertices = lo + corners * (hi - lo)
    faces = np.array([
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],   # x = lo, x = hi
        [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],   # y = lo, y = hi
        [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],   # z = lo, z = hi
    ])
    return vertices, faces


def sphere_mesh(subdivisions=2):
    """A closed icosphere of radius 1, outward-facing."""
    t = (1 + 5 ** 0.5) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
         [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
         [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5],
         [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    v = [np.array(x, dtype=np.float64) / np.linalg.norm(x) for x in v]
    for _ in range(subdivisions):
        middle, faces = {}, []

        def mid(i, j):
            key = (min(i, j), max(i, j))
            if key not in middle:
                m = v[i] + v[j]
                v.append(m / np.linalg.norm(m))
                middle[key] = len(v) - 1
            return middle[key]

        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            faces += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        f = faces
    return np.array(v), np.array(f)
