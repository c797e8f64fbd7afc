"""The broken golden files: each is a valid file with exactly one defect, and the error it must raise.

Most start from the cube of spec/pln-1.md §12 (``cube()``), assembled chunk by chunk
from planefmt's payload encoders; the defect is made in a payload before it
is framed (so its CRC is right and the reader gets as far as the defect), or
in the framed bytes where the framing itself is the defect. Offsets in the
cube: PHDR 8, OBJT 128, PLNS 156, GRUP 260, iNDX 317, PEND 381, end 401.

``also`` lists other codes a conforming reader may give where the spec does
not decide between two (see README.md, "Ambiguities").
"""

from __future__ import annotations

import dataclasses
import math
import re
import zlib

import brotli
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planefmt.container import records, schema, segments, shellfields, shellwalk, varint
from planefmt.container.chunks import chunk_bytes
from planefmt.model import Coding, Colours, GroupKind, Header, ObjectRecord, PartGroup, Quantization, Units

from . import reference
from .build import CUBE, SPEC_HEADER, Layout, box, finish, frame, offsets
from .cases_valid import (IN, L_CELLS, L_PLANES, L_TREE, OUT, SEALED_CUBE_FACETS, SEALED_CUBE_VERTICES, SHELL_CUBE,
                          SHELL_MIXED, SHELL_PYRAMID, TREE_APEX, TREE_BOX, TREE_CUBE, TREE_MIXED, TREE_PYRAMID, tree_of)


@dataclass(frozen=True)
class BrokenCase:
    name: str
    error: str
    description: str
    level: str  # "container" or "geometry"
    also: tuple[str, ...]
    make: Callable[[], bytes]


CASES: list[BrokenCase] = []


def case(name: str, error: str, description: str, *, level: str = "container", also: tuple[str, ...] = ()):
    def register(make: Callable[[], bytes]) -> Callable[[], bytes]:
        CASES.append(BrokenCase(name, error, description, level, also, make))
        return make
    return register


# -- the cube of spec/pln-1.md §12 and its parts ------------------------------------------------

def header(**fields) -> bytes:
    """A PHDR payload: spec/pln-1.md §12's header with counts 6 / 1 / 1, fields replaced."""
    h = dataclasses.replace(SPEC_HEADER, plane_count=6, object_count=1, group_count=1)
    return records.encode_header(dataclasses.replace(h, **fields))


def objt(index: int = 0, name: str = "cube", parent: int | None = None, transform=None) -> bytes:
    return records.encode_object(ObjectRecord(index, name, parent, transform))


def plns(triplets=CUBE, first: int = 0, head: Header = SPEC_HEADER) -> bytes:
    return records.encode_planes(first, np.asarray(triplets), head, False)


def plns_raw(data: bytes, count: int = 6, *, first: int = 0, compression: int = 0,
             raw_size: int | None = None) -> bytes:
    """A PLNS payload around triplet data the encoder would refuse to write."""
    return schema.PlaneBlock.build(dict(first=first, count=count, compression=compression, reserved=b"\0\0\0",
                                        raw_size=len(data) if raw_size is None else raw_size, data=data))


def grup(refs=range(6), *, index: int = 0, obj: int = 0, kind: int = 0, bounding=None, cells=None,
         tree=None, extra: bytes = b"") -> bytes:
    refs = np.array(list(refs), dtype=np.uint32)
    roles = np.zeros(len(refs), bool) if bounding is None else np.array(bounding, bool)
    cells = None if cells is None else tuple(np.array(c, dtype=np.uint32) for c in cells)
    tree = None if tree is None else np.array(tree, dtype=np.uint32)
    return records.encode_group(PartGroup(index, obj, kind, refs, roles, cells, tree, extra), False)


def grup_raw(body: bytes, *, kind: int = 0, compression: int = 0, raw_size: int | None = None) -> bytes:
    """A GRUP payload around a body the encoder would refuse to write."""
    return schema.GroupHead.build(dict(index=0, object=0, kind=kind, compression=compression, reserved=b"\0\0",
                                       raw_size=len(body) if raw_size is None else raw_size, body=body))


def body(refs=range(6), roles: bytes | None = None, extra: bytes = b"") -> bytes:
    refs = np.array(list(refs), dtype="<u4")
    roles = bytes((len(refs) + 7) // 8) if roles is None else roles
    return schema.GroupBody.build(dict(ref_count=len(refs), refs=refs.tobytes(), roles=roles, extra=extra))


def cube(**parts: bytes) -> Layout:
    """The chunks of the spec/pln-1.md §12 cube before iNDX; ``PHDR=``, ``OBJT=``, ... replace one payload."""
    default = {"PHDR": header(), "OBJT": objt(), "PLNS": plns(), "GRUP": grup()}
    default.update(parts)
    return [(t.encode(), p) for t, p in default.items()]


def file(layout: Layout, index: bool = True) -> bytes:
    return frame(finish(layout, index))


CUBE_FILE = file(cube())
PHDR_AT, OBJT_AT, PLNS_AT, GRUP_AT, INDX_AT, PEND_AT = offsets(finish(cube()))


def patched(data: bytes, at: int, new: bytes) -> bytes:
    return data[:at] + new + data[at + len(new):]


def f32_bits(bits: int) -> float:
    return float(np.frombuffer(bits.to_bytes(4, "little"), "<f4")[0])


def geometry_defect(code: str, kind: int, triplets, bounding=None, cells=None, tree=None, vertex_planes=None,
                    facets=None, shell=None) -> None:
    """Check, with the reference decoder, that the planes really have the stated defect."""
    bounding = np.zeros(len(triplets), bool) if bounding is None else np.array(bounding, bool)
    try:
        reference.summary(kind, np.asarray(triplets), bounding, cells, tree, vertex_planes, facets, shell)
    except reference.Defect as exc:
        if exc.code == code:
            return
        raise AssertionError(f"expected {code}, the reference says {exc.code}") from None
    raise AssertionError(f"expected {code}, the reference decodes the group")


# -- signature (spec §3) -----------------------------------------------------------------------

@case("xsig_foreign", "BAD_SIGNATURE", "a PNG signature in front of the cube's chunks")
def _():
    return b"\x89PNG\r\n\x1a\n" + CUBE_FILE[8:]


@case("xsig_crlf_to_lf", "TEXT_MODE_DAMAGE", "the cube after a CR LF -> LF conversion (DOS to Unix text mode)",
      also=("BAD_SIGNATURE",))
def _():
    return CUBE_FILE.replace(b"\r\n", b"\n")


@case("xsig_lf_to_crlf", "TEXT_MODE_DAMAGE", "the cube after a LF -> CR LF conversion (Unix to DOS text mode)",
      also=("BAD_SIGNATURE",))
def _():
    return re.sub(rb"(?<!\r)\n", b"\r\n", CUBE_FILE)


@case("xsig_high_bit", "TEXT_MODE_DAMAGE", "the cube with the 8th bit of every byte stripped (7-bit transfer)",
      also=("BAD_SIGNATURE",))
def _():
    return bytes(b & 0x7F for b in CUBE_FILE)


@case("xsig_empty", "TRUNCATED", "an empty file")
def _():
    return b""


@case("xsig_short", "TRUNCATED", "the first 5 bytes of the signature only")
def _():
    return CUBE_FILE[:5]


# -- truncation (spec §4.1, §4.3) --------------------------------------------------------------

@case("xtrunc_head", "TRUNCATED", "ends inside the 8-byte head of the OBJT chunk")
def _():
    return CUBE_FILE[:OBJT_AT + 3]


@case("xtrunc_phdr", "TRUNCATED", "ends inside the PHDR payload")
def _():
    return CUBE_FILE[:PHDR_AT + 8 + 50]


@case("xtrunc_objt", "TRUNCATED", "ends inside the OBJT payload")
def _():
    return CUBE_FILE[:OBJT_AT + 8 + 6]


@case("xtrunc_plns", "TRUNCATED", "ends inside the PLNS payload")
def _():
    return CUBE_FILE[:PLNS_AT + 8 + 40]


@case("xtrunc_grup", "TRUNCATED", "ends inside the GRUP payload")
def _():
    return CUBE_FILE[:GRUP_AT + 8 + 20]


@case("xtrunc_indx", "TRUNCATED", "ends inside the iNDX payload")
def _():
    return CUBE_FILE[:INDX_AT + 8 + 30]


@case("xtrunc_pend", "TRUNCATED", "ends inside the CRC of PEND (2 bytes missing)")
def _():
    return CUBE_FILE[:-2]


@case("xtrunc_no_pend", "TRUNCATED", "ends cleanly after the iNDX chunk: PEND is missing")
def _():
    return CUBE_FILE[:PEND_AT]


# -- CRC (spec §4.1) ---------------------------------------------------------------------------

@case("xcrc_phdr", "CRC_MISMATCH", "one bit of the PHDR payload (bbox) flipped after framing")
def _():
    at = PHDR_AT + 8 + 60
    return patched(CUBE_FILE, at, bytes([CUBE_FILE[at] ^ 0x01]))


@case("xcrc_plns", "CRC_MISMATCH", "one bit of the PLNS triplet data flipped after framing")
def _():
    at = PLNS_AT + 8 + 20 + 5
    return patched(CUBE_FILE, at, bytes([CUBE_FILE[at] ^ 0x10]))


@case("xcrc_ancillary", "CRC_MISMATCH", "an unknown ancillary chunk whose CRC is wrong: every CRC is checked")
def _():
    layout = cube()
    layout.insert(2, (b"nOTE", b"damaged"))
    data = file(layout)
    crc = offsets(layout)[2] + 8 + len(b"damaged")
    return patched(data, crc, bytes([data[crc] ^ 0xFF]))


# -- chunk framing and types (spec §4.1, §4.2) --------------------------------------------------

@case("xchunk_unknown_critical", "UNKNOWN_CRITICAL_CHUNK", "a critical chunk PMAT no version 1 reader knows")
def _():
    layout = cube()
    return file(layout[:2] + [(b"PMAT", b"\0" * 16)] + layout[2:])


@case("xchunk_type_digit", "BAD_CHUNK_TYPE", "the OBJT tag written OB1T: a digit is not a letter")
def _():
    layout = cube()
    layout[1] = (b"OB1T", layout[1][1])
    return file(layout)


@case("xchunk_type_bracket", "BAD_CHUNK_TYPE",
      "the PLNS tag written PL[S: '[' (0x5B) is next to 'Z' but not a letter")
def _():
    layout = cube()
    layout[2] = (b"PL[S", layout[2][1])
    return file(layout)


@case("xchunk_beyond_eof", "TRUNCATED", "the GRUP length says 1045 bytes, 1000 more than the file holds")
def _():
    return patched(CUBE_FILE, GRUP_AT + 4, (45 + 1000).to_bytes(4, "little"))


@case("xchunk_too_long", "CHUNK_TOO_LONG", "the OBJT length is 2^31, above the 2^31-1 maximum",
      also=("LIMIT_EXCEEDED", "TRUNCATED"))
def _():
    return patched(CUBE_FILE, OBJT_AT + 4, (1 << 31).to_bytes(4, "little"))


# -- chunk order (spec §4.3) -------------------------------------------------------------------

@case("xorder_no_header", "MISSING_HEADER", "the file starts with OBJT: no PHDR")
def _():
    return file(cube()[1:])


@case("xorder_two_headers", "DUPLICATE_HEADER", "PHDR twice")
def _():
    layout = cube()
    return file(layout[:1] + layout)


@case("xorder_two_ends", "TRAILING_DATA", "PEND twice: the second is data after the end")
def _():
    return CUBE_FILE + CUBE_FILE[PEND_AT:]


@case("xorder_trailing", "TRAILING_DATA", "a newline after PEND")
def _():
    return CUBE_FILE + b"\n"


# -- header (spec §5) --------------------------------------------------------------------------

@case("xhdr_major6", "SIZE_MISMATCH", "the version 5.0 header of the cube with version 6.0 in its first byte: read "
      "as version 6 (spec §5), header_size 6 holds flags 0, units 0, tolerance 0, error bound 0 and two later "
      "bytes; the body segment after them says method 0 and raw size 0, with 32 bytes stored (spec §6)")
def _():
    # The bytes of version 5's header with major 6 (the case of version 5.2, which rejected major 6).
    phdr = bytearray(header(version=(5, 0)))
    phdr[0] = 6
    return file(cube(PHDR=bytes(phdr)))


@case("xhdr_major7", "UNSUPPORTED_VERSION", "version 7.0: the cube of version 6.0 with major 7")
def _():
    phdr = bytearray(V6_PHDR)
    phdr[0] = 7
    return v6_framed(bytes(phdr) + segment(cube_records()))


@case("xhdr_predicted_v1", "UNSUPPORTED_CODING", "coding 3 (predicted, version 2.0) in a version 1.0 header")
def _():
    h = bytearray(header(coding=Coding.QUANTIZED, quantization=Quantization(16, 16, 16, 0.0, 1.0)))
    h[4] = 3
    return file(cube(PHDR=bytes(h)))


@case("xhdr_major0", "UNSUPPORTED_VERSION", "version 0.9")
def _():
    return file(cube(PHDR=header(version=(0, 9))))


@case("xhdr_coding7", "UNSUPPORTED_CODING", "triplet coding 7")
def _():
    return file(cube(PHDR=header(coding=7)))


def _quantized_cube(bits, h_range=(0.0, 1.0)) -> bytes:
    q = Quantization(*bits, *h_range)
    planes = plns(head=Header(coding=Coding.QUANTIZED, quantization=Quantization(16, 16, 16, 0.0, 1.0)))
    return file(cube(PHDR=header(coding=Coding.QUANTIZED, quantization=q), PLNS=planes))


@case("xhdr_bits0", "UNSUPPORTED_CODING", "quantized coding with bits_nu = 0")
def _():
    return _quantized_cube((0, 16, 16))


@case("xhdr_bits33", "UNSUPPORTED_CODING", "quantized coding with bits_phi = 33")
def _():
    return _quantized_cube((16, 33, 16))


@case("xhdr_h_reversed", "BAD_HEADER_VALUE", "quantized coding with h_min 1 > h_max 0")
def _():
    return _quantized_cube((16, 16, 16), (1.0, 0.0))


@case("xhdr_h_infinite", "BAD_HEADER_VALUE", "quantized coding with h_max = +inf")
def _():
    return _quantized_cube((16, 16, 16), (0.0, math.inf))


@case("xhdr_units", "BAD_HEADER_VALUE", "units code 8, one past foot")
def _():
    return file(cube(PHDR=header(units=8)))


@case("xhdr_bbox_reversed", "BAD_HEADER_VALUE", "BBOX_KNOWN with bbox_min.y 1 > bbox_max.y 0")
def _():
    return file(cube(PHDR=header(bbox=np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 1.0]]))))


@case("xhdr_tolerance", "BAD_HEADER_VALUE", "tolerance -1e-6: neither NaN nor >= 0")
def _():
    return file(cube(PHDR=header(tolerance=-1e-6)))


@case("xhdr_short", "BAD_PAYLOAD", "a PHDR payload of 100 bytes, under the 108 of version 1.0")
def _():
    return file(cube(PHDR=header()[:100]))


@case("xhdr_counts", "COUNT_MISMATCH", "COUNTS_KNOWN with plane_count 7; the file holds 6 planes")
def _():
    return file(cube(PHDR=header(plane_count=7)))


# -- plane table (spec §6, §7) -----------------------------------------------------------------

@case("xplns_first", "PLANE_INDEX_MISMATCH", "the only PLNS block says first = 1")
def _():
    return file(cube(PLNS=plns(first=1)))


@case("xplns_nan", "BAD_TRIPLET", "float32 nu of the first plane is NaN")
def _():
    t = CUBE.astype(np.float32)
    t[0, 0] = np.nan
    return file(cube(PLNS=plns_raw(t.tobytes())))


@case("xplns_inf_h", "BAD_TRIPLET", "float64 h of the first plane is +inf")
def _():
    t = CUBE.copy()
    t[0, 2] = math.inf
    return file(cube(PHDR=header(coding=Coding.FLOAT64), PLNS=plns_raw(t.astype("<f8").tobytes())))


@case("xplns_nu_above_pi", "BAD_TRIPLET",
      "float32 nu = 0x40490FDC, the float after float32(pi) 0x40490FDB which is the largest allowed")
def _():
    t = CUBE.astype(np.float32)
    t[5, 0] = f32_bits(0x40490FDC)
    return file(cube(PLNS=plns_raw(t.tobytes())))


@case("xplns_phi_2pi", "BAD_TRIPLET", "float32 phi = 0x40C90FDB, float32(2 pi): phi must be below it")
def _():
    t = CUBE.astype(np.float32)
    t[0, 1] = f32_bits(0x40C90FDB)
    return file(cube(PLNS=plns_raw(t.tobytes())))


@case("xplns_nu_above_pi_f64", "BAD_TRIPLET", "float64 nu = nextafter(pi, 4), just above float64 pi")
def _():
    t = CUBE.copy()
    t[5, 0] = math.nextafter(math.pi, 4.0)
    return file(cube(PHDR=header(coding=Coding.FLOAT64), PLNS=plns_raw(t.astype("<f8").tobytes())))


@case("xplns_padding", "BAD_PAYLOAD", "quantized 7/9/5: 6 records fill 126 bits, and a padding bit is set")
def _():
    q = Quantization(7, 9, 5, 0.0, 1.0)
    head = Header(coding=Coding.QUANTIZED, quantization=q)
    payload = bytearray(plns(head=head))
    payload[-1] |= 0x80
    return file(cube(PHDR=header(coding=Coding.QUANTIZED, quantization=q), PLNS=bytes(payload)))


@case("xplns_nu_code", "BAD_TRIPLET", "quantized 16/16/16: a nu code 32769, above M_nu = 2^15 (§7.3)")
def _():
    q = Quantization(16, 16, 16, 0.0, 1.0)
    payload = bytearray(plns(head=Header(coding=Coding.QUANTIZED, quantization=q)))
    payload[20:22] = (32769).to_bytes(2, "little")  # 48-bit records: record 0's nu is bytes 0-1 of the data
    return file(cube(PHDR=header(coding=Coding.QUANTIZED, quantization=q), PLNS=bytes(payload)))


@case("xplns_raw_size", "SIZE_MISMATCH", "PLNS raw_size 84 where 6 float32 planes take 72")
def _():
    return file(cube(PLNS=plns_raw(CUBE.astype("<f4").tobytes(), raw_size=84)))


@case("xplns_stored_size", "SIZE_MISMATCH",
      "uncompressed PLNS data of 76 bytes with raw_size 72 (§6: must be equal)", also=("BAD_PAYLOAD",))
def _():
    return file(cube(PLNS=plns_raw(CUBE.astype("<f4").tobytes() + b"\0" * 4, raw_size=72)))


@case("xplns_method2", "BAD_COMPRESSION", "PLNS compression method 2")
def _():
    return file(cube(PLNS=plns_raw(CUBE.astype("<f4").tobytes(), compression=2)))


@case("xplns_zlib_header", "BAD_COMPRESSION", "a zlib stream whose header check bits are wrong")
def _():
    z = bytearray(zlib.compress(CUBE.astype("<f4").tobytes(), 9))
    z[1] ^= 0x01
    return file(cube(PLNS=plns_raw(bytes(z), compression=1, raw_size=72)))


@case("xplns_zlib_short", "SIZE_MISMATCH", "a zlib stream that inflates to 60 bytes, raw_size 72")
def _():
    z = zlib.compress(CUBE.astype("<f4").tobytes()[:60], 9)
    return file(cube(PLNS=plns_raw(z, compression=1, raw_size=72)))


@case("xplns_zlib_long", "SIZE_MISMATCH", "a zlib stream that inflates to 84 bytes, raw_size 72")
def _():
    z = zlib.compress(CUBE.astype("<f4").tobytes() + b"\0" * 12, 9)
    return file(cube(PLNS=plns_raw(z, compression=1, raw_size=72)))


@case("xplns_zlib_unused", "SIZE_MISMATCH", "two bytes follow the end of the zlib stream")
def _():
    z = zlib.compress(CUBE.astype("<f4").tobytes(), 9) + b"\0\0"
    return file(cube(PLNS=plns_raw(z, compression=1, raw_size=72)))


# -- version 2.0 (spec/pln.md A.2) --------------------------------------------------------------

V2_HEAD = Header(version=(2, 0), coding=Coding.PREDICTED, quantization=Quantization(16, 16, 16, 0.0, 1.0),
                 units=Units.METRE)


def v2(PLNS: bytes | None = None, GRUP: bytes | None = None) -> bytes:
    """The cube as a version 2.0 file, predicted 16/16/16 over [0, 1], with one payload replaced."""
    head = header(version=(2, 0), coding=Coding.PREDICTED, quantization=V2_HEAD.quantization)
    planes = records.encode_planes(0, CUBE, V2_HEAD, False) if PLNS is None else PLNS
    group = GRUP or records.encode_group(PartGroup(0, 0, 0, np.arange(6, dtype=np.uint32), np.zeros(6, bool)),
                                         False, 2)
    return file(cube(PHDR=head, PLNS=planes, GRUP=group))


def v2_planes(streams: bytes, raw_size: int | None = None) -> bytes:
    return plns_raw(streams, 6, raw_size=raw_size)


#: The cube's predicted streams (a valid file with them is checked below): 6 nu, 6 phi, 6 h varints.
V2_STREAMS = records.encode_planes(0, CUBE, V2_HEAD, False)[schema.PLANE_BLOCK_HEAD:]
#: Bytes of the streams' first varint (the first plane's nu code, 2^14, zigzagged: 3 bytes).
V2_FIRST = next(i for i, b in enumerate(V2_STREAMS) if b < 0x80) + 1


@case("xv2_predicted_truncated", "BAD_PAYLOAD",
      "version 2.0, predicted planes: the last h varint has its continuation bit set, the data ends inside it")
def _():
    return v2(v2_planes(V2_STREAMS[:-1] + bytes([V2_STREAMS[-1] | 0x80])))


@case("xv2_predicted_extra", "SIZE_MISMATCH", "version 2.0, predicted planes: one byte after the 18 varints")
def _():
    return v2(v2_planes(V2_STREAMS + b"\x00"))


@case("xv2_predicted_raw_size", "SIZE_MISMATCH",
      "version 2.0, predicted planes: raw_size 17, under the 3 bytes a plane the varints need at least")
def _():
    return v2(v2_planes(V2_STREAMS[:17]))


@case("xv2_predicted_negative", "BAD_TRIPLET",
      "version 2.0, predicted planes: the first nu difference is -1 (zigzag 1), a negative nu code")
def _():
    return v2(v2_planes(b"\x01" + V2_STREAMS[V2_FIRST:]))


@case("xv2_predicted_big", "BAD_PAYLOAD", "version 2.0, predicted planes: a varint of 2^33, over the streams' limit")
def _():
    big = bytes([0x80, 0x80, 0x80, 0x80, 0x20])
    return v2(v2_planes(big + V2_STREAMS[V2_FIRST:]))


@case("xv2_varint_overlong", "BAD_PAYLOAD",
      "version 2.0 group body: ref_count 6 written as 86 00, a varint that is not minimal")
def _():
    return v2(GRUP=grup_raw(b"\x86\x00" + bytes(6) + b"\x00"))


@case("xv2_ref_range", "BAD_PLANE_REFERENCE",
      "version 2.0 group body: references 0 1 2 3 4 as differences, then a difference of 2 reaching plane 6")
def _():
    return v2(GRUP=grup_raw(b"\x06\x00\x01\x01\x01\x01\x02\x00"))


@case("xv2_tree_token", "BAD_GROUP_STRUCTURE",
      "version 2.0 BSP body over 6 references: token 8 would split on local reference 6")
def _():
    return v2(GRUP=grup_raw(b"\x06\x00\x01\x01\x01\x01\x01\x00" + b"\x03\x08\x00\x01", kind=2))


@case("xv2_tree_count", "BAD_GROUP_STRUCTURE",
      "version 2.0 BSP body: token_count 200, more tokens than bytes left")
def _():
    return v2(GRUP=grup_raw(b"\x06\x00\x01\x01\x01\x01\x01\x00" + b"\xc8\x01\x02\x00\x01", kind=2))


@case("xv2_v1_body", "BAD_PAYLOAD",
      "a version 1.0 group body (u32 fields) in a version 2.0 file: read as varints, ref_count 6 and six zero "
      "differences, a role byte, then 21 bytes a convex group cannot have")
def _():
    return v2(GRUP=grup())


# -- version 3.0 (spec/pln.md) ------------------------------------------------------------------

def v3(PHDR: bytes | None = None, OBJT: bytes | None = None, PLNS: bytes | None = None, GRUP: bytes | None = None,
       *, index: bool = True, end: bytes | None = None) -> bytes:
    """The cube of spec/pln-1.md §12 as a version 3.0 file, one payload replaced (``end``: the PEND payload)."""
    layout = cube(PHDR=PHDR or header(version=(3, 0)),
                  OBJT=OBJT or records.encode_object(ObjectRecord(0, "cube", None, None), 3),
                  PLNS=PLNS or records.encode_planes(0, CUBE, V3_HEAD, False),
                  GRUP=GRUP or records.encode_group(PartGroup(0, 0, 0, np.arange(6, dtype=np.uint32),
                                                              np.zeros(6, bool)), False, 3))
    layout = finish(layout, index, 3)
    if end is not None:
        layout[-1] = (schema.PEND, end)
    return frame(layout)


V3_HEAD = dataclasses.replace(SPEC_HEADER, version=(3, 0))
#: The version 3 cube's PHDR: 9 fixed bytes, the bbox as 6 float32, tolerance and error bound as
#: float32, then the counts 6, 1, 1 as one-byte varints (no h range: float32 coding).
V3_PHDR = header(version=(3, 0))


@case("xv3_hdr_short", "BAD_PAYLOAD", "version 3.0 PHDR of a quantized coding that ends inside h_max")
def _():
    q = header(version=(3, 0), coding=Coding.QUANTIZED, quantization=Quantization(16, 16, 16, 0.0, 1.0))
    return v3(PHDR=q[:20])


@case("xv3_hdr_counts_short", "BAD_PAYLOAD",
      "version 3.0 PHDR with COUNTS_KNOWN set whose payload ends after the plane count")
def _():
    return v3(PHDR=V3_PHDR[:-2])


@case("xv3_count_mismatch", "COUNT_MISMATCH", "version 3.0 PHDR declaring 2 groups; the file has 1")
def _():
    return v3(PHDR=V3_PHDR[:-1] + b"\x02")


@case("xv3_varint32", "BAD_PAYLOAD", "version 3.0 OBJT whose index is the varint 2^32 (ff ff ff ff 10), over a "
      "varint32")
def _():
    return v3(OBJT=b"\x80\x80\x80\x80\x10" + records.encode_object(ObjectRecord(0, "cube", None, None), 3)[1:],
              index=False)


@case("xv3_head_not_minimal", "BAD_PAYLOAD", "version 3.0 GRUP head whose index 0 is written 80 00, a varint that "
      "is not minimal")
def _():
    g = records.encode_group(PartGroup(0, 0, 0, np.arange(6, dtype=np.uint32), np.zeros(6, bool)), False, 3)
    return v3(GRUP=b"\x80\x00" + g[1:], index=False)


@case("xv3_plns_short", "BAD_PAYLOAD", "version 3.0 PLNS payload that ends inside its raw_size varint")
def _():
    return v3(PLNS=b"\x00\x06\x00\xc8", index=False)


@case("xv3_parent", "BAD_OBJECT", "version 3.0 OBJT of object 0 with parent 1 (object 0 itself): parents are "
      "stored + 1, and must be earlier objects")
def _():
    return v3(OBJT=b"\x00\x01" + records.encode_object(ObjectRecord(0, "cube", None, None), 3)[2:])


@case("xv3_name_cap", "BAD_OBJECT", "version 3.0 OBJT declaring a name of 70000 bytes (over 65535) in a "
      "payload of 8: the cap is checked before the name is looked for")
def _():
    return v3(OBJT=b"\x00\x00\x00\xf0\xa2\x04cube")


@case("xv3_coding_first", "UNSUPPORTED_CODING", "version 3.0 PHDR of 9 bytes with coding 7: the coding is checked "
      "before the fields it would call for are read")
def _():
    return v3(PHDR=bytes([3, 0, 0, 0, 7, 0, 0, 0, 1]))


@case("xv3_pend_size", "BAD_PAYLOAD", "version 3.0 PEND of 4 bytes (only 0 or 8 are allowed)")
def _():
    return v3(index=False, end=bytes(4))


@case("xv3_pend_zero", "BAD_INDEX", "version 3.0 PEND of 8 bytes holding index offset 0 (no index is an empty PEND)")
def _():
    return v3(index=False, end=bytes(8))


@case("xv3_index_in_header", "BAD_INDEX", "version 3.0 iNDX whose OBJT entry points at byte 16, inside the PHDR "
      "chunk (version 3 offsets start after the PHDR payload, whatever its length)")
def _():
    layout = cube(PHDR=V3_PHDR, OBJT=records.encode_object(ObjectRecord(0, "cube", None, None), 3),
                  PLNS=records.encode_planes(0, CUBE, V3_HEAD, False),
                  GRUP=records.encode_group(PartGroup(0, 0, 0, np.arange(6, dtype=np.uint32), np.zeros(6, bool)),
                                            False, 3))
    at = offsets(layout + [(b"", b"")])
    entries = [(16, schema.OBJT, 0), (at[2], schema.PLNS, 0), (at[3], schema.GRUP, 0)]
    index = records.encode_index(np.array(entries, dtype=schema.INDEX_ENTRY_DTYPE))
    return frame(layout + [(schema.INDX, index), (schema.PEND, records.encode_end(at[-1], 3))])


# -- sealed groups (spec/pln.md §9.9, version 3.1) ---------------------------------------------

V3_F64 = dataclasses.replace(V3_HEAD, coding=Coding.FLOAT64)


def sealed_body(vertex_planes=SEALED_CUBE_VERTICES, facets=SEALED_CUBE_FACETS, *, roles: bytes = b"\0",
                vertex_count: int | None = None) -> bytes:
    """The body of a sealed group over the cube's 6 references (spec §9.2, §9.9), varint by
    varint, since the writer refuses broken ones; ``facets`` rows are (face, i0, i1, i2), the face
    stored as a difference."""
    faces = [f[0] for f in facets]
    stored = np.column_stack([np.diff(faces, prepend=0), [f[1:] for f in facets]])
    count = len(vertex_planes) if vertex_count is None else vertex_count
    refs = b"\x06\x00\x01\x01\x01\x01\x01"  # 6 references 0..5 as differences
    return b"".join([refs, roles, varint.encode([count]), varint.encode(np.ravel(vertex_planes)),
                     varint.encode([len(facets)]), varint.encode(stored)])


def sealed_file(body: bytes, version: tuple[int, int] = (3, 1)) -> bytes:
    """The cube of spec/pln-1.md §12 as a version 3.1 file (or ``version``), float64 (its planes x <= 1 and
    x >= 0 are then 1e-16 from parallel), with a sealed group of ``body`` in place of the convex one."""
    group = schema.GroupHead3.build(dict(index=0, object=0, kind=5, compression=0, raw_size=len(body), body=body))
    return v3(PHDR=header(version=version, coding=Coding.FLOAT64), PLNS=records.encode_planes(0, CUBE, V3_F64, False),
              GRUP=group)


@case("xv3_sealed_in_3_0", "UNKNOWN_GROUP_KIND", "a well-formed sealed cube (kind 5) in a version 3.0 file, "
      "whose version has no kind 5")
def _():
    return sealed_file(sealed_body(), (3, 0))


@case("xv3_sealed_plane_twice", "BAD_GROUP_STRUCTURE", "version 3.1 sealed cube whose vertex 0 is named by the "
      "local references 2, 3, 3: one plane twice")
def _():
    return sealed_file(sealed_body(((2, 3, 3),) + SEALED_CUBE_VERTICES[1:]))


@case("xv3_sealed_face_role", "BAD_GROUP_STRUCTURE", "version 3.1 sealed cube with role bit 1 on reference 5 "
      "(z >= 0), the face plane of its last two triangles: triangles lie on face planes only")
def _():
    return sealed_file(sealed_body(roles=b"\x20"))


@case("xv3_sealed_unused_vertex", "BAD_GROUP_STRUCTURE", "version 3.1 sealed cube with a ninth vertex (named as "
      "vertex 7 is) that no triangle uses")
def _():
    return sealed_file(sealed_body(SEALED_CUBE_VERTICES + ((0, 1, 4),)))


@case("xv3_sealed_vertex_count", "BAD_GROUP_STRUCTURE", "version 3.1 sealed cube whose vertex_count says 25, more "
      "than a third of the 73 bytes left after it (checked before the varints are read)")
def _():
    return sealed_file(sealed_body(vertex_count=25))


@case("xv3_sealed_cut", "BAD_PAYLOAD", "version 3.1 sealed cube whose last varint (a vertex of the last triangle) "
      "has its continuation bit set: the body ends inside it")
def _():
    b = sealed_body()
    return sealed_file(b[:-1] + bytes([b[-1] | 0x80]))


@case("xv3_sealed_cut_after_defect", "BAD_PAYLOAD", "version 3.1 sealed cube whose vertex 0 names local "
      "reference 3 twice (as in xv3_sealed_plane_twice) and whose last varint has its continuation bit set: a "
      "reader checks the values only once it has read all the varints, so the cut varint decides")
def _():
    b = sealed_body(((2, 3, 3),) + SEALED_CUBE_VERTICES[1:])
    return sealed_file(b[:-1] + bytes([b[-1] | 0x80]))


# -- shell groups (spec/pln.md §9.10, version 3.2) ----------------------------------------------

def shell_file(body: bytes, version: tuple[int, int] = (3, 2), colours: bytes | None = None, kind: int = 6) -> bytes:
    """The cube of spec/pln-1.md §12 as a version 3.2 file (or ``version``), float64, with a shell group (or
    a group of ``kind``) of ``body`` (its references and roles included) in place of the convex one, and a
    cOLR chunk of ``colours`` after it if given."""
    group = schema.GroupHead3.build(dict(index=0, object=0, kind=kind, compression=0, raw_size=len(body), body=body))
    layout = cube(PHDR=header(version=version, coding=Coding.FLOAT64), OBJT=records.encode_object(
        ObjectRecord(0, "cube", None, None), 3), PLNS=records.encode_planes(0, CUBE, V3_F64, False), GRUP=group)
    if colours is not None:
        layout.append((schema.COLR, colours))
    return frame(finish(layout, True, 3))


def shell_body(shell=SHELL_CUBE, refs: bytes = b"\x06\x00\x01\x01\x01\x01\x01", roles: bytes = b"\0") -> bytes:
    """A shell group's body: 6 references 0..5 as differences, their roles, the kind data."""
    return refs + roles + shellfields._shell_body(shell)


@case("xv3_shell_in_3_1", "UNKNOWN_GROUP_KIND", "a well-formed shell cube (kind 6) in a version 3.1 file, whose "
      "version has no kind 6")
def _():
    return shell_file(shell_body(), (3, 1))


@case("xv3_shell_code_back", "BAD_GROUP_STRUCTURE", "version 3.2 shell cube whose first triangle's second corner "
      "code is 2: two corners back from the only one named so far")
def _():
    b = bytearray(shell_body())
    codes_at = len(b) - 36  # 12 triangles x 3 one-byte corner codes end the body
    b[codes_at + 1] = 2
    return shell_file(bytes(b))


@case("xv3_shell_unused_corner", "BAD_GROUP_STRUCTURE", "version 3.2 shell cube with a ninth named corner (as "
      "corner 7) that no triangle uses")
def _():
    s = dataclasses.replace(SHELL_CUBE, explicit=np.zeros(9, dtype=bool),
                            vertex_planes=np.vstack([SHELL_CUBE.vertex_planes, SHELL_CUBE.vertex_planes[-1:]]))
    return shell_file(shell_body(s))


@case("xv3_shell_flag_padding", "BAD_PAYLOAD", "version 3.2 shell pyramid (5 explicit corners: flags 0x1f) with "
      "padding bit 7 set (flags 0x9f); read as flags, the rest of the body is well formed")
def _():
    b = bytearray(shellfields._shell_body(SHELL_PYRAMID))
    assert b[3] == 0x1F  # after the three one-byte counts
    b[3] = 0x9F
    return shell_file(b"\x01\x00\0" + bytes(b))


@case("xv3_shell_zero_step", "BAD_GROUP_STRUCTURE", "version 3.2 shell cube whose explicit corner's grid has step 0")
def _():
    return shell_file(shell_body(dataclasses.replace(SHELL_MIXED, step=0.0)))


@case("xv3_shell_cut", "BAD_PAYLOAD", "version 3.2 shell cube whose last corner code has its continuation bit set: "
      "the body ends inside it")
def _():
    b = shell_body()
    return shell_file(b[:-1] + bytes([b[-1] | 0x80]))


@case("xv3_shell_colours", "BAD_COLOURS", "version 3.2 shell cube with a cOLR of 7 colours: one per reference, 6, "
      "as for every group (free triangles take the last reference's)")
def _():
    rgba = np.full((7, 4), 255, dtype=np.uint8)
    return shell_file(shell_body(), colours=records.encode_colours(Colours(0, rgba)))


@case("xv3_shell_no_refs", "BAD_GROUP_STRUCTURE", "version 3.2 shell pyramid of no references: every group has "
      "at least one, shells too")
def _():
    return shell_file(shell_body(SHELL_PYRAMID, refs=b"\x00", roles=b""))


# -- shell trees (spec/pln-3.md §8.10, version 3.3) ----------------------------------------------

CUBE_REFS = b"\x06\x00\x01\x01\x01\x01\x01\0"  # 6 references 0..5 as differences, role bits 0


def tree_file(fields: dict[str, bytes], refs: bytes = CUBE_REFS, version: tuple[int, int] = (3, 3), kind: int = 7) -> bytes:
    """The cube file of ``shell_file`` with a shell tree (kind 7, or 8) of the body ``fields`` (spec §9.11, §9.12)."""
    return shell_file(refs + b"".join(fields.values()), version, kind=kind)


def tree_fields(shell=TREE_CUBE, parallelogram: bool = False, **changed: bytes) -> dict[str, bytes]:
    """The fields of ``shell``'s body by name (kind 8's with ``parallelogram``), ``changed`` ones replaced."""
    return {**shellfields.shell_tree_fields(shell, parallelogram), **changed}


def tree_codes(codes: list[int]) -> bytes:
    return varint.encode(np.array(codes, dtype=np.uint64))


#: TREE_CUBE's corner codes: the root's three new corners, then each attached triangle's third.
CUBE_TREE_CODES = list(varint.decode(shellfields.shell_tree_fields(TREE_CUBE)["codes"], 14, "codes")[0])


@case("xv3_parallelogram_in_3_3", "UNKNOWN_GROUP_KIND", "a well-formed kind 8 shell tree pyramid in a version 3.3 "
      "file, whose version has no kind 8")
def _():
    return tree_file(tree_fields(TREE_PYRAMID, parallelogram=True), refs=b"\x01\x00\0", kind=8)


#: A zigzag strip of 100 free triangles (links alternately 2 and 3), 102 explicit corners: as kind 8
#: every corner from the fourth on is predicted x_(k-1) + x_(k-2) - x_(k-3).
STRIP = tree_of([1] * 102, [], np.zeros((102, 3), dtype=np.int64),
                [(-1, 0, 1, 2)] + [(-1, k + 1, k, k + 2) if k % 2 else (-1, k, k + 1, k + 2) for k in range(1, 100)],
                [0] + [2 if k % 2 else 3 for k in range(1, 100)])


@case("xv3_parallelogram_grows", "BAD_GROUP_STRUCTURE", "version 3.4 kind 8 zigzag strip of 100 triangles whose "
      "explicit corners' x residuals are all 2^52 (the most the spec allows): through the parallelograms the "
      "coordinates grow with the square of the corner's place, past 2^52 at once and past 2^63 by corner 91, "
      "so a reader that checks only after the last, in 64-bit integers, may see them wrap")
def _():
    residuals = np.zeros((3, 102), dtype=np.int64)
    residuals[0, 1:] = 1 << 52
    coordinates = varint.encode(varint.zigzag(residuals.reshape(-1)))
    return tree_file(tree_fields(STRIP, parallelogram=True, coordinates=coordinates), refs=b"\x01\x00\0",
                     version=(3, 4), kind=8)


@case("xv3_tree_in_3_2", "UNKNOWN_GROUP_KIND", "a well-formed shell tree cube (kind 7) in a version 3.2 file, "
      "whose version has no kind 7")
def _():
    return tree_file(tree_fields(), version=(3, 2))


@case("xv3_tree_link_back", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube whose second triangle's link is 4: "
      "attached to edge 0 of the triangle two before it, before the first")
def _():
    links = bytearray(tree_fields()["links"])
    links[1] = 4
    return tree_file(tree_fields(links=bytes(links)))


@case("xv3_tree_root_code_back", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube whose root's second corner "
      "code is 2: two corners back from the only one named so far")
def _():
    return tree_file(tree_fields(codes=tree_codes([0, 2] + CUBE_TREE_CODES[2:])))


@case("xv3_tree_third_unnamed", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube whose second triangle's code "
      "is 3: its second corner (2) plus 1, corner 3, which is not named yet (code 0 names it)")
def _():
    return tree_file(tree_fields(codes=tree_codes(CUBE_TREE_CODES[:3] + [3] + CUBE_TREE_CODES[4:])))


@case("xv3_tree_corner_twice", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube whose sixth triangle's code is "
      "1 (not 2): its second corner (2) plus 0, which it then names twice")
def _():
    assert CUBE_TREE_CODES[7] == 2
    return tree_file(tree_fields(codes=tree_codes(CUBE_TREE_CODES[:7] + [1] + CUBE_TREE_CODES[8:])))


@case("xv3_tree_corner_count", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube declaring 9 corners where its "
      "codes name 8 anew")
def _():
    return tree_file(tree_fields(counts=bytes([9, 12]), flags=b"\0\0"))


@case("xv3_tree_face_range", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube whose first triangle's face code "
      "is 8: local reference 6, of 6")
def _():
    return tree_file(tree_fields(faces=b"\x08" + tree_fields()["faces"][1:]))


@case("xv3_tree_face_bounding", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube whose reference 4 (z <= 1) has "
      "role bit 1: a bounding plane, which two triangles lie on")
def _():
    return tree_file(tree_fields(), refs=CUBE_REFS[:-1] + b"\x10")


@case("xv3_tree_few_planes", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube whose last triangle is free (face "
      "code 1): its corner 6, named, is then on two face planes only")
def _():
    return tree_file(tree_fields(faces=tree_fields()["faces"][:-1] + b"\x01"))


@case("xv3_tree_picks_order", "BAD_GROUP_STRUCTURE", "version 3.3 closed pyramid as a shell tree whose apex, on four "
      "face planes, picks 0 2 1: not ascending")
def _():
    return tree_file(tree_fields(TREE_APEX, picks=bytes([0, 2, 1])), refs=b"\x05\x00\x01\x01\x01\x01\0")


@case("xv3_tree_picks_range", "BAD_GROUP_STRUCTURE", "version 3.3 closed pyramid as a shell tree whose apex, on four "
      "face planes, picks 0 1 4: past the fourth")
def _():
    return tree_file(tree_fields(TREE_APEX, picks=bytes([0, 1, 4])), refs=b"\x05\x00\x01\x01\x01\x01\0")


@case("xv3_tree_trailing", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube with one byte after its flags (no "
      "corner picks, no explicit corner: the body ends there)")
def _():
    return tree_file(tree_fields(flags=tree_fields()["flags"] + b"\0"))


@case("xv3_tree_cut", "BAD_PAYLOAD", "version 3.3 shell tree cube whose body ends before its corner flags")
def _():
    return tree_file(tree_fields(flags=b""))


@case("xv3_tree_flag_padding", "BAD_PAYLOAD", "version 3.3 open pyramid as a shell tree (5 explicit corners: flags "
      "0x1f) with padding bit 7 set (flags 0x9f); read as flags, the rest of the body is well formed")
def _():
    assert tree_fields(TREE_PYRAMID)["flags"] == b"\x1f"
    return tree_file(tree_fields(TREE_PYRAMID, flags=b"\x9f"), refs=b"\x01\x00\0")


@case("xv3_tree_zero_step", "BAD_GROUP_STRUCTURE", "version 3.3 shell tree cube with four explicit corners whose "
      "grid has step 0")
def _():
    return tree_file(tree_fields(dataclasses.replace(TREE_MIXED, step=0.0)))


@case("xv3_tree_coordinate_range", "BAD_GROUP_STRUCTURE", "version 3.3 open pyramid as a shell tree whose first "
      "corner's x residual is 2^52 + 1")
def _():
    coordinates = varint.decode(tree_fields(TREE_PYRAMID)["coordinates"], 15, "coordinates")[0]
    coordinates[0] = varint.zigzag(np.array([2**52 + 1]))[0]
    return tree_file(tree_fields(TREE_PYRAMID, coordinates=varint.encode(coordinates)), refs=b"\x01\x00\0")


@case("xgrup_deflate_bomb", "LIMIT_EXCEEDED", "a deflated GRUP body declaring raw_size 2^32-1 (a deflate bomb)",
      also=("SIZE_MISMATCH",))
def _():
    return file(cube(GRUP=grup_raw(zlib.compress(body(), 9), compression=1, raw_size=0xFFFFFFFF)))


# -- objects (spec §8) -----------------------------------------------------------------------

@case("xobjt_index", "BAD_OBJECT", "the first OBJT has index 1")
def _():
    return file(cube(OBJT=objt(index=1)))


@case("xobjt_parent_self", "BAD_OBJECT", "object 0 names itself as parent")
def _():
    return file(cube(OBJT=objt(parent=0)))


@case("xobjt_parent_later", "BAD_OBJECT", "object 0 names object 1, defined after it, as parent")
def _():
    layout = cube(PHDR=header(object_count=2), OBJT=objt(parent=1))
    return file(layout[:2] + [(schema.OBJT, objt(index=1, name="later"))] + layout[2:])


@case("xobjt_name_utf8", "BAD_OBJECT", "object name b'cub\\xe9' (Latin-1), not UTF-8")
def _():
    name = b"cub\xe9"
    return file(cube(OBJT=schema.Object.build(dict(index=0, parent=0xFFFFFFFF, flags=0, reserved=b"\0",
                                                   name_length=len(name), name=name, transform=None, extra=b""))))


@case("xobjt_transform_row", "BAD_OBJECT", "a transform whose last row is 0 0 0 2")
def _():
    m = np.eye(4)
    m[3, 3] = 2.0
    return file(cube(OBJT=objt(transform=m)))


@case("xobjt_transform_nan", "BAD_OBJECT", "a transform with a NaN translation")
def _():
    m = np.eye(4)
    m[0, 3] = math.nan
    return file(cube(OBJT=objt(transform=m)))


@case("xobjt_no_transform", "BAD_PAYLOAD", "HAS_TRANSFORM set but the payload ends after the name",
      also=("BAD_OBJECT",))
def _():
    payload = bytearray(objt())
    payload[8] = schema.OBJECT_HAS_TRANSFORM
    return file(cube(OBJT=bytes(payload)))


# -- part groups (spec §9) -------------------------------------------------------------------

@case("xgrup_plane_range", "BAD_PLANE_REFERENCE", "a reference to plane 6 of a 6-plane table")
def _():
    return file(cube(GRUP=grup([0, 1, 2, 3, 4, 6])))


@case("xgrup_plane_forward", "BAD_PLANE_REFERENCE", "GRUP before the PLNS chunk that holds its planes")
def _():
    phdr, o, p, g = cube()
    return file([phdr, o, g, p])


@case("xgrup_object_range", "BAD_OBJECT_REFERENCE", "a group of object 1; only object 0 exists")
def _():
    return file(cube(GRUP=grup(obj=1)))


@case("xgrup_object_forward", "BAD_OBJECT_REFERENCE", "GRUP before the OBJT of its object")
def _():
    phdr, o, p, g = cube()
    return file([phdr, p, g, o])


@case("xgrup_index", "GROUP_INDEX_MISMATCH", "the first group has index 1")
def _():
    return file(cube(GRUP=grup(index=1)))


@case("xgrup_kind5", "UNKNOWN_GROUP_KIND", "group kind 5 (the first unknown) in a version 1.0 file")
def _():
    return file(cube(GRUP=grup(kind=5)))


@case("xgrup_no_refs", "BAD_GROUP_STRUCTURE", "a group with ref_count 0")
def _():
    return file(cube(GRUP=grup_raw(body(refs=[]))))


@case("xgrup_role_padding", "BAD_PAYLOAD", "6 role bits, and padding bit 7 of the role byte set")
def _():
    return file(cube(GRUP=grup_raw(body(roles=b"\x80"))))


@case("xgrup_kind_data", "BAD_PAYLOAD", "a convex group with 4 bytes of kind data (kinds 0, 3, 4 have none)")
def _():
    return file(cube(GRUP=grup_raw(body(extra=b"\0\0\0\0"))))


@case("xgrup_body_short", "BAD_PAYLOAD", "ref_count 6 but the body ends inside the fifth reference")
def _():
    return file(cube(GRUP=grup_raw(body()[:22])))


@case("xgrup_head_short", "BAD_PAYLOAD", "a GRUP payload of 12 bytes, under its 16-byte head")
def _():
    return file(cube(GRUP=grup()[:12]))


@case("xgrup_skipped_kind_ref", "BAD_PLANE_REFERENCE",
      "version 1.1, a group of unknown kind 9 referencing plane 6 of 6: its common body is still checked")
def _():
    return file(cube(PHDR=header(version=(1, 1)), GRUP=grup([0, 1, 2, 3, 4, 6], kind=9)))


# -- cells (spec §9.6) and trees (spec §9.7) ---------------------------------------------------

L_ROLES = [False] * 8 + [True]  # the cut plane x = y


def group_file(triplets, group: bytes, name: str = "cube") -> bytes:
    """A float64 file of one object, the planes ``triplets`` and one GRUP payload."""
    head = dataclasses.replace(SPEC_HEADER, coding=Coding.FLOAT64)
    return file(cube(PHDR=header(coding=Coding.FLOAT64, plane_count=len(triplets)), OBJT=objt(name=name),
                     PLNS=plns(triplets, head=head), GRUP=group))


def l_file(group: bytes, planes=L_PLANES) -> bytes:
    """The L of the valid cases cells_l / bsp_l with another GRUP payload."""
    return group_file(planes, group, "L")


def cells_body(counts, entries, refs=range(9)) -> bytes:
    extra = (len(counts).to_bytes(4, "little") + np.array(counts, "<u4").tobytes()
             + np.array(entries, "<u4").tobytes())
    return body(refs, roles=b"\x00\x01", extra=extra)


@case("xcells_entry_range", "BAD_GROUP_STRUCTURE", "a cell entry 18 = 2*9: local reference 9 of 9")
def _():
    return l_file(grup(range(9), kind=1, bounding=L_ROLES, cells=((0, 2, 4, 17, 12, 18), L_CELLS[1])))


@case("xcells_none", "BAD_GROUP_STRUCTURE", "a cells group with cell_count 0")
def _():
    return l_file(grup_raw(cells_body([], []), kind=1))


@case("xcells_empty_cell", "BAD_GROUP_STRUCTURE", "a cell of size 0")
def _():
    return l_file(grup_raw(cells_body([6, 0, 6], L_CELLS[0] + L_CELLS[1]), kind=1))


@case("xcells_extra", "BAD_GROUP_STRUCTURE", "one entry more than the cell sizes account for",
      also=("BAD_PAYLOAD",))
def _():
    return l_file(grup_raw(cells_body([6, 6], L_CELLS[0] + L_CELLS[1] + (0,)), kind=1))


@case("xbsp_incomplete", "BAD_GROUP_STRUCTURE", "the token stream of bsp_l without its last OUT leaf")
def _():
    return l_file(grup(range(8), kind=2, tree=L_TREE[:-1]), L_PLANES[:8])


@case("xbsp_extra_leaf", "BAD_GROUP_STRUCTURE", "a complete tree followed by one more IN leaf")
def _():
    return l_file(grup(range(8), kind=2, tree=L_TREE + (IN,)), L_PLANES[:8])


@case("xbsp_reserved", "BAD_GROUP_STRUCTURE", "an OUT leaf replaced by the reserved token 0xFFFFFFF0")
def _():
    return l_file(grup(range(8), kind=2, tree=L_TREE[:-1] + (0xFFFFFFF0,)), L_PLANES[:8])


@case("xbsp_split_range", "BAD_GROUP_STRUCTURE", "a split on local reference 8 of 8")
def _():
    return l_file(grup(range(8), kind=2, tree=(8,) + L_TREE[1:]), L_PLANES[:8])


@case("xbsp_empty", "BAD_GROUP_STRUCTURE", "token_count 0: no tree at all")
def _():
    return l_file(grup_raw(body(range(8), extra=b"\0\0\0\0"), kind=2), L_PLANES[:8])


@case("xbsp_trailing", "BAD_GROUP_STRUCTURE", "4 bytes after the token stream: the tokens must fill the body",
      also=("BAD_PAYLOAD",))
def _():
    tokens = len(L_TREE).to_bytes(4, "little") + np.array(L_TREE, "<u4").tobytes()
    return l_file(grup_raw(body(range(8), extra=tokens + b"\0\0\0\0"), kind=2), L_PLANES[:8])


# -- colours (spec §10.1) -----------------------------------------------------------------------

def colr(group: int = 0, count: int = 6) -> bytes:
    return records.encode_colours(Colours(group, np.full((count, 4), 200, dtype=np.uint8)))


@case("xcolr_no_group", "BAD_COLOURS", "cOLR for group 1; the file has only group 0")
def _():
    return file(cube() + [(schema.COLR, colr(group=1))])


@case("xcolr_before_group", "BAD_COLOURS", "cOLR for group 0 placed before that group's GRUP")
def _():
    layout = cube()
    return file(layout[:3] + [(schema.COLR, colr())] + layout[3:])


@case("xcolr_count", "BAD_COLOURS", "5 colours for a group of 6 references")
def _():
    return file(cube() + [(schema.COLR, colr(count=5))])


# -- metadata (spec §10.3) ------------------------------------------------------------------

def with_meta(*payloads: bytes, at: int = 1) -> bytes:
    """The cube with raw mETA payloads (what the writer refuses to write) inserted at layout position ``at``."""
    layout = cube()
    return file(layout[:at] + [(schema.META, p) for p in payloads] + layout[at:])


@case("xmeta_no_separator", "BAD_METADATA", "a mETA payload up_axisZ without the 0x00 after its keyword")
def _():
    return with_meta(b"up_axisZ")


@case("xmeta_empty_keyword", "BAD_METADATA", "a mETA whose keyword is empty (the payload starts with 0x00)")
def _():
    return with_meta(b"\x00Z")


@case("xmeta_keyword_space", "BAD_METADATA", "a mETA keyword with a space, 'up axis'")
def _():
    return with_meta(b"up axis\x00Z")


@case("xmeta_value_utf8", "BAD_METADATA", "a mETA value that is not UTF-8 (ff fe) under a keyword no spec defines")
def _():
    return with_meta(b"title\x00\xff\xfe")


@case("xmeta_up_axis_x", "BAD_METADATA", "mETA up_axis = X: only Y and Z are defined")
def _():
    return with_meta(b"up_axis\x00X")


@case("xmeta_repeated", "BAD_METADATA", "two mETA chunks up_axis = Z: a keyword appears once")
def _():
    return with_meta(b"up_axis\x00Z", b"up_axis\x00Z")


@case("xmeta_after_object", "BAD_METADATA", "mETA up_axis = Z after the OBJT: metadata precedes the geometry")
def _():
    return with_meta(b"up_axis\x00Z", at=2)


# -- index and end (spec §4.4, §10.2) -----------------------------------------------------------

def with_index(entries: list[tuple[int, bytes, int]], layout: Layout | None = None,
               index_offset: int | None = None) -> bytes:
    """The cube with the iNDX entries replaced (and PEND pointing at the iNDX unless told)."""
    layout = cube() if layout is None else layout
    at = offsets(layout + [(b"", b"")])[-1]
    payload = records.encode_index(np.array(entries, dtype=schema.INDEX_ENTRY_DTYPE))
    return frame(layout + [(schema.INDX, payload),
                           (schema.PEND, records.encode_end(at if index_offset is None else index_offset))])


GOOD_ENTRIES = [(OBJT_AT, schema.OBJT, 0), (PLNS_AT, schema.PLNS, 0), (GRUP_AT, schema.GRUP, 0)]


@case("xindx_outside", "BAD_INDEX", "the GRUP entry points at byte 10000, beyond the end of the file")
def _():
    return with_index(GOOD_ENTRIES[:2] + [(10000, schema.GRUP, 0)])


@case("xindx_type", "BAD_INDEX", "the entry of the PLNS chunk says OBJT")
def _():
    return with_index([GOOD_ENTRIES[0], (PLNS_AT, schema.OBJT, 0), GOOD_ENTRIES[2]])


@case("xindx_mid_chunk", "BAD_INDEX", "the OBJT entry points 4 bytes into the OBJT chunk")
def _():
    return with_index([(OBJT_AT + 4, schema.OBJT, 0)] + GOOD_ENTRIES[1:])


@case("xindx_ordinal", "BAD_INDEX", "the GRUP entry gives ordinal 1 for group 0")
def _():
    return with_index(GOOD_ENTRIES[:2] + [(GRUP_AT, schema.GRUP, 1)])


@case("xindx_missing", "BAD_INDEX", "the index has no entry for the PLNS chunk")
def _():
    return with_index([GOOD_ENTRIES[0], GOOD_ENTRIES[2]])


@case("xindx_not_last", "CHUNK_ORDER", "an ancillary tEXt chunk between iNDX and PEND")
def _():
    layout = finish(cube())
    return frame(layout[:-1] + [(b"tEXt", b"late"), layout[-1]])


@case("xindx_count", "BAD_INDEX", "iNDX count 2 with 3 entries present", also=("BAD_PAYLOAD",))
def _():
    layout = finish(cube())
    payload = bytearray(layout[-2][1])
    payload[0] = 2
    layout[-2] = (schema.INDX, bytes(payload))
    return frame(layout)


@case("xpend_offset", "BAD_INDEX", "PEND index_offset points at the GRUP chunk, not the iNDX")
def _():
    return with_index(GOOD_ENTRIES, index_offset=GRUP_AT)


@case("xpend_no_index", "BAD_INDEX", "PEND index_offset 317 (where PEND itself is) in a file without iNDX")
def _():
    return frame(cube() + [(schema.PEND, records.encode_end(INDX_AT))])


@case("xpend_payload", "BAD_PAYLOAD", "a PEND payload of 12 bytes instead of 8")
def _():
    return frame(finish(cube(), index=False)[:-1] + [(schema.PEND, bytes(12))])


# -- geometry (spec §9): only decoders of geometry see these ---------------------------------

def geometry_case(name: str, error: str, description: str, *, also: tuple[str, ...] = ()):
    return case(name, error, description, level="geometry", also=also)


def _convex(error: str, triplets) -> bytes:
    geometry_defect(error, 0, triplets)
    return group_file(triplets, grup(range(len(triplets))))


@geometry_case("xgeom_empty", "EMPTY_POLYTOPE", "a convex group with x <= 0 and x >= 1")
def _():
    return _convex("EMPTY_POLYTOPE", box((1, 0, 0), (0, 1, 1)))


@geometry_case("xgeom_flat", "EMPTY_POLYTOPE", "a convex group with x <= 0 and x >= 0: not empty, but no interior")
def _():
    return _convex("EMPTY_POLYTOPE", box((0, 0, 0), (0, 1, 1)))


@geometry_case("xgeom_unbounded3", "UNBOUNDED_POLYTOPE", "a convex group of 3 planes, x <= 1, y <= 1, z <= 1")
def _():
    return _convex("UNBOUNDED_POLYTOPE", CUBE[[0, 1, 4]])


@geometry_case("xgeom_unbounded5", "UNBOUNDED_POLYTOPE", "a convex group of the cube's planes but z <= 1: "
               "a square shaft open upwards")
def _():
    return _convex("UNBOUNDED_POLYTOPE", CUBE[[0, 1, 2, 3, 5]])


@geometry_case("xgeom_tilt_unbounded", "UNBOUNDED_POLYTOPE", "the cube's planes but z >= 0, their angles rounded to "
               "float32: the four sides tilt by 4.4e-8 and meet 2.3e7 below, but their normals surround the origin by "
               "less than spec §9.4's 1e-6")
def _():
    tilted = CUBE[:5].copy()
    tilted[:, :2] = tilted[:, :2].astype(np.float32)
    return _convex("UNBOUNDED_POLYTOPE", tilted)


@geometry_case("xgeom_sliver", "EMPTY_POLYTOPE", "a box 1e-9 x 1 x 1: thinner than spec §9.4's 1e-8 of its diagonal")
def _():
    return _convex("EMPTY_POLYTOPE", box((0, 0, 0), (1e-9, 1, 1)))


@geometry_case("xgeom_patch_unbounded", "UNBOUNDED_POLYTOPE", "a pseudo-convex patch (kind 3) of the five faces "
               "of an open box with no bounding plane over the opening")
def _():
    t = CUBE[[0, 1, 2, 3, 5]]
    geometry_defect("UNBOUNDED_POLYTOPE", 3, t)
    return group_file(t, grup(range(5), kind=3))


@geometry_case("xgeom_cells_unbounded", "UNBOUNDED_POLYTOPE", "a cells group whose second cell lacks y <= 2",
               also=("BAD_GROUP_STRUCTURE",))
def _():
    cells = (L_CELLS[0], (6, 10, 16, 12, 14))
    geometry_defect("UNBOUNDED_POLYTOPE", 1, L_PLANES, L_ROLES, cells)
    return l_file(grup(range(9), kind=1, bounding=L_ROLES, cells=cells))


@geometry_case("xgeom_bsp_unbounded", "UNBOUNDED_POLYTOPE", "a tree whose IN leaf is the half-space z <= 1",
               also=("BAD_GROUP_STRUCTURE",))
def _():
    geometry_defect("UNBOUNDED_POLYTOPE", 2, L_PLANES[:8], None, None, (6, IN, OUT))
    return l_file(grup(range(8), kind=2, tree=(6, IN, OUT)), L_PLANES[:8])


@geometry_case("xgeom_bsp_unbounded_twice", "UNBOUNDED_POLYTOPE", "a tree whose IN leaf is the half-space z <= 1 "
               "reached by the same split twice (the second split's outer side an empty OUT leaf)",
               also=("BAD_GROUP_STRUCTURE",))
def _():
    geometry_defect("UNBOUNDED_POLYTOPE", 2, L_PLANES[:8], None, None, (6, 6, IN, OUT, OUT))
    return l_file(grup(range(8), kind=2, tree=(6, 6, IN, OUT, OUT)), L_PLANES[:8])


@geometry_case("xgeom_v3_sealed_parallel", "BAD_VERTEX", "version 3.1 sealed cube whose vertex 7 is named by "
               "x <= 1, x >= 0 and z <= 1: two parallel planes (|det| 1e-16 in float64)")
def _():
    vertices = SEALED_CUBE_VERTICES[:7] + ((0, 2, 4),)
    geometry_defect("BAD_VERTEX", 5, CUBE, vertex_planes=vertices, facets=SEALED_CUBE_FACETS)
    return sealed_file(sealed_body(vertices))


@geometry_case("xgeom_v3_shell_parallel", "BAD_VERTEX", "version 3.2 shell cube whose last corner is named by "
               "x <= 1, x >= 0 and z <= 1: two parallel planes (|det| 1e-16 in float64)")
def _():
    vp = SHELL_CUBE.vertex_planes.copy()
    vp[-1] = (0, 2, 4)
    s = dataclasses.replace(SHELL_CUBE, vertex_planes=vp)
    geometry_defect("BAD_VERTEX", 6, CUBE, shell=s)
    return shell_file(shell_body(s))


@geometry_case("xgeom_cells_overlap", "BAD_GROUP_STRUCTURE", "a cells group whose two cells are the same prism: "
               "cell interiors must be disjoint")
def _():
    return l_file(grup(range(9), kind=1, bounding=L_ROLES, cells=(L_CELLS[0], L_CELLS[0])))


# -- rules spec/pln.md decides (issue 32): one code each where older documents allowed two --------

@case("xcrc_and_payload", "CRC_MISMATCH", "a PHDR with coding 7 and a wrong CRC: framing is checked before the "
      "payload (spec/pln.md §4.1, §12.1)")
def _():
    return patched(CUBE_FILE, PHDR_AT + 8 + 4, b"\x07")  # the coding byte, after the CRC was computed


@case("xorder_after_index_bad_payload", "CHUNK_ORDER", "an OBJT of 3 bytes (its own payload too short) between "
      "iNDX and PEND: a chunk's place is checked before its payload (spec/pln.md §12.1)")
def _():
    return CUBE_FILE[:PEND_AT] + chunk_bytes(b"OBJT", b"\x01\x00\x00") + CUBE_FILE[PEND_AT:]


@case("xchunk_too_long_max", "CHUNK_TOO_LONG", "the GRUP length is 2^32 - 1: above 2^31 - 1, above any reader's "
      "chunk limit and beyond the end of the file; CHUNK_TOO_LONG comes first (spec/pln.md §4.1)")
def _():
    return patched(CUBE_FILE, GRUP_AT + 4, (0xFFFFFFFF).to_bytes(4, "little"))


@case("xplns_stored_short", "SIZE_MISMATCH", "uncompressed PLNS data of 68 bytes with raw_size 72 (what 6 "
      "float32 planes take): method 0 with a stored size other than raw size (spec/pln.md §6 step 3)")
def _():
    return file(cube(PLNS=plns_raw(CUBE.astype("<f4").tobytes()[:68], raw_size=72)))


@case("xgrup_method_and_bomb", "BAD_COMPRESSION", "GRUP compression method 2 with raw_size 2^32 - 1: the method, "
      "a defect of the file, is checked before the reader's limits (spec/pln.md §6 steps 1-2)")
def _():
    return file(cube(GRUP=grup_raw(body(), compression=2, raw_size=0xFFFFFFFF)))


@case("xplns_zlib_truncated", "SIZE_MISMATCH", "a zlib stream cut after 30 of its bytes: a valid start that ends "
      "inside the stream is SIZE_MISMATCH, not BAD_COMPRESSION (spec/pln.md §6 step 5)")
def _():
    z = zlib.compress(CUBE.astype("<f4").tobytes(), 9)
    assert len(z) > 30
    return file(cube(PLNS=plns_raw(z[:30], compression=1, raw_size=72)))


@case("xplns_zlib_check", "BAD_COMPRESSION", "a zlib stream that inflates to the 72 bytes but whose Adler-32 "
      "check value is wrong: an error the inflater reports (spec/pln.md §6 step 5)")
def _():
    z = bytearray(zlib.compress(CUBE.astype("<f4").tobytes(), 9))
    z[-1] ^= 0x01
    return file(cube(PLNS=plns_raw(bytes(z), compression=1, raw_size=72)))


@case("xplns_padding_and_code", "BAD_PAYLOAD", "quantized 7/9/5 with a padding bit set and the first nu code 127, "
      "above M_nu = 64: padding is checked before the codes (spec/pln.md §7.3)")
def _():
    q = Quantization(7, 9, 5, 0.0, 1.0)
    payload = bytearray(plns(head=Header(coding=Coding.QUANTIZED, quantization=q)))
    payload[20] |= 0x7F  # record 0's nu: bits 0-6 of the data
    payload[-1] |= 0x80
    return file(cube(PHDR=header(coding=Coding.QUANTIZED, quantization=q), PLNS=bytes(payload)))


@case("xv2_predicted_extra_and_code", "SIZE_MISMATCH", "version 2.0, predicted planes: the first nu difference -1 "
      "(a negative code) and one byte after the 18 varints: the fill is checked before the codes (spec/pln.md §7.4)")
def _():
    return v2(v2_planes(b"\x01" + V2_STREAMS[V2_FIRST:] + b"\x00"))


@case("xv2_ref_count_long", "BAD_PAYLOAD", "version 2.0 group body: ref_count 200 in a body of 8 bytes: ref_count "
      "is not compared with the bytes left, the body ends inside the references (spec/pln.md §9.2 step 3)")
def _():
    return v2(GRUP=grup_raw(b"\xc8\x01\x00\x01\x01\x01\x01\x01"))


@case("xv2_ref_range_then_cut", "BAD_PAYLOAD", "version 2.0 group body: ref_count 6, the second difference 9 "
      "reaches past the 6 planes, and the body ends after the fourth: every reference is read before any is checked "
      "(spec/pln.md §9.2 steps 3-4)")
def _():
    return v2(GRUP=grup_raw(b"\x06\x00\x09\x01\x01"))


@case("xv3_sealed_vertex_third", "BAD_GROUP_STRUCTURE", "version 3.1 sealed cube whose vertex_count says 25 with "
      "74 bytes after it (the cube's 73 and one more): 3 x 25 = 75 > 74, whatever a reader's rounding of a third "
      "(spec/pln.md §2.1, §9.9)")
def _():
    return sealed_file(sealed_body(vertex_count=25) + b"\x00")


@case("xv3_shell_counts_short", "BAD_PAYLOAD", "version 3.2 shell cube cut 30 bytes short: its counts (8 corners, "
      "12 triangles) pass their checks against the 43 bytes left after them, and the body ends inside the corner "
      "codes (spec/pln.md §9.10 step 3)")
def _():
    return shell_file(shell_body()[:-30])


@case("xv3_shell_step_then_cut", "BAD_PAYLOAD", "version 3.2 shell cube with its corner explicit: a coordinate step "
      "of 2^53 (beyond 2^52) and the last corner code cut: every field is read before any value is checked "
      "(spec/pln.md §9.10 steps 3, 5)")
def _():
    good = shell_body(SHELL_MIXED)
    big = shellfields._shell_body(dataclasses.replace(SHELL_MIXED, grid=np.array([[1 << 53, 0, 0]])))
    b = good[:8] + big
    return shell_file(b[:-1] + bytes([b[-1] | 0x80]))


@geometry_case("xgeom_cells_empty_cell", "EMPTY_POLYTOPE", "the L's two cells and a third, x >= 1 and x <= 0 "
               "within the box: an empty cell is an error (spec/pln.md §9.6)")
def _():
    cells = L_CELLS + ((7, 11, 0, 4, 12, 14),)
    geometry_defect("EMPTY_POLYTOPE", 1, L_PLANES, L_ROLES, cells)
    return l_file(grup(range(9), kind=1, bounding=L_ROLES, cells=cells))


@geometry_case("xgeom_cells_unbounded_z", "UNBOUNDED_POLYTOPE", "a cells group whose first cell lacks z >= 0: an "
               "unbounded cell is UNBOUNDED_POLYTOPE (spec/pln.md §9.6)")
def _():
    cells = ((0, 2, 4, 17, 12), L_CELLS[1])
    geometry_defect("UNBOUNDED_POLYTOPE", 1, L_PLANES, L_ROLES, cells)
    return l_file(grup(range(9), kind=1, bounding=L_ROLES, cells=cells))


@geometry_case("xgeom_bsp_unbounded_leaf", "UNBOUNDED_POLYTOPE", "a tree whose IN leaf is the half-space z >= 0: "
               "an unbounded IN leaf is UNBOUNDED_POLYTOPE (spec/pln.md §9.7)")
def _():
    geometry_defect("UNBOUNDED_POLYTOPE", 2, L_PLANES[:8], None, None, (7, IN, OUT))
    return l_file(grup(range(8), kind=2, tree=(7, IN, OUT)), L_PLANES[:8])


@geometry_case("xgeom_patch_no_face", "EMPTY_POLYTOPE", "a pseudo-convex patch (kind 3) of the cube's six planes, "
               "every one a bounding plane (role bits 0x3f): the polytope is fine but no face is on a face plane "
               "(spec/pln.md §9.8)")
def _():
    geometry_defect("EMPTY_POLYTOPE", 3, CUBE, [True] * 6)
    return group_file(CUBE, grup(range(6), kind=3, bounding=[True] * 6))


# -- version 4.0: Brotli payloads (spec §6), transforms entry by entry (§8), one colour for a group (§10.1) --

V4_F64 = dataclasses.replace(SPEC_HEADER, version=(4, 0), coding=Coding.FLOAT64)


def v4_file(group_body: bytes | None = None, *, method: int = schema.COMPRESSION_BROTLI, raw_size: int | None = None,
            version: tuple[int, int] = (4, 0), objt: bytes | None = None, colours: bytes | None = None) -> bytes:
    """The kind 8 shell tree pyramid in a version 4.0 file (or ``version``), float64, its group body
    stored as ``group_body`` with compression ``method`` and ``raw_size`` (default: a Brotli stream
    of the body), the object as ``objt``, and a cOLR of ``colours`` after the group if given."""
    body = pyramid_body()
    stored = brotli.compress(body) if group_body is None else group_body
    group = schema.GroupHead3.build(dict(index=0, object=0, kind=8, compression=method,
                                         raw_size=len(body) if raw_size is None else raw_size, body=stored))
    layout = cube(PHDR=header(version=version, coding=Coding.FLOAT64),
                  OBJT=objt or records.encode_object(ObjectRecord(0, "pyramid", None, None), version[0]),
                  PLNS=records.encode_planes(0, CUBE, dataclasses.replace(V4_F64, version=version), False), GRUP=group)
    if colours is not None:
        layout.append((schema.COLR, colours))
    return frame(finish(layout, True, version[0]))


def pyramid_body() -> bytes:
    return b"\x01\x04\0" + b"".join(tree_fields(TREE_PYRAMID, parallelogram=True).values())


@case("xv4_brotli_in_3_4", "BAD_COMPRESSION", "a version 3.4 file whose group body is a well-formed Brotli stream "
      "(method 2): versions before 4.0 have methods 0 and 1 only")
def _():
    return v4_file(version=(3, 4))


@case("xv4_brotli_corrupt", "BAD_COMPRESSION", "version 4.0: a group body whose Brotli stream has a window-size "
      "header that Brotli forbids (the first byte 0x11, WBITS marked reserved)")
def _():
    stored = bytearray(brotli.compress(pyramid_body()))
    stored[0] = 0x11
    return v4_file(bytes(stored))


@case("xv4_brotli_truncated", "SIZE_MISMATCH", "version 4.0: a group body's Brotli stream without its last 3 bytes: "
      "the stored bytes end inside the stream")
def _():
    return v4_file(brotli.compress(pyramid_body())[:-3])


@case("xv4_brotli_trailing", "BAD_COMPRESSION", "version 4.0: a whole Brotli stream followed by one more stored byte "
      "(spec §6: bytes after a Brotli stream are an invalid stream)")
def _():
    return v4_file(brotli.compress(pyramid_body()) + b"\x00")


@case("xv4_brotli_longer", "SIZE_MISMATCH", "version 4.0: a group body's Brotli stream that decompresses to one "
      "byte more than the raw size the head declares")
def _():
    return v4_file(raw_size=len(pyramid_body()) - 1)


def _v4_object(transform_bytes: bytes) -> bytes:
    head = schema.Object3Head.build(dict(index=0, parent=0, flags=schema.OBJECT_HAS_TRANSFORM, name_length=7))
    return head + b"pyramid" + transform_bytes


#: Codes of a translation: m00, m11, m22 code 1; m03, m13, m23 code 2 (f32); the rest 0.
_TRANSLATION_CODES = sum(c << (2 * i) for i, c in enumerate([1, 0, 0, 2, 0, 1, 0, 2, 0, 0, 1, 2])).to_bytes(3, "little")


@case("xv4_transform_truncated", "BAD_PAYLOAD", "version 4.0: an OBJT whose transform codes call for three f32 "
      "values and which ends after two")
def _():
    return v4_file(objt=_v4_object(_TRANSLATION_CODES + np.array([1.0, 2.0], dtype="<f4").tobytes()))


@case("xv4_transform_nan", "BAD_OBJECT", "version 4.0: an OBJT transform whose translation in y is an f32 NaN")
def _():
    return v4_file(objt=_v4_object(_TRANSLATION_CODES + np.array([1.0, np.nan, 3.0], dtype="<f4").tobytes()))


@case("xv4_uniform_colour_in_3_4", "BAD_PAYLOAD", "a version 3.4 file with a 12-byte cOLR for the cube group of 6 "
      "references: one colour for all is a form of version 4.0, so in 3.4 the payload ends inside its colours")
def _():
    return _uniform_in(3, schema.ColoursHead.build(dict(group=0, count=6)) + bytes([1, 2, 3, 255]))


def _uniform_in(major: int, colours: bytes) -> bytes:
    layout = cube(PHDR=header(version=(major, 4 if major == 3 else 0)),
                  OBJT=records.encode_object(ObjectRecord(0, "cube", None, None), major),
                  PLNS=records.encode_planes(0, CUBE, dataclasses.replace(V3_HEAD, version=(major, 0)), False),
                  GRUP=records.encode_group(PartGroup(0, 0, 0, np.arange(6, dtype=np.uint32), np.zeros(6, bool)),
                                            False, major))
    layout.append((schema.COLR, colours))
    return frame(finish(layout, True, major))


@case("xv4_colour_count", "BAD_COLOURS", "version 4.0: a 12-byte cOLR of one colour whose count, 5, is not the "
      "group's 6 references")
def _():
    return _uniform_in(4, schema.ColoursHead.build(dict(group=0, count=5)) + bytes([1, 2, 3, 255]))


# -- shell walks (spec/pln.md §9.13, version 4.1) --------------------------------------------------

def walk_file(fields: dict[str, bytes], version: tuple[int, int] = (4, 1), kind: int = 9) -> bytes:
    """The cube of spec/pln-1.md §12 in a version 4.1 file (or ``version``), float64, with a shell walk
    (kind 9, or ``kind``) of the kind data ``fields`` on its six planes, stored without compression."""
    body = CUBE_REFS + b"".join(fields.values())
    group = schema.GroupHead3.build(dict(index=0, object=0, kind=kind, compression=0, raw_size=len(body), body=body))
    layout = cube(PHDR=header(version=version, coding=Coding.FLOAT64),
                  OBJT=records.encode_object(ObjectRecord(0, "cube", None, None), version[0]),
                  PLNS=records.encode_planes(0, CUBE, dataclasses.replace(V4_F64, version=version), False), GRUP=group)
    return frame(finish(layout, True, version[0]))


def walk_fields(shell=TREE_CUBE, coding: int | None = None, kind: GroupKind = GroupKind.SHELL_WALK,
                **changed: bytes) -> dict[str, bytes]:
    """The fields of ``shell``'s shell walk body (of ``kind``) by name (explicit corners in mode
    ``coding``), ``changed`` ones replaced."""
    return {**shellwalk.shell_walk_fields(shell, coding, kind), **changed}


def walk_values(name: str, shell=TREE_CUBE, mode: int | None = None) -> list[int]:
    """The varints of field ``name`` of ``shell``'s walk body."""
    return _all_varints(np.frombuffer(shellwalk.shell_walk_fields(shell, mode)[name], dtype=np.uint8))


def _all_varints(data: np.ndarray) -> list[int]:
    out, pos = [], 0
    while pos < len(data):
        (x,), used = varint.decode(data[pos:], 1, "field")
        out.append(int(x))
        pos += used
    return out


def _codes(values: list[int]) -> bytes:
    return varint.encode(np.array(values, dtype=np.uint64))


@case("xv41_walk_in_4_0", "UNKNOWN_GROUP_KIND", "a well-formed shell walk cube (kind 9) in a version 4.0 file, "
      "whose version has no kind 9")
def _():
    return walk_file(walk_fields(), version=(4, 0))


@case("xv41_root_symbol", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk cube whose root's symbol is 16: past "
      "the 16 lists of a root's free edges")
def _():
    return walk_file(walk_fields(symbols=_codes([16] + walk_values("symbols")[1:])))


@case("xv41_attached_symbol", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk cube whose second triangle's symbol "
      "is 20: children list 5, past the 5 lists of an attached triangle's free edges")
def _():
    s = walk_values("symbols")
    return walk_file(walk_fields(symbols=_codes(s[:1] + [20] + s[2:])))


@case("xv41_stack_left", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk cube whose last triangle's symbol says "
      "it has a child across its edge 1: the stack holds a slot after the last triangle")
def _():
    s = walk_values("symbols")
    return walk_file(walk_fields(symbols=_codes(s[:-1] + [s[-1] + 4])))


@case("xv41_escape_left", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk cube with one escape more than its walk "
      "uses (escape_count 4, a last escape 0)")
def _():
    f = walk_fields()
    (v, t, x) = _all_varints(np.frombuffer(f["counts"], dtype=np.uint8))
    return walk_file({**f, "counts": _codes([v, t, x + 1]), "escapes": f["escapes"] + b"\x00"})


@case("xv41_escape_short", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk cube whose escape_count is 2 and which "
      "stores two escapes: its root needs three")
def _():
    f = walk_fields()
    (v, t, x) = _all_varints(np.frombuffer(f["counts"], dtype=np.uint8))
    return walk_file({**f, "counts": _codes([v, t, 2]), "escapes": f["escapes"][:2]})


@case("xv41_left_none", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk cube whose second triangle's corner code "
      "is 1, left: the only open edge ending at its corner i1 starts at its parent's opposite corner, so there is "
      "none to name")
def _():
    s = walk_values("symbols")
    return walk_file(walk_fields(symbols=_codes(s[:1] + [s[1] - s[1] % 4 + 1] + s[2:])))


def _second_step(escape: int) -> bytes:
    """The shell walk cube with its second triangle's third corner coded as a step: symbol code 3
    and ``escape`` after the root's three."""
    f = walk_fields()
    s = walk_values("symbols")
    (v, t, x) = _all_varints(np.frombuffer(f["counts"], dtype=np.uint8))
    e = walk_values("escapes")
    return walk_file({**f, "counts": _codes([v, t, x + 1]), "symbols": _codes(s[:1] + [s[1] - s[1] % 4 + 3] + s[2:]),
                      "escapes": _codes(e[:3] + [escape] + e[3:])})


@case("xv41_corner_twice", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk cube whose second triangle's third "
      "corner is coded as a step of -1 from its i1 (escape 1): corner i1 - 1, which is its i0")
def _():
    return _second_step(1)


@case("xv41_unnamed_step", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk cube whose second triangle's third "
      "corner is a step of +1 from its i1 (escape 2): corner 3, not yet named")
def _():
    return _second_step(2)


@case("xv41_mode_bits", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk of the all-explicit cube whose coordinate "
      "mode is 4: a bit above bit 1")
def _():
    return walk_file(walk_fields(TREE_BOX, 0, mode=b"\x04"))


@case("xv41_table_empty", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk of the all-explicit cube in mode 2 "
      "(tables) whose x table has a count of 0")
def _():
    f = walk_fields(TREE_BOX, 2)
    return walk_file({**f, "tables": b"\x00" + f["tables"][1:]})


@case("xv41_table_index", "BAD_GROUP_STRUCTURE", "version 4.1 shell walk of the all-explicit cube in mode 2 whose "
      "x table holds one value (0) where its corners' indices reach 1")
def _():
    f = walk_fields(TREE_BOX, 2)
    t = _all_varints(np.frombuffer(f["tables"], dtype=np.uint8))
    # t: count 2, first 0, gap 0 per axis: drop x's second value.
    return walk_file({**f, "tables": _codes([1, t[1]] + t[3:])})


@case("xv41_truncated", "BAD_PAYLOAD", "version 4.1 shell walk cube whose escape_count is 12 where it stores 3, "
      "and which ends after its faces: the escapes read 9 bytes of the faces, and the body ends inside the faces")
def _():
    f = walk_fields()
    (v, t, x) = _all_varints(np.frombuffer(f["counts"], dtype=np.uint8))
    return walk_file({"counts": _codes([v, t, 12]), "symbols": f["symbols"], "escapes": f["escapes"],
                      "faces": f["faces"]})


# -- shell walks with multi-parallelograms (spec/pln.md §9.14, version 4.2) ------------------------

MULTI = int(GroupKind.SHELL_WALK_MULTI)


@case("xv42_multi_in_4_1", "UNKNOWN_GROUP_KIND", "a well-formed shell walk with multi-parallelograms (kind 10) of "
      "the all-explicit cube in a version 4.1 file, whose version has no kind 10")
def _():
    return walk_file(walk_fields(TREE_BOX, 1, GroupKind.SHELL_WALK_MULTI), version=(4, 1), kind=MULTI)


@case("xv42_mode_bits", "BAD_GROUP_STRUCTURE", "version 4.2 shell walk with multi-parallelograms of the "
      "all-explicit cube whose coordinate mode is 4: a bit above bit 1")
def _():
    return walk_file(walk_fields(TREE_BOX, 0, GroupKind.SHELL_WALK_MULTI, mode=b"\x04"), version=(4, 2), kind=MULTI)


@case("xv42_average_beyond", "BAD_GROUP_STRUCTURE", "version 4.2 shell walk with multi-parallelograms of the "
      "all-explicit cube whose corners' x are 2^52 but the last corner's, 2^52 + 1: every residual is within 2^52 "
      "(the last is 1 over its average of parallelograms, 2^52), the last resolved value is beyond it")
def _():
    grid = np.asarray(TREE_BOX.grid, dtype=np.int64).copy()
    grid[:, 0] = 1 << 52
    grid[-1, 0] += 1
    return walk_file(walk_fields(dataclasses.replace(TREE_BOX, grid=grid), 0, GroupKind.SHELL_WALK_MULTI),
                     version=(4, 2), kind=MULTI)


@case("xv42_table_index", "BAD_GROUP_STRUCTURE", "version 4.2 shell walk with multi-parallelograms of the "
      "all-explicit cube in mode 2 (x table of 2 values) whose last corner, predicted by the average of its four "
      "parallelograms, has an x residual 2 larger: every earlier index is in its table, the last resolves to 2 or 3")
def _():
    f = walk_fields(TREE_BOX, 2, GroupKind.SHELL_WALK_MULTI)
    z = np.array(_all_varints(np.frombuffer(f["coordinates"], dtype=np.uint8)), dtype=np.uint64).reshape(3, -1)
    r = varint.unzigzag(z)
    r[0, -1] += 2
    return walk_file({**f, "coordinates": varint.encode(varint.zigzag(r).reshape(-1))}, version=(4, 2), kind=MULTI)


# -- copies (spec/pln.md §9.15, version 4.2) ------------------------------------------------------

COPY = int(GroupKind.COPY)


def copies_file(bodies: list[tuple[int, bytes]], version: tuple[int, int] = (4, 2)) -> bytes:
    """The cube's planes (float64) in a version 4.2 file (or ``version``) with one object per group of
    ``bodies`` (kind, raw body), each stored without compression."""
    n = len(bodies)
    layout = [(schema.PHDR, header(version=version, coding=Coding.FLOAT64, object_count=n, group_count=n))]
    for i, (kind, body) in enumerate(bodies):
        layout.append((schema.OBJT, records.encode_object(ObjectRecord(i, f"cube{i}", None, None), version[0])))
        if i == 0:
            layout.append((schema.PLNS, records.encode_planes(0, CUBE, dataclasses.replace(V4_F64, version=version),
                                                              False)))
        layout.append((schema.GRUP, schema.GroupHead3.build(dict(index=i, object=i, kind=kind, compression=0,
                                                                 raw_size=len(body), body=body))))
    return frame(finish(layout, True, version[0]))


@case("xv42_copy_in_4_1", "UNKNOWN_GROUP_KIND", "a convex cube and a well-formed copy of it (kind 11) in a version "
      "4.1 file, whose version has no kind 11")
def _():
    return copies_file([(0, CUBE_REFS), (COPY, CUBE_REFS + b"\x00")], version=(4, 1))


@case("xv42_copy_later", "BAD_GROUP_STRUCTURE", "version 4.2: a convex cube and a group copying group 1, itself: "
      "a source not before the copy")
def _():
    return copies_file([(0, CUBE_REFS), (COPY, CUBE_REFS + b"\x01")])


@case("xv42_copy_of_copy", "BAD_GROUP_STRUCTURE", "version 4.2: a convex cube, a copy of it, and a copy of that "
      "copy (source 1, of kind 11)")
def _():
    return copies_file([(0, CUBE_REFS), (COPY, CUBE_REFS + b"\x00"), (COPY, CUBE_REFS + b"\x01")])


@case("xv42_copy_refs", "BAD_GROUP_STRUCTURE", "version 4.2: a convex cube on references 0 to 5 and a copy of it "
      "whose references are 0 to 4: not the source's")
def _():
    return copies_file([(0, CUBE_REFS), (COPY, b"\x05\x00\x01\x01\x01\x01\x00" + b"\x00")])


@case("xv42_copy_roles", "BAD_GROUP_STRUCTURE", "version 4.2: a convex cube and a copy of it whose role bits mark "
      "reference 0 bounding: not the source's")
def _():
    return copies_file([(0, CUBE_REFS), (COPY, CUBE_REFS[:-1] + b"\x01" + b"\x00")])


@case("xv42_copy_trailing", "BAD_PAYLOAD", "version 4.2: a convex cube and a copy of it with a byte after its "
      "source")
def _():
    return copies_file([(0, CUBE_REFS), (COPY, CUBE_REFS + b"\x00\x00")])


@case("xv42_copy_truncated", "BAD_PAYLOAD", "version 4.2: a convex cube and a copy whose body ends inside its "
      "source's varint")
def _():
    return copies_file([(0, CUBE_REFS), (COPY, CUBE_REFS + b"\x80")])


# -- version 5.0: varint chunk lengths, the up axis in the header, groups without references -----

V50 = (5, 0)


def v5_layout(*extra: tuple[bytes, bytes], up_axis: str | None = None, groups: list[bytes] | None = None,
              version: tuple[int, int] = V50) -> Layout:
    """The cube of spec/pln-1.md §12 in a version 5.0 file (or ``version``; float32, as a convex group, or
    ``groups``), chunks ``extra`` after PHDR, before iNDX."""
    groups = [grup_v5(np.arange(6), 0)] if groups is None else groups
    layout = [(schema.PHDR, header(version=version, up_axis=up_axis, group_count=len(groups))), *extra,
              (schema.OBJT, records.encode_object(ObjectRecord(0, "cube", None, None), 5)),
              (schema.PLNS, records.encode_planes(0, CUBE, dataclasses.replace(SPEC_HEADER, version=version), False))]
    return layout + [(schema.GRUP, g) for g in groups]


def grup_v5(refs: np.ndarray, kind: int, shell=None, index: int = 0) -> bytes:
    refs = np.asarray(refs, dtype=np.uint32)
    return records.encode_group(PartGroup(index, 0, kind, refs, np.zeros(len(refs), bool), shell=shell), False, 5)


def v5_file(layout: Layout, index: bool = True) -> bytes:
    return frame(finish(layout, index, 5))


def _v5_length(data: bytes, chunk: int, length: bytes) -> bytes:
    """``data`` (a version 5 file) with the one-byte length of its chunk number ``chunk`` replaced by ``length``."""
    at = offsets(finish(v5_layout(), False, 5))[chunk] + 4
    return data[:at] + length + data[at + 1:]


V5_FILE = v5_file(v5_layout(), index=False)


@case("xv50_length_not_minimal", "BAD_CHUNK_LENGTH", "version 5.0: the OBJT length, 8, written as the two-byte "
      "varint 88 00: not minimal (spec §4.1)")
def _():
    return _v5_length(V5_FILE, 1, b"\x88\x00")


@case("xv50_length_past_5_bytes", "CHUNK_TOO_LONG", "version 5.0: the OBJT length a varint whose fifth byte has "
      "bit 7 set (88 80 80 80 80 00): longer than a varint32 length may be", also=("LIMIT_EXCEEDED", "TRUNCATED"))
def _():
    return _v5_length(V5_FILE, 1, b"\x88\x80\x80\x80\x80\x00")


@case("xv50_length_2_31", "CHUNK_TOO_LONG", "version 5.0: the OBJT length 2^31 (80 80 80 80 08), above the 2^31-1 "
      "maximum", also=("LIMIT_EXCEEDED", "TRUNCATED"))
def _():
    return _v5_length(V5_FILE, 1, b"\x80\x80\x80\x80\x08")


@case("xv50_truncated_length", "TRUNCATED", "version 5.0: the file ends after the GRUP type and the first byte of "
      "a two-byte length varint")
def _():
    at = offsets(finish(v5_layout(), False, 5))[3] + 4
    return V5_FILE[:at] + b"\x80"


@case("xv50_u32_framing", "CRC_MISMATCH", "a version 5.0 header followed by chunks framed as version 4 frames "
      "them (u32 lengths): the OBJT's u32 length 8 read as the varint 08 leaves 00 00 00 in its payload and its "
      "CRC wrong")
def _():
    layout = finish(v5_layout(), False, 5)
    return schema.SIGNATURE + b"".join(chunk_bytes(t, p) for t, p in layout)


@case("xv50_meta_up_axis", "BAD_METADATA", "version 5.0: a mETA chunk up_axis = Z, which a version 5 file says "
      "in its header (spec §10.3)")
def _():
    return v5_file(v5_layout((schema.META, b"up_axis\x00Z")))


@case("xv50_up_axis_3", "BAD_HEADER_VALUE", "version 5.0: bits 4-5 of the header's units byte 3, no up axis "
      "(spec §5)")
def _():
    layout = v5_layout()
    phdr = bytearray(layout[0][1])
    phdr[7] = 0x31
    return v5_file([(schema.PHDR, bytes(phdr))] + layout[1:])


@case("xv50_header_short", "BAD_PAYLOAD", "version 5.0: a PHDR of 7 bytes, under the 8 of the fixed part")
def _():
    layout = v5_layout()
    return v5_file([(schema.PHDR, layout[0][1][:7])] + layout[1:])


@case("xv50_convex_no_refs", "BAD_GROUP_STRUCTURE", "version 5.0: a convex group (kind 0) without references: "
      "only shells and copies may have none (spec §9.2)")
def _():
    body = b"\x00"
    group = schema.GroupHead3.build(dict(index=0, object=0, kind=0, compression=0, raw_size=len(body), body=body))
    return v5_file(v5_layout(groups=[group]))


@case("xv50_colours_no_refs", "BAD_COLOURS", "version 5.0: the open pyramid as a shell without references and a "
      "cOLR of count 0 for it of 8 bytes: a group without references takes one colour, which it lacks (spec §10.1)")
def _():
    colours = schema.ColoursHead.build(dict(group=0, count=0))
    return v5_file(v5_layout(groups=[grup_v5(np.zeros(0), GroupKind.SHELL, SHELL_PYRAMID)]) + [(schema.COLR, colours)])


# -- version 5.1: shell walks with reflections (spec/pln.md §9.16) ----------------------------------

REFLECT = int(GroupKind.SHELL_WALK_REFLECT)


def reflect_file(shell, fields: dict[str, bytes], version: tuple[int, int] = (5, 1), kind: int = REFLECT) -> bytes:
    """``shell`` as a shell walk with reflections (kind 12, or ``kind``) of kind data ``fields`` (its grid in
    f32) on the cube's six planes, whose faces it names, in a version 5.1 file (or ``version``),
    uncompressed."""
    body = CUBE_REFS + b"".join({**fields, "grid": shellfields.grid_bytes(shell, 5)}.values())
    group = schema.GroupHead3.build(dict(index=0, object=0, kind=kind, compression=0, raw_size=len(body), body=body))
    return v5_file(v5_layout(groups=[group], version=version))


def _reflect_residuals(fields: dict[str, bytes]) -> np.ndarray:
    z = np.array(_all_varints(np.frombuffer(fields["coordinates"], dtype=np.uint8)), dtype=np.uint64).reshape(3, -1)
    return varint.unzigzag(z)


@case("xv51_reflect_in_5_0", "UNKNOWN_GROUP_KIND", "a well-formed shell walk with reflections (kind 12) of the "
      "all-explicit box in a version 5.0 file, whose version has no kind 12")
def _():
    return reflect_file(TREE_BOX, walk_fields(TREE_BOX, 0, GroupKind.SHELL_WALK_REFLECT), version=(5, 0))


@case("xv51_reflect_mode_bits", "BAD_GROUP_STRUCTURE", "version 5.1 shell walk with reflections of the "
      "all-explicit box whose coordinate mode is 4: a bit above bit 1")
def _():
    return reflect_file(TREE_BOX, walk_fields(TREE_BOX, 0, GroupKind.SHELL_WALK_REFLECT, mode=b"\x04"))


@case("xv51_reflect_beyond", "BAD_GROUP_STRUCTURE", "version 5.1 shell walk with reflections of the "
      "all-explicit box whose corners' x are 2^52 but the last corner's, 2^52 + 1: the last corner's chain turns "
      "(its steps differ in y and z), its residual is 1 over the prediction 2^52, the resolved value beyond it")
def _():
    grid = np.asarray(TREE_BOX.grid, dtype=np.int64).copy()
    grid[:, 0] = 1 << 52
    grid[-1, 0] += 1
    shell = dataclasses.replace(TREE_BOX, grid=grid)
    return reflect_file(shell, walk_fields(shell, 0, GroupKind.SHELL_WALK_REFLECT))


@case("xv51_reflect_table_index", "BAD_GROUP_STRUCTURE", "version 5.1 shell walk with reflections of the "
      "all-explicit box in mode 2 (x table of 2 values) whose last corner, predicted by its turning chain of "
      "indices, has an x residual 2 larger: every earlier index is in its table, the last resolves past it")
def _():
    f = walk_fields(TREE_BOX, 2, GroupKind.SHELL_WALK_REFLECT)
    r = _reflect_residuals(f)
    r[0, -1] += 2
    return reflect_file(TREE_BOX, {**f, "coordinates": varint.encode(varint.zigzag(r).reshape(-1))})


# -- version 5.2: shell walks stepping from the later gate corner (spec/pln.md §9.17) -----------------

LATER = int(GroupKind.SHELL_WALK_LATER)


def later_file(shell, fields: dict[str, bytes], version: tuple[int, int] = (5, 2)) -> bytes:
    """``shell`` as a shell walk stepping from the later gate corner (kind 13) of kind data ``fields`` in a
    version 5.2 file (or ``version``), as :func:`reflect_file` lays it out."""
    return reflect_file(shell, fields, version, LATER)


@case("xv52_later_in_5_1", "UNKNOWN_GROUP_KIND", "a well-formed shell walk stepping from the later gate corner "
      "(kind 13) of the all-explicit box in a version 5.1 file, whose version has no kind 13")
def _():
    return later_file(TREE_BOX, walk_fields(TREE_BOX, 0, GroupKind.SHELL_WALK_LATER), version=(5, 1))


@case("xv52_later_mode_bits", "BAD_GROUP_STRUCTURE", "version 5.2 shell walk stepping from the later gate corner "
      "of the all-explicit box whose coordinate mode is 4: a bit above bit 1")
def _():
    return later_file(TREE_BOX, walk_fields(TREE_BOX, 0, GroupKind.SHELL_WALK_LATER, mode=b"\x04"))


@case("xv52_later_table_index", "BAD_GROUP_STRUCTURE", "version 5.2 shell walk stepping from the later gate corner "
      "of the all-explicit box in mode 2 (x table of 2 values) whose last corner has an x residual 2 larger: "
      "every earlier index is in its table, the last resolves past it")
def _():
    f = walk_fields(TREE_BOX, 2, GroupKind.SHELL_WALK_LATER)
    r = _reflect_residuals(f)
    r[0, -1] += 2
    return later_file(TREE_BOX, {**f, "coordinates": varint.encode(varint.zigzag(r).reshape(-1))})


# -- what a reader written from the text alone found undecided (issue 49) ---------------------------

def _units_byte(version: tuple[int, int], units: int) -> bytes:
    layout = cube(PHDR=header(version=version))
    phdr = bytearray(layout[0][1])
    phdr[8] = units  # A.1: units at offset 8 of the 108-byte header of versions 1.0 and 2.0
    return file([(schema.PHDR, bytes(phdr))] + layout[1:])


@case("xv1_units_up_axis", "BAD_HEADER_VALUE", "version 1.0 cube whose units byte is 0x21: metre with version 5's "
      "up axis Z in bits 4-5, which versions 1.0 to 4.2 do not have: the unit alone, 33, above 7 (spec A.1, A.5)")
def _():
    return _units_byte((1, 0), 0x21)


@case("xv2_units_up_axis", "BAD_HEADER_VALUE", "version 2.0 cube whose units byte is 0x11: metre with version 5's "
      "up axis Y in bits 4-5, a unit of 17 before version 5 (spec A.1, A.2, A.5)")
def _():
    return _units_byte((2, 0), 0x11)


@case("xv4_skipped_kind_no_refs", "BAD_GROUP_STRUCTURE", "version 4.3 (a newer minor version) with a group of "
      "kind 14 without references after the cube's convex group: before version 5 m = 0 is an error in every "
      "kind, one the reader skips too (spec A.5, §9.2)")
def _():
    skipped = schema.GroupHead3.build(dict(index=1, object=0, kind=14, compression=0, raw_size=1, body=b"\x00"))
    convex = records.encode_group(PartGroup(0, 0, 0, np.arange(6, dtype=np.uint32), np.zeros(6, bool)), False, 4)
    layout = cube(PHDR=header(version=(4, 3), coding=Coding.FLOAT64),
                  OBJT=records.encode_object(ObjectRecord(0, "cube", None, None), 4),
                  PLNS=records.encode_planes(0, CUBE, dataclasses.replace(V4_F64, version=(4, 3)), False),
                  GRUP=convex)
    return frame(finish(layout + [(schema.GRUP, skipped)], True, 4))


def _few_planes_walk() -> dict[str, bytes]:
    """TREE_MIXED's shell walk with its last two triangles free: named corner 5 is then on two face planes."""
    f = walk_fields(TREE_MIXED, 0)
    return {**f, "faces": f["faces"][:-2] + b"\x01\x00"}


@case("xv41_few_planes_cut", "BAD_PAYLOAD", "version 4.1 shell walk of the mixed cube whose last two triangles "
      "are free, leaving named corner 5 on two face planes, and whose body ends inside its coordinates: the named "
      "corners are checked with the rest, once every field is read (spec §9.11, §9.13, §12.1)")
def _():
    f = _few_planes_walk()
    return walk_file({**f, "coordinates": f["coordinates"][:-1]})


@case("xv41_few_planes", "BAD_GROUP_STRUCTURE", "xv41_few_planes_cut with its coordinates whole: named corner 5 "
      "on two face planes")
def _():
    return walk_file(_few_planes_walk())


@case("xv41_mode_bits_cut", "BAD_PAYLOAD", "version 4.1 shell walk of the all-explicit cube whose coordinate mode "
      "is 4 and whose body ends inside its coordinates: the mode's bits 2-7 are checked with the rest, once every "
      "field is read (spec §9.13, §12.1)")
def _():
    f = walk_fields(TREE_BOX, 0, mode=b"\x04")
    return walk_file({**f, "coordinates": f["coordinates"][:-1]})


@case("xmeta_after_index", "CHUNK_ORDER", "mETA up_axis = Z between the iNDX and the PEND: a chunk after iNDX, "
      "checked by its place before its payload (spec §4.3, §10.3, §12.1), not BAD_METADATA")
def _():
    layout = finish(cube())
    return frame(layout[:-1] + [(schema.META, b"up_axis\x00Z"), layout[-1]])


# -- version 6.0 (issue 52): header, body segments, records, index (spec §4.5, §4.6, §5, §10.2) ------------

V6_HEADER = dataclasses.replace(SPEC_HEADER, version=(6, 0))
#: The version 6 header fields of the float32 cube with its bbox and without counts.
V6_PHDR = records.encode_header(V6_HEADER)


def cube_records(**parts: bytes) -> list[tuple[int, bytes]]:
    """The cube's object, planes and group records of version 6; ``OBJT=``, ``PLNS=``, ``GRUP=`` replace one."""
    payloads = {"OBJT": records.encode_object(ObjectRecord(0, "cube", None, None), 6),
                "PLNS": records.encode_planes(0, CUBE, V6_HEADER, False),
                "GRUP": records.encode_group(PartGroup(0, 0, 0, np.arange(6, dtype=np.uint32), np.zeros(6, bool)),
                                             False, 6)}
    payloads.update(parts)
    return [(schema.RECORD_TAGS[t.encode()], p) for t, p in payloads.items()]


def raw_records(items: list[tuple[int, bytes]]) -> bytes:
    return b"".join(segments.record_bytes(t, p) for t, p in items)


def segment(items: list[tuple[int, bytes]] | bytes, method: int = 0, raw_size: int | None = None) -> bytes:
    """A body segment of raw ``items`` (records, or raw bytes), stored with ``method``."""
    raw = items if isinstance(items, bytes) else raw_records(items)
    stored = raw if method == 0 else zlib.compress(raw, 9)
    return bytes([method]) + schema.Varint32.build(len(raw) if raw_size is None else raw_size) + stored


def v6_framed(phdr: bytes, *chunks: tuple[bytes, bytes], end: bytes = b"") -> bytes:
    """Signature, PHDR (u32 length), ``chunks`` and PEND with varint lengths (spec §4.1)."""
    return (schema.SIGNATURE + chunk_bytes(schema.PHDR, phdr)
            + b"".join(chunk_bytes(t, p, True) for t, p in chunks) + chunk_bytes(schema.PEND, end, True))


def v6_fields(fields: bytes, header_size: int | None = None) -> bytes:
    """A version 6.0 PHDR payload's version and header fields, ``header_size`` as given or right."""
    return b"\x06\x00" + schema.Varint32.build(len(fields) if header_size is None else header_size) + fields


V6_FILE = v6_framed(V6_PHDR + segment(cube_records()))


@case("xv6_header_size_past", "BAD_PAYLOAD", "version 6.0: header_size 17, more than the 15 bytes of the PHDR "
      "payload after it (spec §5 check 3)")
def _():
    fields = V6_PHDR[3:]
    return v6_framed(v6_fields(fields, len(fields) + 2))


@case("xv6_header_size_short", "BAD_PAYLOAD", "version 6.0: header_size 4, with flags saying BBOX_KNOWN: the header "
      "fields end inside the bbox (spec §5 check 4), though a segment follows")
def _():
    return v6_framed(v6_fields(V6_PHDR[3:], 4) + segment(cube_records()))


@case("xv6_r32_not_minimal", "BAD_PAYLOAD", "version 6.0: the tolerance an r32 written 80 00, a varint that is not "
      "minimal (spec §2.2)")
def _():
    return v6_framed(v6_fields(bytes([0, 1, 0x80, 0, 0])) + segment(cube_records()))


@case("xv6_r32_past_32_bits", "BAD_PAYLOAD", "version 6.0: the error bound an r32 of 2^32 (80 80 80 80 10), above "
      "a varint32 (spec §2.2)")
def _():
    return v6_framed(v6_fields(bytes([0, 1, 0, 0x80, 0x80, 0x80, 0x80, 0x10])) + segment(cube_records()))


@case("xv6_h_range_reversed", "BAD_HEADER_VALUE", "version 6.0: coding 2 with h_min 1.0 and h_max 0.0 (spec §5 "
      "check 5)")
def _():
    fields = bytes([2 << 3, 1]) + (0x21).to_bytes(2, "little") + b"\xfc\x03\x00" + b"\x00\x00"
    return v6_framed(v6_fields(fields))


@case("xv6_body_empty", "BAD_PAYLOAD", "version 6.0: a BODY chunk with an empty payload, which ends inside the "
      "segment's compression byte (spec §4.5 check 1)")
def _():
    return v6_framed(V6_PHDR + segment(cube_records()), (schema.BODY, b""))


@case("xv6_body_method_3", "BAD_COMPRESSION", "version 6.0: the body segment in PHDR with compression method 3 "
      "(spec §4.5, §6 check 1)")
def _():
    seg = bytearray(segment(cube_records()))
    seg[0] = 3
    return v6_framed(V6_PHDR + bytes(seg))


@case("xv6_body_raw_limit", "LIMIT_EXCEEDED", "version 6.0: a BODY segment of deflate declaring a raw size of "
      "256 MiB + 1, above the payload limit of spec §12.4 (§6 check 2)")
def _():
    return v6_framed(V6_PHDR + segment(cube_records()[:2]),
                     (schema.BODY, segment(cube_records()[2:], 1, (256 << 20) + 1)))


@case("xv6_body_ratio", "LIMIT_EXCEEDED", "version 6.0: a deflated segment of the cube's records declaring a raw "
      "size 1101 times its stored bytes (spec §6 check 4)")
def _():
    stored = zlib.compress(raw_records(cube_records()), 9)
    return v6_framed(V6_PHDR + bytes([1]) + schema.Varint32.build(1101 * len(stored)) + stored)


@case("xv6_body_size", "SIZE_MISMATCH", "version 6.0: the segment in PHDR stored (method 0) with a raw size one "
      "more than its stored bytes (spec §6 check 3)")
def _():
    raw = raw_records(cube_records())
    return v6_framed(V6_PHDR + segment(raw, 0, len(raw) + 1))


@case("xv6_record_past_segment", "BAD_PAYLOAD", "version 6.0: the group record's length one more than the bytes "
      "left in its segment (spec §4.6 check 2)")
def _():
    raw = bytearray(raw_records(cube_records()))
    group = raw_records(cube_records()[:2])
    raw[len(group) + 1] += 1
    return v6_framed(V6_PHDR + segment(bytes(raw)))


@case("xv6_record_head_cut", "BAD_PAYLOAD", "version 6.0: the segment ends after the tag of a fourth record, inside "
      "its head (spec §4.6 check 1)")
def _():
    return v6_framed(V6_PHDR + segment(raw_records(cube_records()) + b"\x04"))


@case("xv6_record_tag_6", "UNKNOWN_CRITICAL_CHUNK", "version 6.0: a record of tag 6 after the cube's group, a "
      "critical record type 6.0 does not define (spec §4.6 check 3)")
def _():
    return v6_framed(V6_PHDR + segment(cube_records() + [(6, b"")]))


@case("xv6_record_tag_0", "UNKNOWN_CRITICAL_CHUNK", "version 6.0: a record of tag 0 before the cube's object "
      "(spec §4.6 check 3)")
def _():
    return v6_framed(V6_PHDR + segment([(0, b"\x00")] + cube_records()))


@case("xv6_objt_chunk", "CHUNK_ORDER", "version 6.0: the cube's object as an OBJT chunk of version 5 after PHDR, "
      "before a segment of its planes and group: a record of a body segment in version 6 (spec §4.2)")
def _():
    return v6_framed(V6_PHDR, (schema.OBJT, records.encode_object(ObjectRecord(0, "cube", None, None), 5)),
                     (schema.BODY, segment(cube_records()[1:])))


@case("xv6_meta_chunk", "CHUNK_ORDER", "version 6.0: a mETA chunk (keyword units_note) after PHDR: metadata is a "
      "record of tag 5 in version 6 (spec §4.2, §10.3)")
def _():
    return v6_framed(V6_PHDR, (schema.META, b"units_note\x00m"), (schema.BODY, segment(cube_records())))


@case("xv6_body_after_index", "CHUNK_ORDER", "version 6.0: a BODY chunk after iNDX (spec §4.3 rule 3)")
def _():
    recs = cube_records()
    entries = [(8, 0, 1, 0), (8, len(raw_records(recs[:1])), 2, 0), (8, len(raw_records(recs[:2])), 3, 0)]
    return v6_framed(V6_PHDR + segment(recs), (schema.INDX, segments.encode_index(entries)),
                     (schema.BODY, segment([(5, b"note\x00x")])))


@case("xv6_meta_after_object", "BAD_METADATA", "version 6.0: a metadata record after the cube's object record "
      "(spec §4.6 check 4, §10.3)")
def _():
    recs = cube_records()
    return v6_framed(V6_PHDR + segment(recs[:1] + [(5, b"note\x00x")] + recs[1:]))


@case("xv6_meta_up_axis", "BAD_METADATA", "version 6.0: a metadata record up_axis = Z, which a version 6 file says "
      "in its header (spec §10.3)")
def _():
    return v6_framed(V6_PHDR + segment([(5, b"up_axis\x00Z")] + cube_records()))


@case("xv6_group_before_object", "BAD_OBJECT_REFERENCE", "version 6.0: the group record before the object record "
      "it names (spec §4.3 rule 2)")
def _():
    o, p, g = cube_records()
    return v6_framed(V6_PHDR + segment([p, g, o]))


@case("xv6_group_before_planes", "BAD_PLANE_REFERENCE", "version 6.0: the group record before the planes record "
      "it references (spec §4.3 rule 2)")
def _():
    o, p, g = cube_records()
    return v6_framed(V6_PHDR + segment([o, g, p]))


@case("xv6_planes_size", "SIZE_MISMATCH", "version 6.0: a planes record of count 6 with 71 bytes of float32 "
      "data, not 72 (spec §7.1 check 3)")
def _():
    planes = records.encode_planes(0, CUBE, V6_HEADER, False)[:-1]
    return v6_framed(V6_PHDR + segment(cube_records(PLNS=planes)))


@case("xv6_planes_count_cut", "BAD_PAYLOAD", "version 6.0: a planes record of one byte 0x86, a count varint the "
      "record ends inside (spec §7.1 check 1)")
def _():
    return v6_framed(V6_PHDR + segment(cube_records(PLNS=b"\x86")))


@case("xv6_colours_extra", "BAD_COLOURS", "version 6.0: a colours record of group 0, count 6, with 28 bytes of "
      "colours: not 4 and more than 6 x 4 (spec §10.1)")
def _():
    return v6_framed(V6_PHDR + segment(cube_records() + [(4, b"\x00\x06" + bytes(28))]))


@case("xv6_colours_short", "BAD_PAYLOAD", "version 6.0: a colours record of group 0, count 6, with 8 bytes of "
      "colours: not 4 and fewer than 6 x 4 (spec §10.1)")
def _():
    return v6_framed(V6_PHDR + segment(cube_records() + [(4, b"\x00\x06" + bytes(8))]))


def _indexed(entries: list[tuple[int, int, int, int]] | None = None, payload: bytes | None = None) -> bytes:
    recs = cube_records()
    right = [(8, 0, 1, 0), (8, len(raw_records(recs[:1])), 2, 0), (8, len(raw_records(recs[:2])), 3, 0)]
    payload = segments.encode_index(right if entries is None else entries) if payload is None else payload
    phdr = V6_PHDR + segment(recs)
    at = 8 + len(chunk_bytes(schema.PHDR, phdr))
    return v6_framed(phdr, (schema.INDX, payload), end=at.to_bytes(8, "little"))


@case("xv6_index_raw_offset", "BAD_INDEX", "version 6.0: an index whose planes entry gives raw offset 1, not the "
      "planes record's offset in its segment (spec §10.2)")
def _():
    return _indexed([(8, 0, 1, 0), (8, 1, 2, 0), (8, len(raw_records(cube_records()[:2])), 3, 0)])


@case("xv6_index_chunk_offset", "BAD_INDEX", "version 6.0: an index whose group entry's chunk offset difference is "
      "1, naming byte 9, not the PHDR chunk at 8 that holds the record (spec §10.2)")
def _():
    return _indexed([(8, 0, 1, 0), (8, len(raw_records(cube_records()[:1])), 2, 0),
                     (9, len(raw_records(cube_records()[:2])), 3, 0)])


@case("xv6_index_count", "BAD_PAYLOAD", "version 6.0: an index of count 5 in 13 bytes: more entries than a quarter "
      "of the bytes after the count (spec §10.2)")
def _():
    recs = cube_records()
    right = segments.encode_index([(8, 0, 1, 0), (8, len(raw_records(recs[:1])), 2, 0),
                                   (8, len(raw_records(recs[:2])), 3, 0)])
    return _indexed(payload=b"\x05" + right[1:])


@case("xv6_index_extra", "BAD_INDEX", "version 6.0: an index with a byte after its three entries (spec §10.2)")
def _():
    recs = cube_records()
    right = segments.encode_index([(8, 0, 1, 0), (8, len(raw_records(recs[:1])), 2, 0),
                                   (8, len(raw_records(recs[:2])), 3, 0)])
    return _indexed(payload=right + b"\x00")


@case("xv6_count_mismatch", "COUNT_MISMATCH", "version 6.0: the header's counts say 2 objects; the file has 1 "
      "(spec §4.4, §5)")
def _():
    phdr = records.encode_header(dataclasses.replace(V6_HEADER, plane_count=6, object_count=2, group_count=1))
    return v6_framed(phdr + segment(cube_records()))


@case("xv50_body_chunk", "UNKNOWN_CRITICAL_CHUNK", "version 5.0: a BODY chunk, a critical chunk type of version "
      "6 only (spec §4.2)")
def _():
    return v5_file(v5_layout((schema.BODY, segment(cube_records()))))
