"""The corner bound of two convex surfaces against the independent measure and the certified search."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from planefmt import codec
from planefmt.convexbound import convex_hausdorff
from planefmt.hausdorff import hausdorff

import shapes
from independent_distance import hausdorff_lower_bound


def _hull(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    hull = trimesh.convex.convex_hull(points)
    return np.asarray(hull.vertices), np.asarray(hull.faces)


@pytest.mark.parametrize("seed, noise", [(1, 1e-2), (2, 1e-4), (3, 1e-7), (4, 0.3)])
def test_the_bound_of_two_convex_hulls_is_the_measured_distance(seed, noise):
    """Two hulls of jittered points on a sphere: the bound is never below the independent measure,
    and (between convex bodies the distance is reached at a corner, which the measure samples)
    exceeds it by no more than rounding."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(80, 3))
    points /= np.linalg.norm(points, axis=1)[:, None]
    a = _hull(points)
    b = _hull(points + rng.normal(scale=noise, size=points.shape))
    upper, lower = convex_hausdorff(*a, *b)
    measured = hausdorff_lower_bound(*a, *b)
    assert upper >= measured - 1e-12
    assert upper <= measured + 1e-9
    assert lower <= upper
    certified = hausdorff(*a, *b, target=0.0)
    assert float(certified.lower) <= upper + 1e-12


def test_a_face_pushed_in_counts_in_both_directions():
    """A cube and the same cube with its top face 0.25 lower: the distance is 0.25 whichever
    surface is the source."""
    v, f = shapes.cube()
    low = v.copy()
    top = v[:, 2] == v[:, 2].max()
    low[top, 2] -= 0.25 * np.ptp(v[:, 2])
    for x, y in (((v, f), (low, f)), ((low, f), (v, f))):
        upper, lower = convex_hausdorff(*x, *y)
        assert upper == pytest.approx(0.25 * np.ptp(v[:, 2]), rel=1e-9)
        assert lower == pytest.approx(upper, rel=1e-9)


def test_a_surface_that_is_not_convex_gets_no_bound():
    v, f = shapes.cube()
    dented = v.copy()
    dented[0] = v.mean(axis=0) * 0.5 + v[0] * 0.5  # a corner pulled halfway to the centre
    ring = trimesh.creation.annulus(0.5, 1.0, 1.0)
    assert convex_hausdorff(dented, f, v, f) is None
    assert convex_hausdorff(v, f, ring.vertices, ring.faces) is None


def test_an_encoded_convex_body_records_the_corner_bound():
    """A cube under a random linear map (every corner on three planes, so the coarse planes decode
    convex, with no corners merged) at 1e-4, coded as one convex group: the header's bound is the
    corners' and not below the independent measure."""
    rng = np.random.default_rng(7)
    v, f = shapes.cube()
    linear = np.eye(3) + 0.3 * rng.normal(size=(3, 3))
    v = v @ linear.T
    if np.linalg.det(linear) < 0:  # a mirror turns the triangles inside out
        f = f[:, ::-1]
    enc = codec.encode_mesh(v, f, tolerance=1e-4)
    assert [g.kind for g in enc.groups] == [codec.GroupKind.CONVEX]
    mesh = codec.decode_mesh(enc)
    diagonal = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    upper, _ = convex_hausdorff(mesh.vertices, mesh.faces, v, f)
    measured = hausdorff_lower_bound(v, f, mesh.vertices, mesh.faces)
    assert enc.error_bound * diagonal >= measured - 1e-12
    assert enc.error_bound == pytest.approx(upper / diagonal, rel=1e-6)
    assert 0.1 * 1e-4 < enc.error_bound <= 1e-4  # coded coarsely enough for the bound to be more than rounding
