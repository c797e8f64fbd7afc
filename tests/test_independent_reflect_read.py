"""Kind 12 (spec/pln.md §9.16, shell walks with reflections) and version 5.1 in the independent reader
conformance/independent/plnread.py, on hand-built version 5.1 files.

The files come from an encoder written here from the text of §9.13 and §9.16 (neither from planefmt
nor from either independent reader, and not sharing code with the other tests). It differs from
plnread on purpose where it can: it keeps the open edges of §9.13 as a plain list searched from its
newest end, finds each corner's step source by scanning the triangles for the one whose code named
it, and computes the reflection of §9.16 as a projection in exact fractions, rounded with Python's
round() after checking that no component is a half (N/D never is: a lattice vector reflected in a
lattice line has no half-integer component, so the text's rounding of halves never applies). Each
mesh (trimesh's primitives, golden shells with named corners, and a cone whose open fan is walked
round its rim) is encoded in all four modes, read back, and compared with the shell the encoder
meant; then hostile bodies built field by field (a resolved value pushed past 2^52 by the
reflection of a turning chain, and not by a chain a component beyond 2^18 keeps from turning; an
index pushed outside its table; a mode bit above 1) must be refused with BAD_GROUP_STRUCTURE, and
the version rules of §9.2, §9.3 and §13 hold for kind 12 (UNKNOWN_GROUP_KIND in a 5.0 file)."""

from __future__ import annotations

import importlib.util
import io
import itertools
import json
import math
import random
import struct
import zlib
from fractions import Fraction
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SUITE = ROOT / "conformance"
LIMIT = 2**52
TURN = 2**18


def _load_plnread():
    spec = importlib.util.spec_from_file_location("plnread", SUITE / "independent" / "plnread.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


plnread = _load_plnread()


# --- bytes --------------------------------------------------------------------------------------

def uv(v: int) -> bytes:
    """An unsigned LEB128 varint (§2.2)."""
    assert v >= 0
    out = bytearray()
    while v >= 0x80:
        out.append((v & 0x7F) | 0x80)
        v >>= 7
    out.append(v)
    return bytes(out)


def zigzag(d: int) -> int:
    return 2 * d if d >= 0 else -2 * d - 1


def make_chunk(tag: bytes, payload: bytes, u32_length: bool) -> bytes:
    """§4.1: PHDR, and every chunk before version 5, with a u32 length; a later chunk of a version 5
    file with a varint32 one."""
    length = struct.pack("<I", len(payload)) if u32_length else uv(len(payload))
    return tag + length + payload + struct.pack("<I", zlib.crc32(tag + payload))


def pln(groups, planes=(), minor=1, major=5):
    """A version major.minor file: planes in float32 where every value is a float32, else float64;
    one object; `groups` as (kind, refs, bounding, kind data), bodies stored uncompressed. Version
    5's header has an 8-byte fixed part (§5), version 4's a 9-byte one (A.5)."""
    f32 = all(struct.unpack("<f", struct.pack("<f", x))[0] == x for p in planes for x in p)
    flags = b"\x00" if major >= 5 else b"\x00\x00"
    header = bytes([major, minor]) + flags + bytes([0 if f32 else 1, 0, 0, 0, 1])
    header += struct.pack("<ff", math.nan, math.nan)
    old = major < 5
    out = b"\x89PLN\r\n\x1a\n" + make_chunk(b"PHDR", header, True)
    if planes:
        raw = b"".join(struct.pack("<3f" if f32 else "<3d", *p) for p in planes)
        out += make_chunk(b"PLNS", uv(0) + uv(len(planes)) + b"\x00" + uv(len(raw)) + raw, old)
    out += make_chunk(b"OBJT", uv(0) + uv(0) + b"\x00" + uv(1) + b"m", old)
    for index, (kind, refs, bounding, data) in enumerate(groups):
        body = uv(len(refs)) + b"".join(uv(r - p) for r, p in zip(refs, [0] + list(refs[:-1])))
        roles = bytearray((len(refs) + 7) // 8)
        for i in bounding:
            roles[i // 8] |= 1 << (i % 8)
        body += bytes(roles) + data
        out += make_chunk(b"GRUP", uv(index) + uv(0) + bytes([kind, 0]) + uv(len(body)) + body, old)
    return out + make_chunk(b"PEND", b"", old)


def read(data: bytes):
    reader = plnread.Reader(io.BytesIO(data), len(data))
    try:
        reader.read()
    except plnread.PlnError as exc:
        return {"error": exc.code, "why": exc.message}
    return json.loads(json.dumps(reader.result()))


# --- the walk (§9.13) -----------------------------------------------------------------------------

def ordered_lists(free):
    """§9.13: the ordered lists of distinct free edges, by length, then in lexicographic order of
    the edges' places among the free edges."""
    out = []
    for length in range(len(free) + 1):
        out += [tuple(free[i] for i in pl) for pl in itertools.permutations(range(len(free)), length)]
    return out


ROOT_CHILDREN = ordered_lists((0, 1, 2))
ATTACHED_CHILDREN = ordered_lists((1, 2))


class OpenList:
    """§9.13's open edges, word for word: a list of directed edges in order of entry."""

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
    that code it, each root rotated at random. Attributes: tris (walk order, corners numbered as
    the walk names them), parent ((p, e) or None per triangle), new (per triangle, the corners its
    codes 0 name anew), source (walk triangle -> source triangle), number (source corner -> corner
    number)."""

    def __init__(self, tris, rng, escape_rate=0.0):
        by_edge = {}
        for t, tri in enumerate(tris):
            for s in range(3):
                by_edge.setdefault((tri[s], tri[(s + 1) % 3]), []).append(t)
        claimed = [False] * len(tris)
        self.tris, self.parent, self.source, self.new = [], [], [], []
        self.symbols, self.escapes = [], []
        self.number = {}
        opened = OpenList()
        stack = []
        unwalked = iter(range(len(tris)))
        while len(self.tris) < len(tris):
            j = len(self.tris)
            named = []
            if stack:
                p, e, t = stack.pop()
                q = self.tris[p]
                i0, i1, x = q[(e + 1) % 3], q[e], q[(e + 2) % 3]
                back = {v: k for k, v in self.number.items()}
                src = tris[t]
                r = next(r for r in range(3) if src[r] == back[i0] and src[(r + 1) % 3] == back[i1])
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
                shift = rng.randrange(3)
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
            kids = []
            for e in rng.sample(free, len(free)):
                a, b = rot[e], rot[(e + 1) % 3]
                for u in by_edge.get((b, a), []):
                    if not claimed[u]:
                        claimed[u] = True
                        kids.append((e, u))
                        break
            edges = tuple(e for e, _ in kids)
            if code is None:
                self.symbols.append(ROOT_CHILDREN.index(edges))
                self.escapes += codes
            else:
                self.symbols.append(4 * ATTACHED_CHILDREN.index(edges) + min(code, 3))
                if code >= 3:
                    self.escapes.append(code - 3)
            opened.add(corners)
            for e, u in kids[::-1]:
                stack.append((j, e, u))


# --- predictions (§9.11, §9.12, §9.13, §9.16) ----------------------------------------------------

def step_source(walk, k, explicit):
    """§9.16: p(k), §9.11's predictor: i0 of the triangle whose code named k anew, where that
    triangle is attached and its i0 explicit; otherwise the previous explicit corner, or None."""
    j = next(j for j, named in enumerate(walk.new) if k in named)
    if walk.parent[j] is not None and walk.tris[j][0] in explicit:
        return walk.tris[j][0]
    earlier = [c for c in explicit if c < k]
    return max(earlier) if earlier else None


def reflection(value, a, b, c):
    """§9.16: g(a) plus d1 = g(b) - g(c) reflected in the line of d2 = g(a) - g(b), each component
    rounded to the nearest integer; None where the chain does not turn."""
    d1 = [value[b][i] - value[c][i] for i in range(3)]
    d2 = [value[a][i] - value[b][i] for i in range(3)]
    if not any(d2) or any(abs(x) > TURN for x in d1 + d2):
        return None
    projection = [Fraction(sum(x * y for x, y in zip(d1, d2)) * y, sum(y * y for y in d2)) for y in d2]
    turned = [2 * p - x for p, x in zip(projection, d1)]
    assert all(t.denominator != 2 for t in turned)  # so round()'s halves to even never decide
    return [value[a][i] + round(turned[i]) for i in range(3)]


def chain(sources, k):
    """(p(k), p(p(k)), p(p(p(k)))) where all three exist."""
    a = sources[k]
    b = sources.get(a)
    c = sources.get(b)
    return None if c is None else (a, b, c)


def walk_prediction(walk, k, explicit, value, sources, mode):
    """§9.13's prediction of explicit corner k: §9.11's, or with mode bit 0 §9.12's."""
    j = next(j for j, named in enumerate(walk.new) if k in named)
    tri = walk.tris[j]
    if walk.parent[j] is not None and mode & 1:
        p, e = walk.parent[j]
        o = walk.tris[p][(e + 2) % 3]
        if tri[0] in explicit and tri[1] in explicit and o in explicit:
            return [value[tri[0]][a] + value[tri[1]][a] - value[o][a] for a in range(3)]
    return list(value[sources[k]]) if sources[k] is not None else [0, 0, 0]


def predict(walk, k, explicit, value, sources, mode, kind=12):
    found = chain(sources, k) if kind == 12 else None
    turned = reflection(value, *found) if found else None
    return turned if turned is not None else walk_prediction(walk, k, explicit, value, sources, mode)


def residuals_for(walk, explicit, value, mode, kind=12):
    """The residual of every explicit corner (corner order) that makes it resolve to `value`."""
    sources = {k: step_source(walk, k, explicit) for k in explicit}
    return [[value[k][a] - p for a, p in enumerate(predict(walk, k, explicit, value, sources, mode, kind))]
            for k in sorted(explicit)]


def turning(walk, explicit, value):
    """The explicit corners whose chain turns on values g."""
    sources = {k: step_source(walk, k, explicit) for k in explicit}
    return [k for k in sorted(explicit) if (found := chain(sources, k)) and reflection(value, *found) is not None]


# --- the kind data --------------------------------------------------------------------------------

ORIGIN, STEP = [0.25, -3.0, 1.5], 0.0625  # float32 values
GRID = struct.pack("<4f", *ORIGIN, STEP)  # §9.11, version 5: four f32


def table_bytes(tables):
    """§9.13: per axis a count, the first value (zigzag), then each gap less one."""
    return b"".join(uv(len(vals)) + uv(zigzag(vals[0])) + b"".join(uv(y - x - 1) for x, y in zip(vals, vals[1:]))
                    for vals in tables)


def residual_bytes(residuals):
    """§9.13: zigzag residuals, every corner's x, then every y, then every z."""
    return b"".join(uv(zigzag(r[a])) for a in range(3) for r in residuals)


def kind_data(walk, faces, explicit_xyz, named_planes, mode, kind=12):
    """Kind 12 data (kind 9 with kind=9) for a walk. faces: per source triangle, a local reference
    or -1; explicit_xyz: source corner -> integer coordinates; named_planes: source corner -> its
    three planes (a subset of its face planes, ascending). Returns the data, the "shell" object a
    reader must report, and g, the values the prediction works on (coordinates, or indices into
    the tables)."""
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
    explicit = {k for k in range(v) if src[k] in explicit_xyz}
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
        if k in explicit:
            continue
        planes = sorted(on[k])
        chosen = named_planes[src[k]]
        vertex_planes.append(list(chosen))
        if len(planes) > 3:
            picks += [planes.index(p) for p in chosen]
    data = uv(v) + uv(len(walk.tris)) + uv(len(walk.escapes))
    data += b"".join(uv(s) for s in walk.symbols) + b"".join(uv(x) for x in walk.escapes)
    data += b"".join(uv(c) for c in codes) + bytes(flags) + b"".join(uv(p) for p in picks)
    grid = [list(explicit_xyz[src[k]]) for k in sorted(explicit)]
    shell = {"explicit": sorted(explicit), "vertex_planes": vertex_planes, "grid": grid,
             "origin": None, "step": None, "facets": [[f] + t for f, t in zip(wfaces, walk.tris)]}
    value = {}
    if explicit:
        shell["origin"], shell["step"] = ORIGIN, STEP
        data += bytes([mode]) + GRID
        value = {k: list(explicit_xyz[src[k]]) for k in explicit}
        if mode & 2:
            tables = [sorted({g[a] for g in grid}) for a in range(3)]
            data += table_bytes(tables)
            value = {k: [tables[a].index(g[a]) for a in range(3)] for k, g in value.items()}
        data += residual_bytes(residuals_for(walk, explicit, value, mode, kind))
    return data, shell, value


def fan_data(residuals, mode=0, tables=None):
    """Kind data built field by field: n = len(residuals) corners, all explicit, and n - 2 free
    triangles round corner 1: (0 1 2), a root with a child across its edge 1 (symbol 2; escapes
    0 0 0, three new corners), then (k-1 1 k) for k = 3, 4, …, each attached to the one before
    across its edge 1 (from 1 to k-1) and naming k anew, with a child across its own edge 1
    (symbol 4), the last none (symbol 0). So the step source of corner k is i0 = k - 1, and of
    corners 1 and 2 the previous explicit corner: every corner from 3 on has a chain."""
    n = len(residuals)
    symbols = [2] + [4] * (n - 4) + [0]
    data = uv(n) + uv(n - 2) + uv(3) + b"".join(uv(s) for s in symbols) + uv(0) * 3 + uv(0) * (n - 2)
    data += bytes([0xFF] * (n // 8) + ([(1 << n % 8) - 1] if n % 8 else []))
    data += bytes([mode]) + GRID + (table_bytes(tables) if tables else b"")
    return data + residual_bytes(residuals)


def fan_shell(grid):
    """The shell a reader reports for fan_data's body whose corners resolve to ``grid``."""
    n = len(grid)
    return {"explicit": list(range(n)), "vertex_planes": [], "grid": grid, "origin": ORIGIN, "step": STEP,
            "facets": [[-1, 0, 1, 2]] + [[-1, k - 1, 1, k] for k in range(3, n)]}


# --- meshes ---------------------------------------------------------------------------------------

def trimesh_meshes():
    import trimesh
    out = {
        "icosphere": trimesh.creation.icosphere(subdivisions=2, radius=50.0),
        "capsule": trimesh.creation.capsule(height=40.0, radius=12.0, count=[10, 10]),
        "torus": trimesh.creation.torus(major_radius=40.0, minor_radius=12.0, major_sections=14,
                                        minor_sections=9),
    }
    meshes = {}
    for name, mesh in out.items():
        xyz = {i: [int(round(c * 8)) for c in p] for i, p in enumerate(mesh.vertices.tolist())}
        meshes[name] = ([list(map(int, f)) for f in mesh.faces.tolist()], xyz)
    return meshes


MESHES = trimesh_meshes()


def cone(sections=40, radius=3000, height=2000):
    """An open fan round an apex (corner 0), its rim corners 1, 2, … on a circle: each triangle
    (r_j, apex, r_j+1) meets the next across (apex, r_j+1), so the walk is one path round the rim."""
    xyz = {0: [0, 0, height]}
    xyz.update({j + 1: [round(radius * math.cos(2 * math.pi * j / sections)),
                        round(radius * math.sin(2 * math.pi * j / sections)), 0] for j in range(sections)})
    return [[j, 0, j + 1] for j in range(1, sections)], xyz


def shuffled(tris, rng):
    tris = [list(t) for t in tris]
    rng.shuffle(tris)
    return [t[r:] + t[:r] for t in tris for r in [rng.randrange(3)]]


def encode_free(tris, xyz, mode, rng, kind=12, escape_rate=0.0):
    """Kind data of explicit corners and free triangles, for a group without references (§9.2,
    version 5); with the shell it stands for, the walk and the values g."""
    used = {c for t in tris for c in t}
    walk = Walk(tris, rng, escape_rate)
    data, shell, value = kind_data(walk, [-1] * len(tris), {c: xyz[c] for c in used}, {}, mode, kind)
    return data, shell, walk, value


def check(data, shell, kind=12, minor=1):
    got = read(data)
    assert "error" not in got, got
    assert got["header"]["version"] == [5, minor]
    group = got["groups"][0]
    assert group["kind"] == kind and group["shell"] == shell
    return got


# --- round trips ----------------------------------------------------------------------------------

@pytest.mark.parametrize("mode", [0, 1, 2, 3])
@pytest.mark.parametrize("name", sorted(MESHES))
def test_trimesh_meshes_round_trip(name, mode):
    tris, xyz = MESHES[name]
    for seed in range(2):
        rng = random.Random(seed * 31 + mode)
        mesh = tris if seed == 0 else shuffled(tris, rng)
        data, shell, walk, value = encode_free(mesh, xyz, mode, rng, escape_rate=0.3 * seed)
        assert turning(walk, set(value), value)
        got = check(pln([(12, [], [], data)]), shell)
        assert got["findings"] == []


GOLDENS = ["shell_tree_mixed_v3_3", "shell_tree_pyramid_v3_4", "shell_walk_sphere_v4_1"]


def golden(name):
    d = json.loads((SUITE / "valid" / f"{name}.json").read_text())
    g = next(g for g in d["groups"] if "shell" in g)
    sh = g["shell"]
    tris = [f[1:] for f in sh["facets"]]
    faces = [f[0] for f in sh["facets"]]
    xyz = dict(zip(sh["explicit"], sh["grid"]))
    named = [c for c in range(len(sh["explicit"]) + len(sh["vertex_planes"])) if c not in xyz]
    return d["planes"], g, tris, faces, xyz, dict(zip(named, sh["vertex_planes"]))


@pytest.mark.parametrize("mode", [0, 1, 2, 3])
@pytest.mark.parametrize("name", GOLDENS)
def test_golden_shells_round_trip(name, mode):
    """Named and explicit corners together, faces on planes: a step source is always explicit."""
    planes, g, tris, faces, xyz, named = golden(name)
    for seed in range(2):
        walk = Walk(tris, random.Random(seed), escape_rate=0.3 * seed)
        data, shell, _ = kind_data(walk, faces, xyz, named, mode)
        check(pln([(12, g["refs"], g["bounding"], data)], planes), shell)


def test_a_cone_walked_round_its_rim():
    """Past its first few corners, whose chains reach the apex, each rim corner's chain is the two
    chords before it, and the reflection predicts it within the rounding of the grid where kind
    9's step from the corner before is a chord off; the same body read as kind 9 decodes to other
    corners."""
    tris, xyz = cone()
    for seed in range(3):
        data, shell, walk, value = encode_free(tris, xyz, 0, random.Random(seed))
        check(pln([(12, [], [], data)]), shell)
        explicit = sorted(value)
        reflected = residuals_for(walk, set(explicit), value, 0)
        stepped = residuals_for(walk, set(explicit), value, 0, kind=9)
        for k in explicit[5:]:
            assert max(map(abs, reflected[k])) <= 1 and max(map(abs, stepped[k])) > 100, (k, reflected[k])
        as_9 = read(pln([(9, [], [], data)]))
        assert as_9["groups"][0]["shell"]["grid"] != shell["grid"]


def test_rounding_by_hand():
    """Corners 0, 1, 2 at (0, 0, 0), (5, -3, 2), (4, 1, 1): d1 = (5, -3, 2), d2 = (-1, 4, -1),
    D = 18, d1.d2 = -19, N = -38 d2 - 18 d1 = (-52, -98, 2); (2N + D) / 2D = (-86, -178, 22) / 36,
    floored (-3, -5, 0), so corner 3 is predicted (1, -4, 1), where a division truncating toward 0
    would give (2, -3, 1)."""
    grid = [[0, 0, 0], [5, -3, 2], [4, 1, 1], [1, -4, 1]]
    residuals = [[0, 0, 0], [5, -3, 2], [-1, 4, -1], [0, 0, 0]]
    for mode in (0, 1):
        assert read(pln([(12, [], [], fan_data(residuals, mode))]))["groups"][0]["shell"] == fan_shell(grid)


# --- hostile bodies -------------------------------------------------------------------------------

@pytest.mark.parametrize("mode", [0, 1])
def test_value_pushed_past_2_52_by_a_turning_chain(mode):
    """Corners 0, 1, 2 at (top - 2s, 0, 0), (top - 2s, s, 0), (top - s, 2s, 0): d1 = (0, s, 0),
    d2 = (s, s, 0); reflected, d1 is (s, 0, 0), so corner 3, residual 0, is (top, 2s, 0). Refused
    where top passes 2^52, read back where it is 2^52; and where s = 2^18 + 1 the chain does not
    turn, so corner 3 is §9.13's prediction, within bounds."""
    for s, top, ok in ((2**17, LIMIT + 1, False), (TURN, LIMIT + 1, False), (TURN, LIMIT, True),
                       (TURN + 1, LIMIT + 1, True)):
        residuals = [[top - 2 * s, 0, 0], [0, s, 0], [s, s, 0], [0, 0, 0]]
        got = read(pln([(12, [], [], fan_data(residuals, mode))]))
        if not ok:
            assert got.get("error") == "BAD_GROUP_STRUCTURE" and "explicit corner 3:" in got["why"], got
            assert "error" not in read(pln([(9, [], [], fan_data(residuals, mode))]))
            continue
        first = [[top - 2 * s, 0, 0], [top - 2 * s, s, 0], [top - s, 2 * s, 0]]
        if s <= TURN:
            third = [top, 2 * s, 0]
        else:  # §9.13: corner 2, or with bit 0 corners 2 + 1 - 0
            third = [top - s, 3 * s, 0] if mode & 1 else first[2]
        assert got["groups"][0]["shell"] == fan_shell(first + [third]), got


def test_reflections_of_reflections_round_an_octagon():
    """Residuals 0 after corner 2: each corner is the one before plus the step before it turned by
    45 degrees, round an octagon whose right-most corners, 4 and 5, are at x = g(0) + 3s: read
    back where that is 2^52, refused at corner 4 where it is one more, though kind 9 reads the same
    residuals."""
    s, n = 1000, 30
    for top in (LIMIT, LIMIT + 1):
        residuals = [[top - 3 * s, 0, 0], [0, s, 0], [s, s, 0]] + [[0, 0, 0]] * (n - 3)
        value = {0: residuals[0], 1: [top - 3 * s, s, 0], 2: [top - 2 * s, 2 * s, 0]}
        for k in range(3, n):
            value[k] = reflection(value, k - 1, k - 2, k - 3)
        assert value[4] == [top, s, 0] and value[12] == value[4] and max(v[0] for v in value.values()) == top
        got = read(pln([(12, [], [], fan_data(residuals))]))
        if top == LIMIT:
            assert got["groups"][0]["shell"] == fan_shell([value[k] for k in range(n)]), got
        else:
            assert got.get("error") == "BAD_GROUP_STRUCTURE" and "explicit corner 4:" in got["why"], got
            assert "error" not in read(pln([(9, [], [], fan_data(residuals))]))


@pytest.mark.parametrize("mode", [2, 3])
def test_index_outside_its_table(mode):
    """Indices (2, 0, 0), (2, 1, 0), (3, 2, 0) in tables of 4, 4 and 1 values: corner 3, residual 0,
    is reflected to x index 4, outside; kind 9 predicts it inside. Then a turning corner of the
    torus pushed to index -1 and to C on each axis by its residual."""
    tables = [[0, 10, 20, 30], [-5, 0, 5, 7], [9]]
    residuals = [[2, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 0]]
    got = read(pln([(12, [], [], fan_data(residuals, mode, tables))]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "explicit corner 3: index 4 outside" in got["why"], got
    assert "error" not in read(pln([(9, [], [], fan_data(residuals, mode, tables))]))
    tris, xyz = MESHES["torus"]
    data, shell, walk, value = encode_free(tris, xyz, mode, random.Random(3))
    explicit = set(value)
    k = turning(walk, explicit, value)[-1]
    size = [len({g[a] for g in shell["grid"]}) for a in range(3)]
    head = data[:len(data) - len(residual_bytes(residuals_for(walk, explicit, value, mode)))]  # to the coordinates
    for axis in range(3):
        for index in (-1, size[axis]):
            pushed = {c: list(g) for c, g in value.items()}
            pushed[k][axis] = index
            got = read(pln([(12, [], [], head + residual_bytes(residuals_for(walk, explicit, pushed, mode)))]))
            assert got.get("error") == "BAD_GROUP_STRUCTURE" and f"explicit corner {k}: index" in got["why"], got


@pytest.mark.parametrize("mode", [4, 0x80, 0xFF])
def test_a_mode_bit_above_1(mode):
    residuals = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    assert read(pln([(12, [], [], fan_data(residuals, mode))])).get("error") == "BAD_GROUP_STRUCTURE"


def test_kind_12_errors_are_kind_9_s():
    """§9.16: the errors are those of §9.13; a few of them, on a kind-12 body."""
    data = fan_data([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    assert read(pln([(12, [], [], data + b"\x00")])).get("error") == "BAD_GROUP_STRUCTURE"
    assert read(pln([(12, [], [], data[:-1])])).get("error") == "BAD_PAYLOAD"
    got = read(pln([(12, [], [], fan_data([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, LIMIT + 1]]))]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "residual" in got["why"], got


# --- versions (§9.2, §9.3, §13) -------------------------------------------------------------------

def test_kind_12_by_version():
    residuals = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    group = (12, [], [], fan_data(residuals))
    shell = read(pln([group]))["groups"][0]["shell"]
    assert shell["grid"] == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 1]]  # d1 = (1, 0, 0) reflected: (-1, 0, 0)
    # §9.3: 5.0 is a minor this reader knows, and kind 12 not one of its kinds
    assert read(pln([group], minor=0))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([group], minor=2))  # a newer minor: read, and said so
    assert got["groups"][0]["shell"] == shell and got["findings"] == ["NEWER_MINOR_VERSION"]
    # kind 13: unknown in 5.1; skipped in 5.2, its m = 0 not an error (§9.2), the next group read
    assert read(pln([(13, [], [], b"\x05")]))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(13, [], [], b"\x05"), group], minor=2))
    assert set(got["findings"]) == {"SKIPPED_GROUP_KIND", "NEWER_MINOR_VERSION"}
    assert "shell" not in got["groups"][0] and got["groups"][1]["shell"] == shell
    # major 4 has no kind 12: unknown in 4.2, skipped in 4.3 (with a reference, A.5)
    plane = [[0.0, 0.0, 1.0]]
    assert read(pln([(12, [0], [], b"\x05")], plane, minor=2, major=4))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(12, [0], [], b"\x05")], plane, minor=3, major=4))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and "shell" not in got["groups"][0]
    # a copy of a kind 12 group, beside kinds 9 and 10, in a 5.1 file
    got = read(pln([group, (9, [], [], fan_data(residuals)), (10, [], [], fan_data(residuals)),
                    (11, [], [], uv(0))]))
    assert got["groups"][1]["shell"]["grid"] == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 1, 1]]  # kind 9: no turn
    assert got["groups"][3]["source"] == 0 and "error" not in got
