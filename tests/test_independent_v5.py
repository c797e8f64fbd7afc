"""Version 5.0 (spec/pln.md §4.1, §5, §9.2, §9.10-§9.14, §10.1, §10.3, Appendix A.5) in the independent
reader conformance/independent/plnspec.py, on hand-built files.

Every file is assembled here from the spec, not from planefmt or the generator: §4.1 framing (PHDR with a
u32 length, every later chunk of a version 5 file with a varint32 length), the 8-byte fixed part of a
version 5 header with the up axis in its units byte, a tetrahedron coded by hand as a shell walk (kind 9,
§9.13) without references and on an f32 grid, a copy of it (kind 11), and an index. The points the golden
files (conformance/*/..._v5_0, xv50_*) leave open: a three-byte length varint, a five-byte one that is not
minimal, the chunk limit, ignored header bits, other mETA keywords beside the header's up axis, groups
without references in a newer minor version, and the version 4 rules of Appendix A.5."""

from __future__ import annotations

import struct

import pytest

from spec_files import SIGNATURE, group_body, grup, objt, phdr, plns, u32_chunk, uv, varint_chunk, zigzag
from spec_files import read_spec as read


def pln(chunks, header: bytes | None = None, index: bool = False, framing=None) -> bytes:
    """A file: PHDR (u32 length), ``chunks`` (type, payload) framed as the header's major frames them
    (``framing`` overrides), then, with ``index``, an iNDX of the OBJT, PLNS and GRUP chunks and an
    8-byte PEND, else an empty PEND."""
    header = phdr() if header is None else header
    frame = framing or (varint_chunk if header[0] >= 5 else u32_chunk)
    out = SIGNATURE + u32_chunk(b"PHDR", header)
    entries, ordinal = [], {b"OBJT": 0, b"PLNS": 0, b"GRUP": 0}
    for ctype, payload in chunks:
        if ctype in ordinal:
            entries.append(struct.pack("<Q4sI", len(out), ctype, ordinal[ctype]))
            ordinal[ctype] += 1 if ctype != b"PLNS" else payload[1]  # one-byte first and count here
        out += frame(ctype, payload)
    if not index:
        return out + frame(b"PEND", b"")
    at = len(out)
    out += frame(b"iNDX", struct.pack("<I", len(entries)) + b"".join(entries))
    return out + frame(b"PEND", struct.pack("<Q", at))


def group(k: int, kind: int, refs, data: bytes, obj: int = 0) -> bytes:
    """§9.1 and §9.2: a GRUP payload, stored, its role bits all 0."""
    return grup(k, obj, kind, group_body(refs, (), data))


# A tetrahedron as a shell walk (§9.13), every corner explicit, every triangle free: root (0 1 2),
# symbol 10 (children across edges 0, 1, 2); (1 0 3) a new corner, symbol 0; (2 1 3) and (0 2 3) left
# codes, symbol 1. Mode 0: corners 0-2 predicted by the previous explicit corner, corner 3 by corner 1.
TET_XYZ = [[0, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 1]]
TET_TRIS = [[0, 1, 2], [1, 0, 3], [2, 1, 3], [0, 2, 3]]
TET_RESIDUALS = [[0, 0, 0], [0, 1, 0], [1, -1, 0], [0, -1, 1]]


def walk_data(grid: bytes) -> bytes:
    data = uv(4) + uv(4) + uv(3) + b"".join(uv(s) for s in (10, 0, 1, 1)) + uv(0) * 3 + uv(1) * 4 + b"\x0f"
    data += b"\x00" + grid  # mode 0, then the grid
    return data + b"".join(uv(zigzag(r[a])) for a in range(3) for r in TET_RESIDUALS)


F32_GRID = struct.pack("<4f", 0.5, -0.25, 0.0, 0.125)  # §9.13 as §9.11, version 5: 16 bytes
F64_GRID = struct.pack("<4d", 0.5, -0.25, 0.0, 0.125)  # A.5: 32 bytes
TET_SHELL = {"explicit": [0, 1, 2, 3], "vertex_planes": [], "grid": TET_XYZ, "origin": [0.5, -0.25, 0.0],
             "step": 0.125, "facets": [[-1, *t] for t in TET_TRIS]}
WALK = group(0, 9, [], walk_data(F32_GRID))


def error(data: bytes) -> str | None:
    return read(data).get("error")


# --- valid files ----------------------------------------------------------------------------------

def test_a_planeless_walk_its_copy_a_three_byte_length_and_an_index():
    """No PLNS, a walk without references on an f32 grid and a copy of it (m = 0, §9.2), the up axis Z
    in the header beside an mETA keyword of its own, an unknown ancillary chunk of 20,000 bytes (a
    three-byte length varint, §4.1) before the objects, so that the index's offsets pass it."""
    big = bytes(range(256)) * 78 + bytes(32)  # 20,000 bytes
    assert len(uv(len(big))) == 3
    chunks = [(b"mETA", b"author\x00me"), (b"zZZZ", big), (b"OBJT", objt(0, b"tet")), (b"GRUP", WALK),
              (b"OBJT", objt(1, b"twin")), (b"GRUP", group(1, 11, [], uv(0), obj=1))]
    got = read(pln(chunks, header=phdr(up=2, counts=(0, 2, 2)), index=True))
    assert "error" not in got, got
    assert got["header"]["version"] == [5, 0] and got["header"]["units"] == 1 and got["header"]["coding"] == 0
    assert got["header"]["counts"] == {"planes": 0, "objects": 2, "groups": 2}
    assert got["metadata"] == {"up_axis": "Z", "author": "me"}
    assert got["findings"] == ["UNKNOWN_ANCILLARY_CHUNK"]
    assert got["planes"] == [] and got["colours"] == []
    assert got["groups"] == [{"index": 0, "object": 0, "kind": 9, "refs": [], "bounding": [], "shell": TET_SHELL},
                             {"index": 1, "object": 1, "kind": 11, "refs": [], "bounding": [], "source": 0}]


def test_ignored_header_bits_and_no_up_axis():
    """§5: flag bits 3-7 and bits 6-7 of units are ignored (§2.1); up axis 0 says none."""
    header = bytearray(phdr(units=3, up=1))
    header[2] |= 0xF8
    header[7] |= 0xC0
    got = read(pln([(b"OBJT", objt(0)), (b"GRUP", WALK)], header=bytes(header)))
    assert got["header"]["units"] == 3 and got["header"]["lossy"] is False and got["metadata"] == {"up_axis": "Y"}
    got = read(pln([(b"OBJT", objt(0)), (b"GRUP", WALK)]))
    assert got["metadata"] == {}


def test_a_shell_on_planes_beside_one_without():
    """Kind 6 (§9.10) with an f32 grid: a shell without references whose triangles are all free, and a
    cOLR only for a group with references."""
    # corners 0-2 explicit, one free triangle: flags 0x07, grid, steps, then codes 0 0 0
    shell = uv(3) + uv(1) + uv(1) + b"\x07" + F32_GRID + b"".join(uv(zigzag(s)) for s in (0, 0, 0, 1, 0, 0, -1, 1, 0))
    shell += uv(0) * 3
    chunks = [(b"OBJT", objt(0)), (b"PLNS", plns([[0.0, 0.0, 1.0]], 0)), (b"GRUP", group(0, 0, [0], b"")),
              (b"cOLR", struct.pack("<II", 0, 1) + bytes(4)), (b"GRUP", group(1, 6, [], shell))]
    got = read(pln(chunks, index=True))
    assert "error" not in got, got
    assert got["groups"][1]["shell"] == {"explicit": [0, 1, 2], "vertex_planes": [],
                                         "grid": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "origin": [0.5, -0.25, 0.0],
                                         "step": 0.125, "facets": [[-1, 0, 1, 2]]}
    colour_none = chunks + [(b"cOLR", struct.pack("<II", 1, 0))]
    assert error(pln(colour_none)) == "BAD_COLOURS"  # §10.1: a count of 0 without its one colour
    # §10.1: a count of 0 with one colour is the colour of every triangle of a group without references
    one = read(pln(chunks + [(b"cOLR", struct.pack("<II", 1, 0) + bytes([9, 8, 7, 255]))], index=True))
    assert "error" not in one and one["colours"][-1] == {"group": 1, "rgba": [[9, 8, 7, 255]]}, one


# --- framing (§4.1) -------------------------------------------------------------------------------

CUBE_LIKE = [(b"OBJT", objt(0)), (b"GRUP", WALK)]


def with_objt_length(length: bytes, tail: bytes | None = None) -> bytes:
    """The file of CUBE_LIKE with the OBJT chunk's length varint replaced by ``length``."""
    at = len(SIGNATURE) + 12 + len(phdr()) + 4
    data = pln(CUBE_LIKE)
    return data[:at] + length + (data[at + 1:] if tail is None else tail)


@pytest.mark.parametrize("length, code", [
    (b"\x85\x00", "BAD_CHUNK_LENGTH"),  # 5 in two bytes
    (b"\x85\x80\x80\x80\x00", "BAD_CHUNK_LENGTH"),  # 5 in five bytes: not minimal, though at most 5 bytes
    (b"\x85\x80\x80\x80\x80\x00", "CHUNK_TOO_LONG"),  # a fifth byte with bit 7 set
    (b"\xff\xff\xff\xff\x07", "LIMIT_EXCEEDED"),  # 2^31 - 1: no longer than 2^31 - 1, above the chunk limit
    (b"\x80\x80\x80\x80\x08", "CHUNK_TOO_LONG"),  # 2^31
    (b"\xff\xff\xff\xff\x0f", "CHUNK_TOO_LONG"),  # 2^32 - 1
])
def test_length_varints(length, code):
    assert error(with_objt_length(length)) == code


def test_the_framing_s_order():
    data = pln(CUBE_LIKE)
    at = len(SIGNATURE) + 12 + len(phdr())
    assert error(data[:at + 3]) == "TRUNCATED"  # inside the type
    assert error(data[:at + 4]) == "TRUNCATED"  # after the type, before the length
    bad_type = data[:at] + b"OB1T" + b"\x85\x00"  # the type before the length (steps 1-3)
    assert error(bad_type) == "BAD_CHUNK_TYPE"
    assert error(data[:at] + b"OBJT\x85\x80") == "TRUNCATED"  # inside the varint
    assert error(data[:at] + b"OBJT\x85\x80\x80\x80\x80") == "CHUNK_TOO_LONG"  # needs no sixth byte
    assert error(data[:at] + b"OBJT\x85\x00") == "BAD_CHUNK_LENGTH"  # before the payload is looked for
    assert error(data[:-1]) == "TRUNCATED"
    assert data[-9:] == varint_chunk(b"PEND", b"")  # §4.4: a 9-byte PEND


def test_a_second_phdr_is_framed_as_every_chunk_after_the_first():
    """SPEC_NOTES 52: in a version 5 file every chunk after the first has a varint length, a second
    PHDR too, which is then DUPLICATE_HEADER; framed with a u32 its CRC is read in the wrong place."""
    assert error(pln([(b"PHDR", phdr())] + CUBE_LIKE)) == "DUPLICATE_HEADER"
    at = len(SIGNATURE) + 12 + len(phdr())
    data = pln(CUBE_LIKE)
    assert error(data[:at] + u32_chunk(b"PHDR", phdr()) + data[at:]) == "CRC_MISMATCH"


def test_version_4_framing_and_grids_stay():
    """A.5: a version 4.2 file has u32 lengths and 32-byte grids and no group without references."""
    v4 = phdr(major=4, minor=2)
    walk = group(0, 9, [0], walk_data(F64_GRID))
    chunks = [(b"OBJT", objt(0)), (b"PLNS", plns([[0.0, 0.0, 1.0]], 0)), (b"GRUP", walk)]
    got = read(pln(chunks, header=v4, index=True))
    assert "error" not in got, got
    assert got["groups"][0]["shell"] == TET_SHELL
    assert error(pln(chunks, header=v4, framing=varint_chunk)) in ("CRC_MISMATCH", "TRUNCATED")
    assert error(pln([(b"OBJT", objt(0)), (b"GRUP", group(0, 9, [], walk_data(F64_GRID)))], header=v4)) \
        == "BAD_GROUP_STRUCTURE"
    # a version 5 walk with the 32 bytes of version 4: 16 bytes too many where the coordinates end
    assert error(pln([(b"OBJT", objt(0)), (b"GRUP", group(0, 9, [], walk_data(F64_GRID)))])) == "BAD_GROUP_STRUCTURE"


# --- header (§5) ----------------------------------------------------------------------------------

def test_header_checks():
    assert error(pln(CUBE_LIKE, header=phdr()[:8])) == "BAD_PAYLOAD"  # the fixed part, no tolerance
    assert error(pln(CUBE_LIKE, header=phdr()[:7])) == "BAD_PAYLOAD"
    assert error(pln(CUBE_LIKE, header=phdr(coding=4)[:8])) == "UNSUPPORTED_CODING"  # step 4 before step 5
    assert error(pln(CUBE_LIKE, header=phdr(coding=4))) == "UNSUPPORTED_CODING"
    assert error(pln(CUBE_LIKE, header=phdr(up=3))) == "BAD_HEADER_VALUE"
    assert error(pln(CUBE_LIKE, header=phdr(units=8))) == "BAD_HEADER_VALUE"
    assert error(pln(CUBE_LIKE, header=phdr(major=7))) == "UNSUPPORTED_VERSION"  # 6 is read since 6.0
    # A.5: in a version 4 header units is the unit alone: 0x21 is above 7
    v4 = [(b"OBJT", objt(0)), (b"PLNS", plns([[0.0, 0.0, 1.0]], 0)), (b"GRUP", group(0, 0, [0], b""))]
    assert error(pln(v4, header=phdr(major=4, minor=2, units=1, up=2))) == "BAD_HEADER_VALUE"


def test_up_axis_in_meta():
    """§10.3: a version 5 file says its up axis in the header; an mETA up_axis is BAD_METADATA there,
    whatever its value, and allowed in a version 4 file."""
    for value in (b"Z", b"Y", b"X"):
        assert error(pln([(b"mETA", b"up_axis\x00" + value)] + CUBE_LIKE)) == "BAD_METADATA"
    v4 = [(b"mETA", b"up_axis\x00Z"), (b"OBJT", objt(0)), (b"PLNS", plns([[0.0, 0.0, 1.0]], 0)),
          (b"GRUP", group(0, 0, [0], b""))]
    assert read(pln(v4, header=phdr(major=4, minor=2)))["metadata"] == {"up_axis": "Z"}


# --- groups without references (§9.2) -------------------------------------------------------------

@pytest.mark.parametrize("kind", [0, 1, 2, 3, 4, 5])
def test_no_references_in_kinds_0_to_5(kind):
    assert error(pln([(b"OBJT", objt(0)), (b"GRUP", group(0, kind, [], b"\x00"))])) == "BAD_GROUP_STRUCTURE"


def test_no_references_in_a_kind_of_a_newer_minor_version():
    """§9.2 step 2: a kind of a newer minor version decides for itself, so a reader that skips it
    accepts m = 0 (SPEC_NOTES 56); version 4 rejects m = 0 in every kind (A.5)."""
    chunks = [(b"OBJT", objt(0)), (b"GRUP", group(0, 14, [], b"\x01\x02"))]
    got = read(pln(chunks, header=phdr(minor=3)))
    assert "error" not in got, got
    assert set(got["findings"]) == {"SKIPPED_GROUP_KIND", "NEWER_MINOR_VERSION"}
    assert error(pln(chunks, header=phdr(minor=2))) == "UNKNOWN_GROUP_KIND"  # 5.2 has no kind 14
    assert error(pln(chunks, header=phdr(major=4, minor=3))) == "BAD_GROUP_STRUCTURE"


def test_a_shell_without_references_names_no_plane():
    """§9.10-§9.13 with m = 0: a face code naming a reference, or a named corner, is beyond m."""
    data = bytearray(walk_data(F32_GRID))
    faces_at = 3 + 4 + 3  # the counts, the symbols, the escapes
    data[faces_at] = 2  # triangle 0 on local reference 0
    assert error(pln([(b"OBJT", objt(0)), (b"GRUP", group(0, 9, [], bytes(data)))])) == "BAD_GROUP_STRUCTURE"
    got = read(pln([(b"OBJT", objt(0)), (b"GRUP", group(0, 10, [], walk_data(F32_GRID)))]))
    assert "error" not in got and got["groups"][0]["refs"] == []  # kind 10 alike
