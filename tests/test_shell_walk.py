"""Shell walks (kind 9, spec §9.13): the walk decodes what the encoder walked, in C and in Python
alike; hostile walks are refused with BAD_GROUP_STRUCTURE or BAD_PAYLOAD in linear time; files for
readers of 3.x carry the walk as a shell tree."""

from __future__ import annotations

import io

import brotli
import numpy as np
import pytest
import trimesh

import planefmt
from planefmt import codec
from planefmt.container import shellfields, shellwalk, varint
from planefmt.container.shellfields import first_use_order
from planefmt.errors import FormatError
from planefmt.groups.shells import shell_tree
from planefmt.model import GroupKind, Shell

from corpus import CORPUS


def explicit_walk(vertices: np.ndarray, faces: np.ndarray, step: float = 0.01) -> Shell:
    """``faces`` over ``vertices`` as a walk of free triangles over explicit corners."""
    rank = first_use_order(faces, len(vertices))
    grid = np.zeros((len(vertices), 3), dtype=np.int64)
    grid[rank[rank >= 0]] = np.rint(vertices[rank >= 0] / step).astype(np.int64)
    grid = grid[:int(rank.max()) + 1]
    flat = Shell(explicit=np.ones(len(grid), dtype=bool), vertex_planes=np.zeros((0, 3), dtype=np.int64), grid=grid,
                 origin=np.zeros(3), step=step, facets=np.column_stack([np.full(len(faces), -1), rank[faces]]))
    return shell_tree(flat)[0]


def decode_body(body: bytes, kind: GroupKind = GroupKind.SHELL_WALK) -> Shell:
    return shellwalk.decode_shell_walk(np.frombuffer(body, dtype=np.uint8), np.zeros(1, dtype=bool), kind)


def same(a: Shell, b: Shell) -> bool:
    return all(np.array_equal(np.asarray(getattr(a, f)).reshape(-1), np.asarray(getattr(b, f)).reshape(-1))
               for f in ("explicit", "grid", "facets", "links"))


_SPHERE = trimesh.creation.icosphere(subdivisions=2)
MESHES = {"sphere": _SPHERE, "torus": trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12),
          "open cap": trimesh.Trimesh(_SPHERE.vertices, _SPHERE.faces[:150], process=False)}


@pytest.mark.parametrize("name", sorted(MESHES))
@pytest.mark.parametrize("mode", [0, 1, 2, 3])
@pytest.mark.parametrize("kind", shellwalk.WALK_KINDS)
def test_a_walk_decodes_to_the_shell_it_was_made_from_in_c_and_in_python(name, mode, kind, monkeypatch):
    m = MESHES[name]
    shell = explicit_walk(np.asarray(m.vertices), np.asarray(m.faces))
    body = b"".join(shellwalk.shell_walk_fields(shell, mode, kind).values())
    assert same(decode_body(body, kind), shell)
    monkeypatch.setattr(shellwalk, "_walk_c", None)
    monkeypatch.setattr(shellwalk, "_walk_codes_c", None)
    monkeypatch.setattr(shellfields, "_average", None)
    monkeypatch.setattr(shellfields, "_parallelograms", None)
    monkeypatch.setattr(shellfields, "_reflect", None)
    monkeypatch.setattr(shellfields, "_tree_terms", None)
    assert b"".join(shellwalk.shell_walk_fields(shell, mode, kind).values()) == body
    assert same(decode_body(body, kind), shell)


def spec_parallelograms(tri: np.ndarray, explicit: np.ndarray) -> list[list[tuple[int, int, int]]]:
    """Spec §9.14's parallelograms of each corner, by its words: loops, not planefmt's sorts."""
    far = {}
    for t in tri.tolist():
        for s in range(3):
            far.setdefault((t[(s + 1) % 3], t[s]), t[(s + 2) % 3])  # the triangle with (b, a) -> its third corner
    out = [[] for _ in explicit]
    for t in tri.tolist():
        for s in range(3):
            k, a, b = t[s], t[(s + 1) % 3], t[(s + 2) % 3]
            c = far.get((a, b))
            if c is not None and max(a, b, c) < k and explicit[[k, a, b, c]].all() and len(out[k]) < 4:
                out[k].append((a, b, c))
    return out


@pytest.mark.parametrize("name", sorted(MESHES))
@pytest.mark.parametrize("in_c", [True, False])
def test_parallelograms_are_the_first_four_of_spec_order(name, in_c, monkeypatch):
    if in_c and shellfields._parallelograms is None:
        pytest.skip("the C extension was not built")
    if not in_c:
        monkeypatch.setattr(shellfields, "_parallelograms", None)
    m = MESHES[name]
    shell = explicit_walk(np.asarray(m.vertices), np.asarray(m.faces))
    tri = np.asarray(shell.facets)[:, 1:]
    explicit = np.asarray(shell.explicit, dtype=bool).copy()
    explicit[::7] = False  # named corners are no terms
    start, terms = shellfields.parallelograms(tri, explicit)
    want = spec_parallelograms(tri, explicit)
    assert [terms[start[k]:start[k + 1]].tolist() for k in range(len(explicit))] == [[list(x) for x in w] for w in want]
    assert max(map(len, want)) >= 3 and sum(len(w) >= 2 for w in want) >= 10


@pytest.mark.skipif(shellfields._average is None, reason="the C extension was not built")
def test_averaged_corners_resolve_the_same_in_c_and_in_python(monkeypatch):
    rng = np.random.default_rng(3)
    m = MESHES["torus"]
    shell = explicit_walk(np.asarray(m.vertices), np.asarray(m.faces))
    tri = np.asarray(shell.facets)[:, 1:]
    explicit = np.ones(len(shell.explicit), dtype=bool)
    start, terms = shellfields.parallelograms(tri, explicit)
    v = len(explicit)
    pointer = np.r_[-1, np.arange(v - 1)]
    plus, minus = np.full(v, -1), np.full(v, -1)
    for scale in (1, 1 << 20, 1 << 40):
        residual = rng.integers(-scale, scale, v)
        fast = shellfields._resolve_averaged(residual, pointer, plus, minus, start, terms)
        with monkeypatch.context() as patch:
            patch.setattr(shellfields, "_average", None)
            slow = shellfields._resolve_averaged(residual, pointer, plus, minus, start, terms)
        assert np.array_equal(fast, slow)
    # Residuals of 2^52 everywhere: sums past 2^52 within a few corners, refused as they are made.
    for average in (shellfields._average, None):
        monkeypatch.setattr(shellfields, "_average", average)
        with pytest.raises(FormatError, match="beyond 2\\^52"):
            shellfields._resolve_averaged(np.full(v, 1 << 52), pointer, plus, minus, start, terms)


def test_a_non_manifold_soup_walks_too():
    # Two triangles on one edge the same way round, a fin of three on one edge, and a flap: every
    # third corner the open edges cannot name is an escape.
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=np.float64)
    f = np.array([[0, 1, 2], [0, 1, 3], [1, 0, 4], [0, 1, 5], [2, 1, 0]])
    shell = explicit_walk(v, f, 0.5)
    assert same(decode_body(shellwalk.shell_walk_body(shell)), shell)


def test_random_bytes_are_refused_as_format_errors_in_c_and_python(monkeypatch):
    shell = explicit_walk(np.asarray(MESHES["sphere"].vertices), np.asarray(MESHES["sphere"].faces))
    body = bytearray(shellwalk.shell_walk_body(shell))
    rng = np.random.default_rng(3)
    for backend in ("c", "python"):
        if backend == "python":
            monkeypatch.setattr(shellwalk, "_walk_c", None)
        refused = 0
        for _ in range(300):
            b = bytearray(body)
            for k in rng.integers(0, len(b), 3):
                b[k] = int(rng.integers(256))
            try:
                decode_body(bytes(b))
            except FormatError as exc:
                assert exc.code in ("BAD_GROUP_STRUCTURE", "BAD_PAYLOAD")
                refused += 1
        assert refused > 100


def test_a_hostile_fan_walks_in_linear_time():
    # 60,000 triangles around one corner, each a root naming two new corners: every open edge starts or
    # ends at corner 0, which a list scanned per query would make quadratic.
    t = 60_000
    symbols = np.zeros(t, dtype=np.uint64)
    escapes = np.zeros(3 * t, dtype=np.uint64)
    escapes[3::3] = (2 * np.arange(1, t) + 1).astype(np.uint64)  # corner 0 again: n - k with n = 2j + 1
    tri, links, _ = shellwalk._walk(symbols, escapes, 2 * t + 1)
    assert (tri[:, 0] == 0).all() and (links == 0).all()


def test_left_and_right_name_the_corners_across_open_edges():
    # A closed surface walked depth first closes onto corners it has named: on the sphere every such
    # corner is left or right of the gate, none needs a corner step.
    m = MESHES["sphere"]
    shell = explicit_walk(np.asarray(m.vertices), np.asarray(m.faces))
    links = np.asarray(shell.links)
    codes = shellwalk._codes(np.asarray(shell.facets)[:, 1:], links, len(shell.explicit))[links != 0]
    assert (codes == 0).sum() == len(shell.explicit) - 3
    assert np.isin(codes, [1, 2]).sum() > 0.45 * len(codes) and (codes >= 3).sum() <= 2


def test_major_3_writes_a_walk_as_the_smaller_shell_tree(tmp_path):
    from planefmt_converters import registry

    scene, _ = registry.read(str(CORPUS / "cad" / "plate_holes.STL"))
    four = codec.encode_scene(scene, tmp_path / "4.pln", tolerance=3.5e-5, major=4)
    three = codec.encode_scene(scene, tmp_path / "3.pln", tolerance=3.5e-5, major=3)
    assert four.version == (4, 1) and three.version in ((3, 3), (3, 4))
    with planefmt.open(tmp_path / "3.pln") as r:
        (group,) = list(r.part_groups())
    assert group.kind in (GroupKind.SHELL_TREE, GroupKind.SHELL_TREE_PARALLELOGRAM)
    a = codec.decode_scene(tmp_path / "4.pln").nodes[0].mesh
    b = codec.decode_scene(tmp_path / "3.pln").nodes[0].mesh
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)


@pytest.mark.parametrize("rel, tolerance", [("nonconvex_watertight/quadknot.obj", 2.8e-5), ("open/capsule.obj", 3e-5)])
def test_the_coordinate_coding_written_is_within_a_percent_of_the_smallest(rel, tolerance):
    """Deflate alone ranked these meshes' codings (walk kind and mode) 7 % (quadknot) and 16 % (capsule) off
    the smallest Brotli body."""
    from planefmt_converters import registry

    scene, _ = registry.read(str(CORPUS / rel))
    buf = io.BytesIO()
    codec.encode_scene(scene, buf, tolerance=tolerance)
    with planefmt.open(io.BytesIO(buf.getvalue())) as r:
        (group,) = [g for g in r.part_groups() if g.kind in shellwalk.WALK_KINDS]
    sizes = {(kind, m): len(brotli.compress(b"".join(shellwalk.shell_walk_fields(group.shell, m, kind).values()),
                                            quality=11))
             for kind in shellwalk.WALK_KINDS for m in shellwalk.MODES}
    written = len(brotli.compress(shellwalk.shell_walk_body(group.shell, group.kind), quality=11))
    assert written <= 1.01 * min(sizes.values()) and written in sizes.values()
