"""The valid golden files: what each holds, how it is written, and what a reader must report.

A case is a list of operations (objects, plane blocks, groups, colours, raw
ancillary chunks) replayed through ``planefmt.Writer``. The same operations
are also assembled chunk by chunk from the payload encoders, and the two
must agree byte for byte: that keeps the broken files, which are assembled
the same way, honest. The one case the writer cannot produce (version 1.1
features) is assembled only.
"""

from __future__ import annotations

import dataclasses
import io
import math
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field

import brotli
import numpy as np

import planefmt
import planefmt.container.quantize
from planefmt.container import records, schema
from planefmt.model import (UP_AXIS, Coding, Colours, GroupKind, Header, Metadata, ObjectRecord, PartGroup,
                            Quantization, Shell, Units)

from . import reference
from .build import (CUBE, SPEC_HEADER, assemble_v6, box, finish, frame, header_json, metadata_json, rounded,
                    shell_json, small_v6, split, stored_header, stored_planes, world_matrices)

#: Relative tolerance of geometry comparisons (see README.md).
GEOMETRY_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Obj:
    name: str
    parent: int | None = None
    transform: np.ndarray | None = None
    extra: bytes = b""  # OBJT fields of a newer minor version (spec §8)


@dataclass(frozen=True)
class Planes:
    triplets: np.ndarray


@dataclass(frozen=True)
class Group:
    obj: int
    kind: int
    refs: tuple[int, ...]
    bounding: tuple[int, ...] = ()  # local indices of bounding / cut planes
    cells: tuple[tuple[int, ...], ...] | None = None
    tree: tuple[int, ...] | None = None
    vertex_planes: tuple[tuple[int, int, int], ...] | None = None  # sealed groups: local references
    facets: tuple[tuple[int, int, int, int], ...] | None = None  # sealed groups: face reference, 3 vertices
    shell: Shell | None = None  # shell groups (spec §9.10)
    extra: bytes = b""  # kind data of a kind this version does not know


@dataclass(frozen=True)
class Colour:
    group: int
    rgba: np.ndarray


@dataclass(frozen=True)
class Meta:
    key: str
    value: str


@dataclass(frozen=True)
class Chunk:
    type: bytes  # version 6: one byte of 128 to 255, an ancillary record (spec §4.6)
    payload: bytes


@dataclass(frozen=True)
class Segment:
    """Version 6: a new body segment starts here, in a BODY chunk (spec §4.5; assembled cases only);
    ``empty``: after a segment of no record."""

    empty: bool = False


@dataclass(frozen=True)
class ValidCase:
    name: str
    description: str
    header: Header
    ops: tuple
    compress: bool = False
    index: bool = True
    stream: bool = False  # written through a non-seekable sink: the header cannot get its counts
    decoded_bbox: bool = False  # header bbox = the decoded geometry's, rounded to 9 decimals
    assembled_only: bool = False  # uses what a version 1.0 writer cannot write
    header_flags: int = 0  # PHDR flag bits beyond the writer's (assembled cases only)
    #: Rewrites the assembled chunks (type, payload) before iNDX and PEND are added: bytes a writer
    #: does not write but a reader must accept (assembled cases only).
    edit: Callable[[list], list] | None = field(default=None, compare=False)
    findings: tuple[str, ...] = ()
    findings_optional: tuple[str, ...] = ()
    #: Version 6: the compression method of each body segment, where not the smallest (assembled cases only).
    methods: tuple[int, ...] | None = None
    table: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        planes = [op.triplets for op in self.ops if isinstance(op, Planes)]
        raw = np.concatenate(planes) if planes else np.zeros((0, 3))
        object.__setattr__(self, "table", stored_planes(raw, self.header.coding, self.header.quantization))

    @property
    def objects(self) -> list[Obj]:
        return [op for op in self.ops if isinstance(op, Obj)]

    @property
    def groups(self) -> list[Group]:
        return [op for op in self.ops if isinstance(op, Group)]

    @property
    def counts(self) -> tuple[int, int, int] | None:
        return None if self.stream else (len(self.table), len(self.objects), len(self.groups))


def _role_bits(g: Group) -> np.ndarray:
    bits = np.zeros(len(g.refs), dtype=bool)
    bits[list(g.bounding)] = True
    return bits


def _cells(g: Group):
    return None if g.cells is None else tuple(np.array(c, dtype=np.uint32) for c in g.cells)


def _tree(g: Group):
    return None if g.tree is None else np.array(g.tree, dtype=np.uint32)


def _vertex_planes(g: Group):
    return None if g.vertex_planes is None else np.array(g.vertex_planes, dtype=np.uint32)


def _facets(g: Group):
    return None if g.facets is None else np.array(g.facets, dtype=np.uint32)


class _Pipe(io.RawIOBase):
    """A write-only, non-seekable sink, as a pipe or socket is."""

    def __init__(self) -> None:
        self.data = bytearray()

    def writable(self) -> bool:
        return True

    def write(self, b) -> int:
        self.data += b
        return len(b)


def written(case: ValidCase, header: Header) -> bytes:
    """The file as ``planefmt.Writer`` writes it."""
    sink = _Pipe() if case.stream else io.BytesIO()
    if header.version[0] >= 3 and case.counts is not None:
        # A version 3 or 4 writer writes the counts it is told up front (spec §5).
        header = dataclasses.replace(header, plane_count=case.counts[0], object_count=case.counts[1],
                                     group_count=case.counts[2])
    with planefmt.Writer(sink, header, compress=case.compress, index=case.index) as w:
        for op in case.ops:
            if isinstance(op, Obj):
                w.add_object(op.name, op.parent, op.transform)
            elif isinstance(op, Planes):
                w.add_planes(op.triplets)
            elif isinstance(op, Group):
                w.add_group(op.obj, op.kind, np.array(op.refs), _role_bits(op), cells=_cells(op), tree=_tree(op),
                            extra=op.extra, vertex_planes=_vertex_planes(op), facets=_facets(op), shell=op.shell)
            elif isinstance(op, Colour):
                w.add_colours(op.group, op.rgba)
            elif isinstance(op, Meta):
                w.add_metadata(op.key, op.value)
            elif isinstance(op, Chunk):
                w.add_chunk(op.type, op.payload)
            else:
                raise AssertionError(f"{case.name}: a writer cannot start a segment where it is told")
    return bytes(sink.data) if case.stream else sink.getvalue()


def assembled(case: ValidCase, header: Header) -> bytes:
    """The file assembled chunk by chunk from planefmt's payload encoders and ``chunk_bytes``."""
    counts = case.counts or (None, None, None)
    header = dataclasses.replace(header, plane_count=counts[0], object_count=counts[1], group_count=counts[2])
    if header.version[0] >= 6:
        return assemble_v6(header, items_v6(case, header), index=case.index, compress=case.compress,
                           methods=case.methods)
    phdr = bytearray(records.encode_header(header))
    phdr[2:4] = (int.from_bytes(phdr[2:4], "little") | case.header_flags).to_bytes(2, "little")
    layout = [(schema.PHDR, bytes(phdr))]
    planes = objects = groups = 0
    copied = copies(case)
    for op in case.ops:
        if isinstance(op, Obj):
            rec = ObjectRecord(objects, op.name, op.parent, op.transform)
            layout.append((schema.OBJT, records.encode_object(rec, header.version[0]) + op.extra))
            objects += 1
        elif isinstance(op, Planes):
            layout.append((schema.PLNS, records.encode_planes(planes, op.triplets, header, case.compress)))
            planes += len(op.triplets)
        elif isinstance(op, Group):
            rec = _group_record(op, groups, copied)
            layout.append((schema.GRUP, records.encode_group(rec, case.compress, header.version[0])))
            groups += 1
        elif isinstance(op, Colour):
            layout.append((schema.COLR, records.encode_colours(Colours(op.group, op.rgba), header.version[0],
                                                               len(case.groups[op.group].refs))))
        elif isinstance(op, Meta):
            layout.append((schema.META, records.encode_metadata(Metadata(op.key, op.value))))
        else:
            layout.append((op.type, op.payload))
    if case.edit is not None:
        layout = case.edit(layout)
    return frame(finish(layout, case.index, header.version[0]))


def _group_record(op: Group, index: int, copied: dict[int, int]) -> PartGroup:
    """Group ``index`` of a case as its record: a copy (kind 11) of its source where the case copies it."""
    rec = PartGroup(index, op.obj, op.kind, np.array(op.refs, dtype=np.uint32), _role_bits(op),
                    cells=_cells(op), tree=_tree(op), extra=op.extra, vertex_planes=_vertex_planes(op),
                    facets=_facets(op), shell=op.shell)
    if index in copied:
        return PartGroup(index, op.obj, int(GroupKind.COPY), rec.refs, rec.bounding, source=copied[index])
    return rec


def items_v6(case: ValidCase, header: Header) -> list[tuple]:
    """The records of a version 6 case, ``(tag, payload)``, with its segment starts and chunks between them."""
    items: list[tuple] = []
    planes = objects = groups = 0
    copied = copies(case)
    for op in case.ops:
        if isinstance(op, Obj):
            items.append((schema.TAG_OBJECT, records.encode_object(ObjectRecord(objects, op.name, op.parent,
                                                                                op.transform), 6) + op.extra))
            objects += 1
        elif isinstance(op, Planes):
            items.append((schema.TAG_PLANES, records.encode_planes(planes, op.triplets, header, case.compress)))
            planes += len(op.triplets)
        elif isinstance(op, Group):
            rec = _group_record(op, groups, copied)
            items.append((schema.TAG_GROUP, records.encode_group(rec, case.compress, 6)))
            groups += 1
        elif isinstance(op, Colour):
            items.append((schema.TAG_COLOURS, records.encode_colours(Colours(op.group, op.rgba), 6,
                                                                     len(case.groups[op.group].refs))))
        elif isinstance(op, Meta):
            items.append((schema.TAG_METADATA, records.encode_metadata(Metadata(op.key, op.value))))
        elif isinstance(op, Segment):
            items.append(split(op.empty))
        else:
            items.append((op.type[0], op.payload) if len(op.type) == 1 else (op.type, op.payload))
    return items


def geometry(case: ValidCase) -> tuple[dict, np.ndarray | None]:
    """The expected geometry section and the world bounding box of the decoded surface."""
    worlds = world_matrices([(o.parent, o.transform) for o in case.objects])
    summaries, corners = [], []
    kinds = records.kinds_of(*case.header.version)
    error = _plane_error(case.header)
    for g in case.groups:
        if g.kind not in kinds:
            summaries.append(None)  # skipped: SKIPPED_GROUP_KIND (kind 5 too, in a version before 3.1)
            continue
        s, points = reference.summary(g.kind, case.table[list(g.refs)], _role_bits(g), g.cells, g.tree,
                                      g.vertex_planes, g.facets, g.shell, error)
        summaries.append({k: v if k in ("vertices", "triangles") else rounded(v) for k, v in s.items()})
        corners.append(points @ worlds[g.obj][:3, :3].T + worlds[g.obj][:3, 3])
    world = None
    if corners:
        points = np.concatenate(corners)
        world = np.array(rounded([points.min(axis=0), points.max(axis=0)]))
    section = {"tolerance": GEOMETRY_TOLERANCE, "world_bbox": None if world is None else world.tolist(),
               "groups": summaries}
    return section, world


def _plane_error(header: Header) -> reference.PlaneError:
    """Spec §9.4's coding error of a case's header, for the merge distance of its counts."""
    q = header.quantization
    return reference.plane_error(int(header.coding), q and (q.bits_nu, q.bits_phi, q.bits_h), q and (q.h_min, q.h_max),
                                 header.tolerance, header.diagonal)


def copies(case: ValidCase) -> dict[int, int]:
    """The groups a writer of the case's version writes as copies (spec §9.15: a group whose kind,
    common body and kind data are an earlier group's), each with its source."""
    if int(GroupKind.COPY) not in records.kinds_of(*case.header.version):
        return {}
    seen, out = {}, {}
    for i, g in enumerate(case.groups):
        body = records.group_body(PartGroup(i, g.obj, g.kind, np.array(g.refs, dtype=np.uint32), _role_bits(g),
                                            cells=_cells(g), tree=_tree(g), extra=g.extra,
                                            vertex_planes=_vertex_planes(g), facets=_facets(g), shell=g.shell))
        if (int(g.kind), body) in seen:
            out[i] = seen[int(g.kind), body]
        else:
            seen[int(g.kind), body] = i
    return out


def expected(case: ValidCase, header: Header, geo: dict, counts: tuple[int, int, int] | None | bool = True) -> dict:
    """The expected result; ``counts`` True: the case's own."""
    counts = case.counts if counts is True else counts
    objects = [{"name": o.name, "parent": o.parent,
                "transform": None if o.transform is None else np.asarray(o.transform, float).ravel().tolist()}
               for o in case.objects]
    groups = []
    copied = copies(case)
    for i, g in enumerate(case.groups):
        entry = {"index": i, "object": g.obj, "kind": g.kind, "refs": list(g.refs), "bounding": list(g.bounding)}
        if i in copied:
            groups.append({**entry, "kind": int(GroupKind.COPY), "source": copied[i]})
            continue
        if g.cells is not None:
            entry["cells"] = [list(c) for c in g.cells]
        if g.tree is not None:
            entry["tree"] = list(g.tree)
        if g.vertex_planes is not None:
            entry["vertex_planes"] = [list(v) for v in g.vertex_planes]
            entry["facets"] = [list(f) for f in g.facets]
        if g.shell is not None:
            entry["shell"] = shell_json(g.shell)
        groups.append(entry)
    colours = [{"group": op.group, "rgba": np.asarray(op.rgba).tolist()} for op in case.ops
               if isinstance(op, Colour)]
    result = {
        "header": header_json(header, counts),
        "planes": case.table.tolist(),
        "objects": objects,
        "groups": groups,
        "colours": colours,
        "findings": sorted(set(case.findings)),
        "findings_optional": sorted(set(case.findings_optional)),
        "geometry": geo,
    }
    metadata = metadata_json(header, {op.key: op.value for op in case.ops if isinstance(op, Meta)})
    if metadata:
        # Only here: the results of the cases before mETA stay as they were.
        result["metadata"] = metadata
    return result


def build(case: ValidCase) -> tuple[bytes, dict]:
    """The file's bytes and its expected result."""
    geo, world = geometry(case)
    header = case.header
    if case.decoded_bbox:
        header = dataclasses.replace(header, bbox=world)
    data = assembled(case, header)
    if not case.assembled_only:
        by_writer = written(case, header)
        if by_writer != data:
            raise AssertionError(f"{case.name}: planefmt.Writer and the chunk assembler disagree")
    if header.version[0] >= 6 and small_v6(items_v6(case, header)):
        # A file of one small segment leaves out its bbox and counts (spec §5).
        return data, expected(case, stored_header(dataclasses.replace(header, bbox=None)), geo, None)
    return data, expected(case, stored_header(header), geo)


# -- shapes ----------------------------------------------------------------------------------

#: A convex "gem" of ten planes at irregular angles and distances (every plane bounds a face).
GEM = np.array([
    [0.0, 0.0, 1.0], [math.pi, 0.0, 0.9],
    [1.1, 0.3, 1.1], [1.2, 1.9, 0.95], [1.0, 3.4, 1.05], [1.3, 4.6, 0.9], [1.15, 5.9, 1.0],
    [2.0, 1.0, 1.2], [2.1, 2.8, 0.85], [1.9, 5.0, 1.1],
])


def tangent_planes(n: int) -> np.ndarray:
    """Planes tangent to the unit sphere at a Fibonacci lattice of ``n`` points.

    Angles are rounded to 6 decimals so that the file does not depend on the
    last bits of the platform's acos.
    """
    golden = math.pi * (3.0 - math.sqrt(5.0))
    return np.array([[round(math.acos(1.0 - 2.0 * (i + 0.5) / n), 6), round(i * golden % (2 * math.pi), 6), 1.0]
                     for i in range(n)])


def affine(linear, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    """The 4x4 matrix of ``p -> linear p + (x, y, z)``."""
    m = np.eye(4)
    m[:3, :3] = linear
    m[:3, 3] = (x, y, z)
    return m


def translation(x: float, y: float, z: float) -> np.ndarray:
    return affine(np.eye(3), x, y, z)


def cube_ops(*extra_ops) -> tuple:
    return (Obj("cube"), Planes(CUBE), Group(0, GroupKind.CONVEX, tuple(range(6))), *extra_ops)


def quantized(bits: tuple[int, int, int], h_range: tuple[float, float]) -> Header:
    return Header(lossy=True, coding=Coding.QUANTIZED, quantization=Quantization(*bits, *h_range),
                  units=Units.METRE)


#: The L-shaped solid [0,2]x[0,1]x[0,1] u [0,1]x[0,2]x[0,1]: its eight face planes, then the cut
#: x = y through the inner corner, which splits it into two convex quadrilateral prisms.
L_PLANES = np.array([
    [math.pi / 2, 1.5 * math.pi, 0.0],  # 0: y >= 0
    [math.pi / 2, 0.0, 2.0],  # 1: x <= 2
    [math.pi / 2, math.pi / 2, 1.0],  # 2: y <= 1 (face for 1 <= x <= 2)
    [math.pi / 2, 0.0, 1.0],  # 3: x <= 1 (face for 1 <= y <= 2)
    [math.pi / 2, math.pi / 2, 2.0],  # 4: y <= 2
    [math.pi / 2, math.pi, 0.0],  # 5: x >= 0
    [0.0, 0.0, 1.0],  # 6: z <= 1
    [math.pi, 0.0, 0.0],  # 7: z >= 0
    [math.pi / 2, 1.75 * math.pi, 0.0],  # 8: x - y <= 0, a cut plane
])
IN, OUT = reference.BSP_IN, reference.BSP_OUT
#: Cells of the L (entries 2 j + s): the prism below the cut x = y uses its complement (17 = 2*8 + 1).
L_CELLS = ((0, 2, 4, 17, 12, 14), (6, 8, 10, 16, 12, 14))
#: A tree of the L over its eight face planes: split on y <= 1, then each side is a chain of splits.
L_TREE = (2, 0, 1, 5, 6, 7, IN, OUT, OUT, OUT, OUT, OUT, 3, 4, 5, 6, 7, IN, OUT, OUT, OUT, OUT, OUT)

_scene_planes_leg = np.array([
    [math.pi / 2, math.nextafter(2 * math.pi, 0.0), 0.1],  # x <= 0.1 with phi just below 2 pi
    [math.pi / 2, math.pi / 2, 0.1],  # y <= 0.1
    [0.0, 1.0, 1.0],  # z <= 1 at the pole, phi = 1 (writers SHOULD store 0; readers take any)
])

_rgba = np.array([[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [255, 255, 0, 128],
                  [0, 255, 255, 0], [255, 0, 255, 255]], dtype=np.uint8)

def _sorted_l() -> tuple[np.ndarray, tuple[int, ...]]:
    """The L's eight face planes sorted by their 8/8/8 codes over [-1, 2] (as a version 2 writer
    sorts them), and its tree renumbered to match."""
    q = Quantization(8, 8, 8, -1.0, 2.0)
    codes = planefmt.container.quantize.quantize(L_PLANES[:8], q)
    order = np.lexsort((codes[:, 2], codes[:, 1], codes[:, 0]))
    rank = np.empty(8, dtype=np.int64)
    rank[order] = np.arange(8)
    return L_PLANES[:8][order], tuple(int(rank[t]) if t < 8 else t for t in L_TREE)


L_SORTED, L_SORTED_TREE = _sorted_l()
#: Version 2.0 headers: the predicted coding, or float64.
V2_L = Header(version=(2, 0), lossy=True, coding=Coding.PREDICTED,
              quantization=Quantization(8, 8, 8, -1.0, 2.0), units=Units.METRE)
V2_F64 = Header(version=(2, 0), coding=Coding.FLOAT64, units=Units.METRE)
#: Version 3.0 headers: compact heads around the planes and bodies of version 2.0.
V3_CUBE = dataclasses.replace(SPEC_HEADER, version=(3, 0))
V3_Q221 = Header(version=(3, 0), coding=Coding.QUANTIZED, quantization=Quantization(2, 2, 1, 0.0, 1.0),
                 units=Units.MILLIMETRE, tolerance=1e-6, error_bound=2.2e-14)

#: The unit cube as a sealed group (kind 5, spec §9.9) over the planes of CUBE: vertex x + 2y + 4z
#: is the corner (x, y, z), named by its three face planes (x = 1 or 0: 0 or 2, y: 1 or 3, z: 4 or 5).
SEALED_CUBE_VERTICES = tuple((0 if x else 2, 1 if y else 3, 4 if z else 5)
                             for z in (0, 1) for y in (0, 1) for x in (0, 1))
#: Each face of CUBE (in its order) by its corners, counter-clockwise seen from outside.
_CUBE_QUADS = ((1, 3, 7, 5), (2, 6, 7, 3), (0, 4, 6, 2), (0, 1, 5, 4), (4, 5, 7, 6), (0, 2, 3, 1))
#: Two triangles per face, (face, i0, i1, i2), in order of face as sealed groups store them.
SEALED_CUBE_FACETS = tuple((f, *t) for f, (a, b, c, d) in enumerate(_CUBE_QUADS) for t in ((a, b, c), (a, c, d)))
#: A vertex plane through the corner (0, 0, 0): normal -(1, 1, 1)/sqrt 3 (nu = acos(-1/sqrt 3), phi = 5 pi/4,
#: to 6 decimals), h = 0.
CORNER_PLANE = np.array([[2.186276, 3.926991, 0.0]])
#: SEALED_CUBE_VERTICES with the corner (0, 0, 0) named by x = 0, y = 0 and CORNER_PLANE (reference 6).
SEALED_CORNER_VERTICES = ((2, 3, 6),) + SEALED_CUBE_VERTICES[1:]

def shell_of(corners, facets, origin=(0.0, 0.0, 0.0), step: float = 1.0) -> Shell:
    """A :class:`Shell` from ``corners`` (each a triple of local references, or ``("grid", x, y, z)``)
    and ``facets`` (face or -1, i0, i1, i2) in any order: triangles sorted by face, free ones last,
    and corners renumbered by first use, as spec §9.10 stores them."""
    fc = sorted(facets, key=lambda f: (f[0] < 0, f[0]))
    order: list[int] = []
    for f in fc:
        order += [i for i in f[1:] if i not in order]
    rank = {old: new for new, old in enumerate(order)}
    explicit = np.array([corners[k][0] == "grid" for k in order])
    return Shell(explicit=explicit,
                 vertex_planes=np.array([corners[k] for k in order if corners[k][0] != "grid"],
                                        dtype=np.int64).reshape(-1, 3),
                 grid=np.array([corners[k][1:] for k in order if corners[k][0] == "grid"], dtype=np.int64).reshape(-1, 3),
                 origin=np.array(origin, dtype=np.float64), step=float(step),
                 facets=np.array([(f[0], *(rank[i] for i in f[1:])) for f in fc], dtype=np.int64))


#: The unit cube as a shell (kind 6, spec §9.10): the corners and triangles of the sealed cube.
SHELL_CUBE = shell_of(SEALED_CUBE_VERTICES, SEALED_CUBE_FACETS)
#: The same with its corner (0, 0, 0) explicit (grid step 0.25, at 0, 0, 0) and the two triangles of
#: face 5 (z >= 0) free: reference 5 then only names corners.
SHELL_MIXED = shell_of((("grid", 0, 0, 0),) + SEALED_CUBE_VERTICES[1:],
                       [(-1 if f == 5 else f, a, b, c) for f, a, b, c in SEALED_CUBE_FACETS], step=0.25)
#: An open square pyramid without a base, every corner explicit on a grid of step 0.5 (apex at
#: (0.5, 0.5, 1)), every triangle free: its one reference (z <= 1 of CUBE, local 0) names nothing
#: and gives the free triangles their colour.
SHELL_PYRAMID = shell_of((("grid", 0, 0, 0), ("grid", 2, 0, 0), ("grid", 2, 2, 0), ("grid", 0, 2, 0), ("grid", 1, 1, 2)),
                         [(-1, 0, 1, 4), (-1, 1, 2, 4), (-1, 2, 3, 4), (-1, 3, 0, 4)], step=0.5)
V32_CUBE = dataclasses.replace(SPEC_HEADER, version=(3, 2))


def tree_of(explicit, vertex_planes, grid, facets, links, step: float = 1.0) -> Shell:
    """A shell tree (kind 7, spec 3.3 §8.10) as its fields: corner flags (1 explicit), each named
    corner's references ascending, explicit corners' integer coordinates, triangles (face or -1,
    i0, i1, i2) in tree order, each attached one starting with the edge it shares, and links."""
    return Shell(explicit=np.array(explicit, dtype=bool), vertex_planes=np.array(vertex_planes, dtype=np.int64).reshape(-1, 3),
                 grid=np.array(grid, dtype=np.int64).reshape(-1, 3), origin=np.zeros(3), step=float(step),
                 facets=np.array(facets, dtype=np.int64), links=np.array(links, dtype=np.int64))


#: SHELL_CUBE as a shell tree: one root, eleven triangles each attached to the one before (links 2
#: and 3: edges 1 and 2 of it); every corner on exactly three face planes, so no picks.
TREE_CUBE = tree_of([0] * 8, [(0, 3, 5), (0, 1, 5), (0, 1, 4), (0, 3, 4), (2, 3, 4), (1, 2, 4), (1, 2, 5), (2, 3, 5)],
                    [], [(0, 0, 1, 2), (0, 0, 2, 3), (4, 3, 2, 4), (4, 4, 2, 5), (1, 5, 2, 6), (1, 6, 2, 1),
                         (5, 6, 1, 7), (5, 7, 1, 0), (3, 7, 0, 3), (3, 7, 3, 4), (2, 7, 4, 5), (2, 7, 5, 6)],
                    [0, 3, 2, 2, 2, 2, 3, 2, 3, 3, 3, 3])
#: TREE_CUBE with the two triangles of face 5 (z >= 0) free: its four corners, no longer on three face
#: planes, are explicit (grid step 0.25), the other four named.
TREE_MIXED = tree_of([1, 1, 0, 0, 0, 0, 1, 1], TREE_CUBE.vertex_planes[2:6], [(4, 0, 0), (4, 4, 0), (0, 4, 0), (0, 0, 0)],
                     [(-1 if f == 5 else f, a, b, c) for f, a, b, c in TREE_CUBE.facets], TREE_CUBE.links, step=0.25)
#: SHELL_PYRAMID as a shell tree: corner 2, the apex (1, 1, 2), is named anew by the root, so its
#: coordinates are coded from corner 1's; corners 3 and 4 from the first corner (2, the apex) of the
#: attached triangles that name them.
TREE_PYRAMID = tree_of([1] * 5, [], [(0, 0, 0), (2, 0, 0), (1, 1, 2), (2, 2, 0), (0, 2, 0)],
                       [(-1, 0, 1, 2), (-1, 2, 1, 3), (-1, 2, 3, 4), (-1, 2, 4, 0)], [0, 2, 3, 3], step=0.5)
#: A closed square pyramid over the unit square, apex (0.5, 0.5, 0.5): the base z >= 0 (reference 0)
#: and the sides y >= 0, x <= 1, y <= 1, x >= 0 leaning in at 45 degrees (1 to 4). The apex is on all
#: four sides: its picks 0, 1, 2 name it by 1, 2, 3.
APEX_PLANES = np.array([[math.pi, 0.0, 0.0], [math.pi / 4, 1.5 * math.pi, 0.0], [math.pi / 4, 0.0, math.sqrt(0.5)],
                        [math.pi / 4, math.pi / 2, math.sqrt(0.5)], [math.pi / 4, math.pi, 0.0]])
TREE_APEX = tree_of([0] * 5, [(0, 1, 4), (0, 2, 3), (0, 1, 2), (0, 3, 4), (1, 2, 3)], [],
                    [(0, 0, 1, 2), (0, 1, 0, 3), (4, 3, 0, 4), (1, 4, 0, 2), (2, 4, 2, 1), (3, 4, 1, 3)],
                    [0, 1, 2, 2, 3, 3])
V33_CUBE = dataclasses.replace(SPEC_HEADER, version=(3, 3))
#: TREE_CUBE with every corner explicit, on the grid of step 1 at the origin: as kind 8 (spec §9.12),
#: corners 3 to 7 are each predicted by the parallelogram of their triangle's shared edge and the
#: parent's opposite corner (corner 3: 0 + 2 - 1 = (1, 0, 1), residual 0).
TREE_BOX = tree_of([1] * 8, [], [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1), (0, 0, 1), (0, 1, 1), (0, 1, 0), (0, 0, 0)],
                   TREE_CUBE.facets, TREE_CUBE.links)
V34_CUBE = dataclasses.replace(SPEC_HEADER, version=(3, 4))
V40_CUBE = dataclasses.replace(SPEC_HEADER, version=(4, 0))
V41_CUBE = dataclasses.replace(SPEC_HEADER, version=(4, 1))
V42_CUBE = dataclasses.replace(SPEC_HEADER, version=(4, 2))
V50_CUBE = dataclasses.replace(SPEC_HEADER, version=(5, 0))
V51_CUBE = dataclasses.replace(SPEC_HEADER, version=(5, 1))
V52_CUBE = dataclasses.replace(SPEC_HEADER, version=(5, 2))
V60_CUBE = dataclasses.replace(SPEC_HEADER, version=(6, 0))


def _explicit_walk(mesh, edge_two_first: bool = False, steps: float = 4.0) -> Shell:
    """``mesh`` (a trimesh) at ``steps`` grid steps a unit, every corner explicit, every triangle free, as
    a shell tree along planefmt's depth-first walk, or along one that walks each triangle's neighbour
    across its edge 2 before the one across its edge 1 (a writer's choice a reader must follow)."""
    from planefmt.container.shellfields import first_use_order
    from planefmt.groups.shells import shell_tree

    rank = first_use_order(mesh.faces, len(mesh.vertices))
    grid = np.empty((len(mesh.vertices), 3), dtype=np.int64)
    grid[rank] = np.rint(mesh.vertices * steps).astype(np.int64)
    tri = rank[mesh.faces]
    flat = Shell(explicit=np.ones(len(grid), dtype=bool), vertex_planes=np.zeros((0, 3), dtype=np.int64), grid=grid,
                 origin=np.zeros(3), step=1.0 / steps, facets=np.column_stack([np.full(len(tri), -1), tri]))
    return shell_tree(flat, _edge_two_first(tri) if edge_two_first else None)[0]


def _edge_two_first(tri: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A depth-first walk of ``tri`` across shared edges, the neighbour across a triangle's edge 2
    before the one across its edge 1: (triangles in walk order, their corners rotated so that the
    edge shared with the parent comes first, links of spec §9.11)."""
    across = {(int(a), int(b)): (j, k) for j, t in enumerate(tri) for k, (a, b) in
              enumerate(((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))) }
    seen, walk, rows, links, place = set(), [], [], [], {}
    for start in range(len(tri)):
        stack = [(start, 0, -1, 0)]
        while stack:
            j, r, p, e = stack.pop()
            if j in seen:
                continue
            seen.add(j)
            place[j] = len(walk)
            row = [int(tri[j][(r + i) % 3]) for i in range(3)]
            links.append(0 if p < 0 else 3 * (len(walk) - p - 1) + e + 1)
            walk.append(j)
            rows.append(row)
            # Pushed edge 1's first, so that edge 2's is popped (walked) first; a root's edge 0 too.
            for k in ((0, 1, 2) if p < 0 else (1, 2)):
                w = across.get((row[(k + 1) % 3], row[k]))
                if w is not None and w[0] not in seen:
                    stack.append((w[0], w[1], place[j], k))
    return np.array(walk), np.array(rows, dtype=np.int64), np.array(links, dtype=np.int64)


def _trimesh(name: str, **kwargs):
    import trimesh

    return getattr(trimesh.creation, name)(**kwargs)


#: trimesh's icosphere of one subdivision (42 corners, 80 triangles) along planefmt's walk: as a shell
#: walk (spec §9.13) it has a branching triangle, left codes, a corner step in an escape and leaves.
WALK_SPHERE = _explicit_walk(_trimesh("icosphere", subdivisions=1))
#: The same walked edge 2 first: a gate's later-named corner is mostly not its first (spec §9.17).
WALK_SPHERE_TWO = _explicit_walk(_trimesh("icosphere", subdivisions=1), True)


def _split_cube_walk() -> Shell:
    """The unit cube, each face split into eight triangles over its corners, its edges' midpoints and its
    centre (26 corners, 48 triangles on CUBE's six planes): the cube's eight corners named by their three
    planes, the other 18 explicit on a grid of step 0.5, walked edge 2 first."""
    import trimesh

    from planefmt.container.shellfields import first_use_order
    from planefmt.groups.shells import shell_tree

    cube = _trimesh("box", extents=[1.0, 1.0, 1.0])
    cube.apply_translation([0.5, 0.5, 0.5])
    v, f = trimesh.remesh.subdivide(cube.vertices, cube.faces)
    normal = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    omega = np.stack([np.sin(CUBE[:, 0]) * np.cos(CUBE[:, 1]), np.sin(CUBE[:, 0]) * np.sin(CUBE[:, 1]),
                      np.cos(CUBE[:, 0])], axis=1)
    face = np.argmax(normal @ omega.T, axis=1)
    rank = first_use_order(f, len(v))
    corner = np.empty_like(v)
    corner[rank] = v
    named = np.all((corner == 0.0) | (corner == 1.0), axis=1)
    tri = rank[f]
    planes = [sorted({int(face[j]) for j in np.flatnonzero((tri == k).any(axis=1))}) for k in np.flatnonzero(named)]
    flat = Shell(explicit=~named, vertex_planes=np.array(planes, dtype=np.int64),
                 grid=np.rint(corner[~named] * 2).astype(np.int64), origin=np.zeros(3), step=0.5,
                 facets=np.column_stack([face, tri]))
    return shell_tree(flat, _edge_two_first(tri))[0]


#: The cube split and walked so that, of its explicit corners, some step from a later gate corner that is
#: explicit and some (whose later gate corner is named) from the previous explicit corner (spec §9.17).
WALK_SPLIT_CUBE = _split_cube_walk()
#: trimesh's torus of 6 by 4 sections (24 corners, 48 triangles) walked edge 2 first: right codes,
#: children in the order (2, 1), corner steps in escapes.
WALK_TORUS = _explicit_walk(_trimesh("torus", major_radius=1.0, minor_radius=0.4, major_sections=6, minor_sections=4),
                            edge_two_first=True)
#: trimesh's torus of 16 by 8 sections (128 corners, 256 triangles) at 64 steps a unit: walked round its
#: circles, so that most corners' chains of steps turn (spec §9.16), by angles the grid only approximates.
WALK_RING = _explicit_walk(_trimesh("torus", major_radius=1.0, minor_radius=0.35, major_sections=16,
                                    minor_sections=8), steps=64.0)
def _exact_walk() -> Shell:
    """Two triangles (0, 1, 2), (2, 1, 3) whose corner 3's chain (2, 1, 0) turns by steps d1 = (-39564,
    142330, 0), d2 = (228053, 255342, 0): its x quotient, exactly 145878, is 2^-33 below an integer that
    binary64 arithmetic rounds 2N + D up to (145879), so only exact integers decode corner 3."""
    from planefmt.groups.shells import shell_tree

    grid = np.array([[0, 0, 0], [-39564, 142330, 0], [188489, 397672, 0], [334368, 374377, 7]], dtype=np.int64)
    flat = Shell(explicit=np.ones(4, dtype=bool), vertex_planes=np.zeros((0, 3), dtype=np.int64), grid=grid,
                 origin=np.zeros(3), step=2.0 ** -16, facets=np.array([[-1, 0, 1, 2], [-1, 2, 1, 3]]))
    return shell_tree(flat)[0]


WALK_EXACT = _exact_walk()
#: The same torus at 2^19 steps a unit: steps around the tube are within 2^18 and turn, steps along the
#: ring are not and fall back to kind 9's prediction.
WALK_RING_FINE = _explicit_walk(_trimesh("torus", major_radius=1.0, minor_radius=0.35, major_sections=16,
                                         minor_sections=8), steps=float(1 << 19))


def walk_mode(shell: Shell, mode: int, major: int = 4) -> Callable[[list], list]:
    """An edit replacing every shell walk GRUP body's kind data by ``shell``'s with its explicit
    corners in coordinate ``mode`` (spec §9.13, §9.14, §9.16, §9.17), whichever a writer would pick: a reader
    must decode each; its grid as a version ``major`` file stores it."""
    from planefmt.container import shellfields, shellwalk, varint

    def edit(layout: list) -> list:
        out = []
        for kind, payload in layout:
            if kind == schema.GRUP and schema.GroupHead3.parse(payload).kind in shellwalk.WALK_KINDS:
                head = schema.GroupHead3.parse(payload)
                raw = np.frombuffer(bytes(head.body), dtype=np.uint8)
                (count,), pos = varint.decode(raw, 1, "count")
                _, used = varint.decode(raw[pos:], int(count), "refs")
                pos += used + (int(count) + 7) // 8
                fields = shellwalk.shell_walk_fields(shell, mode, GroupKind(head.kind))
                body = raw[:pos].tobytes() + b"".join({**fields, "grid": shellfields.grid_bytes(shell, major)}.values())
                payload = schema.GroupHead3.build(dict(head, raw_size=len(body), body=body))
            out.append((kind, payload))
        return out
    return edit


#: A rotation by 30 degrees about z: cos and sin are not float32 values, so version 4 stores them as f64.
ROT30 = np.array([[math.cos(math.pi / 6), -math.sin(math.pi / 6), 0.0], [math.sin(math.pi / 6), math.cos(math.pi / 6), 0.0],
                  [0.0, 0.0, 1.0]])
#: A mirror in x with a -0.0 entry (-0.0 is no code-0 zero: version 4 stores it as an f32).
MIRROR = np.array([[-1.0, -0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])

#: A newer minor version's additions: OBJT bytes after the transform, a group of unknown kind 9
#: between two known ones, a new flag bit (the PHDR bytes are each case's header extra).
NEWER_MINOR = dict(
    ops=(Obj("cube", transform=translation(0.5, 0.0, 0.0), extra=b"later"), Planes(CUBE),
         Group(0, 0, tuple(range(6))), Group(0, 9, tuple(range(6)), bounding=(4, 5), extra=b"\x00\x01\x02\x03"),
         Group(0, GroupKind.PSEUDO_CONVEX, tuple(range(6)), bounding=(4,))),
    decoded_bbox=True, assembled_only=True, header_flags=0x0100,
    findings=("SKIPPED_GROUP_KIND",), findings_optional=("NEWER_MINOR_VERSION",))

def brotli_payloads(layout: list) -> list:
    """Every GRUP body and PLNS block of ``layout`` stored again as a Brotli stream (spec §6, method 2),
    whether or not it is the smaller: a writer picks the smallest, and on these small payloads deflate
    ties."""
    out = []
    for kind, payload in layout:
        if kind == schema.GRUP:
            head = schema.GroupHead3.parse(payload)
            raw = zlib.decompress(head.body) if head.compression == schema.COMPRESSION_ZLIB else bytes(head.body)
            payload = schema.GroupHead3.build(dict(head, compression=schema.COMPRESSION_BROTLI, body=brotli.compress(raw)))
        elif kind == schema.PLNS:
            head = schema.PlaneBlock3.parse(payload)
            raw = zlib.decompress(head.data) if head.compression == schema.COMPRESSION_ZLIB else bytes(head.data)
            payload = schema.PlaneBlock3.build(dict(head, compression=schema.COMPRESSION_BROTLI, data=brotli.compress(raw)))
        out.append((kind, payload))
    return out


def ignored_fields(layout: list) -> list:
    """Every field spec/pln.md §2.1 says readers ignore, set: the PHDR's undefined flag bits (through
    ``header_flags``) and, under a float coding, its widths (and in version 1 its reserved bytes and h
    range, NaN and -inf); the OBJT's undefined flag bits (and in version 1 its reserved byte); in
    version 1 the reserved bytes of PLNS and GRUP heads."""
    out = []
    v1 = layout[0][1][0] == 1  # the PHDR's version_major
    for ctype, payload in layout:
        p = bytearray(payload)
        if ctype == schema.PHDR:
            p[5:8] = b"\x08\x10\x20"  # widths of a coding without widths
            if v1:
                p[9:12] = b"\xa5\x5a\xff"  # reserved
                p[12:28] = np.array([math.nan, -math.inf], "<f8").tobytes()  # h range of a float coding
        elif ctype == schema.OBJT:
            if v1:
                p[8] |= 0xFE  # flags: every bit but HAS_TRANSFORM
                p[9] = 0x77  # reserved
            else:
                p[2] |= 0xFE  # version 3: index 0 and parent 0 (one-byte varints), then flags
        elif ctype == schema.PLNS and v1:
            p[13:16] = b"\x01\x02\x03"
        elif ctype == schema.GRUP and v1:
            p[10:12] = b"\xfe\xff"
        out.append((ctype, bytes(p)))
    return out


#: The L's tree with one more split at its root on x >= 0 (reference 5), whose outer side (x <= 0)
#: splits on x <= 1 (reference 3) into an OUT leaf and an IN leaf whose region, x <= 0 and x >= 1, is
#: empty: an empty IN leaf contributes nothing (spec/pln.md §9.7).
L_TREE_EMPTY_LEAF = (5,) + L_TREE + (3, OUT, IN)
#: patch_convex's open box with its first face reference (x <= 1) given twice.
PATCH_REPEATED_OPS = (Obj("open box"),
                      Planes(np.vstack([box((0, 0, 0), (1, 1, 1))[[0, 1, 2, 3, 5]], [[0.46, math.pi, 0.8]]])),
                      Group(0, GroupKind.PSEUDO_CONVEX, (0, 0, 1, 2, 3, 4, 5), bounding=(6,)))
#: The same face reference given 12 times: more references than planefmt enumerates triples of (14).
PATCH_REPEATED_MANY_OPS = PATCH_REPEATED_OPS[:2] + (
    Group(0, GroupKind.PSEUDO_CONVEX, (0,) * 12 + (1, 2, 3, 4, 5), bounding=(16,)),)

#: copies_v4_2's scene, written again as version 6.0 (copies_v6_0): a shell walk cube and a convex cube,
#: each placed twice, the shell walk's copy with a colour of its own.
COPIES_SCENE = (Obj("walk"), Planes(CUBE), Group(0, GroupKind.SHELL_WALK, tuple(range(6)), shell=TREE_CUBE),
                Obj("walk twin", None, translation(2.0, 0.0, 0.0)),
                Group(1, GroupKind.SHELL_WALK, tuple(range(6)), shell=TREE_CUBE),
                Colour(1, np.tile(np.array([[200, 30, 30, 255]], dtype=np.uint8), (6, 1))),
                Obj("solid", None, translation(0.0, 3.0, 0.0)), Group(2, GroupKind.CONVEX, tuple(range(6))),
                Obj("solid twin", None, translation(2.0, 3.0, 0.0)), Group(3, GroupKind.CONVEX, tuple(range(6))))


CASES = [
    ValidCase("cube_float32", "the unit cube of spec/pln-1.md §12, float32, metres, with index: the 401 bytes "
              "printed there",
              SPEC_HEADER, cube_ops()),
    ValidCase("cube_float64", "the unit cube of spec/pln-1.md §12 in float64",
              dataclasses.replace(SPEC_HEADER, coding=Coding.FLOAT64), cube_ops()),
    ValidCase("cube_noindex", "the spec/pln-1.md §12 cube without iNDX: PEND index_offset 0",
              SPEC_HEADER, cube_ops(), index=False),
    ValidCase("cube_colours", "the spec/pln-1.md §12 cube with a cOLR chunk, one RGBA colour per face",
              SPEC_HEADER, cube_ops(Colour(0, _rgba))),
    ValidCase("cube_ancillary", "the spec/pln-1.md §12 cube with an unknown ancillary chunk nOTE between OBJT and "
              "PLNS",
              SPEC_HEADER, (Obj("cube"), Chunk(b"nOTE", b"an ancillary chunk no reader knows; skip it"),
                            Planes(CUBE), Group(0, GroupKind.CONVEX, tuple(range(6)))),
              findings=("UNKNOWN_ANCILLARY_CHUNK",)),
    ValidCase("cube_q16_16_16", "the unit cube quantized at 16/16/16 bits, lossless: poles, equator, axis "
              "directions and both ends of the h range [0, 1] are exact codes",
              dataclasses.replace(quantized((16, 16, 16), (0.0, 1.0)), lossy=False, tolerance=1e-6,
                                  error_bound=0.0),
              cube_ops(), decoded_bbox=True),
    ValidCase("gem_q11_13_17", "a ten-plane convex gem quantized at odd widths 11/13/17, h range [-1, 2]",
              quantized((11, 13, 17), (-1.0, 2.0)), (Obj("gem"), Planes(GEM), Group(0, 0, tuple(range(10)))),
              decoded_bbox=True),
    ValidCase("gem_q7_9_5", "the gem quantized coarsely at 7/9/5 bits (records straddle bytes, 2 padding bits)",
              quantized((7, 9, 5), (0.5, 1.5)), (Obj("gem"), Planes(GEM), Group(0, 0, tuple(range(10)))),
              decoded_bbox=True),
    ValidCase("gem_q24_24_24", "the gem quantized at 24/24/24 bits",
              quantized((24, 24, 24), (0.0, 2.0)), (Obj("gem"), Planes(GEM), Group(0, 0, tuple(range(10)))),
              decoded_bbox=True),
    ValidCase("gem_q32_32_32", "the gem quantized at the widest widths, 32/32/32 bits",
              quantized((32, 32, 32), (-1000.0, 1000.0)),
              (Obj("gem"), Planes(GEM), Group(0, 0, tuple(range(10)))), decoded_bbox=True),
    ValidCase("prism_q2_3_1", "an octagonal prism at narrow widths 2/3/1 (nu codes 0..2: poles and equator), "
              "with h_min = h_max = 1", quantized((2, 3, 1), (1.0, 1.0)),
              (Obj("prism"), Planes(np.array([[0.0, 0.0, 1.0], [math.pi, 0.0, 1.0]] + [
                  [math.pi / 2, k * math.pi / 4, 1.0] for k in range(8)])),
               Group(0, 0, tuple(range(10)))), decoded_bbox=True),
    ValidCase("sliver_8_7e_8", "a box 8.7e-8 x 1 x 1 in float64: thin, but above spec §9.4's 1e-8 of its diagonal",
              Header(coding=Coding.FLOAT64, units=Units.METRE),
              (Obj("sliver"), Planes(box((0, 0, 0), (8.7e-8, 1, 1))), Group(0, 0, tuple(range(6)))),
              decoded_bbox=True),
    ValidCase("sphere200", "200 planes tangent to the unit sphere, one convex group, float32, uncompressed",
              Header(coding=Coding.FLOAT32, units=Units.METRE),
              (Obj("sphere"), Planes(tangent_planes(200)), Group(0, 0, tuple(range(200)))), decoded_bbox=True),
    ValidCase("sphere200_zlib", "sphere200 with zlib-compressed PLNS data and GRUP body",
              Header(coding=Coding.FLOAT32, units=Units.METRE),
              (Obj("sphere"), Planes(tangent_planes(200)), Group(0, 0, tuple(range(200)))), decoded_bbox=True,
              compress=True),
    ValidCase("stream_nocounts", "two objects written through a non-seekable sink: COUNTS_KNOWN clear, "
              "counts 0, index present", Header(coding=Coding.FLOAT64, units=Units.MILLIMETRE),
              (Obj("cube"), Planes(CUBE), Group(0, 0, tuple(range(6))),
               Obj("gem", transform=translation(3.0, 0.0, 0.0)), Planes(GEM), Group(1, 0, tuple(range(6, 16)))),
              stream=True),
    ValidCase("scene_hierarchy", "five objects, parents and transforms (translation, rotation with scale, "
              "mirror), planes shared between groups, several PLNS blocks, an empty name, a group-less node",
              Header(coding=Coding.FLOAT64, units=Units.CENTIMETRE),
              (Obj("table", transform=translation(10.0, 0.0, 0.0)),
               Obj("top", parent=0, transform=translation(0.0, 0.0, 1.0)),
               Planes(CUBE), Group(1, 0, tuple(range(6))),
               Planes(box((1, 0, 0), (2, 1, 1))[[0, 2]]), Group(1, 0, (6, 1, 7, 3, 4, 5)),
               Obj("leg", parent=0), Planes(_scene_planes_leg), Group(2, 0, (8, 9, 2, 3, 10, 5)),
               Obj("", parent=2, transform=affine([[0, -2, 0], [2, 0, 0], [0, 0, 2]], 0.5, 0.5)),
               Group(3, 0, tuple(range(6))),
               Obj("Würfel ✓", transform=affine(np.diag([-1.0, 1.0, 1.0]), -3.0)),
               Group(4, 0, tuple(range(6)))),
              decoded_bbox=True),
    ValidCase("cells_l", "an L-shaped solid as kind 1: two convex cells split by the cut plane x = y "
              "(role bit set), one using its complement", Header(coding=Coding.FLOAT64, units=Units.METRE),
              (Obj("L"), Planes(L_PLANES),
               Group(0, GroupKind.CELLS, tuple(range(9)), bounding=(8,), cells=L_CELLS)),
              decoded_bbox=True),
    ValidCase("bsp_l", "the same L as kind 2, a BSP tree splitting first on the face plane y = 1: the two IN "
              "leaves touch on y = 1, where the surface is only 1 <= x <= 2",
              Header(coding=Coding.FLOAT64, units=Units.METRE),
              (Obj("L"), Planes(L_PLANES[:8]),
               Group(0, GroupKind.BSP, tuple(range(8)), tree=L_TREE)),
              decoded_bbox=True),
    ValidCase("patch_convex", "kind 3: an open box (bottom and four sides) cut by one slanted bounding plane",
              Header(coding=Coding.FLOAT64, units=Units.METRE),
              (Obj("open box"),
               Planes(np.vstack([box((0, 0, 0), (1, 1, 1))[[0, 1, 2, 3, 5]], [[0.46, math.pi, 0.8]]])),
               Group(0, GroupKind.PSEUDO_CONVEX, tuple(range(6)), bounding=(5,))),
              decoded_bbox=True),
    ValidCase("patch_concave", "kind 4: the inside of a tray 2 x 1 x 0.5, stored inverted (an outward box with a "
              "bounding lid), decoded with faces flipped to point inwards",
              Header(coding=Coding.FLOAT64, units=Units.METRE),
              (Obj("tray"), Planes(box((0, 0, 0), (2, 1, 0.5))),
               Group(0, GroupKind.PSEUDO_CONCAVE, tuple(range(6)), bounding=(4,))),
              decoded_bbox=True),
    ValidCase("minor_1_1", "version 1.1: 8 more PHDR bytes and a new flag bit, 5 more OBJT bytes after the "
              "transform, a group of unknown kind 9 (skipped) between two known ones",
              dataclasses.replace(SPEC_HEADER, version=(1, 1), extra=b"\x01\x02\x03\x04\x05\x06\x07\x08"),
              **NEWER_MINOR),
    ValidCase("sealed_in_1_1", "version 1.1: a group of kind 5, which versions before 3.1 do not have, so a kind "
              "of a newer minor version here (skipped), between two known ones; its 4 bytes of kind data 00 01 02 03 "
              "are opaque (read as a sealed body they would be vertex_count 0)",
              dataclasses.replace(SPEC_HEADER, version=(1, 1)),
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.CONVEX, tuple(range(6))),
               Group(0, GroupKind.SEALED, tuple(range(6)), extra=b"\x00\x01\x02\x03"),
               Group(0, GroupKind.PSEUDO_CONVEX, tuple(range(6)), bounding=(4,))),
              findings=("SKIPPED_GROUP_KIND",), findings_optional=("NEWER_MINOR_VERSION",)),
    ValidCase("l_v2_predicted", "version 2.0: the L of bsp_l in the predicted coding 8/8/8 over h in [-1, 2] "
              "(every plane exact), sorted by code so that runs of one nu and of one normal occur, and its tree "
              "as varint tokens", V2_L,
              (Obj("L"), Planes(L_SORTED), Group(0, GroupKind.BSP, tuple(range(8)), tree=L_SORTED_TREE)),
              decoded_bbox=True, index=False),
    ValidCase("cells_l_v2", "version 2.0: the L of cells_l, float64, its cells as varints, the body deflated",
              V2_F64, (Obj("L"), Planes(L_PLANES),
                       Group(0, GroupKind.CELLS, tuple(range(9)), bounding=(8,), cells=L_CELLS)),
              decoded_bbox=True, compress=True),
    ValidCase("gem_v2_predicted", "version 2.0: the gem of gem_q11_13_17 in the predicted coding, unsorted "
              "(a new nu at every plane: phi and h stored plain), and a patch group with a repeated reference "
              "(a zero difference)",
              dataclasses.replace(quantized((11, 13, 17), (-1.0, 2.0)), version=(2, 0), coding=Coding.PREDICTED),
              (Obj("gem"), Planes(GEM), Group(0, 0, tuple(range(10))),
               Group(0, GroupKind.PSEUDO_CONVEX, (0, 2, 3, 4, 5, 6, 7, 8, 9, 9))),
              decoded_bbox=True, findings_optional=("REDUNDANT_PLANE",)),
    ValidCase("cube_v3", "version 3.0: the unit cube of spec/pln-1.md §12, float32, metres, with index: the bytes "
              "printed in spec/pln-3.md §12 (bbox, tolerance and error bound as float32, counts and heads as "
              "varints, an 8-byte PEND)", V3_CUBE, cube_ops()),
    ValidCase("cube_v3_q2_2_1", "version 3.0: the cube bit-packed at 2/2/1 bits over h in [0, 1] (every plane an "
              "exact code), lossless, the bbox of the decoded cube, no index: an empty PEND", V3_Q221, cube_ops(),
              decoded_bbox=True, index=False),
    ValidCase("l_v3_predicted", "version 3.0: the L of l_v2_predicted (predicted coding 8/8/8, sorted, varint tree) "
              "with version 3 heads, no index", dataclasses.replace(V2_L, version=(3, 0)),
              (Obj("L"), Planes(L_SORTED), Group(0, GroupKind.BSP, tuple(range(8)), tree=L_SORTED_TREE)),
              decoded_bbox=True, index=False),
    ValidCase("scene_v3_stream", "version 3.0 through a non-seekable sink: COUNTS_KNOWN clear and no counts, no "
              "bbox, tolerance NaN; a root, a child with parent 0 (stored 1) and a transform, a name of 130 bytes "
              "(a 2-byte length varint), two deflated PLNS blocks, an index",
              Header(version=(3, 0), coding=Coding.FLOAT64, units=Units.MILLIMETRE, tolerance=math.nan),
              (Obj("cube"), Planes(CUBE), Group(0, 0, tuple(range(6))),
               Obj("gem " + "g" * 126, parent=0, transform=translation(3.0, 0.0, 0.0)), Planes(GEM),
               Group(1, 0, tuple(range(6, 16)))),
              stream=True, compress=True),
    ValidCase("sealed_cube_v3_1", "version 3.1: the unit cube as a sealed group (kind 5), float32, with index: 8 "
              "vertices each named by its three face planes, 12 triangles counter-clockwise from outside, two per "
              "face (face reference differences 0 within a face)", dataclasses.replace(V3_CUBE, version=(3, 1)),
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.SEALED, tuple(range(6)),
                                                vertex_planes=SEALED_CUBE_VERTICES, facets=SEALED_CUBE_FACETS))),
    ValidCase("sealed_corner_v3_1", "version 3.1: the sealed cube in float64, no index, its corner (0, 0, 0) named by "
              "x = 0, y = 0 and a vertex plane through it (reference 6, role bit 1, on no triangle) with normal "
              "-(1, 1, 1)/sqrt 3", Header(version=(3, 1), coding=Coding.FLOAT64, units=Units.METRE),
              (Obj("cube"), Planes(np.vstack([CUBE, CORNER_PLANE])),
               Group(0, GroupKind.SEALED, tuple(range(7)), bounding=(6,), vertex_planes=SEALED_CORNER_VERTICES,
                     facets=SEALED_CUBE_FACETS)),
              decoded_bbox=True, index=False),
    ValidCase("minor_3_5", "version 3.5: 8 more PHDR bytes after the counts and a new flag bit, 5 more OBJT bytes "
              "after the transform, a group of unknown kind 9 (skipped) between two known ones",
              dataclasses.replace(V3_CUBE, version=(3, 5), extra=b"\x01\x02\x03\x04\x05\x06\x07\x08"),
              **NEWER_MINOR),
    ValidCase("shell_cube_v3_2", "version 3.2: the unit cube as a shell (kind 6), float32, with index: 8 corners "
              "each named by its three face planes, 12 triangles on the 6 faces, corners numbered by first use",
              V32_CUBE, (Obj("cube"), Planes(CUBE), Group(0, GroupKind.SHELL, tuple(range(6)), shell=SHELL_CUBE))),
    ValidCase("shell_mixed_v3_2", "version 3.2: the shell cube with its corner (0, 0, 0) explicit (grid origin 0, "
              "step 0.25) and the two triangles of z >= 0 free, with a cOLR of 6 colours (free triangles take the "
              "last one's)", V32_CUBE,
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.SHELL, tuple(range(6)), shell=SHELL_MIXED),
               Colour(0, np.array([[255, 0, 0, 255]] * 5 + [[0, 0, 255, 255]], dtype=np.uint8)))),
    ValidCase("shell_pyramid_v3_2", "version 3.2: an open square pyramid as a shell of one reference that names "
              "nothing: 5 explicit corners on a grid of step 0.5, 4 free triangles in the colour of that reference",
              V32_CUBE,
              (Obj("pyramid"), Planes(CUBE[4:5]), Group(0, GroupKind.SHELL, (0,), shell=SHELL_PYRAMID),
               Colour(0, np.array([[0, 128, 0, 255]], dtype=np.uint8))), decoded_bbox=True),
    ValidCase("shell_tree_cube_v3_3", "version 3.3: the unit cube as a shell tree (kind 7), float32, with index: 12 "
              "triangles, the first a root, each other attached to an edge of the one before; 8 corners each named "
              "by the three face planes of the triangles around it (no picks)",
              V33_CUBE, (Obj("cube"), Planes(CUBE), Group(0, GroupKind.SHELL_TREE, tuple(range(6)), shell=TREE_CUBE))),
    ValidCase("shell_tree_mixed_v3_3", "version 3.3: the shell tree cube with the two triangles of z >= 0 free "
              "(face codes 1, then 0: the parent's, free) and the four corners of that face explicit (grid origin 0, "
              "step 0.25), with a cOLR of 6 colours (free triangles take the last one's)", V33_CUBE,
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.SHELL_TREE, tuple(range(6)), shell=TREE_MIXED),
               Colour(0, np.array([[255, 0, 0, 255]] * 5 + [[0, 0, 255, 255]], dtype=np.uint8)))),
    ValidCase("shell_tree_pyramid_v3_3", "version 3.3: the open square pyramid as a shell tree of one reference: 5 "
              "explicit corners on a grid of step 0.5 coded as residuals from their predictors (the previous explicit "
              "corner, or the first corner of the attached triangle naming them), x of every corner, then y, then z",
              V33_CUBE,
              (Obj("pyramid"), Planes(CUBE[4:5]), Group(0, GroupKind.SHELL_TREE, (0,), shell=TREE_PYRAMID),
               Colour(0, np.array([[0, 128, 0, 255]], dtype=np.uint8))), decoded_bbox=True),
    ValidCase("shell_tree_apex_v3_3", "version 3.3, float64: a closed square pyramid as a shell tree: its base "
              "corners on three face planes each, its apex on four, named by the three its picks 0 1 2 choose",
              dataclasses.replace(V33_CUBE, coding=Coding.FLOAT64),
              (Obj("pyramid"), Planes(APEX_PLANES), Group(0, GroupKind.SHELL_TREE, tuple(range(5)), shell=TREE_APEX)),
              decoded_bbox=True),
    ValidCase("shell_tree_box_v3_4", "version 3.4: the shell tree cube (kind 8) with every corner explicit on the "
              "grid of step 1: the root's three corners coded from the previous explicit corner, every later one "
              "from the parallelogram of its triangle's shared edge and the parent's opposite corner (all residuals "
              "0 but the root's)", V34_CUBE,
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.SHELL_TREE_PARALLELOGRAM, tuple(range(6)), shell=TREE_BOX))),
    ValidCase("shell_tree_pyramid_v3_4", "version 3.4: the open square pyramid of shell_tree_pyramid_v3_3 as kind 8: "
              "corners 3 and 4 coded as residuals from parallelograms, (3, 1, 2) and (1, 3, 2) on the grid",
              V34_CUBE,
              (Obj("pyramid"), Planes(CUBE[4:5]), Group(0, GroupKind.SHELL_TREE_PARALLELOGRAM, (0,), shell=TREE_PYRAMID),
               Colour(0, np.array([[0, 128, 0, 255]], dtype=np.uint8))), decoded_bbox=True),
    ValidCase("brotli_shell_tree_v4_0", "version 4.0: the kind 8 shell tree cube of shell_tree_box_v3_4 and the "
              "kind 8 pyramid beside it, the plane block and both group bodies stored as Brotli streams (compression "
              "method 2, spec §6)", V40_CUBE,
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.SHELL_TREE_PARALLELOGRAM, tuple(range(6)), shell=TREE_BOX),
               Obj("pyramid", None, translation(2.0, 0.0, 0.0)),
               Group(1, GroupKind.SHELL_TREE_PARALLELOGRAM, (4,), shell=TREE_PYRAMID)),
              compress=True, decoded_bbox=True, assembled_only=True, edit=brotli_payloads),
    ValidCase("shell_walk_cube_v4_1", "version 4.1: the shell tree cube of shell_tree_cube_v3_3 as a shell walk "
              "(kind 9): a chain of triangles (children lists 1 and 2), its corners named by their face planes, the "
              "corners it closes on coded as left (1) over the open edges", V41_CUBE,
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.SHELL_WALK, tuple(range(6)), shell=TREE_CUBE))),
    ValidCase("shell_walk_sphere_v4_1", "version 4.1: an icosphere of 80 free triangles as a shell walk: triangles "
              "with two children, leaves, left codes and a corner step in an escape; its 42 explicit corners in mode "
              "3, indices into each axis's table of values predicted by parallelograms", V41_CUBE,
              (Obj("sphere"), Planes(CUBE[4:5]), Group(0, GroupKind.SHELL_WALK, (0,), shell=WALK_SPHERE)),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_SPHERE, 3)),
    ValidCase("shell_walk_torus_v4_1", "version 4.1: a torus of 48 free triangles walked with each triangle's "
              "neighbour across edge 2 before the one across edge 1: right codes, children in the order (2, 1), "
              "corner steps in escapes; its 24 explicit corners in mode 2, indices into each axis's table of "
              "values predicted by the first corner of the triangle naming them", V41_CUBE,
              (Obj("torus"), Planes(CUBE[4:5]), Group(0, GroupKind.SHELL_WALK, (0,), shell=WALK_TORUS)),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_TORUS, 2)),
    ValidCase("shell_walk_multi_sphere_v4_2", "version 4.2: the icosphere of shell_walk_sphere_v4_1 as a shell walk "
              "with multi-parallelograms (kind 10): explicit corners predicted by the floor average of one to four "
              "parallelograms over the triangles around them (negative sums and odd counts among them), the first "
              "corners, which have none, by kind 9's mode 1 parallelogram or by the corner before; mode 1",
              V42_CUBE,
              (Obj("sphere"), Planes(CUBE[4:5]), Group(0, GroupKind.SHELL_WALK_MULTI, (0,), shell=WALK_SPHERE)),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_SPHERE, 1)),
    ValidCase("shell_walk_multi_tables_v4_2", "version 4.2: the torus of shell_walk_torus_v4_1 (walked edge 2 "
              "first) as a shell walk with multi-parallelograms, its explicit corners in mode 2: the averages taken "
              "over indices into each axis's table of values, the corners without a parallelogram predicted by the "
              "first corner of the triangle naming them", V42_CUBE,
              (Obj("torus"), Planes(CUBE[4:5]), Group(0, GroupKind.SHELL_WALK_MULTI, (0,), shell=WALK_TORUS)),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_TORUS, 2)),
    ValidCase("copies_v4_2", "version 4.2: a shell walk cube and a convex cube, each placed twice: the second of "
              "each a copy (kind 11) of the first, in an object translated by (2, 0, 0), the shell walk's copy with "
              "a colour of its own", V42_CUBE,
              COPIES_SCENE,
              decoded_bbox=True),
    ValidCase("walk_planeless_v5_0", "version 5.0: the icosphere of shell_walk_sphere_v4_1 as a shell walk without "
              "references (spec §9.2: m = 0) in a file without planes (coding 0, no PLNS), its grid in f32 (origin 0, "
              "step 0.25), its triangles in the one colour of a cOLR of count 0 (spec §10.1), the up axis Z in the "
              "header's units byte (spec §5), varint chunk lengths (spec §4.1) and no index: a 9-byte PEND",
              dataclasses.replace(V50_CUBE, up_axis="Z"),
              (Obj("sphere"), Group(0, GroupKind.SHELL_WALK, (), shell=WALK_SPHERE),
               Colour(0, np.array([[230, 120, 40, 255]], dtype=np.uint8))), decoded_bbox=True, index=False),
    ValidCase("scene_up_axis_v5_0", "version 5.0: a root, the cube as a convex group in one colour, and the torus of "
              "shell_walk_torus_v4_1 as a shell walk with multi-parallelograms on one reference (for its colour) "
              "placed twice, the second a copy (kind 11); up axis Y in the header, counts, and an index: iNDX "
              "offsets of varint-framed chunks and a 17-byte PEND (spec §4.4)", dataclasses.replace(V50_CUBE, up_axis="Y"),
              (Obj("root"), Obj("cube", 0, translation(0.0, 0.0, 2.0)), Planes(CUBE),
               Group(1, GroupKind.CONVEX, tuple(range(6))),
               Colour(0, np.tile(np.array([[20, 120, 220, 255]], dtype=np.uint8), (6, 1))),
               Obj("torus", 0, translation(3.0, 0.0, 0.0)),
               Group(2, GroupKind.SHELL_WALK_MULTI, (4,), shell=WALK_TORUS),
               Colour(1, np.array([[250, 200, 0, 255]], dtype=np.uint8)),
               Obj("torus twin", 0, translation(-3.0, 0.0, 0.0)),
               Group(3, GroupKind.SHELL_WALK_MULTI, (4,), shell=WALK_TORUS)),
              decoded_bbox=True),
    ValidCase("shell_walk_reflect_knot_v5_1", "version 5.1: a torus of 16 by 8 sections (128 corners) at 64 steps "
              "a unit as a shell walk with reflections (kind 12) without references, in mode 0: most explicit "
              "corners (124 of 128) predicted by turning the step before them (spec §9.16; 180 negative numerators "
              "among them, rounded toward -infinity), the four without a chain of three step sources by kind 9's "
              "prediction", V51_CUBE,
              (Obj("ring"), Group(0, GroupKind.SHELL_WALK_REFLECT, (), shell=WALK_RING),
               Colour(0, np.array([[40, 160, 90, 255]], dtype=np.uint8))),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_RING, 0, 5)),
    ValidCase("shell_walk_reflect_tables_v5_1", "version 5.1: the icosphere of shell_walk_sphere_v4_1 as a shell "
              "walk with reflections on one reference, in mode 3: the chains turn over indices into each axis's "
              "table of values, the corners without a chain predicted by kind 9's parallelograms", V51_CUBE,
              (Obj("sphere"), Planes(CUBE[4:5]), Group(0, GroupKind.SHELL_WALK_REFLECT, (0,), shell=WALK_SPHERE)),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_SPHERE, 3, 5)),
    ValidCase("shell_walk_reflect_far_v5_1", "version 5.1: the torus of shell_walk_reflect_knot_v5_1 at 2^19 steps "
              "a unit, in mode 1: chains whose steps have a component beyond 2^18 do not turn and are predicted by "
              "kind 9's parallelograms (7 of 124 chains), the others turn (2N + D up to 1.2 * 2^55)", V51_CUBE,
              (Obj("ring"), Group(0, GroupKind.SHELL_WALK_REFLECT, (), shell=WALK_RING_FINE),
               Colour(0, np.array([[90, 40, 160, 255]], dtype=np.uint8))),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_RING_FINE, 1, 5)),
    ValidCase("shell_walk_reflect_exact_v5_1", "version 5.1: two triangles as a shell walk with reflections without "
              "references, in mode 0: corner 3 is predicted by its chain's turn (334367, 374378, 0), whose x quotient "
              "145878 binary64 arithmetic floors to 145879 (2N + D rounded): a reader must compute in exact integers "
              "(spec §9.16); its residuals (1, -1, 7)", V51_CUBE,
              (Obj("pair"), Group(0, GroupKind.SHELL_WALK_REFLECT, (), shell=WALK_EXACT),
               Colour(0, np.array([[200, 200, 40, 255]], dtype=np.uint8))),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_EXACT, 0, 5)),
    ValidCase("shell_walk_later_values_v5_2", "version 5.2: the icosphere of shell_walk_sphere_v4_1, walked edge 2 "
              "first, as a shell walk stepping from the later gate corner (kind 13) without references, in mode 0: "
              "each explicit corner named by an attached triangle is its residual from corner max(i0, i1) of that "
              "triangle (spec §9.17), which is not i0 for 39 of its 42 corners: from i0 a reader decodes another "
              "sphere", V52_CUBE,
              (Obj("sphere"), Group(0, GroupKind.SHELL_WALK_LATER, (), shell=WALK_SPHERE_TWO),
               Colour(0, np.array([[60, 90, 200, 255]], dtype=np.uint8))),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_SPHERE_TWO, 0, 5)),
    ValidCase("shell_walk_later_named_v5_2", "version 5.2: the unit cube, each face split into eight triangles "
              "(26 corners, 48 triangles on the cube's planes), as a shell walk stepping from the later gate corner "
              "walked edge 2 first, in mode 0: its eight corners named by their three planes, of its 18 explicit "
              "corners 11 stepping from a later gate corner that is not the gate's first and 5, whose later gate "
              "corner is named, from the previous explicit corner (spec §9.17), neither from the gate's other "
              "corner", V52_CUBE,
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.SHELL_WALK_LATER, tuple(range(6)), shell=WALK_SPLIT_CUBE)),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_SPLIT_CUBE, 0, 5)),
    ValidCase("shell_walk_later_tables_v5_2", "version 5.2: the torus of shell_walk_torus_v4_1 as a shell walk "
              "stepping from the later gate corner on one reference, in mode 2: steps over indices into each axis's "
              "table of values, from the later gate corner, which is not the gate's first for 20 of its 24 "
              "corners (in mode 3 parallelograms would predict every one, as in kind 9)", V52_CUBE,
              (Obj("torus"), Planes(CUBE[4:5]), Group(0, GroupKind.SHELL_WALK_LATER, (0,), shell=WALK_TORUS)),
              decoded_bbox=True, assembled_only=True, edit=walk_mode(WALK_TORUS, 2, 5)),
    ValidCase("shells_v5_0", "version 5.0, written to a pipe (no counts): shells with explicit corners on f32 grids "
              "(spec §9.10: 16 bytes) of kinds 6 (the mixed cube), 7 (the mixed cube as a tree), 8 (the box) and 6 "
              "again without references (the open pyramid, m = 0)", V50_CUBE,
              (Obj("shells"), Planes(CUBE), Group(0, GroupKind.SHELL, tuple(range(6)), shell=SHELL_MIXED),
               Obj("tree", None, translation(2.0, 0.0, 0.0)),
               Group(1, GroupKind.SHELL_TREE, tuple(range(6)), shell=TREE_MIXED),
               Obj("box", None, translation(4.0, 0.0, 0.0)),
               Group(2, GroupKind.SHELL_TREE_PARALLELOGRAM, tuple(range(6)), shell=TREE_BOX),
               Obj("pyramid", None, translation(6.0, 0.0, 0.0)), Group(3, GroupKind.SHELL, (), shell=SHELL_PYRAMID)),
              decoded_bbox=True, stream=True),
    ValidCase("scene_transforms_v4_0", "version 4.0: three cubes under a root, with transforms coded entry by entry "
              "(spec §8): a translation by (2.5, -1, 0.125) (codes 1, 0 and f32), a rotation by 30 degrees about z "
              "with a translation by 0.1 (f64 entries), and a mirror with -0.0 (an f32); a cOLR of one colour for "
              "the six references of the first cube (spec §10.1), one colour per reference for the second",
              V40_CUBE,
              (Obj("root"), Obj("a", 0, translation(2.5, -1.0, 0.125)), Planes(CUBE),
               Group(1, GroupKind.CONVEX, tuple(range(6))), Colour(0, np.array([[200, 30, 40, 255]] * 6, dtype=np.uint8)),
               Obj("b", 0, affine(ROT30, 0.1, 0.0, 0.0)), Group(2, GroupKind.CONVEX, tuple(range(6))),
               Colour(1, np.array([[10, 20, 30, 255]] * 3 + [[90, 80, 70, 128]] * 3, dtype=np.uint8)),
               Obj("c", 0, affine(MIRROR, 0.0, 3.0, -0.0)),
               Group(3, GroupKind.CONVEX, tuple(range(6)))),
              decoded_bbox=True),
    ValidCase("cube_meta_up_z", "version 3.0: the cube of cube_v3 with a mETA chunk up_axis = Z right after PHDR "
              "(spec §10.3: any version may hold it; its version stays 3.0)", V3_CUBE,
              (Meta(UP_AXIS, "Z"), *cube_ops())),
    ValidCase("empty", "the smallest valid file: signature, PHDR (counts 0), PEND without index",
              Header(coding=Coding.FLOAT32), (), index=False),
    # -- rules spec/pln.md decides (issue 32)
    ValidCase("ignored_fields", "the spec/pln-1.md §12 cube of version 1.0 with every field a reader ignores set "
              "(spec/pln.md §2.1, A.1): undefined PHDR and OBJT flag bits, the widths (8/16/32) and h range (NaN, "
              "-inf) of a float coding, the reserved bytes of PHDR, OBJT, PLNS and GRUP; read as the cube",
              SPEC_HEADER, cube_ops(), assembled_only=True, header_flags=0xFFF8, edit=ignored_fields),
    ValidCase("ignored_fields_v3", "the cube of version 3.0 with every field a reader ignores set (spec/pln.md "
              "§2.1): undefined PHDR and OBJT flag bits, the widths (8/16/32) of a float coding",
              V3_CUBE, cube_ops(), assembled_only=True, header_flags=0xFFF8, edit=ignored_fields),
    ValidCase("convex_roles", "the cube's convex group with role bit 1 on reference 5 (z >= 0): role bits of a convex "
              "group carry no meaning, the face z = 0 is decoded (spec/pln.md §9.4)",
              SPEC_HEADER, (Obj("cube"), Planes(CUBE), Group(0, GroupKind.CONVEX, tuple(range(6)), bounding=(5,))),
              assembled_only=True),
    ValidCase("bsp_empty_leaf", "the L of bsp_l with one more split at the root, x >= 0, whose outer side holds an "
              "IN leaf of empty region (x <= 0 and x >= 1): allowed, it adds nothing (spec/pln.md §9.7)",
              Header(coding=Coding.FLOAT64, units=Units.METRE),
              (Obj("L"), Planes(L_PLANES[:8]), Group(0, GroupKind.BSP, tuple(range(8)), tree=L_TREE_EMPTY_LEAF)),
              decoded_bbox=True),
    ValidCase("patch_repeated_face", "kind 3: the open box of patch_convex with its face reference x <= 1 given "
              "twice: the face is decoded once per reference, twice (spec/pln.md §9.8)",
              Header(coding=Coding.FLOAT64, units=Units.METRE), PATCH_REPEATED_OPS, decoded_bbox=True),
    ValidCase("patch_face_repeated", "kind 3: the open box of patch_convex with its face reference x <= 1 given "
              "12 times, 17 references in all: the face is decoded once per reference, 12 times, however many "
              "references repeat it (spec/pln.md §9.8; planefmt gave it once past 14 references)",
              Header(coding=Coding.FLOAT64, units=Units.METRE), PATCH_REPEATED_MANY_OPS, decoded_bbox=True),
    # -- version 6.0 (issue 52): records in body segments (spec §4.5, §4.6), the compact header (§5)
    ValidCase("cube_v6_0", "version 6.0: the cube as one convex group of six quantized planes (widths 2/2/1, h in "
              "[0, 1], metres, tolerance 1e-6 rounded up to 12 mantissa bits), its three records in one "
              "segment in the PHDR payload after the header fields; one segment under 256 raw bytes: no bbox, no "
              "counts (spec §5), no index: 73 bytes, the records uncompressed (method 0, smaller than Brotli here)",
              dataclasses.replace(quantized((2, 2, 1), (0.0, 1.0)), version=(6, 0), lossy=False, tolerance=1e-6,
                                  error_bound=0.0),
              cube_ops(), compress=True, index=False),
    ValidCase("scene_v6_0", "version 6.0: a root, the cube as a convex group in one colour, the torus of "
              "shell_walk_torus_v4_1 as a shell walk with multi-parallelograms on one reference in a colour of its "
              "own, a gem of ten planes under a rotation, and the cube again in one colour per reference; up axis Z "
              "in the header, float32 planes, bbox and counts (over 256 raw bytes), one compressed segment in PHDR",
              dataclasses.replace(V60_CUBE, up_axis="Z"),
              (Obj("root"), Obj("cube", 0, translation(0.0, 0.0, 2.0)), Planes(CUBE),
               Group(1, GroupKind.CONVEX, tuple(range(6))),
               Colour(0, np.tile(np.array([[20, 120, 220, 255]], dtype=np.uint8), (6, 1))),
               Obj("torus", 0, translation(3.0, 0.0, 0.0)),
               Group(2, GroupKind.SHELL_WALK_MULTI, (4,), shell=WALK_TORUS),
               Colour(1, np.array([[250, 200, 0, 255]], dtype=np.uint8)),
               Obj("gem", 0, affine(ROT30, -3.0, 0.0, 0.0)), Planes(GEM),
               Group(3, GroupKind.CONVEX, tuple(range(6, 16))),
               Obj("cube b", 0, translation(0.0, 3.0, 0.0)), Group(4, GroupKind.CONVEX, tuple(range(6))),
               Colour(3, np.array([[10, 20, 30, 255]] * 3 + [[90, 80, 70, 128]] * 3, dtype=np.uint8))),
              compress=True, decoded_bbox=True, index=False),
    ValidCase("shell_walk_v6_0", "version 6.0: the icosphere of shell_walk_sphere_v4_1 as a shell walk (kind 9) "
              "without references in a file without planes (coding 0), in one colour (a colours record of count "
              "0), its grid in f32, uncompressed (method 0): one segment in PHDR", V60_CUBE,
              (Obj("sphere"), Group(0, GroupKind.SHELL_WALK, (), shell=WALK_SPHERE),
               Colour(0, np.array([[230, 120, 40, 255]], dtype=np.uint8))), decoded_bbox=True, index=False),
    ValidCase("segments_v6_0", "version 6.0: three body segments, the first in PHDR stored with Brotli (method "
              "2), then BODY chunks stored with deflate (method 1) and stored raw (method 0), an unknown ancillary "
              "chunk (bOGU) between them and an unknown ancillary record (tag 200) in the last, which a reader skips "
              "(UNKNOWN_ANCILLARY_CHUNK); group 1 references planes of the first segment; an index whose entries "
              "name three chunks (spec §10.2)", V60_CUBE,
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.CONVEX, tuple(range(6))), Segment(),
               Obj("box", None, translation(2.0, 0.0, 0.0)), Planes(box((0.0, 0.0, 0.0), (1.0, 2.0, 0.5))),
               Group(1, GroupKind.CONVEX, (0, 2, 3, 5, 7, 10)),
               Colour(1, np.array([[200, 30, 40, 255]], dtype=np.uint8).repeat(6, axis=0)),
               Chunk(b"bOGU", b"ancillary"), Obj("cube twin", 0, translation(0.0, 2.0, 0.0)),
               Chunk(bytes([200]), b"a record to skip"), Group(2, GroupKind.CONVEX, tuple(range(6)))),
              compress=True, decoded_bbox=True, assembled_only=True, methods=(2, 1, 0),
              findings=("UNKNOWN_ANCILLARY_CHUNK",)),
    ValidCase("empty_segment_v6_0", "version 6.0: a BODY segment of no record (raw size 0, stored with deflate) "
              "between two that hold the cube and its twin, which a reader accepts as an empty sequence of records "
              "(spec §4.5)", V60_CUBE,
              (Obj("cube"), Planes(CUBE), Group(0, GroupKind.CONVEX, tuple(range(6))), Segment(empty=True),
               Obj("cube twin", None, translation(2.0, 0.0, 0.0)), Group(1, GroupKind.CONVEX, tuple(range(6)))),
              compress=True, decoded_bbox=True, assembled_only=True, methods=(0, 1, 0)),
    ValidCase("index_v6_0", "version 6.0: the scene of scene_transforms_v4_0 (transforms entry by entry, one colour "
              "for a group, one per reference for another) written by planefmt.Writer with an index: one segment in "
              "PHDR, iNDX entries whose chunk offsets are all 8 (differences 0 after the first)", V60_CUBE,
              (Obj("root"), Obj("a", 0, translation(2.5, -1.0, 0.125)), Planes(CUBE),
               Group(1, GroupKind.CONVEX, tuple(range(6))), Colour(0, np.array([[200, 30, 40, 255]] * 6, dtype=np.uint8)),
               Obj("b", 0, affine(ROT30, 0.1, 0.0, 0.0)), Group(2, GroupKind.CONVEX, tuple(range(6))),
               Colour(1, np.array([[10, 20, 30, 255]] * 3 + [[90, 80, 70, 128]] * 3, dtype=np.uint8)),
               Obj("c", 0, affine(MIRROR, 0.0, 3.0, -0.0)), Group(3, GroupKind.CONVEX, tuple(range(6)))),
              compress=True, decoded_bbox=True),
    ValidCase("copies_v6_0", "version 6.0: the scene of copies_v4_2 (a shell walk cube and a convex cube, each "
              "placed twice, the second of each a copy, kind 11, of the first) with an index, uncompressed",
              V60_CUBE,
              COPIES_SCENE,
              decoded_bbox=True),
]
