"""Construct declarations of the .pln container, versions 1 and 2 (read beside spec/pln-1.md and
spec/pln-2.md; "2.0 §" marks a section of the latter).

Only structure lives here. Bulk arrays (triplets, plane references, role
bits, cell entries, tree tokens, colours, index entries) are ``Bytes`` fields
that the payload modules view with ``numpy.frombuffer``. All integers and
floats are little-endian.
"""

import construct as cs

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

# spec §4.2 Chunk types
PHDR = b"PHDR"
OBJT = b"OBJT"
PLNS = b"PLNS"
GRUP = b"GRUP"
PEND = b"PEND"
COLR = b"cOLR"
INDX = b"iNDX"
CRITICAL_TYPES = frozenset({PHDR, OBJT, PLNS, GRUP, PEND})

# spec §5 Header (PHDR)
FLAG_LOSSY = 0x0001
FLAG_COUNTS_KNOWN = 0x0002
FLAG_BBOX_KNOWN = 0x0004
Header = cs.Struct(
    "version_major" / cs.Int8ul,
    "version_minor" / cs.Int8ul,
    "flags" / cs.Int16ul,
    "coding" / cs.Int8ul,
    "bits_nu" / cs.Int8ul,
    "bits_phi" / cs.Int8ul,
    "bits_h" / cs.Int8ul,
    "units" / cs.Int8ul,
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

# spec §7 Plane table (PLNS)
PlaneBlock = cs.Struct(
    "first" / cs.Int64ul,
    "count" / cs.Int32ul,
    "compression" / cs.Int8ul,
    "reserved" / cs.Bytes(3),
    "raw_size" / cs.Int32ul,
    "data" / cs.GreedyBytes,
)
PLANE_BLOCK_HEAD = 20

# spec §8.1 Objects (OBJT)
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

# spec §8.2 Part groups (GRUP): a fixed head, then a possibly deflated body
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

# spec §8.2 Group body, common to every kind (known or not)
GroupBody = cs.Struct(
    "ref_count" / cs.Int32ul,
    "refs" / cs.Bytes(cs.this.ref_count * 4),
    "roles" / cs.Bytes((cs.this.ref_count + 7) // 8),
    "extra" / cs.GreedyBytes,
)

# spec §8.3 Kind-specific part of CELLS groups
CellsExtra = cs.Struct(
    "cell_count" / cs.Int32ul,
    "sizes" / cs.Bytes(cs.this.cell_count * 4),
    "entries" / cs.GreedyBytes,
)

# spec §8.4 Kind-specific part of BSP groups
TreeExtra = cs.Struct(
    "token_count" / cs.Int32ul,
    "tokens" / cs.Bytes(cs.this.token_count * 4),
)

# spec 2.0 §2.3 Varints: unsigned LEB128, minimal, at most 10 bytes. Bulk varints (plane streams,
# references, tokens) are decoded with numpy in planefmt.varint, never per element with construct.
VARINT_MAX_BYTES = 10

# spec 2.0 §7.4 Predicted plane data (coding 3): three streams of `count` varints (nu, phi, h),
# each below 2^33, taking 3 to 15 bytes a plane
PREDICTED_LIMIT = 2**33
PREDICTED_BYTES = (3, 15)

# spec 2.0 §8.7 Group body of version 2: ref_count, reference differences, role bits, kind data,
# all varints but the role bits; tree tokens 0 IN, 1 OUT, j + 2 split on local reference j
COMPACT_IN, COMPACT_OUT, COMPACT_SPLIT = 0, 1, 2

# spec §8.5 Face colours (cOLR, ancillary)
Colours = cs.Struct(
    "group" / cs.Int32ul,
    "count" / cs.Int32ul,
    "rgba" / cs.Bytes(cs.this.count * 4),
)

# spec §8.6 Index (iNDX, ancillary); entries viewed as INDEX_ENTRY_DTYPE
Index = cs.Struct(
    "count" / cs.Int32ul,
    "entries" / cs.Bytes(cs.this.count * 16),
)
INDEX_ENTRY_DTYPE = [("offset", "<u8"), ("type", "S4"), ("ordinal", "<u4")]

# spec §4.4 End (PEND)
End = cs.Struct(
    "index_offset" / cs.Int64ul,
)
END_SIZE = 8
