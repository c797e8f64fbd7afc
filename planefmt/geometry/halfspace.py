"""Convex decoding: the intersection of half-spaces ``omega . x <= h`` as a triangle mesh (spec §9.5).

Method. The polytope ``P = {x : omega_i . x <= h_i}`` is computed through
duality: with ``c`` strictly inside ``P``, plane ``i`` maps to the dual point
``y_i = omega_i / (h_i - omega_i . c)``; the facets of the convex hull of the
``y_i`` are the vertices of ``P`` (a facet ``{y : u . y = 1}`` is the vertex
``c + u``), the hull's vertices are the planes that bound a face, and points
strictly inside the dual hull are redundant planes. This is what
``scipy.spatial.HalfspaceIntersection`` does with Qhull's "H" mode; we call
Qhull through ``scipy.spatial.ConvexHull`` on the dual points ourselves
because we need its simplices, equations and neighbours as arrays
(``HalfspaceIntersection`` returns dual facets as Python lists, which is
slow for 10^5 planes) and to merge vertices our own way. Qhull is exact
about combinatorics up to its own precision merging, O(n log n), and the
only 3-D hull in the dependency set (manifold3d's hull is no faster here and
gives no facet equations).

Robustness:

* The interior point ``c``: first the least-squares "centre" solving
  ``omega_i . x + s = h_i`` (one 4x4 solve; inside for all reasonably
  balanced plane sets); if it is not strictly inside, the Chebyshev centre
  from a linear program (``scipy.optimize.linprog``, HiGHS), which also
  decides emptiness: a largest inscribed ball of radius ~0 means an empty
  intersection or one without interior (``EMPTY_POLYTOPE``).
* Boundedness: ``P`` is bounded iff the origin is strictly inside the dual
  hull; a flat dual hull (normals in one plane) or a facet through the
  origin is ``UNBOUNDED_POLYTOPE``.
* Degenerate vertices (four or more planes through one point, e.g. the apex
  of a pyramid or the pole of a UV sphere): Qhull triangulates the dual
  facet, giving one candidate vertex per triangle. Candidates of adjacent
  dual triangles closer than a merge distance are merged into one vertex,
  which is then re-solved in least squares from all its incident planes
  (one Gauss-Newton step from the merged position). The merge distance is
  :data:`MERGE_TOLERANCE` x the polytope's diagonal, or more when the planes
  are known to be off by up to ``plane_error`` (quantized planes): a vertex
  where several planes met then splits into a cluster of vertices joined by
  edges a few plane errors long, and the cluster is merged back.
* Faces: the vertices incident to each plane are ordered by angle in a
  right-handed basis ``(e1, e2, omega)``, which is counter-clockwise seen
  from outside, and fanned into triangles. Planes left with fewer than three
  distinct vertices (they touch the solid at a point or along an edge, or
  repeat another plane) bound no face and are reported as redundant.

Units: coordinates and ``h`` in model units, angles in radians; output
triangles are counter-clockwise seen from outside (outward normals).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError, cKDTree

from ..errors import GeometryError
from .planes import from_triplets, in_plane_basis

#: Candidate vertices of adjacent dual triangles closer than this fraction of
#: the diagonal are one vertex. Far above the ~1e-15 relative error of a
#: float64 3-plane solve, far below any tolerance an encoder verifies.
MERGE_TOLERANCE = 1e-9

#: Clusters from planes off by ``plane_error`` are merged within this many times the largest
#: displacement of a plane at the polytope (``angle error x radius + h error``): vertices move
#: by about the displacement over the sine of the angle between the planes meeting there, and
#: on random hulls the spurious edges measured up to ~1000 displacements (genuine ones: 1e4+).
MERGE_SPREAD = 1000.0
#: ... but never more than this fraction of the polytope's diagonal (nor the caller's limit).
MERGE_CAP = 1e-2

#: Relative margin below which a point is not strictly inside, and a
#: Chebyshev radius below which the intersection has no interior.
_INTERIOR_EPS = 1e-12
#: Dual facets closer to the origin than this (relative to the dual points' size) are vertices over
#: 1e9 times farther from the interior point than its nearest plane: above the joggle of "QJ"
#: (~1e-11). Boundedness is decided before (BOUNDED_MARGIN), so such a vertex means a sliver, or a
#: point hugging one face, and the Chebyshev centre decides.
_UNBOUNDED_EPS = 1e-9


@dataclass(frozen=True)
class Polytope:
    """A decoded convex polytope.

    ``vertices`` (V, 3) float64 in model units; ``triangles`` (T, 3) int64,
    counter-clockwise seen from outside; ``triangle_plane`` (T,) the index of
    the input plane each triangle lies on. Faces as polygons:
    ``polygon_vertices`` (flat, counter-clockwise per polygon) split by
    ``polygon_offsets`` (F + 1,), on planes ``polygon_plane`` (F,).
    ``redundant`` (ascending plane indices) bound no face. ``interior`` is a
    point strictly inside.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    triangle_plane: np.ndarray
    polygon_offsets: np.ndarray
    polygon_vertices: np.ndarray
    polygon_plane: np.ndarray
    redundant: np.ndarray
    interior: np.ndarray

    @property
    def incidences(self) -> tuple[np.ndarray, np.ndarray]:
        """``(vertex, plane)`` index pairs: each polygon vertex with the plane of its polygon."""
        sizes = np.diff(self.polygon_offsets)
        return self.polygon_vertices, np.repeat(self.polygon_plane, sizes)


def decode_convex(triplets: np.ndarray, *, group: object = None,
                  plane_error: tuple[float, float] = (0.0, 0.0), merge_limit: float = math.inf) -> Polytope:
    """The polytope of plane triplets ``(n, 3)`` ``(nu, phi, h)``; see :func:`intersect`."""
    omega, h = from_triplets(triplets)
    return intersect(omega, h, group=group, plane_error=plane_error, merge_limit=merge_limit)


def intersect(omega: np.ndarray, h: np.ndarray, *, group: object = None,
              plane_error: tuple[float, float] = (0.0, 0.0), merge_limit: float = math.inf) -> Polytope:
    """The polytope ``{x : omega_i . x <= h_i}`` of planes ``omega`` (n, 3), ``h`` (n,).

    ``group`` names the part group in error messages. ``plane_error`` is how
    far the planes may be from the ones meant, ``(radians, model units)``
    for the normal and ``h`` (e.g. half a quantization step); it widens the
    merging of degenerate vertices (module docstring), but never beyond
    ``merge_limit`` (model units). Raises
    ``GeometryError`` with code ``EMPTY_POLYTOPE`` (empty, or no interior),
    ``UNBOUNDED_POLYTOPE``, or ``DEGENERATE_GEOMETRY`` (malformed planes).
    """
    label = "planes" if group is None else f"part group {group}"
    omega = np.asarray(omega, dtype=np.float64).reshape(-1, 3)
    h = np.asarray(h, dtype=np.float64).reshape(-1)
    if len(omega) != len(h) or len(h) == 0:
        raise GeometryError(f"{label}: need one h per normal and at least one plane")
    length = np.linalg.norm(omega, axis=1)
    if not (np.isfinite(omega).all() and np.isfinite(h).all() and (length > 0).all()):
        raise GeometryError(f"{label}: plane normals and distances must be finite and non-zero")
    omega = omega / length[:, None]
    h = h / length
    # Decided at unit size (spec §9.4's conditions are relative): a power of two scales exactly, and
    # Qhull fails on the dual points of a solid 1e-101 across (1e101 from the origin).
    reach = float(np.abs(h).max())
    unit = 2.0 ** -round(math.log2(reach)) if reach > 0 else 1.0
    if unit != 1.0:
        poly = _intersect(omega, h * unit, label, (plane_error[0], plane_error[1] * unit), merge_limit * unit)
        return Polytope(**{**poly.__dict__, "vertices": poly.vertices / unit, "interior": poly.interior / unit})
    return _intersect(omega, h, label, plane_error, merge_limit)


#: The least margin by which the unit normals of a bounded polytope surround the origin (spec §9.4):
#: every direction u has a normal with omega . u at least this, so no point of the polytope lies
#: farther from the origin than max |h| / this. Float32's angles tilt parallel planes by ~1e-7:
#: a cube missing a plane is unbounded, not closed 10^7 away.
BOUNDED_MARGIN = 1e-6


def _normal_margin(omega: np.ndarray) -> float:
    """min over unit u of max_i omega_i . u: the distance from the origin to the boundary of the
    hull of the unit normals (0 or less where they lie in a half-space or a plane)."""
    try:
        hull = ConvexHull(omega)
    except (QhullError, ValueError):
        return 0.0
    return float(-hull.equations[:, 3].max())


def _intersect(omega: np.ndarray, h: np.ndarray, label: str, plane_error: tuple[float, float],
               merge_limit: float) -> Polytope:
    """:func:`intersect` of unit normals ``omega`` and ``h`` at unit size."""
    c = _interior_point(omega, h, label)
    if _normal_margin(omega) < BOUNDED_MARGIN:
        raise _unbounded(label, f"the plane normals surround no direction by {BOUNDED_MARGIN:g} (spec §9.4)")
    try:
        poly = _from_point(omega, h, c, label, plane_error, merge_limit)
    except _FarFromCentre:
        # The least-squares centre hugs a face of a long solid: the deepest point decides.
        c = _interior_point(omega, h, label, least_squares=False)
        try:
            poly = _from_point(omega, h, c, label, plane_error, merge_limit)
        except _FarFromCentre:
            raise GeometryError(f"{label}: a sliver thinner than 1e-9 of its extent has no interior (spec §9.4)",
                                code="EMPTY_POLYTOPE") from None
    faces = poly.polygon_plane
    v = poly.vertices
    width = float((h[faces][:, None] - omega[faces] @ v.T).max(axis=1).min())
    extent = float(np.linalg.norm(np.ptp(v, axis=0)))
    if not width > THIN * extent:
        raise GeometryError(f"{label}: the solid is {width:.3g} thick across {extent:.3g}, at most {THIN:g} of "
                            f"its extent: no interior (spec §9.4)", code="EMPTY_POLYTOPE")
    return poly


#: A polytope thinner than this fraction of its diagonal (its least extent along a face's normal) has
#: no interior (spec §9.4): far above float64's rounding at the polytope, below any solid a mesh holds.
THIN = 1e-8


class _FarFromCentre(Exception):
    """A vertex 1e9 times farther from the interior point than its nearest plane."""


def _from_point(omega: np.ndarray, h: np.ndarray, c: np.ndarray, label: str, plane_error: tuple[float, float],
                merge_limit: float) -> Polytope:
    """:func:`_intersect` from the interior point ``c`` of a bounded intersection."""
    # Near-copies of one plane (all but the innermost redundant) would put clusters of dual points
    # closer than Qhull's joggle: one copy each.
    slack = h - omega @ c
    kept = _distinct(omega, slack)
    n_all = len(h)
    omega, h, rhs = omega[kept], h[kept], slack[kept]
    dual = omega / rhs[:, None]
    if len(h) < 4:
        raise _unbounded(label, "fewer than four planes never bound a solid")
    simplices, candidates, reliable, vertex, merge = _vertices(omega, rhs, dual, c, label, plane_error,
                                                               merge_limit, joggle=True)
    if vertex is None:
        # Some vertex is only known from loose triples (planes nearly dependent three at a time,
        # and no group of them pins a point): Qhull's own merging decides, at O(k^2) for k
        # planes through one point.
        simplices, candidates, reliable, vertex, merge = _vertices(omega, rhs, dual, c, label, plane_error,
                                                                   merge_limit, joggle=False)
    nv = int(vertex.max()) + 1

    # Incidences (vertex, plane), each once.
    key = np.unique(np.repeat(vertex, 3) * np.int64(len(h)) + simplices.reshape(-1))
    inc = np.column_stack(np.divmod(key, np.int64(len(h))))
    positions = _refine(omega, rhs, candidates, reliable, vertex, nv, inc) + c

    offsets_out, order, polygon_plane = _faces(omega, positions, inc)
    if len(polygon_plane) < 4:
        raise GeometryError(f"{label}: the solid collapses to a point, segment or polygon when "
                            f"vertices closer than {merge:.3g} merge", code="EMPTY_POLYTOPE")
    tri, tri_plane = _fan(offsets_out, order, polygon_plane)
    polygon_plane, tri_plane = kept[polygon_plane], kept[tri_plane]
    used_vertices, remap = np.unique(tri, return_inverse=True)
    used = np.zeros(n_all, dtype=bool)
    used[polygon_plane] = True
    return Polytope(vertices=positions[used_vertices], triangles=remap.reshape(-1, 3),
                    triangle_plane=tri_plane, polygon_offsets=offsets_out,
                    polygon_vertices=np.searchsorted(used_vertices, order),
                    polygon_plane=polygon_plane, redundant=np.flatnonzero(~used), interior=c)


#: Planes whose unit normals and distances (relative to the largest distance from the interior
#: point) differ by less than this are copies of one plane.
DUPLICATE_TOLERANCE = 1e-10


def _innermost(slack: np.ndarray, label: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Of ``candidates``, the one with the least slack per label."""
    order = candidates[np.lexsort((slack[candidates], label[candidates]))]
    first = np.ones(len(order), dtype=bool)
    first[1:] = label[order][1:] != label[order][:-1]
    return order[first]


def _distinct(omega: np.ndarray, slack: np.ndarray) -> np.ndarray:
    """Indices of the planes to intersect: of each group of near-copies, the innermost.

    Planes first fall into grid cells of side :data:`DUPLICATE_TOLERANCE` (one copy per cell),
    then copies in neighbouring cells are joined: at most 3^4 cells lie within reach of one, so
    the pair search stays linear however many copies a file repeats.
    """
    key = np.column_stack([omega, slack / float(slack.max())])
    cell = np.unique(np.floor(key / DUPLICATE_TOLERANCE).astype(np.int64), axis=0, return_inverse=True)[1]
    rep = np.sort(_innermost(slack, cell.reshape(-1), np.arange(len(slack))))
    pairs = cKDTree(key[rep]).query_pairs(DUPLICATE_TOLERANCE, output_type="ndarray")
    if not len(pairs):
        return rep
    label = connected_components(coo_matrix((np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])),
                                            shape=(len(rep),) * 2), directed=False)[1]
    full = np.zeros(len(slack), dtype=np.int64)
    full[rep] = label
    return np.sort(_innermost(slack, full, rep))


def _vertices(omega: np.ndarray, rhs: np.ndarray, dual: np.ndarray, c: np.ndarray, label: str,
              plane_error: tuple[float, float], merge_limit: float, *, joggle: bool):
    """Dual hull, candidate points and vertex labels: ``(simplices, points, reliable, labels, merge)``.

    ``joggle``: Qhull's "QJ" (O(m log m) also for k planes through one point, whose cost under
    Qhull's coplanar merging is O(k^2): 6.6 s for k = 10^4), the points solved from the planes
    and merged by :func:`_merge_vertices`; ``labels`` is None where a vertex stays known only
    from loose triples. Otherwise "Qt": the merged facets' points, merged by distance.
    """
    try:
        hull = ConvexHull(dual, qhull_options="QJ" if joggle else "Qt")
    except QhullError:
        raise _unbounded(label, "the plane normals do not span space") from None
    # Offsets are -1/|u| for vertex c + u: a facet through (or near) the origin is a vertex at
    # infinity, i.e. a direction in which the solid does not end.
    offsets = hull.equations[:, 3]
    if not (offsets < -_UNBOUNDED_EPS * np.abs(dual).max()).all():
        raise _FarFromCentre()
    simplices = hull.simplices.astype(np.int64)
    facet_points = -hull.equations[:, :3] / offsets[:, None]
    if joggle:
        points, reliable = _triple_points(omega, rhs, simplices, facet_points)
    else:
        points, reliable = facet_points, np.ones(len(simplices), dtype=bool)
    extent = float(np.linalg.norm(np.ptp(points[reliable] if reliable.any() else points, axis=0)))
    radius = float(np.linalg.norm(points + c, axis=1).max())
    merge = max(MERGE_TOLERANCE * extent, min(MERGE_CAP * extent, merge_limit,
                                              MERGE_SPREAD * (plane_error[0] * radius + plane_error[1])))
    if not joggle:
        return simplices, points, reliable, _merge_adjacent(points, hull.neighbors, merge), merge
    labels = _merge_vertices(omega, rhs, points, reliable, simplices, hull.neighbors, merge)
    if not _pinned(omega, reliable, simplices, labels):
        labels = None
    return simplices, points, reliable, labels, merge


def _pinned(omega: np.ndarray, reliable: np.ndarray, simplices: np.ndarray, labels: np.ndarray) -> bool:
    """Whether every vertex has a reliable point or planes that pin one (as resolve_vertices needs)."""
    k = int(labels.max()) + 1
    loose = np.bincount(labels, weights=reliable, minlength=k) == 0
    if not loose.any():
        return True
    inc = _label_planes(labels, simplices, loose[labels])
    return bool((np.linalg.det(_normal_matrices(omega, inc[:, 0], inc[:, 1], k)[loose]) > 1e-12).all())


def _label_planes(labels: np.ndarray, simplices: np.ndarray, sel: np.ndarray) -> np.ndarray:
    """``(label, plane)`` pairs, each once, of the dual triangles ``sel``."""
    return np.unique(np.column_stack([np.repeat(labels[sel], 3), simplices[sel].reshape(-1)]), axis=0)


def _normal_matrices(omega: np.ndarray, owner: np.ndarray, plane: np.ndarray, k: int) -> np.ndarray:
    """``sum omega omega^T`` (k, 3, 3) over the planes of each owner."""
    w = omega[plane]
    out = np.zeros((k, 3, 3))
    np.add.at(out, owner, w[:, :, None] * w[:, None, :])
    return out


def _merge_adjacent(points: np.ndarray, neighbors: np.ndarray, tol: float) -> np.ndarray:
    """Labels ``0..k-1`` merging points of adjacent dual triangles that lie within ``tol``."""
    n = len(points)
    a = np.repeat(np.arange(n), 3)
    b = neighbors.reshape(-1)
    close = (b > a) & (np.linalg.norm(points[a] - points[np.maximum(b, 0)], axis=1) <= tol)
    return _components(n, a[close], b[close])


def _unbounded(label: str, why: str) -> GeometryError:
    return GeometryError(f"{label}: the half-spaces do not bound a finite solid ({why})",
                         code="UNBOUNDED_POLYTOPE")


def _interior_point(omega: np.ndarray, h: np.ndarray, label: str, least_squares: bool = True) -> np.ndarray:
    """A point strictly inside every half-space (the least-squares centre where it is, else the
    Chebyshev centre), or ``EMPTY_POLYTOPE``."""
    scale = max(float(np.abs(h).max()), 1e-300)
    a = np.column_stack([omega, np.ones(len(h))])
    if len(h) >= 4 and least_squares:
        # The point equidistant (in least squares) from all planes: the centre of the inscribed
        # sphere for spheres and boxes, and inside for most solids.
        ata = a.T @ a
        if np.linalg.cond(ata) < 1e12:
            x = np.linalg.solve(ata, a.T @ h)[:3]
            margin = h - omega @ x
            if margin.min() > _INTERIOR_EPS * max(scale, float(np.abs(margin).max())):
                return x
    # Chebyshev centre: maximise r subject to omega_i . x + r <= h_i, with r capped so that the
    # program stays bounded when the solid is not (boundedness is decided afterwards).
    cap = 1e6 * max(scale, 1.0)
    res = linprog(c=[0.0, 0.0, 0.0, -1.0], A_ub=a, b_ub=h,
                  bounds=[(None, None)] * 3 + [(None, cap)], method="highs")
    if res.status != 0 or res.x is None:
        raise GeometryError(f"{label}: no interior point found ({res.message})", code="EMPTY_POLYTOPE")
    x, r = res.x[:3], res.x[3]
    # The solver's own feasibility tolerance (about 1e-7) can leave its point on or past a plane
    # when the solid is that thin: the margin that counts is the point's, not the reported radius.
    margin = float((h - omega @ x).min())
    if not min(r, margin) > _INTERIOR_EPS * max(scale, float(np.abs(x).max())):
        raise GeometryError(f"{label}: the half-spaces have an empty intersection or one without "
                            f"interior (largest inscribed ball radius {min(r, margin):.3g})", code="EMPTY_POLYTOPE")
    return x


#: A triple of unit normals spanning less volume than this pins its point too loosely to place
#: a vertex by it (a float64 solve then errs by up to ~1e-16 / this of the coordinates' size,
#: which the least-squares refinement over all the vertex's planes removes). 1e-6 sent
#: float32-coded sphere hulls to the slow path for triples that were accurate to 1e-10.
RELIABLE_DET = 1e-9


def _triple_points(omega: np.ndarray, rhs: np.ndarray, simplices: np.ndarray,
                   fallback: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The point of each dual triangle's three planes (relative to the interior point), and
    whether it is reliable.

    Solved from the planes themselves, not from the joggled facet. A triple whose normals are
    nearly dependent (:data:`RELIABLE_DET`) is not: its point, solved or the facet's
    ``fallback``, only serves until a neighbour's reliable point takes its place.
    """
    a = omega[simplices]
    det = np.abs(np.linalg.det(a))
    solvable = det > 1e-12
    out = fallback.copy()
    if solvable.any():
        out[solvable] = np.linalg.solve(a[solvable], rhs[simplices[solvable]][:, :, None])[:, :, 0]
    return out, det >= RELIABLE_DET


def _components(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    if not len(a):
        return np.arange(n)
    graph = coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(n, n))
    return connected_components(graph, directed=False)[1].astype(np.int64)


def _merge_vertices(omega: np.ndarray, rhs: np.ndarray, points: np.ndarray, reliable: np.ndarray,
                    simplices: np.ndarray, neighbors: np.ndarray, tol: float) -> np.ndarray:
    """Labels ``0..k-1`` of the dual triangles' points: one label per vertex of the polytope.

    Points of adjacent dual triangles are one vertex when closer than ``tol``. Copies of a
    vertex on many planes, solved from nearly dependent triples (:func:`_triple_points`), can
    be far apart along the direction those triples leave free (the apex of a cone of 10^5
    planes: 0.5 apart on a cone 1.4 across) while every plane of the vertex passes through the vertex.
    Two more rules join them, each tried only where the previous one left points apart: a
    reliable point lying within ``tol`` of the neighbour's three planes; then adjacent
    unreliable triangles. A group a rule joins is kept only if its planes pin one point (their
    normals span space: smallest eigenvalue of the normal matrix at least 1e-6 of the largest)
    lying within ``tol`` of all of them; otherwise its points keep their previous labels.
    """
    n = len(points)
    a = np.repeat(np.arange(n), 3)
    b = neighbors.reshape(-1)
    live = b > a
    a, b = a[live], b[live]
    near = np.linalg.norm(points[a] - points[b], axis=1) <= tol

    def off_planes(p: np.ndarray, q: np.ndarray) -> np.ndarray:
        tri = simplices[q]
        return np.abs(rhs[tri] - np.einsum("ijk,ik->ij", omega[tri], points[p])).max(axis=1)

    labels = _components(n, a[near], b[near])
    edges = near
    for rule in (lambda: (reliable[a] & (off_planes(a, b) <= tol)) | (reliable[b] & (off_planes(b, a) <= tol)),
                 lambda: ~reliable[a] & ~reliable[b]):
        extra = ~edges & rule()
        if not extra.any():
            continue
        edges = edges | extra
        labels = _accept(omega, rhs, points, reliable, simplices, _components(n, a[edges], b[edges]), labels, tol)
    return labels


def _accept(omega: np.ndarray, rhs: np.ndarray, points: np.ndarray, reliable: np.ndarray,
            simplices: np.ndarray, joined: np.ndarray, previous: np.ndarray, tol: float) -> np.ndarray:
    """``joined`` labels where a joined group's planes pin one point within ``tol``, else ``previous``."""
    k = int(joined.max()) + 1
    representative = np.full(k, -1, dtype=np.int64)
    representative[joined[::-1]] = previous[::-1]
    changed = np.zeros(k, dtype=bool)
    changed[joined[previous != representative[joined]]] = True
    group = np.flatnonzero(changed)
    if not len(group):
        return previous
    inc = _label_planes(joined, simplices, changed[joined])
    w = omega[inc[:, 1]]
    eig = np.linalg.eigvalsh(_normal_matrices(omega, inc[:, 0], inc[:, 1], k)[group])
    spans = eig[:, 0] >= 1e-6 * eig[:, 2]
    local = np.full(k, -1, dtype=np.int64)
    local[group] = np.arange(len(group))
    inc_local = local[inc[:, 0]]
    start = _group_means(points, reliable, joined, k)[group]
    position = resolve_vertices(start, inc_local, inc[:, 1], omega, rhs)
    resid = np.zeros(len(group))
    np.maximum.at(resid, inc_local, np.abs(rhs[inc[:, 1]] - np.einsum("ij,ij->i", w, position[inc_local])))
    accepted = np.zeros(k, dtype=bool)
    accepted[group[spans & (resid <= tol)]] = True
    key = np.where(accepted[joined] | ~changed[joined], joined, k + previous)
    return np.unique(key, return_inverse=True)[1].astype(np.int64)


def _group_means(points: np.ndarray, reliable: np.ndarray, label: np.ndarray, k: int) -> np.ndarray:
    """Mean point of each label, over its reliable points where it has any."""
    has = np.bincount(label, weights=reliable, minlength=k) > 0
    weight = np.where(reliable | ~has[label], 1.0, 0.0)
    count = np.bincount(label, weights=weight, minlength=k)
    total = np.column_stack([np.bincount(label, weights=weight * points[:, i], minlength=k) for i in range(3)])
    return total / np.maximum(count, 1e-300)[:, None]


def _refine(omega: np.ndarray, rhs: np.ndarray, candidates: np.ndarray, reliable: np.ndarray,
            vertex: np.ndarray, nv: int, inc: np.ndarray) -> np.ndarray:
    """Vertex positions relative to the interior point (``rhs`` is ``h - omega . c``).

    Starts from the mean of each vertex's merged candidates (its reliable ones where it has
    any) and re-solves it from all its incident planes (:func:`resolve_vertices`).
    """
    return resolve_vertices(_group_means(candidates, reliable, vertex, nv), inc[:, 0], inc[:, 1], omega, rhs)


def resolve_vertices(start: np.ndarray, inc_vertex: np.ndarray, inc_plane: np.ndarray,
                     omega: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Vertices ``(V, 3)`` moved onto their incident planes by one Gauss-Newton step.

    Each vertex ``v`` of ``start`` lies (nearly) on the planes ``inc_plane[j]``
    for ``inc_vertex[j] == v``; the step solves the least-squares system of
    those planes' residuals ``h - omega . v``. It is exact for three planes in
    general position and, for planes that moved slightly (quantization), it is
    where the vertex goes when the solid's combinatorics do not change.
    Vertices whose normal matrix is ill-conditioned (planes meeting at a
    grazing angle) keep ``start``. Model units throughout.
    """
    nv = len(start)
    w = omega[inc_plane]
    resid = h[inc_plane] - np.einsum("ij,ij->i", w, start[inc_vertex])
    ata = _normal_matrices(omega, inc_vertex, inc_plane, nv)
    atr = np.column_stack([np.bincount(inc_vertex, weights=w[:, i] * resid, minlength=nv)
                           for i in range(3)])
    ok = np.linalg.det(ata) > 1e-12
    out = np.array(start, dtype=np.float64)
    if ok.any():
        out[ok] += np.linalg.solve(ata[ok], atr[ok][:, :, None])[:, :, 0]
    return out


def _faces(omega: np.ndarray, positions: np.ndarray,
           inc: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Polygons ``(offsets, vertex order, plane)``: incident vertices sorted counter-clockwise.

    A plane with fewer than three distinct vertices only touches the solid
    (at a vertex or along an edge) and gets no polygon.
    """
    vi, pi = inc[:, 0], inc[:, 1]
    counts = np.bincount(pi, minlength=len(omega))
    keep = counts[pi] >= 3
    vi, pi = vi[keep], pi[keep]
    # float64 also where no plane keeps three vertices: bincount of nothing is an integer array
    centre = np.column_stack([np.bincount(pi, weights=positions[vi, i], minlength=len(omega))
                              for i in range(3)]).astype(np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        centre /= counts[:, None]
    e1, e2 = in_plane_basis(omega)
    d = positions[vi] - centre[pi]
    angle = np.arctan2(np.einsum("ij,ij->i", d, e2[pi]), np.einsum("ij,ij->i", d, e1[pi]))
    order = np.lexsort((angle, pi))
    planes, size = np.unique(pi[order], return_counts=True)
    return np.concatenate([[0], np.cumsum(size)]), vi[order], planes


def _fan(offsets: np.ndarray, order: np.ndarray, plane: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fan triangles ``(v0, vi, vi+1)`` of each polygon, and the plane of each triangle."""
    size = np.diff(offsets)
    per = size - 2
    poly = np.repeat(np.arange(len(size)), per)
    local = np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per) + 1
    base = offsets[:-1][poly]
    tri = np.column_stack([order[base], order[base + local], order[base + local + 1]])
    return tri, plane[poly]
