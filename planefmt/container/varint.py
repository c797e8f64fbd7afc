"""Unsigned LEB128 varints and zigzag signs (spec §2.2), vectorized over whole arrays, and the
reader of packed bit fields (a group's role bits, a shell's corner flags).

A value is written 7 bits at a time, least significant group first, each byte
but the last with its high bit set; values are below 2^64 and minimal (no
final 0x00 byte after a continued one). Zigzag maps signed integers to
unsigned ones, 0, -1, 1, -2, ... to 0, 1, 2, 3, ...
"""

from __future__ import annotations

import numpy as np

from ..errors import FormatError
from .schema import VARINT_MAX_BYTES as MAX_BYTES

try:
    # Encoders write a body's varints several times while they rank codings: a tenth of an encode in
    # numpy's passes (eight corpus meshes at 1e-6: 0.52 s of 4.6).
    from ._chains import unvarints as _unvarints, varints as _varints
except ImportError:  # built without a C compiler
    _unvarints = _varints = None


def encode(values: np.ndarray) -> bytes:
    """The varints of ``values`` (non-negative integers below 2^64), concatenated."""
    v = np.ascontiguousarray(np.asarray(values).astype(np.uint64, copy=False).reshape(-1))
    if len(v) == 0:
        return b""
    if _varints is not None:
        return _varints(v)
    return _encode(v)


def _encode(v: np.ndarray) -> bytes:
    """:func:`encode` in numpy, where the C extension is not built: one pass per byte of the longest."""
    lengths = np.ones(len(v), dtype=np.int64)
    for k in range(1, MAX_BYTES):
        lengths += v >= np.uint64(1) << np.uint64(7 * k)
    owner = np.repeat(np.arange(len(v)), lengths)
    start = np.cumsum(lengths) - lengths
    group = np.arange(len(owner)) - start[owner]
    out = ((v[owner] >> (np.uint64(7) * group.astype(np.uint64))) & np.uint64(0x7F)).astype(np.uint8)
    out[group < lengths[owner] - 1] |= 0x80
    return out.tobytes()


def decode(data: bytes | memoryview | np.ndarray, count: int, what: str) -> tuple[np.ndarray, int]:
    """The first ``count`` varints of ``data`` as uint64, and the bytes they took.

    ``FormatError`` (``BAD_PAYLOAD``) if the data ends inside them, a varint is
    longer than 10 bytes, exceeds 2^64 - 1 or is not minimal; ``what`` names
    the field in the message.
    """
    b = np.frombuffer(data, dtype=np.uint8) if not isinstance(data, np.ndarray) else data
    if count == 0:
        return np.zeros(0, dtype=np.uint64), 0
    # Each varint takes a byte at least: a count past the bytes is an error, found without allocating it.
    if _unvarints is not None and count <= len(b) and b.flags.c_contiguous:
        # A reader decodes a body's fields in a few dozen numpy passes each: a fifth of torus.STL's
        # decode. The loop in C reads valid varints; numpy's passes below say what is wrong with others.
        out = np.empty(count, dtype=np.uint64)
        used = _unvarints(b, out)
        if used >= 0:
            return out, used
    return _decode(b, count, what)


def _decode(b: np.ndarray, count: int, what: str) -> tuple[np.ndarray, int]:
    """:func:`decode` in numpy: without the C extension, and to name what is wrong with invalid varints."""
    # Valid varints end within count * MAX_BYTES bytes: a few header fields need not scan a whole
    # payload. Fewer ends there is an error, told apart by a scan of the rest.
    ends = np.flatnonzero(b[:count * MAX_BYTES] < 0x80)
    if len(ends) < count:
        ends = np.flatnonzero(b < 0x80)
    if len(ends) < count:
        raise FormatError(f"{what}: the data ends inside varint {len(ends)} of {count}", code="BAD_PAYLOAD")
    ends = ends[:count]
    used = int(ends[-1]) + 1
    starts = np.r_[0, ends[:-1] + 1]
    lengths = ends - starts + 1
    if lengths.max() > MAX_BYTES:
        raise FormatError(f"{what}: a varint is longer than {MAX_BYTES} bytes", code="BAD_PAYLOAD")
    if ((lengths > 1) & (b[ends] == 0)).any():
        raise FormatError(f"{what}: a varint is not minimal (ends in a zero group)", code="BAD_PAYLOAD")
    if ((lengths == MAX_BYTES) & (b[ends] > 1)).any():
        raise FormatError(f"{what}: a varint exceeds 2^64 - 1", code="BAD_PAYLOAD")
    owner = np.repeat(np.arange(count), lengths)
    group = np.arange(used) - starts[owner]
    parts = (b[:used].astype(np.uint64) & np.uint64(0x7F)) << (np.uint64(7) * group.astype(np.uint64))
    return np.bitwise_or.reduceat(parts, starts), used


def zigzag(values: np.ndarray) -> np.ndarray:
    """Signed int64 to uint64: 0, -1, 1, -2 ... -> 0, 1, 2, 3 ..."""
    v = np.asarray(values, dtype=np.int64)
    return ((v << 1) ^ (v >> 63)).astype(np.uint64)


def unzigzag(values: np.ndarray) -> np.ndarray:
    """The inverse of :func:`zigzag`, as int64."""
    u = np.asarray(values, dtype=np.uint64)
    return ((u >> np.uint64(1)).astype(np.int64)) ^ (-(u & np.uint64(1)).astype(np.int64))


def bit_field(raw: np.ndarray, pos: int, count: int, body: str, what: str) -> tuple[np.ndarray, int]:
    """``count`` bits packed least significant first from ``raw[pos:]`` as bools, and the position
    after their bytes; ``BAD_PAYLOAD`` where ``body`` ends inside them or a padding bit is set."""
    size = (count + 7) // 8
    if len(raw) < pos + size:
        raise FormatError(f"{body} ends inside its {what}", code="BAD_PAYLOAD")
    bits = np.unpackbits(raw[pos:pos + size], bitorder="little")
    if bits[count:].any():
        raise FormatError(f"non-zero padding bits after the {what}", code="BAD_PAYLOAD")
    return bits[:count].astype(bool), pos + size
