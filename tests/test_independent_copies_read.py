"""Kind 11 (spec/pln.md §9.15, copies, version 4.2) in the independent reader
conformance/independent/plnread.py, on hand-built files.

Every file here is assembled chunk by chunk from the text of the spec (§3 signature, §4 framing,
§5 header, §7 planes in coding 1, §8 objects with 4.0 transforms, §9.1-§9.2 group heads and common
bodies, §10.1 colours, §10.2 index, §4.4 end), not from planefmt nor the suite's generator. The
sources are a convex cube (kind 0, §9.5), a shell walk over a tetrahedron (kind 9, §9.13; its body
written out by hand below, symbol by symbol) and the same body as kind 10; their copies sit in
other objects, translated. Then each error of §9.15, in the order its checks are listed, the
version rules of §9.3 (kind 11 exists in 4.2; UNKNOWN_GROUP_KIND in 4.0 and 4.1; a newer minor
skips the kinds it does not know, and a copy of a skipped group is skipped too), and a read through
a pipe, where the reader cannot look back for the source."""

from __future__ import annotations

import math
import struct

import pytest

from spec_files import SIGNATURE, group_body, grup, phdr, plns, read_pipe, u32_chunk, uv, zigzag
from spec_files import read_read as read

COPY = 11


# --- bytes (§2, §4) -----------------------------------------------------------------------------

def header(major=4, minor=2, counts=None) -> bytes:
    """§5: version, flags (COUNTS_KNOWN if counts), coding 1 (float64), widths 0, units 1 (metre),
    no h range (coding 1), no bbox, tolerance and error bound NaN, then the counts."""
    return u32_chunk(b"PHDR", phdr(major, minor, coding=1, counts=counts))


def planes_chunk(planes) -> bytes:
    """§7.1 with coding 1 (§7.2): float64 triplets, stored (method 0)."""
    return u32_chunk(b"PLNS", plns(planes, 1))


def translation(tx, ty, tz) -> bytes:
    """§8, version 4: twelve 2-bit codes (0 the entry +0.0, 1 the entry 1.0, 3 an f64 follows), then
    the f64 values of the entries of code 3, in entry order."""
    entries = [1.0, 0.0, 0.0, tx, 0.0, 1.0, 0.0, ty, 0.0, 0.0, 1.0, tz]
    bits, values = 0, b""
    for i, e in enumerate(entries):
        code = 0 if e == 0.0 else 1 if e == 1.0 else 3
        bits |= code << (2 * i)
        if code == 3:
            values += struct.pack("<d", e)
    return bits.to_bytes(3, "little") + values


def object_chunk(index, name, move=None, parent=None) -> bytes:
    """§8: index, parent (0 a root, else parent + 1), flags (bit 0 HAS_TRANSFORM), name."""
    p = uv(index) + uv(0 if parent is None else parent + 1) + bytes([1 if move else 0])
    p += uv(len(name)) + name.encode()
    if move:
        p += translation(*move)
    return u32_chunk(b"OBJT", p)


def group_chunk(index, obj, kind, refs, bounding, data, method=0) -> bytes:
    """§9.1 and §9.2: the head and the body (method 0 stored, 1 zlib)."""
    return u32_chunk(b"GRUP", grup(index, obj, kind, group_body(refs, bounding, data), method))


def colour_chunk(group, rgba) -> bytes:
    """§10.1: group, count, one colour per reference."""
    return u32_chunk(b"cOLR", struct.pack("<II", group, len(rgba)) + b"".join(bytes(c) for c in rgba))


def with_index(prefix: bytes) -> bytes:
    """§10.2 and §4.4: an iNDX listing every OBJT, PLNS and GRUP of `prefix` (a signature and
    chunks) with its ordinal, then a PEND holding the index's offset."""
    entries, pos, objects, planes, groups = [], 8, 0, 0, 0
    while pos < len(prefix):
        tag, length = prefix[pos:pos + 4], struct.unpack_from("<I", prefix, pos + 4)[0]
        payload = prefix[pos + 8:pos + 8 + length]
        if tag == b"OBJT":
            entries.append((pos, tag, objects))
            objects += 1
        elif tag == b"PLNS":
            entries.append((pos, tag, planes))
            planes += plns_count(payload)
        elif tag == b"GRUP":
            entries.append((pos, tag, groups))
            groups += 1
        pos += 12 + length
    index = struct.pack("<I", len(entries)) + b"".join(struct.pack("<Q4sI", *e) for e in entries)
    at = len(prefix)
    return prefix + u32_chunk(b"iNDX", index) + u32_chunk(b"PEND", struct.pack("<Q", at))


def plns_count(payload: bytes) -> int:
    """The count of a PLNS head (§7.1): the second varint."""
    values, value, shift = [], 0, 0
    for b in payload:
        value |= (b & 0x7F) << shift
        shift += 7
        if not b & 0x80:
            values.append(value)
            value, shift = 0, 0
            if len(values) == 2:
                return values[1]
    raise ValueError("no PLNS head")


def end() -> bytes:
    return u32_chunk(b"PEND", b"")


def error(data: bytes):
    return read(data).get("error")


# --- sources ------------------------------------------------------------------------------------

H = math.pi / 2
CUBE = [(H, 0.0, 1.0), (H, H, 1.0), (H, math.pi, 0.0), (H, 3 * H, 0.0), (0.0, 0.0, 1.0), (math.pi, 0.0, 0.0)]
SLANT = (math.acos(1 / math.sqrt(3)), math.pi / 4, 1 / math.sqrt(3))  # x + y + z = 1, outward
PLANES = CUBE + [SLANT]
CUBE_REFS = [0, 1, 2, 3, 4, 5]

# The tetrahedron (0, 0, 0), (0, 1, 0), (1, 0, 0), (0, 0, 1) as a shell walk (§9.13), every corner
# explicit, every triangle on a face plane. References: planes 2 (x = 0), 3 (y = 0), 5 (z = 0) and
# 6 (the slanted face), local 0 to 3.
#   triangle 0, root (0 1 2) on z = 0: symbol 10, children across edges (0, 1, 2); escapes 0 0 0
#   triangle 1 on edge 0 of 0: (1 0 3) on x = 0, code 0 (corner 3 new): symbol 0
#   triangle 2 on edge 1 of 0: (2 1 3) slanted; left: the newest open edge ending at 1 is (3, 1),
#     its start 3 is not the parent's opposite corner 0: symbol 1
#   triangle 3 on edge 2 of 0: (0 2 3) on y = 0; left: the newest open edge ending at 2 is (3, 2),
#     its start 3 is not the opposite corner 1: symbol 1; every open edge is then closed
# faces (§9.11): local reference r as r + 2; mode 0; grid origin 0, step 1; residuals by §9.11's
# predictor (the previous explicit corner for the root's corners; corner 3 from i0 = 1 of the
# triangle that names it): (0,0,0), (0,1,0)-(0,0,0), (1,0,0)-(0,1,0), (0,0,1)-(0,1,0).
TETRA_REFS = [2, 3, 5, 6]
TETRA_XYZ = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (0, 0, 1)]
TETRA_RESIDUALS = [(0, 0, 0), (0, 1, 0), (1, -1, 0), (0, -1, 1)]
TETRA_WALK = (uv(4) + uv(4) + uv(3)  # V, T, X
              + bytes([10, 0, 1, 1])  # symbols
              + bytes([0, 0, 0])  # escapes: the root's three codes
              + bytes([2 + 2, 0 + 2, 3 + 2, 1 + 2])  # faces
              + bytes([0x0F])  # flags: corners 0-3 explicit
              + bytes([0])  # mode
              + struct.pack("<4d", 0.0, 0.0, 0.0, 1.0)  # grid
              + b"".join(uv(zigzag(r[axis])) for axis in range(3) for r in TETRA_RESIDUALS))
TETRA_SHELL = {"explicit": [0, 1, 2, 3], "vertex_planes": [], "grid": [list(p) for p in TETRA_XYZ],
               "origin": [0.0, 0.0, 0.0], "step": 1.0,
               "facets": [[2, 0, 1, 2], [0, 1, 0, 3], [3, 2, 1, 3], [1, 0, 2, 3]]}


def scene(groups, minor=2, major=4, colours=(), objects=None, counts=False, index=False):
    """A file: the planes, objects 0 to 3 (0 at the origin, the others translated along x), then
    `groups` as (object, kind, refs, bounding, data[, method]) numbered in order, then colours."""
    objects = objects if objects is not None else [("source", None), ("twin", (2.0, 0.0, 0.0)),
                                                   ("triplet", (4.0, 0.0, 0.0)), ("quad", (6.0, 0.5, 0.0))]
    body = b""
    body += planes_chunk(PLANES)
    for i, (name, move) in enumerate(objects):
        body += object_chunk(i, name, move)
    for i, g in enumerate(groups):
        obj, kind, refs, bounding, data = g[:5]
        method = g[5] if len(g) > 5 else 0
        body += group_chunk(i, obj, kind, refs, bounding, data, method)
    for grp, rgba in colours:
        body += colour_chunk(grp, rgba)
    head = SIGNATURE + header(major, minor, (len(PLANES), len(objects), len(groups)) if counts else None)
    if index:
        return with_index(head + body)
    return head + body + end()


CONVEX = (0, 0, CUBE_REFS, [], b"")
WALK = (0, 9, TETRA_REFS, [], TETRA_WALK)


def copy_of(source, obj, refs, bounding=(), data=None, method=0):
    return (obj, COPY, refs, list(bounding), uv(source) if data is None else data, method)


# --- valid copies -------------------------------------------------------------------------------

def test_the_hand_built_sources_read_as_meant():
    got = read(scene([CONVEX, WALK]))
    assert "error" not in got, got
    assert got["header"]["version"] == [4, 2]
    assert got["groups"][0] == {"index": 0, "object": 0, "kind": 0, "refs": CUBE_REFS, "bounding": []}
    assert got["groups"][1]["shell"] == TETRA_SHELL


def test_copies_of_a_convex_group_and_of_a_shell_walk():
    data = scene([CONVEX, WALK, copy_of(0, 1, CUBE_REFS), copy_of(1, 2, TETRA_REFS), copy_of(1, 3, TETRA_REFS),
                  copy_of(0, 0, CUBE_REFS)], counts=True)
    got = read(data)
    assert "error" not in got, got
    assert got["findings"] == []
    g = got["groups"]
    assert len(g) == 6
    # §9.15 and the README's groups row: listed as stored, kind 11, "source", no kind-specific field
    assert g[2] == {"index": 2, "object": 1, "kind": 11, "refs": CUBE_REFS, "bounding": [], "source": 0}
    assert g[3] == {"index": 3, "object": 2, "kind": 11, "refs": TETRA_REFS, "bounding": [], "source": 1}
    assert g[4] == {"index": 4, "object": 3, "kind": 11, "refs": TETRA_REFS, "bounding": [], "source": 1}
    assert g[5] == {"index": 5, "object": 0, "kind": 11, "refs": CUBE_REFS, "bounding": [], "source": 0}
    assert g[1]["shell"] == TETRA_SHELL
    assert [o["transform"][3] if o["transform"] else None for o in got["objects"]] == [None, 2.0, 4.0, 6.0]
    assert got["geometry"] is None  # a container-level reader
    assert read_pipe(data) == got


def test_a_copy_of_a_kind_10_walk_and_of_groups_with_role_bits():
    """Kind 10 (§9.14) has the same fields as kind 9; a copy names it like any other. Role bits set on
    the source (a kind 0 group's are ignored by a decoder, §9.4, but stored) are repeated by the copy."""
    multi = (0, 10, TETRA_REFS, [], TETRA_WALK)
    got = read(scene([multi, copy_of(0, 1, TETRA_REFS)]))
    assert "error" not in got, got
    assert set(got["groups"][0]) == {"index", "object", "kind", "refs", "bounding", "shell"}
    assert got["groups"][1]["source"] == 0 and "shell" not in got["groups"][1]
    roles = (0, 0, CUBE_REFS, [0, 5], b"")
    got = read(scene([roles, copy_of(0, 1, CUBE_REFS, [0, 5])]))
    assert got["groups"][1] == {"index": 1, "object": 1, "kind": 11, "refs": CUBE_REFS, "bounding": [0, 5],
                                "source": 0}
    # a group of nine references: two role bytes
    refs9 = [0, 0, 1, 2, 3, 4, 5, 5, 6]
    got = read(scene([(0, 0, refs9, [8], b""), copy_of(0, 1, refs9, [8])]))
    assert got["groups"][1]["bounding"] == [8] and got["groups"][1]["refs"] == refs9


def test_compressed_bodies_colours_index_and_a_pipe():
    """A zlib source and a zlib copy (§6), a cOLR of the copy's own (§10.1: count = its ref_count), an
    index listing the copies (§10.2); the same answer on a file and on a pipe."""
    red, blue = [200, 30, 30, 255], [20, 20, 220, 255]
    data = scene([(0, 9, TETRA_REFS, [], TETRA_WALK, 1), copy_of(0, 1, TETRA_REFS, method=1),
                  (0, 0, CUBE_REFS, [], b"", 1), copy_of(2, 2, CUBE_REFS, method=1)],
                 colours=[(1, [red] * 4), (3, [blue] * 6)], index=True, counts=True)
    got = read(data)
    assert "error" not in got, got
    assert [g.get("source") for g in got["groups"]] == [None, 0, None, 2]
    assert got["groups"][0]["shell"] == TETRA_SHELL
    assert got["colours"] == [{"group": 1, "rgba": [red] * 4}, {"group": 3, "rgba": [blue] * 6}]
    assert read_pipe(data) == got
    # a colour count other than the copy's ref_count
    bad = scene([CONVEX, copy_of(0, 1, CUBE_REFS)], colours=[(1, [red] * 4)])
    assert error(bad) == "BAD_COLOURS"


def test_a_source_may_be_far_back():
    """The reader keeps what a later copy needs of every group (here 40 groups back), on a pipe too."""
    groups = [CONVEX] + [(0, 0, CUBE_REFS, [], b"")] * 40 + [copy_of(0, 1, CUBE_REFS), copy_of(40, 2, CUBE_REFS)]
    data = scene(groups)
    got = read_pipe(data)
    assert [g.get("source") for g in got["groups"][-2:]] == [0, 40]
    bad = scene([(0, 0, CUBE_REFS[:5] + [6], [], b"")] + [CONVEX] * 40 + [copy_of(0, 1, CUBE_REFS)])
    assert read_pipe(bad) == {"error": "BAD_GROUP_STRUCTURE"}


# --- the errors of §9.15, in its order ----------------------------------------------------------

def test_step_1_the_varint_and_bytes_after_it():
    for data in (b"",  # the body ends before s
                 b"\x80",  # inside s
                 b"\x80\x00",  # not minimal (§2.2)
                 b"\x81\x80\x80\x80\x80\x80\x80\x80\x80\x02",  # 2^64 or more: a tenth byte above 0x01
                 b"\x80" * 10 + b"\x00",  # longer than 10 bytes
                 b"\x00\x00",  # a byte after s
                 b"\x00\xff\xff"):
        assert error(scene([CONVEX, copy_of(0, 1, CUBE_REFS, data=data)])) == "BAD_PAYLOAD", data
    # in a compressed body as well
    assert error(scene([CONVEX, copy_of(0, 1, CUBE_REFS, data=b"\x00\x00", method=1)])) == "BAD_PAYLOAD"


def test_step_2_a_source_not_earlier_or_itself_a_copy():
    for s in (1, 2, 7, 2**32 - 1, 2**32, 2**63):  # itself, later, and beyond any varint32
        assert error(scene([CONVEX, copy_of(s, 1, CUBE_REFS)])) == "BAD_GROUP_STRUCTURE", s
    assert error(scene([copy_of(0, 0, CUBE_REFS)])) == "BAD_GROUP_STRUCTURE"  # group 0 has no earlier group
    # a copy of a copy, even of one that repeats the source's references and roles
    assert error(scene([CONVEX, copy_of(0, 1, CUBE_REFS), copy_of(1, 2, CUBE_REFS)])) == "BAD_GROUP_STRUCTURE"
    assert error(scene([CONVEX, copy_of(0, 1, CUBE_REFS), copy_of(0, 2, CUBE_REFS)])) is None


def test_step_4_references_and_role_bits():
    cases = [
        (CONVEX, copy_of(0, 1, CUBE_REFS[:5])),  # fewer references
        (CONVEX, copy_of(0, 1, CUBE_REFS + [6])),  # more
        (CONVEX, copy_of(0, 1, [0, 0, 1, 2, 3, 4])),  # as many, one repeated, one missing
        (CONVEX, copy_of(0, 1, [0, 1, 2, 3, 4, 6])),  # as many, one other plane
        (CONVEX, copy_of(0, 1, CUBE_REFS, [0])),  # a role bit the source lacks
        ((0, 0, CUBE_REFS, [3], b""), copy_of(0, 1, CUBE_REFS)),  # one it has, missing
        ((0, 0, CUBE_REFS, [3], b""), copy_of(0, 1, CUBE_REFS, [4])),  # moved
        (WALK, copy_of(0, 1, CUBE_REFS)),  # another group's references
        (WALK, copy_of(0, 1, TETRA_REFS, [2])),
    ]
    for source, copy in cases:
        assert error(scene([source, copy])) == "BAD_GROUP_STRUCTURE", copy


def test_the_order_of_the_checks():
    # the common body (§9.2) before the kind data: a reference past the table, whatever follows
    assert error(scene([CONVEX, copy_of(5, 1, [0, 9], data=uv(5) + b"\x00")])) == "BAD_PLANE_REFERENCE"
    # ref_count 0 (§9.2 step 2) before the kind data
    assert error(scene([CONVEX, (1, COPY, [], [], uv(0) + b"\x00", 0)])) == "BAD_GROUP_STRUCTURE"
    assert error(scene([CONVEX, (1, COPY, [], [], b"\x80", 0)])) == "BAD_GROUP_STRUCTURE"
    # step 1 before step 2: bytes after s, or a truncated s, even where s names no earlier group
    assert error(scene([CONVEX, copy_of(0, 1, CUBE_REFS, data=uv(9) + b"\x00")])) == "BAD_PAYLOAD"
    assert error(scene([CONVEX, copy_of(0, 1, CUBE_REFS, data=b"\x89")])) == "BAD_PAYLOAD"
    # step 1 before step 4
    assert error(scene([CONVEX, copy_of(0, 1, [0], data=uv(0) + b"\x00")])) == "BAD_PAYLOAD"
    # a group before the copy is read whole before it: its own error comes first
    assert error(scene([(0, 0, CUBE_REFS, [], b"\x00"), copy_of(0, 1, [0])])) == "BAD_PAYLOAD"


# --- versions (§9.3, §13) -----------------------------------------------------------------------

def test_kind_11_by_version():
    good = [CONVEX, copy_of(0, 1, CUBE_REFS)]
    for minor in (0, 1):  # not a kind of 4.0 or 4.1: UNKNOWN_GROUP_KIND, before its body is looked at
        assert error(scene(good, minor=minor)) == "UNKNOWN_GROUP_KIND"
        assert error(scene([CONVEX, copy_of(0, 1, CUBE_REFS, data=b"\x00\x00")], minor=minor)) \
            == "UNKNOWN_GROUP_KIND"
    no_moves = [("a", None), ("b", None)]
    assert error(scene(good, major=3, minor=4, objects=no_moves)) == "UNKNOWN_GROUP_KIND"
    # major 3, minor 5: kind 11 is a kind of a newer minor, skipped, whatever its body holds
    got = read(scene([CONVEX, copy_of(7, 1, [0], data=b"\x00\x00")], major=3, minor=5, objects=no_moves))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and "source" not in got["groups"][1]
    # 4.3, newer than this reader knows: a copy is read as in 4.2
    got = read(scene(good, minor=3))
    assert got["groups"][1]["source"] == 0 and "NEWER_MINOR_VERSION" in got["findings"]
    assert "SKIPPED_GROUP_KIND" not in got["findings"]
    assert error(scene([CONVEX, copy_of(0, 1, CUBE_REFS[:5])], minor=3)) == "BAD_GROUP_STRUCTURE"


def test_a_copy_of_a_skipped_group_is_skipped():
    """§9.15 step 3: a 4.3 file's kind 12 is skipped (§9.3), and so is a copy of it; step 3 comes before
    step 4, so the copy's references are not compared with the skipped source's. Steps 1 and 2 still
    apply to the copy."""
    unknown = (0, 12, CUBE_REFS, [], b"\x01\x02\x03")
    got = read(scene([unknown, copy_of(0, 1, CUBE_REFS)], minor=3))
    assert "error" not in got, got
    assert "SKIPPED_GROUP_KIND" in got["findings"]
    assert got["groups"][1] == {"index": 1, "object": 1, "kind": 11, "refs": CUBE_REFS, "bounding": [],
                                "source": 0}
    got = read(scene([unknown, copy_of(0, 1, [1, 2], [0])], minor=3))  # other references, other roles
    assert "error" not in got and got["groups"][1]["source"] == 0
    assert error(scene([unknown, copy_of(0, 1, CUBE_REFS, data=b"\x00\x00")], minor=3)) == "BAD_PAYLOAD"
    assert error(scene([unknown, copy_of(1, 1, CUBE_REFS)], minor=3)) == "BAD_GROUP_STRUCTURE"
    # a copy of a copy of a skipped group: step 2 (the source is a copy) before step 3
    assert error(scene([unknown, copy_of(0, 1, CUBE_REFS), copy_of(1, 2, CUBE_REFS)], minor=3)) \
        == "BAD_GROUP_STRUCTURE"
    # a later group of a known kind is read as ever, and a copy of it checked
    got = read(scene([unknown, copy_of(0, 1, CUBE_REFS), CONVEX, copy_of(2, 2, CUBE_REFS)], minor=3))
    assert got["groups"][3]["source"] == 2
    assert error(scene([unknown, CONVEX, copy_of(1, 2, CUBE_REFS, [1])], minor=3)) == "BAD_GROUP_STRUCTURE"


@pytest.mark.parametrize("source", [CONVEX, WALK], ids=["convex", "walk"])
def test_every_prefix_of_a_copy_file_is_refused_and_no_byte_crashes_it(source):
    """Truncations answer TRUNCATED; a changed byte answers a code of §12.2 or a result, never a crash
    (CRCs recomputed so that the change reaches the payload)."""
    refs = source[2]
    data = scene([source, copy_of(0, 1, refs), copy_of(0, 2, refs)], index=True)
    assert "error" not in read(data)
    for n in range(0, len(data), 7):
        assert error(data[:n]) in {"TRUNCATED"}
    codes = set(plnread_codes())
    pos, spans = 8, []
    while pos < len(data):
        length = struct.unpack_from("<I", data, pos + 4)[0]
        spans.append((pos, length))
        pos += 12 + length
    for start, length in spans:
        tag = data[start:start + 4]
        if tag != b"GRUP":
            continue
        for k in range(length):
            for value in (0x00, 0x01, 0x80, 0xFF):
                payload = bytearray(data[start + 8:start + 8 + length])
                payload[k] = value
                damaged = data[:start] + u32_chunk(tag, bytes(payload)) + data[start + 12 + length:]
                got = read(damaged)
                assert "error" not in got or got["error"] in codes, got


def plnread_codes():
    return ["BAD_PAYLOAD", "BAD_GROUP_STRUCTURE", "BAD_PLANE_REFERENCE", "BAD_OBJECT_REFERENCE",
            "GROUP_INDEX_MISMATCH", "UNKNOWN_GROUP_KIND", "BAD_COMPRESSION", "SIZE_MISMATCH", "LIMIT_EXCEEDED",
            "BAD_INDEX", "COUNT_MISMATCH"]
