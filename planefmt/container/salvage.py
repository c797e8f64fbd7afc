"""Recover what is intact from a damaged .pln file (``pln info --salvage``).

The streaming reader stops at the first error, as the spec requires. Salvage
is the opposite trade: it reads the whole input into memory, walks the chunk
framing, and when a chunk is damaged it reports the loss and resynchronizes
on the next position where a known chunk type is followed by a length that
fits and a matching CRC. Every object, plane block and part group that is
intact and whose dependencies (its object, the planes it references) are
intact is recovered; everything else is listed in ``losses``.

Version 6 (spec §4.5): a damaged body segment loses all its records. Records carry no index there (an
object's, a plane's or a group's is its position), so the records of later segments are placed by the
file's iNDX where it is intact; without it they are lost too, and said so.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass, field
from typing import BinaryIO

import construct as cs
import numpy as np

from ..errors import FormatError, PlnError
from ..model import Header, ObjectRecord, PartGroup, Record, UnknownChunk
from . import records, schema, segments
from .budget import Budget
from .chunks import Limits, RawChunk, check_signature, is_ancillary, type_name, valid_type
from .crc import crc32

_KNOWN = (schema.PHDR, schema.OBJT, schema.PLNS, schema.GRUP, schema.COLR, schema.META, schema.INDX, schema.PEND,
          schema.BODY)


@dataclass(frozen=True)
class Loss:
    """Something salvage could not recover: an error code, what was lost, and where."""

    code: str
    message: str
    offset: int | None


@dataclass
class Salvaged:
    """The recovered records in file order and the list of losses."""

    header: Header | None
    records: list[Record] = field(default_factory=list)
    losses: list[Loss] = field(default_factory=list)

    @property
    def part_groups(self) -> list[PartGroup]:
        return [r for r in self.records if isinstance(r, PartGroup)]


def salvage(source: str | os.PathLike | BinaryIO, *, limits: Limits | None = None,
            max_bytes: int = 1 << 31, budget: Budget | None = None) -> Salvaged:
    """Recover every intact record of ``source`` (a path or binary stream) and report the rest; a group
    whose declared counts would pass ``budget`` (spec §12.4) is lost."""
    limits = limits or Limits()
    if isinstance(source, (str, os.PathLike)):
        with open(source, "rb") as f:
            data = f.read(max_bytes + 1)
    else:
        data = source.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise PlnError(f"salvage reads at most {max_bytes} bytes", code="LIMIT_EXCEEDED")
    return _Salvager(data, limits, budget or Budget(limits)).run()


class _Salvager:
    def __init__(self, data: bytes, limits: Limits, budget: Budget) -> None:
        self.data = data
        self.limits = limits
        self.budget = budget
        self.out = Salvaged(header=None)
        self.table = np.empty((0, 3))
        self.lost_planes = np.zeros(0, dtype=bool)
        self.objects = 0
        self.object_ok: set[int] = set()  # indices of the objects recovered
        self.groups = 0
        self.group_refs: dict[int, int] = {}
        # Version 6: whether the positions of later records are unknown (a segment was lost), and the
        # index's entries where it could be read (spec §10.2), which give them back.
        self.unplaced = False
        self.entries: list[segments.Entry] | None = None

    def lose(self, code: str, message: str, offset: int | None) -> None:
        self.out.losses.append(Loss(code, message, offset))

    def _lose_run(self, code: str, what: str, first: int, end: int, offset: int) -> None:
        """One loss for records ``first``..``end - 1`` missing: a damaged index can claim billions."""
        if end - first == 1:
            self.lose(code, f"{what} {first} lost", offset)
        elif end > first:
            self.lose(code, f"{what}s {first}..{end - 1} lost", offset)

    def run(self) -> Salvaged:
        sig = self.data[: len(schema.SIGNATURE)]
        try:
            check_signature(sig)
            pos = len(schema.SIGNATURE)
        except FormatError as exc:
            self.lose(exc.code, exc.reason, 0)
            pos = 0
        while pos < len(self.data):
            chunk = self._chunk_at(pos)
            if chunk is None:
                after = self._framed(pos)
                if after is not None and (after == len(self.data) or self._chunk_at(after) is not None):
                    # Framing is intact (the next chunk starts where the length says): only this one is lost.
                    self.lose("CRC_MISMATCH", f"chunk {type_name(self.data[pos:pos + 4])} lost: CRC mismatch", pos)
                    self._lost_chunk()
                    pos = after
                    continue
                nxt = self._resync(pos + 1)
                self.lose("BAD_PAYLOAD",
                          f"damaged bytes {pos}..{(nxt if nxt is not None else len(self.data)) - 1} skipped", pos)
                self._lost_chunk()
                if nxt is None:
                    break
                pos = nxt
                continue
            pos = chunk.end
            if chunk.type == schema.PEND:
                if pos != len(self.data):
                    self.lose("TRAILING_DATA", f"{len(self.data) - pos} bytes after PEND ignored", pos)
                return self._finish()
            try:
                self._take(chunk)
            except PlnError as exc:
                self.lose(exc.code, f"chunk {chunk.name} lost: {exc.reason}", chunk.offset)
        self.lose("TRUNCATED", "the file ends without PEND", len(self.data))
        return self._finish()

    def _finish(self) -> Salvaged:
        h = self.out.header
        if h is not None and h.group_count is not None and self.groups < h.group_count:
            self.lose("COUNT_MISMATCH", f"part groups {self.groups}..{h.group_count - 1} lost", None)
        return self.out

    def _heads(self, pos: int) -> list[tuple[int, int]]:
        """(length, head bytes) of each framing that may stand at ``pos``: PHDR's u32, version 5's varint
        after it, and both while no header is known (spec §4.1)."""
        ctype = self.data[pos:pos + 4]
        if len(ctype) < 4 or not valid_type(ctype):
            return []
        h = self.out.header
        out = []
        if ctype == schema.PHDR or h is None or h.version[0] < 5:
            if pos + 8 <= len(self.data):
                out.append((int.from_bytes(self.data[pos + 4:pos + 8], "little"), 8))
        if ctype != schema.PHDR and (h is None or h.version[0] >= 5):
            try:
                length = schema.Varint32.parse(self.data[pos + 4:pos + 4 + schema.LENGTH_VARINT_BYTES])
                out.append((length, 4 + len(schema.Varint32.build(length))))
            except cs.ConstructError:
                pass
        return out

    def _framed(self, pos: int) -> int | None:
        """Where the next chunk starts if a valid type and a length that fits stand at ``pos``."""
        for length, head in self._heads(pos):
            after = pos + head + length + 4
            if after <= len(self.data):
                return after
        return None

    def _chunk_at(self, pos: int) -> RawChunk | None:
        for length, head in self._heads(pos):
            end = pos + head + length
            if length > self.limits.max_chunk_length or end + 4 > len(self.data):
                continue
            payload = self.data[pos + head:end]
            if crc32(payload, crc32(self.data[pos:pos + 4])) == int.from_bytes(self.data[end:end + 4], "little"):
                return RawChunk(self.data[pos:pos + 4], payload, pos, head + 4)
        return None

    def _resync(self, start: int) -> int | None:
        """The first offset >= start where a known chunk type begins an intact chunk."""
        candidates = sorted(p for t in _KNOWN for p in _find_all(self.data, t, start))
        for p in candidates:
            if self._chunk_at(p) is not None:
                return p
        return None

    def _take(self, chunk: RawChunk) -> None:
        t = chunk.type
        if t == schema.PHDR:
            if self.out.header is None:
                self.out.header, _ = records.decode_header(chunk.payload)
                if self.out.header.version[0] >= 6:
                    self.entries = self._index6()
                    start = records.decode_header6(chunk.payload)[2]
                    if start < len(chunk.payload):
                        self._take_segment(chunk, start)
            return
        if self.out.header is None:
            raise FormatError("no intact PHDR before this chunk", code="MISSING_HEADER")
        if self.out.header.version[0] >= 6:
            if t == schema.BODY:
                self._take_segment(chunk, 0)
                return
            if t in schema.RECORD_CHUNKS:
                raise FormatError(f"a {type_name(t)} chunk in a version 6 file", code="CHUNK_ORDER")
        if t == schema.OBJT:
            self._take_object(chunk)
        elif t == schema.PLNS:
            self._take_planes(chunk)
        elif t == schema.GRUP:
            self._take_group(chunk)
        elif t == schema.COLR:
            self.out.records.append(records.decode_colours(chunk.payload, self.group_refs, self.out.header.version[0]))
        elif t == schema.META:
            # Salvage keeps what it can read wherever it is: a late or repeated keyword is no loss.
            self.out.records.append(records.decode_metadata(chunk.payload))
        elif t == schema.INDX:
            return
        elif is_ancillary(t):
            self.out.records.append(UnknownChunk(t, bytes(chunk.payload), chunk.offset))
        else:
            raise FormatError(f"unknown critical chunk {type_name(t)}", code="UNKNOWN_CRITICAL_CHUNK")

    def _lost_chunk(self) -> None:
        """Version 6: a lost chunk may have been a body segment, after which records are not placed."""
        h = self.out.header
        if h is not None and h.version[0] >= 6:
            self.unplaced = True

    def _index6(self) -> list[segments.Entry] | None:
        """The entries of a version 6 file's iNDX, found through its PEND (spec §4.4), or None."""
        end = self.data[-17:]
        if len(end) < 17 or end[:4] != schema.PEND or end[4] != 8:
            return None
        at = int.from_bytes(end[5:13], "little")
        chunk = self._chunk_at(at) if at < len(self.data) else None
        if chunk is None or chunk.type != schema.INDX:
            return None
        try:
            return segments.decode_index(chunk.payload)
        except PlnError:
            return None

    def _take_segment(self, chunk: RawChunk, start: int) -> None:
        """The records of a version 6 body segment: all lost where it is damaged (spec §4.5)."""
        if self.unplaced and not self._place(chunk.offset):
            raise FormatError("an earlier segment was lost and the file has no intact index: the indices of "
                              "this segment's records are unknown", code="BAD_INDEX")
        try:
            raw = segments.segment_raw(memoryview(chunk.payload)[start:], self.limits)
            views = list(segments.records(raw))
        except PlnError:
            self.unplaced = True
            raise
        header = self.out.header
        for view in views:
            t = schema.RECORD_TYPES.get(view.tag)
            try:
                if t == schema.OBJT:
                    self._take_object(RawChunk(t, view.payload, chunk.offset), self.objects)
                elif t == schema.PLNS:
                    self._take_planes(RawChunk(t, view.payload, chunk.offset), len(self.lost_planes))
                elif t == schema.GRUP:
                    self._take_group(RawChunk(t, view.payload, chunk.offset), self.groups)
                elif t == schema.COLR:
                    self.out.records.append(records.decode_colours(view.payload, self.group_refs, 6))
                elif t == schema.META:
                    self.out.records.append(records.decode_metadata(view.payload))
                elif view.tag >= schema.ANCILLARY_TAG:
                    self.out.records.append(UnknownChunk(bytes([view.tag]), bytes(view.payload), view.offset))
                else:
                    raise FormatError(f"unknown critical record of tag {view.tag}", code="UNKNOWN_CRITICAL_CHUNK")
            except PlnError as exc:
                self.lose(exc.code, f"record {t.decode() if t else view.tag} at raw byte {view.offset} of the "
                          f"{chunk.name} chunk lost: {exc.reason}", chunk.offset)
                if t == schema.OBJT:
                    self.objects += 1
                elif t == schema.GRUP:
                    self.groups += 1
                elif t == schema.PLNS:
                    try:
                        count = records.leading_index(view.payload, header.version[0], 0)
                        self._grow(len(self.lost_planes) + count, lost=True)
                    except PlnError:
                        self.unplaced = True

    def _place(self, chunk_offset: int) -> bool:
        """Version 6: the object, plane and group counts before the segment of the chunk at ``chunk_offset``,
        from the index's first entry of each tag at or after it; False without an index."""
        if self.entries is None:
            return False
        later = [e for e in self.entries if e[0] >= chunk_offset]
        earlier = [e for e in self.entries if e[0] < chunk_offset]

        def first(tag: int) -> int | None:
            return next((e[3] for e in later if e[2] == tag), None)

        objects = first(schema.TAG_OBJECT)
        groups = first(schema.TAG_GROUP)
        planes = first(schema.TAG_PLANES)
        self.objects = objects if objects is not None else 1 + max(
            (e[3] for e in earlier if e[2] == schema.TAG_OBJECT), default=-1)
        self.groups = groups if groups is not None else 1 + max(
            (e[3] for e in earlier if e[2] == schema.TAG_GROUP), default=-1)
        if planes is not None and planes > len(self.lost_planes):
            self._grow(planes, lost=True)
        self.unplaced = False
        return True

    def _take_object(self, chunk: RawChunk, index: int | None = None) -> None:
        if index is None:
            index = records.leading_index(chunk.payload, self.out.header.version[0], 4)
        if index < self.objects or index > self.limits.max_objects:
            raise FormatError(f"object index {index} out of sequence", code="BAD_OBJECT")
        self._lose_run("BAD_OBJECT", "object", self.objects, index, chunk.offset)
        self.object_ok.add(index)
        self.objects = index + 1
        obj = records.decode_object(chunk.payload, index, self.out.header.version[0])
        if obj.parent is not None and obj.parent not in self.object_ok:
            obj = ObjectRecord(obj.index, obj.name, None, obj.transform)
            self.lose("BAD_OBJECT", f"object {index} ({obj.name!r}) lost its parent; kept as a root", chunk.offset)
        self.out.records.append(obj)

    def _take_planes(self, chunk: RawChunk, first: int | None = None) -> None:
        if first is None:
            first = records.leading_index(chunk.payload, self.out.header.version[0], 8)
        have = len(self.lost_planes)
        if first < have or first > self.limits.max_planes:
            raise FormatError(f"plane block at {first} overlaps or is out of range", code="PLANE_INDEX_MISMATCH")
        if first > have:
            self.lose("PLANE_INDEX_MISMATCH", f"planes {have}..{first - 1} lost", chunk.offset)
            self._grow(first, lost=True)
        block = records.decode_planes(chunk.payload, self.out.header, first, self.limits)
        self._grow(first + len(block.triplets), lost=False)
        self.table[first:first + len(block.triplets)] = block.triplets
        self.out.records.append(block)

    def _grow(self, n: int, *, lost: bool) -> None:
        extra = n - len(self.lost_planes)
        self.table = np.concatenate([self.table, np.full((extra, 3), np.nan)])
        self.lost_planes = np.concatenate([self.lost_planes, np.full(extra, lost)])

    def _take_group(self, chunk: RawChunk, index: int | None = None) -> None:
        if index is None:
            index = records.leading_index(chunk.payload, self.out.header.version[0], 4)
        if index < self.groups:
            raise FormatError(f"group index {index} out of sequence", code="GROUP_INDEX_MISMATCH")
        self._lose_run("GROUP_INDEX_MISMATCH", "part group", self.groups, index, chunk.offset)
        self.groups = index + 1
        group, _ = records.decode_group(chunk.payload, expected_index=index, objects=self.objects,
                                        planes=len(self.lost_planes), minor=self.out.header.version[1],
                                        limits=self.limits, major=self.out.header.version[0], budget=self.budget)
        if group.object not in self.object_ok:
            raise FormatError(f"part group {index} belongs to lost object {group.object}",
                              code="BAD_OBJECT_REFERENCE")
        if self.lost_planes[group.refs].any():
            raise FormatError(f"part group {index} references lost planes", code="BAD_PLANE_REFERENCE")
        self.group_refs[index] = len(group.refs)
        self.out.records.append(dataclasses.replace(group, planes=self.table[group.refs]))


def _find_all(data: bytes, tag: bytes, start: int):
    pos = data.find(tag, start)
    while pos != -1:
        yield pos
        pos = data.find(tag, pos + 1)


__all__ = ["Loss", "Salvaged", "salvage"]
