"""The paper's lossy options (§5 there): ``tau`` merges neighbouring planes whose normals differ by
less than ``tau`` radians (:func:`merge_planes`), ``delta`` drops planes whose faces cover less
than ``delta`` of the total area (:func:`drop_planes`).
"""

from __future__ import annotations

import numpy as np

from ..geometry.polygonize import Polygons, edge_adjacency


#: Rounds of mutual-best-pair merging for ``tau`` (each merges at least the closest pair).
_TAU_ROUNDS = 64


def merge_planes(poly: Polygons, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The paper's lossy τ: merge neighbouring planes whose normals differ by less than ``tau`` radians.

    Merging is done in rounds of mutual best pairs (the closest neighbour of
    each cluster of planes), so that chains of small angles do not fold a
    smooth surface into one plane: two clusters merge only if every member
    normal stays within ``tau`` of the merged normal (bounded by the member
    spread plus the angle between the two clusters). A merged plane has the
    area-weighted normal and the ``h`` halfway between its extreme vertices,
    which minimises the largest vertex distance for that normal.
    Returns ``(omega, h, face_plane)`` with the merged planes appended and
    faces re-pointed; unmerged planes are unchanged.
    """
    k = len(poly.h)
    edges = edge_adjacency(poly.faces, len(poly.vertices))
    pa, pb = poly.face_plane[edges.a // 3], poly.face_plane[edges.b // 3]
    keep = (pa != pb) & (pa >= 0) & (pb >= 0)
    pairs = np.unique(np.sort(np.column_stack([pa[keep], pb[keep]]), axis=1), axis=0)
    cluster = np.arange(k)
    normal = poly.omega.copy()
    spread = np.zeros(k)
    for _ in range(_TAU_ROUNDS):
        ca, cb = cluster[pairs[:, 0]], cluster[pairs[:, 1]]
        diff = ca != cb
        ca, cb = ca[diff], cb[diff]
        theta = np.arccos(np.clip(np.einsum("ij,ij->i", normal[ca], normal[cb]), -1.0, 1.0))
        ok = theta + np.maximum(spread[ca], spread[cb]) < tau
        if not ok.any():
            break
        src = np.concatenate([ca[ok], cb[ok]])
        dst = np.concatenate([cb[ok], ca[ok]])
        ang = np.concatenate([theta[ok], theta[ok]])
        order = np.lexsort((ang, src))
        first = np.r_[True, src[order][1:] != src[order][:-1]]
        best = np.full(k, -1)
        best[src[order][first]] = dst[order][first]
        c = np.flatnonzero(best >= 0)
        mutual = c[(best[best[c]] == c) & (c < best[c])]
        root = np.arange(k)
        root[best[mutual]] = mutual
        cluster = root[cluster]
        normal, spread = _cluster_normals(poly, cluster, k)
    return _merged_planes(poly, cluster, normal)


def _cluster_normals(poly: Polygons, cluster: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    vec = np.column_stack([np.bincount(cluster, weights=poly.omega[:, i] * poly.area, minlength=k)
                           for i in range(3)])
    length = np.linalg.norm(vec, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        normal = vec / length[:, None]
    normal[~(length > 0)] = poly.omega[~(length > 0)]
    angle = np.arccos(np.clip(np.einsum("ij,ij->i", poly.omega, normal[cluster]), -1.0, 1.0))
    spread = np.zeros(k)
    np.maximum.at(spread, cluster, angle)
    return normal, spread


def _merged_planes(poly: Polygons, cluster: np.ndarray,
                   normal: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    k = len(poly.h)
    size = np.bincount(cluster, minlength=k)
    merged = size[cluster] > 1
    face_plane = poly.face_plane.copy()
    on = face_plane >= 0
    fc = np.full(len(face_plane), -1)
    fc[on] = cluster[face_plane[on]]
    sel = on & merged[np.maximum(face_plane, 0)]
    ids, new = np.unique(fc[sel], return_inverse=True)
    d = np.einsum("fj,fkj->fk", normal[fc[sel]], poly.vertices[poly.faces[sel]])
    lo = np.full(len(ids), np.inf)
    hi = np.full(len(ids), -np.inf)
    np.minimum.at(lo, new, d.min(axis=1))
    np.maximum.at(hi, new, d.max(axis=1))
    face_plane[sel] = k + new
    return (np.concatenate([poly.omega, normal[ids]]), np.concatenate([poly.h, 0.5 * (lo + hi)]),
            face_plane)


def drop_planes(poly: Polygons, face_plane: np.ndarray, delta: float) -> np.ndarray:
    """The paper's lossy δ: faces on planes covering less than ``delta`` x total area lose their plane."""
    on = face_plane >= 0
    area = np.bincount(face_plane[on], weights=_face_areas(poly)[on])
    small = area < delta * area.sum()
    out = face_plane.copy()
    out[on & small[np.maximum(face_plane, 0)]] = -1
    return out


def _face_areas(poly: Polygons) -> np.ndarray:
    p = poly.vertices[poly.faces]
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 1]), axis=1)
