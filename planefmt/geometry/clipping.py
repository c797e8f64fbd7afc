"""Triangles split by planes, vectorized: the fragment bookkeeping of the solid encoder.

A fragment is a triangle ``(3, 3)`` of model coordinates lying on one of the
mesh's planes. Splitting a batch of triangles by one plane ``omega . x = h``
(outward unit normal ``omega``, model units) classifies every vertex with a
tolerance ``eps`` (model units): ``-1`` inside (``omega . x < h - eps``),
``+1`` outside, ``0`` on the plane; a triangle with vertices strictly on both
sides is clipped into its inner and outer polygons (at most four vertices
each, Sutherland-Hodgman), which are fanned back into triangles. Vertices on
the plane belong to both sides, so no sliver thinner than ``eps`` is ever
created. Winding is preserved: pieces face the way their triangle faced.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def vertex_sides(distances: np.ndarray, eps: float) -> np.ndarray:
    """``-1`` / ``0`` / ``+1`` per signed distance (model units): inside, on (within ``eps``), outside."""
    return np.where(distances > eps, 1, np.where(distances < -eps, -1, 0)).astype(np.int8)


def clip_triangles(tri: np.ndarray, dist: np.ndarray, side: np.ndarray,
                   keep: int) -> tuple[np.ndarray, np.ndarray]:
    """The part of each triangle on one side of a plane, as triangles.

    ``tri`` (n, 3, 3); ``dist`` (n, 3) signed vertex distances to the plane;
    ``side`` (n, 3) from :func:`vertex_sides`; ``keep`` is ``-1`` for the inner
    part, ``+1`` for the outer one. Every triangle must have a vertex strictly
    on each side. Returns ``(triangles (k, 3, 3), source (k,))`` where
    ``source`` indexes the input triangle each piece came from.
    """
    n = len(tri)
    pts = np.zeros((n, 6, 3))
    valid = np.zeros((n, 6), dtype=bool)
    for i in range(3):
        j = (i + 1) % 3
        a, b = tri[:, i], tri[:, j]
        da, db = dist[:, i], dist[:, j]
        valid[:, 2 * i] = side[:, i] * keep >= 0
        pts[:, 2 * i] = a
        cross = side[:, i] * side[:, j] < 0
        # The crossing point is computed from the edge in a canonical direction (lower vertex
        # first by side), so both sides of a split get bit-identical points.
        lo_is_a = side[:, i] < 0
        p_lo = np.where(lo_is_a[:, None], a, b)
        p_hi = np.where(lo_is_a[:, None], b, a)
        d_lo = np.where(lo_is_a, da, db)
        d_hi = np.where(lo_is_a, db, da)
        t = d_lo / np.where(cross, d_lo - d_hi, 1.0)
        pts[:, 2 * i + 1] = p_lo + t[:, None] * (p_hi - p_lo)
        valid[:, 2 * i + 1] = cross
    # Compact each row's valid points to the front, keeping their cyclic order.
    order = np.argsort(~valid, axis=1, kind="stable")
    pts = np.take_along_axis(pts, order[:, :, None], axis=1)
    count = valid.sum(axis=1)
    first = np.stack([pts[:, 0], pts[:, 1], pts[:, 2]], axis=1)
    quad = count >= 4
    second = np.stack([pts[quad, 0], pts[quad, 2], pts[quad, 3]], axis=1)
    source = np.concatenate([np.arange(n), np.flatnonzero(quad)])
    return np.concatenate([first, second]), source


def triangle_areas(tri: np.ndarray) -> np.ndarray:
    """Areas (model units squared) of triangles ``(n, 3, 3)``."""
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def split_polygons(pts: np.ndarray, count: np.ndarray, labels: np.ndarray, omega: np.ndarray,
                   h: np.ndarray | float, plane_id: int, eps: float, sides: tuple[int, ...] = (-1, 1)
                   ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None,
                              tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None, np.ndarray]:
    """Convex polygons split by one plane: ``(inner, outer, on)``.

    ``pts`` (n, m, 3) holds ``count[i]`` corners of polygon ``i`` (the rest is
    padding); ``labels`` (n, m) the plane each edge lies on (edge ``k`` runs
    from corner ``k`` to the next). ``omega`` (3,) and ``h`` give the plane,
    ``plane_id`` its label on the edges it creates. ``inner`` and ``outer``
    are ``(pts, count, labels, source)``: the pieces on the side
    ``omega . x <= h`` and ``>= h`` and the input polygon each came from; a
    polygon wholly on one side passes unchanged. Corners within ``eps`` of
    the plane belong to both sides, so no piece thinner than ``eps`` is made.
    ``on`` marks polygons with every corner on the plane (in neither output).
    Only the sides listed in ``sides`` (``-1`` inner, ``+1`` outer) are
    computed; the other output is None.
    """
    n, m = pts.shape[:2]
    slot = np.arange(m)
    valid = slot[None, :] < count[:, None]
    d = pts @ np.asarray(omega, dtype=np.float64) - h
    side = np.where(valid, vertex_sides(d, eps), 0)
    lo = (side < 0).any(axis=1)
    hi = (side > 0).any(axis=1)
    on = ~lo & ~hi
    cross = np.flatnonzero(lo & hi)
    edges = _Edges.of(pts[cross], count[cross], labels[cross], d[cross], side[cross])
    out: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None] = []
    for keep, whole in ((-1, lo & ~hi), (1, hi & ~lo)):
        if keep not in sides:
            out.append(None)
            continue
        ids = np.flatnonzero(whole)
        p, c, lab = _clip_rows(edges, keep, plane_id)
        width = max(int(count[ids].max(initial=3)), p.shape[1])
        stacked = np.zeros((len(ids) + len(cross), width, 3))
        stacked_lab = np.zeros((len(ids) + len(cross), width), dtype=np.int64)
        w0 = min(width, m)
        stacked[:len(ids), :w0] = pts[ids, :w0]
        stacked_lab[:len(ids), :w0] = labels[ids, :w0]
        stacked[len(ids):, :p.shape[1]] = p
        stacked_lab[len(ids):, :p.shape[1]] = lab
        cnt = np.concatenate([count[ids], c])
        src = np.concatenate([ids, cross])
        good = cnt >= 3
        out.append((stacked[good], cnt[good], stacked_lab[good], src[good]))
    return out[0], out[1], on


@dataclass
class _Edges:
    """What both sides of a split share, per padded polygon row that straddles the plane: the
    rows (``pts``, ``labels``, vertex ``side``), which slots are corners (``live``), the slot each
    edge ends at (``nxt``), and each edge's crossing point (``crossing`` marks edges that have
    one)."""

    pts: np.ndarray
    labels: np.ndarray
    side: np.ndarray
    live: np.ndarray
    nxt: np.ndarray
    crossing: np.ndarray
    point: np.ndarray

    @classmethod
    def of(cls, pts: np.ndarray, count: np.ndarray, labels: np.ndarray, d: np.ndarray,
           side: np.ndarray) -> "_Edges":
        n, m = pts.shape[:2]
        slot = np.arange(m)[None, :]
        live = slot < count[:, None]
        nxt = np.where(slot + 1 < count[:, None], slot + 1, 0)
        rows = np.arange(n)[:, None]
        b = pts[rows, nxt]
        sb = side[rows, nxt]
        db = d[rows, nxt]
        crossing = live & (side * sb < 0)
        # The crossing point from the edge's end on the inner side, so that both sides of a split,
        # and the neighbour sharing the edge, compute the same point.
        lo_is_a = side < 0
        p_lo = np.where(lo_is_a[:, :, None], pts, b)
        p_hi = np.where(lo_is_a[:, :, None], b, pts)
        d_lo = np.where(lo_is_a, d, db)
        d_hi = np.where(lo_is_a, db, d)
        t = d_lo / np.where(crossing, d_lo - d_hi, 1.0)
        return cls(pts, labels, side, live, nxt, crossing, p_lo + t[:, :, None] * (p_hi - p_lo))


def _clip_rows(e: _Edges, keep: int, plane_id: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sutherland-Hodgman on padded polygon rows; every row straddles the plane.

    Slot ``2 k`` of the output holds corner ``k`` if it is kept, slot ``2 k + 1``
    the crossing on edge ``k``, if any; the kept slots are then compacted in
    order. The edge after an output point runs along the input edge ``k`` when
    the next output point lies on that edge too (the crossing on it, or the
    kept corner ``k + 1``), and along the clipping plane otherwise.
    """
    n, m = e.pts.shape[:2]
    if n == 0:
        return np.zeros((0, 3, 3)), np.zeros(0, dtype=np.int64), np.zeros((0, 3), dtype=np.int64)
    rows = np.arange(n)[:, None]
    kept = e.live & (e.side * keep >= 0)
    kept_next = kept[rows, e.nxt]
    outp = np.empty((n, 2 * m, 3))
    outp[:, 0::2] = e.pts
    outp[:, 1::2] = e.point
    ok = np.empty((n, 2 * m), dtype=bool)
    ok[:, 0::2] = kept
    ok[:, 1::2] = e.crossing
    lab = np.empty((n, 2 * m), dtype=np.int64)
    lab[:, 0::2] = np.where(e.crossing | kept_next, e.labels, plane_id)
    lab[:, 1::2] = np.where(kept_next, e.labels, plane_id)
    order = np.argsort(~ok, axis=1, kind="stable")
    c = ok.sum(axis=1)
    width = int(c.max(initial=0))
    return outp[rows, order[:, :width]], c, lab[rows, order[:, :width]]
