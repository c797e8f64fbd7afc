"""Kind 12 (spec/pln.md §9.16, shell walks with reflections) and version 5.1 in the independent reader
conformance/independent/plnread.py, on hand-built version 5.1 files.

The files come from an encoder written from the text of §9.13 and §9.16 (neither from planefmt nor
from either independent reader): tests/spec_files.py's walk, and the prediction here. It differs
from plnread on purpose where it can: the walk keeps the open edges of §9.13 as a plain list
searched from its newest end, each corner's step source is found by scanning the triangles for the
one whose code named it, and the reflection of §9.16 is computed as a projection in exact fractions,
rounded with Python's round() after checking that no component is a half (N/D never is: a lattice
vector reflected in a lattice line has no half-integer component, so the text's rounding of halves
never applies). Each mesh (trimesh's primitives, golden shells with named corners, and a cone whose
open fan is walked round its rim) is encoded in all four modes, read back, and compared with the
shell the encoder meant; then hostile bodies built field by field (a resolved value pushed past 2^52
by the reflection of a turning chain, and not by a chain a component beyond 2^18 keeps from turning;
an index pushed outside its table; a mode bit above 1) must be refused with BAD_GROUP_STRUCTURE, and
the version rules of §9.2, §9.3 and §13 hold for kind 12 (UNKNOWN_GROUP_KIND in a 5.0 file)."""

from __future__ import annotations

import math
import random
import struct
from fractions import Fraction
from functools import partial

import pytest

from spec_files import (Walk, golden_shell, pln_file, residual_bytes, shuffled, table_bytes, trimesh_meshes, uv,
                        walk_head)
from spec_files import read_read as read

LIMIT = 2**52
TURN = 2**18

pln = partial(pln_file, major=5, minor=1, name=b"m")


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


def kind_data(walk, faces, explicit_xyz, named_planes, mode, kind=12):
    """Kind 12 data (kind 9 with kind=9) for a walk, faces, explicit_xyz and named_planes as
    walk_head takes them. Returns the data, the "shell" object a reader must report, and g, the
    values the prediction works on (coordinates, or indices into the tables)."""
    data, shell = walk_head(walk, faces, explicit_xyz, named_planes)
    value = {}
    if shell["explicit"]:
        shell["origin"], shell["step"] = ORIGIN, STEP
        data += bytes([mode]) + GRID
        value = {k: list(g) for k, g in zip(shell["explicit"], shell["grid"])}
        if mode & 2:
            tables = [sorted({g[a] for g in shell["grid"]}) for a in range(3)]
            data += table_bytes(tables)
            value = {k: [tables[a].index(g[a]) for a in range(3)] for k, g in value.items()}
        data += residual_bytes(residuals_for(walk, set(value), value, mode, kind))
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

MESHES = trimesh_meshes("icosphere", "capsule", "torus")


def cone(sections=40, radius=3000, height=2000):
    """An open fan round an apex (corner 0), its rim corners 1, 2, … on a circle: each triangle
    (r_j, apex, r_j+1) meets the next across (apex, r_j+1), so the walk is one path round the rim."""
    xyz = {0: [0, 0, height]}
    xyz.update({j + 1: [round(radius * math.cos(2 * math.pi * j / sections)),
                        round(radius * math.sin(2 * math.pi * j / sections)), 0] for j in range(sections)})
    return [[j, 0, j + 1] for j in range(1, sections)], xyz


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


@pytest.mark.parametrize("mode", [0, 1, 2, 3])
@pytest.mark.parametrize("name", GOLDENS)
def test_golden_shells_round_trip(name, mode):
    """Named and explicit corners together, faces on planes: a step source is always explicit."""
    planes, g, (tris, faces, xyz, named) = golden_shell(name)
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
    got = read(pln([group], minor=3))  # a newer minor: read, and said so
    assert got["groups"][0]["shell"] == shell and got["findings"] == ["NEWER_MINOR_VERSION"]
    # kind 14: unknown in 5.2; skipped in 5.3, its m = 0 not an error (§9.2), the next group read
    assert read(pln([(14, [], [], b"\x05")], minor=2))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(14, [], [], b"\x05"), group], minor=3))
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
