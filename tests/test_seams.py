"""Sewing decoded polygons (planefmt.groups.seams): rings that welding pinches."""

from __future__ import annotations

import numpy as np

from planefmt.groups.seams import Planes, stitch


def _edge_uses(triangles: np.ndarray) -> np.ndarray:
    e = np.sort(np.column_stack([triangles.reshape(-1), triangles[:, [1, 2, 0]].reshape(-1)]), axis=1)
    return np.unique(e, axis=0, return_counts=True)[1]


def test_a_ring_welded_through_one_vertex_is_fanned_as_its_two_loops() -> None:
    """Two corners of one ring within the welding distance (a thin polygon's opposite corners) make
    it pass that vertex twice; fanned as one ring, its triangles would cover the pinch twice (edges
    on four triangles of one polygon: busted.STL had 14 such edges)."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [2, 1, 0], [2, 2, 0], [1, 1 + 1e-13, 0]], dtype=float)
    planes = Planes(np.array([[0.0, 0.0, 1.0]]), np.array([0.0]))
    v, t, polygon = stitch(pts, np.array([0, 6]), np.arange(6), planes, np.array([0]),
                           np.full(6, -1), 1e-9, 2.0)
    assert (_edge_uses(t) <= 2).all()
    area = np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1).sum() / 2
    assert np.isclose(area, 1.0)
    assert (polygon == 0).all()
    normals = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    assert (normals[:, 2] > 0).all()


def test_a_simple_ring_is_fanned_from_its_first_corner() -> None:
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    planes = Planes(np.array([[0.0, 0.0, 1.0]]), np.array([0.0]))
    v, t, polygon = stitch(pts, np.array([0, 4]), np.arange(4), planes, np.array([0]), np.full(4, -1), 1e-9, 1.0)
    assert len(v) == 4 and t.tolist() == [[0, 1, 2], [0, 2, 3]] and polygon.tolist() == [0, 0]


def test_a_welded_vertex_sits_where_its_best_conditioned_copy_is() -> None:
    """Copies of one vertex solved from nearly dependent planes may lie far off along them; the one
    from well-conditioned planes is where the vertex is (busted.STL: a vertex welded as the mean of
    its copies sat 2.8e-8 off a crease, and the T-junctions on the crease no longer met it)."""
    s = 1e-9
    omega = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0], [1, s, 0]], dtype=float)
    omega /= np.linalg.norm(omega, axis=1)[:, None]
    planes = Planes(omega, np.zeros(4))
    good = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    off = [4e-10, 2e-10, 0.0]
    poor = [[-1, 0, 0], off, [0, 1, 0], [-1, 1, 0]]
    pts = np.array(good + poor, dtype=float)
    # Corner 0 lies on planes 0, 1, 2 (orthogonal); corner 5, its copy, on 0, 3 and 1 (nearly one
    # plane, so it claims a large error). Edge k runs from corner k to the next.
    labels = np.array([2, -1, -1, 1, 3, 1, -1, -1])
    v, t, _ = stitch(pts, np.array([0, 4, 8]), np.arange(8), planes, np.array([0, 0]), labels, 1e-9, 1.0)
    assert len(v) == 6
    origin = np.flatnonzero(np.linalg.norm(v, axis=1) < 1e-9)
    assert len(origin) == 1 and np.linalg.norm(v[origin[0]]) < 1e-12


def _box() -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    m = trimesh.creation.box([1.0, 2.0, 3.0])
    return np.asarray(m.vertices, dtype=float), np.asarray(m.faces, dtype=np.int64)


def test_a_flat_slit_is_closed_facing_the_surface_around_it() -> None:
    from planefmt.geometry.topology import is_closed_manifold, signed_volume
    from planefmt.groups.seams import fill_slits

    v, f = _box()
    holed = f[1:]
    fill, beside = fill_slits(v, holed, 1e-9)
    closed = np.concatenate([holed, fill])
    assert len(fill) == 1 and is_closed_manifold(closed, len(v))
    assert np.isclose(signed_volume(v, closed), 6.0)
    # The triangle beside the hole lies on the same face of the box.
    n = np.cross(v[fill[0, 1]] - v[fill[0, 0]], v[fill[0, 2]] - v[fill[0, 0]])
    m = np.cross(v[holed[beside[0], 1]] - v[holed[beside[0], 0]], v[holed[beside[0], 2]] - v[holed[beside[0], 0]])
    assert np.allclose(np.cross(n, m), 0.0) and n @ m > 0


def test_holes_that_are_not_flat_slits_are_left_open() -> None:
    from planefmt.groups.seams import fill_slits

    v, f = _box()
    # Two triangles of two faces meeting at an edge: a bent hole, its corners 0.3+ off any plane.
    normal = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    first = 0
    other = next(k for k in range(1, len(f)) if len(set(f[k]) & set(f[first])) == 2
                 and abs(normal[k] @ normal[first]) < 1e-9)
    bent = np.delete(f, [first, other], axis=0)
    assert fill_slits(v, bent, 1e-6) is None
    assert fill_slits(v, bent, 10.0) is not None
    # An edge on three triangles: not a surface whose holes can be told apart.
    assert fill_slits(v, np.concatenate([f, f[:1]]), 10.0) is None
    empty, _ = fill_slits(v, f, 1e-9)
    assert len(empty) == 0
