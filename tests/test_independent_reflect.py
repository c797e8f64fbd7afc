"""Kind 12 (spec/pln.md §9.16, shell walks with reflections) and version 5.1 in the independent reader
conformance/independent/plnspec.py, on hand-built version 5.1 files.

The files come from an encoder written from §9.13 and §9.16 alone (not from planefmt, nor from the
reader): the walk, tests/spec_files.py's, keeps its open edges as a plain list in order of entry, as
§9.13 words it, and the reflection is computed here as the text explains it, d1 reflected in the
line of d2 with exact fractions, 2(d1.d2)/D d2 - d1, rounded by floor(x + 1/2), not by the reader's
integer formula. Each mesh (trimesh's icosphere and torus, a tube of rings walked round, and two
golden shells with named corners) is encoded in the four modes, read back, and compared with the
shell the encoder meant; the tube checks that chains turn and that their reflections predict better
than kind 9. Then hostile bodies: a resolved value pushed past 2^52 by the reflection of a turning
chain (its residual 0), and not by a chain that a component beyond 2^18 keeps from turning; indices
pushed outside their tables; a mode bit above 1; and the versions of §9.3 and §13 (kind 12 in a 5.0
file, kind 14 in 5.1 and 5.3, kind 12 in major 4)."""

from __future__ import annotations

import math
import random
from fractions import Fraction
from functools import partial

import pytest

from spec_files import CodedWalk, golden_shell, icosphere, pln_file, plnspec, torus, uv
from spec_files import read_spec as read

LIM = 1 << 52
TURN = 1 << 18

pln = partial(pln_file, major=5, minor=1)


class Walk(CodedWalk):
    """A walk coded as kind 12 (§9.16), or with kind=9 as kind 9, in a version 5 file."""

    kind = 12
    grid_format = "<4f"  # §9.11, version 5: four f32, which the grid's values are

    def chain(self, k):
        a = self.step_source(k)
        b = None if a is None else self.step_source(a)
        c = None if b is None else self.step_source(b)
        return None if c is None else (a, b, c)

    def reflection(self, k, g):
        """Where k's chain turns, g(a) plus d1 reflected in the line of d2, each component rounded
        to the nearest integer, halves up; otherwise None."""
        chain = self.chain(k)
        if chain is None:
            return None
        a, b, c = chain
        d1 = [g[b][x] - g[c][x] for x in range(3)]
        d2 = [g[a][x] - g[b][x] for x in range(3)]
        dd = sum(y * y for y in d2)
        if dd == 0 or max(abs(y) for y in d1 + d2) > TURN:
            return None
        along = Fraction(2 * sum(y * z for y, z in zip(d1, d2)), dd)
        return [g[a][x] + math.floor(along * d2[x] - d1[x] + Fraction(1, 2)) for x in range(3)]

    def predict(self, k, g, mode, kind):
        turned = self.reflection(k, g) if kind == 12 else None
        return super().predict(k, g, mode, kind) if turned is None else turned

    def turning(self, mode):
        """The explicit corners whose chain turns on the encoder's values."""
        g = self.values(mode)
        return [k for k in self.explicit if self.reflection(k, g) is not None]


# --- meshes ---------------------------------------------------------------------------------------

def tube(sections=24, rings=6, radius=4000, pitch=900):
    """An open tube: rings of corners on circles, each band of quads split into two triangles;
    walked as a path, it goes round each band before it climbs to the next."""
    def c(i, j):
        return i * sections + j % sections
    xyz = {c(i, j): [round(radius * math.cos(2 * math.pi * j / sections)),
                     round(radius * math.sin(2 * math.pi * j / sections)), i * pitch]
           for i in range(rings) for j in range(sections)}
    tris = []
    for i in range(rings - 1):
        for j in range(sections):
            tris += [[c(i, j), c(i, j + 1), c(i + 1, j + 1)], [c(i, j), c(i + 1, j + 1), c(i + 1, j)]]
    return tris, [-1] * len(tris), xyz, {}


def fan_walk(n):
    """A walk of n triangles round corner 1, each attached to the last across its edge 1: (0 1 2),
    (2 1 3), (3 1 4), …, so that every corner's step source is the corner before it; its corners
    are placed by the residuals a test gives."""
    tris = [[0, 1, 2]] + [[k - 1, 1, k] for k in range(3, n + 2)]
    walk = Walk(tris, [-1] * len(tris), {c: [0, 0, 0] for c in range(n + 2)}, {}, rng=random.Random(0))
    assert all(walk.step_source(k) == k - 1 for k in range(1, n + 2))
    return walk


MESHES = {"icosphere": icosphere, "torus": torus, "tube": lambda rng: tube()}


def decoded(data, planes=(), refs=(), bounding=(), kind=12, minor=1):
    got = read(pln([(kind, list(refs), list(bounding), data)], planes, minor=minor))
    assert "error" not in got, got
    assert got["header"]["version"] == [5, minor]
    return got["groups"][0]["shell"]


# --- round trips ----------------------------------------------------------------------------------

@pytest.mark.parametrize("mesh", list(MESHES))
@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_meshes_round_trip(mesh, mode):
    """Without references (§9.2, version 5); the walk's escapes and left and right codes mixed."""
    for seed in range(2):
        rng = random.Random(seed)
        walk = Walk(*MESHES[mesh](rng), rng=rng, escape_rate=0.3 * seed)
        assert walk.turning(mode)
        got = read(pln([(12, [], [], walk.body(mode))]))
        assert "error" not in got, got
        assert got["header"]["version"] == [5, 1] and got["findings"] == []
        assert got["groups"][0]["kind"] == 12 and got["groups"][0]["shell"] == walk.shell()


@pytest.mark.parametrize("name", ["shell_tree_mixed_v3_3", "shell_walk_torus_v4_1"])
@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_golden_shells_round_trip(name, mode):
    """Named corners among the explicit ones: a step source is explicit, so a triangle whose i0 is
    named steps from the previous explicit corner, and so may the chain."""
    planes, g, mesh = golden_shell(name)
    for seed in range(2):
        walk = Walk(*mesh, rng=random.Random(seed), escape_rate=0.3 * seed)
        assert decoded(walk.body(mode), planes, g["refs"], g["bounding"]) == walk.shell()


def test_chains_turn_round_a_tube():
    """A tube walked as one path round band after band: past the first band (whose two rings are
    named in turn, so that its chains zigzag between them), each corner's chain is the two chords
    before it on its ring, and the reflection predicts it within the rounding of the grid, where
    kind 9's step from the corner before is a chord off. Read as kind 9, the body decodes to other
    corners."""
    sections = 24
    walk = Walk(*tube(sections=sections), rng=random.Random(4), path=True)
    assert walk.parent.count(None) == 1 and len(walk.turning(0)) == len(walk.explicit) - 3
    later = walk.explicit[2 * sections:]
    step = walk.residuals(0, 9)
    for mode in (0, 1):
        reflected = walk.residuals(mode, 12)
        exact = [k for k in later if max(map(abs, reflected[k])) <= 1]
        assert 4 * len(exact) > 3 * len(later)
        assert all(max(map(abs, step[k])) > 500 for k in exact)
        data = walk.body(mode)
        assert decoded(data) == walk.shell()
        assert decoded(data, kind=9)["grid"] != walk.shell()["grid"]


def test_the_reader_s_reflection_is_the_text_s():
    """plnspec's integer formula floor((2N + D) / 2D) against the reflection in fractions, on steps
    of both signs up to 2^18 in each component (many of them reflected to negative non-integers,
    where a division that truncates toward 0 would round the wrong way), and no turn for D = 0 or
    a component past 2^18."""
    rng = random.Random(7)
    walk = fan_walk(2)
    negative_inexact = 0
    for trial in range(3000):
        bound = rng.choice((3, 50, TURN))
        d1, d2 = ([rng.randint(-bound, bound) for _ in range(3)] for _ in range(2))
        g = {0: [rng.randint(-LIM, LIM) for _ in range(3)]}
        g[1] = [x + y for x, y in zip(g[0], d1)]
        g[2] = [x + y for x, y in zip(g[1], d2)]
        assert plnspec.Reader.reflection(g[2], g[1], g[0]) == walk.reflection(3, g)
        if any(d2):
            along = Fraction(2 * sum(a * b for a, b in zip(d1, d2)), sum(b * b for b in d2))
            negative_inexact += any(x < 0 and x.denominator > 1 for x in (along * b - a for a, b in zip(d1, d2)))
    assert negative_inexact > 1000
    assert plnspec.Reader.reflection([5, 5, 5], [5, 5, 5], [0, 0, 0]) is None  # D = 0
    for d1, d2, turns in (([TURN, 0, 0], [0, TURN, -TURN], True), ([TURN + 1, 0, 0], [1, 0, 0], False),
                          ([0, 0, 1], [-TURN - 1, 0, 0], False)):
        gc = [10, 20, 30]
        gb = [x + y for x, y in zip(gc, d1)]
        ga = [x + y for x, y in zip(gb, d2)]
        assert (plnspec.Reader.reflection(ga, gb, gc) is not None) == turns


# --- hostile bodies -------------------------------------------------------------------------------

@pytest.mark.parametrize("mode", [0, 1])
def test_a_value_pushed_past_2_52_by_a_turning_chain(mode):
    """Corners 0, 1, 2 at steps d1 = (0, s, 0), d2 = (s, s, 0), within 2^52; corner 3, residual 0,
    is predicted 2(d1.d2)/D d2 - d1 = (s, 0, 0) past corner 2: refused where that passes 2^52 (kind
    9 reads the same residuals), accepted at 2^52 exactly, and accepted where s = 2^18 + 1 keeps the
    chain from turning."""
    walk = fan_walk(2)
    for s, top, ok in ((1 << 17, LIM + 1, False), (TURN, LIM + 1, False), (TURN, LIM, True),
                       (TURN + 1, LIM + 1, True)):
        g = {0: [top - 2 * s, 0, 0]}
        g[1] = [g[0][0], s, 0]
        g[2] = [g[0][0] + s, 2 * s, 0]
        residuals = {0: g[0], 1: [0, s, 0], 2: [s, s, 0], 3: [0, 0, 0]}
        resolved = walk.resolve(residuals, mode)
        assert all(resolved[k] == g[k] for k in range(3))
        assert (resolved[3] == [top, 2 * s, 0]) == (s <= TURN)
        got = read(pln([(12, [], [], walk.body(mode, residuals=residuals))]))
        if ok:
            assert got["groups"][0]["shell"]["grid"] == [resolved[k] for k in range(4)], got
        else:
            assert got.get("error") == "BAD_GROUP_STRUCTURE" and "explicit corner 3:" in got["why"], got
            assert "error" not in read(pln([(9, [], [], walk.body(mode, residuals=residuals))]))


def test_reflections_of_reflections_round_an_octagon():
    """Residuals 0 after corner 2: each corner is the one before plus the step before it turned by
    45 degrees, (s, 0, 0), (s, -s, 0), (0, -s, 0), …, round an octagon whose right-most corners, 4
    and 5, are at x = g(0) + 3s: read back exactly where that is 2^52, refused at corner 4 where it
    is one more, though kind 9 reads the same residuals."""
    walk = fan_walk(30)
    s = 1000
    for top in (LIM, LIM + 1):
        residuals = {k: [0, 0, 0] for k in walk.explicit}
        residuals.update({0: [top - 3 * s, 0, 0], 1: [0, s, 0], 2: [s, s, 0]})
        g = walk.resolve(residuals, 0)
        assert g[4] == [top, s, 0] and g[12] == g[4] and max(g[k][0] for k in walk.explicit) == top
        got = read(pln([(12, [], [], walk.body(0, residuals=residuals))]))
        if top == LIM:
            assert got["groups"][0]["shell"]["grid"] == [g[k] for k in walk.explicit], got
        else:
            assert got.get("error") == "BAD_GROUP_STRUCTURE" and "explicit corner 4:" in got["why"], got
            assert "error" not in read(pln([(9, [], [], walk.body(0, residuals=residuals))]))


@pytest.mark.parametrize("mode", [2, 3])
def test_an_index_outside_its_table(mode):
    """One turning corner's index at -1, 0, C - 1 and C on each axis, the other corners' kept; then
    a reflection alone that steps out of the x table."""
    rng = random.Random(6)
    walk = Walk(*tube(), rng=rng)
    tables = walk.tables()
    k = walk.turning(mode)[len(walk.turning(mode)) // 2]
    for axis in range(3):
        for index, ok in ((-1, False), (0, True), (len(tables[axis]) - 1, True), (len(tables[axis]), False)):
            g = walk.values(mode)
            g[k][axis] = index
            got = read(pln([(12, [], [], walk.body(mode, residuals=walk.residuals(mode, 12, g)))]))
            if ok:
                assert "error" not in got, got
            else:
                assert got.get("error") == "BAD_GROUP_STRUCTURE" and f"corner {k}: index" in got["why"], got
    # indices (C - 2, 0, 0), (C - 2, 1, 0), (C - 1, 2, 0): corner 3 reflected to (C, 2, 0)
    fanned = fan_walk(2)
    c = 4  # at most E (§9.13)
    tables = [list(range(c)), [0, 1, 2, 3], [0]]
    residuals = {0: [c - 2, 0, 0], 1: [0, 1, 0], 2: [1, 1, 0], 3: [0, 0, 0]}
    assert fanned.resolve(residuals, mode)[3] == [c, 2, 0]
    got = read(pln([(12, [], [], fanned.body(mode, residuals=residuals, tables=tables))]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "corner 3: index 4 outside" in got["why"], got
    got = read(pln([(9, [], [], fanned.body(mode, residuals=residuals, tables=tables))]))
    assert "error" not in got, got


@pytest.mark.parametrize("mode", [4, 0x80, 0x7])
def test_a_mode_bit_above_1(mode):
    """§9.13: mode bits 2-7 MUST be 0."""
    rng = random.Random(8)
    walk = Walk(*tube(sections=6, rings=2), rng=rng)
    good = walk.body(0)
    bad = walk.head + bytes([mode]) + good[len(walk.head) + 1:]
    assert read(pln([(12, [], [], bad)])).get("error") == "BAD_GROUP_STRUCTURE"


def test_errors_of_9_13_hold_for_kind_12():
    """§9.16: "the errors are those of §9.13": bytes after the coordinates, a body cut short, a
    residual beyond 2^52."""
    rng = random.Random(8)
    walk = Walk(*tube(sections=6, rings=2), rng=rng)
    ok = walk.body(1)
    assert read(pln([(12, [], [], ok + b"\x00")])).get("error") == "BAD_GROUP_STRUCTURE"
    assert read(pln([(12, [], [], ok[:-1])])).get("error") == "BAD_PAYLOAD"
    residuals = walk.residuals(1)
    residuals[walk.explicit[-1]][2] = LIM + 1
    got = read(pln([(12, [], [], walk.body(1, residuals=residuals))]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "residual" in got["why"], got


# --- versions (§9.2, §9.3, §13) -------------------------------------------------------------------

def test_kind_12_by_version():
    rng = random.Random(1)
    walk = Walk(*tube(sections=8, rings=3), rng=rng)
    group = (12, [], [], walk.body(1))
    assert read(pln([group], minor=0))["error"] == "UNKNOWN_GROUP_KIND"  # 5.0 is not above 5.1
    got = read(pln([group], minor=3))  # a newer minor of major 5: read, and said so
    assert got["groups"][0]["shell"] == walk.shell() and got["findings"] == ["NEWER_MINOR_VERSION"]
    # kind 14: unknown in 5.1, skipped in 5.3 with m = 0 (its own minor version decides, §9.2)
    assert read(pln([(14, [], [], b"\x01")]))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(14, [], [], b"\x01"), group], minor=3))
    assert set(got["findings"]) == {"SKIPPED_GROUP_KIND", "NEWER_MINOR_VERSION"} and "shell" not in got["groups"][0]
    assert got["groups"][1]["shell"] == walk.shell()
    # major 4 has no kind 12: unknown in 4.2, skipped in 4.3, where every group has a reference (A.5)
    plane = [[0.0, 0.0, 1.0]]
    assert read(pln([(12, [0], [], b"\x01")], plane, minor=2, major=4))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(12, [0], [], b"\x01")], plane, minor=3, major=4))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and "shell" not in got["groups"][0]
    assert read(pln([(12, [], [], b"\x01")], plane, minor=3, major=4))["error"] == "BAD_GROUP_STRUCTURE"


def test_kinds_9_to_11_in_a_5_1_file():
    """Kinds 9, 10 and 11 are kinds of 5.1 too (§9.3), without references as in 5.0."""
    rng = random.Random(2)
    walk = Walk(*tube(sections=8, rings=3), rng=rng)
    groups = [(9, [], [], walk.body(1, kind=9)), (10, [], [], walk.body(1, kind=9)), (11, [], [], uv(0)),
              (12, [], [], walk.body(1))]
    got = read(pln(groups))
    assert "error" not in got, got
    assert got["groups"][0]["shell"] == got["groups"][3]["shell"] == walk.shell()
    assert got["groups"][1]["shell"]["facets"] == walk.shell()["facets"] and got["groups"][2]["source"] == 0
