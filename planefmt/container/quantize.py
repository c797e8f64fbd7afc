"""Plane triplet payloads: float32 / float64 records, the quantized bit stream and the predicted
varint streams (spec §7).

Everything here is vectorized: a PLNS payload is viewed with
``numpy.frombuffer`` and never parsed element by element.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import FormatError, PlnError
from ..model import Coding, Quantization
from . import varint
from .schema import PREDICTED_LIMIT

TWO_PI = 2.0 * math.pi
#: float32 nearest to pi and 2*pi; both round *up*, so float32 ranges end there.
PI_F32 = float(np.float32(math.pi))
TWO_PI_F32 = float(np.float32(TWO_PI))

MAX_BITS = 32


def check_quantization(q: Quantization) -> None:
    """Raise ``VersionError``-coded ``PlnError`` if widths or the h range are invalid (spec §7.3)."""
    for name, bits in (("nu", q.bits_nu), ("phi", q.bits_phi), ("h", q.bits_h)):
        if not 1 <= bits <= MAX_BITS:
            raise PlnError(f"bits_{name} = {bits} is outside 1..{MAX_BITS}", code="UNSUPPORTED_CODING")
    # A width that overflows binary64 would make every dequantized h infinite (spec §5, §7.3).
    if not (math.isfinite(q.h_min) and math.isfinite(q.h_max) and math.isfinite(q.h_max - q.h_min)) \
            or q.h_min > q.h_max:
        raise PlnError(f"invalid h range [{q.h_min}, {q.h_max}]", code="BAD_HEADER_VALUE")


def check_triplets(triplets: np.ndarray, coding: Coding) -> None:
    """Raise ``PlnError(BAD_TRIPLET)`` unless every triplet is finite and in range (spec §7.2)."""
    t = np.asarray(triplets)
    if t.ndim != 2 or t.shape[1] != 3:
        raise PlnError(f"triplets must have shape (n, 3), not {t.shape}", code="BAD_TRIPLET")
    if len(t) == 0:
        return
    nu_max, phi_end = (PI_F32, TWO_PI_F32) if coding == Coding.FLOAT32 else (math.pi, TWO_PI)
    # Column extremes decide it in a few contiguous passes; NaN makes every comparison false.
    nu, phi, h = t[:, 0], t[:, 1], t[:, 2]
    if (nu.min() >= 0 and nu.max() <= nu_max and phi.min() >= 0 and phi.max() < phi_end
            and np.isfinite(h.min()) and np.isfinite(h.max())):
        return
    ok = np.isfinite(t).all(axis=1) & (nu >= 0) & (nu <= nu_max) & (phi >= 0) & (phi < phi_end)
    i = int(np.flatnonzero(~ok)[0])
    raise PlnError(f"plane {i}: triplet {tuple(float(v) for v in t[i])} is not finite or out of range",
                   code="BAD_TRIPLET")


def quantize(triplets: np.ndarray, q: Quantization) -> np.ndarray:
    """Integer codes ``(n, 3)`` uint64 of triplets, by the rounding rule of spec §7.3.

    Round half up (``floor(x + 0.5)``) in float64; nu codes run 0..2**(bits_nu-1) so
    that the poles and the equator are exact; phi wraps modulo ``2**bits_phi``; at
    the poles the phi code is 0. Triplets must be in range.
    """
    t = np.asarray(triplets, dtype=np.float64)
    m_nu = float(1 << (q.bits_nu - 1))
    m_phi = 1 << q.bits_phi
    m_h = float((1 << q.bits_h) - 1)
    codes = np.empty(t.shape, dtype=np.uint64)
    qn = np.clip(np.floor(t[:, 0] / math.pi * m_nu + 0.5), 0, m_nu)
    qp = np.floor(t[:, 1] / TWO_PI * m_phi + 0.5) % m_phi
    qp[(qn == 0) | (qn == m_nu)] = 0
    span = q.h_max - q.h_min
    if span > 0:
        qh = np.clip(np.floor((t[:, 2] - q.h_min) / span * m_h + 0.5), 0, m_h)
    else:
        qh = np.zeros(len(t))
    codes[:, 0] = qn
    codes[:, 1] = qp
    codes[:, 2] = qh
    return codes


def dequantize(codes: np.ndarray, q: Quantization) -> np.ndarray:
    """Triplets ``(n, 3)`` float64 from integer codes (spec §7.3)."""
    c = np.asarray(codes, dtype=np.float64)
    out = np.empty(c.shape, dtype=np.float64, order="F")
    out[:, 0] = c[:, 0] * (math.pi / (1 << (q.bits_nu - 1)))
    out[:, 1] = c[:, 1] * (TWO_PI / (1 << q.bits_phi))
    out[:, 2] = q.h_min + c[:, 2] * ((q.h_max - q.h_min) / ((1 << q.bits_h) - 1))
    return out


def roundtrip(triplets: np.ndarray, coding: Coding, q: Quantization | None = None) -> np.ndarray:
    """The triplets a reader gets back after writing ``triplets`` with this coding."""
    return decode_payload(encode_payload(triplets, coding, q), len(triplets), coding, q)


def payload_size(count: int, coding: Coding, q: Quantization | None) -> int | None:
    """Exact byte size of the uncompressed triplet data of ``count`` planes; None for the predicted
    coding, whose size depends on the planes (3 to 15 bytes a plane)."""
    if coding == Coding.PREDICTED and q is not None:
        return None
    if coding == Coding.FLOAT32:
        return 12 * count
    if coding == Coding.FLOAT64:
        return 24 * count
    if coding == Coding.QUANTIZED and q is not None:
        return (count * q.bits_per_plane + 7) // 8
    raise PlnError(f"unsupported triplet coding {int(coding)}", code="UNSUPPORTED_CODING")


def _widths(q: Quantization) -> tuple[int, int, int]:
    return (q.bits_nu, q.bits_phi, q.bits_h)


def encode_payload(triplets: np.ndarray, coding: Coding, q: Quantization | None = None) -> bytes:
    """Uncompressed PLNS triplet data for ``triplets`` (validated first)."""
    t = np.asarray(triplets, dtype=np.float64)
    check_triplets(t, Coding.FLOAT64 if coding.quantized else coding)
    if coding == Coding.FLOAT64:
        return t.astype("<f8").tobytes()
    if coding == Coding.FLOAT32:
        t32 = t.astype("<f4")
        # phi just below 2*pi can round up to float32(2*pi): the same direction as 0.
        t32[t32[:, 1] >= np.float32(TWO_PI_F32), 1] = 0
        return t32.tobytes()
    if coding == Coding.QUANTIZED and q is not None:
        codes = quantize(t, q)
        bits = np.concatenate(
            [((codes[:, c, None] >> np.arange(w, dtype=np.uint64)) & 1).astype(np.uint8)
             for c, w in enumerate(_widths(q))], axis=1)
        return np.packbits(bits.ravel(), bitorder="little").tobytes()
    if coding == Coding.PREDICTED and q is not None:
        return _predict(quantize(t, q).astype(np.int64))
    raise PlnError(f"unsupported triplet coding {int(coding)}", code="UNSUPPORTED_CODING")


def decode_payload(data: bytes, count: int, coding: Coding, q: Quantization | None = None) -> np.ndarray:
    """Triplets ``(count, 3)`` float64 from uncompressed PLNS triplet data.

    The array is column-major (each of nu, phi, h contiguous), which makes the
    range checks single passes. Raises ``FormatError`` on a size mismatch or
    non-zero padding bits and ``PlnError(BAD_TRIPLET)`` on out-of-range floats.
    """
    expected = payload_size(count, coding, q)
    if coding == Coding.PREDICTED and q is not None:
        return dequantize(_check_codes(_unpredict(data, count), q), q)
    if len(data) != expected:
        raise FormatError(f"triplet data is {len(data)} bytes, {count} planes need {expected}",
                          code="SIZE_MISMATCH")
    if coding in (Coding.FLOAT32, Coding.FLOAT64):
        stored = np.frombuffer(data, dtype="<f4" if coding == Coding.FLOAT32 else "<f8").reshape(count, 3)
        t = np.empty((count, 3), dtype=np.float64, order="F")
        np.copyto(t, stored)
        check_triplets(t, coding)
        return t
    assert q is not None
    return dequantize(_check_codes(unpack_codes(np.frombuffer(data, dtype=np.uint8), count, _widths(q)), q), q)


def _check_codes(codes: np.ndarray, q: Quantization) -> np.ndarray:
    """The codes, if each is in its component's range (``BAD_TRIPLET`` otherwise)."""
    if not len(codes):
        return codes
    limits = (1 << (q.bits_nu - 1), (1 << q.bits_phi) - 1, (1 << q.bits_h) - 1)
    for c, (name, top) in enumerate(zip(("nu", "phi", "h"), limits)):
        col = codes[:, c].astype(np.int64)
        if col.min() < 0 or col.max() > top:
            i = int(np.flatnonzero((col < 0) | (col > top))[0])
            raise PlnError(f"plane {i}: {name} code {int(col[i])} is outside 0..{top}", code="BAD_TRIPLET")
    return codes


def _predict(codes: np.ndarray) -> bytes:
    """The three varint streams of the predicted coding (spec §7.4) for ``(n, 3)`` codes.

    nu: zigzag difference from the previous plane's code (0 before the first); phi: the
    difference if nu equals the previous nu, else the code itself; h: the difference if nu and
    phi both equal the previous ones, else the code. Planes sorted by code (the writer's order)
    make runs of one normal, which cost a zero and a small h difference each.
    """
    prev = np.vstack([np.zeros((1, 3), dtype=np.int64), codes[:-1]])
    first = np.zeros(len(codes), dtype=bool)
    first[:1] = True
    same_nu = ~first & (codes[:, 0] == prev[:, 0])
    same_normal = same_nu & (codes[:, 1] == prev[:, 1])
    d = codes - prev
    nu = varint.zigzag(d[:, 0])
    phi = np.where(same_nu, varint.zigzag(d[:, 1]), codes[:, 1].astype(np.uint64))
    h = np.where(same_normal, varint.zigzag(d[:, 2]), codes[:, 2].astype(np.uint64))
    return varint.encode(nu) + varint.encode(phi) + varint.encode(h)


def _unpredict(data: bytes, count: int) -> np.ndarray:
    """Codes ``(count, 3)`` int64 from the predicted streams, which must fill ``data`` exactly."""
    raw = np.frombuffer(data, dtype=np.uint8)
    values, used = varint.decode(raw, 3 * count, "predicted triplets")
    if used != len(raw):
        raise FormatError(f"predicted triplet data is {len(raw)} bytes, its {3 * count} varints take {used}",
                          code="SIZE_MISMATCH")
    # Codes are below 2^32, their zigzag differences below 2^33 (PREDICTED_LIMIT).
    if count and values.max() >= PREDICTED_LIMIT:
        raise FormatError("a predicted triplet varint is 2^33 or more", code="BAD_PAYLOAD")
    v = values.astype(np.int64).reshape(3, count)
    codes = np.empty((count, 3), dtype=np.int64)
    codes[:, 0] = np.cumsum(varint.unzigzag(v[0]))
    idx = np.arange(count)
    same_nu = np.r_[False, codes[1:, 0] == codes[:-1, 0]] if count else np.zeros(0, dtype=bool)
    codes[:, 1] = _runs(np.where(same_nu, varint.unzigzag(v[1]), v[1]), same_nu, idx)
    same_normal = same_nu & np.r_[False, codes[1:, 1] == codes[:-1, 1]] if count else same_nu
    codes[:, 2] = _runs(np.where(same_normal, varint.unzigzag(v[2]), v[2]), same_normal, idx)
    return codes


def _runs(values: np.ndarray, continued: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Running sums restarting wherever ``continued`` is False (there the value itself)."""
    total = np.cumsum(values)
    start = np.maximum.accumulate(np.where(continued, 0, idx))
    return total - total[start] + values[start]


def unpack_codes(raw: np.ndarray, count: int, widths: tuple[int, ...]) -> np.ndarray:
    """Integer codes ``(count, len(widths))`` from the LSB-first bit stream of spec §7.3.

    Any 8 consecutive records fill exactly ``sum(widths)`` bytes, so viewing the
    stream as rows of 8 records puts every code of a given slot at the same bit
    offset in its row: each code is assembled from at most 5 byte columns with
    constant shifts, with no per-bit expansion and no gathers.
    """
    per = sum(widths)
    total = count * per
    if total % 8 and raw[-1] >> (total % 8):
        raise FormatError("non-zero padding bits after the last quantized triplet", code="BAD_PAYLOAD")
    if all(w in (8, 16, 32) for w in widths):
        # Byte-aligned widths: one structured view reads each component in a single pass.
        offsets = np.cumsum((0,) + widths[:-1]) // 8
        dtype = np.dtype({"names": [f"c{i}" for i in range(len(widths))],
                          "formats": [f"<u{w // 8}" for w in widths],
                          "offsets": offsets.tolist(), "itemsize": per // 8})
        records = raw.view(dtype)
        codes = np.empty((count, len(widths)), dtype=np.uint64, order="F")
        for c in range(len(widths)):
            codes[:, c] = records[f"c{c}"]
        return codes
    rows = (count + 7) // 8
    block = np.zeros(rows * per, dtype=np.uint8)
    block[: len(raw)] = raw
    block = block.reshape(rows, per)
    codes = np.empty((rows * 8, len(widths)), dtype=np.uint64, order="F")
    for slot in range(8):
        offset = slot * per
        for c, w in enumerate(widths):
            first, shift = offset >> 3, offset & 7
            word = np.zeros(rows, dtype=np.uint64)
            for k in range(min((shift + w + 7) // 8, per - first)):
                word |= block[:, first + k].astype(np.uint64) << np.uint64(8 * k)
            codes[slot::8, c] = (word >> np.uint64(shift)) & np.uint64((1 << w) - 1)
            offset += w
    return codes[:count]


def half_steps(q: Quantization) -> np.ndarray:
    """Largest error per component ``(nu, phi, h)`` of quantize-then-dequantize."""
    return np.array(q.steps()) / 2.0
