"""Closed non-convex solids as unions of convex cells cut from the mesh's own planes (paper, algorithm 1).

Encoding is a BSP autopartition (Thibault & Naylor 1987): every splitting
plane is the plane of a face of the mesh, so a cell is described by face
planes only (spec §9.6, §9.7), and the decomposition is consistent under any
small change of the planes (quantization): neighbouring cells share their
splitting plane, so they still tile the solid.

* Fragments. The mesh's triangles, lying on their (polygonized) planes, are
  pushed down the tree and split at every node (:mod:`planefmt.clipping`).
  Fragments within ``eps`` of the splitting plane, and every fragment of the
  splitter's own plane, are consumed there.
* Splitter choice. In a cell whose fragments are few enough to test
  exhaustively, a plane is *supporting* if every fragment lies on its inner
  side (within ``eps``). If all planes are supporting, the fragments are the
  faces of one convex piece: it becomes one cell at once, instead of a chain
  of nodes each peeling off an empty outer side (the chain trees that made a
  naive boundary extraction quadratic). Otherwise the splitter is the best of
  a few random non-supporting ("reflex") planes by ``w * splits + imbalance``.
* Hull first. A convex piece lists every plane it has a fragment of, so a
  plane bounding many pieces (the caps of an extruded profile, the faces of
  a plate around its holes) is written once per piece. Split first on the
  body's convex-hull face planes, whose outer sides are OUT leaves, they
  bound every cell below and are written once.
* The tree's size is what the file pays for; which strategy (candidates,
  ``w``, hull first or not) makes the smallest tree depends on the body, so
  the encoder builds the trees of a set of strategies (:data:`STRATEGIES`,
  :data:`FLAT_STRATEGIES`) and tries the smallest first.
* Leaves. A child with no fragment is uniformly inside or outside; it is IN
  when it lies on the side the splitter's fragments face away from, by net
  area (coincident opposite faces, zero-thickness fins, cancel). This holds
  for one closed, outward, non-self-intersecting body; bodies are encoded one by one, and
  the encoder verifies the decoded surface, so a body where it fails
  (self-intersection, self-contact) is caught and encoded otherwise.
* Output. The tree as preorder tokens (``BSP``, spec §9.7), each convex
  piece written as a chain.

Decoding (:func:`decode_tree`) pushes square pieces of each splitting plane
down the tree to the boundary between IN and OUT leaves
(:func:`planefmt.bsptree.boundary`), welds them into one closed surface
(closing cracks and slits where the welds alone do not), and falls back to
the same traversal in exact arithmetic (:mod:`planefmt.exactbsp`) where
that surface is still open.

Conventions: planes ``(omega, h)``, outward unit normals, inside where
``omega . x <= h``; lengths in model units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from .clipping import clip_triangles, vertex_sides
from .errors import GeometryError
from .bsptree import boundary, parse
from .exactbsp import exact_boundary
from .model import BSP_IN, BSP_OUT
from .polygonize import edge_adjacency
from .seams import Planes, close_cracks, fill_slits, stitch

#: A splitter strategy: (candidates evaluated per node, weight of a split fragment, hull planes first).
Splitter = tuple[int, float, bool]
#: Splitter strategies (the weight of a split fragment is against one of imbalance). The first alone made trees of 335, 957, 2139, 3427, 2995, 4205 and
#: 5069 tokens on the corpus's 20mm cube, angle_block, plate_holes, octagonal_pocket, box,
#: featuretype and tray at draco-14's error; the smallest of the others, 141, 427, 1253, 1587,
#: 1675, 2057 and 1769: the hull planes are written once, not in every convex piece, and weighing
#: splits more keeps the pieces fewer and larger.
STRATEGIES = ((8, 3.0, False), (8, 3.0, True), (64, 10.0, True), (64, 30.0, True))
#: The same without hull planes first (the strategies of 39501da). A hull-first tree is smaller, but
#: its cells can need finer planes to decode within a tolerance, so the file is not always
#: smaller: 1002_tray_bottom.STL at draco-14's error took 28 bits and 5,925 bytes where these
#: trees took 18 bits and 4,941 bytes. The encoder keeps the smaller file of the two sets.
FLAT_STRATEGIES = ((8, 3.0, False), (64, 10.0, False), (64, 30.0, False))
#: Hull planes split first, those of the largest area: a decoder pushes each one's square through
#: everything below it, so a chain of a nearly convex body's thousands of hull planes decodes in
#: quadratic time (tests' dented sphere, 2,808 triangles on 2,612 planes: 128 s to encode and check
#: with all, on a loaded machine). 32 keep the trees of the CAD meshes as small (plate_holes, 198
#: hull planes: 1,253 tokens, 1,255 with all).
HULL_MAX = 32
#: Net area of a plane's fragments, relative to their total, below which they cancel (a fin's two
#: sides): the plane then tells neither side's class.
CANCEL = 1e-9
#: Cells with at most this many fragments are tested for convexity exhaustively
#: (cost: planes x fragment vertices).
EXHAUSTIVE = 2048


@dataclass(frozen=True)
class Partition:
    """The result of :func:`partition`: a BSP tree over the body's planes.

    ``tokens`` (uint32) is the preorder token stream of spec §9.7 over the
    plane indices given to :func:`partition`; a convex piece is written as a
    chain (each of its planes splits, the outer side is OUT, the innermost
    leaf IN). ``splits`` counts the split nodes chosen by the splitter,
    ``pieces`` the convex pieces and ``chain`` the split nodes of their
    chains and of the hull planes' chain; ``strategy`` is the splitter
    strategy that made it.
    """

    tokens: np.ndarray
    splits: int
    pieces: int
    chain: int
    strategy: Splitter


def partition(omega: np.ndarray, h: np.ndarray, tri: np.ndarray, tri_plane: np.ndarray, eps: float,
              reflex_planes: np.ndarray, *, seed: int = 0, strategy: Splitter = STRATEGIES[0]
              ) -> Partition:
    """BSP autopartition of a closed body's triangles ``tri`` (n, 3, 3) on planes ``tri_plane`` (n,).

    ``omega`` (k, 3), ``h`` (k,) are the planes; ``eps`` (model units) the
    distance within which a point counts as on a plane; ``reflex_planes``
    (k,) bool marks planes with a concave edge in the mesh, the splitter
    candidates in cells too large for the exhaustive convexity test;
    ``strategy`` one of :data:`STRATEGIES`. Deterministic for a given
    ``seed`` and ``strategy``.
    """
    rng = np.random.default_rng(seed)
    tokens: list[int] = []
    splits = pieces = chain = 0
    # Work items: (triangles, planes) of a cell, or a leaf token.
    stack: list[tuple[np.ndarray, np.ndarray] | int] = [(tri, tri_plane)]
    if strategy[2]:
        hull, rest = _hull_planes(omega, h, tri, tri_plane, eps)
        if len(hull) and rest.any():
            # A chain whose outer sides are OUT: its inner end is the rest of the body.
            tokens.extend(int(q) for q in hull)
            chain += len(hull)
            stack = [BSP_OUT] * len(hull) + [(tri[rest], tri_plane[rest])]
    while stack:
        item = stack.pop()
        if isinstance(item, int):
            tokens.append(item)
            continue
        t, pl = item
        planes = np.unique(pl)
        if len(t) <= EXHAUSTIVE:
            reflex = _reach(omega[planes], h[planes], t.reshape(-1, 3)) > eps
        else:
            reflex = reflex_planes[planes]
        if not reflex.any():
            # One convex piece: every plane with a fragment here bounds it.
            tokens.extend(int(q) for q in planes)
            tokens.append(BSP_IN)
            tokens.extend([BSP_OUT] * len(planes))
            pieces += 1
            chain += len(planes)
            continue
        p = _choose_splitter(omega, h, t, planes[reflex], eps, rng, strategy)
        splits += 1
        d = t @ omega[p] - h[p]
        side = vertex_sides(d, eps)
        on = (pl == p) | (side == 0).all(axis=1)
        inner = ~on & (side <= 0).all(axis=1)
        outer = ~on & (side >= 0).all(axis=1)
        straddle = ~(on | inner | outer)
        ins, outs = [t[inner]], [t[outer]]
        inp, outp = [pl[inner]], [pl[outer]]
        if straddle.any():
            ts, ds, ss, ps = t[straddle], d[straddle], side[straddle], pl[straddle]
            for keep, tl, plist in ((-1, ins, inp), (1, outs, outp)):
                pieces_t, src = clip_triangles(ts, ds, ss, keep)
                tl.append(pieces_t)
                plist.append(ps[src])
        tin, tout = np.concatenate(ins), np.concatenate(outs)
        tokens.append(int(p))
        inner_in = True
        if not (len(tin) and len(tout)):
            inner_in = _inner_is_solid(t[on], omega[p])
        # Pushed outer first so that the inner subtree is emitted first (preorder, spec §9.7). A side
        # without fragments is one leaf, inside or outside as the splitter's fragments say.
        stack.append((tout, np.concatenate(outp)) if len(tout) else (BSP_OUT if inner_in else BSP_IN))
        stack.append((tin, np.concatenate(inp)) if len(tin) else (BSP_IN if inner_in else BSP_OUT))
    return Partition(tokens=np.asarray(tokens, dtype=np.uint32), splits=splits, pieces=pieces, chain=chain,
                     strategy=strategy)


def _inner_is_solid(on: np.ndarray, normal: np.ndarray) -> bool:
    """Whether the inner side of a splitting plane is the solid next to its fragments ``on`` (n, 3, 3).

    Crossing the plane along ``normal`` the winding number drops by one per
    fragment facing that way and rises by one per fragment facing back; for a
    body whose winding number is 0 or 1 the jump has one sign all over the
    plane, so the sign of the net area tells a fragment-free side's class.
    Coincident opposite faces (a zero-thickness fin, as where a shaft's cap
    meets a head's top) cancel; only faces the plane's own way would claim
    the wrong side there.
    """
    area = np.cross(on[:, 1] - on[:, 0], on[:, 2] - on[:, 0])
    net = float((area @ normal).sum())
    total = float(np.linalg.norm(area, axis=1).sum())
    if not abs(net) > CANCEL * total:
        raise GeometryError("a splitting plane's fragments cancel: its empty side has no class",
                            code="DEGENERATE_GEOMETRY")
    return net > 0


def _hull_planes(omega: np.ndarray, h: np.ndarray, t: np.ndarray, pl: np.ndarray, eps: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Up to :data:`HULL_MAX` planes of ``pl`` no fragment of ``t`` (n, 3, 3) is outside of, whose
    fragments face out, the largest first, and which triangles are on none of them; no planes if
    every plane is one (a convex body).

    A plane qualifies only where its fragments' net area faces along its normal (as
    :func:`_inner_is_solid` decides a side): its outer side is then outside the body.
    """
    planes = np.unique(pl)
    hull = planes[_reach(omega[planes], h[planes], t.reshape(-1, 3)) <= eps]
    if len(hull) == len(planes):
        return hull[:0], np.ones(len(t), dtype=bool)
    area = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    size = np.linalg.norm(area, axis=1)
    if len(hull) > HULL_MAX:
        by_plane = np.bincount(pl, weights=size)[hull]
        hull = np.sort(hull[np.argsort(-by_plane, kind="stable")[:HULL_MAX]])
    side = vertex_sides(np.einsum("nvj,kj->nvk", t, omega[hull]) - h[hull], eps)
    on = (pl[:, None] == hull[None, :]) | (side == 0).all(axis=1)
    net = np.einsum("nk,nk->k", on, area @ omega[hull].T)
    good = net > CANCEL * (on.T @ size)
    return hull[good], ~on[:, good].any(axis=1)


def _choose_splitter(omega: np.ndarray, h: np.ndarray, t: np.ndarray, pool: np.ndarray, eps: float,
                     rng: np.random.Generator, strategy: Splitter) -> int:
    """The best of ``strategy[0]`` random planes of ``pool`` by ``strategy[1] * splits + |inner - outer|``."""
    if len(pool) == 1:
        return int(pool[0])
    candidates, weight, _ = strategy
    cand = rng.choice(pool, size=min(candidates, len(pool)), replace=False)
    d = np.einsum("nvj,kj->knv", t, omega[cand]) - h[cand][:, None, None]
    side = vertex_sides(d, eps)
    lo = (side < 0).any(axis=2)
    hi = (side > 0).any(axis=2)
    splits = (lo & hi).sum(axis=1)
    inner = (lo & ~hi).sum(axis=1)
    outer = (hi & ~lo).sum(axis=1)
    score = weight * splits + np.abs(inner - outer)
    return int(cand[np.argmin(score)])


def _reach(omega: np.ndarray, h: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``max_x omega_i . x - h_i`` over ``points`` for each plane: the maximum is at a hull vertex."""
    pts = np.unique(points, axis=0)
    if len(pts) > 64:
        try:
            pts = pts[ConvexHull(pts, qhull_options="Qt").vertices]
        except QhullError:
            pass
    return (omega @ pts.T - h[:, None]).max(axis=1)



#: On-plane tolerance of the decoder, relative to the largest |h|: a few hundred ulps, so that
#: every decision is made as exact arithmetic would make it (features of planes that nearly meet
#: at one point are resolved consistently, not snapped).
SPLIT_EPS = 4e-13
#: Vertex welding distances of the decoder, relative to the largest |h|, tried in turn until the
#: surface is a closed 2-manifold. The first is above the rounding of points computed along
#: different clip sequences from well-conditioned planes; the others close the sub-tolerance edges
#: where four or more planes nearly meet at one point (pins.glb: cylinder facets and a cap, two
#: corners 2.7e-8 apart at |h| 200, that welding by error estimate joined one way in one cell and
#: the other way in its neighbour; torus.STL, six triangle planes through every vertex, closes only
#: at 1e-6). The encoder verifies the surface the decoder makes, so a weld that moves a vertex
#: beyond the tolerance is caught there.
WELD_TOL = (4e-11, 1e-9, 1e-8, 1e-7, 1e-6)
#: Welding distances, relative to the largest |h|, for the vertices of the cracks no global weld
#: closes (ballA.off: merged planes 3e-6 off their vertices leave cracks up to 8e-6 at |h| 11;
#: closed at 1e-5).
CRACK_WELD = (1e-7, 1e-6, 1e-5, 1e-4)


def decode_tree(omega: np.ndarray, h: np.ndarray, tokens: np.ndarray, face: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The closed surface of a BSP group: ``(vertices (V, 3), triangles (T, 3), plane (T,))``.

    ``omega`` (m, 3), ``h`` (m,) are the group's planes in reference order,
    ``face`` (m,) True for face planes (cut planes carry no surface, spec
    §9.4); ``plane`` is the reference each triangle lies on. Raises
    ``BAD_GROUP_STRUCTURE`` for a malformed tree and ``UNBOUNDED_POLYTOPE``
    when an IN leaf does not end.
    """
    surface = TreeSurface(omega, h, tokens, face)
    if surface.closed:
        return surface.rounded
    return surface.exact() or surface.rounded


class TreeSurface:
    """The surfaces :func:`decode_tree` chooses from, for an encoder that weighs them itself.

    ``rounded`` is the surface of the rounded decisions (welded, cracks and
    slits closed where that closes it) and ``closed`` whether it is closed;
    :meth:`exact` the surface exact arithmetic makes, computed on demand.
    Arguments and raised errors as :func:`decode_tree`.
    """

    def __init__(self, omega: np.ndarray, h: np.ndarray, tokens: np.ndarray, face: np.ndarray) -> None:
        self._omega, self._h, self._face = omega, h, face
        self._tree = parse(tokens, len(h))
        reach = float(np.abs(h).max(initial=0.0))
        reach = reach if reach > 0 else 1.0
        for size in (8.0 * reach, 8e3 * reach):
            polygons = boundary(self._tree, omega, h, size, SPLIT_EPS * reach)
            labels, count = polygons[2], polygons[1]
            if not (labels[np.arange(labels.shape[1])[None, :] < count[:, None]] < 0).any():
                break
        else:
            raise GeometryError("an IN leaf of the BSP tree does not end", code="UNBOUNDED_POLYTOPE")
        self._size = size
        self.rounded, self.closed = _rounded_surface(polygons, omega, h, face, reach)

    def exact(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The exact surface, or None where it is not closed either (or exceeds its budget).

        It comes last in :func:`decode_tree` so that every surface the rounded decoding closes
        decodes as it did: where the rounded decisions misplace pieces (many nearly coincident or
        concurrent planes) it has no cracks to weld, but its sub-rounding features (tunnels,
        sheets touching along an edge) can differ from the source's topology, which the encoder
        checks.
        """
        try:
            surface = exact_boundary(self._tree, self._omega, self._h, self._size, self._face)
        except GeometryError:
            return None
        return surface if edge_adjacency(surface[1], len(surface[0])).closed else None


def _rounded_surface(polygons: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], omega: np.ndarray,
                     h: np.ndarray, face: np.ndarray, reach: float
                     ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], bool]:
    """The first closed surface the welds, crack closing and slit filling make of the rounded
    boundary ``polygons``, and True; else the plain welded surface and False."""
    pts, count, labels, plane = polygons
    keep = face[plane]
    pts, count, labels, plane = pts[keep], count[keep], labels[keep], plane[keep]
    slot = np.arange(pts.shape[1])[None, :] < count[:, None]
    offsets = np.concatenate([[0], np.cumsum(count)])
    # Edges carried by their welded ends only after the plain welds failed, so that every surface
    # that closes without it decodes as it did: where nearly coincident planes cut a face (pins.glb
    # "sides": two planes 6e-4 degrees apart) welded ends move edges 5e-5 off the vertices lying
    # on them.
    plain = None
    welded = []
    for carried in (False, True):
        first = None
        for weld in WELD_TOL:
            vertices, triangles, polygon = stitch(pts[slot], offsets, np.arange(int(count.sum())),
                                                  Planes(omega, h), plane, labels[slot], weld * reach, reach, carried)
            if edge_adjacency(triangles, len(vertices)).closed:
                return (vertices, triangles, plane[polygon]), True
            first = first or (vertices, triangles, plane[polygon])
            if not carried:
                welded.append((weld, vertices, triangles, plane[polygon]))
        closed = close_cracks(first[0], first[1], tuple(r * reach for r in CRACK_WELD))
        if closed is not None:
            return (closed[0], closed[1], first[2][closed[2]]), True
        plain = plain or first
    # Then slits that faces nearly coinciding leave, closed flat (the encoder verifies the result).
    for weld, vertices, triangles, planes in welded:
        slits = fill_slits(vertices, triangles, weld * reach)
        if slits is not None and len(slits[0]):
            filled = np.concatenate([triangles, slits[0]])
            if edge_adjacency(filled, len(vertices)).closed:
                return (vertices, filled, np.concatenate([planes, planes[slits[1]]])), True
    return plain, False


def decode_bsp_group(omega: np.ndarray, h: np.ndarray, tokens: np.ndarray, face: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A BSP group as the codec wants it: ``(vertices, triangles, inc_vertex, inc_ref, triangle_ref)``.

    Incidences pair each vertex with the reference of every surface triangle
    around it (the planes it lies on); ``triangle_ref`` is each triangle's.
    """
    vertices, triangles, plane = decode_tree(omega, h, tokens, face)
    inc = np.unique(np.column_stack([triangles.reshape(-1), np.repeat(plane, 3)]), axis=0)
    return vertices, triangles, inc[:, 0], inc[:, 1], plane
