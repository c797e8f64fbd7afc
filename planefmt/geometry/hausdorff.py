"""Certified two-sided Hausdorff distance between triangle meshes.

Conventions. A mesh is ``(vertices, faces)``: float ``(n, 3)`` coordinates and
integer ``(m, 3)`` vertex indices. Its *surface* is the union of its closed,
solid triangles (vertices no face uses are ignored; zero-area triangles count as
the segments or points they are). Distances are Euclidean, unsigned, in model
units (the units of the coordinates) and computed in float64.
``h(A, B) = sup_{x in A} d(x, B)`` is the one-sided distance and
``H = max(h(A, B), h(B, A))`` the two-sided Hausdorff distance.
:func:`relative_hausdorff` divides by the bounding-box diagonal of A's surface.

Method. For each direction the triangles of the source mesh are *pieces*,
refined by midpoint 4-splits, level by level, only where needed.

* Lower bound: the exact distance (:mod:`planefmt.geometry.trianglegeom`) of points of
  the source surface: vertices, piece corners and centroids, and the points
  where a piece meets a cut plane (below).
* Upper bound of a piece P: the least of these certificates, tried from the
  cheapest on and only while the bound exceeds the current threshold:

  - Lipschitz: ``d(x, B) <= d(g, B) + |x - g|`` with g the centroid of P.
  - Convexity: the distance to a convex set is convex, so its maximum over P is
    at a corner of P. The convex sets are the triangle nearest to g, then the
    convex planar patches of B (:mod:`planefmt.geometry.planarpatches`) nearest to the
    corners and to g, each with its certified slack ``sigma``: a piece lying
    across internal edges of a planar polygon of B is certified at once.
  - Region: if P projects into a coplanar region of B (any shape; checked
    against the region's boundary edges), each point of P is within its
    distance to the region's plane plus the region's flatness; that distance
    is affine, so largest at a corner. This covers pieces over points where
    three or more patches of a non-convex face meet.
  - Cut: a plane through an edge shared by two patches, bisecting their faces,
    splits P into two convex parts, each bounded by convexity against one
    patch at its corners, including the points on the plane. This certifies
    pieces that straddle the line where the nearest face changes (a sliver
    bridging a concave corner, a chamfer) without refining along that line.
  - Star: half-planes through an axis at the vertex of B nearest to g (or
    the centroid of its cluster of vertices joined by edges no longer than
    the threshold) cut P into convex wedge parts, each bounded by convexity
    against the patches on its two spokes (:mod:`planefmt.geometry.stars`). This
    certifies pieces over a vertex where several nearly coplanar faces meet,
    as on every vertex of a decoded smooth mesh.

  Every bound adds a margin of ``64 * eps`` times the coordinates' magnitude
  for rounding (the region certificate also a rim of a few such margins times
  the piece's aspect ratio), so it is never below the true supremum.
* Refinement stops once ``upper <= target`` or ``lower > target`` (with a
  target), or ``upper - lower <= tolerance`` (without); a piece is retired as
  soon as its bound is at most the current threshold. If ``max_pieces`` runs
  out first, the result has ``certified=False`` and ``upper`` is still a valid
  bound, only not a tight one.

Guarantee: ``lower <= H <= upper`` always, for any input. Each one-sided pair
is refined only as far as the two-sided answer needs, so it may be looser.

Cost: building a BVH (:class:`planefmt.geometry.trianglegeom.TriangleIndex`) and the
patches of each mesh, ``O(n log n)`` plus a Python pass over coplanar regions
that are not convex; then one exact nearest-triangle query (about 15 us on one
core) per corner and centroid of every piece. Identical or nearly identical
meshes, and planar faces triangulated differently, are certified on the
original triangles or after a few levels. Refinement goes deep only where the
distance is near its maximum and around the few points no certificate covers
(a region's boundary vertex where three or more patches meet, when pieces
there also stick out of the region): about ``4 * log2(size / threshold)``
pieces around each. Bunny (69k triangles) against itself or a 1e-7 jittered
copy at a 1e-6 target: about 3 s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import GeometryError
from .planarpatches import ConvexPatches
from .stars import VertexStars
from .trianglegeom import TriangleIndex, check_mesh, closest_distance, point_triangle_distance

__all__ = ["HausdorffResult", "closest_distance", "hausdorff", "point_triangle_distance", "relative_hausdorff"]

#: Default stop gap ``upper - lower`` without a target, relative to the diagonal of both meshes' box.
DEFAULT_RELATIVE_TOLERANCE = 1e-9
#: Default budget of pieces evaluated, over both directions (the triangles of both meshes always are).
DEFAULT_MAX_PIECES = 2_000_000
#: Patch slack allowed, as a fraction of the target (or of the tolerance).
PATCH_TOLERANCE_FRACTION = 0.01

_EPS = float(np.finfo(np.float64).eps)


@dataclass(frozen=True)
class HausdorffResult:
    """Certified bounds on the Hausdorff distance, in model units (or relative, see :func:`relative_hausdorff`).

    ``lower <= H <= upper`` always holds. ``a_to_b`` and ``b_to_a`` bound the
    one-sided distances as ``(lower, upper)``. ``certified`` is True when the
    refinement reached its goal: ``upper <= target`` or ``lower > target`` with a
    target, ``upper - lower <= tolerance`` without; False when the piece budget
    ran out first.
    """

    lower: float
    upper: float
    a_to_b: tuple[float, float]
    b_to_a: tuple[float, float]
    certified: bool


class _Direction:
    """Pieces of one source surface measured against one target mesh."""

    def __init__(self, source: tuple[np.ndarray, np.ndarray], index: TriangleIndex,
                 patches: ConvexPatches, margin: float) -> None:
        self.index, self.patches, self.margin = index, patches, margin
        # Rim allowed between a piece and a region it projects into; far above rounding.
        self.inset = 4.0 * margin
        v, f = source
        self.points = v
        self.dist = np.full(len(v), np.nan)
        self.face = np.full(len(v), -1, dtype=np.int64)
        used = np.unique(f)
        self.dist[used], self.face[used] = index.query(v[used])
        self.lower = float(self.dist[used].max())
        self.retired_upper = 0.0
        self.frozen_upper = 0.0
        self.pieces = f
        self.bound = np.empty(0)
        self.stars: VertexStars | None = None

    @property
    def upper(self) -> float:
        live = float(self.bound.max()) if len(self.bound) else 0.0
        return max(self.retired_upper, self.frozen_upper, live)

    def evaluate(self, threshold: float) -> None:
        """Bound every piece; certificates beyond the cheapest run only where it exceeds ``threshold``."""
        if not len(self.pieces):
            self.bound = np.empty(0)
            return
        corners = self.points[self.pieces]
        d = self.dist[self.pieces]
        f = self.face[self.pieces]
        centroid = corners.mean(axis=1)
        dg, fg = self.index.query(centroid, hint=f[:, 0])
        self.lower = max(self.lower, float(dg.max()))
        radius = np.sqrt(((corners - centroid[:, None]) ** 2).sum(axis=2)).max(axis=1)
        bound = dg + radius
        need = np.flatnonzero(bound > threshold)
        if len(need):
            bound[need] = np.minimum(bound[need], self._nearest_triangle_bound(corners[need], d[need], f[need], fg[need]))
            need = need[bound[need] > threshold]
        if len(need):
            cands = self.patches.patch_of[np.column_stack([f[need], fg[need]])]
            dist_to = self._patch_distances(corners[need], cands)
            slack = self.patches.slack[cands]
            convex = np.where(np.isnan(dist_to).any(axis=1), np.inf, dist_to.max(axis=1) + slack).min(axis=1)
            bound[need] = np.minimum(bound[need], convex)
            keep = bound[need] > threshold
            need, cands, dist_to, slack = need[keep], cands[keep], dist_to[keep], slack[keep]
        if len(need):
            bound[need] = np.minimum(bound[need], self._region_bound(corners[need], centroid[need], fg[need]))
            keep = bound[need] > threshold
            need, cands, dist_to, slack = need[keep], cands[keep], dist_to[keep], slack[keep]
        if len(need):
            bound[need] = np.minimum(bound[need], self._cut_bound(corners[need], f[need], cands, dist_to, slack))
            need = need[bound[need] > threshold]
        if len(need):
            bound[need] = np.minimum(bound[need], self._star_bound(corners[need], centroid[need], threshold))
        self.bound = bound + self.margin

    def _star_bound(self, corners: np.ndarray, centroid: np.ndarray, threshold: float) -> np.ndarray:
        """Wedge bound around the target vertex nearest to each piece's centroid (:mod:`planefmt.geometry.stars`).

        Vertices joined by edges no longer than the first threshold asked for form one star's cluster.
        """
        if self.stars is None:
            self.stars = VertexStars(self.index.vertices, self.index.faces, self.patches, threshold)
        return self.stars.bound(corners, self.index.nearest_vertex(centroid))

    def _nearest_triangle_bound(self, corners: np.ndarray, d: np.ndarray, f: np.ndarray, fg: np.ndarray) -> np.ndarray:
        # A corner whose own nearest triangle is fg already has its distance to it.
        out = d.copy()
        other = f != fg[:, None]
        rows, cols = np.nonzero(other)
        out[rows, cols] = self.index.distances(corners[rows, cols], fg[rows])
        return out.max(axis=1)

    def _region_bound(self, corners: np.ndarray, centroid: np.ndarray, fg: np.ndarray) -> np.ndarray:
        """Plane-distance bound for pieces whose projection lies inside a coplanar region of the target.

        If the piece projects into the region (up to a rim, see
        ``ConvexPatches.region_cover``), each of its points is within its
        distance to the region's plane plus the region's flatness ``tau`` plus the
        rim, and the plane distance is largest at a corner.
        """
        bound = np.full(len(corners), np.inf)
        pat = self.patches
        rows = np.flatnonzero(pat.region_of[fg] >= 0)
        if not len(rows):
            return bound
        region = pat.region_of[fg[rows]]
        anchor = self.index.closest_points(centroid[rows], fg[rows])
        ok, rim = pat.region_cover(corners[rows], anchor, region, self.inset)
        n = pat.region_normal[region]
        height = np.abs(np.einsum("kij,kj->ki", corners[rows], n) - pat.region_offset[region][:, None]).max(axis=1)
        bound[rows[ok]] = (height + pat.region_tau[region] + rim)[ok]
        return bound

    def _patch_distances(self, corners: np.ndarray, cands: np.ndarray) -> np.ndarray:
        """``(k, 3 corners, 4 candidates)`` distances to the candidates' convex sets; NaN for repeated candidates."""
        k = len(corners)
        out = np.full((k, 3, cands.shape[1]), np.nan)
        first = np.ones(cands.shape, dtype=bool)
        for j in range(1, cands.shape[1]):
            first[:, j] = (cands[:, :j] != cands[:, j:j + 1]).all(axis=1)
        rows, cols = np.nonzero(first)
        pts = corners[rows].reshape(-1, 3)
        pat = np.repeat(cands[rows, cols], 3)
        out[rows, :, cols] = self.patches.distance(pts, pat).reshape(-1, 3)
        return out

    def _cut_bound(self, corners: np.ndarray, faces: np.ndarray, cands: np.ndarray, dist_to: np.ndarray,
                   slack: np.ndarray) -> np.ndarray:
        """Least cut bound of each piece over the pairs of its candidate patches that have a cut plane."""
        k, m = cands.shape
        ii, jj = np.triu_indices(m, 1)
        rows = np.repeat(np.arange(k), len(ii))
        ci, cj = np.tile(ii, k), np.tile(jj, k)
        first, second = cands[rows, ci], cands[rows, cj]
        lo, hi = np.minimum(first, second), np.maximum(first, second)
        found, origin, normal = self.patches.cut(lo, hi)
        keep = found & ~np.isnan(dist_to[rows, 0, ci]) & ~np.isnan(dist_to[rows, 0, cj])
        rows, ci, cj, lo, hi, origin, normal = (x[keep] for x in (rows, ci, cj, lo, hi, origin, normal))
        swap = (first[keep] != lo)[:, None]
        d_lo = np.where(swap, dist_to[rows, :, cj], dist_to[rows, :, ci])
        d_hi = np.where(swap, dist_to[rows, :, ci], dist_to[rows, :, cj])
        b = self._split_bound(corners[rows], faces[rows], origin, normal, lo, hi, d_lo, d_hi)
        b += np.maximum(slack[rows, ci], slack[rows, cj])
        bound = np.full(k, np.inf)
        np.minimum.at(bound, rows, b)
        return bound

    def _split_bound(self, corners: np.ndarray, faces: np.ndarray, origin: np.ndarray, normal: np.ndarray,
                     lo: np.ndarray, hi: np.ndarray, d_lo: np.ndarray, d_hi: np.ndarray) -> np.ndarray:
        """Convexity bound over the two parts of each piece on either side of its cut plane.

        A corner whose side rounding cannot settle (``|s| <= err``) counts on
        both sides. A crossing point is off by at most ``2 * err`` of side value,
        hence by ``2 * err * |ab| / |s_a - s_b|`` in position; a crossing next to
        an unsettled corner is that close to it. Both go into the bound, as the
        distance to a patch is 1-Lipschitz.
        """
        s = np.einsum("kij,kj->ki", corners - origin[:, None], normal)
        err = 8.0 * _EPS * (np.abs(corners).max(axis=(1, 2)) + np.abs(origin).max(axis=1) + np.abs(s).max(axis=1))
        settled = np.abs(s) > err[:, None]
        bound = np.maximum(np.where(s >= -err[:, None], d_lo, 0.0).max(axis=1),
                           np.where(s <= err[:, None], d_hi, 0.0).max(axis=1))
        rows, points, hints, shift = [], [], [], []
        for a, b in ((0, 1), (1, 2), (2, 0)):
            length = np.linalg.norm(corners[:, b] - corners[:, a], axis=1)
            gap = np.abs(s[:, a] - s[:, b])
            # One corner settled, the other not: the crossing (if any) hugs the unsettled one.
            one = settled[:, a] ^ settled[:, b]
            near = np.where(settled[:, a], b, a)
            # A zero-length edge has no crossing off its corner (0/0 would make the bound NaN).
            reach = err * length
            with np.errstate(divide="ignore", invalid="ignore"):
                hug = np.where(reach > 0, reach / np.maximum(gap - err, 0.0), 0.0)
            corner_bound = np.maximum(d_lo[np.arange(len(s)), near], d_hi[np.arange(len(s)), near]) + hug
            bound = np.where(one, np.maximum(bound, corner_bound), bound)
            r = np.flatnonzero(settled[:, a] & settled[:, b] & (np.sign(s[:, a]) != np.sign(s[:, b])))
            t = s[r, a] / (s[r, a] - s[r, b])
            rows.append(r)
            points.append(corners[r, a] + t[:, None] * (corners[r, b] - corners[r, a]))
            hints.append(faces[r, a])
            shift.append(2.0 * err[r] * length[r] / gap[r])
        rows, x, hint, shift = (np.concatenate(z) for z in (rows, points, hints, shift))
        if len(rows):
            on_cut = np.maximum(self.patches.distance(x, lo[rows]), self.patches.distance(x, hi[rows])) + shift
            np.maximum.at(bound, rows, on_cut)
            # The crossing points lie on the source surface: exact lower bounds.
            self.lower = max(self.lower, float(self.index.query(x, hint=hint)[0].max()))
        return bound

    def retire(self, threshold: float) -> None:
        done = self.bound <= threshold
        if done.any():
            self.retired_upper = max(self.retired_upper, float(self.bound[done].max()))
            self.pieces, self.bound = self.pieces[~done], self.bound[~done]

    def split(self, chosen: np.ndarray) -> None:
        """Replace the chosen pieces by their four midpoint children; the others, left over by the budget, are frozen."""
        frozen = np.setdiff1d(np.arange(len(self.pieces)), chosen)
        if len(frozen):
            self.frozen_upper = max(self.frozen_upper, float(self.bound[frozen].max()))
        p = self.pieces[chosen]
        if not len(p):
            self.pieces, self.bound = p, np.empty(0)
            return
        edges = np.stack([p[:, [0, 1]], p[:, [1, 2]], p[:, [2, 0]]], axis=1).reshape(-1, 2)
        key = np.sort(edges, axis=1)
        unique, inverse = np.unique(key, axis=0, return_inverse=True)
        mid_ids = len(self.points) + np.arange(len(unique))
        mids = 0.5 * (self.points[unique[:, 0]] + self.points[unique[:, 1]])
        md, mf = self.index.query(mids, hint=self.face[unique[:, 0]])
        self.points = np.concatenate([self.points, mids])
        self.dist = np.concatenate([self.dist, md])
        self.face = np.concatenate([self.face, mf])
        self.lower = max(self.lower, float(md.max()))
        m = mid_ids[inverse.reshape(-1, 3)]
        m01, m12, m20 = m[:, 0], m[:, 1], m[:, 2]
        self.pieces = np.concatenate([
            np.column_stack([p[:, 0], m01, m20]),
            np.column_stack([m01, p[:, 1], m12]),
            np.column_stack([m20, m12, p[:, 2]]),
            np.column_stack([m01, m12, m20]),
        ])


def hausdorff(vertices_a: np.ndarray, faces_a: np.ndarray, vertices_b: np.ndarray, faces_b: np.ndarray, *,
              target: float | None = None, tolerance: float | None = None,
              max_pieces: int = DEFAULT_MAX_PIECES) -> HausdorffResult:
    """Certified bounds on the two-sided Hausdorff distance between two triangle meshes, in model units.

    With ``target``, refinement stops as soon as ``upper <= target`` or
    ``lower > target``. Without, it stops once ``upper - lower <= tolerance``
    (default ``1e-9`` times the diagonal of the box of both meshes).
    ``max_pieces`` caps the pieces evaluated; see :class:`HausdorffResult`.
    Raises ``GeometryError`` for an empty mesh or invalid input.
    """
    a = check_mesh(vertices_a, faces_a, "mesh A")
    b = check_mesh(vertices_b, faces_b, "mesh B")
    used = np.concatenate([a[0][np.unique(a[1])], b[0][np.unique(b[1])]])
    diag = float(np.linalg.norm(np.ptp(used, axis=0)))
    if tolerance is None:
        tolerance = DEFAULT_RELATIVE_TOLERANCE * diag
    margin = 64.0 * _EPS * (float(np.abs(used).max()) + diag)
    goal = target if target is not None else tolerance
    merge_tol = PATCH_TOLERANCE_FRACTION * goal
    index_a, index_b = TriangleIndex(*a), TriangleIndex(*b)
    # A region bound is never below its flatness: regions flatter than the goal, or of no use.
    sides = (_Direction(a, index_b, ConvexPatches(*b, merge_tol, goal), margin),
             _Direction(b, index_a, ConvexPatches(*a, merge_tol, goal), margin))
    evaluated = len(a[1]) + len(b[1])
    certified = False
    while True:
        lower = max(s.lower for s in sides)
        if target is not None and lower > target:
            # Decided already: only the cheap (Lipschitz) bounds, so that upper is valid.
            threshold = np.inf
        else:
            threshold = target if target is not None else lower + tolerance
        for s in sides:
            s.evaluate(threshold)
        lower = max(s.lower for s in sides)
        if target is not None and lower > target:
            certified = True
            break
        threshold = target if target is not None else lower + tolerance
        for s in sides:
            s.retire(threshold)
        live = [len(s.pieces) for s in sides]
        if sum(live) == 0:
            certified = all(s.frozen_upper <= threshold for s in sides)
            break
        room = (max_pieces - evaluated) // 4
        if room <= 0:
            for s in sides:
                s.split(np.empty(0, dtype=np.int64))
            break
        # Over budget, refine the pieces with the largest bounds first.
        bounds = np.concatenate([s.bound for s in sides])
        chosen = np.argsort(-bounds, kind="stable")[:room]
        offsets = np.cumsum([0] + live)
        for k, s in enumerate(sides):
            mine = chosen[(chosen >= offsets[k]) & (chosen < offsets[k + 1])] - offsets[k]
            s.split(np.sort(mine))
            evaluated += 4 * len(mine)
    return _result(sides, margin, certified)


def _result(sides: tuple[_Direction, _Direction], margin: float, certified: bool) -> HausdorffResult:
    # Exact distances may overshoot by rounding; the lower bounds give that back.
    pairs = [(max(0.0, s.lower - margin), s.upper) for s in sides]
    return HausdorffResult(lower=max(p[0] for p in pairs), upper=max(p[1] for p in pairs),
                           a_to_b=pairs[0], b_to_a=pairs[1], certified=certified)


def relative_hausdorff(mesh_a: tuple[np.ndarray, np.ndarray], mesh_b: tuple[np.ndarray, np.ndarray], *,
                       target: float | None = None, tolerance: float | None = None,
                       max_pieces: int = DEFAULT_MAX_PIECES) -> HausdorffResult:
    """:func:`hausdorff` of ``(vertices, faces)`` pairs with every length divided by A's box diagonal.

    The diagonal is that of the axis-aligned bounding box of the vertices A's
    faces use; ``target`` and ``tolerance`` are relative to it too. Raises
    ``GeometryError`` if it is zero.
    """
    va, fa = check_mesh(*mesh_a, "mesh A")
    diag = float(np.linalg.norm(np.ptp(va[np.unique(fa)], axis=0)))
    if not diag > 0:
        raise GeometryError("mesh A has a zero bounding-box diagonal")
    r = hausdorff(va, fa, *mesh_b, target=None if target is None else target * diag,
                  tolerance=None if tolerance is None else tolerance * diag, max_pieces=max_pieces)
    return HausdorffResult(lower=r.lower / diag, upper=r.upper / diag,
                           a_to_b=(r.a_to_b[0] / diag, r.a_to_b[1] / diag),
                           b_to_a=(r.b_to_a[0] / diag, r.b_to_a[1] / diag), certified=r.certified)
