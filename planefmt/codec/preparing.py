"""A mesh prepared for coding (:class:`_Object`): welded, mended where the paper's scheme finds a
cracked solid, polygonized, simplified by the lossy options, and split into bodies, each encoded
by the scheme's strategies (:func:`_prepare`); and the structure a decoding must keep
(:func:`structure_kept`: a closed source decodes closed with its volume, an open one keeps its area).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..errors import GeometryError, PlnError, PlnWarning
from ..geometry.planes import to_triplets, transform_points
from ..geometry.polygonize import COPLANAR_TOLERANCE, Polygons, edge_adjacency, polygonize, split_planes, weld
from ..geometry.redundant import drop_redundant_corners
from ..geometry.repair import mend_cracks, merge_close_vertices
from ..geometry.topology import euler_characteristic, is_closed_manifold, signed_volume
from ..geometry.planetable import PlaneTable
from ..groups.solids import STRATEGIES, Splitter
from ..model import GroupKind, Mesh, Node
from .lossy import drop_planes, merge_planes
from .strategies import BODY_STRATEGIES, Body, GroupSpec, SCHEMES, encode_shell_body


#: Closing the cracks of open meshes (:func:`planefmt.geometry.repair.mend_cracks`), as fractions of
#: the tolerance: vertices closer than ``_MERGE`` of it (capped at the lossless tolerance) are one
#: point written with two roundings (angle_block.STL: 46 pairs 6e-17 apart, so the solid looked open
#: and took 24x the bytes as patches); T-vertices within ``_SPLIT`` of it of an edge split that edge.
_MERGE = 1e-3

_SPLIT = 0.1

#: The share of the tolerance dropping corners may move the surface by (by construction; what the
#: corners' coding may then move it by is the rest). Measured bounds on the corpus's CAD parts at
#: Draco-14's error: up to 1.6 % of it (1002_tray_bottom.STL, 4.5e-7 of 2.9e-5).
DROP_SHARE = 1 / 16


@dataclass(frozen=True)
class _Object:
    """A mesh prepared for coding: its planes, groups and source surface (local coordinates)."""

    vertices: np.ndarray
    faces: np.ndarray
    triplets: np.ndarray
    groups: tuple[GroupSpec, ...]
    world: np.ndarray
    simplified: bool
    fit: float  # model units
    mended: float  # model units: how far closing cracks or dropping corners moved the source (geometry.repair, .redundant)
    closed: bool  # the source is a closed 2-manifold: its decoding must be one, of the same volume
    volume: float  # model units cubed, local coordinates
    euler: int
    area: float  # model units squared, local coordinates
    rim: float  # model units, local coordinates: length of the edges on one face only (open sources)
    plane_colours: np.ndarray | None  # (planes, 4) uint8 RGBA: a source face's colour on each plane
    name: str = ""  # the scene node's, for messages
    face_plane: np.ndarray | None = None  # (faces,) each face's plane in ``triplets``, -1 for none (shell scheme)
    face_colours: np.ndarray | None = None  # (faces, 4) uint8 RGBA of ``faces`` (shell scheme)
    walk_plane: np.ndarray | None = None  # (faces,) the plane a shell's walk keeps together, where not face_plane
    walk_defer: bool = False  # a shell's walk leaves each other walk plane for later (groups.shells.spanning_walk)


def _prepare(vertices: np.ndarray, faces: np.ndarray, world: np.ndarray, tolerance: float,
             delta: float | None, tau: float | None, face_colours: np.ndarray | None = None,
             diagonal: float | None = None, splitters: tuple[Splitter, ...] = STRATEGIES,
             scheme: str = "shell", keep_corners: bool = False, keep_triangles: bool = False) -> _Object:
    """One node's mesh polygonized and encoded body by body.

    ``diagonal``: the diagonal of the whole source in world units (0 for a
    single mesh: its own), when the polygon fit is to be held to the
    tolerance before the bodies are encoded (an unforced lossless encode);
    :func:`_choose` checks the same against a diagonal no larger, so this
    only fails sooner. ``splitters``: the BSP splitter strategies of solids.
    ``scheme``: ``shell`` (convex groups and one shell group of the other
    bodies) or ``paper`` (convex groups, trees, sealed groups and patches).
    ``keep_corners``: at a lossy tolerance the shell scheme drops the corners that carry no shape
    (:mod:`planefmt.geometry.redundant`) unless this is set. ``keep_triangles``: every body a shell,
    whose triangles are the source's one to one (a convex group's are made from its planes), and
    every corner kept.
    """
    if scheme not in SCHEMES:
        raise PlnError(f"unknown scheme {scheme!r}: one of {', '.join(SCHEMES)}", code="UNSUPPORTED_CODING")
    if keep_triangles and scheme != "shell":
        raise PlnError("keep_triangles needs the shell scheme: the paper's re-makes every triangle from planes",
                       code="UNSUPPORTED_CODING")
    keep_corners = keep_corners or keep_triangles
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise GeometryError(f"tolerance must be a positive fraction of the diagonal, not {tolerance}")
    for name, value in (("delta", delta), ("tau", tau)):
        if value is not None and not (math.isfinite(value) and value >= 0):
            raise GeometryError(f"{name} must be a non-negative number, not {value}")
    vertices, faces = weld(vertices, faces)
    if scheme == "shell":
        # A triangle with a repeated corner has no area: leaving it out changes no surface.
        keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
        if not keep.any():
            raise GeometryError(f"none of the {len(faces)} triangles has three distinct corners",
                                code="DEGENERATE_GEOMETRY")
        faces = faces[keep]
        if face_colours is not None:
            face_colours = np.asarray(face_colours, dtype=np.uint8).reshape(-1, 4)[keep]
        # Points a rounding apart are one point written twice (the touching poles of two spheres made
        # apart, 6e-17 from each other): no coding keeps them apart, and readers that weld within
        # float noise (trimesh on load) join them, so the source is taken joined.
        vertices, faces, kept, mended = merge_close_vertices(
            vertices, faces, _MERGE * min(tolerance, LOSSLESS_TOLERANCE) * _diagonal(vertices))
        if face_colours is not None:
            face_colours = face_colours[kept]
    else:
        mended = 0.0
    closed = is_closed_manifold(faces, len(vertices))
    if not closed and scheme == "paper":
        # An open mesh may be a solid with cracks: closed, it can be stored as one. What it must
        # keep is still an open mesh's (its area): a decoding as patches remains acceptable.
        size = _diagonal(vertices)
        repaired = mend_cracks(vertices, faces, merge=_MERGE * min(tolerance, LOSSLESS_TOLERANCE) * size,
                               split=_SPLIT * tolerance * size)
        vertices, faces, mended = repaired.vertices, repaired.faces, repaired.offset
        if face_colours is not None:
            face_colours = np.asarray(face_colours, dtype=np.uint8).reshape(-1, 4)[repaired.origin]
    # A fit within the tolerance: King_geom.usd's gently curved quads fitted 1.42e-6 of the
    # diagonal from their vertices with the default drift bound, over the lossless 1e-6.
    poly = polygonize(vertices, faces, tolerance=min(COPLANAR_TOLERANCE, tolerance / 2), max_drift=tolerance)
    colours = None if face_colours is None else np.asarray(face_colours, dtype=np.uint8).reshape(-1, 4)
    # A shell's free triangles take its last reference's colour: an object of several colours keeps
    # the plane of every face (each plane takes its faces' colour), and a plane in several colours
    # becomes one plane per colour (geo.usda: 24 faces in 11 colours on 4 planes).
    every = colours is not None and bool((colours != colours[0]).any())
    if every and scheme == "shell":
        poly = split_planes(poly, np.unique(colours, axis=0, return_inverse=True)[1].reshape(-1))
    if scheme == "shell" and not keep_corners and tolerance > LOSSLESS_TOLERANCE and not (tau or delta):
        poly, colours, dropped = _dropped_corners(poly, colours, tolerance, every)
        mended += dropped
    omega, h, face_plane = poly.omega, poly.h, poly.face_plane
    if tau:
        omega, h, face_plane = merge_planes(poly, tau)
    if delta:
        face_plane = drop_planes(poly, face_plane, delta)
    simplified = bool(tau) or bool(delta)
    if diagonal is not None and not simplified and scheme == "paper":
        world_diag = max(diagonal, _diagonal(transform_points(poly.vertices, world)))
        fit = poly.max_distance * float(np.linalg.norm(world[:3, :3], 2))
        if fit > tolerance * world_diag * (1.0 + 1e-9):
            raise _fit_error(fit / world_diag, tolerance)
    body_of_face = _bodies(poly)
    by_body = np.argsort(body_of_face, kind="stable")
    groups: list[GroupSpec] = []
    table = PlaneTable(omega, h)
    for b, faces_b in enumerate(np.split(by_body, np.cumsum(np.bincount(body_of_face))[:-1])):
        body = Body(poly, faces_b, face_plane[faces_b], omega, h, tolerance, table, simplified, splitters, every)
        groups.extend(_encode_body(body, b, KEEP_TRIANGLES if keep_triangles else SCHEMES[scheme]))
    groups = _one_shell(groups)
    omega, h = (np.array(a) for a in table.arrays())
    # Keep only the planes the groups use, numbered in first-use order.
    used = np.concatenate([g.refs for g in groups])
    _, first = np.unique(used, return_index=True)
    order = used[np.sort(first)]
    index = np.full(len(h), -1, dtype=np.int64)
    index[order] = np.arange(len(order))
    groups = [replace(g, refs=index[g.refs]) for g in groups]
    plane_colours = None
    if face_colours is not None:
        # Each plane takes the colour of the first source face on it; bounding planes have none.
        plane_colours = np.zeros((len(order), 4), dtype=np.uint8)
        on = np.flatnonzero(face_plane >= 0)[::-1]
        mapped = index[face_plane[on]]
        plane_colours[mapped[mapped >= 0]] = colours[on][mapped >= 0]
        stored = index[np.maximum(face_plane, 0)]
        recoloured = int(((face_plane >= 0) & (stored >= 0)
                          & (plane_colours[np.maximum(stored, 0)] != colours).any(axis=1)).sum())
        if recoloured:
            warnings.warn(PlnWarning(f"the colours of {recoloured} of {len(colours)} faces: each takes the colour "
                                     f"of its plane's first face (the {scheme} scheme stores one colour per plane)"),
                          stacklevel=3)
    kept = np.where(face_plane >= 0, index[np.maximum(face_plane, 0)], -1)
    return _Object(vertices=poly.vertices, faces=poly.faces, triplets=to_triplets(omega[order], h[order]),
                   groups=tuple(groups), world=world, simplified=simplified, fit=poly.max_distance,
                   mended=mended, closed=closed or _mended_solid(poly, groups),
                   volume=signed_volume(poly.vertices, poly.faces), euler=euler_characteristic(poly.faces),
                   area=_area(poly.vertices, poly.faces), rim=_rim(poly.vertices, poly.faces),
                   plane_colours=plane_colours, face_plane=kept, face_colours=colours)


def _dropped_corners(poly: Polygons, colours: np.ndarray | None, tolerance: float,
                     every: bool) -> tuple[Polygons, np.ndarray | None, float]:
    """``poly`` without its flat and straight corners (:mod:`planefmt.geometry.redundant`), polygonized
    again, its faces' ``colours`` and the bound of how far the surface moved (model units). A
    collapse may move it at most :data:`DROP_SHARE` of the tolerance, which the coding's budget then
    loses."""
    label = poly.face_plane
    on = np.maximum(label, 0)
    reduced = drop_redundant_corners(poly.vertices, poly.faces, label, poly.omega[on], poly.distance[on],
                                     DROP_SHARE * tolerance * poly.diagonal)
    if not reduced.dropped:
        return poly, colours, 0.0
    colours = None if colours is None else colours[reduced.origin]
    again = polygonize(reduced.vertices, reduced.faces, tolerance=min(COPLANAR_TOLERANCE, tolerance / 2),
                       max_drift=tolerance)
    if every:
        again = split_planes(again, np.unique(colours, axis=0, return_inverse=True)[1].reshape(-1))
    return again, colours, reduced.offset


#: The shell scheme's strategy where the source's triangles are kept: every body a shell.
KEEP_TRIANGLES = [("shell", encode_shell_body)]

#: Kinds whose groups are closed surfaces when their source body is.
SOLID_KINDS = frozenset({GroupKind.CONVEX, GroupKind.CELLS, GroupKind.BSP, GroupKind.SEALED})


def _mended_solid(poly: Polygons, groups: Sequence[GroupSpec]) -> bool:
    """Whether a mended mesh came out closed and every body of it a solid: its decoding is then held
    to a closed source's structure (closed, Euler characteristic, volume), whose volume test lets
    a lossy tolerance move the surface, rather than to an open one's area (octagonal_pocket.stl
    fell back to float64 planes at every tolerance: quantized cells changed its area by more than
    1e-6)."""
    return all(int(g.kind) in SOLID_KINDS for g in groups) and \
        is_closed_manifold(poly.faces, len(poly.vertices))


def _area(vertices: np.ndarray, faces: np.ndarray) -> float:
    p = vertices[faces]
    return float(np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()) / 2.0


def _rim(vertices: np.ndarray, faces: np.ndarray) -> float:
    edges = np.sort(np.asarray(faces, dtype=np.int64)[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    # Each edge as one int64, in the order of its rows (sorting pairs of indices as rows is several times
    # slower), so that the lengths are summed in the same order.
    n = int(edges.max(initial=0)) + 1
    unique, count = np.unique(edges[:, 0] * n + edges[:, 1], return_counts=True)
    rim = unique[count == 1]
    return float(np.linalg.norm(vertices[rim // n] - vertices[rim % n], axis=1).sum())


#: Relative volume (closed sources) or area (open ones) a lossless decoding must keep.
STRUCTURE_TOLERANCE = 1e-6

#: Tolerances up to this (fraction of the diagonal) are lossless: volume and area within STRUCTURE_TOLERANCE.
LOSSLESS_TOLERANCE = 1e-6


def structure_kept(mesh: Mesh, obj: _Object, distance: float = 0.0) -> bool:
    """Whether a decoding keeps the source's structure: a closed source decodes closed, with its
    Euler characteristic and volume; an open one keeps its area (both within
    :data:`STRUCTURE_TOLERANCE`, relative).

    ``distance`` (model units, local coordinates): the Hausdorff distance a lossy tolerance allows.
    Two closed surfaces that far apart enclose volumes differing by at most the volume of the
    band of that half-width around the source, about ``2 * area * distance``; the volume test
    allows that much where it is more than the relative one. An open surface's rim may move that
    far: the area test allows ``rim * distance`` likewise (RoughnessTest.usdz's open spheres at
    1e-4: patches cut 1.6e-6 of their area, for an allowance of 1.5e-3).
    """
    return structure_problem(mesh, obj, distance) is None


def structure_problem(mesh: Mesh, obj: _Object, distance: float = 0.0, topology: bool = True,
                      moved: float | None = None, joins: bool = False,
                      moved_extent: tuple[float, int] | None = None) -> str | None:
    """How a decoding fails :func:`structure_kept`, in words; None if it keeps the structure. Without
    ``topology``, closedness and the Euler characteristic are taken as kept (they are by construction).

    Closedness and the Euler characteristic are those of the decoding welded by position, as most
    readers take it (trimesh on load); without ``topology``, corners that land on one point are the
    problem. ``joins``: an open source's Euler characteristic, so welded, is kept too (the shell
    scheme, where bodies that touch must still touch: a convex group's corners are its planes', not
    those of the shell or group it touched).

    ``moved`` (model units): the decoding's triangles are the source's one to one, each corner moved
    by at most that (a shell); with ``moved_extent`` (the half perimeters, summed, and the count of the
    triangles that moved so), only those did, and the rest (convex groups) has the allowance it has
    without ``moved``, the two added. An open surface's area may then change by what
    such moves make, at most ``moved`` times half of each triangle's perimeter plus ``2 moved^2``
    per triangle (|d(a x b)| over the corners), beside the rim's allowance: bun_zipper.ply at 2.5e-4
    (draco-11's error) lost 2e-4 of its area to its corners' moves and, held to the rim's 3e-6,
    was encoded with a sixteenth of the budget (93.0 kB at 6e-5 measured, against 71.1 kB at 2.4e-4).
    """
    welded, merged = _welded(mesh)
    if not topology and merged:
        # Shells decode one corner per source corner: corners that land on one point are joined by
        # every reader that welds by position (trimesh on load), whatever the indices say.
        return f"{merged} corners decode onto the position of another corner"
    if joins and not obj.closed and euler_characteristic(welded) != obj.euler:
        return (f"Euler characteristic {euler_characteristic(welded)} once welded by position, the source's "
                f"{obj.euler} (bodies that touched come apart, or corners join)")
    half_perimeters, moving = 0.0, len(obj.faces)
    if moved is not None and moved_extent is not None:
        half_perimeters, moving = moved_extent
    elif moved is not None:
        p = obj.vertices[obj.faces]
        half_perimeters = float(np.linalg.norm(p - p[:, [1, 2, 0]], axis=2).sum()) / 2.0
    combine = (lambda a, b: a + b) if moved_extent is not None else max
    if obj.closed:
        if topology and not is_closed_manifold(welded, int(welded.max(initial=-1)) + 1):
            sides = np.sort(np.column_stack([welded.reshape(-1), welded[:, [1, 2, 0]].reshape(-1)]), axis=1)
            _, count = np.unique(sides, axis=0, return_counts=True)
            return (f"a closed source decodes open once welded by position ({int((count != 2).sum())} edges not "
                    f"on exactly two triangles)")
        if topology and euler_characteristic(welded) != obj.euler:
            return f"Euler characteristic {euler_characteristic(welded)} once welded by position, the source's {obj.euler}"
        allowed = max(STRUCTURE_TOLERANCE * abs(obj.volume), 2.0 * obj.area * distance)
        if moved is not None:
            # Each triangle sweeps at most its area times the move, plus the move squared times its
            # half perimeter and the move cubed, when its corners move by at most ``moved``.
            allowed = combine(allowed, 2.0 * (obj.area * moved + half_perimeters * moved * moved
                                              + moving * moved ** 3))
        off = abs(signed_volume(mesh.vertices, mesh.faces) - obj.volume)
        return None if off <= allowed else f"volume off by {off / abs(obj.volume):.2g} (relative)"
    off = abs(_area(mesh.vertices, mesh.faces) - obj.area)
    allowed = max(STRUCTURE_TOLERANCE * obj.area, obj.rim * distance)
    if moved is not None and moved_extent is not None:
        # The convex bodies beside the shells, each closed, moved by at most ``distance``: a convex
        # body's area grows under an offset d by d times its edges' lengths times their exterior
        # angles (each under pi) plus 4 pi d^2 (Steiner), and its edges' lengths are its triangles'
        # half perimeters (car.glb: ten boxes beside a shell in an object without a rim, held to an
        # allowance of 0 and refused at every budget).
        p = obj.vertices[obj.faces]
        convex = max(float(np.linalg.norm(p - p[:, [1, 2, 0]], axis=2).sum()) / 2.0 - half_perimeters, 0.0)
        bodies = sum(g.kind == GroupKind.CONVEX for g in obj.groups)
        allowed += math.pi * distance * convex + 4.0 * math.pi * bodies * distance * distance
    if moved is not None:
        allowed = combine(allowed, moved * half_perimeters + 2.0 * moving * moved * moved)
    return None if off <= allowed else f"area off by {off / obj.area:.2g} (relative)"


def _welded(mesh: Mesh) -> tuple[np.ndarray, int]:
    """``mesh``'s faces over its used vertices welded by position (numbered 0..), and how many used
    vertices that merged into another."""
    faces = np.asarray(mesh.faces, dtype=np.int64)
    used = np.unique(faces)
    # Positions numbered in the order np.unique(axis=0) gives them, by a sort of three keys (sorting
    # the rows as records is several times slower).
    points = np.asarray(mesh.vertices)[used]
    order = np.lexsort(points.T[::-1])
    ranked = points[order]
    new = np.r_[True, (ranked[1:] != ranked[:-1]).any(axis=1)]
    index = np.empty(len(points), dtype=np.int64)
    index[order] = np.cumsum(new) - 1
    lookup = np.zeros(len(mesh.vertices), dtype=np.int64)
    lookup[used] = index
    return lookup[faces], len(used) - int(new.sum())


def _bodies(poly: Polygons) -> np.ndarray:
    """Body label per face: edge-connected components."""
    edges = edge_adjacency(poly.faces, len(poly.vertices))
    m = len(poly.faces)
    graph = coo_matrix((np.ones(len(edges.a), dtype=np.int8), (edges.a // 3, edges.b // 3)), shape=(m, m))
    return connected_components(graph, directed=False)[1]


def _one_shell(groups: list[GroupSpec]) -> list[GroupSpec]:
    """``groups`` with their shells joined into one, last: bodies that touch at a corner share it."""
    shells = [g for g in groups if g.kind == GroupKind.SHELL]
    if not shells:
        return groups
    refs = np.unique(np.concatenate([g.refs for g in shells]))
    joined = GroupSpec(GroupKind.SHELL, refs, np.zeros(len(refs), dtype=bool),
                       faces=np.concatenate([g.faces for g in shells]))
    return [g for g in groups if g.kind != GroupKind.SHELL] + [joined]


def _encode_body(body: Body, index: int,
                 strategies: Sequence[tuple[str, Callable[[Body], list[GroupSpec] | None]]] = BODY_STRATEGIES
                 ) -> list[GroupSpec]:
    if strategies is BODY_STRATEGIES and not (body.face_plane >= 0).any():
        raise GeometryError(f"body {index}: every plane was dropped (delta too large)")
    for _, strategy in strategies:
        groups = strategy(body)
        if groups is not None:
            return groups
    raise GeometryError(f"body {index} ({len(body.faces)} triangles): no strategy encodes it")


def _fit_error(relative: float, tolerance: float) -> GeometryError:
    return GeometryError(f"the fitted polygon planes are {relative:.3g} of the diagonal from the source vertices, "
                         f"above the tolerance {tolerance:g}", code="TOLERANCE_NOT_MET")


def _diagonal(points: np.ndarray) -> float:
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(points) else 0.0


def _world_transforms(nodes: Sequence[Node]) -> list[np.ndarray]:
    worlds: list[np.ndarray] = []
    for i, n in enumerate(nodes):
        local = np.eye(4) if n.transform is None else np.asarray(n.transform, dtype=np.float64)
        if n.parent is not None and not 0 <= n.parent < i:
            raise GeometryError(f"node {i} ({n.name!r}): parent {n.parent} does not precede it")
        worlds.append(local if n.parent is None else worlds[n.parent] @ local)
    return worlds
