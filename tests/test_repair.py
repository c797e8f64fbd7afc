"""Meshes closed but for their cracks (planefmt.geometry.repair): two vertices of one point, T-junctions.
Mended, they are stored as solids; what the mending moved is counted in the verified error."""

from __future__ import annotations


import numpy as np
import pytest
import trimesh

from planefmt import codec
from planefmt.codec import preparing
from planefmt.geometry.topology import is_closed_manifold, signed_volume
from planefmt.model import GroupKind
from planefmt.geometry.repair import merge_close_vertices, split_t_junctions

from corpus import CORPUS



def unit_cube() -> tuple[np.ndarray, np.ndarray]:
    box = trimesh.creation.box([1, 1, 1])
    box.apply_translation([0.5, 0.5, 0.5])
    return np.asarray(box.vertices, dtype=np.float64), np.asarray(box.faces, dtype=np.int64)


def cube_with_twin_vertex() -> tuple[np.ndarray, np.ndarray]:
    """The unit cube with one corner written twice, 6e-17 apart, one triangle using the twin."""
    v, f = unit_cube()
    corner = int(np.flatnonzero((v == 0.0).all(axis=1))[0])
    row, col = np.argwhere(f == corner)[0]
    f = f.copy()
    f[row, col] = len(v)
    return np.vstack([v, [6.123233995736766e-17, 0.0, 0.0]]), f


def cube_with_t_junction() -> tuple[np.ndarray, np.ndarray]:
    """The unit cube whose face y = 0 is a fan around the midpoint of its edge x = 0, z in [0, 1]:
    the face x = 0 keeps that edge whole, so the midpoint is a T-vertex."""
    v, f = unit_cube()
    on_face = np.all(np.isclose(v[f][:, :, 1], 0.0), axis=1)
    f = f[~on_face]
    index = {tuple(p): i for i, p in enumerate(v.round().astype(int).tolist())}
    a, b, c, d = (index[p] for p in [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)])
    m = len(v)
    v = np.vstack([v, [0.0, 0.0, 0.5]])
    # Counter-clockwise seen from -y: (0,0,0) -> (1,0,0) -> (1,0,1) -> (0,0,1).
    fan = np.array([[m, a, b], [m, b, c], [m, c, d]])
    return v, np.vstack([f, fan])


def test_twin_vertices_merge_and_the_cube_is_one_convex_group():
    v, f = cube_with_twin_vertex()
    assert not is_closed_manifold(f, len(v))
    mv, mf, kept, moved = merge_close_vertices(v, f, 1e-9)
    assert len(mv) == 8 and np.array_equal(kept, np.arange(len(f))) and 0 < moved < 1e-16
    assert is_closed_manifold(mf, len(mv))
    enc = codec.encode_mesh(v, f, tolerance=1e-6, scheme="paper")
    assert [g.kind for g in enc.groups] == [GroupKind.CONVEX]
    assert len(enc.triplets) == 6 and 0 <= enc.error_bound <= 1e-6


def test_t_junction_splits_into_a_closed_cube():
    v, f = cube_with_t_junction()
    assert not is_closed_manifold(f, len(v))
    split = split_t_junctions(v, f, 1e-9)
    assert split.splits == 1 and split.offset == 0.0
    assert len(split.faces) == len(f) + 1
    assert is_closed_manifold(split.faces, len(v))
    assert signed_volume(v, split.faces) == pytest.approx(1.0, abs=1e-12)
    # Every new face comes from the face it split, and orientation is kept (the volume above).
    assert np.bincount(split.origin, minlength=len(f)).tolist().count(2) == 1
    enc = codec.encode_mesh(v, f, tolerance=1e-6, scheme="paper")
    assert [g.kind for g in enc.groups] == [GroupKind.CONVEX]
    mesh = codec.decode_mesh(enc)
    assert is_closed_manifold(mesh.faces, len(mesh.vertices))


def test_a_vertex_off_the_edge_is_no_t_junction():
    v, f = cube_with_t_junction()
    v[-1] = [-1e-3, 0.0, 0.5]
    split = split_t_junctions(v, f, 1e-6)
    assert split.splits == 0 and np.array_equal(split.faces, f)


def test_twin_vertices_of_a_corpus_part_make_it_a_solid():
    """octagonal_pocket.STL has vertices 6e-17 from their twins (27 pairs): mended, it is one BSP
    group (it took 5,209 patch references before), and held to a closed solid's structure."""
    mesh = trimesh.load(CORPUS / "cad" / "octagonal_pocket.stl", process=False)
    obj = preparing._prepare(np.asarray(mesh.vertices), np.asarray(mesh.faces), np.eye(4), 1e-6, None, None,
                         scheme="paper")
    assert [g.kind for g in obj.groups] == [GroupKind.BSP]
    assert obj.closed and 0 < obj.mended < 1e-15
