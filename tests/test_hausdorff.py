"""Exact point-triangle distances, nearest-triangle queries and the certified Hausdorff distance."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from planefmt.errors import GeometryError
from planefmt.geometry.hausdorff import closest_distance, hausdorff, point_triangle_distance, relative_hausdorff

from corpus import CORPUS


def load(rel: str) -> tuple[np.ndarray, np.ndarray]:
    m = trimesh.load(CORPUS / rel, force="mesh")
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)


def diagonal(v: np.ndarray) -> float:
    return float(np.linalg.norm(np.ptp(v, axis=0)))


def cube(subdivisions: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Unit cube, 2 triangles per face, or 2 * 4**k after k midpoint subdivisions."""
    m = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    for _ in range(subdivisions):
        v, f = trimesh.remesh.subdivide(v, f)
    return v, f


def l_prism(top: tuple[tuple[int, int, int], ...] = ((0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5))):
    """A closed L-shaped prism, 0 <= z <= 1, its L-shaped (non-convex) caps triangulated by ``top``."""
    poly = np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], dtype=np.float64)
    n = len(poly)
    v = np.vstack([np.column_stack([poly, np.zeros(n)]), np.column_stack([poly, np.ones(n)])])
    faces = [(n + a, n + b, n + c) for a, b, c in top] + [(c, b, a) for a, b, c in top]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i)]
    return v, np.array(faces, dtype=np.int64)


def flip_coplanar_diagonals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Re-triangulate: flip the shared edge of disjoint pairs of exactly coplanar triangles forming convex quads."""
    f = f.copy()
    edges = {}
    for t, tri in enumerate(f.tolist()):
        for k in range(3):
            edges.setdefault((tri[k], tri[(k + 1) % 3]), []).append((t, k))
    normal = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    used = np.zeros(len(f), dtype=bool)
    for (a, b), [(t1, k1)] in edges.items():
        other = edges.get((b, a))
        if other is None or len(other) != 1 or used[t1] or used[other[0][0]]:
            continue
        t2, k2 = other[0]
        c, d = f[t1, (k1 + 2) % 3], f[t2, (k2 + 2) % 3]
        n1, n2 = np.cross(v[a] - v[c], v[d] - v[c]), np.cross(v[d] - v[c], v[b] - v[c])
        if abs(np.dot(normal[t1], v[d] - v[a])) > 0 or min(n1 @ normal[t1], n2 @ normal[t1]) <= 0:
            continue
        f[t1], f[t2] = (c, a, d), (c, d, b)
        used[t1] = used[t2] = True
    return f


def grid_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray, n: int = 300) -> float:
    u, w = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    inside = u + w <= 1
    pts = a + u[inside, None] * (b - a) + w[inside, None] * (c - a)
    return float(np.linalg.norm(pts - p, axis=1).min())


# --- point-triangle distance -------------------------------------------------------------------

def test_point_triangle_distance_matches_dense_grid():
    rng = np.random.default_rng(7)
    tris = rng.normal(size=(60, 3, 3))
    tris[:20, 2] = tris[:20, 0] + rng.uniform(0, 1, size=(20, 1)) * (tris[:20, 1] - tris[:20, 0])
    tris[:20, 2] += 1e-3 * rng.normal(size=(20, 3))  # thin triangles
    pts = rng.normal(size=(60, 3))
    d = point_triangle_distance(pts, tris[:, 0], tris[:, 1], tris[:, 2])
    n = 300
    for p, t, dist in zip(pts, tris, d):
        ref = grid_distance(p, *t, n=n)
        spacing = np.linalg.norm(t - np.roll(t, 1, axis=0), axis=1).max() / n
        assert dist <= ref + 1e-12
        assert ref - dist <= spacing


def test_point_triangle_distance_analytic_regions():
    a, b, c = np.array([0.0, 0, 0]), np.array([2.0, 0, 0]), np.array([0.0, 2, 0])
    cases = {
        (0.5, 0.5, 3.0): 3.0,                      # face region
        (-1.0, -1.0, 0.0): math.sqrt(2),           # vertex a
        (3.0, -1.0, 1.0): math.sqrt(3),            # vertex b
        (1.0, -2.0, 0.0): 2.0,                     # edge ab
        (2.0, 2.0, 0.0): math.sqrt(2),             # edge bc
        (-0.5, 1.0, 0.5): math.sqrt(0.5),          # edge ca
        (0.3, 0.4, 0.0): 0.0,                      # on the triangle
    }
    pts = np.array(list(cases))
    d = point_triangle_distance(pts, a, b, c)
    np.testing.assert_allclose(d, list(cases.values()), rtol=0, atol=1e-15)


def test_point_triangle_distance_thin_and_degenerate_triangles():
    # A sliver 1e-9 high: the projection is inside, so the distance is the height above it.
    a, b, c = np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.5, 1e-9, 0])
    d = point_triangle_distance(np.array([[0.5, 0.5e-9, 1e-6], [0.5, 1e-9 + 1e-6, 0.0]]), a, b, c)
    np.testing.assert_allclose(d, [1e-6, 1e-6], rtol=1e-9, atol=0)
    # Collinear vertices: the distance to the segment they span.
    seg = point_triangle_distance(np.array([[0.5, 1.0, 0.0], [3.0, 0.0, 0.0]]),
                                  np.array([0.0, 0, 0]), np.array([2.0, 0, 0]), np.array([1.0, 0, 0]))
    np.testing.assert_allclose(seg, [1.0, 1.0], atol=1e-15)
    # Coincident vertices: the distance to the point.
    pt = point_triangle_distance(np.array([1.0, 2.0, 2.0]), np.zeros(3), np.zeros(3), np.zeros(3))
    np.testing.assert_allclose(pt, [3.0], atol=1e-15)


def test_closest_distance_matches_brute_force():
    v, f = cube(1)
    rng = np.random.default_rng(3)
    pts = rng.uniform(-0.5, 1.5, size=(300, 3))
    d, face = closest_distance(pts, v, f)
    tri = v[f]
    for p, dist, fi in zip(pts, d, face):
        all_d = point_triangle_distance(np.broadcast_to(p, (len(f), 3)), tri[:, 0], tri[:, 1], tri[:, 2])
        assert dist == all_d.min()
        assert all_d[fi] == dist
    # Outside the unit cube the distance is the distance to the box.
    box = np.linalg.norm(np.maximum(np.maximum(-pts, pts - 1), 0), axis=1)
    outside = box > 0
    np.testing.assert_allclose(d[outside], box[outside], atol=1e-15)


# --- Hausdorff ---------------------------------------------------------------------------------

def test_mesh_against_itself_is_zero_and_certified():
    v, f = cube()
    r = hausdorff(v, f, v, f)
    assert r.certified and r.lower == 0.0
    assert r.upper <= 1e-12 * diagonal(v)


def test_cube_triangulated_two_ways():
    va, fa = cube(0)  # 2 triangles per face
    vb, fb = cube(1)  # 8 triangles per face
    assert len(fa) == 12 and len(fb) == 48
    r = hausdorff(va, fa, vb, fb)
    assert r.certified and r.upper <= 1e-12 * diagonal(va)


@pytest.mark.parametrize("target", [None, 0.05, 0.2])
def test_cube_with_pushed_vertex(target):
    v, f = cube()
    d = 0.1
    moved = v.copy()
    corner = np.argmax(v.sum(axis=1))
    moved[corner] += d / math.sqrt(3)  # along the outward diagonal: d away from the cube
    r = hausdorff(v, f, moved, f, target=target)
    assert r.certified
    assert r.lower <= d + 1e-12 and r.upper >= d - 1e-12
    if target is None or target > d:
        assert abs(r.lower - d) <= 1e-9 and abs(r.upper - d) <= 1e-9
        assert r.b_to_a[0] == pytest.approx(d, abs=1e-9)
    else:
        assert r.lower > target


def test_thin_wrong_cell_across_a_concave_corner():
    # B is A plus a sliver whose corners lie on A's two inner walls x = 1 and y = 1;
    # its interior bridges the concave corner, 0.45 away from A at its middle.
    va, fa = l_prism()
    sliver = np.array([(1.0, 1.9, 0.5), (1.9, 1.0, 0.5), (1.9, 1.0, 0.5001)])
    vb = np.vstack([va, sliver])
    fb = np.vstack([fa, [[len(va), len(va) + 1, len(va) + 2]]])
    # Area-weighted sampling almost never lands on the sliver.
    samples = trimesh.Trimesh(vb, fb, process=False).sample(20000, seed=1)
    sampled = closest_distance(samples, va, fa)[0].max()
    assert sampled < 0.1
    for target in (None, 1e-6):
        r = hausdorff(va, fa, vb, fb, target=target)
        assert r.certified
        if target is None:
            assert abs(r.lower - 0.45) <= 1e-9 and abs(r.upper - 0.45) <= 1e-9
        else:
            assert r.lower > 0.44
        assert r.a_to_b[1] <= 1e-12


def test_non_convex_faces_triangulated_differently():
    va, fa = l_prism()
    vb, fb = l_prism(((3, 4, 5), (3, 5, 0), (3, 0, 1), (3, 1, 2)))
    r = hausdorff(va, fa, vb, fb)
    assert r.certified and r.upper <= 1e-12 * diagonal(va)


def test_degenerate_triangles_are_harmless():
    v, f = cube()
    v2 = np.vstack([v, [[0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]])
    extra = np.array([[0, 1, 1], [len(v), len(v) + 1, len(v)], [0, len(v), 1]])  # a point, a point, a segment
    f2 = np.vstack([f, extra])
    r = hausdorff(v, f, v2, f2)
    assert r.certified and r.upper <= 1e-12


def test_empty_or_invalid_meshes_raise():
    v, f = cube()
    with pytest.raises(GeometryError):
        hausdorff(v, f, v, np.empty((0, 3), dtype=np.int64))
    with pytest.raises(GeometryError):
        hausdorff(np.empty((0, 3)), np.empty((0, 3), dtype=np.int64), v, f)
    with pytest.raises(GeometryError):
        hausdorff(v, f + 100, v, f)
    bad = v.copy()
    bad[0, 0] = np.nan
    with pytest.raises(GeometryError):
        hausdorff(bad, f, v, f)


def test_budget_exhausted_is_reported_and_still_an_upper_bound():
    v, f = cube(1)
    rng = np.random.default_rng(5)
    moved = v + 0.01 * rng.normal(size=v.shape)
    exact = hausdorff(v, f, moved, f)
    assert exact.certified
    cut = hausdorff(v, f, moved, f, max_pieces=len(f) * 2 + 8)
    assert not cut.certified
    assert cut.upper >= exact.lower - 1e-12 and cut.lower <= exact.upper + 1e-12


def test_relative_hausdorff_divides_by_the_diagonal_of_a():
    v, f = cube()
    scaled = v * 3.0
    moved = scaled.copy()
    corner = np.argmax(scaled.sum(axis=1))
    moved[corner] += 0.3 / math.sqrt(3)
    r = relative_hausdorff((scaled, f), (moved, f))
    assert r.certified
    assert r.lower == pytest.approx(0.3 / diagonal(scaled), abs=1e-9)
    assert r.upper == pytest.approx(0.3 / diagonal(scaled), abs=1e-9)
    assert relative_hausdorff((scaled, f), (moved, f), target=1e-6).lower > 1e-6


def test_corpus_cad_part_against_retriangulated_and_perturbed_copies():
    v, f = load("cad/featuretype.STL")
    diag = diagonal(v)
    r = hausdorff(v, f, v, f)
    assert r.certified and r.upper <= 1e-12 * diag
    # The same surface cut into four times as many triangles: zero up to the
    # default tolerance (1e-9 of the diagonal) and the float32 flatness of its faces.
    vs, fs = trimesh.remesh.subdivide(v, f)
    r = hausdorff(v, f, vs, fs)
    assert r.certified and r.upper <= 1e-9 * diag
    r = hausdorff(v, f, vs, fs, target=1e-6 * diag)
    assert r.certified and r.upper <= 1e-6 * diag
    rng = np.random.default_rng(11)
    shift = rng.normal(size=v.shape)
    shift *= 1e-7 * diag / np.linalg.norm(shift, axis=1, keepdims=True)
    r = hausdorff(v, f, v + shift, f, target=1e-6 * diag)
    assert r.certified and 0 < r.lower <= r.upper <= 1e-6 * diag
    assert r.lower <= 1e-7 * diag * (1 + 1e-9)


def test_corpus_subdivided_cube_against_twelve_triangles():
    v, f = load("convex/cube_subd.obj")
    box = trimesh.creation.box(bounds=np.array([v.min(axis=0), v.max(axis=0)]))
    r = hausdorff(v, f, np.asarray(box.vertices), np.asarray(box.faces))
    assert r.certified and r.upper <= 1e-12 * diagonal(v)
    rng = np.random.default_rng(2)
    moved = v + 1e-4 * diagonal(v) * rng.uniform(-1, 1, size=v.shape) / math.sqrt(3)
    r = relative_hausdorff((v, f), (moved, f), target=1e-3)
    assert r.certified and r.upper <= 1e-3 and r.lower <= 1e-4


def test_corpus_faces_with_holes_triangulated_differently():
    # Flipping diagonals inside the planar faces (with holes and pockets) keeps
    # the surface; pieces of one triangulation straddle the other's triangles.
    v, f = load("cad/featuretype.STL")
    flipped = flip_coplanar_diagonals(v, f)
    assert (np.sort(flipped, axis=1) != np.sort(f, axis=1)).any(axis=1).sum() > 1000
    diag = diagonal(v)
    r = hausdorff(v, f, v, flipped, target=1e-6 * diag)
    assert r.certified and r.upper <= 1e-6 * diag
    r = hausdorff(v, f, v, flipped)
    assert r.certified and r.upper <= 1e-9 * diag


def fold_with_micro_fillet(width: float, facets: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Faces z=0 and x=0 (0 <= y <= 1) meeting through strips ``width`` wide: one in each face,
    then a quarter-round fillet of ``facets`` strips. Returns vertices, faces and each face's
    strip (0 = big face z=0, last = big face x=0)."""
    t = np.linspace(0.0, 0.5 * np.pi, facets + 1)
    arc = np.column_stack([width - width * np.sin(t), width - width * np.cos(t)])
    profile = np.vstack([[1.0, 0.0], [2 * width, 0.0], arc, [0.0, 2 * width], [0.0, 1.0]])
    n = len(profile)
    v = np.concatenate([np.column_stack([profile[:, 0], np.full(n, y), profile[:, 1]]) for y in (0.0, 1.0)])
    i = np.arange(n - 1)
    f = np.concatenate([np.column_stack([i, i + 1, n + i + 1]), np.column_stack([i, n + i + 1, n + i])])
    return v, f, np.concatenate([i, i])


def test_thin_strips_do_not_chain_perpendicular_faces_into_one_region():
    """Strips thinner than the merge tolerance are flat against any plane through their long edge;
    a chain of them made one coplanar region of two perpendicular faces (0.35 thick), whose
    boundary edges then fell within reach of every piece (angle_block.STL's exact decoding: 76
    million candidate pairs, 24 GB). With a flatness limit the region splits at the strips."""
    from planefmt.geometry.planarpatches import ConvexPatches

    v, f, strip = fold_with_micro_fillet(1e-7)
    tol = 2e-7
    first, last = strip == 0, strip == strip.max()
    chained = ConvexPatches(v, f, tol)
    joined = chained.region_of[first][0]
    assert joined >= 0 and (chained.region_of[first | last] == joined).all()
    assert chained.region_tau[joined] > 0.3
    split = ConvexPatches(v, f, tol, flatness=100 * tol)
    a, b = split.region_of[first], split.region_of[last]
    assert (a == a[0]).all() and (b == b[0]).all() and a[0] >= 0 and b[0] >= 0 and a[0] != b[0]
    valid = np.unique(split.region_of[split.region_of >= 0])
    assert (split.region_tau[valid] <= 100 * tol).all()
    # Against the sharp fold it rounds off (2e-7 away at most): certified at a 1e-6 target.
    sharp = np.array([[1, 0, 0], [0, 0, 0], [0, 0, 1], [1, 1, 0], [0, 1, 0], [0, 1, 1]], dtype=np.float64)
    r = hausdorff(v, f, sharp, np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]]), target=1e-6)
    assert r.certified and 0 < r.lower <= r.upper <= 1e-6
