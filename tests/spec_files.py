""".pln bytes built from the words of spec/pln.md, for the tests of the independent readers
conformance/independent/plnspec.py and plnread.py: varints, chunks, headers, one-object files, the
shell walk of §9.13 with its kind data, a few meshes, and the two readers run on bytes.

Written from spec/pln.md alone, like the tests' own encoders, and importing nothing of planefmt: a
file the readers agree on must not come from the code they are checked against."""

from __future__ import annotations

import importlib.util
import io
import itertools
import json
import math
import struct
import subprocess
import sys
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SUITE = ROOT / "conformance"
PLNREAD = SUITE / "independent" / "plnread.py"


def _load(name):
    # by path: conformance/ is a folder of the repository, not an installed package
    spec = importlib.util.spec_from_file_location(name, SUITE / "independent" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


plnspec = _load("plnspec")
plnread = _load("plnread")


# --- reading ------------------------------------------------------------------------------------

def read_spec(data: bytes) -> dict:
    """plnspec's result, or its error code and reason."""
    try:
        return plnspec.Reader(data).read()
    except plnspec.PlnError as exc:
        return {"error": exc.code, "why": str(exc)}


def read_read(data: bytes) -> dict:
    """plnread in process, on a stream that says its size (as a regular file does): its result as
    its command line prints it (JSON), or its error code and reason."""
    reader = plnread.Reader(io.BytesIO(data), len(data))
    try:
        reader.read()
    except plnread.PlnError as exc:
        return {"error": exc.code, "why": exc.message}
    return json.loads(json.dumps(reader.result()))


def read_pipe(data: bytes) -> dict:
    """plnread as the runner calls it, its input a pipe (no size, no seeking back)."""
    # timeout: a hang guard far above normal (a file takes under 3 s on a loaded machine)
    proc = subprocess.run([sys.executable, str(PLNREAD), "/dev/stdin"], input=data, capture_output=True,
                          timeout=120)
    out = json.loads(proc.stdout)
    assert (proc.returncode == 0) == ("error" not in out), proc.stderr
    return out


# --- bytes (§2 to §9.2) -------------------------------------------------------------------------

SIGNATURE = b"\x89PLN\r\n\x1a\n"


def uv(v: int) -> bytes:
    """§2.2: unsigned LEB128, minimal."""
    assert v >= 0
    out = bytearray()
    while v >= 0x80:
        out.append(0x80 | (v & 0x7F))
        v >>= 7
    out.append(v)
    return bytes(out)


def zigzag(d: int) -> int:
    """§2.2: signed to unsigned, 0, -1, 1, -2, … as 0, 1, 2, 3, …"""
    return 2 * d if d >= 0 else -2 * d - 1


def _crc(ctype: bytes, payload: bytes) -> bytes:
    return struct.pack("<I", zlib.crc32(ctype + payload))


def u32_chunk(ctype: bytes, payload: bytes) -> bytes:
    """§4.1 with a u32 length: PHDR in every version, every chunk before version 5."""
    return ctype + struct.pack("<I", len(payload)) + payload + _crc(ctype, payload)


def varint_chunk(ctype: bytes, payload: bytes, length: bytes | None = None) -> bytes:
    """§4.1, version 5, a chunk after PHDR: its length a varint32 (``length``: other bytes in its place)."""
    return ctype + (uv(len(payload)) if length is None else length) + payload + _crc(ctype, payload)


def phdr(major=5, minor=0, flags=0, coding=0, units=1, up=0, counts=None) -> bytes:
    """§5 (version 5: flags a u8, the up axis in bits 4-5 of units) or A.5 (before it: flags a u16);
    widths 0, tolerance and error bound NaN, then the counts (COUNTS_KNOWN) if given."""
    if counts is not None:
        flags |= 2
    if major >= 5:
        p = bytes([major, minor, flags, coding, 0, 0, 0, units | up << 4])
    else:
        p = bytes([major, minor]) + struct.pack("<HB3BB", flags, coding, 0, 0, 0, units | up << 4)
    p += struct.pack("<ff", math.nan, math.nan)
    if counts is not None:
        p += b"".join(uv(n) for n in counts)
    return p


def plns(planes, coding: int) -> bytes:
    """§7.1: the first index 0, the count, method 0 (stored), the raw size, then the planes in
    float32 (coding 0) or float64 (coding 1), §7.2."""
    raw = b"".join(struct.pack("<3f" if coding == 0 else "<3d", *p) for p in planes)
    return uv(0) + uv(len(planes)) + b"\x00" + uv(len(raw)) + raw


def objt(index: int, name: bytes = b"o") -> bytes:
    """§8: a root object without a transform."""
    return uv(index) + uv(0) + b"\x00" + uv(len(name)) + name


def group_body(refs, bounding, data: bytes) -> bytes:
    """§9.2: ref_count, the references as differences, the role bits (``bounding``: the places of
    the bounding references), the kind data."""
    refs = list(refs)
    roles = bytearray((len(refs) + 7) // 8)
    for i in bounding:
        roles[i >> 3] |= 1 << (i & 7)
    return uv(len(refs)) + b"".join(uv(r - p) for p, r in zip([0] + refs, refs)) + bytes(roles) + data


def grup(index: int, obj: int, kind: int, body: bytes, method: int = 0) -> bytes:
    """§9.1: index, object, kind, compression, raw size, then the body, stored (method 0) or
    deflated (method 1, §6)."""
    stored = zlib.compress(body, 9) if method == 1 else body
    return uv(index) + uv(obj) + bytes([kind, method]) + uv(len(body)) + stored


def pln_file(groups, planes=(), *, major, minor, units=1, name=b"o") -> bytes:
    """A version major.minor file of one object and ``groups`` (kind, refs, bounding, kind data),
    stored. The planes, if any, float32 where every value is one (the goldens', whose float32 pi is
    above binary64's), else float64."""
    coding = 0 if all(struct.unpack("<f", struct.pack("<f", x))[0] == x for p in planes for x in p) else 1
    frame = varint_chunk if major >= 5 else u32_chunk
    out = SIGNATURE + u32_chunk(b"PHDR", phdr(major, minor, coding=coding, units=units))
    if planes:
        out += frame(b"PLNS", plns(planes, coding))
    out += frame(b"OBJT", objt(0, name))
    for index, (kind, refs, bounding, data) in enumerate(groups):
        out += frame(b"GRUP", grup(index, 0, kind, group_body(refs, bounding, data)))
    return out + frame(b"PEND", b"")


# --- the walk (§9.13) ---------------------------------------------------------------------------

def _ordered_lists(free):
    """The ordered lists of distinct free edges: by length, then lexicographically by the edges'
    places among the free edges."""
    return [tuple(free[i] for i in p) for n in range(len(free) + 1)
            for p in itertools.permutations(range(len(free)), n)]


ROOT_LISTS = _ordered_lists((0, 1, 2))
ATTACHED_LISTS = _ordered_lists((1, 2))
assert len(ROOT_LISTS) == 16 and len(ATTACHED_LISTS) == 5


class OpenEdges:
    """§9.13's open edges word for word, a list of directed edges in order of entry searched from
    its newest end, against which the readers' constant-time structures are checked."""

    def __init__(self):
        self.items = []

    def add(self, tri):
        for s in range(3):
            a, b = tri[s], tri[(s + 1) % 3]
            for k in range(len(self.items) - 1, -1, -1):
                if self.items[k] == (b, a):
                    del self.items[k]
                    break
            else:
                self.items.append((a, b))

    def left(self, i1, x):
        starts = [a for a, b in self.items[::-1] if b == i1]
        if starts and starts[0] == x:
            starts = starts[1:]
        return starts[0] if starts else None

    def right(self, i0, x):
        ends = [b for a, b in self.items[::-1] if a == i0]
        if ends and ends[0] == x:
            ends = ends[1:]
        return ends[0] if ends else None


class Walk:
    """A depth-first walk over a triangle list (source corner ids), with the symbols and escapes
    that code it. A triangle's children are, across each free edge in a random order, the first
    unclaimed triangle with the reverse edge; with ``path``, only the first of those in the order of
    its free edges, so that the walk goes on along a strip as far as it can. With
    ``rotate_roots``, each root starts at a random corner, else as its source triangle lists it.
    Attributes: tris (walk order, corners numbered as the walk names them), parent ((p, e) or None
    per triangle), new (per triangle, the corners its codes 0 name), creator (corner -> the
    triangle that named it), source (walk triangle -> source triangle), number (source corner ->
    corner number)."""

    def __init__(self, tris, rng, escape_rate=0.0, rotate_roots=True, path=False):
        by_edge = {}
        for t, tri in enumerate(tris):
            for s in range(3):
                by_edge.setdefault((tri[s], tri[(s + 1) % 3]), []).append(t)
        claimed = [False] * len(tris)
        self.tris, self.parent, self.source, self.new, self.creator = [], [], [], [], {}
        self.symbols, self.escapes = [], []
        self.number = {}
        opened = OpenEdges()
        stack = []
        unwalked = iter(range(len(tris)))
        while len(self.tris) < len(tris):
            j = len(self.tris)
            named = []
            if stack:
                p, e, t = stack.pop()
                q = self.tris[p]
                i0, i1, x = q[(e + 1) % 3], q[e], q[(e + 2) % 3]
                src = tris[t]
                r = next(r for r in range(3)
                         if (self.number.get(src[r]), self.number.get(src[(r + 1) % 3])) == (i0, i1))
                rot = [src[r], src[(r + 1) % 3], src[(r + 2) % 3]]
                if rot[2] not in self.number:
                    code = 0
                    self.number[rot[2]] = len(self.number)
                    named.append(self.number[rot[2]])
                else:
                    w = self.number[rot[2]]
                    if opened.left(i1, x) == w and rng.random() >= escape_rate:
                        code = 1
                    elif opened.right(i0, x) == w and rng.random() >= escape_rate:
                        code = 2
                    else:
                        code = 3 + zigzag(w - i1)
                corners = [i0, i1, self.number[rot[2]]]
                self.parent.append((p, e))
                free = (1, 2)
            else:
                t = next(u for u in unwalked if not claimed[u])
                shift = rng.randrange(3) if rotate_roots else 0
                rot = list(tris[t][shift:]) + list(tris[t][:shift])
                corners, codes = [], []
                for v in rot:
                    if v not in self.number:
                        codes.append(0)
                        self.number[v] = len(self.number)
                        named.append(self.number[v])
                    else:
                        codes.append(len(self.number) - self.number[v])
                    corners.append(self.number[v])
                self.parent.append(None)
                free = (0, 1, 2)
                code = None
            claimed[t] = True
            self.tris.append(corners)
            self.source.append(t)
            self.new.append(named)
            self.creator.update((k, j) for k in named)
            kids = []
            for e in free if path else rng.sample(free, len(free)):
                a, b = rot[e], rot[(e + 1) % 3]
                for u in by_edge.get((b, a), []):
                    if not claimed[u]:
                        claimed[u] = True
                        kids.append((e, u))
                        break
                if path and kids:
                    break
            edges = tuple(e for e, _ in kids)
            if code is None:
                self.symbols.append(ROOT_LISTS.index(edges))
                self.escapes += codes
            else:
                self.symbols.append(4 * ATTACHED_LISTS.index(edges) + min(code, 3))
                if code >= 3:
                    self.escapes.append(code - 3)
            opened.add(corners)
            for e, u in kids[::-1]:
                stack.append((j, e, u))
        assert not stack


def walk_head(walk, faces, explicit_xyz, named_planes):
    """§9.13's kind data up to and including the picks. faces: per source triangle, a local
    reference or -1; explicit_xyz: source corner -> integer coordinates; named_planes: source
    corner -> its three planes (a subset of its face planes, ascending). Returns the bytes and the
    "shell" a reader reports, its origin and step None until a grid follows."""
    v = len(walk.number)
    src = {k: s for s, k in walk.number.items()}
    wfaces = [faces[t] for t in walk.source]
    codes = []
    for j, f in enumerate(wfaces):
        if walk.parent[j] is not None:
            inherit = wfaces[walk.parent[j][0]]
        else:
            inherit = wfaces[j - 1] if j else -1
        codes.append(0 if f == inherit else 1 if f < 0 else f + 2)
    explicit = [k for k in range(v) if src[k] in explicit_xyz]
    flags = bytearray((v + 7) // 8)
    for k in explicit:
        flags[k // 8] |= 1 << (k % 8)
    on = {k: set() for k in range(v)}
    for tri, f in zip(walk.tris, wfaces):
        if f >= 0:
            for k in tri:
                on[k].add(f)
    picks, vertex_planes = [], []
    for k in range(v):
        if src[k] in explicit_xyz:
            continue
        planes = sorted(on[k])
        chosen = named_planes[src[k]]
        vertex_planes.append(list(chosen))
        if len(planes) > 3:
            picks += [planes.index(p) for p in chosen]
    data = uv(v) + uv(len(walk.tris)) + uv(len(walk.escapes))
    data += b"".join(uv(s) for s in walk.symbols) + b"".join(uv(x) for x in walk.escapes)
    data += b"".join(uv(c) for c in codes) + bytes(flags) + b"".join(uv(p) for p in picks)
    shell = {"explicit": explicit, "vertex_planes": vertex_planes,
             "grid": [list(explicit_xyz[src[k]]) for k in explicit], "origin": None, "step": None,
             "facets": [[f] + t for f, t in zip(wfaces, walk.tris)]}
    return data, shell


def table_bytes(tables) -> bytes:
    """§9.13: per axis a count, the first value (zigzag), then each gap less one."""
    return b"".join(uv(len(vals)) + uv(zigzag(vals[0])) + b"".join(uv(y - x - 1) for x, y in zip(vals, vals[1:]))
                    for vals in tables)


def residual_bytes(residuals) -> bytes:
    """§9.13: zigzag residuals, every corner's x, then every y, then every z."""
    return b"".join(uv(zigzag(r[a])) for a in range(3) for r in residuals)


class CodedWalk(Walk):
    """A walk, its roots as their source triangles list them, and its kind data: ``head`` to the
    picks, then the mode, the grid and the residuals of ``predict``'s prediction, here §9.13's (a
    kind of its own overrides it). tris, faces, xyz, planes as walk_head takes them."""

    kind = 9
    grid = (0.5, -1.0, 2.0, 0.125)
    grid_format = "<4d"  # §9.11: four f64 before version 5, four f32 ("<4f") in it

    def __init__(self, tris, faces, xyz, planes, rng, escape_rate=0.0, path=False):
        super().__init__(tris, rng, escape_rate, rotate_roots=False, path=path)
        self.head, self.head_shell = walk_head(self, faces, xyz, planes)
        self.explicit = self.head_shell["explicit"]
        self.coords = dict(zip(self.explicit, self.head_shell["grid"]))
        self.flags = [1 if c in self.coords else 0 for c in range(len(self.number))]

    def step_source(self, k):
        """The step source p(k): §9.11's predictor, i0 of the triangle that named k where that is
        attached and i0 explicit, else the previous explicit corner, else None."""
        j = self.creator[k]
        if self.parent[j] is not None and self.flags[self.tris[j][0]]:
            return self.tris[j][0]
        before = [c for c in self.explicit if c < k]
        return before[-1] if before else None

    def predict(self, k, g, mode, kind):
        """The prediction of explicit corner k from g (resolved values of the corners below k):
        with mode bit 0 §9.12's parallelogram where its corners are explicit, else §9.11's."""
        j = self.creator[k]
        tri = self.tris[j]
        if mode & 1 and self.parent[j] is not None:  # §9.12
            p, e = self.parent[j]
            o = self.tris[p][(e + 2) % 3]
            if self.flags[tri[0]] and self.flags[tri[1]] and self.flags[o]:
                return [g[tri[0]][x] + g[tri[1]][x] - g[o][x] for x in range(3)]
        a = self.step_source(k)
        return [0, 0, 0] if a is None else list(g[a])

    def tables(self):
        return [sorted({self.coords[c][x] for c in self.explicit}) for x in range(3)]

    def values(self, mode):
        """g: the coordinates, or with tables the indices into each axis's table."""
        if mode & 2:
            t = self.tables()
            return {c: [t[x].index(self.coords[c][x]) for x in range(3)] for c in self.explicit}
        return {c: list(self.coords[c]) for c in self.explicit}

    def residuals(self, mode, kind=None, g=None):
        """The residuals of values g (by default the coordinates' values) in a body of ``kind``
        (by default the walk's)."""
        kind = self.kind if kind is None else kind
        g = self.values(mode) if g is None else g
        return {k: [g[k][x] - p for x, p in enumerate(self.predict(k, g, mode, kind))] for k in self.explicit}

    def resolve(self, residuals, mode, kind=None):
        """The values a reader of ``kind`` (by default the walk's) resolves from residuals, unchecked."""
        kind = self.kind if kind is None else kind
        g = {}
        for k in self.explicit:
            g[k] = [p + r for p, r in zip(self.predict(k, g, mode, kind), residuals[k])]
        return g

    def body(self, mode, kind=None, residuals=None, tables=None):
        """The kind data: the head, then where a corner is explicit the mode, the grid, the tables
        (mode bit 1) and the residuals, each by default the encoder's."""
        if not self.explicit:
            return self.head
        if residuals is None:
            residuals = self.residuals(mode, kind)
        data = self.head + bytes([mode]) + struct.pack(self.grid_format, *self.grid)
        if mode & 2:
            data += table_bytes(tables or self.tables())
        return data + residual_bytes([residuals[k] for k in self.explicit])

    def shell(self):
        """The "shell" a reader reports for body()."""
        shell = dict(self.head_shell)
        if self.explicit:
            shell["origin"], shell["step"] = list(self.grid[:3]), self.grid[3]
        return shell


# --- meshes -------------------------------------------------------------------------------------

def golden_shell(name):
    """The planes, the shell group and the mesh (triangles, faces, explicit corners' coordinates,
    named corners' planes) of conformance/valid/``name``.json."""
    d = json.loads((SUITE / "valid" / f"{name}.json").read_text())
    g = next(g for g in d["groups"] if "shell" in g)
    sh = g["shell"]
    xyz = dict(zip(sh["explicit"], sh["grid"]))
    named = [c for c in range(len(xyz) + len(sh["vertex_planes"])) if c not in xyz]
    mesh = ([f[1:] for f in sh["facets"]], [f[0] for f in sh["facets"]], xyz, dict(zip(named, sh["vertex_planes"])))
    return d["planes"], g, mesh


def shuffled(tris, rng):
    """The triangles in a random order, each rotated at random."""
    tris = [list(t) for t in tris]
    rng.shuffle(tris)
    return [t[r:] + t[:r] for t in tris for r in [rng.randrange(3)]]


def from_trimesh(mesh, scale, rng):
    """A mesh of explicit corners on an integer grid, its triangles shuffled."""
    vs = [[round(float(x) * scale) for x in v] for v in mesh.vertices]
    tris = shuffled([[int(i) for i in f] for f in mesh.faces], rng)
    return tris, [-1] * len(tris), dict(enumerate(vs)), {}


def icosphere(rng):
    import trimesh
    return from_trimesh(trimesh.creation.icosphere(subdivisions=2), 1000, rng)


def torus(rng):
    import trimesh
    return from_trimesh(trimesh.creation.torus(major_radius=3.0, minor_radius=1.0, major_sections=16,
                                               minor_sections=10), 300, rng)


def trimesh_meshes(*names):
    """trimesh's primitives by name, each (triangles, {corner: integer coordinates}) at 8 units a
    unit, in trimesh's order."""
    import trimesh
    make = {
        "icosphere": lambda: trimesh.creation.icosphere(subdivisions=2, radius=50.0),
        "box": lambda: trimesh.creation.box(extents=(30.0, 20.0, 10.0)),
        "capsule": lambda: trimesh.creation.capsule(height=40.0, radius=12.0, count=[10, 10]),
        "cylinder": lambda: trimesh.creation.cylinder(radius=20.0, height=30.0, sections=14),
        "torus": lambda: trimesh.creation.torus(major_radius=40.0, minor_radius=12.0, major_sections=14,
                                                minor_sections=9),
        "cone": lambda: trimesh.creation.cone(radius=15.0, height=25.0, sections=11),
    }
    meshes = {}
    for name in names:
        mesh = make[name]()
        xyz = {i: [int(round(c * 8)) for c in p] for i, p in enumerate(mesh.vertices.tolist())}
        meshes[name] = ([list(map(int, f)) for f in mesh.faces.tolist()], xyz)
    return meshes


# --- files that cost more than their size (issue 49): the decode budget of §12.4 -----------------

def pack(body: bytes, method: int) -> bytes:
    """§6: the stored bytes of method 0 (stored), 1 (zlib) or 2 (Brotli)."""
    if method == 2:
        import brotli
        return brotli.compress(body, quality=5)
    return zlib.compress(body, 9) if method == 1 else body


def fan_walk(t: int) -> bytes:
    """§9.13 kind data of a walk of ``t`` ≥ 2 triangles fanned round corner 0: the root's child across
    its edge 0, every other triangle's across its edge 1, each naming one new corner; every corner
    explicit at 0, 0, 0 (V = t + 2), every triangle free. About five bytes a triangle, all alike."""
    v = t + 2
    flags = bytearray(b"\xff" * (v // 8)) + (bytes([(1 << (v % 8)) - 1]) if v % 8 else b"")
    return (uv(v) + uv(t) + uv(3) + uv(1) + uv(4) * (t - 2) + uv(0) + uv(0) * 3 + uv(0) * t + bytes(flags)
            + b"\x00" + struct.pack("<4f", 0.0, 0.0, 0.0, 1.0) + b"\x00" * (3 * v))


def stored_file(groups, *, plns_blocks=(), coding=0, objects=1, h_range=None, bits=(0, 0, 0)) -> bytes:
    """A version 5.0 file: the header (``h_range``, ``bits`` for codings 2 and 3), PLNS payloads as
    given, ``objects`` objects, then ``groups`` (object, kind, body, method) in turn."""
    p = bytes([5, 0, 0, coding, *bits, 1])
    if h_range is not None:
        p += struct.pack("<2d", *h_range)
    out = SIGNATURE + u32_chunk(b"PHDR", p + struct.pack("<ff", math.nan, math.nan))
    out += b"".join(varint_chunk(b"PLNS", block) for block in plns_blocks)
    out += b"".join(varint_chunk(b"OBJT", objt(k, b"o%d" % k)) for k in range(objects))
    for index, (obj, kind, body, method) in enumerate(groups):
        stored = pack(body, method)
        out += varint_chunk(b"GRUP", uv(index) + uv(obj) + bytes([kind, method]) + uv(len(body)) + stored)
    return out + varint_chunk(b"PEND", b"")


def walk_file(t: int, method: int = 1, copies: int = 0) -> bytes:
    """One fan walk of ``t`` triangles (group 0, no references) and ``copies`` copies of it (§9.15)."""
    walk = (0, 9, group_body([], [], fan_walk(t)), method)
    return stored_file([walk] + [(0, 11, group_body([], [], uv(0)), 0)] * copies)


def zero_planes_block(first: int, count: int, method: int = 1) -> bytes:
    """§7.1: ``count`` float32 planes (0, 0, 0) from ``first`` on, compressed with ``method``."""
    raw = bytes(12 * count)
    return uv(first) + uv(count) + bytes([method]) + uv(len(raw)) + pack(raw, method)


# --- version 6.0 (§2.2 r32, §4.5 body segments, §4.6 records, §5 compact header, §10.2 index) ----

def r32(x: float) -> bytes:
    """§2.2: the binary32 bit pattern of ``x``, its 32 bits reversed, as a varint32."""
    bits = struct.unpack("<I", struct.pack("<f", x))[0]
    return uv(int(format(bits, "032b")[::-1], 2))


def phdr6(*, minor=0, flags=0, coding=0, units=1, bits=(1, 1, 1), h_range=None, bbox=None,
          tolerance=math.nan, error_bound=math.nan, counts=None, later=b"") -> bytes:
    """§5, version 6: version, header_size, then flags (the coding in bits 3-4), units, the widths
    and h range (codings 2 and 3), the bbox (``bbox``: BBOX_KNOWN), tolerance and error bound, the
    counts (``counts``: COUNTS_KNOWN), and ``later`` header bytes of a newer minor version."""
    flags |= coding << 3 | (4 if bbox is not None else 0) | (2 if counts is not None else 0)
    fields = bytes([flags, units])
    if coding in (2, 3):
        fields += struct.pack("<H", sum((b - 1) << (5 * k) for k, b in enumerate(bits)))
        fields += r32(h_range[0]) + r32(h_range[1])
    if bbox is not None:
        fields += b"".join(r32(x) for x in bbox)
    fields += r32(tolerance) + r32(error_bound)
    if counts is not None:
        fields += b"".join(uv(n) for n in counts)
    fields += later
    return bytes([6, minor]) + uv(len(fields)) + fields


def record(tag: int, payload: bytes) -> bytes:
    """§4.6: tag, length, payload."""
    return bytes([tag]) + uv(len(payload)) + payload


def segment(records, method: int = 0) -> bytes:
    """§4.5: compression, raw size, the records' bytes stored (0), deflated (1) or Brotli'd (2)."""
    raw = b"".join(records)
    return bytes([method]) + uv(len(raw)) + pack(raw, method)


def objt6(name: bytes = b"o", parent: int | None = None) -> bytes:
    """§8 without index: a root object (or a child of ``parent``) without a transform."""
    return uv(0 if parent is None else parent + 1) + b"\x00" + uv(len(name)) + name


def plns6(planes, coding: int = 0) -> bytes:
    """§7.1, a planes record's payload: count, then float32 (0) or float64 (1) triplets."""
    return uv(len(planes)) + b"".join(struct.pack("<3f" if coding == 0 else "<3d", *p) for p in planes)


def grup6(obj: int, kind: int, body: bytes) -> bytes:
    """§9.1, a group record's payload: object, kind, the body (§9.2)."""
    return uv(obj) + bytes([kind]) + body


def colr6(group: int, count: int, rgba: bytes) -> bytes:
    """§10.1, a colours record's payload: group, count (varint32 each), the colours."""
    return uv(group) + uv(count) + rgba


def v6_file(header: bytes, first=None, bodies=(), *, index=None, pend=None, chunks=()) -> bytes:
    """A version 6 file: PHDR (``header`` and the segment ``first`` after it, if any), a BODY chunk
    per segment of ``bodies``, other ``chunks`` (type, payload), an iNDX of payload ``index`` (PEND
    then holds its offset unless ``pend`` says otherwise), PEND."""
    out = SIGNATURE + u32_chunk(b"PHDR", header + (first or b""))
    out += b"".join(varint_chunk(b"BODY", s) for s in bodies)
    out += b"".join(varint_chunk(t, p) for t, p in chunks)
    if index is not None:
        if pend is None:
            pend = struct.pack("<Q", len(out))
        out += varint_chunk(b"iNDX", index)
    return out + varint_chunk(b"PEND", b"" if pend is None else pend)


def index6(entries) -> bytes:
    """§10.2, version 6: count, then per entry (chunk offset, raw offset, tag, ordinal) the chunk
    offset as a difference from the previous entry's, the raw offset, the tag, the ordinal."""
    out, prev = uv(len(entries)), 0
    for chunk, raw, tag, ordinal in entries:
        out += uv(chunk - prev) + uv(raw) + bytes([tag]) + uv(ordinal)
        prev = chunk
    return out


def _v5_chunks(data: bytes):
    """§4.1 (version 5): the chunks after the signature as (type, payload): PHDR's length a u32,
    every later one a varint32."""
    pos, first, out = 8, True, []
    while pos < len(data):
        ctype = data[pos:pos + 4]
        pos += 4
        if first:
            length = struct.unpack_from("<I", data, pos)[0]
            pos += 4
            first = False
        else:
            length = shift = 0
            while True:
                b = data[pos]
                pos += 1
                length |= (b & 0x7F) << shift
                shift += 7
                if not b & 0x80:
                    break
        out.append((ctype, data[pos:pos + length]))
        pos += length + 4
    return out


class _Payload:
    """A version 5 payload read front to back, for v6_records."""

    def __init__(self, data: bytes):
        self.data, self.pos = data, 0

    def take(self, n: int) -> bytes:
        self.pos += n
        return self.data[self.pos - n:self.pos]

    def varint(self) -> int:
        value = shift = 0
        while True:
            b = self.take(1)[0]
            value |= (b & 0x7F) << shift
            shift += 7
            if not b & 0x80:
                return value

    def rest(self) -> bytes:
        return self.take(len(self.data) - self.pos)


def _unpack(method: int, stored: bytes) -> bytes:
    if method == 2:
        import brotli
        return brotli.decompress(stored)
    return zlib.decompress(stored) if method == 1 else stored


def v6_records(v5: bytes):
    """A valid version 5 file as version 6 parts (Appendix A.6 against §4.6 and §5): the keyword
    arguments of phdr6 its header holds, and its records, each (tag, payload): an OBJT without its
    index, a PLNS as count and raw data, a GRUP as object, kind and raw body, a cOLR with varint32
    group and count, an mETA as it is; iNDX and unknown ancillary chunks are dropped."""
    chunks = _v5_chunks(v5)
    h = _Payload(chunks[0][1])
    _, minor, flags, coding = h.take(4)
    bits, units = tuple(h.take(3)), h.take(1)[0]
    kw = {"minor": 0, "flags": flags & 1, "coding": coding, "units": units}
    if coding >= 2:
        kw["bits"], kw["h_range"] = bits, struct.unpack("<2d", h.take(16))
    if flags & 4:
        kw["bbox"] = struct.unpack("<6f", h.take(24))
    kw["tolerance"], kw["error_bound"] = struct.unpack("<2f", h.take(8))
    if flags & 2:
        kw["counts"] = (h.varint(), h.varint(), h.varint())
    records = []
    for ctype, payload in chunks[1:]:
        c = _Payload(payload)
        if ctype == b"OBJT":
            c.varint()
            records.append((1, c.rest()))
        elif ctype == b"PLNS":
            c.varint()
            count, method = c.varint(), c.take(1)[0]
            c.varint()
            records.append((2, uv(count) + _unpack(method, c.rest())))
        elif ctype == b"GRUP":
            c.varint()
            obj, kind, method = c.varint(), *c.take(2)
            c.varint()
            records.append((3, uv(obj) + bytes([kind]) + _unpack(method, c.rest())))
        elif ctype == b"cOLR":
            group, count = struct.unpack("<II", c.take(8))
            records.append((4, uv(group) + uv(count) + c.rest()))
        elif ctype == b"mETA":
            records.append((5, payload))
    return kw, records


def v6_layout(header: bytes, records, groups, methods, *, with_index=False) -> bytes:
    """A version 6 file of ``records`` (tag, payload) cut into segments: ``groups`` the number of
    records of each segment in turn (the first in PHDR), ``methods`` each segment's compression;
    with an index of every record of tag 1, 2 or 3 (§10.2) if asked."""
    segments, entries, at = [], [], 0
    offset = 8 + 12 + len(header)  # where the first BODY chunk will start
    counters = {1: 0, 2: 0, 3: 0}
    for k, (n, method) in enumerate(zip(groups, methods)):
        recs = records[at:at + n]
        at += n
        chunk = 8 if k == 0 else offset
        raw = 0
        for tag, payload in recs:
            if tag in counters:
                entries.append((chunk, raw, tag, counters[tag]))
                counters[tag] += 1 if tag != 2 else _plane_count(payload)
            raw += len(record(tag, payload))
        seg = segment([record(t, p) for t, p in recs], method) if recs or k else b""
        segments.append(seg)
        if k == 0:
            offset += len(seg)
        else:
            offset += len(varint_chunk(b"BODY", seg))
    assert at == len(records)
    return v6_file(header, segments[0], segments[1:], index=index6(entries) if with_index else None)


def _plane_count(payload: bytes) -> int:
    return _Payload(payload).varint()
