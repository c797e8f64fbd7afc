"""The two-sided Hausdorff distance between two closed convex triangle surfaces, from their corners.

A convex group decodes to a convex polytope, and its source is a convex body:
between two such surfaces the distance needs no search. For convex bodies
``K`` and ``L`` with support functions ``h_K``, ``h_L``, the distance of the
solids is ``d = sup_u |h_K(u) - h_L(u)|``, and the surfaces are no farther
apart: a point ``x`` of ``∂K`` outside the interior of ``L`` is ``d(x, L) <= d``
from ``∂L``; one inside leaves ``L`` along ``K``'s outward normal ``u`` at ``x``
within ``h_L(u) - u·x = h_L(u) - h_K(u) <= d``. The distance of the solids is
reached at a corner (``d(·, L)`` is convex, and zero inside ``L``), so

    δ(∂K, ∂L) <= max(max_{v corner of K} d(v, L), max_{v corner of L} d(v, K)),

exact point-to-triangle distances from the corners outside the other solid,
where a certified search (:mod:`planefmt.geometry.hausdorff`) refines pieces of the
surface. The corners' distances from the other *surface* bound the distance
from below. The bound holds in real arithmetic for convex surfaces; corners
that stand off their surface's planes by rounding are measured, and the
surface is taken as convex only when that is below :data:`CONVEX_SLACK`.
"""

from __future__ import annotations

import numpy as np

from .trianglegeom import closest_distance, table_distances, triangle_table

#: A surface whose corners stand farther outside its triangles' planes than this fraction of its
#: diagonal is not taken as convex (float rounding of a convex one stays far below).
CONVEX_SLACK = 1e-9
#: Plane-corner pairs per batch of the convexity test.
_BATCH = 1 << 21
#: Point-triangle pairs up to which every pair is measured rather than a search tree built.
_ALL_PAIRS = 1 << 15


def convex_hausdorff(a_vertices: np.ndarray, a_faces: np.ndarray, b_vertices: np.ndarray,
                     b_faces: np.ndarray) -> tuple[float, float] | None:
    """``(upper, lower)`` bounds of the two-sided Hausdorff distance (model units) between two closed
    convex triangle surfaces (counter-clockwise from outside), or None when either is not convex.

    ``lower`` is the largest distance of a corner of either surface from the other surface.
    """
    ax = _Convex.of(a_vertices, a_faces)
    bx = _Convex.of(b_vertices, b_faces)
    if ax is None or bx is None:
        return None
    ab, ab_low = _directed(ax, bx)
    ba, ba_low = _directed(bx, ax)
    return max(ab, ba), max(ab_low, ba_low)


class _Convex:
    """A closed triangle surface taken as convex: its corners, triangles and triangle planes."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray, offsets: np.ndarray,
                 rounding: float):
        self.vertices, self.faces = vertices, faces
        self.normals, self.offsets = normals, offsets  # unit outward normals n_S, c_S = n_S·x on S
        self.rounding = rounding  # how far (model units) a corner stands outside a triangle's plane

    @staticmethod
    def of(vertices: np.ndarray, faces: np.ndarray) -> _Convex | None:
        v = np.asarray(vertices, dtype=np.float64)
        f = np.asarray(faces, dtype=np.int64)
        if len(f) < 4:
            return None
        tri = v[f]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        length = np.linalg.norm(n, axis=1)
        # A sliver's plane is rounding; its corners are the other triangles' too.
        keep = length > 0
        n = n[keep] / length[keep, None]
        c = np.einsum("ij,ij->i", n, tri[keep, 0])
        used = v[np.unique(f)]
        # Triangles of one face (a subdivided cube: 3,072 triangles on 6 planes) test the corners once.
        # Only planes equal to the last bit: one standing for near-equal ones would widen the rounding,
        # which the bound adds, past what a tolerance of 1e-12 leaves (cube_subd at 1e-12 then failed
        # as a convex group: 760 B as a shell against 166 B).
        rep = np.unique(np.column_stack([n, c]), axis=0, return_index=True)[1]
        n, c = n[rep], c[rep]
        rounding = 0.0
        step = max(1, _BATCH // len(used))
        for start in range(0, len(n), step):
            rounding = max(rounding, float((n[start:start + step] @ used.T - c[start:start + step, None]).max()))
        diagonal = float(np.linalg.norm(used.max(axis=0) - used.min(axis=0)))
        rounding = max(rounding, 0.0)
        if rounding > CONVEX_SLACK * diagonal:
            return None
        return _Convex(v, f, n, c, rounding)


def _directed(x: _Convex, y: _Convex) -> tuple[float, float]:
    """``(upper, lower)`` from the largest distance of ``x``'s corners from ``y``'s solid."""
    corners = np.unique(x.faces)
    # Only corners outside y's solid (off the inner side of one of its planes) are any distance from it.
    outside = corners[(x.vertices[corners] @ y.normals.T - y.offsets).max(axis=1) > 0]
    near = _distances(x.vertices[outside], y.vertices, y.faces)
    far = float(near.max(initial=0.0))
    # y's corners off its planes by rounding move its surface by as much, and x's corners are
    # measured against y's triangles: both ways, twice the rounding covers it.
    return far + 2.0 * (x.rounding + y.rounding), far


def _distances(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Exact distance from each point to the triangle mesh: every pair for small ones (a convex
    group has a few hundred triangles), a search tree otherwise."""
    if len(points) * len(faces) > _ALL_PAIRS:
        return closest_distance(points, vertices, faces)[0]
    table = triangle_table(vertices[faces])
    pairs = table_distances(np.repeat(points, len(faces), axis=0), table, np.tile(np.arange(len(faces)), len(points)))
    return pairs.reshape(len(points), len(faces)).min(axis=1)
