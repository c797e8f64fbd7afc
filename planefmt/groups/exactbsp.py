"""The surface of a BSP tree decided in exact arithmetic: polygons whose corners are plane triples.

:func:`planefmt.groups.bsptree.boundary` computes corners in float64 and decides
sides within a tolerance; where many nearly coincident or nearly concurrent
planes meet (a finely tessellated fillet, a flat cap whose triangles tilt by
1e-8 rad) those decisions can disagree between the pieces that share a
corner, and welding cannot repair what the classification got wrong
(King_geom.usd: polygons 0.96 of the diagonal off the solid). Here the same
traversal (Thibault & Naylor 1987; Naylor, Amanatides & Thibault 1990) runs
on symbolic polygons: a corner is the triple of planes it lies on (the
polygon's own, and the two of its edges), a crossing on edge ``e`` of a
polygon on ``p`` cut by ``q`` is ``(p, e, q)``, and every side test is the
exact sign of :mod:`planefmt.geometry.predicates`. So the pieces are those exact
arithmetic on the stored planes makes, a corner shared by two pieces is the
same triple in both, and the surface has no crack: every edge is on an even
number of triangles (two, except where sheets touch along an edge). Only the
final coordinates are rounded. Features below the planes' rounding (a tunnel
where a dozen planes nearly meet) are exact features of the stored solid and
stay; :func:`planefmt.groups.solids.decode_tree` therefore tries this last.

Sewing: corners with the same (sorted) triple are one vertex; distinct
triples are one vertex only when the point of one lies exactly on the planes
of the other. A vertex splits an edge on planes ``p, e`` (a T-junction)
when it lies on both, which its triples say, strictly between the ends.

Conventions: planes ``(omega, h)``, outward unit normals, inner side
``omega . x <= h``; the square each sub-hyperplane starts as is bounded by
six box planes ``|x_i| <= size`` appended after the tree's planes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..errors import GeometryError
from ..geometry.predicates import ExactPlanes
from .bsptree import SPLIT, Tree, inner_done, outer_done
from .seams import components, fan_rings

#: Exact (integer) side tests one decoding may spend, about 40 s of them: King_geom's 4,608-triangle
#: torus on its own planes needs 2.6e5; planes concurrent everywhere (a hostile file) stop here.
EXACT_LIMIT = 1_000_000


@dataclass
class _Batch:
    """Symbolic polygons: ``corner`` (n, m, 3) plane triples, ``labels`` (n, m) the plane of the edge
    leaving each corner, ``count`` (n,), and the tags of :class:`planefmt.groups.bsptree._Batch`."""

    corner: np.ndarray
    labels: np.ndarray
    count: np.ndarray
    plane: np.ndarray
    src: np.ndarray
    phase: np.ndarray
    face: np.ndarray
    cls: np.ndarray

    def take(self, idx: np.ndarray) -> "_Batch":
        return _Batch(self.corner[idx], self.labels[idx], self.count[idx], self.plane[idx], self.src[idx],
                      self.phase[idx], self.face[idx], self.cls[idx])

    def __len__(self) -> int:
        return len(self.count)


_TAGS = ("count", "plane", "src", "phase", "face", "cls")


def _empty() -> _Batch:
    z = np.zeros(0, dtype=np.int64)
    return _Batch(np.zeros((0, 3, 3), dtype=np.int64), np.zeros((0, 3), dtype=np.int64), z, z, z, z, z, z)


def _concat(batches: list[_Batch]) -> _Batch:
    batches = [b for b in batches if len(b)]
    if not batches:
        return _empty()
    width = max(b.corner.shape[1] for b in batches)
    total = sum(len(b) for b in batches)
    corner = np.zeros((total, width, 3), dtype=np.int64)
    labels = np.zeros((total, width), dtype=np.int64)
    at = 0
    for b in batches:
        corner[at:at + len(b), :b.corner.shape[1]] = b.corner
        labels[at:at + len(b), :b.corner.shape[1]] = b.labels
        at += len(b)
    return _Batch(corner, labels, *(np.concatenate([getattr(b, f) for b in batches]) for f in _TAGS))


def _split(b: _Batch, planes: ExactPlanes, q: int, want: tuple[int, ...] = (-1, 1)
           ) -> tuple[_Batch | None, _Batch | None, np.ndarray]:
    """``b`` split by plane ``q``: ``(inner, outer, on)``; ``on`` marks polygons with every corner on ``q``.

    Corners on ``q`` belong to both sides (no piece of zero area is made);
    only the sides in ``want`` are computed.
    """
    n, m = b.count.shape[0], b.corner.shape[1]
    live = np.arange(m)[None, :] < b.count[:, None]
    side = np.zeros((n, m), dtype=np.int8)
    side[live] = planes.sides(b.corner[live], q)
    lo = (side < 0).any(axis=1)
    hi = (side > 0).any(axis=1)
    on = ~lo & ~hi
    cross = np.flatnonzero(lo & hi)
    out: list[_Batch | None] = []
    for keep, whole in ((-1, lo & ~hi), (1, hi & ~lo)):
        if keep not in want:
            out.append(None)
            continue
        clipped = _clip(b.take(cross), side[cross], keep, q)
        out.append(_concat([b.take(np.flatnonzero(whole)), clipped]))
    return out[0], out[1], on


def _clip(b: _Batch, side: np.ndarray, keep: int, q: int) -> _Batch:
    """Sutherland-Hodgman on symbolic rows that all straddle ``q``; the crossing on edge ``k`` is the
    triple ``(plane, labels[k], q)``. Keeps the rows' tags (their ``src`` etc.)."""
    n, m = b.corner.shape[:2]
    if n == 0:
        return b
    slot = np.arange(m)[None, :]
    live = slot < b.count[:, None]
    nxt = np.where(slot + 1 < b.count[:, None], slot + 1, 0)
    sb = np.take_along_axis(side, nxt, axis=1)
    crossing = live & (side.astype(np.int64) * sb < 0)
    kept = live & (side * keep >= 0)
    kept_next = np.take_along_axis(kept, nxt, axis=1)
    outc = np.empty((n, 2 * m, 3), dtype=np.int64)
    outc[:, 0::2] = b.corner
    outc[:, 1::2, 0] = b.plane[:, None]
    outc[:, 1::2, 1] = b.labels
    outc[:, 1::2, 2] = q
    ok = np.empty((n, 2 * m), dtype=bool)
    ok[:, 0::2] = kept
    ok[:, 1::2] = crossing
    lab = np.empty((n, 2 * m), dtype=np.int64)
    lab[:, 0::2] = np.where(crossing | kept_next, b.labels, q)
    lab[:, 1::2] = np.where(kept_next, b.labels, q)
    order = np.argsort(~ok, axis=1, kind="stable")
    c = ok.sum(axis=1)
    width = max(int(c.max(initial=0)), 3)
    res = b.take(np.arange(n))
    res.corner = np.take_along_axis(outc, order[:, :width, None], axis=1)
    res.labels = np.take_along_axis(lab, order[:, :width], axis=1)
    res.count = c
    return res.take(np.flatnonzero(c >= 3))


def _squares(tree: Tree, omega: np.ndarray, nodes: np.ndarray, box: int) -> _Batch:
    """Each node's plane inside the box, as a square over the two axes its normal is least along,
    counter-clockwise seen from the normal's side."""
    p = tree.plane[nodes]
    w = omega[p]
    a = np.argmax(np.abs(w), axis=1)
    u, v = (a + 1) % 3, (a + 2) % 3
    # Edges on u = +size, v = +size, u = -size, v = -size run counter-clockwise around the +a axis.
    edges = np.column_stack([box + 2 * u, box + 2 * v, box + 2 * u + 1, box + 2 * v + 1])
    flip = w[np.arange(len(p)), a] < 0
    # Reversed, the ring (v3, v2, v1, v0) has edges (U-, V+, U+, V-).
    edges[flip] = edges[flip][:, [2, 1, 0, 3]]
    corner = np.stack([np.column_stack([p, edges[:, (k - 1) % 4], edges[:, k]]) for k in range(4)], axis=1)
    z = np.zeros(len(p), dtype=np.int64)
    return _Batch(corner, edges, z + 4, p, nodes.astype(np.int64), z + 1, z, z)


def _sub_hyperplanes(tree: Tree, planes: ExactPlanes, box: int) -> dict[int, _Batch]:
    """``R_N = cell(N) ∩ plane(N)`` for every split node (absent where empty), clipped root first."""
    nodes = np.flatnonzero(tree.kind == SPLIT)
    allb = _squares(tree, planes.omega, nodes, box)
    width = 4
    corner = np.zeros((len(tree.kind), width, 3), dtype=np.int64)
    labels = np.zeros((len(tree.kind), width), dtype=np.int64)
    count = np.zeros(len(tree.kind), dtype=np.int64)
    corner[nodes] = allb.corner
    labels[nodes] = allb.labels
    count[nodes] = 4
    for node in nodes:
        j = int(tree.plane[node])
        for lo, hi, keep in ((node + 1, tree.outer[node], -1), (tree.outer[node], tree.end[node], 1)):
            live = lo + np.flatnonzero(count[lo:hi] >= 3)
            if len(live) == 0:
                continue
            z = np.zeros(len(live), dtype=np.int64)
            b = _Batch(corner[live], labels[live], count[live], tree.plane[live], live.astype(np.int64), z, z, z)
            inner, outer, _ = _split(b, planes, j, (keep,))
            piece = inner if keep < 0 else outer
            assert piece is not None
            if piece.corner.shape[1] > corner.shape[1]:
                wider = max(piece.corner.shape[1], 2 * corner.shape[1])
                corner = np.concatenate([corner, np.zeros((len(count), wider - corner.shape[1], 3), dtype=np.int64)],
                                        axis=1)
                labels = np.concatenate([labels, np.zeros((len(count), wider - labels.shape[1]), dtype=np.int64)],
                                        axis=1)
            count[live] = 0  # pieces coplanar with an ancestor's plane have no region of their own
            corner[piece.src, :piece.corner.shape[1]] = piece.corner
            labels[piece.src, :piece.corner.shape[1]] = piece.labels
            count[piece.src] = piece.count
    out = {}
    for node in nodes[count[nodes] >= 3]:
        c = int(count[node])
        z = np.zeros(1, dtype=np.int64)
        out[int(node)] = _Batch(corner[node:node + 1, :c], labels[node:node + 1, :c], count[node:node + 1],
                                tree.plane[node:node + 1], z + node, z + 1, z, z)
    return out


def _surface(tree: Tree, planes: ExactPlanes, box: int) -> _Batch:
    """The surface polygons of the union of IN leaves, oriented counter-clockwise seen from outside."""
    regions = _sub_hyperplanes(tree, planes, box)
    surface: list[_Batch] = []
    result = _empty()
    # Frames: [node, stage, batch, pieces returned by the inner subtree].
    stack: list[list] = [[0, 0, _empty(), None]]
    while stack:
        frame = stack[-1]
        node, stage, batch = frame[0], frame[1], frame[2]
        if tree.kind[node] != SPLIT:
            batch.cls = np.full(len(batch), tree.kind[node], dtype=np.int64)
            result = batch
            stack.pop()
            continue
        j = int(tree.plane[node])
        if stage == 0:
            inner, outer, on = _split(batch, planes, j)
            assert inner is not None and outer is not None
            inside = [inner, batch.take(np.flatnonzero(on))]
            if node in regions:
                inside.append(regions[node])
            frame[1], frame[2] = 1, outer
            stack.append([node + 1, 0, _concat(inside), None])
        elif stage == 1:
            moved, frame[3] = inner_done(result, node)
            frame[1] = 2
            stack.append([tree.outer[node], 0, _concat([batch, moved]), None])
        else:
            result = _concat([frame[3], outer_done(result, node, surface)])
            stack.pop()
    s = _concat(surface)
    for i in np.flatnonzero(s.face < 0):
        c = s.count[i]
        s.corner[i, :c] = s.corner[i, :c][::-1]
        s.labels[i, :c] = s.labels[i, :c][::-1][np.r_[1:c, 0]]
    return s


def exact_boundary(tree: Tree, omega: np.ndarray, h: np.ndarray, size: float, face: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The surface of the union of IN leaves: ``(vertices (V, 3), triangles (T, 3), plane (T,))``.

    ``size`` (model units) bounds the model (rounded up to a power of two, so
    the box planes are exact); ``UNBOUNDED_POLYTOPE`` if an IN leaf reaches the
    box. ``face`` (m,) True for planes that carry surface (default all);
    ``plane`` is the local reference each triangle lies on. Every edge of
    the exact surface is on an even number of triangles; vertices where
    sheets touch come once per sheet (:func:`split_pinches`).
    """
    m = len(h)
    size = float(2.0 ** np.ceil(np.log2(size)))
    eye = np.eye(3)
    w = np.concatenate([omega, np.repeat(eye, 2, axis=0) * np.tile([1.0, -1.0], 3)[:, None]])
    c = np.concatenate([h, np.full(6, size)])
    planes = ExactPlanes(w, c, EXACT_LIMIT)
    s = _surface(tree, planes, m)
    slot = np.arange(s.corner.shape[1])[None, :] < s.count[:, None]
    if (s.labels[slot] >= m).any():
        raise GeometryError("an IN leaf of the BSP tree does not end", code="UNBOUNDED_POLYTOPE")
    if face is not None:
        s = s.take(np.flatnonzero(np.asarray(face, dtype=bool)[s.plane]))
        slot = np.arange(s.corner.shape[1])[None, :] < s.count[:, None]
    vertices, triangles, polygon = _sew(s, planes, slot)
    vertices, triangles = split_pinches(vertices, triangles)
    return vertices, triangles, s.plane[polygon]


def split_pinches(vertices: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A copy of a vertex for each fan of triangles around it (fans joined across the edges at it).

    Exact pieces can touch at a single point (cells meeting at a corner); as one vertex that
    point is not a manifold, and counts once in the Euler characteristic where the solid counts
    it once per sheet. Edges on other than two triangles join fans as they are.
    """
    t = len(triangles)
    if t == 0:
        return vertices, triangles
    corner = np.arange(3 * t).reshape(t, 3)
    ea = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    ca = np.concatenate([corner[:, [0, 1]], corner[:, [1, 2]], corner[:, [2, 0]]])
    key = np.sort(ea, axis=1)
    flip = ea[:, 0] > ea[:, 1]
    ca = np.where(flip[:, None], ca[:, ::-1], ca)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, ca = key[order], ca[order]
    same = (key[1:] == key[:-1]).all(axis=1)
    pairs = np.concatenate([np.column_stack([ca[:-1][same, 0], ca[1:][same, 0]]),
                            np.column_stack([ca[:-1][same, 1], ca[1:][same, 1]])])
    _, first, new = np.unique(components(pairs, 3 * t), return_index=True, return_inverse=True)
    return vertices[triangles.reshape(-1)[first]], new.reshape(t, 3)


def _sew(s: _Batch, planes: ExactPlanes, slot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One triangle mesh from the symbolic polygons: vertices by triple, T-junctions split, fanned."""
    poly = np.repeat(np.arange(len(s)), s.count)
    triples = np.sort(s.corner[slot], axis=1)
    elabel = s.labels[slot]
    uniq, label = np.unique(triples, axis=0, return_inverse=True)
    label = label.reshape(-1)
    pts = planes.points(uniq)
    label = _same_points(planes, uniq, pts)[label]
    # Vertex ids after merging exactly equal points; a vertex's planes are all its triples'.
    ids, vid = np.unique(label, return_inverse=True)
    vid = vid.reshape(-1)
    tri_vid = np.unique(np.column_stack([vid, triples]), axis=0)
    vertices = pts[ids]
    size = s.count.copy()
    start = np.concatenate([[0], np.cumsum(size)])
    ring = vid
    prev = np.arange(len(ring)) - 1
    prev[start[:-1]] = start[1:] - 1
    keep = ring != ring[prev]
    poly, ring, elabel, ctri = poly[keep], ring[keep], elabel[keep], triples[keep]
    size = np.bincount(poly, minlength=len(size))
    live = size >= 3
    sel = live[poly]
    poly, ring, elabel, ctri = poly[sel], ring[sel], elabel[sel], ctri[sel]
    size = size * live
    start = np.concatenate([[0], np.cumsum(size)])
    nxt = np.arange(len(ring)) + 1
    ends = start[1:][size > 0] - 1
    nxt[ends] = start[:-1][size > 0]
    edge, ins, t = _on_edges(planes, vertices, tri_vid, ring, ring[nxt], ctri, ctri[nxt], s.plane[poly], elabel)
    return fan_rings(vertices, ring, poly, len(size), edge, ins, t)


def _same_points(planes: ExactPlanes, triples: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """For distinct triples, the smallest index of a triple naming exactly the same point."""
    n = len(triples)
    scale = float(np.abs(pts).max(initial=1.0))
    pairs = cKDTree(pts).query_pairs(1e-9 * scale, output_type="ndarray")
    rep = np.arange(n)
    if len(pairs) == 0:
        return rep
    a, b = pairs[:, 0], pairs[:, 1]
    same = np.ones(len(pairs), dtype=bool)
    for k in range(3):
        same &= planes.sides(triples[a], triples[b, k]) == 0
    good = pairs[same]
    if len(good) == 0:
        return rep
    comp = components(good, n)
    first = np.full(comp.max() + 1, n, dtype=np.int64)
    np.minimum.at(first, comp, np.arange(n))
    return first[comp]


def _on_edges(planes: ExactPlanes, vertices: np.ndarray, tri_vid: np.ndarray, a: np.ndarray,
              b: np.ndarray, ta: np.ndarray, tb: np.ndarray, p: np.ndarray, e: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices strictly inside edges ``a -> b`` (corner triples ``ta``, ``tb``) on planes ``p`` and
    ``e``: ``(edge, vertex, position)``, positions in (0, 1) increasing along each edge.

    A vertex is on the line of two planes when both are among its planes (those of all its
    triples); it is strictly between the ends when, for a plane through each end that crosses
    the line, it lies on the side the other end lies on (exact signs).
    """
    vp = np.unique(np.column_stack([np.repeat(tri_vid[:, 0], 3), tri_vid[:, 1:].reshape(-1)]), axis=0)
    start = np.searchsorted(vp[:, 0], vp[:, 0], side="left")
    size = np.searchsorted(vp[:, 0], vp[:, 0], side="right") - start
    # Every pair of a vertex's planes (a self-join of its rows).
    row = np.repeat(np.arange(len(vp)), size)
    mate = np.repeat(start, size) + (np.arange(int(size.sum())) - np.repeat(np.cumsum(size) - size, size))
    keep = vp[row, 1] < vp[mate, 1]
    row, mate = row[keep], mate[keep]
    big = np.int64(int(max(vp[:, 1].max(initial=0), p.max(initial=0), e.max(initial=0))) + 1)
    pk = vp[row, 1] * big + vp[mate, 1]
    pv = vp[row, 0]
    order = np.lexsort((pv, pk))
    pk, pv = pk[order], pv[order]
    ek = np.minimum(p, e) * big + np.maximum(p, e)
    lo = np.searchsorted(pk, ek, side="left")
    cnt = np.searchsorted(pk, ek, side="right") - lo
    edge = np.repeat(np.arange(len(a)), cnt)
    vid = pv[np.repeat(lo, cnt) + (np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt))]
    ok = (vid != a[edge]) & (vid != b[edge])
    edge, vid = edge[ok], vid[ok]
    # One triple of each vertex names it for the side tests.
    first = np.searchsorted(tri_vid[:, 0], np.arange(int(tri_vid[:, 0].max(initial=-1)) + 1))
    tv = tri_vid[first[vid], 1:]
    inside = np.ones(len(edge), dtype=bool)
    for end, other in ((ta, tb), (tb, ta)):
        inside &= _beyond(planes, end[edge], other[edge], tv, p[edge], e[edge])
    edge, vid, tv = edge[inside], vid[inside], tv[inside]
    # Order along each edge, exactly: one vertex precedes another when the other lies beyond it
    # (rounded positions of points solved from nearly dependent planes can be in either order).
    order = np.argsort(edge, kind="stable")
    edge, vid, tv = edge[order], vid[order], tv[order]
    lo = np.searchsorted(edge, edge, side="left")
    total = np.searchsorted(edge, edge, side="right") - lo
    rank = np.zeros(len(edge), dtype=np.int64)
    many = np.flatnonzero(total > 1)
    if len(many):
        per = total[many]
        i = np.repeat(many, per)
        j = np.repeat(lo[many], per) + (np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per))
        i, j = i[i != j], j[i != j]
        k = edge[i]
        after = _beyond(planes, tv[j], tb[k], tv[i], p[k], e[k])
        np.add.at(rank, i[after], 1)
    order = np.lexsort((rank, edge))
    edge, vid = edge[order], vid[order]
    return edge, vid, (np.arange(len(edge)) - lo + 1.0) / (total + 1.0)


def _beyond(planes: ExactPlanes, end: np.ndarray, other: np.ndarray, v: np.ndarray, p: np.ndarray,
            e: np.ndarray) -> np.ndarray:
    """Whether points ``v`` on the line of planes ``p, e`` lie strictly beyond ``end`` towards ``other``
    (all given as triples on that line): on ``other``'s side of a plane of ``end`` crossing the line."""
    out = np.zeros(len(v), dtype=bool)
    decided = np.zeros(len(v), dtype=bool)
    for k in range(3):
        x = end[:, k]
        idx = np.flatnonzero(~decided & (x != p) & (x != e))
        so = planes.sides(other[idx], x[idx])
        idx, so = idx[so != 0], so[so != 0]
        out[idx] = planes.sides(v[idx], x[idx]) == so
        decided[idx] = True
    return out
