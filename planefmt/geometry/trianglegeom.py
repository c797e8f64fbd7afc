"""Exact point-to-triangle distances and a bounding-volume hierarchy over triangles.

Units are those of the input coordinates; every distance is unsigned and
Euclidean, computed in float64. Triangles are given as vertex arrays and may be
degenerate (collinear or coincident vertices): a zero-area triangle is treated as
the segment or point it is.

Accuracy. Every candidate distance is the distance from the query point to a
point that lies in the triangle up to rounding, so a result never underestimates
the true distance by more than a few ulps of the coordinates' magnitude. The
in-plane closest point is found in a frame built on the triangle's longest edge
(project out that edge, then the orthogonal in-plane direction): direction
errors of that frame only rotate the triangle about its longest edge, which moves
the apex by a few ulps, so thin triangles keep full accuracy. (The textbook
Gram-matrix solve can lose ``eps * L**2 / h**2`` in relative terms on a triangle
of length L and height h.)
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import GeometryError

#: Triangles per BVH leaf and children per internal node.
LEAF_SIZE = 8
BRANCHING = 8
#: Query points handled per traversal batch; bounds the size of the pair frontier.
QUERY_BATCH = 16384
#: Point-triangle pairs evaluated per kernel call; bounds temporary memory.
PAIR_BATCH = 1 << 13

_EPS = np.finfo(np.float64).eps

# Rows of a (structure-of-arrays) triangle table, see triangle_table.
_A, _B, _C = 0, 3, 6
_EDGES = ((0, 9, 18), (3, 12, 19), (6, 15, 20))  # (start vertex, edge vector, inverse squared length)
_O, _E, _W = 21, 24, 27
_INV_EE, _INV_WW, _XV = 30, 31, 32
_ROWS = 33


def _safe_inverse(x: np.ndarray) -> np.ndarray:
    # A zero (or subnormal) squared length marks a degenerate edge or height; an
    # inverse of 0 then pins the parameter to the start, which is still a point
    # of the triangle, so the result stays a true distance to the triangle.
    with np.errstate(divide="ignore", over="ignore"):
        inv = 1.0 / x
    inv[~np.isfinite(inv) | (x <= 0)] = 0.0
    return inv


def triangle_table(tri: np.ndarray) -> np.ndarray:
    """Per-triangle constants of the distance kernel, shape ``(33, n)``, from ``tri`` of shape ``(n, 3, 3)``."""
    tri = np.asarray(tri, dtype=np.float64)
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    t = np.empty((_ROWS, len(tri)))
    t[0:3], t[3:6], t[6:9] = a.T, b.T, c.T
    edges = np.stack([b - a, c - b, a - c], axis=1)
    t[9:12], t[12:15], t[15:18] = edges[:, 0].T, edges[:, 1].T, edges[:, 2].T
    sq = np.einsum("nij,nij->ni", edges, edges)
    t[18:21] = _safe_inverse(sq.ravel()).reshape(sq.shape).T
    # Frame on the longest edge: the apex then projects inside that edge
    # (0 <= xv <= 1) and the in-plane height direction is as well conditioned
    # as the triangle allows.
    k = np.argmax(sq, axis=1)
    rows = np.arange(len(tri))
    o = tri[rows, k]
    e = edges[rows, k]
    inv_ee = _safe_inverse(sq[rows, k])
    v = tri[rows, (k + 2) % 3] - o
    xv = np.einsum("ij,ij->i", v, e) * inv_ee
    w = v - xv[:, None] * e
    t[_O:_O + 3], t[_E:_E + 3], t[_W:_W + 3] = o.T, e.T, w.T
    t[_INV_EE] = inv_ee
    t[_INV_WW] = _safe_inverse(np.einsum("ij,ij->i", w, w))
    t[_XV] = xv
    return t


def _squared_distance_kernel(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Squared distances from points ``p`` (3, m) to the triangles of table columns ``t`` (33, m)."""
    best = np.full(p.shape[1], np.inf)
    for start, edge, inv in _EDGES:
        r = p - t[start:start + 3]
        ed = t[edge:edge + 3]
        s = (r[0] * ed[0] + r[1] * ed[1] + r[2] * ed[2]) * t[inv]
        np.clip(s, 0.0, 1.0, out=s)
        r -= s * ed
        np.minimum(best, r[0] * r[0] + r[1] * r[1] + r[2] * r[2], out=best)
    # Interior: coordinates (x, y) of the projection in the frame o + x*e + y*w.
    # The triangle is (0,0), (1,0), (xv,1) there; when inside, o + x*e + y*w is a
    # point of the triangle and its distance is the distance to the plane.
    r = p - t[_O:_O + 3]
    e, w = t[_E:_E + 3], t[_W:_W + 3]
    x = (r[0] * e[0] + r[1] * e[1] + r[2] * e[2]) * t[_INV_EE]
    r -= x * e
    y = (r[0] * w[0] + r[1] * w[1] + r[2] * w[2]) * t[_INV_WW]
    xv = t[_XV]
    inside = (y >= 0.0) & (y <= 1.0) & (x >= xv * y) & (1.0 - x >= (1.0 - xv) * y)
    r -= y * w
    interior = r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
    np.minimum(best, np.where(inside, interior, np.inf), out=best)
    return best


def table_distances(points: np.ndarray, table: np.ndarray, tri_ids: np.ndarray) -> np.ndarray:
    """Distances from ``points[i]`` (rows of an (m, 3) array) to triangle ``tri_ids[i]`` of ``table``."""
    out = np.empty(len(points))
    for lo in range(0, len(points), PAIR_BATCH):
        hi = lo + PAIR_BATCH
        out[lo:hi] = _squared_distance_kernel(points[lo:hi].T, table[:, tri_ids[lo:hi]])
    return np.sqrt(out)


def table_closest_points(points: np.ndarray, table: np.ndarray, tri_ids: np.ndarray) -> np.ndarray:
    """Closest point of triangle ``tri_ids[i]`` of ``table`` to ``points[i]``, by the same rules as the distance."""
    p = np.asarray(points, dtype=np.float64).T
    t = table[:, tri_ids]
    best = np.full(p.shape[1], np.inf)
    out = np.empty_like(p)
    for start, edge, inv in _EDGES:
        ed = t[edge:edge + 3]
        s = np.clip(((p - t[start:start + 3]) * ed).sum(axis=0) * t[inv], 0.0, 1.0)
        q = t[start:start + 3] + s * ed
        d = ((p - q) ** 2).sum(axis=0)
        better = d < best
        best[better], out[:, better] = d[better], q[:, better]
    r = p - t[_O:_O + 3]
    e, w = t[_E:_E + 3], t[_W:_W + 3]
    x = (r * e).sum(axis=0) * t[_INV_EE]
    y = ((r - x * e) * w).sum(axis=0) * t[_INV_WW]
    xv = t[_XV]
    inside = (y >= 0.0) & (y <= 1.0) & (x >= xv * y) & (1.0 - x >= (1.0 - xv) * y)
    q = t[_O:_O + 3] + x * e + y * w
    better = inside & (((p - q) ** 2).sum(axis=0) < best)
    out[:, better] = q[:, better]
    return out.T


def point_triangle_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Exact Euclidean distance from each point to the (closed, solid) triangle ``abc``.

    All four arguments are ``(n, 3)`` arrays or broadcast to that shape (one
    triangle for many points, or one point for many triangles). Returns ``(n,)``.
    """
    p, a, b, c = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (points, a, b, c)))
    if p.ndim == 1:
        return point_triangle_distance(p[None], a[None], b[None], c[None])
    table = triangle_table(np.stack([a, b, c], axis=1))
    return table_distances(p, table, np.arange(len(p)))


def check_mesh(vertices: np.ndarray, faces: np.ndarray, name: str = "mesh") -> tuple[np.ndarray, np.ndarray]:
    """``(vertices, faces)`` as float64 ``(n, 3)`` and int64 ``(m, 3)``; ``GeometryError`` if empty or invalid."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces)
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
        raise GeometryError(f"{name}: vertices must be (n, 3) and faces (m, 3), not {v.shape} and {f.shape}")
    if len(f) == 0:
        raise GeometryError(f"{name} has no faces")
    if not np.issubdtype(f.dtype, np.integer):
        raise GeometryError(f"{name}: faces must hold integer vertex indices, not {f.dtype}")
    f = f.astype(np.int64)
    if f.min() < 0 or f.max() >= len(v):
        raise GeometryError(f"{name}: a face references a vertex outside 0..{len(v) - 1}")
    if not np.isfinite(v[np.unique(f)]).all():
        raise GeometryError(f"{name}: a vertex used by a face is NaN or infinite")
    return v, f


def _median_split_order(centroids: np.ndarray) -> np.ndarray:
    """Order of the points by recursive splits along the longest axis of each part's box.

    A part of size s > LEAF_SIZE splits into a first part of ``LEAF_SIZE * 2**k``
    points (the largest such size below s) and the rest, so that every aligned
    run of ``LEAF_SIZE * BRANCHING**j`` points is a subtree: the runs the BVH
    groups are spatially compact. All parts of a level split in one sort.
    """
    n = len(centroids)
    order = np.arange(n)
    starts, sizes = np.array([0]), np.array([n])
    while (sizes > LEAF_SIZE).any():
        part = np.repeat(np.arange(len(sizes)), sizes)
        c = centroids[order]
        extent = np.maximum.reduceat(c, starts) - np.minimum.reduceat(c, starts)
        axis = np.argmax(extent, axis=1)
        order = order[np.lexsort((c[np.arange(n), axis[part]], part))]
        big = sizes > LEAF_SIZE
        first = LEAF_SIZE * 2 ** np.maximum(np.ceil(np.log2(np.maximum(sizes, 1) / LEAF_SIZE)).astype(np.int64) - 1, 0)
        first = np.where(big, first, sizes)
        counts = np.where(big, 2, 1)
        new_starts = np.repeat(starts, counts)
        new_sizes = np.repeat(first, counts)
        second = np.cumsum(counts)[big] - 1
        new_starts[second] += first[big]
        new_sizes[second] = sizes[big] - first[big]
        starts, sizes = new_starts, new_sizes
    return order


class TriangleIndex:
    """A BVH over the triangles of a mesh answering exact nearest-triangle queries.

    Leaves are runs of ``LEAF_SIZE`` triangles in the order of recursive median
    splits of their centroids; each internal node covers ``BRANCHING``
    consecutive children.
    Queries run level-synchronously over all (point, node) pairs at once.
    Pruning discards a node only when the distance to its axis-aligned box,
    which is a lower bound for every triangle in it, exceeds a distance already
    achieved by some triangle, enlarged by a relative and an absolute margin
    that dominate rounding; the true nearest triangle is therefore never pruned.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        v, f = check_mesh(vertices, faces)
        self.vertices, self.faces = v, f
        tri = v[f]
        self.table = triangle_table(tri)
        self.scale = float(np.abs(tri).max()) + float(np.ptp(tri.reshape(-1, 3), axis=0).max())
        order = _median_split_order(tri.mean(axis=1))
        self._order = order
        lo = tri.min(axis=1)[order].T.copy()
        hi = tri.max(axis=1)[order].T.copy()
        # Boxes (3, n) per level: triangles (in split order), leaves, ..., top.
        self._boxes = [(lo, hi)]
        fans = [LEAF_SIZE]
        while len(self._boxes) == 1 or self._boxes[-1][0].shape[1] > BRANCHING:
            clo, chi = self._boxes[-1]
            starts = np.arange(0, clo.shape[1], fans[-1])
            self._boxes.append((np.minimum.reduceat(clo, starts, axis=1), np.maximum.reduceat(chi, starts, axis=1)))
            fans.append(BRANCHING)
        self._fans = fans
        # Nearest-vertex seeds: a point's distance to the faces around its
        # nearest mesh vertex is a tight starting bound for pruning.
        used = np.unique(f)
        self._kd = cKDTree(v[used])
        self._kd_vertex = used
        incidence = np.argsort(f.ravel(), kind="stable")
        self._vf_faces = incidence // 3
        self._vf_ptr = np.searchsorted(f.ravel()[incidence], np.arange(len(v) + 1))

    def nearest_vertex(self, points: np.ndarray) -> np.ndarray:
        """Index of a mesh vertex (one that a face uses) nearest to each point."""
        return self._kd_vertex[self._kd.query(np.asarray(points, dtype=np.float64).reshape(-1, 3))[1]]

    def closest_points(self, points: np.ndarray, tri_ids: np.ndarray) -> np.ndarray:
        """The point of triangle ``tri_ids[i]`` nearest to ``points[i]``."""
        return table_closest_points(points, self.table, np.asarray(tri_ids))

    def distances(self, points: np.ndarray, tri_ids: np.ndarray) -> np.ndarray:
        """Exact distances from ``points[i]`` to triangle ``tri_ids[i]``."""
        return table_distances(np.asarray(points, dtype=np.float64), self.table, np.asarray(tri_ids))

    def query(self, points: np.ndarray, hint: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Exact distance from each point to the mesh and the index of a nearest face.

        ``hint`` (optional, one face index per point) only seeds the search bound.
        """
        p = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        dist = np.empty(len(p))
        face = np.empty(len(p), dtype=np.int64)
        for lo in range(0, len(p), QUERY_BATCH):
            sl = slice(lo, lo + QUERY_BATCH)
            dist[sl], face[sl] = self._query_batch(p[sl], None if hint is None else np.asarray(hint)[sl])
        return dist, face

    def _seed(self, p: np.ndarray, hint: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        _, nearest = self._kd.query(p)
        vert = self._kd_vertex[nearest]
        counts = self._vf_ptr[vert + 1] - self._vf_ptr[vert]
        qi = np.repeat(np.arange(len(p)), counts)
        offs = np.arange(len(qi)) - np.repeat(np.cumsum(counts) - counts, counts)
        cand = self._vf_faces[np.repeat(self._vf_ptr[vert], counts) + offs]
        best, face = _group_min(qi, cand, self.distances(p[qi], cand), len(p))
        if hint is not None:
            d = self.distances(p, hint)
            better = d < best
            best[better], face[better] = d[better], hint[better]
        return best, face

    def candidates(self, points: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pairs ``(i, face)`` of every face whose box is within ``radius[i]`` of ``points[i]`` (a superset
        of the faces within that distance), grouped by ``i``."""
        p = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        keep = (np.asarray(radius, dtype=np.float64) * (1.0 + 1e-9) + 64.0 * _EPS * self.scale) ** 2
        qi, node = self._candidates(p, np.broadcast_to(keep, (len(p),)))
        return qi, self._order[node]

    def _candidates(self, p: np.ndarray, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(point, triangle position) pairs whose triangle box is within ``sqrt(keep)`` of the point."""
        pt = p.T
        top = self._boxes[-1][0].shape[1]
        # Pairs (query, node) stay grouped by query in ascending order throughout.
        qi = np.repeat(np.arange(len(p)), top)
        node = np.tile(np.arange(top), len(p))
        for level in range(len(self._boxes) - 1, -1, -1):
            lo, hi = self._boxes[level]
            x = pt[:, qi]
            gap = np.maximum(lo[:, node] - x, 0.0)
            gap += np.maximum(x - hi[:, node], 0.0)
            alive = (gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2]) <= keep[qi]
            qi, node = qi[alive], node[alive]
            if level == 0:
                break
            fan = self._fans[level - 1]
            child = (node[:, None] * fan + np.arange(fan)).ravel()
            qi = np.repeat(qi, fan)
            valid = child < self._boxes[level - 1][0].shape[1]
            qi, node = qi[valid], child[valid]
        return qi, node

    def _query_batch(self, p: np.ndarray, hint: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        ub, best_face = self._seed(p, hint)
        qi, node = self._candidates(p, (ub * (1.0 + 1e-9) + 64.0 * _EPS * self.scale) ** 2)
        tri = self._order[node]
        d, f = _group_min(qi, tri, self.distances(p[qi], tri), len(p))
        better = d < ub
        ub[better], best_face[better] = d[better], f[better]
        return ub, best_face


def _group_min(group: np.ndarray, item: np.ndarray, value: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Per group in ``0..n-1`` (``group`` sorted ascending), the smallest value and the item holding it.

    Groups with no entry get ``inf`` and ``-1``.
    """
    best = np.full(n, np.inf)
    arg = np.full(n, -1, dtype=np.int64)
    if len(group):
        starts = np.flatnonzero(np.r_[True, group[1:] != group[:-1]])
        mins = np.minimum.reduceat(value, starts)
        counts = np.diff(np.r_[starts, len(group)])
        hit = np.flatnonzero(value == np.repeat(mins, counts))
        _, first = np.unique(group[hit], return_index=True)
        best[group[starts]] = mins
        arg[group[hit[first]]] = item[hit[first]]
    return best, arg


def closest_distance(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact unsigned distance from each point to the triangle mesh, and a nearest face index.

    Builds a :class:`TriangleIndex`; reuse one directly for repeated queries.
    """
    return TriangleIndex(vertices, faces).query(points)
