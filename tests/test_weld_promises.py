"""Issue 50 items 4, 6, 7 and 8: what an encode keeps holds for a reader that welds by position.

The meshes are made here, small, after the real files of the issue: touching convex bodies (item 4's
64 bodies), closed bodies whose corners lie a coding step apart (item 6's chess piece), and a scene
of tiny open meshes (item 8's glTF scene)."""

from __future__ import annotations

import io

import numpy as np
import pytest
import trimesh

from planefmt.codec import encode_mesh, encode_scene
from planefmt.geometry.polygonize import weld
from planefmt.geometry.topology import euler_characteristic
from planefmt.model import Mesh, Node, Scene

OCTAHEDRON = (0.5 * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float),
              [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])


def welded(vertices: np.ndarray, faces: np.ndarray) -> tuple[int, int]:
    """Vertices and Euler characteristic once welded by position, as trimesh and most tools read a file."""
    v, f = weld(vertices, faces)
    return len(v), euler_characteristic(f)


def touching_bodies() -> tuple[np.ndarray, np.ndarray]:
    """64 convex bodies on a 4x4x4 grid: cubes whose faces' centres are corners, touched there by the
    tips of octahedra between them."""
    parts = []
    for i, j, k in np.ndindex(4, 4, 4):
        m = trimesh.Trimesh(*OCTAHEDRON, process=False) if (i + j + k) % 2 else trimesh.creation.box().subdivide()
        m.apply_translation((i, j, k))
        parts.append(m)
    m = trimesh.util.concatenate(parts)
    return np.asarray(m.vertices), np.asarray(m.faces)


def test_touching_convex_bodies_still_touch_at_the_default_tolerance():
    v, f = touching_bodies()
    e = encode_mesh(v, f)
    assert not e.lossy
    assert welded(e.mesh.vertices, e.mesh.faces) == welded(v, f)


def test_keep_triangles_decodes_the_source_triangles():
    v, f = touching_bodies()
    e = encode_mesh(v, f, keep_triangles=True)
    sv, sf = weld(v, f)
    dv, df = weld(e.mesh.vertices, e.mesh.faces)
    assert len(df) == len(sf)
    # Each decoded corner is its source corner within the bound, so the triangles match by nearest corner.
    near = np.linalg.norm(dv[:, None, :] - sv[None, :, :], axis=2).argmin(axis=1)
    assert np.array_equal(np.unique(np.sort(near[df], axis=1), axis=0), np.unique(np.sort(sf, axis=1), axis=0))


def test_keep_triangles_against_a_convex_body():
    box = trimesh.creation.box().subdivide()
    v, f = np.asarray(box.vertices), np.asarray(box.faces)
    assert len(encode_mesh(v, f).mesh.faces) < len(f)
    assert len(encode_mesh(v, f, keep_triangles=True).mesh.faces) == len(f)


def tori(gap: float) -> tuple[np.ndarray, np.ndarray]:
    """Two closed tori, a corner of one ``gap`` from a corner of the other."""
    a = trimesh.creation.torus(1.0, 0.3, major_sections=16, minor_sections=8)
    b = a.copy()
    b.apply_translation(a.vertices[a.vertices[:, 0].argmax()] - b.vertices[b.vertices[:, 0].argmin()] + [gap, 0, 0])
    m = trimesh.util.concatenate([a, b])
    return np.asarray(m.vertices), np.asarray(m.faces)


@pytest.mark.parametrize("tolerance", [1e-4, 1e-3])
def test_distinct_corners_stay_distinct(tolerance):
    v, f = tori(1e-4)
    e = encode_mesh(v, f, tolerance=tolerance)
    assert e.error_bound <= tolerance
    assert welded(e.mesh.vertices, e.mesh.faces) == welded(v, f)


def l_prism() -> trimesh.Trimesh:
    xy = np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float)
    v = np.vstack([np.column_stack([xy, np.zeros(6)]), np.column_stack([xy, np.ones(6)])])
    fan = [(3, 4, 5), (3, 5, 0), (3, 0, 1), (3, 1, 2)]
    f = [(a, c, b) for a, b, c in fan] + [(a + 6, b + 6, c + 6) for a, b, c in fan]
    for i in range(6):
        j = (i + 1) % 6
        f += [(i, j, j + 6), (i, j + 6, i + 6)]
    return trimesh.Trimesh(v, f, process=False).subdivide().subdivide()


def test_a_looser_tolerance_works_where_a_tighter_one_does():
    # Two CAD-like bodies whose flat faces lose their inner corners at a lossy tolerance, a corner of one
    # 2e-5 from a corner of the other: every looser tolerance keeps them apart too.
    a, b = l_prism(), l_prism()
    b.apply_translation(a.vertices[np.lexsort(a.vertices.T)][-1] - b.vertices[np.lexsort(b.vertices.T)][0]
                        + [2e-5, 2e-5, 0])
    m = trimesh.util.concatenate([a, b])
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    for tolerance in (1e-5, 1e-4, 1e-3, 3e-3):
        e = encode_mesh(v, f, tolerance=tolerance)
        assert e.error_bound <= tolerance
        assert welded(e.mesh.vertices, e.mesh.faces)[1] == welded(v, f)[1]


def test_tiny_open_meshes_in_a_large_scene_convert_at_the_default_tolerance():
    rng = np.random.default_rng(1)
    nodes = []
    for i in range(40):
        s = trimesh.creation.icosphere(subdivisions=1, radius=0.002)
        used, inverse = np.unique(s.faces[s.triangles_center[:, 2] > 0], return_inverse=True)
        vertices = s.vertices[used] * (1 + 0.01 * rng.standard_normal((len(used), 3))) + rng.uniform(0, 2, 3)
        nodes.append(Node(f"m{i}", mesh=Mesh(vertices, inverse.reshape(-1, 3))))
    header = encode_scene(Scene(tuple(nodes)), io.BytesIO())
    assert not header.lossy and header.error_bound <= 1e-6
