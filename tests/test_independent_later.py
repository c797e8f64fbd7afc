"""Kind 13 (spec/pln.md §9.17, shell walks stepping from the later gate corner) and version 5.2 in the
independent reader conformance/independent/plnspec.py, on hand-built version 5.2 files.

The files come from an encoder written from §9.13 and §9.17 alone (not from planefmt, nor from the
reader): the walk is tests/spec_files.py's, and kind 13's predictor is computed here as the text words
it: of the two corners of the gate (i0 and i1 of the attached triangle whose code names the corner
anew), the one the walk named later, found from the order in which the walk's codes 0 named its
corners (not as a larger number), where that corner is explicit; otherwise the previous explicit
corner; with mode bit 0, §9.12's parallelogram where its three corners are explicit. Each mesh
(trimesh's icosphere, torus and cylinder, a cube split into 4 x 4 squares a face whose eight corners
are named by the planes of shell_tree_mixed_v3_3, and two golden shells, one with named corners) is
encoded in the four modes, read back, and compared with the shell the encoder meant; the same bodies
read as kind 9 decode to other corners, those the encoder resolves by kind 9's rule (i0), and a named
later gate corner is seen to send its corner to the previous explicit one. Then hostile bodies: a
mode bit above 1; indices pushed outside their tables; a resolved value pushed past 2^52 by the later
gate corner where kind 9's i0 keeps it within; §9.13's other errors; and the versions of §9.3 and §13
(kind 13 in 5.0 and 5.1, in 5.2 and 5.3, in major 4; kind 14 in 5.2 and 5.3)."""

from __future__ import annotations

import random
from functools import partial

import pytest

from spec_files import CodedWalk, golden_shell, icosphere, pln_file, torus, trimesh_meshes, uv
from spec_files import read_spec as read

LIM = 1 << 52

pln = partial(pln_file, major=5, minor=2)


class Walk(CodedWalk):
    """A walk coded as kind 13 (§9.17), or with kind=9 as kind 9, in a version 5 file."""

    kind = 13
    grid_format = "<4f"  # §9.11, version 5: four f32, which the grid's values are

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # the order in which the walk names its corners: the codes 0 of each triangle, in triangle
        # order (a root's in its corner order)
        named = [k for ks in self.new for k in ks]
        self.naming = {k: place for place, k in enumerate(named)}
        assert sorted(self.naming) == list(range(len(self.number)))

    def gate_corner(self, k):
        """§9.17: of the gate's two corners, i0 and i1 of the attached triangle that named k, the one
        named later; None where a root named k."""
        j = self.creator[k]
        if self.parent[j] is None:
            return None
        i0, i1 = self.tris[j][:2]
        return i1 if self.naming[i1] > self.naming[i0] else i0

    def later_source(self, k):
        """§9.17's predictor: the later gate corner where it is explicit; otherwise the previous
        explicit corner in corner order; None for the first explicit corner."""
        gate = self.gate_corner(k)
        if gate is not None and self.flags[gate]:
            return gate
        before = [c for c in self.explicit if c < k]
        return before[-1] if before else None

    def predict(self, k, g, mode, kind):
        if kind != 13:
            return super().predict(k, g, mode, kind)
        j = self.creator[k]
        if mode & 1 and self.parent[j] is not None:  # §9.12's parallelogram, as in kind 9
            p, e = self.parent[j]
            i0, i1, o = self.tris[j][0], self.tris[j][1], self.tris[p][(e + 2) % 3]
            if self.flags[i0] and self.flags[i1] and self.flags[o]:
                return [g[i0][x] + g[i1][x] - g[o][x] for x in range(3)]
        a = self.later_source(k)
        return [0, 0, 0] if a is None else list(g[a])

    def differing(self, mode):
        """The explicit corners whose kind-13 prediction, on the encoder's values, is not kind 9's."""
        g = self.values(mode)
        return [k for k in self.explicit if self.predict(k, g, mode, 13) != self.predict(k, g, mode, 9)]


# --- meshes ---------------------------------------------------------------------------------------

def cylinder(rng):
    """trimesh's cylinder: long thin triangles round a tube and fans on its caps, as CAD's."""
    tris, xyz = trimesh_meshes("cylinder")["cylinder"]
    return tris, [-1] * len(tris), xyz, {}


MESHES = {"icosphere": icosphere, "torus": torus, "cylinder": cylinder}
GOLDEN = ["shell_tree_mixed_v3_3", "shell_walk_torus_v4_1"]


def split_cube(n=4):
    """The cube [0, n]^3, each face split into n x n squares of two triangles on its face plane:
    its eight corners named by their three face planes, every other corner explicit. The planes,
    references and role bits are those of shell_tree_mixed_v3_3's unit cube (local references 0
    to 5: x = 1, y = 1, x = 0, y = 0, z = 1, z = 0), the grid's step 1/n. Returns them and the mesh."""
    plane = {(0, 1): 0, (1, 1): 1, (0, 0): 2, (1, 0): 3, (2, 1): 4, (2, 0): 5}  # (axis, far side) -> reference
    ids, xyz, tris, faces = {}, {}, [], []
    for axis in range(3):
        a, b = [x for x in range(3) if x != axis]
        for side in (0, 1):
            # counter-clockwise seen from outside: (a, b, axis) in the order of the axes, on the far side
            ccw = ((axis + 1) % 3 == a) == bool(side)
            for u in range(n):
                for v in range(n):
                    square = []
                    for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0, 0, 0]
                        p[axis], p[a], p[b] = side * n, u + du, v + dv
                        square.append(ids.setdefault(tuple(p), len(ids)))
                        xyz[ids[tuple(p)]] = p
                    q = square if ccw else square[::-1]
                    tris += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
                    faces += [plane[axis, side]] * 2
    edges = {(t[s], t[(s + 1) % 3]) for t in tris for s in range(3)}
    assert len(edges) == 3 * len(tris) and all((y, x) in edges for x, y in edges)  # closed, oriented
    named = {k: sorted(plane[x, p[x] // n] for x in range(3)) for k, p in xyz.items() if all(c in (0, n) for c in p)}
    planes, g, _ = golden_shell("shell_tree_mixed_v3_3")
    return planes, g, (tris, faces, {k: p for k, p in xyz.items() if k not in named}, named)


def quad(xyz=None):
    """Root (0 1 2) and, across its edge 2 (from 2 to 0), the triangle (0 2 3): its gate is i0 = 0,
    i1 = 2, so kind 9 steps corner 3 from corner 0 and kind 13 from corner 2. Every corner is
    explicit; a test gives its own residuals. No corner has a chain of §9.16 (corner 3 steps from
    0 there, which steps from none)."""
    xyz = xyz or {0: [0, 0, 0], 1: [4, 0, 0], 2: [4, 4, 0], 3: [0, 4, 1]}
    walk = Walk([[0, 1, 2], [0, 2, 3]], [-1, -1], xyz, {}, rng=random.Random(0))
    assert walk.tris == [[0, 1, 2], [0, 2, 3]] and walk.parent == [None, (0, 2)]
    assert walk.later_source(3) == 2 and walk.step_source(3) == 0
    return walk


def decoded(data, planes=(), refs=(), bounding=(), kind=13, minor=2):
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
        if not mode & 1:  # with bit 0 the parallelogram predicts nearly every corner of these
            assert len(walk.differing(mode)) > len(walk.explicit) // 4
        got = read(pln([(13, [], [], walk.body(mode))]))
        assert "error" not in got, got
        assert got["header"]["version"] == [5, 2] and got["findings"] == []
        assert got["groups"][0]["kind"] == 13 and got["groups"][0]["shell"] == walk.shell()


@pytest.mark.parametrize("name", GOLDEN)
@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_golden_shells_round_trip(name, mode):
    """Named corners among the explicit ones (shell_tree_mixed_v3_3): a later gate corner that is
    named sends its corner to the previous explicit corner, though the other gate corner may be
    explicit; the torus's corners are all explicit, on one reference."""
    planes, g, mesh = golden_shell(name)
    for seed in range(2):
        walk = Walk(*mesh, rng=random.Random(seed), escape_rate=0.3 * seed)
        assert decoded(walk.body(mode), planes, g["refs"], g["bounding"]) == walk.shell()


@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_split_cube_round_trip(mode):
    """Named corners with explicit corners round them: where a gate corner is named the parallelogram
    cannot predict, so kind 13 predicts otherwise than kind 9 in every mode."""
    planes, g, mesh = split_cube()
    for seed in range(2):
        walk = Walk(*mesh, rng=random.Random(seed), escape_rate=0.3 * seed)
        assert walk.differing(mode)
        assert decoded(walk.body(mode), planes, g["refs"], g["bounding"]) == walk.shell()


def test_a_named_later_gate_corner_falls_back_to_the_previous_explicit_corner():
    """On the split cube some explicit corner's later gate corner is named while the earlier one is
    explicit and is not the previous explicit corner: §9.17 steps it from the previous explicit
    corner ("otherwise"), so a reader that stepped from the other gate corner would decode another
    corner; plnspec decodes the encoder's."""
    planes, g, mesh = split_cube()
    found = 0
    for seed in range(4):
        walk = Walk(*mesh, rng=random.Random(seed))
        for k in walk.explicit:
            gate = walk.gate_corner(k)
            if gate is None or walk.flags[gate]:
                continue
            i0, i1 = walk.tris[walk.creator[k]][:2]
            other = i0 if gate == i1 else i1
            if walk.flags[other] and walk.later_source(k) != other:
                found += 1
        for mode in (0, 2):
            assert decoded(walk.body(mode), planes, g["refs"], g["bounding"]) == walk.shell()
    assert found


@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_the_rule_matters(mode):
    """A kind-13 body read as kind 9 (its kind byte changed, nothing else): the corners kind 9's rule
    (i0) resolves from the same residuals, which are other corners than the encoder's on some mesh
    (without mode bit 0 on every mesh but the small mixed shell, with it on the split cube); and a
    kind-9 body read as kind 13 likewise."""
    other = 0
    for name, make in [*MESHES.items(), *((n, None) for n in GOLDEN + ["split_cube"])]:
        if make is None:
            planes, g, mesh = split_cube() if name == "split_cube" else golden_shell(name)
            refs, bounding = g["refs"], g["bounding"]
        else:
            planes, refs, bounding, mesh = (), (), (), make(random.Random(3))
        walk = Walk(*mesh, rng=random.Random(3))
        residuals = walk.residuals(mode)
        as9 = walk.resolve(residuals, mode, kind=9)
        got = read(pln([(9, list(refs), list(bounding), walk.body(mode))], planes))
        if mode & 2:  # indices: kind 9's may fall outside their tables
            tables = walk.tables()
            inside = all(0 <= as9[k][x] < len(tables[x]) for k in walk.explicit for x in range(3))
            if not inside:
                assert got.get("error") == "BAD_GROUP_STRUCTURE" and "outside" in got["why"], got
                other += 1
                continue
            want = [[tables[x][as9[k][x]] for x in range(3)] for k in walk.explicit]
        else:
            want = [as9[k] for k in walk.explicit]
        assert "error" not in got, got
        assert got["groups"][0]["shell"]["grid"] == want
        differs = want != walk.shell()["grid"]
        assert differs == bool(walk.differing(mode))
        if not mode & 1 and name != "shell_tree_mixed_v3_3" or name == "split_cube":
            assert differs, name
        other += differs
        # the other way round: a kind-9 body read as kind 13
        body9 = walk.body(mode, kind=9)
        as13 = walk.resolve(walk.residuals(mode, kind=9), mode)
        got = read(pln([(13, list(refs), list(bounding), body9)], planes))
        if not mode & 2:
            assert got["groups"][0]["shell"]["grid"] == [as13[k] for k in walk.explicit], got
    assert other


# --- hostile bodies -------------------------------------------------------------------------------

@pytest.mark.parametrize("mode", [4, 0x80, 0x5, 0xFD])
def test_a_mode_bit_above_1(mode):
    """§9.13: mode bits 2-7 MUST be 0."""
    walk = Walk(*cylinder(None), rng=random.Random(8))
    good = walk.body(0)
    bad = walk.head + bytes([mode]) + good[len(walk.head) + 1:]
    got = read(pln([(13, [], [], bad)]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "mode" in got["why"], got


@pytest.mark.parametrize("mode", [0, 1])
def test_a_value_pushed_past_2_52_by_the_later_gate_corner(mode):
    """The quad: corners 0, 1, 2 at x = 0, 1, s; corner 3's residual r. Kind 13 resolves s + r, kind
    9 0 + r (mode 1: o = 1 is explicit, so the parallelogram 0 + s - 1 + r, the same for both):
    refused past 2^52 on either side, accepted at 2^52 exactly."""
    walk = quad()
    s = 1 << 51
    for sign in (1, -1):
        for r, ok in ((LIM - s, True), (LIM - s + 1, False)):
            residuals = {0: [0, 0, 0], 1: [sign, 0, 0], 2: [sign * (s - 1), 0, 0], 3: [sign * r, 0, 0]}
            g = walk.resolve(residuals, mode)
            assert [g[k][0] for k in range(3)] == [0, sign, sign * s]
            top = s + r if mode == 0 else s - 1 + r
            assert g[3] == [sign * top, 0, 0]
            got = read(pln([(13, [], [], walk.body(mode, residuals=residuals))]))
            if ok or top <= LIM:
                assert got["groups"][0]["shell"]["grid"] == [g[k] for k in range(4)], got
            else:
                assert got.get("error") == "BAD_GROUP_STRUCTURE" and "explicit corner 3:" in got["why"], got
            as9 = read(pln([(9, [], [], walk.body(mode, residuals=residuals))]))
            if mode == 0:
                assert "error" not in as9, as9  # r alone is within 2^52
            else:
                assert ("error" in as9) == ("error" in got)


@pytest.mark.parametrize("mode", [2, 3])
def test_an_index_outside_its_table(mode):
    """One corner that kind 13 predicts otherwise than kind 9, its index at -1, 0, C - 1 and C on
    each axis, the other corners' kept; then the quad in mode 2, whose x indices 0, 1, 3 and corner
    3's residual 1 step out of the x table of 4 values from the later gate corner (index 4), not
    from i0 (index 1)."""
    rng = random.Random(6)
    walk = Walk(*icosphere(rng), rng=rng)
    tables = walk.tables()
    ks = walk.differing(mode) or walk.explicit[3:]
    k = ks[len(ks) // 2]
    for axis in range(3):
        for index, ok in ((-1, False), (0, True), (len(tables[axis]) - 1, True), (len(tables[axis]), False)):
            g = walk.values(mode)
            g[k][axis] = index
            got = read(pln([(13, [], [], walk.body(mode, residuals=walk.residuals(mode, 13, g)))]))
            if ok:
                assert "error" not in got, got
            else:
                assert got.get("error") == "BAD_GROUP_STRUCTURE" and f"corner {k}: index" in got["why"], got
    if mode == 2:
        q = quad()
        tables = [[0, 1, 2, 3], [0], [0]]  # C at most E = 4 (§9.13)
        for r, ok in ((0, True), (1, False)):
            residuals = {0: [0, 0, 0], 1: [1, 0, 0], 2: [2, 0, 0], 3: [r, 0, 0]}
            assert q.resolve(residuals, mode)[3] == [3 + r, 0, 0]
            got = read(pln([(13, [], [], q.body(mode, residuals=residuals, tables=tables))]))
            if ok:
                assert got["groups"][0]["shell"]["grid"] == [[0, 0, 0], [1, 0, 0], [3, 0, 0], [3, 0, 0]], got
            else:
                assert got.get("error") == "BAD_GROUP_STRUCTURE" and "corner 3: index 4 outside" in got["why"], got
            assert "error" not in read(pln([(9, [], [], q.body(mode, residuals=residuals, tables=tables))]))


def test_errors_of_9_13_hold_for_kind_13():
    """§9.17: "the checks and errors are those of §9.13": bytes after the coordinates, a body cut
    short, a residual beyond 2^52, a table count of 0."""
    walk = Walk(*cylinder(None), rng=random.Random(8))
    ok = walk.body(1)
    assert read(pln([(13, [], [], ok + b"\x00")])).get("error") == "BAD_GROUP_STRUCTURE"
    assert read(pln([(13, [], [], ok[:-1])])).get("error") == "BAD_PAYLOAD"
    residuals = walk.residuals(1)
    residuals[walk.explicit[-1]][2] = LIM + 1
    got = read(pln([(13, [], [], walk.body(1, residuals=residuals))]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "residual" in got["why"], got
    tabled = walk.body(2)
    at = len(walk.head) + 1 + 16  # the mode, the grid, then the x table's count
    got = read(pln([(13, [], [], tabled[:at] + uv(0) + tabled[at + len(uv(len(walk.tables()[0]))):])]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "count 0" in got["why"], got


# --- versions (§9.2, §9.3, §13) -------------------------------------------------------------------

def test_kind_13_by_version():
    walk = Walk(*cylinder(None), rng=random.Random(1))
    group = (13, [], [], walk.body(0))
    for minor in (0, 1):  # not above 5.2, and no kind 13 in them
        assert read(pln([group], minor=minor))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([group]))
    assert got["header"]["version"] == [5, 2] and got["findings"] == []
    assert got["groups"][0]["shell"] == walk.shell()
    got = read(pln([group], minor=3))  # a newer minor of major 5: read, and said so
    assert got["groups"][0]["shell"] == walk.shell() and got["findings"] == ["NEWER_MINOR_VERSION"]
    # kind 14: unknown in 5.2, skipped in 5.3 with m = 0 (its own minor version decides, §9.2)
    assert read(pln([(14, [], [], b"\x01")]))["error"] == "UNKNOWN_GROUP_KIND"
    assert read(pln([group, (14, [], [], b"\x01")]))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(14, [], [], b"\x01"), group], minor=3))
    assert set(got["findings"]) == {"SKIPPED_GROUP_KIND", "NEWER_MINOR_VERSION"} and "shell" not in got["groups"][0]
    assert got["groups"][1]["shell"] == walk.shell()
    # major 4 has no kind 13: unknown in 4.2, skipped in 4.3, where every group has a reference (A.5)
    plane = [[0.0, 0.0, 1.0]]
    assert read(pln([(13, [0], [], b"\x01")], plane, minor=2, major=4))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(13, [0], [], b"\x01")], plane, minor=3, major=4))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and "shell" not in got["groups"][0]


def test_kinds_9_to_12_in_a_5_2_file():
    """Kinds 9 to 12 are kinds of 5.2 too (§9.3), without references as in 5.0 and 5.1 (kind 12 on the
    quad, which has no chain, so that kind 9's residuals are kind 12's)."""
    walk = Walk(*cylinder(None), rng=random.Random(2))
    groups = [(9, [], [], walk.body(0, kind=9)), (10, [], [], walk.body(0, kind=9)), (11, [], [], uv(0)),
              (12, [], [], quad().body(2, kind=9)), (13, [], [], walk.body(0))]
    got = read(pln(groups))
    assert "error" not in got, got
    assert [g["kind"] for g in got["groups"]] == [9, 10, 11, 12, 13] and got["findings"] == []
    assert got["groups"][0]["shell"] == got["groups"][4]["shell"] == walk.shell()
    assert got["groups"][1]["shell"]["facets"] == walk.shell()["facets"] and got["groups"][2]["source"] == 0
    assert got["groups"][3]["shell"] == quad().shell()
