"""Version 5.0 (spec/pln.md §4.1, §5, §9.2, §9.10, §10.1) in the independent reader
conformance/independent/plnread.py, on hand-built files: the points the version 5.0 goldens do not
decide. Every file is assembled from the text of the spec (§3 signature, §4.1 framing: PHDR's u32
length, then varint32 lengths; §5 the 8-byte fixed header; §8 objects; §9.1-§9.2 groups; §9.10 a
shell of explicit corners and free triangles on an f32 grid), not from planefmt nor the suite's
generator: a length varint of two bytes, read from a file and from a pipe; the framing checks in the
order of §4.1; the ignored bits 6-7 of the units byte; and m = 0 by kind and version."""

from __future__ import annotations

import struct

from spec_files import SIGNATURE, grup, objt, phdr, read_pipe, u32_chunk, uv, varint_chunk, zigzag
from spec_files import read_read as read


def header(major=5, minor=0, units=1) -> bytes:
    """§5: version 5's 8-byte fixed part (flags a u8: none; coding 0; widths 0; units), then
    tolerance and error bound NaN; version 4's 9-byte one (flags a u16) for major 4."""
    return u32_chunk(b"PHDR", phdr(major, minor, units=units))


# §9.10, version 5: a shell without references (m = 0, no roles): three explicit corners on an f32
# grid (origin 0.1, 0, 0, step 0.5), one free triangle
ORIGIN = struct.unpack("<f", struct.pack("<f", 0.1))[0]
PLANELESS_SHELL = (uv(0) + uv(3) + uv(1) + uv(1) + bytes([0b111]) + struct.pack("<4f", 0.1, 0.0, 0.0, 0.5)
                   + b"".join(uv(zigzag(d)) for d in (0, 0, 0, 1, 0, 0, -1, 1, 0)) + uv(0) + uv(0) + uv(0))


def v5_file(*chunks: tuple[bytes, bytes], units=1, minor=0) -> bytes:
    return (SIGNATURE + header(5, minor, units) + b"".join(varint_chunk(t, p) for t, p in chunks)
            + varint_chunk(b"PEND", b""))


def test_two_byte_length_varint_from_a_file_and_a_pipe():
    name = "n" * 200  # an OBJT payload of 205 bytes: its length the varint CD 01
    data = v5_file((b"OBJT", objt(0, name.encode())), (b"GRUP", grup(0, 0, 6, PLANELESS_SHELL)))
    assert data[8 + 12 + 16:8 + 12 + 16 + 6] == b"OBJT\xcd\x01"
    for got in (read(data), read_pipe(data)):
        assert got["header"]["version"] == [5, 0]
        assert got["objects"] == [{"name": name, "parent": None, "transform": None}]
        shell = got["groups"][0]["shell"]
        assert got["groups"][0]["refs"] == [] and shell["origin"] == [ORIGIN, 0.0, 0.0]
        assert shell["step"] == 0.5 and shell["grid"] == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
        assert shell["facets"] == [[-1, 0, 1, 2]]


def test_framing_checks_in_the_order_of_section_4_1():
    base = SIGNATURE + header()
    # a bad type is BAD_CHUNK_TYPE before the input ends inside the varint
    assert read_pipe(base + b"OB1T")["error"] == "BAD_CHUNK_TYPE"
    assert read_pipe(base + b"OBJ")["error"] == "TRUNCATED"
    assert read_pipe(base + b"OBJT\x80")["error"] == "TRUNCATED"
    # five bytes ending in 0x00: not minimal, before "too long"
    assert read(base + b"OBJT\x80\x80\x80\x80\x00")["error"] == "BAD_CHUNK_LENGTH"
    # 2^31 - 1 in five bytes is the format's maximum, above the reader's limit; 2^28 + 1 in four bytes too
    assert read_pipe(base + b"OBJT\xff\xff\xff\xff\x07")["error"] == "LIMIT_EXCEEDED"
    assert read_pipe(base + b"OBJT" + uv(2**28 + 1))["error"] == "LIMIT_EXCEEDED"
    assert read_pipe(base + b"OBJT\x80\x80\x80\x80\x10")["error"] == "CHUNK_TOO_LONG"


def test_units_byte_bits_6_and_7_are_ignored():
    got = read(v5_file((b"OBJT", objt(0)), units=0xC1 | (2 << 4)))
    assert got["header"]["units"] == 1 and got["metadata"] == {"up_axis": "Z"}
    got = read(v5_file((b"OBJT", objt(0)), units=0xC1))
    assert got["header"]["units"] == 1 and got["metadata"] == {}
    assert read(v5_file((b"OBJT", objt(0)), units=8))["error"] == "BAD_HEADER_VALUE"


def test_no_references_by_kind_and_version():
    # a copy of a shell without references has none either (§9.2, §9.15)
    copy = uv(0) + uv(0)  # m = 0, source 0
    got = read(v5_file((b"OBJT", objt(0)), (b"GRUP", grup(0, 0, 6, PLANELESS_SHELL)),
                       (b"GRUP", grup(1, 0, 11, copy))))
    assert got["groups"][1] == {"index": 1, "object": 0, "kind": 11, "refs": [], "bounding": [], "source": 0}
    # kinds 0 to 5 need one (kind 5 here; kind 0 is xv50_convex_no_refs)
    assert read(v5_file((b"OBJT", objt(0)), (b"GRUP", grup(0, 0, 5, uv(0)))))["error"] == "BAD_GROUP_STRUCTURE"
    # a kind of a newer minor version (14 in 5.3) decides for itself: skipped, m = 0 accepted
    got = read(v5_file((b"OBJT", objt(0)), (b"GRUP", grup(0, 0, 14, uv(0) + b"\x2a")), minor=3))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and got["groups"][0]["refs"] == []
    # before version 5 every group has one (Appendix A.5), a shell of 4.2 too
    old = (SIGNATURE + header(4, 2) + u32_chunk(b"OBJT", objt(0))
           + u32_chunk(b"GRUP", grup(0, 0, 6, PLANELESS_SHELL)) + u32_chunk(b"PEND", b""))
    assert read(old)["error"] == "BAD_GROUP_STRUCTURE"


def test_a_later_colr_of_a_group_replaces_the_earlier_one():
    # §10.1: the last cOLR of a group applies; the group is listed once, where its first cOLR was
    planes = [(0.0, 0.0, 1.0)]
    plns_payload = uv(0) + uv(1) + b"\x00" + uv(12) + struct.pack("<3f", *planes[0])
    body = uv(1) + uv(0) + b"\x00"  # one reference, plane 0, no role bits
    colr = lambda group, rgba: struct.pack("<II", group, 1) + bytes(rgba)  # noqa: E731
    got = read(v5_file((b"PLNS", plns_payload), (b"OBJT", objt(0)), (b"GRUP", grup(0, 0, 0, body)),
                       (b"GRUP", grup(1, 0, 0, body)), (b"cOLR", colr(0, [1, 2, 3, 4])),
                       (b"cOLR", colr(1, [9, 9, 9, 9])), (b"cOLR", colr(0, [5, 6, 7, 8]))))
    assert got["colours"] == [{"group": 0, "rgba": [[5, 6, 7, 8]]}, {"group": 1, "rgba": [[9, 9, 9, 9]]}]
