"""Decoding files and part groups into meshes and scenes: :func:`decode_scene` (streaming, in
batches of groups), :func:`decode_mesh`, and :func:`salvage_scene` for the intact part of a
damaged file.
"""

from __future__ import annotations

import hashlib
import os
import warnings
from collections.abc import Iterable, Sequence
from typing import BinaryIO

import numpy as np

from ..container import quantize, records
from ..container.budget import Budget
from ..container.chunks import Limits
from ..container.reader import Reader
from ..container.salvage import salvage
from ..errors import FormatError, GeometryError, LimitError, PlnError, SkippedGroupsWarning
from ..geometry.planes import transform_points
from ..model import UP_AXIS, Colours, Header, Mesh, Metadata, Node, ObjectRecord, PartGroup, Scene, Units
from .decoding import (DecodedGroup, EXACT, GroupLike, _concatenate, decode_group, decode_groups, header_plane_error,
                       plane_error)
from .encoding import Encoded
from .preparing import _world_transforms


#: Part groups a reader holds before decoding them together (:func:`decode_groups`), and the references
#: they may hold in all: what the groups of one batch produce before the budget (spec §12.4) is checked
#: is bounded by their planes (a convex polytope of m planes has at most 2m - 4 corners).
_DECODE_BATCH = 4096
_DECODE_BATCH_REFS = 1 << 16


def decode_mesh(source: Encoded | np.ndarray | str | os.PathLike | BinaryIO,
                groups: Iterable[GroupLike] | None = None, *, header: Header | None = None,
                limits: Limits | None = None) -> Mesh:
    """Triangles: of a .pln file (``decode_mesh("model.pln")``, a path or binary stream: every object in
    world coordinates, as one mesh), or of part groups (``decode_mesh(triplets, groups, header=...)`` or
    ``decode_mesh(encoded)``).

    ``triplets`` (n, 3) is the plane table the groups' ``refs`` index, as a
    reader returns it; ``header`` (its coding) sets the plane error the
    decoder allows for (exact planes without it). For an :class:`Encoded`,
    its planes go through the coding first, so the result is what a reader
    of its file decodes. Raises ``GeometryError`` (e.g. ``EMPTY_POLYTOPE``,
    ``UNBOUNDED_POLYTOPE``) naming the group, and for a file whatever
    :func:`decode_scene` raises; ``limits`` as :func:`decode_scene`'s (a file only: groups in
    memory are the caller's own).
    """
    if isinstance(source, (str, os.PathLike)) or hasattr(source, "read"):
        return _world_mesh(decode_scene(source, limits=limits))
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


def decode_scene(source: str | os.PathLike | BinaryIO, *, limits: Limits | None = None) -> Scene:
    """Read a .pln file into a :class:`Scene`: one node per object, its groups decoded and joined.

    Streams: part groups are decoded in batches of up to 4096 as they are read; a copy (spec §9.15)
    reuses its source's decoding. Groups of a kind from a newer minor version are skipped, as spec
    §13 asks of a reader, with one :class:`PlnWarning` naming them. ``limits`` (spec §12.4) bound
    what the file may make the reader produce: with the defaults, 2**22 triangles and vertices in
    all; more is ``LimitError`` (``LIMIT_EXCEEDED``) before the memory is spent.
    """
    parts: dict[int, list[tuple[int, DecodedGroup]]] = {}
    colours: dict[int, np.ndarray] = {}
    pending: list[PartGroup] = []
    skipped: list[PartGroup] = []
    # Every group decoded so far, by index: the surfaces copies reuse (held by ``parts`` in any case).
    decoded: dict[int, DecodedGroup] = {}

    def flush() -> None:
        fresh = [g for g in pending if g.source is None]
        try:
            batch = decode_groups([(g.planes, g, g.index) for g in fresh], error, r.budget.triangles_left)
        except LimitError as exc:
            raise exc.located(file=r.name, chunk="GRUP")
        for g, d in zip(fresh, batch):
            decoded[g.index] = d
        for g in pending:
            d = decoded[g.index if g.source is None else g.source]
            try:
                r.budget.charge_decoded(g, len(d.vertices), len(d.triangles))
            except PlnError as exc:
                raise exc.located(file=r.name, chunk="GRUP")
            parts.setdefault(g.object, []).append((g.index, d))
        pending.clear()

    with Reader(source, limits=limits) as r:
        error = header_plane_error(r.header)
        known = records.kinds_of(*r.header.version)
        held = 0
        for rec in r:
            if isinstance(rec, PartGroup):
                if int(rec.kind) not in known:
                    skipped.append(rec)
                    continue
                # Decoded in batches of groups read (patches together), bounding what is held.
                pending.append(rec)
                held += len(rec.refs)
                if len(pending) >= _DECODE_BATCH or held >= _DECODE_BATCH_REFS:
                    flush()
                    held = 0
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


def salvage_scene(source: str | os.PathLike | BinaryIO, *, limits: Limits | None = None) -> tuple[Scene, list[str]]:
    """What :func:`decode_scene` gives for the intact part of a damaged file, and what was lost.

    Reads through :func:`planefmt.container.salvage.salvage`: every intact object and
    part group is kept, a group that no longer decodes (its planes were
    damaged into an empty or unbounded set) joins the losses, and so does a group past ``limits``
    (:func:`decode_scene`'s). Raises ``FormatError`` (``MISSING_HEADER``) when no header survived.
    """
    limits = limits or Limits()
    budget = Budget(limits)
    got = salvage(source, limits=limits, budget=budget)
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
    decoded: dict[int, DecodedGroup] = {}
    refs = {g.index: (g.refs, g.bounding) for g in got.part_groups}
    for g in (g for g in got.part_groups if int(g.kind) in known):
        try:
            if g.source is None:
                d = decoded[g.index] = decode_group(g.planes, g, g.index, error, budget.triangles_left)
                budget.charge_decoded(g, len(d.vertices), len(d.triangles))
            elif g.source in decoded and all(np.array_equal(a, b) for a, b in zip(refs[g.source], refs[g.index])):
                # a copy (spec §9.15) of a group salvaged, with its references and roles: its surface
                d = decoded[g.source]
                budget.charge(g.index, vertices=len(d.vertices), triangles=len(d.triangles))
            else:
                raise GeometryError(f"part group {g.index}: a copy of group {g.source}, lost or with other "
                                    "references",
                                    code="BAD_GROUP_STRUCTURE")
            parts.setdefault(g.object, []).append((g.index, d))
        except (GeometryError, LimitError) as exc:
            lost.append(f"part group {g.index} lost: {exc.reason}")
    colours = {r.group: r.rgba for r in got.records if isinstance(r, Colours)}
    up = [got.header.up_axis] + [r.value for r in got.records if isinstance(r, Metadata) and r.key == UP_AXIS]
    return _assemble(objects, parts, got.header.units, colours, next((u for u in up if u), None)), lost


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
    # A lone mesh shares with nothing: hashing it took 6 % of bun_zipper.ply's decode.
    alone = sum(o.index in parts for o in objects) < 2

    def shared(mesh: Mesh) -> Mesh:
        if alone:
            return mesh
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
