"""Synthetic test meshes for the solid and patch codecs: (vertices, faces), counter-clockwise from outside.

Closed solids come from manifold3d booleans (watertight by construction,
float64 meshes); open and broken surfaces are built directly.
"""

from __future__ import annotations

import numpy as np


def _manifold_mesh(m) -> tuple[np.ndarray, np.ndarray]:
    mesh = m.to_mesh64()
    return np.asarray(mesh.vert_properties, dtype=np.float64)[:, :3], np.asarray(mesh.tri_verts, dtype=np.int64)


def random_boxes(seed: int, count: int = 4, rotate: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The union of ``count`` random boxes, some rotated: a non-convex watertight solid."""
    import manifold3d as mf

    rng = np.random.default_rng(seed)
    shape = None
    for _ in range(count):
        size = rng.uniform(0.5, 2.0, 3)
        box = mf.Manifold.cube(size.tolist(), center=True)
        if rotate:
            box = box.rotate(rng.uniform(-40, 40, 3).tolist())
        box = box.translate(rng.uniform(-1.0, 1.0, 3).tolist())
        shape = box if shape is None else shape + box
    return _manifold_mesh(shape)


def ring(segments: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """A thick ring (cylinder minus a coaxial cylinder): genus 1, Euler characteristic 0."""
    import manifold3d as mf

    outer = mf.Manifold.cylinder(1.0, 2.0, 2.0, segments)
    inner = mf.Manifold.cylinder(3.0, 1.0, 1.0, segments).translate([0.0, 0.0, -1.0])
    return _manifold_mesh(outer - inner)


def dented_sphere(segments: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """A sphere with a spherical dent: nearly convex, the case that made chain trees."""
    import manifold3d as mf

    ball = mf.Manifold.sphere(1.0, segments)
    bite = mf.Manifold.sphere(0.4, segments).translate([0.0, 0.0, 1.1])
    return _manifold_mesh(ball - bite)


def plate_with_holes() -> tuple[np.ndarray, np.ndarray]:
    """A plate with two round through holes and a pocket (prismatic CAD: genus 2)."""
    import manifold3d as mf

    plate = mf.Manifold.cube([4.0, 2.0, 0.5], center=True)
    hole = mf.Manifold.cylinder(1.0, 0.3, 0.3, 32).translate([0.0, 0.0, -0.5])
    pocket = mf.Manifold.cube([0.8, 0.8, 0.3], center=True).translate([0.0, 0.0, 0.2])
    return _manifold_mesh(plate - hole.translate([-1.2, 0.0, 0.0]) - hole.translate([1.2, 0.0, 0.0]) - pocket)


def cube(lo: float = 0.0, hi: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """An axis-aligned cube as 12 triangles."""
    v = np.array([[x, y, z] for x in (lo, hi) for y in (lo, hi) for z in (lo, hi)], dtype=np.float64)
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    f = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    return v, np.array(f, dtype=np.int64)


def fig7_block() -> tuple[np.ndarray, np.ndarray]:
    """The paper's Fig. 7: a block with a rectangular step (pocket) in its top, 16 vertices, 14 quads.

    Box [0,4]x[0,3]x[0,2]; pocket [1,3]x[1,2]x[1,2]. The top face is the
    annulus around the pocket as four trapezoids. Pseudo-convex: bottom, four
    sides, four trapezoids (9 polygons); pseudo-concave: four pocket walls and
    its floor (5 polygons).
    """
    v = np.array([[0, 0, 0], [4, 0, 0], [4, 3, 0], [0, 3, 0], [0, 0, 2], [4, 0, 2], [4, 3, 2], [0, 3, 2],
                  [1, 1, 2], [3, 1, 2], [3, 2, 2], [1, 2, 2], [1, 1, 1], [3, 1, 1], [3, 2, 1], [1, 2, 1]],
                 dtype=np.float64)
    quads = [[0, 3, 2, 1], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7],
             [4, 5, 9, 8], [5, 6, 10, 9], [6, 7, 11, 10], [7, 4, 8, 11],
             [8, 9, 13, 12], [9, 10, 14, 13], [10, 11, 15, 14], [11, 8, 12, 15], [12, 13, 14, 15]]
    f = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    return v, np.array(f, dtype=np.int64)


def grid_surface(func, n: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """An open height field ``z = func(x, y)`` over [-1, 1]^2 on an n x n grid, facing +z."""
    xs = np.linspace(-1.0, 1.0, n + 1)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    v = np.column_stack([x.ravel(), y.ravel(), func(x, y).ravel()])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return v, np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def hemisphere(n: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """An open upper hemisphere (pseudo-convex as a whole, but faceted)."""
    th = np.linspace(0.0, np.pi / 2, n + 1)[1:]
    ph = np.linspace(0.0, 2 * np.pi, 2 * n, endpoint=False)
    t, p = np.meshgrid(th, ph, indexing="ij")
    v = np.concatenate([[[0.0, 0.0, 1.0]],
                        np.column_stack([(np.sin(t) * np.cos(p)).ravel(), (np.sin(t) * np.sin(p)).ravel(),
                                         np.cos(t).ravel()])])
    m = 2 * n
    f = [[0, 1 + j, 1 + (j + 1) % m] for j in range(m)]
    for i in range(n - 1):
        for j in range(m):
            a, b = 1 + i * m + j, 1 + i * m + (j + 1) % m
            c, d = a + m, b + m
            f += [[a, c, d], [a, d, b]]
    return v, np.array(f, dtype=np.int64)


def moebius(n: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """A Moebius strip: open and not orientable (no consistent outward side exists)."""
    u = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    rows = []
    for w in (-0.3, 0.3):
        rows.append(np.column_stack([(1 + w * np.cos(u / 2)) * np.cos(u), (1 + w * np.cos(u / 2)) * np.sin(u),
                                     w * np.sin(u / 2)]))
    v = np.concatenate(rows)
    f = []
    for i in range(n):
        j = (i + 1) % n
        a, b = i, i + n
        c, d = (j, j + n) if j else (n, 0)  # the half twist swaps the sides at the seam
        f += [[a, b, d], [a, d, c]]
    return v, np.array(f, dtype=np.int64)


def fin(count: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """``count`` triangles sharing one edge (a non-manifold edge), fanned around it."""
    v = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    f = []
    for k in range(count):
        a = 2 * np.pi * k / count
        v.append([np.cos(a), np.sin(a), 0.5])
        f.append([0, 1, 2 + k])
    return np.array(v), np.array(f, dtype=np.int64)


def soup(seed: int, count: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """``count`` disconnected random triangles."""
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-1, 1, (count, 1, 3))
    v = (centre + rng.normal(0, 0.15, (count, 3, 3))).reshape(-1, 3)
    return v, np.arange(3 * count).reshape(-1, 3)


def area(v: np.ndarray, f: np.ndarray) -> float:
    """Total triangle area."""
    return float(0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum())
