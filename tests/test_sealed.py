"""Sealed surfaces (kind 5, spec §9.9): closed bodies whose BSP trees do not decode faithfully."""

from __future__ import annotations

import io

import numpy as np
import pytest

import planefmt
from planefmt import codec
from planefmt.groups.bodies import decode_groups, encode_groups
from planefmt.geometry.topology import euler_characteristic, is_closed_manifold, signed_volume
from planefmt.errors import GeometryError, PlnError
from planefmt.geometry.hausdorff import hausdorff
from planefmt.model import GroupKind, Header, Mesh, Node, Scene
from planefmt.geometry.planetable import PlaneTable
from planefmt.geometry.planes import from_triplets, to_triplets
from planefmt.groups.sealed import corners, decode_sealed, encode_sealed

import shapes
from corpus import CORPUS

TOL = 1e-6


@pytest.fixture
def no_tree(monkeypatch):
    """Every BSP attempt refused, as for King_geom.usd's smooth bodies (tunnels below the tolerance)."""
    import planefmt.groups.bodies

    def refuse(*args, **kwargs):
        args[-1].note = "refused by the test"
        return None

    monkeypatch.setattr(planefmt.groups.bodies, "encode_solid", refuse)
    monkeypatch.setattr(planefmt.groups.bodies, "MIXED_ROUNDS", 0)


def _corpus(rel: str) -> tuple[np.ndarray, np.ndarray]:
    from planefmt_converters import registry
    from planefmt_converters.assemble import flatten

    scene, _ = registry.read(str(CORPUS / rel))
    mesh = flatten(scene)
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)


@pytest.mark.parametrize("rel", ["nonconvex_watertight/torus.STL", "nonconvex_watertight/fuze.obj",
                                 "cad/box.STL"])
def test_closed_corpus_bodies_decode_sealed_with_their_topology(rel, no_tree) -> None:
    """Closed, the source's Euler characteristic and volume, certified Hausdorff within the
    tolerance: smooth (torus, fuze) and flat CAD faces (box: vertices inside flat polygons and on
    straight creases need vertex planes)."""
    v, f = _corpus(rel)
    enc = encode_groups(v, f, tolerance=TOL)
    assert {r.kind for r in enc.reports} == {"sealed"}, [r.note for r in enc.reports]
    dv, df = decode_groups(*from_triplets(to_triplets(enc.omega, enc.h)), enc.groups)
    sv, sf = enc.vertices, enc.faces
    diag = float(np.linalg.norm(np.ptp(sv[np.unique(sf)], axis=0)))
    assert is_closed_manifold(df, len(dv))
    assert euler_characteristic(df) == euler_characteristic(sf)
    vol = signed_volume(sv, sf)
    assert abs(signed_volume(dv, df) - vol) <= 1e-6 * abs(vol)
    h = hausdorff(dv, df, sv, sf, target=TOL * diag)
    assert h.certified and h.upper <= TOL * diag, h.upper / diag
    extra = len(np.unique(np.concatenate([g.refs[g.bounding] for g in enc.groups])))
    print(f"{rel}: {len(sf)} triangles, {len(enc.h)} planes of which {extra} vertex planes, "
          f"H {h.upper / diag:.2g} of the diagonal")
    if rel == "cad/box.STL":
        assert extra > 0


def test_every_vertex_level_meets_the_budget() -> None:
    """A cube cut into a 4x4 grid per face: grid points inside a face lie on one plane (two vertex
    planes each), points on an edge on two (one each), the corners on three (none)."""
    v, f = _grid_cube(4)
    w = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    planes, face_plane = np.unique(np.round(np.column_stack([w, np.einsum("ij,ij->i", w, v[f[:, 0]])]), 12),
                                   axis=0, return_inverse=True)
    table = PlaneTable(planes[:, :3], planes[:, 3])
    s = encode_sealed(v, f, face_plane.reshape(-1), table, 1e-9)
    used = np.unique(f)
    inner = ((v[used] > 0) & (v[used] < 1)).sum(axis=1)  # coordinates strictly inside: 2 = face, 1 = edge
    assert np.array_equal(np.isin(s.vertex_planes, s.added).sum(axis=1), inner)
    assert (inner == 2).any() and (inner == 1).any() and (inner == 0).sum() == 8
    omega, h = table.arrays()
    assert np.abs(corners(omega, h, s.vertex_planes) - v[used]).max() <= 1e-12
    assert s.error <= 1e-9


def _grid_cube(n: int) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    box = trimesh.creation.box(extents=(1, 1, 1))
    box.apply_translation((0.5, 0.5, 0.5))
    for _ in range(int(np.log2(n))):
        box = box.subdivide()
    box.merge_vertices()
    return np.asarray(box.vertices, dtype=np.float64), np.asarray(box.faces)


@pytest.mark.parametrize("major", [5, 6])
def test_sealed_files_are_version_5_0_and_decode_as_encoded(no_tree, major) -> None:
    v, f = shapes.ring(12)
    buf = io.BytesIO()
    header = codec.encode_scene(Scene(nodes=(Node(name="ring", mesh=Mesh(v, f)),)), buf, tolerance=TOL, scheme="paper",
                                major=major)
    assert header.version == (major, 0)
    with planefmt.open(io.BytesIO(buf.getvalue())) as r:
        groups = list(r.part_groups())
    assert [g.kind for g in groups] == [GroupKind.SEALED]
    g = groups[0]
    assert not g.bounding[g.facets[:, 0]].any() and (np.diff(g.facets[:, 0].astype(np.int64)) >= 0).all()
    mesh = codec.decode_scene(io.BytesIO(buf.getvalue())).nodes[0].mesh
    assert is_closed_manifold(mesh.faces, len(mesh.vertices))
    assert euler_characteristic(mesh.faces) == euler_characteristic(f) == 0
    diag = float(np.linalg.norm(np.ptp(v, axis=0)))
    assert hausdorff(mesh.vertices, mesh.faces, v, f).upper <= header.error_bound * diag * (1 + 1e-6)


def test_a_vertex_on_parallel_planes_is_a_bad_vertex() -> None:
    omega = np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])
    h = np.array([1.0, 0.0, 1.0, 1.0])
    with pytest.raises(GeometryError) as e:
        decode_sealed(omega, h, np.array([[0, 1, 2], [0, 2, 3], [1, 2, 3]]), np.array([[0, 0, 1, 2]]))
    assert e.value.code == "BAD_VERTEX"
    group = planefmt.PartGroup(index=0, object=0, kind=GroupKind.SEALED, refs=np.arange(4, dtype=np.uint32),
                               bounding=np.zeros(4, bool), vertex_planes=np.array([[0, 1, 2], [0, 2, 3], [1, 2, 3]]),
                               facets=np.array([[0, 0, 1, 2]]))
    with pytest.raises(GeometryError) as e:
        codec.decode_group(to_triplets(omega, h), group, 0)
    assert e.value.code == "BAD_VERTEX" and "part group 0" in str(e.value)


def test_writers_of_older_versions_refuse_sealed_groups() -> None:
    for version in [(1, 0), (2, 0), (3, 0)]:
        with planefmt.Writer(io.BytesIO(), Header(version=version)) as w:
            w.add_object("o")
            w.add_planes(to_triplets(np.eye(3), np.ones(3)))
            with pytest.raises(PlnError) as e:
                w.add_group(0, GroupKind.SEALED, np.arange(3), vertex_planes=np.array([[0, 1, 2]] * 3),
                            facets=np.array([[0, 0, 1, 2]]))
            assert e.value.code == "UNKNOWN_GROUP_KIND"


def test_kind_5_of_an_older_version_is_opaque_and_skipped() -> None:
    """In a 1.1 file kind 5 is a newer minor version's kind like any other: its bytes are kept,
    not parsed, and a reader skips it (a 1.0 file with it is an error)."""
    for version, finding in [((1, 1), "SKIPPED_GROUP_KIND"), ((1, 0), None)]:
        buf = io.BytesIO()
        with planefmt.Writer(buf, Header(version=version)) as w:
            w.add_object("o")
            w.add_planes(to_triplets(np.eye(3), np.ones(3)))
            w.add_group(0, GroupKind.SEALED, np.arange(3), extra=b"\x07anything")
        if finding is None:
            with pytest.raises(PlnError) as e, planefmt.open(io.BytesIO(buf.getvalue())) as r:
                list(r)
            assert e.value.code == "UNKNOWN_GROUP_KIND"
            continue
        with planefmt.open(io.BytesIO(buf.getvalue())) as r:
            (g,) = list(r.part_groups())
            assert g.extra == b"\x07anything" and g.facets is None
            assert finding in [code for code, _ in r.findings]
        codes = [f.code for f in planefmt.codec.validate(io.BytesIO(buf.getvalue()))]
        assert sorted(codes) == ["NEWER_MINOR_VERSION", finding]


def test_a_closed_surface_facing_inwards_decodes_closed() -> None:
    """Not a solid (negative volume), so no tree; patches close only where one polytope holds them
    all (an inverted cube), otherwise its triangles go into a sealed group (an inverted ring)."""
    for (v, f), kind in [(shapes.cube(), "patches"), (shapes.ring(12), "sealed")]:
        f = f[:, ::-1]
        enc = encode_groups(v, f, tolerance=TOL)
        assert [r.kind for r in enc.reports] == [kind], [r.note for r in enc.reports]
        mesh = codec.decode_mesh(codec.encode_mesh(v, f, tolerance=TOL, scheme="paper"))
        assert is_closed_manifold(mesh.faces, len(mesh.vertices))
        assert euler_characteristic(mesh.faces) == euler_characteristic(f)
        assert signed_volume(mesh.vertices, mesh.faces) == pytest.approx(signed_volume(v, f), rel=1e-6)
        assert signed_volume(v, f) < 0


@pytest.mark.parametrize("seed", range(4))
def test_plane_table_extend_gives_what_add_gives_row_by_row(seed: int) -> None:
    """``PlaneTable.extend`` (one numpy pass) against ``add`` called per row: the same indices, planes
    and signs, with rows repeated within a batch, across batches, equal to input planes (which are
    not reused, as ``add`` does not reuse them) and -0.0 beside 0.0."""
    rng = np.random.default_rng(seed)
    values = np.array([-1.0, -0.0, 0.0, 0.5, 1.0])
    for _ in range(50):
        base = int(rng.integers(0, 5))
        w0, h0 = rng.choice(values, size=(base, 3)), rng.choice(values, size=base)
        by_row, batched = PlaneTable(w0, h0), PlaneTable(w0, h0)
        for _ in range(int(rng.integers(1, 6))):
            k = int(rng.integers(0, 40))
            w, h = rng.choice(values, size=(k, 3)), rng.choice(values, size=k)
            if base and k and rng.random() < 0.3:
                w[0], h[0] = w0[0], h0[0]
            expected = [by_row.add(x, float(c)) for x, c in zip(w, h)]
            assert batched.extend(w, h).tolist() == expected
            x, c = rng.choice(values, size=3), float(rng.choice(values))
            assert batched.add(x, c) == by_row.add(x, c)
        (oa, ha), (ob, hb) = by_row.arrays(), batched.arrays()
        assert np.array_equal(oa, ob) and np.array_equal(ha, hb)
        assert np.array_equal(np.signbit(oa), np.signbit(ob)) and np.array_equal(np.signbit(ha), np.signbit(hb))
