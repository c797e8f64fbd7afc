"""Building blocks of the golden files: chunk layouts, the spec's triplet decoding, expected JSON.

Broken files are chunk layouts, lists of ``(type, payload)``, made from
planefmt's payload encoders, given one defect, and framed with planefmt's
``chunk_bytes`` so that every CRC is computed, never typed. The expected
plane values are derived here from the spec's formulas (§7.2, §7.3), not
read back through planefmt, so that the suite checks planefmt's reader
rather than echoing it.
"""

from __future__ import annotations

import dataclasses
import json
import math
import zlib

import brotli
import numpy as np

from planefmt import chunk_bytes
from planefmt.container import headers, records, schema, segments
from planefmt.model import UP_AXIS, Coding, Header, Quantization, Units

Layout = list[tuple[bytes, bytes]]

#: The cube of spec/pln-1.md §12 as (nu, phi, h): faces x = 1, y = 1, x = 0, y = 0, z = 1, z = 0.
CUBE = np.array([
    [math.pi / 2, 0.0, 1.0],
    [math.pi / 2, math.pi / 2, 1.0],
    [math.pi / 2, math.pi, 0.0],
    [math.pi / 2, 1.5 * math.pi, 0.0],
    [0.0, 0.0, 1.0],
    [math.pi, 0.0, 0.0],
])

#: The header of spec/pln-1.md §12 (the writer fills in the counts).
SPEC_HEADER = Header(coding=Coding.FLOAT32, units=Units.METRE, bbox=np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]),
                     tolerance=1e-6, error_bound=0.0)


def box(lo, hi) -> np.ndarray:
    """Triplets of the six faces of the box ``lo <= x <= hi``, in the order of ``CUBE``."""
    t = CUBE.copy()
    t[:, 2] = [hi[0], hi[1], -lo[0], -lo[1], hi[2], -lo[2]]
    return t


def compact(layout: Layout) -> bool:
    """Whether ``layout``'s chunks after PHDR have varint lengths: its header says version 5 (spec §4.1)."""
    return bool(layout) and layout[0][0] == schema.PHDR and layout[0][1][:1] >= b"\x05"


def frame(layout: Layout, signature: bytes = schema.SIGNATURE) -> bytes:
    """``layout`` framed as its header's version frames it: PHDR with a u32 length, the rest as §4.1 says."""
    short = compact(layout)
    return signature + b"".join(chunk_bytes(t, p, short and i > 0) for i, (t, p) in enumerate(layout))


def offsets(layout: Layout) -> list[int]:
    """Byte offset of each chunk of ``layout`` in the framed file."""
    short = compact(layout)
    out, pos = [], len(schema.SIGNATURE)
    for i, (t, payload) in enumerate(layout):
        out.append(pos)
        pos += len(chunk_bytes(t, payload, short and i > 0)) if t else 12 + len(payload)
    return out


def index_payload(layout: Layout, major: int = 1) -> bytes:
    """The iNDX payload listing the OBJT, PLNS and GRUP chunks of ``layout`` (spec §10.2).

    Ordinals are read from the payloads themselves (object index, first plane,
    group index: a u32 / u64 in versions 1 and 2, a varint in version 3), so a
    layout with a defect in those fields keeps an index that agrees with its
    chunks.
    """
    entries = [(off, t, records.leading_index(p, major, 4)) for off, (t, p) in zip(offsets(layout), layout)
               if t in (schema.OBJT, schema.PLNS, schema.GRUP)]
    return records.encode_index(np.array(entries, dtype=schema.INDEX_ENTRY_DTYPE))


def finish(layout: Layout, index: bool = True, major: int = 1) -> Layout:
    """``layout`` followed by its iNDX (optional) and PEND chunks."""
    if not index:
        return layout + [(schema.PEND, records.encode_end(0, major))]
    at = offsets(layout + [(b"", b"")])[-1]
    return layout + [(schema.INDX, index_payload(layout, major)), (schema.PEND, records.encode_end(at, major))]


def stored_header(h: Header) -> Header:
    """The header values a reader gets back: version 3 stores the bbox rounded outward to float32 and
    tolerance and error bound rounded up (spec §5), written out here from that rule; so does 4."""
    if h.version[0] < 3:
        return h

    def toward(x: float, direction: float) -> float:
        f = np.float32(x)
        if (direction > 0 and float(f) < x) or (direction < 0 and float(f) > x):
            f = np.nextafter(f, np.float32(direction))
        return float(f)

    bbox = None if h.bbox is None else np.array(
        [[toward(float(x), -math.inf) for x in h.bbox[0]], [toward(float(x), math.inf) for x in h.bbox[1]]])
    def up(v: float) -> float:
        return v if math.isnan(v) else toward(v, math.inf)

    if h.version[0] >= 6:
        # Version 6 keeps 12 explicit mantissa bits of both (spec §5).
        return dataclasses.replace(h, bbox=bbox, tolerance=headers.r32_up(h.tolerance, "tolerance"),
                                   error_bound=headers.r32_up(h.error_bound, "error_bound"))
    return dataclasses.replace(h, bbox=bbox, tolerance=up(h.tolerance), error_bound=up(h.error_bound))


# -- spec §7: what a reader decodes ----------------------------------------------------------

def stored_planes(triplets: np.ndarray, coding: int, q: Quantization | None) -> np.ndarray:
    """The triplets a conforming reader decodes after a writer stored ``triplets``."""
    t = np.asarray(triplets, dtype=np.float64).reshape(-1, 3)
    if coding == Coding.FLOAT64:
        return t.copy()
    if coding == Coding.FLOAT32:
        t32 = t.astype(np.float32)
        t32[t32[:, 1] >= np.float32(2 * math.pi), 1] = 0  # §7.2: phi rounded up to 2 pi is stored as 0
        return t32.astype(np.float64)
    # §7.3, written out as the spec states it: binary64, round(x) = floor(x + 0.5).
    m_nu, n_phi, m_h = 2.0 ** (q.bits_nu - 1), 2.0 ** q.bits_phi, 2.0 ** q.bits_h - 1
    out = np.empty_like(t)
    for row, (nu, phi, h) in zip(out, t):
        q_nu = min(max(math.floor(nu / math.pi * m_nu + 0.5), 0), m_nu)
        q_phi = math.floor(phi / (2 * math.pi) * n_phi + 0.5) % n_phi
        if q_nu in (0, m_nu):
            q_phi = 0
        q_h = 0
        if q.h_max != q.h_min:
            q_h = min(max(math.floor((h - q.h_min) / (q.h_max - q.h_min) * m_h + 0.5), 0), m_h)
        row[:] = (q_nu * (math.pi / m_nu), q_phi * (2 * math.pi / n_phi),
                  q.h_min + q_h * ((q.h_max - q.h_min) / m_h))
    return out


def world_matrices(objects: list[tuple[int | None, np.ndarray | None]]) -> list[np.ndarray]:
    """World matrix of each object from ``(parent, local transform)`` pairs (spec §8)."""
    out: list[np.ndarray] = []
    for parent, m in objects:
        local = np.eye(4) if m is None else np.asarray(m, dtype=np.float64)
        out.append(local if parent is None else out[parent] @ local)
    return out


# -- expected JSON ---------------------------------------------------------------------------

def rounded(x):
    """Geometry floats to 9 decimals: Qhull's last bits vary between machines, the files must not."""
    if isinstance(x, (list, tuple, np.ndarray)):
        return [rounded(v) for v in x]
    return None if x is None else round(float(x), 9) + 0.0  # + 0.0 turns -0.0 into 0.0


def optional_float(x: float) -> float | None:
    """JSON has no NaN: the contract writes NaN (not given / not measured) as null."""
    return None if math.isnan(x) else float(x)


def shell_json(shell) -> dict:
    """A shell group's corners and triangles as the contract reports them (README.md): indices of
    the explicit corners, named corners' references, grid, triangles (face -1: free)."""
    return {"explicit": np.flatnonzero(shell.explicit).tolist(),
            "vertex_planes": np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1, 3).tolist(),
            "grid": np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3).tolist(),
            # The grid is stored only for explicit corners (spec §9.10).
            "origin": [float(x) for x in shell.origin] if np.any(shell.explicit) else None,
            "step": float(shell.step) if np.any(shell.explicit) else None,
            "facets": np.asarray(shell.facets, dtype=np.int64).tolist()}


def header_json(h: Header, counts: tuple[int, int, int] | None) -> dict:
    q = h.quantization
    return {
        "version": list(h.version),
        "lossy": h.lossy,
        "coding": int(h.coding),
        "bits": [q.bits_nu, q.bits_phi, q.bits_h] if q else [0, 0, 0],
        "h_range": [q.h_min, q.h_max] if q else [0.0, 0.0],
        "units": int(h.units),
        "bbox": None if h.bbox is None else np.asarray(h.bbox, dtype=np.float64).tolist(),
        "tolerance": optional_float(h.tolerance),
        "error_bound": optional_float(h.error_bound),
        "counts": None if counts is None else dict(zip(("planes", "objects", "groups"), counts)),
    }


def metadata_json(h: Header, metadata: dict[str, str]) -> dict[str, str]:
    """What a reader reports as the file's metadata: its mETA chunks, and version 5's up axis (spec §5)."""
    return {**metadata, **({UP_AXIS: h.up_axis} if h.up_axis is not None else {})}


def dumps(obj, indent: int = 0) -> str:
    """JSON with one line per innermost list: readable, and diffable line by line."""
    pad, inner = " " * indent, " " * (indent + 1)
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        items = [f"{inner}{json.dumps(k)}: {dumps(v, indent + 1)}" for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(obj, list) and any(isinstance(v, (dict, list)) for v in obj):
        return "[\n" + ",\n".join(inner + dumps(v, indent + 1) for v in obj) + "\n" + pad + "]"
    return json.dumps(obj, allow_nan=False, ensure_ascii=False)


# -- version 6: records in body segments (spec §4.5, §4.6, §10.2) -----------------------------------

#: One item of a version 6 layout: ``(tag, payload)`` a record; ``(b"BODY", b"")`` the start of a new
#: segment; ``(ctype, payload)`` of a four-letter type an ancillary chunk between segments.
Item = tuple


def split(empty: bool = False) -> Item:
    """Marks where a new body segment starts (a BODY chunk); ``empty``: a BODY chunk whose segment holds
    no record comes first (spec §4.5 allows one; a writer never needs it)."""
    return (schema.BODY, b"empty" if empty else b"")


def forced_segment(raw: bytes, method: int) -> bytes:
    """A body segment of ``raw`` stored with ``method`` (0, 1 or 2), whichever size that gives."""
    stored = {0: lambda b: b, 1: lambda b: zlib.compress(b, 9), 2: lambda b: brotli.compress(b, quality=11)}[method](raw)
    return bytes([method]) + schema.Varint32.build(len(raw)) + stored


def small_v6(items: list[Item]) -> bool:
    """Whether a writer leaves the bbox and counts out (spec §5 "Small files"): one segment, in PHDR, under
    256 raw bytes."""
    if any(isinstance(i[0], bytes) for i in items):
        return False
    return sum(len(segments.record_bytes(t, p)) for t, p in items) < 256


def assemble_v6(header: Header, items: list[Item], *, index: bool = False, compress: bool = True,
                methods: tuple[int, ...] | None = None) -> bytes:
    """A version 6 file: ``items`` (records, segment starts, chunks) in body segments, the first in PHDR,
    each stored by the smallest method (``methods``: the method of each segment), then iNDX and PEND."""
    if small_v6(items):
        header = dataclasses.replace(header, bbox=None, plane_count=None, object_count=None, group_count=None)
    out = bytearray(schema.SIGNATURE)
    entries, ordinals = [], {schema.TAG_OBJECT: 0, schema.TAG_PLANES: 0, schema.TAG_GROUP: 0}
    pending: list[tuple[int, bytes]] = []
    written = 0  # segments written

    def flush() -> None:
        nonlocal written
        raw = b"".join(segments.record_bytes(t, p) for t, p in pending)
        if written and not raw:
            return
        segment = b"" if not raw else (forced_segment(raw, methods[written]) if methods
                                        else segments.segment_bytes(raw, compress))
        chunk = len(out)
        pos = 0
        for t, p in pending:
            if t in ordinals:
                entries.append((chunk, pos, t, ordinals[t]))
                ordinals[t] += records.leading_index(p, 3, 0) if t == schema.TAG_PLANES else 1
            pos += len(segments.record_bytes(t, p))
        if written:
            out.extend(chunk_bytes(schema.BODY, segment, True))
        else:
            out.extend(chunk_bytes(schema.PHDR, records.encode_header(header) + segment))
        written += 1
        pending.clear()

    for item in items:
        if item[0] == schema.BODY:
            flush()
            if item[1]:
                out.extend(chunk_bytes(schema.BODY, forced_segment(b"", methods[written] if methods else 0), True))
                written += 1
        elif isinstance(item[0], bytes):
            flush()
            out.extend(chunk_bytes(item[0], item[1], True))
        else:
            pending.append(item)
    flush()
    at = 0
    if index:
        at = len(out)
        out.extend(chunk_bytes(schema.INDX, segments.encode_index(entries), True))
    out.extend(chunk_bytes(schema.PEND, records.encode_end(at, 6), True))
    return bytes(out)
