"""Reference geometry of part groups (spec §9, §9.9), for the expected results of valid cases.

Deliberately independent of planefmt's own decoder (``planefmt.geometry.halfspace``,
``planefmt.codec``): the suite checks that decoder against this one. It is
written for clarity on the handful of small groups the suite holds, not for
speed: linear programs (scipy's HiGHS) decide emptiness and boundedness,
Qhull's half-space intersection gives the vertices, and faces are polygons
gathered plane by plane. A sealed group's vertices are solved by Cramer's
rule, not by planefmt's LU solve.

Every function takes planes as ``omega`` (n, 3) unit outward normals and
``h`` (n,) in model units, the solid side being ``omega . x <= h``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, HalfspaceIntersection, QhullError

#: Candidate vertices closer than this fraction of the polytope's extent are one vertex,
#: and a vertex this close to a plane lies on it. Qhull's vertices are good to ~1e-15.
WELD = 1e-9

#: Vertex and triangle counts are only stated where distinct vertices are at least this
#: fraction of the extent apart: ten times spec §9.4's 1e-9 that every decoder merges (its other merge
#: rules are the reference's own, merged_labels).
DISTINCT = 1e-8

#: A vertex whose planes' unit normals span less than this (|det| of three) is ill-conditioned
#: (spec §9.4's merge rules).
CONDITIONED = 1e-9


@dataclass(frozen=True)
class PlaneError:
    """How far a file's coding may move a plane (spec §9.4): ``angle`` (A), ``h`` (H) plus
    ``h_relative`` times the group's largest |h|, and ``limit`` (L), all model units or radians."""

    angle: float = 0.0
    h: float = 0.0
    h_relative: float = 0.0
    limit: float = float("inf")


def plane_error(coding: int, bits=None, h_range=None, tolerance: float = float("nan"),
                diagonal: float = float("nan")) -> PlaneError:
    """Spec §9.4's A, H and L of a header: codings 2 and 3 half a step, 0 half an f32 unit."""
    limit = tolerance / 2 * diagonal
    limit = limit if np.isfinite(limit) else float("inf")
    if coding in (2, 3):
        return PlaneError(max(np.pi / 2.0 ** bits[0], np.pi / 2.0 ** bits[1]),
                          (h_range[1] - h_range[0]) / (2 * (2.0 ** bits[2] - 1)), 0.0, limit)
    if coding == 0:
        return PlaneError(2.0 ** -22, 0.0, 2.0 ** -24, limit)
    return PlaneError(limit=limit)


#: |det| of three unit normals at or below which they are linearly dependent (spec §9.9).
DEPENDENT = 1e-12

#: Tokens of spec §9.7.
BSP_IN, BSP_OUT = 0xFFFFFFFE, 0xFFFFFFFF


class Defect(Exception):
    """The planes do not describe a valid part group; ``code`` is the spec's error code."""

    def __init__(self, code: str, reason: str) -> None:
        super().__init__(reason)
        self.code = code


@dataclass(frozen=True)
class Face:
    """A convex polygon of a polytope: vertices counter-clockwise seen from outside."""

    normal: np.ndarray  # (3,) outward unit normal
    offset: float  # normal . x = offset on the face
    points: np.ndarray  # (k, 3)
    plane: int  # row of the half-space it lies on

    @property
    def area_vector(self) -> np.ndarray:
        p = self.points
        return 0.5 * np.cross(p[1:-1] - p[0], p[2:] - p[0]).sum(axis=0)

    @property
    def area(self) -> float:
        return float(np.linalg.norm(self.area_vector))


def planes_of(triplets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(omega, h)`` of triplets ``(nu, phi, h)`` (spec §2.3)."""
    t = np.asarray(triplets, dtype=np.float64).reshape(-1, 3)
    s = np.sin(t[:, 0])
    omega = np.column_stack([s * np.cos(t[:, 1]), s * np.sin(t[:, 1]), np.cos(t[:, 0])])
    return omega, t[:, 2].copy()


#: Spec §9.4: the unit normals of a bounded polytope surround the origin by at least this much, and
#: a polytope is no thinner than THIN x its diagonal.
BOUNDED_MARGIN = 1e-6
THIN = 1e-8


def convex_faces(omega: np.ndarray, h: np.ndarray) -> list[Face]:
    """Faces of ``{x : omega_i . x <= h_i}``; raises ``Defect`` if it is empty, flat or unbounded
    (spec §9.4's relative criteria: decided at unit size, by a power of two that scales exactly)."""
    reach = float(np.abs(h).max())
    unit = 2.0 ** -round(np.log2(reach)) if reach > 0 else 1.0
    faces = _unit_faces(omega, h * unit)
    return [Face(f.normal, f.offset / unit, f.points / unit, f.plane) for f in faces]


def _unit_faces(omega: np.ndarray, h: np.ndarray) -> list[Face]:
    free = [(None, None)] * 3
    extent = []
    for axis in range(3):
        for sign in (1.0, -1.0):
            c = np.zeros(3)
            c[axis] = -sign
            res = linprog(c, A_ub=omega, b_ub=h, bounds=free, method="highs")
            if res.status == 2:
                raise Defect("EMPTY_POLYTOPE", "the half-spaces have no common point")
            if res.status == 3:
                raise Defect("UNBOUNDED_POLYTOPE", "the half-spaces do not bound a finite region")
            extent.append(res.x[axis])
    try:
        margin = -float(ConvexHull(omega).equations[:, 3].max())  # min over unit u of max omega . u
    except QhullError:
        margin = 0.0
    if margin < BOUNDED_MARGIN:
        raise Defect("UNBOUNDED_POLYTOPE", "the plane normals surround the origin by less than 1e-6")
    size = float(np.linalg.norm(np.array(extent[0::2]) - np.array(extent[1::2])))
    # Chebyshev centre: the deepest point, and the radius of the largest ball inside.
    res = linprog([0, 0, 0, -1.0], A_ub=np.column_stack([omega, np.ones(len(h))]), b_ub=h,
                  bounds=free + [(0, None)], method="highs")
    if not res.x[3] > WELD * size:
        raise Defect("EMPTY_POLYTOPE", "the intersection has no interior")
    points = HalfspaceIntersection(np.column_stack([omega, -h]), res.x[:3]).intersections
    vertices = _weld(points, WELD * size)
    faces = []
    for i, (n, d) in enumerate(zip(omega, h)):
        on = vertices[np.abs(vertices @ n - d) <= WELD * size]
        if len(on) < 3:
            continue  # the plane touches the polytope at a point or an edge: no face
        centre = on.mean(axis=0)
        e1 = np.cross(n, np.eye(3)[np.argmin(np.abs(n))])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)  # (e1, e2, n) right-handed: ascending angle is counter-clockwise
        angle = np.arctan2((on - centre) @ e2, (on - centre) @ e1)
        faces.append(Face(n, float(d), on[np.argsort(angle)], i))
    width = min(max(f.offset - vertices @ f.normal) for f in faces)
    if width <= THIN * float(np.linalg.norm(np.ptp(vertices, axis=0))):
        raise Defect("EMPTY_POLYTOPE", "thinner than 1e-8 of its diagonal")
    return faces


def _weld(points: np.ndarray, tol: float) -> np.ndarray:
    """One point per cluster of points within ``tol`` (degenerate vertices come several times)."""
    out = []
    left = np.asarray(points, dtype=np.float64)
    while len(left):
        near = np.linalg.norm(left - left[0], axis=1) <= tol
        out.append(left[near].mean(axis=0))
        left = left[~near]
    return np.array(out)


def flipped(face: Face) -> Face:
    return Face(-face.normal, -face.offset, face.points[::-1], face.plane)


def _overlap(face: Face, other: Face) -> float:
    """Area common to two coplanar, oppositely oriented convex faces."""
    e1 = face.points[1] - face.points[0]
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(face.normal, e1)
    origin = face.points[0]

    def flat(p: np.ndarray) -> list[np.ndarray]:
        return list(np.column_stack([(p - origin) @ e1, (p - origin) @ e2]))

    subject = flat(face.points)
    clip = flat(other.points[::-1])  # reversed: counter-clockwise in this face's basis too
    # Sutherland-Hodgman: keep the part of the subject left of every clip edge.
    for a, b in zip(clip, clip[1:] + clip[:1]):
        if not subject:
            return 0.0
        edge = b - a
        side = [edge[0] * (p - a)[1] - edge[1] * (p - a)[0] for p in subject]
        kept = []
        for k, p in enumerate(subject):
            q, sq = subject[k - 1], side[k - 1]
            if (side[k] >= 0) != (sq >= 0):
                kept.append(q + (p - q) * (sq / (sq - side[k])))
            if side[k] >= 0:
                kept.append(p)
        subject = kept
    if len(subject) < 3:
        return 0.0
    x, y = np.array(subject).T
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _cell_faces(omega: np.ndarray, h: np.ndarray, entries) -> list[Face]:
    """Faces of one cell: entries ``2 j + s`` of local planes, ``s = 1`` for the complement. An entry
    given twice (a tree that splits on a plane its path already took) bounds the cell once."""
    entries = list(dict.fromkeys(int(e) for e in entries))
    j = np.asarray(entries, dtype=np.int64) >> 1
    sign = np.where(np.asarray(entries) & 1, -1.0, 1.0)
    faces = convex_faces(omega[j] * sign[:, None], h[j] * sign)
    return [Face(f.normal, f.offset, f.points, int(j[f.plane])) for f in faces]


def _leaf_faces(omega: np.ndarray, h: np.ndarray, entries) -> list[Face]:
    """Faces of an IN leaf's region; none where it is empty or flat, which spec/pln.md §9.7 allows (an
    unbounded region is still a ``Defect``)."""
    try:
        return _cell_faces(omega, h, entries)
    except Defect as exc:
        if exc.code != "EMPTY_POLYTOPE":
            raise
        return []


def bsp_cells(tokens, m: int) -> list[list[int]]:
    """The IN leaves of a preorder BSP token stream (spec §9.7), as cell entry lists."""
    cells: list[list[int]] = []
    stack = [[]]  # half-spaces of the region each pending subtree covers
    for t in (int(x) for x in tokens):
        region = stack.pop()
        if t == BSP_IN:
            cells.append(region)
        elif t != BSP_OUT:
            assert t < m
            stack.append(region + [2 * t + 1])  # outer subtree, visited after the inner one
            stack.append(region + [2 * t])
    return cells


def _solid_union(cells: list[list[Face]], size: float) -> tuple[float, np.ndarray]:
    """Area and area vector of the boundary of a union of convex cells with disjoint interiors.

    A face fragment is interior exactly where another cell's face lies on the
    same plane facing the other way; everything else is surface.
    """
    area, vector = 0.0, np.zeros(3)
    for c, faces in enumerate(cells):
        for f in faces:
            hidden = sum(_overlap(f, g) for d, other in enumerate(cells) if d != c for g in other
                         if f.normal @ g.normal < -1 + 1e-12 and abs(f.offset + g.offset) <= WELD * size)
            visible = f.area - hidden
            area += visible
            vector += f.normal * visible
    return area, vector


def sealed_vertices(omega: np.ndarray, h: np.ndarray, vertex_planes) -> np.ndarray:
    """Where each triple of local planes meets (spec §9.9); raises ``Defect`` (``BAD_VERTEX``)
    where the normals are linearly dependent or the point is not finite."""
    out = []
    for k, (a, b, c) in enumerate(vertex_planes):
        bc, ca, ab = np.cross(omega[b], omega[c]), np.cross(omega[c], omega[a]), np.cross(omega[a], omega[b])
        det = float(omega[a] @ bc)
        x = (h[a] * bc + h[b] * ca + h[c] * ab) / det if abs(det) > DEPENDENT else np.full(3, np.nan)
        if not np.isfinite(x).all():
            raise Defect("BAD_VERTEX", f"vertex {k}: planes {a}, {b}, {c} do not meet in one point (det {det:g})")
        out.append(x)
    return np.array(out)


def merged_labels(omega: np.ndarray, h: np.ndarray, faces: list[Face], vertices: np.ndarray,
                  error: PlaneError) -> np.ndarray:
    """One label per vertex of a polytope: spec §9.4's merge rules, in their words.

    d = max(1e-9 D, min(1e-2 D, L, 1000 (A R + H))). Rule 1 joins the ends of every edge at most d
    long. Rule 2, on edges whose ends rule 1 left apart, joins them where a well-conditioned end
    lies within d of every plane through the other; rule 3 then where both ends are
    ill-conditioned. A group rule 2 or 3 changes stands only if its planes pin one point within d
    of each; else its vertices keep their labels from before the rule.
    """
    size = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    radius = float(np.linalg.norm(vertices, axis=1).max())
    e = error.angle * radius + error.h + error.h_relative * float(np.abs(h).max())
    d = max(WELD * size, min(1e-2 * size, error.limit, 1000 * e))
    on = np.abs(vertices @ omega.T - h) <= WELD * size  # (V, n): the planes through each vertex
    planes = [np.flatnonzero(row) for row in on]
    conditioned = np.array([any(abs(np.linalg.det(omega[list(t)])) >= CONDITIONED
                                for t in _triples(p)) for p in planes])
    index = {tuple(v): i for i, v in enumerate(vertices)}
    edges = sorted({tuple(sorted((index[tuple(a)], index[tuple(b)])))
                    for f in faces for a, b in zip(f.points, np.roll(f.points, -1, axis=0))})

    def near(u: int, v: int) -> bool:
        return bool(np.linalg.norm(vertices[u] - vertices[v]) <= d)

    def within(u: int, v: int) -> bool:
        return bool(conditioned[u] and np.abs(omega[planes[v]] @ vertices[u] - h[planes[v]]).max() <= d)

    chosen = [(u, v) for u, v in edges if near(u, v)]
    labels = _joined(len(vertices), chosen)
    for rule in (lambda u, v: within(u, v) or within(v, u), lambda u, v: not conditioned[u] and not conditioned[v]):
        extra = [(u, v) for u, v in edges if (u, v) not in chosen and rule(u, v)]
        if not extra:
            continue
        chosen += extra
        joined = _joined(len(vertices), chosen)
        out = labels + len(vertices)
        for group in set(joined.tolist()):
            members = np.flatnonzero(joined == group)
            if len(set(labels[members].tolist())) == 1 or _pins(omega, h, sorted(set().union(
                    *(planes[m].tolist() for m in members))), d):
                out[members] = group
        labels = np.unique(out, return_inverse=True)[1]
    return labels


def _merged_counts(omega: np.ndarray, h: np.ndarray, every: list[Face], faces: list[Face],
                   vertices: np.ndarray, error: PlaneError) -> tuple[int, int]:
    """Vertex and triangle counts of ``faces`` (of the polytope whose faces are ``every``) once
    its vertices are merged (spec §9.4): a face left with fewer than three vertices is none."""
    labels = merged_labels(omega, h, every, vertices, error)
    index = {tuple(v): i for i, v in enumerate(vertices)}
    used, triangles = set(), 0
    for f in faces:
        loop = [int(labels[index[tuple(p)]]) for p in f.points]
        loop = [x for k, x in enumerate(loop) if x != loop[k - 1]] or loop[:1]
        if len(loop) >= 3:
            used.update(loop)
            triangles += len(loop) - 2
    return len(used), triangles


def _triples(p: np.ndarray):
    return ((a, b, c) for i, a in enumerate(p) for j, b in enumerate(p[i + 1:], i + 1) for c in p[j + 1:])


def _joined(n: int, pairs) -> np.ndarray:
    """Connected components of ``n`` vertices over ``pairs``, each labelled by its smallest vertex."""
    label = np.arange(n)
    for u, v in pairs:
        a, b = label[u], label[v]
        label[label == max(a, b)] = min(a, b)
    return label


def _pins(omega: np.ndarray, h: np.ndarray, planes: list[int], d: float) -> bool:
    """Whether ``planes`` pin one point (smallest eigenvalue of the sum of omega omega^T at least
    1e-6 of the largest) lying within ``d`` of each."""
    w = omega[planes]
    eig = np.linalg.eigvalsh(w.T @ w)
    if eig[0] < 1e-6 * eig[2]:
        return False
    x = np.linalg.lstsq(w, h[planes], rcond=None)[0]
    return bool(np.abs(w @ x - h[planes]).max() <= d)


def summary(kind: int, triplets: np.ndarray, bounding: np.ndarray, cells=None, tree=None, vertex_planes=None,
            facets=None, shell=None, error: PlaneError = PlaneError()) -> tuple[dict, np.ndarray]:
    """The geometry summary of the conformance contract for one group (see README.md).

    ``triplets`` (m, 3) are the planes of the group's references in order;
    ``bounding`` (m,) its role bits; ``cells``, ``tree``, ``vertex_planes``
    and ``facets`` (face, i0, i1, i2) as the kind has them, in local
    references. Returns the summary and the vertices of the decoded surface
    (local coordinates, with repeats); raises ``Defect`` for invalid geometry.
    """
    omega, h = planes_of(triplets)
    volume = None
    if kind in (6, 7, 8, 9, 10, 12, 13):
        # spec §9.10 (§9.11 to §9.14 and §9.16 the same once read): named corners as sealed vertices, explicit ones on
        # the grid; no volume (a shell may be open).
        explicit = np.asarray(shell.explicit, dtype=bool)
        points = np.zeros((len(explicit), 3))
        if (~explicit).any():
            points[~explicit] = sealed_vertices(omega, h, shell.vertex_planes)
        for k, g in zip(np.flatnonzero(explicit), np.asarray(shell.grid).reshape(-1, 3)):
            points[k] = [shell.origin[i] + shell.step * float(g[i]) for i in range(3)]
        tri = np.asarray(shell.facets)[:, 1:]
        a, b, c = (points[tri[:, k]] for k in range(3))
        cross = np.cross(b - a, c - a)
        area = float(np.linalg.norm(cross, axis=1).sum()) / 2
        vector = cross.sum(axis=0) / 2
        counts = (len(points), len(tri))
    elif kind == 5:
        points = sealed_vertices(omega, h, vertex_planes)
        a, b, c = (points[[f[k] for f in facets]] for k in (1, 2, 3))
        cross = np.cross(b - a, c - a)
        area = float(np.linalg.norm(cross, axis=1).sum()) / 2
        vector = cross.sum(axis=0) / 2
        volume = float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6  # divergence theorem
        counts = (len(points), len(facets))  # vertex identity as stored: readers must not weld (spec §9.9)
    elif kind in (0, 3, 4):
        every = convex_faces(omega, h)
        faces = every
        if kind == 0:
            if len(faces) < len(h):
                raise Defect("REDUNDANT_PLANE", "a plane of the convex group bounds no face")
            volume = sum(f.area * f.offset for f in faces) / 3.0  # divergence theorem
        else:
            faces = [f for f in faces if not bounding[f.plane]]
            if not faces:
                raise Defect("EMPTY_POLYTOPE", "no face of the patch lies on a face plane (spec §9.8)")
            if kind == 4:
                faces = [flipped(f) for f in faces]
        points = np.concatenate([f.points for f in faces])
        vertices = np.unique(np.concatenate([f.points for f in every]), axis=0)
        area = sum(f.area for f in faces)
        vector = sum(f.area_vector for f in faces)
        gaps = np.linalg.norm(vertices[:, None] - vertices[None], axis=2) + np.eye(len(vertices)) * 1e300
        if gaps.min() < DISTINCT * np.linalg.norm(np.ptp(vertices, axis=0)):
            raise ValueError("vertices too close together for the counts to be unambiguous")
        counts = _merged_counts(omega, h, every, faces, vertices, error)
    else:
        entries = cells if kind == 1 else bsp_cells(tree, len(h))
        cell_faces = [_cell_faces(omega, h, e) if kind == 1 else _leaf_faces(omega, h, e) for e in entries]
        cell_faces = [faces for faces in cell_faces if faces]
        points = np.concatenate([f.points for faces in cell_faces for f in faces])
        area, vector = _solid_union(cell_faces, float(np.linalg.norm(np.ptp(points, axis=0))))
        volume = sum(f.area * f.offset for faces in cell_faces for f in faces) / 3.0
        counts = (None, None)  # how T-junctions are resolved is the decoder's choice
    return {
        "vertices": counts[0], "triangles": counts[1], "area": area, "area_vector": vector,
        "volume": volume, "bbox": [points.min(axis=0), points.max(axis=0)],
    }, points
