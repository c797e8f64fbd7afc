"""Closed non-convex solids as BSP trees of their own planes (planefmt.groups.solids, bsptree, seams, bodies)."""

from __future__ import annotations


import numpy as np
import pytest

from planefmt.groups import bodies, solids
from planefmt.groups.bodies import decode_groups, encode_groups
from planefmt.geometry.topology import euler_characteristic, is_closed_manifold, signed_volume
from planefmt.groups.bsptree import parse
from planefmt.errors import GeometryError
from planefmt.geometry.hausdorff import closest_distance, hausdorff
from planefmt.model import BSP_IN, BSP_OUT, GroupKind
from planefmt.geometry.planes import from_triplets, to_triplets
from planefmt.groups.solids import decode_tree

import shapes
from corpus import CORPUS

TOL = 1e-6


def check_solid(v: np.ndarray, f: np.ndarray, splitters: tuple = solids.STRATEGIES) -> dict:
    """Encode and decode a closed mesh; assert the solid contract; return numbers for the caller."""
    enc = encode_groups(v, f, tolerance=TOL, splitters=splitters)
    # The planes as a float64 file holds them, (nu, phi, h): what a reader decodes.
    dv, df = decode_groups(*from_triplets(to_triplets(enc.omega, enc.h)), enc.groups)
    sv, sf = enc.vertices, enc.faces
    diag = float(np.linalg.norm(np.ptp(sv[np.unique(sf)], axis=0)))
    assert is_closed_manifold(df, len(dv)), [r.note for r in enc.reports]
    assert euler_characteristic(df) == euler_characteristic(sf)
    vol = signed_volume(sv, sf)
    assert abs(signed_volume(dv, df) - vol) <= 1e-6 * abs(vol)
    h = hausdorff(dv, df, sv, sf, target=TOL * diag)
    assert h.certified and h.upper <= TOL * diag, (h.lower / diag, h.upper / diag)
    return {"kinds": [r.kind for r in enc.reports], "notes": [r.note for r in enc.reports], "groups": enc.groups,
            "planes": len(enc.h), "details": [r.details for r in enc.reports]}


@pytest.mark.parametrize("seed", range(6))
def test_random_box_unions_are_exact_watertight_solids(seed: int) -> None:
    v, f = shapes.random_boxes(seed)
    out = check_solid(v, f)
    assert "solid" in out["kinds"] or "convex" in out["kinds"]


@pytest.mark.parametrize("make", [shapes.ring, shapes.plate_with_holes, shapes.dented_sphere])
def test_curved_and_holed_solids(make) -> None:
    v, f = make()
    out = check_solid(v, f)
    assert out["kinds"] == ["solid"]
    # Only the mesh's own planes: a BSP group has no bounding (cut) planes.
    assert all(not g.bounding.any() for g in out["groups"])


@pytest.mark.parametrize("shared", [False, True])
def test_touching_bodies_stay_separate(shared: bool) -> None:
    """Two cubes touching along a face: both faces of the contact survive decoding.

    Without shared vertices (box.STL's case) they are two closed bodies; with
    them, one non-manifold body, encoded as patches, exactly.
    """
    a = shapes.cube(0.0, 1.0)
    b = shapes.cube(0.0, 1.0)
    v = np.concatenate([a[0], b[0] + [1.0, 0.0, 0.0]])
    f = np.concatenate([a[1], b[1] + len(a[0])])
    if not shared:
        v = v + np.repeat([[0.0, 0.0, 0.0], [0.0, 0.0, 1e-3]], 8, axis=0)
    enc = encode_groups(v, f, tolerance=TOL)
    assert len(enc.reports) == (1 if shared else 2)
    dv, df = decode_groups(enc.omega, enc.h, enc.groups)
    assert shapes.area(dv, df) == pytest.approx(12.0, rel=1e-9)
    assert euler_characteristic(df) == 4
    # Exact vertex distances both ways (the certified measure does not settle on coincident,
    # opposite faces within its budget; it is exercised on every other shape here).
    assert closest_distance(dv, enc.vertices, enc.faces)[0].max() <= TOL
    assert closest_distance(enc.vertices, dv, df)[0].max() <= TOL


def test_nearly_convex_bodies_are_not_peeled_plane_by_plane() -> None:
    """A nearly convex body: its convex remainder is one piece, not a chain of empty peelings (one
    split per plane, which a decoder walks in quadratic time). 2,808 triangles on 2,612 planes: 619
    splits, 131 pieces when this was written; a peeling chain splits on nearly every plane."""
    v, f = shapes.dented_sphere(64)
    out = check_solid(v, f)
    (kept,) = [d for d in out["details"][0].values() if isinstance(d, dict) and d.get("check") == "ok"]
    print(f"dented sphere: {len(f)} triangles, {out['planes']} planes, {kept}")
    assert kept["splits"] < out["planes"] / 2


def test_decoding_survives_perturbed_planes() -> None:
    """Cells share their splitting planes, so moved planes (a coarse coding) still tile the solid."""
    v, f = shapes.plate_with_holes()
    enc = encode_groups(v, f, tolerance=TOL)
    (g,) = enc.groups
    assert g.kind == GroupKind.BSP
    rng = np.random.default_rng(7)
    omega = enc.omega + rng.normal(0, 1e-7, enc.omega.shape)
    omega /= np.linalg.norm(omega, axis=1)[:, None]
    h = enc.h + rng.normal(0, 1e-7, enc.h.shape)
    dv, df, _ = decode_tree(omega[g.refs], h[g.refs], g.tree, ~g.bounding)
    assert is_closed_manifold(df, len(dv))
    assert euler_characteristic(df) == euler_characteristic(enc.faces)


def test_inside_out_and_open_bodies_are_not_solids() -> None:
    v, f = shapes.cube()
    enc = encode_groups(v, f[:, ::-1], tolerance=TOL)
    assert [r.kind for r in enc.reports] == ["patches"]
    dv, df = decode_groups(enc.omega, enc.h, enc.groups)
    # Orientation kept: every decoded triangle faces into the cube, as the source did.
    n = np.cross(dv[df[:, 1]] - dv[df[:, 0]], dv[df[:, 2]] - dv[df[:, 0]])
    centre = dv[df].mean(axis=1) - 0.5
    assert (np.einsum("ij,ij->i", n, centre) < 0).all()


# -- the token stream (spec §9.7) ------------------------------------------------------------------

@pytest.mark.parametrize("tokens", [
    [], [0], [0, BSP_IN], [BSP_IN, BSP_OUT], [0, BSP_IN, BSP_OUT, BSP_OUT], [5, BSP_IN, BSP_OUT],
    [0xFFFFFFF3], [0, 0xFFFFFFF0, BSP_OUT],
])
def test_malformed_trees_are_rejected(tokens: list[int]) -> None:
    with pytest.raises(GeometryError) as err:
        parse(np.array(tokens, dtype=np.uint32), 2)
    assert err.value.code == "BAD_GROUP_STRUCTURE"


def test_tree_parse_finds_subtrees() -> None:
    # 0 [inner: 1 [IN] [OUT]] [outer: OUT]
    tree = parse(np.array([0, 1, BSP_IN, BSP_OUT, BSP_OUT], dtype=np.uint32), 2)
    assert tree.outer.tolist() == [4, 3, -1, -1, -1]
    assert tree.end.tolist() == [5, 4, 3, 4, 5]


def test_unbounded_in_leaf_is_an_error() -> None:
    omega = np.array([[0.0, 0.0, 1.0]])
    with pytest.raises(GeometryError) as err:
        decode_tree(omega, np.array([1.0]), np.array([0, BSP_IN, BSP_OUT], dtype=np.uint32), np.array([True]))
    assert err.value.code == "UNBOUNDED_POLYTOPE"


def test_cut_planes_carry_no_surface() -> None:
    """A cube split in two by a cut plane decodes to the cube, without the cut face."""
    w = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1], [1, 0, 0]])
    h = np.array([1.0, 0, 1, 0, 1, 0, 0.5])
    chain = [0, 1, 2, 3, 4, 5, BSP_IN] + [BSP_OUT] * 6
    tokens = np.array([6] + chain + chain, dtype=np.uint32)  # both halves of x = 0.5 are IN
    face = np.array([True] * 6 + [False])
    dv, df, plane = decode_tree(w, h, tokens, face)
    assert is_closed_manifold(df, len(dv))
    assert shapes.area(dv, df) == pytest.approx(6.0)
    assert signed_volume(dv, df) == pytest.approx(1.0)
    assert 6 not in plane


def _corpus_node(relative: str, name: str) -> tuple[np.ndarray, np.ndarray]:
    from pathlib import Path

    from planefmt_converters import registry

    path = CORPUS / relative
    scene, _ = registry.read(str(path))
    mesh = next(n.mesh for n in scene.nodes if n.name == name)
    return mesh.vertices, mesh.faces


def test_zero_thickness_fin_leaves_are_classed_by_net_area() -> None:
    """bolt.usda: the shaft's cap lies in the head's top, a downward face on the top plane.

    A splitter on that cap plane used to call its empty far side solid (an IN
    leaf without end); by net area the up-facing top outweighs it.
    """
    v, f = _corpus_node("usd/bolt.usda", "bolt")
    assert check_solid(v, f)["kinds"] == ["solid"]


def test_nearly_concurrent_planes_weld_into_one_closed_surface() -> None:
    """pins.glb, a dowel: cylinder facets and a cap meet in corners 2.7e-8 apart at |h| 200."""
    v, f = _corpus_node("gltf_scene/pins.glb", "dowel#1:9:6:8:7")
    assert check_solid(v, f)["kinds"] == ["solid"]


@pytest.mark.slow  # about 75 s on a quiet core: make test-slow, which CI runs
def test_smooth_closed_body_uses_exact_planes_and_closes_its_cracks() -> None:
    """ballA.off: merged planes pass up to 3e-6 from their vertices, where many meet the cells'
    corners stray; the second attempt on exactly coplanar planes decodes closed once the cracks
    of nearly concurrent planes are welded."""
    from pathlib import Path

    from planefmt_converters import registry
    from planefmt_converters.assemble import flatten

    path = CORPUS / "nonconvex_watertight" / "ballA.off"
    scene, _ = registry.read(str(path))
    mesh = flatten(scene)
    out = check_solid(mesh.vertices, mesh.faces)
    assert out["kinds"] == ["solid"] and out["notes"] == ["exact planes"]


@pytest.mark.slow  # about 50 s on a quiet core: make test-slow, which CI runs
def test_merged_planes_that_stray_are_replaced_by_exact_ones_only_there() -> None:
    """angle_block.STL at 1e-6: its merged planes meet at grazing angles, so a corner of the first
    splitter strategy's tree strays 1.9e-5 for a target of 2.2e-6; the all-exact planes do not
    decode closed (or not certifiably). Exact planes only where the merged tree strayed give a
    solid on far fewer faces' own planes. (The hull-first trees decode within the target on the
    merged planes: the first strategy alone keeps this path tested.)"""
    path = CORPUS / "cad" / "angle_block.STL"
    import trimesh

    mesh = trimesh.load(path, process=False)
    out = check_solid(np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces), solids.STRATEGIES[:1])
    assert out["kinds"] == ["solid"] and out["notes"][0].startswith("mixed planes"), out["notes"]
    exact, total = out["details"][0]["exact faces"], len(mesh.faces)
    print(f"angle_block: {exact} of {total} faces on their exact planes, {out['planes']} planes")
    assert 0 < exact < total / 4


def test_the_smallest_tree_of_the_splitter_strategies_is_kept() -> None:
    """The 20mm cube (embossed letters): the first strategy alone makes a larger tree than the one
    kept; both are solids that meet the contract."""
    path = CORPUS / "cad" / "20mm-xyz-cube.stl"
    import trimesh

    mesh = trimesh.load(path, process=False)
    v, f = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)
    kept = check_solid(v, f)
    first = check_solid(v, f, solids.STRATEGIES[:1])
    assert kept["kinds"] == first["kinds"] == ["solid"]
    tokens = [sum(len(g.tree) for g in out["groups"]) for out in (kept, first)]
    print(f"20mm cube: {tokens[0]} tokens kept, {tokens[1]} of strategy {solids.STRATEGIES[0]}")
    assert tokens[0] < tokens[1]


def _partition_input(v: np.ndarray, f: np.ndarray) -> tuple:
    from planefmt.groups.bodies import plane_positions, reflex_planes
    from planefmt.geometry.polygonize import polygonize

    poly = polygonize(v, f, tolerance=1e-9)
    x, rmax = plane_positions(poly.vertices, poly.faces, poly.face_plane, poly.omega, poly.h)
    eps = max(1e-12, 4.0 * rmax)
    return (poly.omega, poly.h, x[poly.faces], poly.face_plane, eps,
            reflex_planes(x, poly.faces, poly.face_plane, poly.omega, poly.h, eps))


def test_hull_planes_are_split_first_and_written_once() -> None:
    """The plate with holes and a pocket: its six outer faces' planes lead the tree, each with an
    OUT outer side, and no node below splits on them again."""
    v, f = shapes.plate_with_holes()
    omega, h, tri, tri_plane, eps, reflex = _partition_input(v, f)
    extent = {0: 2.0, 1: 1.0, 2: 0.25}
    outer = {j for j in np.unique(tri_plane) for axis, e in extent.items() for sign in (-1.0, 1.0)
             if np.allclose(omega[j], sign * np.eye(3)[axis], atol=1e-9) and abs(h[j] - e) < 1e-9}
    assert len(outer) == 6
    hull_first = solids.partition(omega, h, tri, tri_plane, eps, reflex, strategy=(8, 3.0, True))
    tokens = hull_first.tokens.astype(np.int64)
    assert set(tokens[:6]) == outer and (tokens[-6:] == BSP_OUT).all()
    assert not set(tokens[6:-6]) & outer
    plain = solids.partition(omega, h, tri, tri_plane, eps, reflex, strategy=(8, 3.0, False))
    print(f"plate with holes: {len(tokens)} tokens hull first, {len(plain.tokens)} without")
    assert len(tokens) < len(plain.tokens)


def test_hull_planes_split_first_are_the_largest_few() -> None:
    """A nearly convex body has thousands of hull planes; only the HULL_MAX largest lead its tree
    (a decoder pushes each one's square through everything below it)."""
    v, f = shapes.dented_sphere(32)
    omega, h, tri, tri_plane, eps, _ = _partition_input(v, f)
    hull, rest = solids._hull_planes(omega, h, tri, tri_plane, eps)
    assert len(hull) == solids.HULL_MAX
    area = np.bincount(tri_plane, weights=np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]),
                                                         axis=1))
    reach = np.einsum("nvj,kj->knv", tri, omega).reshape(len(omega), -1).max(axis=1) - h
    others = np.setdiff1d(np.flatnonzero((reach <= eps) & (area > 0)), hull)
    assert len(others) and area[hull].min() >= area[others].max()
    assert not np.isin(tri_plane[rest], hull).any() and np.isin(tri_plane[~rest], hull).all()


def test_edges_cut_by_nearly_coincident_planes_are_carried_by_their_ends(monkeypatch) -> None:
    """pins.glb "sides" (genus 10): two of its planes 6e-4 degrees apart cut the cap; their corners
    weld 5e-5 off the line the vertices of the neighbouring cells lie on. Only carrying each edge
    with its ends' rounding error inserts those vertices and closes the surface. (The encoder's
    mixed planes avoid that tree; without them it is the all-exact planes' tree that decodes. The
    hull-first trees decode on the merged planes: the first splitter strategy alone keeps this
    path tested.)"""
    monkeypatch.setattr(bodies, "MIXED_ROUNDS", 0)
    v, f = _corpus_node("gltf_scene/pins.glb", "sides#1:5:2:4:3")
    out = check_solid(v, f, solids.STRATEGIES[:1])
    assert out["kinds"] == ["solid"] and out["notes"] == ["exact planes"]


def test_pieces_clipped_without_qhull_keep_their_planes(monkeypatch) -> None:
    """Where Qhull cannot intersect a convex piece, its faces are clipped square by square; they lie
    on the piece's own planes, and the triangles say so (busted.STL: such faces were tagged with the
    planes of the tree's first nodes, 1.6 degrees off)."""
    import planefmt.geometry.halfspace

    v, f = shapes.ring()
    enc = encode_groups(v, f, tolerance=TOL)
    (group,) = [g for g in enc.groups if g.kind == GroupKind.BSP]
    omega, h = from_triplets(to_triplets(enc.omega[group.refs], enc.h[group.refs]))
    face = ~group.bounding
    dv, dt, plane = decode_tree(omega, h, group.tree, face)

    def no_qhull(*args, **kwargs):
        raise GeometryError("stub: Qhull declines", code="DEGENERATE_GEOMETRY")

    monkeypatch.setattr(planefmt.geometry.halfspace, "intersect", no_qhull)
    cv, ct, cplane = decode_tree(omega, h, group.tree, face)
    assert is_closed_manifold(ct, len(cv))
    off = np.abs(np.einsum("ij,ij->i", omega[cplane], cv[ct].mean(axis=1)) - h[cplane])
    assert off.max() <= 1e-9 * float(np.abs(h).max())
    # The same surface as through Qhull, plane by plane.
    area = np.linalg.norm(np.cross(dv[dt[:, 1]] - dv[dt[:, 0]], dv[dt[:, 2]] - dv[dt[:, 0]]), axis=1) / 2
    carea = np.linalg.norm(np.cross(cv[ct[:, 1]] - cv[ct[:, 0]], cv[ct[:, 2]] - cv[ct[:, 0]]), axis=1) / 2
    by_plane = np.bincount(plane, weights=area, minlength=len(h))
    np.testing.assert_allclose(np.bincount(cplane, weights=carea, minlength=len(h)), by_plane,
                               atol=1e-9 * by_plane.max())
