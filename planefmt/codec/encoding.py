"""Encoding meshes and scenes: :func:`encode_mesh` (an :class:`Encoded` in memory) and
:func:`encode_scene` (a .pln file). Objects are prepared, the coding chosen, and the planes
written once each, in first-use order, before the first group that uses them.
"""

from __future__ import annotations

import io
import math
import os
import warnings
import zlib
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from typing import BinaryIO

import numpy as np

from .. import progress
from ..container import compression, quantize, records, shellfields, shellwalk
from ..container.chunks import Limits
from ..container.writer import BLOCK_PLANES, SMALL_SEGMENT_BYTES, SMALL_SHELLS_BYTES, Writer
from ..errors import GeometryError, PlnError, PlnWarning
from ..geometry.planes import transform_points
from ..groups.shells import reordered, reordered_tree
from ..groups.solids import FLAT_STRATEGIES, STRATEGIES, Splitter
from ..model import (BSP_MAX_SPLIT, FREE, TREE_KINDS, UP_AXIS, Coding, GroupKind, Header, Mesh, Node, PartGroup, Quantization,
                     Scene, Shell, Units)
from .choosing import F32_RANGE, _Choice, _choose, _choose_shells
from .decoding import SHELL_KINDS
from .preparing import LOSSLESS_TOLERANCE, _Object, _diagonal, _prepare, _world_transforms
from .strategies import GroupSpec


#: Brotli quality of the segments of a candidate whose size is estimated (the shell scheme's trials rank
#: candidates by it): about 80 times as fast as quality 11 on segments of 20-50 kB, and within 2 % of its
#: ratios between candidates (bench corpus, nine meshes at 1e-6, 1e-4 and Draco-14's error; measured on
#: a shared machine, 2026-12-08).
ESTIMATE_QUALITY = 5


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


def encode_mesh(vertices: np.ndarray, faces: np.ndarray, *, tolerance: float = 1e-6,
                coding: Coding | None = None, bits: int | tuple[int, int, int] | None = None,
                delta: float | None = None, tau: float | None = None, watertight: bool = True,
                scheme: str = "shell", keep_corners: bool = False, keep_triangles: bool = False) -> Encoded:
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

    At a tolerance above 1e-6 the shell scheme first drops the corners
    that carry no shape: corners inside one plane's faces and corners on a
    straight crease between two planes, collapsed into a neighbour so that
    the surface stays where it is (within a bound by construction, counted
    in the error: :mod:`planefmt.geometry.redundant`). The decoded mesh then
    has fewer corners and triangles than the source (box.STL: 1,060 corners of
    4,455). ``keep_corners=True`` keeps every corner and triangle.

    What every encode keeps (spec §5, "lossless" at the default tolerance): the surface within the
    tolerance, and the source's topology as a reader that welds vertices by position sees it (closed
    bodies closed, Euler characteristic, bodies that touch still touching, no two corners joined).
    The triangles themselves are kept where the bodies are shells; a convex body of at most
    :data:`planefmt.codec.strategies.CONVEX_MAX_PLANES` planes is its planes, its triangles made from them on decoding.
    ``keep_triangles=True`` makes every body a shell and keeps every corner: the decoded triangles
    are then the source's (those with three distinct corners) one to one.

    Raises ``GeometryError``: ``DEGENERATE_GEOMETRY`` for malformed input,
    ``TOLERANCE_NOT_MET`` when no coding meets the tolerance and keeps the
    source's structure.
    """
    forced = coding is not None or bits is not None

    def prepare(_: int, splitters: tuple[Splitter, ...] = STRATEGIES, tolerance: float = tolerance) -> _Object:
        return _prepare(vertices, faces, np.eye(4), tolerance, delta, tau, diagonal=None if forced else 0.0,
                        splitters=splitters, scheme=scheme, keep_corners=keep_corners, keep_triangles=keep_triangles)

    def size(objects: list[_Object], choice: _Choice, brotli: bool = True, estimate: bool = False) -> int:
        buf = io.BytesIO()
        # Trials verified and written as the file is, Brotli included (encode_scene's are deflated only).
        _write(Scene((Node("", mesh=Mesh(vertices, faces)),)), buf, [0], objects, choice, tolerance,
               scheme == "shell", False, brotli=brotli, segment_quality=ESTIMATE_QUALITY if estimate else None)
        return len(buf.getvalue())

    def encode(tol: float) -> tuple[list[_Object], _Choice]:
        return _encode_objects(partial(prepare, tolerance=tol), 1, tol, coding, bits, watertight, size, scheme)

    (obj,), choice = _or_tighter(encode, tolerance, forced)
    return Encoded(triplets=obj.triplets, groups=obj.groups, coding=choice.coding,
                   quantization=choice.quantization, bbox=choice.bbox, tolerance=float(tolerance),
                   error_bound=choice.error_bound, lossy=choice.lossy, mesh=choice.meshes[0],
                   fit_error=obj.fit / choice.diagonal)


def encode_scene(scene: Scene, target: str | os.PathLike | BinaryIO, *, tolerance: float = 1e-6,
                 coding: Coding | None = None, bits: int | tuple[int, int, int] | None = None,
                 delta: float | None = None, tau: float | None = None, compress: bool = True,
                 compact: bool = True, watertight: bool = True, scheme: str = "shell", major: int = 6,
                 keep_corners: bool = False, keep_triangles: bool = False) -> Header:
    """Write ``scene`` to a .pln file (path, written atomically, or binary stream); returns its header.

    One object per node, keeping name, parent and transform; each node's
    mesh is encoded in its local coordinates (a mesh several nodes share is
    stored once per node: the format has no shared part groups). The scene's
    ``up_axis``, if any, is in the header (spec §5; a mETA chunk before version 5, §10.3). One coding serves the whole
    file; the tolerance is a fraction of the diagonal of the decoded scene's
    world bbox, and errors are measured in world coordinates. Identical
    planes (after coding) are stored once, written just before the first
    group that uses them: in first-use order, or with ``compact`` sorted
    within each object's block. Options as for :func:`encode_mesh`.

    ``compress`` (the default, as ``pln convert``): payloads deflated or Brotli-compressed, whichever
    is smaller, where that saves bytes. ``compact`` (the default, as ``pln convert``; False writes
    version 1.0): a version 6.0 file (spec/pln.md: every record in body segments compressed whole, the h
    range chosen as float32 values before quantizing; ``major`` 5: 5.0 to 5.2, each chunk framed and
    compressed alone; ``major`` 4: 4.0 to 4.2, with 32-bit chunk lengths,
    a mETA up axis and float64 shell grids): quantized planes in whichever of the bit-packed
    and the predicted coding takes fewer bytes, group references, cells and trees as varints, chunk
    heads as varints, transforms entry by entry, a group's one colour once. The planes and the
    decoded surface are those of the version 1 file. A scene with sealed or shell groups is written
    as version ``major`` whatever ``compact`` says: version 1.0 has no such kinds. ``major`` 3 writes, for
    readers of 3.x, the lowest version 3.0 to 3.4 that holds the file (spec Appendix A.3): deflate
    only, transforms as 16 doubles, a colour per reference.
    """
    if major not in (3, 4, 5, 6):
        raise PlnError(f"version {major}.x cannot be written: 3, 4, 5 or 6 (or 1.0 with compact=False)",
                       code="UNSUPPORTED_VERSION")
    token = F32_RANGE.set(major >= 6 and compact)
    try:
        return _encode_scene(scene, target, tolerance, coding, bits, delta, tau, compress, compact, watertight,
                             scheme, major, keep_corners, keep_triangles)
    finally:
        F32_RANGE.reset(token)


def _encode_scene(scene: Scene, target: str | os.PathLike | BinaryIO, tolerance: float, coding: Coding | None,
                  bits: int | tuple[int, int, int] | None, delta: float | None, tau: float | None, compress: bool,
                  compact: bool, watertight: bool, scheme: str, major: int, keep_corners: bool,
                  keep_triangles: bool) -> Header:
    # Each encode starts cold, so that an encode repeated on the same scene (a benchmark's) costs what
    # the first did.
    shellwalk.forget()
    compression.forget()
    worlds = _world_transforms(scene.nodes)
    meshes = [i for i, n in enumerate(scene.nodes) if n.mesh is not None and len(n.mesh.faces)]
    forced = coding is not None or bits is not None
    diagonal = _scene_diagonal(scene, worlds, meshes) if not forced else None

    if not meshes:
        raise GeometryError("the scene has no mesh to encode")

    def prepare(k: int, splitters: tuple[Splitter, ...] = STRATEGIES, tolerance: float = tolerance) -> _Object:
        node = scene.nodes[meshes[k]]
        return replace(_prepare(node.mesh.vertices, node.mesh.faces, worlds[meshes[k]], tolerance, delta, tau,
                                node.mesh.face_colours, diagonal, splitters, scheme, keep_corners, keep_triangles),
                       name=node.name)

    def size(objects: list[_Object], choice: _Choice, brotli: bool = False, estimate: bool = False) -> int:
        buf = io.BytesIO()
        # A candidate measured for its size only: the file written is verified.
        _write(scene, buf, meshes, objects, choice, tolerance, compress, compact, major, verify=False, brotli=brotli,
               segment_quality=ESTIMATE_QUALITY if estimate else None)
        return len(buf.getvalue())

    def encode(tol: float) -> tuple[list[_Object], _Choice]:
        return _encode_objects(partial(prepare, tolerance=tol), len(meshes), tol, coding, bits, watertight, size,
                               scheme)

    objects, choice = _or_tighter(encode, tolerance, forced)
    header = _write(scene, target, meshes, objects, choice, tolerance, compress, compact, major)
    _warn_past_default_limits(scene, meshes)
    return header


def _warn_past_default_limits(scene: Scene, meshes: list[int]) -> None:
    """A :class:`PlnWarning` where the scene is larger than a reader decodes by default (spec §12.4): the
    encoder's own checks decode without the limit, a reader of the file must be told to raise it."""
    triangles = sum(len(scene.nodes[i].mesh.faces) for i in meshes)
    vertices = sum(len(scene.nodes[i].mesh.vertices) for i in meshes)
    defaults = Limits()
    if triangles > defaults.max_triangles or vertices > defaults.max_vertices:
        warnings.warn(PlnWarning(
            f"the scene has {triangles:,} triangles over {vertices:,} vertices, more than the {defaults.max_triangles:,} "
            f"triangles and {defaults.max_vertices:,} vertices a reader decodes by default: read the file with "
            f"planefmt.Limits(max_triangles=..., max_vertices=...), pln --max-triangles N --max-vertices N, or the "
            f"JavaScript reader's limits: {{triangles: N, vertices: N}}"), stacklevel=3)


#: Where a lossy tolerance is not met, tighter ones are tried, each this factor under the last, down to
#: the lossless tolerance.
FALLBACK_STEP = math.sqrt(10.0)


def _or_tighter(encode: Callable[[float], tuple[list[_Object], _Choice]], tolerance: float,
                forced: bool) -> tuple[list[_Object], _Choice]:
    """``encode(tolerance)``, or where that meets no coding, ``encode`` at the first tighter tolerance
    (steps of :data:`FALLBACK_STEP` down to :data:`LOSSLESS_TOLERANCE`) that does: a looser tolerance
    never fails where a tighter one works. Its measured bound, under ``tolerance``, is what is
    recorded, and the requested tolerance as the one asked for."""
    try:
        return encode(tolerance)
    except GeometryError as err:
        if forced or tolerance <= LOSSLESS_TOLERANCE or err.code != "TOLERANCE_NOT_MET":
            raise
        failure = err
    tighter = tolerance
    while tighter > LOSSLESS_TOLERANCE:
        tighter = max(tighter / FALLBACK_STEP, LOSSLESS_TOLERANCE)
        try:
            return encode(tighter)
        except GeometryError as err:
            if err.code != "TOLERANCE_NOT_MET":
                raise
    raise failure


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
           choice: _Choice, tolerance: float, compress: bool, compact: bool, major: int = 4,
           verify: bool = True, brotli: bool = True, segment_quality: int | None = None) -> Header:
    """Write the scene's ``objects`` (those of nodes ``meshes``) in the chosen coding; its header.
    ``verify`` off: a candidate measured for its size; ``brotli`` off: deflated only; ``segment_quality``:
    version 6 segments at that Brotli quality (a size estimated)."""
    if major == 3:
        objects = [replace(o, groups=tuple(_as_tree(g) for g in o.groups)) for o in objects]
    elif major == 4:
        objects = [replace(o, groups=tuple(_unreflected(g) for g in o.groups)) for o in objects]
    if major >= 5 and compact:
        objects = [_unreferenced(o) for o in objects]
    sealed = any(g.kind == GroupKind.SEALED for o in objects for g in o.groups)
    shells = any(g.kind in SHELL_KINDS for o in objects for g in o.groups)
    compact = compact or sealed or shells
    coding, quantization = choice.coding, choice.quantization
    if not any(len(o.triplets) for o in objects):
        # No plane to code: the coding without an h range in the header.
        coding, quantization = Coding.FLOAT32, None
    table = quantize.roundtrip(np.concatenate([o.triplets for o in objects]).reshape(-1, 3), coding, quantization)
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
    stored = coding
    if compact and stored.quantized:
        stored = min((Coding.QUANTIZED, Coding.PREDICTED), key=lambda c: _table_bytes(rows, c, quantization, compress))
    by_node = {i: (o, a) for i, o, a in zip(meshes, objects, offsets)}
    placed = {i: _placed(o, global_index[a:a + len(o.triplets)], compact) for i, (o, a) in by_node.items()}
    version = _version(objects, major) if compact else (1, 0)
    if version[0] == 4 and _repeats([p for groups in placed.values() for p in groups], verify):
        version = max(version, records.KIND_VERSION[int(GroupKind.COPY)])
    header = Header(version=version, lossy=choice.lossy, coding=stored,
                    quantization=quantization, units=scene.units, bbox=choice.bbox,
                    tolerance=float(tolerance), error_bound=choice.error_bound,
                    plane_count=len(rows), object_count=len(scene.nodes),
                    group_count=sum(len(o.groups) for o in objects),
                    up_axis=scene.up_axis if version[0] >= 5 else None)
    # An index gives a small file no random access worth its bytes: compact files leave it to the writer.
    index = True if not compact else None
    # Shells decode the same without a bbox; polytopes' merge distance is capped by it (spec §9.4).
    small = SMALL_SHELLS_BYTES if all(g.kind in SHELL_KINDS for o in objects for g in o.groups) \
        else SMALL_SEGMENT_BYTES
    with _writer(target, header, compress, index, verify, brotli, small, segment_quality) as w:
        if scene.up_axis is not None and version[0] < 5:
            w.add_metadata(UP_AXIS, scene.up_axis)
        for i, node in enumerate(scene.nodes):
            obj_index = w.add_object(node.name, node.parent, node.transform)
            if i not in by_node:
                continue
            o, a = by_node[i]
            refs = global_index[a:a + len(o.triplets)]
            if len(refs) and refs.max() >= w.plane_count:
                w.add_planes(rows[w.plane_count:refs.max() + 1])
            for p, group_refs, bounding, local in placed[i]:
                k = w.add_group(obj_index, p.kind, group_refs, bounding, cells=p.cells, tree=p.tree,
                                vertex_planes=p.vertex_planes, facets=p.facets, shell=p.shell)
                if o.plane_colours is not None:
                    # A group without references takes the object's one colour (spec §10.1).
                    w.add_colours(k, o.plane_colours[local] if len(local) else o.plane_colours[:1])
    return header


def _unreferenced(o: _Object) -> _Object:
    """``o`` without planes where its groups are shell trees or walks over explicit corners only, in one
    colour or none: their triangles' planes name no corner, so all may be free, and version 5 lets such
    a group have no reference (spec §9.2) and one colour for all its triangles (§10.1), where 4 kept
    a reference for its colour (a plane block and a 16-byte h range in the header)."""
    colours = o.plane_colours
    if (colours is not None and (colours != colours[:1]).any()) or not all(
            g.kind in TREE_KINDS and g.shell is not None and np.all(g.shell.explicit) for g in o.groups):
        return o

    def free(shell: Shell) -> Shell:
        facets = np.array(shell.facets, dtype=np.int64)
        facets[:, 0] = FREE
        return replace(shell, facets=facets)

    none = np.zeros(0, dtype=np.int64)
    return replace(o, triplets=o.triplets[:0], face_plane=None, plane_colours=None if colours is None else colours[:1],
                   groups=tuple(replace(g, refs=none, bounding=np.zeros(0, dtype=bool), shell=free(g.shell))
                                for g in o.groups))


def _placed(o: _Object, refs: np.ndarray, compact: bool) -> list[tuple[GroupSpec, np.ndarray, np.ndarray, np.ndarray]]:
    """``o``'s groups as written, its planes at table indices ``refs``: each group with its references
    in increasing order where ``compact`` (version 2 and later), its references in the table, its role
    bits and its local references in that order."""
    out = []
    for g in o.groups:
        perm = np.argsort(refs[g.refs], kind="stable") if compact else np.arange(len(g.refs))
        out.append((_permuted(g, perm), refs[g.refs[perm]], g.bounding[perm], g.refs[perm]))
    return out


def _repeats(placed: list[tuple[GroupSpec, np.ndarray, np.ndarray, np.ndarray]], decide: bool = True) -> bool:
    """Whether two of the groups ``placed`` (group, references, role bits, local references) have one
    kind, one common body and one kind data: the writer of version 4.2 writes the later a copy (spec
    §9.15). ``decide``: :func:`records.group_body`'s (a size trial's writer asks for no Brotli decision,
    so neither does this)."""
    # Only groups of one kind on the same references and role bits can repeat: their bodies alone are made.
    alike: dict[tuple, list] = {}
    for p, refs, bounding, _ in placed:
        alike.setdefault((int(p.kind), np.asarray(refs).tobytes(), np.asarray(bounding).tobytes()), []).append(p)
    for (kind, _, _), groups in alike.items():
        if len(groups) > 1:
            bodies = [records.group_body(PartGroup(index=0, object=0, kind=kind, refs=np.zeros(0, dtype=np.uint32),
                                                   bounding=np.zeros(0, dtype=bool), cells=p.cells, tree=p.tree,
                                                   vertex_planes=p.vertex_planes, facets=p.facets, shell=p.shell),
                                         decide)
                      for p in groups]
            if len(set(bodies)) < len(bodies):
                return True
    return False


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
    shell = None if g.shell is None else (reordered_tree if g.kind in TREE_KINDS else reordered)(g.shell, local)
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


def _as_tree(g: GroupSpec) -> GroupSpec:
    """``g``, a shell walk (version 4.1 or 4.2) written as the shell tree it is for readers of 3.x:
    kind 7 or 8, whichever deflates smaller."""
    if g.kind not in shellwalk.WALK_KINDS:
        return g
    bodies = shellfields.shell_tree_bodies(g.shell)
    return replace(g, kind=min(bodies, key=lambda k: len(zlib.compress(bodies[k], 9))))


def _unreflected(g: GroupSpec) -> GroupSpec:
    """``g``, a shell walk with reflections or steps from the later gate corner (versions 5.1, 5.2)
    written for readers of 4.x: kind 9 or 10, whichever codes it smaller (the corners are the same, so is
    the bound)."""
    if g.kind not in (GroupKind.SHELL_WALK_REFLECT, GroupKind.SHELL_WALK_LATER):
        return g
    return replace(g, kind=shellwalk.shell_walk_choice(g.shell, shellwalk.WALK_KINDS[:2])[0])


def _version(objects: list[_Object], major: int) -> tuple[int, int]:
    """The lowest minor version of ``major`` (4, or 3 for readers of 3.x: spec A.3) whose kinds hold
    every group (spec §11)."""
    return max((records.KIND_VERSION.get(int(g.kind), (major, 0)) for o in objects for g in o.groups
                if records.KIND_VERSION.get(int(g.kind), (0, 0))[0] == major), default=(major, 0))


def _writer(target: str | os.PathLike | BinaryIO, header: Header, compress: bool, index: bool | None = True,
            verify: bool = True, brotli: bool = True, small_segment: int = SMALL_SEGMENT_BYTES,
            segment_quality: int | None = None) -> Writer:
    # Candidates measured for their sizes are deflated only (``brotli`` off): Brotli's densest quality
    # would triple King_geom.usd's encode (1.8 s to 5.9 s) for a ranking deflate mostly gives as well.
    return Writer(target, header, compress=compress, index=index, verify=verify, brotli=brotli,
                  small_segment=small_segment, segment_quality=segment_quality)
