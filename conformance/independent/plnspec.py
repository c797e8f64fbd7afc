#!/usr/bin/env python3
"""A container-level reader of .pln files (versions 1.0, 2.0, 3.0 to 3.4, 4.0 to 4.2, 5.0 to 5.2, 6.0), written from
spec/pln.md alone (no planefmt, no construct, none of the other readers or spec documents).

    python conformance/independent/plnspec.py FILE

prints one JSON object in the form of conformance/README.md ("The contract"): the file's
header, plane table, objects, part-group records, colours, metadata and findings, and exits 0; or
prints {"error": "CODE"} and exits 1. It does not decode geometry ("geometry": null).

Version 4.0 (§6 compression method 2, Brotli; §8 transforms coded entry by entry; §10.1 a cOLR
of one colour for every reference) was added from the 4.0 text of those sections and of §13 and
Appendix A. Its Brotli payloads need the PyPI package `brotli` (1.2 or later bounds the output
per call; with 1.1 the stored bytes are fed one at a time); it is imported only when a method 2 payload is met, so files of versions 1.0
to 3.4, and 4.0 files without Brotli payloads, are read without it.

Version 4.1 (§9.13, kind 9, shell walks) was added from the 4.1 text of §9.13 and of the sections
it builds on (§9.11, §9.12, §9.3, §5, §13), before any 4.1 golden file existed: the walk keeps
its open edges in a map from each directed edge to the stack of its entries and, per corner,
doubly linked lists of the entries starting and ending there, newest first (OpenEdges), so that
each triangle takes constant time; what follows the escapes is read by the code of §9.11
(shell_tree_rest), with §9.13's mode byte and value tables.

Version 4.2 (§9.14, kind 10, shell walks with multi-parallelograms) was added from the 4.2 text of
§9.14 and of §9.3, §5 and §13, before any 4.2 golden file existed: kind 9's walk and everything
after it, with one rule changed, the prediction of an explicit corner (the rounded average of up to
four parallelograms over the triangles around it, from a map of each directed edge to the first
triangle that has it; kind 9's prediction where there is none).

Version 4.2's kind 11 (§9.15, copies) was added from the text of §9.15 and §9.3: one varint, the
source group's index, checked in §9.15's order (the varint and nothing after it; an earlier source,
not a copy; a skipped source skips the copy; the same references and role bits), and listed as
stored with "source" (conformance/README.md, the groups row).

Version 5.0 was added from the 5.0 text of §4.1, §4.4, §5, §9.2, §9.10-§9.14, §10.1, §10.3, §12, §13
and Appendix A.5: every chunk after the first framed with a varint32 length (varint_head; the first,
PHDR, keeps its u32), the header's 8-byte fixed part with the up axis in bits 4-5 of units, reported
as the metadata "up_axis" (as the 5.0 goldens expect) and an mETA up_axis rejected, groups without
references in kinds 6 to 11 (and in skipped kinds), a cOLR of count 0 holding one colour (without it rejected), and shell grids of
four f32 (grid). Versions 1.0 to 4.2 are read as before (A.5).

Version 5.1 (§9.16, kind 12, shell walks with reflections) was added from the 5.1 text of §9.16 and of
§9.2, §9.3, §11, §13 and Appendix A.4, before any 5.1 golden file existed: kind 9's walk and everything
after it, with one rule changed, the prediction of an explicit corner whose chain of step sources
(§9.11's predictors, k <- a <- b <- c) turns: the step b - c reflected in the line of the step a - b,
added to a, in exact integers (reflection); §9.13's prediction where there is no chain or it does not
turn. Kind 12 is a kind of 5.1 and later minors of major 5 (UNKNOWN_GROUP_KIND in 5.0, skipped in
major 3 and 4 files of a newer minor) and may have no references.

Version 5.2 (§9.17, kind 13, shell walks stepping from the later gate corner) was added from the 5.2 text
of §9.17 and of §9.11, §9.13, §9.2, §9.3, §5, §11, §13 and Appendix A.4: kind 9's walk and everything after
it, with one rule changed, §9.11's predictor of an explicit corner: max(i0, i1), the gate corner named
later, of the attached triangle whose code names it anew, where that corner is explicit (else, as before,
the previous explicit corner); mode bit 0's parallelogram is kind 9's. Kind 13 is a kind of 5.2 and later
minors of major 5 (UNKNOWN_GROUP_KIND in 5.0 and 5.1, skipped in major 3 and 4 files of a newer minor) and
may have no references.

Version 6.0 was added from the 6.0 text of §2.2 (r32), §4.2-§4.6 (BODY chunks, body segments and
records), §5 (the compact header: header_size, the coding in flags, r32 values), §7.1, §8, §9.1,
§10.1-§10.2 and §12.1: the records of every segment (the PHDR payload after the header fields, and
each BODY chunk) are read by the parsers of the chunks they replace, without the fields version 6
drops; such a chunk in a version 6 file is CHUNK_ORDER. Versions 1.0 to 5.2 are read as before.

Section numbers (§) are those of spec/pln.md. Where the spec left a choice to this reader, the
comment says "SPEC_NOTES n", the item of conformance/independent/SPEC_NOTES.md that records it.
"""

from __future__ import annotations

import json
import math
import struct
import sys
import zlib

import numpy as np

SIGNATURE = b"\x89PLN\r\n\x1a\n"

# §12.4: this reader's limits (the same values as the defaults the spec quotes).
CHUNK_LIMIT = 256 * 1024 * 1024
PAYLOAD_LIMIT = 256 * 1024 * 1024
RATIO_LIMIT = 1100
PLANE_LIMIT = 1 << 22
REF_LIMIT = 1 << 24
OBJECT_LIMIT = 1 << 24

KNOWN_CHUNKS = {b"PHDR", b"OBJT", b"PLNS", b"GRUP", b"cOLR", b"mETA", b"iNDX", b"PEND"}
# §10.3: the values of the keywords the spec defines
META_VALUES = {"up_axis": ("Y", "Z")}
NEWEST_MINOR = {1: 0, 2: 0, 3: 4, 4: 2, 5: 2, 6: 0}  # §9.3: "for this document: 1.0, 2.0, 3.4, 4.2, 5.2" (SPEC_NOTES 62, 66)
UP_AXES = {1: "Y", 2: "Z"}
# §4.2, §4.6: version 6's records, which replace the chunks of versions 1 to 5 (such a chunk in a
# version 6 file is CHUNK_ORDER), by tag; tags 128-255 are ancillary
RECORD_TYPES = {1: b"OBJT", 2: b"PLNS", 3: b"GRUP", 4: b"cOLR", 5: b"mETA"}  # §5, version 5: bits 4-5 of units (0 not said, 3 BAD_HEADER_VALUE)

# §7.2: the f32 and f64 values nearest to pi and 2 pi.
PI_F32 = np.frombuffer(struct.pack("<I", 0x40490FDB), "<f4")[0]
TWO_PI_F32 = np.frombuffer(struct.pack("<I", 0x40C90FDB), "<f4")[0]
PI_F64 = struct.unpack("<d", struct.pack("<Q", 0x400921FB54442D18))[0]
TWO_PI_F64 = struct.unpack("<d", struct.pack("<Q", 0x401921FB54442D18))[0]

V1_IN, V1_OUT = 0xFFFFFFFE, 0xFFFFFFFF  # README: tree tokens in the numbering of version 1.0


class PlnError(Exception):
    def __init__(self, code: str, why: str = ""):
        super().__init__(f"{code}: {why}" if why else code)
        self.code = code


def fail(code: str, why: str = ""):
    raise PlnError(code, why)


# ---------------------------------------------------------------------------------------------
# §2: a cursor over a payload or body; running off its end is BAD_PAYLOAD.

class Cursor:
    def __init__(self, buf: bytes, pos: int = 0, end: int | None = None):
        self.buf = buf
        self.pos = pos
        self.end = len(buf) if end is None else end

    def left(self) -> int:
        return self.end - self.pos

    def take(self, n: int, what: str = "field") -> bytes:
        if n < 0 or n > self.end - self.pos:
            fail("BAD_PAYLOAD", f"ends inside {what}")
        out = self.buf[self.pos:self.pos + n]
        self.pos += n
        return out

    def unpack(self, fmt: str, what: str = "field"):
        size = struct.calcsize(fmt)
        return struct.unpack(fmt, self.take(size, what))

    def u8(self, what="u8") -> int:
        return self.unpack("<B", what)[0]

    def u16(self, what="u16") -> int:
        return self.unpack("<H", what)[0]

    def u32(self, what="u32") -> int:
        return self.unpack("<I", what)[0]

    def u64(self, what="u64") -> int:
        return self.unpack("<Q", what)[0]

    def f32(self, what="f32") -> float:
        return self.unpack("<f", what)[0]

    def f64(self, what="f64") -> float:
        return self.unpack("<d", what)[0]

    def varint(self, what="varint") -> int:
        """§2.2: unsigned LEB128, minimal, at most 10 bytes, a tenth byte at most 0x01."""
        value = 0
        for i in range(10):
            if self.pos >= self.end:
                fail("BAD_PAYLOAD", f"ends inside {what}")
            b = self.buf[self.pos]
            self.pos += 1
            value |= (b & 0x7F) << (7 * i)
            if not b & 0x80:
                if i > 0 and b == 0:
                    fail("BAD_PAYLOAD", f"{what} not minimal")
                if i == 9 and b > 1:
                    fail("BAD_PAYLOAD", f"{what} of 2^64 or more")
                return value
        fail("BAD_PAYLOAD", f"{what} longer than 10 bytes")

    def varint32(self, what="varint32") -> int:
        value = self.varint(what)
        if value >= 1 << 32:
            fail("BAD_PAYLOAD", f"{what} of 2^32 or more")
        return value

    def varints(self, n: int, what: str) -> list[int]:
        return [self.varint(what) for _ in range(n)]


def r32(c: Cursor, what: str) -> float:
    """§2.2: a varint32 whose 32 bits, reversed, are a binary32 value (widened exactly)."""
    v = c.varint32(what)
    return struct.unpack("<f", struct.pack("<I", int(f"{v:032b}"[::-1], 2)))[0]


def unzigzag(z: int) -> int:
    return z >> 1 if not z & 1 else -((z + 1) >> 1)


def bit_string(data: bytes, nbits: int, what: str) -> list[int]:
    """§2.1: bits least significant first; a set padding bit is BAD_PAYLOAD."""
    bits = [(data[k >> 3] >> (k & 7)) & 1 for k in range(len(data) * 8)]
    if any(bits[nbits:]):
        fail("BAD_PAYLOAD", f"a set padding bit in {what}")
    return bits[:nbits]


def none_if_nan(x: float):
    return None if math.isnan(x) else x


# ---------------------------------------------------------------------------------------------
# §9.13: the open edges of a shell walk

class OpenEdges:
    """The list of open directed edges (a, b) of §9.13, in order of entry, kept so that each
    triangle takes constant time: a map from each directed edge to the stack of its entries, and
    per corner two doubly linked lists of the entries starting and ending there, newest first.
    Entries are numbered in order of entry; a closed entry is unlinked and never reused."""

    def __init__(self):
        self.by_edge: dict[tuple[int, int], list[int]] = {}  # (a, b) -> its entries, newest last
        self.start: list[int] = []
        self.end: list[int] = []
        # the list of entries starting at a corner (out) and ending at it (in): next is older
        self.out_next: list[int] = []
        self.out_prev: list[int] = []
        self.in_next: list[int] = []
        self.in_prev: list[int] = []
        self.out_head: dict[int, int] = {}  # corner -> its newest entry starting there
        self.in_head: dict[int, int] = {}  # corner -> its newest entry ending there

    def toggle(self, a: int, b: int):
        """Edge (a, b) of a triangle: the newest entry (b, a) leaves the list where there is one
        (the edge is closed), otherwise (a, b) enters it as the newest entry."""
        reverse = self.by_edge.get((b, a))
        if reverse:
            self.unlink(reverse.pop())
            if not reverse:
                del self.by_edge[(b, a)]
            return
        k = len(self.start)
        self.start.append(a)
        self.end.append(b)
        self.by_edge.setdefault((a, b), []).append(k)
        old = self.out_head.get(a, -1)
        self.out_next.append(old)
        self.out_prev.append(-1)
        if old >= 0:
            self.out_prev[old] = k
        self.out_head[a] = k
        old = self.in_head.get(b, -1)
        self.in_next.append(old)
        self.in_prev.append(-1)
        if old >= 0:
            self.in_prev[old] = k
        self.in_head[b] = k

    def unlink(self, k: int):
        a, b = self.start[k], self.end[k]
        nxt, prv = self.out_next[k], self.out_prev[k]
        if prv >= 0:
            self.out_next[prv] = nxt
        else:
            self.out_head[a] = nxt
        if nxt >= 0:
            self.out_prev[nxt] = prv
        nxt, prv = self.in_next[k], self.in_prev[k]
        if prv >= 0:
            self.in_next[prv] = nxt
        else:
            self.in_head[b] = nxt
        if nxt >= 0:
            self.in_prev[nxt] = prv

    def starts_ending_at(self, c: int) -> list[int]:
        """The starts of the newest and the second newest open edges that end at c (fewer where
        there are fewer)."""
        out, k = [], self.in_head.get(c, -1)
        while k >= 0 and len(out) < 2:
            out.append(self.start[k])
            k = self.in_next[k]
        return out

    def ends_starting_at(self, c: int) -> list[int]:
        """The ends of the newest and the second newest open edges that start at c."""
        out, k = [], self.out_head.get(c, -1)
        while k >= 0 and len(out) < 2:
            out.append(self.end[k])
            k = self.out_next[k]
        return out


# ---------------------------------------------------------------------------------------------
# §6: compression

def decompress(method: int, raw_size: int, stored: bytes, major: int) -> bytes:
    # step 1: method 2 exists in version 4 only (Appendix A: BAD_COMPRESSION in 1.0 to 3.4)
    if method not in ((0, 1, 2) if major >= 4 else (0, 1)):
        fail("BAD_COMPRESSION", f"method {method} in a version {major} file")
    if raw_size > PAYLOAD_LIMIT:
        fail("LIMIT_EXCEEDED", f"raw size {raw_size}")
    if method == 0:
        if len(stored) != raw_size:
            fail("SIZE_MISMATCH", f"stored {len(stored)} bytes, raw size {raw_size}")
        return stored
    if raw_size > RATIO_LIMIT * len(stored):  # step 4, methods 1 and 2
        fail("LIMIT_EXCEEDED", f"raw size {raw_size} from {len(stored)} stored bytes")
    if method == 2:
        return brotli_decompress(raw_size, stored)
    inflater = zlib.decompressobj()
    try:
        out = inflater.decompress(stored, raw_size + 1)  # never more than raw size + 1 bytes
    except zlib.error as exc:
        fail("BAD_COMPRESSION", str(exc))
    if len(out) > raw_size:
        fail("SIZE_MISMATCH", "inflates to more than raw size")
    if not inflater.eof:
        fail("SIZE_MISMATCH", "the stored bytes end inside the zlib stream")
    if inflater.unused_data:
        fail("SIZE_MISMATCH", "stored bytes after the zlib stream")
    if len(out) != raw_size:
        fail("SIZE_MISMATCH", f"inflates to {len(out)} bytes, raw size {raw_size}")
    return out


BROTLI_PIECE = 1 << 16  # stored bytes handed to the Brotli decoder at a time


def brotli_decompress(raw_size: int, stored: bytes) -> bytes:
    """§6 step 6, method 2: one Brotli stream (RFC 7932) of exactly raw size bytes ending with the
    last stored byte. An invalid stream, and stored bytes after the stream's end, are
    BAD_COMPRESSION; an output other than raw size bytes, or a stream the stored bytes end inside,
    SIZE_MISMATCH. The stored bytes are handed over in pieces and the output drained in blocks of
    at most about 32 KiB (output_buffer_limit=1: the binding stops growing its buffer after one
    block), and decoding stops as soon as the output passes raw size, so this reader holds at
    most raw size + 32 KiB (§6: at most raw size + 16 MiB; SPEC_NOTES 25)."""
    try:
        import brotli
    except ImportError:
        raise SystemExit("plnspec.py: compression method 2 (Brotli) needs the package 'brotli'")
    d = brotli.Decompressor()
    # brotli 1.1 has no output bound: there the stored bytes go one at a time, and one byte
    # yields at most about one meta-block, 16 MiB (§6)
    bounded = hasattr(d, "can_accept_more_data")
    piece = BROTLI_PIECE if bounded else 1
    out = bytearray()
    pos = 0
    while not d.is_finished():
        if (not bounded or d.can_accept_more_data()) and pos < len(stored):
            data = stored[pos:pos + piece]
            pos += len(data)
        else:
            data = b""  # output still held back by the block bound, or the input is all given
        try:
            block = d.process(data, output_buffer_limit=1) if bounded else d.process(data)
        except brotli.error:  # the binding also reports bytes after the stream's end so
            fail("BAD_COMPRESSION", "invalid Brotli stream, or bytes after its end")
        out += block
        if len(out) > raw_size:
            fail("SIZE_MISMATCH", "decompresses to more than raw size")
        if not data and not block and not d.is_finished():
            if pos == len(stored):
                fail("SIZE_MISMATCH", "the stored bytes end inside the Brotli stream")
            if bounded and not d.can_accept_more_data():
                raise RuntimeError("the Brotli decoder neither gives output nor takes input")
    if pos < len(stored):  # the stream ended at the end of a piece, and more pieces follow
        fail("BAD_COMPRESSION", f"{len(stored) - pos} stored bytes after the Brotli stream")
    if len(out) != raw_size:
        fail("SIZE_MISMATCH", f"decompresses to {len(out)} bytes, raw size {raw_size}")
    return bytes(out)


# ---------------------------------------------------------------------------------------------

class Reader:
    def __init__(self, data: bytes):
        self.data = data
        self.findings: list[str] = []
        self.header: dict | None = None
        self.major = self.minor = 0
        self.coding = 0
        self.bits = (0, 0, 0)
        self.h_range = (0.0, 0.0)
        self.counts: dict | None = None
        self.phdr_length = 0
        self.rest = b""  # version 6: the PHDR payload after the header fields, the first body segment
        self.planes: list[list[float]] = []
        self.objects: list[dict] = []
        self.groups: list[dict] = []
        self.group_refs: list[int] = []  # ref_count of every group read, skipped ones included
        self.group_roles: list[list[int]] = []  # role bits of every group read (§9.15 compares them)
        self.group_skipped: list[bool] = []  # whether its kind data was skipped (§9.3, §9.15 step 3)
        self.colours: list[dict] = []
        self.metadata: dict[str, str] = {}
        self.chunks: list[tuple[int, bytes, int]] = []  # (offset, type, ordinal) of OBJT/PLNS/GRUP
        self.index_offset: int | None = None

    def finding(self, code: str):
        if code not in self.findings:
            self.findings.append(code)

    # §3
    def signature(self):
        d = self.data
        if len(d) < 8 and SIGNATURE.startswith(d):
            fail("TRUNCATED", "inside the signature")
        if d[:8] == SIGNATURE:
            return
        if d[1:4] == b"PLN" and d[0] in (0x89, 0x09):  # SPEC_NOTES 1: §3's rule, literally
            fail("TEXT_MODE_DAMAGE")
        fail("BAD_SIGNATURE")

    # §4
    def read(self) -> dict:
        self.signature()
        d = self.data
        pos = 8
        after_index = False
        while True:
            offset = pos
            # §4.1 framing: the first chunk (PHDR) with a u32 length in every version; every later
            # chunk of a version 5 file with a varint32 length (by place, not by type: SPEC_NOTES 52)
            if self.header is not None and self.major >= 5:
                ctype, length, head = self.varint_head(pos)
            else:
                if len(d) - pos < 8:
                    fail("TRUNCATED", "no PEND" if pos == len(d) else "inside a chunk head")
                ctype = d[pos:pos + 4]
                self.check_type(ctype)
                length = struct.unpack_from("<I", d, pos + 4)[0]
                head = 8
                if length > 0x7FFFFFFF:
                    fail("CHUNK_TOO_LONG", str(length))
            if length > CHUNK_LIMIT:
                fail("LIMIT_EXCEEDED", f"chunk length {length}")
            if len(d) - pos - head < length + 4:
                fail("TRUNCATED", f"inside {ctype!r}")
            payload = d[pos + head:pos + head + length]
            crc = struct.unpack_from("<I", d, pos + head + length)[0]
            if zlib.crc32(ctype + payload) != crc:
                fail("CRC_MISMATCH", repr(ctype))
            pos += head + length + 4
            # §4.3 place, in the order of §12.1 item 3.2
            if self.header is None and ctype != b"PHDR":  # SPEC_NOTES 2: ancillary ones too
                fail("MISSING_HEADER", repr(ctype))
            if after_index and ctype != b"PEND":
                fail("CHUNK_ORDER", f"{ctype!r} after iNDX")
            v6 = self.header is not None and self.major >= 6
            if v6 and ctype in RECORD_TYPES.values():
                fail("CHUNK_ORDER", f"{ctype!r}: a record of a body segment in version 6")
            if ctype == b"PHDR" and self.header is not None:
                fail("DUPLICATE_HEADER")
            if (ctype not in KNOWN_CHUNKS and not (v6 and ctype == b"BODY")) and not ctype[0] & 0x20:
                fail("UNKNOWN_CRITICAL_CHUNK", repr(ctype))
            # payload
            if ctype == b"PHDR":
                self.phdr(payload)
                self.phdr_length = length
                if self.major >= 6 and self.rest:
                    self.segment(self.rest, offset)
            elif ctype == b"BODY":
                self.segment(payload, offset)
            elif ctype == b"OBJT":
                self.objt(payload, (offset, b"OBJT"))
            elif ctype == b"PLNS":
                self.plns(payload, (offset, b"PLNS"))
            elif ctype == b"GRUP":
                self.grup(payload, (offset, b"GRUP"))
            elif ctype == b"cOLR":
                self.colr(payload)
            elif ctype == b"mETA":
                self.meta(payload)
            elif ctype == b"iNDX":
                self.indx(payload, offset)
                self.index_offset = offset
                after_index = True
            elif ctype == b"PEND":
                self.pend(payload)
                if pos != len(d):
                    fail("TRAILING_DATA", f"{len(d) - pos} bytes after PEND")
                return self.result()
            else:
                self.finding("UNKNOWN_ANCILLARY_CHUNK")

    @staticmethod
    def check_type(ctype: bytes):
        if not all(0x41 <= b <= 0x5A or 0x61 <= b <= 0x7A for b in ctype):
            fail("BAD_CHUNK_TYPE", repr(ctype))

    def varint_head(self, pos: int) -> tuple[bytes, int, int]:
        """§4.1, version 5: the type, then the length as a varint32 of at most 5 bytes. Steps 1-3:
        the input ending inside the type (TRUNCATED), the type (BAD_CHUNK_TYPE), the input ending
        inside the varint (TRUNCATED), then the varint: not minimal, BAD_CHUNK_LENGTH; a fifth byte
        with bit 7 set, or a length above 2^31 - 1, CHUNK_TOO_LONG (not §2.2's BAD_PAYLOAD:
        SPEC_NOTES 53). Returns the type, the length and the head's size (4 + the varint's)."""
        d = self.data
        if len(d) - pos < 4:
            fail("TRUNCATED", "no PEND" if pos == len(d) else "inside a chunk type")
        ctype = d[pos:pos + 4]
        self.check_type(ctype)
        length = 0
        for i in range(5):
            at = pos + 4 + i
            if at >= len(d):
                fail("TRUNCATED", f"inside the length of {ctype!r}")
            b = d[at]
            length |= (b & 0x7F) << (7 * i)
            if not b & 0x80:
                if i > 0 and b == 0:
                    fail("BAD_CHUNK_LENGTH", f"the length of {ctype!r} not minimal")
                if length > 0x7FFFFFFF:
                    fail("CHUNK_TOO_LONG", str(length))
                return ctype, length, 5 + i
        fail("CHUNK_TOO_LONG", f"the length of {ctype!r} longer than 5 bytes")

    # §5 and A.1
    def phdr(self, p: bytes):
        if len(p) < 2:
            fail("BAD_PAYLOAD", "PHDR under 2 bytes")
        major, minor = p[0], p[1]
        if major not in (1, 2, 3, 4, 5, 6):
            fail("UNSUPPORTED_VERSION", f"{major}.{minor}")
        self.major, self.minor = major, minor
        if major >= 6:
            self.phdr_v6(p)
        elif major >= 5:
            self.phdr_v5(p)
        elif major >= 3:  # A.5 (4) and A.3 (3): the same layout
            self.phdr_v3(p)
        else:
            self.phdr_v1(p)
        if minor > NEWEST_MINOR[major]:
            self.finding("NEWER_MINOR_VERSION")

    def phdr_v6(self, p: bytes):
        """§5, version 6: header_size, then within it flags (the coding in bits 3-4), units, the
        widths (u16, each less one in 5 bits) and h range (two r32) of codings 2 and 3, the bbox
        (six r32) with BBOX_KNOWN, tolerance and error bound (r32), the counts with COUNTS_KNOWN;
        what header_size holds past them is skipped, and the payload after it is the first body
        segment (self.rest), read after the header's checks (§5 step 9)."""
        c = Cursor(p, 2)
        size = c.varint32("header_size")
        if size > c.left():
            fail("BAD_PAYLOAD", f"header_size {size}, {c.left()} bytes after it")
        h = Cursor(p, c.pos, c.pos + size)  # the header fields: reading past them is BAD_PAYLOAD
        self.rest = p[c.pos + size:]
        flags = h.u8("flags")
        units = h.u8("units")
        coding = flags >> 3 & 3
        bits, h_range = (0, 0, 0), None
        if coding >= 2:
            widths = h.u16("widths")
            bits = tuple((widths >> shift & 31) + 1 for shift in (0, 5, 10))
            h_range = (r32(h, "h_min"), r32(h, "h_max"))
        bbox = [r32(h, "bbox") for _ in range(6)] if flags & 4 else None
        tolerance = r32(h, "tolerance")
        error_bound = r32(h, "error_bound")
        counts = None
        if flags & 2:
            counts = {"planes": h.varint("plane_count"), "objects": h.varint32("object_count"),
                      "groups": h.varint32("group_count")}
        self.header_checks(flags, coding, bits, units, h_range, bbox, tolerance, error_bound, counts)

    # §4.5, §4.6 (version 6)
    def segment(self, p: bytes, offset: int):
        """A body segment: compression, raw size, the data (§6, its checks and limits); its raw
        bytes whole records, each tag, length (at most the bytes left), payload, read by the
        section of its tag. Ancillary tags (128-255) are skipped; others unknown, critical."""
        c = Cursor(p)
        method = c.u8("the segment's compression")
        raw_size = c.varint32("the segment's raw size")
        raw = decompress(method, raw_size, p[c.pos:], self.major)
        r = Cursor(raw)
        while r.left():
            at = r.pos
            tag = r.u8("a record's tag")
            length = r.varint32("a record's length")
            if length > r.left():
                fail("BAD_PAYLOAD", f"record at {at} of {length} bytes, {r.left()} left in the segment")
            payload = r.take(length)
            kind = RECORD_TYPES.get(tag)
            if kind is None:
                if tag < 128:
                    fail("UNKNOWN_CRITICAL_CHUNK", f"record tag {tag} at {at}")
                self.finding("UNKNOWN_ANCILLARY_CHUNK")
            elif kind == b"OBJT":
                self.objt(payload, (offset, at, tag))
            elif kind == b"PLNS":
                self.plns(payload, (offset, at, tag))
            elif kind == b"GRUP":
                self.grup(payload, (offset, at, tag))
            elif kind == b"cOLR":
                self.colr(payload)
            else:
                self.meta(payload)

    def phdr_v5(self, p: bytes):
        """§5, version 5: an 8-byte fixed part, flags a u8, the up axis in bits 4-5 of units."""
        if len(p) < 8:
            fail("BAD_PAYLOAD", "PHDR under 8 bytes")
        c = Cursor(p, 2)
        flags = c.u8()
        self.phdr_rest(c, flags)

    def phdr_v3(self, p: bytes):
        """A.5 (and A.3): a 9-byte fixed part, flags a u16, units the unit alone."""
        if len(p) < 9:
            fail("BAD_PAYLOAD", "PHDR under 9 bytes")
        c = Cursor(p, 2)
        flags = c.u16()
        self.phdr_rest(c, flags)

    def phdr_rest(self, c: Cursor, flags: int):
        """§5 from coding on, the same in versions 3 to 5 but for the units byte."""
        coding = c.u8()
        if coding > 3:
            fail("UNSUPPORTED_CODING", str(coding))
        bits = tuple(c.take(3))
        units = c.u8()
        h_range = (c.f64("h_min"), c.f64("h_max")) if coding >= 2 else None
        bbox = [c.f32("bbox") for _ in range(6)] if flags & 4 else None
        tolerance = c.f32("tolerance")
        error_bound = c.f32("error_bound")
        counts = None
        if flags & 2:
            counts = {"planes": c.varint("plane_count"), "objects": c.varint32("object_count"),
                      "groups": c.varint32("group_count")}
        self.header_checks(flags, coding, bits, units, h_range, bbox, tolerance, error_bound, counts)

    def phdr_v1(self, p: bytes):
        # A.1: at least 108 bytes, after the version check; the coding check (SPEC_NOTES 4: after
        # the length, as in §5 steps 3-4), then §5 steps 6-9.
        if len(p) < 108:
            fail("BAD_PAYLOAD", "version 1/2 PHDR under 108 bytes")
        c = Cursor(p, 2)
        flags = c.u16()
        coding = c.u8()
        if coding > (2 if self.major == 1 else 3):  # A.2: version 2 adds coding 3
            fail("UNSUPPORTED_CODING", str(coding))
        bits = tuple(c.take(3))
        units = c.u8()
        c.take(3)  # reserved
        h_range = (c.f64(), c.f64())
        bbox = [c.f64() for _ in range(6)]
        tolerance, error_bound = c.f64(), c.f64()
        plane_count = c.u64()
        object_count, group_count = c.u32(), c.u32()
        counts = {"planes": plane_count, "objects": object_count, "groups": group_count} \
            if flags & 2 else None
        self.header_checks(flags, coding, bits, units, h_range if coding >= 2 else None,
                           bbox if flags & 4 else None, tolerance, error_bound, counts)

    def header_checks(self, flags, coding, bits, units, h_range, bbox, tolerance, error_bound, counts):
        up_axis = 0
        if self.major >= 5:  # §5: bits 0-3 the unit, bits 4-5 the up axis, bits 6-7 ignored
            units, up_axis = units & 0x0F, (units >> 4) & 3
        if coding >= 2:
            if any(not 1 <= b <= 32 for b in bits):
                fail("UNSUPPORTED_CODING", f"widths {bits}")
            if not all(math.isfinite(h) for h in h_range) or h_range[0] > h_range[1]:
                fail("BAD_HEADER_VALUE", f"h range {h_range}")
            if not math.isfinite(h_range[1] - h_range[0]):  # SPEC_NOTES 9: a range too wide for §7.3
                fail("BAD_HEADER_VALUE", f"h range {h_range}: h_max - h_min overflows")
        if units > 7 or up_axis == 3:
            fail("BAD_HEADER_VALUE", f"units {units}, up axis {up_axis}")
        if bbox is not None:
            if not all(math.isfinite(v) for v in bbox) or any(bbox[i] > bbox[i + 3] for i in range(3)):
                fail("BAD_HEADER_VALUE", f"bbox {bbox}")
        for name, v in (("tolerance", tolerance), ("error_bound", error_bound)):
            if not (math.isnan(v) or (math.isfinite(v) and v >= 0)):
                fail("BAD_HEADER_VALUE", f"{name} {v}")
        self.coding = coding
        self.bits = bits if coding >= 2 else (0, 0, 0)
        self.h_range = h_range if coding >= 2 else (0.0, 0.0)
        self.counts = counts
        if up_axis:  # reported as the file's metadata (the v5 goldens; SPEC_NOTES 55)
            self.metadata["up_axis"] = UP_AXES[up_axis]
        self.header = {
            "version": [self.major, self.minor],
            "lossy": bool(flags & 1),
            "coding": coding,
            "bits": list(self.bits),
            "h_range": list(self.h_range),
            "units": units,
            "bbox": [bbox[:3], bbox[3:]] if bbox is not None else None,
            "tolerance": none_if_nan(tolerance),
            "error_bound": none_if_nan(error_bound),
            "counts": counts,
        }

    # §7
    def plns(self, p: bytes, key: tuple):
        c = Cursor(p)
        if self.major >= 6:  # §7.1: count and the raw data, its size the rest of the record
            count = c.varint32("count")
            first, method, raw_size = len(self.planes), 0, c.left()
        elif self.major >= 3:
            first = c.varint("first")
            count = c.varint32("count")
            method = c.u8("compression")
            raw_size = c.varint32("raw_size")
        else:  # A.1: a 20-byte head
            if len(p) < 20:
                fail("BAD_PAYLOAD", "PLNS head under 20 bytes")
            first, count, method = c.u64(), c.u32(), c.u8()
            c.take(3)
            raw_size = c.u32()
        if first != len(self.planes):
            fail("PLANE_INDEX_MISMATCH", f"first {first}, {len(self.planes)} planes before")
        if first + count > PLANE_LIMIT:
            fail("LIMIT_EXCEEDED", f"{first + count} planes")
        coding = self.coding
        if coding == 0:
            ok = raw_size == 12 * count
        elif coding == 1:
            ok = raw_size == 24 * count
        elif coding == 2:
            ok = raw_size == (count * sum(self.bits) + 7) // 8
        else:
            ok = 3 * count <= raw_size <= 15 * count
        if not ok:
            fail("SIZE_MISMATCH", f"raw size {raw_size} for {count} planes")
        raw = decompress(method, raw_size, p[c.pos:], self.major)
        if coding in (0, 1):
            planes = self.float_planes(raw, count, coding)
        elif coding == 2:
            planes = self.quantized_planes(raw, count)
        else:
            planes = self.predicted_planes(raw, count)
        self.chunks.append(key + (first,))
        self.planes.extend(planes)

    @staticmethod
    def float_planes(raw: bytes, count: int, coding: int) -> list[list[float]]:
        """§7.2"""
        if coding == 0:
            a = np.frombuffer(raw, "<f4").reshape(count, 3)
            pi, two_pi = PI_F32, TWO_PI_F32
        else:
            a = np.frombuffer(raw, "<f8").reshape(count, 3)
            pi, two_pi = PI_F64, TWO_PI_F64
        with np.errstate(invalid="ignore"):
            if not np.isfinite(a).all():
                fail("BAD_TRIPLET", "a value not finite")
            nu, phi = a[:, 0], a[:, 1]
            if not ((nu >= 0) & (nu <= pi) & (phi >= 0) & (phi < two_pi)).all():
                fail("BAD_TRIPLET", "nu or phi out of range")
        return a.astype(np.float64).tolist()

    def dequantize(self, qn, qp, qh) -> list[list[float]]:
        """§7.3, in binary64: nu = q * (pi / M), phi = q * (2 pi / N), h = h_min + q * (range / M_h)."""
        bn, bp, bh = self.bits
        m_nu, n_phi, m_h = 2 ** (bn - 1), 2 ** bp, 2 ** bh - 1
        h_min, h_max = self.h_range
        nu = np.asarray(qn, np.float64) * (math.pi / m_nu)
        phi = np.asarray(qp, np.float64) * (2 * math.pi / n_phi)
        h = h_min + np.asarray(qh, np.float64) * ((h_max - h_min) / m_h)
        return np.stack([nu, phi, h], axis=1).tolist() if len(nu) else []

    def quantized_planes(self, raw: bytes, count: int) -> list[list[float]]:
        """§7.3: a bit string of count records (q_nu, q_phi, q_h), a padding bit before a code."""
        bn, bp, bh = self.bits
        width = bn + bp + bh
        bits = np.unpackbits(np.frombuffer(raw, np.uint8), bitorder="little")
        if bits[count * width:].any():
            fail("BAD_PAYLOAD", "a set padding bit in quantized planes")
        rec = bits[:count * width].reshape(count, width).astype(np.uint64)

        def field(lo, n):
            weights = np.left_shift(np.uint64(1), np.arange(n, dtype=np.uint64))
            return (rec[:, lo:lo + n] * weights).sum(axis=1, dtype=np.uint64)

        qn, qp, qh = field(0, bn), field(bn, bp), field(bn + bp, bh)
        if (qn > np.uint64(2 ** (bn - 1))).any():
            fail("BAD_TRIPLET", "a nu code above M_nu")
        return self.dequantize(qn, qp, qh)

    def predicted_planes(self, raw: bytes, count: int) -> list[list[float]]:
        """§7.4, checks in its order, each over the whole block before the next (SPEC_NOTES 5)."""
        c = Cursor(raw)
        streams = [c.varints(count, "predicted plane data") for _ in range(3)]
        if c.left():
            fail("SIZE_MISMATCH", f"{c.left()} bytes after the predicted varints")
        if any(v >= 1 << 33 for s in streams for v in s):
            fail("BAD_PAYLOAD", "a predicted varint of 2^33 or more")
        bn, bp, bh = self.bits
        m_nu, n_phi, m_h = 2 ** (bn - 1), 2 ** bp, 2 ** bh - 1
        qn, qp, qh = [], [], []
        a = b = h = 0
        for i in range(count):
            prev_a, prev_b = a, b
            a = prev_a + unzigzag(streams[0][i])
            same_a = i > 0 and a == prev_a
            b = prev_b + unzigzag(streams[1][i]) if same_a else streams[1][i]
            same_b = same_a and b == prev_b
            h = h + unzigzag(streams[2][i]) if same_b else streams[2][i]
            if not (0 <= a <= m_nu and 0 <= b <= n_phi - 1 and 0 <= h <= m_h):
                fail("BAD_TRIPLET", f"predicted plane {i}: codes {a}, {b}, {h}")
            qn.append(a)
            qp.append(b)
            qh.append(h)
        return self.dequantize(qn, qp, qh)

    # §8 and A.1
    def objt(self, p: bytes, key: tuple):
        if len(self.objects) >= OBJECT_LIMIT:
            fail("LIMIT_EXCEEDED", "objects")
        c = Cursor(p)
        if self.major >= 3:
            # §8, version 6: no index; an object's is its place among the object records
            index = len(self.objects) if self.major >= 6 else c.varint32("index")
            parent = c.varint32("parent")
            flags = c.u8("flags")
            name_length = c.varint("name_length")
            if name_length > 65535:
                fail("BAD_OBJECT", f"name_length {name_length}")
            parent = None if parent == 0 else parent - 1
        else:
            index, parent, flags = c.u32("index"), c.u32("parent"), c.u8("flags")
            c.u8("reserved")
            name_length = c.u16("name_length")
            parent = None if parent == 0xFFFFFFFF else parent
        name = c.take(name_length, "the name")
        transform = None
        if flags & 1:
            transform = self.transform_v4(c) if self.major >= 4 else [c.f64("the transform") for _ in range(16)]
        n = len(self.objects)
        if index != n:
            fail("BAD_OBJECT", f"index {index}, {n} objects before")
        if parent is not None and parent >= n:
            fail("BAD_OBJECT", f"parent {parent} not an earlier object")
        try:
            name = name.decode("utf-8")
        except UnicodeDecodeError:
            fail("BAD_OBJECT", "name not UTF-8")
        if transform is not None:
            # A.3: the last row is checked in 1.0 to 3.4; in 4.0 it is not stored (always 0 0 0 1)
            if not all(math.isfinite(v) for v in transform) or transform[12:] != [0.0, 0.0, 0.0, 1.0]:
                fail("BAD_OBJECT", f"transform {transform}")
        self.chunks.append(key + (index,))
        self.objects.append({"name": name, "parent": parent, "transform": transform})

    @staticmethod
    def transform_v4(c: Cursor) -> list[float]:
        """§8, version 4: a bit string (§2.1) of twelve 2-bit codes in 3 bytes, entry i's code bit
        2i + 2 x bit 2i+1 (0: +0.0, 1: 1.0, 2: an f32 follows, 3: an f64 follows), then the values
        of codes 2 and 3 in entry order; the entries are the top three rows, row by row, the
        last row is 0 0 0 1. Ending inside the codes or the values is BAD_PAYLOAD (step 4); the
        24 code bits fill their 3 bytes, so there is no padding (SPEC_NOTES 27)."""
        codes = int.from_bytes(c.take(3, "the transform's codes"), "little")
        entries = []
        for i in range(12):
            code = (codes >> (2 * i)) & 3
            if code == 0:
                entries.append(0.0)
            elif code == 1:
                entries.append(1.0)
            elif code == 2:
                entries.append(c.f32("the transform's values"))  # widened exactly
            else:
                entries.append(c.f64("the transform's values"))
        return entries + [0.0, 0.0, 0.0, 1.0]

    # §9
    def kinds(self) -> set[int]:
        if self.major >= 6:
            return set(range(14))  # §9.3: kinds 0-13 in 6.0
        if self.major >= 5:
            # §9.3: kinds 0-11 in 5.0, 0-12 in 5.1, 0-13 in 5.2 (and later)
            return set(range(12 + (self.minor >= 1) + (self.minor >= 2)))
        if self.major >= 4:
            # §9.3: kinds 0-8 in 4.0, 0-9 in 4.1, 0-11 in 4.2 (and later: SPEC_NOTES 29)
            return set(range(9 + min(self.minor, 1) + 2 * (self.minor >= 2)))
        if self.major == 3:
            return set(range(5 + min(self.minor, 4)))  # §9.3: 3.1 adds kind 5, 3.2 kind 6, 3.3 kind 7, 3.4 kind 8
        return set(range(5))

    def grup(self, p: bytes, key: tuple):
        c = Cursor(p)
        if self.major >= 6:  # §9.1: object, kind, the body (stored: the segment is compressed)
            obj = c.varint32("object")
            kind = c.u8("kind")
            index, method, raw_size = len(self.groups), 0, c.left()
        elif self.major >= 3:
            index = c.varint32("index")
            obj = c.varint32("object")
            kind = c.u8("kind")
            method = c.u8("compression")
            raw_size = c.varint32("raw_size")
        else:  # A.1: a 16-byte head
            if len(p) < 16:
                fail("BAD_PAYLOAD", "GRUP head under 16 bytes")
            index, obj, kind, method = c.u32(), c.u32(), c.u8(), c.u8()
            c.take(2)
            raw_size = c.u32()
        if index != len(self.groups):
            fail("GROUP_INDEX_MISMATCH", f"index {index}, {len(self.groups)} groups before")
        if obj >= len(self.objects):
            fail("BAD_OBJECT_REFERENCE", f"object {obj}, {len(self.objects)} defined")
        skipped = False
        if kind not in self.kinds():
            if self.minor <= NEWEST_MINOR[self.major]:
                fail("UNKNOWN_GROUP_KIND", f"kind {kind} in {self.major}.{self.minor}")
            skipped = True
        body = decompress(method, raw_size, p[c.pos:], self.major)  # skipped kinds too (SPEC_NOTES 12)
        b = Cursor(body)
        if self.major == 1:
            refs, roles = self.common_body_v1(b)
        else:
            refs, roles = self.common_body(b, kind, skipped)
        group = {"index": index, "object": obj, "kind": kind, "refs": refs,
                 "bounding": [i for i, r in enumerate(roles) if r]}
        if skipped:
            self.finding("SKIPPED_GROUP_KIND")
        elif kind in (0, 3, 4):
            if b.left():
                fail("BAD_PAYLOAD", f"kind data after the roles of kind {kind}")
        elif kind == 1:
            group["cells"] = self.cells_v1(b, len(refs)) if self.major == 1 else self.cells(b, len(refs))
        elif kind == 2:
            group["tree"] = self.tree_v1(b, len(refs)) if self.major == 1 else self.tree(b, len(refs))
        elif kind == 5:
            group.update(self.sealed(b, refs, roles))
        elif kind == 6:
            group["shell"] = self.shell(b, refs, roles)
        elif kind in (7, 8):
            group["shell"] = self.shell_tree(b, refs, roles, parallelogram=kind == 8)
        elif kind in (9, 10, 12, 13):
            group["shell"] = self.shell_walk(b, refs, roles, multi=kind == 10, reflect=kind == 12,
                                             later=kind == 13)
        elif kind == 11:
            group["source"], skipped = self.copy(b, index, refs, roles)
            if skipped:
                self.finding("SKIPPED_GROUP_KIND")
        self.chunks.append(key + (index,))
        self.groups.append(group)
        self.group_refs.append(len(refs))
        self.group_roles.append(roles)
        self.group_skipped.append(skipped)

    # §9.15 (added at version 4.2, from §9.15 and §9.3)
    def copy(self, b: Cursor, index: int, refs: list[int], roles: list[int]) -> tuple[int, bool]:
        """Kind 11: one varint, the index of the source group, checked in §9.15's order. Returns the
        source and whether the copy is skipped (its source's kind was). Listed as stored: kind 11
        with "source" (README's groups row), also where it is skipped (SPEC_NOTES 48)."""
        # 1. the varint (a full varint, not a varint32: SPEC_NOTES 46), then nothing after it
        s = b.varint("the source")
        if b.left():
            fail("BAD_PAYLOAD", f"{b.left()} bytes after the source")  # not §12.1 item 6's code (SPEC_NOTES 45)
        # 2. an earlier group, not a copy (by its stored kind, even a copy that was skipped: SPEC_NOTES 47)
        if s >= index:
            fail("BAD_GROUP_STRUCTURE", f"source {s} not below the copy's index {index}")
        if self.groups[s]["kind"] == 11:
            fail("BAD_GROUP_STRUCTURE", f"source {s} is a copy")
        # 3. a skipped source: the copy is skipped too, and step 4 is not taken (SPEC_NOTES 48)
        if self.group_skipped[s]:
            return s, True
        # 4. the same references, in the same order, and the same role bits
        if refs != self.groups[s]["refs"]:
            fail("BAD_GROUP_STRUCTURE", f"references {refs}, the source's {self.groups[s]['refs']}")
        if roles != self.group_roles[s]:
            fail("BAD_GROUP_STRUCTURE", "role bits other than the source's")
        return s, False

    def common_body(self, b: Cursor, kind: int, skipped: bool) -> tuple[list[int], list[int]]:
        """§9.2 (versions 2 to 5)."""
        m = b.varint("ref_count")
        if m > REF_LIMIT:
            fail("LIMIT_EXCEEDED", f"ref_count {m}")
        # version 5: m = 0 in kinds 0-5 only (shells and copies, kinds 6-13, may have none: SPEC_NOTES 67); a
        # skipped kind of a newer minor version "decides for itself", which a reader that skips it
        # cannot know, so it is accepted (SPEC_NOTES 56).
        # Versions 2 to 4 (A.5): in every kind, skipped ones included.
        if m == 0 and (self.major < 5 or (not skipped and kind <= 5)):
            fail("BAD_GROUP_STRUCTURE", f"ref_count 0 in a group of kind {kind}")
        diffs = b.varints(m, "the references")
        n = len(self.planes)
        refs, total = [], 0
        for d in diffs:
            if d >= n:
                fail("BAD_PLANE_REFERENCE", f"difference {d}, {n} planes defined")
            total += d
            if total >= n:
                fail("BAD_PLANE_REFERENCE", f"reference {total}, {n} planes defined")
            refs.append(total)
        roles = bit_string(b.take((m + 7) // 8, "the roles"), m, "the roles")
        return refs, roles

    def common_body_v1(self, b: Cursor) -> tuple[list[int], list[int]]:
        """A.1: u32 references in any order."""
        if b.left() < 4:
            fail("BAD_PAYLOAD", "body under 4 bytes")
        m = b.u32()
        if m > REF_LIMIT:
            fail("LIMIT_EXCEEDED", f"ref_count {m}")
        if b.left() < 4 * m + (m + 7) // 8:
            fail("BAD_PAYLOAD", "body shorter than its references and roles")
        if m == 0:
            fail("BAD_GROUP_STRUCTURE", "ref_count 0")
        refs = list(struct.unpack(f"<{m}I", b.take(4 * m)))
        n = len(self.planes)
        for r in refs:
            if r >= n:
                fail("BAD_PLANE_REFERENCE", f"reference {r}, {n} planes defined")
        roles = bit_string(b.take((m + 7) // 8), m, "the roles")
        return refs, roles

    # §9.6
    def cells(self, b: Cursor, m: int) -> list[list[int]]:
        kind_size = b.left()
        c = b.varint("cell_count")
        if c > b.left() or c > REF_LIMIT:  # SPEC_NOTES 6 (bytes after cell_count), 8 (the code)
            fail("BAD_GROUP_STRUCTURE", f"cell_count {c}")
        sizes = b.varints(c, "the cell sizes")
        if c == 0 or 0 in sizes:
            fail("BAD_GROUP_STRUCTURE", "no cell, or an empty cell")
        if any(s > kind_size for s in sizes) or sum(sizes) > b.left():  # SPEC_NOTES 7
            fail("BAD_GROUP_STRUCTURE", "cell sizes above the bytes left")
        cells = [b.varints(s, "the cell entries") for s in sizes]
        if b.left():
            fail("BAD_GROUP_STRUCTURE", "bytes after the cell entries")
        if any(e >> 1 >= m for cell in cells for e in cell):
            fail("BAD_GROUP_STRUCTURE", "an entry on a reference >= m")
        return cells

    def cells_v1(self, b: Cursor, m: int) -> list[list[int]]:
        c = b.u32("cell_count")  # SPEC_NOTES 11: no limit but the body's size
        sizes = list(struct.unpack(f"<{c}I", b.take(4 * c, "the cell sizes")))
        if c == 0 or 0 in sizes:
            fail("BAD_GROUP_STRUCTURE", "no cell, or an empty cell")
        if b.left() != 4 * sum(sizes):
            fail("BAD_GROUP_STRUCTURE", "entries not exactly the cells' sizes")
        cells = [list(struct.unpack(f"<{s}I", b.take(4 * s))) for s in sizes]
        if any(e >> 1 >= m for cell in cells for e in cell):
            fail("BAD_GROUP_STRUCTURE", "an entry on a reference >= m")
        return cells

    # §9.7
    @staticmethod
    def check_tree(tokens: list[int], is_split):
        slots = 1
        for k, t in enumerate(tokens):
            if slots <= 0:
                fail("BAD_GROUP_STRUCTURE", "tokens after a complete tree")
            slots += 1 if is_split(t) else -1
        if slots != 0:
            fail("BAD_GROUP_STRUCTURE", "not one complete tree")

    def tree(self, b: Cursor, m: int) -> list[int]:
        t = b.varint("token_count")
        if t > b.left():  # SPEC_NOTES 6: the bytes after token_count
            fail("BAD_GROUP_STRUCTURE", f"token_count {t}")
        tokens = b.varints(t, "the tokens")
        if b.left():
            fail("BAD_GROUP_STRUCTURE", "bytes after the tokens")
        if any(tok > m + 1 for tok in tokens):
            fail("BAD_GROUP_STRUCTURE", "a split on a reference >= m")
        self.check_tree(tokens, lambda tok: tok >= 2)
        return [V1_IN if tok == 0 else V1_OUT if tok == 1 else tok - 2 for tok in tokens]

    def tree_v1(self, b: Cursor, m: int) -> list[int]:
        t = b.u32("token_count")  # SPEC_NOTES 10: ending inside it is BAD_PAYLOAD
        tokens = list(struct.unpack(f"<{t}I", b.take(4 * t, "the tokens")))
        if b.left():
            fail("BAD_GROUP_STRUCTURE", "bytes after the tokens")
        if t == 0:
            fail("BAD_GROUP_STRUCTURE", "no token")
        for tok in tokens:
            if 0xFFFFFFF0 <= tok <= 0xFFFFFFFD:
                fail("BAD_GROUP_STRUCTURE", f"reserved token {tok:#x}")
            if tok < 0xFFFFFFF0 and tok >= m:
                fail("BAD_GROUP_STRUCTURE", "a split on a reference >= m")
        self.check_tree(tokens, lambda tok: tok < 0xFFFFFFF0)
        return tokens

    # §9.9
    def sealed(self, b: Cursor, refs: list[int], roles: list[int]) -> dict:
        m = len(refs)
        v = b.varint("vertex_count")
        if v < 3 or 3 * v > b.left():
            fail("BAD_GROUP_STRUCTURE", f"vertex_count {v}")
        flat = b.varints(3 * v, "the vertex planes")
        vertex_planes = [flat[3 * k:3 * k + 3] for k in range(v)]
        t = b.varint("triangle_count")
        if t < 1 or 4 * t > b.left():
            fail("BAD_GROUP_STRUCTURE", f"triangle_count {t}")
        tri = b.varints(4 * t, "the triangles")
        if b.left():
            fail("BAD_GROUP_STRUCTURE", "bytes after the triangles")
        facets, f, used = [], 0, [False] * v  # f never decreases (SPEC_NOTES 13)
        for k in range(t):
            d, i0, i1, i2 = tri[4 * k:4 * k + 4]
            f += d
            if f >= m or roles[f]:
                fail("BAD_GROUP_STRUCTURE", f"triangle {k}: face reference {f}")
            if max(i0, i1, i2) >= v or len({i0, i1, i2}) < 3:
                fail("BAD_GROUP_STRUCTURE", f"triangle {k}: vertices {i0, i1, i2}")
            for i in (i0, i1, i2):
                used[i] = True
            facets.append([f, i0, i1, i2])
        for k, abc in enumerate(vertex_planes):
            if max(abc) >= m or len(set(abc)) < 3:
                fail("BAD_GROUP_STRUCTURE", f"vertex {k}: planes {abc}")
        if not all(used):
            fail("BAD_GROUP_STRUCTURE", "a vertex on no triangle")
        return {"vertex_planes": vertex_planes, "facets": facets}

    # §9.10
    def shell(self, b: Cursor, refs: list[int], roles: list[int]) -> dict:
        m = len(refs)
        v = b.varint("corner_count")
        t = b.varint("triangle_count")
        u = b.varint("free_count")
        left = b.left()
        if v < 3 or v > 8 * left or t < 1 or 3 * t > left or u > t:
            fail("BAD_GROUP_STRUCTURE", f"counts V={v} T={t} U={u} with {left} bytes left")
        flags = bit_string(b.take((v + 7) // 8, "the corner flags"), v, "the corner flags")
        explicit = [k for k in range(v) if flags[k]]
        e = len(explicit)
        flat = b.varints(3 * (v - e), "the corner planes")
        named = [flat[3 * k:3 * k + 3] for k in range(v - e)]
        origin = step = None
        steps = []
        if e:
            origin, step = self.grid(b)
            steps = b.varints(3 * e, "the coordinates")
        faces = b.varints(t - u, "the faces")
        codes = b.varints(3 * t, "the corner codes")
        if b.left():
            fail("BAD_GROUP_STRUCTURE", "bytes after the corner codes")
        # step 5
        lim = 1 << 52
        grid, xyz = [], [0, 0, 0]
        for k in range(e):
            st = [unzigzag(z) for z in steps[3 * k:3 * k + 3]]
            xyz = [a + s for a, s in zip(xyz, st)]
            if any(abs(s) > lim for s in st) or any(abs(a) > lim for a in xyz):
                fail("BAD_GROUP_STRUCTURE", f"explicit corner {k}: beyond 2^52")
            grid.append(list(xyz))
        f, face_refs = 0, []
        for j, d in enumerate(faces):
            f += d
            if f >= m or roles[f]:
                fail("BAD_GROUP_STRUCTURE", f"planar triangle {j}: face reference {f}")
            face_refs.append(f)
        n, corners = 0, []
        for k, code in enumerate(codes):
            if code == 0:
                corners.append(n)
                n += 1
            else:
                if n - code < 0:
                    fail("BAD_GROUP_STRUCTURE", f"corner code {k} names a corner below 0")
                corners.append(n - code)
        for k, abc in enumerate(named):
            if max(abc) >= m or len(set(abc)) < 3:
                fail("BAD_GROUP_STRUCTURE", f"named corner {k}: planes {abc}")
        if e and not (all(math.isfinite(x) for x in origin) and math.isfinite(step) and step > 0):
            fail("BAD_GROUP_STRUCTURE", f"grid origin {origin}, step {step}")
        facets = []
        for j in range(t):
            tri = corners[3 * j:3 * j + 3]
            if len(set(tri)) < 3:
                fail("BAD_GROUP_STRUCTURE", f"triangle {j} names one corner twice")
            facets.append([face_refs[j] if j < t - u else -1, *tri])
        if n != v:
            fail("BAD_GROUP_STRUCTURE", f"{n} corners used of {v}")
        return {"explicit": explicit, "vertex_planes": named, "grid": grid,
                "origin": origin, "step": step, "facets": facets}

    def grid(self, b: Cursor) -> tuple[list[float], float]:
        """§9.10-§9.14: origin x, y, z and step, f32 each in version 5 (widened exactly), f64 each in
        versions 3 and 4 (A.5); kinds 9 and 10 too, though §9.13's table still says 32 bytes
        (SPEC_NOTES 54)."""
        if self.major >= 5:
            ox, oy, oz, step = struct.unpack("<4f", b.take(16, "the grid"))
        else:
            ox, oy, oz, step = struct.unpack("<4d", b.take(32, "the grid"))
        return [ox, oy, oz], step

    # §9.11 (added at version 3.3, from §9.11 and the sections it refers to)
    def shell_tree(self, b: Cursor, refs: list[int], roles: list[int], parallelogram: bool = False) -> dict:
        """A shell stored along a spanning tree of its triangles. Reported as the shell of §9.10
        with the same corners and triangles (conformance/README.md, kind 7). Kind 8 (§9.12,
        ``parallelogram``) predicts an explicit corner by the parallelogram of its attached
        triangle's shared edge and the parent's opposite corner, where all three are explicit."""
        # 1. the two counts, read, then checked against the bytes left after both (as §9.11 says;
        #    the same pattern as §9.10, SPEC_NOTES 15)
        v = b.varint("corner_count")
        t = b.varint("triangle_count")
        left = b.left()
        if v < 3 or v > 8 * left or t < 1 or 3 * t > left:
            fail("BAD_GROUP_STRUCTURE", f"counts V={v} T={t} with {left} bytes left")
        # 2. the links, the corner codes, the faces and the flags, read
        links = b.varints(t, "the links")
        roots = sum(1 for ell in links if ell == 0)
        codes = b.varints(t + 2 * roots, "the corner codes")
        face_codes = b.varints(t, "the faces")
        flags = bit_string(b.take((v + 7) // 8, "the corner flags"), v, "the corner flags")
        # 3. the links, the corner codes and the faces, checked
        parents = []
        for j, ell in enumerate(links):
            if ell == 0:
                parents.append(None)
                continue
            d, e = (ell - 1) // 3 + 1, (ell - 1) % 3
            if j - d < 0:
                fail("BAD_GROUP_STRUCTURE", f"triangle {j}: link {ell} past the first triangle")
            parents.append((j - d, e))
        n, k, tris = 0, 0, []
        named_by = []  # the triangle whose code names each corner anew, in corner order
        for j in range(t):
            if parents[j] is None:
                tri = []
                for _ in range(3):
                    code = codes[k]
                    k += 1
                    if code == 0:
                        tri.append(n)
                        named_by.append(j)
                        n += 1
                    elif n - code < 0:
                        fail("BAD_GROUP_STRUCTURE", f"root triangle {j}: code {code} names a corner below 0")
                    else:
                        tri.append(n - code)
            else:
                p, e = parents[j]
                q = tris[p]
                i0, i1 = q[(e + 1) % 3], q[e]
                code = codes[k]
                k += 1
                if code == 0:
                    i2 = n
                    named_by.append(j)
                    n += 1
                else:
                    i2 = i1 + unzigzag(code - 1)  # SPEC_NOTES 20: code 1 names i1 itself
                    if not 0 <= i2 < n:
                        fail("BAD_GROUP_STRUCTURE", f"triangle {j}: code {code} names corner {i2}, "
                                                    f"{n} named before it")
                tri = [i0, i1, i2]
            if len(set(tri)) < 3:
                fail("BAD_GROUP_STRUCTURE", f"triangle {j} names one corner twice: {tri}")
            tris.append(tri)
        if n != v:  # with the corner codes, before the picks are read (SPEC_NOTES 18)
            fail("BAD_GROUP_STRUCTURE", f"{n} corners named, V = {v}")
        return self.shell_tree_rest(b, len(refs), roles, v, flags, face_codes, parents, tris, named_by,
                                    parallelogram=parallelogram)

    def shell_tree_rest(self, b: Cursor, m: int, roles: list[int], v: int, flags: list[int],
                        face_codes: list[int], parents: list, tris: list[list[int]], named_by: list[int],
                        parallelogram: bool = False, walk: bool = False, multi: bool = False,
                        reflect: bool = False, later: bool = False) -> dict:
        """What §9.11 and §9.13 share after the triangles are known: the faces checked, the picks,
        (kinds 9, 10, 12, 13: the mode byte), the grid, (kinds 9, 10, 12, 13: the value tables), the
        coordinates; then the rest checked. ``parents`` holds (p, e) for an attached triangle, None
        for a root. Kinds 10 (``multi``, §9.14), 12 (``reflect``, §9.16) and 13 (``later``, §9.17)
        change only the prediction of explicit corners."""
        faces = []  # local reference of each triangle, -1 for a free one
        for j, fc in enumerate(face_codes):
            if fc == 0:
                # the parent's face as resolved, free included (SPEC_NOTES 22); for a root j > 0
                # triangle j - 1's, for triangle 0 free
                if parents[j] is not None:
                    f = faces[parents[j][0]]
                else:
                    f = faces[j - 1] if j > 0 else -1
            elif fc == 1:
                f = -1
            else:
                f = fc - 2
                if f >= m:
                    fail("BAD_GROUP_STRUCTURE", f"triangle {j}: face code {fc} above m + 1 = {m + 1}")
                if roles[f]:
                    fail("BAD_GROUP_STRUCTURE", f"triangle {j}: face {f} is a bounding plane")
            faces.append(f)
        # the face planes of every corner: distinct local references, ascending (SPEC_NOTES 21);
        # they decide how many picks follow
        planes_of = [set() for _ in range(v)]
        for tri, f in zip(tris, faces):
            if f >= 0:
                for i in tri:
                    planes_of[i].add(f)
        named = [c for c in range(v) if not flags[c]]
        pk = {c: sorted(planes_of[c]) for c in named}
        w = sum(1 for c in named if len(pk[c]) > 3)
        # 4. the picks, (kind 9: the mode,) the grid, (kind 9: the tables,) the coordinates, read
        picks = b.varints(3 * w, "the picks")
        explicit = [c for c in range(v) if flags[c]]
        e_count = len(explicit)
        origin = step = None
        residuals = []
        mode = 0
        tables = None  # kind 9 with mode bit 1: the values of each axis, ascending
        if e_count:
            if walk:
                mode = b.u8("the mode")  # its bits 2-7 are checked with the rest (SPEC_NOTES 31)
                parallelogram = bool(mode & 1)
            origin, step = self.grid(b)
            if mode & 2:
                tables = [self.value_table(b, e_count, "xyz"[a]) for a in range(3)]
            residuals = b.varints(3 * e_count, "the coordinates")
        # 5. the rest, checked: bytes left first, as §9.10 step 4 and §12.1 item 6 (SPEC_NOTES 19)
        if b.left():
            fail("BAD_GROUP_STRUCTURE", f"{b.left()} bytes after the "
                                        f"{'coordinates' if e_count else 'picks'}")
        vertex_planes, w_at = [], 0
        for c in named:
            ps = pk[c]
            if len(ps) < 3:  # among "the rest", after the picks are read (SPEC_NOTES 18)
                fail("BAD_GROUP_STRUCTURE", f"named corner {c} on {len(ps)} face planes")
            if len(ps) == 3:
                vertex_planes.append(ps)
                continue
            i, j, l = picks[3 * w_at:3 * w_at + 3]
            w_at += 1
            if not i < j < l:
                fail("BAD_GROUP_STRUCTURE", f"named corner {c}: picks {i, j, l} not ascending")
            if l >= len(ps):
                fail("BAD_GROUP_STRUCTURE", f"named corner {c}: pick {l} past its {len(ps)} face planes")
            vertex_planes.append([ps[i], ps[j], ps[l]])
        grid = []
        if e_count:
            if not (all(math.isfinite(x) for x in origin) and math.isfinite(step) and step > 0):
                fail("BAD_GROUP_STRUCTURE", f"grid origin {origin}, step {step}")
            lim = 1 << 52
            if mode & ~3:
                fail("BAD_GROUP_STRUCTURE", f"mode {mode:#04x}: a bit above 1 set")
            if tables is not None:
                for a, values in enumerate(tables):
                    if any(abs(x) > lim for x in values):  # every table value (SPEC_NOTES 35)
                        fail("BAD_GROUP_STRUCTURE", f"the {'xyz'[a]} table: a value beyond 2^52")
            # the predictor of each explicit corner: i0 of the attached triangle that names it anew,
            # where that i0 is explicit; otherwise the previous explicit corner (none for the first).
            # The rule of the "Explicit corners" paragraph, not the overview's bullet (SPEC_NOTES 23).
            # Kind 9 with tables: the values predicted and resolved are indices into each axis's
            # table, resolved the same way, each within [0, C) (§9.13). Kind 10: the average of the
            # corner's parallelograms where it has one, this prediction otherwise (§9.14). Kind 12:
            # this predictor is the step source (§9.16), whatever bit 0 of the mode. Kind 13 (§9.17):
            # the predictor is max(i0, i1) instead of i0, where that corner is explicit (else the
            # previous explicit corner, not the other gate corner: SPEC_NOTES 68); mode bit 0's
            # parallelogram is unchanged.
            res = [[unzigzag(r) for r in residuals[a * e_count:(a + 1) * e_count]] for a in range(3)]
            # kind 10 (§9.14): each explicit corner's parallelograms (a, b, c), at most four
            parallelograms = self.multi_parallelograms(tris, flags) if multi else None
            xyz = {}
            sources = {}  # kind 12 (§9.16): each explicit corner's step source, §9.11's predictor
            for x, c in enumerate(explicit):
                r = [res[a][x] for a in range(3)]
                if any(abs(s) > lim for s in r):
                    fail("BAD_GROUP_STRUCTURE", f"explicit corner {c}: residual {r} beyond 2^52")
                j = named_by[c]
                pred = None
                gate = max(tris[j][0], tris[j][1]) if later else tris[j][0]  # i0, or kind 13's later one
                if parents[j] is not None and flags[gate]:
                    pred = gate
                elif x > 0:
                    pred = explicit[x - 1]
                sources[c] = pred
                base = xyz[pred] if pred is not None else [0, 0, 0]
                if parallelogram and parents[j] is not None:
                    p, e = parents[j]
                    i0, i1, o = tris[j][0], tris[j][1], tris[p][(e + 2) % 3]
                    if flags[i0] and flags[i1] and flags[o]:
                        base = [a + b_ - c_ for a, b_, c_ in zip(xyz[i0], xyz[i1], xyz[o])]
                # kind 10: where c has no parallelogram, the prediction above (by bit 0 of the
                # mode, which then rarely matters, SPEC_NOTES 42)
                if parallelograms is not None and parallelograms[c]:
                    # §9.14: floor((S + floor(n/2)) / n) on each axis, S the sum of g(a) + g(b) - g(c)
                    # over the n parallelograms; Python's // rounds toward -infinity, as the text asks.
                    # Every term is a corner below c, resolved and checked already; the prediction
                    # itself is not checked, only what it resolves to (SPEC_NOTES 41)
                    par = parallelograms[c]
                    base = [(sum(xyz[pa][ax] + xyz[pb][ax] - xyz[pc][ax] for pa, pb, pc in par) + len(par) // 2)
                            // len(par) for ax in range(3)]
                # kind 12 (§9.16): the reflection where the chain of step sources turns, §9.13's
                # prediction above (by bit 0) otherwise; the chain's corners are below c, resolved
                # and checked already
                chain = self.chain(sources, c) if reflect else None
                turned = self.reflection(*(xyz[y] for y in chain)) if chain else None
                if turned is not None:
                    base = turned
                point = [a + s for a, s in zip(base, r)]
                if any(abs(a) > lim for a in point):
                    fail("BAD_GROUP_STRUCTURE", f"explicit corner {c}: "
                                                f"{'index' if tables else 'coordinate'} {point} beyond 2^52")
                if tables is not None:
                    for a in range(3):
                        if not 0 <= point[a] < len(tables[a]):
                            fail("BAD_GROUP_STRUCTURE", f"explicit corner {c}: index {point[a]} outside "
                                                        f"the {len(tables[a])} values of the {'xyz'[a]} table")
                xyz[c] = point
            if tables is not None:
                grid = [[tables[a][xyz[c][a]] for a in range(3)] for c in explicit]
            else:
                grid = [xyz[c] for c in explicit]
        facets = [[f, *tri] for f, tri in zip(faces, tris)]
        return {"explicit": explicit, "vertex_planes": vertex_planes, "grid": grid,
                "origin": origin, "step": step, "facets": facets}

    @staticmethod
    def multi_parallelograms(tris: list[list[int]], flags: list[int]) -> list[list[tuple[int, int, int]]]:
        """§9.14, per corner k: its parallelograms (a, b, c), the first four in triangle order, then
        place order. For each place s of k in a triangle, (a, b) = (i_s+1, i_s+2) is the edge opposite
        k and c its far corner: the corner other than a and b of the first triangle, in triangle
        order, that has the edge (b, a) (SPEC_NOTES 37: the first only, whatever its third corner
        is). A candidate counts where c exists and a, b, c are all explicit and numbered below k;
        a repeated triangle repeats its parallelogram (SPEC_NOTES 38). The triangles may come
        anywhere in triangle order (SPEC_NOTES 39). One pass to map each directed edge to the first
        triangle that has it, then one over the triangles' places (SPEC_NOTES 43)."""
        first = {}  # directed edge -> the corner other than its ends of the first triangle with it
        for tri in tris:
            for s in range(3):
                first.setdefault((tri[s], tri[(s + 1) % 3]), tri[(s + 2) % 3])
        out: list[list[tuple[int, int, int]]] = [[] for _ in flags]
        for tri in tris:  # triangle order; within a triangle k has one place (SPEC_NOTES 40)
            for s in range(3):
                k = tri[s]
                if not flags[k] or len(out[k]) >= 4:
                    continue
                a, b = tri[(s + 1) % 3], tri[(s + 2) % 3]
                c = first.get((b, a))
                if c is None:
                    continue
                # c is neither a nor b; c == k (the same triangle reversed) fails "below k"
                if flags[a] and flags[b] and flags[c] and a < k and b < k and c < k:
                    out[k].append((a, b, c))
        return out

    @staticmethod
    def chain(sources: dict[int, int | None], k: int) -> tuple[int, int, int] | None:
        """§9.16: (a, b, c) = (p(k), p(a), p(b)) where all three exist, p the step source."""
        a = sources[k]
        b = None if a is None else sources[a]
        c = None if b is None else sources[b]
        return None if c is None else (a, b, c)

    @staticmethod
    def reflection(ga: list[int], gb: list[int], gc: list[int]) -> list[int] | None:
        """§9.16: g(a) + floor((2N + D) / 2D) on each axis, N = 2(d1.d2) d2 - D d1, d1 = g(b) - g(c),
        d2 = g(a) - g(b), D = d2.d2; None where the chain does not turn (D = 0, or a component of d1
        or d2 beyond 2^18). Python's integers are exact and its // rounds toward -infinity, as the
        text asks (no quotient is ever a half: SPEC_NOTES 63); the prediction itself is not bounded,
        only what it resolves to."""
        d1 = [y - x for x, y in zip(gc, gb)]
        d2 = [y - x for x, y in zip(gb, ga)]
        dd = sum(x * x for x in d2)
        if dd == 0 or any(abs(x) > 1 << 18 for x in d1 + d2):
            return None
        dot = sum(x * y for x, y in zip(d1, d2))
        return [g + (2 * (2 * dot * y - dd * x) + dd) // (2 * dd) for g, x, y in zip(ga, d1, d2)]

    @staticmethod
    def value_table(b: Cursor, e_count: int, axis: str) -> list[int]:
        """§9.13, one axis's table: a count C, 1 <= C <= E, checked when read (§12.1 item 4,
        SPEC_NOTES 31); the first value, zigzag; C - 1 gaps g, each next value the previous + g + 1."""
        count = b.varint(f"the {axis} table's count")
        if count < 1 or count > e_count:
            fail("BAD_GROUP_STRUCTURE", f"the {axis} table's count {count}, E = {e_count}")
        value = unzigzag(b.varint(f"the {axis} table's first value"))
        values = [value]
        for _ in range(count - 1):
            value += b.varint(f"the {axis} table's values") + 1
            values.append(value)
        return values

    # §9.13 (added at version 4.1, from §9.13 and the sections it builds on)
    # The ordered lists of distinct free edges a symbol's c numbers: by length, then in
    # lexicographic order of the edges' places in the triangle's free edges.
    ATTACHED_CHILDREN = [(), (1,), (2,), (1, 2), (2, 1)]
    ROOT_CHILDREN = [(), (0,), (1,), (2,), (0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1),
                     (0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]

    def shell_walk(self, b: Cursor, refs: list[int], roles: list[int], multi: bool = False,
                   reflect: bool = False, later: bool = False) -> dict:
        """Kind 9, a shell tree coded as a depth-first walk: one symbol per triangle (its
        children's edges and, attached, the kind of its third corner), escapes for what the
        symbols cannot say, then what §9.11 stores after its corner codes, with a mode byte and
        optional per-axis value tables before the coordinates. Reported as kinds 7 and 8 are.
        Kind 10 (§9.14, ``multi``) is the same body with explicit corners predicted by the
        average of their parallelograms (multi_parallelograms); kind 12 (§9.16, ``reflect``) with
        those whose chain of step sources turns predicted by the reflection of its earlier step;
        kind 13 (§9.17, ``later``) with explicit corners stepping from the later-named gate corner."""
        # 1. the three counts, read, then checked against the bytes left after all three
        v = b.varint("corner_count")
        t = b.varint("triangle_count")
        x_count = b.varint("escape_count")
        left = b.left()
        if v < 3 or v > 8 * left or t < 1 or 2 * t > left or x_count > left:
            fail("BAD_GROUP_STRUCTURE", f"counts V={v} T={t} X={x_count} with {left} bytes left")
        # 2. the symbols, the escapes, the faces and the flags, read
        symbols = b.varints(t, "the symbols")
        escapes = b.varints(x_count, "the escapes")
        face_codes = b.varints(t, "the faces")
        flags = bit_string(b.take((v + 7) // 8, "the corner flags"), v, "the corner flags")
        # 3. the walk
        esc = 0

        def escape(j: int) -> int:
            nonlocal esc
            if esc >= x_count:
                fail("BAD_GROUP_STRUCTURE", f"triangle {j}: the walk needs more than the {x_count} escapes")
            esc += 1
            return escapes[esc - 1]

        stack: list[tuple[int, int]] = []  # slots (triangle, edge), the top last
        open_edges = OpenEdges()
        n, tris, parents, named_by = 0, [], [], []
        for j in range(t):
            s = symbols[j]
            if not stack:  # a root
                if s >= 16:
                    fail("BAD_GROUP_STRUCTURE", f"root triangle {j}: symbol {s} above 15")
                children = self.ROOT_CHILDREN[s]
                parents.append(None)
                tri = []
                for _ in range(3):  # the codes of §9.10
                    code = escape(j)
                    if code == 0:
                        tri.append(n)
                        named_by.append(j)
                        n += 1
                    elif n - code < 0:
                        fail("BAD_GROUP_STRUCTURE", f"root triangle {j}: code {code} names a corner below 0")
                    else:
                        tri.append(n - code)
            else:
                p, e = stack.pop()
                if s >= 20:
                    fail("BAD_GROUP_STRUCTURE", f"triangle {j}: symbol {s}, c = {s // 4} above 4")
                children = self.ATTACHED_CHILDREN[s // 4]
                k = s % 4
                if k == 3:
                    k = 3 + escape(j)
                parents.append((p, e))
                q = tris[p]
                i0, i1, x = q[(e + 1) % 3], q[e], q[(e + 2) % 3]
                if k == 0:
                    i2 = n
                    named_by.append(j)  # the triangle whose code 0 names the corner (SPEC_NOTES 34)
                    n += 1
                elif k in (1, 2):
                    # 1, left: the start of the newest open edge ending at i1 (the second newest
                    # where that start is x); 2, right: the end of the newest open edge starting
                    # at i0 (likewise); the second newest whatever its end (SPEC_NOTES 33)
                    found = open_edges.starts_ending_at(i1) if k == 1 else open_edges.ends_starting_at(i0)
                    if found and found[0] == x:
                        found = found[1:]
                    if not found:
                        fail("BAD_GROUP_STRUCTURE", f"triangle {j}: a {'left' if k == 1 else 'right'} "
                                                    f"code with no open edge to name")
                    i2 = found[0]
                else:
                    i2 = i1 + unzigzag(k - 3)  # k = 3 names i1 itself (SPEC_NOTES 30)
                    if not 0 <= i2 < n:
                        fail("BAD_GROUP_STRUCTURE", f"triangle {j}: code {k} names corner {i2}, "
                                                    f"{n} named before it")
                tri = [i0, i1, i2]
            if len(set(tri)) < 3:
                fail("BAD_GROUP_STRUCTURE", f"triangle {j} names one corner twice: {tri}")
            tris.append(tri)
            for a in range(3):
                open_edges.toggle(tri[a], tri[(a + 1) % 3])
            for edge in reversed(children):  # the first list entry ends on top
                stack.append((j, edge))
        if stack:
            fail("BAD_GROUP_STRUCTURE", f"{len(stack)} slots left on the stack after the last triangle")
        if esc != x_count:
            fail("BAD_GROUP_STRUCTURE", f"{x_count - esc} escapes left over")
        if n != v:
            fail("BAD_GROUP_STRUCTURE", f"{n} corners named, V = {v}")
        # 4. the faces checked, then the picks and the rest, as §9.11 (with the links the walk gives)
        return self.shell_tree_rest(b, len(refs), roles, v, flags, face_codes, parents, tris, named_by,
                                    walk=True, multi=multi, reflect=reflect, later=later)

    # §10.1
    def colr(self, p: bytes):
        c = Cursor(p)
        if self.major >= 6:  # §10.1: group and count varint32
            group, count = c.varint32("the colours' group"), c.varint32("the colours' count")
        else:
            group, count = c.u32("the cOLR head"), c.u32("the cOLR head")
        one = self.major >= 4 and c.left() == 4  # version 4: one colour every reference takes
        if one:
            rgba = c.take(4, "the colour")
        else:  # A: in 1.0 to 3.4 always count x 4 bytes
            rgba = c.take(4 * count, "the colours")
            if c.left():
                fail("BAD_COLOURS", "bytes after the colours")
        if group >= len(self.groups):
            fail("BAD_COLOURS", f"group {group} not read yet")
        if count != self.group_refs[group]:
            fail("BAD_COLOURS", f"{count} colours for {self.group_refs[group]} references")
        if count == 0 and not one:  # version 5: a group without references takes one colour (before: m >= 1)
            fail("BAD_COLOURS", "a count of 0 without its one colour")
        if one:  # reported expanded, as the per-reference form would be (SPEC_NOTES 28); count 0: the one
            colours = [list(rgba) for _ in range(max(count, 1))]
        else:
            colours = [list(rgba[4 * i:4 * i + 4]) for i in range(count)]
        # §10.1: the last cOLR of a group applies, listed where the group's first was
        for entry in self.colours:
            if entry["group"] == group:
                entry["rgba"] = colours
                break
        else:
            self.colours.append({"group": group, "rgba": colours})

    # §10.3 (added with that section, from its text)
    def meta(self, p: bytes):
        if self.chunks:
            fail("BAD_METADATA", "mETA after an OBJT, PLNS or GRUP")
        if b"\x00" not in p:
            fail("BAD_METADATA", "no 0x00 after the keyword")
        keyword, value = p.split(b"\x00", 1)
        if not 1 <= len(keyword) <= 79 or any(b < 0x21 or b > 0x7E for b in keyword):
            fail("BAD_METADATA", f"keyword {keyword!r}")
        try:
            text = value.decode("utf-8")
        except UnicodeDecodeError:
            fail("BAD_METADATA", "value not UTF-8")
        key = keyword.decode("ascii")
        if self.major >= 5 and key == "up_axis":  # §10.3: version 5 says it in the header
            fail("BAD_METADATA", "up_axis in a version 5 file")
        if key in self.metadata:
            fail("BAD_METADATA", f"{key} twice")
        if key in META_VALUES and text not in META_VALUES[key]:
            fail("BAD_METADATA", f"{key} = {text!r}")
        self.metadata[key] = text

    # §10.2
    def indx(self, p: bytes, offset: int):
        c = Cursor(p)
        if self.major >= 6:
            self.indx_v6(c)
            return
        count = c.u32("the index count")
        raw = c.take(16 * count, "the index entries")
        if c.left():
            fail("BAD_INDEX", "bytes after the entries")
        entries = [struct.unpack_from("<Q4sI", raw, 16 * i) for i in range(count)]
        lowest = 8 + 12 + self.phdr_length
        last = -1
        for off, ctype, ordinal in entries:
            if off < lowest or off >= offset:
                fail("BAD_INDEX", f"offset {off} outside [{lowest}, {offset})")
            if off <= last:
                fail("BAD_INDEX", "offsets do not increase")
            last = off
            if ctype not in (b"OBJT", b"PLNS", b"GRUP"):
                fail("BAD_INDEX", f"type {ctype!r}")
        if [tuple(e) for e in entries] != self.chunks:
            fail("BAD_INDEX", "entries do not match the chunks read")

    def indx_v6(self, c: Cursor):
        """§10.2, version 6: count, then per record of tag 1-3 its chunk's offset (summed from
        differences), its raw offset, its tag and its ordinal, which must be what was read."""
        count = c.varint("the index count")
        if 4 * count > c.left():
            fail("BAD_PAYLOAD", f"index count {count}, {c.left()} bytes of entries")
        entries, chunk = [], 0
        for _ in range(count):
            chunk += c.varint("an entry's chunk offset")
            entries.append((chunk, c.varint("an entry's raw offset"), c.u8("an entry's tag"),
                            c.varint("an entry's ordinal")))
        if c.left():
            fail("BAD_INDEX", "bytes after the entries")
        if entries != self.chunks:
            fail("BAD_INDEX", "entries do not match the records read")

    # §4.4 and A.1
    def pend(self, p: bytes):
        if self.major >= 3:
            if len(p) not in (0, 8):
                fail("BAD_PAYLOAD", f"PEND of {len(p)} bytes")
            if len(p) == 8:
                off = struct.unpack("<Q", p)[0]
                if off == 0 or off != self.index_offset:
                    fail("BAD_INDEX", f"PEND index offset {off}")
        else:
            if len(p) != 8:
                fail("BAD_PAYLOAD", f"version {self.major} PEND of {len(p)} bytes")
            off = struct.unpack("<Q", p)[0]
            if off != 0 and off != self.index_offset:  # SPEC_NOTES 3: 0 is accepted after an iNDX
                fail("BAD_INDEX", f"PEND index offset {off}")
        if self.counts is not None:
            got = {"planes": len(self.planes), "objects": len(self.objects), "groups": len(self.groups)}
            if got != self.counts:
                fail("COUNT_MISMATCH", f"header {self.counts}, file {got}")

    def result(self) -> dict:
        return {"header": self.header, "planes": self.planes, "objects": self.objects,
                "groups": self.groups, "colours": self.colours, "metadata": self.metadata,
                "findings": self.findings,
                "geometry": None}


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: plnspec.py FILE", file=sys.stderr)
        return 2
    with open(argv[1], "rb") as fh:
        data = fh.read()
    try:
        result = Reader(data).read()
    except PlnError as exc:
        print(json.dumps({"error": exc.code}))
        print(str(exc), file=sys.stderr)
        return 1
    print(json.dumps(result, allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
