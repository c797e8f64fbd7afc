"""The geometry codec: triangle meshes to part groups of planes and back, with verified error.

Conventions (spec §2.3): planes ``(omega, h)`` with outward unit normals,
the solid where ``omega . x <= h``; triplets ``(nu, phi, h)`` in radians,
radians, model units; triangles counter-clockwise seen from outside.
Tolerances and error bounds are **fractions of the bounding-box diagonal**;
distances are otherwise in model units.

Encoding a mesh (:func:`encode_mesh`):

1. Vertices are welded by position and adjacent coplanar triangles merged
   into polygons, one plane each (:mod:`planefmt.polygonize`, coplanarity
   tolerance ``min(5e-7, tolerance / 2)`` of the diagonal).
2. Lossy options of the paper (§5 there): ``tau`` merges neighbouring planes
   whose normals differ by less than ``tau`` radians, ``delta`` drops planes
   whose faces cover less than ``delta`` of the total area.
3. The mesh is split into bodies (edge-connected pieces). Each body goes to
   the first strategy of :data:`BODY_STRATEGIES` that takes it; a strategy
   returns the body's part groups: a closed, outward, convex body (within
   the tolerance) one ``CONVEX`` group; any other body what
   :func:`planefmt.bodies.encode_body` makes of it (a ``BSP`` group for a
   closed solid, a ``SEALED`` group for a closed body no tree decodes with
   its topology, else pseudo-convex / pseudo-concave patches).
4. The triplet coding is chosen and **verified**: each candidate's planes go
   through :func:`quantize.roundtrip` (exactly what a reader gets back), are
   decoded, and the two-sided Hausdorff distance between decoded and source
   surface is measured (:func:`planefmt.hausdorff.hausdorff`); a candidate
   must meet the tolerance and keep the source's structure
   (:func:`structure_kept`). A first-order prediction of the vertex
   displacement (planes re-intersected at each decoded vertex) skips widths
   that cannot pass without decoding them: where faces meet at a small angle
   the vertex error grows like ``1 / sin angle``, so the angles, not ``h``,
   set the widths. Among the remaining quantized widths the narrowest that
   passes is found by bisection (coarse planes can drop a thin cell of a BSP
   solid where finer ones keep it, so a few failures at the narrow end say
   nothing of the rest); if none passes, float32, then float64. The winner's
   measured error is the header's ``error_bound``.
5. At a lossy tolerance, where a body kept a hull-first BSP tree, steps 3–4
   run again with the flat splitter strategies and the smaller file is kept
   (:func:`_encode_objects`; :func:`encode_scene` does the same per scene).

Decoding dispatches on ``group.kind`` through :data:`DECODERS`.
"""

from __future__ import annotations

import hashlib
import io
import itertools
import math
import os
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from typing import BinaryIO, Protocol

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError

from . import progress, quantize, records
from .errors import CODES, FormatError, GeometryError, PlnError, PlnWarning, SkippedGroupsWarning
from .halfspace import decode_convex, intersect, resolve_vertices
from .hausdorff import DEFAULT_MAX_PIECES, closest_distance, hausdorff
from .model import (BSP_MAX_SPLIT, UP_AXIS, Coding, Colours, GroupKind, Header, Mesh, Metadata, Node, ObjectRecord,
                    PartGroup, Quantization, Scene, Units)
from .convexbound import convex_hausdorff
from .bodies import encode_body, euler_characteristic, is_closed_manifold, signed_volume
from .cells import decode_cells_group
from .patches import PlaneTable, decode_patch_groups
from .planes import from_triplets, to_triplets, transform_points
from .polygonize import COPLANAR_TOLERANCE, Polygons, edge_adjacency, polygonize, weld
from .repair import mend_cracks
from .reader import Reader
from .solids import FLAT_STRATEGIES, STRATEGIES, Splitter, decode_bsp_group
from .salvage import salvage
from .sealed import decode_sealed
from .shells import (FREE, Shell, ShellPlan, decode_shell, encode_shell, plan_shell, reordered, reordered_tree,
                     shell_tree)
from .trianglegeom import TriangleIndex
from .validate import GROUP_CHECKS, Finding
from .writer import BLOCK_PLANES, Writer

#: Quantized widths tried for nu and phi.
MIN_BITS, MAX_BITS = 2, 32

#: Attempts at a certified Hausdorff bound with a rising target (each 1.1x the last at least).
_MEASURE_STEPS = 64

#: Refinement budget of a pass/fail verification of a quantized coding in the bisection: a
#: candidate whose bound cannot be certified within it counts as failed. Float64, the last, gets
#: ``DEFAULT_MAX_PIECES`` (plate_holes.STL: certified with 2M pieces in 24 s, not with 200k).
#: plate_holes.STL at 2e-5, 20-bit planes (true error under 2.6e-6): uncertified with 100k
#: pieces in 11.6 s, certified with 400k in 13.8 s; the bisection then stops at 21 bits, not 26.
_VERIFY_PIECES = 500_000
#: If no width passes, the narrowest one left undecided by the budget with a certified lower bound
#: at most this fraction of the target is verified again with ``_RETRY_PIECES``.
#: 1002_tray_bottom.STL at tolerance 1e-4, 22-bit angles (lower bound 7e-7): uncertified with 100k
#: pieces, certified with 2M, both in about 16 s.
_LIKELY_PASS = 0.25
_RETRY_PIECES = DEFAULT_MAX_PIECES
#: Budget of a second verification of float planes, the last coding, when the first ran out of
#: pieces with the lower bound at most ``_LIKELY_PASS`` of the target. ADIS16480.STL at 1e-6 (one
#: BSP group; the source's sliver triangles run along decoded outlines 1e-9 inside their own, and
#: are refined along them until the Lipschitz bound holds): lower bound 5.6e-8, certified with
#: 2.9 million pieces in about 200 s, not with 2 million.
_FINAL_PIECES = 8_000_000

#: Closing the cracks of open meshes (:func:`planefmt.repair.mend_cracks`), as fractions of the tolerance: vertices
#: closer than ``_MERGE`` of it (capped at the lossless tolerance) are one point written with two
#: roundings (angle_block.STL: 46 pairs 6e-17 apart, so the solid looked open and took 24x the
#: bytes as patches); T-vertices within ``_SPLIT`` of it of an edge split that edge.
_MERGE = 1e-3
_SPLIT = 0.1

#: A predicted vertex step larger than this many times its planes' offset from it is not trusted
#: (:meth:`_Incidences.moved`).
_STEP_LIMIT = 1e3

#: An incidence whose vertex is farther than this fraction of the largest |h| from its plane (in
#: the exact decoding) is not used to predict where the vertex goes.
_ON_PLANE = 1e-7

#: Part groups a reader holds before decoding them together (:func:`decode_groups`).
_DECODE_BATCH = 4096

#: Rounds of mutual-best-pair merging for ``tau`` (each merges at least the closest pair).
_TAU_ROUNDS = 64


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
    splitters: tuple[Splitter, ...] = STRATEGIES  # BSP splitter strategies (planefmt.solids)
    every_plane: bool = False  # shells keep the plane of a face of one triangle too (colours ride on planes)


@dataclass(frozen=True)
class DecodedGroup:
    """A decoded part group: triangles, and which local references each vertex lies on."""

    vertices: np.ndarray  # (V, 3) model units
    triangles: np.ndarray  # (T, 3) counter-clockwise from outside
    inc_vertex: np.ndarray  # (I,) vertex of each incidence
    inc_ref: np.ndarray  # (I,) local reference (index into group.refs) of each incidence
    redundant: np.ndarray  # local references that bound no face
    triangle_ref: np.ndarray  # (T,) local reference each triangle lies on


@dataclass(frozen=True)
class Encoded:
    """A mesh encoded as planes.

    ``triplets`` (n, 3) are the planes before coding (radians, model units);
    ``groups`` reference them. ``coding`` and ``quantization`` are the chosen
    coding; ``bbox`` (2, 3) the decoded geometry's box; ``tolerance`` the
    requested and ``error_bound`` the verified two-sided Hausdorff distance,
    both fractions of the bbox diagonal. ``lossy`` follows spec §5: planes
    dropped or merged, or the error above the tolerance. ``mesh`` is what a
    reader decodes; ``fit_error`` the largest vertex distance to a fitted
    polygon plane, as a fraction of the diagonal.
    """

    triplets: np.ndarray
    groups: tuple[GroupSpec, ...]
    coding: Coding
    quantization: Quantization | None
    bbox: np.ndarray
    tolerance: float
    error_bound: float
    lossy: bool
    mesh: Mesh
    fit_error: float

    @property
    def payload_bytes(self) -> int:
        """Bytes of the uncompressed triplet data (spec §7)."""
        return quantize.payload_size(len(self.triplets), self.coding, self.quantization)

    def header(self, units: Units = Units.UNSPECIFIED) -> Header:
        """The PHDR record for a file holding this mesh as its only object."""
        return Header(lossy=self.lossy, coding=self.coding, quantization=self.quantization, units=units,
                      bbox=self.bbox, tolerance=self.tolerance, error_bound=self.error_bound)


# -- strategies: bodies to part groups ---------------------------------------------------------

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
    """Any other body through :func:`planefmt.bodies.encode_body`: a closed outward body as a BSP
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
    """A convex body of at most :data:`CONVEX_MAX_PLANES` planes as one ``CONVEX`` group (the paper's
    pure planes), any other as a shell."""
    planes = np.unique(body.face_plane[body.face_plane >= 0])
    groups = encode_convex_body(body) if len(planes) <= CONVEX_MAX_PLANES else None
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


# -- decoders: part groups to triangles -------------------------------------------------------

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


def decode_patch(planes: np.ndarray, group: GroupLike, label: object, error: PlaneError) -> DecodedGroup:
    """A pseudo-convex or pseudo-concave patch: the polytope's faces on face planes (spec §9.8).

    Small patches are intersected in numpy (:mod:`planefmt.polytopes`); where that finds no
    polytope, Qhull (:func:`planefmt.halfspace.intersect`) decides: near-duplicate bounding
    planes (TestScene.gltf's floor: two copies of one normal, h 3e-7 apart) defeat the former's
    vertex tests but not the latter's hull.
    """
    omega, h = from_triplets(planes)
    face = ~np.asarray(group.bounding, dtype=bool)
    concave = int(group.kind) == GroupKind.PSEUDO_CONCAVE
    try:
        (v, t, inc_v, inc_r, t_ref), = decode_patch_groups(omega, h, [len(h)], face, np.array([concave]))
    except GeometryError:
        poly = intersect(omega, h, group=label)
        on_face = face[poly.triangle_plane]
        t, t_ref = poly.triangles[on_face], poly.triangle_plane[on_face]
        if concave:
            t = t[:, ::-1]
        used, local = np.unique(t, return_inverse=True)
        inc_v, inc_r = poly.incidences
        on = np.isin(inc_v, used)
        v, t = poly.vertices[used], local.reshape(-1, 3)
        inc_v, inc_r = np.searchsorted(used, inc_v[on]), inc_r[on]
    if len(t) == 0:
        raise GeometryError(f"part group {label}: no face of the patch lies on a face plane",
                            code="EMPTY_POLYTOPE")
    return DecodedGroup(v, t, inc_v, inc_r, np.zeros(0, dtype=np.int64), t_ref)


def decode_shell_group(planes: np.ndarray, group: GroupLike, label: object, error: PlaneError) -> DecodedGroup:
    """A ``SHELL`` or ``SHELL_TREE`` group: its triangles over its corners, named by three planes or
    explicit (spec §9.10, §9.11). Linear time: one batched 3×3 solve."""
    shell = group.shell
    if shell is None:
        raise GeometryError(f"part group {label}: shell groups are kind 6 only from version 3.2 on, kind 7 "
                            f"from 3.3", code="UNKNOWN_GROUP_KIND")
    omega, h = from_triplets(planes)
    try:
        v, t = decode_shell(omega, h, shell)
    except GeometryError as exc:
        raise GeometryError(f"part group {label}: {exc.reason}", code=exc.code) from None
    face = np.asarray(shell.facets, dtype=np.int64)[:, 0]
    named = np.flatnonzero(~np.asarray(shell.explicit, dtype=bool))
    return DecodedGroup(v, t, np.repeat(named, 3), np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1),
                        np.setdiff1d(np.arange(len(planes)), face), face)


#: Decoder of each part-group kind: ``decode(planes, group, label, error)`` with ``planes`` the
#: (m, 3) triplets of ``group.refs`` and ``error`` the coding's :class:`PlaneError`.
DECODERS: dict[int, Callable[[np.ndarray, GroupLike, object, "PlaneError"], DecodedGroup]] = {
    GroupKind.CONVEX: decode_convex_group,
    GroupKind.CELLS: decode_cells,
    GroupKind.BSP: decode_bsp,
    GroupKind.PSEUDO_CONVEX: decode_patch,
    GroupKind.PSEUDO_CONCAVE: decode_patch,
    GroupKind.SEALED: decode_sealed_group,
    GroupKind.SHELL: decode_shell_group,
    GroupKind.SHELL_TREE: decode_shell_group,
}
#: The kinds of shell groups, which the encoder chooses between by size once their corners are known.
SHELL_KINDS = (GroupKind.SHELL, GroupKind.SHELL_TREE)
#: The shell layouts the encoder chooses among (``bench/shell_bits.py`` measures version 3.2's alone
#: by setting it to ``(GroupKind.SHELL,)``).
SHELL_LAYOUTS = SHELL_KINDS


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
                 error: PlaneError = EXACT) -> DecodedGroup:
    """Decode one part group from the triplets ``planes`` (m, 3) of its references.

    ``error`` is the coding's :func:`plane_error` (exact planes by default).
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
        return decoder(planes, group, label, error)
    except (ArithmeticError, IndexError, ValueError, np.linalg.LinAlgError, QhullError) as exc:
        # Planes from a file can be anything; a numeric failure deep in a decoder is still bad input.
        raise GeometryError(f"part group {label}: its planes do not decode ({type(exc).__name__}: {exc})",
                            code="DEGENERATE_GEOMETRY") from exc


def decode_groups(items: Sequence[tuple[np.ndarray, GroupLike, object]],
                  error: PlaneError = EXACT) -> list[DecodedGroup]:
    """:func:`decode_group` of each ``(planes, group, label)``, the patch groups in one batch.

    A mesh stored as patches has tens of thousands of small groups (bun_zipper.ply: 28k); one
    :func:`planefmt.patches.decode_patch_groups` call intersects them together, and gives each the
    result it gets alone. If the batch finds a bad group, every patch is decoded on its own, which
    names the group and tries Qhull where the batch gives up.
    """
    out: list[DecodedGroup | None] = [None] * len(items)
    patches = [i for i, (_, g, _) in enumerate(items)
               if int(g.kind) in (GroupKind.PSEUDO_CONVEX, GroupKind.PSEUDO_CONCAVE)]
    if len(patches) > 1:
        try:
            planes = np.concatenate([np.asarray(items[i][0], dtype=np.float64).reshape(-1, 3) for i in patches])
            omega, h = from_triplets(planes)
            face = np.concatenate([~np.asarray(items[i][1].bounding, dtype=bool) for i in patches])
            concave = np.array([int(items[i][1].kind) == GroupKind.PSEUDO_CONCAVE for i in patches])
            decoded = decode_patch_groups(omega, h, [len(np.asarray(items[i][1].refs)) for i in patches],
                                          face, concave)
            for i, (v, t, inc_v, inc_r, t_ref) in zip(patches, decoded):
                if len(t):
                    out[i] = DecodedGroup(v, t, inc_v, inc_r, np.zeros(0, dtype=np.int64), t_ref)
        except (GeometryError, ArithmeticError, IndexError, ValueError, np.linalg.LinAlgError, QhullError):
            out = [None] * len(items)
    return [d if d is not None else decode_group(planes, g, label, error)
            for d, (planes, g, label) in zip(out, items)]


def decode_mesh(source: Encoded | np.ndarray | str | os.PathLike | BinaryIO,
                groups: Iterable[GroupLike] | None = None, *, header: Header | None = None) -> Mesh:
    """Triangles: of a .pln file (``decode_mesh("model.pln")``, a path or binary stream: every object in
    world coordinates, as one mesh), or of part groups (``decode_mesh(triplets, groups, header=...)`` or
    ``decode_mesh(encoded)``).

    ``triplets`` (n, 3) is the plane table the groups' ``refs`` index, as a
    reader returns it; ``header`` (its coding) sets the plane error the
    decoder allows for (exact planes without it). For an :class:`Encoded`,
    its planes go through the coding first, so the result is what a reader
    of its file decodes. Raises ``GeometryError`` (e.g. ``EMPTY_POLYTOPE``,
    ``UNBOUNDED_POLYTOPE``) naming the group, and for a file whatever
    :func:`decode_scene` raises.
    """
    if isinstance(source, (str, os.PathLike)) or hasattr(source, "read"):
        return _world_mesh(decode_scene(source))
    if isinstance(source, Encoded):
        table = quantize.roundtrip(source.triplets, source.coding, source.quantization)
        groups = source.groups
        error = plane_error(source.coding, source.quantization, source.tolerance,
                            float(np.linalg.norm(source.bbox[1] - source.bbox[0])))
    else:
        try:
            table = np.asarray(source, dtype=np.float64).reshape(-1, 3)
        except (TypeError, ValueError) as exc:
            raise PlnError(f"decode_mesh takes a .pln path or stream, an Encoded, or an (n, 3) plane table, "
                           f"not {type(source).__name__}") from exc
        error = EXACT if header is None else header_plane_error(header)
    return _concatenate(decode_groups([(table[np.asarray(g.refs, dtype=np.int64)], g, i)
                                       for i, g in enumerate(groups or ())], error))


def _world_mesh(scene: Scene) -> Mesh:
    """Every mesh of ``scene`` in world coordinates, as one; a mirroring transform's faces reversed so that
    they stay wound outward. Face colours where every mesh has them."""
    placed = []
    for node, world in zip(scene.nodes, _world_transforms(scene.nodes)):
        if node.mesh is not None:
            faces = node.mesh.faces[:, ::-1] if np.linalg.det(world[:3, :3]) < 0 else node.mesh.faces
            placed.append((transform_points(node.mesh.vertices, world), faces, node.mesh.face_colours))
    if not placed:
        return Mesh(np.empty((0, 3)), np.empty((0, 3), dtype=np.int64))
    offsets = np.cumsum([0] + [len(v) for v, _, _ in placed[:-1]])
    colours = None
    if all(c is not None for _, _, c in placed):
        colours = np.concatenate([c for _, _, c in placed])
    return Mesh(np.concatenate([v for v, _, _ in placed]),
                np.concatenate([f + o for (_, f, _), o in zip(placed, offsets)]).astype(np.int64), colours)


def _concatenate(parts: Sequence[DecodedGroup]) -> Mesh:
    if not parts:
        return Mesh(np.empty((0, 3)), np.empty((0, 3), dtype=np.int64))
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
    return Mesh(np.concatenate([p.vertices for p in parts]),
                np.concatenate([p.triangles + o for p, o in zip(parts, offsets)]).astype(np.int64))


# -- encoding ---------------------------------------------------------------------------------

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
    mended: float  # model units: how far closing cracks moved the source (planefmt.repair)
    closed: bool  # the source is a closed 2-manifold: its decoding must be one, of the same volume
    volume: float  # model units cubed, local coordinates
    euler: int
    area: float  # model units squared, local coordinates
    rim: float  # model units, local coordinates: length of the edges on one face only (open sources)
    plane_colours: np.ndarray | None  # (planes, 4) uint8 RGBA: a source face's colour on each plane
    name: str = ""  # the scene node's, for messages
    face_plane: np.ndarray | None = None  # (faces,) each face's plane in ``triplets``, -1 for none (shell scheme)
    face_colours: np.ndarray | None = None  # (faces, 4) uint8 RGBA of ``faces`` (shell scheme)


def encode_mesh(vertices: np.ndarray, faces: np.ndarray, *, tolerance: float = 1e-6,
                coding: Coding | None = None, bits: int | tuple[int, int, int] | None = None,
                delta: float | None = None, tau: float | None = None, watertight: bool = True,
                scheme: str = "shell") -> Encoded:
    """Encode a triangle mesh (model units, counter-clockwise from outside) as planes.

    ``tolerance``: the two-sided Hausdorff distance allowed between decoded
    and source surface, as a fraction of the bbox diagonal (default 1e-6,
    "lossless"). ``coding``/``bits`` force a coding (``bits`` one width for
    nu, phi and h, or a triple; implies quantized); a forced coding is not
    held to the tolerance: its measured error is reported. ``delta``
    (fraction of the total area) and ``tau`` (radians) simplify the planes;
    then ``tolerance`` bounds the error the *coding* adds to the simplified
    planes' own, and the total is measured and recorded.

    ``watertight=False`` lets a closed source that no coding keeps a closed
    solid (King_geom.usd) be stored as an open surface, held to
    an open one's checks (distance and area); the result is then lossy and a
    :class:`PlnWarning` says so. By default such a source fails.

    ``scheme``: ``"shell"`` (default) stores convex bodies as convex groups
    and everything else as one shell group (spec §9.10), whose error
    holds by construction; ``"paper"`` uses the paper's BSP trees, sealed
    groups and patches for non-convex bodies, verified by a certified
    Hausdorff search (slow: minutes for a few thousand CAD triangles).

    Raises ``GeometryError``: ``DEGENERATE_GEOMETRY`` for malformed input,
    ``TOLERANCE_NOT_MET`` when no coding meets the tolerance and keeps the
    source's structure.
    """
    forced = coding is not None or bits is not None

    def prepare(_: int, splitters: tuple[Splitter, ...] = STRATEGIES) -> _Object:
        return _prepare(vertices, faces, np.eye(4), tolerance, delta, tau, diagonal=None if forced else 0.0,
                        splitters=splitters, scheme=scheme)

    def size(objects: list[_Object], choice: _Choice) -> int:
        buf = io.BytesIO()
        _write(Scene((Node("", mesh=Mesh(vertices, faces)),)), buf, [0], objects, choice, tolerance,
               scheme == "shell", False)
        return len(buf.getvalue())

    (obj,), choice = _encode_objects(prepare, 1, tolerance, coding, bits, watertight, size, scheme)
    return Encoded(triplets=obj.triplets, groups=obj.groups, coding=choice.coding,
                   quantization=choice.quantization, bbox=choice.bbox, tolerance=float(tolerance),
                   error_bound=choice.error_bound, lossy=choice.lossy, mesh=choice.meshes[0],
                   fit_error=obj.fit / choice.diagonal)


def _prepare(vertices: np.ndarray, faces: np.ndarray, world: np.ndarray, tolerance: float,
             delta: float | None, tau: float | None, face_colours: np.ndarray | None = None,
             diagonal: float | None = None, splitters: tuple[Splitter, ...] = STRATEGIES,
             scheme: str = "shell") -> _Object:
    """One node's mesh polygonized and encoded body by body.

    ``diagonal``: the diagonal of the whole source in world units (0 for a
    single mesh: its own), when the polygon fit is to be held to the
    tolerance before the bodies are encoded (an unforced lossless encode);
    :func:`_choose` checks the same against a diagonal no larger, so this
    only fails sooner. ``splitters``: the BSP splitter strategies of solids.
    ``scheme``: ``shell`` (convex groups and one shell group of the other
    bodies) or ``paper`` (convex groups, trees, sealed groups and patches).
    """
    if scheme not in SCHEMES:
        raise PlnError(f"unknown scheme {scheme!r}: one of {', '.join(SCHEMES)}", code="UNSUPPORTED_CODING")
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
    closed = is_closed_manifold(faces, len(vertices))
    mended = 0.0
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
    colours = None if face_colours is None else np.asarray(face_colours, dtype=np.uint8).reshape(-1, 4)
    # A shell's free triangles take its last reference's colour: an object of several colours keeps
    # the plane of every face (each plane takes its faces' colour).
    every = colours is not None and bool((colours != colours[0]).any())
    for b, faces_b in enumerate(np.split(by_body, np.cumsum(np.bincount(body_of_face))[:-1])):
        body = Body(poly, faces_b, face_plane[faces_b], omega, h, tolerance, table, simplified, splitters, every)
        groups.extend(_encode_body(body, b, SCHEMES[scheme]))
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
        plane_colours[mapped[mapped >= 0]] = np.asarray(face_colours, dtype=np.uint8).reshape(-1, 4)[on][mapped >= 0]
    kept = np.where(face_plane >= 0, index[np.maximum(face_plane, 0)], -1)
    return _Object(vertices=poly.vertices, faces=poly.faces, triplets=to_triplets(omega[order], h[order]),
                   groups=tuple(groups), world=world, simplified=simplified, fit=poly.max_distance,
                   mended=mended, closed=closed or _mended_solid(poly, groups),
                   volume=signed_volume(poly.vertices, poly.faces), euler=euler_characteristic(poly.faces),
                   area=_area(poly.vertices, poly.faces), rim=_rim(poly.vertices, poly.faces),
                   plane_colours=plane_colours, face_plane=kept, face_colours=colours)


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
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    rim = unique[count == 1]
    return float(np.linalg.norm(vertices[rim[:, 0]] - vertices[rim[:, 1]], axis=1).sum())


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


def structure_problem(mesh: Mesh, obj: _Object, distance: float = 0.0, topology: bool = True) -> str | None:
    """How a decoding fails :func:`structure_kept`, in words; None if it keeps the structure. Without
    ``topology``, closedness and the Euler characteristic are taken as kept (they are by construction)."""
    if obj.closed:
        if topology and not is_closed_manifold(mesh.faces, len(mesh.vertices)):
            sides = np.sort(np.column_stack([mesh.faces.reshape(-1), mesh.faces[:, [1, 2, 0]].reshape(-1)]), axis=1)
            _, count = np.unique(sides, axis=0, return_counts=True)
            return f"a closed source decodes open ({int((count != 2).sum())} edges not on exactly two triangles)"
        if topology and euler_characteristic(mesh.faces) != obj.euler:
            return f"Euler characteristic {euler_characteristic(mesh.faces)}, the source's {obj.euler}"
        allowed = max(STRUCTURE_TOLERANCE * abs(obj.volume), 2.0 * obj.area * distance)
        off = abs(signed_volume(mesh.vertices, mesh.faces) - obj.volume)
        return None if off <= allowed else f"volume off by {off / abs(obj.volume):.2g} (relative)"
    off = abs(_area(mesh.vertices, mesh.faces) - obj.area)
    allowed = max(STRUCTURE_TOLERANCE * obj.area, obj.rim * distance)
    return None if off <= allowed else f"area off by {off / obj.area:.2g} (relative)"


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


def merge_planes(poly: Polygons, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The paper's lossy τ: merge neighbouring planes whose normals differ by less than ``tau`` radians.

    Merging is done in rounds of mutual best pairs (the closest neighbour of
    each cluster of planes), so that chains of small angles do not fold a
    smooth surface into one plane: two clusters merge only if every member
    normal stays within ``tau`` of the merged normal (bounded by the member
    spread plus the angle between the two clusters). A merged plane has the
    area-weighted normal and the ``h`` halfway between its extreme vertices,
    which minimises the largest vertex distance for that normal.
    Returns ``(omega, h, face_plane)`` with the merged planes appended and
    faces re-pointed; unmerged planes are unchanged.
    """
    k = len(poly.h)
    edges = edge_adjacency(poly.faces, len(poly.vertices))
    pa, pb = poly.face_plane[edges.a // 3], poly.face_plane[edges.b // 3]
    keep = (pa != pb) & (pa >= 0) & (pb >= 0)
    pairs = np.unique(np.sort(np.column_stack([pa[keep], pb[keep]]), axis=1), axis=0)
    cluster = np.arange(k)
    normal = poly.omega.copy()
    spread = np.zeros(k)
    for _ in range(_TAU_ROUNDS):
        ca, cb = cluster[pairs[:, 0]], cluster[pairs[:, 1]]
        diff = ca != cb
        ca, cb = ca[diff], cb[diff]
        theta = np.arccos(np.clip(np.einsum("ij,ij->i", normal[ca], normal[cb]), -1.0, 1.0))
        ok = theta + np.maximum(spread[ca], spread[cb]) < tau
        if not ok.any():
            break
        src = np.concatenate([ca[ok], cb[ok]])
        dst = np.concatenate([cb[ok], ca[ok]])
        ang = np.concatenate([theta[ok], theta[ok]])
        order = np.lexsort((ang, src))
        first = np.r_[True, src[order][1:] != src[order][:-1]]
        best = np.full(k, -1)
        best[src[order][first]] = dst[order][first]
        c = np.flatnonzero(best >= 0)
        mutual = c[(best[best[c]] == c) & (c < best[c])]
        root = np.arange(k)
        root[best[mutual]] = mutual
        cluster = root[cluster]
        normal, spread = _cluster_normals(poly, cluster, k)
    return _merged_planes(poly, cluster, normal)


def _cluster_normals(poly: Polygons, cluster: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    vec = np.column_stack([np.bincount(cluster, weights=poly.omega[:, i] * poly.area, minlength=k)
                           for i in range(3)])
    length = np.linalg.norm(vec, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        normal = vec / length[:, None]
    normal[~(length > 0)] = poly.omega[~(length > 0)]
    angle = np.arccos(np.clip(np.einsum("ij,ij->i", poly.omega, normal[cluster]), -1.0, 1.0))
    spread = np.zeros(k)
    np.maximum.at(spread, cluster, angle)
    return normal, spread


def _merged_planes(poly: Polygons, cluster: np.ndarray,
                   normal: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    k = len(poly.h)
    size = np.bincount(cluster, minlength=k)
    merged = size[cluster] > 1
    face_plane = poly.face_plane.copy()
    on = face_plane >= 0
    fc = np.full(len(face_plane), -1)
    fc[on] = cluster[face_plane[on]]
    sel = on & merged[np.maximum(face_plane, 0)]
    ids, new = np.unique(fc[sel], return_inverse=True)
    d = np.einsum("fj,fkj->fk", normal[fc[sel]], poly.vertices[poly.faces[sel]])
    lo = np.full(len(ids), np.inf)
    hi = np.full(len(ids), -np.inf)
    np.minimum.at(lo, new, d.min(axis=1))
    np.maximum.at(hi, new, d.max(axis=1))
    face_plane[sel] = k + new
    return (np.concatenate([poly.omega, normal[ids]]), np.concatenate([poly.h, 0.5 * (lo + hi)]),
            face_plane)


def drop_planes(poly: Polygons, face_plane: np.ndarray, delta: float) -> np.ndarray:
    """The paper's lossy δ: faces on planes covering less than ``delta`` x total area lose their plane."""
    on = face_plane >= 0
    area = np.bincount(face_plane[on], weights=_face_areas(poly)[on])
    small = area < delta * area.sum()
    out = face_plane.copy()
    out[on & small[np.maximum(face_plane, 0)]] = -1
    return out


def _face_areas(poly: Polygons) -> np.ndarray:
    p = poly.vertices[poly.faces]
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 1]), axis=1)


# -- choosing and verifying the coding --------------------------------------------------------

@dataclass(frozen=True)
class _Choice:
    coding: Coding
    quantization: Quantization | None
    meshes: list[Mesh]  # decoded, local coordinates
    bbox: np.ndarray  # world
    diagonal: float
    error_bound: float  # fraction of diagonal
    lossy: bool


def _candidates(coding: Coding | None, bits: int | tuple[int, int, int] | None, table: np.ndarray,
                radius: float) -> list[tuple[Coding, Quantization | None]]:
    """Codings to try, cheapest first; forced ones alone."""
    h_min, h_max = float(table[:, 2].min()), float(table[:, 2].max())
    if bits is not None:
        widths = (bits,) * 3 if isinstance(bits, int) else tuple(bits)
        if len(widths) != 3 or not all(isinstance(b, (int, np.integer)) for b in widths):
            raise PlnError(f"bits must be an int or three ints, not {bits!r}", code="UNSUPPORTED_CODING")
        q = Quantization(*(int(b) for b in widths), h_min, h_max)
        quantize.check_quantization(q)
        return [(Coding.QUANTIZED, q)]
    if coding is not None and not Coding(coding).quantized:
        return [(Coding(coding), None)]
    out: list[tuple[Coding, Quantization | None]] = []
    span = h_max - h_min
    for b in range(MIN_BITS, MAX_BITS + 1):
        # nu and phi get equal widths (equal steps on the equator). h's half step is kept at half
        # the displacement an angle half step causes at the far end of the model: the angles
        # cost two widths, h one, so this split minimises bits for a given error.
        target = 0.5 * Quantization(b, b, 1, 0.0, 0.0).steps()[0] * max(radius, 1e-300)
        bits_h = 1 if span <= 0 else min(MAX_BITS, max(1, math.ceil(math.log2(span / target + 1))))
        out.append((Coding.QUANTIZED, Quantization(b, b, bits_h, h_min, h_max)))
    if coding is None:
        out += [(Coding.FLOAT32, None), (Coding.FLOAT64, None)]
    return out


def _choose(objects: Sequence[_Object], tolerance: float, coding: Coding | None,
            bits: int | tuple[int, int, int] | None, watertight: bool = True) -> _Choice:
    """Pick the cheapest coding whose decoded surfaces meet the tolerance; verify it.

    Without ``watertight``, closed objects whose float64 decoding fails a
    solid's checks (closed, Euler characteristic, volume) are held to an
    open surface's checks when nothing else passes.
    """
    forced = coding is not None or bits is not None
    simplified = any(o.simplified for o in objects)
    offsets = np.cumsum([0] + [len(o.triplets) for o in objects])
    spans = list(zip(offsets[:-1], offsets[1:]))
    table = np.concatenate([o.triplets for o in objects])
    diag_src = _diagonal(np.concatenate([transform_points(o.vertices, o.world) for o in objects]))
    scale = [float(np.linalg.norm(o.world[:3, :3], 2)) for o in objects]
    radius = max(float(np.linalg.norm(o.vertices, axis=1).max()) for o in objects)

    base = [_decode_object(o.triplets, o, EXACT) for o in objects]
    base_meshes = [_concatenate(d) for d in base]
    if simplified:
        # The tolerance bounds what the coding adds to the simplified planes' own error.
        base_err = [_measure(m, o, tolerance * diag_src) for m, o in zip(base_meshes, objects)]
        extra = max(base_err)
    else:
        # Lossless: what float64 planes lose is the polygon fit; measured with the chosen coding.
        base_err = [(o.fit + o.mended) * s for o, s in zip(objects, scale)]
        extra = 0.0

    def limit(meshes: list[Mesh]) -> tuple[float, np.ndarray]:
        world = np.concatenate([transform_points(m.vertices, o.world) for m, o in zip(meshes, objects)])
        return extra + tolerance * min(diag_src, _diagonal(world)), world

    allowance, _ = limit(base_meshes)
    if not forced and max(base_err) > allowance:
        raise _fit_error(max(base_err) / diag_src, tolerance)

    # Lossless keeps the volume to STRUCTURE_TOLERANCE; a lossy tolerance lets it move with the surface.
    band = tolerance if tolerance > LOSSLESS_TOLERANCE else 0.0

    # Lower bounds (fractions of the bound) of quantized candidates whose verification ran out of pieces.
    undecided: dict[int, float] = {}
    # Why the float64 planes, the finest coding, failed: the reason given when nothing passes.
    why: list[str] = []

    def named(k: int) -> str:
        return f"object {k}" + (f" ({objects[k].name!r})" if objects[k].name else "")

    tried = [0]

    def attempt(cod: Coding, q: Quantization | None, pieces: int | None = None, key: int = -1) -> _Choice | None:
        """The choice of this coding if its decoding keeps the structure and verifies; None if not."""
        # How many codings a search verifies is not known beforehand: a count, not a fraction.
        progress.report("verifying codings", tried[0])
        tried[0] += 1
        if cod == Coding.FLOAT64:
            decoded = base
        else:
            rt = quantize.roundtrip(table, cod, q)
            try:
                error = plane_error(cod, q, tolerance, diag_src)
                decoded = [_decode_object(rt[a:b], o, error) for (a, b), o in zip(spans, objects)]
            except GeometryError:
                # Coarse planes can lose a face or the solid altogether: not this coding.
                if forced:
                    raise
                return None
        meshes = base_meshes if decoded is base else [_concatenate(d) for d in decoded]
        if not forced and not simplified:
            problems = [(k, structure_problem(m, o, band * diag_src / sc))
                        for k, (m, o, sc) in enumerate(zip(meshes, objects, scale))]
            problems = [(k, p) for k, p in problems if p is not None]
            if problems:
                if cod == Coding.FLOAT64:
                    why[:] = [f"{named(k)}: {p}" for k, p in problems[:1]]
                return None
        bound, world = limit(meshes)
        if forced:
            errors = [_measure(m, o, bound) for m, o in zip(meshes, objects)]
        else:
            # Float64 is the finest coding, with no next one to certify sooner: it gets the full budget.
            if pieces is None:
                pieces = DEFAULT_MAX_PIECES if cod == Coding.FLOAT64 else _VERIFY_PIECES
            checks = [_verify(m, o, bound, pieces, d) for m, o, d in zip(meshes, objects, decoded)]
            errors = [c[0] for c in checks]
            if max(errors) > bound:
                if all(c[1] <= bound for c in checks):
                    undecided[key] = max(c[1] for c in checks) / bound
                if cod == Coding.FLOAT64:
                    k = max(range(len(checks)), key=lambda i: checks[i][1])
                    far = checks[k][1] > bound
                    why[:] = [f"{named(k)}: " + (f"decodes {checks[k][1] / diag_src:.2g} of the diagonal from its "
                                                 f"source" if far else
                                                 f"its distance is not certified within {pieces:,} pieces")]
                return None
        diagonal = _diagonal(world)
        error_bound = max(errors) / diagonal
        return _Choice(coding=cod, quantization=q, meshes=meshes,
                       bbox=np.stack([world.min(axis=0), world.max(axis=0)]), diagonal=diagonal,
                       error_bound=error_bound, lossy=simplified or error_bound > tolerance)

    candidates = _candidates(coding, bits, table, radius)
    if forced:
        return attempt(*candidates[0])
    # Half the room for the prediction: the certified bound the verification needs comes quickly
    # only with a margin between the true error and the target.
    room = 0.5 * (allowance - extra)
    own = [0.0 if simplified else e for e in base_err]
    widths = [q for cod, q in candidates if cod == Coding.QUANTIZED]

    incidences = [_Incidences.of(d, o) for d, o in zip(base, objects)]

    def moved(q: Quantization) -> list[tuple[np.ndarray, float]]:
        rt = quantize.roundtrip(table, Coding.QUANTIZED, q)
        return [inc.moved(rt[a:b]) for inc, (a, b) in zip(incidences, spans)]

    admitted = [i for i, q in enumerate(widths)
                if max(e + s * max(_peak(np.linalg.norm(m - inc.vertices, axis=1)), floor)
                       for e, s, (m, floor), inc in zip(own, scale, moved(q), incidences)) <= room]
    # Where nearly parallel planes meet, a vertex slides far along the surface for a small turn of
    # the planes; its distance from the surface is what the error sees (plate_holes.STL at 2e-5:
    # 6.7e-4 of the diagonal moved, 2.5e-5 off the surface, 17 bits). Narrower widths than the
    # displacement admits are admitted by that distance, down to the first that fails it.
    indexes = None
    for i in range(min(admitted, default=len(widths)) - 1, -1, -1):
        indexes = indexes or [TriangleIndex(o.vertices, o.faces) for o in objects]
        if max(e + s * max(_peak(ix.query(m)[0]), floor)
               for e, s, (m, floor), ix in zip(own, scale, moved(widths[i]), indexes)) > room:
            break
        admitted.append(i)
    quantized = [widths[i] for i in sorted(set(admitted))]
    # The narrowest widths that pass, by bisection: finer planes decode closer to the source (the
    # search assumes so; whatever it picks is verified like any other).
    lo, hi, best = 0, len(quantized) - 1, None
    failed: set[Quantization] = set()
    while lo <= hi:
        mid = (lo + hi) // 2
        found = attempt(Coding.QUANTIZED, quantized[mid], key=mid)
        if found is None:
            failed.add(quantized[mid])
            lo = mid + 1
        else:
            best, hi = found, mid - 1
    if best is not None:
        # The screen's margin and the bisection are conservative: narrower widths than the best
        # found often verify as well (plate_holes.STL at 3.7e-5: 17 bits where the bisection stops at
        # 19, 3,053 -> 2,706 bytes). Each is tried in turn down to the first that fails; one the
        # bisection saw fail is not tried again.
        i = widths.index(best.quantization)
        while i > 0 and widths[i - 1] not in failed:
            found = attempt(Coding.QUANTIZED, widths[i - 1])
            if found is None:
                break
            best, i = found, i - 1
        return best
    # A width whose bound merely ran out of pieces, its lower bound far under the target, gets one
    # more try with a larger budget before the float codings (1002_tray_bottom.STL at 1e-4).
    # Not when lossless: there the float64 fallback is as small as it gets near the finest widths,
    # and the retry cost 1002_tray_bottom.STL 302 s instead of 108 s.
    likely = sorted(k for k, ratio in undecided.items() if ratio <= _LIKELY_PASS)
    if likely and tolerance > LOSSLESS_TOLERANCE:
        found = attempt(Coding.QUANTIZED, quantized[likely[0]], pieces=_RETRY_PIECES)
        if found is not None:
            return found
    for cod, q in candidates:
        if cod in (Coding.FLOAT32, Coding.FLOAT64):
            found = attempt(cod, q, key=-2 if cod == Coding.FLOAT64 else -1)
            if found is None and cod == Coding.FLOAT64 and undecided.get(-2, 1.0) <= _LIKELY_PASS:
                found = attempt(cod, q, pieces=_FINAL_PIECES)
            if found is not None:
                return found
    # Closed objects whose float64 decoding is no solid: what watertight=False would store open.
    opened = [k for k, (m, o) in enumerate(zip(base_meshes, objects))
              if o.closed and structure_problem(m, o) is not None]
    if not watertight:
        # Only when the solid cannot be had: coarser widths that open a solid that finer ones keep
        # closed would otherwise win.
        if opened:
            found = _choose([replace(o, closed=False) if k in opened else o for k, o in enumerate(objects)],
                            tolerance, coding, bits)
            for k in opened:
                warnings.warn(f"{named(k)} is closed but no coding keeps it a closed solid: stored as an open surface "
                              f"(distance and area kept, not watertight), marked lossy", PlnWarning, stacklevel=4)
            return replace(found, lossy=True)
    hint = ""
    if watertight and opened:
        hint = "; watertight=False (pln convert --allow-open) would store it as an open surface"
    raise GeometryError(f"no triplet coding meets the tolerance {tolerance:g} (two-sided Hausdorff distance; "
                        f"closed sources must also decode closed, with their volume and Euler characteristic, "
                        f"open ones with their area, within {STRUCTURE_TOLERANCE:g})"
                        + (f"; with float64 planes {why[0]}" if why else "") + hint, code="TOLERANCE_NOT_MET")


#: Plane widths (nu and phi; h follows) a shell scheme's coding is chosen among, by file size: every
#: width is correct (a corner its planes cannot name within the budget is explicit), so the choice
#: is one of bytes only.
SHELL_WIDTHS = tuple(range(8, 33, 2))
#: Times the corner budget is quartered when a decoding misses a lossless volume or area.
_SHELL_TIGHTENINGS = 6


def _shell_plans(obj: _Object) -> dict[int, ShellPlan]:
    """The :class:`ShellPlan` of each shell group of ``obj`` (by position), from its exact planes."""
    plans = {}
    for k, g in enumerate(obj.groups):
        if g.kind != GroupKind.SHELL:
            continue
        fp = obj.face_plane[g.faces]
        # References are in the object's first-use order, not sorted.
        by_value = np.argsort(g.refs)
        at = np.minimum(np.searchsorted(g.refs[by_value], fp), len(g.refs) - 1)
        local = np.where((fp >= 0) & (g.refs[by_value][at] == fp), by_value[at], FREE)
        omega, _ = from_triplets(obj.triplets[g.refs])
        plans[k] = plan_shell(obj.vertices, obj.faces[g.faces], local, omega)
    return plans


def _shells_for(obj: _Object, plans: dict[int, ShellPlan], planes: np.ndarray,
                budget: float) -> tuple[_Object, float]:
    """``obj`` with its shell groups' corners named or made explicit for the coded ``planes`` (the
    object's triplets as a reader decodes them) within ``budget`` (model units), and the largest
    displacement of a decoded corner from its source vertex (model units), measured on the decoding."""
    groups = list(obj.groups)
    moved = 0.0
    for k, plan in plans.items():
        g = groups[k]
        omega, h = from_triplets(planes[g.refs])
        shell = encode_shell(plan, omega, h, budget)
        options = [(GroupKind.SHELL, shell, plan.points)] if GroupKind.SHELL in SHELL_LAYOUTS else []
        if GroupKind.SHELL_TREE in SHELL_LAYOUTS:
            tree, source = shell_tree(shell, plan.walk)
            options.append((GroupKind.SHELL_TREE, tree, plan.points[source]))
        # Whichever layout deflates smaller: the tree on every corpus mesh measured (bench/shell_bits.py),
        # though a soup of separate triangles pays a link and a root's three codes for each.
        kind, shell, points = min(options, key=lambda c: len(records.pack(records.shell_kind_data(c[0], c[1]), True,
                                                                          records.SHELL_TREE_LEVEL)[1]))
        # A tree's named corners are solved with their planes in ascending order of reference, which the
        # writer renumbers (``reordered_tree``): every order of the three is measured, so the bound
        # holds for the one written.
        orders = itertools.permutations(range(3)) if kind == GroupKind.SHELL_TREE else [(0, 1, 2)]
        for order in orders:
            vp = np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1, 3)[:, list(order)]
            decoded, _ = decode_shell(omega, h, replace(shell, vertex_planes=vp))
            moved = max(moved, float(np.linalg.norm(decoded - points, axis=1).max(initial=0.0)))
        groups[k] = replace(g, kind=kind, shell=shell)
    return replace(obj, groups=tuple(groups)), moved


def _planeless(obj: _Object) -> _Object | None:
    """``obj`` with its shells stripped of their planes, or None where that changes it (it has
    convex groups, or colours that ride on planes)."""
    if any(g.kind != GroupKind.SHELL for g in obj.groups):
        return None
    if obj.face_colours is not None and (obj.face_colours != obj.face_colours[0]).any():
        return None
    # A group keeps one reference (spec §9: m >= 1), which its free triangles take their colour from;
    # the table keeps only those planes (CAD/box.STL at draco-14's error: 2.4 kB of 14 kB were planes
    # nothing referred to).
    keep = np.unique([g.refs[0] for g in obj.groups])
    fp = obj.face_plane
    face_plane = None if fp is None else np.where(np.isin(fp, keep), np.searchsorted(keep, fp), -1)
    return replace(obj, triplets=obj.triplets[keep], face_plane=face_plane,
                   plane_colours=None if obj.plane_colours is None else obj.plane_colours[keep],
                   groups=tuple(replace(g, refs=np.searchsorted(keep, g.refs[:1]), bounding=g.bounding[:1])
                                for g in obj.groups))


def _as_shells(obj: _Object) -> _Object:
    """``obj`` with its convex groups turned into (one) shell over their planes."""
    groups = [GroupSpec(GroupKind.SHELL, g.refs, np.zeros(len(g.refs), dtype=bool), faces=g.faces)
              if g.kind == GroupKind.CONVEX else g for g in obj.groups]
    return replace(obj, groups=tuple(_one_shell(groups)))


def _convex_part(obj: _Object) -> _Object:
    """The object reduced to its convex groups and their source faces, for the paper's verification."""
    groups = tuple(g for g in obj.groups if g.kind == GroupKind.CONVEX)
    faces = obj.faces[np.concatenate([g.faces for g in groups])]
    planes = np.unique(np.concatenate([g.refs for g in groups]))
    omega, h = from_triplets(obj.triplets[planes])
    used = np.unique(faces)
    fit = float(np.abs(omega @ obj.vertices[used].T - h[:, None]).min(axis=0).max(initial=0.0))
    return replace(obj, faces=faces, groups=groups, fit=fit, closed=True,
                   volume=signed_volume(obj.vertices, faces), euler=euler_characteristic(faces),
                   area=_area(obj.vertices, faces), rim=0.0)


def _choose_shells(objects: list[_Object], tolerance: float, coding: Coding | None,
                   bits: int | tuple[int, int, int] | None,
                   size: Callable[[list[_Object], _Choice], int]) -> tuple[list[_Object], _Choice]:
    """The objects of the shell scheme with their shells built, and the coding, smallest file first.

    Convex groups are verified as the paper's scheme verifies them (certified
    Hausdorff distance on their bodies alone), which fixes the coding; with
    none, every width of :data:`SHELL_WIDTHS` is tried and the smallest file
    kept. A shell's error holds by construction: decoded and source
    triangles correspond one to one, so the two-sided Hausdorff distance is at
    most the largest corner displacement, measured on the decoding. A
    decoding that misses a lossless volume or area (the Euler characteristic
    and closedness are the source's by construction) is made again with a
    quarter of the budget.
    """
    forced = coding is not None or bits is not None
    scale = [float(np.linalg.norm(o.world[:3, :3], 2)) for o in objects]
    diag_src = _diagonal(np.concatenate([transform_points(o.vertices, o.world) for o in objects]))
    convex_error = 0.0
    candidates: list[tuple[Coding, Quantization | None]] = []
    if any(g.kind == GroupKind.CONVEX for o in objects for g in o.groups):
        parts = [_convex_part(o) for o in objects if any(g.kind == GroupKind.CONVEX for g in o.groups)]
        try:
            c = _choose(parts, tolerance, coding, bits)
        except GeometryError:
            if forced:
                raise
            objects = [_as_shells(o) for o in objects]
        else:
            candidates = [(c.coding, c.quantization)]
            convex_error = c.error_bound * c.diagonal
    if not candidates:
        table = np.concatenate([o.triplets for o in objects])
        radius = max(float(np.linalg.norm(o.vertices, axis=1).max()) for o in objects)
        every = _candidates(coding, bits, table, radius)
        candidates = every if forced else \
            [(cod, q) for cod, q in every if cod == Coding.QUANTIZED and q.bits_nu in SHELL_WIDTHS]
    band = tolerance if tolerance > LOSSLESS_TOLERANCE else 0.0
    best: tuple[int, list[_Object], _Choice] | None = None
    why = ""
    # Planes that name no corner within the budget only cost bytes: the same shells without them
    # (every corner explicit, every triangle free) compete too, where colours do not ride on them.
    freed = [_planeless(o) for o in objects]
    variants = [(objects, candidates)]
    if not forced and all(f is not None for f in freed):
        variants.append((freed, candidates[:1]))
    trials = [(objs, cod, q) for objs, cands in variants for cod, q in cands]
    plans = {id(objs): [_shell_plans(o) for o in objs] for objs, _ in variants}
    for k, (objs, cod, q) in enumerate(trials):
        progress.report("choosing a coding", k, len(trials))
        offsets = np.cumsum([0] + [len(o.triplets) for o in objs])
        rt = quantize.roundtrip(np.concatenate([o.triplets for o in objs]), cod, q)
        budget = tolerance * diag_src / (1.0 + 2.0 * tolerance)
        for _ in range(_SHELL_TIGHTENINGS):
            built, moved = zip(*(_shells_for(o, pl, rt[a:b], budget / sc)
                                 for o, pl, a, b, sc in zip(objs, plans[id(objs)], offsets[:-1], offsets[1:], scale)))
            error = plane_error(cod, q, tolerance, diag_src)
            meshes = [_concatenate(_decode_object(rt[a:b], o, error))
                      for o, a, b in zip(built, offsets[:-1], offsets[1:])]
            # Shells alone keep the source's topology by construction: only volume or area can move.
            problems = [structure_problem(m, o, band * diag_src / sc,
                                          topology=any(g.kind not in SHELL_KINDS for g in o.groups))
                        for m, o, sc in zip(meshes, built, scale)]
            problems = [p for p in problems if p is not None]
            if not problems:
                break
            why = problems[0]
            budget /= 4.0
        else:
            continue
        world = np.concatenate([transform_points(m.vertices, o.world) for m, o in zip(meshes, built)])
        diagonal = _diagonal(world)
        err = max([convex_error] + [d * sc for d, sc in zip(moved, scale)])
        bound = err / diagonal if diagonal > 0 else 0.0
        choice = _Choice(coding=cod, quantization=q, meshes=meshes,
                         bbox=np.stack([world.min(axis=0), world.max(axis=0)]), diagonal=diagonal,
                         error_bound=bound, lossy=any(o.simplified for o in objects) or bound > tolerance)
        n = size(list(built), choice)
        if best is None or n < best[0]:
            best = (n, list(built), choice)
    if best is None:
        raise GeometryError(f"no coding keeps the source's structure with corners within the tolerance "
                            f"{tolerance:g}: {why}", code="TOLERANCE_NOT_MET")
    return best[1], best[2]


def _fit_error(relative: float, tolerance: float) -> GeometryError:
    return GeometryError(f"the fitted polygon planes are {relative:.3g} of the diagonal from the source vertices, "
                         f"above the tolerance {tolerance:g}", code="TOLERANCE_NOT_MET")


def _diagonal(points: np.ndarray) -> float:
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(points) else 0.0


def _decode_object(triplets: np.ndarray, obj: _Object, error: PlaneError) -> list[DecodedGroup]:
    return decode_groups([(triplets[g.refs], g, i) for i, g in enumerate(obj.groups)], error)


def _peak(values: np.ndarray) -> float:
    return float(values.max(initial=0.0))


@dataclass(frozen=True)
class _Incidences:
    """An object's decoded vertices, all groups together, and the object-table planes they lie on."""

    vertices: np.ndarray
    inc_vertex: np.ndarray
    inc_plane: np.ndarray

    @staticmethod
    def of(decoded: list[DecodedGroup], obj: _Object) -> _Incidences:
        """From ``decoded``, the object's groups decoded from its exact planes. Incidences whose
        vertex is off its plane there (welded across a crack: octagonal_pocket.stl has 6 of 6,236,
        up to 0.27 of the diagonal off) would pull the vertex away; they are left out."""
        # One array for all groups: patch meshes have tens of thousands (bun_zipper.ply).
        offsets = np.cumsum([0] + [len(d.vertices) for d in decoded])
        empty = np.zeros(0, dtype=np.int64)
        vertices = np.concatenate([d.vertices for d in decoded]) if decoded else np.zeros((0, 3))
        inc_vertex = np.concatenate([d.inc_vertex + k for d, k in zip(decoded, offsets)] or [empty])
        inc_plane = np.concatenate([np.asarray(g.refs)[d.inc_ref] for d, g in zip(decoded, obj.groups)] or [empty])
        omega, h = from_triplets(obj.triplets)
        gap = np.abs(np.einsum("ij,ij->i", omega[inc_plane], vertices[inc_vertex]) - h[inc_plane])
        on = gap <= _ON_PLANE * float(np.abs(h).max(initial=1.0))
        return _Incidences(vertices=vertices, inc_vertex=inc_vertex[on], inc_plane=inc_plane[on])

    def moved(self, triplets: np.ndarray) -> tuple[np.ndarray, float]:
        """The vertices as the planes ``triplets`` would put them (model units), and the largest
        offset of those planes from a vertex whose step is not to be trusted.

        A vertex of nearly dependent planes can get a step thousands of times what its planes moved
        (octagonal_pocket.stl: 0.38 of the diagonal for planes moved 1e-6 at it, at every width):
        such a vertex keeps its place and counts with its planes' offset instead.
        """
        omega, h = from_triplets(triplets)
        out = resolve_vertices(self.vertices, self.inc_vertex, self.inc_plane, omega, h)
        gap = np.abs(np.einsum("ij,ij->i", omega[self.inc_plane], self.vertices[self.inc_vertex])
                     - h[self.inc_plane])
        offset = np.zeros(len(out))
        np.maximum.at(offset, self.inc_vertex, gap)
        wild = np.linalg.norm(out - self.vertices, axis=1) > _STEP_LIMIT * offset
        out[wild] = self.vertices[wild]
        return out, _peak(offset[wild])


def _verify(mesh: Mesh, obj: _Object, target: float, pieces: int,
            decoded: list[DecodedGroup] | None = None) -> tuple[float, float]:
    """``(upper, lower)``: certified bounds (world model units) of the two-sided Hausdorff distance to
    the source, refined until ``upper <= target`` or the decision is made; ``upper`` is infinity
    when it is not at most ``target``.

    Convex groups over convex source bodies (``decoded`` given) are bounded from their corners
    (:func:`planefmt.convexbound.convex_hausdorff`), group by group, without a search.
    """
    shift = _mended(obj)
    convex = _convex_bounds(decoded, obj) if decoded is not None else None
    if convex is not None:
        upper, lower = convex
    else:
        a = transform_points(mesh.vertices, obj.world)
        b = transform_points(obj.vertices, obj.world)
        r = hausdorff(a, mesh.faces, b, obj.faces, target=target - shift, max_pieces=pieces)
        upper, lower = float(r.upper), float(r.lower)
    upper += shift
    return (upper if upper <= target else math.inf), max(lower - shift, 0.0)


def _convex_bounds(decoded: list[DecodedGroup], obj: _Object) -> tuple[float, float] | None:
    """``(upper, lower)`` of the two-sided Hausdorff distance (world model units) of an object made
    of convex groups, each against its source body, or None where a group or body is not convex.

    The distance between the unions is at most the largest between a body and its own group's
    decoding: each is part of its union's surface."""
    groups = obj.groups
    if not groups or any(g.kind != GroupKind.CONVEX for g in groups):
        return None
    if len(groups) == 1 and groups[0].faces is None:
        sources = [obj.faces]
    elif all(g.faces is not None for g in groups):
        sources = [obj.faces[g.faces] for g in groups]
    else:
        return None
    upper = lower = 0.0
    b = transform_points(obj.vertices, obj.world)
    for d, faces in zip(decoded, sources):
        found = convex_hausdorff(transform_points(d.vertices, obj.world), d.triangles, b, faces)
        if found is None:
            return None
        upper, lower = max(upper, found[0]), max(lower, found[1])
    return upper, lower


def _mended(obj: _Object) -> float:
    """How far (world units) the source the decoding is measured against lies from the input."""
    return obj.mended * float(np.linalg.norm(obj.world[:3, :3], 2))


def _measure(mesh: Mesh, obj: _Object, target: float) -> float:
    """Certified upper bound (world model units) of the two-sided Hausdorff distance to the source,
    within about 10% of the distance.

    The target starts at 1.1 times the largest distance of a decoded vertex
    to the source (a lower bound of the distance) and is raised to 1.1 times
    the certified lower bound (which exceeds a failed target) until a bound
    is certified.
    """
    a = transform_points(mesh.vertices, obj.world)
    b = transform_points(obj.vertices, obj.world)
    shift = _mended(obj)
    target = max(target, 1.1 * float(closest_distance(a, b, obj.faces)[0].max(initial=0.0)))
    for _ in range(_MEASURE_STEPS):
        r = hausdorff(a, mesh.faces, b, obj.faces, target=target, max_pieces=DEFAULT_MAX_PIECES)
        if r.upper <= target:
            return float(r.upper) + shift
        target = 1.1 * max(target, float(r.lower))
    return float(r.upper) + shift


# -- scenes and files -------------------------------------------------------------------------

def encode_scene(scene: Scene, target: str | os.PathLike | BinaryIO, *, tolerance: float = 1e-6,
                 coding: Coding | None = None, bits: int | tuple[int, int, int] | None = None,
                 delta: float | None = None, tau: float | None = None, compress: bool = True,
                 compact: bool = True, watertight: bool = True, scheme: str = "shell") -> Header:
    """Write ``scene`` to a .pln file (path, written atomically, or binary stream); returns its header.

    One object per node, keeping name, parent and transform; each node's
    mesh is encoded in its local coordinates (a mesh several nodes share is
    stored once per node: the format has no shared part groups). The scene's
    ``up_axis``, if any, is a mETA chunk (spec §10.3). One coding serves the whole
    file; the tolerance is a fraction of the diagonal of the decoded scene's
    world bbox, and errors are measured in world coordinates. Identical
    planes (after coding) are stored once, written just before the first
    group that uses them: in first-use order, or with ``compact`` sorted
    within each object's block. Options as for :func:`encode_mesh`.

    ``compress`` (the default, as ``pln convert``): payloads deflated where
    that saves bytes. ``compact`` (the default, as ``pln convert``; False
    writes version 1.0): a version 3.0 file (spec/pln.md): quantized planes in
    whichever of the bit-packed and the predicted coding takes fewer bytes,
    group references, cells and trees as varints, chunk heads as varints. The
    planes and the decoded surface are those of the version 1 file. A scene
    with sealed groups (closed bodies no BSP tree decodes faithfully) is
    written as version 3.1 whatever ``compact`` says: version 1.0 has no such
    kind, and a writer uses the lowest version that covers what it writes.
    """
    worlds = _world_transforms(scene.nodes)
    meshes = [i for i, n in enumerate(scene.nodes) if n.mesh is not None and len(n.mesh.faces)]
    forced = coding is not None or bits is not None
    diagonal = _scene_diagonal(scene, worlds, meshes) if not forced else None

    if not meshes:
        raise GeometryError("the scene has no mesh to encode")

    def prepare(k: int, splitters: tuple[Splitter, ...] = STRATEGIES) -> _Object:
        node = scene.nodes[meshes[k]]
        return replace(_prepare(node.mesh.vertices, node.mesh.faces, worlds[meshes[k]], tolerance, delta, tau,
                                node.mesh.face_colours, diagonal, splitters, scheme), name=node.name)

    def size(objects: list[_Object], choice: _Choice) -> int:
        buf = io.BytesIO()
        _write(scene, buf, meshes, objects, choice, tolerance, compress, compact)
        return len(buf.getvalue())

    objects, choice = _encode_objects(prepare, len(meshes), tolerance, coding, bits, watertight, size, scheme)
    return _write(scene, target, meshes, objects, choice, tolerance, compress, compact)


def _encode_objects(prepare: Callable[..., _Object], count: int, tolerance: float, coding: Coding | None,
                    bits: int | tuple[int, int, int] | None, watertight: bool,
                    size: Callable[[list[_Object], _Choice], int], scheme: str = "shell"
                    ) -> tuple[list[_Object], _Choice]:
    """The objects ``prepare(k[, splitters])`` (k < ``count``) and the coding to write them in.

    The shell scheme chooses by file size among codings that are all correct
    (:func:`_choose_shells`); the paper's scheme as follows.

    Hull-first trees are smaller but can need finer planes (solids.FLAT_STRATEGIES): where one was
    kept and the widths are free to shrink (a lossy tolerance, no forced coding), the objects are
    encoded again with the flat strategies and the encoding whose file ``size`` finds smaller is
    kept (a set whose objects meet no coding is passed over). At 1e-6 the hull-first files were
    never the larger on the corpus meshes measured (six), and CAD encodes take minutes.
    """
    objects = []
    for k in range(count):
        progress.report("encoding objects", k, count)
        objects.append(prepare(k))
    if scheme == "shell":
        return _choose_shells(objects, tolerance, coding, bits, size)
    forced = coding is not None or bits is not None
    hull = [k for k, o in enumerate(objects) if any(g.splitter and g.splitter[2] for g in o.groups)]
    if not hull or forced or tolerance <= LOSSLESS_TOLERANCE:
        return objects, _choose(objects, tolerance, coding, bits, watertight)
    flat = [prepare(k, FLAT_STRATEGIES) if k in hull else o for k, o in enumerate(objects)]
    found = []
    failure = None
    for candidate in (objects, flat):
        # Only the kept encoding's warnings reach the caller.
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                choice = _choose(candidate, tolerance, coding, bits, watertight)
            except GeometryError as err:
                failure = failure or err
                continue
        found.append((size(candidate, choice), candidate, choice, caught))
    if not found:
        raise failure
    _, best, choice, caught = min(found, key=lambda f: f[0])
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return best, choice


def _write(scene: Scene, target: str | os.PathLike | BinaryIO, meshes: list[int], objects: list[_Object],
           choice: _Choice, tolerance: float, compress: bool, compact: bool) -> Header:
    """Write the scene's ``objects`` (those of nodes ``meshes``) in the chosen coding; its header."""
    sealed = any(g.kind == GroupKind.SEALED for o in objects for g in o.groups)
    shells = any(g.kind in SHELL_KINDS for o in objects for g in o.groups)
    trees = any(g.kind == GroupKind.SHELL_TREE for o in objects for g in o.groups)
    compact = compact or sealed or shells
    table = quantize.roundtrip(np.concatenate([o.triplets for o in objects]), choice.coding,
                               choice.quantization)
    # Rows identical after coding are one plane; the plane table is in first-use order, so each
    # object's new planes are the next block of it. Coding is idempotent: the writer re-codes
    # these rows to the same values.
    _, first, inverse = np.unique(table, axis=0, return_index=True, return_inverse=True)
    offsets = np.cumsum([0] + [len(o.triplets) for o in objects])
    if compact:
        # Sorted by value within each object's block (np.unique's rows are): runs of one normal,
        # which the predicted coding stores as zeros and small h differences.
        order = np.lexsort((np.arange(len(first)), np.searchsorted(offsets, first, side="right")))
    else:
        order = np.argsort(first, kind="stable")
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    global_index = rank[inverse.reshape(-1)]
    rows = table[first[order]]
    stored = choice.coding
    if compact and stored.quantized:
        stored = min((Coding.QUANTIZED, Coding.PREDICTED), key=lambda c: _table_bytes(rows, c, choice.quantization,
                                                                                       compress))
    header = Header(version=((3, 3) if trees else (3, 2) if shells else (3, 1) if sealed else (3, 0)) if compact
                    else (1, 0), lossy=choice.lossy, coding=stored,
                    quantization=choice.quantization, units=scene.units, bbox=choice.bbox,
                    tolerance=float(tolerance), error_bound=choice.error_bound,
                    plane_count=len(rows), object_count=len(scene.nodes),
                    group_count=sum(len(o.groups) for o in objects))
    by_node = {i: (o, a) for i, o, a in zip(meshes, objects, offsets)}
    # An index gives a small file no random access worth its bytes: compact files leave it to the writer.
    index = True if not compact else None
    with _writer(target, header, compress, index) as w:
        if scene.up_axis is not None:
            w.add_metadata(UP_AXIS, scene.up_axis)
        for i, node in enumerate(scene.nodes):
            obj_index = w.add_object(node.name, node.parent, node.transform)
            if i not in by_node:
                continue
            o, a = by_node[i]
            refs = global_index[a:a + len(o.triplets)]
            if refs.max() >= w.plane_count:
                w.add_planes(rows[w.plane_count:refs.max() + 1])
            for g in o.groups:
                perm = np.argsort(refs[g.refs], kind="stable") if compact else np.arange(len(g.refs))
                p = _permuted(g, perm)
                k = w.add_group(obj_index, g.kind, refs[g.refs[perm]], g.bounding[perm], cells=p.cells, tree=p.tree,
                                vertex_planes=p.vertex_planes, facets=p.facets, shell=p.shell)
                if o.plane_colours is not None:
                    w.add_colours(k, o.plane_colours[g.refs[perm]])
    return header


def _table_bytes(rows: np.ndarray, coding: Coding, q: Quantization, compress: bool) -> int:
    """Bytes of the plane table ``rows`` in ``coding``, deflated where that is smaller, as the writer
    stores it (the block heads are the same for either coding)."""
    return sum(len(records.pack(quantize.encode_payload(rows[s:s + BLOCK_PLANES], coding, q), compress)[1])
               for s in range(0, len(rows), BLOCK_PLANES))


def _permuted(g: GroupSpec, perm: np.ndarray) -> GroupSpec:
    """``g`` once its references are reordered as ``refs[perm]`` (version 2 groups list them in
    increasing order): its local references renumbered, a sealed group's triangles re-sorted by
    face."""
    local = np.empty(len(perm), dtype=np.int64)
    local[perm] = np.arange(len(perm))
    cells = None if g.cells is None else tuple(
        (2 * local[np.asarray(c, dtype=np.int64) >> 1] + (np.asarray(c, dtype=np.int64) & 1)).astype(np.uint32)
        for c in g.cells)
    tree = None
    if g.tree is not None:
        t = np.asarray(g.tree, dtype=np.int64)
        split = t <= BSP_MAX_SPLIT
        tree = np.where(split, local[np.where(split, t, 0)], t).astype(np.uint32)
    vertex_planes = facets = None
    if g.vertex_planes is not None and g.facets is not None:
        vertex_planes = local[np.asarray(g.vertex_planes, dtype=np.int64)]
        facets = np.asarray(g.facets, dtype=np.int64).copy()
        facets[:, 0] = local[facets[:, 0]]
        facets = facets[np.argsort(facets[:, 0], kind="stable")]
    shell = None if g.shell is None else (reordered_tree if g.kind == GroupKind.SHELL_TREE else reordered)(g.shell, local)
    return GroupSpec(g.kind, g.refs[perm], g.bounding[perm], cells, tree, vertex_planes, facets, shell=shell)


def _scene_diagonal(scene: Scene, worlds: list[np.ndarray], meshes: list[int]) -> float | None:
    """World bbox diagonal of the used vertices of the nodes ``meshes``; None if some mesh is malformed."""
    points = []
    for i in meshes:
        v, f = np.asarray(scene.nodes[i].mesh.vertices), np.asarray(scene.nodes[i].mesh.faces)
        if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or not np.issubdtype(f.dtype, np.integer) \
                or f.min() < 0 or f.max() >= len(v):
            return None
        points.append(transform_points(v[np.unique(f)].astype(np.float64), worlds[i]))
    d = _diagonal(np.concatenate(points)) if points else 0.0
    return d if math.isfinite(d) else None


def _writer(target: str | os.PathLike | BinaryIO, header: Header, compress: bool, index: bool | None = True) -> Writer:
    return Writer(target, header, compress=compress, index=index)


def _world_transforms(nodes: Sequence[Node]) -> list[np.ndarray]:
    worlds: list[np.ndarray] = []
    for i, n in enumerate(nodes):
        local = np.eye(4) if n.transform is None else np.asarray(n.transform, dtype=np.float64)
        if n.parent is not None and not 0 <= n.parent < i:
            raise GeometryError(f"node {i} ({n.name!r}): parent {n.parent} does not precede it")
        worlds.append(local if n.parent is None else worlds[n.parent] @ local)
    return worlds


def decode_scene(source: str | os.PathLike | BinaryIO) -> Scene:
    """Read a .pln file into a :class:`Scene`: one node per object, its groups decoded and joined.

    Streams: part groups are decoded in batches of up to 4096 as they are read.
    Groups of a kind from a newer minor version are skipped, as spec §13 asks
    of a reader, with one :class:`PlnWarning` naming them.
    """
    parts: dict[int, list[tuple[int, DecodedGroup]]] = {}
    colours: dict[int, np.ndarray] = {}
    pending: list[PartGroup] = []
    skipped: list[PartGroup] = []

    def flush() -> None:
        for rec, d in zip(pending, decode_groups([(g.planes, g, g.index) for g in pending], error)):
            parts.setdefault(rec.object, []).append((rec.index, d))
        pending.clear()

    with Reader(source) as r:
        error = header_plane_error(r.header)
        known = records.kinds_of(*r.header.version)
        for rec in r:
            if isinstance(rec, PartGroup):
                if int(rec.kind) not in known:
                    skipped.append(rec)
                    continue
                # Decoded in batches of groups read (patches together), bounding what is held.
                pending.append(rec)
                if len(pending) >= _DECODE_BATCH:
                    flush()
            elif isinstance(rec, Colours):
                colours[rec.group] = rec.rgba
        flush()
        if skipped:
            warnings.warn(SkippedGroupsWarning(skipped_groups(skipped), r.name), stacklevel=2)
        return _assemble(r.objects, parts, r.header.units, colours, r.up_axis)


def skipped_groups(groups: Sequence[GroupLike]) -> str:
    """The part groups of newer minor versions' kinds a reader skipped (spec §13), named."""
    which = ", ".join(f"{g.index} (kind {int(g.kind)})" for g in groups)
    return f"part group{'s' if len(groups) > 1 else ''} {which} of a newer minor version than this reader knows"


def salvage_scene(source: str | os.PathLike | BinaryIO) -> tuple[Scene, list[str]]:
    """What :func:`decode_scene` gives for the intact part of a damaged file, and what was lost.

    Reads through :func:`planefmt.salvage.salvage`: every intact object and
    part group is kept, a group that no longer decodes (its planes were
    damaged into an empty or unbounded set) joins the losses. Raises
    ``FormatError`` (``MISSING_HEADER``) when no header survived.
    """
    got = salvage(source)
    if got.header is None:
        raise FormatError("no intact PHDR chunk: nothing to salvage", code="MISSING_HEADER",
                          file=os.fspath(source) if isinstance(source, (str, os.PathLike))
                          else getattr(source, "name", None))
    lost = [f"{x.message}" + ("" if x.offset is None else f" (byte {x.offset})") for x in got.losses]
    error = header_plane_error(got.header)
    objects = [r for r in got.records if isinstance(r, ObjectRecord)]
    parts: dict[int, list[tuple[int, DecodedGroup]]] = {}
    known = records.kinds_of(*got.header.version)
    skipped = [g for g in got.part_groups if int(g.kind) not in known]
    if skipped:
        lost.append(f"{skipped_groups(skipped)} skipped")
    for g in (g for g in got.part_groups if int(g.kind) in known):
        try:
            parts.setdefault(g.object, []).append((g.index, decode_group(g.planes, g, g.index, error)))
        except GeometryError as exc:
            lost.append(f"part group {g.index} lost: {exc.reason}")
    colours = {r.group: r.rgba for r in got.records if isinstance(r, Colours)}
    up = [r.value for r in got.records if isinstance(r, Metadata) and r.key == UP_AXIS]
    return _assemble(objects, parts, got.header.units, colours, up[0] if up else None), lost


#: Face colour of decoded triangles whose group has no cOLR, in an object where others have one.
UNCOLOURED = np.array([200, 200, 200, 255], dtype=np.uint8)


def _assemble(objects: Sequence[ObjectRecord], parts: dict[int, list[tuple[int, DecodedGroup]]], units: Units,
              colours: dict[int, np.ndarray], up_axis: str | None) -> Scene:
    # Salvaged objects may have gaps in their indices; nodes are numbered by position.
    position = {o.index: i for i, o in enumerate(objects)}
    # A mesh its source placed at several nodes is stored once per object (a .pln file has no shared part
    # groups) and decodes to the same triangles each time: those objects share one Mesh again, as the
    # source's nodes did, so that writers can instance it.
    decoded: dict[bytes, Mesh] = {}

    def shared(mesh: Mesh) -> Mesh:
        kept = decoded.setdefault(_digest(mesh), mesh)
        return kept if kept is mesh or _same_mesh(kept, mesh) else mesh

    nodes = tuple(Node(name=o.name, parent=None if o.parent is None else position[o.parent], transform=o.transform,
                       mesh=shared(_object_mesh(parts[o.index], colours)) if o.index in parts else None)
                  for o in objects)
    return Scene(nodes=nodes, units=units, up_axis=up_axis)


def _digest(mesh: Mesh) -> bytes:
    h = hashlib.blake2b(digest_size=16)
    for a in (mesh.vertices, mesh.faces, mesh.face_colours):
        h.update(b"-" if a is None else repr(a.shape).encode() + np.ascontiguousarray(a).tobytes())
    return h.digest()


def _same_mesh(a: Mesh, b: Mesh) -> bool:
    return (np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
            and (a.face_colours is None) == (b.face_colours is None)
            and (a.face_colours is None or np.array_equal(a.face_colours, b.face_colours)))


def _object_mesh(parts: list[tuple[int, DecodedGroup]], colours: dict[int, np.ndarray]) -> Mesh:
    """The groups of one object joined; face colours from their cOLR chunks (spec §10.1), if any."""
    mesh = _concatenate([d for _, d in parts])
    if not any(k in colours for k, _ in parts):
        return mesh
    # A shell's free triangles (reference -1) take its last reference's colour (spec §9.10).
    face = np.concatenate([colours[k][d.triangle_ref] if k in colours else np.tile(UNCOLOURED, (len(d.triangles), 1))
                           for k, d in parts]).astype(np.uint8)
    return Mesh(mesh.vertices, mesh.faces, face_colours=face)


def check_group(group: PartGroup, reader: Reader) -> list[Finding]:
    """Geometry findings of one part group for ``planefmt.validate`` (spec §9, §12.3).

    ``EMPTY_POLYTOPE`` / ``UNBOUNDED_POLYTOPE`` errors, one ``REDUNDANT_PLANE``
    warning per plane of a convex group that bounds no face. Kinds without a
    decoder yet get one ``GEOMETRY_NOT_CHECKED`` note.
    """
    if group.planes is None:
        return []
    where = dict(file=reader.name, chunk="GRUP", group=group.index)
    if int(group.kind) not in records.kinds_of(*reader.header.version):
        return []  # a newer minor version's kind: SKIPPED_GROUP_KIND already says so
    if int(group.kind) not in DECODERS:
        return [Finding("GEOMETRY_NOT_CHECKED", CODES["GEOMETRY_NOT_CHECKED"].severity,
                        f"part group {group.index}: kind {GroupKind(group.kind).name} is not decoded by this "
                        f"version of planefmt", **where)]
    try:
        decoded = decode_group(group.planes, group, group.index,
                               header_plane_error(reader.header))
    except GeometryError as exc:
        return [Finding(exc.code, CODES[exc.code].severity, exc.reason, **where)]
    return [Finding("REDUNDANT_PLANE", CODES["REDUNDANT_PLANE"].severity,
                    f"part group {group.index}: plane {int(group.refs[j])} (reference {int(j)}) bounds no face",
                    **where) for j in decoded.redundant]


# The validator runs every registered geometry check; registering here keeps it free of the codec.
GROUP_CHECKS.append(check_group)
