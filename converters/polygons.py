"""Triangulation of polygon meshes given as face vertex counts and indices.

USD (and other polygon formats) store faces as ``counts`` (vertices per face)
and the flat ``indices`` of their corners. Convex faces are fanned from their
first corner, all at once with numpy; only faces found non-convex, which are
rare in practice, are ear-clipped one at a time.
"""

from __future__ import annotations

import numpy as np

#: Relative tolerance of the convexity and ear tests (of the face's scale squared).
_EPS = 1e-12


def triangulate(points: np.ndarray, counts: np.ndarray,
                indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of the polygons ``counts``/``indices`` over ``points``.

    Returns ``(triangles (t, 3) int64, face (t,) int64)`` where ``face[i]`` is
    the polygon that triangle ``i`` came from. Winding follows the polygon's
    corner order. Faces with fewer than three corners yield no triangle.
    The caller checks that ``counts`` sum to ``len(indices)`` and that the
    indices address ``points``.
    """
    counts = np.asarray(counts, dtype=np.int64)
    indices = np.asarray(indices, dtype=np.int64)
    starts = np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.int64)
    per_face = np.maximum(counts - 2, 0)
    face = np.repeat(np.arange(len(counts)), per_face)
    # k = 1 .. count-2 within each face: fan triangle (0, k, k+1)
    k = np.arange(len(face)) - np.repeat(np.cumsum(per_face) - per_face, per_face) + 1
    first = starts[face]
    triangles = np.stack([indices[first], indices[first + k], indices[first + k + 1]], axis=1)

    concave = np.flatnonzero(_non_convex(points, counts, indices, starts))
    if len(concave) == 0:
        return triangles, face
    keep = ~np.isin(face, concave)
    extra = [_ear_clip(points, indices[starts[f]:starts[f] + counts[f]]) for f in concave]
    triangles = np.concatenate([triangles[keep]] + extra)
    face = np.concatenate([face[keep]] + [np.full(len(t), f) for t, f in zip(extra, concave)])
    return triangles, face


def _non_convex(points: np.ndarray, counts: np.ndarray, indices: np.ndarray,
                starts: np.ndarray) -> np.ndarray:
    """Mask of faces with four or more corners where a fan could go wrong.

    A face is convex when every corner turns the same way as the face's
    Newell normal; collinear corners are allowed.
    """
    big = counts >= 4
    if not big.any():
        return big
    sizes = np.where(big, counts, 0)
    face = np.repeat(np.arange(len(counts)), sizes)
    # position of each corner in the flat index array
    corner = np.arange(len(face)) - np.repeat(np.cumsum(sizes) - sizes, sizes) + starts[face]
    local = corner - starts[face]
    nxt = starts[face] + (local + 1) % counts[face]
    prv = starts[face] + (local - 1) % counts[face]
    here, after, before = (points[indices[c]] for c in (corner, nxt, prv))
    normal = np.zeros((len(counts), 3))
    np.add.at(normal, face, np.cross(here, after))  # Newell's method: sum of corner crosses
    turn = np.einsum("ij,ij->i", np.cross(here - before, after - here), normal[face])
    scale = np.zeros(len(counts))
    np.maximum.at(scale, face, np.einsum("ij,ij->i", after - here, after - here))
    bad = np.zeros(len(counts), dtype=bool)
    np.logical_or.at(bad, face, turn < -_EPS * scale[face] * np.sqrt(
        np.einsum("ij,ij->i", normal[face], normal[face])))
    return bad


def _ear_clip(points: np.ndarray, ring: np.ndarray) -> np.ndarray:
    """Ear-clipping triangulation of one simple polygon (corner indices ``ring``)."""
    xyz = points[ring]
    normal = np.cross(xyz, np.roll(xyz, -1, axis=0)).sum(axis=0)
    # Project onto the plane most facing the normal, keeping its orientation.
    axis = int(np.argmax(np.abs(normal)))
    u, v = [(1, 2), (2, 0), (0, 1)][axis]
    uv = xyz[:, [u, v]]
    if normal[axis] < 0:
        uv[:, 1] = -uv[:, 1]  # mirror, so the polygon runs counter-clockwise in uv
    remaining = list(range(len(ring)))
    triangles: list[tuple[int, int, int]] = []
    while len(remaining) > 3:
        for i in range(len(remaining)):
            a, b, c = remaining[i - 1], remaining[i], remaining[(i + 1) % len(remaining)]
            if _is_ear(uv, a, b, c, remaining):
                triangles.append((ring[a], ring[b], ring[c]))
                del remaining[i]
                break
        else:
            # No ear: a self-intersecting or degenerate ring. Fan the rest
            # rather than fail; the surface there is ill-defined anyway.
            triangles.extend((ring[remaining[0]], ring[remaining[j]], ring[remaining[j + 1]])
                             for j in range(1, len(remaining) - 1))
            remaining = []
    if len(remaining) == 3:
        triangles.append(tuple(ring[j] for j in remaining))
    return np.asarray(triangles, dtype=np.int64).reshape(-1, 3)


def _is_ear(uv: np.ndarray, a: int, b: int, c: int, remaining: list[int]) -> bool:
    """True if corner ``b`` is convex and triangle ``abc`` holds no other corner."""
    pa, pb, pc = uv[a], uv[b], uv[c]
    if _cross2(pb - pa, pc - pb) <= 0:
        return False
    for j in remaining:
        if j in (a, b, c):
            continue
        p = uv[j]
        if _cross2(pb - pa, p - pa) >= 0 and _cross2(pc - pb, p - pb) >= 0 \
                and _cross2(pa - pc, p - pc) >= 0:
            return False
    return True


def _cross2(p: np.ndarray, q: np.ndarray) -> float:
    return float(p[0] * q[1] - p[1] * q[0])
