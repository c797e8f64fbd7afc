"""Body segments and their records (spec §4.5, §4.6) and the index of version 6 (spec §10.2).

A version 6 file holds every object, plane block, part group, colours and metadata record in body
segments: the rest of the PHDR payload and each BODY chunk, each compressed as a whole. A reader
holds one segment's raw bytes at a time; the record payloads it yields are views of them.
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from dataclasses import dataclass

import construct as cs

from . import schema
from .chunks import Limits
from .compression import pack, unpack
from .headers import BYTE, VARINT32, quick_head
from ..errors import FormatError


@dataclass(frozen=True)
class RecordView:
    """One record of a segment: its tag, its offset in the segment's raw bytes, and its payload."""

    tag: int
    offset: int
    payload: memoryview

    @property
    def size(self) -> int:
        """Bytes of the record in the raw segment: tag, length and payload."""
        return 1 + len(schema.Varint32.build(len(self.payload))) + len(self.payload)


def segment_raw(payload: bytes | memoryview, limits: Limits) -> bytes | bytearray | memoryview:
    """The raw bytes of a body segment (spec §4.5 checks 1 and 2: its head, then §6's checks)."""
    view = memoryview(payload)
    quick = quick_head(view, (BYTE, VARINT32), 1 + schema.LENGTH_VARINT_BYTES)
    if quick is not None:
        (compression, raw_size), offset = quick
        return unpack(compression, view[offset:], raw_size, limits, 6)
    try:
        head = schema.Segment.parse(bytes(view[:1 + schema.LENGTH_VARINT_BYTES]))
    except (cs.ConstructError, ValueError) as exc:
        raise FormatError(f"body segment ends inside its head, or a bad raw size ({type(exc).__name__})",
                          code="BAD_PAYLOAD") from None
    return unpack(head.compression, view[head.data_offset:], head.raw_size, limits, 6)


def records(raw: bytes | bytearray | memoryview) -> Iterator[RecordView]:
    """The records of a segment's raw bytes in order (spec §4.6 checks 1 and 2); a record that the
    segment ends inside is ``BAD_PAYLOAD`` when it is reached."""
    view = memoryview(raw)
    pos = 0
    while pos < len(view):
        quick = quick_head(view[pos:], (BYTE, VARINT32), 1 + schema.LENGTH_VARINT_BYTES)
        if quick is None:
            try:
                head = schema.RecordHead.parse(bytes(view[pos:pos + 1 + schema.LENGTH_VARINT_BYTES]))
            except (cs.ConstructError, ValueError) as exc:
                raise FormatError(f"the segment ends inside the head of a record at raw byte {pos}, or its length "
                                  f"is a bad varint32 ({type(exc).__name__})", code="BAD_PAYLOAD") from None
            tag, length, offset = head.tag, head.length, head.payload_offset
        else:
            (tag, length), offset = quick
        start = pos + offset
        if length > len(view) - start:
            raise FormatError(f"record of tag {tag} at raw byte {pos} declares {length} bytes, "
                              f"{len(view) - start} are left in the segment", code="BAD_PAYLOAD")
        yield RecordView(tag, pos, view[start:start + length])
        pos = start + length


def record_bytes(tag: int, payload: bytes) -> bytes:
    """One record: tag, length, payload (spec §4.6)."""
    return bytes([tag]) + schema.Varint32.build(len(payload)) + payload


def segment_bytes(raw: bytes, compress: bool = True, brotli: bool = True, quality: int | None = None) -> bytes:
    """A body segment of ``raw``: whichever of methods 0, 1 and 2 is smallest (spec §4.5); without ``brotli``,
    of methods 0 and 1. ``quality``: Brotli's, if not the writer's (an encoder's estimate of a size)."""
    method, stored = pack(raw, compress, brotli_allowed=brotli, quality=quality)
    return bytes([method]) + schema.Varint32.build(len(raw)) + stored


# spec §10.2 Index of version 6 -------------------------------------------------------------------

#: One index entry: the offset of the chunk holding the record, its offset in the segment's raw
#: bytes, its tag, its ordinal.
Entry = tuple[int, int, int, int]


def encode_index(entries: list[Entry]) -> bytes:
    out = [schema.Varint.build(len(entries))]
    previous = 0
    for chunk, raw, tag, ordinal in entries:
        out.append(schema.IndexEntry6.build(dict(chunk_offset=chunk - previous, raw_offset=raw, tag=tag,
                                                 ordinal=ordinal)))
        previous = chunk
    return b"".join(out)


def decode_index(payload: bytes) -> list[Entry]:
    """The entries of a version 6 iNDX (spec §10.2): BAD_PAYLOAD where it ends inside them, BAD_INDEX for
    bytes after them; what they say is checked against the file by the reader."""
    stream = io.BytesIO(bytes(payload))
    try:
        count = schema.Varint.parse_stream(stream)
        if count * schema.INDEX6_MIN_ENTRY > len(payload) - stream.tell():
            raise FormatError(f"iNDX declares {count} entries, more than its {len(payload)} bytes hold",
                              code="BAD_PAYLOAD")
        entries, chunk = [], 0
        for _ in range(count):
            e = schema.IndexEntry6.parse_stream(stream)
            chunk += e.chunk_offset
            entries.append((chunk, e.raw_offset, e.tag, e.ordinal))
    except (cs.ConstructError, ValueError) as exc:
        raise FormatError(f"iNDX ends inside its entries, or a bad varint ({type(exc).__name__})",
                          code="BAD_PAYLOAD") from None
    if stream.tell() != len(payload):
        raise FormatError(f"{len(payload) - stream.tell()} bytes after the iNDX entries", code="BAD_INDEX")
    return entries
