"""Kind 10 (spec/pln.md §9.14, shell walks with multi-parallelograms) in the independent reader
conformance/independent/plnread.py, on hand-built version 4.2 files.

The files come from an encoder written from the text of §9.13 and §9.14 (neither from planefmt
nor from either independent reader): tests/spec_files.py's walk, and the prediction here. It
differs from plnread on purpose where it can: the walk keeps the open edges of §9.13 as a plain
list searched from its newest end, a far corner is found by scanning the triangles in order for
the first that has the reverse edge, and an average is rounded with exact fractions (math.floor
of a Fraction) rather than integer floor division. Each mesh (golden shells with named and explicit corners,
trimesh's primitives, open and shuffled meshes, triangle soups with non-manifold and repeated
edges) is encoded in all four modes, read back, and compared with the shell the encoder meant;
then hostile bodies (a resolved value pushed past 2^52 along a chain of corners whose residuals
all stay within 2^52; an index pushed outside its table) must be refused with
BAD_GROUP_STRUCTURE, and the version rules of §9.3 and §13 hold for kind 10."""

from __future__ import annotations

import math
import random
import struct
from fractions import Fraction
from functools import partial

import pytest

from spec_files import (Walk, golden_shell, pln_file, plnread, residual_bytes, shuffled, table_bytes,
                        trimesh_meshes, uv, walk_head, zigzag)
from spec_files import read_read as read

LIMIT = 2**52

pln = partial(pln_file, major=4, minor=2, units=0, name=b"m")


# --- predictions (§9.11, §9.12, §9.13, §9.14) ----------------------------------------------------

def far_corner(tris, a, b):
    """§9.14: the corner other than a and b of the first triangle, in triangle order, that has the
    edge (b, a); None where none has it."""
    for tri in tris:
        for s in range(3):
            if tri[s] == b and tri[(s + 1) % 3] == a:
                return tri[(s + 2) % 3]
    return None


def parallelograms(tris, k, explicit):
    """§9.14: the first four parallelograms (a, b, c) of corner k."""
    out = []
    for tri in tris:
        for s in range(3):
            if tri[s] != k:
                continue
            a, b = tri[(s + 1) % 3], tri[(s + 2) % 3]
            c = far_corner(tris, a, b)
            if c is not None and all(v in explicit and v < k for v in (a, b, c)):
                out.append((a, b, c))
    return out[:4]


def walk_prediction(walk, k, explicit, value, previous, mode):
    """§9.13's prediction of explicit corner k: §9.11's, or with mode bit 0 §9.12's."""
    j = walk.creator[k]
    tri = walk.tris[j]
    if walk.parent[j] is not None and mode & 1:
        p, e = walk.parent[j]
        o = walk.tris[p][(e + 2) % 3]
        if tri[0] in explicit and tri[1] in explicit and o in explicit:
            return [value[tri[0]][a] + value[tri[1]][a] - value[o][a] for a in range(3)]
    if walk.parent[j] is not None and tri[0] in explicit:
        return list(value[tri[0]])
    return list(value[previous]) if previous is not None else [0, 0, 0]


def predict(walk, k, explicit, value, previous, mode, multi, stats=None):
    grams = parallelograms(walk.tris, k, explicit) if multi else []
    if stats is not None:
        stats[len(grams)] = stats.get(len(grams), 0) + 1
    if not grams:
        return walk_prediction(walk, k, explicit, value, previous, mode)
    n = len(grams)
    sums = [sum(value[a][ax] + value[b][ax] - value[c][ax] for a, b, c in grams) for ax in range(3)]
    if stats is not None:
        for total in sums:
            if total < 0 and (total + n // 2) % n:
                stats[("negative inexact", n)] = stats.get(("negative inexact", n), 0) + 1
    return [math.floor(Fraction(s + n // 2, n)) for s in sums]


def residuals_for(walk, explicit, value, mode, multi, stats=None):
    """The residual of every explicit corner (corner order) that makes it resolve to `value`."""
    out, previous = [], None
    for k in sorted(explicit):
        pred = predict(walk, k, explicit, value, previous, mode, multi, stats)
        out.append([value[k][a] - pred[a] for a in range(3)])
        previous = k
    return out


def resolve(walk, explicit, residuals, mode, multi):
    """The decoder's side, for the hostile tests: resolved values in corner order, and the first
    corner whose residual or value is beyond 2^52 (or None)."""
    value, previous = {}, None
    for k, res in zip(sorted(explicit), residuals):
        pred = predict(walk, k, explicit, value, previous, mode, multi)
        value[k] = [pred[a] + res[a] for a in range(3)]
        if any(abs(r) > LIMIT for r in res) or any(abs(v) > LIMIT for v in value[k]):
            return value, k
        previous = k
    return value, None


# --- the kind data --------------------------------------------------------------------------------

ORIGIN, STEP = [0.25, -3.0, 1.5], 0.0625


def kind_data(walk, faces, explicit_xyz, named_planes, mode, multi=True, residuals=None, tables=None, stats=None):
    """Kind 10 data (kind 9 with multi=False) for a walk, faces, explicit_xyz and named_planes as
    walk_head takes them. Returns the data and the "shell" object a reader must report.
    `residuals` and `tables` override what the encoder would compute (hostile bodies)."""
    data, shell = walk_head(walk, faces, explicit_xyz, named_planes)
    if shell["explicit"]:
        shell["origin"], shell["step"] = ORIGIN, STEP
        data += bytes([mode]) + struct.pack("<4d", *ORIGIN, STEP)
        value = {k: list(g) for k, g in zip(shell["explicit"], shell["grid"])}
        if mode & 2:
            if tables is None:
                tables = [sorted({g[a] for g in shell["grid"]}) for a in range(3)]
            data += table_bytes(tables)
            value = {k: [tables[a].index(g[a]) for a in range(3)] for k, g in value.items()}
        if residuals is None:
            residuals = residuals_for(walk, set(value), value, mode, multi, stats)
        data += residual_bytes(residuals)
    return data, shell


# --- meshes ---------------------------------------------------------------------------------------

MESHES = trimesh_meshes("icosphere", "box", "capsule", "cylinder", "torus", "cone")


def open_mesh(tris, rng, drop=0.15):
    """A mesh with holes: some triangles dropped (corners no triangle uses disappear)."""
    return [t for t in tris if rng.random() >= drop]


def soup(rng, corners=10, count=36):
    """Random triangles over few corners: non-manifold edges, repeated and reversed triangles."""
    tris = [rng.sample(range(corners), 3) for _ in range(count)]
    tris += [tris[0][::-1], list(tris[1])]
    xyz = {c: [rng.randrange(-40, 41), rng.randrange(-9, 9), rng.randrange(1000)] for c in range(corners)}
    return tris, xyz


PLANE = [[0.0, 0.0, 1.0]]


def encode_free(tris, xyz, mode, rng, multi=True, escape_rate=0.0, stats=None):
    """A shell of explicit corners and free triangles, as a file of one group of one reference."""
    used = {c for t in tris for c in t}
    walk = Walk(tris, rng, escape_rate)
    data, shell = kind_data(walk, [-1] * len(tris), {c: xyz[c] for c in used}, {}, mode, multi, stats=stats)
    return pln([(10 if multi else 9, [0], [], data)], PLANE), shell, walk


def check(data, shell, kind=10, minor=2):
    got = read(data)
    assert "error" not in got, got
    assert got["header"]["version"] == [4, minor]
    group = got["groups"][0]
    assert group["kind"] == kind and group["shell"] == shell
    return got


# --- round trips ----------------------------------------------------------------------------------

@pytest.mark.parametrize("mode", [0, 1, 2, 3])
@pytest.mark.parametrize("name", sorted(MESHES))
def test_trimesh_meshes_round_trip(name, mode):
    tris, xyz = MESHES[name]
    for seed in range(3):
        rng = random.Random(seed * 31 + mode)
        mesh = tris if seed == 0 else shuffled(tris, rng)
        if seed == 2:
            mesh = open_mesh(mesh, rng)
        data, shell, _ = encode_free(mesh, xyz, mode, rng, escape_rate=0.25 * seed)
        got = check(data, shell)
        assert "NEWER_MINOR_VERSION" not in got["findings"]


@pytest.mark.parametrize("mode", [0, 1, 2, 3])
def test_soups_round_trip(mode):
    for seed in range(12):
        rng = random.Random(1000 + seed)
        tris, xyz = soup(rng, corners=6 + seed % 5, count=20 + 3 * seed)
        data, shell, _ = encode_free(tris, xyz, mode, rng, escape_rate=0.3 if seed % 2 else 0.0)
        check(data, shell)


GOLDENS = ["shell_tree_cube_v3_3", "shell_tree_mixed_v3_3", "shell_tree_apex_v3_3", "shell_tree_pyramid_v3_3",
           "shell_tree_box_v3_4", "shell_tree_pyramid_v3_4", "shell_walk_cube_v4_1", "shell_walk_sphere_v4_1",
           "shell_walk_torus_v4_1", "shell_walk_multi_sphere_v4_2", "shell_walk_multi_tables_v4_2"]


@pytest.mark.parametrize("mode", [0, 1, 2, 3])
@pytest.mark.parametrize("name", GOLDENS)
def test_golden_shells_round_trip(name, mode):
    """Named and explicit corners together, faces on planes: the parallelograms skip named corners."""
    planes, g, (tris, faces, xyz, named) = golden_shell(name)
    for seed in range(4):
        rng = random.Random(seed)
        walk = Walk(tris, rng, escape_rate=0.3 * (seed % 2))
        data, shell = kind_data(walk, faces, xyz, named, mode)
        check(pln([(10, g["refs"], g["bounding"], data)], planes), shell)


def test_every_count_of_parallelograms_is_met():
    """The meshes above reach corners of 0, 1, 2, 3 and 4 parallelograms, and corners with more
    than four candidates (capped)."""
    stats = {}
    capped = 0
    for name in ("icosphere", "torus", "capsule"):
        tris, xyz = MESHES[name]
        for seed in range(2):
            rng = random.Random(seed)
            data, shell, walk = encode_free(shuffled(tris, rng) if seed else tris, xyz, 1, rng, stats=stats)
            check(data, shell)
            explicit = set(range(len(walk.number)))
            for k in explicit:
                whole = [1 for tri in walk.tris for s in range(3) if tri[s] == k
                         and (c := far_corner(walk.tris, tri[(s + 1) % 3], tri[(s + 2) % 3])) is not None
                         and max(tri[(s + 1) % 3], tri[(s + 2) % 3], c) < k]
                capped += len(whole) > 4
    assert {n for n in stats if isinstance(n, int)} == {0, 1, 2, 3, 4} and capped > 0, (stats, capped)


def test_kind_9_and_kind_10_read_one_body_differently():
    """The same walk coded for kind 9 and for kind 10: each read back as its kind says, and the
    kind-10 body read as kind 9 gives other coordinates (the rule §9.14 changes)."""
    tris, xyz = MESHES["icosphere"]
    for mode in range(4):
        d9, shell9, _ = encode_free(tris, xyz, mode, random.Random(5), multi=False)
        d10, shell10, _ = encode_free(tris, xyz, mode, random.Random(5), multi=True)
        check(d9, shell9, kind=9)
        check(d10, shell10, kind=10)
        # retag the kind-10 group as kind 9: the CRC is recomputed by rebuilding the file
        walk = Walk(tris, random.Random(5))
        data, _ = kind_data(walk, [-1] * len(tris), xyz, {}, mode, multi=True)
        got = read(pln([(9, [0], [], data)], PLANE))
        assert got.get("error") or got["groups"][0]["shell"]["grid"] != shell10["grid"]


def test_rounding_toward_minus_infinity():
    """§9.14's parallelograms on a hand-numbered hub, and its rounding worked out by hand; then
    round trips whose averages have negative sums that n does not divide, for n = 2, 3 and 4,
    where rounding toward zero (or half away from zero) would decode other coordinates."""
    # ring 0..3 around hub 4, far sides 5..8 over the ring's edges, listed before the hub's
    tris = [[0, 1, 5], [1, 2, 6], [2, 3, 7], [3, 0, 8], [4, 1, 0], [4, 2, 1], [4, 3, 2], [4, 0, 3]]
    explicit = set(range(9))
    # hub triangle (4 1 0): opposite edge (1, 0), reverse (0, 1) in (0 1 5), far corner 5 > 4: none;
    # so the hub has no parallelogram with this numbering, and corner 5 has (1, 0, 4)? 4 < 5 yes
    assert parallelograms(tris, 4, explicit) == []
    assert parallelograms(tris, 5, explicit) == [(0, 1, 4)]
    assert parallelograms(tris, 8, explicit) == [(3, 0, 4)]
    # renumbered so the hub comes last: 4 <-> 8
    swap = {4: 8, 8: 4}
    tris2 = [[swap.get(c, c) for c in t] for t in tris]
    assert parallelograms(tris2, 8, explicit) == [(1, 0, 5), (2, 1, 6), (3, 2, 7), (0, 3, 4)]
    value = {0: [0, 0, 0], 1: [1, -1, 2], 2: [0, -2, 1], 3: [-1, 0, 0], 5: [3, 4, -2], 6: [2, 2, 2],
             7: [0, 0, 7], 4: [1, 1, 1]}
    grams = parallelograms(tris2, 8, explicit)
    sums = [sum(value[a][x] + value[b][x] - value[c][x] for a, b, c in grams) for x in range(3)]
    assert sums == [-6, -13, -2]
    # floor((S + 2) / 4): -4/4 -> -1, -11/4 -> -3, 0/4 -> 0 (toward zero: -1, -2, 0)
    assert [math.floor(Fraction(s + 2, 4)) for s in sums] == [-1, -3, 0]
    assert [int((s + 2) / 4) for s in sums] == [-1, -2, 0]
    # round trips that meet such averages
    events = {}
    for name in ("icosphere", "torus", "capsule"):
        tris3, xyz = MESHES[name]
        for mode in (0, 3):
            data, shell, walk = encode_free(tris3, xyz, mode, random.Random(2), stats=events)
            check(data, shell)
    assert all(events.get(("negative inexact", n), 0) > 0 for n in (2, 3, 4)), events


def test_average_prediction_by_hand():
    """A file built by hand, field by field: two triangles (0 1 2) and (2 1 3), then (3 1 4)
    attached; corner 3's candidate over (2 1)... see the comments. The reader's coordinates are
    compared with numbers worked out here from §9.14's formula."""
    # root (0 1 2) with a child across edge 1 (1 -> 2): symbol 2; its codes 0 0 0.
    # attached (2 1 3), code 0 (corner 3 new), a child across its edge 1 (1 -> 3): symbol 4*1 + 0.
    # attached (3 1 4), code 0 (corner 4 new), no child: symbol 0.
    # Far corners: corner 3 in (2 1 3) at place 2: a = 2, b = 1, reverse (1 2) is in (0 1 2): c = 0.
    #   So corner 3 has one parallelogram (2, 1, 0): prediction g(2) + g(1) - g(0).
    # corner 4 in (3 1 4): a = 3, b = 1, reverse (1 3) is in (2 1 3)? its edges are (2 1) (1 3) (3 2):
    #   (1 3) yes, c = 2: one parallelogram (3, 1, 2).
    body = uv(5) + uv(3) + uv(3) + uv(2) + uv(4) + uv(0) + uv(0) * 3 + uv(1) + uv(0) + uv(0)
    body += bytes([0x1F]) + bytes([0]) + struct.pack("<4d", 0, 0, 0, 1)
    g = {0: [0, 0, 0], 1: [10, 0, 0], 2: [0, 10, 0]}
    g[3] = [g[2][a] + g[1][a] - g[0][a] + [1, -1, 5][a] for a in range(3)]  # residual (1, -1, 5)
    g[4] = [g[3][a] + g[1][a] - g[2][a] + [-7, 0, 2][a] for a in range(3)]  # residual (-7, 0, 2)
    # kind 9 mode 0 would predict corner 3 from i0 = 2 and corner 4 from i0 = 3 instead
    res = [g[0], [10, 0, 0], [-10, 10, 0], [1, -1, 5], [-7, 0, 2]]
    for a in range(3):
        body += b"".join(uv(zigzag(r[a])) for r in res)
    got = read(pln([(10, [0], [], body)], PLANE))
    assert got["groups"][0]["shell"]["grid"] == [g[k] for k in range(5)], got
    assert got["groups"][0]["shell"]["facets"] == [[-1, 0, 1, 2], [-1, 2, 1, 3], [-1, 3, 1, 4]]
    # kind 9 reads the same body with §9.11's prediction: corner 3 = g(2) + residual
    got9 = read(pln([(9, [0], [], body)], PLANE, minor=1))
    assert got9["groups"][0]["shell"]["grid"][3] == [0 + 1, 10 - 1, 0 + 5]


# --- hostile bodies -------------------------------------------------------------------------------

def strip(length):
    """A long strip of triangles (a chain of corners each predicted over the one before): corners
    0, 1 and then one new corner per triangle."""
    tris = []
    for i in range(length):
        tris.append([i, i + 1, i + 2] if i % 2 == 0 else [i + 1, i, i + 2])
    return tris


def hostile(tris, residual_of, mode=1, rng_seed=0):
    """A kind-10 file whose residuals are given (corner order -> [rx, ry, rz]), and the first
    corner the text says must fail (None if none)."""
    walk = Walk(tris, random.Random(rng_seed))
    explicit = set(range(len(walk.number)))
    residuals = [residual_of(k) for k in sorted(explicit)]
    xyz = {s: [0, 0, 0] for s in walk.number}  # unused: residuals are given
    data, _ = kind_data(walk, [-1] * len(tris), xyz, {}, mode, residuals=residuals)
    _, bad = resolve(walk, explicit, residuals, mode, True)
    return pln([(10, [0], [], data)], PLANE), bad, walk


@pytest.mark.parametrize("mode", [0, 1])
def test_value_pushed_past_2_52_along_a_chain(mode):
    """Every residual within 2^52, but the values grow along the strip (each corner the average of
    parallelograms over the ones before, plus a large residual) until one passes 2^52."""
    tris = strip(120)
    for big in (2**46, 2**50, 2**52):
        data, bad, walk = hostile(tris, lambda k: [big, -big, big // 3], mode)
        assert bad is not None, "the chain must pass 2^52"
        got = read(data)
        assert got.get("error") == "BAD_GROUP_STRUCTURE", got
    # within bounds: small residuals along the same strip decode, and match the encoder's side
    data, bad, walk = hostile(tris, lambda k: [1, -2, 3], mode)
    assert bad is None
    got = read(data)
    value, _ = resolve(walk, set(range(len(walk.number))), [[1, -2, 3]] * len(walk.number), mode, True)
    assert got["groups"][0]["shell"]["grid"] == [value[k] for k in sorted(value)]


def test_value_exactly_at_and_past_2_52():
    """Corner 3 of (0 1 2), (2 1 3) has one parallelogram; with corners 0, 1 and 2 all at s·2^51
    on x it is predicted s·2^51, and a residual of s·2^51 resolves it to s·2^52 (valid), one more
    to beyond 2^52 (refused), every residual within 2^52. A residual beyond 2^52 alone is refused."""
    tris = [[0, 1, 2], [2, 1, 3]]
    for sign in (1, -1):
        for extra, ok in ((0, True), (1, False)):
            res = [[sign * 2**51, 0, 0], [0, 0, 0], [0, 0, 0], [sign * (2**51 + extra), 0, 0]]
            data, bad, walk = hostile(tris, lambda k: res[k], mode=0)
            assert parallelograms(walk.tris, 3, {0, 1, 2, 3}) != []
            assert (bad is None) == ok
            got = read(data)
            if ok:
                assert got["groups"][0]["shell"]["grid"][3] == [sign * LIMIT, 0, 0], got
            else:
                assert got.get("error") == "BAD_GROUP_STRUCTURE", got
    data, bad, _ = hostile(tris, lambda k: [LIMIT + 1, 0, 0] if k == 0 else [0, 0, 0], mode=0)
    assert bad == 0 and read(data).get("error") == "BAD_GROUP_STRUCTURE"


@pytest.mark.parametrize("mode", [2, 3])
def test_index_outside_its_table(mode):
    """With tables, a resolved index below 0 or at C is refused, including one the average pushes
    out of a table whose residuals are all small."""
    tris, xyz = MESHES["icosphere"]
    walk = Walk(tris, random.Random(3))
    explicit = set(range(len(walk.number)))
    src = {k: s for s, k in walk.number.items()}
    grid = [xyz[src[k]] for k in sorted(explicit)]
    tables = [sorted({p[a] for p in grid}) for a in range(3)]
    value = {k: [tables[a].index(xyz[src[k]][a]) for a in range(3)] for k in explicit}
    residuals = residuals_for(walk, explicit, value, mode, True)
    data, shell = kind_data(walk, [-1] * len(tris), xyz, {}, mode, residuals=residuals, tables=tables)
    check(pln([(10, [0], [], data)], PLANE), shell)
    last = max(explicit)
    for axis in range(3):
        for push in (len(tables[axis]) - value[last][axis], -value[last][axis] - 1):  # to C, to -1
            bad = [list(r) for r in residuals]
            bad[-1][axis] += push
            data, _ = kind_data(walk, [-1] * len(tris), xyz, {}, mode, residuals=bad, tables=tables)
            assert read(pln([(10, [0], [], data)], PLANE)).get("error") == "BAD_GROUP_STRUCTURE"
    # an early corner out of its table: every later corner's prediction would build on it
    first_with = next(k for k in sorted(explicit) if parallelograms(walk.tris, k, explicit))
    bad = [list(r) for r in residuals]
    bad[sorted(explicit).index(first_with)][0] += len(tables[0])
    data, _ = kind_data(walk, [-1] * len(tris), xyz, {}, mode, residuals=bad, tables=tables)
    assert read(pln([(10, [0], [], data)], PLANE)).get("error") == "BAD_GROUP_STRUCTURE"


def test_tables_chain_stays_in_table_only_by_its_residuals():
    """Small tables on a long strip in mode 2: residuals that keep every index in range decode;
    residuals of 1 everywhere push the averaged indices out (BAD_GROUP_STRUCTURE)."""
    tris = strip(40)
    walk = Walk(tris, random.Random(0))
    n = len(walk.number)
    tables = [list(range(n)), [0, 5], [-3]]
    xyz = {s: [0, 0, -3] for s in walk.number}
    explicit = set(range(n))
    value = {k: [k, k % 2, 0] for k in explicit}
    residuals = residuals_for(walk, explicit, value, 2, True)
    data, _ = kind_data(walk, [-1] * len(tris), xyz, {}, 2, residuals=residuals, tables=tables)
    got = read(pln([(10, [0], [], data)], PLANE))
    assert got["groups"][0]["shell"]["grid"] == [[tables[0][k], tables[1][k % 2], -3] for k in range(n)]
    data, _ = kind_data(walk, [-1] * len(tris), xyz, {}, 2, residuals=[[1, 0, 0]] * n, tables=tables)
    assert read(pln([(10, [0], [], data)], PLANE)).get("error") == "BAD_GROUP_STRUCTURE"


# --- versions (§5, §9.3, §13) ---------------------------------------------------------------------

def small():
    tris, xyz = MESHES["box"]
    walk = Walk(tris, random.Random(0))
    return kind_data(walk, [-1] * len(tris), xyz, {}, 1)


def test_kind_10_by_version():
    data, shell = small()
    group = (10, [0], [], data)
    got = read(pln([group], PLANE, minor=2))
    assert got["groups"][0]["shell"] == shell and "NEWER_MINOR_VERSION" not in got["findings"]
    for minor in (0, 1):  # §9.3: kind 10 is not a kind of 4.0 or 4.1, minors this reader knows
        assert read(pln([group], PLANE, minor=minor))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([group], PLANE, minor=3))  # a newer minor: read, and said so
    assert got["groups"][0]["shell"] == shell and "NEWER_MINOR_VERSION" in got["findings"]
    # kind 12: unknown in 4.2, skipped in 4.3 (its common body still checked, its group counted);
    # kind 11 is the copy of §9.15, a kind of 4.2 (tests/test_independent_copies_read.py)
    assert read(pln([(12, [0], [], b"\x07")], PLANE, minor=2))["error"] == "UNKNOWN_GROUP_KIND"
    got = read(pln([(12, [0], [], b"\x07"), group], PLANE, minor=3))
    assert "SKIPPED_GROUP_KIND" in got["findings"] and "shell" not in got["groups"][0]
    assert got["groups"][1]["shell"] == shell
    # kind 9 is still a kind of 4.2
    d9, s9, _ = encode_free(*MESHES["box"], 1, random.Random(0), multi=False)
    check(d9, s9, kind=9)


def test_kind_10_errors_are_kind_9_s():
    """§9.14: the errors are those of §9.13; a few of them, on a kind-10 body."""
    data, _ = small()
    assert read(pln([(10, [0], [], data + b"\x00")], PLANE)).get("error") == "BAD_GROUP_STRUCTURE"
    assert read(pln([(10, [0], [], data[:-1])], PLANE)).get("error") == "BAD_PAYLOAD"
    cursor = plnread.Cursor(data, "t")
    v, t, x = cursor.varint(), cursor.varint(), cursor.varint()
    first_symbol = len(uv(v)) + len(uv(t)) + len(uv(x))
    bad = bytearray(data)
    bad[first_symbol] = 16  # a root symbol past its range
    assert read(pln([(10, [0], [], bytes(bad))], PLANE)).get("error") == "BAD_GROUP_STRUCTURE"
