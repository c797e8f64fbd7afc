"""Exact side tests (planefmt.geometry.predicates) and the exact surface of a BSP tree (planefmt.groups.exactbsp)."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

import planefmt.groups.bodies as bodies
import planefmt.groups.solids as solids
from planefmt.groups.bodies import encode_groups, plane_positions, reflex_planes
from planefmt.geometry.topology import euler_characteristic, is_closed_manifold, signed_volume
from planefmt.groups.bsptree import parse
from planefmt.groups.exactbsp import exact_boundary, split_pinches
from planefmt.model import GroupKind
from planefmt.geometry.planes import from_triplets, to_triplets
from planefmt.geometry.predicates import points, sides
from planefmt.geometry.trianglegeom import TriangleIndex

import shapes
from corpus import CORPUS

KING = CORPUS / "usd" / "King_geom.usd"


def _rational_side(omega: np.ndarray, h: np.ndarray, t: np.ndarray, q: int) -> int:
    """sign(omega_q . X - h_q) with X solved from planes t by Cramer's rule in rationals."""
    a = [[Fraction(float(x)) for x in omega[p]] for p in t]
    b = [Fraction(float(h[p])) for p in t]

    def det(m: list[list[Fraction]]) -> Fraction:
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))

    d = det(a)
    x = []
    for col in range(3):
        m = [row[:] for row in a]
        for r in range(3):
            m[r][col] = b[r]
        x.append(det(m) / d)
    value = sum(Fraction(float(omega[q][i])) * x[i] for i in range(3)) - Fraction(float(h[q]))
    return (value > 0) - (value < 0)


def test_sides_agree_with_rational_arithmetic_on_and_near_the_plane():
    rng = np.random.default_rng(7)
    n = 120
    omega = rng.normal(size=(n, 3))
    omega /= np.linalg.norm(omega, axis=1)[:, None]
    h = rng.normal(size=n)
    # Planes through the (rounded) point of planes 0, 1, 2: each one is within rounding of it, on
    # either side or exactly through it, where a float evaluation cannot tell.
    x = points(omega, h, np.array([[0, 1, 2]]))[0]
    near = rng.normal(size=(60, 3))
    near /= np.linalg.norm(near, axis=1)[:, None]
    # Axis planes through a dyadic point, and planes 3 and 4 moved onto it: exactly concurrent.
    axis = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0.6, 0.8, 0.0], [0, 0.8, 0.6]])
    dyadic = np.array([0.5, 0.25, 0.125])
    omega = np.vstack([omega, near, axis])
    h = np.concatenate([h, near @ x, axis @ dyadic])
    t = rng.integers(0, n, (400, 3))
    t = np.vstack([t[(t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])],
                   np.tile([0, 1, 2], (60, 1)), np.tile([n + 60, n + 61, n + 62], (2, 1))])
    q = np.concatenate([rng.integers(0, n, len(t) - 62), np.arange(n, n + 60), [n + 63, n + 64]])
    got = sides(omega, h, t, q)
    want = np.array([0 if qq in tt else _rational_side(omega, h, tt, int(qq)) for tt, qq in zip(t, q)])
    assert np.array_equal(got, want)
    # The near planes really are undecidable in float64: both signs occur among them.
    assert set(want[-62:-2].tolist()) == {-1, 1}
    assert sides(omega, h, np.array([[0, 1, 2]]), np.array([1]))[0] == 0


@pytest.mark.parametrize("make", [shapes.fig7_block, shapes.ring, shapes.plate_with_holes,
                                  lambda: shapes.random_boxes(1)], ids=["fig7", "ring", "plate", "boxes"])
def test_exact_surface_is_the_solid(make):
    v, f = make()
    enc = encode_groups(v, f, tolerance=1e-6)
    omega, h = from_triplets(to_triplets(enc.omega, enc.h))
    bsp = [g for g in enc.groups if g.kind == GroupKind.BSP]
    assert bsp
    diag = float(np.linalg.norm(np.ptp(enc.vertices, axis=0)))
    source = TriangleIndex(enc.vertices, enc.faces)
    for g in bsp:
        w, c = omega[g.refs], h[g.refs]
        dv, dt, plane = exact_boundary(parse(g.tree, len(c)), w, c, 8.0 * float(np.abs(c).max()))
        assert is_closed_manifold(dt, len(dv))
        assert euler_characteristic(dt) == euler_characteristic(enc.faces)
        vol = signed_volume(enc.vertices, enc.faces)
        assert abs(signed_volume(dv, dt) - vol) <= 1e-12 * abs(vol)
        d, _ = source.query(dv[np.unique(dt)])
        assert d.max() <= 1e-12 * diag
        # Each triangle lies on the plane it names.
        assert np.abs(np.einsum("tij,tj->ti", dv[dt], w[plane]) - c[plane][:, None]).max() <= 1e-12 * diag


def test_split_pinches_gives_each_sheet_its_own_vertex():
    """Two tetrahedra touching at one vertex: one vertex for both is not a manifold point."""
    tet = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1]], dtype=float)
    other = np.array([[0, 5, 4], [0, 4, 6], [4, 5, 6], [0, 6, 5]])
    f = np.vstack([tet, other])
    assert euler_characteristic(f) == 3
    nv, nf = split_pinches(v, f)
    assert len(nv) == 8 and euler_characteristic(nf) == 4
    assert np.array_equal(nv[nf], v[f])


@pytest.mark.slow  # about 90 s on a quiet core: make test-slow, which CI runs
def test_exact_decoding_closes_what_rounded_decisions_misplace(monkeypatch):
    """King_geom.usd's base (7,392 triangles, fillets of 30 planes within a micrometre): its first
    tree decodes open when sides are decided in float64 and closed, with the source's volume and
    Euler characteristic, in exact arithmetic."""
    from planefmt.groups.bodies import body_labels
    from planefmt.geometry.polygonize import polygonize
    from planefmt.geometry.repair import merge_close_vertices
    from planefmt.groups.solids import partition
    from planefmt_converters import registry
    from planefmt_converters.assemble import flatten

    mesh = flatten(registry.read(KING)[0])
    diag = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    v, f, _, _ = merge_close_vertices(mesh.vertices, mesh.faces, 1e-9 * diag)
    poly = polygonize(v, f, tolerance=5e-7)
    labels = body_labels(poly.faces, len(poly.vertices))
    sel = labels == np.argmax(np.bincount(labels) == 7392)
    ff, fp = poly.faces[sel], poly.face_plane[sel]
    x, rmax = plane_positions(poly.vertices, ff, fp, poly.omega, poly.h)
    eps = max(1e-14 * diag, 4.0 * rmax, 64.0 * np.finfo(np.float64).eps * float(np.abs(x).max()))
    part = partition(poly.omega, poly.h, x[ff], fp, eps, reflex_planes(x, ff, fp, poly.omega, poly.h, eps), seed=0)
    split = part.tokens <= np.uint32(0xFFFFFFEF)
    used, local = np.unique(part.tokens[split], return_inverse=True)
    tokens = part.tokens.copy()
    tokens[split] = local.astype(np.uint32)
    w, c = from_triplets(to_triplets(poly.omega[used], poly.h[used]))
    face = np.ones(len(used), dtype=bool)

    surface = solids.TreeSurface(w, c, tokens, face)
    rv, rt, _ = surface.rounded
    assert not surface.closed and not is_closed_manifold(rt, len(rv))
    dv, dt, _ = surface.exact()
    assert is_closed_manifold(dt, len(dv))
    assert euler_characteristic(dt) == euler_characteristic(ff) == 2
    vol = signed_volume(poly.vertices, ff)
    assert abs(signed_volume(dv, dt) - vol) <= 1e-9 * abs(vol)
    d, _ = TriangleIndex(poly.vertices, ff).query(dv[np.unique(dt)])
    assert d.max() <= 1e-6 * diag
    # The encoder keeps it only once its distance certifies.
    assert bodies._certify(poly.vertices, ff, dv, dt, 1e-6 * diag) is None
    monkeypatch.setattr(bodies, "EXACT_CERTIFY_PIECES", 1)
    assert "not certified" in bodies._certify(poly.vertices, ff, dv, dt, 1e-6 * diag)


def test_exact_side_tests_are_capped(monkeypatch):
    """A square pyramid: its four side planes pass (within rounding) through the apex, where no
    float64 bound decides a side; with no exact test allowed the decoding stops with
    LIMIT_EXCEEDED (decode_tree then keeps its rounded surface, as the King test shows)."""
    import planefmt.groups.exactbsp as exactbsp
    from planefmt.errors import GeometryError

    omega = np.array([[1.0, 0, 1], [-1.0, 0, 1], [0, 1.0, 1], [0, -1.0, 1], [0, 0, -1.0]])
    omega /= np.linalg.norm(omega, axis=1)[:, None]
    h = omega @ np.array([0.0, 0.0, 1.0])
    h[4] = 0.0
    tokens = np.array([0, 1, 2, 3, 4, 0xFFFFFFFE] + [0xFFFFFFFF] * 5, dtype=np.uint32)
    dv, dt, _ = exact_boundary(parse(tokens, 5), omega, h, 8.0)
    assert is_closed_manifold(dt, len(dv)) and abs(signed_volume(dv, dt) - 4.0 / 3.0) <= 1e-12
    monkeypatch.setattr(exactbsp, "EXACT_LIMIT", 0)
    with pytest.raises(GeometryError) as err:
        exact_boundary(parse(tokens, 5), omega, h, 8.0)
    assert err.value.code == "LIMIT_EXCEEDED"


def test_a_chain_of_200000_splits_is_refused_before_its_quadratic_decode():
    # issue 49 item 3: a chain of 20,000 repeated splits took 25 s; the work bound of spec §9.7 (the
    # sum of the nodes' depths) refuses the 200,000 chain in parse, before any clip.
    import numpy as np

    from planefmt.errors import LimitError
    from planefmt.groups.bsptree import parse
    from planefmt.model import BSP_IN, BSP_OUT

    n = 200_000
    tokens = np.array([0] * n + [BSP_IN] + [BSP_OUT] * n, dtype=np.int64)
    with pytest.raises(LimitError) as info:
        parse(tokens, 1)
    assert info.value.code == "LIMIT_EXCEEDED"


@pytest.mark.parametrize("tokens", [(2, 2, 0, 1, 1), (2, 2, 2, 0, 1, 1, 1)], ids=["twice", "three times"])
def test_an_in_leaf_reached_by_one_split_repeated_is_unbounded(tmp_path, tokens):
    # issue 49 item 3: the IN leaf x <= 1 behind the same split twice was "valid (0 findings)" with an
    # empty mesh (the convex piece's repeated plane clipped its own face away); spec §9.7.
    import math

    import planefmt
    from planefmt.errors import GeometryError
    from spec_files import pln_file, uv

    path = tmp_path / "twice.pln"
    path.write_bytes(pln_file([(2, [0], [], uv(len(tokens)) + bytes(tokens))], [(math.pi / 2, 0.0, 1.0)],
                              major=5, minor=2))
    with pytest.raises(GeometryError) as info:
        planefmt.decode_mesh(path)
    assert info.value.code == "UNBOUNDED_POLYTOPE"
