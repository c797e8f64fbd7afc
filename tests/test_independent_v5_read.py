"""Version 5.0 (spec/pln.md §4.1, §5, §9.2, §9.10, §10.1) in the independent reader
conformance/independent/plnread.py, on hand-built files: the points the version 5.0 goldens do not
decide. Every file is assembled from the text of the spec (§3 signature, §4.1 framing: PHDR's u32
length, then varint32 lengths; §5 the 8-byte fixed header; §8 objects; §9.1-§9.2 groups; §9.10 a
shell of explicit corners and free triangles on an f32 grid), not from planefmt nor the suite's
generator: a length varint of two bytes, read from a file and from a pipe; the framing checks in the
order of §4.1; the ignored bits 6-7 of the units byte; and m = 0 by kind and version."""

from __future__ import annotations

import importlib.util
import io
import json
import math
import struct
import subprocess
import sys
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PLNREAD = ROOT / "conformance" / "independent" / "plnread.py"


def _load_plnread():
    spec = importlib.util.spec_from_file_location("plnread_v5", PLNREAD)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


plnread = _load_plnread()

SIGNATURE = bytes([0x89, 0x50, 0x4C, 0x4E, 0x0D, 0x0A, 0x1A, 0x0A])


def uv(v: int) -> bytes:
    """§2.2: unsigned LEB128, minimal."""
    out = bytearray()
    while v >= 0x80:
        out.append((v & 0x7F) | 0x80)
        v >>= 7
    out.append(v)
    return bytes(out)


def zz(d: int) -> int:
    return 2 * d if d >= 0 else -2 * d - 1


def crc(tag: bytes, payload: bytes) -> bytes:
    return struct.pack("<I", zlib.crc32(tag + payload))


def chunk4(tag: bytes, payload: bytes) -> bytes:
    """§4.1 with a u32 length: PHDR in every version, every chunk before version 5."""
    return tag + struct.pack("<I", len(payload)) + payload + crc(tag, payload)


def chunk5(tag: bytes, payload: bytes, length: bytes | None = None) -> bytes:
    """§4.1, version 5, a chunk after PHDR: its length a varint32 (or the bytes given)."""
    return tag + (uv(len(payload)) if length is None else length) + payload + crc(tag, payload)


def header(major=5, minor=0, units=1) -> bytes:
    """§5: version 5's 8-byte fixed part (flags a u8: none; coding 0; widths 0; units), then
    tolerance and error bound NaN; version 4's 9-byte one (flags a u16) for major 4."""
    flags = b"\x00" if major >= 5 else b"\x00\x00"
    p = bytes([major, minor]) + flags + bytes([0, 0, 0, 0, units]) + struct.pack("<ff", math.nan, math.nan)
    return chunk4(b"PHDR", p)


def obj(name: str = "o") -> bytes:
    """§8: index 0, a root, no transform."""
    return uv(0) + uv(0) + b"\x00" + uv(len(name.encode())) + name.encode()


def group(index: int, kind: int, body: bytes) -> bytes:
    """§9.1: index, object 0, kind, method 0, raw size, body."""
    return uv(index) + uv(0) + bytes([kind, 0]) + uv(len(body)) + body


# §9.10, version 5: a shell without references (m = 0, no roles): three explicit corners on an f32
# grid (origin 0.1, 0, 0, step 0.5), one free triangle
ORIGIN = struct.unpack("<f", struct.pack("<f", 0.1))[0]
PLANELESS_SHELL = (uv(0) + uv(3) + uv(1) + uv(1) + bytes([0b111]) + struct.pack("<4f", 0.1, 0.0, 0.0, 0.5)
                   + b"".join(uv(zz(d)) for d in (0, 0, 0, 1, 0, 0, -1, 1, 0)) + uv(0) + uv(0) + uv(0))


def v5_file(*chunks: tuple[bytes, bytes], units=1, minor=0) -> bytes:
    return (SIGNATURE + header(5, minor, units) + b"".join(chunk5(t, p) for t, p in chunks)
            + chunk5(b"PEND", b""))


def read(data: bytes):
    reader = plnread.Reader(io.BytesIO(data), len(data))
    try:
        reader.read()
    except plnread.PlnError as exc:
        return {"error": exc.code, "why": exc.message}
    return json.loads(json.dumps(reader.result()))


def read_pipe(data: bytes):
    """As the runner calls it through a pipe: no size, the varints read a byte at a time."""
    proc = subprocess.run([sys.executable, str(PLNREAD), "/dev/stdin"], input=data, capture_output=True,
                          timeout=120)
    out = json.loads(proc.stdout)
    assert (proc.returncode == 0) == ("error" not in out), proc.stderr
    return out


def test_two_byte_length_varint_from_a_file_and_a_pipe():
    name = "n" * 200  # an OBJT payload of 205 bytes: its length the varint CD 01
    data = v5_file((b"OBJT", obj(name)), (b"GRUP", group(0, 6, PLANELESS_SHELL)))
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
    got = read(v5_file((b"OBJT", obj()), units=0xC1 | (2 << 4)))
    assert got["header"]["units"] == 1 and got["metadata"] == {"up_axis": "Z"}
    got = read(v5_file((b"OBJT", obj()), units=0xC1))
    assert got["header"]["units"] == 1 and got["metadata"] == {}
    assert read(v5_file((b"OBJT", obj()), units=8))["error"] == "BAD_HEADER_VALUE"


def test_no_references_by_kind_and_version():
    # a copy of a shell without references has none either (§9.2, §9.15)
    copy = uv(0) + uv(0)  # m = 0, source 0
    got = read(v5_file((b"OBJT", obj()), (b"GRUP", group(0, 6, PLANELESS_SHELL)), (b"GRUP", group(1, 11, copy))))
    assert got["groups"][1] == {"index": 1, "object": 0, "kind": 11, "refs": [], "bounding": [], "source": 0}
    # kinds 0 to 5 need one (kind 5 here; kind 0 is xv50_convex_no_refs)
    assert read(v5_file((b"OBJT", obj()), (b"GRUP", group(0, 5, uv(0)))))["error"] == "BAD_GROUP_STRUCTURE"
    # a kind of a newer minor version (13 in 5.2) decides for itself: skipped, m = 0 accepted
    got = read(v5_file((b"OBJT", obj()), (b"GRUP", group(0, 13, uv(0) + b"\x2a")), minor=2))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and got["groups"][0]["refs"] == []
    # before version 5 every group has one (Appendix A.5), a shell of 4.2 too
    old = (SIGNATURE + header(4, 2) + chunk4(b"OBJT", obj()) + chunk4(b"GRUP", group(0, 6, PLANELESS_SHELL))
           + chunk4(b"PEND", b""))
    assert read(old)["error"] == "BAD_GROUP_STRUCTURE"
