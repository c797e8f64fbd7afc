"""Polygonization: adjacent coplanar triangles become one polygon on one plane (paper §6).

Coplanarity is decided by **distance**, not by the angle between triangle
normals: two adjacent triangles are coplanar when the far vertex of one lies
within ``tolerance x diagonal`` of the other's plane (``diagonal`` the
bounding-box diagonal, model units). On CAD meshes stored as float32 (STL),
long thin triangles have normals that are off by far more than any sensible
angle threshold while their vertices are on the plane to within float32
rounding; an angle test splits such faces into many planes.

Long thin triangles whose height is below the tolerance ("slivers") have no
reliable plane at all; they join an adjacent polygon whose plane holds their
three vertices, and only form a polygon of their own when none does.

Then each polygon gets one fitted plane: its normal is the direction of the
polygon's vector area (the sum of its triangles' cross products, which
weighs each triangle by its area and so lets the big, well-conditioned ones
decide), ``h`` is taken at the area-weighted centroid. Polygons on the same
plane (not adjacent, e.g. two coplanar faces of a CAD part) share one plane:
planes are deduplicated with ``numpy.unique`` on rounded rows and refitted.

Everything is vectorized over triangles; conventions are those of
:mod:`planefmt.geometry.planes` (outward normals, ``omega . x <= h`` inside,
counter-clockwise faces seen from outside).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..errors import GeometryError
from .planes import to_triplets

#: Default coplanarity tolerance, as a fraction of the bounding-box diagonal.
#: The plane counts of the corpus's float32 CAD meshes reach a plateau from
#: about 2e-7 (float32 rounding of coordinates up to ~3 diagonals from the
#: origin) to beyond 1e-6; this is half the codec's default tolerance.
COPLANAR_TOLERANCE = 5e-7

#: A fitted plane may be this many tolerances away from a vertex of its
#: polygon before the polygon is judged a curved surface and split up.
_DRIFT = 4.0

#: Sliver attachment spreads at most this many triangles along a chain of slivers.
_SLIVER_ROUNDS = 16


@dataclass(frozen=True)
class Edges:
    """Undirected edges shared by two triangle sides (or more, at non-manifold edges).

    ``a``, ``b``: flat side ids ``3 * triangle + slot`` of the two sides of
    each shared edge, where side ``slot`` of face ``f`` runs from
    ``f[slot]`` to ``f[(slot + 1) % 3]``. ``closed`` is True when every side
    is shared with exactly one other side running the opposite way (a closed,
    consistently oriented, edge-manifold surface).
    """

    a: np.ndarray
    b: np.ndarray
    closed: bool


def edge_adjacency(faces: np.ndarray, vertex_count: int) -> Edges:
    """The pairs of triangle sides lying on the same undirected edge."""
    f = np.asarray(faces, dtype=np.int64)
    start = f.reshape(-1)
    end = f[:, [1, 2, 0]].reshape(-1)
    lo, hi = np.minimum(start, end), np.maximum(start, end)
    key = lo * np.int64(vertex_count) + hi
    order = np.argsort(key, kind="stable")
    ks = key[order]
    same = ks[1:] == ks[:-1]
    a, b = order[:-1][same], order[1:][same]
    # Closed and oriented: every key occurs exactly twice, as u->v and v->u.
    counts = np.diff(np.flatnonzero(np.r_[True, ks[1:] != ks[:-1], True]))
    closed = bool(len(f)) and bool((counts == 2).all()) and bool(
        (start[a] == end[b]).all() and (end[a] == start[b]).all())
    return Edges(a=a, b=b, closed=closed)


@dataclass(frozen=True)
class Polygons:
    """The polygonization of a triangle mesh.

    ``vertices`` (n, 3) float64 are the input vertices welded by exact
    position and ``faces`` (m, 3) the input faces re-indexed to them (same
    order as the input). ``omega`` (k, 3), ``h`` (k,) are the distinct
    planes (model units); ``area`` (k,) the face area on each (model units
    squared); ``distance`` (k,) the largest distance of a vertex of a face on
    the plane to the plane (model units). ``face_plane`` (m,) and
    ``face_polygon`` (m,) give each face's plane and connected polygon (-1
    for faces of zero area, which lie on no plane); ``polygon_plane`` (p,)
    each polygon's plane. ``diagonal`` is the bounding-box diagonal.
    """

    vertices: np.ndarray
    faces: np.ndarray
    omega: np.ndarray
    h: np.ndarray
    area: np.ndarray
    distance: np.ndarray
    face_plane: np.ndarray
    face_polygon: np.ndarray
    polygon_plane: np.ndarray
    diagonal: float

    @property
    def max_distance(self) -> float:
        """Largest vertex-to-fitted-plane distance over all planes, in model units."""
        return float(self.distance.max(initial=0.0))

    @property
    def triplets(self) -> np.ndarray:
        """The planes as ``(k, 3)`` triplets ``(nu, phi, h)``."""
        return to_triplets(self.omega, self.h)


def weld(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices with identical coordinates (STL repeats them per triangle)."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
        raise GeometryError(f"vertices must be (n, 3) and faces (m, 3), not {v.shape} and {f.shape}")
    if len(f) == 0:
        raise GeometryError("the mesh has no faces")
    if f.min() < 0 or f.max() >= len(v):
        raise GeometryError(f"face indices must lie in 0..{len(v) - 1}")
    if not np.isfinite(v).all():
        raise GeometryError("vertex coordinates must be finite")
    used, f = np.unique(f, return_inverse=True)
    unique, inverse = np.unique(v[used], axis=0, return_inverse=True)
    return unique, inverse.reshape(-1)[f.reshape(-1)].reshape(-1, 3)


def polygonize(vertices: np.ndarray, faces: np.ndarray, *,
               tolerance: float = COPLANAR_TOLERANCE, max_drift: float | None = None) -> Polygons:
    """Merge adjacent coplanar triangles into polygons and fit one plane per distinct plane.

    ``tolerance`` is a fraction of the bounding-box diagonal (see the module
    docstring); ``max_drift`` (same unit) caps how far a fitted plane may be
    from a vertex of its faces (default ``_DRIFT`` tolerances): a polygon or
    merged plane that strays further is split up. Raises ``GeometryError``
    for malformed or empty input and for a mesh of zero area.
    """
    v, f = weld(vertices, faces)
    diagonal = float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))
    if diagonal == 0.0:
        raise GeometryError("all vertices coincide: the mesh has no area")
    eps = tolerance * diagonal
    drift = _DRIFT * eps if max_drift is None else min(_DRIFT * eps, max_drift * diagonal)
    m = len(f)
    p = v[f]  # (m, 3 corners, 3)
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 1])
    norm = np.linalg.norm(cross, axis=1)
    longest = np.linalg.norm(p - p[:, [1, 2, 0]], axis=2).max(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = cross / norm[:, None]
        sliver = ~(norm / longest > eps)  # height <= eps, including zero area and NaN
    unit[sliver] = 0.0

    edges = edge_adjacency(f, len(v))
    ta, sa = np.divmod(edges.a, 3)
    tb, sb = np.divmod(edges.b, 3)
    # Far vertex of each side's triangle, tested against the plane of the triangle with the
    # larger area (the better-conditioned normal), measured from a vertex of the shared edge.
    far_a, far_b = f[ta, (sa + 2) % 3], f[tb, (sb + 2) % 3]
    ref_is_a = norm[ta] >= norm[tb]
    ref = np.where(ref_is_a, ta, tb)
    far = np.where(ref_is_a, far_b, far_a)
    d = np.abs(np.einsum("ij,ij->i", unit[ref], v[far] - v[f[ta, sa]]))
    coplanar = ((d <= eps) & (np.einsum("ij,ij->i", unit[ta], unit[tb]) > 0.0)
                & ~sliver[ta] & ~sliver[tb])
    polygon = _components(m, ta[coplanar], tb[coplanar])
    polygon[sliver] = -1
    polygon = _renumber(polygon)

    omega, h = _fit(v, f, cross, polygon, polygon.max() + 1)
    dist = _corner_distances(v, f, omega, h, polygon)
    # A polygon whose vertices stray from its fitted plane is a gently curved surface that the
    # pairwise test chained together: keep its triangles as separate polygons instead.
    curved = _max_per_label(dist, polygon, len(omega)) > drift
    if curved.any():
        split = (polygon >= 0) & curved[np.maximum(polygon, 0)]
        polygon[split] = polygon.max() + 1 + np.arange(int(split.sum()))
        polygon = _renumber(polygon)
        omega, h = _fit(v, f, cross, polygon, polygon.max() + 1)

    polygon = _attach_slivers(v, f, sliver, polygon, omega, h, ta, tb, eps)
    lone = sliver & (polygon < 0) & (norm > 0)
    polygon[lone] = polygon.max() + 1 + np.arange(int(lone.sum()))
    unit[lone] = cross[lone] / norm[lone, None]
    omega, h = _fit(v, f, cross, polygon, polygon.max() + 1)

    plane, polygon_plane = _dedupe(v, f, cross, polygon, omega, h, eps, tolerance, drift)
    k = polygon_plane.max() + 1
    omega, h = _fit(v, f, cross, plane, k)
    dist = _corner_distances(v, f, omega, h, plane)
    area = np.bincount(plane[plane >= 0], weights=0.5 * norm[plane >= 0], minlength=k)
    return Polygons(vertices=v, faces=f, omega=omega, h=h, area=area,
                    distance=_max_per_label(dist, plane, k), face_plane=plane, face_polygon=polygon,
                    polygon_plane=polygon_plane, diagonal=diagonal)


def split_planes(poly: Polygons, label: np.ndarray) -> Polygons:
    """``poly`` with every plane split into one plane per distinct ``label`` (m,) of its faces, and
    every polygon likewise: the planes of a shell carry its colours (spec §10.1: one colour per
    reference), so faces of one plane in two colours need two planes, of equal ``omega`` and ``h``.
    Planes and polygons of one label keep their order; a plane of one label is unchanged."""
    label = np.asarray(label, dtype=np.int64)
    on = poly.face_plane >= 0
    span = int(label.max(initial=0)) + 1
    plane_key, plane = np.unique(poly.face_plane[on] * span + label[on], return_inverse=True)
    polygon_key, polygon = np.unique(poly.face_polygon[on] * span + label[on], return_inverse=True)
    face_plane = np.full(len(label), -1, dtype=np.int64)
    face_polygon = np.full(len(label), -1, dtype=np.int64)
    face_plane[on], face_polygon[on] = plane, polygon
    source = plane_key // span
    p = poly.vertices[poly.faces[on]]
    area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 1]), axis=1) * 0.5
    polygon_plane = np.empty(len(polygon_key), dtype=np.int64)
    polygon_plane[polygon] = plane
    return Polygons(vertices=poly.vertices, faces=poly.faces, omega=poly.omega[source], h=poly.h[source],
                    area=np.bincount(plane, weights=area, minlength=len(plane_key)),
                    distance=poly.distance[source], face_plane=face_plane, face_polygon=face_polygon,
                    polygon_plane=polygon_plane, diagonal=poly.diagonal)


def _components(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    graph = coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(n, n))
    return connected_components(graph, directed=False)[1].astype(np.int64)


def _renumber(labels: np.ndarray) -> np.ndarray:
    """Labels ``0..k-1`` for the non-negative labels, in order of first appearance; -1 stays."""
    out = np.full(len(labels), -1, dtype=np.int64)
    keep = labels >= 0
    _, first, inverse = np.unique(labels[keep], return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    out[keep] = rank[inverse]
    return out


def _fit(v: np.ndarray, f: np.ndarray, cross: np.ndarray, label: np.ndarray,
         k: int) -> tuple[np.ndarray, np.ndarray]:
    """One plane per label: normal along the vector area, through the area-weighted centroid."""
    keep = label >= 0
    lab = label[keep]
    c = cross[keep]
    area2 = np.linalg.norm(c, axis=1)
    centroid = v[f[keep]].mean(axis=1)
    vec = np.column_stack([np.bincount(lab, weights=c[:, i], minlength=k) for i in range(3)])
    weight = np.bincount(lab, weights=area2, minlength=k)
    total = np.column_stack([np.bincount(lab, weights=area2 * centroid[:, i], minlength=k)
                             for i in range(3)])
    length = np.linalg.norm(vec, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        omega = vec / length[:, None]
        point = total / weight[:, None]
    # A label of slivers only has no area to weigh by: its single triangle decides.
    degenerate = ~(length > 0) | ~(weight > 0)
    if degenerate.any():
        first = np.full(k, -1, dtype=np.int64)
        first[lab[::-1]] = np.flatnonzero(keep)[::-1]
        idx = first[degenerate]
        cn = np.linalg.norm(cross[idx], axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            omega[degenerate] = cross[idx] / cn
        point[degenerate] = v[f[idx]].mean(axis=1)
    h = np.einsum("ij,ij->i", omega, point)
    return omega, h


def _corner_distances(v: np.ndarray, f: np.ndarray, omega: np.ndarray, h: np.ndarray,
                      label: np.ndarray) -> np.ndarray:
    """Largest distance of each face's corners to the plane of its label (0 for label -1)."""
    lab = np.maximum(label, 0)
    d = np.abs(np.einsum("ij,ikj->ik", omega[lab], v[f]) - h[lab, None]).max(axis=1)
    d[label < 0] = 0.0
    return np.nan_to_num(d, nan=np.inf)


def _max_per_label(values: np.ndarray, label: np.ndarray, k: int) -> np.ndarray:
    out = np.zeros(k)
    keep = label >= 0
    np.maximum.at(out, label[keep], values[keep])
    return out


def _attach_slivers(v: np.ndarray, f: np.ndarray, sliver: np.ndarray, polygon: np.ndarray,
                    omega: np.ndarray, h: np.ndarray, ta: np.ndarray, tb: np.ndarray,
                    eps: float) -> np.ndarray:
    """Give each sliver the polygon of a neighbour whose plane holds all three of its vertices."""
    polygon = polygon.copy()
    src = np.concatenate([ta, tb])
    dst = np.concatenate([tb, ta])
    for _ in range(_SLIVER_ROUNDS):
        cand = sliver[dst] & (polygon[dst] < 0) & (polygon[src] >= 0)
        if not cand.any():
            break
        s, t = src[cand], dst[cand]
        pid = polygon[s]
        d = np.abs(np.einsum("ij,ikj->ik", omega[pid], v[f[t]]) - h[pid, None]).max(axis=1)
        ok = d <= eps
        if not ok.any():
            break
        # Several neighbours may qualify: any one will do, the last write wins.
        polygon[t[ok]] = pid[ok]
    return polygon


def _dedupe(v: np.ndarray, f: np.ndarray, cross: np.ndarray, polygon: np.ndarray,
            omega: np.ndarray, h: np.ndarray, eps: float,
            tolerance: float, drift: float) -> tuple[np.ndarray, np.ndarray]:
    """Planes shared by several polygons: ``(face_plane, polygon_plane)``.

    Polygons whose rows ``(omega, h)`` round to the same values on a grid of
    the tolerance become one plane, refitted from all their faces; a merged
    plane that then strays from a vertex by more than the drift bound is
    split back into its polygons.
    """
    angle_step = max(tolerance, 1e-15)
    key = np.column_stack([np.round(omega / angle_step), np.round(h / max(eps, 1e-300))])
    _, polygon_plane = np.unique(key, axis=0, return_inverse=True)
    polygon_plane = _renumber(polygon_plane.reshape(-1))
    plane = np.where(polygon >= 0, polygon_plane[np.maximum(polygon, 0)], -1)
    k = polygon_plane.max() + 1
    om, hh = _fit(v, f, cross, plane, k)
    bad = _max_per_label(_corner_distances(v, f, om, hh, plane), plane, k) > drift
    if bad.any():
        revert = bad[polygon_plane]
        polygon_plane[revert] = k + np.arange(int(revert.sum()))
        polygon_plane = _renumber(polygon_plane)
        plane = np.where(polygon >= 0, polygon_plane[np.maximum(polygon, 0)], -1)
    return plane, polygon_plane
