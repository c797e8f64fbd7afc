"""Streaming reader of .pln files (spec §4–§12).

``open()`` reads the signature and header at once and everything else lazily:
iterating yields records one at a time in file order, with memory bounded by
the largest chunk (plus the plane table when ``retain_planes`` is set, which
part groups need to resolve their planes). Works on pipes and sockets; on
seekable files the trailing index gives random access to part groups.
"""

from __future__ import annotations

import collections
import copy
import dataclasses
import os
import sys
from collections import Counter
from collections.abc import Iterator
from typing import BinaryIO

import numpy as np

from . import records, schema, segments
from .budget import Budget, declared
from .chunks import ChunkStream, Limits, RawChunk, chunk_bytes, is_ancillary
from ..errors import FormatError, PlnError
from ..model import UP_AXIS, GroupKind, ObjectRecord, PartGroup, Record, UnknownChunk


#: Payload bytes of the groups a reader keeps as decoded for later copies (Reader._remember): a scene's
#: copies of small parts (gltf_scene/pins.glb: five of two groups) decoded each source twice.
RECENT_BYTES = 256 * 1024


class Reader:
    """A .pln file opened for reading; see :func:`open`."""

    def __init__(self, source: str | os.PathLike | BinaryIO, *, retain_planes: bool = True,
                 limits: Limits | None = None, name: str | None = None) -> None:
        self._own = isinstance(source, (str, os.PathLike))
        if self._own:
            self.name = name or os.fspath(source)
            self._fp: BinaryIO = builtin_open(source, "rb")
        else:
            self._fp = source
            self.name = name or getattr(source, "name", None) or "<stream>"
            if not isinstance(self.name, str):
                self.name = "<stream>"
        self.limits = limits or Limits()
        #: The output of the groups read so far (spec §12.4): a sealed or shell group is charged as its counts
        #: are read, a copy of one its source's counts; a decoder charges the other kinds as it decodes them.
        self.budget = Budget(self.limits)
        self.retain_planes = retain_planes
        self.findings: list[tuple[str, str]] = []
        self.objects: list[ObjectRecord] = []
        # mETA chunks precede every OBJT, PLNS and GRUP chunk: complete once the first of those is read.
        self.metadata: dict[str, str] = {}
        self.chunk_stats: Counter[str] = Counter()  # payload + framing bytes per chunk type
        self.chunk_counts: Counter[str] = Counter()
        # Version 6: raw bytes (tag, length, payload) and count of the records of each type (spec §4.6).
        self.record_stats: Counter[str] = Counter()
        self.record_counts: Counter[str] = Counter()
        # Version 6: the chunk whose segment is being read, and its raw bytes (spec §4.5).
        self._segment: tuple[RawChunk, bytes | bytearray | memoryview] | None = None
        self._table = np.empty((0, 3), dtype=np.float64)
        self._plane_count = 0
        self._group_refs: dict[int, int] = {}
        # Version 4.2's copies (spec §9.15) name earlier groups: where the file can be read again (a
        # regular file or an in-memory buffer) a source is re-read at its offset, so memory stays that of
        # the largest chunk; a pipe's reader keeps every group's stored payload. And the sources decoded
        # so far.
        self._payloads: dict[int, bytes] = {}
        self._offsets: dict[int, int] = {}
        self._sources: dict[int, PartGroup] = {}
        # The groups read last, as decoded, while their payloads are small (_remember).
        self._recent: collections.OrderedDict[int, tuple[PartGroup, int]] = collections.OrderedDict()
        self._recent_bytes = 0
        self._group_count = 0
        self._done = False
        self._started = False
        self.index_offset: int | None = None
        # (offset, type, ordinal) of every OBJT, PLNS and GRUP chunk so far: what iNDX must list (version 6:
        # (chunk offset, raw offset, tag, ordinal) of every record of tags 1 to 3).
        self._listed: list[tuple] = []
        self._base = _tell(self._fp)
        try:
            self._stream = ChunkStream(self._fp, file=self.name, limits=self.limits)
            self._stream.read_signature()
            first = self._stream.next_chunk()
            if first.type != schema.PHDR:
                raise FormatError(f"first chunk is {first.name}, not PHDR", code="MISSING_HEADER",
                                  chunk=first.name, offset=first.offset)
            self._count(first)
            # Version 6's header also says where its first body segment starts: parsed once for both.
            head = self._located(lambda raw: records.decode_header_at(raw.payload), first)
            self.header, found = head[:2]
            self._after_header = first.end
            self._first = first
            if self.header.version[0] >= 6:
                self._segment_start = head[2]
            # Version 5 frames every chunk after PHDR with a varint length (spec §4.1).
            self._stream.compact = self._compact = self.header.version[0] >= 5
            self.findings.extend(found)
        except BaseException:
            self.close()
            raise

    # -- context manager and iteration ------------------------------------------------------

    def __enter__(self) -> "Reader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the file if this reader opened it (a caller's stream stays open)."""
        if self._own and not self._fp.closed:
            self._fp.close()

    @property
    def up_axis(self) -> str | None:
        """The world axis that points up, ``"Y"`` or ``"Z"`` (spec §5, §10.3), None where the file does not
        say; before version 5, known once the first object, plane block or part group has been read."""
        return self.header.up_axis or self.metadata.get(UP_AXIS)

    @property
    def planes(self) -> np.ndarray:
        """The plane table read so far: ``(n, 3)`` triplets (empty unless ``retain_planes``)."""
        return self._table[: self._plane_count] if self.retain_planes else self._table

    # Counts: the header's where it records them (a file whose chunks disagree fails with COUNT_MISMATCH
    # when read to its end), else what was read so far (a stream's writer may not have known them).

    @property
    def plane_count(self) -> int:
        """Planes in the file's table: the header's count, else those read so far."""
        recorded = self.header.plane_count
        return self._plane_count if recorded is None else max(recorded, self._plane_count)

    @property
    def group_count(self) -> int:
        """Part groups in the file: the header's count, else those read so far."""
        recorded = self.header.group_count
        return self._group_count if recorded is None else max(recorded, self._group_count)

    @property
    def object_count(self) -> int:
        """Objects in the file: the header's count, else those read so far (``objects`` holds the records
        read so far: object records follow the header, so they are known only once read)."""
        recorded = self.header.object_count
        return len(self.objects) if recorded is None else max(recorded, len(self.objects))

    def __iter__(self) -> Iterator[Record]:
        if self._started:
            raise PlnError("a reader iterates once; open the file again to re-read it", code="CHUNK_ORDER",
                           file=self.name)
        self._started = True
        if self.header.version[0] >= 6:
            yield from self._records6()
            return
        while not self._done:
            raw = self._stream.next_chunk()
            self._count(raw)
            record = self._located(self._dispatch, raw)
            if record is not None:
                yield record

    def _records6(self) -> Iterator[Record]:
        """The records of a version 6 file: those of each body segment in turn, one segment held at a time
        (spec §4.5), then iNDX and PEND."""
        if self._segment_start < len(self._first.payload):
            yield from self._segment_records(self._first, self._segment_start)
        while not self._done:
            raw = self._stream.next_chunk()
            self._count(raw)
            if raw.type == schema.BODY and self.index_offset is None:
                yield from self._segment_records(raw, 0)
            elif raw.type in schema.RECORD_CHUNKS and self.index_offset is None:
                raise FormatError(f"a {raw.name} chunk: a record of a body segment in version 6",
                                  code="CHUNK_ORDER", file=self.name, chunk=raw.name, offset=raw.offset)
            else:
                record = self._located(self._dispatch, raw)
                if record is not None:
                    yield record

    def _segment_records(self, chunk: RawChunk, start: int) -> Iterator[Record]:
        raw = self._located(lambda c: segments.segment_raw(memoryview(c.payload)[start:], self.limits), chunk)
        self._segment = (chunk, raw)
        views = segments.records(raw)
        while True:
            try:
                view = next(views, None)
                if view is None:
                    break
                record = self._record(chunk, view)
            except PlnError as exc:
                raise exc.located(file=self.name, chunk=chunk.name, offset=chunk.offset)
            if record is not None:
                yield record
        self._segment = None

    def _record(self, chunk: RawChunk, view: segments.RecordView) -> Record | None:
        """One record of a segment (spec §4.6 checks 3 to 5), as the chunk of version 5 it replaces."""
        t = schema.RECORD_TYPES.get(view.tag)
        name = t.decode() if t else f"tag {view.tag}"
        self.record_stats[name] += view.size
        self.record_counts[name] += 1
        if t is None:
            if view.tag >= schema.ANCILLARY_TAG:
                self.findings.append(("UNKNOWN_ANCILLARY_CHUNK", f"skipped record of tag {view.tag} at raw byte "
                                      f"{view.offset} of the {chunk.name} chunk at byte {chunk.offset}"))
                return UnknownChunk(type=bytes([view.tag]), payload=bytes(view.payload), offset=view.offset)
            raise FormatError(f"unknown critical record of tag {view.tag} at raw byte {view.offset}",
                              code="UNKNOWN_CRITICAL_CHUNK")
        try:
            return self._payload(t, view.payload, (chunk.offset, view.offset))
        except PlnError as exc:
            exc.reason = f"{exc.reason} (record {name} at raw byte {view.offset} of the segment)"
            raise

    def records(self) -> Iterator[Record]:
        """Every record in file order (same as iterating the reader)."""
        return iter(self)

    def part_groups(self) -> Iterator[PartGroup]:
        """Part groups one at a time, with ``planes`` resolved when planes are retained."""
        for record in self:
            if isinstance(record, PartGroup):
                yield record

    def read_all(self) -> list[Record]:
        return list(self)

    # -- dispatch --------------------------------------------------------------------------

    def _count(self, raw: RawChunk) -> None:
        self.chunk_stats[raw.name] += len(raw.payload) + raw.framing
        self.chunk_counts[raw.name] += 1

    def _located(self, fn, raw: RawChunk):
        try:
            return fn(raw)
        except PlnError as exc:
            raise exc.located(file=self.name, chunk=raw.name, offset=raw.offset)

    def _listing(self, where: tuple[int, int] | int, t: bytes, ordinal: int) -> tuple:
        """What iNDX lists for a record (spec §10.2): version 6, (chunk offset, raw offset, tag, ordinal)."""
        if isinstance(where, tuple):
            return (*where, schema.RECORD_TAGS[t], ordinal)
        return (where, t, ordinal)

    def _dispatch(self, raw: RawChunk) -> Record | None:
        t = raw.type
        if self.index_offset is not None and t != schema.PEND:
            raise FormatError(f"{raw.name} after iNDX: iNDX must be followed by PEND", code="CHUNK_ORDER")
        return self._payload(t, raw.payload, raw.offset)

    def _payload(self, t: bytes, payload: bytes, where: tuple[int, int] | int) -> Record | None:
        """A chunk of type ``t``, or the record of version 6 that replaces it, at ``where``: a chunk's offset,
        or a record's (chunk offset, raw offset)."""
        if t == schema.PLNS:
            self._listed.append(self._listing(where, t, self._plane_count))
            block = records.decode_planes(payload, self.header, self._plane_count, self.limits)
            self._append_planes(block.triplets)
            return block
        if t == schema.OBJT:
            if len(self.objects) >= self.limits.max_objects:
                raise PlnError(f"more than {self.limits.max_objects} objects", code="LIMIT_EXCEEDED")
            self._listed.append(self._listing(where, t, len(self.objects)))
            obj = records.decode_object(payload, len(self.objects), self.header.version[0])
            self.objects.append(obj)
            return obj
        if t == schema.GRUP:
            group, found = records.decode_group(
                payload, expected_index=self._group_count, objects=len(self.objects),
                planes=self._plane_count, minor=self.header.version[1], limits=self.limits,
                major=self.header.version[0], budget=self.budget)
            self.findings.extend(found)
            self._listed.append(self._listing(where, t, group.index))
            self._group_refs[group.index] = len(group.refs)
            self._group_count += 1
            if int(GroupKind.COPY) in records.kinds_of(*self.header.version):
                if self._rereadable:
                    self._offsets[group.index] = where
                else:
                    self._payloads[group.index] = bytes(payload)
                if group.kind != GroupKind.COPY:
                    self._remember(group, len(payload))
            # a kind-11 group of a file whose version has no copies (a newer minor of major 3: fuzz
            # input py-foreign-44153) is skipped, with no source to read
            if group.kind == GroupKind.COPY and group.source is not None:
                group = self._copied(group)
            if self.retain_planes:
                group = _with_planes(group, self._table[group.refs])
            return group
        if t == schema.COLR:
            return records.decode_colours(payload, self._group_refs, self.header.version[0])
        if t == schema.META:
            if self._listed:
                raise FormatError("mETA after an OBJT, PLNS or GRUP chunk: metadata precedes the geometry",
                                  code="BAD_METADATA")
            meta = records.decode_metadata(payload)
            if meta.key == UP_AXIS and self.header.version[0] >= 5:
                raise FormatError("a version 5 file says its up axis in the header, not in mETA", code="BAD_METADATA")
            if meta.key in self.metadata:
                raise FormatError(f"a second mETA {meta.key}", code="BAD_METADATA")
            self.metadata[meta.key] = meta.value
            return meta
        raw = RawChunk(t, payload, where)
        if t == schema.INDX:
            self.index_offset = raw.offset
            if self.header.version[0] >= 6:
                self._check_index(segments.decode_index(raw.payload))
            else:
                self._check_index(records.decode_index(raw.payload, raw.offset, self._after_header))
            return None
        if t == schema.PEND:
            self._finish(raw)
            return None
        if t == schema.PHDR:
            raise FormatError("a second PHDR chunk", code="DUPLICATE_HEADER")
        if is_ancillary(t):
            self.findings.append(("UNKNOWN_ANCILLARY_CHUNK", f"skipped chunk {raw.name} at byte {raw.offset}"))
            return UnknownChunk(type=t, payload=bytes(raw.payload), offset=raw.offset)
        raise FormatError(f"unknown critical chunk {raw.name}", code="UNKNOWN_CRITICAL_CHUNK")

    def _remember(self, group: PartGroup, size: int) -> None:
        """Keep a small group just read for the copies that may follow (spec §9.15), which otherwise decode
        its payload again: the latest ones of at most :data:`RECENT_BYTES` of payload in all."""
        if size > RECENT_BYTES:
            return
        self._recent[group.index] = (group, size)
        self._recent_bytes += size
        while self._recent_bytes > RECENT_BYTES:
            _, (_, dropped) = self._recent.popitem(last=False)
            self._recent_bytes -= dropped

    def _copied(self, copy: PartGroup) -> PartGroup:
        """A copy (spec §9.15) as its source group: the source's kind and surface, the copy's index and
        object, ``source`` set; the source read again from its stored payload, or through the index."""
        s = copy.source
        source = self._sources.get(s)
        if source is None and s in self._recent:
            source = self._sources[s] = dataclasses.replace(self._recent[s][0], planes=None)
        if source is None:
            payload = self._payloads.get(s)
            if payload is None and s in self._offsets:
                payload = self._source_payload(self._offsets[s])
            if payload is not None:
                source, _ = records.decode_group(
                    payload, expected_index=s, objects=len(self.objects), planes=self._plane_count,
                    minor=self.header.version[1], limits=self.limits, major=self.header.version[0])
            else:
                source = self.group(s)
            self._sources[s] = source = dataclasses.replace(source, planes=None)
        if source.kind == GroupKind.COPY:
            raise FormatError(f"group {copy.index} copies group {s}, itself a copy", code="BAD_GROUP_STRUCTURE")
        if not (np.array_equal(source.refs, copy.refs) and np.array_equal(source.bounding, copy.bounding)):
            raise FormatError(f"group {copy.index} copies group {s} with other references or role bits",
                              code="BAD_GROUP_STRUCTURE")
        if not isinstance(source.kind, GroupKind):
            self.findings.append(("SKIPPED_GROUP_KIND", f"group {copy.index} copies group {s}, of a kind skipped"))
        counts = declared(source)
        if counts is not None:
            self.budget.charge(copy.index, vertices=counts[0], triangles=counts[1])
        return dataclasses.replace(source, index=copy.index, object=copy.object, source=s)

    @property
    def _rereadable(self) -> bool:
        return self._base is not None and self._stream._size is not None

    def _source_payload(self, where: tuple[int, int] | int) -> bytes:
        """The stored payload of an earlier group: its chunk read again (version 6: the record in its segment,
        the one held where it is that one, else its chunk read and decompressed again)."""
        if isinstance(where, int):
            return self._reread(where).payload
        chunk_offset, raw_offset = where
        if self._segment is not None and self._segment[0].offset == chunk_offset:
            raw = self._segment[1]
        else:
            chunk = self._reread(chunk_offset, (schema.PHDR, schema.BODY))
            start = records.decode_header6(chunk.payload)[2] if chunk.type == schema.PHDR else 0
            raw = segments.segment_raw(memoryview(chunk.payload)[start:], self.limits)
        view = next(segments.records(memoryview(raw)[raw_offset:]))
        return view.payload

    def _reread(self, offset: int, types: tuple[bytes, ...] = (schema.GRUP,)) -> RawChunk:
        """The GRUP chunk at ``offset`` (from the file's start), its CRC checked again; the stream is left
        where it was."""
        here = self._fp.tell()
        try:
            # PHDR has a u32 length in every version (spec §4.1).
            stream = ChunkStream(self._fp, file=self.name, limits=self.limits,
                                 compact=self._compact and offset != len(schema.SIGNATURE))
            stream.seek(self._base + offset)
            stream.offset = offset
            raw = stream.next_chunk()
        finally:
            self._fp.seek(here)
        if raw.type not in types:
            raise FormatError(f"byte {offset} held a {types[0].decode()} chunk, now {raw.name}: the file changed "
                              "while read", code="BAD_GROUP_STRUCTURE", offset=offset)
        return raw

    def _check_index(self, entries: np.ndarray | list) -> None:
        """iNDX must list exactly the OBJT, PLNS and GRUP chunks read so far (spec §10.2); in version 6 the
        object, planes and group records."""
        if isinstance(entries, list):
            if len(entries) != len(self._listed):
                raise FormatError(f"iNDX lists {len(entries)} records; the file has {len(self._listed)} object, "
                                  "planes and group records", code="BAD_INDEX")
            for i, (got, want) in enumerate(zip(entries, self._listed)):
                if got != want:
                    raise FormatError(f"iNDX entry {i} says (chunk at byte {got[0]}, raw byte {got[1]}, tag "
                                      f"{got[2]}, ordinal {got[3]}); the file has {want}", code="BAD_INDEX")
            return
        listed = np.array(self._listed, dtype=schema.INDEX_ENTRY_DTYPE)
        if len(entries) != len(listed):
            raise FormatError(f"iNDX lists {len(entries)} chunks; the file has {len(listed)} OBJT, PLNS and GRUP "
                              "chunks before it", code="BAD_INDEX")
        wrong = np.flatnonzero(entries != listed)
        if len(wrong):
            i = int(wrong[0])
            got, want = entries[i], listed[i]
            raise FormatError(f"iNDX entry {i} says {got['type'].decode('latin-1')} #{got['ordinal']} at byte "
                              f"{got['offset']}; the file has {want['type'].decode()} #{want['ordinal']} at byte "
                              f"{want['offset']}", code="BAD_INDEX")

    def _finish(self, raw: RawChunk) -> None:
        index_offset = records.decode_end(raw.payload, self.header.version[0])
        if index_offset and index_offset != self.index_offset:
            raise FormatError(f"PEND points at byte {index_offset}, the iNDX chunk is at {self.index_offset}",
                              code="BAD_INDEX")
        h = self.header
        if h.plane_count is not None and (h.plane_count, h.object_count, h.group_count) != (
                self._plane_count, len(self.objects), self._group_count):
            raise FormatError(
                f"header counts {h.plane_count} planes, {h.object_count} objects, {h.group_count} groups; "
                f"the file holds {self._plane_count}, {len(self.objects)}, {self._group_count}",
                code="COUNT_MISMATCH")
        self._done = True
        if not self._stream.at_eof():
            raise FormatError("bytes follow the PEND chunk", code="TRAILING_DATA", offset=raw.end)

    def _append_planes(self, triplets: np.ndarray) -> None:
        n = self._plane_count + len(triplets)
        if self.retain_planes:
            if n > len(self._table):
                grown = np.empty((max(n, 2 * len(self._table)), 3), dtype=np.float64)
                grown[: self._plane_count] = self._table[: self._plane_count]
                self._table = grown
            self._table[self._plane_count:n] = triplets
        self._plane_count = n

    # -- random access ---------------------------------------------------------------------

    def index(self) -> np.ndarray | list[segments.Entry]:
        """The iNDX entries (offset, type, ordinal) of a seekable file, read from its end; version 6: (chunk
        offset, raw offset, tag, ordinal) of each record of tags 1 to 3 (spec §10.2)."""
        if self._base is None:
            raise PlnError("random access needs a seekable file", code="BAD_INDEX", file=self.name)
        end = self._fp.seek(0, os.SEEK_END) - self._base
        major = self.header.version[0]
        stream = ChunkStream(self._fp, file=self.name, limits=self.limits, compact=self._compact)
        # The two PEND chunks a file can end in (spec §4.4): empty (no index), or the index's offset.
        empty = chunk_bytes(schema.PEND, b"", self._compact)
        last = len(empty) + schema.END_SIZE
        if major >= 3 and end >= len(empty):
            self._fp.seek(self._base + end - len(empty))
            if self._fp.read(len(empty)) == empty:
                raise FormatError("the file has no index", code="BAD_INDEX", file=self.name, offset=end - len(empty))
        if end < last:
            raise FormatError("file too short to end with PEND", code="TRUNCATED", file=self.name)
        stream.seek(self._base + end - last)
        stream.offset = end - last
        raw = stream.next_chunk()
        if raw.type != schema.PEND:
            raise FormatError("the file does not end with a PEND chunk", code="MISSING_END", file=self.name,
                              offset=end - last)
        index_offset = self._located(lambda r: records.decode_end(r.payload, major), raw)
        if not index_offset or index_offset >= end - last:
            raise FormatError("the file has no index", code="BAD_INDEX", file=self.name, offset=end - last)
        stream.seek(self._base + index_offset)
        stream.offset = index_offset
        raw = stream.next_chunk()
        if raw.type != schema.INDX:
            raise FormatError("PEND does not point at an iNDX chunk", code="BAD_INDEX", file=self.name,
                              offset=index_offset)
        try:
            if major >= 6:
                return segments.decode_index(raw.payload)
            return records.decode_index(raw.payload, index_offset, self._after_header)
        except PlnError as exc:
            raise exc.located(file=self.name, chunk="iNDX", offset=index_offset)

    def group(self, k: int) -> PartGroup:
        """Part group ``k`` by random access (seekable files with an index only).

        Reads the objects and plane blocks it depends on and the group chunk itself.
        """
        entries = self.index()
        if isinstance(entries, list):
            return self._group6(k, entries)
        types = entries["type"]
        groups = np.flatnonzero(types == schema.GRUP)
        if not 0 <= k < len(groups):
            raise PlnError(f"no part group {k}; the file has {len(groups)}", code="BAD_INDEX", file=self.name)
        pos = groups[k]
        sub = self._fresh()
        stream = ChunkStream(self._fp, file=self.name, limits=self.limits, compact=self._compact)
        for i in np.flatnonzero(np.isin(types[: pos + 1], [schema.OBJT, schema.PLNS])).tolist() + [int(pos)]:
            offset = int(entries["offset"][i])
            stream.seek(self._base + offset)
            stream.offset = offset
            raw = stream.next_chunk()
            if raw.type != types[i]:
                raise FormatError(f"index says {types[i].decode()} at byte {offset}, found {raw.name}",
                                  code="BAD_INDEX", file=self.name, offset=offset)
            sub._group_count = k
            record = sub._located(sub._dispatch, raw)
        return record


    def _fresh(self) -> "Reader":
        """A shallow copy that shares the file but starts from an empty plane table and object list, its
        budget one group's output, not the file's."""
        sub = copy.copy(self)
        sub.objects, sub._table, sub._plane_count, sub._group_refs = [], np.empty((0, 3)), 0, {}
        sub._payloads, sub._offsets, sub._sources = {}, {}, {}
        sub.budget = Budget(self.limits)
        sub.findings, sub.retain_planes, sub.index_offset, sub._listed = [], True, None, []
        return sub

    def _group6(self, k: int, entries: list[segments.Entry]) -> PartGroup:
        """Group ``k`` of a version 6 file through its index: the object and planes records before it and
        its own, each segment they are in read and decompressed once."""
        groups = [i for i, e in enumerate(entries) if e[2] == schema.TAG_GROUP]
        if not 0 <= k < len(groups):
            raise PlnError(f"no part group {k}; the file has {len(groups)}", code="BAD_INDEX", file=self.name)
        pos = groups[k]
        sub = self._fresh()
        sub.record_stats, sub.record_counts = Counter(), Counter()
        wanted = [i for i in range(pos) if entries[i][2] in (schema.TAG_OBJECT, schema.TAG_PLANES)] + [pos]
        record = None
        for i in wanted:
            chunk_offset, raw_offset, tag, _ = entries[i]
            if sub._segment is None or sub._segment[0].offset != chunk_offset:
                chunk = sub._reread(chunk_offset, (schema.PHDR, schema.BODY))
                start = records.decode_header6(chunk.payload)[2] if chunk.type == schema.PHDR else 0
                sub._segment = (chunk, sub._located(
                    lambda c: segments.segment_raw(memoryview(c.payload)[start:], self.limits), chunk))
            chunk, raw = sub._segment
            try:
                view = next(segments.records(memoryview(raw)[raw_offset:]), None)
                if view is None or view.tag != tag:
                    raise FormatError(f"index says tag {tag} at raw byte {raw_offset}, found "
                                      f"{'nothing' if view is None else view.tag}", code="BAD_INDEX")
                sub._group_count = k
                record = sub._record(chunk, segments.RecordView(view.tag, raw_offset, view.payload))
            except PlnError as exc:
                raise exc.located(file=self.name, chunk=chunk.name, offset=chunk.offset)
        return record


builtin_open = open


def open(source: str | os.PathLike | BinaryIO, *, retain_planes: bool = True,  # noqa: A001
         limits: Limits | None = None, name: str | None = None) -> Reader:
    """Open a .pln file or binary stream for reading (use as a context manager).

    ``source`` may be a path, ``"-"`` for standard input, or a binary file
    object (which is left open on close). ``retain_planes=False`` keeps memory
    bounded by the largest chunk but leaves ``PartGroup.planes`` unresolved (except
    on a stream that cannot be read again, such as a pipe, whose groups' stored
    payloads a version 4.2 or 5.0 reader keeps for copies to name, spec §9.15).
    """
    if isinstance(source, str) and source == "-":
        return Reader(sys.stdin.buffer, retain_planes=retain_planes, limits=limits, name=name or "<stdin>")
    return Reader(source, retain_planes=retain_planes, limits=limits, name=name)


def _with_planes(group: PartGroup, planes: np.ndarray) -> PartGroup:
    return dataclasses.replace(group, planes=planes)


def _tell(fp: BinaryIO) -> int | None:
    try:
        return fp.tell() if fp.seekable() else None
    except (AttributeError, ValueError, OSError):
        return None
