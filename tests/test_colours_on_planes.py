"""Face colours that differ within one plane (geo.usda: 24 faces in 11 colours on 4 planes) reach
the decoded file face by face under the default shell scheme; the paper's scheme, whose groups
store one colour per plane, says which faces it recoloured instead of recolouring them silently."""

from __future__ import annotations

import numpy as np
import pytest

from planefmt import PlnWarning, codec
from planefmt.model import Mesh, Node, Scene

from corpus import CORPUS


def _matched(source: Mesh, decoded: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """For each source face, the decoded face of the nearest centroid, and that distance."""
    from scipy.spatial import cKDTree

    distance, match = cKDTree(decoded.vertices[decoded.faces].mean(axis=1)).query(
        source.vertices[source.faces].mean(axis=1))
    return match, distance


def _checkerboard(n: int = 4) -> Mesh:
    """A flat n x n grid of squares, two triangles each, coloured like a checkerboard: one plane."""
    xs = np.arange(n + 1, dtype=np.float64)
    v = np.array([(x, y, 0.0) for y in xs for x in xs])
    faces, colours = [], []
    for y in range(n):
        for x in range(n):
            a, b, c, d = y * (n + 1) + x, y * (n + 1) + x + 1, (y + 1) * (n + 1) + x + 1, (y + 1) * (n + 1) + x
            faces += [(a, b, c), (a, c, d)]
            colours += [(255, 0, 0, 255) if (x + y) % 2 else (0, 0, 255, 255)] * 2
    return Mesh(v, np.array(faces, dtype=np.int64), face_colours=np.array(colours, dtype=np.uint8))


def _cube() -> Scene:
    """A convex cube whose two triangles on each face differ in colour: a convex group would give each
    face one colour, so it is stored as a shell."""
    import trimesh

    box = trimesh.creation.box()
    colours = np.array([(20 * i, 255 - 20 * i, 7 * i, 255) for i in range(12)], dtype=np.uint8)
    return Scene(nodes=(Node("cube", mesh=Mesh(np.asarray(box.vertices), np.asarray(box.faces),
                                                face_colours=colours)),))


def _geo() -> Scene:
    from planefmt_converters import registry

    return registry.read(str(CORPUS / "usd" / "geo.usda"))[0]


@pytest.mark.parametrize("make", [lambda: Scene(nodes=(Node("board", mesh=_checkerboard()),)), _cube, _geo],
                         ids=["checkerboard", "convex cube", "geo.usda"])
def test_shell_keeps_every_face_colour_within_a_plane(make, tmp_path) -> None:
    scene = make()
    source = next(node.mesh for node in scene.nodes if node.mesh is not None)
    assert len(np.unique(source.face_colours, axis=0)) > 1
    with _no_pln_warning():
        codec.encode_scene(scene, tmp_path / "c.pln", tolerance=1e-4)
    decoded = next(node.mesh for node in codec.decode_scene(tmp_path / "c.pln").nodes if node.mesh is not None)
    assert len(decoded.faces) == len(source.faces)
    match, distance = _matched(source, decoded)
    diagonal = float(np.linalg.norm(np.ptp(source.vertices, axis=0)))
    assert len(np.unique(match)) == len(match) and distance.max() <= 1e-4 * diagonal
    assert np.array_equal(decoded.face_colours[match], source.face_colours)


def test_paper_scheme_reports_the_faces_it_recolours(tmp_path) -> None:
    scene = Scene(nodes=(Node("board", mesh=_checkerboard()),))
    with pytest.warns(PlnWarning, match=r"the colours of 16 of 32 faces"):
        codec.encode_scene(scene, tmp_path / "c.pln", tolerance=1e-4, scheme="paper")


class _no_pln_warning:
    def __enter__(self):
        import warnings

        self._catch = warnings.catch_warnings(record=True)
        self._caught = self._catch.__enter__()
        warnings.simplefilter("always", PlnWarning)
        return self

    def __exit__(self, *exc):
        self._catch.__exit__(*exc)
        lines = [str(w.message) for w in self._caught if issubclass(w.category, PlnWarning)]
        assert not lines, lines
        return False
