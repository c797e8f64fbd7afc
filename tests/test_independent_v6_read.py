"""Version 6.0 (spec/pln.md §2.2 r32, §4.2-§4.6 body segments and records, §5 the compact header,
§10.1 colours, §10.2 the index) in the independent reader conformance/independent/plnread.py, on
hand-built files. Every file is assembled from the text of the spec (spec_files: r32, phdr6, record,
segment, v6_file, index6), not from planefmt nor the suite's generator: the unit cube of §5's
example in PHDR's own segment, a scene of two objects with colours, records spread over PHDR and
BODY chunks of every compression method, the index, and one file per check the version adds."""

from __future__ import annotations

import json
import math
import struct

import pytest

from spec_files import (SIGNATURE, colr6, group_body, grup6, index6, objt6, phdr, phdr6, plns6, plnread, plnspec,
                        r32, read_pipe, read_read, read_spec, record, segment, u32_chunk, uv, v6_file, v6_layout,
                        v6_records, varint_chunk, SUITE)


def read(data: bytes) -> dict:
    """plnread's answer, which plnspec, the other independent reader, must give too (its result or
    its error code)."""
    got = read_read(data)
    other = read_spec(data)
    if "error" in got:
        assert other.get("error") == got["error"], (got, other)
    else:
        assert json.loads(json.dumps(other)) == got
    return got

PI = math.pi


def f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


# §7.3 with widths 2, 2, 1 and h range [0, 1]: nu codes 0..2 (0, pi/2, pi), phi codes 0..3, h codes 0..1
CUBE_CODES = [(0, 0, 1), (2, 0, 1), (1, 0, 1), (1, 2, 1), (1, 1, 1), (1, 3, 1)]
CUBE_PLANES = [[qn * PI / 2, qp * 2 * PI / 4, float(qh)] for qn, qp, qh in CUBE_CODES]


def quantized(codes, bits=(2, 2, 1)) -> bytes:
    """§7.3: the records (q_nu, q_phi, q_h) as one bit string, least significant bit first."""
    value, at = 0, 0
    for rec in codes:
        for q, b in zip(rec, bits):
            value |= q << at
            at += b
    return value.to_bytes((at + 7) // 8, "little")


def cube_header(**kw) -> bytes:
    """§5's example: LOSSY, coding 2, widths 2, 2, 1, h range [0, 1], metre, tolerance and error 0."""
    return phdr6(flags=1, coding=2, bits=(2, 2, 1), h_range=(0.0, 1.0), tolerance=0.0, error_bound=0.0, **kw)


def cube_records(name=b"cube"):
    return [record(1, objt6(name)), record(2, uv(6) + quantized(CUBE_CODES)),
            record(3, grup6(0, 0, group_body(range(6), [], b"")))]


def cube(**kw) -> bytes:
    return v6_file(cube_header(), segment(cube_records()), **kw)


F32_PLANES = [[f32(x) for x in p] for p in ([0, 0, 0.5], [PI, 0, 0.5], [PI / 2, 0, 0.5], [PI / 2, PI, 0.5],
                                            [PI / 2, PI / 2, 0.5], [PI / 2, 3 * PI / 2, 0.5])]


def f32_header(**kw) -> bytes:
    """§5: coding 0 (float32 planes), metre, tolerance and error bound NaN, unless ``kw`` says otherwise."""
    return phdr6(**kw)


def cube_f32_records(obj=0, first=0):
    return [record(2, plns6(F32_PLANES)), record(3, grup6(obj, 0, group_body(range(first, first + 6), [], b"")))]


# --- r32 (§2.2) -----------------------------------------------------------------------------------

def test_r32_examples_of_section_2_2():
    examples = {0.0: "00", 1.0: "fc03", -1.0: "fd03", 0.5: "fc01"}
    for value, text in examples.items():
        assert r32(value).hex() == text
        assert plnread.Cursor(bytes.fromhex(text), "t").r32() == value
        assert plnspec.r32(plnspec.Cursor(bytes.fromhex(text)), "t") == value
    assert r32(math.nan).hex() == "fe07" and math.isnan(plnread.Cursor(b"\xfe\x07", "t").r32())
    # any f32 in at most 5 bytes, read back exactly
    for value in (f32(0.1), -f32(3.4e38), f32(1e-40), math.inf):
        assert len(r32(value)) <= 5 and plnread.Cursor(r32(value), "t").r32() == value


# --- the cube (§5's example), one segment in PHDR ---------------------------------------------------

def test_cube_header_is_the_example_of_section_5_and_the_file_reads():
    header = cube_header()
    # header_size 9: flags, units, widths (2), h_min (1), h_max (2), tolerance, error bound
    assert header.hex() == "060009110121" + "00" + "00fc03" + "0000"
    data = cube()
    assert b"BODY" not in data
    for got in (read(data), read_pipe(data)):
        assert got["header"] == {"version": [6, 0], "lossy": True, "coding": 2, "bits": [2, 2, 1],
                                 "h_range": [0.0, 1.0], "units": 1, "bbox": None, "tolerance": 0.0,
                                 "error_bound": 0.0, "counts": None}
        assert got["planes"] == CUBE_PLANES
        assert got["objects"] == [{"name": "cube", "parent": None, "transform": None}]
        assert got["groups"] == [{"index": 0, "object": 0, "kind": 0, "refs": list(range(6)), "bounding": []}]
        assert got["findings"] == [] and got["colours"] == [] and got["metadata"] == {}


def test_cube_with_bbox_and_counts():
    header = cube_header(bbox=(-0.5, -0.5, -0.5, 0.5, 0.5, 0.5), counts=(6, 1, 1))
    got = read(v6_file(header, segment(cube_records())))
    assert got["header"]["bbox"] == [[-0.5] * 3, [0.5] * 3]
    assert got["header"]["counts"] == {"planes": 6, "objects": 1, "groups": 1}
    bad = cube_header(counts=(6, 2, 1))
    assert read(v6_file(bad, segment(cube_records())))["error"] == "COUNT_MISMATCH"


def test_header_ignored_bits_and_later_fields():
    # flags bits 5-7 and widths bit 15 are ignored; header bytes past the known fields are a newer
    # minor's: skipped, whatever they hold
    header = bytearray(cube_header())
    header[3] |= 0xE0
    header[6] |= 0x80
    assert read(v6_file(bytes(header), segment(cube_records())))["planes"] == CUBE_PLANES
    later = cube_header(minor=1, later=b"\xff\x00\x07")
    got = read(v6_file(later, segment(cube_records())))
    assert got["planes"] == CUBE_PLANES and got["findings"] == ["NEWER_MINOR_VERSION"]
    assert got["header"]["version"] == [6, 1]
    # the up axis in units bits 4-5, reported as metadata; a coding 0 header has no widths, no h range
    got = read(v6_file(phdr6(units=1 | 2 << 4), segment([record(1, objt6())])))
    assert got["metadata"] == {"up_axis": "Z"} and got["header"]["bits"] == [0, 0, 0]


def test_header_checks():
    base = cube_header()
    # header_size past the payload (no segment follows)
    assert base[2] == 9
    assert read(v6_file(b"\x06\x00\x0a" + base[3:]))["error"] == "BAD_PAYLOAD"
    # header_size below the fields the flags and coding call for (the error bound outside), and below 2
    short = b"\x06\x00\x08" + base[3:-1]
    assert read(v6_file(short))["error"] == "BAD_PAYLOAD"
    assert read(v6_file(b"\x06\x00\x01\x00"))["error"] == "BAD_PAYLOAD"
    assert read(v6_file(b"\x06\x00"))["error"] == "BAD_PAYLOAD"
    # header_size not minimal; an r32 not minimal; an r32 of 2^32
    assert read(v6_file(b"\x06\x00\x8a\x00" + base[3:]))["error"] == "BAD_PAYLOAD"
    fields = bytes([0x11, 1, 0x21, 0]) + b"\x00" + b"\xfc\x83\x00" + b"\x00\x00"
    assert read(v6_file(b"\x06\x00" + uv(len(fields)) + fields))["error"] == "BAD_PAYLOAD"
    fields = bytes([0, 1]) + b"\x80\x80\x80\x80\x10" + b"\x00"
    assert read(v6_file(b"\x06\x00" + uv(len(fields)) + fields))["error"] == "BAD_PAYLOAD"
    # values: the h range, the units, the bbox, the tolerance
    for kw in ({"h_range": (1.0, 0.0)}, {"h_range": (0.0, math.inf)}, {"h_range": (math.nan, 1.0)}):
        header = phdr6(coding=3, bits=(2, 2, 1), **kw)
        assert read(v6_file(header))["error"] == "BAD_HEADER_VALUE"
    assert read(v6_file(phdr6(units=8)))["error"] == "BAD_HEADER_VALUE"
    assert read(v6_file(phdr6(units=1 | 3 << 4)))["error"] == "BAD_HEADER_VALUE"
    assert read(v6_file(phdr6(bbox=(0, 0, 1, 1, 1, 0))))["error"] == "BAD_HEADER_VALUE"
    assert read(v6_file(phdr6(tolerance=-1.0)))["error"] == "BAD_HEADER_VALUE"
    assert read(v6_file(phdr6(error_bound=math.inf)))["error"] == "BAD_HEADER_VALUE"
    # a version 7 file
    assert read(SIGNATURE + u32_chunk(b"PHDR", b"\x07\x00") + varint_chunk(b"PEND", b""))["error"] == \
        "UNSUPPORTED_VERSION"


# --- a scene of two objects with colours -------------------------------------------------------------

def scene_records():
    red, blue = bytes([255, 0, 0, 255]), bytes([0, 0, 255, 128])
    per_ref = b"".join(bytes([k, 2 * k, 3 * k, 255]) for k in range(6))
    return [record(1, objt6(b"first")), *cube_f32_records(0, 0), record(4, colr6(0, 6, red)),
            record(1, objt6(b"second", parent=0)), *cube_f32_records(1, 6), record(4, colr6(1, 6, per_ref)),
            record(4, colr6(0, 6, blue))], red, blue, per_ref


def test_scene_of_two_objects_with_colours_in_body_chunks():
    records, red, blue, per_ref = scene_records()
    for method in (0, 1, 2):
        data = v6_file(f32_header(counts=(12, 2, 2)), None, [segment(records[:4], method), segment(records[4:], method)])
        for got in (read(data), read_pipe(data)):
            assert got["objects"] == [{"name": "first", "parent": None, "transform": None},
                                      {"name": "second", "parent": 0, "transform": None}]
            assert got["planes"] == F32_PLANES * 2
            assert [(g["index"], g["object"], g["refs"]) for g in got["groups"]] == \
                [(0, 0, list(range(6))), (1, 1, list(range(6, 12)))]
            # §10.1: group 0's second colours record replaces its first (red), listed where that was
            assert got["colours"] == [{"group": 0, "rgba": [list(blue)] * 6},
                                      {"group": 1, "rgba": [list(per_ref[4 * k:4 * k + 4]) for k in range(6)]}]


def test_colours_record_checks():
    head = [record(1, objt6()), *cube_f32_records()]
    for colours, code in ((colr6(1, 6, b"\x00" * 4), "BAD_COLOURS"),  # a group not read yet
                          (colr6(0, 5, b"\x00" * 20), "BAD_COLOURS"),  # a count other than ref_count
                          (colr6(0, 6, b"\x00" * 28), "BAD_COLOURS"),  # bytes after the colours
                          (colr6(0, 6, b"\x00" * 8), "BAD_PAYLOAD"),  # ends inside the colours
                          (uv(0), "BAD_PAYLOAD"),  # ends inside the count
                          (b"\x80\x00\x06", "BAD_PAYLOAD")):  # a group varint not minimal
        got = read(v6_file(f32_header(), segment(head + [record(4, colours)])))
        assert got["error"] == code, colours
    # colours before their group
    got = read(v6_file(f32_header(), segment([record(1, objt6()), record(4, colr6(0, 6, b"\x00" * 4)),
                                               *cube_f32_records()])))
    assert got["error"] == "BAD_COLOURS"


# --- segments and records (§4.5, §4.6) ---------------------------------------------------------------

def test_records_spread_over_phdr_and_body_chunks_of_every_method():
    records = [record(5, b"author\x00me"), record(1, objt6()), *cube_f32_records(), record(200, b"xyz")]
    data = v6_file(f32_header(), segment(records[:2], 1), [segment(records[2:3], 2), segment([], 0),
                                                           segment(records[3:], 1)])
    got = read(data)
    assert got["metadata"] == {"author": "me"} and got["findings"] == ["UNKNOWN_ANCILLARY_CHUNK"]
    assert got["groups"][0]["refs"] == list(range(6)) and got["planes"] == F32_PLANES
    # an unknown ancillary chunk among the BODY chunks is skipped
    got = read(v6_file(f32_header(), segment(records[:2]), [segment(records[2:4])], chunks=[(b"zZzZ", b"1")]))
    assert got["findings"] == ["UNKNOWN_ANCILLARY_CHUNK"]


def test_segment_checks():
    one = [record(1, objt6())]
    raw = b"".join(one)
    cases = {
        "empty BODY": (b"", "BAD_PAYLOAD"),
        "ends inside raw_size": (b"\x00\x80", "BAD_PAYLOAD"),
        "raw_size not minimal": (b"\x00\x83\x00" + raw, "BAD_PAYLOAD"),
        "method 3": (b"\x03" + uv(len(raw)) + raw, "BAD_COMPRESSION"),
        "stored size": (b"\x00" + uv(len(raw) + 1) + raw, "SIZE_MISMATCH"),
        "deflated size": (b"\x01" + uv(len(raw) + 1) + segment(one, 1)[2:], "SIZE_MISMATCH"),
        "bad zlib": (b"\x01" + uv(len(raw)) + b"\x00" * 8, "BAD_COMPRESSION"),
        "ratio": (b"\x01" + uv(1100 * 8 + 1) + b"\x00" * 8, "LIMIT_EXCEEDED"),
        "raw limit": (b"\x00" + uv(256 * 1024 * 1024 + 1), "LIMIT_EXCEEDED"),
    }
    for what, (body, code) in cases.items():
        got = read(v6_file(f32_header(), None, [body]))
        assert got["error"] == code, what
        assert "BODY" in got["why"] or code in ("SIZE_MISMATCH", "BAD_COMPRESSION", "LIMIT_EXCEEDED"), what
        # the same segment in PHDR (where it is not empty)
        if body:
            assert read(v6_file(f32_header(), body))["error"] == code, what


def test_record_checks():
    obj = record(1, objt6())
    cases = {
        "ends inside the length": (obj + b"\x02", "BAD_PAYLOAD"),
        "ends inside the tag's length varint": (obj + b"\x02\x80", "BAD_PAYLOAD"),
        "length past the segment": (obj + b"\x02\x10" + b"\x00" * 15, "BAD_PAYLOAD"),
        "length not minimal": (obj + b"\x01\x85\x00" + objt6(), "BAD_PAYLOAD"),
        "tag 0": (obj + record(0, b""), "UNKNOWN_CRITICAL_CHUNK"),
        "tag 6": (obj + record(6, b"ab"), "UNKNOWN_CRITICAL_CHUNK"),
        "tag 127": (obj + record(127, b""), "UNKNOWN_CRITICAL_CHUNK"),
        "metadata after an object": (obj + record(5, b"a\x00b"), "BAD_METADATA"),
        "up_axis as metadata": (record(5, b"up_axis\x00Y"), "BAD_METADATA"),
        "planes record of the wrong size": (obj + record(2, plns6(F32_PLANES)[:-1]), "SIZE_MISMATCH"),
        "planes record ends inside its count": (obj + record(2, b"\x80"), "BAD_PAYLOAD"),
        "group of a later object": (obj + record(2, plns6(F32_PLANES)) + record(3, grup6(1, 0, group_body(
            range(6), [], b""))), "BAD_OBJECT_REFERENCE"),
        "group of a later plane": (obj + record(2, plns6(F32_PLANES)) + record(3, grup6(0, 0, group_body(
            range(7), [], b""))), "BAD_PLANE_REFERENCE"),
        "group record ends inside its kind": (obj + record(3, uv(0)), "BAD_PAYLOAD"),
        "kind 14 in 6.0": (obj + record(2, plns6(F32_PLANES)) + record(3, grup6(0, 14, group_body(
            range(6), [], b""))), "UNKNOWN_GROUP_KIND"),
        "kind 0 with kind data": (obj + record(2, plns6(F32_PLANES)) + record(3, grup6(0, 0, group_body(
            range(6), [], b"\x00"))), "BAD_PAYLOAD"),
        "a parent not earlier": (record(1, objt6(parent=0)), "BAD_OBJECT"),
        "object record ends inside its name": (record(1, objt6(b"abc")[:-1]), "BAD_PAYLOAD"),
        "object record ends inside its flags": (record(1, b"\x00"), "BAD_PAYLOAD"),
    }
    for what, (raw, code) in cases.items():
        for where in ("PHDR", "BODY"):
            data = (v6_file(f32_header(), bytes([0]) + uv(len(raw)) + raw) if where == "PHDR"
                    else v6_file(f32_header(), None, [bytes([0]) + uv(len(raw)) + raw]))
            got = read(data)
            assert got["error"] == code, (what, where, got)
    # tags 128-255: skipped, whatever their payload
    got = read(v6_file(f32_header(), segment([obj, record(128, b"\xff"), record(255, b"")])))
    assert got["findings"] == ["UNKNOWN_ANCILLARY_CHUNK"] and len(got["objects"]) == 1
    # a kind of a newer minor (6.1) is skipped
    newer = [obj, record(2, plns6(F32_PLANES)), record(3, grup6(0, 14, group_body(range(6), [], b"\x2a")))]
    got = read(v6_file(f32_header(minor=1), segment(newer)))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and got["groups"][0]["kind"] == 14


def test_error_names_the_chunk_and_the_record():
    raw = record(1, objt6()) + record(6, b"")
    reader = plnread.Reader(__import__("io").BytesIO(v6_file(f32_header(), None, [segment([raw])])), None)
    with pytest.raises(plnread.PlnError) as exc:
        reader.read()
    body_offset = 8 + 12 + len(f32_header())
    assert exc.value.chunk == "BODY" and exc.value.offset == body_offset
    assert "raw offset %d" % len(record(1, objt6())) in exc.value.message


def test_version_5_chunks_in_a_version_6_file_and_body_elsewhere():
    for ctype, payload in ((b"OBJT", b"\x00\x00\x00\x01o"), (b"PLNS", b""), (b"GRUP", b""), (b"cOLR", b""),
                           (b"mETA", b"a\x00b")):
        got = read(v6_file(f32_header(), segment([record(1, objt6())]), chunks=[(ctype, payload)]))
        assert got["error"] == "CHUNK_ORDER", ctype
    # BODY after iNDX; BODY in a version 5 file
    data = v6_file(f32_header(), None, index=index6([]))
    pend_at = data.rindex(b"PEND")
    got = read(data[:pend_at] + varint_chunk(b"BODY", segment([])) + data[pend_at:])
    assert got["error"] == "CHUNK_ORDER"
    v5 = SIGNATURE + u32_chunk(b"PHDR", phdr(5, 0)) + varint_chunk(b"BODY", segment([])) + varint_chunk(b"PEND", b"")
    assert read(v5)["error"] == "UNKNOWN_CRITICAL_CHUNK"


# --- the index (§10.2) -------------------------------------------------------------------------------

def indexed_scene():
    """Records in PHDR's segment and two BODY chunks, and the entries of an index of them."""
    records, *_ = scene_records()
    header = f32_header()
    first, bodies = segment(records[:2]), [segment(records[2:4], 1), segment(records[4:], 2)]
    body1 = 8 + 12 + len(header) + len(first)
    body2 = body1 + len(varint_chunk(b"BODY", bodies[0]))
    offs = lambda recs: [sum(map(len, recs[:k])) for k in range(len(recs))]  # noqa: E731
    o0, o1, o2 = offs(records[:2]), offs(records[2:4]), offs(records[4:])
    entries = [(8, o0[0], 1, 0), (8, o0[1], 2, 0), (body1, o1[0], 3, 0),
               (body2, o2[0], 1, 1), (body2, o2[1], 2, 6), (body2, o2[2], 3, 1)]
    return header, first, bodies, entries


def test_index_of_records_in_phdr_and_body_chunks():
    header, first, bodies, entries = indexed_scene()
    data = v6_file(header, first, bodies, index=index6(entries))
    for got in (read(data), read_pipe(data)):
        assert len(got["groups"]) == 2 and got["findings"] == []
    # an empty PEND after an index is allowed
    assert "error" not in read(v6_file(header, first, bodies, index=index6(entries), pend=b""))


def test_index_checks():
    header, first, bodies, entries = indexed_scene()

    def with_index(payload, pend=None):
        return read(v6_file(header, first, bodies, index=payload, pend=pend))["error"]

    wrong = {
        "a raw offset": [entries[0], (8, entries[1][1] + 1, 2, 0)] + entries[2:],
        "a chunk offset": entries[:2] + [(entries[2][0] + 1,) + entries[2][1:]] + entries[3:],
        "a tag": entries[:1] + [(8, entries[1][1], 1, 0)] + entries[2:],
        "an ordinal": entries[:5] + [entries[5][:3] + (0,)],
        "a missing entry": entries[:5],
        "an extra entry": entries + [entries[5]],
        "two entries swapped": [entries[1], entries[0]] + entries[2:],
    }
    for what, bad in wrong.items():
        assert with_index(index6(bad)) == "BAD_INDEX", what
    good = index6(entries)
    assert with_index(good + b"\x00") == "BAD_INDEX"  # bytes after the entries
    assert with_index(good[:-1]) == "BAD_PAYLOAD"  # ends inside the last entry
    assert with_index(b"") == "BAD_PAYLOAD"  # ends inside the count
    assert with_index(uv(2**40)) == "BAD_PAYLOAD"  # a count no payload of this size holds
    assert with_index(good, pend=struct.pack("<Q", 0)) == "BAD_INDEX"
    assert with_index(good, pend=struct.pack("<Q", 9)) == "BAD_INDEX"
    assert with_index(good, pend=b"\x00") == "BAD_PAYLOAD"


def test_place_checks_in_the_order_of_section_12_1():
    # after iNDX a PHDR is CHUNK_ORDER (before DUPLICATE_HEADER); a PHDR elsewhere DUPLICATE_HEADER
    data = v6_file(f32_header(), None, index=index6([]))
    pend_at = data.rindex(b"PEND")
    assert read(data[:pend_at] + varint_chunk(b"PHDR", f32_header()) + data[pend_at:])["error"] == "CHUNK_ORDER"
    got = read(v6_file(f32_header(), None, chunks=[(b"PHDR", f32_header())]))
    assert got["error"] == "DUPLICATE_HEADER"
    # an unknown critical chunk; a CRC error in a BODY chunk before its payload is looked at
    assert read(v6_file(f32_header(), None, chunks=[(b"XBDY", b"")]))["error"] == "UNKNOWN_CRITICAL_CHUNK"
    data = v6_file(f32_header(), None, [b""])
    body_at = data.index(b"BODY")
    bad = data[:body_at + 5] + b"\x00\x00\x00\x00" + data[body_at + 9:]
    assert read(bad)["error"] == "CRC_MISMATCH"


# --- real meshes: the version 5 goldens' records, laid out as version 6 -----------------------------

GOLDENS = sorted(p.name for p in SUITE.glob("valid/*_v5_[0-9].pln"))


@pytest.mark.parametrize("name", GOLDENS)
def test_v5_goldens_as_version_6_read_as_in_version_5(name):
    """Each version 5 golden (meshes of tests/corpus and trimesh's primitives, written by planefmt) as
    version 6 (spec_files.v6_records: the records §4.6 makes of its chunks): in PHDR's segment
    alone, deflated; and a record a BODY chunk, Brotli'd, with an index. Both read as the version 5
    file does, but for the header's version and the h range, now two binary32 values."""
    v5 = (SUITE / "valid" / name).read_bytes()
    want = read(v5)
    kw, records = v6_records(v5)
    header = phdr6(**kw)
    exact_h = all(f32(h) == h for h in kw.get("h_range", ()))
    layouts = [v6_layout(header, records, [len(records)], [1]),
               v6_layout(header, records, [0] + [1] * len(records), [0] + [2] * len(records), with_index=True)]
    for data in layouts:
        got = read(data)
        for key in ("objects", "groups", "colours", "metadata", "findings"):
            assert got[key] == want[key], key
        assert len(got["planes"]) == len(want["planes"])
        if exact_h:
            assert got["planes"] == want["planes"]
        assert got["header"]["version"] == [6, 0]
        for key in ("lossy", "coding", "bits", "units", "bbox", "tolerance", "error_bound", "counts"):
            assert got["header"][key] == want["header"][key], key
