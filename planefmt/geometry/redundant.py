"""Corners that carry no shape, and dropping them without moving the surface.

A corner whose triangles all lie on one plane (*flat*), or on two planes
meeting in a straight crease that runs through it (*straight*: CAD
tessellators split the long edges of a face where a neighbouring face needs
more corners), can be collapsed into a neighbour along one of its edges
(a half-edge collapse): its triangles become a fan from that neighbour over
the same outline, on the same planes. CAD parts hold many: at Draco-14's
error `box.STL` drops 3,395 of its 4,455 corners, `1002_tray_bottom.STL` 394
of its 2,216.

A collapse of corner v into its neighbour u is made only where the result
covers what v's triangles covered, so that the distance it moves the surface
is bounded by construction rather than found by a search:

* v is inside a closed, manifold fan (every edge at it shared by exactly two
  triangles, one cycle of triangles round it), and so is u;
* v's triangles are on at most two planes (``label``: plane, and colour where
  colours differ); with two, exactly two of v's edges separate them, u is the
  far end of one of those and v lies between u and the other's far end;
* every triangle of v not on the collapsed edge keeps a positive area seen
  along its plane's normal, before and after v moves to u (no fold);
* u and v have exactly two common neighbours (the link condition: no edge
  is made twice, the topology is kept).

Seen along each plane's normal, the collapsed triangles then cover v's
outline on that plane exactly (flat corners) or less a sliver along the
crease (straight corners). Every corner of a triangle on plane p is within
``distance[p]`` of it, before and after, so each point of one surface has a
point of the other within 2 d (d the largest ``distance`` of the planes at
v); along a crease, points within d of both planes are within r = d / s of
their line (s = min(sin θ/2, cos θ/2), θ the angle between the normals), so
the sliver adds 2 r. The bound is per plane, not per collapse: it holds for
any number of collapses, which keep each plane's outline and each corner on
its planes. A collapse whose bound exceeds ``cap`` is not made.

Collapses are made one corner at a time, corners in index order, each into
the farthest neighbour that passes (the lower-numbered of two as far: on the
five CAD parts that drop corners, 13,645 B of files at Draco-14's error
against 13,702 into the lowest-numbered and 13,727 into the nearest, before
kind 13), in passes over the corners until
one makes none; ``_collapse.c`` runs the passes in C (a corner's checks see
every collapse before it, which rounds of numpy could not: box.STL's chains
of straight corners took 47 rounds of 10 to 20 ms), and without the extension
:func:`_passes_python` runs the same rules in Python, slowly. Conventions as
in :mod:`planefmt.geometry.planes` (counter-clockwise triangles seen from
outside).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

try:
    from ._collapse import passes as _passes_c
except ImportError:  # built without a C compiler
    _passes_c = None

#: A pass that makes no collapse ends the reduction; this caps the passes (each makes one at least).
MAX_PASSES = 64

#: A triangle's area seen along its plane's normal must exceed this fraction of |e1| |e2| (sin of the
#: corner angle): a fold, or a triangle too thin to have a side, is not made.
_MIN_SINE = 1e-9


@dataclass(frozen=True)
class Reduced:
    """A mesh with its redundant corners dropped: ``faces`` index ``vertices``; ``origin`` gives the
    input face each face is; ``offset`` bounds the two-sided Hausdorff distance to the input (model
    units, by construction); ``dropped`` counts the corners dropped."""

    vertices: np.ndarray
    faces: np.ndarray
    origin: np.ndarray
    offset: float
    dropped: int


def _fans(faces: np.ndarray, n: int) -> np.ndarray:
    """Per corner, whether its triangles form one closed manifold fan."""
    m = len(faces)
    src = faces.reshape(-1)
    dst = faces[:, [1, 2, 0]].reshape(-1)
    key = src * np.int64(n) + dst
    order = np.argsort(key, kind="stable")
    sk = key[order]
    unique_dir = np.ones(len(sk), dtype=bool)
    dup = sk[1:] == sk[:-1]
    unique_dir[1:] &= ~dup
    unique_dir[:-1] &= ~dup
    twin_key = dst * np.int64(n) + src
    pos = np.clip(np.searchsorted(sk, twin_key), 0, max(len(sk) - 1, 0))
    has_twin = sk[pos] == twin_key
    ok_half = has_twin & unique_dir[np.argsort(order)] & unique_dir[pos]
    good = np.ones(n, dtype=bool)
    np.logical_and.at(good, src, ok_half)
    np.logical_and.at(good, dst, ok_half)
    # One cycle of triangles round each corner: incidences (triangle, corner) at the same vertex joined
    # across the edge leaving it; the count of cycles at a vertex is its count of components.
    twin = order[pos]
    inc = np.arange(3 * m)
    # Half-edge h leaves corner src[h] in triangle h // 3; its twin arrives at src[h] in triangle twin // 3,
    # where the incidence of src[h] is the twin's next corner.
    arrive = (twin // 3) * 3 + (twin % 3 + 1) % 3
    use = has_twin
    graph = coo_matrix((np.ones(int(use.sum())), (inc[use], arrive[use])), shape=(3 * m, 3 * m))
    _, comp = connected_components(graph, directed=False)
    pair = np.unique(src * np.int64(3 * m) + comp)
    cycles = np.bincount(pair // (3 * m), minlength=n)
    return good & (cycles == 1)




def drop_redundant_corners(vertices: np.ndarray, faces: np.ndarray, label: np.ndarray, normal: np.ndarray,
                           distance: np.ndarray, cap: float) -> Reduced:
    """Collapse flat and straight corners (module docstring) where a collapse's bound is at most ``cap``
    (model units).

    ``label`` (m,): each triangle's plane (and colour), -1 for a triangle on none, whose corners are
    kept; ``normal`` (m, 3): the unit outward normal of each triangle's plane; ``distance`` (m,): the
    largest distance of a corner of a triangle on that plane from it (model units).
    """
    p = np.ascontiguousarray(vertices, dtype=np.float64)
    f = np.array(faces, dtype=np.int64).reshape(-1, 3)
    label = np.ascontiguousarray(label, dtype=np.int64)
    normal = np.ascontiguousarray(normal, dtype=np.float64)
    distance = np.ascontiguousarray(distance, dtype=np.float64)
    n = len(p)
    alive = np.ones(len(f), dtype=np.int64)
    # Fans are needed only round the corners on at most two labels and their neighbours (what may be
    # collapsed or collapsed into): on a scan, where few are, finding every fan would cost more than the
    # rest (bun_zipper.ply: 57 such corners of 34,834).
    inc = f.reshape(-1)
    lab = np.repeat(label, 3)
    lo = np.full(n, np.iinfo(np.int64).max)
    hi = np.full(n, -1)
    np.minimum.at(lo, inc, lab)
    np.maximum.at(hi, inc, lab)
    few = lo >= 0
    np.logical_and.at(few, inc, (lab == lo[inc]) | (lab == hi[inc]))
    if not few.any():
        return Reduced(vertices=p, faces=f, origin=np.arange(len(f)), offset=0.0, dropped=0)
    near = np.zeros(n, dtype=bool)
    near[f[few[f].any(axis=1)]] = True
    manifold = (_fans(f[near[f].any(axis=1)], n) & near).astype(np.int64)
    run = _passes_c if _passes_c is not None else _passes_python
    dropped, offset = run(p, f, label, normal, distance, manifold, float(cap), alive)
    f = f[alive.astype(bool)]
    used = np.unique(f)
    index = np.full(n, -1, dtype=np.int64)
    index[used] = np.arange(len(used))
    return Reduced(vertices=p[used], faces=index[f], origin=np.flatnonzero(alive), offset=offset,
                   dropped=dropped)


def _upright(a: list[float], b: list[float], c: list[float], nrm: list[float]) -> bool:
    """Whether triangle a, b, c seen along ``nrm`` turns counter-clockwise, not too thin to have a side
    (the arithmetic of ``_collapse.c``'s ``upright``, operation for operation)."""
    e1 = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    e2 = (c[0] - a[0], c[1] - a[1], c[2] - a[2])
    cx = e1[1] * e2[2] - e1[2] * e2[1]
    cy = e1[2] * e2[0] - e1[0] * e2[2]
    cz = e1[0] * e2[1] - e1[1] * e2[0]
    lhs = cx * nrm[0] + cy * nrm[1] + cz * nrm[2]
    l1 = math.sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2])
    l2 = math.sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2])
    return lhs > _MIN_SINE * l1 * l2


def _passes_python(p: np.ndarray, f: np.ndarray, label: np.ndarray, normal: np.ndarray, distance: np.ndarray,
                   manifold: np.ndarray, cap: float, alive: np.ndarray) -> tuple[int, float]:
    """The collapses of ``_collapse.passes`` in Python: ``f`` and ``alive`` (1 live, 0 collapsed) in
    place; returns (corners dropped, the largest bound of a collapse made)."""
    pts, tri = p.tolist(), f.tolist()
    lab, nrm, dist, man = label.tolist(), normal.tolist(), distance.tolist(), manifold.tolist()
    n = len(pts)
    live = [True] * len(tri)
    at: list[list[int]] = [[] for _ in range(n)]
    for t, corners in enumerate(tri):
        for x in corners:
            at[x].append(t)
    gone = [False] * n
    dropped, offset = 0, 0.0
    for _ in range(MAX_PASSES):
        made = 0
        for v in range(n):
            if gone[v] or not man[v]:
                continue
            fs = [t for t in at[v] if live[t]]
            at[v] = fs
            labels = sorted({lab[t] for t in fs})
            if labels[0] < 0 or len(labels) > 2 or not all(_upright(*(pts[x] for x in tri[t]), nrm[t]) for t in fs):
                continue
            d = max(dist[t] for t in fs)
            around: dict[int, list[int]] = {}
            for t in fs:
                for x in tri[t]:
                    if x != v:
                        around.setdefault(x, []).append(t)
            if len(labels) == 1:
                bound, targets = 2.0 * d, sorted(around)
            else:
                targets = sorted(x for x, ts in around.items() if lab[ts[0]] != lab[ts[1]])
                if len(targets) != 2:
                    continue
                pv, p1, p2 = pts[v], pts[targets[0]], pts[targets[1]]
                if ((p1[0] - pv[0]) * (p2[0] - pv[0]) + (p1[1] - pv[1]) * (p2[1] - pv[1])
                        + (p1[2] - pv[2]) * (p2[2] - pv[2])) >= 0.0:
                    continue
                t1, t2 = around[targets[0]]
                n1, n2 = nrm[t1], nrm[t2]
                cos = min(1.0, max(-1.0, n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2]))
                half = math.acos(cos) / 2.0
                s = min(math.sin(half), math.cos(half))
                if not s > 0.0:
                    continue
                bound = 2.0 * d + 2.0 * d / s
            if not bound <= cap:
                continue
            pv = pts[v]
            far = {x: (pts[x][0] - pv[0]) * (pts[x][0] - pv[0]) + (pts[x][1] - pv[1]) * (pts[x][1] - pv[1])
                   + (pts[x][2] - pv[2]) * (pts[x][2] - pv[2]) for x in targets}
            for u in sorted(targets, key=lambda x: (-far[x], x)):
                if not man[u]:
                    continue
                common = {x for t in at[u] if live[t] for x in tri[t]}
                if sum(1 for x in around if x != u and x in common) != 2:
                    continue
                if not all(u in tri[t] or _upright(*(pts[u] if x == v else pts[x] for x in tri[t]), nrm[t])
                           for t in fs):
                    continue
                for t in fs:
                    if u in tri[t]:
                        live[t] = False
                    else:
                        tri[t][tri[t].index(v)] = u
                        at[u].append(t)
                at[v], gone[v] = [], True
                offset = max(offset, bound)
                dropped += 1
                made += 1
                break
        if not made:
            break
    f[:] = np.asarray(tri, dtype=np.int64).reshape(-1, 3)
    alive[:] = np.asarray(live, dtype=np.int64)
    return dropped, offset
