"""Hostile .pln files, written from spec/pln.md: one function per attack class of issue 49, each
``make(size) -> bytes``, ``size`` scaling the work or memory the file asks of a reader.

A conforming reader ends every one of them in a result or its own error, within time and memory
that its limits bound (spec §12.4), not the product of the sizes the file declares. The bytes come
from ``tests/spec_files.py`` (written from the spec, importing nothing of planefmt), so a reader is
not checked against files its own encoder made. ``tests/test_hostile.py`` runs every class through
both readers under time and memory caps; ``bench/hostile.py`` prints what each costs at 10x the
sizes of the issue.

    python fuzz/hostile.py DIR [SCALE]     # writes every class at SCALE x its modest size
"""

from __future__ import annotations

import importlib.util
import math
import struct
import sys
import zlib
from collections.abc import Callable
from pathlib import Path

import brotli
import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _load_spec_files():
    spec = importlib.util.spec_from_file_location("spec_files", ROOT / "tests" / "spec_files.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


sf = _load_spec_files()
uv, zigzag = sf.uv, sf.zigzag

# §7.2: the cube x, y, z in [0, 1] as (nu, phi, h): +x, +y, -x, -y, +z, -z
CUBE = [(math.pi / 2, 0.0, 1.0), (math.pi / 2, math.pi / 2, 1.0), (math.pi / 2, math.pi, 0.0),
        (math.pi / 2, 1.5 * math.pi, 0.0), (0.0, 0.0, 1.0), (math.pi, 0.0, 0.0)]


# --- framing (§3 to §9.2, version 5) -------------------------------------------------------------

def v5(chunks: list[tuple[bytes, bytes]], minor: int = 0, coding: int = 1, header: bytes | None = None) -> bytes:
    """A version 5.minor file: PHDR (float64 planes unless ``coding``, or ``header`` as given), the
    chunks, PEND."""
    head = sf.phdr(5, minor, coding=coding) if header is None else header
    return (sf.SIGNATURE + sf.u32_chunk(b"PHDR", head) + b"".join(sf.varint_chunk(t, p) for t, p in chunks)
            + sf.varint_chunk(b"PEND", b""))


def compressed(raw: bytes, method: int) -> bytes:
    """§6: method, raw size, stored bytes."""
    stored = raw if method == 0 else zlib.compress(raw, 9) if method == 1 else brotli.compress(raw, quality=5)
    return bytes([method]) + uv(len(raw)) + stored


def plns(planes, first: int = 0, method: int = 0) -> bytes:
    """§7.1 in float64: ``planes`` a list of triplets or raw triplet bytes."""
    raw = planes if isinstance(planes, bytes) else b"".join(struct.pack("<3d", *p) for p in planes)
    return uv(first) + uv(len(raw) // 24) + compressed(raw, method)


def grup(index: int, kind: int, body: bytes, method: int = 0, obj: int = 0) -> bytes:
    """§9.1: the head, then ``body`` (the common body and kind data) compressed by ``method``."""
    return uv(index) + uv(obj) + bytes([kind]) + compressed(body, method)


def cube_file(groups: list[tuple[int, bytes]], planes=CUBE, minor: int = 0, method: int = 1) -> bytes:
    """One object, ``planes``, and groups (kind, body) numbered in order."""
    return v5([(b"OBJT", sf.objt(0)), (b"PLNS", plns(list(planes)))]
              + [(b"GRUP", grup(i, k, b, method)) for i, (k, b) in enumerate(groups)], minor)


def body(refs, data: bytes = b"", bounding=()) -> bytes:
    return sf.group_body(refs, bounding, data)


def explicit_flags(v: int) -> bytes:
    """§9.10: ``v`` corner flags, every corner explicit, the padding bits clear (§2.1)."""
    flags = bytearray(b"\xff" * ((v + 7) // 8))
    if v % 8:
        flags[-1] = (1 << (v % 8)) - 1
    return bytes(flags)


# --- a strip of explicit corners as a shell walk (§9.13) --------------------------------------

def strip_walk(t: int) -> bytes:
    """The kind data of a kind 9 walk of ``t`` free triangles along a strip, every corner explicit
    and new: a root (child across edge 1), then attached triangles with one child each across
    edges 1 and 2 in turn, the last none. About 5 bytes a triangle, which deflate shrinks ~1000x."""
    v = t + 2
    symbols = bytearray([2]) + bytes([4 * (1 + (j % 2)) for j in range(1, t - 1)]) + (b"\x00" if t > 1 else b"")
    if t == 1:
        symbols = bytearray([0])
    faces = b"\x01" + b"\x00" * (t - 1)
    residuals = [1] * v + [j % 2 for j in range(v)] + [0] * v  # x, then y, then z (§9.11)
    return (uv(v) + uv(t) + uv(3) + bytes(symbols) + b"\x00\x00\x00" + faces + explicit_flags(v)
            + b"\x00" + struct.pack("<4f", 0, 0, 0, 1) + b"".join(uv(zigzag(r)) for r in residuals))


# --- the classes of issue 49 ----------------------------------------------------------------------

def copies(n: int, t: int = 3394) -> bytes:
    """1: one walk of ``t`` triangles and ``n`` copies of it (kind 11, §9.15), ~17 bytes each:
    the output is (n + 1) t triangles."""
    groups = [(9, body([], strip_walk(t)))] + [(11, body([], uv(0)))] * n
    return cube_file(groups, planes=[], method=1)


def walk_open_edges(n: int) -> bytes:
    """2 (hash-agnostic part): a walk of ``n`` roots over three old corners each, every root
    leaving its three edges open, so that the open-edge structure holds 3n entries among few
    corners. The colliding variant of the issue targets each reader's own hash, which the spec does
    not give, so it is not written here."""
    rng = np.random.default_rng(n)
    v = 64
    first = v // 3
    escapes = [0, 0, 0] * first  # roots naming corners 0 .. 3 first - 1 anew
    named = 3 * first
    for _ in range(n):
        a, b, c = rng.choice(named, 3, replace=False)
        escapes += [named - int(a), named - int(b), named - int(c)]
    t = first + n
    flags = explicit_flags(named)
    residuals = [k for k in range(named)] + [k % 7 for k in range(named)] + [k % 5 for k in range(named)]
    data = (uv(named) + uv(t) + uv(len(escapes)) + b"\x00" * t + b"".join(uv(e) for e in escapes)
            + b"\x01" * t + flags + b"\x00" + struct.pack("<4f", 0, 0, 0, 1)
            + b"".join(uv(zigzag(r)) for r in residuals))
    return cube_file([(9, body([], data))], planes=[], method=1)


def tree_chain(n: int) -> bytes:
    """3: a tree (kind 2, §9.7) of ``n`` splits on one plane x <= 1, each inside the last: its IN
    leaf is the half-space x <= 1, reached by the same split n times, unbounded
    (``UNBOUNDED_POLYTOPE``). Deflated, 100,000 splits take ~400 bytes."""
    tokens = [2] * n + [0] + [1] * n
    return cube_file([(2, body([0], b"".join(uv(x) for x in [len(tokens)] + tokens)))], planes=CUBE[:1])


def tree_twice_in(n: int) -> bytes:
    """3: the smallest case of tree_chain, ``n`` ignored beyond 1: split on x <= 1 twice, IN."""
    return tree_chain(2)


def convex_needle(n: int) -> bytes:
    """4: a convex group (kind 0) of ``n`` + 2 planes, a prism of n sides 1e-5 across and 1 long
    in float32 (§7.2): merging vertices closer than a float32 plane's error leaves its faces with
    fewer than three vertices."""
    n = max(3, n)
    phi = np.linspace(0, 2 * np.pi, n, endpoint=False)
    sides = [(math.pi / 2, float(p), 5e-6) for p in phi]
    planes = sides + [(0.0, 0.0, 1.0), (math.pi, 0.0, 0.0)]
    head = sf.phdr(5, 0, coding=0)
    raw = b"".join(struct.pack("<3f", *p) for p in planes)
    block = uv(0) + uv(len(planes)) + compressed(raw, 0)
    return v5([(b"OBJT", sf.objt(0)), (b"PLNS", block), (b"GRUP", grup(0, 0, body(range(len(planes)))))],
              header=head)


def _deflated_zeros(size: int) -> bytes:
    """zlib of ``size`` zero bytes, fed 1 MiB at a time (the bench asks for gigabytes)."""
    z, piece, out = zlib.compressobj(9), bytes(1 << 20), []
    for at in range(0, size, 1 << 20):
        out.append(z.compress(piece[:min(1 << 20, size - at)]))
    return b"".join(out) + z.flush()


def zero_planes(n: int) -> bytes:
    """5: ``n`` zero planes (0, 0, 0: +z through the origin, each a valid triplet) in float32
    blocks of at most 2^24 planes, deflated at ~1000x, and no group."""
    chunks, first = [], 0
    while first < n:
        count = min(n - first, 1 << 24)
        stored = _deflated_zeros(12 * count)
        chunks.append((b"PLNS", uv(first) + uv(count) + b"\x01" + uv(12 * count) + stored))
        first += count
    return v5(chunks, coding=0)


def _near_ratio(raw_size: int, method: int) -> bytes:
    """Raw bytes of ``raw_size`` (float64 triplets of +z planes) that ``method`` compresses about
    500 to 1000 times: zeros with a plane of h = 1 every few thousand bytes."""
    count = raw_size // 24
    for every in (2048, 1024, 512, 256, 128, 64):
        # h = 1.0 (f64 bytes 6, 7: f0 3f) at random planes, judged on a 4 MiB sample
        sample = _sprinkled(min(count, 1 << 17), every)
        stored = zlib.compress(sample, 9) if method == 1 else brotli.compress(sample, quality=5)
        if len(sample) <= 700 * len(stored):
            break
    return _sprinkled(count, every)


def _sprinkled(count: int, every: int) -> bytes:
    raw = np.zeros(24 * count, dtype=np.uint8)
    at = 24 * np.random.default_rng(count).integers(0, count, max(1, count // every))
    raw[at + 22], raw[at + 23] = 0xF0, 0x3F
    return raw.tobytes()


def declared_stream(mib: int, method: int = 2) -> bytes:
    """6: a plane block whose Brotli (or deflate, ``method`` 1) stream declares ``mib`` MiB and
    inflates to it, within the ratio limit (§6: a reader holds at most raw size + 16 MiB)."""
    raw = _near_ratio(mib << 20, method)
    return v5([(b"PLNS", plns(raw, 0, method))])


def tiny_walk(t: int) -> bytes:
    """7: one deflated walk of ``t`` triangles, about 5 bytes each before deflate."""
    return cube_file([(9, body([], strip_walk(t)))], planes=[], method=1)


def marginal_open_cube(n: int = 0) -> bytes:
    """8: the cube without its -x plane, +x tilted by float32 rounding: closed, if at all, far away
    (readers disagreed: accept against UNBOUNDED_POLYTOPE)."""
    tilt = float(np.float32(math.pi / 2) - np.float32(2e-7))
    planes = [(tilt, 0.0, 1.0)] + CUBE[1:2] + CUBE[3:]
    return cube_file([(0, body(range(5)))], planes=planes)


def marginal_sliver(n: int = 0) -> bytes:
    """8: the cube squashed to 8.7e-8 in z (EMPTY_POLYTOPE against accepted)."""
    planes = CUBE[:4] + [(0.0, 0.0, 8.7e-8), CUBE[5]]
    return cube_file([(0, body(range(6)))], planes=planes)


def marginal_tiny_cube(n: int = 0) -> bytes:
    """8: the cube scaled to side 7e-102: valid by §9.4's relative criteria."""
    planes = [(nu, phi, h * 7e-102) for nu, phi, h in CUBE]
    return cube_file([(0, body(range(6)))], planes=planes)


def h_range_overflow(n: int = 0) -> bytes:
    """10: a quantized header (coding 2, §5, §7.3) whose h range [-1.7e308, 1.7e308] is finite but
    overflows when subtracted; the cube's planes coded in it."""
    head = bytes([5, 0, 0, 2, 8, 8, 8, 1]) + struct.pack("<dd", -1.7e308, 1.7e308) + struct.pack("<ff", math.nan, math.nan)
    codes = [(64, 0, 255), (64, 64, 255), (64, 128, 0), (64, 192, 0), (0, 0, 255), (128, 0, 0)]
    raw = b"".join(bytes(c) for c in codes)
    block = uv(0) + uv(6) + compressed(raw, 0)
    return v5([(b"OBJT", sf.objt(0)), (b"PLNS", block), (b"GRUP", grup(0, 0, body(range(6))))], header=head)


# --- classes found beyond the issue -------------------------------------------------------------

def cells_overlapping(n: int) -> bytes:
    """Cells (kind 1, §9.6): ``n`` cells, each the cube's six half-spaces: one cell n times, whose
    planes separate none of them (the tree a decoder builds may grow, §9.6's bound)."""
    cell = [2 * j for j in range(6)]
    data = uv(n) + uv(6) * n + b"".join(uv(e) for e in cell) * n
    return cube_file([(1, body(range(6), data))])


def patch_repeated_face(n: int) -> bytes:
    """Patches (kind 3, §9.8): the cube with its +z face reference repeated ``n`` times: one face
    per reference, n faces, from a body of ~n bytes that deflate shrinks ~1000x."""
    refs = list(range(5)) + [4] * n + [5]
    return cube_file([(3, body(refs))])


def patch_repeated_polygon(n: int, k: int | None = None) -> bytes:
    """Patches (kind 3, §9.8, §12.4): a prism of ``n`` sides, its +z face (n - 2 triangles) given
    ``k`` (default n) times: k (n - 2) triangles from n + k + 2 references, quadratic in the body
    (n = 3000: 9 M triangles from 72 kB), which a reader counts before making them."""
    k = n if k is None else k
    phi = np.linspace(0, 2 * np.pi, n, endpoint=False)
    planes = [(math.pi / 2, float(p), 1.0) for p in phi] + [(0.0, 0.0, 1.0), (math.pi, 0.0, 1.0)]
    return cube_file([(3, body(list(range(n + 1)) + [n] * (k - 1) + [n + 1]))], planes=planes)


def sealed_many(t: int) -> bytes:
    """Sealed (kind 5, §9.9): the cube's 8 vertices and ``t`` triangles over them, deflated."""
    # local references +x 0, +y 1, -x 2, -y 3, +z 4, -z 5; corners z = 0 first, then z = 1
    verts = [(2, 3, 5), (0, 3, 5), (0, 1, 5), (2, 1, 5), (2, 3, 4), (0, 3, 4), (0, 1, 4), (2, 1, 4)]
    tris = [(4, 4, 5, 6)] + [(0, 4, 6, 7)] * (t - 1) + [(0, 0, 1, 2), (0, 0, 2, 3)]
    data = (uv(8) + b"".join(uv(x) for v in verts for x in v) + uv(len(tris))
            + b"".join(uv(d) + uv(a) + uv(b) + uv(c) for d, a, b, c in tris))
    return cube_file([(5, body(range(6), data))])


def shell_many(t: int) -> bytes:
    """Shells (kind 6, §9.10): ``t`` free triangles over explicit corners, deflated."""
    v = t + 2
    flags = explicit_flags(v)
    coords = b"".join(uv(zigzag(1)) + uv(zigzag(k % 2 * 2 - 1)) + uv(0) for k in range(v))
    corners = uv(0) * 3 + b"".join(uv(2) + uv(1) + uv(0) for _ in range(t - 1))
    data = uv(v) + uv(t) + uv(t) + flags + struct.pack("<4f", 0, 0, 0, 1) + coords + corners
    return cube_file([(6, body([], data))], planes=[])


def shell_tree_chain(t: int, kind: int = 7) -> bytes:
    """Shell trees (kinds 7, 8, §9.11, §9.12): ``t`` triangles, each attached to edge 1 of the
    one before (a parent chain t long), every corner explicit."""
    v = t + 2
    links = b"\x00" + uv(2) * (t - 1)
    codes = b"\x00\x00\x00" + b"\x00" * (t - 1)
    faces = b"\x01" + b"\x00" * (t - 1)
    flags = explicit_flags(v)
    residuals = [1] * v + [k % 2 for k in range(v)] + [0] * v
    data = (uv(v) + uv(t) + links + codes + faces + flags + struct.pack("<4f", 0, 0, 0, 1)
            + b"".join(uv(zigzag(r)) for r in residuals))
    return cube_file([(kind, body([], data))], planes=[])


def object_chain(n: int) -> bytes:
    """Objects (§8): ``n`` objects, each the child of the one before and translated by 1 in x, the
    cube's convex group in the last: a transform chain n deep."""
    translate = bytes([0b01000001, 0b00000100, 0b00010000])  # codes 1 (1.0) on m00, m03, m11, m22 (§8)
    objs = [(b"OBJT", uv(k) + uv(k) + b"\x01" + uv(1) + b"o" + translate) for k in range(n)]
    return v5(objs + [(b"PLNS", plns(CUBE)), (b"GRUP", grup(0, 0, body(range(6)), obj=n - 1))])


def copies_in_objects(n: int) -> bytes:
    """Objects and copies: ``n`` root objects, each with a copy of one 3,394-triangle walk."""
    chunks = [(b"OBJT", sf.objt(k)) for k in range(n)]
    chunks.append((b"GRUP", grup(0, 9, body([], strip_walk(3394)), 1)))
    chunks += [(b"GRUP", grup(k, 11, body([], uv(0)), obj=k)) for k in range(1, n)]
    return v5(chunks)


def colour_expansion(n: int, refs: int = 1 << 20) -> bytes:
    """Colours (§10.1): a patch of ``refs`` references, then ``n`` one-colour cOLR chunks of 12
    bytes for it, each standing for refs colours."""
    rs = list(range(5)) + [4] * (refs - 6) + [5]
    colour = struct.pack("<II", 0, refs) + b"\xc8\x1e\x28\xff"
    return v5([(b"OBJT", sf.objt(0)), (b"PLNS", plns(CUBE)), (b"GRUP", grup(0, 3, body(rs), 1))]
              + [(b"cOLR", colour)] * n)


def metadata_many(n: int) -> bytes:
    """Metadata (§10.3): ``n`` mETA chunks of distinct keywords before the cube."""
    metas = [(b"mETA", b"k%d\x00v" % k) for k in range(n)]
    return v5(metas + [(b"OBJT", sf.objt(0)), (b"PLNS", plns(CUBE)), (b"GRUP", grup(0, 0, body(range(6))))])


def index_anywhere(n: int) -> bytes:
    """Index (§10.2, §4.4): the cube with an iNDX of ``n`` entries, each pointing at the PHDR, and a
    PEND that points at it (``BAD_INDEX``; a reader seeking by it must not follow it)."""
    chunks = [(b"OBJT", sf.objt(0)), (b"PLNS", plns(CUBE)), (b"GRUP", grup(0, 0, body(range(6))))]
    data = v5(chunks)[:-len(sf.varint_chunk(b"PEND", b""))]
    entries = struct.pack("<I", n) + (struct.pack("<Q", 8) + b"GRUP" + struct.pack("<I", 0)) * n
    at = len(data)
    return data + sf.varint_chunk(b"iNDX", entries) + sf.varint_chunk(b"PEND", struct.pack("<Q", at))


def varint_edges(n: int) -> bytes:
    """Varints (§2.2): ``n`` groups whose ref_count is the largest 10-byte varint, 2^64 - 1, and one
    of 2^63 (``LIMIT_EXCEEDED`` before anything is allocated), after the cube."""
    big = b"\xff" * 9 + b"\x01"
    groups = [(b"GRUP", grup(0, 0, body(range(6))))]
    groups += [(b"GRUP", grup(k, 0, big)) for k in range(1, n + 1)]
    return v5([(b"OBJT", sf.objt(0)), (b"PLNS", plns(CUBE))] + groups)


def predicted_planes(n: int) -> bytes:
    """Nested ratio (§7.4 inside §6): ``n`` planes in the predicted coding, three one-byte varints
    each, deflated ~1000x: one stored byte stands for ~300 planes, 7 kB of float64."""
    head = bytes([5, 0, 0, 3, 8, 8, 8, 1]) + struct.pack("<dd", 0.0, 1.0) + struct.pack("<ff", math.nan, math.nan)
    chunks, first = [], 0
    while first < n:
        count = min(n - first, 1 << 24)
        chunks.append((b"PLNS", uv(first) + uv(count) + compressed(bytes(3 * count), 1)))
        first += count
    return v5(chunks, header=head)


def many_chunks(n: int) -> bytes:
    """Framing (§4.2): ``n`` empty unknown ancillary chunks (9 bytes each) before the cube."""
    return v5([(b"tEXt", b"")] * n + [(b"OBJT", sf.objt(0)), (b"PLNS", plns(CUBE)),
                                       (b"GRUP", grup(0, 0, body(range(6))))])


#: name -> (make, the modest size the test suite runs, the size bench/hostile.py runs: 10x the
#: issue's, except 256 MiB for a declared stream, the largest raw size within the default limits).
#: Names say the issue's item (``i1_`` ...) or ``x_`` for a class found beyond it.
CLASSES: dict[str, tuple[Callable[[int], bytes], int, int]] = {
    "i1_copies": (copies, 100, 50_000),  # the 5,000 copies
    # the 100,000 colliding edges: 333,334 roots leave 1,000,002 open
    "i2_walk_open_edges": (walk_open_edges, 10_000, 333_334),
    "i3_tree_chain": (tree_chain, 2_000, 1_000_000),
    "i3_tree_twice_in": (tree_twice_in, 2, 2),
    "i4_convex_needle": (convex_needle, 3, 80),
    "i5_zero_planes": (zero_planes, 1 << 20, 220_000_000),
    "i6_brotli_declared": (declared_stream, 16, 256),
    "i6_deflate_declared": (lambda mib: declared_stream(mib, 1), 16, 256),
    "i7_tiny_walk": (tiny_walk, 100_000, 10_000_000),
    "i8_open_cube": (marginal_open_cube, 0, 0),
    "i8_sliver": (marginal_sliver, 0, 0),
    "i8_tiny_cube": (marginal_tiny_cube, 0, 0),
    "i10_h_range_overflow": (h_range_overflow, 0, 0),
    "x_cells_overlapping": (cells_overlapping, 200, 20_000),
    "x_patch_repeated_face": (patch_repeated_face, 10_000, 1_000_000),
    "x_patch_repeated_polygon": (patch_repeated_polygon, 300, 3_000),
    "x_sealed_many": (sealed_many, 100_000, 10_000_000),
    "x_shell_many": (shell_many, 100_000, 10_000_000),
    "x_shell_tree_chain": (shell_tree_chain, 100_000, 10_000_000),
    "x_shell_tree_chain_kind8": (lambda t: shell_tree_chain(t, 8), 100_000, 10_000_000),
    "x_object_chain": (object_chain, 2_000, 200_000),
    "x_copies_in_objects": (copies_in_objects, 100, 10_000),
    "x_colour_expansion": (colour_expansion, 20, 2_000),
    "x_metadata_many": (metadata_many, 10_000, 1_000_000),
    "x_index_anywhere": (index_anywhere, 10_000, 1_000_000),
    "x_varint_edges": (varint_edges, 100, 10_000),
    "x_predicted_planes": (predicted_planes, 1 << 20, 100_000_000),
    "x_many_chunks": (many_chunks, 100_000, 10_000_000),
}


def main(argv: list[str]) -> None:
    dest = Path(argv[1] if len(argv) > 1 else "hostile")
    scale = float(argv[2]) if len(argv) > 2 else 1.0
    dest.mkdir(parents=True, exist_ok=True)
    for name, (make, modest, _) in CLASSES.items():
        data = make(max(1, int(modest * scale)) if modest else 0)
        (dest / f"{name}.pln").write_bytes(data)
        print(f"{name}: {len(data):,} bytes")


if __name__ == "__main__":
    main(sys.argv)
