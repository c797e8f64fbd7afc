"""Chunk payloads <-> model records (spec §5–§10), with every check the spec requires.

Decoders take a payload (already framed and CRC-checked) and raise
``PlnError`` subclasses without location; the reader adds file, chunk and
offset. Encoders take model records and return payload bytes.
"""

from __future__ import annotations

import math
import zlib

import construct as cs
import numpy as np

from . import quantize, schema, varint
from .chunks import Limits
from .errors import FormatError, LimitError, PlnError, VersionError
from .model import (BSP_IN, BSP_MAX_SPLIT, BSP_OUT, FREE, MAX_GRID, NO_PARENT, UP_AXES, UP_AXIS, Coding, Colours,
                    GroupKind, Header, Metadata, ObjectRecord, PartGroup, PlaneBlock, Quantization, Shell, Units)

#: Major versions read, each with the newest minor version this reader knows.
VERSIONS = {1: 0, 2: 0, 3: 3}
#: Triplet codings each major version allows (spec §5, §7.4; Appendix A.1).
CODINGS = {1: (0, 1, 2), 2: (0, 1, 2, 3), 3: (0, 1, 2, 3)}
KNOWN_KINDS = frozenset(int(k) for k in GroupKind)
#: The kind each version added after 1.0: ``(major, minor)`` it needs.
KIND_VERSION = {int(GroupKind.SEALED): (3, 1), int(GroupKind.SHELL): (3, 2), int(GroupKind.SHELL_TREE): (3, 3)}


def _kind(value: int) -> GroupKind | int:
    """A kind this reader knows as its :class:`GroupKind`; one of a newer minor version stays an int."""
    return GroupKind(value) if value in GroupKind._value2member_map_ else value


def kinds_of(major: int, minor: int) -> frozenset[int]:
    """The part-group kinds a file of version ``major.minor`` may hold (as far as this reader knows)."""
    return frozenset(k for k in KNOWN_KINDS
                     if k not in KIND_VERSION or (major, minor) >= KIND_VERSION[k])


def _parse(struct: cs.Construct, payload: bytes, what: str):
    try:
        return struct.parse(payload)
    except (cs.ConstructError, ValueError, OverflowError) as exc:
        raise FormatError(f"{what} payload is malformed ({type(exc).__name__})", code="BAD_PAYLOAD") from None


# spec §5 Header ------------------------------------------------------------------------------

def encode_header(h: Header) -> bytes:
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
    if h.version[0] == 3:
        return schema.Header3.build(dict(
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


def header_size(major: int) -> int:
    """The smallest PHDR payload of a version ``major`` file."""
    return schema.HEADER3_FIXED if major == 3 else schema.HEADER_SIZE


def decode_header(payload: bytes) -> tuple[Header, list[tuple[str, str]]]:
    """The header and non-fatal findings (code, message)."""
    if len(payload) < 2:
        raise FormatError("PHDR is too short to hold a version", code="BAD_PAYLOAD")
    major, minor = payload[0], payload[1]
    if major not in VERSIONS:
        raise VersionError(f"major version {major} is not supported (this reader reads 1.x, 2.x and 3.x)")
    if len(payload) < header_size(major):
        raise FormatError(f"PHDR is {len(payload)} bytes, version {major} needs {header_size(major)}",
                          code="BAD_PAYLOAD")
    findings = []
    if minor > VERSIONS[major]:
        findings.append(("NEWER_MINOR_VERSION", f"file is version {major}.{minor}; read as {major}.{VERSIONS[major]}"))
    if major == 3:
        # The coding decides which fields follow the fixed part, so it is checked before they are read.
        if payload[4] not in CODINGS[major]:
            raise VersionError(f"triplet coding {payload[4]} is not supported in a version {major} file",
                               code="UNSUPPORTED_CODING")
        r = _parse(schema.Header3, payload, "PHDR")
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
    units = Units(r.units) if r.units in Units._value2member_map_ else None
    if units is None:
        raise FormatError(f"unknown units code {r.units}", code="BAD_HEADER_VALUE")
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
        group_count=counts.group_count if known else None, extra=bytes(r.extra),
    )
    return header, findings


def leading_index(payload: bytes, major: int, width: int) -> int:
    """The number an OBJT, PLNS or GRUP payload starts with (index or first plane): a u32 / u64 of
    ``width`` bytes in versions 1 and 2, a varint in version 3."""
    if major == 3:
        return _parse(schema.Varint, bytes(payload[:schema.VARINT_MAX_BYTES]), "chunk head")
    return int.from_bytes(payload[:width], "little")


# spec §6 Compression -------------------------------------------------------------------------

#: Deflate level of shell tree bodies (spec 3.3 §8.10): level 9's longer match search gains 1% on their
#: small-alphabet links and codes at 14 times the time (smooth_dense/bun_zipper.ply at draco-14's
#: error: 132.1 kB in 1.9 s, against 133.5 kB in 0.14 s at level 6); every other payload is deflated at 9.
SHELL_TREE_LEVEL = 6


def pack(data: bytes, compress: bool, level: int = 9) -> tuple[int, bytes]:
    """(compression method, stored bytes): deflate at ``level`` only where it saves bytes."""
    if compress:
        z = zlib.compress(data, level)
        if len(z) < len(data):
            return schema.COMPRESSION_ZLIB, z
    return schema.COMPRESSION_NONE, data


def unpack(method: int, stored: bytes, raw_size: int, limits: Limits) -> bytes:
    """The raw bytes of a stored payload, checked in the order of spec/pln.md §6, with the deflate-bomb
    caps of spec §12.4: the method (a defect of the file) before the reader's own limits."""
    if method not in (schema.COMPRESSION_NONE, schema.COMPRESSION_ZLIB):
        raise FormatError(f"unknown compression method {method}", code="BAD_COMPRESSION")
    if raw_size > limits.max_raw_size:
        raise LimitError(f"declared raw size {raw_size} exceeds the limit {limits.max_raw_size}")
    if method == schema.COMPRESSION_NONE:
        if len(stored) != raw_size:
            raise FormatError(f"raw size {raw_size} != stored size {len(stored)}", code="SIZE_MISMATCH")
        return stored
    if raw_size > max(len(stored), 1) * limits.max_compression_ratio:
        raise LimitError(f"declared raw size {raw_size} is over {limits.max_compression_ratio}x "
                         f"the {len(stored)} stored bytes")
    d = zlib.decompressobj()
    try:
        raw = d.decompress(stored, raw_size + 1)
    except zlib.error as exc:
        raise FormatError(f"corrupt deflate stream ({exc})", code="BAD_COMPRESSION") from None
    if len(raw) != raw_size or not d.eof or d.unconsumed_tail or d.unused_data:
        raise FormatError(f"deflate stream does not inflate to exactly {raw_size} bytes",
                          code="SIZE_MISMATCH")
    return raw


# spec §7 Plane table -------------------------------------------------------------------------

def encode_planes(first: int, triplets: np.ndarray, header: Header, compress: bool) -> bytes:
    raw = quantize.encode_payload(triplets, header.coding, header.quantization)
    method, stored = pack(raw, compress)
    if header.version[0] == 3:
        return schema.PlaneBlock3.build(dict(first=first, count=len(triplets), compression=method,
                                             raw_size=len(raw), data=stored))
    return schema.PlaneBlock.build(dict(first=first, count=len(triplets), compression=method,
                                        reserved=b"\0\0\0", raw_size=len(raw), data=stored))


def decode_planes(payload: bytes, header: Header, expected_first: int, limits: Limits) -> PlaneBlock:
    # Only the head goes through construct: the data stays a zero-copy view.
    if header.version[0] == 3:
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
    raw = unpack(r.compression, memoryview(payload)[start:], r.raw_size, limits)
    triplets = quantize.decode_payload(raw, r.count, header.coding, header.quantization)
    return PlaneBlock(first=r.first, triplets=triplets)


# spec §8 Objects ---------------------------------------------------------------------------

def encode_object(o: ObjectRecord, major: int = 1) -> bytes:
    name = o.name.encode("utf-8")
    if len(name) > 0xFFFF:
        raise PlnError(f"object name is {len(name)} bytes, at most 65535", code="BAD_OBJECT")
    t = None if o.transform is None else np.asarray(o.transform, dtype="<f8").reshape(4, 4).tobytes()
    flags = schema.OBJECT_HAS_TRANSFORM if t is not None else 0
    if major == 3:
        head = dict(index=o.index, parent=0 if o.parent is None else o.parent + 1, flags=flags, name_length=len(name))
        return schema.Object3.build(dict(head=head, name=name, transform=t, extra=b""))
    return schema.Object.build(dict(
        index=o.index, parent=NO_PARENT if o.parent is None else o.parent,
        flags=flags, reserved=b"\0", name_length=len(name), name=name, transform=t, extra=b""))


def decode_object(payload: bytes, expected_index: int, major: int = 1) -> ObjectRecord:
    if major == 3:
        # The head first: a name length over the cap is BAD_OBJECT before the name is looked for.
        head = _parse(schema.Object3Head, bytes(payload[:3 * schema.VARINT_MAX_BYTES + 1]), "OBJT")
        if head.name_length > schema.OBJECT3_MAX_NAME:
            raise FormatError(f"object name of {head.name_length} bytes, at most 65535", code="BAD_OBJECT")
        r = _parse(schema.Object3, payload, "OBJT")
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
        transform = np.frombuffer(r.transform, dtype="<f8").reshape(4, 4).astype(np.float64)
        if not np.isfinite(transform).all() or not np.array_equal(transform[3], [0, 0, 0, 1]):
            raise FormatError("transform is not a finite affine matrix (last row 0 0 0 1)", code="BAD_OBJECT")
    return ObjectRecord(index=index, name=name, parent=parent, transform=transform)


# spec §9 Part groups ------------------------------------------------------------------

def encode_group(g: PartGroup, compress: bool, major: int = 1) -> bytes:
    """The GRUP payload; ``major`` 2 and 3 write the varint body of spec §9.2, 3 with the varint
    head of 3.0 (spec §9.1, §9.2; version 1's u32 body: Appendix A.1)."""
    if g.facets is not None and major != 3:
        raise PlnError("sealed groups need version 3.1", code="UNKNOWN_GROUP_KIND")
    if g.shell is not None and major != 3:
        raise PlnError("shell groups need version 3.2", code="UNKNOWN_GROUP_KIND")
    body = _compact_body(g) if major >= 2 else _body(g)
    method, stored = pack(body, compress, SHELL_TREE_LEVEL if g.kind == GroupKind.SHELL_TREE else 9)
    if major == 3:
        return schema.GroupHead3.build(dict(index=g.index, object=g.object, kind=int(g.kind), compression=method,
                                            raw_size=len(body), body=stored))
    return schema.GroupHead.build(dict(index=g.index, object=g.object, kind=int(g.kind), compression=method,
                                       reserved=b"\0\0", raw_size=len(body), body=stored))


def _roles(g: PartGroup) -> bytes:
    return np.packbits(np.asarray(g.bounding, dtype=bool), bitorder="little").tobytes()


def _compact_body(g: PartGroup) -> bytes:
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
    elif g.kind == GroupKind.SHELL and g.shell is not None:
        out.append(_shell_body(g.shell))
    elif g.kind == GroupKind.SHELL_TREE and g.shell is not None:
        out.append(_shell_tree_body(g.shell))
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


def decode_group(payload: bytes, *, expected_index: int, objects: int, planes: int,
                 minor: int, limits: Limits, major: int = 1) -> tuple[PartGroup, list[tuple[str, str]]]:
    """A part group of a version ``major``.``minor`` file, checked against the objects and planes
    defined so far."""
    if major == 3:
        head = _parse(schema.GroupHead3, payload, "GRUP")
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
    body = unpack(head.compression, bytes(head.body), head.raw_size, limits)
    if major >= 2:
        group = _decode_compact(head, body, planes, limits, kinds)
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


def _decode_compact(head, body: bytes, planes: int, limits: Limits, kinds: frozenset[int]) -> PartGroup:
    """A version 2 or 3 group body (spec §9.2)."""
    raw = np.frombuffer(body, dtype=np.uint8)
    (count,), pos = varint.decode(raw, 1, "group reference count")
    count = int(count)
    if count > limits.max_refs_per_group:
        raise LimitError(f"group declares {count} references, the limit is {limits.max_refs_per_group}")
    if count == 0:
        raise FormatError(f"group {head.index} references no planes", code="BAD_GROUP_STRUCTURE")
    gaps, used = varint.decode(raw[pos:], count, "group references")
    pos += used
    if gaps.max() >= planes:
        raise FormatError(f"group {head.index} references a plane past the {planes} defined",
                          code="BAD_PLANE_REFERENCE")
    refs = np.cumsum(gaps.astype(np.int64))
    if refs[-1] >= planes:
        raise FormatError(f"group {head.index} references plane {int(refs[-1])}, only {planes} defined",
                          code="BAD_PLANE_REFERENCE")
    bounding, pos = _bit_field(raw, pos, count, "group body", "role bits")
    rest = raw[pos:]
    cells = tree = vertex_planes = facets = shell = None
    extra = b""
    if head.kind not in kinds:
        extra = rest.tobytes()
    elif head.kind == GroupKind.SHELL:
        shell = _decode_shell(rest, bounding)
    elif head.kind == GroupKind.SHELL_TREE:
        shell = _decode_shell_tree(rest, bounding)
    elif head.kind == GroupKind.CELLS:
        cells = _decode_compact_cells(rest, count, limits)
    elif head.kind == GroupKind.BSP:
        tree = _decode_compact_tree(rest, count)
    elif head.kind == GroupKind.SEALED:
        vertex_planes, facets = _decode_sealed(rest, bounding)
    elif len(rest):
        raise FormatError(f"{len(rest)} unexpected bytes after the role bits", code="BAD_PAYLOAD")
    return PartGroup(index=head.index, object=head.object, kind=_kind(head.kind), refs=refs.astype(np.uint32),
                     bounding=bounding, cells=cells, tree=tree, extra=extra, vertex_planes=vertex_planes,
                     facets=facets, shell=shell)


def _bit_field(raw: np.ndarray, pos: int, count: int, body: str, what: str) -> tuple[np.ndarray, int]:
    """``count`` bits packed least significant first from ``raw[pos:]`` as bools, and the position
    after their bytes; ``BAD_PAYLOAD`` where ``body`` ends inside them or a padding bit is set."""
    size = (count + 7) // 8
    if len(raw) < pos + size:
        raise FormatError(f"{body} ends inside its {what}", code="BAD_PAYLOAD")
    bits = np.unpackbits(raw[pos:pos + size], bitorder="little")
    if bits[count:].any():
        raise FormatError(f"non-zero padding bits after the {what}", code="BAD_PAYLOAD")
    return bits[:count].astype(bool), pos + size


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


def _decode_sealed(raw: np.ndarray, bounding: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertex triples (V, 3) and facets (T, 4: face reference, three vertices) of a SEALED body
    (spec §9.9), checked."""
    (v,), pos = varint.decode(raw, 1, "sealed vertex count")
    if not 3 <= int(v) <= (len(raw) - pos) // schema.SEALED_VERTEX_FIELDS:
        raise FormatError(f"sealed group: {int(v)} vertices declared, fewer than 3 or more than the body holds",
                          code="BAD_GROUP_STRUCTURE")
    triples, used = varint.decode(raw[pos:], schema.SEALED_VERTEX_FIELDS * int(v), "sealed vertex planes")
    pos += used
    (t,), used = varint.decode(raw[pos:], 1, "sealed triangle count")
    pos += used
    if not 1 <= int(t) <= (len(raw) - pos) // schema.SEALED_TRIANGLE_FIELDS:
        raise FormatError(f"sealed group: {int(t)} triangles declared, none or more than the body holds",
                          code="BAD_GROUP_STRUCTURE")
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

def encode_colours(c: Colours) -> bytes:
    rgba = np.ascontiguousarray(c.rgba, dtype=np.uint8).reshape(-1, 4)
    return schema.Colours.build(dict(group=c.group, count=len(rgba), rgba=rgba.tobytes()))


def decode_colours(payload: bytes, group_refs: dict[int, int]) -> Colours:
    """A cOLR chunk, checked against ``group_refs``: the colour count of each group read so far."""
    r = _parse(schema.Colours, payload, "cOLR")
    if len(payload) != 8 + 4 * r.count:
        raise FormatError("cOLR size does not match its count", code="BAD_COLOURS")
    if r.group not in group_refs or group_refs[r.group] != r.count:
        raise FormatError(f"cOLR for group {r.group} does not match a preceding group's references",
                          code="BAD_COLOURS")
    return Colours(group=r.group, rgba=np.frombuffer(r.rgba, dtype=np.uint8).reshape(-1, 4).copy())


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
    """The PEND payload; version 3 leaves it empty when there is no index (spec §4.4)."""
    if major == 3 and not index_offset:
        return b""
    return schema.End.build(dict(index_offset=index_offset))


def decode_end(payload: bytes, major: int = 1) -> int:
    sizes = schema.END3_SIZES if major == 3 else (schema.END_SIZE,)
    if len(payload) not in sizes:
        raise FormatError(f"PEND payload is {len(payload)} bytes, not {' or '.join(map(str, sizes))}",
                          code="BAD_PAYLOAD")
    if not payload:
        return 0
    index_offset = schema.End.parse(payload).index_offset
    if major == 3 and not index_offset:
        raise FormatError("a version 3 PEND of 8 bytes must point at the index, not 0", code="BAD_INDEX")
    return index_offset


# spec §9.10 Shells --------------------------------------------------------------------------

def corner_codes(triangles: np.ndarray) -> np.ndarray:
    """The corner codes of spec §9.10 of ``triangles`` (T, 3) whose corners are numbered by first
    use: 0 for a corner's first use, ``k`` for a later one of the k-th newest corner."""
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1)
    if not len(tri):
        return tri
    new = np.r_[True, tri[1:] > np.maximum.accumulate(tri)[:-1]]
    return np.where(new, 0, np.cumsum(new) - tri)


def first_use_order(triangles: np.ndarray, count: int) -> np.ndarray:
    """New number of each of ``count`` corners when numbered in order of first use by ``triangles``
    (read row by row); -1 for corners no triangle uses."""
    flat = np.asarray(triangles, dtype=np.int64).reshape(-1)
    seen, first = np.unique(flat, return_index=True)
    rank = np.full(count, -1, dtype=np.int64)
    rank[seen[np.argsort(first, kind="stable")]] = np.arange(len(seen))
    return rank


def check_shell(shell: Shell, bounding: np.ndarray) -> None:
    """``FormatError`` (``BAD_GROUP_STRUCTURE``) naming the first rule of spec §9.10 ``shell``
    breaks for a group whose references have roles ``bounding``."""
    def bad(reason: str) -> FormatError:
        return FormatError(f"shell group: {reason}", code="BAD_GROUP_STRUCTURE")
    explicit = np.asarray(shell.explicit, dtype=bool)
    vp = np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1, 3)
    grid = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
    fc = np.asarray(shell.facets, dtype=np.int64)
    v = len(explicit)
    if v < 3 or fc.ndim != 2 or fc.shape[1] != 4 or not len(fc):
        raise bad("needs at least 3 corners and 1 triangle")
    if len(vp) != int((~explicit).sum()) or len(grid) != int(explicit.sum()):
        raise bad("one triple per named corner and one coordinate row per explicit corner")
    count = len(bounding)
    if len(vp) and (vp.min() < 0 or vp.max() >= count):
        raise bad("a corner refers past the group's references")
    if ((vp[:, 0] == vp[:, 1]) | (vp[:, 1] == vp[:, 2]) | (vp[:, 0] == vp[:, 2])).any():
        raise bad("a corner names one plane twice")
    if np.abs(grid).max(initial=0) > MAX_GRID:
        raise bad("a grid coordinate is beyond 2^52")
    if explicit.any() and not (np.isfinite(shell.origin).all() and math.isfinite(shell.step) and shell.step > 0):
        raise bad("the grid's origin and step must be finite, the step positive")
    face, tri = fc[:, 0], fc[:, 1:]
    planar = face != FREE
    if planar.any() and ((~planar[:np.flatnonzero(planar)[-1]]).any()):
        raise bad("a free triangle comes before a planar one")
    f = face[planar]
    if len(f) and (f.min() < 0 or f.max() >= count or bounding[f].any()):
        raise bad("a triangle lies on a reference that is not a face plane")
    if (np.diff(f) < 0).any():
        raise bad("triangles are not in order of their face references")
    if tri.min() < 0 or tri.max() >= v:
        raise bad("a triangle refers past the group's corners")
    if ((tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 0] == tri[:, 2])).any():
        raise bad("a triangle names one corner twice")
    if not np.array_equal(first_use_order(tri, v), np.arange(v)):
        raise bad("corners are not numbered in order of first use, or one is unused")


def _shell_body(shell: Shell) -> bytes:
    """The kind data of a SHELL group (spec §9.10)."""
    explicit = np.asarray(shell.explicit, dtype=bool)
    fc = np.asarray(shell.facets, dtype=np.int64)
    face = fc[:, 0]
    planar = face[face != FREE]
    codes = corner_codes(fc[:, 1:])
    out = [varint.encode([len(explicit), len(fc), len(fc) - len(planar)]),
           np.packbits(explicit, bitorder="little").tobytes(),
           varint.encode(np.asarray(shell.vertex_planes, dtype=np.uint64).reshape(-1))]
    if explicit.any():
        grid = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
        out += [schema.ShellGrid.build(dict(origin=[float(x) for x in shell.origin], step=float(shell.step))),
                varint.encode(varint.zigzag(np.diff(grid, axis=0, prepend=np.zeros((1, 3), dtype=np.int64))))]
    out += [varint.encode(np.diff(planar, prepend=0)), varint.encode(codes)]
    return b"".join(out)


def _decode_shell(raw: np.ndarray, bounding: np.ndarray) -> Shell:
    """The corners and triangles of a SHELL body (spec §9.10), checked."""
    (v, t, u), pos = varint.decode(raw, 3, "shell counts")
    v, t, u = int(v), int(t), int(u)
    left = len(raw) - pos
    if not (3 <= v <= 8 * left and 1 <= t <= left // 3 and u <= t):
        raise FormatError(f"shell group: {v} corners, {t} triangles, {u} free: outside the ranges the body "
                          f"allows", code="BAD_GROUP_STRUCTURE")
    explicit, pos = _bit_field(raw, pos, v, "shell group: the body", "corner flags")
    e = int(explicit.sum())
    # Every field is read before any value is checked (spec/pln.md §9.10): a body that ends inside one
    # is BAD_PAYLOAD whatever else is wrong. The counts' checks above bound what is decoded.
    triples, used = varint.decode(raw[pos:], 3 * (v - e), "shell corner planes")
    pos += used
    origin, step, grid = np.zeros(3), 0.0, np.zeros((0, 3), dtype=np.int64)
    if e:
        if len(raw) < pos + schema.SHELL_GRID_BYTES:
            raise FormatError("shell group: the body ends inside its grid", code="BAD_PAYLOAD")
        g = schema.ShellGrid.parse(raw[pos:pos + schema.SHELL_GRID_BYTES].tobytes())
        pos += schema.SHELL_GRID_BYTES
        origin, step = np.array(g.origin, dtype=np.float64), float(g.step)
        deltas, used = varint.decode(raw[pos:], 3 * e, "shell corner coordinates")
        pos += used
        steps = varint.unzigzag(deltas).reshape(-1, 3)
    gaps, used = varint.decode(raw[pos:], t - u, "shell face references")
    pos += used
    codes, used = varint.decode(raw[pos:], 3 * t, "shell triangle corners")
    if pos + used != len(raw):
        raise FormatError("shell group: the triangles do not fill the body", code="BAD_GROUP_STRUCTURE")
    if e:
        # Checked before the cumulative sum, which steps near 2^63 would overflow (and compared on both
        # sides: abs(-2^63) is still negative in int64).
        if ((steps > MAX_GRID) | (steps < -MAX_GRID)).any():
            raise FormatError("shell group: a grid coordinate is beyond 2^52", code="BAD_GROUP_STRUCTURE")
        grid = np.cumsum(steps, axis=0)
    if len(gaps) and gaps.max() >= len(bounding):
        raise FormatError("shell group: a face reference is past the group's references",
                          code="BAD_GROUP_STRUCTURE")
    if codes.max() > np.uint64(3 * t):
        raise FormatError("shell group: a triangle corner refers back past the first corner",
                          code="BAD_GROUP_STRUCTURE")
    codes = codes.astype(np.int64)
    new = codes == 0
    seen = np.cumsum(new)
    tri = np.where(new, seen - 1, seen - codes)
    if tri.min() < 0:
        raise FormatError("shell group: a triangle corner refers back past the first corner",
                          code="BAD_GROUP_STRUCTURE")
    face = np.r_[np.cumsum(gaps.astype(np.int64)), np.full(u, FREE, dtype=np.int64)]
    shell = Shell(explicit=explicit, vertex_planes=triples.astype(np.int64).reshape(-1, 3), grid=grid,
                  origin=origin, step=step, facets=np.column_stack([face, tri.reshape(-1, 3)]))
    check_shell(shell, bounding)
    return shell


# spec 3.3 §8.10 Shell trees ----------------------------------------------------------------------

def resolve_chains(value: np.ndarray, pointer: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """``value[k]`` where ``pointer[k] < 0``, else ``offset[k]`` plus the resolved value at
    ``pointer[k]``, which is always an earlier entry. Pointer jumping: each round halves every chain,
    so a tree of depth 817 (CAD/box.STL) takes 11 rounds of numpy work over the arrays, where
    following parents would take 817 or a loop over triangles."""
    value, pointer, offset = value.copy(), pointer.copy(), offset.copy()
    pending = np.flatnonzero(pointer >= 0)
    while len(pending):
        target = pointer[pending]
        ready = pointer[target] < 0
        done, wait, via = pending[ready], pending[~ready], target[~ready]
        # Jump from what the targets were at the start of the round, not what this round made them.
        offset[wait], pointer[wait] = offset[wait] + offset[via], pointer[via]
        value[done] = offset[done] + value[target[ready]]
        pointer[done] = -1
        pending = wait
    return value


def incident_planes(triangles: np.ndarray, face: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distinct face references of the planar triangles at each of ``count`` corners, ascending:
    (references, start and count of each corner's run in them)."""
    live = face != FREE
    m = int(face.max(initial=0)) + 1
    key = np.unique(triangles[live].reshape(-1) * m + np.repeat(face[live], 3))
    corner = key // m
    runs = np.bincount(corner, minlength=count)
    return key % m, np.cumsum(runs) - runs, runs


def _tree_parents(links: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    root = links == 0
    d = (links - 1) // 3 + 1
    return root, np.where(root, -1, np.arange(len(links)) - d), np.where(root, 0, (links - 1) % 3)


def _tree_predictors(links: np.ndarray, triangles: np.ndarray, explicit: np.ndarray, per: np.ndarray,
                     new: np.ndarray) -> np.ndarray:
    """For each corner, the corner its grid coordinates are coded from (spec 3.3 §8.10): the first
    corner of the attached triangle that names it anew, where that corner is explicit; otherwise the
    previous explicit corner; -1 for none (coded from 0). ``per``: each triangle's corner codes (3 or
    1); ``new``: which codes name a corner anew."""
    v = len(explicit)
    creator = np.repeat(np.arange(len(triangles)), per)[new]
    gate = triangles[creator, 0]
    previous = np.r_[-1, np.maximum.accumulate(np.where(explicit, np.arange(v), -1))[:-1]]
    return np.where((links[creator] != 0) & explicit[gate], gate, previous)


def shell_kind_data(kind: GroupKind, shell: Shell) -> bytes:
    """The kind data of a SHELL (spec 3.2 §8.9) or SHELL_TREE (3.3 §8.10) group."""
    return _shell_tree_body(shell) if kind == GroupKind.SHELL_TREE else _shell_body(shell)


def check_shell_tree(shell: Shell, bounding: np.ndarray) -> None:
    """``FormatError`` (``BAD_GROUP_STRUCTURE``) unless ``shell`` is a shell tree of spec 3.3 §8.10 for
    a group whose references have roles ``bounding``: what its body decodes to, it is."""
    if shell.links is None or len(shell.links) != len(shell.facets):
        raise FormatError("shell tree: one link per triangle", code="BAD_GROUP_STRUCTURE")
    back = _decode_shell_tree(np.frombuffer(_shell_tree_body(shell), dtype=np.uint8), np.asarray(bounding, bool))
    fields = ("explicit", "vertex_planes", "grid", "facets", "links")
    if not all(np.array_equal(np.asarray(getattr(back, f)).reshape(-1), np.asarray(getattr(shell, f)).reshape(-1))
               for f in fields) or (back.grid.size and (not np.array_equal(back.origin, shell.origin)
                                                         or back.step != shell.step)):
        raise FormatError("shell tree: its body does not decode to it (triangles not attached at their first "
                          "edge, corners not numbered by first use, or named corners not three of their face "
                          "planes in ascending order)", code="BAD_GROUP_STRUCTURE")


def _shell_tree_body(shell: Shell) -> bytes:
    """The kind data of a SHELL_TREE group (spec 3.3 §8.10)."""
    return b"".join(shell_tree_fields(shell).values())


def shell_tree_fields(shell: Shell) -> dict[str, bytes]:
    """The fields of a SHELL_TREE body (spec 3.3 §8.10) by name, in body order."""
    explicit = np.asarray(shell.explicit, dtype=bool)
    fc = np.asarray(shell.facets, dtype=np.int64)
    links = np.asarray(shell.links, dtype=np.int64)
    root, parent, edge = _tree_parents(links)
    face, tri = fc[:, 0], fc[:, 1:]
    t, v = len(fc), len(explicit)
    # The stream of corner codes: a root's three corners, an attached triangle's third.
    slots = np.where(root[:, None], tri, np.column_stack([np.full((t, 2), -1), tri[:, 2]]))
    stream = slots.reshape(-1)
    stream = stream[stream >= 0]
    is_root = np.repeat(root, np.where(root, 3, 1))
    c1 = np.repeat(tri[:, 1], np.where(root, 3, 1))
    new = np.r_[True, stream[1:] > np.maximum.accumulate(stream)[:-1]]
    before = np.cumsum(new) - new
    codes = np.where(new, 0, np.where(is_root, before - stream,
                                      varint.zigzag(stream - c1).astype(np.int64) + 1))
    same = np.where(root, np.r_[FREE, face[:-1]], face[np.maximum(parent, 0)]) == face
    faces = np.where(same, 0, np.where(face == FREE, 1, face + 2))
    out = {"counts": varint.encode([v, t]), "links": varint.encode(links), "codes": varint.encode(codes),
           "faces": varint.encode(faces), "flags": np.packbits(explicit, bitorder="little").tobytes(), "picks": b""}
    named = np.flatnonzero(~explicit)
    if len(named):
        refs, start, runs = incident_planes(tri, face, v)
        vp = np.asarray(shell.vertex_planes, dtype=np.int64).reshape(-1, 3)
        wide = runs[named] > 3
        # Each plane's place in its corner's run: one search over (corner, reference) keys.
        span = max(int(refs.max(initial=0)), int(vp.max(initial=0))) + 1
        key = np.repeat(np.arange(v), runs) * span + refs
        out["picks"] = varint.encode(np.searchsorted(key, named[wide, None] * span + vp[wide])
                                     - start[named[wide], None])
    if explicit.any():
        g_all = np.zeros((v, 3), dtype=np.int64)
        g_all[explicit] = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
        pred = _tree_predictors(links, tri, explicit, np.where(root, 3, 1), new)
        base = np.where(pred[:, None] >= 0, g_all[np.maximum(pred, 0)], 0)
        out["grid"] = schema.ShellGrid.build(dict(origin=[float(x) for x in shell.origin], step=float(shell.step)))
        # Axis by axis: each axis's residuals deflate as one run (CAD/box.STL: 7.5 kB against 8.8 kB
        # interleaved).
        out["coordinates"] = varint.encode(varint.zigzag((g_all - base)[explicit].T))
    return out


def _decode_shell_tree(raw: np.ndarray, bounding: np.ndarray) -> Shell:
    """The corners and triangles of a SHELL_TREE body (spec 3.3 §8.10), checked."""
    def bad(reason: str) -> FormatError:
        return FormatError(f"shell tree: {reason}", code="BAD_GROUP_STRUCTURE")
    (v, t), pos = varint.decode(raw, 2, "shell tree counts")
    v, t = int(v), int(t)
    left = len(raw) - pos
    if not (3 <= v <= 8 * left and 1 <= t <= left // 3):
        raise bad(f"{v} corners, {t} triangles: outside the ranges the body allows")
    links, used = varint.decode(raw[pos:], t, "shell tree links")
    pos += used
    codes, used = varint.decode(raw[pos:], t + 2 * int((links == 0).sum()), "shell tree corner codes")
    pos += used
    faces, used = varint.decode(raw[pos:], t, "shell tree faces")
    pos += used
    explicit, pos = _bit_field(raw, pos, v, "shell tree: the body", "corner flags")
    if links.max() > np.uint64(3 * t):
        raise bad("a triangle is attached to one before the first")
    links = links.astype(np.int64)
    root, parent, edge = _tree_parents(links)
    if (parent[~root] < 0).any():
        raise bad("a triangle is attached to one before the first")
    if codes.max() > np.uint64(2 * v + 1):
        raise bad("a corner code is past the group's corners")
    codes = codes.astype(np.int64)
    per = np.where(root, 3, 1)
    end = np.cumsum(per)
    first = end - per
    new = codes == 0
    before = np.cumsum(new) - new
    is_root = np.repeat(root, per)
    # Each triangle slot (3 per triangle) is a corner, or a pointer to an earlier slot plus an offset.
    value = np.zeros(3 * t, dtype=np.int64)
    pointer = np.full(3 * t, -1, dtype=np.int64)
    offset = np.zeros(3 * t, dtype=np.int64)
    direct = np.where(new, before, before - codes)
    rows = np.flatnonzero(root)
    value[(3 * rows[:, None] + np.arange(3)).reshape(-1)] = direct[(first[rows, None] + np.arange(3)).reshape(-1)]
    att = np.flatnonzero(~root)
    pointer[3 * att] = 3 * parent[att] + (edge[att] + 1) % 3
    pointer[3 * att + 1] = 3 * parent[att] + edge[att]
    third = first[att]
    fresh = new[third]
    value[3 * att[fresh] + 2] = before[third[fresh]]
    old = att[~fresh]
    pointer[3 * old + 2] = 3 * old + 1
    offset[3 * old + 2] = varint.unzigzag((codes[third[~fresh]] - 1).astype(np.uint64))
    if (~new & is_root & (codes > before)).any():
        raise bad("a triangle corner refers back past the first corner")
    tri = resolve_chains(value, pointer, offset).reshape(-1, 3)
    named_again = tri[old, 2]
    if ((named_again < 0) | (named_again >= before[third[~fresh]])).any():
        raise bad("a triangle's third corner is not one named before it")
    if int(new.sum()) != v:
        raise bad(f"{int(new.sum())} corners are named anew, not {v}")
    if ((tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 0] == tri[:, 2])).any():
        raise bad("a triangle names one corner twice")
    m = len(bounding)
    if faces.max() > np.uint64(m + 1):
        raise bad("a face reference is past the group's references")
    faces = faces.astype(np.int64)
    fvalue = np.where(faces == 1, FREE, faces - 2)
    fpointer = np.where(faces == 0, np.where(root, np.arange(t) - 1, parent), -1)
    fvalue[(faces == 0) & (fpointer < 0)] = FREE
    fpointer[fpointer < 0] = -1
    face = resolve_chains(fvalue, fpointer, np.zeros(t, dtype=np.int64))
    planar = face != FREE
    if bounding[face[planar]].any():
        raise bad("a triangle lies on a reference that is not a face plane")
    named = np.flatnonzero(~explicit)
    vertex_planes = np.zeros((0, 3), dtype=np.int64)
    if len(named):
        refs, start, runs = incident_planes(tri, face, v)
        if (runs[named] < 3).any():
            raise bad("a named corner is on fewer than three face planes")
        wide = named[runs[named] > 3]
        picks, used = varint.decode(raw[pos:], 3 * len(wide), "shell tree corner planes")
        pos += used
        picks = picks.reshape(-1, 3)
        if len(wide) and ((picks[:, 0] >= picks[:, 1]) | (picks[:, 1] >= picks[:, 2])
                          | (picks[:, 2] >= runs[wide].astype(np.uint64))).any():
            raise bad("a corner's planes are not three of its face planes in ascending order")
        pick = np.tile(np.arange(3, dtype=np.int64), (len(named), 1))
        pick[runs[named] > 3] = picks.astype(np.int64)
        vertex_planes = refs[start[named, None] + pick]
    e = int(explicit.sum())
    origin, step, grid = np.zeros(3), 0.0, np.zeros((0, 3), dtype=np.int64)
    if e:
        if len(raw) < pos + schema.SHELL_GRID_BYTES:
            raise FormatError("shell tree: the body ends inside its grid", code="BAD_PAYLOAD")
        g = schema.ShellGrid.parse(raw[pos:pos + schema.SHELL_GRID_BYTES].tobytes())
        pos += schema.SHELL_GRID_BYTES
        origin, step = np.array(g.origin, dtype=np.float64), float(g.step)
        deltas, used = varint.decode(raw[pos:], 3 * e, "shell tree corner coordinates")
        pos += used
        steps = varint.unzigzag(deltas).reshape(3, -1).T
        if np.abs(steps).max(initial=0) > MAX_GRID:
            raise bad("a grid residual is beyond 2^52")
        pred = _tree_predictors(links, tri, explicit, per, new)
        ex = np.flatnonzero(explicit)
        residual = np.zeros((3, v), dtype=np.int64)
        residual[:, ex] = steps.T
        chained = resolve_chains(residual.reshape(-1), (np.where(pred >= 0, pred, -1) + np.where(
            pred >= 0, np.arange(3)[:, None] * v, 0)).reshape(-1), residual.reshape(-1))
        grid = chained.reshape(3, v).T[ex]
        if np.abs(grid).max(initial=0) > MAX_GRID:
            raise bad("a grid coordinate is beyond 2^52")
    if pos != len(raw):
        raise bad("the corners do not fill the body")
    shell = Shell(explicit=explicit, vertex_planes=vertex_planes, grid=grid, origin=origin, step=step,
                  facets=np.column_stack([face, tri]), links=links)
    if e and not (np.isfinite(origin).all() and math.isfinite(step) and step > 0):
        raise bad("the grid's origin and step must be finite, the step positive")
    return shell
