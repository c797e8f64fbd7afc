"""Construct declarations of the .pln container, versions 1 to 6, read beside spec/pln.md: each
under the section it implements ("spec §x"), the fixed-size structures of versions 1 and 2 under its
Appendix A.1.

Only structure lives here. Bulk arrays (triplets, plane references, role
bits, cell entries, tree tokens, colours, index entries) are ``Bytes`` fields
that the payload modules view with ``numpy.frombuffer``. All integers and
floats are little-endian.
"""

import construct as cs
import numpy as np

VARINT_MAX_BYTES = 10


class Leb128(cs.Construct):
    """A minimal unsigned LEB128 varint below ``2**bits`` (spec §2.2; varint32 of 3.0): the
    heads of version 3 chunks. Parsing fails on a varint that is not minimal, is longer than 10
    bytes, or is out of range, so that every byte string has at most one reading."""

    def __init__(self, bits: int = 64):
        super().__init__()
        self.bits = bits

    def _parse(self, stream, context, path):
        value = shift = 0
        for n in range(1, VARINT_MAX_BYTES + 1):
            b = cs.stream_read(stream, 1, path)[0]
            value |= (b & 0x7F) << shift
            shift += 7
            if b < 0x80:
                if n > 1 and b == 0:
                    raise cs.ValidationError("varint is not minimal", path=path)
                if value >> self.bits:
                    raise cs.ValidationError(f"varint is 2^{self.bits} or more", path=path)
                return value
        raise cs.ValidationError(f"varint is longer than {VARINT_MAX_BYTES} bytes", path=path)

    def _build(self, obj, stream, context, path):
        if not isinstance(obj, int) or obj < 0 or obj >> self.bits:
            raise cs.IntegerError(f"{obj!r} is not an integer in 0..2^{self.bits} - 1", path=path)
        out, rest = bytearray(), obj
        while rest >= 0x80:
            out.append(rest & 0x7F | 0x80)
            rest >>= 7
        out.append(rest)
        cs.stream_write(stream, bytes(out), len(out), path)
        return obj

    def _sizeof(self, context, path):
        raise cs.SizeofError("a varint has no fixed size", path=path)


Varint = Leb128(64)
Varint32 = Leb128(32)

# spec §3 Signature
SIGNATURE = b"\x89PLN\r\n\x1a\n"
Signature = cs.Const(SIGNATURE)

# spec §4 Chunk framing: type, length, payload, CRC-32 over type + payload
ChunkHead = cs.Struct(
    "type" / cs.Bytes(4),
    "length" / cs.Int32ul,
)
ChunkTail = cs.Struct(
    "crc" / cs.Int32ul,
)
MAX_CHUNK_LENGTH = 2**31 - 1
#: Version 5 frames every chunk after PHDR with a varint32 length (spec §4.1): at most 5 bytes.
LENGTH_VARINT_BYTES = 5

# spec §4.2 Chunk types
PHDR = b"PHDR"
OBJT = b"OBJT"
PLNS = b"PLNS"
GRUP = b"GRUP"
PEND = b"PEND"
COLR = b"cOLR"
INDX = b"iNDX"
META = b"mETA"
#: Version 6: one body segment (spec §4.5).
BODY = b"BODY"
CRITICAL_TYPES = frozenset({PHDR, OBJT, PLNS, GRUP, PEND})
#: The chunk types that are records of a body segment in version 6 (spec §4.2: CHUNK_ORDER there).
RECORD_CHUNKS = frozenset({OBJT, PLNS, GRUP, COLR, META})

# spec §5 Header (PHDR): the flags of every version; the 108-byte layout of versions 1 and 2 (Appendix A.1)
FLAG_LOSSY = 0x0001
FLAG_COUNTS_KNOWN = 0x0002
FLAG_BBOX_KNOWN = 0x0004
#: The first 9 bytes, the same in every version (version 3 has nothing else that is fixed).
HEADER_FIXED = (
    "version_major" / cs.Int8ul,
    "version_minor" / cs.Int8ul,
    "flags" / cs.Int16ul,
    "coding" / cs.Int8ul,
    "bits_nu" / cs.Int8ul,
    "bits_phi" / cs.Int8ul,
    "bits_h" / cs.Int8ul,
    "units" / cs.Int8ul,
)
Header = cs.Struct(
    *HEADER_FIXED,
    "reserved" / cs.Bytes(3),
    "h_min" / cs.Float64l,
    "h_max" / cs.Float64l,
    "bbox_min" / cs.Array(3, cs.Float64l),
    "bbox_max" / cs.Array(3, cs.Float64l),
    "tolerance" / cs.Float64l,
    "error_bound" / cs.Float64l,
    "plane_count" / cs.Int64ul,
    "object_count" / cs.Int32ul,
    "group_count" / cs.Int32ul,
    "extra" / cs.GreedyBytes,
)
HEADER_SIZE = 108

# spec §6 Compression of PLNS data and GRUP bodies
COMPRESSION_NONE = 0
COMPRESSION_ZLIB = 1
#: Version 4.0 and later: one Brotli stream (RFC 7932).
COMPRESSION_BROTLI = 2
#: Largest raw size / stored size a writer stores (spec §6): every reader within spec §12.4's limits reads it.
MAX_WRITTEN_RATIO = 1024

#: Largest payload compressed at Brotli's densest quality, 11, which takes about 2 s a megabyte
#: (smooth_dense/bun_zipper.ply's 326 kB shell tree at 3e-5: 93.5 kB in 0.67 s; quality 9 gives
#: 102.1 kB in 0.04 s, deflate 106.5 kB): larger ones take quality 9, so that no encode waits on it.
BROTLI_DENSEST_BYTES = 1024 * 1024


def brotli_quality(size: int) -> int:
    """The Brotli quality a writer compresses ``size`` bytes at."""
    return 11 if size <= BROTLI_DENSEST_BYTES else 9


# spec Appendix A.1 Plane table head (PLNS) of versions 1 and 2
PlaneBlock = cs.Struct(
    "first" / cs.Int64ul,
    "count" / cs.Int32ul,
    "compression" / cs.Int8ul,
    "reserved" / cs.Bytes(3),
    "raw_size" / cs.Int32ul,
    "data" / cs.GreedyBytes,
)
PLANE_BLOCK_HEAD = 20

# spec Appendix A.1 Objects (OBJT) of versions 1 and 2
OBJECT_HAS_TRANSFORM = 0x01
Object = cs.Struct(
    "index" / cs.Int32ul,
    "parent" / cs.Int32ul,
    "flags" / cs.Int8ul,
    "reserved" / cs.Bytes(1),
    "name_length" / cs.Int16ul,
    "name" / cs.Bytes(cs.this.name_length),
    "transform" / cs.If(cs.this.flags & OBJECT_HAS_TRANSFORM, cs.Bytes(128)),
    "extra" / cs.GreedyBytes,
)

# spec Appendix A.1 Part groups (GRUP) of versions 1 and 2: a fixed head, then a possibly deflated body
GroupHead = cs.Struct(
    "index" / cs.Int32ul,
    "object" / cs.Int32ul,
    "kind" / cs.Int8ul,
    "compression" / cs.Int8ul,
    "reserved" / cs.Bytes(2),
    "raw_size" / cs.Int32ul,
    "body" / cs.GreedyBytes,
)
GROUP_HEAD = 16

# spec Appendix A.1 Group body of version 1, common to every kind (known or not)
GroupBody = cs.Struct(
    "ref_count" / cs.Int32ul,
    "refs" / cs.Bytes(cs.this.ref_count * 4),
    "roles" / cs.Bytes((cs.this.ref_count + 7) // 8),
    "extra" / cs.GreedyBytes,
)

# spec Appendix A.1 Kind-specific part of CELLS groups of version 1
CellsExtra = cs.Struct(
    "cell_count" / cs.Int32ul,
    "sizes" / cs.Bytes(cs.this.cell_count * 4),
    "entries" / cs.GreedyBytes,
)

# spec Appendix A.1 Kind-specific part of BSP groups of version 1
TreeExtra = cs.Struct(
    "token_count" / cs.Int32ul,
    "tokens" / cs.Bytes(cs.this.token_count * 4),
)

# spec §2.2 Varints: unsigned LEB128, minimal, at most 10 bytes (VARINT_MAX_BYTES above). Bulk
# varints (plane streams, references, tokens) are decoded with numpy in planefmt.container.varint, never per
# element with construct; Leb128 serves the few in version 3 chunk heads.

# spec §7.4 Predicted plane data (coding 3): three streams of `count` varints (nu, phi, h),
# each below 2^33, taking 3 to 15 bytes a plane
PREDICTED_LIMIT = 2**33
PREDICTED_BYTES = (3, 15)

# spec §9.2 Group body of version 2: ref_count, reference differences, role bits, kind data,
# all varints but the role bits; tree tokens 0 IN, 1 OUT, j + 2 split on local reference j
COMPACT_IN, COMPACT_OUT, COMPACT_SPLIT = 0, 1, 2
# spec §9.9 Sealed group (kind 5) data: vertex count, three local references per vertex,
# triangle count, then per triangle the face reference's difference from the previous one and its
# three vertices; all varints (read in bulk by varint.decode)
SEALED_VERTEX_FIELDS, SEALED_TRIANGLE_FIELDS = 3, 4

# spec §9.10 Shell group (kind 6) data: corner, triangle and free-triangle counts (varints),
# one flag bit per corner, three references per named corner (varints), and where a corner is
# explicit this grid, then zigzag varint coordinate steps, face reference steps and corner codes
ShellGrid = cs.Struct(
    "origin" / cs.Array(3, cs.Float64l),
    "step" / cs.Float64l,
)
SHELL_GRID_BYTES = 32
# spec §9.10, version 5: the same grid in float32
ShellGrid5 = cs.Struct(
    "origin" / cs.Array(3, cs.Float32l),
    "step" / cs.Float32l,
)


def shell_grid(major: int) -> tuple[cs.Struct, int]:
    """The grid of a shell group's explicit corners in a version ``major`` file, and its size."""
    return (ShellGrid5, 16) if major >= 5 else (ShellGrid, SHELL_GRID_BYTES)
# spec §9.11 Shell tree (kind 7) and §9.12 (kind 8, explicit corners predicted by parallelograms)
# data: corner and triangle counts, links, corner codes, face codes (varints), one flag bit per
# corner, picks (varints), then where a corner is explicit the same ShellGrid and zigzag varint
# residuals, every x, then every y, then every z (read in bulk by shellfields.py)
# spec §9.13 Shell walk (kind 9, version 4.1) data: corner, triangle and escape counts, one symbol
# per triangle (its children and its third corner's code), the escapes, face codes (varints), one
# flag bit per corner, picks, then where a corner is explicit a mode byte (bit 0 parallelogram, bit 1
# tables), the same ShellGrid, per axis a table of values where bit 1 says so (count, first, gaps),
# and the zigzag varint residuals (the walk is sequential: shellwalk.py and _chains.c)
# spec §9.14 (kind 10, version 4.2), §9.16 (kind 12, version 5.1) and §9.17 (kind 13, version 5.2): the
# same data, explicit corners predicted otherwise (averaged parallelograms; a turning chain of step
# sources, resolved in _chains.c; steps from the later-named gate corner)
SHELL_WALK_MODES = 0b11

# spec §10.1 Face colours (cOLR, ancillary)
Colours = cs.Struct(
    "group" / cs.Int32ul,
    "count" / cs.Int32ul,
    "rgba" / cs.Bytes(cs.this.count * 4),
)
#: The head of every cOLR; in version 4 a payload of this head and 4 bytes is one colour for all.
ColoursHead = cs.Struct(
    "group" / cs.Int32ul,
    "count" / cs.Int32ul,
)

# spec §10.3 Metadata (mETA, ancillary): a keyword of printable ASCII, a NUL, a UTF-8 value
Metadata = cs.Struct(
    "keyword" / cs.NullTerminated(cs.GreedyBytes, term=b"\x00"),
    "value" / cs.GreedyBytes,
)
METADATA_KEYWORD_BYTES = (1, 79)

# spec §10.2 Index (iNDX, ancillary); entries viewed as INDEX_ENTRY_DTYPE
Index = cs.Struct(
    "count" / cs.Int32ul,
    "entries" / cs.Bytes(cs.this.count * 16),
)
INDEX_ENTRY_DTYPE = [("offset", "<u8"), ("type", "S4"), ("ordinal", "<u4")]

# spec §4.4 End (PEND); versions 1 and 2 always 8 bytes (Appendix A.1)
End = cs.Struct(
    "index_offset" / cs.Int64ul,
)
END_SIZE = 8

# spec §5 Header of version 3: a fixed part, then only the fields the coding and flags call for
HEADER3_FIXED = 9
CODINGS_WITH_RANGE = (2, 3)
_HEADER_FIELDS = (
    "h_range" / cs.If(lambda this: this.coding in CODINGS_WITH_RANGE, cs.Array(2, cs.Float64l)),
    "bbox" / cs.If(cs.this.flags & FLAG_BBOX_KNOWN, cs.Array(6, cs.Float32l)),
    "tolerance" / cs.Float32l,
    "error_bound" / cs.Float32l,
    "counts" / cs.If(cs.this.flags & FLAG_COUNTS_KNOWN, cs.Struct(
        "plane_count" / Varint,
        "object_count" / Varint32,
        "group_count" / Varint32,
    )),
    "extra" / cs.GreedyBytes,
)
Header3 = cs.Struct(*HEADER_FIXED, *_HEADER_FIELDS)
# spec §5 Header of version 5: flags in one byte, and the units byte holds the up axis in bits 4 and 5
HEADER5_FIXED = 8
Header5 = cs.Struct(*(f if f.name != "flags" else "flags" / cs.Int8ul for f in HEADER_FIXED), *_HEADER_FIELDS)
UNITS_MASK = 0x0F
UP_AXIS_SHIFT = 4
#: The up axis codes of version 5's units byte (spec §5): 0 not said, then the axes of spec §10.3.
UP_AXIS_CODES = (None, "Y", "Z")

# spec §7.1 Plane table head of version 3
PlaneBlock3 = cs.Struct(
    "first" / Varint,
    "count" / Varint32,
    "compression" / cs.Int8ul,
    "raw_size" / Varint32,
    "data_offset" / cs.Tell,
    "data" / cs.GreedyBytes,
)
#: Longest head of PlaneBlock3 (varints of 10, 5 and 5 bytes and the compression byte).
PLANE_BLOCK3_MAX_HEAD = 21

# spec §8 Objects of version 3: parent 0 for a root, else the parent's index + 1
OBJECT3_MAX_NAME = 0xFFFF
Object3Head = cs.Struct(
    "index" / Varint32,
    "parent" / Varint32,
    "flags" / cs.Int8ul,
    "name_length" / Varint,
)
Object3 = cs.Struct(
    "head" / Object3Head,
    "name" / cs.Bytes(cs.this.head.name_length),
    "transform" / cs.If(cs.this.head.flags & OBJECT_HAS_TRANSFORM, cs.Bytes(128)),
    "extra" / cs.GreedyBytes,
)

# spec §8 Objects of version 4: the transform's top three rows entry by entry, each a 2-bit code
# (0: +0.0, 1: 1.0, 2: an f32 follows, 3: an f64 follows) of a 3-byte bit string, then the values.
TRANSFORM_CODE_BYTES = 3
TRANSFORM_ENTRIES = 12
TRANSFORM_VALUE_SIZES = (0, 0, 4, 8)


def transform_codes(codes: bytes) -> list[int]:
    """The twelve 2-bit codes of a version 4 transform (bit 2i + 2 * bit 2i + 1 of the bit string)."""
    bits = int.from_bytes(bytes(codes), "little")
    return [(bits >> (2 * i)) & 3 for i in range(TRANSFORM_ENTRIES)]


Transform4 = cs.Struct(
    "codes" / cs.Bytes(TRANSFORM_CODE_BYTES),
    "values" / cs.Bytes(lambda ctx: sum(TRANSFORM_VALUE_SIZES[c] for c in transform_codes(ctx.codes))),
)
Object4 = cs.Struct(
    "head" / Object3Head,
    "name" / cs.Bytes(cs.this.head.name_length),
    "transform" / cs.If(cs.this.head.flags & OBJECT_HAS_TRANSFORM, Transform4),
    "extra" / cs.GreedyBytes,
)

# spec §9.1 Part group head of version 3; the body is that of spec §9.2
GroupHead3 = cs.Struct(
    "index" / Varint32,
    "object" / Varint32,
    "kind" / cs.Int8ul,
    "compression" / cs.Int8ul,
    "raw_size" / Varint32,
    "body" / cs.GreedyBytes,
)

# spec §4.4 End of version 3: empty (no index) or the index offset
END3_SIZES = (0, END_SIZE)


# spec §2.2 r32: a binary32 bit pattern with its 32 bits reversed, as a varint32 (version 6)
def reverse32(value: int) -> int:
    """``value``'s 32 bits in reverse order (bit 0 <-> bit 31)."""
    return int(f"{value:032b}"[::-1], 2)


class _R32(cs.Adapter):
    def _decode(self, obj, context, path):
        return float(np.array([reverse32(obj)], dtype="<u4").view("<f4")[0])

    def _encode(self, obj, context, path):
        if obj != obj:  # NaN: the quiet NaN of spec §5, whatever the payload of the value given
            return reverse32(F32_NAN)
        with np.errstate(over="ignore"):
            bits = int(np.array([obj], dtype="<f4").view("<u4")[0])
        return reverse32(bits)


F32_NAN = 0x7FC00000
R32 = _R32(Leb128(32))

# spec §4.5 Body segment (version 6): compression, raw size, the data compressed per spec §6
Segment = cs.Struct(
    "compression" / cs.Int8ul,
    "raw_size" / Varint32,
    "data_offset" / cs.Tell,
)
#: A writer starts a new segment before a record that would take its raw size past this (spec §4.5).
SEGMENT_RAW_BYTES = 1 << 20

# spec §4.6 Records (version 6): tag, length, payload
RecordHead = cs.Struct(
    "tag" / cs.Int8ul,
    "length" / Varint32,
    "payload_offset" / cs.Tell,
)
TAG_OBJECT, TAG_PLANES, TAG_GROUP, TAG_COLOURS, TAG_METADATA = 1, 2, 3, 4, 5
#: The chunk type of version 5 that each record of version 6 replaces.
RECORD_TYPES = {TAG_OBJECT: OBJT, TAG_PLANES: PLNS, TAG_GROUP: GRUP, TAG_COLOURS: COLR, TAG_METADATA: META}
RECORD_TAGS = {t: tag for tag, t in RECORD_TYPES.items()}
#: Tags 128-255 are ancillary records (a reader skips those it does not know).
ANCILLARY_TAG = 0x80

# spec §5 Header of version 6: the version, header_size, then header_size bytes of fields
FLAG_CODING_SHIFT = 3
FLAG_CODING_MASK = 0b11
WIDTH_BITS = 5
Header6Fields = cs.Struct(
    "flags" / cs.Int8ul,
    "units" / cs.Int8ul,
    "coding" / cs.Computed(lambda this: this.flags >> FLAG_CODING_SHIFT & FLAG_CODING_MASK),
    "widths" / cs.If(lambda this: this.coding in CODINGS_WITH_RANGE, cs.Int16ul),
    "h_range" / cs.If(lambda this: this.coding in CODINGS_WITH_RANGE, cs.Array(2, R32)),
    "bbox" / cs.If(cs.this.flags & FLAG_BBOX_KNOWN, cs.Array(6, R32)),
    "tolerance" / R32,
    "error_bound" / R32,
    "counts" / cs.If(cs.this.flags & FLAG_COUNTS_KNOWN, cs.Struct(
        "plane_count" / Varint,
        "object_count" / Varint32,
        "group_count" / Varint32,
    )),
    "extra" / cs.GreedyBytes,
)
Header6 = cs.Struct(
    "version_major" / cs.Int8ul,
    "version_minor" / cs.Int8ul,
    "header_size" / Varint32,
    "fields" / cs.FixedSized(cs.this.header_size, Header6Fields),
    "segment_offset" / cs.Tell,
)


def widths6(bits_nu: int, bits_phi: int, bits_h: int) -> int:
    """The u16 ``widths`` of a version 6 header: each width less one, 5 bits each (spec §5)."""
    return (bits_nu - 1) | (bits_phi - 1) << WIDTH_BITS | (bits_h - 1) << 2 * WIDTH_BITS


def from_widths6(widths: int) -> tuple[int, int, int]:
    mask = (1 << WIDTH_BITS) - 1
    return tuple(1 + (widths >> WIDTH_BITS * i & mask) for i in range(3))


# spec §7.1 Planes record (version 6): the count, then the raw triplet data
PlaneRecordHead = cs.Struct(
    "count" / Varint32,
    "data_offset" / cs.Tell,
)

# spec §8 Object record (version 6): the object chunk of version 4 without its index
Object6Head = cs.Struct(
    "parent" / Varint32,
    "flags" / cs.Int8ul,
    "name_length" / Varint,
)
Object6 = cs.Struct(
    "head" / Object6Head,
    "name" / cs.Bytes(cs.this.head.name_length),
    "transform" / cs.If(cs.this.head.flags & OBJECT_HAS_TRANSFORM, Transform4),
    "extra" / cs.GreedyBytes,
)

# spec §9.1 Group record (version 6): the object, the kind, the body (uncompressed: its segment is)
GroupHead6 = cs.Struct(
    "object" / Varint32,
    "kind" / cs.Int8ul,
    "body_offset" / cs.Tell,
)

# spec §10.1 Colours record (version 6): group and count as varint32s
ColoursHead6 = cs.Struct(
    "group" / Varint32,
    "count" / Varint32,
    "rgba_offset" / cs.Tell,
)

# spec §10.2 Index of version 6: a count, then per record of tags 1 to 3 its chunk's offset (a difference
# from the previous entry's), its offset in the segment's raw bytes, its tag and its ordinal
IndexEntry6 = cs.Struct(
    "chunk_offset" / Varint,
    "raw_offset" / Varint,
    "tag" / cs.Int8ul,
    "ordinal" / Varint,
)
INDEX6_MIN_ENTRY = 4
