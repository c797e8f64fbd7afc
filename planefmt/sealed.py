"""Sealed surfaces (kind 5, spec §9.9): triangles whose corners are meeting points of three planes.

A BSP tree's surface is computed from its planes alone, so its topology is
whatever those planes make of it. Where a smooth, finely tessellated solid
has vertices on six or more faces whose planes (rounded, or merged within
the tolerance) no longer pass through one point, the cells meet in slivers
and tunnels far below the tolerance, and the decoded surface has another
Euler characteristic than the source (King_geom.usd: -2 and -6 where the
source has 2; every plane choice tried). A sealed group keeps the source's
connectivity instead: each vertex is named by three of the group's planes
and each triangle by its face plane and three vertices, so the decoded
surface is closed, with the source's Euler characteristic, whenever the
source is, and each vertex moves only as far as its three planes put it.

The encoder picks each vertex's planes among its faces' planes, the best
conditioned triple (largest ``|det|`` of the normals); where no triple of
them puts the vertex within the budget (a vertex inside a flat polygon, on
a straight crease, or where the faces are nearly parallel) it adds
*vertex planes* through the vertex (role: bounding), orthogonal to the face
planes it keeps. Planes ``(omega, h)``: outward unit normals, model units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import GeometryError
from .patches import PlaneTable

#: Smallest ``|det|`` of three unit normals the encoder names a vertex by (below it, a rounding
#: of the planes by 1e-16 moves the vertex by more than 1e-10 of the model's size).
MIN_DETERMINANT = 1e-6
#: Smallest sine of the angle between the two face planes a crease vertex keeps.
MIN_SINE = 1e-3
#: ``|det|`` of three unit normals at or below which they count as linearly dependent (spec
#: §9.9): normals decoded from triplets are off by rounding, so parallel planes never give 0.
DEPENDENT = 1e-12


@dataclass(frozen=True)
class Sealed:
    """A sealed group over a :class:`PlaneTable`: ``vertex_planes`` (V, 3) table indices of each
    vertex's planes, ``facets`` (T, 4): each triangle's face plane (a table index) and its three
    vertices (indices into ``vertex_planes``), counter-clockwise seen from outside; ``added`` the
    table indices of the vertex planes added for it; ``error`` the largest vertex displacement
    (model units)."""

    vertex_planes: np.ndarray
    facets: np.ndarray
    added: np.ndarray
    error: float


def corners(omega: np.ndarray, h: np.ndarray, vertex_planes: np.ndarray) -> np.ndarray:
    """Meeting points (V, 3) of the plane triples ``vertex_planes`` (V, 3) (indices into ``omega``,
    ``h``). Raises ``GeometryError`` where a triple's normals do not span space."""
    a = omega[vertex_planes]
    b = h[vertex_planes]
    bad = ~(np.abs(np.linalg.det(a)) > DEPENDENT)
    x = np.full((len(a), 3), np.nan)
    if (~bad).any():
        x[~bad] = np.linalg.solve(a[~bad], b[~bad, :, None])[:, :, 0]
    bad |= ~np.isfinite(x).all(axis=1)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise GeometryError(f"{int(bad.sum())} vertices are named by planes that do not meet in one point "
                            f"(vertex {k}: planes {vertex_planes[k].tolist()})", code="BAD_VERTEX")
    return x


def _first_per_group(groups: np.ndarray, score: np.ndarray, n: int) -> np.ndarray:
    """Row of the smallest ``score`` for each group 0..n-1 (rows sorted by nothing); -1 if none."""
    order = np.lexsort((score, groups))
    g = groups[order]
    first = np.r_[True, g[1:] != g[:-1]]
    out = np.full(n, -1, dtype=np.int64)
    out[g[first]] = order[first]
    return out


def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.linalg.norm(x, axis=1, keepdims=True)


def encode_sealed(vertices: np.ndarray, faces: np.ndarray, face_plane: np.ndarray, table: PlaneTable,
                  budget: float) -> Sealed:
    """The sealed group of a body's triangles ``faces`` over ``vertices``.

    ``face_plane`` is each triangle's plane in ``table`` (-1 for triangles of
    no area, which take a plane of their first vertex). Each vertex is named
    by three planes putting it within ``budget`` (model units) of where it
    is, vertex planes added to ``table`` where its face planes cannot.
    """
    faces = np.asarray(faces, dtype=np.int64)
    used, local = np.unique(faces, return_inverse=True)
    local = local.reshape(-1, 3)
    n = len(used)
    p = vertices[used]
    omega, h = table.arrays()
    live = face_plane >= 0
    if not live.any():
        raise GeometryError(f"a body of {len(faces)} triangles, none with an area", code="DEGENERATE_GEOMETRY")
    inc = np.unique(np.column_stack([local[live].reshape(-1), np.repeat(face_plane[live], 3)]), axis=0)
    iv, ip = inc[:, 0], inc[:, 1]
    # A: the plane its vertex lies closest to; B: the most different from A; C: the best triple.
    off = np.abs(np.einsum("ij,ij->i", omega[ip], p[iv]) - h[ip])
    ra = _first_per_group(iv, off, n)
    has = ra >= 0
    a = np.where(has, ip[np.maximum(ra, 0)], -1)
    wa = omega[np.maximum(a, 0)]
    rb = _first_per_group(iv, np.abs(np.einsum("ij,ij->i", omega[ip], wa[iv])), n)
    b = np.where(has, ip[np.maximum(rb, 0)], -1)
    wb = omega[np.maximum(b, 0)]
    ab = np.cross(wa, wb)
    rc = _first_per_group(iv, -np.abs(np.einsum("ij,ij->i", omega[ip], ab[iv])), n)
    c = np.where(has, ip[np.maximum(rc, 0)], -1)
    triple = np.column_stack([a, b, c])
    sine = np.linalg.norm(ab, axis=1)
    det = np.abs(np.einsum("ij,ij->i", ab, omega[np.maximum(c, 0)]))
    u = _unit(np.cross(wa, np.eye(3)[np.argmin(np.abs(wa), axis=1)]))
    # Fallbacks in order: a crease vertex keeps A and B and takes the plane through it across
    # their edge; then A and two planes through it across A; then three axis planes, exact.
    levels = [
        (has & (det >= MIN_DETERMINANT), (), []),
        (has & (sine >= MIN_SINE), (2,), [ab / np.maximum(sine, MIN_SINE)[:, None]]),
        (has, (1, 2), [u, np.cross(wa, u)]),
        (np.ones(n, dtype=bool), (0, 1, 2), [np.broadcast_to(e, (n, 3)) for e in np.eye(3)]),
    ]
    todo = np.ones(n, dtype=bool)
    added = []
    for possible, slots, normals in levels:
        k = np.flatnonzero(todo & possible)
        if not len(k):
            continue
        t = triple[k].copy()
        for slot, w in zip(slots, normals):
            t[:, slot] = table.extend(w[k], np.einsum("ij,ij->i", w[k], p[k]))
        omega, h = table.arrays()
        good = np.linalg.norm(corners(omega, h, t) - p[k], axis=1) <= budget
        if len(slots) == 3:
            good[:] = True
        triple[k[good]] = t[good]
        added.append(t[good][:, list(slots)].reshape(-1))
        todo[k[good]] = False
    planes_added = np.unique(np.concatenate(added)) if added else np.zeros(0, dtype=np.int64)
    omega, h = table.arrays()
    error = float(np.linalg.norm(corners(omega, h, triple) - p, axis=1).max(initial=0.0))
    # A triangle of no area lies on every plane through its vertices; any face plane serves.
    fp = np.where(live, face_plane, np.where(has[local[:, 0]], a[local[:, 0]], face_plane[live][0]))
    order = np.argsort(fp, kind="stable")
    facets = np.column_stack([fp, local])[order]
    return Sealed(triple, facets, planes_added, error)


def decode_sealed(omega: np.ndarray, h: np.ndarray, vertex_planes: np.ndarray,
                  facets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and triangles (T, 3) of a sealed group; ``vertex_planes`` and ``facets``
    index ``omega``, ``h`` (the group's planes) as :class:`Sealed` describes."""
    return corners(omega, h, np.asarray(vertex_planes, dtype=np.int64)), \
        np.asarray(facets, dtype=np.int64)[:, 1:]
