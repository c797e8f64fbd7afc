"""Kind 13 (spec/pln.md §9.17, shell walks stepping from the later gate corner) and version 5.2 in
the independent reader conformance/independent/plnread.py, on hand-built version 5.2 files.

The files come from an encoder written from the text of §9.13 and §9.17 (neither from planefmt nor
from either independent reader): tests/spec_files.py's walk (CodedWalk), and the predictor here. It
differs from plnread on purpose where it can: the triangle that names a corner anew is found by
scanning each triangle's list of corners named by its codes 0, its gate is taken from the parent's
edge (q_e, q_(e+1)), not from the triangle's own i0 and i1, and the later-named of the gate's two
corners is the one that comes later in the order the codes named the corners, not the larger
number; the parallelogram of mode bit 0 is summed from the parent's corners too. Each mesh
(trimesh's primitives, golden shells with named corners, whose later gate corner may be named
where the earlier one is explicit) is encoded in all four modes, read back, and compared with the
shell the encoder meant; the same bodies read as kind 9 decode to other corners (the rule
matters). Then hostile bodies built field by field (a resolved value pushed past 2^52 by steps from
the later gate corner that kind 9 reads within bounds; an index pushed outside its table; a mode
bit above 1) must be refused with BAD_GROUP_STRUCTURE, and the version rules of §9.2, §9.3 and §13
hold for kind 13 (UNKNOWN_GROUP_KIND in a 5.0 or 5.1 file) and for kind 14 (UNKNOWN_GROUP_KIND in a
5.2 file, SKIPPED_GROUP_KIND in a 5.3 one)."""

from __future__ import annotations

import itertools
import json
import random
import struct
import zlib
from functools import partial

import pytest

from spec_files import (SUITE, CodedWalk, golden_shell, pln_file, residual_bytes, shuffled, table_bytes,
                        trimesh_meshes, uv)
from spec_files import read_read as read

LIMIT = 2**52

pln = partial(pln_file, major=5, minor=2, name=b"m")


# --- the encoder (§9.11, §9.12, §9.13, §9.17) -----------------------------------------------------

class LaterWalk(CodedWalk):
    """A walk coded as kind 13 (§9.17), or with kind=9 as kind 9 (CodedWalk's), in a version 5
    file (its grid four f32)."""

    kind = 13
    grid = (0.25, -3.0, 1.5, 0.0625)  # float32 values
    grid_format = "<4f"

    def naming_triangle(self, k):
        """The triangle one of whose codes 0 named k."""
        return next(j for j, named in enumerate(self.new) if k in named)

    def gate(self, j):
        """The two corners attached triangle j shares with its parent: (q_e, q_(e+1)) of the
        parent's edge e, which j names (i1, i0)."""
        p, e = self.parent[j]
        return self.tris[p][e], self.tris[p][(e + 1) % 3]

    def later_gate_corner(self, j):
        """Of attached triangle j's gate, the corner its code 0 named later in the walk."""
        order = list(itertools.chain.from_iterable(self.new))  # corners in the order named
        return max(self.gate(j), key=order.index)

    def later_source(self, k):
        """§9.17's predictor of explicit corner k: of the gate of the triangle that named k anew,
        the corner named later, where that triangle is attached and that corner explicit;
        otherwise the previous explicit corner, or None."""
        j = self.naming_triangle(k)
        if self.parent[j] is not None:
            later = self.later_gate_corner(j)
            if self.flags[later]:
                return later
        before = [c for c in self.explicit if c < k]
        return before[-1] if before else None

    def predict(self, k, g, mode, kind):
        if kind != 13:
            return super().predict(k, g, mode, kind)
        j = self.naming_triangle(k)
        if mode & 1 and self.parent[j] is not None:  # §9.12, kind 9's: the parallelogram
            p, e = self.parent[j]
            a, b, o = (self.tris[p][(e + s) % 3] for s in range(3))
            if self.flags[a] and self.flags[b] and self.flags[o]:
                return [g[a][x] + g[b][x] - g[o][x] for x in range(3)]
        source = self.later_source(k)
        return [0, 0, 0] if source is None else list(g[source])

    def cases(self):
        """Per explicit corner, how its predictor is chosen: "i1" (the later gate corner is i1,
        so kind 9's i0 is not it), "i0" (it is i0), "named" (the later gate corner is named, so
        the previous explicit corner, where kind 9 may step from an explicit i0), or "none"
        (a root's corner)."""
        out = {}
        for k in self.explicit:
            j = self.naming_triangle(k)
            if self.parent[j] is None:
                out[k] = "none"
                continue
            later = self.later_gate_corner(j)
            out[k] = "named" if not self.flags[later] else "i0" if later == self.tris[j][0] else "i1"
        return out


def values_to_grid(walk, g, mode):
    """The integer coordinates a reader reports for values g (with tables, indices into them)."""
    if mode & 2:
        tables = walk.tables()
        return [[tables[x][g[k][x]] for x in range(3)] for k in walk.explicit]
    return [list(g[k]) for k in walk.explicit]


def check(data, shell, kind=13, minor=2):
    got = read(data)
    assert "error" not in got, got
    assert got["header"]["version"] == [5, minor]
    group = got["groups"][0]
    assert group["kind"] == kind and group["shell"] == shell
    return got


# --- meshes ---------------------------------------------------------------------------------------

MESHES = trimesh_meshes("icosphere", "torus", "cylinder", "box")


def free_walk(tris, xyz, rng, escape_rate=0.0, path=False):
    used = {c for t in tris for c in t}
    return LaterWalk(tris, [-1] * len(tris), {c: xyz[c] for c in used}, {}, rng, escape_rate, path=path)


def mesh_walks(name, mode):
    """Three walks of a trimesh primitive: as listed, shuffled with escapes, and along strips."""
    tris, xyz = MESHES[name]
    for seed in range(3):
        rng = random.Random(seed * 31 + mode)
        mesh = tris if seed == 0 else shuffled(tris, rng)
        yield free_walk(mesh, xyz, rng, escape_rate=0.3 * (seed == 1), path=seed == 2)


# --- round trips ----------------------------------------------------------------------------------

@pytest.mark.parametrize("mode", [0, 1, 2, 3])
@pytest.mark.parametrize("name", sorted(MESHES))
def test_trimesh_meshes_round_trip(name, mode):
    cases = set()
    for walk in mesh_walks(name, mode):
        cases.update(walk.cases().values())
        got = check(pln([(13, [], [], walk.body(mode))]), walk.shell())
        assert got["findings"] == []
    assert "i1" in cases  # the later gate corner is not always i0 (along a strip it mostly is)


def half_named(name):
    """The golden shell ``name`` with every other explicit corner on exactly three face planes
    named by them instead (§9.11: a named corner's planes are the faces around it)."""
    planes, g, (tris, faces, xyz, named) = golden_shell(name)
    around = {}
    for tri, face in zip(tris, faces):
        for c in tri:
            around.setdefault(c, set()).add(face)
    named = dict(named)
    for c in sorted(xyz)[::2]:
        if -1 not in around[c] and len(around[c]) == 3:
            named[c] = sorted(around[c])
    xyz = {c: v for c, v in xyz.items() if c not in named}
    return planes, g, (tris, faces, xyz, named)


GOLDENS = {name: partial(golden_shell, name) for name in
           ("shell_tree_mixed_v3_3", "shell_tree_pyramid_v3_4", "shell_walk_torus_v4_1")}
GOLDENS["shell_tree_box_v3_4, half named"] = partial(half_named, "shell_tree_box_v3_4")


@pytest.mark.parametrize("mode", [0, 1, 2, 3])
@pytest.mark.parametrize("name", sorted(GOLDENS))
def test_golden_shells_round_trip(name, mode):
    """Named and explicit corners together, faces on planes, the group's references kept."""
    planes, g, (tris, faces, xyz, named) = GOLDENS[name]()
    for seed in range(4):
        walk = LaterWalk(tris, faces, xyz, named, random.Random(seed), escape_rate=0.3 * (seed % 2))
        check(pln([(13, g["refs"], g["bounding"], walk.body(mode))], planes), walk.shell())


def test_a_later_gate_corner_that_is_named():
    """§9.17: "where that triangle is attached and that corner is explicit": where the later gate
    corner is named, the predictor is the previous explicit corner, though the earlier one may be
    explicit (kind 9 steps from i0 there). The golden shells with named corners walk into that
    case."""
    seen = 0
    for name in ("shell_tree_mixed_v3_3", "shell_tree_box_v3_4, half named"):
        planes, g, (tris, faces, xyz, named) = GOLDENS[name]()
        for seed in range(40):
            walk = LaterWalk(tris, faces, xyz, named, random.Random(seed))
            hits = [k for k, case in walk.cases().items() if case == "named"]
            for k in hits:
                assert walk.later_source(k) == max(c for c in walk.explicit if c < k)
                seen += walk.flags[walk.tris[walk.naming_triangle(k)][0]]  # kind 9 would step from i0
            if hits:
                check(pln([(13, g["refs"], g["bounding"], walk.body(0))], planes), walk.shell())
    assert seen


# --- the rule matters -----------------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(MESHES))
def test_read_as_kind_9_the_same_body_is_another_shell(name):
    """Each body read as kind 9 (a kind of 5.2 too) resolves its residuals from i0, as the
    encoder's kind-9 predictor says: to other corners than the kind-13 reading where a corner's
    later gate corner is its i1, to the same where the walk goes along strips (each triangle
    attached across the edge from i1 to the corner its parent named, so that i0 is the later)."""
    differ = 0
    for walk in mesh_walks(name, 0):
        residuals = walk.residuals(0)
        grid = walk.shell()["grid"]
        as_9 = read(pln([(9, [], [], walk.body(0))]))["groups"][0]["shell"]["grid"]
        assert as_9 == values_to_grid(walk, walk.resolve(residuals, 0, kind=9), 0)
        as_13 = read(pln([(13, [], [], walk.body(0, kind=9))]))["groups"][0]["shell"]["grid"]
        rule_matters = "i1" in walk.cases().values()
        assert (as_9 != grid) == (as_13 != grid) == rule_matters
        differ += rule_matters
    assert differ


def test_the_goldens():
    """The 5.2 goldens read as their JSON says; shell_walk_later_values_v5_2, its kind byte made 9
    (its CRC recomputed), decodes to another sphere."""
    for name in ("shell_walk_later_values_v5_2", "shell_walk_later_tables_v5_2"):
        want = json.loads((SUITE / "valid" / f"{name}.json").read_text())
        got = read((SUITE / "valid" / f"{name}.pln").read_bytes())
        assert got["header"] == want["header"] and got["header"]["version"] == [5, 2]
        assert got["groups"] == want["groups"] and got["groups"][-1]["kind"] == 13
    for name in ("xv52_later_in_5_1", "xv52_later_mode_bits", "xv52_later_table_index"):
        want = json.loads((SUITE / "invalid" / f"{name}.json").read_text())
        assert read((SUITE / "invalid" / f"{name}.pln").read_bytes())["error"] == want["error"]
    data = (SUITE / "valid" / "shell_walk_later_values_v5_2.pln").read_bytes()
    as_9 = read(with_group_kind(data, 9))
    got = read(data)
    assert as_9["groups"][0]["kind"] == 9
    assert as_9["groups"][0]["shell"]["grid"] != got["groups"][0]["shell"]["grid"]


def with_group_kind(data: bytes, kind: int) -> bytes:
    """A version 5 file with every GRUP's kind byte set to ``kind`` (§4.1: PHDR's length a u32,
    then varint lengths; §9.1: index and object varints, then the kind)."""
    out = bytearray(data[:8])
    pos = 8
    while pos < len(data):
        ctype = data[pos:pos + 4]
        if ctype == b"PHDR":
            start, length = pos + 8, int.from_bytes(data[pos + 4:pos + 8], "little")
        else:
            start, length, shift = pos + 4, 0, 0
            while True:
                byte = data[start]
                start += 1
                length |= (byte & 0x7F) << shift
                shift += 7
                if byte < 0x80:
                    break
        payload = bytearray(data[start:start + length])
        if ctype == b"GRUP":
            at = 0
            for _ in range(2):
                while payload[at] >= 0x80:
                    at += 1
                at += 1
            payload[at] = kind
        out += data[pos:start] + payload + struct.pack("<I", zlib.crc32(ctype + payload))
        pos = start + length + 4
    return bytes(out)


# --- a fan, field by field ------------------------------------------------------------------------

GRID = struct.pack("<4f", *LaterWalk.grid)


def fan_data(residuals, mode=0, tables=None):
    """Kind data built field by field: n = len(residuals) corners, all explicit, and n - 2 free
    triangles round corner 0: (0 1 2), a root with a child across its edge 2 (symbol 3; escapes
    0 0 0), then (0 k-1 k) for k = 3, 4, …, each attached to the one before across its edge 2
    (from k-1 to 0), so that i0 = 0 and i1 = k - 1, naming k anew, with a child across its own
    edge 2 (symbol 8), the last none (symbol 0). Kind 9 steps every rim corner k from the apex,
    kind 13 from k - 1: in mode 0 its corners are the sums of the residuals so far."""
    n = len(residuals)
    symbols = [3] + [8] * (n - 4) + [0]
    data = uv(n) + uv(n - 2) + uv(3) + b"".join(uv(s) for s in symbols) + uv(0) * 3 + uv(0) * (n - 2)
    data += bytes([0xFF] * (n // 8) + ([(1 << n % 8) - 1] if n % 8 else []))
    data += bytes([mode]) + GRID + (table_bytes(tables) if tables else b"")
    return data + residual_bytes(residuals)


def fan_shell(grid):
    n = len(grid)
    return {"explicit": list(range(n)), "vertex_planes": [], "grid": grid, "origin": list(LaterWalk.grid[:3]),
            "step": LaterWalk.grid[3], "facets": [[-1, 0, 1, 2]] + [[-1, 0, k - 1, k] for k in range(3, n)]}


def sums(residuals):
    return [list(map(sum, zip(*residuals[:k + 1]))) for k in range(len(residuals))]


def test_a_fan_by_hand():
    residuals = [[3, -1, 2], [1, 0, 0], [0, 1, 0], [-1, 0, 1], [0, 0, -2], [5, 5, 5]]
    got = read(pln([(13, [], [], fan_data(residuals))]))
    assert got["groups"][0]["shell"] == fan_shell(sums(residuals)), got
    apex, first = sums(residuals[:3])[0], sums(residuals[:3])
    as_9 = read(pln([(9, [], [], fan_data(residuals))]))["groups"][0]["shell"]
    assert as_9 == fan_shell(first + [[a + r for a, r in zip(apex, res)] for res in residuals[3:]])
    # mode 1: every rim corner from 3 on is the parallelogram over its gate and the parent's
    # opposite corner, g(0) + g(k-1) - g(k-2), the same in kinds 9 and 13
    g = sums(residuals[:3])
    for k in range(3, len(residuals)):
        g.append([g[0][x] + g[k - 1][x] - g[k - 2][x] + residuals[k][x] for x in range(3)])
    for kind in (9, 13):
        assert read(pln([(kind, [], [], fan_data(residuals, 1))]))["groups"][0]["shell"] == fan_shell(g)


# --- hostile bodies -------------------------------------------------------------------------------

@pytest.mark.parametrize("sign", [1, -1])
def test_value_pushed_past_2_52_by_steps_from_the_later_corner(sign):
    """Residuals ±1 on x round the fan from g(0) = ±(2^52 - 5): corner k is ±(2^52 - 5 + k), read
    back up to corner 5 (±2^52), refused at corner 6; kind 9 steps each from the apex and reads
    them all. And a single residual: corner 2 at x = 2^52, corner 3 one past it."""
    for n in (6, 7):
        residuals = [[sign * (LIMIT - 5), 0, 0]] + [[sign, 0, 0]] * (n - 1)
        got = read(pln([(13, [], [], fan_data(residuals))]))
        if n == 6:
            assert got["groups"][0]["shell"] == fan_shell(sums(residuals)), got
            assert sums(residuals)[-1][0] == sign * LIMIT
        else:
            assert got.get("error") == "BAD_GROUP_STRUCTURE" and "explicit corner 6:" in got["why"], got
        assert "error" not in read(pln([(9, [], [], fan_data(residuals))]))
    residuals = [[0, 0, 0], [sign * LIMIT, 0, 0], [0, 1, 0], [sign, 0, 0]]
    got = read(pln([(13, [], [], fan_data(residuals))]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "explicit corner 3:" in got["why"], got
    assert read(pln([(9, [], [], fan_data(residuals))]))["groups"][0]["shell"]["grid"][3] == [sign, 0, 0]
    residuals[3] = [0, 0, 0]
    assert read(pln([(13, [], [], fan_data(residuals))]))["groups"][0]["shell"]["grid"][3] == [sign * LIMIT, 1, 0]


def test_index_outside_its_table_in_a_fan():
    """Mode 2, tables of 3, 1 and 1 values: x indices 0, 1, 1, then a residual of +1 steps corner 3
    from corner 2's index 2 to 3, outside (kind 9: from corner 0's 0 to 1, inside); a residual of
    -1 steps it to 1, inside (kind 9: to -1, outside)."""
    tables = [[0, 10, 20], [5], [7]]
    for r, bad in ((1, 13), (-1, 9)):
        residuals = [[0, 0, 0], [1, 0, 0], [1, 0, 0], [r, 0, 0]]
        for kind in (9, 13):
            got = read(pln([(kind, [], [], fan_data(residuals, 2, tables))]))
            if kind == bad:
                index = 3 if kind == 13 else -1
                assert got.get("error") == "BAD_GROUP_STRUCTURE", got
                assert f"explicit corner 3: index {index} outside" in got["why"], got
            else:
                x = [0, 10, 20, 20 + 10 * r] if kind == 13 else [0, 10, 20, 10]
                assert got["groups"][0]["shell"]["grid"] == [[v, 5, 7] for v in x], got


@pytest.mark.parametrize("mode", [2, 3])
def test_index_outside_its_table_in_a_mesh(mode):
    """The last corner of the cylinder whose predictor is its later gate corner, pushed to index -1
    and to C on each axis by its residual (the corners after it coded from the pushed value)."""
    tris, xyz = MESHES["cylinder"]
    walk = free_walk(tris, xyz, random.Random(5))
    k = [c for c, case in walk.cases().items() if case == "i1"][-1]
    size = [len(t) for t in walk.tables()]
    head = walk.body(mode)[:-len(residual_bytes([walk.residuals(mode)[c] for c in walk.explicit]))]
    for axis in range(3):
        for index in (-1, size[axis]):
            g = walk.values(mode)
            g[k][axis] = index
            residuals = walk.residuals(mode, g=g)
            got = read(pln([(13, [], [], head + residual_bytes([residuals[c] for c in walk.explicit]))]))
            assert got.get("error") == "BAD_GROUP_STRUCTURE", got
            assert f"explicit corner {k}: index {index} outside" in got["why"], got


@pytest.mark.parametrize("mode", [4, 6, 0x80, 0xFF])
def test_a_mode_bit_above_1(mode):
    residuals = [[0, 0, 0], [1, 0, 0], [0, 0, 0], [0, 0, 0]]
    tables = [[0, 10], [5], [7]] if mode & 2 else None
    got = read(pln([(13, [], [], fan_data(residuals, mode, tables))]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "mode" in got["why"], got
    # the same with the mode's low bits alone is read
    assert "error" not in read(pln([(13, [], [], fan_data(residuals, mode & 3, tables))]))


def test_kind_13_errors_are_kind_9_s():
    """§9.17: the checks and errors are those of §9.13; a few of them, on a kind-13 body."""
    data = fan_data([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    assert read(pln([(13, [], [], data + b"\x00")])).get("error") == "BAD_GROUP_STRUCTURE"
    assert read(pln([(13, [], [], data[:-1])])).get("error") == "BAD_PAYLOAD"
    got = read(pln([(13, [], [], fan_data([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, LIMIT + 1]]))]))
    assert got.get("error") == "BAD_GROUP_STRUCTURE" and "residual" in got["why"], got
    bad_symbol = uv(4) + uv(2) + uv(3) + uv(3) + uv(20)  # an attached symbol 20: c = 5, past 4
    assert read(pln([(13, [], [], bad_symbol + data[len(bad_symbol):])])).get("error") == "BAD_GROUP_STRUCTURE"


# --- versions (§9.2, §9.3, §13) -------------------------------------------------------------------

def test_kind_13_by_version():
    residuals = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    group = (13, [], [], fan_data(residuals))
    got = read(pln([group]))
    shell = got["groups"][0]["shell"]
    assert shell["grid"] == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 1, 1]] and got["findings"] == []
    # §9.3: 5.0 and 5.1 are minors this reader knows, and kind 13 not one of their kinds
    for minor in (0, 1):
        assert read(pln([group], minor=minor))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([group], minor=3))  # a newer minor: read, and said so
    assert got["groups"][0]["shell"] == shell and got["findings"] == ["NEWER_MINOR_VERSION"]
    # kind 14: unknown in 5.2; skipped in 5.3, its m = 0 not an error (§9.2), the next group read
    assert read(pln([(14, [], [], b"\x05")]))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(14, [], [], b"\x05"), group], minor=3))
    assert set(got["findings"]) == {"SKIPPED_GROUP_KIND", "NEWER_MINOR_VERSION"}
    assert "shell" not in got["groups"][0] and got["groups"][1]["shell"] == shell
    # major 4 has no kind 13: unknown in 4.2, skipped in 4.3 (with a reference, A.5)
    plane = [[0.0, 0.0, 1.0]]
    assert read(pln([(13, [0], [], b"\x05")], plane, minor=2, major=4))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(13, [0], [], b"\x05")], plane, minor=3, major=4))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and "shell" not in got["groups"][0]
    # a copy of a kind 13 group, beside kinds 9 and 12, in a 5.2 file
    got = read(pln([group, (9, [], [], fan_data(residuals)), (12, [], [], fan_data(residuals)),
                    (11, [], [], uv(0))]))
    assert got["groups"][1]["shell"]["grid"] == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 1]]  # kind 9: from 0
    assert got["groups"][3]["source"] == 0 and "error" not in got and got["findings"] == []
