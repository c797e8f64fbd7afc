"""An object with a convex body beside its shell may still code the shell without planes (issue 52).

The encoder's planeless variant (every corner explicit, every triangle free: no plane table for the
shell) was offered only to objects without convex groups, so a closed bolt in an open part made the part's
shell name its corners by planes whatever they cost: kuka_kr10r1100sixx_link_2.stl (bench corpus) at
Draco-14's error, 33,421 bytes against 17,286 without them. Convex groups keep their planes; the
shell keeps one reference, for its colour.
"""

from __future__ import annotations

import io
import warnings

import numpy as np

import planefmt
from planefmt import codec
from planefmt.geometry.hausdorff import relative_hausdorff
from planefmt.model import GroupKind, Mesh, Node, Scene


def _tube_and_box(n: int = 48, rings: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """An open tube of ``n`` flat facets (two coplanar triangles each, so planes could name its
    corners) and, apart from it, a closed box: a convex group and a shell in one object."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    z = np.linspace(0.0, 2.0, rings)
    v = np.column_stack([np.tile(np.cos(t), rings), np.tile(np.sin(t), rings), np.repeat(z, n)])
    r, i = np.meshgrid(np.arange(rings - 1), np.arange(n), indexing="ij")
    a, b = (r * n + i).ravel(), (r * n + (i + 1) % n).ravel()
    f = np.concatenate([np.column_stack([a, b, b + n]), np.column_stack([a, b + n, a + n])])
    box = np.array([[x, y, w] for x in (3.0, 3.5) for y in (0.0, 0.5) for w in (0.0, 0.5)])
    box_faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]) + len(v)
    return np.vstack([v, box]), np.vstack([f, box_faces])


def test_a_shell_beside_a_convex_body_is_coded_without_planes_where_that_is_smaller():
    v, f = _tube_and_box()
    buf = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        codec.encode_scene(Scene(nodes=[Node(name="part", mesh=Mesh(vertices=v, faces=f))]), buf, tolerance=4e-5)
    with planefmt.open(io.BytesIO(buf.getvalue())) as reader:
        groups = list(reader.part_groups())
    # The tube's shell names no corner by planes (before: 48 plane references); the box is a convex group
    # of its six planes, or a part of that planeless shell where that makes the smaller file.
    shells = [len(g.refs) for g in groups if g.kind != GroupKind.CONVEX]
    assert shells and max(shells) <= 1
    assert all(len(g.refs) == 6 for g in groups if g.kind == GroupKind.CONVEX)
    decoded = codec.decode_mesh(io.BytesIO(buf.getvalue()))
    assert relative_hausdorff((v, f), (decoded.vertices, decoded.faces), tolerance=1e-7).upper <= 4e-5
