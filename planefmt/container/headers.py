"""Header helpers of every version and the version 6 header (spec §5): float32 rounding of stored values,
r32 rounding, the compact header's fields; and the payload parser that turns construct's errors into
``BAD_PAYLOAD``."""

from __future__ import annotations

import math
import struct
import types

import construct as cs
import numpy as np

from . import schema
from ..errors import FormatError, PlnError
from ..model import Coding, Header, Quantization, Units
from .versions import VERSIONS



def _parse(struct: cs.Construct, payload: bytes, what: str):
    try:
        return struct.parse(payload)
    except (cs.ConstructError, ValueError, OverflowError) as exc:
        raise FormatError(f"{what} payload is malformed ({type(exc).__name__})", code="BAD_PAYLOAD") from None


def _f32_toward(values: np.ndarray, direction: float, what: str) -> list[float]:
    """Each value rounded to the nearest float32 on the side of ``direction`` (spec §5)."""
    v = np.asarray(values, dtype=np.float64)
    with np.errstate(over="ignore"):
        f = v.astype(np.float32)
    wrong = (f < v) if direction > 0 else (f > v)
    f = np.where(wrong, np.nextafter(f, np.float32(direction)), f)
    if not np.isfinite(f).all():
        raise PlnError(f"{what} is beyond the float32 range", code="BAD_HEADER_VALUE")
    return [float(x) for x in f]


def _f32_up(value: float, name: str) -> float:
    return value if math.isnan(value) else _f32_toward(np.array([value]), math.inf, f"{name} {value}")[0]


#: Version 6 keeps 12 explicit mantissa bits of tolerance and error_bound (spec §5): at most 3 bytes each.
R32_DROPPED_BITS = 11


def r32_up(value: float, name: str) -> float:
    """``value`` rounded up to the smallest binary32 value whose low 11 bits are zero (spec §5, version 6);
    NaN stays NaN, 0 stays 0."""
    if math.isnan(value):
        return value
    f = _f32_up(value, name)
    bits = int(np.array([f], dtype="<f4").view("<u4")[0])
    low = (1 << R32_DROPPED_BITS) - 1
    if bits & low:
        bits = (bits | low) + 1  # value >= 0: a larger pattern is a larger value
    out = float(np.array([bits], dtype="<u4").view("<f4")[0])
    if not math.isfinite(out):
        raise PlnError(f"{name} {value} is beyond the float32 range", code="BAD_HEADER_VALUE")
    return out


def f32_range(h_min: float, h_max: float) -> tuple[float, float]:
    """An h range as binary32 values holding [h_min, h_max] (spec §5, version 6: chosen before quantizing)."""
    low = _f32_toward(np.array([h_min]), -math.inf, "h_min")[0]
    high = _f32_toward(np.array([h_max]), math.inf, "h_max")[0]
    return low, high


def _r32_bytes(bits: np.ndarray) -> np.ndarray:
    """Bytes of each float32 bit pattern as an r32 (spec §2.2): its reversed bits as a varint."""
    lowest = np.where(bits == 0, np.int64(1) << 32, bits & -bits)  # 0 takes one byte, as if bit 32 were set
    low = np.log2(lowest.astype(np.float64)).astype(np.int64)
    return np.maximum(1, -(-(32 - low) // 7))


def r32_size(values: tuple[float, ...]) -> int:
    """Bytes of float32 ``values`` as r32s (spec §2.2)."""
    return int(_r32_bytes(np.array(values, dtype="<f4").view("<u4").astype(np.int64)).sum())


def _truncations(value: float, up: bool) -> np.ndarray:
    """Float32 patterns on the side ``up`` of ``value`` whose low 0 to 31 bits are clear (or carried out):
    the values of each r32 length nearest to it on that side."""
    bits = np.int64(np.array([_f32_toward(np.array([value]), math.inf if up else -math.inf, "h")[0]],
                             dtype="<f4").view("<u4")[0])
    mask = (np.int64(1) << np.arange(32, dtype=np.int64)) - 1
    sign = bits >> 31
    out = np.where(bits & mask, (bits | mask) + 1, bits) if up != bool(sign) else (bits & ~mask)
    # A carry into the sign, or an exponent of all ones, is no value on that side.
    return np.unique(out[((out >> 31) == sign) & ((out & 0x7F800000) != 0x7F800000)])


def short_range(h_min: float, h_max: float, levels: int, room: float) -> tuple[float, float]:
    """An h range of two float32 values for planes whose h lie in [h_min, h_max], quantized to ``levels``
    steps (spec §5 and §7.3, version 6), of the fewest r32 bytes among those that move no plane more than
    ``room`` beyond what :func:`f32_range`'s range does: a plane up to ``room`` outside it quantizes onto
    its end, and a wider range has wider steps. Ties: the one that moves planes least."""
    tight = f32_range(h_min, h_max)
    lows = _truncations(h_min + room, up=False)
    highs = _truncations(h_max - room, up=True)
    lo = lows.astype("<u4").view("<f4").astype(np.float64)[:, None]
    hi = highs.astype("<u4").view("<f4").astype(np.float64)[None, :]
    width = hi - lo
    moved = np.maximum(np.maximum(lo - h_min, h_max - hi), 0.0) \
        + np.maximum(width - (tight[1] - tight[0]), 0.0) / (2.0 * max(levels, 1))
    ok = (width >= 0) & (moved <= room)
    if not ok.any():
        return tight
    cost = np.where(ok, _r32_bytes(lows)[:, None] + _r32_bytes(highs)[None, :], 99)
    i, j = np.unravel_index(np.lexsort((moved.ravel(), cost.ravel()))[0], cost.shape)
    return float(lo[i, 0]), float(hi[0, j])


def encode_header6(h: Header) -> bytes:
    """A version 6 header (spec §5) without a segment: the writer appends its first one."""
    q = h.quantization
    flags = (schema.FLAG_LOSSY if h.lossy else 0) | int(h.coding) << schema.FLAG_CODING_SHIFT
    counts = (h.plane_count, h.object_count, h.group_count)
    if all(c is not None for c in counts):
        flags |= schema.FLAG_COUNTS_KNOWN
    if h.bbox is not None:
        flags |= schema.FLAG_BBOX_KNOWN
    if h.coding.quantized and f32_range(q.h_min, q.h_max) != (q.h_min, q.h_max):
        raise PlnError(f"a version 6 h range is two float32 values, not [{q.h_min!r}, {q.h_max!r}]",
                       code="BAD_HEADER_VALUE")
    bbox = None if h.bbox is None else np.asarray(h.bbox, dtype=np.float64)
    fields = schema.Header6Fields.build(dict(
        flags=flags, units=int(h.units) | schema.UP_AXIS_CODES.index(h.up_axis) << schema.UP_AXIS_SHIFT,
        widths=schema.widths6(q.bits_nu, q.bits_phi, q.bits_h) if h.coding.quantized else None,
        h_range=[q.h_min, q.h_max] if h.coding.quantized else None,
        bbox=None if bbox is None else [*_f32_toward(bbox[0], -math.inf, "a bounding box coordinate"),
                                        *_f32_toward(bbox[1], math.inf, "a bounding box coordinate")],
        tolerance=r32_up(h.tolerance, "tolerance"), error_bound=r32_up(h.error_bound, "error_bound"),
        counts=dict(plane_count=counts[0], object_count=counts[1], group_count=counts[2])
        if flags & schema.FLAG_COUNTS_KNOWN else None, extra=h.extra))
    return bytes([h.version[0], h.version[1]]) + schema.Varint32.build(len(fields)) + fields


def _varint(data: bytes, pos: int, bits: int) -> tuple[int, int]:
    """schema.Leb128(bits) at ``pos``: its value and the position after it; ValueError where construct's
    parse fails (the caller then parses with construct, whose error a reader reports)."""
    value = shift = 0
    for n in range(1, schema.VARINT_MAX_BYTES + 1):
        b = data[pos]
        pos += 1
        value |= (b & 0x7F) << shift
        shift += 7
        if b < 0x80:
            if (n > 1 and b == 0) or value >> bits:
                raise ValueError
            return value, pos
    raise ValueError


#: A field of :func:`quick_head`: a byte, a varint32 or a varint (spec §2.2).
BYTE, VARINT32, VARINT64 = 8, 32, 64


def quick_head(data, layout: tuple[int, ...], window: int) -> tuple[list[int], int] | None:
    """The fields ``layout`` (:data:`BYTE`, :data:`VARINT32`, :data:`VARINT64`) at the start of ``data`` and
    the position after them, as construct parses them from ``bytes(data[:window])``; None where that parse
    fails, which the caller then runs for its error. A record head this way takes a microsecond, through
    construct twenty (a scene's objects, groups and records)."""
    end = min(len(data), window)
    out, pos = [], 0
    try:
        for field in layout:
            if field == BYTE:
                out.append(data[pos])
                pos += 1
            else:
                value, pos = _varint(data, pos, field)
                out.append(value)
    except (IndexError, ValueError):
        return None
    return (out, pos) if pos <= end else None


def _r32(data: bytes, pos: int) -> tuple[float, int]:
    bits, pos = _varint(data, pos, 32)
    return struct.unpack("<f", struct.pack("<I", schema.reverse32(bits)))[0], pos


def _header6_fields(payload: bytes) -> tuple[types.SimpleNamespace, int] | None:
    """schema.Header6's ``fields`` and ``segment_offset`` read by hand, a tenth of construct's time (which
    took half of a small file's Reader); None where that parse would fail, which then says why."""
    try:
        size, pos = _varint(payload, 2, 32)
        end = pos + size
        if end > len(payload):
            return None
        f = types.SimpleNamespace(flags=payload[pos], units=payload[pos + 1], widths=None, h_range=None, bbox=None,
                                  counts=None)
        pos += 2
        f.coding = f.flags >> schema.FLAG_CODING_SHIFT & schema.FLAG_CODING_MASK
        if f.coding in schema.CODINGS_WITH_RANGE:
            f.widths = payload[pos] | payload[pos + 1] << 8
            pos += 2
            f.h_range = [0.0, 0.0]
            for i in range(2):
                f.h_range[i], pos = _r32(payload, pos)
        if f.flags & schema.FLAG_BBOX_KNOWN:
            f.bbox = [0.0] * 6
            for i in range(6):
                f.bbox[i], pos = _r32(payload, pos)
        f.tolerance, pos = _r32(payload, pos)
        f.error_bound, pos = _r32(payload, pos)
        if f.flags & schema.FLAG_COUNTS_KNOWN:
            planes, pos = _varint(payload, pos, 64)
            objects, pos = _varint(payload, pos, 32)
            groups, pos = _varint(payload, pos, 32)
            f.counts = types.SimpleNamespace(plane_count=planes, object_count=objects, group_count=groups)
        if pos > end:
            return None
        f.extra = bytes(payload[pos:end])
        return f, end
    except (IndexError, ValueError):
        return None


def decode_header6(payload: bytes) -> tuple[Header, list[tuple[str, str]], int]:
    """A version 6 header (spec §5, checks 3 to 8), its findings, and the offset of the first body segment
    in the payload (its length where there is none)."""
    major, minor = payload[0], payload[1]
    fast = _header6_fields(payload)
    if fast is None:
        r = _parse(schema.Header6, bytes(payload), "PHDR")
        f, segment_offset = r.fields, r.segment_offset
    else:
        f, segment_offset = fast
    findings = []
    if minor > VERSIONS[major]:
        findings.append(("NEWER_MINOR_VERSION", f"file is version {major}.{minor}; read as {major}.{VERSIONS[major]}"))
    coding = Coding(f.coding)
    q = None
    if coding.quantized:
        h_min, h_max = f.h_range
        if not (math.isfinite(h_min) and math.isfinite(h_max) and h_min <= h_max):
            raise FormatError(f"h range [{h_min}, {h_max}] is not finite or reversed", code="BAD_HEADER_VALUE")
        q = Quantization(*schema.from_widths6(f.widths), h_min, h_max)
    code, up = f.units & schema.UNITS_MASK, f.units >> schema.UP_AXIS_SHIFT & 3
    if up >= len(schema.UP_AXIS_CODES):
        raise FormatError(f"unknown up axis code {up}", code="BAD_HEADER_VALUE")
    if code not in Units._value2member_map_:
        raise FormatError(f"unknown units code {code}", code="BAD_HEADER_VALUE")
    bbox = None
    if f.flags & schema.FLAG_BBOX_KNOWN:
        bbox = np.array([f.bbox[:3], f.bbox[3:]], dtype=np.float64)
        if not np.isfinite(bbox).all() or (bbox[0] > bbox[1]).any():
            raise FormatError("bounding box is not finite or min > max", code="BAD_HEADER_VALUE")
    for name in ("tolerance", "error_bound"):
        v = getattr(f, name)
        if not (math.isnan(v) or (math.isfinite(v) and v >= 0)):
            raise FormatError(f"{name} must be NaN or a finite value >= 0, not {v}", code="BAD_HEADER_VALUE")
    c = f.counts
    header = Header(
        version=(major, minor), lossy=bool(f.flags & schema.FLAG_LOSSY), coding=coding, quantization=q,
        units=Units(code), bbox=bbox, tolerance=f.tolerance, error_bound=f.error_bound,
        plane_count=c.plane_count if c else None, object_count=c.object_count if c else None,
        group_count=c.group_count if c else None, extra=bytes(f.extra), up_axis=schema.UP_AXIS_CODES[up])
    return header, findings, segment_offset


def quick_object6(payload: bytes, quick: tuple[list[int], int]) -> cs.Container | None:
    """schema.Object6 from its head as :func:`quick_head` read it: name, transform (codes and values) and
    extra bytes sliced by hand; None where construct's parse would fail."""
    (_, flags, name_length), pos = quick
    end = pos + name_length
    name = bytes(payload[pos:end])
    transform = None
    if flags & schema.OBJECT_HAS_TRANSFORM:
        codes = bytes(payload[end:end + schema.TRANSFORM_CODE_BYTES])
        if len(codes) < schema.TRANSFORM_CODE_BYTES:
            return None
        end += schema.TRANSFORM_CODE_BYTES
        size = sum(schema.TRANSFORM_VALUE_SIZES[c] for c in schema.transform_codes(codes))
        transform = cs.Container(codes=codes, values=bytes(payload[end:end + size]))
        end += size
    if end > len(payload):
        return None
    return cs.Container(name=name, transform=transform, extra=bytes(payload[end:]))
