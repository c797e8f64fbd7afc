"""Cells groups (kind 1, spec §9.6): decoded as the union of their cells, defects found with their codes."""

from __future__ import annotations

import io
import itertools
import math

import numpy as np
import pytest

import planefmt
from planefmt import cells, codec
from planefmt.bodies import euler_characteristic, is_closed_manifold, signed_volume
from planefmt.errors import GeometryError
from planefmt.model import GroupKind, Header
from planefmt.planes import to_triplets
from planefmt.validate import validate

#: The L of conformance/cases_valid.py: [0,2]x[0,1]x[0,1] u [0,1]x[0,2]x[0,1], its eight face planes
#: and the cut x = y (reference 8); cell entries 2 j + s.
L_OMEGA = np.array([[0, -1, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, 0, 1], [0, 0, -1],
                    [math.sqrt(0.5), -math.sqrt(0.5), 0]])
L_H = np.array([0, 2, 1, 1, 2, 0, 1, 0, 0], dtype=float)
L_CELLS = ((0, 2, 4, 17, 12, 14), (6, 8, 10, 16, 12, 14))
L_FACE = np.arange(9) < 8


def _group(kind: int, m: int, cells_=None, face=None):
    face = np.ones(m, dtype=bool) if face is None else face
    return codec.GroupSpec(GroupKind(kind), np.arange(m), ~face,
                           cells=None if cells_ is None else tuple(np.array(c, dtype=np.uint32) for c in cells_))


def _decode(omega, h, cells_, face=None):
    d = codec.decode_group(to_triplets(np.asarray(omega, dtype=float), np.asarray(h, dtype=float)),
                           _group(1, len(h), cells_, face), 0)
    return d.vertices, d.triangles


def _area(v, t):
    p = v[t]
    return float(np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()) / 2


def test_the_l_decodes_closed_with_the_volume_and_area_of_its_arithmetic():
    # Volume 2 + 1; area: top and bottom 3 each, the sides the L's perimeter 8 times height 1.
    v, t = _decode(L_OMEGA, L_H, L_CELLS, L_FACE)
    assert is_closed_manifold(t, len(v)) and euler_characteristic(t) == 2
    assert signed_volume(v, t) == pytest.approx(3.0, rel=1e-12)
    assert _area(v, t) == pytest.approx(14.0, rel=1e-12)
    # Nothing on the cut x = y: it separates the cells and carries no surface.
    centres = v[t].mean(axis=1)
    assert not np.isclose(centres[:, 0], centres[:, 1]).any()


def _grid(n: int):
    """Unit cubes of an n x n x n grid as cells over shared planes x = i, y = i, z = i."""
    omega, h = [], []
    for axis in range(3):
        for i in range(n + 1):
            omega.append(np.eye(3)[axis])
            h.append(float(i))
    plane = {(axis, i): axis * (n + 1) + i for axis in range(3) for i in range(n + 1)}
    cells_ = []
    for x, y, z in itertools.product(range(n), repeat=3):
        cell = []
        for axis, c in enumerate((x, y, z)):
            cell += [2 * plane[axis, c + 1], 2 * plane[axis, c] + 1]  # x <= c + 1, x >= c
        cells_.append(cell)
    return np.array(omega), np.array(h), cells_


def test_a_grid_of_cells_decodes_to_its_box_with_a_tree_as_large_as_its_entries():
    omega, h, grid = _grid(3)
    v, t = _decode(omega, h, grid)
    assert is_closed_manifold(t, len(v))
    assert signed_volume(v, t) == pytest.approx(27.0, rel=1e-12)
    assert _area(v, t) == pytest.approx(54.0, rel=1e-12)
    corners = [np.array(list(itertools.product(*[(lo, lo + 1) for lo in c]))) for c in itertools.product(range(3), repeat=3)]
    tokens = cells._tree(omega, h, [np.array(c) for c in grid], corners)
    # One split per entry at most, one leaf per split plus one: no cell is repeated across branches.
    entries = sum(len(c) for c in grid)
    assert len(tokens) <= 2 * entries + 1


def test_overlapping_cells_are_bad_group_structure():
    with pytest.raises(GeometryError) as err:
        _decode(L_OMEGA, L_H, (L_CELLS[0], L_CELLS[0]), L_FACE)
    assert err.value.code == "BAD_GROUP_STRUCTURE" and "overlap" in str(err.value)


def test_an_unbounded_cell_is_unbounded_polytope():
    with pytest.raises(GeometryError) as err:
        _decode(L_OMEGA, L_H, (L_CELLS[0], (6, 10, 16, 12, 14)), L_FACE)
    assert err.value.code == "UNBOUNDED_POLYTOPE" and "cell 1" in str(err.value)


def test_a_tree_beyond_its_limit_stops_the_decoding(monkeypatch):
    # The 2 x 2 x 2 grid's tree has 43 tokens for 48 entries and 8 cells: a limit of 28.
    monkeypatch.setattr(cells, "TOKENS_PER_ENTRY", 0.5)
    omega, h, grid = _grid(2)
    with pytest.raises(GeometryError) as err:
        _decode(omega, h, grid)
    assert err.value.code == "LIMIT_EXCEEDED"


def test_a_file_with_a_cells_group_decodes_and_validates():
    sink = io.BytesIO()
    with planefmt.Writer(sink, Header()) as w:
        o = w.add_object("L")
        w.add_planes(to_triplets(L_OMEGA.astype(float), L_H))
        w.add_group(o, GroupKind.CELLS, np.arange(9), ~L_FACE, cells=tuple(np.array(c, dtype=np.uint32) for c in L_CELLS))
    mesh = codec.decode_scene(io.BytesIO(sink.getvalue())).nodes[0].mesh
    assert signed_volume(mesh.vertices, mesh.faces) == pytest.approx(3.0, rel=1e-9)
    assert validate(io.BytesIO(sink.getvalue())) == []
