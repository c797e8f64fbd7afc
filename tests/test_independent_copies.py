"""Kind 11 (spec/pln.md §9.15, copies) in the independent reader conformance/independent/plnspec.py,
on hand-built version 4.2 files.

Every file is assembled here from the spec (§4 chunks, §5 header, §7 float64 planes, §8 objects with
transforms coded entry by entry, §9.1-§9.2 group heads and common bodies, §10.1 colours, §10.2 an
index), not from planefmt or the generator: a convex unit cube (kind 0) and a tetrahedron coded as a
shell walk (kind 9, §9.13) by hand below, each copied into objects of their own. Then each error of
§9.15, and pairs of errors that tell its order of checks (and its place after the head and the common
body) apart, and the versions of §9.3."""

from __future__ import annotations

import json
import math
import struct
import subprocess
import sys

import pytest

from spec_files import ROOT, SIGNATURE, SUITE, group_body, grup, phdr, plns, u32_chunk, uv, zigzag
from spec_files import read_spec as read


# --- the content ----------------------------------------------------------------------------------

# §2.3: the unit cube [0, 1]^3, +x -x +y -y +z -z as (nu, phi, h), then one plane for the walk's refs
CUBE_PLANES = [[math.pi / 2, 0.0, 1.0], [math.pi / 2, math.pi, 0.0], [math.pi / 2, math.pi / 2, 1.0],
               [math.pi / 2, 3 * math.pi / 2, 0.0], [0.0, 0.0, 1.0], [math.pi, 0.0, 0.0]]
PLANES = CUBE_PLANES + [[0.0, 0.0, 0.0]]
CUBE_REFS = [0, 1, 2, 3, 4, 5]

# A tetrahedron as a shell walk (§9.13), every corner explicit, every triangle free. Root (0 1 2),
# codes 0 0 0, symbol 10: children across its edges (0, 1, 2), edge 0's on top. Attached to the
# root's edge 0: (1 0 3), a new corner (code 0), no child: symbol 0. Open edges then (1,2) (2,0)
# (0,3) (3,1). Attached to edge 1: (2 1 3), left (code 1): the newest open edge ending at 1 is
# (3,1), whose start 3 is not the root's opposite corner 0: symbol 1. Attached to edge 2: (0 2 3),
# left: the newest open edge ending at 2 is (3,2), start 3, not the opposite corner 1: symbol 1.
# Every edge is then closed. Corners 0 (0,0,0), 1 (0,1,0), 2 (1,0,0), 3 (0,0,1): outward.
TET_XYZ = [[0, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 1]]
TET_TRIS = [[0, 1, 2], [1, 0, 3], [2, 1, 3], [0, 2, 3]]
# §9.11 predictors (mode 0): corners 0-2 named by the root: the previous explicit corner (none for
# 0); corner 3 named by an attached triangle whose i0, corner 1, is explicit: corner 1
TET_RESIDUALS = [[0, 0, 0], [0, 1, 0], [1, -1, 0], [0, -1, 1]]


def walk_data() -> bytes:
    data = uv(4) + uv(4) + uv(3)  # V, T, X
    data += b"".join(uv(s) for s in (10, 0, 1, 1))  # symbols
    data += uv(0) * 3  # escapes: the root's three codes
    data += uv(1) * 4  # faces: free
    data += bytes([0x0F])  # flags: all four explicit; no picks (no named corner)
    data += bytes([0]) + struct.pack("<4d", 0.0, 0.0, 0.0, 1.0)  # mode 0, grid
    for axis in range(3):
        data += b"".join(uv(zigzag(r[axis])) for r in TET_RESIDUALS)
    return data


TET_SHELL = {"explicit": [0, 1, 2, 3], "vertex_planes": [], "grid": TET_XYZ, "origin": [0.0, 0.0, 0.0],
             "step": 1.0, "facets": [[-1, *t] for t in TET_TRIS]}


def transform(tx: float) -> bytes:
    """§8: a translation by (tx, 0, 0): codes 1 on the diagonal, 2 (an f32) for m03, 0 elsewhere."""
    codes = [1, 0, 0, 2, 0, 1, 0, 0, 0, 0, 1, 0]
    bits = sum(c << (2 * i) for i, c in enumerate(codes))
    return bits.to_bytes(3, "little") + struct.pack("<f", tx)


def matrix(tx):
    return None if tx is None else [1.0, 0.0, 0.0, tx, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]


def copy_data(source: int) -> bytes:
    return uv(source)


def pln(groups, objects=(None,), minor=2, colours=(), index=False, counts=False) -> bytes:
    """A version 4.minor file: PHDR, one float64 PLNS, objects (each a root, None or the x of a
    translation), groups (object, kind, refs, bounding, data[, method]), cOLR (group, count, rgba:
    one colour for every reference), optionally an iNDX and its PEND offset."""
    counted = (len(PLANES), len(objects), len(groups)) if counts else None
    out = SIGNATURE + u32_chunk(b"PHDR", phdr(4, minor, coding=1, counts=counted))
    entries = [(len(out), b"PLNS", 0)]
    out += u32_chunk(b"PLNS", plns(PLANES, 1))
    for k, tx in enumerate(objects):
        entries.append((len(out), b"OBJT", k))
        out += u32_chunk(b"OBJT", uv(k) + uv(0) + bytes([tx is not None]) + uv(1) + bytes([0x61 + k])
                         + (transform(tx) if tx is not None else b""))
    for k, (obj, kind, refs, bounding, data, *method) in enumerate(groups):
        entries.append((len(out), b"GRUP", k))
        out += u32_chunk(b"GRUP", grup(k, obj, kind, group_body(refs, bounding, data), *method))
    for group, count, rgba in colours:
        out += u32_chunk(b"cOLR", struct.pack("<II", group, count) + bytes(rgba))
    if index:
        at = len(out)
        table = struct.pack("<I", len(entries)) + b"".join(struct.pack("<Q4sI", *e) for e in entries)
        out += u32_chunk(b"iNDX", table)
        return out + u32_chunk(b"PEND", struct.pack("<Q", at))
    return out + u32_chunk(b"PEND", b"")


def error(data: bytes) -> str | None:
    return read(data).get("error")


WALK = (0, 9, [6], [], walk_data())
CUBE = (0, 0, CUBE_REFS, [], b"")


def group(index, obj, kind, refs, bounding=(), **extra):
    return {"index": index, "object": obj, "kind": kind, "refs": refs, "bounding": list(bounding), **extra}


# --- valid files ----------------------------------------------------------------------------------

def scene(**kw) -> bytes:
    """A tetrahedron walk and a convex cube, each copied into an object translated by (2, 0, 0); the
    walk's copy with a colour of its own, and the cube copied a second time, into its own object."""
    groups = [WALK, (1, 11, [6], [], copy_data(0)), (2, 0, CUBE_REFS, [], b""),
              (3, 11, CUBE_REFS, [], copy_data(2)), (2, 11, CUBE_REFS, [], copy_data(2))]
    return pln(groups, objects=(None, 2.0, None, 2.0), colours=[(1, 1, [200, 30, 30, 255])], **kw)


SCENE_GROUPS = [group(0, 0, 9, [6], shell=TET_SHELL), group(1, 1, 11, [6], source=0),
                group(2, 2, 0, CUBE_REFS), group(3, 3, 11, CUBE_REFS, source=2),
                group(4, 2, 11, CUBE_REFS, source=2)]


@pytest.mark.parametrize("kw", [{}, {"index": True, "counts": True}])
def test_copies_of_a_shell_walk_and_a_convex_group(kw):
    got = read(scene(**kw))
    assert "error" not in got, got
    assert got["header"]["version"] == [4, 2] and got["findings"] == []
    assert got["groups"] == SCENE_GROUPS  # a copy: as stored, "source" and no kind-specific field
    assert [o["transform"] for o in got["objects"]] == [matrix(None), matrix(2.0), matrix(None), matrix(2.0)]
    assert got["colours"] == [{"group": 1, "rgba": [[200, 30, 30, 255]]}]
    assert got["geometry"] is None


def test_the_command_line_prints_the_same():
    path = ROOT / "tests" / "_copies_scene.pln"
    try:
        path.write_bytes(scene())
        proc = subprocess.run([sys.executable, str(SUITE / "independent" / "plnspec.py"), str(path)],
                              capture_output=True, text=True)
    finally:
        path.unlink(missing_ok=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert json.loads(proc.stdout)["groups"] == SCENE_GROUPS


def test_copies_with_role_bits_compressed_bodies_and_several_copies_of_one_source():
    walk = (0, 9, [0, 6], [0], walk_data())  # a bounding reference the free triangles never use
    groups = [walk, (0, 11, [0, 6], [0], copy_data(0), 1), (1, 11, [0, 6], [0], copy_data(0)),
              (1, 0, CUBE_REFS, [], b"", 1), (0, 11, CUBE_REFS, [], copy_data(3), 1)]
    got = read(pln(groups, objects=(None, -1.5)))
    assert "error" not in got, got
    assert got["groups"][1:3] == [group(1, 0, 11, [0, 6], [0], source=0), group(2, 1, 11, [0, 6], [0], source=0)]
    assert got["groups"][4] == group(4, 0, 11, CUBE_REFS, source=3)
    assert got["groups"][0]["shell"] == TET_SHELL


def test_a_copy_of_group_0_source_0_is_the_smallest_kind_data():
    got = read(pln([CUBE, (0, 11, CUBE_REFS, [], b"\x00")]))
    assert got["groups"][1] == group(1, 0, 11, CUBE_REFS, source=0)


# --- versions (§9.3) ------------------------------------------------------------------------------

def test_kind_11_by_minor_version():
    groups = [CUBE, (0, 11, CUBE_REFS, [], copy_data(0))]
    for minor in (0, 1):  # not a kind of 4.0 or 4.1, minors this reader knows
        assert error(pln(groups, minor=minor)) == "UNKNOWN_GROUP_KIND"
    got = read(pln(groups, minor=2))
    assert got["groups"][1]["source"] == 0 and "NEWER_MINOR_VERSION" not in got["findings"]
    got = read(pln(groups, minor=3))  # a newer minor: kind 11 is still a copy
    assert got["groups"][1]["source"] == 0 and "NEWER_MINOR_VERSION" in got["findings"]
    assert "SKIPPED_GROUP_KIND" not in got["findings"]
    assert error(pln([CUBE, (0, 12, CUBE_REFS, [], b"\x00")], minor=2)) == "UNKNOWN_GROUP_KIND"


def test_a_copy_of_a_skipped_group_is_skipped():
    """§9.15 step 3, in a 4.3 file whose kind 12 this reader skips: the copy is skipped too, and its
    references are not compared (step 4 is not reached: SPEC_NOTES 48); a copy of that copy is a copy
    of a copy (step 2, by the stored kind: SPEC_NOTES 47)."""
    skipped = (0, 12, CUBE_REFS, [1], b"\x05\x06\x07")
    got = read(pln([skipped, (0, 11, CUBE_REFS, [1], copy_data(0)), CUBE], minor=3))
    assert "error" not in got, got
    assert "SKIPPED_GROUP_KIND" in got["findings"]
    assert got["groups"][1] == group(1, 0, 11, CUBE_REFS, [1], source=0)
    other = read(pln([skipped, (0, 11, [0, 1], [], copy_data(0))], minor=3))  # other refs and roles
    assert "error" not in other and other["groups"][1]["source"] == 0
    # steps 1 and 2 still apply to a copy whose source was skipped
    assert error(pln([skipped, (0, 11, CUBE_REFS, [1], copy_data(0) + b"\x00")], minor=3)) == "BAD_PAYLOAD"
    assert error(pln([skipped, (0, 11, CUBE_REFS, [1], copy_data(0)),
                      (0, 11, CUBE_REFS, [1], copy_data(1))], minor=3)) == "BAD_GROUP_STRUCTURE"
    # a copy of an unskipped group in the same file is compared as ever
    assert error(pln([skipped, CUBE, (0, 11, CUBE_REFS, [1], copy_data(1))], minor=3)) == "BAD_GROUP_STRUCTURE"


# --- the errors of §9.15, and their order ---------------------------------------------------------

C = CUBE_REFS
ERRORS = {
    # step 1: the varint, then nothing after it
    "no kind data": ([CUBE, (0, 11, C, [], b"")], "BAD_PAYLOAD"),
    "ends inside the varint": ([CUBE, (0, 11, C, [], b"\x80")], "BAD_PAYLOAD"),
    "ends inside a long varint": ([CUBE, (0, 11, C, [], b"\xff\xff\xff")], "BAD_PAYLOAD"),
    "a varint not minimal": ([CUBE, (0, 11, C, [], b"\x80\x00")], "BAD_PAYLOAD"),
    "a varint of 2^64": ([CUBE, (0, 11, C, [], b"\xff" * 9 + b"\x02")], "BAD_PAYLOAD"),
    "a varint of 11 bytes": ([CUBE, (0, 11, C, [], b"\x80" * 10 + b"\x00")], "BAD_PAYLOAD"),
    "a byte after it": ([CUBE, (0, 11, C, [], b"\x00\x00")], "BAD_PAYLOAD"),
    "a second varint after it": ([CUBE, (0, 11, C, [], b"\x00\x80\x01")], "BAD_PAYLOAD"),
    # step 2: an earlier group, not a copy
    "itself": ([CUBE, (0, 11, C, [], copy_data(1))], "BAD_GROUP_STRUCTURE"),
    "a later group": ([CUBE, (0, 11, C, [], copy_data(2)), CUBE], "BAD_GROUP_STRUCTURE"),
    "group 0 copying group 0": ([(0, 11, C, [], copy_data(0))], "BAD_GROUP_STRUCTURE"),
    "a source of 2^32 (a varint, not a varint32)": ([CUBE, (0, 11, C, [], uv(1 << 32))], "BAD_GROUP_STRUCTURE"),
    "a source of 2^64 - 1": ([CUBE, (0, 11, C, [], uv((1 << 64) - 1))], "BAD_GROUP_STRUCTURE"),
    "a copy of a copy": ([CUBE, (0, 11, C, [], copy_data(0)), (0, 11, C, [], copy_data(1))], "BAD_GROUP_STRUCTURE"),
    # step 4: the same references, in the same order, and the same role bits
    "fewer references": ([CUBE, (0, 11, C[:5], [], copy_data(0))], "BAD_GROUP_STRUCTURE"),
    "more references": ([CUBE, (0, 11, C + [6], [], copy_data(0))], "BAD_GROUP_STRUCTURE"),
    "a reference repeated": ([CUBE, (0, 11, [0, 1, 2, 3, 4, 4], [], copy_data(0))], "BAD_GROUP_STRUCTURE"),
    "another plane": ([CUBE, (0, 11, [0, 1, 2, 3, 4, 6], [], copy_data(0))], "BAD_GROUP_STRUCTURE"),
    "a role bit set": ([CUBE, (0, 11, C, [3], copy_data(0))], "BAD_GROUP_STRUCTURE"),
    "a role bit clear": ([(0, 9, [0, 6], [0], walk_data()), (0, 11, [0, 6], [], copy_data(0))], "BAD_GROUP_STRUCTURE"),
    "a walk's copy with a cube's references": ([WALK, CUBE, (0, 11, C, [], copy_data(0))], "BAD_GROUP_STRUCTURE"),
    # the order: step 1 before steps 2 and 4
    "a byte after a later source": ([CUBE, (0, 11, C, [], copy_data(5) + b"\x00")], "BAD_PAYLOAD"),
    "a byte after, other references": ([CUBE, (0, 11, C[:5], [], b"\x00\x00")], "BAD_PAYLOAD"),
    "cut short, other role bits": ([CUBE, (0, 11, C, [0], b"\x80")], "BAD_PAYLOAD"),
    "a copy of a copy, with a byte after": ([CUBE, (0, 11, C, [], copy_data(0)),
                                             (0, 11, C, [], copy_data(1) + b"\x01")], "BAD_PAYLOAD"),
    # the head and the common body come first (§9.1, §9.2)
    "a later source, in an object not defined": ([CUBE, (1, 11, C, [], copy_data(7))], "BAD_OBJECT_REFERENCE"),
    "a later source, a plane not defined": ([CUBE, (0, 11, C[:5] + [7], [], copy_data(7))], "BAD_PLANE_REFERENCE"),
    "cut short, a padding bit set": ([CUBE, (0, 11, C, [6], b"\x80")], "BAD_PAYLOAD"),
}


@pytest.mark.parametrize("name", list(ERRORS))
def test_errors_of_9_15(name):
    groups, code = ERRORS[name]
    assert error(pln(groups)) == code, read(pln(groups))
    # the same body deflated gives the same answer (§6 comes before the body)
    assert error(pln([(*g, 1) for g in groups])) == code


def test_each_code_names_the_check():
    """The reader's reason, not only its code, for one case of each step."""
    assert "bytes after the source" in read(pln(ERRORS["a byte after it"][0]))["why"]
    assert "not below" in read(pln(ERRORS["itself"][0]))["why"]
    assert "is a copy" in read(pln(ERRORS["a copy of a copy"][0]))["why"]
    assert "references" in read(pln(ERRORS["fewer references"][0]))["why"]
    assert "role bits" in read(pln(ERRORS["a role bit set"][0]))["why"]


def test_colours_of_a_copy_are_its_own():
    """§9.15: a cOLR names the copy or none does; its count is the copy's ref_count (§10.1)."""
    groups = [CUBE, (0, 11, C, [], copy_data(0))]
    got = read(pln(groups, colours=[(1, 6, [1, 2, 3, 4] * 6)]))
    assert got["colours"] == [{"group": 1, "rgba": [[1, 2, 3, 4]] * 6}]
    assert error(pln(groups, colours=[(1, 5, [1, 2, 3, 4] * 5)])) == "BAD_COLOURS"
    assert error(pln(groups, colours=[(2, 6, [1, 2, 3, 4] * 6)])) == "BAD_COLOURS"


def test_counts_and_index_count_copies():
    data = scene(index=True, counts=True)
    assert "error" not in read(data)
    # an index that leaves out a copy's chunk does not match the file
    groups = [CUBE, (0, 11, C, [], copy_data(0))]
    good = pln(groups, index=True)
    assert "error" not in read(good)
    at = good.rindex(b"iNDX")
    payload = good[at + 8:at + 8 + struct.unpack_from("<I", good, at + 4)[0]]
    count = struct.unpack_from("<I", payload)[0]
    short = struct.pack("<I", count - 1) + payload[4:4 + 16 * (count - 1)]
    bad = good[:at] + u32_chunk(b"iNDX", short) + u32_chunk(b"PEND", struct.pack("<Q", at))
    assert error(bad) == "BAD_INDEX"
