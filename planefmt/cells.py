"""Cells groups (kind 1, spec §9.6): a solid as the union of explicit convex cells.

Each cell is decoded as a convex polytope first (bounded, with an interior:
``UNBOUNDED_POLYTOPE``, ``EMPTY_POLYTOPE``). The surface of the union is then
that of a BSP tree over the group's own planes, decoded as a kind 2 group is
(:func:`planefmt.solids.decode_bsp_group`: interior fragments dropped, welded
without T-junctions), so that cells and trees share one boundary extraction.
The tree tests a point against the first cell that may hold it, one split per
entry, ending IN; where the point leaves that cell, the cells that may still
hold it follow. A cell lying wholly on one side of a split is left out of the
other side's subtree, so cells cut from a BSP tree, as writers make them, give
a tree about as large as their entries.

Cells MUST have disjoint interiors (spec §9.6): the union's volume is compared with
the sum of the cells' volumes, and a shortfall is ``BAD_GROUP_STRUCTURE``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .errors import GeometryError
from .halfspace import intersect
from .model import BSP_IN, BSP_OUT
from .solids import decode_bsp_group

#: Tree tokens allowed per cell entry (and per cell) before decoding gives up: cells that no
#: split separates (hostile files) would otherwise make the tree grow exponentially.
TOKENS_PER_ENTRY = 64
#: Relative volume by which the union may fall short of the sum of its cells (rounding of the
#: welded surface), as a fraction of that sum.
OVERLAP_TOLERANCE = 1e-6
#: Vertex distances (relative to the cells' extent) within which a cell counts as touching a plane.
SIDE_TOLERANCE = 1e-9


def decode_cells_group(omega: np.ndarray, h: np.ndarray, cells: Sequence[np.ndarray], face: np.ndarray,
                       label: object = None, plane_error: tuple[float, float] = (0.0, 0.0),
                       merge_limit: float = float("inf")
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The surface of a cells group: ``(vertices, triangles, inc_vertex, inc_ref, triangle_ref)``.

    ``omega`` (m, 3), ``h`` (m,) are the group's planes in reference order,
    ``cells`` its cells' entries ``2 j + s`` (spec §9.6), ``face`` (m,) True for
    face planes. ``plane_error`` and ``merge_limit`` are those of
    :func:`planefmt.halfspace.intersect`, for the cells alone.
    """
    where = "planes" if label is None else f"part group {label}"
    entries = [np.asarray(c, dtype=np.int64).reshape(-1) for c in cells]
    if not entries or any(len(e) == 0 or (e >= 2 * len(h)).any() or (e < 0).any() for e in entries):
        raise GeometryError(f"{where}: malformed cells", code="BAD_GROUP_STRUCTURE")
    corners, volumes = [], []
    for k, e in enumerate(entries):
        sign = np.where(e & 1, -1.0, 1.0)
        poly = intersect(omega[e >> 1] * sign[:, None], h[e >> 1] * sign, group=f"{label}, cell {k}",
                         plane_error=plane_error, merge_limit=merge_limit)
        corners.append(poly.vertices)
        volumes.append(_volume(poly.vertices, poly.triangles))
    tokens = _tree(omega, h, entries, corners, where)
    v, t, inc_v, inc_r, t_ref = decode_bsp_group(omega, h, tokens, face)
    union, total = _volume(v, t), float(sum(volumes))
    if union < total * (1 - OVERLAP_TOLERANCE):
        raise GeometryError(f"{where}: cells overlap (their union holds {union:.6g} of their {total:.6g} volume)",
                            code="BAD_GROUP_STRUCTURE")
    return v, t, inc_v, inc_r, t_ref


def _volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6


def _tree(omega: np.ndarray, h: np.ndarray, entries: list[np.ndarray], corners: list[np.ndarray],
          where: str = "planes") -> np.ndarray:
    """Preorder tokens (spec §9.7) of a tree whose IN leaves are the cells, as the module says.

    Built with an explicit stack: a chain has as many levels as its cell has entries, beyond
    Python's recursion limit in large cells.
    """
    points = np.concatenate(corners)
    eps = SIDE_TOLERANCE * max(float(np.abs(h).max()), float(np.ptp(points, axis=0).max()))
    starts = np.cumsum([0] + [len(c) for c in corners[:-1]])
    flat = np.concatenate(entries)
    flat_cell = np.repeat(np.arange(len(entries)), [len(e) for e in entries])
    sides: dict[int, np.ndarray] = {}

    def side(j: int) -> np.ndarray:
        """Per cell, a bit mask: 1 if it reaches into ω·x < h of plane j, 2 if into ω·x > h."""
        if j not in sides:
            d = points @ omega[j] - h[j]
            mask = (np.minimum.reduceat(d, starts) < -eps).astype(np.int8)
            mask |= (np.maximum.reduceat(d, starts) > eps).astype(np.int8) << 1
            # A cell with an entry on plane j lies on that side exactly, whatever its corners say.
            on = (flat >> 1) == j
            mask[flat_cell[on]] = np.where(flat[on] & 1, 2, 1)
            sides[j] = mask
        return sides[j]

    limit = TOKENS_PER_ENTRY * (sum(len(e) for e in entries) + len(entries))
    tokens: list[int] = []
    # Work items: the cells that may hold a point of the region, the cell being followed (-1: none
    # yet), how many of its entries were passed, and the entries 2 j + s the path to the region
    # took. An entry the path already took is not split on again: a split whose region lies on one
    # side of it would give the tree a sub-hyperplane on the region's own boundary, which the
    # boundary extraction would take for surface.
    stack: list[tuple[np.ndarray, int, int, frozenset[int]]] = [(np.arange(len(entries)), -1, 0, frozenset())]
    while stack:
        if len(tokens) > limit:
            raise GeometryError(f"{where}: the cells make a tree of more than {limit:,.0f} nodes (cells that "
                                f"their own planes do not separate)", code="LIMIT_EXCEEDED")
        candidates, cell, passed, path = stack.pop()
        if cell < 0:
            if len(candidates) == 0:
                tokens.append(BSP_OUT)
                continue
            cell, candidates = int(candidates[0]), candidates[1:]
        while passed < len(entries[cell]) and int(entries[cell][passed]) in path:
            passed += 1
        if passed == len(entries[cell]):
            tokens.append(BSP_IN)
            continue
        e = int(entries[cell][passed])
        j, outside = e >> 1, e & 1
        tokens.append(j)
        mask = side(j)[candidates]
        # The side away from the cell: only the cells reaching into it.
        away = (candidates[(mask & (1 if outside else 2)) != 0], -1, 0, path | {e ^ 1})
        # The cell's side: the chain goes on, the others that reach into it stay candidates.
        along = (candidates[(mask & (2 if outside else 1)) != 0], cell, passed + 1, path | {e})
        inner, outer = (away, along) if outside else (along, away)
        stack.append(outer)
        stack.append(inner)
    return np.array(tokens, dtype=np.uint32)
