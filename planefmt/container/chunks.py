"""Chunk framing (spec §3–§4): signature check, bounded chunk reads, CRC, ``chunk_bytes``.

Framing knows nothing of payload meaning. ``chunk_bytes`` is the one helper
that frames a payload; the writer, the conformance generator and the tests
that build broken files all use it.
"""

from __future__ import annotations

import io
import os
import stat
from dataclasses import dataclass
from collections.abc import Iterator
from typing import BinaryIO

from ..errors import ChecksumError, FormatError, LimitError, TruncatedError
from . import schema
from .crc import crc32
from .limits import Limits

#: Payloads are read in blocks of this size so that a declared length never
#: allocates more than the bytes that actually arrive.
READ_BLOCK = 1 << 20


def chunk_bytes(ctype: bytes, payload: bytes, compact: bool = False) -> bytes:
    """Frame ``payload`` as one chunk: type, length, payload, CRC-32 (spec §4.1); ``compact``: the
    length as a varint32, as version 5 frames every chunk after PHDR."""
    if len(ctype) != 4:
        raise ValueError("chunk type must be 4 bytes")
    crc = crc32(payload, crc32(ctype))
    length = schema.Varint32.build(len(payload)) if compact else len(payload).to_bytes(4, "little")
    return ctype + length + payload + crc.to_bytes(4, "little")


def is_ancillary(ctype: bytes) -> bool:
    """Bit 5 of the first byte set (a lowercase letter) marks an ancillary chunk."""
    return bool(ctype[0] & 0x20)


def valid_type(ctype: bytes) -> bool:
    return len(ctype) == 4 and all(65 <= (b & ~0x20) <= 90 for b in ctype)


def type_name(ctype: bytes) -> str:
    return ctype.decode("latin-1") if valid_type(ctype) else ctype.hex()


def check_signature(data: bytes, *, file: str | None = None) -> None:
    """Raise ``FormatError`` unless ``data`` is the 8-byte signature (spec §3).

    Damage a text-mode transfer does (CR LF -> LF, LF -> CR LF, the high bit
    stripped) is reported as TEXT_MODE_DAMAGE rather than a foreign file.
    """
    if data == schema.SIGNATURE:
        return
    if len(data) < len(schema.SIGNATURE) and schema.SIGNATURE.startswith(data):
        raise TruncatedError("file ends inside the signature", file=file, offset=0)
    if data[1:4] == b"PLN" and data[:1] in (b"\x89", b"\x09"):
        raise FormatError("signature damaged by a text-mode transfer (line endings or 8th bit)",
                          code="TEXT_MODE_DAMAGE", file=file, offset=0)
    raise FormatError("not a .pln file (bad signature)", code="BAD_SIGNATURE", file=file, offset=0)


@dataclass(frozen=True)
class RawChunk:
    """A framed chunk as read: its type, payload and the offset of its first byte."""

    type: bytes
    payload: bytes
    offset: int
    framing: int = 12  # bytes of type, length and CRC

    @property
    def end(self) -> int:
        """The offset of the byte after the chunk."""
        return self.offset + self.framing + len(self.payload)

    @property
    def name(self) -> str:
        return type_name(self.type)


class ChunkStream:
    """Reads chunks from a binary stream, one at a time, checking every CRC.

    Works on non-seekable streams (pipes, sockets): it never seeks unless asked
    to, tracks its own byte offset, and reads payloads in bounded blocks.
    ``compact``: lengths are varint32s (version 5, every chunk after PHDR).
    """

    def __init__(self, fp: BinaryIO, *, file: str | None, limits: Limits, start: int = 0,
                 compact: bool = False) -> None:
        self.fp = fp
        self.file = file
        self.limits = limits
        self.offset = start
        self.compact = compact
        self._size = _stream_size(fp)

    def remaining(self) -> int | None:
        """Bytes left in a regular file, None for a stream whose size is unknown."""
        return None if self._size is None else self._size - self.fp.tell()

    def read_exact(self, n: int, *, chunk: str | None, what: str) -> bytes:
        left = self.remaining()
        if left is not None and n > left:
            raise TruncatedError(f"{what} needs {n} bytes but only {left} remain",
                                 file=self.file, chunk=chunk, offset=self.offset)
        if left is not None:
            # The size was checked against the file: safe to allocate once and fill in place.
            buf = bytearray(n)
            view = memoryview(buf)
            got = 0
            while got < n:
                k = self.fp.readinto(view[got:]) if hasattr(self.fp, "readinto") else None
                if k is None:
                    block = self.fp.read(n - got)
                    k = len(block)
                    view[got:got + k] = block
                if not k:
                    raise TruncatedError(f"file ends after {got} of {n} bytes of {what}",
                                         file=self.file, chunk=chunk, offset=self.offset)
                got += k
            self.offset += n
            return bytes(buf) if n <= 64 else buf
        parts = []
        got = 0
        while got < n:
            block = self.fp.read(min(READ_BLOCK, n - got))
            if not block:
                raise TruncatedError(f"file ends after {got} of {n} bytes of {what}",
                                     file=self.file, chunk=chunk, offset=self.offset)
            parts.append(block)
            got += len(block)
        data = parts[0] if len(parts) == 1 else b"".join(parts)
        self.offset += n
        return data

    def read_signature(self) -> None:
        start = self.offset
        data = b""
        while len(data) < len(schema.SIGNATURE):
            block = self.fp.read(len(schema.SIGNATURE) - len(data))
            if not block:
                break
            data += block
        self.offset = start + len(data)
        if not data:
            raise TruncatedError("empty file", file=self.file, offset=0)
        check_signature(data, file=self.file)

    def next_chunk(self) -> RawChunk:
        """Read the next chunk; raise a located ``FormatError`` if it is damaged."""
        start = self.offset
        head = self.read_exact(4 if self.compact else 8, chunk=None, what="chunk head")
        ctype = head[:4]
        name = type_name(ctype)
        if not valid_type(ctype):
            raise FormatError(f"chunk type {ctype!r} is not four ASCII letters", code="BAD_CHUNK_TYPE",
                              file=self.file, offset=start)
        length = self._compact_length(name, start) if self.compact else int.from_bytes(head[4:], "little")
        if length > schema.MAX_CHUNK_LENGTH:
            raise FormatError(f"declared length {length} exceeds 2^31-1", code="CHUNK_TOO_LONG",
                              file=self.file, chunk=name, offset=start)
        if length > self.limits.max_chunk_length:
            raise LimitError(f"declared length {length} exceeds the limit {self.limits.max_chunk_length}",
                             file=self.file, chunk=name, offset=start)
        payload = self.read_exact(length, chunk=name, what=f"a {length}-byte payload")
        tail = self.read_exact(4, chunk=name, what="the CRC")
        crc = crc32(payload, crc32(ctype))
        if crc != int.from_bytes(tail, "little"):
            raise ChecksumError(f"CRC mismatch (stored {int.from_bytes(tail, 'little'):08x}, computed {crc:08x})",
                                file=self.file, chunk=name, offset=start)
        return RawChunk(ctype, payload, start, self.offset - start - length)

    def _compact_length(self, name: str, start: int) -> int:
        """A version 5 length: a minimal varint32 of at most 5 bytes, read a byte at a time (spec §4.1)."""
        value = 0
        for n in range(schema.LENGTH_VARINT_BYTES):
            b = self.read_exact(1, chunk=None, what="chunk head")[0]
            value |= (b & 0x7F) << 7 * n
            if b < 0x80:
                if n and not b:
                    raise FormatError("the chunk length is not a minimal varint", code="BAD_CHUNK_LENGTH",
                                      file=self.file, chunk=name, offset=start)
                return value
        raise FormatError("the chunk length's varint runs past 5 bytes", code="CHUNK_TOO_LONG",
                          file=self.file, chunk=name, offset=start)

    def at_eof(self) -> bool:
        """True if nothing follows; consumes at most one byte."""
        return not self.fp.read(1)

    def seek(self, offset: int) -> None:
        self.fp.seek(offset)
        self.offset = offset


def chunks_of(data: bytes, *, limits: Limits | None = None) -> Iterator[RawChunk]:
    """Every chunk of an in-memory file, framed as its header's version frames them (spec §4.1: varint
    lengths after a version 5 PHDR); framing checked, payloads not."""
    stream = ChunkStream(io.BytesIO(data), file=None, limits=limits or Limits())
    stream.read_signature()
    while stream.offset < len(data):
        chunk = stream.next_chunk()
        if chunk.type == schema.PHDR and chunk.payload[:1] >= b"\x05":
            stream.compact = True
        yield chunk


def _stream_size(fp: BinaryIO) -> int | None:
    """Total size of a regular file or in-memory buffer, None for pipes and sockets."""
    if isinstance(fp, io.BytesIO):
        return len(fp.getbuffer())
    try:
        st = os.fstat(fp.fileno())
    except (AttributeError, OSError, io.UnsupportedOperation):
        return None
    return st.st_size if stat.S_ISREG(st.st_mode) else None
