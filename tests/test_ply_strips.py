"""Issue 50 item 10: PLY files of triangle strips (the Cyberware scans' ``tristrips`` element) are read as
the triangles the strips describe, with the strips' alternating winding undone and their joints dropped."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from planefmt.errors import ConversionError
from planefmt_converters import registry
from planefmt_converters.cli import main
from planefmt_converters.ply import strip_triangles

from plystrips import grid_strips, ply_bytes


def test_strip_triangles_alternate_restart_and_drop_joints() -> None:
    strip = np.array([0, 1, 2, 3, 4, -1, 5, 5, 6, 7, 8])
    assert strip_triangles([strip], 9).tolist() == [[0, 1, 2], [2, 1, 3], [2, 3, 4], [6, 5, 7], [6, 7, 8]]
    # rows are strips of their own: no triangle spans two rows
    assert strip_triangles([np.array([0, 1, 2]), np.array([3, 4, 5, 6])], 7).tolist() == [
        [0, 1, 2], [3, 4, 5], [5, 4, 6]]


def test_cyberware_style_strips_read_as_the_grid_triangles(tmp_path: Path) -> None:
    rows, cols = 7, 9
    vertices, strip = grid_strips(rows, cols)
    src = tmp_path / "scan.ply"
    src.write_bytes(ply_bytes(vertices, strip))
    scene, dropped = registry.read(src)
    (node,) = scene.nodes
    mesh = node.mesh
    assert dropped == [] and node.name == ""
    # every grid cell as its two triangles, split on the (r+1, j)-(r, j+1) diagonal; grid row 1's strip
    # starts on row r+1, which splits its cells on the other diagonal
    r, j = np.meshgrid(np.arange(rows - 1), np.arange(cols - 1), indexing="ij")
    a, b, c, d = r * cols + j, (r + 1) * cols + j, r * cols + j + 1, (r + 1) * cols + j + 1
    other = (r == 1)[..., None]
    first = np.where(other, np.stack([a, b, d], -1), np.stack([a, b, c], -1))
    second = np.where(other, np.stack([a, c, d], -1), np.stack([c, b, d], -1))
    expected = np.concatenate([first.reshape(-1, 3), second.reshape(-1, 3)])
    corners = {tuple(sorted(map(tuple, np.round(tri, 6)))) for tri in mesh.vertices[mesh.faces]}
    wanted = {tuple(sorted(map(tuple, np.round(tri, 6)))) for tri in vertices.astype(np.float32).astype(np.float64)[expected]}
    assert len(mesh.faces) == 2 * (rows - 1) * (cols - 1) and corners == wanted
    p = mesh.vertices[mesh.faces]
    normals = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert (normals[:, 2] < 0).all()  # one winding, the first strip's, also after the joint


def test_ascii_strips_of_several_rows_convert(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    src = tmp_path / "strips.ply"
    src.write_text("ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                   "element tristrips 2\nproperty list int int vertex_indices\nend_header\n"
                   "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n4 0 2 1 3\n4 0 1 4 5\n")
    assert main(["convert", str(src), str(tmp_path / "out.obj")]) == 0
    assert "warning" not in capsys.readouterr().err
    scene, _ = registry.read(tmp_path / "out.obj")
    assert len(scene.nodes[0].mesh.faces) == 4


def test_strip_index_outside_the_vertices_is_refused(tmp_path: Path) -> None:
    vertices, strip = grid_strips(3, 3)
    strip[4] = len(vertices)
    src = tmp_path / "bad.ply"
    src.write_bytes(ply_bytes(vertices, strip))
    with pytest.raises(ConversionError, match="vertex index 9 is outside the 9 vertices"):
        registry.read(src)


def test_a_real_scan_as_strips_reads_as_its_triangles() -> None:
    # tests/data/bun_head_strips.ply: the head of the corpus's Stanford bunny written as strips
    # (tests/data/SOURCES.md); read back, the bunny's own triangles of that cut, one winding.
    bunny, _ = registry.read(Path(__file__).parent / "corpus" / "smooth_dense" / "bun_zipper.ply")
    v, f = bunny.nodes[0].mesh.vertices, bunny.nodes[0].mesh.faces
    cut = f[((v[f][:, :, 1] > 0.15) & (v[f][:, :, 0] < -0.05)).all(axis=1)]
    scene, dropped = registry.read(Path(__file__).parent / "data" / "bun_head_strips.ply")
    mesh = scene.nodes[0].mesh
    assert dropped == [] and len(mesh.faces) == len(cut) == 5568

    def corners(vertices: np.ndarray, faces: np.ndarray) -> set:
        # each triangle as its corners' positions, rotated to start at the least: rotation keeps the winding
        tri = [tuple(map(tuple, vertices[t])) for t in faces]
        return {t[i:] + t[:i] for t in tri for i in [t.index(min(t))]}

    assert corners(mesh.vertices, mesh.faces) == corners(v, cut)
