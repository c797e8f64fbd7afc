"""The paper's non-convex example (its Fig. 7, a block with a step), encoded as the paper's algorithm 2 does.

The paper stores it as one pseudo-convex part (9 polygons and 4 bounding
planes) and one pseudo-concave part (5 polygons and 4 bounding planes):
22 planes, 264 bytes of float32 planes. In PLN a patch's face on a plane is
that plane's face of one convex polytope, a convex polygon (spec §9.8), so
the top face, a rectangle with the pocket's hole, needs at least four
patches: the pseudo-convex part cannot be one group. The test builds the
block, encodes it with the patch encoder, checks the pocket is the one
pseudo-concave group, that every decoded surface is the block, and prints
the bytes of each coding beside the paper's.
"""

from __future__ import annotations

import numpy as np

import planefmt
from planefmt.bodies import Group, decode_groups, encode_open
from planefmt.hausdorff import hausdorff
from planefmt.model import Coding, GroupKind, Header
from planefmt.patches import PlaneTable
from planefmt.planes import to_triplets
from planefmt.polygonize import polygonize

import shapes

#: The paper's figures for Fig. 7: float32 planes of the plane coding, and the quad mesh's bytes.
PAPER_PLANE_BYTES = 264
PAPER_QUAD_MESH_BYTES = 864
TOL = 1e-6


def _write(path, omega: np.ndarray, h: np.ndarray, groups: list[Group]) -> int:
    with planefmt.Writer(path, Header(coding=Coding.FLOAT32), index=False) as w:
        o = w.add_object("fig7")
        w.add_planes(to_triplets(omega, h))
        for g in groups:
            w.add_group(o, g.kind, g.refs, g.bounding, tree=g.tree)
    return path.stat().st_size


def _assert_is_block(vertices: np.ndarray, faces: np.ndarray, src_v: np.ndarray, src_f: np.ndarray,
                     tol: float) -> float:
    r = hausdorff(vertices, faces, src_v, src_f, target=tol)
    assert r.certified and r.upper <= tol, (r.lower, r.upper)
    area = shapes.area(vertices, faces)
    assert abs(area - shapes.area(src_v, src_f)) <= 1e-6 * area
    return r.upper


def test_fig7_block_as_pseudo_convex_and_pseudo_concave_patches(tmp_path) -> None:
    v, f = shapes.fig7_block()
    poly = polygonize(v, f)
    assert len(poly.h) == 11  # 14 polygons, the 4 top trapezoids on one plane
    table = PlaneTable(poly.omega, poly.h)
    groups, report = encode_open(poly.vertices, poly.faces, poly.face_plane, poly.distance, table,
                                 TOL * poly.diagonal)
    omega, h = table.arrays()
    omega, h = omega.copy(), h.copy()
    concave = [g for g in groups if g.kind == GroupKind.PSEUDO_CONCAVE]
    convex = [g for g in groups if g.kind == GroupKind.PSEUDO_CONVEX]
    assert len(concave) + len(convex) == len(groups)
    # The pocket (four walls and its floor, 10 triangles) is the one pseudo-concave group.
    assert len(concave) == 1 and concave[0].triangles == 10
    assert len(np.unique(concave[0].refs[~concave[0].bounding])) == 5
    # The rest, pseudo-convex: the top's four convex pieces at least.
    assert len(convex) >= 4 and sum(g.triangles for g in convex) == 18

    dv, df = decode_groups(omega, h, groups)
    _assert_is_block(dv, df, v, f, TOL * poly.diagonal)

    used = np.unique(np.concatenate([g.refs for g in groups]))
    patch_bytes = _write(tmp_path / "patches.pln", omega, h, groups)
    scene = planefmt.decode_scene(tmp_path / "patches.pln")
    mesh = scene.nodes[0].mesh
    # float32 planes: a few ulps of the unit coordinates.
    _assert_is_block(mesh.vertices, mesh.faces, v, f, 1e-5 * poly.diagonal)

    codec_path = tmp_path / "codec.pln"
    planefmt.encode_scene(planefmt.Scene((planefmt.Node("fig7", mesh=planefmt.Mesh(v, f)),)), codec_path)
    with planefmt.open(codec_path) as r:
        kinds = sorted({GroupKind(g.kind).name.lower() for g in r if isinstance(g, planefmt.PartGroup)})
    codec_bytes = codec_path.stat().st_size

    print("\nFig. 7 block, 16 vertices, 14 quads, 28 triangles:")
    print(f"  paper, plane coding:   {PAPER_PLANE_BYTES} bytes (22 float32 planes: 1 pseudo-convex + "
          f"1 pseudo-concave part)")
    print(f"  paper, quad mesh:      {PAPER_QUAD_MESH_BYTES} bytes")
    print(f"  planefmt patches:      {len(convex)} pseudo-convex + {len(concave)} pseudo-concave groups, "
          f"{len(used)} planes ({12 * len(used)} bytes as float32), whole file {patch_bytes} bytes")
    print(f"  planefmt codec choice: {', '.join(kinds)}, whole file {codec_bytes} bytes")
    assert codec_bytes <= patch_bytes
