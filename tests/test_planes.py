"""Plane math (planefmt.geometry.planes) and polygonization (planefmt.geometry.polygonize), issue 3."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from planefmt.geometry import planes
from planefmt.errors import GeometryError
from planefmt.geometry.polygonize import edge_adjacency, polygonize, weld

from corpus import CORPUS

CUBE_V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                   [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float)
CUBE_F = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                   [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])


def load(rel: str) -> trimesh.Trimesh:
    return trimesh.load(CORPUS / rel, process=False, force="mesh")


# -- planes ------------------------------------------------------------------------------------

def test_triangle_planes_follow_the_paper():
    omega, h, area = planes.triangle_planes(CUBE_V, CUBE_F)
    # Counter-clockwise from outside: normals point away from the centre, h = omega . P1.
    centre = CUBE_V.mean(axis=0)
    tri_centres = CUBE_V[CUBE_F].mean(axis=1)
    assert (np.einsum("ij,ij->i", omega, tri_centres - centre) > 0).all()
    assert np.allclose(h, np.einsum("ij,ij->i", omega, CUBE_V[CUBE_F[:, 0]]))
    assert np.allclose(area, 0.5)
    deg_omega, _, deg_area = planes.triangle_planes(CUBE_V, np.array([[0, 1, 1]]))
    assert deg_area[0] == 0 and np.isnan(deg_omega).all()


def test_angles_at_the_poles_and_the_seam():
    omega = np.array([[0, 0, 1], [0, 0, -1], [0.0, -0.0, 1], [-0.0, -0.0, -1], [1, -1e-300, 0],
                      [1, -1e-17, 0], [1, -0.0, 0], [-1, -0.0, 0], [-1, 0, 0]])
    nu, phi = planes.angles_from_normals(omega)
    assert nu.tolist()[:4] == [0.0, math.pi, 0.0, math.pi]
    assert (phi[:4] == 0.0).all() and not np.signbit(phi[:4]).any()
    # Tiny negative y wraps to 0, never to 2*pi; the seam at -x is pi from either side.
    assert (phi < 2 * math.pi).all() and (phi >= 0).all()
    assert phi[4] == 0.0 and phi[5] == 0.0 and phi[6] == 0.0 and not np.signbit(phi[6])
    assert phi[7] == pytest.approx(math.pi) and phi[8] == math.pi


def test_nu_keeps_precision_near_the_poles():
    tilt = 1e-9
    nu, _ = planes.angles_from_normals(np.array([[math.sin(tilt), 0.0, math.cos(tilt)]]))
    assert nu[0] == pytest.approx(tilt, rel=1e-12)  # arccos(cos 1e-9) would give 0


unit = st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)).filter(
    lambda v: 1e-3 < math.hypot(*v))


@given(st.lists(unit, min_size=1, max_size=30), st.floats(-1e3, 1e3))
def test_triplets_round_trip(normals, h):
    omega = np.array(normals)
    omega /= np.linalg.norm(omega, axis=1)[:, None]
    t = planes.to_triplets(omega, np.full(len(omega), h))
    assert ((t[:, 0] >= 0) & (t[:, 0] <= math.pi) & (t[:, 1] >= 0) & (t[:, 1] < 2 * math.pi)).all()
    back, hb = planes.from_triplets(t)
    assert np.allclose(back, omega, atol=1e-14) and (hb == h).all()


def affine(draw_values) -> np.ndarray:
    q, scale, shift = draw_values
    q = np.array(q) / np.linalg.norm(q)
    w, x, y, z = q
    rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                    [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                    [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = rot @ np.diag(scale)
    m[:3, 3] = shift
    return m


quaternions = st.tuples(*[st.floats(-1, 1)] * 4).filter(lambda q: np.linalg.norm(q) > 0.1)
scales = st.tuples(*[st.floats(0.2, 5.0).flatmap(lambda s: st.sampled_from([s, -s]))] * 3)
shifts = st.tuples(*[st.floats(-100, 100)] * 3)


@settings(max_examples=60)
@given(quaternions, scales, shifts, st.integers(0, 2**31 - 1))
def test_affine_maps_half_spaces_onto_half_spaces(q, scale, shift, seed):
    rng = np.random.default_rng(seed)
    omega = rng.normal(size=(8, 3))
    omega /= np.linalg.norm(omega, axis=1)[:, None]
    h = rng.uniform(-5, 5, 8)
    m = affine((q, scale, shift))
    om2, h2 = planes.transform(omega, h, m)
    # Points on a plane map onto the mapped plane; points inside stay inside (also under reflection).
    basis = np.cross(omega, rng.normal(size=(8, 3)))
    on = omega * h[:, None] + basis * rng.uniform(-3, 3, (8, 1))
    mapped = planes.transform_points(on, m)
    assert np.allclose(np.einsum("ij,ij->i", om2, mapped), h2, atol=1e-9 * (1 + np.abs(mapped).max()))
    inside = on - omega * 0.5
    assert (np.einsum("ij,ij->i", om2, planes.transform_points(inside, m)) < h2).all()
    assert np.allclose(np.linalg.norm(om2, axis=1), 1.0)
    t2 = planes.transform_triplets(planes.to_triplets(omega, h), m)
    assert np.allclose(planes.normals_from_angles(t2[:, 0], t2[:, 1]), om2, atol=1e-12)


@given(shifts, quaternions, st.integers(0, 2**31 - 1))
def test_translation_and_rotation_theorems(shift, q, seed):
    rng = np.random.default_rng(seed)
    omega = rng.normal(size=(5, 3))
    omega /= np.linalg.norm(omega, axis=1)[:, None]
    h = rng.uniform(-5, 5, 5)
    a = np.array(shift)
    om_t, h_t = planes.translate(omega, h, a)
    assert np.array_equal(om_t, omega) and np.allclose(h_t, h + omega @ a)
    m = np.eye(4)
    m[:3, 3] = a
    assert np.allclose(planes.transform(omega, h, m)[1], h_t, atol=1e-9)
    r = affine((q, (1.0, 1.0, 1.0), (0.0, 0.0, 0.0)))[:3, :3]
    om_r, h_r = planes.rotate(omega, h, r)
    assert np.allclose(om_r, omega @ r.T) and np.array_equal(h_r, h)


def test_bad_transforms_are_geometry_errors():
    with pytest.raises(GeometryError):
        planes.transform(np.eye(3), np.ones(3), np.diag([1.0, 1.0, 0.0, 1.0]))
    with pytest.raises(GeometryError):
        planes.rotate(np.eye(3), np.ones(3), np.diag([1.0, 1.0, -1.0]))


# -- polygonization ----------------------------------------------------------------------------

def test_cube_polygonizes_to_six_planes():
    p = polygonize(CUBE_V, CUBE_F)
    assert len(p.h) == 6 and len(p.polygon_plane) == 6
    assert p.max_distance == 0.0 and np.allclose(p.area, 1.0)
    # Each plane is one of the paper's six, with both of its triangles.
    assert (np.bincount(p.face_plane) == 2).all()
    assert sorted(np.round(p.h, 12).tolist()) == [0, 0, 0, 1, 1, 1]


def test_separate_coplanar_faces_share_one_plane_and_slivers_join():
    # Two unit squares in z = 0 two apart (not adjacent), facing -z; plus a zero-area triangle on
    # the first square's edge, which has no plane of its own.
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [3, 0, 0], [4, 0, 0], [4, 1, 0], [3, 1, 0],
                  [0.5, 0, 0]], dtype=float)
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 6, 5], [4, 7, 6], [0, 8, 1]])
    p = polygonize(v, f)
    assert len(p.polygon_plane) == 2 and len(p.h) == 1
    assert np.allclose(p.omega[0], [0, 0, -1]) and p.h[0] == 0.0
    assert p.face_plane[4] == 0 and p.face_polygon[4] == p.face_polygon[0]


def test_noisy_quads_fit_one_plane_with_reported_distance():
    rng = np.random.default_rng(7)
    n = 40
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    z = 0.3 * x + 0.1 * y + 1e-9 * rng.standard_normal(x.shape)
    v = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    i = np.arange(n * n).reshape(n, n)
    a, b, c, d = i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, 1:].ravel(), i[1:, :-1].ravel()
    f = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    p = polygonize(v, f)
    assert len(p.h) == 1
    expected = np.array([-0.3, -0.1, 1.0]) / np.linalg.norm([-0.3, -0.1, 1.0])
    assert np.allclose(p.omega[0], expected, atol=1e-8)
    dist = np.abs(v @ p.omega[0] - p.h[0]).max()
    assert p.max_distance == pytest.approx(dist) and 0 < p.max_distance < 1e-8


def test_curved_surfaces_are_not_chained_into_one_plane():
    # A gently curved strip: each adjacent pair is within the tolerance, the whole is not.
    n = 400
    t = np.linspace(0, 1, n)
    sag = 1e-4 * t ** 2
    v = np.concatenate([np.column_stack([t, np.zeros(n), sag]), np.column_stack([t, np.full(n, 0.01), sag])])
    k = np.arange(n - 1)
    f = np.concatenate([np.column_stack([k, k + 1, k + n + 1]), np.column_stack([k, k + n + 1, k + n])])
    p = polygonize(v, f, tolerance=1e-6)
    assert len(p.h) > 1
    assert p.max_distance <= 4e-6 * p.diagonal


def angle_polygon_count(vertices: np.ndarray, faces: np.ndarray, angle: float) -> int:
    """Polygons an angle-only coplanarity test finds (normals within ``angle`` radians)."""
    v, f = weld(vertices, faces)
    omega, _, _ = planes.triangle_planes(v, f)
    e = edge_adjacency(f, len(v))
    ta, tb = e.a // 3, e.b // 3
    ok = np.einsum("ij,ij->i", omega[ta], omega[tb]) >= math.cos(angle)
    graph = coo_matrix((np.ones(int(ok.sum())), (ta[ok], tb[ok])), shape=(len(f), len(f)))
    return connected_components(graph, directed=False)[0]


@pytest.mark.parametrize("rel", ["cad/angle_block.STL", "cad/plate_holes.STL", "cad/1002_tray_bottom.STL"])
def test_distance_test_finds_the_true_polygons_of_float32_cad(rel):
    mesh = load(rel)
    counts = {tol: len(polygonize(mesh.vertices, mesh.faces, tolerance=tol).polygon_plane)
              for tol in (3e-7, 5e-7, 1e-6, 2e-6)}
    # A plateau over a decade of tolerances: the count is the mesh's, not the threshold's.
    assert len(set(counts.values())) == 1
    p = polygonize(mesh.vertices, mesh.faces)
    assert p.max_distance <= 5e-7 * p.diagonal
    # Normal angles of thin float32 triangles scatter: an angle test at 1e-6 rad splits faces.
    assert angle_polygon_count(mesh.vertices, mesh.faces, 1e-6) > counts[5e-7]


@pytest.mark.parametrize("rel", ["cad/angle_block.STL", "cad/plate_holes.STL", "cad/1002_tray_bottom.STL"])
def test_polygons_are_the_facets_trimesh_finds(rel):
    """A second method: trimesh's facets (adjacent coplanar faces, by its own tests), and each face
    outside a facet a polygon of its own (angle_block.STL: 210, plate_holes.STL: 439)."""
    mesh = trimesh.load(CORPUS / rel, process=True, force="mesh")
    mesh.merge_vertices()
    in_facets = sum(len(f) for f in mesh.facets)
    raw = load(rel)
    assert len(polygonize(raw.vertices, raw.faces).polygon_plane) == len(mesh.facets) + len(mesh.faces) - in_facets


@pytest.mark.parametrize("rel,planes_expected", [("convex/cube_subd.obj", 6), ("convex/tet.ply", 4),
                                                 ("convex/unit_sphere.STL", None)])
def test_corpus_convex_plane_counts(rel, planes_expected):
    """A cube's six faces, a tetrahedron's four; a faceted sphere's triangles have no coplanar
    neighbours, so one plane each."""
    mesh = load(rel)
    expected = len(mesh.faces) if planes_expected is None else planes_expected
    assert len(polygonize(mesh.vertices, mesh.faces).h) == expected


def test_closed_and_oriented_detection():
    assert edge_adjacency(CUBE_F, 8).closed
    assert not edge_adjacency(CUBE_F[:-1], 8).closed
    flipped = CUBE_F.copy()
    flipped[0] = flipped[0, ::-1]
    assert not edge_adjacency(flipped, 8).closed


@pytest.mark.parametrize("vertices,faces", [
    (np.zeros((0, 3)), np.zeros((0, 3), dtype=int)),
    (np.array([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]]), np.array([[0, 1, 2]])),
    (np.zeros((3, 3)), np.array([[0, 1, 2]])),
    (np.eye(3), np.array([[0, 1, 5]])),
])
def test_bad_meshes_are_geometry_errors(vertices, faces):
    with pytest.raises(GeometryError):
        polygonize(vertices, faces)
