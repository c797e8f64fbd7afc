"""Geometry checks of a .pln file: :func:`validate` runs the container's checks
(:func:`planefmt.container.validate.validate`) and, with ``geometry=True``, decodes every part
group (:func:`check_group`), so that empty and unbounded polytopes and redundant planes are found too.
"""

from __future__ import annotations

import os
from typing import BinaryIO

from ..container import records
from ..container import validate as container
from ..container.chunks import Limits
from ..container.reader import Reader
from ..container.validate import Finding
from ..errors import CODES, GeometryError, LimitError
from ..model import GroupKind, PartGroup
from .decoding import DECODERS, decode_group, header_plane_error


def check_group(group: PartGroup, reader: Reader) -> list[Finding]:
    """Geometry findings of one part group (spec §9, §12.3).

    ``EMPTY_POLYTOPE`` / ``UNBOUNDED_POLYTOPE`` errors, one ``REDUNDANT_PLANE``
    warning per plane of a convex group that bounds no face. Kinds without a
    decoder yet get one ``GEOMETRY_NOT_CHECKED`` note. What a group decodes to is charged to the reader's
    budget (spec §12.4: ``LimitError`` past it); a copy of a group checked already is charged its source's
    output without decoding it again.
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
    budget = reader.budget
    try:
        if group.source is not None and group.source in budget.decoded:
            budget.charge_decoded(group, *budget.decoded[group.source])
            return []
        try:
            decoded = decode_group(group.planes, group, group.index,
                                   header_plane_error(reader.header), budget.triangles_left)
        except GeometryError as exc:
            return [Finding(exc.code, CODES[exc.code].severity, exc.reason, **where)]
        budget.charge_decoded(group, len(decoded.vertices), len(decoded.triangles))
    except LimitError as exc:
        raise exc.located(file=reader.name, chunk="GRUP")
    return [Finding("REDUNDANT_PLANE", CODES["REDUNDANT_PLANE"].severity,
                    f"part group {group.index}: plane {int(group.refs[j])} (reference {int(j)}) bounds no face",
                    **where) for j in decoded.redundant]


def validate(source: str | os.PathLike | BinaryIO, *, geometry: bool = True,
             limits: Limits | None = None) -> list[Finding]:
    """All findings for ``source``, its part groups decoded unless ``geometry`` is False; an empty
    list means a conforming file."""
    return container.validate(source, checks=(check_group,) if geometry else (), limits=limits)
