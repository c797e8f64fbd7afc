"""Shell groups (kind 6, spec §9.10): triangles over shared corners, each corner named by three
planes or stored as coordinates.

A shell keeps its source's triangles and their connectivity. A corner where
three of its faces' planes meet well-conditioned is *named* by them (one
batched 3×3 solve decodes every named corner); elsewhere (smooth regions,
where neighbouring planes are nearly parallel and a plane triple amplifies
rounding, or a corner on fewer than three planes) it is *explicit*: integer
coordinates on a grid of the group's own step. Faces with a plane (two or
more coplanar source triangles) keep it; a triangle alone on its plane is
*free* and stores none.

The error bound holds by construction: decoded and source triangles
correspond one to one and each decoded triangle is the affine image of its
source, so no point moves farther than its triangle's farthest corner, and
the two-sided Hausdorff distance is at most the largest corner displacement,
which the encoder measures in O(n) from exactly the planes a reader decodes.
Planes ``(omega, h)``: outward unit normals, model units; triangles
counter-clockwise seen from outside.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, depth_first_order

from ..errors import GeometryError
from ..model import FREE, MAX_GRID, Shell
from ..container import varint

try:
    # The encoder walks every candidate shell: a sixth of an encode in Python (eight corpus meshes at
    # 1e-6: 0.63 s of 4.0).
    from ..container._chains import spanning as _spanning
except ImportError:  # built without a C compiler
    _spanning = None
from ..container.shellfields import corner_codes, first_use_order
from .sealed import corners

#: Smallest ``|det|`` of three unit normals the encoder names a corner by: below it a plane
#: rounding of one part in 1e16 already moves the corner by 1e-10 of the model.
MIN_DETERMINANT = 1e-6
def decode_shell(omega: np.ndarray, h: np.ndarray, shell: Shell) -> tuple[np.ndarray, np.ndarray]:
    """Corners (V, 3) and triangles (T, 3) of a shell over the group's planes ``omega``, ``h`` (local
    references). Raises ``GeometryError`` (``BAD_VERTEX``) where a named corner's planes do not meet
    in one point or a corner is not finite."""
    explicit = np.asarray(shell.explicit, dtype=bool)
    points = np.empty((len(explicit), 3))
    if (~explicit).any():
        points[~explicit] = corners(omega, h, np.asarray(shell.vertex_planes, dtype=np.int64))
    if explicit.any():
        points[explicit] = np.asarray(shell.origin, dtype=np.float64) + shell.step * \
            np.asarray(shell.grid, dtype=np.int64).astype(np.float64)
    if not np.isfinite(points).all():
        raise GeometryError("a shell corner is not finite", code="BAD_VERTEX")
    return points, np.asarray(shell.facets, dtype=np.int64)[:, 1:]


def _first_per_group(groups: np.ndarray, score: np.ndarray, n: int) -> np.ndarray:
    order = np.lexsort((score, groups))
    g = groups[order]
    first = np.r_[True, g[1:] != g[:-1]] if len(g) else np.zeros(0, dtype=bool)
    out = np.full(n, -1, dtype=np.int64)
    out[g[first]] = order[first]
    return out


def corner_triples(points: np.ndarray, triangles: np.ndarray, face: np.ndarray,
                   omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each corner, the best-conditioned triple of its faces' planes (local references) and
    ``|det|`` of their normals (0 where a corner has fewer than three planes).

    The triple is chosen greedily, in O(incidences): the first plane at random
    among the corner's (the lowest reference), the second the most nearly
    orthogonal to it, the third the farthest from the line of the first two.
    """
    n = len(points)
    live = face != FREE
    # One int64 key per (corner, plane) pair: a 1-D unique, far faster than rows.
    m = len(omega) + 1
    key = np.unique(triangles[live].reshape(-1) * m + np.repeat(face[live], 3))
    iv, ip = key // m, key % m
    ra = _first_per_group(iv, ip.astype(np.float64), n)
    has = ra >= 0
    a = np.where(has, ip[np.maximum(ra, 0)] if len(ip) else 0, 0)
    wa = omega[a] if len(omega) else np.zeros((n, 3))
    rb = _first_per_group(iv, np.abs(np.einsum("ij,ij->i", omega[ip], wa[iv])) if len(ip) else np.zeros(0), n)
    b = np.where(has, ip[np.maximum(rb, 0)] if len(ip) else 0, 0)
    ab = np.cross(wa, omega[b] if len(omega) else np.zeros((n, 3)))
    rc = _first_per_group(iv, -np.abs(np.einsum("ij,ij->i", omega[ip], ab[iv])) if len(ip) else np.zeros(0), n)
    c = np.where(has, ip[np.maximum(rc, 0)] if len(ip) else 0, 0)
    det = np.abs(np.einsum("ij,ij->i", ab, omega[c])) if len(omega) else np.zeros(n)
    det = np.where(has & (a != b) & (b != c) & (a != c), det, 0.0)
    return np.column_stack([a, b, c]), det


@dataclass(frozen=True)
class ShellPlan:
    """What of a shell does not depend on its planes' coding: triangles sorted by face, corners
    numbered by first use (``points`` (V, 3) in that order),
    each corner's triple of planes with ``|det|`` of their exact normals, and the
    :func:`spanning_walk` of its triangles (the encoder tries a dozen codings, one walk); ``order``,
    the source's triangle each of ``facets`` is."""

    points: np.ndarray
    facets: np.ndarray
    triple: np.ndarray
    det: np.ndarray
    walk: tuple[np.ndarray, np.ndarray, np.ndarray]
    order: np.ndarray


def rewalked(plan: ShellPlan, walk_face: np.ndarray, defer: bool = False) -> ShellPlan:
    """``plan`` with the walk :func:`plan_shell` makes for ``walk_face`` (each source triangle's
    plane that the walk keeps together) and ``defer``, where the triangles' faces, hence their order
    and corners, are ``plan``'s: the rest of the plan is not made again."""
    together = np.asarray(walk_face, dtype=np.int64)[plan.order]
    return replace(plan, walk=spanning_walk(plan.facets[:, 1:], together, defer))


def plan_shell(points: np.ndarray, triangles: np.ndarray, face: np.ndarray, omega: np.ndarray,
               walk_face: np.ndarray | None = None, defer: bool = False) -> ShellPlan:
    """The :class:`ShellPlan` of ``triangles`` (T, 3) over ``points`` (V, 3, model units), each on the
    local reference ``face`` (or :data:`FREE`) of planes with exact normals ``omega``. ``walk_face``:
    each triangle's plane (any numbering) that the walk keeps together, where not ``face``;
    ``defer``: the walk leaves each other plane for later (:func:`spanning_walk`)."""
    triangles = np.asarray(triangles, dtype=np.int64)
    face = np.asarray(face, dtype=np.int64)
    together = face if walk_face is None else np.asarray(walk_face, dtype=np.int64)
    # Planar triangles by face (runs of one reference), free ones last; within a run in the source's
    # order or in that of a depth-first walk across shared edges, whichever codes the corners in
    # fewer deflated bytes (npm_bunny.ply: the walk's 8.0 kB against 13.4; plate_holes.STL: 2.6
    # against 2.5).
    run = np.where(face == FREE, np.iinfo(np.int64).max, face)
    orders = [np.argsort(run, kind="stable"), np.lexsort((walk_order(triangles, len(points)), run))]
    order = min(orders, key=lambda o: len(zlib.compress(varint.encode(corner_codes(
        first_use_order(triangles[o], len(points))[triangles[o]])), 6)))
    triangles, face, together = triangles[order], face[order], together[order]
    rank = first_use_order(triangles, len(points))
    used = np.flatnonzero(rank >= 0)
    source = np.empty(len(used), dtype=np.int64)
    source[rank[used]] = used
    tri = rank[triangles]
    p = points[source]
    triple, det = corner_triples(p, tri, face, omega)
    return ShellPlan(points=p, facets=np.column_stack([face, tri]), triple=triple, det=det,
                     walk=spanning_walk(tri, together, defer), order=order)


def walk_order(triangles: np.ndarray, count: int) -> np.ndarray:
    """Rank of each triangle in a depth-first walk across shared edges (every connected piece in
    turn, from a virtual root joined to each piece's first triangle)."""
    t = len(triangles)
    a = triangles.reshape(-1)
    b = triangles[:, [1, 2, 0]].reshape(-1)
    key = np.minimum(a, b) * count + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    same = key[order][1:] == key[order][:-1]
    u, v = order[:-1][same] // 3, order[1:][same] // 3
    pieces = connected_components(coo_matrix((np.ones(len(u)), (u, v)), shape=(t, t)), directed=False)[1]
    _, first = np.unique(pieces, return_index=True)
    rows = np.r_[u, v, np.full(len(first), t)]
    cols = np.r_[v, u, first]
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(t + 1, t + 1)).tocsr()
    visit = depth_first_order(graph, t, directed=True, return_predecessors=False)
    rank = np.empty(t + 1, dtype=np.int64)
    rank[visit] = np.arange(len(visit))
    return rank[:t]


def encode_shell(plan: ShellPlan, omega: np.ndarray, h: np.ndarray, budget: float) -> Shell:
    """The shell of ``plan`` over planes ``omega``, ``h`` exactly as a reader decodes them.

    Every corner is named by its best triple where that puts it within
    ``budget`` (model units) of where it is, and is explicit otherwise, on a
    grid of step ``2 * budget / sqrt(3)`` (half a cell's diagonal is the
    budget).
    """
    if not (math.isfinite(budget) and budget > 0):
        raise GeometryError(f"a shell needs a positive error budget, not {budget}")
    p, triple = plan.points, plan.triple
    named = plan.det >= MIN_DETERMINANT
    if named.any():
        # Coarsely coded normals can make a well-conditioned triple dependent.
        k = np.flatnonzero(named)
        named[k[~(np.abs(np.linalg.det(omega[triple[k]])) >= MIN_DETERMINANT)]] = False
    if named.any():
        k = np.flatnonzero(named)
        named[k[~(np.linalg.norm(corners(omega, h, triple[k]) - p[k], axis=1) <= budget)]] = False
    explicit = ~named
    # Origin and step are float32 values, which version 5 stores (spec §9.10): the step rounded down
    # keeps half a cell's diagonal within the budget, and any origin does.
    step = _f32_down(2.0 * budget / math.sqrt(3.0))
    origin = np.zeros(3)
    grid = np.zeros((0, 3), dtype=np.int64)
    if explicit.any():
        q = p[explicit]
        span = float((q.max(axis=0) - q.min(axis=0)).max()) + step
        if span / step >= MAX_GRID:
            raise GeometryError(f"a shell spans {span:g} model units, more than {MAX_GRID:.3g} steps of "
                                f"{step:g} (the budget)", code="DEGENERATE_GEOMETRY")
        joined = []
        for shift in _SHIFTS:
            origin = _f32_down(q.min(axis=0) - shift * step)
            grid, distinct = _apart(q, np.rint((q - origin) / step).astype(np.int64), origin, step, budget)
            if distinct:
                break
            joined.append((origin, grid))
        else:
            origin, grid = joined[0]
    return Shell(explicit=explicit, vertex_planes=triple[named], grid=grid, origin=origin, step=step,
                 facets=plan.facets)


#: The 26 grid steps to a cell's neighbours, nearest first.
_NEIGHBOURS = np.array([d for d in np.ndindex(3, 3, 3) if d != (1, 1, 1)], dtype=np.int64) - 1
_NEIGHBOURS = _NEIGHBOURS[np.argsort((_NEIGHBOURS ** 2).sum(axis=1), kind="stable")]

#: Grid origins tried, in steps below the least corner, until no two corners share a point: corners
#: nearer each other than a step stay on one point wherever they sit near a grid point, and have two
#: within the budget from half a step along an axis (a point at (0.5, 0, 0) of a cell is half a step from
#: two), which another origin gives them (formulaGeo.usda at 4e-5: two pairs 3.6e-4 steps apart, 0.1 step
#: from a point). The first is the origin planefmt always took.
_SHIFTS = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.5], [0.5, 0.5, 0.0],
                    [0.0, 0.5, 0.5], [0.5, 0.0, 0.5], [0.5, 0.5, 0.5], [0.25, 0.75, 0.5], [0.75, 0.25, 0.5],
                    [0.5, 0.25, 0.75], [0.25, 0.5, 0.25]])


def _rows(grid: np.ndarray) -> np.ndarray:
    """Each row of an (n, 3) int64 ``grid`` as one 24-byte value, for sorting and searching whole rows."""
    return np.ascontiguousarray(grid).view(np.dtype((np.void, 24))).reshape(-1)


def _row_keys(grid: np.ndarray, margin: int) -> Callable[[np.ndarray], np.ndarray]:
    """A function giving each row of an (n, 3) int64 array one value, distinct rows distinct values, for
    rows within ``margin`` of ``grid``'s range on every axis: one int64 where the range's cells fit in
    one (sorting them is about 8 times as fast as sorting 24-byte rows), else :func:`_rows`."""
    if not len(grid):
        return _rows
    low = grid.min(axis=0) - margin
    dims = [int(d) for d in grid.max(axis=0) - low + margin + 1]
    if dims[0] * dims[1] * dims[2] >= 1 << 62:
        return _rows
    scale = np.array([dims[1] * dims[2], dims[2], 1], dtype=np.int64)
    return lambda rows: (np.asarray(rows, dtype=np.int64) - low) @ scale


#: Rounds of :func:`_apart`: each settles the corners that wanted distinct free points.
_APART_ROUNDS = 8


def _apart(points: np.ndarray, grid: np.ndarray, origin: np.ndarray, step: float,
           budget: float) -> tuple[np.ndarray, bool]:
    """``grid`` (the nearest grid point of each of ``points``) with corners that round onto one point
    moved apart: all but the nearest of them to a free neighbouring point within ``budget`` of their
    source, where there is one; and whether every corner then has a point of its own.

    Distinct corners on one point are joined by every reader that welds by position, which the encoder
    refuses (a closed source must stay closed so welded); it used to refuse the whole grid and retry at
    a quarter of the budget, every corner paying for a few: ten of kuka_kr10r1420_link_4.stl's 4,379
    corners met at Draco-14's error, and the file came out 1.7 times Draco's on a grid 64 times finer
    than the tolerance asks. Moved corners stay within the budget, so the bound holds as before; where
    no free point is near enough, the corners stay joined and the caller's check still sees them.
    """
    grid = grid.copy()
    # Each round moves a corner by one step at most, and looks one step further.
    keys = _row_keys(grid, _APART_ROUNDS + 1)
    for rounds in range(_APART_ROUNDS + 1):
        taken, inverse, count = np.unique(keys(grid), return_inverse=True, return_counts=True)
        if (count == 1).all():
            return grid, True
        if rounds == _APART_ROUNDS:
            break
        inverse = inverse.reshape(-1)
        # Of the corners on one point, the nearest keeps it (a corner alone on its point keeps it: only
        # the few that share one are sorted).
        shared = np.flatnonzero(count[inverse] > 1)
        gap = np.linalg.norm(origin + step * grid[shared] - points[shared], axis=1)
        order = np.lexsort((gap, inverse[shared]))
        keeps = np.zeros(len(shared), dtype=bool)
        keeps[order[np.r_[True, inverse[shared][order][1:] != inverse[shared][order][:-1]]]] = True
        movers = shared[~keeps]
        cand = grid[movers, None, :] + _NEIGHBOURS[None, :, :]
        near = np.linalg.norm(origin + step * cand - points[movers, None, :], axis=2) <= budget
        flat = keys(cand.reshape(-1, 3))
        at = np.minimum(np.searchsorted(taken, flat), len(taken) - 1)
        free = (taken[at] != flat).reshape(near.shape)
        ok = near & free
        has = ok.any(axis=1)
        if not has.any():
            break
        pick = np.argmax(ok, axis=1)
        movers, chosen = movers[has], cand[np.flatnonzero(has), pick[has]]
        # Two movers that chose one point: the first takes it, the other tries again next round.
        _, once = np.unique(keys(chosen), return_index=True)
        grid[movers[once]] = chosen[once]
    return grid, False


def _f32_down(x):
    """``x`` rounded down to float32 values, as float64."""
    x = np.asarray(x, dtype=np.float64)
    f = x.astype(np.float32)
    return np.where(f.astype(np.float64) > x, np.nextafter(f, np.float32(-np.inf)), f).astype(np.float64)[()]


def reordered(shell: Shell, local: np.ndarray) -> Shell:
    """``shell`` once its group's references are renumbered, reference ``j`` becoming ``local[j]``:
    triangles re-sorted by their new face references and corners renumbered by first use, the
    same corners and triangles."""
    fc = np.asarray(shell.facets, dtype=np.int64)
    face = np.full(len(fc), FREE, dtype=np.int64)
    planar = fc[:, 0] != FREE
    face[planar] = local[fc[planar, 0]]
    order = np.argsort(np.where(face == FREE, np.iinfo(np.int64).max, face), kind="stable")
    tri = fc[order, 1:]
    rank = first_use_order(tri, len(shell.explicit))
    back = np.argsort(rank)
    explicit = np.asarray(shell.explicit, dtype=bool)
    named_row = np.cumsum(~explicit) - 1
    grid_row = np.cumsum(explicit) - 1
    new_explicit = explicit[back]
    vertex_planes = local[np.asarray(shell.vertex_planes, dtype=np.int64)[named_row[back[~new_explicit]]]]
    grid = np.asarray(shell.grid, dtype=np.int64)[grid_row[back[new_explicit]]]
    return Shell(explicit=new_explicit, vertex_planes=vertex_planes.reshape(-1, 3), grid=grid.reshape(-1, 3),
                 origin=shell.origin, step=shell.step, facets=np.column_stack([face[order], rank[tri]]))


def spanning_walk(triangles: np.ndarray, face: np.ndarray,
                  defer: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A depth-first walk of ``triangles`` (T, 3) across edges two of them share with opposite
    orientations, each piece from its first triangle: (triangles in walk order, the rotation of
    each that puts the edge it shares with its parent first, links of spec 3.3 §8.10). A neighbour on
    the same ``face`` reference is walked to first, so that a plane's triangles follow one another
    and most triangles are coded "on the parent's plane". With ``defer``, a neighbour on another
    face (not :data:`FREE`) is not walked to but left until the walk has run out, then taken (the
    last left first) as a child of the triangle that left it where that triangle is on the path
    from the last triangle walked to its root, whose subtrees then all precede it, or else as a
    root (which costs three corner codes): the free triangles around a face (a CAD part's fillets
    and holes) are walked before the next face, and their corners coded from one another rather
    than across that face's long triangles.

    Depth first because a triangle's parent is then mostly the one just before
    (link 1 or 2: about 1.5 bits a triangle after deflate on CAD/box.STL,
    against 1.8 breadth first) and a third corner named again is mostly a near
    neighbour of the gate's second corner.
    """
    t = len(triangles)
    a = triangles.reshape(-1)
    b = triangles[:, [1, 2, 0]].reshape(-1)
    count = int(a.max()) + 1
    key, twin_key = a * count + b, b * count + a
    order = np.argsort(key, kind="stable")
    at = np.minimum(np.searchsorted(key[order], twin_key), len(key) - 1)
    twin = np.where(key[order[at]] == twin_key, order[at], -1)
    if _spanning is not None:
        walk_a, rot, links = (np.empty(t, dtype=np.int64) for _ in range(3))
        _spanning(np.ascontiguousarray(twin, dtype=np.int64), np.ascontiguousarray(face, dtype=np.int64),
                  walk_a, rot, links, int(defer))
    else:
        walk_a, rot, links = _walk_python(twin.tolist(), face.tolist(), t, defer)
    rows = np.take_along_axis(triangles[walk_a], (np.arange(3)[None, :] + rot[:, None]) % 3, axis=1)
    return walk_a, rows, links


def _walk_python(twin: list[int], faces: list[int], t: int,
                 defer: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`spanning_walk`'s walk, rotations and links in Python, where the C extension is not built."""
    seen = [False] * t
    walk, rotation, links, parent = [], [], [], []
    on_path: list[bool] = []
    position = [0] * t
    left: list[tuple[int, int, int, int]] = []
    start = 0
    # One step per triangle: the encoder may loop where a reader may not (spec 3.3 §8.10 decodes
    # with numpy alone).
    while True:
        while left and seen[left[-1][0]]:
            left.pop()
        anchor = -1
        if left:
            j, r, p, k = left.pop()
            anchor = p if on_path[p] else -1
            stack = [(j, r, p, k) if anchor >= 0 else (j, r, -1, 0)]
        else:
            while start < t and seen[start]:
                start += 1
            if start == t:
                break
            stack = [(start, 0, -1, 0)]
            start += 1
        m = len(walk) - 1
        while m >= 0 and m != anchor:
            on_path[m] = False
            m = parent[m]
        while stack:
            j, r, p, link = stack.pop()
            if seen[j]:
                continue
            seen[j] = True
            position[j] = len(walk)
            walk.append(j)
            rotation.append(r)
            parent.append(p)
            on_path.append(False)
            links.append(0 if p < 0 else 3 * (len(walk) - 1 - p - 1) + link + 1)
            ahead = []
            for k in ((2, 1, 0) if p < 0 else (2, 1)):
                w = twin[3 * j + (r + k) % 3]
                if w < 0 or seen[w // 3]:
                    continue
                if defer and faces[w // 3] not in (faces[j], FREE):
                    left.append((w // 3, w % 3, position[j], k))
                else:
                    ahead.append((faces[w // 3] == faces[j], w // 3, w % 3, position[j], k))
            # The stack pops last first: same-plane neighbours go on last.
            stack.extend(step[1:] for step in sorted(ahead, key=lambda step: step[0]))
        m = len(walk) - 1
        while m >= 0 and not on_path[m]:
            on_path[m] = True
            m = parent[m]
    return np.array(walk, dtype=np.int64), np.array(rotation, dtype=np.int64), np.array(links, dtype=np.int64)


def shell_tree(shell: Shell, walk: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> tuple[Shell, np.ndarray]:
    """``shell`` laid out as a shell tree (kind 7, spec 3.3 §8.10): the same corners and triangles
    (each triangle's corners rotated), in the order of :func:`spanning_walk` (``walk``, that of its
    triangles, if known), corners renumbered by first use, each named corner's references ascending;
    and the corner of ``shell`` each of its corners is."""
    fc = np.asarray(shell.facets, dtype=np.int64)
    walk, rows, links = spanning_walk(fc[:, 1:], fc[:, 0]) if walk is None else walk
    explicit = np.asarray(shell.explicit, dtype=bool)
    rank = first_use_order(rows, len(explicit))
    back = np.argsort(rank)
    named_row = np.cumsum(~explicit) - 1
    grid_row = np.cumsum(explicit) - 1
    new_explicit = explicit[back]
    vertex_planes = np.sort(np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1, 3)[
        named_row[back[~new_explicit]]], axis=1)
    grid = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)[grid_row[back[new_explicit]]]
    return replace(shell, explicit=new_explicit, vertex_planes=vertex_planes, grid=grid,
                   facets=np.column_stack([fc[walk, 0], rank[rows]]), links=links), back


def reordered_tree(shell: Shell, local: np.ndarray) -> Shell:
    """A shell tree once its group's references are renumbered, reference ``j`` becoming
    ``local[j]``: the same triangles in the same order, each named corner's references ascending
    again (the same three planes, solved in another order, which the encoder measured too); the
    shell itself where nothing is renumbered (its body, made once, is then reused)."""
    if np.array_equal(local, np.arange(len(local))):
        return shell
    fc = np.asarray(shell.facets, dtype=np.int64).copy()
    planar = fc[:, 0] != FREE
    fc[planar, 0] = local[fc[planar, 0]]
    vertex_planes = np.sort(local[np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1, 3)], axis=1)
    return replace(shell, vertex_planes=vertex_planes, facets=fc)
