"""Streaming writer of .pln files (spec §4, §11).

Objects, planes and part groups are written as they come; counts need not be
known in advance. On ``close()`` the writer appends the iNDX and PEND chunks,
patches the header counts where the output is seekable, and, when writing to
a path, renames its temporary file onto the target (atomic: on failure nothing
is left under the target name).
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import tempfile
from pathlib import Path
from typing import BinaryIO

import numpy as np

from . import headers, records, schema, segments, shellfields, shellwalk
from .chunks import chunk_bytes, is_ancillary, valid_type
from ..errors import PlnError
from ..model import (TREE_KINDS, UP_AXIS, Colours, GroupKind, Header, Metadata, ObjectRecord, PartGroup, PlaneBlock, Record,
                    Shell, UnknownChunk)

def _read_umask() -> int:
    # os.umask can only be read by setting it: done once at import, not per file (threads).
    mask = os.umask(0)
    os.umask(mask)
    return mask


_NEW_FILE_MODE = 0o666 & ~_read_umask()

#: Planes per PLNS chunk: bounds the memory a streaming reader needs per chunk.
BLOCK_PLANES = 1 << 16
#: Bytes before the index from which ``index=None`` writes one (a few milliseconds of streaming read).
INDEX_MIN_BYTES = 1 << 16
#: Version 6: a file whose records are one segment of fewer raw bytes than this leaves out its bbox and
#: counts (spec §5 "Small files"): 12 to 35 bytes that a reader gets by decoding. A writer may pass a larger
#: ``small_segment`` for a file whose decoding does not depend on the bbox (spec §9.4: no group of kinds 0
#: to 5, whose merge distance the bbox caps): the encoder passes :data:`SMALL_SHELLS_BYTES`.
SMALL_SEGMENT_BYTES = 256
#: The same for files of shells and copies of shells alone: at 4,096 the bench corpus's glTF and USD scenes'
#: median .pln / Draco-14 came to 1.016 and 0.974 from 1.032 and 1.008 (``bench/small_bytes.py``'s bytes,
#: less the bbox and counts of every file of one segment under it; 1,024 gave the same medians).
SMALL_SHELLS_BYTES = 4096


class Writer:
    """Write a .pln file to a path (atomically) or to a binary stream.

    ``header`` gives version, coding, quantization, units, bbox and error
    bound. Versions 1 and 2: its counts are ignored and replaced by the actual
    ones where the output is seekable. Version 3 (spec/pln.md): counts given
    in it are written and must match what is written by :meth:`close`
    (``COUNT_MISMATCH`` otherwise, and the output is discarded); without them
    the file declares none. ``index``: write an ``iNDX`` chunk; None writes
    one when the file is :data:`INDEX_MIN_BYTES` or more before it. ``verify``: check that each
    shell group's body decodes to the shell given (spec §9.10, §9.11); the encoder turns it off only
    to measure the size of a candidate it may not write. ``brotli``: with ``compress``, in a version 4
    or 5 file, each payload Brotli-compressed where that is smaller than deflate (spec §6); the encoder's size
    trials turn it off (Brotli's densest quality takes about 1 s a megabyte); a version 6 segment is
    Brotli-compressed where that is smallest whatever it says, at ``segment_quality`` if given (an encoder's
    estimate of a candidate's size: not the file's bytes). ``copies``: in a file whose
    version has copies (4.2, spec §9.15), a group whose kind, references, role bits and kind data are an
    earlier group's is written as a copy of it. Version 6 (spec §4.5): records are buffered into body
    segments of at most 1 MiB raw, the first written in PHDR once it is full or the file is closed (so
    nothing is written before), each other one in a BODY chunk; a quantized h range is rounded outward to
    float32 (spec §5), and a file of one segment under ``small_segment`` raw bytes leaves out its bbox and
    counts. Use as a context manager: leaving the block by an exception discards a path target's
    temporary file.
    """

    def __init__(self, target: str | os.PathLike | BinaryIO, header: Header, *, compress: bool = False,
                 index: bool | None = True, verify: bool = True, brotli: bool = True, copies: bool = True,
                 small_segment: int = SMALL_SEGMENT_BYTES, segment_quality: int | None = None) -> None:
        if int(header.coding) not in records.CODINGS.get(header.version[0], ()):
            raise PlnError(f"coding {int(header.coding)} cannot be written in a version {header.version[0]} file",
                           code="UNSUPPORTED_CODING")
        self._compress = compress
        self._small_segment = small_segment
        self._brotli = brotli
        self._segment_quality = segment_quality
        self._index = index
        self._verify = verify
        # Each group's (kind, body digest) -> its index, where copies may be written.
        self._bodies: dict[tuple[int, bytes], int] | None = \
            {} if copies and int(GroupKind.COPY) in records.kinds_of(*header.version) else None
        self._path: Path | None = None
        self._tmp: str | None = None
        if isinstance(target, (str, os.PathLike)):
            self._path = Path(target)
            fd, self._tmp = tempfile.mkstemp(prefix=f".{self._path.name}.", suffix=".tmp",
                                             dir=self._path.parent or ".")
            # mkstemp makes 0600 files; give the output the mode open() would (or the target's own).
            try:
                mode = self._path.stat().st_mode & 0o7777
            except FileNotFoundError:
                mode = _NEW_FILE_MODE
            os.fchmod(fd, mode)
            self._fp: BinaryIO = os.fdopen(fd, "wb")
        else:
            self._fp = target
        self._major = header.version[0]
        self._version = tuple(header.version)
        q = header.quantization
        if self._major >= 6 and header.coding.quantized and q is not None:
            header = dataclasses.replace(header, quantization=dataclasses.replace(
                q, **dict(zip(("h_min", "h_max"), headers.f32_range(q.h_min, q.h_max)))))
        declared = (header.plane_count, header.object_count, header.group_count)
        # Version 3 counts are varints: written up front if the caller declares them, never patched.
        self._declared = declared if self._major >= 3 and None not in declared else None
        if self._declared is None:
            header = dataclasses.replace(header, plane_count=None, object_count=None, group_count=None)
        self._header = header
        self._start = _tell(self._fp)
        self._pos = 0
        self._planes = 0
        self._objects = 0
        self._groups: list[int] = []  # reference count per group, for cOLR checks
        self._entries: list[tuple[int, bytes, int]] = []
        self._metadata: set[str] = set()
        self._closed = False
        # Version 6: the records of the segment being filled, its raw size, and the index entries (raw
        # offset, tag, ordinal) of its records; whether PHDR is written.
        self._segment: list[bytes] = []
        self._segment_size = 0
        self._segment_entries: list[tuple[int, int, int]] = []
        self._headed = self._major < 6
        try:
            if self._major >= 6:
                records.encode_header(self._header)  # a header that cannot be written fails here, not at close
                return
            self._emit_raw(schema.SIGNATURE)
            self._emit(schema.PHDR, records.encode_header(self._header))
        except BaseException:
            self.abort()
            raise

    @property
    def plane_count(self) -> int:
        return self._planes

    @property
    def bytes_written(self) -> int:
        """Bytes of .pln data emitted so far, signature included."""
        return self._pos

    def _emit_raw(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            # Raw streams (sockets, pipes opened unbuffered) may accept only part of a write.
            n = self._fp.write(view)
            view = view[len(view) if n is None else n:]
        self._pos += len(data)

    def _emit(self, ctype: bytes, payload: bytes, ordinal: int | None = None) -> None:
        tag = schema.RECORD_TAGS.get(ctype)
        if self._major >= 6 and tag is not None:
            self._record(tag, payload, ordinal)
            return
        if ordinal is not None:
            self._entries.append((self._pos, ctype, ordinal))
        # Version 5 frames every chunk after PHDR with a varint length (spec §4.1).
        self._emit_raw(chunk_bytes(ctype, payload, self._major >= 5 and ctype != schema.PHDR))

    def _record(self, tag: int, payload: bytes, ordinal: int | None) -> None:
        """Add a record to the segment being filled, starting a new one where it would pass 1 MiB (spec §4.5)."""
        record = segments.record_bytes(tag, payload)
        if self._segment_size and self._segment_size + len(record) > schema.SEGMENT_RAW_BYTES:
            self._flush()
        if ordinal is not None:
            self._segment_entries.append((self._segment_size, tag, ordinal))
        self._segment.append(record)
        self._segment_size += len(record)

    def _flush(self, last: bool = False) -> None:
        """Write the segment being filled: in PHDR if it is the first (``last``: and the file's only one),
        else as a BODY chunk."""
        raw = b"".join(self._segment)
        # Brotli is tried on a segment even in the encoder's size trials (``brotli`` off): one segment compressed
        # whole ranks candidates far from their deflated sizes (measured at 3e-5: the bench corpus's
        # basicTextured_flatten.usda, 37,322 bytes so, 55,236 with the trials' segments deflated).
        segment = segments.segment_bytes(raw, self._compress, quality=self._segment_quality) if raw else b""
        if not self._headed:
            header = self._header
            if last and len(raw) < self._small_segment:
                header = dataclasses.replace(header, bbox=None, plane_count=None, object_count=None, group_count=None)
            self._emit_raw(schema.SIGNATURE)
            chunk = self._pos
            self._emit_raw(chunk_bytes(schema.PHDR, records.encode_header(header) + segment))
            self._headed = True
        elif raw:
            chunk = self._pos
            self._emit_raw(chunk_bytes(schema.BODY, segment, True))
        self._entries.extend((chunk, offset, tag, ordinal) for offset, tag, ordinal in self._segment_entries)
        self._segment, self._segment_size, self._segment_entries = [], 0, []

    def add_object(self, name: str, parent: int | None = None, transform: np.ndarray | None = None) -> int:
        """Start object ``name``; returns its index. ``transform``: 4x4 local -> parent."""
        index = self._objects
        if parent is not None and not 0 <= parent < index:
            raise PlnError(f"parent {parent} is not an earlier object", code="BAD_OBJECT")
        if transform is not None:
            transform = np.asarray(transform, dtype=np.float64).reshape(4, 4)
            if not np.isfinite(transform).all() or not np.array_equal(transform[3], [0, 0, 0, 1]):
                raise PlnError("transform must be a finite affine 4x4 matrix", code="BAD_OBJECT")
        self._emit(schema.OBJT, records.encode_object(ObjectRecord(index, name, parent, transform), self._major), index)
        self._objects += 1
        return index

    def add_planes(self, triplets: np.ndarray) -> int:
        """Append ``(n, 3)`` triplets to the plane table; returns the index of the first."""
        t = np.asarray(triplets, dtype=np.float64).reshape(-1, 3)
        first = self._planes
        for s in range(0, len(t), BLOCK_PLANES):
            block = t[s:s + BLOCK_PLANES]
            self._emit(schema.PLNS, records.encode_planes(self._planes, block, self._header, self._compress, self._brotli),
                       self._planes)
            self._planes += len(block)
        return first

    def add_group(self, obj: int, kind: int, refs: np.ndarray, bounding: np.ndarray | None = None, *,
                  cells: tuple[np.ndarray, ...] | None = None, tree: np.ndarray | None = None,
                  extra: bytes = b"", vertex_planes: np.ndarray | None = None,
                  facets: np.ndarray | None = None, shell: Shell | None = None) -> int:
        """Write a part group of object ``obj`` over plane-table indices ``refs``; returns its index.

        ``bounding[i]`` marks ``refs[i]`` as a bounding/cut plane (default: all faces). A BSP
        group needs ``tree``, a CELLS group ``cells``, a SEALED group (version 3.1 and later)
        ``vertex_planes`` and ``facets`` in local references (spec §9.9), a SHELL group
        (version 3.2 and later) ``shell`` (spec §9.10).
        """
        refs = np.asarray(refs, dtype=np.int64).reshape(-1)
        if len(refs) == 0 and not (self._major >= 5 and int(kind) in records.UNREFERENCED_KINDS):
            raise PlnError("a part group needs at least one plane (version 5: but for shells and copies)",
                           code="BAD_GROUP_STRUCTURE")
        if len(refs) and (refs.min() < 0 or refs.max() >= self._planes):
            raise PlnError(f"references must lie in 0..{self._planes - 1}: planes are written before "
                           f"the groups that use them", code="BAD_PLANE_REFERENCE")
        if not 0 <= obj < self._objects:
            raise PlnError(f"object {obj} has not been added", code="BAD_OBJECT_REFERENCE")
        bounding = np.zeros(len(refs), bool) if bounding is None else np.asarray(bounding, bool).reshape(-1)
        if len(bounding) != len(refs):
            raise PlnError("one role bit per reference", code="BAD_GROUP_STRUCTURE")
        if kind == GroupKind.BSP:
            records.check_tree(np.asarray(tree, dtype=np.uint32), len(refs))
        if kind == GroupKind.CELLS and (not cells or any(
                len(c) == 0 or (np.asarray(c) >> 1).max() >= len(refs) for c in cells)):
            raise PlnError("cells must be non-empty and refer to the group's references",
                           code="BAD_GROUP_STRUCTURE")
        if kind == GroupKind.SEALED and int(kind) in records.kinds_of(*self._version):
            vertex_planes, facets = records.check_sealed(vertex_planes, facets, bounding)
        elif vertex_planes is not None or facets is not None:
            # Without the kind in its version, kind 5 is opaque ``extra`` (a skipped group re-written).
            raise PlnError(f"sealed groups need version 3.1, not {self._version[0]}.{self._version[1]}",
                           code="UNKNOWN_GROUP_KIND")
        if kind == GroupKind.SHELL and int(kind) in records.kinds_of(*self._version):
            if shell is None:
                raise PlnError("a shell group needs its corners and triangles", code="BAD_GROUP_STRUCTURE")
            if self._verify:
                shellfields.check_shell(shell, bounding)
        elif kind in TREE_KINDS and int(kind) in records.kinds_of(*self._version):
            if shell is None:
                raise PlnError("a shell tree needs its corners and triangles", code="BAD_GROUP_STRUCTURE")
            if self._verify:
                if kind in shellwalk.WALK_KINDS:
                    shellwalk.check_shell_walk(shell, bounding, kind)
                else:
                    shellfields.check_shell_tree(shell, bounding, kind == GroupKind.SHELL_TREE_PARALLELOGRAM)
        elif shell is not None:
            raise PlnError(f"shell groups need version 3.2 (shell trees 3.3), not {self._version[0]}."
                           f"{self._version[1]}", code="UNKNOWN_GROUP_KIND")
        index = len(self._groups)
        group = PartGroup(index=index, object=obj, kind=int(kind), refs=refs.astype(np.uint32),
                          bounding=bounding, cells=cells, tree=tree, extra=extra, vertex_planes=vertex_planes,
                          facets=facets, shell=shell)
        body = None
        if self._bodies is not None and kind != GroupKind.COPY:
            body = records.group_body(group, self._brotli, self._major)
            key = (int(kind), hashlib.sha256(body).digest())
            if key in self._bodies:
                group = PartGroup(index=index, object=obj, kind=int(GroupKind.COPY), refs=group.refs,
                                  bounding=bounding, source=self._bodies[key])
                body = None
            else:
                self._bodies[key] = index
        self._emit(schema.GRUP, records.encode_group(group, self._compress, self._major, self._brotli, body), index)
        self._groups.append(len(refs))
        return index

    def add_colours(self, group: int, rgba: np.ndarray) -> None:
        """Attach one RGBA8 colour per reference of an already written group (cOLR); to a group without
        references (version 5), one colour for all its triangles (spec §10.1)."""
        rgba = np.asarray(rgba, dtype=np.uint8).reshape(-1, 4)
        refs = self._groups[group] if 0 <= group < len(self._groups) else -1
        if refs < 0 or len(rgba) != (refs or 1):
            raise PlnError("colours need a written group and one colour per reference (one colour for a group "
                           "without references)", code="BAD_COLOURS")
        self._emit(schema.COLR, records.encode_colours(Colours(group, rgba), self._major, refs))

    def add_metadata(self, key: str, value: str) -> None:
        """Write a mETA chunk (spec §10.3): ``key`` = ``value``, each key once, before any object,
        plane or group. ``add_metadata(planefmt.UP_AXIS, "Z")`` records that +z points up (version 5:
        ``Header.up_axis`` does)."""
        if key == UP_AXIS and self._major >= 5:
            raise PlnError("a version 5 file says its up axis in the header (Header.up_axis)", code="BAD_METADATA")
        if self._entries or self._segment_entries:
            raise PlnError("metadata is written before the first object, plane block and part group",
                           code="BAD_METADATA")
        if key in self._metadata:
            raise PlnError(f"mETA {key} is already written", code="BAD_METADATA")
        self._emit(schema.META, records.encode_metadata(Metadata(key, value)))
        self._metadata.add(key)

    def add_chunk(self, ctype: bytes, payload: bytes) -> None:
        """Write an ancillary chunk verbatim (e.g. one a reader did not know); version 6: a one-byte ``ctype``
        of 128 to 255 is an ancillary record (spec §4.6), and a chunk follows the records written before it."""
        if self._major >= 6 and len(ctype) == 1 and ctype[0] >= schema.ANCILLARY_TAG:
            self._record(ctype[0], payload, None)
            return
        if not valid_type(ctype) or not is_ancillary(ctype) or ctype == schema.INDX:
            raise PlnError(f"only ancillary chunks other than iNDX can be written raw, not {ctype!r}",
                           code="BAD_CHUNK_TYPE")
        if self._major >= 6:
            self._flush()
        self._emit(ctype, payload)

    def write_record(self, record: Record) -> None:
        """Replay a record yielded by a reader (planes keep their indices only if replayed in order)."""
        if isinstance(record, ObjectRecord):
            self.add_object(record.name, record.parent, record.transform)
        elif isinstance(record, PlaneBlock):
            self.add_planes(record.triplets)
        elif isinstance(record, PartGroup):
            self.add_group(record.object, record.kind, record.refs, record.bounding, cells=record.cells,
                           tree=record.tree, extra=record.extra, vertex_planes=record.vertex_planes,
                           facets=record.facets, shell=record.shell)
        elif isinstance(record, Colours):
            self.add_colours(record.group, record.rgba)
        elif isinstance(record, Metadata):
            self.add_metadata(record.key, record.value)
        elif isinstance(record, UnknownChunk):
            self.add_chunk(record.type, record.payload)
        else:
            raise TypeError(f"not a record: {record!r}")

    def close(self) -> None:
        """Write iNDX and PEND, patch counts if seekable, and commit a path target."""
        if self._closed:
            return
        try:
            if self._major >= 6:
                self._flush(last=not self._headed)
            index_offset = 0
            # Auto (None): an index only where random access saves reading much; in a small file
            # it is bytes for nothing (simple_pole.glb at 1e-6: 736 of 4,000 bytes).
            if self._index or (self._index is None and self._pos >= INDEX_MIN_BYTES):
                index_offset = self._pos
                if self._major >= 6:
                    self._emit(schema.INDX, segments.encode_index(self._entries))
                else:
                    entries = np.array(self._entries, dtype=schema.INDEX_ENTRY_DTYPE)
                    self._emit(schema.INDX, records.encode_index(entries))
            actual = (self._planes, self._objects, len(self._groups))
            if self._declared is not None and self._declared != actual:
                raise PlnError(f"the header declares {self._declared[0]} planes, {self._declared[1]} objects, "
                               f"{self._declared[2]} groups; {actual[0]}, {actual[1]}, {actual[2]} were written",
                               code="COUNT_MISMATCH")
            self._emit(schema.PEND, records.encode_end(index_offset, self._major))
            if self._major < 3:
                self._patch_counts()
            self._fp.flush()
            if self._path is not None:
                os.fsync(self._fp.fileno())
                self._fp.close()
                os.replace(self._tmp, self._path)
                self._tmp = None
            self._closed = True
        except BaseException:
            self.abort()
            raise

    def _patch_counts(self) -> None:
        if self._start is None or not _seekable(self._fp):
            return
        header = dataclasses.replace(self._header, plane_count=self._planes, object_count=self._objects,
                                     group_count=len(self._groups))
        end = self._fp.tell()
        self._fp.seek(self._start + len(schema.SIGNATURE))
        self._fp.write(chunk_bytes(schema.PHDR, records.encode_header(header)))
        self._fp.seek(end)

    def abort(self) -> None:
        """Discard the output: a path target's temporary file is removed."""
        self._closed = True
        if self._path is not None:
            try:
                self._fp.close()
            finally:
                if self._tmp is not None and os.path.exists(self._tmp):
                    os.unlink(self._tmp)
                self._tmp = None

    def __enter__(self) -> "Writer":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


def _seekable(fp: BinaryIO) -> bool:
    try:
        return bool(fp.seekable())
    except (AttributeError, ValueError, OSError):
        return False


def _tell(fp: BinaryIO) -> int | None:
    if not _seekable(fp):
        return None
    try:
        return fp.tell()
    except OSError:
        return None
