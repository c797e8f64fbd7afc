"""Decoding part groups: one decoder per kind (:data:`DECODERS`), the plane error a coding allows
(:class:`PlaneError`), and :func:`decode_group` / :func:`decode_groups`, which turn the triplets
of a group's references into triangles.

Each decoder adapts a kind's geometry (``planefmt.groups``) to :class:`DecodedGroup`: the
triangles and which of the group's planes each vertex lies on, which the encoder's error
prediction and the validator's redundant-plane findings use.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.spatial import QhullError

from ..container import quantize
from ..errors import GeometryError, LimitError
from ..geometry.halfspace import decode_convex, intersect
from ..geometry.planes import from_triplets
from ..groups.cells import decode_cells_group
from ..groups.patches import decode_patch_groups, first_references, repeat_faces
from ..groups.sealed import decode_sealed
from ..groups.shells import Shell, decode_shell
from ..groups.solids import decode_bsp_group
from ..model import SHELL_KINDS, Coding, GroupKind, Header, Mesh, Quantization


class GroupLike(Protocol):
    """What decoding needs of a part group: a ``PartGroup`` from the reader or a :class:`GroupSpec`."""

    kind: int
    refs: np.ndarray
    bounding: np.ndarray
    cells: tuple[np.ndarray, ...] | None
    tree: np.ndarray | None
    vertex_planes: np.ndarray | None
    facets: np.ndarray | None
    shell: Shell | None


@dataclass(frozen=True)
class DecodedGroup:
    """A decoded part group: triangles, and which local references each vertex lies on."""

    vertices: np.ndarray  # (V, 3) model units
    triangles: np.ndarray  # (T, 3) counter-clockwise from outside
    inc_vertex: np.ndarray  # (I,) vertex of each incidence
    inc_ref: np.ndarray  # (I,) local reference (index into group.refs) of each incidence
    redundant: np.ndarray  # local references that bound no face
    triangle_ref: np.ndarray  # (T,) local reference each triangle lies on


def decode_convex_group(planes: np.ndarray, group: GroupLike, label: object,
                        error: PlaneError) -> DecodedGroup:
    """A ``CONVEX`` group: the intersection of all its inner half-spaces (spec §9.5)."""
    poly = decode_convex(planes, group=label, plane_error=error.of(planes), merge_limit=error.merge_limit)
    inc_vertex, inc_ref = poly.incidences
    return DecodedGroup(poly.vertices, poly.triangles, inc_vertex, inc_ref, poly.redundant, poly.triangle_plane)


def decode_bsp(planes: np.ndarray, group: GroupLike, label: object, error: PlaneError) -> DecodedGroup:
    """A ``BSP`` group: the closed surface of its IN leaves, welded without T-junctions (spec §9.7)."""
    if group.tree is None:
        raise GeometryError(f"part group {label}: a BSP group without a tree", code="BAD_GROUP_STRUCTURE")
    omega, h = from_triplets(planes)
    v, t, inc_v, inc_r, t_ref = decode_bsp_group(omega, h, np.asarray(group.tree, dtype=np.uint32),
                                                 ~np.asarray(group.bounding, dtype=bool))
    return DecodedGroup(v, t, inc_v, inc_r, np.zeros(0, dtype=np.int64), t_ref)


def decode_cells(planes: np.ndarray, group: GroupLike, label: object, error: PlaneError) -> DecodedGroup:
    """A ``CELLS`` group: the closed surface of the union of its convex cells (spec §9.6)."""
    if group.cells is None:
        raise GeometryError(f"part group {label}: a cells group without cells", code="BAD_GROUP_STRUCTURE")
    omega, h = from_triplets(planes)
    v, t, inc_v, inc_r, t_ref = decode_cells_group(omega, h, group.cells, ~np.asarray(group.bounding, dtype=bool),
                                                   label, error.of(planes), error.merge_limit)
    return DecodedGroup(v, t, inc_v, inc_r, np.zeros(0, dtype=np.int64), t_ref)


def decode_sealed_group(planes: np.ndarray, group: GroupLike, label: object, error: PlaneError) -> DecodedGroup:
    """A ``SEALED`` group: its triangles, each corner where its three planes meet (spec §9.9)."""
    if group.vertex_planes is None or group.facets is None:
        raise GeometryError(f"part group {label}: sealed groups are kind 5 only from version 3.1 on",
                            code="UNKNOWN_GROUP_KIND")
    omega, h = from_triplets(planes)
    vertex_planes = np.asarray(group.vertex_planes, dtype=np.int64)
    facets = np.asarray(group.facets, dtype=np.int64)
    try:
        v, t = decode_sealed(omega, h, vertex_planes, facets)
    except GeometryError as exc:
        raise GeometryError(f"part group {label}: {exc.reason}", code=exc.code) from None
    return DecodedGroup(v, t, np.repeat(np.arange(len(v)), 3), vertex_planes.reshape(-1),
                        np.zeros(0, dtype=np.int64), facets[:, 0])


def decode_patch(planes: np.ndarray, group: GroupLike, label: object, error: PlaneError,
                 max_triangles: float = math.inf) -> DecodedGroup:
    """A pseudo-convex or pseudo-concave patch: the polytope's faces on face planes, once per face
    reference (spec §9.8); ``LimitError`` before making more than ``max_triangles``.

    Small patches are intersected in numpy (:mod:`planefmt.geometry.polytopes`); where that finds no
    polytope, Qhull (:func:`planefmt.geometry.halfspace.intersect`) decides: near-duplicate bounding
    planes (TestScene.gltf's floor: two copies of one normal, h 3e-7 apart) defeat the former's
    vertex tests but not the latter's hull. Either intersects each plane of the table once, however
    often the group names it: Qhull keeps one of planes that are one (spec §9.4).
    """
    omega, h = from_triplets(planes)
    face = ~np.asarray(group.bounding, dtype=bool)
    concave = int(group.kind) == GroupKind.PSEUDO_CONCAVE
    refs = np.asarray(group.refs, dtype=np.int64)
    try:
        (v, t, inc_v, inc_r, t_ref), = decode_patch_groups(omega, h, [len(h)], face, np.array([concave]), refs,
                                                           max_triangles)
    except GeometryError:
        first, twin = first_references(refs, omega, h, np.zeros(len(refs), dtype=np.int64))
        distinct = np.flatnonzero((first == np.arange(len(refs))) & ~twin)
        poly = intersect(omega[distinct], h[distinct], group=label)
        try:
            emit, t_ref = repeat_faces(distinct[poly.triangle_plane], first, face & ~twin, max_triangles)
        except LimitError as exc:
            raise LimitError(f"part group {label}: {exc.reason}") from None
        t = poly.triangles[emit]
        if concave:
            t = t[:, ::-1]
        used, local = np.unique(t, return_inverse=True)
        inc_v, inc_r = poly.incidences
        on = np.isin(inc_v, used)
        v, t = poly.vertices[used], local.reshape(-1, 3)
        inc_v, inc_r = np.searchsorted(used, inc_v[on]), distinct[inc_r[on]]
    except LimitError as exc:
        raise LimitError(f"part group {label}: {exc.reason}") from None
    if len(t) == 0:
        raise GeometryError(f"part group {label}: no face of the patch lies on a face plane",
                            code="EMPTY_POLYTOPE")
    return DecodedGroup(v, t, inc_v, inc_r, np.zeros(0, dtype=np.int64), t_ref)


def decode_shell_group(planes: np.ndarray, group: GroupLike, label: object, error: PlaneError) -> DecodedGroup:
    """A shell group, kind 6, 7 or 8: its triangles over its corners, named by three planes or
    explicit (spec §9.10 to §9.12). Linear time: one batched 3×3 solve."""
    shell = group.shell
    if shell is None:
        raise GeometryError(f"part group {label}: shell groups are kind 6 only from version 3.2 on, kind 7 "
                            f"from 3.3, kind 8 from 3.4", code="UNKNOWN_GROUP_KIND")
    omega, h = from_triplets(planes)
    try:
        v, t = decode_shell(omega, h, shell)
    except GeometryError as exc:
        raise GeometryError(f"part group {label}: {exc.reason}", code=exc.code) from None
    face = np.asarray(shell.facets, dtype=np.int64)[:, 0]
    named = np.flatnonzero(~np.asarray(shell.explicit, dtype=bool))
    # The references no triangle lies on, ascending (np.setdiff1d's answer, without its sort).
    unused = np.ones(len(planes), dtype=bool)
    unused[face[(face >= 0) & (face < len(planes))]] = False
    return DecodedGroup(v, t, np.repeat(named, 3), np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1),
                        np.flatnonzero(unused), face)


#: Decoder of each part-group kind: ``decode(planes, group, label, error)`` with ``planes`` the
#: (m, 3) triplets of ``group.refs`` and ``error`` the coding's :class:`PlaneError`.
_PATCH_KINDS = (GroupKind.PSEUDO_CONVEX, GroupKind.PSEUDO_CONCAVE)

DECODERS: dict[int, Callable[[np.ndarray, GroupLike, object, "PlaneError"], DecodedGroup]] = {
    GroupKind.CONVEX: decode_convex_group,
    GroupKind.CELLS: decode_cells,
    GroupKind.BSP: decode_bsp,
    GroupKind.PSEUDO_CONVEX: decode_patch,
    GroupKind.PSEUDO_CONCAVE: decode_patch,
    GroupKind.SEALED: decode_sealed_group,
    GroupKind.SHELL: decode_shell_group,
    GroupKind.SHELL_TREE: decode_shell_group,
    GroupKind.SHELL_TREE_PARALLELOGRAM: decode_shell_group,
    GroupKind.SHELL_WALK: decode_shell_group,
    GroupKind.SHELL_WALK_MULTI: decode_shell_group,
    GroupKind.SHELL_WALK_REFLECT: decode_shell_group,
    GroupKind.SHELL_WALK_LATER: decode_shell_group,
}


@dataclass(frozen=True)
class PlaneError:
    """How far a coding may move a plane: ``angle`` radians for the normal, ``h`` model units plus
    ``h_relative`` times the largest ``|h|`` of the part group for the distance.

    ``merge_limit`` (model units) caps how far decoders may move vertices when they merge the
    clusters such errors make: half the file's tolerance, so merging stays within what the
    encoder verifies.
    """

    angle: float = 0.0
    h: float = 0.0
    h_relative: float = 0.0
    merge_limit: float = math.inf

    def of(self, planes: np.ndarray) -> tuple[float, float]:
        """``(radians, model units)`` for the triplets ``planes`` of one part group."""
        h_max = float(np.abs(planes[:, 2]).max(initial=0.0))
        return self.angle, self.h + self.h_relative * h_max


EXACT = PlaneError()


def plane_error(coding: Coding, quantization: Quantization | None, tolerance: float = math.nan,
                diagonal: float = math.nan) -> PlaneError:
    """Half a step for quantized planes, half a float32 ulp for float32, nothing for float64.

    Decoders merge the vertex clusters this much error makes of vertices
    where several planes meet, moving vertices by at most half of
    ``tolerance`` (fraction) x ``diagonal`` (model units) where both are
    known; the encoder verifies that very decoding.
    """
    limit = 0.5 * tolerance * diagonal
    limit = limit if math.isfinite(limit) else math.inf
    if coding.quantized and quantization is not None:
        nu, phi, h = quantize.half_steps(quantization)
        return PlaneError(angle=float(max(nu, phi)), h=float(h), merge_limit=limit)
    if coding == Coding.FLOAT32:
        return PlaneError(angle=float(np.spacing(np.float32(2 * math.pi))) / 2, h_relative=2.0 ** -24,
                          merge_limit=limit)
    return EXACT


def header_plane_error(header: Header) -> PlaneError:
    """The :func:`plane_error` of a file's coding, tolerance and bbox."""
    return plane_error(header.coding, header.quantization, header.tolerance, header.diagonal)


def decode_group(planes: np.ndarray, group: GroupLike, label: object = None,
                 error: PlaneError = EXACT, max_triangles: float = math.inf) -> DecodedGroup:
    """Decode one part group from the triplets ``planes`` (m, 3) of its references.

    ``error`` is the coding's :func:`plane_error` (exact planes by default). ``max_triangles`` bounds
    the output of the one kind whose output may grow faster than its body, patches that repeat a face
    reference (``LimitError`` before it is made); the caller charges every kind's output (spec §12.4).
    """
    decoder = DECODERS.get(int(group.kind))
    if decoder is None:
        try:
            name = GroupKind(group.kind).name
        except ValueError:
            name = f"kind {group.kind}"
        raise GeometryError(f"part group {label}: decoding {name} groups is not implemented yet",
                            code="UNKNOWN_GROUP_KIND")
    planes = np.asarray(planes, dtype=np.float64).reshape(-1, 3)
    try:
        if int(group.kind) in _PATCH_KINDS:
            return decode_patch(planes, group, label, error, max_triangles)
        return decoder(planes, group, label, error)
    except (ArithmeticError, IndexError, ValueError, np.linalg.LinAlgError, QhullError) as exc:
        # Planes from a file can be anything; a numeric failure deep in a decoder is still bad input.
        raise GeometryError(f"part group {label}: its planes do not decode ({type(exc).__name__}: {exc})",
                            code="DEGENERATE_GEOMETRY") from exc


def decode_groups(items: Sequence[tuple[np.ndarray, GroupLike, object]],
                  error: PlaneError = EXACT, max_triangles: float = math.inf) -> list[DecodedGroup]:
    """:func:`decode_group` of each ``(planes, group, label)``, the patch groups in one batch, their
    triangles together at most ``max_triangles``.

    A mesh stored as patches has tens of thousands of small groups (bun_zipper.ply: 28k); one
    :func:`planefmt.groups.patches.decode_patch_groups` call intersects them together, and gives each the
    result it gets alone. If the batch finds a bad group, every patch is decoded on its own, which
    names the group and tries Qhull where the batch gives up.
    """
    out: list[DecodedGroup | None] = [None] * len(items)
    patches = [i for i, (_, g, _) in enumerate(items)
               if int(g.kind) in _PATCH_KINDS]
    if len(patches) > 1:
        try:
            planes = np.concatenate([np.asarray(items[i][0], dtype=np.float64).reshape(-1, 3) for i in patches])
            omega, h = from_triplets(planes)
            face = np.concatenate([~np.asarray(items[i][1].bounding, dtype=bool) for i in patches])
            concave = np.array([int(items[i][1].kind) == GroupKind.PSEUDO_CONCAVE for i in patches])
            refs = np.concatenate([np.asarray(items[i][1].refs, dtype=np.int64) for i in patches])
            decoded = decode_patch_groups(omega, h, [len(np.asarray(items[i][1].refs)) for i in patches],
                                          face, concave, refs, max_triangles)
            for i, (v, t, inc_v, inc_r, t_ref) in zip(patches, decoded):
                if len(t):
                    out[i] = DecodedGroup(v, t, inc_v, inc_r, np.zeros(0, dtype=np.int64), t_ref)
        except (GeometryError, LimitError, ArithmeticError, IndexError, ValueError, np.linalg.LinAlgError,
                QhullError):
            out = [None] * len(items)
    made = sum(len(d.triangles) for d in out if d is not None)
    for i, (planes, g, label) in enumerate(items):
        if out[i] is None:
            out[i] = decode_group(planes, g, label, error, max_triangles - made)
            made += len(out[i].triangles)
    return out


def _concatenate(parts: Sequence[DecodedGroup]) -> Mesh:
    if not parts:
        return Mesh(np.empty((0, 3)), np.empty((0, 3), dtype=np.int64))
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
    return Mesh(np.concatenate([p.vertices for p in parts]),
                np.concatenate([p.triangles + o for p, o in zip(parts, offsets)]).astype(np.int64))
