"""Sewing decoded polygons (planefmt.seams): rings that welding pinches."""

from __future__ import annotations

import numpy as np

from planefmt.seams import Planes, stitch


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
