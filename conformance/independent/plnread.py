"""plnread: an independent, container-level reader of the .pln format.

It was written from `spec/pln-1.md`, `spec/pln-2.md` and `spec/pln-3.md`
alone (plus the output contract of `conformance/README.md`), without looking
at planefmt or at the suite's generator, to show that the written spec and
the conformance contract are enough for a second implementation.  It uses
the Python 3.11 standard library, and for the Brotli payloads of version
4.0 (compression method 2) the PyPI package `brotli` (1.2 bounds the output
of each call; with 1.1 the stored bytes are given one at a time), imported only when such a payload is met: files of versions 1.0 to 3.4, and
4.0 files without Brotli payloads, need nothing else.  It reads versions
1.0, 2.0, 3.0 to 3.4, 4.0 to 4.2, 5.0 to 5.2 and 6.0 (pln.md §13: files of major versions 1 to 6,
each as its own version defines it).  Its version 3.1 part, the sealed groups of pln-3 §8.8,
was added later by a session that had seen planefmt's version 3.1 code; its
version 3.2 part, the shells of pln-3 §8.9, by one that read only the spec
text and the golden files' JSON, not planefmt's shell code; its version 3.3
part, the shell trees of pln-3 §8.10 (pln.md §9.11), by the session that wrote
planefmt's (from the spec text, decoding triangle by triangle where planefmt
jumps pointers over arrays).  Its mETA part (pln.md §10.3, ancillary metadata
of any version) was added with that section, from its text; a valid file's
JSON lists the chunks as "metadata": {keyword: value}.

It checks everything a reader must check without decoding geometry
(signature, chunk framing, CRC-32, header, plane table in every coding,
objects, part groups of every kind with their cells/tree structure,
colours, index, end chunk, versioning, zlib compression, limits) and, for a
valid file, prints the JSON object of conformance/README.md ("geometry" is
null: this reader does not decode geometry).  Version 4.0 (pln.md §5 to
§13 and Appendix A, added from that text) is version 3.4 with three
changes: compression method 2, one Brotli stream (pln.md §6; method 2 is
BAD_COMPRESSION in 1.0 to 3.4); an OBJT transform coded entry by entry, 3
bytes of 2-bit codes then the f32/f64 values, its last row implicit
(pln.md §8), reported as the 16 entries of M; and a cOLR of exactly 12
bytes, one colour every reference takes (pln.md §10.1), reported expanded,
one colour per reference.  Version 2.0 files are
reported in the same form as 1.0 ones: predicted planes (coding 3) are
dequantized like coding 2, and varint group bodies (pln-2 §8.7) are given
as absolute plane indices, cells entries 2j + s and tree tokens in the
version 1 numbering (0xFFFFFFFE IN, 0xFFFFFFFF OUT, j a split).  Version
3.0 files are reported in the same form too: the compact header's f32
bounding box, tolerance and error bound are widened to binary64 exactly, an
h range absent for codings 0 and 1 is [0.0, 0.0], counts absent without
COUNTS_KNOWN are null, and an OBJT parent stored as index + 1 (0 for a root)
is given as the parent's index or null.  A sealed group (kind 5, version
3.1) adds "vertex_planes", each vertex's three local references, and
"facets", each triangle as [face local reference, i0, i1, i2] with the face
references summed from their differences.  A shell (kind 6, version 3.2)
adds "shell": {"explicit": the explicit corners' indices, "vertex_planes":
each named corner's three local references, "grid": each explicit corner's
integer coordinates (the zigzag steps summed), "origin" and "step" (null
without explicit corners), "facets": each triangle as [face local reference
or -1 for a free one, i0, i1, i2] with the corner codes resolved}; a shell
tree (kind 7, version 3.3; kind 8, 3.4) the same object, its triangles in tree
order, and a shell walk (kind 9, version 4.1, pln.md §9.13) the same object,
its triangles in walk order, an explicit corner's "grid" entry its integer
coordinates (the values of the value tables, where the group has them, not
the indices into them).  Kind 9 was added from the 4.1 text of pln.md §9.13
and the sections it builds on, before any 4.1 golden file existed; its open
edges are kept so that each triangle takes constant time (OpenEdges).  Adding
it also moved the check of a shell tree's picks after the grid and the
coordinates are read, where pln.md §9.11 puts it ("reads the picks, the grid
and the coordinates, and checks the rest"); this reader had checked each pick
as it read it.
Kind 10 (version 4.2, pln.md §9.14, shell walks with multi-parallelograms)
was added from the 4.2 text of §9.14 alone, before the 4.2 golden files
existed: kind 9 with an explicit corner that has parallelograms (over the
triangles around it whose far corner is decoded) predicted by their average,
rounded toward -infinity after adding half the count; reported as kind 9 is.
Kind 11 (version 4.2, pln.md §9.15, copies) was added from the 4.2 text of
§9.15 alone: one varint, the index of an earlier source group that is not
itself a copy, whose references and role bits the copy must repeat; reported
as stored, with "source" and no kind-specific field.  Since this reader never
looks back, it keeps each group's kind and whether it was skipped, besides
the references and role bits it reports anyway (its output has no geometry,
so it keeps no surface).

Version 5.0 (pln.md §4.1, §5, §9.2, §9.10-§9.14, §10.1, §10.3 and Appendix
A.5, added from that text) is version 4.2 with four changes: every chunk
after PHDR has its length as a minimal varint32 of at most 5 bytes, read a
byte at a time (BAD_CHUNK_LENGTH where not minimal; CHUNK_TOO_LONG for a
fifth byte with bit 7 set or a length above 2^31 - 1); the header's fixed
part is 8 bytes, flags a u8, and its units byte holds the unit (bits 0-3,
reported as "units") and the up axis (bits 4-5: 0 none, 1 Y, 2 Z, reported
in "metadata" as a mETA up_axis is; a mETA up_axis is BAD_METADATA there);
groups of kinds 6 to 11 may have no references (and then one colour: a
cOLR of count 0 and 12 bytes; of 8 bytes, BAD_COLOURS); and a shell's grid is four f32 (16 bytes), widened
exactly.

Version 5.1 (pln.md §9.16, kind 12, shell walks with reflections) was added
from the 5.1 text of §9.16 and of §9.2, §9.3, §11, §13 and Appendix A.4,
before the 5.1 golden files existed: kind 9 with an explicit corner whose
chain of step sources (§9.11's predictor k <- a <- b <- c, whatever bit 0 of
the mode) turns predicted by a's value plus the step b - c reflected in the
line of the step a - b, in exact integers rounded toward -infinity after
adding half (reflected_step); reported as kind 9 is.  Kind 12 is a kind of
5.1 and later minors of major 5 (UNKNOWN_GROUP_KIND in a 5.0 file), and
like the other shells may have no references.

Version 5.2 (pln.md §9.17, kind 13, shell walks stepping from the later gate
corner) was added from the 5.2 text of §9.17 and of §9.3, §9.11, §9.13 and
§13, without planefmt's code or plnspec.py: kind 9 with one rule changed,
§9.11's predictor of an explicit corner, which is corner max(i0, i1) of the
triangle whose code named it anew (where that triangle is attached and that
corner explicit), not i0; otherwise the previous explicit corner, or none.
Mode bit 0's parallelogram is kind 9's.  Reported as kind 9 is.  Kind 13 is a
kind of 5.2 and later minors of major 5 (UNKNOWN_GROUP_KIND in a 5.0 or 5.1
file), and like the other shells may have no references.

Version 6.0 (pln.md §2.2, §4.2-§4.6, §5, §7.1, §8, §9.1, §10.1-§10.3 and
§12.1, added from the 6.0 text before the 6.0 golden files existed) keeps
version 5's framing and moves what followed the header into body segments:
the PHDR payload is the version, header_size, the header fields (flags with
the coding in bits 3-4, units, a u16 of widths and the h range for codings 2
and 3, the bbox, tolerance and error bound as r32, each binary32's bits
reversed as a varint32, the counts), then optionally the file's first body
segment; each BODY chunk is one more.  A segment is compression, raw_size
and data (pln.md §6, its checks and limits), its raw bytes a sequence of
records (tag, length, payload) whose payloads are version 5's OBJT, PLNS,
GRUP, cOLR and mETA payloads without their index, first, compression and
raw_size fields, read by the same parsers; such a chunk in a version 6 file
is CHUNK_ORDER.  The index lists each object, planes and group record by
its chunk's offset (as differences), its offset in the segment's raw bytes,
its tag and its ordinal.  One segment is held at a time.

This reader reads its input front to back (it works on pipes) and never
seeks, so it does no random access: MISSING_END (pln-1 §4.4, pln-3 §4.4) is
a code it never raises; a file whose last chunk is not PEND is TRUNCATED or
TRAILING_DATA here.

Section numbers below are those of spec/pln-1.md; "pln-2 §x" and "pln-3 §x"
mark a section of spec/pln-2.md or spec/pln-3.md (which use the section
numbers of pln-1), the documents it was written from, kept as history.
Four places follow spec/pln.md, the one document that replaced them, where
this reader had read the old text otherwise (each marked "pln.md §x"): the
h range and widths of codings 0 and 1 are ignored, not checked; a zlib
stream that the stored bytes end inside is SIZE_MISMATCH; and a version 2
group's references are all read before any is checked.

Usage:
    python conformance/independent/plnread.py FILE.pln

    # through the conformance runner, from the repository root:
    python -m conformance --impl "python conformance/independent/plnread.py"

Exit status 0 and one JSON object on stdout for a valid file; exit status 1
and {"error": "CODE"} on stdout (a human-readable message on stderr) for an
invalid one; exit status 2 for a usage or I/O error.
"""

import json
import math
import os
import struct
import sys
import zlib

# --------------------------------------------------------------------------
# Constants (spec sections in brackets)

SIGNATURE = bytes([0x89, 0x50, 0x4C, 0x4E, 0x0D, 0x0A, 0x1A, 0x0A])  # §3

# the versions this reader implements: major -> highest minor it knows
# (1.0, 2.0, 3.4, 4.2 and 5.2, as pln.md §9.3 says, not §5's 1 for major 5:
# SPEC_NOTES 62; pln.md §13: a reader of 5.2 reads major versions 1 to 5)
READER_VERSIONS = {1: 0, 2: 0, 3: 4, 4: 2, 5: 2, 6: 0}

MAX_CHUNK_LENGTH = 2**31 - 1  # §4.1, format maximum
# pln.md §4.1, version 5: every chunk after PHDR has its length as a minimal
# varint32 of at most 5 bytes (PHDR keeps its u32 length in every version)
VARINT_LENGTH_MAJOR = 5
LENGTH_VARINT_MAX_BYTES = 5

# §10.3 limits (the reference reader's defaults)
LIMIT_CHUNK = 256 * 1024 * 1024
LIMIT_RAW = 256 * 1024 * 1024
LIMIT_DEFLATE_RATIO = 1100  # pln.md §12.4: of a compressed payload, methods 1 and 2
LIMIT_PLANES = 2**22
LIMIT_REFS = 2**24
LIMIT_OBJECTS = 2**24

READ_BLOCK = 1 << 20  # payloads are read in bounded blocks (§4.1)

KNOWN_CHUNKS = {b"PHDR", b"OBJT", b"PLNS", b"GRUP", b"cOLR", b"mETA", b"iNDX", b"PEND"}

# version 6: the records of the body segments (PHDR's tail and BODY chunks)
# replace the OBJT, PLNS, GRUP, cOLR and mETA chunks; such a chunk in a
# version 6 file is CHUNK_ORDER
SEGMENT_MAJOR = 6
RECORD_CHUNKS = (b"OBJT", b"PLNS", b"GRUP", b"cOLR", b"mETA")
TAG_OBJECT, TAG_PLANES, TAG_GROUP, TAG_COLOURS, TAG_METADATA = 1, 2, 3, 4, 5
FIRST_ANCILLARY_TAG = 128  # tags 128-255: ancillary records, skipped
CODING_SHIFT, CODING_MASK = 3, 0b11  # version 6: the coding is bits 3-4 of flags
WIDTH_BITS = 5  # version 6: each width - 1 in 5 bits of a u16

# pln.md §10.3: a keyword is 1-79 bytes of 0x21-0x7E; the values of the keywords it defines
META_KEYWORD_MAX = 79
META_VALUES = {"up_axis": ("Y", "Z")}

FLAG_LOSSY, FLAG_COUNTS_KNOWN, FLAG_BBOX_KNOWN = 1, 2, 4  # §5
OBJ_HAS_TRANSFORM = 1  # §8.1
KNOWN_KINDS = {0, 1, 2, 3, 4}  # §8.2
# pln-3 §8.2: kind 5, the sealed surface (§8.8), exists in files of version 3.1
# and later only, kind 6, the shell (§8.9), in files of version 3.2 and later,
# kind 7, the shell tree (§8.10), in files of version 3.3 and later; pln.md
# §9.3: kind 8 in 3.4 and later, kind 9, the shell walk (pln.md §9.13), in 4.1
# and later, kind 10, the shell walk with multi-parallelograms (pln.md
# §9.14), and kind 11, the copy (pln.md §9.15), in 4.2 and later, kind 12,
# the shell walk with reflections (pln.md §9.16), in 5.1 and later, kind 13,
# the shell walk stepping from the later gate corner (pln.md §9.17), in 5.2
# and later; in older files each is a kind the file's version does not have
SEALED_KIND, SHELL_KIND, SHELL_TREE_KIND, PARALLELOGRAM_KIND, WALK_KIND = 5, 6, 7, 8, 9
MULTI_WALK_KIND = 10
COPY_KIND = 11  # pln.md §9.15, the copy, in 4.2 and later
REFLECT_WALK_KIND = 12
LATER_WALK_KIND = 13
KIND_SINCE = {SEALED_KIND: (3, 1), SHELL_KIND: (3, 2), SHELL_TREE_KIND: (3, 3), PARALLELOGRAM_KIND: (3, 4),
              WALK_KIND: (4, 1), MULTI_WALK_KIND: (4, 2), COPY_KIND: (4, 2), REFLECT_WALK_KIND: (5, 1),
              LATER_WALK_KIND: (5, 2)}
MULTI_PARALLELOGRAMS = 4  # pln.md §9.14: a corner has at most four parallelograms
TURN_LIMIT = 2**18  # pln.md §9.16: a chain turns only where every component of its steps is within it
SHELL_COORD_LIMIT = 2**52  # pln-3 §8.9: each grid step and coordinate of magnitude at most 2^52
SHELL_GRID_BYTES = 32  # pln-3 §8.9: origin x, y, z and step s, f64 each
F32_GRID_MAJOR = 5  # pln.md §9.10-§9.14: version 5's grids are f32 each, 16 bytes (Appendix A.5)
NO_REFS_MAJOR = 5  # pln.md §9.2: in version 5, m may be 0 in kinds 6 to 12 (and 13, a shell walk)
LAST_KIND_NEEDING_REFS = 5  # pln.md §9.2: m = 0 in kinds 0 to 5 is BAD_GROUP_STRUCTURE

F32_PI = struct.unpack("<f", struct.pack("<I", 0x40490FDB))[0]  # §7.1
F32_2PI = struct.unpack("<f", struct.pack("<I", 0x40C90FDB))[0]

TOKEN_IN, TOKEN_OUT, TOKEN_RESERVED_LO = 0xFFFFFFFE, 0xFFFFFFFF, 0xFFFFFFF0  # §8.4
V2_TOKEN_IN, V2_TOKEN_OUT, V2_TOKEN_SPLIT = 0, 1, 2  # pln-2 §8.7: 0 IN, 1 OUT, j + 2 split

CODING_QUANTIZED, CODING_PREDICTED = 2, 3  # §7.3, pln-2 §7.4
VARINT_MAX_BYTES = 10  # pln-2 §2.3: below 2^64, at most 10 bytes
PLANE_VARINT_LIMIT = 2**33  # pln-2 §7.4: every varint of the plane streams
VARINT32_LIMIT = 2**32  # pln-3: a varint32 MUST be below 2^32
NO_PARENT = 0xFFFFFFFF
V3_NO_PARENT = 0  # pln-3 §8.1: parent 0 for a root, otherwise the parent's index + 1
MAX_NAME_LENGTH = 65535  # pln-3 §8.1: name_length at most 65535 (the u16 of §8.1)

V3_HEADER_FIXED = 9  # pln-3 §5: version_major .. units, no reserved bytes
V5_HEADER_FIXED = 8  # pln.md §5: version 5's flags are a u8, so coding is at offset 3
UP_AXES = {0: None, 1: "Y", 2: "Z"}  # pln.md §5, version 5: bits 4-5 of units; 3 is BAD_HEADER_VALUE
PEND_PAYLOAD_V1 = 8  # §4.4
PEND_PAYLOADS_V3 = (0, 8)  # pln-3 §4.4: empty without an index, else the u64 offset
CHUNK_FRAME = 12  # §4.1: type, length, crc around a payload


class PlnError(Exception):
    """A reader error of spec §10.1."""

    def __init__(self, code, message, chunk=None, offset=None):
        super().__init__(message)
        self.code = code
        self.message = message
        self.chunk = chunk
        self.offset = offset


# --------------------------------------------------------------------------
# Small helpers


def u8(b, o):
    return b[o]


def u16(b, o):
    return struct.unpack_from("<H", b, o)[0]


def u32(b, o):
    return struct.unpack_from("<I", b, o)[0]


def u64(b, o):
    return struct.unpack_from("<Q", b, o)[0]


def f64(b, o):
    return struct.unpack_from("<d", b, o)[0]


def is_letter(c):
    return 0x41 <= c <= 0x5A or 0x61 <= c <= 0x7A


def nan_to_none(x):
    return None if isinstance(x, float) and math.isnan(x) else x


class Cursor:
    """Reads a payload front to back; running past its end is BAD_PAYLOAD."""

    def __init__(self, data, what):
        self.data = data
        self.pos = 0
        self.what = what

    def remaining(self):
        return len(self.data) - self.pos

    def need(self, n, what=None):
        if n > self.remaining():
            raise PlnError(
                "BAD_PAYLOAD",
                "%s: %s needs %d bytes, %d remain"
                % (self.what, what or "field", n, self.remaining()),
            )

    def take(self, n, what=None):
        self.need(n, what)
        b = self.data[self.pos:self.pos + n]
        self.pos += n
        return b

    def u8(self, what=None):
        self.need(1, what)
        v = self.data[self.pos]
        self.pos += 1
        return v

    def u16(self, what=None):
        self.need(2, what)
        v = u16(self.data, self.pos)
        self.pos += 2
        return v

    def u32(self, what=None):
        self.need(4, what)
        v = u32(self.data, self.pos)
        self.pos += 4
        return v

    def f32s(self, n, what=None):
        # widened to binary64 exactly (§7.2)
        self.need(4 * n, what)
        v = list(struct.unpack_from("<%df" % n, self.data, self.pos))
        self.pos += 4 * n
        return v

    def f64s(self, n, what=None):
        self.need(8 * n, what)
        v = list(struct.unpack_from("<%dd" % n, self.data, self.pos))
        self.pos += 8 * n
        return v

    def rest(self):
        b = self.data[self.pos:]
        self.pos = len(self.data)
        return b

    def u32_array(self, n, what=None):
        # the length is checked against the bytes present before allocating
        self.need(4 * n, what)
        v = list(struct.unpack_from("<%dI" % n, self.data, self.pos)) if n else []
        self.pos += 4 * n
        return v

    def varint(self, what=None):
        """pln-2 §2.3: unsigned LEB128, minimal, at most 10 bytes (the 10th at
        most 0x01), below 2^64; any breach, or data ending inside, is BAD_PAYLOAD."""
        data, pos = self.data, self.pos
        value = 0
        for n in range(VARINT_MAX_BYTES):
            if pos >= len(data):
                raise PlnError("BAD_PAYLOAD",
                               "%s: the data ends inside %s, a varint" % (self.what, what or "a field"))
            b = data[pos]
            pos += 1
            value |= (b & 0x7F) << (7 * n)
            if not b & 0x80:
                if n > 0 and b == 0:
                    raise PlnError("BAD_PAYLOAD",
                                   "%s: %s is a varint that is not minimal" % (self.what, what or "field"))
                if n == VARINT_MAX_BYTES - 1 and b > 0x01:
                    raise PlnError("BAD_PAYLOAD",
                                   "%s: %s is a varint of 2^64 or more" % (self.what, what or "field"))
                self.pos = pos
                return value
        raise PlnError("BAD_PAYLOAD",
                       "%s: %s is a varint longer than %d bytes" % (self.what, what or "field",
                                                                    VARINT_MAX_BYTES))

    def varint32(self, what=None):
        """pln-3: a varint (pln-2 §2.3) whose value MUST be below 2^32 (BAD_PAYLOAD)."""
        v = self.varint(what)
        if v >= VARINT32_LIMIT:
            raise PlnError("BAD_PAYLOAD",
                           "%s: %s is a varint32 of %d, not below 2^32" % (self.what, what or "field", v))
        return v

    def r32(self, what=None):
        """Version 6: an r32, a binary32 whose bit pattern, its 32 bits
        reversed (bit 0 <-> bit 31), is a minimal varint32; widened to
        binary64 exactly.  A bad varint is BAD_PAYLOAD."""
        v = self.varint32(what)
        return struct.unpack("<f", struct.pack("<I", reverse32(v)))[0]


def reverse32(v):
    """The 32 bits of v in reverse order (bit 0 <-> bit 31)."""
    return int(format(v, "032b")[::-1], 2)


def unzigzag(u):
    """pln-2 §2.3: the inverse of zigzag (0, 1, 2, 3, 4 ... -> 0, -1, 1, -2, 2 ...)."""
    return -((u + 1) >> 1) if u & 1 else u >> 1


def check_bit_padding(data, nbits, what):
    """§2.1: the unused bits of the last byte must be 0."""
    if nbits % 8 and data:
        last = data[-1]
        if last >> (nbits % 8):
            raise PlnError("BAD_PAYLOAD", "%s: non-zero padding bits" % what)


def decompress(method, raw_size, stored, what, major):
    """§6 compression, with the §10.3 limits checked before inflating."""
    # pln.md §6 step 1: method 2 (Brotli) exists in version 4 only (Appendix A)
    if method not in ((0, 1, 2) if major >= 4 else (0, 1)):
        raise PlnError("BAD_COMPRESSION", "%s: compression method %d in a version %d file"
                       % (what, method, major))
    if raw_size > LIMIT_RAW:
        raise PlnError("LIMIT_EXCEEDED", "%s: raw size %d above the limit" % (what, raw_size))
    if method == 0:
        if len(stored) != raw_size:
            raise PlnError(
                "SIZE_MISMATCH",
                "%s: %d stored bytes, raw size %d" % (what, len(stored), raw_size),
            )
        return stored
    if raw_size > LIMIT_DEFLATE_RATIO * len(stored):
        raise PlnError(
            "LIMIT_EXCEEDED",
            "%s: raw size %d above %d x the %d stored bytes"
            % (what, raw_size, LIMIT_DEFLATE_RATIO, len(stored)),
        )
    if method == 2:
        return unbrotli(raw_size, stored, what)
    d = zlib.decompressobj()
    try:
        out = d.decompress(stored, raw_size + 1)  # never more than raw_size + 1
    except zlib.error as e:
        raise PlnError("BAD_COMPRESSION", "%s: invalid zlib stream (%s)" % (what, e))
    if len(out) > raw_size:
        raise PlnError("SIZE_MISMATCH", "%s: inflates to more than raw size %d" % (what, raw_size))
    if not d.eof:
        # pln.md §6 step 5: a stream the stored bytes end inside (no error from
        # the inflater on what it consumed) is SIZE_MISMATCH, however much it
        # inflated to; an error the inflater reports is BAD_COMPRESSION
        if len(out) < raw_size:
            raise PlnError("SIZE_MISMATCH", "%s: zlib stream ends early" % what)
        try:
            more = d.decompress(d.unconsumed_tail, 1)
        except zlib.error as e:
            raise PlnError("BAD_COMPRESSION", "%s: invalid zlib stream (%s)" % (what, e))
        if more:
            raise PlnError("SIZE_MISMATCH", "%s: inflates to more than raw size %d" % (what, raw_size))
        if not d.eof:
            raise PlnError("SIZE_MISMATCH", "%s: zlib stream ends early" % what)
    if len(out) != raw_size:
        raise PlnError(
            "SIZE_MISMATCH", "%s: inflates to %d bytes, raw size %d" % (what, len(out), raw_size)
        )
    if d.unused_data:
        raise PlnError(
            "SIZE_MISMATCH", "%s: %d bytes after the zlib stream" % (what, len(d.unused_data))
        )
    return out


BROTLI_STEP = 32768  # stored bytes given to the Brotli decoder per call


def unbrotli(raw_size, stored, what):
    """pln.md §6 step 6, method 2: one Brotli stream (RFC 7932) that
    decompresses to exactly raw_size bytes and ends with the last stored
    byte.  An invalid stream and stored bytes after its end are
    BAD_COMPRESSION (the binding itself reports the latter as a decoder
    error); a stream the stored bytes end inside, or an output other than
    raw_size bytes, is SIZE_MISMATCH.  The stored bytes are given
    BROTLI_STEP at a time and the output taken in the binding's smallest
    blocks (output_buffer_limit=1: about 32 KiB a call), and decoding stops
    as soon as the output passes raw_size, so at most raw_size + 32 KiB is
    held (pln.md §6 allows raw size + 16 MiB; SPEC_NOTES 25)."""
    try:
        import brotli
    except ImportError:
        raise SystemExit("plnread: compression method 2 (Brotli) needs the Python package 'brotli'")
    dec = brotli.Decompressor()
    # brotli 1.1's process() has no output bound: the stored bytes are then
    # given one at a time (one byte yields at most about a meta-block, 16 MiB)
    bounded = hasattr(dec, "can_accept_more_data")
    step = BROTLI_STEP if bounded else 1
    out = []
    total = 0
    given = 0  # stored bytes given to the decoder
    while not dec.is_finished():
        data = b""
        if given < len(stored) and (not bounded or dec.can_accept_more_data()):
            data = stored[given:given + step]
            given += len(data)
        try:
            block = dec.process(data, output_buffer_limit=1) if bounded else dec.process(data)
        except brotli.error:
            raise PlnError("BAD_COMPRESSION", "%s: invalid Brotli stream, or bytes after its end" % what)
        out.append(block)
        total += len(block)
        if total > raw_size:
            raise PlnError("SIZE_MISMATCH", "%s: Brotli stream decompresses to more than raw size %d"
                           % (what, raw_size))
        if not data and not block and not dec.is_finished():
            if given == len(stored):
                raise PlnError("SIZE_MISMATCH", "%s: Brotli stream ends early" % what)
            if bounded and not dec.can_accept_more_data():
                raise RuntimeError("Brotli decoder takes no input and gives no output")
    if given < len(stored):
        raise PlnError("BAD_COMPRESSION", "%s: %d bytes after the Brotli stream"
                       % (what, len(stored) - given))
    if total != raw_size:
        raise PlnError("SIZE_MISMATCH", "%s: Brotli stream decompresses to %d bytes, raw size %d"
                       % (what, total, raw_size))
    return b"".join(out)


def multi_parallelograms(tris, is_explicit):
    """pln.md §9.14: each explicit corner's parallelograms, as a dict
    corner -> [(a, b, c), ...] (at most four; corners with none are left
    out).  The far corner of a directed edge (a, b) is the corner other than
    a and b of the first triangle, in triangle order, that has the edge
    (b, a).  The candidates of corner k are taken triangle by triangle in
    triangle order, and within a triangle place by place (s = 0, 1, 2) where
    i_s = k: a = i_(s+1), b = i_(s+2), c the far corner of (a, b); one is a
    parallelogram where c exists and a, b and c are all explicit and all
    numbered below k.  One pass over the triangles for the edge map, one
    for the candidates."""
    first = {}  # directed edge -> the first triangle, in triangle order, that has it
    for j, tri in enumerate(tris):
        for s in range(3):
            first.setdefault((tri[s], tri[(s + 1) % 3]), j)
    grams = {}
    for tri in tris:
        for s in range(3):
            k = tri[s]
            if k not in is_explicit:
                continue
            found = grams.get(k)
            if found is not None and len(found) == MULTI_PARALLELOGRAMS:
                continue
            a, b = tri[(s + 1) % 3], tri[(s + 2) % 3]
            other = first.get((b, a))
            if other is None:
                continue
            far = next(x for x in tris[other] if x != a and x != b)
            if a < k and b < k and far < k and a in is_explicit and b in is_explicit and far in is_explicit:
                grams.setdefault(k, []).append((a, b, far))
    return grams


def reflected_step(values, sources, k):
    """pln.md §9.16: the prediction of explicit corner k where its chain
    turns, else None.  The chain is a = p(k), b = p(a), c = p(b), p the
    step source (``sources``, None for none), all three existing; with
    d1 = g(b) - g(c), d2 = g(a) - g(b) and D = d2.d2, it turns where D > 0
    and every component of d1 and d2 is within 2^18.  The prediction is
    g(a) + floor((2N + D) / 2D) on each axis, N = 2(d1.d2) d2 - D d1:
    d1 reflected in the line of d2, halves rounded toward +infinity.
    ``values`` holds g of the corners resolved so far (every corner of the
    chain is below k, so resolved and checked); Python's integers are exact
    and its // rounds toward -infinity (no quotient is ever a half:
    SPEC_NOTES 63)."""
    a = sources[k]
    b = None if a is None else sources[a]
    c = None if b is None else sources[b]
    if c is None:
        return None
    d1 = [values[b][i] - values[c][i] for i in range(3)]
    d2 = [values[a][i] - values[b][i] for i in range(3)]
    dd = sum(x * x for x in d2)
    if dd == 0 or any(abs(x) > TURN_LIMIT for x in d1 + d2):
        return None
    dot = sum(x * y for x, y in zip(d1, d2))
    return [values[a][i] + (2 * (2 * dot * d2[i] - dd * d1[i]) + dd) // (2 * dd) for i in range(3)]


class OpenEdges:
    """pln.md §9.13: the list of open directed edges of a shell walk, in
    order of entry.  Each entry is a list [a, b, newer_out, older_out,
    newer_in, older_in]: the links of the doubly linked lists of the
    entries that start at a and that end at b, newest first (the head of
    each list is in ``starts`` / ``ends``); ``stacks`` maps an edge (a, b)
    to its entries, newest last.  Adding a triangle, and each left or right
    answer, takes constant time."""

    A, B, NEWER_OUT, OLDER_OUT, NEWER_IN, OLDER_IN = range(6)

    def __init__(self):
        self.stacks = {}
        self.starts = {}  # corner -> newest entry starting there
        self.ends = {}  # corner -> newest entry ending there

    def add_triangle(self, corners):
        """The edges (i0, i1), (i1, i2), (i2, i0) in that order: the newest
        entry of an edge's reverse leaves the list (the edge is closed),
        or else the edge enters it."""
        for k in range(3):
            a, b = corners[k], corners[(k + 1) % 3]
            reverse = self.stacks.get((b, a))
            if reverse:
                self._remove(reverse.pop())
            else:
                self._insert(a, b)

    def _insert(self, a, b):
        entry = [a, b, None, self.starts.get(a), None, self.ends.get(b)]
        if entry[self.OLDER_OUT] is not None:
            entry[self.OLDER_OUT][self.NEWER_OUT] = entry
        if entry[self.OLDER_IN] is not None:
            entry[self.OLDER_IN][self.NEWER_IN] = entry
        self.starts[a] = entry
        self.ends[b] = entry
        self.stacks.setdefault((a, b), []).append(entry)

    def _remove(self, entry):
        a, b, newer_out, older_out, newer_in, older_in = entry
        if newer_out is None:
            self.starts[a] = older_out
        else:
            newer_out[self.OLDER_OUT] = older_out
        if older_out is not None:
            older_out[self.NEWER_OUT] = newer_out
        if newer_in is None:
            self.ends[b] = older_in
        else:
            newer_in[self.OLDER_IN] = older_in
        if older_in is not None:
            older_in[self.NEWER_IN] = newer_in

    def left(self, i1, opposite):
        """Code 1: the start of the newest open edge ending at i1, or of the
        second newest where that start is the parent's opposite corner;
        None where there is no such edge."""
        entry = self.ends.get(i1)
        if entry is not None and entry[self.A] == opposite:
            entry = entry[self.OLDER_IN]
        return None if entry is None else entry[self.A]

    def right(self, i0, opposite):
        """Code 2: the end of the newest open edge starting at i0, or of the
        second newest where that end is the parent's opposite corner."""
        entry = self.starts.get(i0)
        if entry is not None and entry[self.B] == opposite:
            entry = entry[self.OLDER_OUT]
        return None if entry is None else entry[self.B]


# --------------------------------------------------------------------------
# The reader


class Reader:
    def __init__(self, stream, size=None):
        self.f = stream
        self.size = size  # total input size if known
        self.pos = 0

        self.header = None
        self.major = 1
        self.minor = 0
        self.planes = []
        self.objects = []
        self.groups = []  # JSON dicts
        self.group_refcounts = []
        # pln.md §9.15: what a later copy needs of each group, kept as it is read
        # (this reader never looks back in its input): its kind and whether it
        # was skipped; its references and role bits are in self.groups
        self.group_kinds = []
        self.group_skipped = []
        self.colours = []
        self.colour_slot = {}  # group -> its place in self.colours
        self.metadata = {}
        self.findings = []
        self.chunk_list = []  # (offset, type, ordinal) of OBJT, PLNS, GRUP
        self.index_offset = None  # offset of the iNDX chunk, if seen
        self.after_header = None  # offset of the chunk after PHDR (pln-3 §8.6)
        self.last_was_index = False
        self.first_segment = b""  # version 6: the body segment in PHDR's payload, if any

    # -- input -------------------------------------------------------------

    def read_exact(self, n, what):
        """Read n bytes or raise TRUNCATED, in bounded blocks."""
        if self.size is not None and n > self.size - self.pos:
            raise PlnError(
                "TRUNCATED",
                "%s: needs %d bytes, %d remain" % (what, n, max(0, self.size - self.pos)),
                offset=self.pos,
            )
        parts = []
        left = n
        while left:
            b = self.f.read(min(left, READ_BLOCK))
            if not b:
                raise PlnError("TRUNCATED", "%s: input ends" % what, offset=self.pos)
            parts.append(b)
            left -= len(b)
            self.pos += len(b)
        return b"".join(parts)

    def at_eof(self):
        b = self.f.read(1)
        if b:
            self.pos += 1
            return False
        return True

    def finding(self, code):
        if code not in self.findings:
            self.findings.append(code)

    # -- top level ---------------------------------------------------------

    def read(self):
        self.read_signature()
        first = True
        while True:
            offset = self.pos
            # pln.md §4.1: PHDR, the first chunk, has a u32 length in every
            # version; every later chunk of a version 5 file a varint32
            if not first and self.major >= VARINT_LENGTH_MAJOR:
                ctype, length = self.read_varint_head(offset)
                name = ctype.decode("latin-1")
            else:
                head = self.f.read(8)
                if len(head) < 8:
                    if not head:
                        raise PlnError("TRUNCATED", "input ends before PEND", offset=offset)
                    raise PlnError("TRUNCATED", "input ends inside a chunk head", offset=offset)
                self.pos += 8
                ctype = head[:4]
                length = u32(head, 4)
                name = ctype.decode("latin-1")
                if not all(is_letter(c) for c in ctype):
                    raise PlnError("BAD_CHUNK_TYPE", "chunk type %r is not four ASCII letters" % ctype,
                                   name, offset)
            if length > MAX_CHUNK_LENGTH:
                raise PlnError("CHUNK_TOO_LONG", "length %d above 2^31-1" % length, name, offset)
            if length > LIMIT_CHUNK:
                raise PlnError("LIMIT_EXCEEDED", "length %d above the limit" % length, name, offset)
            try:
                payload = self.read_exact(length, "%s payload" % name)
                crc_bytes = self.read_exact(4, "%s CRC" % name)
            except PlnError as e:
                e.chunk, e.offset = name, offset
                raise
            crc = u32(crc_bytes, 0)
            if zlib.crc32(ctype + payload) & 0xFFFFFFFF != crc:
                raise PlnError("CRC_MISMATCH", "CRC mismatch", name, offset)

            try:
                if first:
                    if ctype != b"PHDR":
                        raise PlnError("MISSING_HEADER", "first chunk is not PHDR")
                    self.read_header(payload)
                    first = False
                    if self.major >= SEGMENT_MAJOR and self.first_segment:
                        self.read_segment(self.first_segment, offset, name)
                    continue
                # pln.md §12.1 item 3.2: after iNDX, a chunk other than PEND
                # (a PHDR too); in version 6 a chunk of a record's type; a second PHDR
                if self.last_was_index and ctype != b"PEND":
                    raise PlnError("CHUNK_ORDER", "iNDX is not immediately followed by PEND (§4.3)")
                if self.major >= SEGMENT_MAJOR and ctype in RECORD_CHUNKS:
                    raise PlnError("CHUNK_ORDER", "a %s chunk in a version %d file: a record of a body segment"
                                   % (name, self.major))
                if ctype == b"PHDR":
                    raise PlnError("DUPLICATE_HEADER", "a second PHDR")
                if ctype == b"PEND":
                    self.read_end(payload)
                    if not self.at_eof():
                        raise PlnError("TRAILING_DATA", "bytes after PEND")
                    return
                if self.major >= SEGMENT_MAJOR and ctype == b"BODY":
                    self.read_segment(payload, offset, name)
                elif ctype == b"OBJT":
                    self.read_object(payload, (offset, b"OBJT"))
                elif ctype == b"PLNS":
                    self.read_planes(payload, (offset, b"PLNS"))
                elif ctype == b"GRUP":
                    self.read_group(payload, (offset, b"GRUP"))
                elif ctype == b"cOLR":
                    self.read_colours(payload)
                elif ctype == b"mETA":
                    self.read_metadata(payload)
                elif ctype == b"iNDX":
                    self.read_index(payload, offset)
                elif ctype[0] & 0x20:
                    self.finding("UNKNOWN_ANCILLARY_CHUNK")
                else:
                    raise PlnError("UNKNOWN_CRITICAL_CHUNK", "unknown critical chunk")
            except PlnError as e:
                if e.chunk is None:
                    e.chunk, e.offset = name, offset
                raise

    def read_segment(self, p, offset, name):
        """Version 6: a body segment (PHDR's bytes after the header, or a BODY
        chunk's payload): compression (u8), raw_size (varint32), the data,
        decompressed as §6 says with its limits; its raw bytes a sequence of
        whole records, each tag (u8), length (varint32, at most the bytes
        left in the segment), payload.  A segment that ends inside a record
        is BAD_PAYLOAD.  Errors name the chunk, its offset and the record's
        offset in the raw bytes."""
        c = Cursor(p, "%s body segment" % name)
        method = c.u8("compression")
        raw_size = c.varint32("raw_size")
        raw = decompress(method, raw_size, c.rest(), "%s body segment" % name, self.major)
        r = Cursor(raw, "%s body segment (raw)" % name)
        while r.remaining():
            at = r.pos
            try:
                tag = r.u8("record tag")
                length = r.varint32("record length")
                if length > r.remaining():
                    raise PlnError("BAD_PAYLOAD", "record length %d, %d bytes left in the segment"
                                   % (length, r.remaining()))
                self.read_record(tag, r.take(length), (offset, at, tag))
            except PlnError as e:
                e.message = "record at raw offset %d: %s" % (at, e.message)
                raise

    def read_record(self, tag, p, entry):
        """Version 6: a record, read by the parser of the chunk it replaces."""
        if tag == TAG_OBJECT:
            self.read_object(p, entry)
        elif tag == TAG_PLANES:
            self.read_planes(p, entry)
        elif tag == TAG_GROUP:
            self.read_group(p, entry)
        elif tag == TAG_COLOURS:
            self.read_colours(p)
        elif tag == TAG_METADATA:
            self.read_metadata(p)
        elif tag >= FIRST_ANCILLARY_TAG:
            self.finding("UNKNOWN_ANCILLARY_CHUNK")
        else:
            raise PlnError("UNKNOWN_CRITICAL_CHUNK", "record tag %d" % tag)

    def read_varint_head(self, offset):
        """pln.md §4.1, version 5: the 4-byte type, then the length as a
        varint32 read a byte at a time, checked in the order of §4.1: the
        input ends inside the type (TRUNCATED); a type that is not four
        letters (BAD_CHUNK_TYPE); the input ends inside the varint
        (TRUNCATED); a varint that is not minimal, a last byte 0x00 after
        others (BAD_CHUNK_LENGTH); a fifth byte with bit 7 set
        (CHUNK_TOO_LONG, without reading further).  A length above 2^31 - 1
        is left to the caller (CHUNK_TOO_LONG)."""
        ctype = self.f.read(4)
        if len(ctype) < 4:
            if not ctype:
                raise PlnError("TRUNCATED", "input ends before PEND", offset=offset)
            raise PlnError("TRUNCATED", "input ends inside a chunk type", offset=offset)
        self.pos += 4
        name = ctype.decode("latin-1")
        if not all(is_letter(c) for c in ctype):
            raise PlnError("BAD_CHUNK_TYPE", "chunk type %r is not four ASCII letters" % ctype, name, offset)
        length = 0
        for n in range(LENGTH_VARINT_MAX_BYTES):
            b = self.f.read(1)
            if not b:
                raise PlnError("TRUNCATED", "input ends inside the length varint", name, offset)
            self.pos += 1
            b = b[0]
            length |= (b & 0x7F) << (7 * n)
            if not b & 0x80:
                if n > 0 and b == 0:
                    raise PlnError("BAD_CHUNK_LENGTH", "the length varint is not minimal", name, offset)
                return ctype, length
        raise PlnError("CHUNK_TOO_LONG", "the length varint's fifth byte has bit 7 set", name, offset)

    def read_signature(self):
        sig = b""
        while len(sig) < 8:
            b = self.f.read(8 - len(sig))
            if not b:
                break
            sig += b
        self.pos = len(sig)
        if sig == SIGNATURE:
            return
        if len(sig) < 8 and SIGNATURE.startswith(sig):
            raise PlnError("TRUNCATED", "input ends inside the signature", offset=0)
        if len(sig) >= 4 and sig[1:4] == b"PLN" and sig[0] in (0x89, 0x09):
            raise PlnError("TEXT_MODE_DAMAGE", "signature damaged by a text-mode transfer", offset=0)
        raise PlnError("BAD_SIGNATURE", "not a .pln signature", offset=0)

    # -- §5 header ---------------------------------------------------------

    def read_header(self, p):
        # pln.md §5 step 1, a payload under 2 bytes (BAD_PAYLOAD, raised by
        # the parsers below), before step 2, a major version other than 1 to 5
        if len(p) >= 2 and p[0] not in READER_VERSIONS:
            raise PlnError("UNSUPPORTED_VERSION", "major version %d" % p[0])
        # the layout is chosen by the major version: that of §5 for 1 and 2
        # (pln-2 §5), the compact one of pln-3 §5 for 3 to 5 (pln.md §5;
        # version 5's flags a u8, Appendix A.5); every field is read
        # (BAD_PAYLOAD) before any value is checked
        if len(p) >= 1 and p[0] >= SEGMENT_MAJOR:
            fields = self.parse_header_v6(p)
        elif len(p) >= 1 and p[0] >= 3:
            fields = self.parse_header_v3(p)
        else:
            fields = self.parse_header_v1(p)
        (major, minor, flags, coding, bn, bp, bh, units, h_min, h_max,
         bbox_min, bbox_max, tolerance, error_bound, plane_count, object_count, group_count) = fields
        # pln-3 §8.6: the first chunk after the header, the lowest offset an index entry may give
        self.after_header = len(SIGNATURE) + CHUNK_FRAME + len(p)

        if minor > READER_VERSIONS[major]:
            self.finding("NEWER_MINOR_VERSION")
        # coding 3, predicted, exists in major versions 2 (pln-2 §5) and 3 (pln-3 §5)
        codings = (0, 1, 2) if major == 1 else (0, 1, 2, 3)
        if coding not in codings:
            raise PlnError("UNSUPPORTED_CODING", "coding %d in a version %d file" % (coding, major))
        if coding in (CODING_QUANTIZED, CODING_PREDICTED):
            for w in (bn, bp, bh):
                if not 1 <= w <= 32:
                    raise PlnError("UNSUPPORTED_CODING", "quantized width %d outside 1-32" % w)
        # pln.md §5: the h range exists for codings 2 and 3 only; otherwise
        # it and the widths are ignored (pln.md §2.1), whatever they hold
        if coding in (CODING_QUANTIZED, CODING_PREDICTED):
            if not (math.isfinite(h_min) and math.isfinite(h_max)) or h_min > h_max:
                raise PlnError("BAD_HEADER_VALUE", "h range [%r, %r]" % (h_min, h_max))
        else:
            bn = bp = bh = 0
            h_min = h_max = 0.0
        # pln.md §5 step 7: version 5's units byte holds the unit in bits 0-3
        # and the up axis in bits 4-5 (bits 6-7 ignored); before, the unit alone
        up_axis = None
        if major >= 5:
            unit, axis = units & 0x0F, (units >> 4) & 0x03
            if unit > 7 or axis not in UP_AXES:
                raise PlnError("BAD_HEADER_VALUE", "units byte 0x%02X: unit %d, up axis %d" % (units, unit, axis))
            units, up_axis = unit, UP_AXES[axis]
        if units > 7:
            raise PlnError("BAD_HEADER_VALUE", "units %d" % units)
        if flags & FLAG_BBOX_KNOWN:
            for a, b in zip(bbox_min, bbox_max):
                if not (math.isfinite(a) and math.isfinite(b)) or a > b:
                    raise PlnError("BAD_HEADER_VALUE", "bbox %r %r" % (bbox_min, bbox_max))
        for name, v in (("tolerance", tolerance), ("error_bound", error_bound)):
            if not (math.isnan(v) or (math.isfinite(v) and v >= 0)):
                raise PlnError("BAD_HEADER_VALUE", "%s %r" % (name, v))

        self.major = major
        self.minor = minor
        self.coding = coding
        self.bits = (bn, bp, bh)
        self.h_range = (h_min, h_max)
        self.flags = flags
        self.counts = (plane_count, object_count, group_count)
        if up_axis is not None:
            # reported as a mETA up_axis would be (conformance/README.md's
            # "metadata", the expected JSON of the version 5.0 goldens)
            self.metadata["up_axis"] = up_axis
        self.header = {
            "version": [major, minor],
            "lossy": bool(flags & FLAG_LOSSY),
            "coding": coding,
            "bits": [bn, bp, bh],
            "h_range": [h_min, h_max],
            "units": units,
            "bbox": [bbox_min, bbox_max] if flags & FLAG_BBOX_KNOWN else None,
            "tolerance": nan_to_none(tolerance),
            "error_bound": nan_to_none(error_bound),
            "counts": (
                {"planes": plane_count, "objects": object_count, "groups": group_count}
                if flags & FLAG_COUNTS_KNOWN else None
            ),
        }

    def parse_header_v1(self, p):
        """§5: the fixed 108-byte layout of versions 1 and 2 (later bytes ignored)."""
        if len(p) < 108:
            raise PlnError("BAD_PAYLOAD", "PHDR payload of %d bytes, under 108" % len(p))
        major, minor, flags = p[0], p[1], u16(p, 2)
        coding, bn, bp, bh, units = p[4], p[5], p[6], p[7], p[8]
        h_min, h_max = f64(p, 12), f64(p, 20)
        bbox_min = [f64(p, 28 + 8 * i) for i in range(3)]
        bbox_max = [f64(p, 52 + 8 * i) for i in range(3)]
        tolerance, error_bound = f64(p, 76), f64(p, 84)
        plane_count, object_count, group_count = u64(p, 92), u32(p, 100), u32(p, 104)
        return (major, minor, flags, coding, bn, bp, bh, units, h_min, h_max,
                bbox_min, bbox_max, tolerance, error_bound, plane_count, object_count, group_count)

    def parse_header_v3(self, p):
        """pln-3 §5: a 9-byte fixed part, then the fields the flags and the
        coding call for, in table order; a payload that ends inside them is
        BAD_PAYLOAD, bytes after them are later fields and ignored.  pln.md
        §5, version 5: the fixed part is 8 bytes, flags a u8."""
        c = Cursor(p, "PHDR")
        v5 = p[0] >= 5
        c.need(V5_HEADER_FIXED if v5 else V3_HEADER_FIXED, "the fixed part")
        major, minor = c.u8("version_major"), c.u8("version_minor")
        flags = c.u8("flags") if v5 else c.u16("flags")
        coding, bn, bp, bh = c.u8("coding"), c.u8("bits_nu"), c.u8("bits_phi"), c.u8("bits_h")
        units = c.u8("units")
        # pln-3 §5: the coding is checked as soon as the fixed part is read,
        # because it decides which fields follow
        if coding not in (0, 1, 2, 3):
            raise PlnError("UNSUPPORTED_CODING", "coding %d in a version %d file" % (coding, major))
        # h range only for codings 2 and 3 ("coding 2 or 3")
        h_min = h_max = 0.0
        if coding in (CODING_QUANTIZED, CODING_PREDICTED):
            h_min, h_max = c.f64s(2, "h_min, h_max")
        bbox_min = bbox_max = None
        if flags & FLAG_BBOX_KNOWN:
            bbox = c.f32s(6, "bbox_min, bbox_max")
            bbox_min, bbox_max = bbox[:3], bbox[3:]
        tolerance, error_bound = c.f32s(2, "tolerance, error_bound")
        plane_count = object_count = group_count = 0
        if flags & FLAG_COUNTS_KNOWN:
            plane_count = c.varint("plane_count")
            object_count = c.varint32("object_count")
            group_count = c.varint32("group_count")
        # later fields (c.rest()): ignored (pln-3 §5, §11)
        return (major, minor, flags, coding, bn, bp, bh, units, h_min, h_max,
                bbox_min, bbox_max, tolerance, error_bound, plane_count, object_count, group_count)

    def parse_header_v6(self, p):
        """Version 6: version_major, version_minor (u8 each), header_size
        (varint32: the bytes of the fields that follow, up to and including
        the counts), then in those bytes flags (u8: bits 0-2 as before, bits
        3-4 the coding), units (u8), for codings 2 and 3 the widths (u16:
        each width - 1 in 5 bits, nu, phi, h from bit 0) and h_min, h_max,
        with BBOX_KNOWN the bbox, then tolerance and error_bound (every
        value an r32), with COUNTS_KNOWN the three counts.  A header_size
        past the payload's end, fields that do not fit in header_size, and
        a bad varint or r32 are BAD_PAYLOAD; header bytes after the fields
        are a newer minor's and ignored.  The payload's bytes after the
        header are the file's first body segment (kept in self.first_segment)."""
        c = Cursor(p, "PHDR")
        major, minor = c.u8("version_major"), c.u8("version_minor")
        size = c.varint32("header_size")
        if size > c.remaining():
            raise PlnError("BAD_PAYLOAD", "PHDR: header_size %d, %d bytes follow it" % (size, c.remaining()))
        h = Cursor(c.take(size), "PHDR header fields (header_size %d)" % size)
        flags = h.u8("flags")
        units = h.u8("units")
        coding = (flags >> CODING_SHIFT) & CODING_MASK
        bn = bp = bh = 0
        h_min = h_max = 0.0
        mask = (1 << WIDTH_BITS) - 1
        if coding in (CODING_QUANTIZED, CODING_PREDICTED):
            widths = h.u16("widths")
            bn, bp, bh = [((widths >> (WIDTH_BITS * k)) & mask) + 1 for k in range(3)]
            h_min, h_max = h.r32("h_min"), h.r32("h_max")
        bbox_min = bbox_max = None
        if flags & FLAG_BBOX_KNOWN:
            bbox = [h.r32("bbox value %d" % k) for k in range(6)]
            bbox_min, bbox_max = bbox[:3], bbox[3:]
        tolerance, error_bound = h.r32("tolerance"), h.r32("error_bound")
        plane_count = object_count = group_count = 0
        if flags & FLAG_COUNTS_KNOWN:
            plane_count = h.varint("plane_count")
            object_count = h.varint32("object_count")
            group_count = h.varint32("group_count")
        self.first_segment = c.rest()
        return (major, minor, flags, coding, bn, bp, bh, units, h_min, h_max,
                bbox_min, bbox_max, tolerance, error_bound, plane_count, object_count, group_count)

    # -- §8.1 objects ------------------------------------------------------

    def read_object(self, p, entry):
        # pln.md §8 checks, in its order: the object limit; the head
        # (BAD_PAYLOAD); name_length; the name and the transform (BAD_PAYLOAD);
        # then index, parent, UTF-8 and the transform's values (BAD_OBJECT)
        if len(self.objects) + 1 > LIMIT_OBJECTS:
            raise PlnError("LIMIT_EXCEEDED", "more than %d objects" % LIMIT_OBJECTS)
        c = Cursor(p, "OBJT")
        if self.major >= SEGMENT_MAJOR:
            # version 6: no index, an object's index is its place among the object records
            index = len(self.objects)
            parent, flags, name_len = self.read_object_head_v3(c, with_index=False)[1:]
        elif self.major >= 3:
            index, parent, flags, name_len = self.read_object_head_v3(c)
        else:
            head = c.take(12, "OBJT head")
            index, parent, flags, name_len = u32(head, 0), u32(head, 4), head[8], u16(head, 10)
        if name_len > MAX_NAME_LENGTH:  # only a pln-3 varint can exceed it; checked before the name
            raise PlnError("BAD_OBJECT", "name_length %d above %d" % (name_len, MAX_NAME_LENGTH))
        raw_name = c.take(name_len, "name")
        m = None
        if flags & OBJ_HAS_TRANSFORM:
            if self.major >= 4:
                m = self.read_transform_v4(c)
            else:
                m = list(struct.unpack("<16d", c.take(128, "transform")))
        if index != len(self.objects):
            raise PlnError("BAD_OBJECT", "object index %d, expected %d" % (index, len(self.objects)))
        if parent != NO_PARENT and parent >= index:
            raise PlnError("BAD_OBJECT", "parent %d is not an earlier object" % parent)
        try:
            name = raw_name.decode("utf-8")
        except UnicodeDecodeError:
            raise PlnError("BAD_OBJECT", "name is not UTF-8")
        transform = None
        if m is not None:
            if not all(math.isfinite(v) for v in m):
                raise PlnError("BAD_OBJECT", "transform entry not finite")
            # pln.md Appendix A: checked in 1.0 to 3.4; not stored in 4.0
            if m[12:16] != [0.0, 0.0, 0.0, 1.0]:
                raise PlnError("BAD_OBJECT", "transform last row %r is not 0 0 0 1" % m[12:16])
            transform = m
        # later fields: ignored (§8.1, §11)
        self.objects.append({
            "name": name,
            "parent": None if parent == NO_PARENT else parent,
            "transform": transform,
        })
        self.chunk_list.append(entry + (index,))

    def read_transform_v4(self, c):
        """pln.md §8, version 4: codes, a 3-byte bit string (§2.1, least
        significant bit first) of twelve 2-bit codes, entry i's code being bit
        2i + 2 * bit 2i+1 (0 is +0.0, 1 is 1.0, 2 an f32 follows, 3 an f64
        follows), for m00 .. m23 row by row; then the f32/f64 values in entry
        order.  The last row is 0 0 0 1, not stored.  A payload that ends
        inside the codes or the values is BAD_PAYLOAD."""
        codes = c.take(3, "transform codes")
        bits = codes[0] | codes[1] << 8 | codes[2] << 16
        m = []
        for i in range(12):
            code = (bits >> (2 * i)) & 0b11
            if code == 0:
                m.append(0.0)
            elif code == 1:
                m.append(1.0)
            elif code == 2:
                m.append(c.f32s(1, "transform value %d (f32)" % i)[0])  # widened exactly
            else:
                m.append(c.f64s(1, "transform value %d (f64)" % i)[0])
        return m + [0.0, 0.0, 0.0, 1.0]

    def read_object_head_v3(self, c, with_index=True):
        """pln-3 §8.1: index, parent (varint32, 0 for a root, else the parent's
        index + 1), flags (u8), name_length (varint); returned with the parent
        in the numbering of §8.1 (NO_PARENT for a root).  Version 6: no
        index (returned as None)."""
        index = c.varint32("object index") if with_index else None
        parent = c.varint32("parent")
        flags = c.u8("flags")
        name_len = c.varint("name_length")
        return index, (NO_PARENT if parent == V3_NO_PARENT else parent - 1), flags, name_len

    # -- §7 plane table ----------------------------------------------------

    def read_planes(self, p, entry):
        if self.major >= SEGMENT_MAJOR:
            # version 6: count, then the raw triplet data, its size the rest of the record
            c = Cursor(p, "PLNS")
            count = c.varint32("count")
            first, method, stored = len(self.planes), 0, c.rest()
            raw_size = len(stored)
        elif self.major >= 3:
            first, count, method, raw_size, stored = self.read_planes_head_v3(p)
        else:
            if len(p) < 20:
                raise PlnError("BAD_PAYLOAD", "PLNS payload of %d bytes, under 20" % len(p))
            first, count, method, raw_size, stored = u64(p, 0), u32(p, 8), p[12], u32(p, 16), p[20:]
        if first != len(self.planes):
            raise PlnError("PLANE_INDEX_MISMATCH",
                           "first %d, %d planes before" % (first, len(self.planes)))
        if len(self.planes) + count > LIMIT_PLANES:
            raise PlnError("LIMIT_EXCEEDED", "plane table above %d planes" % LIMIT_PLANES)
        if self.coding == CODING_PREDICTED:
            # pln-2 §7.4: not implied by count; 1 to 5 bytes a varint, checked before inflating
            if not 3 * count <= raw_size <= 15 * count:
                raise PlnError("SIZE_MISMATCH",
                               "raw_size %d outside [%d, %d] for %d predicted planes"
                               % (raw_size, 3 * count, 15 * count, count))
        else:
            if self.coding == 0:
                expected = 12 * count
            elif self.coding == 1:
                expected = 24 * count
            else:
                expected = (count * sum(self.bits) + 7) // 8
            if raw_size != expected:
                raise PlnError("SIZE_MISMATCH",
                               "raw_size %d, %d planes take %d" % (raw_size, count, expected))
        data = decompress(method, raw_size, stored, "PLNS data", self.major)
        base = len(self.planes)
        if self.coding == 0:
            vals = struct.unpack("<%df" % (3 * count), data)
            self.add_float_planes(vals, count, F32_PI, F32_2PI, base)
        elif self.coding == 1:
            vals = struct.unpack("<%dd" % (3 * count), data)
            self.add_float_planes(vals, count, math.pi, 2 * math.pi, base)
        elif self.coding == CODING_QUANTIZED:
            self.add_quantized_planes(data, count, base)
        else:
            self.add_predicted_planes(data, count, base)
        self.chunk_list.append(entry + (first,))

    def read_planes_head_v3(self, p):
        """pln-3 §7: first (varint), count (varint32), compression (u8),
        raw_size (varint32), then the stored data; a payload that ends inside
        the head is BAD_PAYLOAD."""
        c = Cursor(p, "PLNS")
        first = c.varint("first")
        count = c.varint32("count")
        method = c.u8("compression")
        raw_size = c.varint32("raw_size")
        return first, count, method, raw_size, c.rest()

    def add_float_planes(self, vals, count, pi, two_pi, base):
        planes = self.planes
        for i in range(count):
            nu, phi, h = vals[3 * i], vals[3 * i + 1], vals[3 * i + 2]
            if not (math.isfinite(nu) and math.isfinite(phi) and math.isfinite(h)):
                raise PlnError("BAD_TRIPLET", "plane %d not finite" % (base + i))
            if not (0.0 <= nu <= pi):
                raise PlnError("BAD_TRIPLET", "plane %d: nu %r outside [0, pi]" % (base + i, nu))
            if not (0.0 <= phi < two_pi):
                raise PlnError("BAD_TRIPLET", "plane %d: phi %r outside [0, 2pi)" % (base + i, phi))
            planes.append([nu, phi, h])

    def add_quantized_planes(self, data, count, base):
        """§7.3: a bit string of (q_nu, q_phi, q_h) records."""
        bn, bp, bh = self.bits
        rec = bn + bp + bh
        check_bit_padding(data, count * rec, "PLNS quantized data")
        m_nu = 2 ** (bn - 1)
        mask_nu, mask_phi, mask_h = (1 << bn) - 1, (1 << bp) - 1, (1 << bh) - 1
        codes = []
        for i in range(count):
            start = i * rec
            b0 = start >> 3
            b1 = (start + rec + 7) >> 3
            v = int.from_bytes(data[b0:b1], "little") >> (start & 7)
            q_nu = v & mask_nu
            q_phi = (v >> bn) & mask_phi
            q_h = (v >> (bn + bp)) & mask_h
            if q_nu > m_nu:
                raise PlnError("BAD_TRIPLET",
                               "plane %d: nu code %d above %d" % (base + i, q_nu, m_nu))
            codes.append((q_nu, q_phi, q_h))
        self.add_dequantized_planes(codes)

    def add_predicted_planes(self, data, count, base):
        """pln-2 §7.4: three streams of `count` varints (nu, phi, h), each code
        predicted from the previous plane's, then dequantized as §7.3 says."""
        c = Cursor(data, "PLNS predicted data")
        streams = []
        for name in ("nu", "phi", "h"):
            stream = []
            for i in range(count):
                v = c.varint("the %s varint of plane %d" % (name, base + i))
                if v >= PLANE_VARINT_LIMIT:
                    raise PlnError("BAD_PAYLOAD", "plane %d: %s varint %d not below 2^33"
                                   % (base + i, name, v))
                stream.append(v)
            streams.append(stream)
        if c.remaining():
            raise PlnError("SIZE_MISMATCH", "%d bytes after the %d varints of the predicted planes"
                           % (c.remaining(), 3 * count))
        bn, bp, bh = self.bits
        max_nu, max_phi, max_h = 2 ** (bn - 1), 2 ** bp - 1, 2 ** bh - 1
        s_nu, s_phi, s_h = streams
        codes = []
        a = b = cc = 0  # a_{-1} = 0; b and c are only used for i > 0
        for i in range(count):
            prev_a, prev_b, prev_c = a, b, cc
            # 1. nu: zigzag(a_i - a_{i-1}), a_{-1} = 0
            a = prev_a + unzigzag(s_nu[i])
            # 2. phi: a difference if i > 0 and a_i = a_{i-1}; otherwise the code
            same_nu = i > 0 and a == prev_a
            b = prev_b + unzigzag(s_phi[i]) if same_nu else s_phi[i]
            # 3. h: a difference if also b_i = b_{i-1}; otherwise the code
            cc = prev_c + unzigzag(s_h[i]) if same_nu and b == prev_b else s_h[i]
            for what, q, top in (("nu", a, max_nu), ("phi", b, max_phi), ("h", cc, max_h)):
                if not 0 <= q <= top:
                    raise PlnError("BAD_TRIPLET", "plane %d: %s code %d outside [0, %d]"
                                   % (base + i, what, q, top))
            codes.append((a, b, cc))
        self.add_dequantized_planes(codes)

    def add_dequantized_planes(self, codes):
        """§7.3 dequantization, for codings 2 and 3."""
        bn, bp, bh = self.bits
        m_nu = 2 ** (bn - 1)
        n_phi = 2 ** bp
        m_h = 2 ** bh - 1
        h_min, h_max = self.h_range
        step_nu = math.pi / m_nu
        step_phi = (2 * math.pi) / n_phi
        step_h = (h_max - h_min) / m_h
        planes = self.planes
        for q_nu, q_phi, q_h in codes:
            planes.append([q_nu * step_nu, q_phi * step_phi, h_min + q_h * step_h])

    # -- §8.2 part groups --------------------------------------------------

    def read_group(self, p, entry):
        if self.major >= SEGMENT_MAJOR:
            # version 6: object, kind, then the body, stored (the segment is compressed)
            c = Cursor(p, "GRUP")
            obj = c.varint32("object")
            kind = c.u8("kind")
            index, method, stored = len(self.groups), 0, c.rest()
            raw_size = len(stored)
        elif self.major >= 3:
            index, obj, kind, method, raw_size, stored = self.read_group_head_v3(p)
        else:
            if len(p) < 16:
                raise PlnError("BAD_PAYLOAD", "GRUP payload of %d bytes, under 16" % len(p))
            index, obj, kind, method, raw_size = u32(p, 0), u32(p, 4), p[8], p[9], u32(p, 12)
            stored = p[16:]
        if index != len(self.groups):
            raise PlnError("GROUP_INDEX_MISMATCH",
                           "group index %d, expected %d" % (index, len(self.groups)))
        if obj >= len(self.objects):
            raise PlnError("BAD_OBJECT_REFERENCE",
                           "object %d, %d defined" % (obj, len(self.objects)))
        known = kind in KNOWN_KINDS or (kind in KIND_SINCE and (self.major, self.minor) >= KIND_SINCE[kind])
        if not known and self.minor <= READER_VERSIONS[self.major]:
            raise PlnError("UNKNOWN_GROUP_KIND",
                           "kind %d in a version %d.%d file" % (kind, self.major, self.minor))
        body = decompress(method, raw_size, stored, "GRUP body", self.major)

        c = Cursor(body, "GRUP body")
        v2 = self.major >= 2  # pln-2 §8.7: varint bodies, in major 3 too (pln-3 §8.2)
        shell = known and kind == SHELL_KIND
        refs = self.read_refs_v2(c, kind) if v2 else self.read_refs(c)
        m = len(refs)
        roles = c.take((m + 7) // 8, "roles")
        check_bit_padding(roles, m, "GRUP roles")
        bounding = [i for i in range(m) if (roles[i >> 3] >> (i & 7)) & 1]

        g = {"index": index, "object": obj, "kind": kind, "refs": refs, "bounding": bounding}
        skipped = not known
        if not known:
            self.finding("SKIPPED_GROUP_KIND")  # kind data is not interpreted
        elif kind == COPY_KIND:
            g["source"] = source = self.read_copy(c, index, refs, bounding)
            skipped = self.group_skipped[source]
        elif kind in (0, 3, 4):
            if c.remaining():
                raise PlnError("BAD_PAYLOAD",
                               "%d bytes of kind data for kind %d" % (c.remaining(), kind))
        elif kind == 1:
            g["cells"] = self.read_cells_v2(c, m) if v2 else self.read_cells(c, m)
        elif kind == 2:
            g["tree"] = self.read_tree_v2(c, m) if v2 else self.read_tree(c, m)
        elif kind == SEALED_KIND:
            g["vertex_planes"], g["facets"] = self.read_sealed(c, m, set(bounding))
        elif shell:
            g["shell"] = self.read_shell(c, m, set(bounding))
        elif kind in (SHELL_TREE_KIND, PARALLELOGRAM_KIND):
            g["shell"] = self.read_shell_tree(c, m, set(bounding), kind == PARALLELOGRAM_KIND)
        elif kind in (WALK_KIND, MULTI_WALK_KIND, REFLECT_WALK_KIND, LATER_WALK_KIND):
            g["shell"] = self.read_shell_walk(c, m, set(bounding), kind == MULTI_WALK_KIND,
                                              kind == REFLECT_WALK_KIND, kind == LATER_WALK_KIND)
        self.groups.append(g)
        self.group_refcounts.append(m)
        self.group_kinds.append(kind)
        self.group_skipped.append(skipped)
        self.chunk_list.append(entry + (index,))

    def read_copy(self, c, index, refs, bounding):
        """pln.md §9.15, kind 11: one varint s, the index of the source group,
        checked in the order §9.15 lists: (1) the body ends inside s or s is a
        bad varint, or bytes follow it: BAD_PAYLOAD; (2) s not below this
        group's index, or a source of kind 11: BAD_GROUP_STRUCTURE; (3) a
        source whose kind was skipped (§9.3): the copy is skipped too
        (SKIPPED_GROUP_KIND), and (4) is not checked; (4) references or role
        bits other than the source's: BAD_GROUP_STRUCTURE.  s is "one varint",
        not a varint32: a value of 2^32 or more is not below the index (2).
        Returns s; the group is reported as stored, with "source": s."""
        s = c.varint("source")
        if c.remaining():
            raise PlnError("BAD_PAYLOAD", "%d bytes after a copy's source" % c.remaining())
        if s >= index:
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "copy %d names source %d, not an earlier group" % (index, s))
        if self.group_kinds[s] == COPY_KIND:
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "copy %d names group %d, itself a copy" % (index, s))
        if self.group_skipped[s]:
            self.finding("SKIPPED_GROUP_KIND")
            return s
        source = self.groups[s]
        if refs != source["refs"]:
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "copy %d: references other than its source %d's" % (index, s))
        if bounding != source["bounding"]:
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "copy %d: role bits other than its source %d's" % (index, s))
        return s

    def read_group_head_v3(self, p):
        """pln-3 §8.2: index, object (varint32), kind, compression (u8),
        raw_size (varint32), then the stored body; a payload that ends inside
        the head is BAD_PAYLOAD."""
        c = Cursor(p, "GRUP")
        index = c.varint32("group index")
        obj = c.varint32("object")
        kind = c.u8("kind")
        method = c.u8("compression")
        raw_size = c.varint32("raw_size")
        return index, obj, kind, method, raw_size, c.rest()

    def check_ref_count(self, m, kind=0):
        """pln.md §9.2 step 2: m above the limit (LIMIT_EXCEEDED); m = 0
        (BAD_GROUP_STRUCTURE) in every group before version 5 (Appendix
        A.5), and in version 5 in kinds 0 to 5 only: a shell or a copy
        (kinds 6 to 13) may have none, and a kind of a newer minor version,
        skipped here, decides for itself."""
        if m > LIMIT_REFS:
            raise PlnError("LIMIT_EXCEEDED", "ref_count %d above %d" % (m, LIMIT_REFS))
        if m == 0 and (self.major < NO_REFS_MAJOR or kind <= LAST_KIND_NEEDING_REFS):
            raise PlnError("BAD_GROUP_STRUCTURE", "ref_count 0 in a group of kind %d, version %d"
                           % (kind, self.major))

    def read_refs(self, c):
        """§8.2: ref_count (u32) and refs (u32 plane indices)."""
        m = c.u32("ref_count")
        self.check_ref_count(m)
        refs = c.u32_array(m, "refs")
        n_planes = len(self.planes)
        for r in refs:
            if r >= n_planes:
                raise PlnError("BAD_PLANE_REFERENCE",
                               "reference to plane %d, %d defined" % (r, n_planes))
        return refs

    def read_refs_v2(self, c, kind):
        """pln-2 §8.7: ref_count (varint) and refs as varint differences
        (non-decreasing), each difference checked before it is summed."""
        m = c.varint("ref_count")
        self.check_ref_count(m, kind)
        n_planes = len(self.planes)
        refs = []
        r = 0
        # pln.md §9.2: all m differences are read (BAD_PAYLOAD) before any is checked
        diffs = [c.varint("reference difference %d" % i) for i in range(m)]
        for i, d in enumerate(diffs):
            if d >= n_planes or r + d >= n_planes:
                raise PlnError("BAD_PLANE_REFERENCE",
                               "reference %d: %d + difference %d, %d planes defined"
                               % (i, r, d, n_planes))
            r += d
            refs.append(r)
        return refs

    def read_cells(self, c, m):
        """§8.3."""
        n = c.u32("cell_count")
        if n == 0:
            raise PlnError("BAD_GROUP_STRUCTURE", "cell_count 0")
        sizes = c.u32_array(n, "cell sizes")
        total = 0
        for s in sizes:
            if s == 0:
                raise PlnError("BAD_GROUP_STRUCTURE", "a cell of size 0")
            total += s
        entries = c.u32_array(total, "cell entries")
        if c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "%d bytes after the cell entries" % c.remaining())
        for e in entries:
            if (e >> 1) >= m:
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "cell entry %d: local reference %d of %d" % (e, e >> 1, m))
        cells = []
        k = 0
        for s in sizes:
            cells.append(entries[k:k + s])
            k += s
        return cells

    def read_cells_v2(self, c, m):
        """pln-2 §8.7, kind 1: the fields of §8.3 as varints."""
        n = c.varint("cell_count")
        if n == 0:
            raise PlnError("BAD_GROUP_STRUCTURE", "cell_count 0")
        if n > c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "cell_count %d, %d bytes left" % (n, c.remaining()))
        sizes = []
        total = 0
        for k in range(n):
            s = c.varint("size of cell %d" % k)
            if s == 0:
                raise PlnError("BAD_GROUP_STRUCTURE", "a cell of size 0")
            if s > c.remaining():
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "cell %d of size %d, %d bytes left" % (k, s, c.remaining()))
            sizes.append(s)
            total += s
        if total > c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "%d cell entries, %d bytes left" % (total, c.remaining()))
        cells = []
        for k, s in enumerate(sizes):
            cell = []
            for _ in range(s):
                e = c.varint("an entry of cell %d" % k)
                if (e >> 1) >= m:
                    raise PlnError("BAD_GROUP_STRUCTURE",
                                   "cell entry %d: local reference %d of %d" % (e, e >> 1, m))
                cell.append(e)
            cells.append(cell)
        if c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "%d bytes after the cell entries" % c.remaining())
        return cells

    def read_tree(self, c, m):
        """§8.4."""
        t = c.u32("token_count")
        tokens = c.u32_array(t, "tokens")
        if c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE", "%d bytes after the tokens" % c.remaining())
        return self.check_tree(tokens, m)

    def read_tree_v2(self, c, m):
        """pln-2 §8.7, kind 2: varint tokens 0 IN, 1 OUT, j + 2 split on j,
        returned in the numbering of §8.4 and checked as §8.4 says."""
        t = c.varint("token_count")
        if t > c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "token_count %d, %d bytes left" % (t, c.remaining()))
        tokens = []
        for i in range(t):
            tok = c.varint("token %d" % i)
            if tok == V2_TOKEN_IN:
                tokens.append(TOKEN_IN)
            elif tok == V2_TOKEN_OUT:
                tokens.append(TOKEN_OUT)
            else:
                j = tok - V2_TOKEN_SPLIT
                if j >= m:
                    raise PlnError("BAD_GROUP_STRUCTURE",
                                   "token %d: %d, a split on local reference %d of %d"
                                   % (i, tok, j, m))
                tokens.append(j)  # j < m <= LIMIT_REFS, below the reserved tokens
        if c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE", "%d bytes after the tokens" % c.remaining())
        return self.check_tree(tokens, m)

    def read_sealed(self, c, m, bounding):
        """pln-3 §8.8, kind 5: vertex_count, each vertex's three local
        references, triangle_count, then per triangle a face reference
        difference and three vertex indices.  In the order §8.8 gives: each
        count is checked against the bytes left when it is read (pln-2 §8.7);
        everything else only once all the varints the counts call for are
        read, so that a body ending inside one is BAD_PAYLOAD even where an
        earlier value is also wrong."""
        # 1. the varints, counts checked as they are read
        v = c.varint("vertex_count")
        if not 3 <= v <= c.remaining() // 3:
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "vertex_count %d, %d bytes left" % (v, c.remaining()))
        vertices = [[c.varint("a plane of vertex %d" % k) for _ in range(3)] for k in range(v)]
        t = c.varint("triangle_count")
        if not 1 <= t <= c.remaining() // 4:
            raise PlnError("BAD_GROUP_STRUCTURE",
                           "triangle_count %d, %d bytes left" % (t, c.remaining()))
        stored = [[c.varint("%s of triangle %d" % (what, k))
                   for what in ("the face difference", "vertex i0", "vertex i1", "vertex i2")]
                  for k in range(t)]
        # 2. the values
        if c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE", "%d bytes after the triangles" % c.remaining())
        for k, planes in enumerate(vertices):
            if max(planes) >= m or len(set(planes)) != 3:
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "vertex %d: local references %r, of %d" % (k, planes, m))
        facets = []
        used = set()
        face = 0
        for k, (d, *corners) in enumerate(stored):
            if d >= m or face + d >= m:
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "triangle %d: face %d + difference %d, of %d" % (k, face, d, m))
            face += d
            if face in bounding:
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "triangle %d: local reference %d is a vertex plane (role bit 1)" % (k, face))
            if max(corners) >= v or len(set(corners)) != 3:
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "triangle %d: vertices %r, of %d" % (k, corners, v))
            used.update(corners)
            facets.append([face] + corners)
        if len(used) != v:
            raise PlnError("BAD_GROUP_STRUCTURE", "%d of %d vertices on no triangle" % (v - len(used), v))
        return vertices, facets

    def read_shell(self, c, m, bounding):
        """pln-3 §8.9, kind 6: corner_count V, triangle_count T, free_count U;
        ceil(V/8) bytes of flags (bit k: corner k explicit); the three local
        references of each of the N = V - E named corners; if E > 0 the grid
        (origin x, y, z and step s, f64) and the zigzag steps of the explicit
        corners' integer coordinates; T - U face differences; 3T corner codes
        (0 the next new corner, k >= 1 corner n - k).  The three counts are
        checked against the bytes left after them (the table measures them
        there), the padding of the flags as they are read (BAD_PAYLOAD),
        everything else once every field the counts call for is read.
        Returned as the JSON "shell" object: explicit corners, named corners'
        references, explicit corners' integer coordinates, origin and step
        (null without explicit corners), and facets [face or -1, i0, i1, i2]."""
        # 1. the fields, counts checked as they are read
        v = c.varint("corner_count")
        t = c.varint("triangle_count")
        u = c.varint("free_count")
        left = c.remaining()
        if not 3 <= v <= 8 * left:
            raise PlnError("BAD_GROUP_STRUCTURE", "corner_count %d, %d bytes left" % (v, left))
        if not 1 <= t <= left // 3:
            raise PlnError("BAD_GROUP_STRUCTURE", "triangle_count %d, %d bytes left" % (t, left))
        if u > t:
            raise PlnError("BAD_GROUP_STRUCTURE", "free_count %d of %d triangles" % (u, t))
        flags = c.take((v + 7) // 8, "corner flags")
        check_bit_padding(flags, v, "GRUP shell corner flags")
        explicit = [k for k in range(v) if (flags[k >> 3] >> (k & 7)) & 1]
        e = len(explicit)
        named = [[c.varint("a plane of named corner %d" % k) for _ in range(3)] for k in range(v - e)]
        origin = step = None
        steps = []
        if e:
            origin, step = self.read_grid(c)
            steps = [[unzigzag(c.varint("a coordinate step of explicit corner %d" % k)) for _ in range(3)]
                     for k in range(e)]
        diffs = [c.varint("the face difference of triangle %d" % k) for k in range(t - u)]
        codes = [c.varint("corner code %d" % k) for k in range(3 * t)]
        # 2. the values
        if c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE", "%d bytes after the corner codes" % c.remaining())
        for k, planes in enumerate(named):
            if max(planes) >= m or len(set(planes)) != 3:
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "named corner %d: local references %r, of %d" % (k, planes, m))
        if e:
            if not all(math.isfinite(x) for x in origin) or not (math.isfinite(step) and step > 0):
                raise PlnError("BAD_GROUP_STRUCTURE", "grid origin %r, step %r" % (origin, step))
        grid = []
        xyz = [0, 0, 0]
        for k, st in enumerate(steps):
            for a in range(3):
                xyz[a] += st[a]
                if abs(st[a]) > SHELL_COORD_LIMIT or abs(xyz[a]) > SHELL_COORD_LIMIT:
                    raise PlnError("BAD_GROUP_STRUCTURE",
                                   "explicit corner %d: step %d to coordinate %d, beyond 2^52"
                                   % (k, st[a], xyz[a]))
            grid.append(list(xyz))
        faces = []
        face = 0  # f_{-1} = 0
        for k, d in enumerate(diffs):
            if d >= m or face + d >= m:
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "triangle %d: face %d + difference %d, of %d" % (k, face, d, m))
            face += d
            if face in bounding:
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "triangle %d: local reference %d is a bounding plane (role bit 1)" % (k, face))
            faces.append(face)
        faces += [-1] * u  # the last U triangles are free
        facets = []
        n = 0  # corners named by a code 0 so far
        for k in range(t):
            corners = []
            for code in codes[3 * k:3 * k + 3]:
                if code == 0:
                    corners.append(n)
                    n += 1
                elif code > n:
                    raise PlnError("BAD_GROUP_STRUCTURE",
                                   "triangle %d: corner code %d, %d corners named so far" % (k, code, n))
                else:
                    corners.append(n - code)
            if len(set(corners)) != 3:
                raise PlnError("BAD_GROUP_STRUCTURE", "triangle %d: corners %r" % (k, corners))
            facets.append([faces[k]] + corners)
        if n != v:
            raise PlnError("BAD_GROUP_STRUCTURE", "%d corners used, corner_count %d" % (n, v))
        return {"explicit": explicit, "vertex_planes": named, "grid": grid,
                "origin": origin, "step": step, "facets": facets}

    def read_grid(self, c):
        """pln-3 §8.9, pln.md §9.10-§9.14: a shell's grid, origin x, y, z and
        step s; f64 each (32 bytes) in versions 3 and 4, f32 each (16 bytes,
        widened exactly) in version 5.  Checked by the caller."""
        read = c.f32s if self.major >= F32_GRID_MAJOR else c.f64s
        origin = read(3, "grid origin")
        return origin, read(1, "grid step")[0]

    def read_shell_tree(self, c, m, bounding, parallelogram=False):
        """pln-3 §8.10, kind 7: corner_count V, triangle_count T; T links
        (0 a root, else 3(d - 1) + e + 1: attached to edge e of triangle
        j - d); the corner codes (three for a root, one for an attached
        triangle); T face codes (0 the parent's, or the previous triangle's
        for a root, 1 free, r + 2 reference r); the corner flags; three picks
        per named corner on more than three face planes; the grid and the
        coordinate residuals (every x, then every y, then every z) if any
        corner is explicit.  Read in the order the section gives: counts
        (checked against the bytes left), links, codes, faces, flags (padding
        checked as read); then the triangles and faces are checked, which
        decide the number of picks; then the rest.  Returned as the JSON
        "shell" object of a kind 6 group (the triangles decoded in order,
        each attached one from its parent's corners).  pln.md §9.12, kind 8
        (``parallelogram``): an explicit corner named by an attached triangle
        whose two shared corners and whose parent's opposite corner are
        explicit is predicted by i0 + i1 - opposite."""
        v = c.varint("corner_count")
        t = c.varint("triangle_count")
        left = c.remaining()
        if not 3 <= v <= 8 * left:
            raise PlnError("BAD_GROUP_STRUCTURE", "corner_count %d, %d bytes left" % (v, left))
        if not 1 <= t <= left // 3:
            raise PlnError("BAD_GROUP_STRUCTURE", "triangle_count %d, %d bytes left" % (t, left))
        links = [c.varint("link %d" % j) for j in range(t)]
        roots = sum(1 for link in links if link == 0)
        codes = [c.varint("corner code %d" % k) for k in range(t + 2 * roots)]
        face_codes = [c.varint("face code %d" % j) for j in range(t)]
        flags = c.take((v + 7) // 8, "corner flags")
        check_bit_padding(flags, v, "GRUP shell tree corner flags")
        # the triangles, in order: a parent comes before its children
        tris = []
        parents = []  # (parent, edge) of each attached triangle, None for a root
        n = 0
        next_code = 0
        creator = {}  # corner -> the triangle whose code named it anew
        for j, link in enumerate(links):
            if link == 0:
                parents.append(None)
                corners = []
                for _ in range(3):
                    code = codes[next_code]
                    next_code += 1
                    if code == 0:
                        creator[n] = j
                        corners.append(n)
                        n += 1
                    elif code > n:
                        raise PlnError("BAD_GROUP_STRUCTURE",
                                       "triangle %d: corner code %d, %d corners named so far" % (j, code, n))
                    else:
                        corners.append(n - code)
            else:
                d, e = (link - 1) // 3 + 1, (link - 1) % 3
                if d > j:
                    raise PlnError("BAD_GROUP_STRUCTURE", "triangle %d: link %d, parent before the first" % (j, link))
                parents.append((j - d, e))
                q = tris[j - d]
                corners = [q[(e + 1) % 3], q[e]]
                code = codes[next_code]
                next_code += 1
                if code == 0:
                    creator[n] = j
                    corners.append(n)
                    n += 1
                else:
                    third = corners[1] + unzigzag(code - 1)
                    if not 0 <= third < n:
                        raise PlnError("BAD_GROUP_STRUCTURE",
                                       "triangle %d: third corner %d, %d corners named so far" % (j, third, n))
                    corners.append(third)
            if len(set(corners)) != 3:
                raise PlnError("BAD_GROUP_STRUCTURE", "triangle %d: corners %r" % (j, corners))
            tris.append(corners)
        if n != v:
            raise PlnError("BAD_GROUP_STRUCTURE", "%d corners named anew, corner_count %d" % (n, v))
        return self.read_shell_tree_rest(c, m, bounding, v, flags, face_codes, tris, parents, creator,
                                         parallelogram)

    def read_shell_tree_rest(self, c, m, bounding, v, flags, face_codes, tris, parents, creator,
                             parallelogram=False, walk=False, multi=False, reflect=False, later=False):
        """What pln.md §9.11 and §9.13 have in common once the triangles,
        each one's parent (or None) and the triangle that named each corner
        anew are known: the faces (checked here, since they decide the
        picks), the picks, the grid and the coordinates.  A shell walk
        (``walk``, pln.md §9.13) has a mode byte before the grid (bit 0:
        the parallelogram of §9.12; bit 1: per-axis value tables, read after
        the grid, into which the predicted and resolved values index).
        A shell walk with multi-parallelograms (``multi``, pln.md §9.14)
        predicts an explicit corner that has parallelograms by their
        average, and any other as a shell walk does; a shell walk with
        reflections (``reflect``, pln.md §9.16) one whose chain of step
        sources turns by reflected_step, and any other as a shell walk
        does; a shell walk stepping from the later gate corner (``later``,
        pln.md §9.17) as a shell walk does, but with §9.11's predictor
        corner max(i0, i1) of the naming triangle, not i0."""
        explicit = [k for k in range(v) if (flags[k >> 3] >> (k & 7)) & 1]
        is_explicit = set(explicit)
        faces = []
        for j, code in enumerate(face_codes):
            if code == 0:
                if parents[j] is not None:
                    face = faces[parents[j][0]]
                else:
                    face = faces[j - 1] if j else -1
            elif code == 1:
                face = -1
            else:
                face = code - 2
                if face >= m:
                    raise PlnError("BAD_GROUP_STRUCTURE", "triangle %d: face code %d, of %d" % (j, code, m))
                if face in bounding:
                    raise PlnError("BAD_GROUP_STRUCTURE",
                                   "triangle %d: local reference %d is a bounding plane (role bit 1)" % (j, face))
            faces.append(face)
        around = [set() for _ in range(v)]
        for face, corners in zip(faces, tris):
            if face >= 0:
                for k in corners:
                    around[k].add(face)
        named = [(k, sorted(around[k])) for k in range(v) if k not in is_explicit]

        def few_planes():
            # with the rest, once every field is read (pln.md §9.11, §9.13 since issue 49;
            # SPEC_NOTES 18, 32 had it before the picks)
            for k, planes in named:
                if len(planes) < 3:
                    raise PlnError("BAD_GROUP_STRUCTURE", "named corner %d on face planes %r" % (k, planes))
        # the picks are read here and checked with the rest, after the grid
        # and the coordinates are read (pln.md §9.11, §9.13: "reads the
        # picks, the grid and the coordinates, and checks the rest")
        picks = {k: [c.varint("a pick of corner %d" % k) for _ in range(3)]
                 for k, planes in named if len(planes) > 3}
        origin = step = None
        grid = []
        if not explicit:
            few_planes()
        if explicit:
            e = len(explicit)
            mode = c.u8("mode") if walk else 0
            if walk:
                parallelogram = bool(mode & 1)
            origin, step = self.read_grid(c)
            tables = None
            if mode & 2:
                # pln.md §9.13: per axis a count C (1 <= C <= E, checked as
                # it is read, pln.md §12.1 item 4, SPEC_NOTES 31), the first value as a
                # zigzag varint, then C - 1 gaps g: next = previous + g + 1
                tables = []
                for axis in "xyz":
                    count = c.varint("the %s table's count" % axis)
                    if not 1 <= count <= e:
                        raise PlnError("BAD_GROUP_STRUCTURE",
                                       "the %s table's count %d, %d explicit corners" % (axis, count, e))
                    values = [unzigzag(c.varint("the %s table's first value" % axis))]
                    for _ in range(count - 1):
                        values.append(values[-1] + c.varint("a gap of the %s table" % axis) + 1)
                    tables.append(values)
            residuals = [[unzigzag(c.varint("a coordinate residual")) for _ in range(e)] for _ in range(3)]
            few_planes()
            if c.remaining():
                raise PlnError("BAD_GROUP_STRUCTURE", "%d bytes after the coordinates" % c.remaining())
            if not all(math.isfinite(x) for x in origin) or not (math.isfinite(step) and step > 0):
                raise PlnError("BAD_GROUP_STRUCTURE", "grid origin %r, step %r" % (origin, step))
            if mode > 3:  # with the rest (SPEC_NOTES 31)
                raise PlnError("BAD_GROUP_STRUCTURE", "mode 0x%02X: a bit above bit 1 set" % mode)
            if tables is not None:
                for axis, values in zip("xyz", tables):
                    for value in values:
                        if abs(value) > SHELL_COORD_LIMIT:
                            raise PlnError("BAD_GROUP_STRUCTURE",
                                           "the %s table's value %d, beyond 2^52" % (axis, value))
            xyz = {}  # with tables, each corner's indices into them; otherwise its coordinates
            previous = None
            grams = multi_parallelograms(tris, is_explicit) if multi else {}
            sources = {}  # pln.md §9.16: each explicit corner's step source, its §9.11 predictor
            for r, k in enumerate(explicit):  # corner order: every predictor comes first
                j = creator[k]
                first = tris[j][0]
                # pln.md §9.17, kind 13: the later-named of the gate's corners i0, i1
                gate = max(first, tris[j][1]) if later else first
                pred = gate if parents[j] is not None and gate in is_explicit else previous
                sources[k] = pred
                base = [xyz[pred][a] if pred is not None else 0 for a in range(3)]
                if k in grams:
                    # pln.md §9.14: floor((S + floor(n/2)) / n), S the sum of
                    # g(a) + g(b) - g(c) over the n parallelograms; Python's //
                    # rounds toward -infinity, and its integers cannot wrap
                    # (every term was checked within 2^52 as it was resolved)
                    count = len(grams[k])
                    base = [(sum(xyz[a][axis] + xyz[b][axis] - xyz[far][axis] for a, b, far in grams[k])
                             + count // 2) // count for axis in range(3)]
                elif parallelogram and parents[j] is not None:
                    p, edge = parents[j]
                    second, opposite = tris[j][1], tris[p][(edge + 2) % 3]
                    if first in is_explicit and second in is_explicit and opposite in is_explicit:
                        base = [xyz[first][a] + xyz[second][a] - xyz[opposite][a] for a in range(3)]
                if reflect:
                    # pln.md §9.16: where the chain turns, instead of the
                    # prediction above (§9.13's, by bit 0 of the mode)
                    base = reflected_step(xyz, sources, k) or base
                xyz[k] = []
                for a in range(3):
                    value = residuals[a][r] + base[a]
                    if abs(residuals[a][r]) > SHELL_COORD_LIMIT or abs(value) > SHELL_COORD_LIMIT:
                        raise PlnError("BAD_GROUP_STRUCTURE",
                                       "explicit corner %d: residual %d to %s %d, beyond 2^52"
                                       % (k, residuals[a][r], "index" if tables else "coordinate", value))
                    if tables is not None and not 0 <= value < len(tables[a]):
                        raise PlnError("BAD_GROUP_STRUCTURE",
                                       "explicit corner %d: index %d outside the %s table of %d values"
                                       % (k, value, "xyz"[a], len(tables[a])))
                    xyz[k].append(value)
                previous = k
            if tables is not None:
                grid = [[tables[a][xyz[k][a]] for a in range(3)] for k in explicit]
            else:
                grid = [xyz[k] for k in explicit]
        elif c.remaining():
            raise PlnError("BAD_GROUP_STRUCTURE", "%d bytes after the corner picks" % c.remaining())
        vertex_planes = []
        for k, planes in named:
            if len(planes) == 3:
                vertex_planes.append(planes)
                continue
            i, jj, ll = picks[k]
            if not i < jj < ll < len(planes):
                raise PlnError("BAD_GROUP_STRUCTURE", "corner %d: picks %d %d %d of %d" % (k, i, jj, ll, len(planes)))
            vertex_planes.append([planes[i], planes[jj], planes[ll]])
        return {"explicit": explicit, "vertex_planes": vertex_planes, "grid": grid,
                "origin": origin, "step": step, "facets": [[f] + k for f, k in zip(faces, tris)]}

    # pln.md §9.13: the ordered lists of distinct free edges a symbol's c
    # numbers, by length, then lexicographically by the edges' places among
    # the triangle's free edges ((1, 2) attached, (0, 1, 2) a root)
    WALK_CHILDREN_ATTACHED = ((), (1,), (2,), (1, 2), (2, 1))
    WALK_CHILDREN_ROOT = ((), (0,), (1,), (2,), (0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1),
                          (0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0))

    def read_shell_walk(self, c, m, bounding, multi=False, reflect=False, later=False):
        """pln.md §9.13, kind 9: corner_count V, triangle_count T,
        escape_count X (read, then checked against the bytes left after the
        three); T symbols, X escapes, T face codes and the corner flags
        (padding checked as read); then the walk: a stack of slots (triangle,
        edge), a root where it is empty, otherwise a triangle attached to
        the popped slot's edge; its symbol says across which of its free
        edges it has children and, attached, how its third corner is coded
        (0 new, 1 left, 2 right, 3 + an escape a zigzag step from i1); a
        root's three corner codes are escapes.  Left and right name the
        other end of an open edge at i1 or i0 (see OpenEdges).  After the
        walk, the links it gives and everything after the escapes are those
        of §9.11 (read_shell_tree_rest), with a mode byte and per-axis value
        tables for the explicit corners.  Returned as a kind 7 group's
        "shell", its triangles in walk order.  pln.md §9.14, kind 10
        (``multi``): the same, but an explicit corner with parallelograms
        (see multi_parallelograms) is predicted by their rounded average.
        pln.md §9.16, kind 12 (``reflect``): the same, but an explicit
        corner whose chain turns is predicted by reflected_step.
        pln.md §9.17, kind 13 (``later``): the same, but an explicit corner
        named anew by an attached triangle steps from the later-named of its
        gate's corners, max(i0, i1), where that one is explicit."""
        v = c.varint("corner_count")
        t = c.varint("triangle_count")
        x = c.varint("escape_count")
        left = c.remaining()
        if not 3 <= v <= 8 * left:
            raise PlnError("BAD_GROUP_STRUCTURE", "corner_count %d, %d bytes left" % (v, left))
        if not 1 <= t <= left // 2:
            raise PlnError("BAD_GROUP_STRUCTURE", "triangle_count %d, %d bytes left" % (t, left))
        if x > left:
            raise PlnError("BAD_GROUP_STRUCTURE", "escape_count %d, %d bytes left" % (x, left))
        symbols = [c.varint("symbol %d" % j) for j in range(t)]
        escapes = [c.varint("escape %d" % k) for k in range(x)]
        face_codes = [c.varint("face code %d" % j) for j in range(t)]
        flags = c.take((v + 7) // 8, "corner flags")
        check_bit_padding(flags, v, "GRUP shell walk corner flags")

        escape_iter = iter(escapes)

        def next_escape(j):
            value = next(escape_iter, None)
            if value is None:
                raise PlnError("BAD_GROUP_STRUCTURE",
                               "triangle %d: the walk uses more than the %d escapes" % (j, x))
            return value

        stack = []
        edges = OpenEdges()
        tris, parents = [], []
        creator = {}
        n = 0
        for j, symbol in enumerate(symbols):
            if not stack:
                if symbol >= 16:
                    raise PlnError("BAD_GROUP_STRUCTURE", "root triangle %d: symbol %d" % (j, symbol))
                children = self.WALK_CHILDREN_ROOT[symbol]
                parents.append(None)
                corners = []
                for _ in range(3):
                    code = next_escape(j)
                    if code == 0:
                        creator[n] = j
                        corners.append(n)
                        n += 1
                    elif code > n:
                        raise PlnError("BAD_GROUP_STRUCTURE",
                                       "root triangle %d: corner code %d, %d corners named so far" % (j, code, n))
                    else:
                        corners.append(n - code)
            else:
                p, e = stack.pop()
                if symbol >= 4 * len(self.WALK_CHILDREN_ATTACHED):
                    raise PlnError("BAD_GROUP_STRUCTURE", "triangle %d: symbol %d" % (j, symbol))
                children = self.WALK_CHILDREN_ATTACHED[symbol >> 2]
                code = symbol & 3
                if code == 3:
                    code += next_escape(j)
                parents.append((p, e))
                q = tris[p]
                i0, i1, opposite = q[(e + 1) % 3], q[e], q[(e + 2) % 3]
                if code == 0:
                    creator[n] = j
                    third = n
                    n += 1
                elif code == 1:
                    third = edges.left(i1, opposite)
                    if third is None:
                        raise PlnError("BAD_GROUP_STRUCTURE",
                                       "triangle %d: a left code, no open edge ends at corner %d "
                                       "(other than from %d)" % (j, i1, opposite))
                elif code == 2:
                    third = edges.right(i0, opposite)
                    if third is None:
                        raise PlnError("BAD_GROUP_STRUCTURE",
                                       "triangle %d: a right code, no open edge starts at corner %d "
                                       "(other than to %d)" % (j, i0, opposite))
                else:
                    third = i1 + unzigzag(code - 3)
                    if not 0 <= third < n:
                        raise PlnError("BAD_GROUP_STRUCTURE",
                                       "triangle %d: third corner %d, %d corners named so far" % (j, third, n))
                corners = [i0, i1, third]
            if len(set(corners)) != 3:
                raise PlnError("BAD_GROUP_STRUCTURE", "triangle %d: corners %r" % (j, corners))
            tris.append(corners)
            edges.add_triangle(corners)
            for edge in children[::-1]:
                stack.append((j, edge))
        if stack:
            raise PlnError("BAD_GROUP_STRUCTURE", "%d slots on the stack after the last triangle" % len(stack))
        unused = sum(1 for _ in escape_iter)
        if unused:
            raise PlnError("BAD_GROUP_STRUCTURE", "%d escapes the walk does not use" % unused)
        if n != v:
            raise PlnError("BAD_GROUP_STRUCTURE", "%d corners named anew, corner_count %d" % (n, v))
        return self.read_shell_tree_rest(c, m, bounding, v, flags, face_codes, tris, parents, creator,
                                         walk=True, multi=multi, reflect=reflect, later=later)

    def check_tree(self, tokens, m):
        """§8.4: exactly one complete tree in preorder (tokens numbered as in §8.4)."""
        slots = 1
        for i, tok in enumerate(tokens):
            if slots <= 0:
                raise PlnError("BAD_GROUP_STRUCTURE", "token %d after a complete tree" % i)
            if tok < TOKEN_RESERVED_LO:
                if tok >= m:
                    raise PlnError("BAD_GROUP_STRUCTURE",
                                   "split on local reference %d of %d" % (tok, m))
                slots += 1
            elif tok in (TOKEN_IN, TOKEN_OUT):
                slots -= 1
            else:
                raise PlnError("BAD_GROUP_STRUCTURE", "reserved token 0x%08X" % tok)
        if slots != 0:
            raise PlnError("BAD_GROUP_STRUCTURE", "incomplete tree (%d open slots)" % slots)
        return tokens

    # -- §8.5 colours ------------------------------------------------------

    def read_colours(self, p):
        # pln.md §10.1, checks in its order: a payload that ends inside the
        # head or the colours (BAD_PAYLOAD); bytes after them, a group not
        # read yet, a count other than its ref_count (BAD_COLOURS)
        if self.major >= SEGMENT_MAJOR:
            # version 6: group and count are varint32s
            c = Cursor(p, "cOLR")
            group, count = c.varint32("group"), c.varint32("count")
            p = c.rest()
        else:
            if len(p) < 8:
                raise PlnError("BAD_PAYLOAD", "cOLR payload of %d bytes, under 8" % len(p))
            group, count = u32(p, 0), u32(p, 4)
            p = p[8:]
        # version 4: a payload of exactly 12 bytes (version 6: 4 bytes after
        # the head) is one colour for every reference, whatever the count; in
        # 1.0 to 3.4 (Appendix A) always count x 4 bytes, so 12 bytes with a
        # count above 1 end inside them
        one_colour = self.major >= 4 and len(p) == 4
        if not one_colour:
            if len(p) < 4 * count:
                raise PlnError("BAD_PAYLOAD", "cOLR: %d bytes after the head end inside %d colours"
                               % (len(p), count))
            if len(p) > 4 * count:
                raise PlnError("BAD_COLOURS", "%d bytes after the %d colours"
                               % (len(p) - 4 * count, count))
        if group >= len(self.groups):
            raise PlnError("BAD_COLOURS", "colours for group %d, %d defined" % (group, len(self.groups)))
        if count != self.group_refcounts[group]:
            raise PlnError("BAD_COLOURS", "%d colours for %d references"
                           % (count, self.group_refcounts[group]))
        if count == 0 and not one_colour:
            # pln.md §10.1: a group without references (§9.2, version 5) takes one colour
            raise PlnError("BAD_COLOURS", "a cOLR of count 0 without its one colour, for group %d" % group)
        if one_colour:
            # reported as the per-reference form would be (SPEC_NOTES 28); count 0: the one colour
            rgba = [list(p[0:4]) for _ in range(max(count, 1))]
        else:
            rgba = [list(p[4 * i:4 + 4 * i]) for i in range(count)]
        # pln.md §10.1: a later cOLR of a group replaces the one before; the
        # group is listed once, where its first cOLR was
        if group in self.colour_slot:
            self.colours[self.colour_slot[group]]["rgba"] = rgba
        else:
            self.colour_slot[group] = len(self.colours)
            self.colours.append({"group": group, "rgba": rgba})

    # -- pln.md §10.3 metadata ---------------------------------------------

    def read_metadata(self, p):
        if self.chunk_list:
            raise PlnError("BAD_METADATA", "mETA after an OBJT, PLNS or GRUP chunk")
        nul = p.find(b"\x00")
        if nul < 0:
            raise PlnError("BAD_METADATA", "mETA without a 0x00 after its keyword")
        keyword = p[:nul]
        if not 1 <= len(keyword) <= META_KEYWORD_MAX or any(c < 0x21 or c > 0x7E for c in keyword):
            raise PlnError("BAD_METADATA", "mETA keyword %r is not 1-79 printable ASCII bytes" % keyword)
        try:
            value = p[nul + 1:].decode("utf-8")
        except UnicodeDecodeError:
            raise PlnError("BAD_METADATA", "mETA value is not UTF-8")
        key = keyword.decode("ascii")
        if key == "up_axis" and self.major >= 5:
            # pln.md §10.3: a version 5 file says its up axis in the header (§5)
            raise PlnError("BAD_METADATA", "mETA up_axis in a version %d file" % self.major)
        if key in self.metadata:
            raise PlnError("BAD_METADATA", "a second mETA %s" % key)
        if key in META_VALUES and value not in META_VALUES[key]:
            raise PlnError("BAD_METADATA", "mETA %s = %r" % (key, value))
        self.metadata[key] = value

    # -- §8.6 index --------------------------------------------------------

    def read_index(self, p, offset):
        if self.index_offset is not None:
            raise PlnError("CHUNK_ORDER", "a second iNDX (§4.3)")
        if self.major >= SEGMENT_MAJOR:
            self.read_index_v6(p, offset)
            return
        if len(p) < 4:
            raise PlnError("BAD_PAYLOAD", "iNDX payload of %d bytes, under 4" % len(p))
        count = u32(p, 0)
        if len(p) != 4 + 16 * count:
            raise PlnError("BAD_INDEX", "iNDX count %d, payload of %d bytes" % (count, len(p)))
        entries = []
        for i in range(count):
            o = 4 + 16 * i
            entries.append((u64(p, o), bytes(p[o + 8:o + 12]), u32(p, o + 12)))
        prev = -1
        for i, (off, typ, _) in enumerate(entries):
            if off <= prev:
                raise PlnError("BAD_INDEX", "entry %d: offsets do not increase" % i)
            prev = off
            # pln-3 §8.6: "after the header" is at or after the chunk that follows PHDR
            if self.major >= 3 and off < self.after_header:
                raise PlnError("BAD_INDEX", "entry %d: offset %d before %d, the end of the header"
                               % (i, off, self.after_header))
            if off >= offset:
                raise PlnError("BAD_INDEX", "entry %d: offset %d not before the index" % (i, off))
        if len(entries) != len(self.chunk_list):
            raise PlnError("BAD_INDEX", "%d entries for %d OBJT/PLNS/GRUP chunks"
                           % (len(entries), len(self.chunk_list)))
        for i, (e, actual) in enumerate(zip(entries, self.chunk_list)):
            if e != actual:
                raise PlnError("BAD_INDEX", "entry %d is %r, the chunk is %r" % (i, e, actual))
        self.index_offset = offset
        self.last_was_index = True

    def read_index_v6(self, p, offset):
        """Version 6: count (varint), then per record of tag 1, 2 or 3 in
        file order: chunk_offset (varint, the offset of the PHDR or BODY
        chunk whose segment holds the record, as a difference from the
        previous entry's, the first from 0), raw_offset (varint, the
        record's offset in that segment's raw bytes), tag (u8), ordinal
        (varint).  A payload that ends inside them, or a bad varint:
        BAD_PAYLOAD; bytes after them, or any entry other than the record
        this reader read there: BAD_INDEX."""
        c = Cursor(p, "iNDX")
        count = c.varint("count")
        # each entry takes at least 4 bytes: a count the payload cannot hold is not allocated for
        if count > c.remaining() // 4:
            raise PlnError("BAD_PAYLOAD", "iNDX count %d, %d bytes of entries" % (count, c.remaining()))
        entries = []
        chunk_offset = 0
        for i in range(count):
            chunk_offset += c.varint("entry %d chunk_offset" % i)
            raw_offset = c.varint("entry %d raw_offset" % i)
            tag = c.u8("entry %d tag" % i)
            ordinal = c.varint("entry %d ordinal" % i)
            entries.append((chunk_offset, raw_offset, tag, ordinal))
        if c.remaining():
            raise PlnError("BAD_INDEX", "%d bytes after the %d iNDX entries" % (c.remaining(), count))
        if len(entries) != len(self.chunk_list):
            raise PlnError("BAD_INDEX", "%d entries for %d object, planes and group records"
                           % (len(entries), len(self.chunk_list)))
        for i, (e, actual) in enumerate(zip(entries, self.chunk_list)):
            if e != actual:
                raise PlnError("BAD_INDEX", "entry %d is %r, the record is %r" % (i, e, actual))
        self.index_offset = offset
        self.last_was_index = True

    # -- §4.4 end ----------------------------------------------------------

    def read_end(self, p):
        if self.major >= 3:
            self.read_end_v3(p)
        else:
            if len(p) != PEND_PAYLOAD_V1:
                raise PlnError("BAD_PAYLOAD", "PEND payload of %d bytes, not 8" % len(p))
            index_offset = u64(p, 0)
            if index_offset != 0 and index_offset != self.index_offset:
                raise PlnError("BAD_INDEX", "PEND index_offset %d, iNDX at %r"
                               % (index_offset, self.index_offset))
        if self.flags & FLAG_COUNTS_KNOWN:
            actual = (len(self.planes), len(self.objects), len(self.groups))
            if actual != self.counts:
                raise PlnError("COUNT_MISMATCH", "header counts %r, file %r" % (self.counts, actual))

    def read_end_v3(self, p):
        """pln-3 §4.4: an empty payload (no index) or the u64 offset of the
        iNDX chunk, never 0; any other length is BAD_PAYLOAD."""
        if len(p) not in PEND_PAYLOADS_V3:
            raise PlnError("BAD_PAYLOAD", "PEND payload of %d bytes, not 0 or 8" % len(p))
        if not p:
            # like index_offset 0 in versions 1 and 2, an empty PEND is not
            # checked against an iNDX the file may hold (pln-3 §4.4 names no code)
            return
        index_offset = u64(p, 0)
        if index_offset == 0:
            raise PlnError("BAD_INDEX", "PEND index_offset 0 (pln-3 §4.4: an empty PEND says no index)")
        if index_offset != self.index_offset:
            raise PlnError("BAD_INDEX", "PEND index_offset %d, iNDX at %r"
                           % (index_offset, self.index_offset))

    # -- output ------------------------------------------------------------

    def result(self):
        return {
            "header": self.header,
            "planes": self.planes,
            "objects": self.objects,
            "groups": self.groups,
            "colours": self.colours,
            "metadata": self.metadata,
            "findings": self.findings,
            "geometry": None,
        }


def main(argv):
    if len(argv) != 2:
        sys.stderr.write("usage: plnread.py FILE.pln\n")
        return 2
    path = argv[1]
    try:
        f = open(path, "rb")
    except OSError as e:
        sys.stderr.write("plnread: %s\n" % e)
        return 2
    with f:
        try:
            st = os.fstat(f.fileno())
            import stat as _stat
            size = st.st_size if _stat.S_ISREG(st.st_mode) else None
        except OSError:
            size = None
        reader = Reader(f, size)
        try:
            reader.read()
        except PlnError as e:
            where = ""
            if e.chunk is not None:
                where += " in %s" % e.chunk
            if e.offset is not None:
                where += " at offset %d" % e.offset
            sys.stderr.write("%s: %s%s: %s\n" % (path, e.code, where, e.message))
            sys.stdout.write(json.dumps({"error": e.code}) + "\n")
            return 1
    sys.stdout.write(json.dumps(reader.result(), allow_nan=False) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
