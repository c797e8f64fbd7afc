"""Sewing decoded polygons into one surface: vertex welding, T-junction splitting, triangulation.

Decoded pieces (the faces of convex cells or patches) are computed one by
one, so a point shared by several pieces comes out as several copies that
differ by rounding, and an edge of one piece can run along two edges of its
neighbour (a T-junction, a crack in the triangle mesh). :func:`stitch`
welds the copies of a vertex, inserts into every polygon edge the vertices
lying on it, and triangulates; both tests use the planes each point lies on
(see :func:`stitch`: how far copies of a vertex may be apart depends on
the angles between its planes). Triangulation:
a polygon that received no vertex is fanned from its first corner, one that
did is fanned from its centroid (a convex polygon with points on its edges
has no other fan free of zero-area triangles); a ring that welding makes
pass one vertex twice (two corners of a thin polygon joined) is fanned as
its separate loops. Polygons are convex and counter-clockwise seen from
outside; so are the triangles.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..geometry.polygonize import edge_adjacency


def weld(points: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Merge points closer than ``tol`` (transitively): ``(merged (k, 3), label (n,))``.

    A merged point is the mean of its members.
    """
    return _merge(points, cKDTree(points).query_pairs(tol, output_type="ndarray"))


def components(pairs: np.ndarray, n: int) -> np.ndarray:
    """Component label (n,) of each of ``n`` items joined by index ``pairs`` (k, 2), transitively."""
    g = coo_matrix((np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    return connected_components(g, directed=False)[1].astype(np.int64)


def _merge(points: np.ndarray, pairs: np.ndarray, weight: np.ndarray | None = None
           ) -> tuple[np.ndarray, np.ndarray]:
    """Connected components of ``pairs`` over ``points``: ``(means (k, 3), label (n,))``, each mean
    weighted by ``weight`` (n,) if given."""
    n = len(points)
    if len(pairs) == 0:
        return points.copy(), np.arange(n)
    label = components(pairs, n)
    k = int(label.max()) + 1
    wt = np.ones(n) if weight is None else weight
    count = np.bincount(label, weights=wt, minlength=k)
    merged = np.column_stack([np.bincount(label, weights=wt * points[:, i], minlength=k) for i in range(3)])
    return merged / count[:, None], label


#: Rounding of a point solved from three planes, in units of ``eps * scale / |det|`` (measured:
#: copies computed along different clip sequences differ by up to about 4 of these units).
ERROR_FACTOR = 16.0
#: Largest welding reach a corner's error estimate may claim, relative to the coordinates' size.
MAX_REACH = 1e-6


class Planes:
    """The planes corners lie on: ``omega`` (k, 3) unit normals, ``h`` (k,), model units."""

    def __init__(self, omega: np.ndarray, h: np.ndarray) -> None:
        self.omega = np.asarray(omega, dtype=np.float64)
        self.h = np.asarray(h, dtype=np.float64)

    def error(self, triple: np.ndarray, scale: float) -> np.ndarray:
        """Expected rounding error (model units) of the points of plane triples ``(n, 3)``.

        A point solved from three planes moves by about ``eps * scale / |det|``
        (``det`` of their normals) under rounding of size ``eps * scale``;
        :data:`ERROR_FACTOR` covers the clip sequences that compute it.
        Zero where a triple is incomplete (such a corner welds by distance alone).
        """
        ok = (triple >= 0).all(axis=1)
        w = self.omega[np.maximum(triple, 0)]
        det = np.abs(np.einsum("ij,ij->i", w[:, 0], np.cross(w[:, 1], w[:, 2])))
        with np.errstate(divide="ignore"):
            err = ERROR_FACTOR * np.finfo(np.float64).eps * scale / det
        return np.where(ok, err, 0.0)


def stitch(points: np.ndarray, offsets: np.ndarray, corners: np.ndarray, planes: Planes,
           plane: np.ndarray, edge_plane: np.ndarray, tol: float,
           scale: float, carried: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One triangle mesh from polygons ``corners[offsets[i]:offsets[i+1]]`` over ``points``.

    Polygon ``i`` lies on plane ``plane[i]`` of ``planes``; ``edge_plane``
    gives, per corner, the plane of the edge leaving it (negative: none). A
    corner is thus the point of three planes, its *triple*, and rounding can
    have moved it by :meth:`Planes.error` (``scale`` the size of the
    coordinates): far along planes that meet at a grazing angle, where a
    fixed welding distance either misses copies of one vertex or merges
    distinct ones. Two corners are one vertex when closer than ``tol`` or
    than the larger of their errors; a vertex splits an edge (a T-junction)
    when it lies as close to the segment, strictly between its ends; with
    ``carried``, or within the errors of the segment's ends (a welded end
    moves the whole edge). Returns
    ``(vertices (V, 3), triangles (T, 3), polygon (T,))``, ``polygon`` the
    input polygon of each triangle. Polygons that collapse below three
    distinct vertices are dropped.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    size = np.diff(offsets)
    poly = np.repeat(np.arange(len(size)), size)
    prev = np.arange(len(corners)) - 1
    prev[offsets[:-1][size > 0]] = offsets[1:][size > 0] - 1
    triple = np.full((len(points), 3), -1, dtype=np.int64)
    triple[corners] = np.column_stack([plane[poly], edge_plane[prev], edge_plane])
    err = planes.error(triple, scale)
    err[~np.isfinite(err)] = 0.0
    # Planes meeting at a grazing angle can claim an error as large as the model: searching every
    # point within the largest claim found all pairs (ADIS16480.STL: more than 6 GB). Each point
    # searches its own reach, capped at MAX_REACH of the coordinates' size.
    err = np.minimum(err, MAX_REACH * scale)
    tree = cKDTree(points)
    pairs = tree.query_pairs(tol, output_type="ndarray")
    wide = np.flatnonzero(err > tol)
    if len(wide):
        near = cKDTree(points[wide]).sparse_distance_matrix(tree, float(err[wide].max()), output_type="ndarray")
        near = near[near["v"] <= err[wide][near["i"]]]
        extra = np.column_stack([wide[near["i"]], near["j"]])
        extra = np.sort(extra[extra[:, 0] != extra[:, 1]], axis=1)
        pairs = np.unique(np.vstack([pairs.reshape(-1, 2), extra]), axis=0)
    if len(pairs):
        a, b = pairs[:, 0], pairs[:, 1]
        dist = np.linalg.norm(points[a] - points[b], axis=1)
        pairs = pairs[dist <= np.maximum(tol, np.maximum(err[a], err[b]))]
    # Weighted by their expected rounding: a copy solved from nearly dependent planes may lie far off
    # along them, and its well-conditioned copies are where the vertex is.
    vertices, label = _merge(points, pairs, 1.0 / np.maximum(err, tol) ** 2)
    # A welded vertex is as uncertain as its most uncertain copy.
    verr = np.zeros(len(vertices))
    np.maximum.at(verr, label, err)
    ring = label[corners]
    # Drop corners equal to their predecessor in the ring (edges that collapsed when welding).
    keep = ring != ring[prev]
    poly, ring, eplane = poly[keep], ring[keep], edge_plane[keep]
    size = np.bincount(poly, minlength=len(size))
    live = size >= 3
    sel = live[poly]
    poly, ring, eplane = poly[sel], ring[sel], eplane[sel]
    size = size * live
    start = np.concatenate([[0], np.cumsum(size)])
    # Edges a -> b of every polygon, and the vertices lying on them.
    nxt = np.arange(len(ring)) + 1
    ends = start[1:][size > 0] - 1
    nxt[ends] = start[:-1][size > 0]
    edge, ins, t = _on_edges(vertices, verr, ring, ring[nxt], tol, carried)
    return fan_rings(vertices, ring, poly, len(size), edge, ins, t)


def fan_rings(vertices: np.ndarray, ring: np.ndarray, poly: np.ndarray, count: int, edge: np.ndarray,
              ins: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangles of ``count`` rings of vertex ids ``ring`` (grouped by ``poly``, in order) with the vertices
    ``ins`` inserted into ring edges ``edge`` at positions ``t`` in (0, 1): ``(vertices, triangles, polygon)``."""
    key = np.concatenate([np.arange(len(ring), dtype=np.float64), edge + t])
    seq = np.concatenate([ring, ins])
    owner = np.concatenate([poly, poly[edge]])
    order = np.lexsort((key, owner))
    seq, owner = seq[order], owner[order]
    grown = np.bincount(poly[edge], minlength=count) > 0
    seq, owner, grown, source = _loops(seq, owner, grown, count)
    vertices, tris, polygon = _triangulate(vertices, seq, owner, grown, len(grown))
    return vertices, tris, source[polygon]


def _loops(seq: np.ndarray, owner: np.ndarray, grown: np.ndarray, count: int
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rings that pass a vertex twice (welding joined two corners of a thin polygon) split into
    their simple loops: ``(seq, owner, grown, source)``, ``source`` the input ring of each loop.

    Fanned as one ring, such a ring covers its pinch twice (edges on four triangles of one
    polygon). Loops of fewer than three vertices have no area and are dropped.
    """
    key = owner * np.int64(int(seq.max(initial=0)) + 1) + seq
    _, inverse, times = np.unique(key, return_inverse=True, return_counts=True)
    pinched = np.unique(owner[times[inverse.reshape(-1)] > 1])
    if len(pinched) == 0:
        return seq, owner, grown, np.arange(count)
    starts = np.searchsorted(owner, np.arange(count + 1))
    keep = ~np.isin(owner, pinched)
    out_seq, out_owner = [seq[keep]], [owner[keep]]
    source, flags = list(range(count)), list(grown)
    for ring in pinched.tolist():
        path: list[int] = []
        loops = []
        for x in seq[starts[ring]:starts[ring + 1]].tolist():
            if x in path:
                at = path.index(x)
                loops.append(path[at:])
                del path[at + 1:]
            else:
                path.append(x)
        loops.append(path)
        loops = [loop for loop in loops if len(loop) >= 3]
        for k, loop in enumerate(loops):
            target = ring if k == 0 else len(source)
            if k:
                source.append(ring)
                flags.append(True)
            out_seq.append(np.asarray(loop, dtype=np.int64))
            out_owner.append(np.full(len(loop), target, dtype=np.int64))
        flags[ring] = True
    seq, owner = np.concatenate(out_seq), np.concatenate(out_owner)
    order = np.argsort(owner, kind="stable")
    return seq[order], owner[order], np.asarray(flags), np.asarray(source, dtype=np.int64)


def _on_edges(vertices: np.ndarray, verr: np.ndarray, a: np.ndarray, b: np.ndarray,
              tol: float, carried: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices strictly inside edges ``a -> b``: ``(edge, vertex, t)`` with ``t`` in (0, 1).

    A vertex is on an edge when within ``tol``, or its rounding error
    ``verr``, of the segment; with ``carried``, also within its own error
    plus the ends' (interpolated along the edge).
    """
    if len(a) == 0:
        empty = np.empty(0, dtype=np.int64)
        return empty, empty, np.empty(0)
    pa, pb = vertices[a], vertices[b]
    mid = 0.5 * (pa + pb)
    radius = 0.5 * np.linalg.norm(pb - pa, axis=1) + max(tol, float(verr.max(initial=0.0)))
    hits = cKDTree(vertices).query_ball_point(mid, radius, return_sorted=False)
    count = np.fromiter((len(x) for x in hits), dtype=np.int64, count=len(hits))
    edge = np.repeat(np.arange(len(a)), count)
    cand = np.fromiter((i for x in hits for i in x), dtype=np.int64, count=int(count.sum()))
    ok = (cand != a[edge]) & (cand != b[edge])
    edge, cand = edge[ok], cand[ok]
    d = pb[edge] - pa[edge]
    r = vertices[cand] - pa[edge]
    length2 = np.einsum("ij,ij->i", d, d)
    t = np.einsum("ij,ij->i", r, d) / np.where(length2 > 0, length2, 1.0)
    dist = np.linalg.norm(r - t[:, None] * d, axis=1)
    length = np.sqrt(length2)
    reach = verr[cand]
    if carried:
        u = np.clip(t, 0.0, 1.0)
        reach = reach + (1.0 - u) * verr[a[edge]] + u * verr[b[edge]]
    near = dist <= np.maximum(tol, reach)
    inside = near & (t * length > tol) & ((1.0 - t) * length > tol)
    return edge[inside], cand[inside], t[inside]


def _triangulate(vertices: np.ndarray, seq: np.ndarray, owner: np.ndarray, grown: np.ndarray,
                 count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fan triangles of the rings ``seq`` grouped by ``owner``: from the first corner, or the
    centroid of grown rings."""
    size = np.bincount(owner, minlength=count)
    start = np.concatenate([[0], np.cumsum(size)])
    plain = ~grown & (size >= 3)
    # Plain rings: (v0, vi, vi+1).
    per = np.where(plain, size - 2, 0)
    p = np.repeat(np.arange(count), per)
    local = np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per) + 1
    base = start[p]
    tri_plain = np.column_stack([seq[base], seq[base + local], seq[base + local + 1]])
    # Grown rings: a new centroid vertex c, triangles (c, vi, vi+1) around the ring.
    g = np.flatnonzero(grown & (size >= 3))
    sel = np.isin(owner, g)
    gi = np.searchsorted(g, owner[sel])
    centre = np.column_stack([np.bincount(gi, weights=vertices[seq[sel], c], minlength=len(g))
                              for c in range(3)]) / size[g][:, None]
    cidx = len(vertices) + np.arange(len(g))
    idx = np.flatnonzero(sel)
    nxt = idx + 1
    last = start[g + 1] - 1
    wrap = np.isin(idx, last)
    nxt[wrap] = start[owner[idx[wrap]]]
    tri_grown = np.column_stack([cidx[gi], seq[idx], seq[nxt]])
    tris = np.concatenate([tri_plain, tri_grown]).astype(np.int64)
    polygon = np.concatenate([p, owner[idx]])
    return np.concatenate([vertices, centre]), tris, polygon


def close_cracks(vertices: np.ndarray, triangles: np.ndarray, reaches: tuple[float, ...]
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Weld only the vertices of edges not shared by exactly two triangles, at each reach in turn
    (model units), until every edge is: ``(vertices, triangles, kept)`` (``kept`` selects the input
    triangles that did not collapse), or None if no reach closes the surface.

    Where several nearly concurrent planes meet, the corners of neighbouring cells differ by more
    than any global welding distance that keeps the rest of the surface intact; the cracks they
    leave are bounded by such edges, and only their vertices move.
    """
    e = np.sort(np.column_stack([triangles.reshape(-1), triangles[:, [1, 2, 0]].reshape(-1)]), axis=1)
    edges, count = np.unique(e, axis=0, return_counts=True)
    loose = np.unique(edges[count != 2])
    if len(loose) == 0:
        return vertices, triangles, np.ones(len(triangles), dtype=bool)
    tree = cKDTree(vertices[loose])
    for reach in reaches:
        pairs = loose[tree.query_pairs(reach, output_type="ndarray")]
        merged, label = _merge(vertices, pairs.reshape(-1, 2))
        t = label[triangles]
        kept = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 2] != t[:, 0])
        if edge_adjacency(t[kept], len(merged)).closed:
            return merged, t[kept], kept
    return None


def fill_slits(vertices: np.ndarray, triangles: np.ndarray, reach: float
               ) -> tuple[np.ndarray, np.ndarray] | None:
    """Triangles closing the holes of a surface whose every hole is a flat slit: ``(fill (k, 3),
    beside (k,))``, ``beside`` a triangle on each one's hole; None if some edge is on more than two
    triangles, a vertex starts two holes, or a hole's corners stray more than ``reach`` (model
    units) from its own plane.

    Where two faces nearly coincide (busted.STL: 5e-6 degrees apart), the planes' solid holds a
    wedge between them thinner than any weld, running past their shared edge; welded, its two
    sides leave a slit along the faces, flat to within the wedge's thickness. Each hole is fanned
    from its first corner, facing the way the surface around it does.
    """
    sides = np.column_stack([triangles.reshape(-1), triangles[:, [1, 2, 0]].reshape(-1)])
    _, inverse, count = np.unique(np.sort(sides, axis=1), axis=0, return_inverse=True, return_counts=True)
    uses = count[inverse.reshape(-1)]
    empty = np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int64)
    if (uses > 2).any():
        return None
    loose = np.flatnonzero(uses == 1)
    if len(loose) == 0:
        return empty
    if len(np.unique(sides[loose, 0])) != len(loose):
        return None
    after = dict(zip(sides[loose, 0].tolist(), sides[loose, 1].tolist()))
    owner = dict(zip(sides[loose, 0].tolist(), (loose // 3).tolist()))
    fans, beside = [], []
    todo = set(after)
    while todo:
        first = min(todo)
        todo.remove(first)
        loop = [first]
        nxt = after[first]
        while nxt != first:
            if nxt not in todo:
                return None
            todo.remove(nxt)
            loop.append(nxt)
            nxt = after[nxt]
        ring = vertices[loop]
        # The smallest singular value is the root of the corners' summed squared distances from
        # the loop's best plane: at most reach puts every corner within reach of it.
        if len(loop) < 3 or np.linalg.svd(ring - ring.mean(axis=0), compute_uv=False)[-1] > reach:
            return None
        at = np.arange(1, len(loop) - 1)
        ids = np.asarray(loop, dtype=np.int64)
        fan = np.column_stack([np.full(len(at), ids[0]), ids[at + 1], ids[at]])
        # Of the triangles around the hole, the one facing most nearly as the fill does.
        around = np.array([owner[x] for x in loop], dtype=np.int64)
        t = vertices[triangles[around]]
        facing = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        facing /= np.maximum(np.linalg.norm(facing, axis=1), np.finfo(np.float64).tiny)[:, None]
        p = vertices[fan]
        area = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]).sum(axis=0)
        fans.append(fan)
        beside.append(np.full(len(at), around[np.argmax(facing @ area)], dtype=np.int64))
    return np.concatenate(fans), np.concatenate(beside)
