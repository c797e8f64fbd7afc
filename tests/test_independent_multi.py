"""Kind 10 (spec/pln.md §9.14, shell walks with multi-parallelograms) in the independent reader
conformance/independent/plnspec.py, on hand-built version 4.2 files.

The files come from an encoder written from §9.13 and §9.14 alone (not from planefmt, nor from the
reader): the walk, tests/spec_files.py's, keeps its open edges as a plain list in order of entry, as
§9.13 words it, and the far corners of §9.14 are found here by scanning the triangles in order for
the reverse edge, with no map, so both check the reader's faster structures against the text. The
prediction's rounding is computed with fractions. Each mesh (trimesh's icosphere and torus, an open
height-field patch, a triangle soup and two golden shells with named corners) is encoded in the four
modes, read back, and compared with the shell the encoder meant; then hostile bodies (a value pushed
past 2^52 along a chain of predictions whose residuals are all within 2^52; an index outside its
table) are checked for BAD_GROUP_STRUCTURE."""

from __future__ import annotations

import math
import random
from fractions import Fraction
from functools import partial

import pytest

from spec_files import CodedWalk, golden_shell, icosphere, pln_file, plnspec, torus
from spec_files import read_spec as read

LIM = 1 << 52

pln = partial(pln_file, major=4, minor=2)


class Walk(CodedWalk):
    """A walk coded as kind 10 (§9.14), or with kind=9 as kind 9."""

    kind = 10

    def far(self, a, b):
        """The far corner of (a, b): the third corner of the first triangle with (b, a)."""
        for tri in self.tris:
            for s in range(3):
                if (tri[s], tri[(s + 1) % 3]) == (b, a):
                    return tri[(s + 2) % 3]
        return None

    def parallelograms(self, k):
        out = []
        for tri in self.tris:
            for s in range(3):
                if tri[s] == k:
                    a, b = tri[(s + 1) % 3], tri[(s + 2) % 3]
                    c = self.far(a, b)
                    if c is not None and all(self.flags[y] and y < k for y in (a, b, c)):
                        out.append((a, b, c))
        return out[:4]

    def predict(self, k, g, mode, kind):
        par = self.parallelograms(k) if kind == 10 else []
        if par:
            n = len(par)
            return [math.floor(Fraction(sum(g[a][x] + g[b][x] - g[c][x] for a, b, c in par) + n // 2, n))
                    for x in range(3)]
        return super().predict(k, g, mode, kind)


# --- meshes ---------------------------------------------------------------------------------------

def patch(rng, nx=9, ny=7):
    """An open height field, each quad split along a random diagonal."""
    def c(i, j):
        return i * ny + j
    tris = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            a, b, cc, d = c(i, j), c(i + 1, j), c(i + 1, j + 1), c(i, j + 1)
            tris += [[a, b, cc], [a, cc, d]] if rng.random() < 0.5 else [[a, b, d], [b, cc, d]]
    rng.shuffle(tris)
    xyz = {c(i, j): [10 * i + rng.randrange(3), 10 * j + rng.randrange(3), rng.randrange(-20, 20)]
           for i in range(nx) for j in range(ny)}
    return tris, [-1] * len(tris), xyz, {}


def soup(rng, corners=10, count=36):
    """Random triangles over a few corners: non-manifold edges, repeated and reversed triangles."""
    tris = [rng.sample(range(corners), 3) for _ in range(count)]
    tris += [list(reversed(tris[0])), list(tris[1])]
    used = sorted({c for t in tris for c in t})
    return tris, [-1] * len(tris), {c: [rng.randrange(-50, 50) for _ in range(3)] for c in used}, {}


PLANE = [[0.0, 0.0, 1.0]]
MESHES = {"icosphere": icosphere, "torus": torus, "patch": patch, "soup": soup}


def decoded(data, planes=PLANE, refs=(0,), bounding=(), kind=10, minor=2):
    got = read(pln([(kind, list(refs), list(bounding), data)], planes, minor=minor))
    assert "error" not in got, got
    assert got["header"]["version"] == [4, minor]
    return got["groups"][0]["shell"]


# --- round trips ----------------------------------------------------------------------------------

@pytest.mark.parametrize("mesh", list(MESHES))
@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_meshes_round_trip(mesh, mode):
    for seed in range(3):
        rng = random.Random(seed)
        walk = Walk(*MESHES[mesh](rng), rng=rng, escape_rate=0.25 * seed)
        data = walk.body(mode)
        got = read(pln([(10, [0], [], data)], PLANE))
        assert "error" not in got, got
        assert got["header"]["version"] == [4, 2] and "NEWER_MINOR_VERSION" not in got["findings"]
        assert got["groups"][0]["kind"] == 10 and got["groups"][0]["shell"] == walk.shell()


@pytest.mark.parametrize("name", ["shell_tree_mixed_v3_3", "shell_tree_apex_v3_3", "shell_walk_sphere_v4_1",
                                  "shell_walk_torus_v4_1"])
@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_golden_shells_round_trip(name, mode):
    planes, g, mesh = golden_shell(name)
    for seed in range(3):
        walk = Walk(*mesh, rng=random.Random(seed), escape_rate=0.3 * (seed % 2))
        assert decoded(walk.body(mode), planes, g["refs"], g["bounding"]) == walk.shell()


@pytest.mark.parametrize("mesh", list(MESHES))
def test_the_reader_s_parallelograms_are_the_text_s(mesh):
    """plnspec's map of first triangles against the scan of the text, corner by corner; and the
    meshes exercise what the rule distinguishes: corners with 0 to 4 parallelograms, corners with
    more than four candidates, averages that round."""
    rng = random.Random(5)
    walk = Walk(*MESHES[mesh](rng), rng=rng)
    fast = plnspec.Reader.multi_parallelograms(walk.tris, walk.flags)
    counts = set()
    for k in range(len(walk.flags)):
        want = walk.parallelograms(k) if walk.flags[k] else []
        assert fast[k] == want, k
        counts.add(len(want))
    assert 0 in counts and (4 in counts or mesh == "patch")
    if mesh in ("icosphere", "torus"):
        assert counts >= {0, 1, 2, 3, 4}


def test_kind_10_differs_from_kind_9():
    """The same residuals read as kind 9 and as kind 10 give different corners, and a kind-10 body
    is smaller in residual magnitude on a smooth surface than kind 9's parallelogram."""
    rng = random.Random(3)
    walk = Walk(*icosphere(rng), rng=rng)
    for mode in range(4):
        data = walk.body(mode, kind=10)
        assert decoded(data) == walk.shell()
        as_9 = read(pln([(9, [0], [], data)], PLANE, minor=1))
        assert "error" in as_9 or as_9["groups"][0]["shell"] != walk.shell()
    r9 = walk.residuals(1, 9)
    r10 = walk.residuals(1, 10)
    assert sum(abs(x) for r in r10.values() for x in r) < sum(abs(x) for r in r9.values() for x in r)


def test_mode_bit_0_matters_only_where_an_edge_is_in_two_triangles():
    """SPEC_NOTES 42: where the parent of the triangle naming k is the first triangle with their
    shared edge reversed, §9.12's parallelogram is also k's first candidate of §9.14, so bit 0 of
    the mode (which only chooses kind 10's fallback) changes no residual; on a soup it can."""
    for mesh in ("icosphere", "torus", "patch"):
        rng = random.Random(12)
        walk = Walk(*MESHES[mesh](rng), rng=rng)
        for tables in (0, 2):
            assert walk.residuals(tables, 10) == walk.residuals(tables | 1, 10), mesh
            assert walk.residuals(tables, 9) != walk.residuals(tables | 1, 9), mesh
    # Edge (A, B) in Q and j, (B, A) in t' and p, in that order: Q (a root) takes t' across it,
    # then p (a root) takes j; the first triangle with (B, A) is t', whose third corner N is named,
    # so K, named by j, has no parallelogram, and §9.12's over p's opposite corner O applies with
    # bit 0. N lies on three face planes, its other two triangles after the rest.
    A, B, X, N, O, K, Y1, Y2, Y3 = range(9)
    tris = [[A, B, X], [B, A, N], [A, O, B], [A, B, K], [N, Y1, Y2], [N, Y3, Y1]]
    faces = [-1, 0, -1, -1, 1, 2]
    xyz = {A: [0, 0, 0], B: [10, 0, 0], X: [5, 9, 1], O: [5, -9, -2], K: [4, 8, 3], Y1: [1, 1, 1],
           Y2: [2, 2, 2], Y3: [3, 1, 2]}
    planes = [[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 2.0, 1.0]]
    walk = Walk(tris, faces, xyz, {N: [0, 1, 2]}, rng=random.Random(0))
    k = walk.tris[3][2]
    assert walk.parent[3] == (2, 2) and not walk.flags[walk.tris[1][2]] and walk.parallelograms(k) == []
    assert plnspec.Reader.multi_parallelograms(walk.tris, walk.flags)[k] == []
    assert walk.residuals(0, 10)[k] != walk.residuals(1, 10)[k]
    for mode in range(4):
        assert decoded(walk.body(mode), planes, [0, 1, 2]) == walk.shell()


def test_rounding_of_the_average():
    """floor((S + floor(n/2)) / n), toward -infinity: a fan of corners whose parallelograms sum to
    negative and positive values not divisible by n, each read back exactly."""
    rng = random.Random(9)
    tris, faces, xyz, named = patch(rng, 6, 6)
    walk = Walk(tris, faces, xyz, named, rng=rng)
    seen = set()
    for trial in range(30):
        residuals = {k: [rng.randrange(-7, 8) for _ in range(3)] for k in walk.explicit}
        g = walk.resolve(residuals, 0, 10)
        for k in walk.explicit:
            par = walk.parallelograms(k)
            if len(par) > 1:
                s = sum(g[a][0] + g[b][0] - g[c][0] for a, b, c in par)
                seen.add((len(par), s % len(par), s < 0))
        got = decoded(walk.body(0, residuals=residuals))
        assert got["grid"] == [g[k] for k in walk.explicit]
    assert {(2, 1, True), (2, 1, False), (3, 2, True), (3, 1, False)} <= seen


# --- versions -------------------------------------------------------------------------------------

def test_kind_10_by_minor_version():
    rng = random.Random(1)
    walk = Walk(*patch(rng, 4, 4), rng=rng)
    group = (10, [0], [], walk.body(1))
    got = read(pln([group], PLANE, minor=2))
    assert got["groups"][0]["shell"] == walk.shell() and "NEWER_MINOR_VERSION" not in got["findings"]
    for minor in (0, 1):  # §9.3: not a kind of 4.0 or 4.1, whose minor is not above 4.2
        assert read(pln([group], PLANE, minor=minor))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([group], PLANE, minor=3))  # a newer minor: read, and reported
    assert got["groups"][0]["shell"] == walk.shell() and "NEWER_MINOR_VERSION" in got["findings"]
    # kind 12: a kind 4.2 lacks (kind 11 is a copy since §9.15, tests/test_independent_copies.py)
    assert read(pln([(12, [0], [], b"\x01")], PLANE, minor=2))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(12, [0], [], b"\x01"), group], PLANE, minor=3))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and "shell" not in got["groups"][0]
    assert got["groups"][1]["shell"] == walk.shell()


# --- hostile bodies -------------------------------------------------------------------------------

def test_a_value_pushed_past_2_52_along_a_chain():
    """Residuals all within 2^52, resolved values that grow along chains of averaged
    parallelograms: refused exactly where a resolved value passes 2^52."""
    rng = random.Random(2)
    walk = Walk(*patch(rng, 12, 3), rng=rng)
    outcomes = set()
    for mode in (0, 1):
        for r in (1 << 44, 1 << 46, 1 << 47, 1 << 48, 1 << 50, LIM):
            residuals = {k: [r, -r, r // 3] for k in walk.explicit}
            g = walk.resolve(residuals, mode, 10)
            over = [k for k in walk.explicit if max(abs(x) for x in g[k]) > LIM]
            got = read(pln([(10, [0], [], walk.body(mode, residuals=residuals))], PLANE))
            if over:
                assert got.get("error") == "BAD_GROUP_STRUCTURE", got
                assert over[0] != walk.explicit[0]  # along a chain, not at its start
                assert f"explicit corner {over[0]}:" in got["why"]
            else:
                assert "error" not in got, got
            outcomes.add(bool(over))
    assert outcomes == {True, False}


def test_2_52_exactly():
    """The last explicit corner's value at 2^52 in magnitude, and one past it, with a residual
    within 2^52: accepted, then refused; and a residual past 2^52."""
    for sign in (1, -1):
        rng = random.Random(4)
        tris, faces, xyz, named = patch(rng, 5, 4)
        xyz = {c: [sign * (100 + x) for x in p] for c, p in xyz.items()}
        walk = Walk(tris, faces, xyz, named, rng=rng)
        k = walk.explicit[-1]
        for value, ok in ((sign * LIM, True), (sign * (LIM + 1), False)):
            g = walk.values(0)
            g[k] = [value, g[k][1], g[k][2]]
            residuals = walk.residuals(0, 10, g)
            assert all(abs(x) <= LIM for r in residuals.values() for x in r)
            got = read(pln([(10, [0], [], walk.body(0, residuals=residuals))], PLANE))
            assert ("error" not in got) == ok and (ok or got["error"] == "BAD_GROUP_STRUCTURE"), got
    residuals = walk.residuals(0, 10)
    residuals[walk.explicit[0]] = [LIM + 1, 0, 0]  # a residual beyond 2^52
    got = read(pln([(10, [0], [], walk.body(0, residuals=residuals))], PLANE))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "residual" in got["why"]


@pytest.mark.parametrize("mode", [2, 3])
def test_an_index_outside_its_table(mode):
    """One corner's index at -1, 0, C - 1 and C on each axis, the other corners' values kept."""
    rng = random.Random(6)
    walk = Walk(*torus(rng), rng=rng)
    tables = walk.tables()
    assert decoded(walk.body(mode)) == walk.shell()
    k = walk.explicit[len(walk.explicit) // 2]
    for axis in range(3):
        for index, ok in ((-1, False), (0, True), (len(tables[axis]) - 1, True), (len(tables[axis]), False)):
            g = walk.values(mode)
            g[k][axis] = index
            got = read(pln([(10, [0], [], walk.body(mode, residuals=walk.residuals(mode, 10, g)))], PLANE))
            if ok:
                assert "error" not in got, got
            else:
                assert got.get("error") == "BAD_GROUP_STRUCTURE" and f"corner {k}: index" in got["why"], got
    # every residual but two 0: the averages alone walk the indices out of their tables
    zero = {c: [0, 0, 0] for c in walk.explicit}
    zero[walk.explicit[0]] = [len(t) - 1 for t in tables]
    zero[walk.explicit[1]] = [-(len(t) - 1) for t in tables]
    g = walk.resolve(zero, mode, 10)
    assert all(0 <= g[c][x] < len(tables[x]) for c in walk.explicit[:2] for x in range(3))
    assert any(not 0 <= g[c][x] < len(tables[x]) for c in walk.explicit for x in range(3))
    got = read(pln([(10, [0], [], walk.body(mode, residuals=zero))], PLANE))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "outside" in got["why"], got


def test_hand_built_errors_of_9_13_hold_for_kind_10():
    """The walk, the mode and the tables are §9.13's: a few of its errors in a kind-10 body."""
    rng = random.Random(8)
    walk = Walk(*patch(rng, 4, 4), rng=rng)
    ok = walk.body(0)
    cases = {
        "bytes after": (ok + b"\x00", "BAD_GROUP_STRUCTURE"),
        "cut": (ok[:-1], "BAD_PAYLOAD"),
        "mode bit 2": (walk.head + b"\x04" + ok[len(walk.head) + 1:], "BAD_GROUP_STRUCTURE"),
        "table count 0": (walk.head + b"\x02" + ok[len(walk.head) + 1:len(walk.head) + 33] + b"\x00" + bytes(60),
                          "BAD_GROUP_STRUCTURE"),
    }
    for name, (data, code) in cases.items():
        assert read(pln([(10, [0], [], data)], PLANE)).get("error") == code, name
