"""Strategies that turn one body (an edge-connected piece of a mesh) into part groups.

The paper's scheme (:data:`BODY_STRATEGIES`): a convex group where the body is convex, else a
BSP tree, a sealed group or patches (:func:`planefmt.groups.bodies.encode_body`). The default
shell scheme (:data:`SHELL_STRATEGIES`): small convex bodies as convex groups, every other body
as a shell. :class:`GroupSpec` is a part group as the encoder builds it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from ..errors import GeometryError
from ..geometry.polygonize import Polygons, edge_adjacency
from ..groups.bodies import encode_body
from ..geometry.planetable import PlaneTable
from ..groups.shells import Shell
from ..groups.solids import STRATEGIES, Splitter
from ..model import GroupKind


@dataclass(frozen=True)
class GroupSpec:
    """A part group as the encoder builds it: ``refs`` index the object's plane list; cells, tree,
    vertex planes and facets use local references (indices into ``refs``)."""

    kind: GroupKind
    refs: np.ndarray  # (m,) int64
    bounding: np.ndarray  # (m,) bool: True for bounding/cut planes
    cells: tuple[np.ndarray, ...] | None = None
    tree: np.ndarray | None = None
    vertex_planes: np.ndarray | None = None  # (V, 3) SEALED groups
    facets: np.ndarray | None = None  # (T, 4) SEALED groups
    splitter: Splitter | None = None  # the strategy that built a BSP tree; not written
    shell: Shell | None = None  # SHELL groups, once the coding is chosen
    faces: np.ndarray | None = None  # indices of the source's polygonized faces the group stands for (shell scheme)


@dataclass(frozen=True)
class Body:
    """One edge-connected piece of a mesh, as a strategy of :data:`BODY_STRATEGIES` sees it.

    ``polygons`` is the lossless polygonization of the whole mesh and
    ``faces`` the indices of this body's faces in it; ``face_plane`` gives
    each of those faces' plane in the (possibly simplified) plane list
    ``omega``, ``h`` (-1: the face's plane was dropped). ``tolerance`` is a
    fraction of the diagonal. A strategy that needs planes of its own
    (bounding planes of patches) adds them to ``table``.
    """

    polygons: Polygons
    faces: np.ndarray
    face_plane: np.ndarray
    omega: np.ndarray
    h: np.ndarray
    tolerance: float
    table: PlaneTable  # the object's planes: ``omega``, ``h``, then the bounding planes strategies add
    simplified: bool  # tau or delta changed the planes
    splitters: tuple[Splitter, ...] = STRATEGIES  # BSP splitter strategies (planefmt.groups.solids)
    every_plane: bool = False  # shells keep the plane of a face of one triangle too (colours ride on planes)


def is_convex(body: Body) -> bool:
    """Whether the body bounds a convex solid, within ``body.tolerance`` of the diagonal.

    Closed and consistently oriented with positive volume; at every edge
    between two planes the far vertex of each side lies on the inner side of
    the other's plane (up to the tolerance); and the volume equals its convex
    hull's (which rules out surfaces that wind around a convex solid twice).
    """
    poly = body.polygons
    eps = body.tolerance * poly.diagonal
    f = poly.faces[body.faces]
    edges = edge_adjacency(f, len(poly.vertices))
    if not edges.closed:
        return False
    v = poly.vertices
    centre = v[f].reshape(-1, 3).mean(axis=0)
    p = v[f] - centre
    volume = float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum()) / 6.0
    if not volume > 0.0:
        return False
    plane = poly.face_plane[body.faces]
    ta, sa = np.divmod(edges.a, 3)
    tb, sb = np.divmod(edges.b, 3)
    cross = (plane[ta] != plane[tb]) & (plane[ta] >= 0) & (plane[tb] >= 0)
    for (t1, t2, s2) in ((ta, tb, sb), (tb, ta, sa)):
        far = f[t2[cross], (s2[cross] + 2) % 3]
        pl = plane[t1[cross]]
        if (np.einsum("ij,ij->i", poly.omega[pl], v[far]) - poly.h[pl] > eps).any():
            return False
    area = float(poly.area[np.unique(plane[plane >= 0])].sum())
    try:
        hull = ConvexHull(v[np.unique(f)], qhull_options="Qt")
    except QhullError:
        return False
    # A surface winding twice around a convex solid has twice its volume; 1e-9 allows rounding.
    return abs(hull.volume - volume) <= 2.0 * eps * area + 1e-9 * hull.volume


def encode_convex_body(body: Body) -> list[GroupSpec] | None:
    """One ``CONVEX`` group of the body's planes, or None if the body is not convex."""
    if not is_convex(body):
        return None
    refs = np.unique(body.face_plane[body.face_plane >= 0])
    return [GroupSpec(GroupKind.CONVEX, refs, np.zeros(len(refs), dtype=bool))]


def encode_general_body(body: Body) -> list[GroupSpec]:
    """Any other body through :func:`planefmt.groups.bodies.encode_body`: a closed outward body as a BSP
    tree of its own face planes (verified closed, same volume and Euler characteristic), falling
    back to, and anything else as, verified pseudo-convex and pseudo-concave patches."""
    if body.simplified:
        raise GeometryError(f"a non-convex body ({len(body.faces)} triangles): the lossy options "
                            f"delta and tau apply to convex bodies only in this version")
    poly = body.polygons
    groups, _ = encode_body(poly.vertices, poly.faces[body.faces], body.face_plane, poly.distance,
                            body.table, body.tolerance * poly.diagonal, body.splitters)
    return [GroupSpec(g.kind, g.refs, g.bounding, tree=g.tree, vertex_planes=g.vertex_planes, facets=g.facets,
                      splitter=g.splitter) for g in groups]


def encode_shell_body(body: Body) -> list[GroupSpec]:
    """One ``SHELL`` group of the body's triangles over its planes: the planes of faces of two or more
    triangles (of every face with ``body.every_plane``); its corners are named or made explicit
    once the planes' coding is known (:func:`_shells_for`)."""
    fp = body.face_plane
    if not (fp >= 0).any():
        raise GeometryError(f"a body of {len(fp)} triangles, none with an area", code="DEGENERATE_GEOMETRY")
    count = np.bincount(fp[fp >= 0], minlength=len(body.h))
    keep = (fp >= 0) & ((count[np.maximum(fp, 0)] >= 2) | body.every_plane)
    # A group has at least one reference (spec §9).
    refs = np.unique(fp[keep]) if keep.any() else fp[fp >= 0][:1]
    return [GroupSpec(GroupKind.SHELL, refs, np.zeros(len(refs), dtype=bool), faces=body.faces)]


#: Planes of the largest convex body the shell scheme stores as a convex group. Its error is
#: certified by the Hausdorff search, whose time grows with the planes (unit_sphere.STL, 1,280
#: triangles on 1,280 planes: 23-31 s at 1e-6; test_sphere.stl, 224 on 128: 0.4 s); a larger body is a
#: shell, whose bound holds by construction.
CONVEX_MAX_PLANES = 256


def encode_convex_or_shell(body: Body) -> list[GroupSpec]:
    """A convex body of at most :data:`CONVEX_MAX_PLANES` planes, each in one colour, as one ``CONVEX``
    group (the paper's pure planes), any other as a shell."""
    planes = np.unique(body.face_plane[body.face_plane >= 0])
    # Colours split a plane into equal planes (preparing.split_planes); a convex group decodes one
    # face on each plane, in one colour, where a shell keeps each triangle's.
    one_colour = len(np.unique(np.column_stack([body.omega[planes], body.h[planes]]), axis=0)) == len(planes)
    groups = encode_convex_body(body) if len(planes) <= CONVEX_MAX_PLANES and one_colour else None
    if groups is None:
        return encode_shell_body(body)
    return [replace(groups[0], faces=body.faces)]


#: Strategies tried in order for each body: ``(name, encode)``; ``encode`` returns the body's
#: part groups or None when it does not apply. The paper's scheme: convex groups, BSP trees,
#: sealed groups and patches.
BODY_STRATEGIES: list[tuple[str, Callable[[Body], list[GroupSpec] | None]]] = [
    ("convex", encode_convex_body),
    ("solid or patches", encode_general_body),
]

#: The default scheme: convex groups and shells.
SHELL_STRATEGIES: list[tuple[str, Callable[[Body], list[GroupSpec] | None]]] = [
    ("convex or shell", encode_convex_or_shell),
]

#: Encoding schemes: ``shell`` (the default) and ``paper``.
SCHEMES = {"shell": SHELL_STRATEGIES, "paper": BODY_STRATEGIES}
