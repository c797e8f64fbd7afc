"""A second measure of the distance between two triangle meshes, sharing no code with planefmt.

planefmt certifies its error bound with :mod:`planefmt.hausdorff`, a BVH of
:mod:`planefmt.trianglegeom` and the wedge bounds of :mod:`planefmt.stars`.
The tests check that bound against this module, which is written from the
textbook instead: the exact distance from a point to a triangle by the
Voronoi regions of Ericson, *Real-Time Collision Detection* (2005), §5.1.5,
in numpy, from dense samples of each surface (a barycentric grid on every
face, its corners and edges included, finer on the faces that come out
farthest) to every triangle of the other.
Triangles are only passed over where a box test proves them farther than a
triangle vertex already found (scipy's k-d tree), so each sample's distance
is exact. The largest sampled distance, both ways, is a lower bound of the
two-sided Hausdorff distance: a recorded bound below it is wrong.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

#: Points times triangles evaluated in one numpy batch (memory: about 40 floats each).
BATCH = 1 << 18
#: Samples per spatial chunk of points that share one box test.
CHUNK = 256
#: Grid steps per triangle side of the points whose nearest one bounds each sample's distance.
UPPER_STEPS = 4


def point_triangle_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Distance from points ``p`` to triangles ``(a, b, c)``, all (..., 3) broadcast together.

    Ericson's ClosestPtPointTriangle: the closest point lies in the region of a
    vertex, of an edge, or inside the face, told apart by the signs of dot
    products; each region's closest point is computed for every pair and the
    right one picked.
    """
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    bp = p - b
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    cp = p - c
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2

    with np.errstate(divide="ignore", invalid="ignore"):
        # Inside the face: barycentric (1 - v - w, v, w).
        denom = va + vb + vc
        v_face, w_face = vb / denom, vc / denom
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        closest = a + ab * v_face[..., None] + ac * w_face[..., None]
    # Regions in Ericson's order of tests, the last one tested first so that earlier ones win.
    closest = np.where(((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0))[..., None], b + (c - b) * t_bc[..., None], closest)
    closest = np.where(((vb <= 0) & (d2 >= 0) & (d6 <= 0))[..., None], a + ac * t_ac[..., None], closest)
    closest = np.where(((d6 >= 0) & (d5 <= d6))[..., None], c, closest)
    closest = np.where(((vc <= 0) & (d1 >= 0) & (d3 <= 0))[..., None], a + ab * t_ab[..., None], closest)
    closest = np.where(((d3 >= 0) & (d4 <= d3))[..., None], b, closest)
    closest = np.where(((d1 <= 0) & (d2 <= 0))[..., None], a, closest)
    # A degenerate triangle (a segment or point) leaves NaN in the face's formula only where some
    # edge or vertex region applies; its distance is then that of its edges.
    bad = ~np.isfinite(closest).all(axis=-1)
    out = np.linalg.norm(p - closest, axis=-1)
    if bad.any():
        segs = np.minimum(np.minimum(_segment(p, a, b), _segment(p, b, c)), _segment(p, a, c))
        out = np.where(bad, segs, out)
    return out


def _dot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", x, y)


def _segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    length2 = _dot(ab, ab)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(np.where(length2 > 0, _dot(p - a, ab) / length2, 0.0), 0.0, 1.0)
    return np.linalg.norm(p - (a + ab * t[..., None]), axis=-1)


def grid(vertices: np.ndarray, faces: np.ndarray, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Points of a barycentric grid with ``steps`` steps per side on every face (its corners and
    edges included), and the face each point is on."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    i, j = np.meshgrid(np.arange(steps + 1), np.arange(steps + 1), indexing="ij")
    keep = (i + j) <= steps
    u, w = (i[keep] / steps)[None, :, None], (j[keep] / steps)[None, :, None]
    points = (a[:, None] + (b - a)[:, None] * u + (c - a)[:, None] * w).reshape(-1, 3)
    return points, np.repeat(np.arange(len(f)), int(keep.sum()))


def distances(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The exact distance from each point to the nearest triangle of ``(vertices, faces)``."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    tri = v[f]
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    # Each point's distance to the nearest point of a grid on every triangle bounds its distance
    # to the surface; a grid, not the vertices alone, keeps that bound short beside long thin
    # triangles (CAD), whose box test would otherwise take in most of the mesh.
    best, _ = cKDTree(np.concatenate([v[np.unique(f)], grid(v, f, UPPER_STEPS)[0]])).query(points)
    levels = _Levels(lo, hi)
    order = _spatial_order(points)
    for start in range(0, len(points), CHUNK):
        idx = order[start:start + CHUNK]
        p = points[idx]
        reach = float(best[idx].max())
        p_lo, p_hi = p.min(axis=0), p.max(axis=0)
        near = levels.near((p_lo + p_hi) / 2, float(np.linalg.norm(p_hi - p_lo)) / 2 + reach)
        gap = np.maximum(np.maximum(lo[near] - p_hi, p_lo - hi[near]), 0.0)
        candidates = near[np.einsum("ij,ij->i", gap, gap) <= reach * reach]
        step = max(1, BATCH // len(p))
        for k in range(0, len(candidates), step):
            c = candidates[k:k + step]
            # Only the pairs whose box test leaves the triangle within the point's own bound.
            gap = np.maximum(np.maximum(lo[c][None] - p[:, None], p[:, None] - hi[c][None]), 0.0)
            point, which = np.nonzero(np.einsum("ijk,ijk->ij", gap, gap) <= best[idx][:, None] ** 2)
            t = tri[c[which]]
            d = point_triangle_distance(p[point], t[:, 0], t[:, 1], t[:, 2])
            nearest = best[idx]
            np.minimum.at(nearest, point, d)
            best[idx] = nearest
    return best


class _Levels:
    """Triangles by the size of their boxes, in powers of two, a k-d tree of box centres each:
    a ball query on a level, widened by that level's largest half-diagonal, finds every box
    that meets the ball, so long triangles do not widen the search around short ones."""

    def __init__(self, lo: np.ndarray, hi: np.ndarray):
        centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo, axis=1) / 2
        level = np.floor(np.log2(np.maximum(radius, np.finfo(float).tiny))).astype(np.int64)
        self.levels = []
        for value in np.unique(level):
            members = np.flatnonzero(level == value)
            self.levels.append((cKDTree(centre[members]), members, float(radius[members].max())))

    def near(self, centre: np.ndarray, radius: float) -> np.ndarray:
        """Indices of the triangles whose box may meet the ball (``centre``, ``radius``)."""
        found = [members[tree.query_ball_point(centre, radius + widest)]
                 for tree, members, widest in self.levels]
        return np.concatenate(found).astype(np.int64)


def directed(source_vertices: np.ndarray, source_faces: np.ndarray, vertices: np.ndarray, faces: np.ndarray,
             steps: int = 6, refine: int = 8, fine: int = 100) -> float:
    """A lower bound of the largest distance from the surface ``source`` to the surface
    ``(vertices, faces)``: every source face sampled on a grid of ``steps`` per side, then the
    ``refine`` faces farthest on it again on a grid of ``fine`` per side (the farthest point of a
    face is seldom one of a coarse grid's)."""
    points, owner = grid(source_vertices, source_faces, steps)
    d = distances(points, vertices, faces)
    per_face = np.zeros(len(source_faces))
    np.maximum.at(per_face, owner, d)
    worst = float(d.max(initial=0.0))
    for k in np.argsort(per_face)[::-1][:refine]:
        p, _ = grid(source_vertices, np.asarray(source_faces)[k:k + 1], fine)
        worst = max(worst, float(distances(p, vertices, faces).max()))
    return worst


def _spatial_order(points: np.ndarray) -> np.ndarray:
    """An order of ``points`` in which consecutive ones are close: by 3-D Morton code."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    q = ((points - lo) / np.where(hi > lo, hi - lo, 1.0) * 1023).astype(np.int64)
    code = np.zeros(len(points), dtype=np.int64)
    for bit in range(10):
        for axis in range(3):
            code |= ((q[:, axis] >> bit) & 1) << (3 * bit + axis)
    return np.argsort(code, kind="stable")


def hausdorff_lower_bound(a_vertices: np.ndarray, a_faces: np.ndarray, b_vertices: np.ndarray,
                          b_faces: np.ndarray, steps: int = 6) -> float:
    """A lower bound of the two-sided Hausdorff distance (model units) between two triangle meshes."""
    return max(directed(a_vertices, a_faces, b_vertices, b_faces, steps),
               directed(b_vertices, b_faces, a_vertices, a_faces, steps))
