"""BSP trees of spec §9.7: parsing the token stream, and the surface of the union of IN leaves.

Boundary extraction (after Thibault & Naylor 1987; Naylor, Amanatides &
Thibault 1990). For every split node ``N`` on plane ``p``, its
*sub-hyperplane* ``R_N = cell(N) ∩ p`` is a convex polygon. A point of
``R_N`` lies on the surface exactly when the leaf just inside ``p`` (in
``N``'s inner subtree) and the leaf just outside (in its outer subtree)
differ. So ``R_N`` is pushed down the inner subtree, split at every node it
crosses, and each piece that reaches a leaf takes that leaf's class; the
pieces are then pushed down the outer subtree in the same way. Pieces that
end IN inside and OUT outside are surface facing ``omega_p``; OUT inside and
IN outside, surface facing ``-omega_p``.

Every decision is made by the tree: two pieces meet a plane or a leaf the
same way whoever computes them, so there is no comparison of independently
computed cells. This is what makes the result one closed surface where
planes meet at grazing angles or nearly at one point (where independent
cell faces disagree by more than any safe tolerance). Pieces are processed
in numpy batches, one batch per node: ``O(nodes x depth)`` polygon clips in
``O(nodes)`` vectorized calls.

Conventions: planes ``(omega, h)``, outward unit normals, inner side
``omega . x <= h``; lengths in model units; output polygons
counter-clockwise seen from outside.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, TypeVar

import numpy as np

from ..errors import GeometryError, LimitError
from ..geometry.clipping import split_polygons
from ..geometry.halfspace import intersect
from ..geometry.planes import in_plane_basis
from ..model import BSP_IN, BSP_MAX_SPLIT, BSP_OUT

#: Leaf classes of :class:`Tree` nodes.
SPLIT, IN, OUT = 0, 1, 2


@dataclass(frozen=True)
class Tree:
    """A parsed BSP tree, nodes in preorder.

    ``plane`` (n,) the local reference a split node splits on (-1 at
    leaves); ``kind`` (n,) :data:`SPLIT`, :data:`IN` or :data:`OUT`;
    ``outer`` (n,) the outer child of a split node (its inner child is the
    next node), ``end`` (n,) one past the last node of each subtree.
    """

    plane: np.ndarray
    kind: np.ndarray
    outer: np.ndarray
    end: np.ndarray


#: The most work a tree may ask of the decoder (spec §9.7): the sum over its nodes of their depths,
#: the clips :func:`boundary` makes. A chain of 20,000 splits (4e8) took 25 s; 2^25 takes about a second.
MAX_TREE_WORK = 1 << 25


def parse(tokens: np.ndarray, refs: int) -> Tree:
    """Parse preorder tokens (spec §9.7) over ``refs`` local references; ``BAD_GROUP_STRUCTURE`` if malformed."""
    tok = np.asarray(tokens, dtype=np.int64).reshape(-1)
    n = len(tok)
    if n == 0:
        raise GeometryError("BSP tree has no tokens", code="BAD_GROUP_STRUCTURE")
    split = tok <= BSP_MAX_SPLIT
    if (split & (tok >= refs)).any():
        raise GeometryError(f"BSP tree splits on a reference outside 0..{refs - 1}", code="BAD_GROUP_STRUCTURE")
    if (~split & (tok != BSP_IN) & (tok != BSP_OUT)).any():
        raise GeometryError("BSP tree holds a reserved token", code="BAD_GROUP_STRUCTURE")
    # Open slots after each token: +1 per split, -1 per leaf, starting from 1.
    slots = 1 + np.cumsum(np.where(split, 1, -1))
    if slots[-1] != 0 or (slots[:-1] <= 0).any():
        raise GeometryError("BSP tokens do not form exactly one complete tree", code="BAD_GROUP_STRUCTURE")
    # Walking backwards, the top of the stack is the subtree starting at i + 1 (a split node's
    # inner subtree) and the one below it the subtree that follows (its outer subtree).
    end = np.empty(n, dtype=np.int64)
    stack: list[int] = []
    for i in range(n - 1, -1, -1):
        if split[i]:
            stack.pop()
            end[i] = stack.pop()
        else:
            end[i] = i + 1
        stack.append(int(end[i]))
    outer = np.where(split, 0, -1)
    idx = np.flatnonzero(split)
    outer[idx] = end[idx + 1]
    # Depth in preorder: a split's inner child is one deeper, its outer child too (at outer[i]).
    depth = np.zeros(n, dtype=np.int64)
    for i in idx.tolist():
        depth[i + 1] = depth[outer[i]] = depth[i] + 1
    work = int(depth.sum())
    if work > MAX_TREE_WORK:
        raise LimitError(f"BSP tree of {n} tokens asks {work} clips of its decoder, above {MAX_TREE_WORK} "
                         f"(the sum of its nodes' depths, spec §9.7)")
    kind = np.where(split, SPLIT, np.where(tok == BSP_IN, IN, OUT))
    return Tree(plane=np.where(split, tok, -1), kind=kind, outer=outer, end=end)


def sub_hyperplanes(tree: Tree, omega: np.ndarray, h: np.ndarray, size: float,
                    eps: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``R_N = cell(N) ∩ plane(N)`` for every node: padded polygons ``(pts (n, m, 3), count (n,), labels (n, m))``.

    Each starts as a square of half-side ``size`` (model units) on the node's
    plane, counter-clockwise around its normal, and is clipped by the
    half-spaces of its ancestors, root first (one batch per ancestor: its
    inner subtree is a contiguous run of nodes, and so is its outer one).
    ``labels`` give the plane (local reference) each edge lies on; the
    square's own edges have negative labels. Leaves get ``count`` 0.

    Nodes of a convex piece (:func:`_chains`) are left out: for them
    :func:`piece_faces` gives ``R_N`` already cut down to the piece.
    """
    n = len(tree.kind)
    pts = np.zeros((n, 4, 3))
    labels = np.zeros((n, 4), dtype=np.int64)
    count = np.zeros(n, dtype=np.int64)
    nodes = np.flatnonzero(tree.kind == SPLIT)
    in_piece = np.zeros(n, dtype=bool)
    ends = _chains(tree)
    for start in np.flatnonzero(ends >= 0):
        in_piece[start:ends[start]] = True
    nodes = nodes[~in_piece[nodes]]
    w = omega[tree.plane[nodes]]
    e1, e2 = in_plane_basis(w)
    centre = h[tree.plane[nodes]][:, None] * w
    for c, (a, b) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
        pts[nodes, c] = centre + size * (a * e1 + b * e2)
        labels[nodes, c] = -1 - c
    count[nodes] = 4
    for node in nodes:
        j = int(tree.plane[node])
        for lo, hi, keep in ((node + 1, tree.outer[node], -1), (tree.outer[node], tree.end[node], 1)):
            live = lo + np.flatnonzero(count[lo:hi] >= 3)
            if len(live) == 0:
                continue
            inner, outer, _ = split_polygons(pts[live], count[live], labels[live], omega[j], h[j], j, eps,
                                             sides=(keep,))
            piece_pts, piece_cnt, piece_lab, src = inner if keep < 0 else outer  # type: ignore[misc]
            if piece_pts.shape[1] > pts.shape[1]:
                # Grown geometrically: widening copies every node's polygon.
                wider = max(piece_pts.shape[1], 2 * pts.shape[1])
                pts = np.concatenate([pts, np.zeros((n, wider - pts.shape[1], 3))], axis=1)
                labels = np.concatenate([labels, np.zeros((n, wider - labels.shape[1]), dtype=np.int64)], axis=1)
            count[live] = 0  # pieces coplanar with an ancestor's plane have no region of their own
            pts[live[src], :piece_pts.shape[1]] = piece_pts
            labels[live[src], :piece_pts.shape[1]] = piece_lab
            count[live[src]] = piece_cnt
    return pts, count, labels


def piece_faces(tree: Tree, start: int, leaf: int, omega: np.ndarray, h: np.ndarray,
                size: float, eps: float) -> _Batch:
    """The surface of a convex piece (nodes ``start .. leaf - 1``): the faces of its polytope on its planes.

    The polytope is the cell of ``start`` (its ancestors' half-spaces) cut by
    the piece's planes, computed by one Qhull call
    (:func:`planefmt.geometry.halfspace.intersect`); a face's edge lies on the plane of
    the face across it. Where Qhull cannot (a degenerate piece), each node's
    square is clipped by every half-space instead. Pieces are tagged as
    surface facing their plane's normal.
    """
    path: list[tuple[int, int]] = []  # (plane, side) of the ancestors of start, root first
    node = 0
    while node != start:
        j = int(tree.plane[node])
        if start < tree.outer[node]:
            path.append((j, 0))
            node += 1
        else:
            path.append((j, 1))
            node = int(tree.outer[node])
    # A half-space the path takes twice bounds the piece once: the copy would give no face of its own
    # (the fallback clips its square away on the first copy) and so hide a piece that does not end.
    own = [(int(tree.plane[k]), 0) for k in range(start, leaf)]
    taken = dict.fromkeys(path)
    path = list(taken)
    kept: list[int] = []
    for k, r in enumerate(own):
        if r not in taken:
            taken[r] = None
            kept.append(k)
    node_of = start + np.array(kept, dtype=np.int64)
    rows = path + [own[k] for k in kept]
    plane = np.array([r[0] for r in rows], dtype=np.int64)
    sign = np.array([1.0 - 2.0 * r[1] for r in rows])
    try:
        poly = intersect(omega[plane] * sign[:, None], h[plane] * sign)
    except GeometryError:
        return _clipped_piece(rows, len(path), node_of, omega, h, size, eps)
    offs = poly.polygon_offsets
    size_f = np.diff(offs)
    ring = poly.polygon_vertices
    face_row = np.repeat(poly.polygon_plane, size_f)
    nxt = np.arange(len(ring)) + 1
    nxt[offs[1:] - 1] = offs[:-1]
    # The other plane of edge a -> b: the face holding b -> a.
    key = ring * np.int64(len(poly.vertices)) + ring[nxt]
    back = ring[nxt] * np.int64(len(poly.vertices)) + ring
    order = np.argsort(key)
    pos = np.minimum(np.searchsorted(key[order], back), len(key) - 1)
    found = key[order][pos] == back
    edge_label = np.where(found, plane[face_row[order][pos]], -1)
    if not found.all():
        # Qhull merged a vertex so that the edge has no twin: any other plane through both ends.
        inc_v, inc_p = poly.incidences
        planes_of: dict[int, set[int]] = {}
        for vv, pp in zip(inc_v.tolist(), inc_p.tolist()):
            planes_of.setdefault(vv, set()).add(pp)
        for k in np.flatnonzero(~found):
            a, b = int(ring[k]), int(ring[nxt[k]])
            other = (planes_of.get(a, set()) & planes_of.get(b, set())) - {int(face_row[k])}
            edge_label[k] = plane[min(other)] if other else tree.plane[start]
    keep = poly.polygon_plane >= len(path)
    faces = np.flatnonzero(keep)
    width = int(size_f[faces].max(initial=3))
    pts = np.zeros((len(faces), width, 3))
    lab = np.full((len(faces), width), -1, dtype=np.int64)
    for i, fidx in enumerate(faces):
        a, b = offs[fidx], offs[fidx + 1]
        pts[i, :b - a] = poly.vertices[ring[a:b]]
        lab[i, :b - a] = edge_label[a:b]
    src = node_of[poly.polygon_plane[faces] - len(path)]
    z = np.zeros(len(faces), dtype=np.int64)
    return _Batch(pts, lab, size_f[faces].astype(np.int64), src, z + 3, z + 1, z)


def _clipped_piece(rows: list[tuple[int, int]], depth: int, node_of: np.ndarray, omega: np.ndarray,
                   h: np.ndarray, size: float, eps: float) -> _Batch:
    """The faces of a convex piece by clipping a square on each of its planes by every other half-space.

    ``rows`` are the ``(plane, side)`` of the piece's ancestors (the first
    ``depth``), then of its own nodes ``node_of``; each face is tagged with
    its node, as :func:`piece_faces` tags them.
    """
    parts = []
    for k in range(depth, len(rows)):
        j = rows[k][0]
        w = omega[j][None]
        e1, e2 = in_plane_basis(w)
        c = h[j] * omega[j]
        sq = np.stack([c + size * (a * e1[0] + b * e2[0]) for a, b in ((1, 1), (-1, 1), (-1, -1), (1, -1))])
        pts, cnt, lab = sq[None], np.array([4]), np.array([[-1, -2, -3, -4]])
        for m, (q, side) in enumerate(rows):
            if m == k:
                continue
            inner, outer, _ = split_polygons(pts, cnt, lab, omega[q], h[q], q, eps, sides=(-1,) if side == 0 else (1,))
            pts, cnt, lab, _src = inner if side == 0 else outer  # type: ignore[misc]
            if len(cnt) == 0:
                break
        if len(cnt):
            z = np.zeros(1, dtype=np.int64)
            parts.append(_Batch(pts, lab, cnt, z + node_of[k - depth], z + 3, z + 1, z))
    return _concat(parts) if parts else _empty()


@dataclass
class _Batch:
    """Polygons travelling down the tree: corners, counts, and tags.

    ``src`` the node whose sub-hyperplane a piece belongs to; ``phase`` 1
    while it travels its node's inner subtree, 2 in the outer one; ``face``
    in phase 2: +1 if the piece ended IN on the inner side, -1 if OUT.
    ``cls`` the class of the leaf reached; ``labels`` the plane of each edge.
    """

    pts: np.ndarray
    labels: np.ndarray
    count: np.ndarray
    src: np.ndarray
    phase: np.ndarray
    face: np.ndarray
    cls: np.ndarray

    def take(self, idx: np.ndarray) -> "_Batch":
        return _Batch(self.pts[idx], self.labels[idx], self.count[idx], self.src[idx], self.phase[idx],
                      self.face[idx], self.cls[idx])

    def __len__(self) -> int:
        return len(self.count)


def _concat(batches: list[_Batch]) -> _Batch:
    width = max((b.pts.shape[1] for b in batches), default=3)
    total = sum(len(b) for b in batches)
    pts = np.zeros((total, width, 3))
    labels = np.zeros((total, width), dtype=np.int64)
    at = 0
    for b in batches:
        pts[at:at + len(b), :b.pts.shape[1]] = b.pts
        labels[at:at + len(b), :b.pts.shape[1]] = b.labels
        at += len(b)
    cat = [np.concatenate([getattr(b, f) for b in batches]) if batches else np.zeros(0, dtype=np.int64)
           for f in ("count", "src", "phase", "face", "cls")]
    return _Batch(pts, labels, *cat)


def _empty() -> _Batch:
    z = np.zeros(0, dtype=np.int64)
    return _Batch(np.zeros((0, 3, 3)), np.zeros((0, 3), dtype=np.int64), z, z, z, z, z)


def boundary(tree: Tree, omega: np.ndarray, h: np.ndarray, size: float,
             eps: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The surface of the union of IN leaves: ``(pts (k, m, 3), count (k,), labels (k, m), plane (k,))``.

    Polygons are counter-clockwise seen from outside the solid, ``plane`` the
    local reference each lies on, ``labels`` the reference each edge lies on
    (edge ``i`` from corner ``i`` to the next; negative: the starting square).
    ``size`` bounds the model (see :func:`sub_hyperplanes`); ``eps`` (model
    units) is the on-plane tolerance.
    """
    rpts, rcount, rlab = sub_hyperplanes(tree, omega, h, size, eps)
    chain_end = _chains(tree)
    surface: list[_Batch] = []
    # Frames: [node, stage, batch, pieces returned by the inner subtree].
    result: _Batch = _empty()
    stack: list[list] = [[0, 0, _empty(), None]]
    while stack:
        frame = stack[-1]
        node, stage, batch = frame[0], frame[1], frame[2]
        kind = tree.kind[node]
        if kind != SPLIT:
            batch.cls = np.full(len(batch), kind, dtype=np.int64)
            result = batch
            stack.pop()
            continue
        j = int(tree.plane[node])
        if stage == 0 and chain_end[node] >= 0:
            result = _convex_piece(node, int(chain_end[node]), tree, batch, omega, h, size, eps, surface)
            stack.pop()
            continue
        if stage == 0:
            inner, outer, on = split_polygons(batch.pts, batch.count, batch.labels, omega[j], h[j], j, eps)
            parts = []
            for piece in (inner, outer):
                b = batch.take(piece[3])  # type: ignore[index]
                b.pts, b.count, b.labels = piece[0], piece[1], piece[2]  # type: ignore[index]
                parts.append(b)
            # A piece lying on this node's plane (two splits on one plane) goes inside.
            inside = [parts[0], batch.take(np.flatnonzero(on))]
            if rcount[node] >= 3:
                z = np.zeros(1, dtype=np.int64)
                c = int(rcount[node])
                inside.append(_Batch(rpts[node:node + 1, :c], rlab[node:node + 1, :c], rcount[node:node + 1],
                                     z + node, z + 1, z, z))
            frame[1], frame[2] = 1, parts[1]
            stack.append([node + 1, 0, _concat(inside), None])
        elif stage == 1:
            moved, frame[3] = inner_done(result, node)
            frame[1] = 2
            stack.append([tree.outer[node], 0, _concat([batch, moved]), None])
        else:
            result = _concat([frame[3], outer_done(result, node, surface)])
            stack.pop()
    return _orient(_concat(surface), tree)


class Pieces(Protocol):
    """Polygons travelling down a tree, however their corners are held (:class:`_Batch`, or the
    symbolic batches of :mod:`planefmt.groups.exactbsp`)."""

    src: np.ndarray
    phase: np.ndarray
    face: np.ndarray
    cls: np.ndarray

    def take(self: "P", idx: np.ndarray) -> "P": ...


P = TypeVar("P", bound=Pieces)


def inner_done(result: P, node: int) -> tuple[P, P]:
    """Pieces of ``node``'s sub-hyperplane back from its inner subtree, tagged with the class they
    reached there, to travel the outer one: ``(moved, rest)`` (any batch with ``src``, ``phase``,
    ``face``, ``cls`` and ``take``)."""
    mine = (result.src == node) & (result.phase == 1)
    moved = result.take(np.flatnonzero(mine))
    moved.phase = np.full(len(moved), 2, dtype=np.int64)
    moved.face = np.where(moved.cls == IN, 1, -1)
    return moved, result.take(np.flatnonzero(~mine))


def outer_done(result: P, node: int, surface: list[P]) -> P:
    """Pieces of ``node``'s sub-hyperplane back from its outer subtree: those with different classes
    on the two sides go to ``surface``; returns the other pieces of ``result``."""
    mine = (result.src == node) & (result.phase == 2)
    up = ((result.face == 1) & (result.cls == OUT)) | ((result.face == -1) & (result.cls == IN))
    out = np.flatnonzero(mine & up)
    if len(out):
        surface.append(result.take(out))
    return result.take(np.flatnonzero(~mine))


def _chains(tree: Tree) -> np.ndarray:
    """For each node starting a convex piece, the index of its IN leaf, else -1.

    A convex piece is a run of split nodes each of whose outer child is an
    OUT leaf, the last one's inner child an IN leaf (how encoders write one
    convex cell as a tree).
    """
    n = len(tree.kind)
    end = np.full(n, -1, dtype=np.int64)
    for i in range(n - 1, -1, -1):
        if tree.kind[i] != SPLIT or tree.kind[tree.outer[i]] != OUT:
            continue
        nxt = i + 1
        if tree.kind[nxt] == IN:
            end[i] = nxt
        elif end[nxt] >= 0:
            end[i] = end[nxt]
    return end


def _convex_piece(first: int, leaf: int, tree: Tree, batch: _Batch, omega: np.ndarray, h: np.ndarray,
                  size: float, eps: float, surface: list[_Batch]) -> _Batch:
    """Push ``batch`` through the convex piece of nodes ``first .. leaf - 1`` in one loop.

    Equivalent to visiting the nodes one by one: a piece leaves to OUT at the
    first plane it is outside of, and is IN if inside all. The piece's own
    surface (its faces on its planes, :func:`piece_faces`) goes to
    ``surface``. Returns the pieces of ``batch`` with their leaf classes.
    """
    faces = piece_faces(tree, first, leaf, omega, h, size, eps)
    if len(faces):
        surface.append(faces)
    done: list[_Batch] = []
    rest = batch
    for node in range(first, leaf):
        if len(rest) == 0:
            break
        j = int(tree.plane[node])
        inner, outer, on = split_polygons(rest.pts, rest.count, rest.labels, omega[j], h[j], j, eps)
        out = rest.take(outer[3])  # type: ignore[index]
        out.pts, out.count, out.labels = outer[0], outer[1], outer[2]  # type: ignore[index]
        out.cls = np.full(len(out), OUT, dtype=np.int64)
        done.append(out)
        keep = rest.take(inner[3])  # type: ignore[index]
        keep.pts, keep.count, keep.labels = inner[0], inner[1], inner[2]  # type: ignore[index]
        rest = _concat([keep, rest.take(np.flatnonzero(on))])
    rest.cls = np.full(len(rest), IN, dtype=np.int64)
    return _concat(done + [rest])


def _orient(s: _Batch, tree: Tree) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pieces facing ``-omega`` get their corners reversed (edge labels follow their edges)."""
    pts, labels, count = s.pts, s.labels, s.count
    for i in np.flatnonzero(s.face < 0):
        c = count[i]
        pts[i, :c] = pts[i, :c][::-1]
        # Reversed, edge k runs from old corner c-1-k to old corner c-2-k: old edge c-2-k.
        labels[i, :c] = labels[i, :c][::-1][np.r_[1:c, 0]]
    return pts, count, labels, tree.plane[s.src]
