"""Wedge bounds around a vertex star (planefmt.geometry.stars) and what they add to the Hausdorff certificate."""

from __future__ import annotations

import numpy as np
import trimesh

from planefmt.geometry import hausdorff as hd
from planefmt.geometry.halfspace import intersect
from planefmt.geometry.planarpatches import ConvexPatches
from planefmt.geometry.stars import VertexStars
from planefmt.geometry.trianglegeom import closest_distance


def fan(angles: np.ndarray, radii: np.ndarray, heights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A closed fan around the origin: spokes at the given angles (ascending), triangles counter-clockwise."""
    k = len(angles)
    v = np.vstack([[0.0, 0.0, 0.0], np.column_stack([radii * np.cos(angles), radii * np.sin(angles), heights])])
    f = np.array([[0, 1 + i, 1 + (i + 1) % k] for i in range(k)], dtype=np.int64)
    return v, f


def stars_of(v: np.ndarray, f: np.ndarray, cluster_edge: float = 0.0) -> VertexStars:
    return VertexStars(v, f, ConvexPatches(v, f, 0.0), cluster_edge)


def test_bound_is_never_below_the_sampled_distance_over_random_stars():
    rng = np.random.default_rng(7)
    checked = 0
    for trial in range(120):
        k = int(rng.integers(3, 13))
        angles = np.sort(rng.uniform(0, 2 * np.pi, k))
        if np.diff(np.r_[angles, angles[0] + 2 * np.pi]).max() > 0.9 * np.pi:
            continue
        # Nearly flat stars (a smooth mesh's) and steep ones (a cone's tip).
        v, f = fan(angles, rng.uniform(0.5, 1.5, k), rng.normal(0, (0.02, 0.3)[trial % 2], k))
        stars = stars_of(v, f)
        if stars.row[0] < 0:
            continue
        pieces = rng.uniform(-0.4, 0.4, (10, 3, 3))
        pieces[:, :, 2] *= rng.uniform(0, 0.1)
        bound = stars.bound(pieces, np.zeros(len(pieces), dtype=np.int64))
        weights = rng.dirichlet([1, 1, 1], 1000)
        for piece, b in zip(pieces, bound):
            sampled = closest_distance(np.vstack([weights @ piece, piece]), v, f)[0].max()
            assert sampled <= b + 1e-12
            checked += np.isfinite(b)
    assert checked > 500


def test_small_piece_over_a_flat_star_is_bounded_by_its_height():
    angles = np.arange(6) * np.pi / 3
    v, f = fan(angles, np.ones(6), np.zeros(6))
    stars = stars_of(v, f)
    # A piece 1e-3 above the star's plane, straddling every wedge: its distance is exactly 1e-3.
    piece = np.array([[[-0.1, -0.1, 1e-3], [0.1, -0.05, 1e-3], [0.0, 0.1, 1e-3]]])
    b = stars.bound(piece, np.array([0]))
    assert 1e-3 <= b[0] < 1e-3 + 1e-13


def test_spokes_leaving_a_gap_of_pi_give_no_star():
    angles = np.arange(6) * np.pi / 3
    v, f = fan(angles, np.ones(6), np.zeros(6))
    # Two triangles: spokes at 0, 60 and 120 degrees leave 240 degrees uncovered by convex wedges.
    stars = stars_of(v, f[:2])
    assert stars.row[0] == -1
    piece = np.array([[[-0.1, -0.1, 1e-3], [0.1, -0.05, 1e-3], [0.0, 0.1, 1e-3]]])
    assert np.isinf(stars.bound(piece, np.array([0]))[0])
    # Five of six: a hole in the fan, but the wedges still cover space; the bound stays valid.
    bound = stars_of(v, f[:5]).bound(piece, np.array([0]))[0]
    weights = np.random.default_rng(0).dirichlet([1, 1, 1], 2000)
    assert closest_distance(weights @ piece[0], v, f[:5])[0].max() <= bound < np.inf


def test_a_cluster_of_close_vertices_is_one_star():
    """A hexagonal fan whose centre is a triangle 1e-7 across, as where several planes nearly meet."""
    angles = np.arange(6) * np.pi / 3
    rim = np.column_stack([np.cos(angles), np.sin(angles), 0.05 * (-1.0) ** np.arange(6)])
    core = 1e-7 * np.array([[1.0, 0.0, 0.0], [-0.5, 0.8, 0.0], [-0.5, -0.8, 0.0]])
    v = np.vstack([core, rim])
    f = [(0, 1, 2)]
    owner = [0, 0, 1, 1, 2, 2]
    for i in range(6):
        j = (i + 1) % 6
        f.append((owner[i], 3 + i, 3 + j))
        if owner[j] != owner[i]:
            f.append((owner[i], 3 + j, owner[j]))
    f = np.array(f, dtype=np.int64)
    piece = np.array([[[-0.01, -0.01, 1e-3], [0.01, -0.005, 1e-3], [0.0, 0.01, 1e-3]]])
    weights = np.random.default_rng(0).dirichlet([1, 1, 1], 20000)
    sampled = closest_distance(np.vstack([weights @ piece[0], piece[0]]), v, f)[0].max()
    one = stars_of(v, f, cluster_edge=1e-6)
    assert one.row[0] == one.row[1] == one.row[2] >= 0
    b = one.bound(piece, np.array([1]))[0]
    assert sampled <= b <= 1.01 * sampled
    # Each core vertex alone has wedges over thin triangles: valid, far from tight.
    assert stars_of(v, f).bound(piece, np.array([1]))[0] > 5 * b


def smooth_pair() -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """An icosphere and the polytope of its face planes, each moved by up to 5e-8: a decoded smooth mesh.

    The polytope's vertices sit near, not on, the sphere's; where six or five nearly
    coplanar triangles meet, the nearest face changes between triangles that share no edge.
    """
    m = trimesh.creation.icosphere(subdivisions=3)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    normal = np.asarray(m.face_normals)
    h = np.einsum("ij,ij->i", normal, v[f[:, 0]]) + 5e-8 * np.random.default_rng(3).uniform(-1, 1, len(f))
    p = intersect(normal, h)
    return (v, f), (p.vertices, p.triangles)


def test_smooth_mesh_against_its_moved_planes_certifies_only_with_stars(monkeypatch):
    a, b = smooth_pair()
    target = 1e-6
    with_stars = hd.hausdorff(*a, *b, target=target, max_pieces=300_000)
    assert with_stars.certified and with_stars.upper <= target
    monkeypatch.setattr(hd._Direction, "_star_bound",
                        lambda self, corners, centroid, threshold: np.full(len(corners), np.inf))
    without = hd.hausdorff(*a, *b, target=target, max_pieces=300_000)
    assert not without.certified
    assert without.lower == with_stars.lower
