"""Chunk payloads <-> model records (spec §5–§10), with every check the spec requires.

Decoders take a payload (already framed and CRC-checked) and raise
``PlnError`` subclasses without location; the reader adds file, chunk and
offset. Encoders take model records and return payload bytes.
"""

from __future__ import annotations

import math
import struct

import construct as cs
import numpy as np

from . import quantize, schema, varint
from .headers import (BYTE, VARINT32, VARINT64, _f32_toward, _f32_up, _parse, decode_header6, encode_header6,
                      quick_head, quick_object6)
from .budget import Budget, Charge
from .chunks import Limits
from .compression import SHELL_TREE_LEVEL, pack, unpack
from ..errors import FormatError, LimitError, PlnError, VersionError
from ..model import (BSP_IN, BSP_MAX_SPLIT, BSP_OUT, NO_PARENT, TREE_KINDS, UP_AXES, UP_AXIS, Coding, Colours,
                    GroupKind, Header, Metadata, ObjectRecord, PartGroup, PlaneBlock, Quantization, Units)
from .shellfields import _decode_shell, _decode_shell_tree
from .shellwalk import WALK_KINDS, decode_shell_walk, shell_kind_data
from .versions import VERSIONS

#: Triplet codings each major version allows (spec §5, §7.4; Appendix A.1).
CODINGS = {1: (0, 1, 2), 2: (0, 1, 2, 3), 3: (0, 1, 2, 3), 4: (0, 1, 2, 3), 5: (0, 1, 2, 3), 6: (0, 1, 2, 3)}
KNOWN_KINDS = frozenset(int(k) for k in GroupKind)
#: The kind each version added after 1.0: ``(major, minor)`` it needs.
KIND_VERSION = {int(GroupKind.SEALED): (3, 1), int(GroupKind.SHELL): (3, 2), int(GroupKind.SHELL_TREE): (3, 3),
                int(GroupKind.SHELL_TREE_PARALLELOGRAM): (3, 4), int(GroupKind.SHELL_WALK): (4, 1),
                int(GroupKind.SHELL_WALK_MULTI): (4, 2), int(GroupKind.COPY): (4, 2),
                int(GroupKind.SHELL_WALK_REFLECT): (5, 1), int(GroupKind.SHELL_WALK_LATER): (5, 2)}
#: Kinds whose groups may have no reference in version 5 (spec §9.2): shells of free triangles over
#: explicit corners, and copies of them.
UNREFERENCED_KINDS = frozenset({int(GroupKind.SHELL), *map(int, TREE_KINDS), int(GroupKind.COPY)})


def _kind(value: int) -> GroupKind | int:
    """A kind this reader knows as its :class:`GroupKind`; one of a newer minor version stays an int."""
    return GroupKind(value) if value in GroupKind._value2member_map_ else value


def kinds_of(major: int, minor: int) -> frozenset[int]:
    """The part-group kinds a file of version ``major.minor`` may hold (as far as this reader knows)."""
    return frozenset(k for k in KNOWN_KINDS
                     if k not in KIND_VERSION or (major, minor) >= KIND_VERSION[k])


# spec §5 Header ------------------------------------------------------------------------------

def encode_header(h: Header) -> bytes:
    if h.version[0] >= 6:
        return encode_header6(h)
    q = h.quantization
    flags = (schema.FLAG_LOSSY if h.lossy else 0)
    counts = (h.plane_count, h.object_count, h.group_count)
    if all(c is not None for c in counts):
        flags |= schema.FLAG_COUNTS_KNOWN
    if h.bbox is not None:
        flags |= schema.FLAG_BBOX_KNOWN
    bbox = np.zeros((2, 3)) if h.bbox is None else np.asarray(h.bbox, dtype=np.float64)
    fields = dict(
        version_major=h.version[0], version_minor=h.version[1], flags=flags, coding=int(h.coding),
        bits_nu=q.bits_nu if q else 0, bits_phi=q.bits_phi if q else 0, bits_h=q.bits_h if q else 0,
        units=int(h.units), extra=h.extra)
    if h.version[0] >= 5:
        fields["units"] = int(h.units) | schema.UP_AXIS_CODES.index(h.up_axis) << schema.UP_AXIS_SHIFT
    elif h.up_axis is not None:
        raise PlnError("before version 5 the up axis is a mETA chunk, not a header field", code="BAD_HEADER_VALUE")
    if h.version[0] >= 3:
        return (schema.Header5 if h.version[0] >= 5 else schema.Header3).build(dict(
            fields, h_range=[q.h_min, q.h_max] if h.coding.quantized else None,
            bbox=None if h.bbox is None else [*_f32_toward(bbox[0], -math.inf, "a bounding box coordinate"),
                                              *_f32_toward(bbox[1], math.inf, "a bounding box coordinate")],
            tolerance=_f32_up(h.tolerance, "tolerance"), error_bound=_f32_up(h.error_bound, "error_bound"),
            counts=dict(plane_count=counts[0], object_count=counts[1], group_count=counts[2])
            if flags & schema.FLAG_COUNTS_KNOWN else None))
    return schema.Header.build(dict(
        fields, reserved=b"\0\0\0", h_min=q.h_min if q else 0.0, h_max=q.h_max if q else 0.0,
        bbox_min=list(bbox[0]), bbox_max=list(bbox[1]),
        tolerance=h.tolerance, error_bound=h.error_bound,
        plane_count=h.plane_count or 0, object_count=h.object_count or 0, group_count=h.group_count or 0,
    ))


def header_size(major: int) -> int:
    """The smallest PHDR payload of a version ``major`` file."""
    return schema.HEADER5_FIXED if major >= 5 else schema.HEADER3_FIXED if major >= 3 else schema.HEADER_SIZE


def decode_header(payload: bytes) -> tuple[Header, list[tuple[str, str]]]:
    """The header and non-fatal findings (code, message)."""
    return decode_header_at(payload)[:2]


def decode_header_at(payload: bytes) -> tuple[Header, list[tuple[str, str]], int | None]:
    """:func:`decode_header`, and where the first body segment of a version 6 file starts (else None)."""
    if len(payload) < 2:
        raise FormatError("PHDR is too short to hold a version", code="BAD_PAYLOAD")
    major, minor = payload[0], payload[1]
    if major not in VERSIONS:
        raise VersionError(f"major version {major} is not supported (this reader reads 1.x to 6.x)")
    if major >= 6:
        return decode_header6(payload)
    if len(payload) < header_size(major):
        raise FormatError(f"PHDR is {len(payload)} bytes, version {major} needs {header_size(major)}",
                          code="BAD_PAYLOAD")
    findings = []
    if minor > VERSIONS[major]:
        findings.append(("NEWER_MINOR_VERSION", f"file is version {major}.{minor}; read as {major}.{VERSIONS[major]}"))
    if major >= 3:
        # The coding decides which fields follow the fixed part, so it is checked before they are read.
        at = 3 if major >= 5 else 4
        if payload[at] not in CODINGS[major]:
            raise VersionError(f"triplet coding {payload[at]} is not supported in a version {major} file",
                               code="UNSUPPORTED_CODING")
        r = _parse(schema.Header5 if major >= 5 else schema.Header3, payload, "PHDR")
        h_min, h_max = r.h_range if r.h_range is not None else (0.0, 0.0)
        bbox_min, bbox_max = (r.bbox[:3], r.bbox[3:]) if r.bbox is not None else (None, None)
        counts = r.counts or cs.Container(plane_count=0, object_count=0, group_count=0)
    else:
        r = _parse(schema.Header, payload, "PHDR")
        h_min, h_max, bbox_min, bbox_max, counts = r.h_min, r.h_max, r.bbox_min, r.bbox_max, r
    if r.coding not in CODINGS[major]:
        raise VersionError(f"triplet coding {r.coding} is not supported in a version {major} file",
                           code="UNSUPPORTED_CODING")
    coding = Coding(r.coding)
    q = None
    if coding.quantized:
        q = Quantization(r.bits_nu, r.bits_phi, r.bits_h, h_min, h_max)
        quantize.check_quantization(q)
    code, up_axis = r.units, None
    if major >= 5:
        code, up = r.units & schema.UNITS_MASK, r.units >> schema.UP_AXIS_SHIFT & 3
        if up >= len(schema.UP_AXIS_CODES):
            raise FormatError(f"unknown up axis code {up}", code="BAD_HEADER_VALUE")
        up_axis = schema.UP_AXIS_CODES[up]
    units = Units(code) if code in Units._value2member_map_ else None
    if units is None:
        raise FormatError(f"unknown units code {code}", code="BAD_HEADER_VALUE")
    bbox = None
    if r.flags & schema.FLAG_BBOX_KNOWN:
        bbox = np.array([bbox_min, bbox_max], dtype=np.float64)
        if not np.isfinite(bbox).all() or (bbox[0] > bbox[1]).any():
            raise FormatError("bounding box is not finite or min > max", code="BAD_HEADER_VALUE")
    for name in ("tolerance", "error_bound"):
        v = getattr(r, name)
        if not (math.isnan(v) or (math.isfinite(v) and v >= 0)):
            raise FormatError(f"{name} must be NaN or a finite value >= 0, not {v}", code="BAD_HEADER_VALUE")
    known = bool(r.flags & schema.FLAG_COUNTS_KNOWN)
    header = Header(
        version=(major, minor), lossy=bool(r.flags & schema.FLAG_LOSSY), coding=coding, quantization=q,
        units=units, bbox=bbox, tolerance=r.tolerance, error_bound=r.error_bound,
        plane_count=counts.plane_count if known else None, object_count=counts.object_count if known else None,
        group_count=counts.group_count if known else None, extra=bytes(r.extra), up_axis=up_axis,
    )
    return header, findings, None


def leading_index(payload: bytes, major: int, width: int) -> int:
    """The number an OBJT, PLNS or GRUP payload starts with (index or first plane): a u32 / u64 of
    ``width`` bytes in versions 1 and 2, a varint in versions 3 and 4."""
    if major >= 3:
        return _parse(schema.Varint, bytes(payload[:schema.VARINT_MAX_BYTES]), "chunk head")
    return int.from_bytes(payload[:width], "little")


# spec §7 Plane table -------------------------------------------------------------------------

def encode_planes(first: int, triplets: np.ndarray, header: Header, compress: bool, brotli_allowed: bool = True) -> bytes:
    raw = quantize.encode_payload(triplets, header.coding, header.quantization)
    if header.version[0] >= 6:
        return schema.Varint32.build(len(triplets)) + raw
    method, stored = pack(raw, compress, brotli_allowed=brotli_allowed and header.version[0] >= 4)
    if header.version[0] >= 3:
        return schema.PlaneBlock3.build(dict(first=first, count=len(triplets), compression=method,
                                             raw_size=len(raw), data=stored))
    return schema.PlaneBlock.build(dict(first=first, count=len(triplets), compression=method,
                                        reserved=b"\0\0\0", raw_size=len(raw), data=stored))


def decode_planes(payload: bytes, header: Header, expected_first: int, limits: Limits) -> PlaneBlock:
    # Only the head goes through construct: the data stays a zero-copy view.
    if header.version[0] >= 6:
        return _decode_planes6(payload, header, expected_first, limits)
    if header.version[0] >= 3:
        r = _parse(schema.PlaneBlock3, bytes(payload[:schema.PLANE_BLOCK3_MAX_HEAD]), "PLNS")
        start = r.data_offset
    else:
        if len(payload) < schema.PLANE_BLOCK_HEAD:
            raise FormatError("PLNS payload is shorter than its 20-byte head", code="BAD_PAYLOAD")
        r = _parse(schema.PlaneBlock, bytes(payload[:schema.PLANE_BLOCK_HEAD]), "PLNS")
        start = schema.PLANE_BLOCK_HEAD
    if r.first != expected_first:
        raise FormatError(f"block starts at plane {r.first}, the table has {expected_first}",
                          code="PLANE_INDEX_MISMATCH")
    if r.first + r.count > limits.max_planes:
        raise LimitError(f"plane table would exceed {limits.max_planes} planes")
    expected = quantize.payload_size(r.count, header.coding, header.quantization)
    if expected is None:
        # Predicted: three varints of 1 to 5 bytes a plane (codes below 2^33).
        low, high = schema.PREDICTED_BYTES
        if not low * r.count <= r.raw_size <= high * r.count:
            raise FormatError(f"raw size {r.raw_size} is outside 3..15 bytes a plane for {r.count} planes",
                              code="SIZE_MISMATCH")
    elif r.raw_size != expected:
        raise FormatError(f"raw size {r.raw_size} != {expected} bytes for {r.count} planes",
                          code="SIZE_MISMATCH")
    raw = unpack(r.compression, memoryview(payload)[start:], r.raw_size, limits, header.version[0])
    triplets = quantize.decode_payload(raw, r.count, header.coding, header.quantization)
    return PlaneBlock(first=r.first, triplets=triplets)


def _decode_planes6(payload: bytes, header: Header, first: int, limits: Limits) -> PlaneBlock:
    """A planes record (spec §7.1, version 6): the count, then raw triplet data, its size checked against it."""
    r = _parse(schema.PlaneRecordHead, bytes(payload[:5]), "planes record")
    if first + r.count > limits.max_planes:
        raise LimitError(f"plane table would exceed {limits.max_planes} planes")
    data = memoryview(payload)[r.data_offset:]
    expected = quantize.payload_size(r.count, header.coding, header.quantization)
    if expected is None:
        low, high = schema.PREDICTED_BYTES
        if not low * r.count <= len(data) <= high * r.count:
            raise FormatError(f"{len(data)} bytes of data are outside 3..15 bytes a plane for {r.count} planes",
                              code="SIZE_MISMATCH")
    elif len(data) != expected:
        raise FormatError(f"{len(data)} bytes of data != {expected} bytes for {r.count} planes", code="SIZE_MISMATCH")
    return PlaneBlock(first=first, triplets=quantize.decode_payload(data, r.count, header.coding, header.quantization))


# spec §8 Objects ---------------------------------------------------------------------------

def encode_object(o: ObjectRecord, major: int = 1) -> bytes:
    name = o.name.encode("utf-8")
    if len(name) > 0xFFFF:
        raise PlnError(f"object name is {len(name)} bytes, at most 65535", code="BAD_OBJECT")
    m = None if o.transform is None else np.asarray(o.transform, dtype=np.float64).reshape(4, 4)
    flags = schema.OBJECT_HAS_TRANSFORM if m is not None else 0
    if major >= 6:
        return schema.Object6.build(dict(head=dict(parent=0 if o.parent is None else o.parent + 1, flags=flags,
                                                   name_length=len(name)),
                                         name=name, transform=None if m is None else _transform4(m), extra=b""))
    if major >= 3:
        head = dict(index=o.index, parent=0 if o.parent is None else o.parent + 1, flags=flags, name_length=len(name))
        if major >= 4:
            return schema.Object4.build(dict(head=head, name=name, transform=None if m is None else _transform4(m),
                                             extra=b""))
        return schema.Object3.build(dict(head=head, name=name, transform=None if m is None else m.astype("<f8").tobytes(),
                                         extra=b""))
    return schema.Object.build(dict(
        index=o.index, parent=NO_PARENT if o.parent is None else o.parent,
        flags=flags, reserved=b"\0", name_length=len(name), name=name,
        transform=None if m is None else m.astype("<f8").tobytes(), extra=b""))


def _transform4(m: np.ndarray) -> dict:
    """Spec §8, version 4: each entry of the top three rows with the shortest code that holds it."""
    if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
        raise PlnError("a transform's last row must be 0 0 0 1", code="BAD_OBJECT")
    entries = m[:3].reshape(-1)
    with np.errstate(over="ignore"):  # an entry beyond the f32 range is no f32: it takes code 3
        f32 = entries.astype(np.float32)
    exact32 = f32.astype(np.float64) == entries
    zero = (entries == 0.0) & ~np.signbit(entries)
    codes = np.where(zero, 0, np.where(entries == 1.0, 1, np.where(exact32, 2, 3)))
    bits = sum(int(c) << (2 * i) for i, c in enumerate(codes))
    values = b"".join(f32[i].astype("<f4").tobytes() if c == 2 else entries[i].astype("<f8").tobytes()
                      for i, c in enumerate(codes) if c >= 2)
    return dict(codes=bits.to_bytes(schema.TRANSFORM_CODE_BYTES, "little"), values=values)


def _transform_from4(t) -> np.ndarray:
    codes = schema.transform_codes(t.codes)
    # One unpack of every stored value (codes 2 and 3: f32, f64), not an array per entry.
    values = struct.unpack("<" + "".join("f" if c == 2 else "d" for c in codes if c >= 2), bytes(t["values"]))
    stored = iter(values)
    entries = [float(c) if c < 2 else next(stored) for c in codes] + [0.0, 0.0, 0.0, 1.0]
    return np.array(entries, dtype=np.float64).reshape(4, 4)


def decode_object(payload: bytes, expected_index: int, major: int = 1) -> ObjectRecord:
    if major >= 6:
        # An object record has no index: it is its position (spec §8).
        quick = quick_head(payload, (VARINT32, BYTE, VARINT64), 2 * schema.VARINT_MAX_BYTES + 1)
        if quick is None:
            head = _parse(schema.Object6Head, bytes(payload[:2 * schema.VARINT_MAX_BYTES + 1]), "object record")
        else:
            (parent, flags, name_length), _ = quick
            head = cs.Container(parent=parent, flags=flags, name_length=name_length)
        if head.name_length > schema.OBJECT3_MAX_NAME:
            raise FormatError(f"object name of {head.name_length} bytes, at most 65535", code="BAD_OBJECT")
        r = quick_object6(payload, quick) if quick is not None else None
        if r is None:
            r = _parse(schema.Object6, payload, "object record")
        index, parent = expected_index, None if head.parent == 0 else head.parent - 1
    elif major >= 3:
        # The head first: a name length over the cap is BAD_OBJECT before the name is looked for.
        head = _parse(schema.Object3Head, bytes(payload[:3 * schema.VARINT_MAX_BYTES + 1]), "OBJT")
        if head.name_length > schema.OBJECT3_MAX_NAME:
            raise FormatError(f"object name of {head.name_length} bytes, at most 65535", code="BAD_OBJECT")
        r = _parse(schema.Object4 if major >= 4 else schema.Object3, payload, "OBJT")
        index, parent = head.index, None if head.parent == 0 else head.parent - 1
    else:
        r = _parse(schema.Object, payload, "OBJT")
        index, parent = r.index, None if r.parent == NO_PARENT else r.parent
    if index != expected_index:
        raise FormatError(f"object index {index}, expected {expected_index}", code="BAD_OBJECT")
    if parent is not None and parent >= index:
        raise FormatError(f"parent {parent} of object {index} is not an earlier object", code="BAD_OBJECT")
    try:
        name = bytes(r.name).decode("utf-8")
    except UnicodeDecodeError:
        raise FormatError("object name is not valid UTF-8", code="BAD_OBJECT") from None
    transform = None
    if r.transform is not None:
        if major >= 4:
            transform = _transform_from4(r.transform)
        else:
            transform = np.frombuffer(r.transform, dtype="<f8").reshape(4, 4).astype(np.float64)
        if not np.isfinite(transform).all() or not np.array_equal(transform[3], [0, 0, 0, 1]):
            raise FormatError("transform is not a finite affine matrix (last row 0 0 0 1)", code="BAD_OBJECT")
    return ObjectRecord(index=index, name=name, parent=parent, transform=transform)


# spec §9 Part groups ------------------------------------------------------------------

def encode_group(g: PartGroup, compress: bool, major: int = 1, brotli_allowed: bool = True,
                 body: bytes | None = None) -> bytes:
    """The GRUP payload; ``major`` 2 and 3 write the varint body of spec §9.2, 3 with the varint
    head of 3.0 (spec §9.1, §9.2; version 1's u32 body: Appendix A.1). ``body``: the raw body of
    versions 2 to 4, where the caller has made it already."""
    if g.facets is not None and major < 3:
        raise PlnError("sealed groups need version 3.1", code="UNKNOWN_GROUP_KIND")
    if g.shell is not None and major < 3:
        raise PlnError("shell groups need version 3.2", code="UNKNOWN_GROUP_KIND")
    if body is None:
        body = group_body(g, brotli_allowed, major) if major >= 2 else _body(g)
    if major >= 6:
        return schema.GroupHead6.build(dict(object=g.object, kind=int(g.kind))) + body
    method, stored = pack(body, compress, SHELL_TREE_LEVEL if g.kind in TREE_KINDS else 9,
                          brotli_allowed=brotli_allowed and major >= 4)
    if major >= 3:
        return schema.GroupHead3.build(dict(index=g.index, object=g.object, kind=int(g.kind), compression=method,
                                            raw_size=len(body), body=stored))
    return schema.GroupHead.build(dict(index=g.index, object=g.object, kind=int(g.kind), compression=method,
                                       reserved=b"\0\0", raw_size=len(body), body=stored))


def _roles(g: PartGroup) -> bytes:
    return np.packbits(np.asarray(g.bounding, dtype=bool), bitorder="little").tobytes()


def group_body(g: PartGroup, decide: bool = True, major: int = 4) -> bytes:
    """The raw (uncompressed) GRUP body of versions 2 to 5 (spec §9.2): references, roles, kind data
    (``decide`` False: a shell walk's mode as deflate ranks them, for a size trial)."""
    refs = np.asarray(g.refs, dtype=np.int64)
    gaps = np.diff(refs, prepend=0)
    if len(refs) and gaps[1:].min(initial=0) < 0:
        raise PlnError("a version 2 group's references must not decrease", code="BAD_GROUP_STRUCTURE")
    out = [varint.encode([len(refs)]), varint.encode(gaps), _roles(g)]
    if g.kind == GroupKind.CELLS:
        cells = g.cells or ()
        out += [varint.encode([len(cells)]), varint.encode([len(c) for c in cells])]
        out += [varint.encode(np.asarray(c, dtype=np.uint64)) for c in cells]
    elif g.kind == GroupKind.BSP:
        tokens = np.asarray(g.tree, dtype=np.uint64)
        coded = np.where(tokens == BSP_IN, schema.COMPACT_IN,
                         np.where(tokens == BSP_OUT, schema.COMPACT_OUT, tokens + np.uint64(schema.COMPACT_SPLIT)))
        out += [varint.encode([len(tokens)]), varint.encode(coded)]
    elif g.kind == GroupKind.SEALED and g.facets is not None:
        facets = np.asarray(g.facets, dtype=np.int64)
        gaps = np.diff(facets[:, 0], prepend=0)
        if gaps.min(initial=0) < 0:
            raise PlnError("a sealed group's triangles must be in order of their face references",
                           code="BAD_GROUP_STRUCTURE")
        out += [varint.encode([len(g.vertex_planes)]), varint.encode(np.asarray(g.vertex_planes, dtype=np.uint64)),
                varint.encode([len(facets)]),
                varint.encode(np.column_stack([gaps, facets[:, 1:]]).astype(np.uint64))]
    elif g.kind in (GroupKind.SHELL, *TREE_KINDS) and g.shell is not None:
        out.append(shell_kind_data(g.kind, g.shell, decide, major))
    elif g.kind == GroupKind.COPY:
        out.append(varint.encode([g.source]))
    else:
        out.append(g.extra)
    return b"".join(out)


def _body(g: PartGroup) -> bytes:
    refs = np.asarray(g.refs, dtype="<u4")
    roles = _roles(g)
    extra = g.extra
    if g.kind == GroupKind.CELLS:
        cells = g.cells or ()
        sizes = np.array([len(c) for c in cells], dtype="<u4")
        entries = np.concatenate([np.asarray(c, dtype="<u4") for c in cells]) if cells else np.zeros(0, "<u4")
        extra = schema.CellsExtra.build(dict(cell_count=len(cells), sizes=sizes.tobytes(),
                                             entries=entries.astype("<u4").tobytes()))
    elif g.kind == GroupKind.BSP:
        tokens = np.asarray(g.tree, dtype="<u4")
        extra = schema.TreeExtra.build(dict(token_count=len(tokens), tokens=tokens.tobytes()))
    return schema.GroupBody.build(dict(ref_count=len(refs), refs=refs.tobytes(), roles=roles, extra=extra))


#: The longest head of a version 3 to 5 group (spec §9.1): index, object, kind, compression, raw size.
GROUP_HEAD3_MAX = 5 + 5 + 1 + 1 + 5


def decode_group(payload: bytes, *, expected_index: int, objects: int, planes: int, minor: int, limits: Limits,
                 major: int = 1, budget: Budget | None = None) -> tuple[PartGroup, list[tuple[str, str]]]:
    """A part group of a version ``major``.``minor`` file, checked against the objects and planes
    defined so far; a kind that declares its output's counts charges them to ``budget`` (spec §12.4)."""
    if major >= 6:
        quick = quick_head(payload, (VARINT32, BYTE), schema.LENGTH_VARINT_BYTES + 1)
        if quick is None:
            r = _parse(schema.GroupHead6, bytes(payload[:schema.LENGTH_VARINT_BYTES + 1]), "group record")
            quick = [r.object, r.kind], r.body_offset
        (obj, kind), offset = quick
        head = cs.Container(index=expected_index, object=obj, kind=kind)
        stored = memoryview(payload)[offset:]
    elif major >= 3:
        # Only the head goes through construct (three varint32s and two bytes): the stored body stays a
        # view of the payload, which a large compressed body (spec §6) would otherwise hold twice more.
        prefix = bytes(payload[:GROUP_HEAD3_MAX])
        head = _parse(schema.GroupHead3, prefix, "GRUP")
        stored = memoryview(payload)[len(prefix) - len(head.body):]
    elif len(payload) < schema.GROUP_HEAD:
        raise FormatError("GRUP payload is shorter than its 16-byte head", code="BAD_PAYLOAD")
    else:
        head = _parse(schema.GroupHead, payload, "GRUP")
    if head.index != expected_index:
        raise FormatError(f"group index {head.index}, expected {expected_index}", code="GROUP_INDEX_MISMATCH")
    if head.object >= objects:
        raise FormatError(f"group {head.index} names object {head.object}, only {objects} defined",
                          code="BAD_OBJECT_REFERENCE")
    findings = []
    kinds = kinds_of(major, minor)
    if head.kind not in kinds:
        if minor <= VERSIONS.get(major, 0):
            raise FormatError(f"unknown part group kind {head.kind} in a version {major}.{minor} file",
                              code="UNKNOWN_GROUP_KIND")
        findings.append(("SKIPPED_GROUP_KIND", f"group {head.index} has kind {head.kind} of a newer minor version"))
    # Version 6: the segment holding the record was decompressed whole (spec §4.5).
    body = stored if major >= 6 else unpack(head.compression, stored if major >= 3 else bytes(head.body),
                                            head.raw_size, limits, major)
    if major >= 2:
        group = _decode_compact(head, body, planes, limits, kinds, major,
                                None if budget is None else budget.of(head.index))
        return group, findings
    if len(body) < 4:
        raise FormatError("group body is shorter than its reference count", code="BAD_PAYLOAD")
    count = int.from_bytes(body[:4], "little")
    if count > limits.max_refs_per_group:
        raise LimitError(f"group declares {count} references, the limit is {limits.max_refs_per_group}")
    b = _parse(schema.GroupBody, body, "GRUP body")
    refs = np.frombuffer(b.refs, dtype="<u4").astype(np.uint32)
    if count == 0:
        raise FormatError(f"group {head.index} references no planes", code="BAD_GROUP_STRUCTURE")
    if refs.max() >= planes:
        raise FormatError(f"group {head.index} references plane {int(refs.max())}, only {planes} defined",
                          code="BAD_PLANE_REFERENCE")
    role_bits = np.unpackbits(np.frombuffer(b.roles, dtype=np.uint8), bitorder="little")
    if role_bits[count:].any():
        raise FormatError("non-zero padding bits after the role bits", code="BAD_PAYLOAD")
    bounding = role_bits[:count].astype(bool)
    extra = bytes(b.extra)
    cells = tree = None
    if head.kind == GroupKind.CELLS:
        cells = _decode_cells(extra, count)
        extra = b""
    elif head.kind == GroupKind.BSP:
        tree = _decode_tree(extra, count)
        extra = b""
    elif head.kind in kinds and extra:
        raise FormatError(f"{len(extra)} unexpected bytes after the role bits", code="BAD_PAYLOAD")
    group = PartGroup(index=head.index, object=head.object, kind=_kind(head.kind), refs=refs, bounding=bounding,
                      cells=cells, tree=tree, extra=extra)
    return group, findings


def _decode_compact(head, body: bytes, planes: int, limits: Limits, kinds: frozenset[int], major: int,
                    charge: Charge | None = None) -> PartGroup:
    """A group body of versions 2 to 5 (spec §9.2)."""
    raw = np.frombuffer(body, dtype=np.uint8)
    (count,), pos = varint.decode(raw, 1, "group reference count")
    count = int(count)
    if count > limits.max_refs_per_group:
        raise LimitError(f"group declares {count} references, the limit is {limits.max_refs_per_group}")
    if count == 0 and not (major >= 5 and head.kind not in kinds - UNREFERENCED_KINDS):
        raise FormatError(f"group {head.index} references no planes", code="BAD_GROUP_STRUCTURE")
    gaps, used = varint.decode(raw[pos:], count, "group references")
    pos += used
    if count and gaps.max() >= planes:
        raise FormatError(f"group {head.index} references a plane past the {planes} defined",
                          code="BAD_PLANE_REFERENCE")
    refs = np.cumsum(gaps.astype(np.int64))
    if count and refs[-1] >= planes:
        raise FormatError(f"group {head.index} references plane {int(refs[-1])}, only {planes} defined",
                          code="BAD_PLANE_REFERENCE")
    bounding, pos = varint.bit_field(raw, pos, count, "group body", "role bits")
    rest = raw[pos:]
    cells = tree = vertex_planes = facets = shell = source = None
    extra = b""
    if head.kind not in kinds:
        extra = rest.tobytes()
    elif head.kind == GroupKind.SHELL:
        shell = _decode_shell(rest, bounding, major, charge)
    elif head.kind in WALK_KINDS:
        shell = decode_shell_walk(rest, bounding, head.kind, major, charge)
    elif head.kind in TREE_KINDS:
        shell = _decode_shell_tree(rest, bounding, head.kind == GroupKind.SHELL_TREE_PARALLELOGRAM, major, charge)
    elif head.kind == GroupKind.CELLS:
        cells = _decode_compact_cells(rest, count, limits)
    elif head.kind == GroupKind.BSP:
        tree = _decode_compact_tree(rest, count)
    elif head.kind == GroupKind.SEALED:
        vertex_planes, facets = _decode_sealed(rest, bounding, charge)
    elif head.kind == GroupKind.COPY:
        (source,), used = varint.decode(rest, 1, "copy source")
        if used != len(rest):
            raise FormatError(f"{len(rest) - used} unexpected bytes after a copy's source", code="BAD_PAYLOAD")
        if source >= head.index:
            raise FormatError(f"group {head.index} copies group {int(source)}, not an earlier one",
                              code="BAD_GROUP_STRUCTURE")
        source = int(source)
    elif len(rest):
        raise FormatError(f"{len(rest)} unexpected bytes after the role bits", code="BAD_PAYLOAD")
    return PartGroup(index=head.index, object=head.object, kind=_kind(head.kind), refs=refs.astype(np.uint32),
                     bounding=bounding, cells=cells, tree=tree, extra=extra, vertex_planes=vertex_planes,
                     facets=facets, shell=shell, source=source)


def _decode_counted(raw: np.ndarray, what: str, limit: int) -> tuple[np.ndarray, int]:
    """A varint count (at most ``limit`` and at most the bytes left) followed by that many varints."""
    (n,), pos = varint.decode(raw, 1, f"{what} count")
    if int(n) > min(limit, len(raw) - pos):
        raise FormatError(f"{what}: {int(n)} declared, more than the body holds or the limit allows",
                          code="BAD_GROUP_STRUCTURE")
    values, used = varint.decode(raw[pos:], int(n), what)
    return values, pos + used


def _decode_compact_cells(raw: np.ndarray, count: int, limits: Limits) -> tuple[np.ndarray, ...]:
    sizes, pos = _decode_counted(raw, "cell sizes", limits.max_refs_per_group)
    if len(sizes) == 0 or (sizes == 0).any():
        raise FormatError("a CELLS group needs at least one cell and no empty cell", code="BAD_GROUP_STRUCTURE")
    if (sizes > np.uint64(len(raw))).any() or int(sizes.sum()) > len(raw) - pos:
        raise FormatError("cell entries do not match the cell sizes", code="BAD_GROUP_STRUCTURE")
    entries, used = varint.decode(raw[pos:], int(sizes.sum()), "cell entries")
    if pos + used != len(raw):
        raise FormatError("cell entries do not fill the body", code="BAD_GROUP_STRUCTURE")
    if (entries >> np.uint64(1)).max() >= count:
        raise FormatError("a cell entry refers past the group's references", code="BAD_GROUP_STRUCTURE")
    return tuple(np.split(entries.astype(np.uint32), np.cumsum(sizes.astype(np.int64))[:-1]))


def _decode_compact_tree(raw: np.ndarray, count: int) -> np.ndarray:
    coded, pos = _decode_counted(raw, "BSP tokens", len(raw))
    if pos != len(raw):
        raise FormatError("bytes follow the BSP token stream", code="BAD_GROUP_STRUCTURE")
    if len(coded) and coded.max() >= count + schema.COMPACT_SPLIT:
        raise FormatError(f"BSP token {int(coded.max())} is not a leaf or a reference", code="BAD_GROUP_STRUCTURE")
    tokens = np.where(coded == schema.COMPACT_IN, BSP_IN, np.where(
        coded == schema.COMPACT_OUT, BSP_OUT, coded - np.uint64(schema.COMPACT_SPLIT))).astype(np.uint32)
    check_tree(tokens, count)
    return tokens


def _decode_sealed(raw: np.ndarray, bounding: np.ndarray,
                   charge: Charge | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Vertex triples (V, 3) and facets (T, 4: face reference, three vertices) of a SEALED body
    (spec §9.9), checked; ``charge`` takes V and T as each is read and checked (spec §12.4)."""
    (v,), pos = varint.decode(raw, 1, "sealed vertex count")
    if not 3 <= int(v) <= (len(raw) - pos) // schema.SEALED_VERTEX_FIELDS:
        raise FormatError(f"sealed group: {int(v)} vertices declared, fewer than 3 or more than the body holds",
                          code="BAD_GROUP_STRUCTURE")
    if charge is not None:
        charge(vertices=int(v))
    triples, used = varint.decode(raw[pos:], schema.SEALED_VERTEX_FIELDS * int(v), "sealed vertex planes")
    pos += used
    (t,), used = varint.decode(raw[pos:], 1, "sealed triangle count")
    pos += used
    if not 1 <= int(t) <= (len(raw) - pos) // schema.SEALED_TRIANGLE_FIELDS:
        raise FormatError(f"sealed group: {int(t)} triangles declared, none or more than the body holds",
                          code="BAD_GROUP_STRUCTURE")
    if charge is not None:
        charge(triangles=int(t))
    facets, used = varint.decode(raw[pos:], schema.SEALED_TRIANGLE_FIELDS * int(t), "sealed triangles")
    if pos + used != len(raw):
        raise FormatError("sealed triangles do not fill the body", code="BAD_GROUP_STRUCTURE")
    facets = facets.reshape(-1, schema.SEALED_TRIANGLE_FIELDS)
    if facets[:, 0].max() >= len(bounding):
        raise FormatError("a sealed triangle's face reference is past the group's references",
                          code="BAD_GROUP_STRUCTURE")
    facets[:, 0] = np.cumsum(facets[:, 0])
    return check_sealed(triples.reshape(-1, schema.SEALED_VERTEX_FIELDS), facets, bounding)


def check_sealed(vertex_planes: np.ndarray | None, facets: np.ndarray | None,
                 bounding: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``vertex_planes`` (V, 3) and ``facets`` (T, 4) of a SEALED group as uint32, or
    ``FormatError`` (``BAD_GROUP_STRUCTURE``) naming the first rule of spec §9.9 they break."""
    def bad(reason: str) -> FormatError:
        return FormatError(f"sealed group: {reason}", code="BAD_GROUP_STRUCTURE")
    if vertex_planes is None or facets is None:
        raise bad("vertex planes and triangles are both required")
    vp = np.asarray(vertex_planes, dtype=np.int64)
    fc = np.asarray(facets, dtype=np.int64)
    if vp.ndim != 2 or vp.shape[1] != 3 or len(vp) < 3 or fc.ndim != 2 or fc.shape[1] != 4 or not len(fc):
        raise bad("needs at least 3 vertices of 3 planes and 1 triangle of a face and 3 vertices")
    count = len(bounding)
    if vp.min() < 0 or vp.max() >= count:
        raise bad("a vertex refers past the group's references")
    if ((vp[:, 0] == vp[:, 1]) | (vp[:, 1] == vp[:, 2]) | (vp[:, 0] == vp[:, 2])).any():
        raise bad("a vertex names one plane twice")
    face, corner = fc[:, 0], fc[:, 1:]
    if face.min() < 0 or face.max() >= count or bounding[face].any():
        raise bad("a triangle lies on a reference that is not a face plane")
    if (np.diff(face) < 0).any():
        raise bad("triangles are not in order of their face references")
    if corner.min() < 0 or corner.max() >= len(vp):
        raise bad("a triangle refers past the group's vertices")
    if ((corner[:, 0] == corner[:, 1]) | (corner[:, 1] == corner[:, 2]) | (corner[:, 0] == corner[:, 2])).any():
        raise bad("a triangle names one vertex twice")
    if len(np.unique(corner)) != len(vp):
        raise bad("a vertex is on no triangle")
    return vp.astype(np.uint32), fc.astype(np.uint32)


def _decode_cells(extra: bytes, count: int) -> tuple[np.ndarray, ...]:
    c = _parse(schema.CellsExtra, extra, "CELLS")
    sizes = np.frombuffer(c.sizes, dtype="<u4").astype(np.int64)
    if c.cell_count == 0 or (sizes == 0).any():
        raise FormatError("a CELLS group needs at least one cell and no empty cell", code="BAD_GROUP_STRUCTURE")
    if len(c.entries) != 4 * int(sizes.sum()):
        raise FormatError("cell entries do not match the cell sizes", code="BAD_GROUP_STRUCTURE")
    entries = np.frombuffer(c.entries, dtype="<u4").astype(np.uint32)
    if (entries >> 1).max() >= count:
        raise FormatError("a cell entry refers past the group's references", code="BAD_GROUP_STRUCTURE")
    return tuple(np.split(entries, np.cumsum(sizes)[:-1]))


def _decode_tree(extra: bytes, count: int) -> np.ndarray:
    t = _parse(schema.TreeExtra, extra, "BSP")
    if len(extra) != 4 + 4 * t.token_count:
        raise FormatError("bytes follow the BSP token stream", code="BAD_GROUP_STRUCTURE")
    tokens = np.frombuffer(t.tokens, dtype="<u4").astype(np.uint32)
    check_tree(tokens, count)
    return tokens


def check_tree(tokens: np.ndarray, count: int) -> None:
    """Raise unless ``tokens`` is one complete preorder BSP tree over ``count`` references."""
    if len(tokens) == 0:
        raise FormatError("empty BSP token stream", code="BAD_GROUP_STRUCTURE")
    leaf = tokens >= BSP_IN
    bad = ~leaf & ((tokens > BSP_MAX_SPLIT) | (tokens >= count))
    if bad.any():
        raise FormatError(f"BSP token {int(tokens[np.flatnonzero(bad)[0]])} is not a leaf or a reference",
                          code="BAD_GROUP_STRUCTURE")
    # Open slots after each token: a split fills one slot and opens two, a leaf fills one.
    open_slots = 1 + np.cumsum(np.where(leaf, -1, 1))
    if (open_slots[:-1] <= 0).any() or open_slots[-1] != 0:
        raise FormatError("BSP token stream is not exactly one complete tree", code="BAD_GROUP_STRUCTURE")


# spec §10.1 Colours ---------------------------------------------------------------------------

def encode_colours(c: Colours, major: int = 1, count: int | None = None) -> bytes:
    """A cOLR payload; from version 4 on, a group in one colour stores it once (spec §10.1). ``count``:
    the group's references, where known (0: a group without references, which takes one colour)."""
    rgba = np.ascontiguousarray(c.rgba, dtype=np.uint8).reshape(-1, 4)
    if major >= 6:
        one = count == 0 or len(rgba) > 1 and (rgba == rgba[0]).all()
        return (schema.ColoursHead6.build(dict(group=c.group, count=0 if count == 0 else len(rgba)))
                + (rgba[0].tobytes() if one else rgba.tobytes()))
    if count == 0 or major >= 4 and len(rgba) > 1 and (rgba == rgba[0]).all():
        return schema.ColoursHead.build(dict(group=c.group, count=0 if count == 0 else len(rgba))) + rgba[0].tobytes()
    return schema.Colours.build(dict(group=c.group, count=len(rgba), rgba=rgba.tobytes()))


def decode_colours(payload: bytes, group_refs: dict[int, int], major: int = 1) -> Colours:
    """A cOLR chunk, checked against ``group_refs``: the colour count of each group read so far."""
    if major >= 6:
        return _decode_colours6(payload, group_refs)
    head = _parse(schema.ColoursHead, bytes(payload[:8]), "cOLR")
    uniform = major >= 4 and len(payload) == 12
    if not uniform:
        r = _parse(schema.Colours, payload, "cOLR")
        if len(payload) != 8 + 4 * r.count:
            raise FormatError("cOLR size does not match its count", code="BAD_COLOURS")
    if head.group not in group_refs or group_refs[head.group] != head.count or not (head.count or uniform):
        raise FormatError(f"cOLR for group {head.group} does not match a preceding group's references (a group "
                          "without references takes one colour)", code="BAD_COLOURS")
    rgba = np.frombuffer(bytes(payload[8:]), dtype=np.uint8).reshape(-1, 4)
    # A group without references takes its one colour (version 5), kept as one row.
    return Colours(group=head.group, rgba=np.repeat(rgba, max(head.count, 1), axis=0) if uniform else rgba.copy())


def _decode_colours6(payload: bytes, group_refs: dict[int, int]) -> Colours:
    """A colours record (spec §10.1, version 6): varint32 group and count, then one colour or count."""
    quick = quick_head(payload, (VARINT32, VARINT32), 2 * schema.LENGTH_VARINT_BYTES)
    if quick is None:
        head = _parse(schema.ColoursHead6, bytes(payload[:2 * schema.LENGTH_VARINT_BYTES]), "colours record")
    else:
        (group, count), offset = quick
        head = cs.Container(group=group, count=count, rgba_offset=offset)
    rgba = bytes(payload[head.rgba_offset:])
    uniform = len(rgba) == 4
    if not uniform and len(rgba) < 4 * head.count:
        raise FormatError(f"colours record ends inside its {head.count} colours", code="BAD_PAYLOAD")
    if not uniform and len(rgba) > 4 * head.count:
        raise FormatError(f"{len(rgba) - 4 * head.count} bytes after the colours", code="BAD_COLOURS")
    if head.group not in group_refs or group_refs[head.group] != head.count or not (head.count or uniform):
        raise FormatError(f"colours for group {head.group} do not match a preceding group's references (a group "
                          "without references takes one colour)", code="BAD_COLOURS")
    colours = np.frombuffer(rgba, dtype=np.uint8).reshape(-1, 4)
    return Colours(group=head.group, rgba=np.repeat(colours, max(head.count, 1), axis=0) if uniform else colours.copy())


# spec §10.3 Metadata ------------------------------------------------------------------------

def encode_metadata(m: Metadata) -> bytes:
    """A mETA payload; raises ``BAD_METADATA`` for what :func:`decode_metadata` would refuse or read otherwise."""
    try:
        payload = schema.Metadata.build(dict(keyword=m.key.encode("ascii"), value=m.value.encode("utf-8")))
    except UnicodeEncodeError:
        raise FormatError(f"mETA {m.key!r}: keyword not ASCII or value not encodable as UTF-8",
                          code="BAD_METADATA") from None
    if decode_metadata(payload) != m:  # a NUL in the keyword would end it early
        raise FormatError(f"mETA keyword {m.key!r} holds a NUL", code="BAD_METADATA")
    return payload


def decode_metadata(payload: bytes) -> Metadata:
    """A mETA chunk: the keyword and its value, checked (the value too, for a keyword the spec defines)."""
    if b"\x00" not in payload:
        raise FormatError("mETA payload has no 0x00 byte after its keyword", code="BAD_METADATA")
    r = _parse(schema.Metadata, payload, "mETA")
    low, high = schema.METADATA_KEYWORD_BYTES
    raw = np.frombuffer(r.keyword, dtype=np.uint8)
    if not low <= len(raw) <= high or ((raw < 0x21) | (raw > 0x7E)).any():
        raise FormatError(f"mETA keyword {bytes(r.keyword)!r} is not {low} to {high} printable ASCII characters "
                          "without space", code="BAD_METADATA")
    key = bytes(r.keyword).decode("ascii")
    try:
        value = bytes(r.value).decode("utf-8")
    except UnicodeDecodeError:
        raise FormatError(f"mETA {key}: the value is not UTF-8", code="BAD_METADATA") from None
    if key == UP_AXIS and value not in UP_AXES:
        raise FormatError(f"mETA {UP_AXIS} is {value[:20]!r}, not one of {', '.join(UP_AXES)}", code="BAD_METADATA")
    return Metadata(key, value)


# spec §10.2 Index and §4.4 End (PEND of versions 1 and 2: Appendix A.1) ---------------------

def encode_index(entries: np.ndarray) -> bytes:
    return schema.Index.build(dict(count=len(entries), entries=entries.astype(schema.INDEX_ENTRY_DTYPE).tobytes()))


def decode_index(payload: bytes, index_offset: int, first_chunk: int = 8 + 12 + schema.HEADER_SIZE) -> np.ndarray:
    """The iNDX entries; ``first_chunk`` is the offset of the chunk after PHDR (spec §10.2)."""
    r = _parse(schema.Index, payload, "iNDX")
    if len(payload) != 4 + 16 * r.count:
        raise FormatError("iNDX size does not match its count", code="BAD_INDEX")
    entries = np.frombuffer(r.entries, dtype=schema.INDEX_ENTRY_DTYPE)
    offsets = entries["offset"]
    if len(entries) and ((offsets < first_chunk).any() or (offsets >= index_offset).any()
                         or (np.diff(offsets.astype(np.int64)) <= 0).any()):
        raise FormatError("index offsets are outside the chunk area or not increasing", code="BAD_INDEX")
    if not np.isin(entries["type"], [schema.OBJT, schema.PLNS, schema.GRUP]).all():
        raise FormatError("index entry of a chunk type other than OBJT, PLNS, GRUP", code="BAD_INDEX")
    return entries


def encode_end(index_offset: int, major: int = 1) -> bytes:
    """The PEND payload; versions 3 and 4 leave it empty when there is no index (spec §4.4)."""
    if major >= 3 and not index_offset:
        return b""
    return schema.End.build(dict(index_offset=index_offset))


def decode_end(payload: bytes, major: int = 1) -> int:
    sizes = schema.END3_SIZES if major >= 3 else (schema.END_SIZE,)
    if len(payload) not in sizes:
        raise FormatError(f"PEND payload is {len(payload)} bytes, not {' or '.join(map(str, sizes))}",
                          code="BAD_PAYLOAD")
    if not payload:
        return 0
    index_offset = schema.End.parse(payload).index_offset
    if major >= 3 and not index_offset:
        raise FormatError("a version 3 or 4 PEND of 8 bytes must point at the index, not 0", code="BAD_INDEX")
    return index_offset
