"""Cracks of meshes that are closed but for rounding or triangulation: two vertices of one
point, and T-junctions.

Coincident vertices written with different rounding (``6.1e-17`` next to
``0``, the cosine of a right angle in the exporter's arithmetic) make two
vertices of one point; :func:`merge_close_vertices` merges them.

A T-junction is a vertex lying inside another triangle's edge. CAD exporters
triangulate faces one by one: where a face's edge meets two edges of the
next face, the middle vertex sits on the first face's edge without being
one of its corners. The surface is closed, but as an indexed mesh those
edges are used once (border edges), so the solid looks open and would be
stored as patches rather than as a solid.

:func:`split_t_junctions` splits each triangle at the vertices lying on its
border edges (into a fan from the opposite corner), which adds no vertex and
moves the surface by at most the distance of those vertices from the edge
they split (reported, model units). :func:`mend_cracks` does both.
Conventions as in :mod:`planefmt.geometry.planes`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

#: Splitting rounds: a triangle is split along one edge per round, so three rounds handle
#: T-vertices on all its edges; one more finds none (the fans add no border edges).
_ROUNDS = 4


@dataclass(frozen=True)
class Repaired:
    """A mesh with its cracks closed: ``faces`` index ``vertices``; ``origin`` gives the input face
    each face comes from; ``offset`` bounds how far the surface moved (model units)."""

    vertices: np.ndarray
    faces: np.ndarray
    origin: np.ndarray
    offset: float


def mend_cracks(vertices: np.ndarray, faces: np.ndarray, merge: float, split: float) -> Repaired:
    """Merge vertices closer than ``merge`` (model units), then split triangles at T-vertices within
    ``split`` of their edges."""
    v, f, kept, moved = merge_close_vertices(vertices, faces, merge)
    split = split_t_junctions(v, f, split)
    return Repaired(vertices=v, faces=split.faces, origin=kept[split.origin], offset=moved + split.offset)


def merge_close_vertices(vertices: np.ndarray, faces: np.ndarray,
                         eps: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Vertices closer than ``eps`` (model units, chained) merged into the first of them.

    Returns the vertices, the faces re-indexed to them without those that collapsed, the input
    indices of the faces kept, and the largest distance a vertex moved.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    pairs = cKDTree(v).query_pairs(eps, output_type="ndarray")
    if len(pairs) == 0:
        return v, f, np.arange(len(f)), 0.0
    n = len(v)
    g = coo_matrix((np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    label = connected_components(g, directed=False)[1]
    _, first = np.unique(label, return_index=True)
    moved = float(np.linalg.norm(v - v[first][label], axis=1).max())
    f = label[f]
    kept = np.flatnonzero((f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0]))
    return v[first], f[kept], kept, moved


@dataclass(frozen=True)
class Split:
    """The faces after splitting; ``origin`` the input face each one comes from; ``offset`` how far
    the split moved the surface (model units); ``splits`` the T-vertices inserted."""

    faces: np.ndarray
    origin: np.ndarray
    offset: float
    splits: int


def split_t_junctions(vertices: np.ndarray, faces: np.ndarray, eps: float) -> Split:
    """Split triangles at vertices within ``eps`` (model units) of the inside of their border edges.

    A vertex counts only if it is the end of another border edge (the other side of the junction)
    and projects strictly inside the edge, at least ``eps`` from both ends.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    origin = np.arange(len(f))
    offset, splits = 0.0, 0
    for _ in range(_ROUNDS):
        found = _junctions(v, f, eps)
        if found is None:
            break
        face, side, vertex, param, distance = found
        offset = max(offset, float(distance.max()))
        splits += len(vertex)
        f, kept = _fan(f, face, side, vertex, param)
        origin = origin[kept]
    return Split(faces=f, origin=origin, offset=offset, splits=splits)


def _border_sides(f: np.ndarray, n: int) -> np.ndarray:
    """Flat side ids (3 * face + slot) of sides whose undirected edge no other side shares."""
    start = f.reshape(-1)
    end = f[:, [1, 2, 0]].reshape(-1)
    key = np.minimum(start, end) * np.int64(n) + np.maximum(start, end)
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    return np.flatnonzero(counts[inverse] == 1)


def _junctions(v: np.ndarray, f: np.ndarray, eps: float):
    """The T-vertices of one round, at most one side per face: (face, side, vertex, param, distance)."""
    border = _border_sides(f, len(v))
    if len(border) == 0:
        return None
    face, side = np.divmod(border, 3)
    a = f[face, side]
    b = f[face, (side + 1) % 3]
    ends = np.unique(np.concatenate([a, b]))
    pa, pb = v[a], v[b]
    length = np.linalg.norm(pb - pa, axis=1)
    tree = cKDTree(v[ends])
    near = tree.query_ball_point((pa + pb) / 2.0, length / 2.0 + eps)
    sizes = np.fromiter((len(x) for x in near), dtype=np.int64, count=len(near))
    if sizes.sum() == 0:
        return None
    edge = np.repeat(np.arange(len(border)), sizes)
    vertex = ends[np.concatenate([np.asarray(x, dtype=np.int64) for x in near if len(x)])]
    d = pb[edge] - pa[edge]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.einsum("ij,ij->i", v[vertex] - pa[edge], d) / (length[edge] ** 2)
    foot = pa[edge] + t[:, None] * d
    distance = np.linalg.norm(v[vertex] - foot, axis=1)
    inside = t * length[edge]
    keep = ((vertex != a[edge]) & (vertex != b[edge]) & (distance <= eps)
            & (inside >= eps) & (length[edge] - inside >= eps))
    if not keep.any():
        return None
    edge, vertex, t, distance = edge[keep], vertex[keep], t[keep], distance[keep]
    # One side per face and round: the fans of a face's other sides would overlap this one's.
    first_side = np.full(len(f), 3)
    np.minimum.at(first_side, face[edge], side[edge])
    own = side[edge] == first_side[face[edge]]
    edge, vertex, t, distance = edge[own], vertex[own], t[own], distance[own]
    return face[edge], side[edge], vertex, t, distance


def _fan(f: np.ndarray, face: np.ndarray, side: np.ndarray, vertex: np.ndarray,
         param: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each split face replaced by the fan from its opposite corner over the side's points in order;
    and the face of ``f`` each new face comes from."""
    order = np.lexsort((param, face))
    face, side, vertex = face[order], side[order], vertex[order]
    first = np.r_[True, face[1:] != face[:-1]]
    last = np.r_[face[1:] != face[:-1], True]
    start = f[face, side]
    end = f[face, (side + 1) % 3]
    apex = f[face, (side + 2) % 3]
    prev = np.where(first, start, np.r_[0, vertex[:-1]])
    fan = np.column_stack([prev, vertex, apex])
    closing = np.column_stack([vertex[last], end[last], apex[last]])
    rest = np.ones(len(f), dtype=bool)
    rest[face] = False
    kept = np.concatenate([np.flatnonzero(rest), face, face[last]])
    return np.concatenate([f[rest], fan, closing]), kept
