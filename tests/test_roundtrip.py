"""Outputs that survive their own round trip (issue 35, items 4-6).

Every format ``pln convert`` writes from a ``.pln`` file, read back, must
re-encode to ``.pln`` at the default tolerance (item 5), hold no zero-area
triangle its source did not have (item 4), and be closed where its source is
(item 6), its vertices welded as a reader welds them after float32 rounding.
On small real corpus meshes through the default scheme, and on synthetic
meshes whose float64 geometry does not survive float32 rounding as it is.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from planefmt.bodies import is_closed_manifold
from planefmt.model import Mesh, Node, Scene
from planefmt_converters import pln, registry
from planefmt_converters.assemble import flatten, with_area
from planefmt_converters.cli import main

from corpus import CORPUS

#: Every format ``pln convert`` writes besides .pln.
OUTPUTS = ("obj", "ply", "stl", "off", "glb", "gltf", "usda", "usdc", "usdz")
#: One open mesh, one closed, one scene of several closed objects.
SOURCES = [CORPUS / "open" / "suzanne.ply", CORPUS / "nonconvex_watertight" / "fuze.obj",
           CORPUS / "gltf_scene" / "simple_pole.glb"]


def _read(path: Path) -> tuple[Scene, list[str]]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return registry.read(path)


def _closed(scene: Scene) -> bool:
    """Every object closed (flattening keeps objects apart)."""
    mesh = flatten(scene)
    return is_closed_manifold(mesh.faces, len(mesh.vertices))


def _check_output(scene: Scene, out: Path, closed: bool, faces: int) -> None:
    back, dropped = _read(out)
    mesh = flatten(back)
    # the reader drops (and reports) triangles whose corners it welded into one
    assert not any("degenerate" in note for note in dropped), (out.suffix, dropped)
    assert len(mesh.faces) == faces, out.suffix
    assert with_area(mesh.vertices, mesh.faces).all(), f"{out.suffix}: zero-area triangles"
    assert _closed(back) == closed, out.suffix
    assert main(["convert", str(out), str(out.with_suffix(out.suffix + ".pln"))]) == 0, out.suffix


@pytest.mark.parametrize("source", SOURCES, ids=[p.name for p in SOURCES])
def test_every_output_of_a_corpus_mesh_survives_its_round_trip(source: Path, tmp_path: Path) -> None:
    x = tmp_path / "x.pln"
    assert main(["convert", str(source), str(x)]) == 0
    assert main(["convert", str(x), str(tmp_path / "again.pln")]) == 0
    decoded, _ = _read(x)
    closed = _closed(_read(source)[0])
    assert _closed(decoded) == closed
    for ext in OUTPUTS:
        out = tmp_path / f"x.{ext}"
        assert main(["convert", str(x), str(out)]) == 0, ext
        _check_output(decoded, out, closed, len(flatten(decoded).faces))


def _cube_with_sliver() -> Mesh:
    """A closed cube [1, 2]^3 whose front face is split at M, a point 1e-9 outside its bottom edge AB,
    with the sliver (A, B, M) closing the fold: every triangle has an area in float64, while M rounds
    to float32 onto AB (y = z = 1) and the sliver to a segment."""
    v = np.array([[x, y, z] for x in (1.0, 2.0) for y in (1.0, 2.0) for z in (1.0, 2.0)])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = [t for q in quads for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]
    assert (0, 4, 5) in faces  # the front face (y = 1) holds the directed edge A -> B
    m = len(v)
    v = np.vstack([v, [1.3, 1.0 - 1e-9, 1.0 - 1e-9]])
    faces.remove((0, 4, 5))
    faces += [(0, 4, m), (0, m, 5), (m, 4, 5)]
    return Mesh(vertices=v, faces=np.array(faces))


def _fan_with_short_edge() -> Mesh:
    """An open fan around a centre and a second vertex 1e-10 from it, which float32 rounding welds:
    the two triangles over that edge lose their area."""
    ring = np.column_stack([np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4), np.zeros(8)]) + 3.0
    centre = np.array([[3.0, 3.0, 3.0], [3.0 + 1e-10, 3.0 + 1e-10, 3.0]])
    v = np.vstack([ring, centre])
    # ring 0..3 around vertex 8, ring 4..7 around vertex 9, and the two triangles across edge 8-9
    faces = [(8, i, i + 1) for i in range(3)] + [(9, i, (i + 1) % 8) for i in range(4, 8)] + [(8, 3, 9), (8, 9, 0)]
    faces += [(9, 3, 4)]
    return Mesh(vertices=v, faces=np.array(faces))


@pytest.mark.parametrize("ext", OUTPUTS)
@pytest.mark.parametrize("mesh", [_cube_with_sliver(), _fan_with_short_edge()], ids=["closed-sliver", "open-weld"])
def test_a_float32_output_holds_what_its_readers_see(mesh: Mesh, ext: str, tmp_path: Path) -> None:
    assert with_area(mesh.vertices, mesh.faces).all()
    closed = is_closed_manifold(mesh.faces, len(mesh.vertices))
    scene = Scene(nodes=(Node(name="part", mesh=mesh),))
    out = tmp_path / f"x.{ext}"
    notes = registry.write(scene, out)
    back, _ = _read(out)
    rounded = mesh.vertices.astype(np.float32) != mesh.vertices
    # text formats keep float64: nothing to weld or flip there
    faces = len(mesh.faces) - (2 if rounded.any() and ext not in ("obj", "off") and not closed else 0)
    _check_output(scene, out, closed, faces)
    if ext not in ("obj", "off"):
        assert any("without area at float32 precision" in note for note in notes), notes


def test_re_encoding_drops_nothing_from_an_output(tmp_path: Path) -> None:
    """The .pln writer's notes name dropped zero-area triangles: an output has none to drop."""
    scene, _ = _read(SOURCES[0])
    x = tmp_path / "x.pln"
    pln.write(scene, x)
    decoded, _ = _read(x)
    for ext in ("ply", "glb"):
        registry.write(decoded, tmp_path / f"x.{ext}")
        back, _ = _read(tmp_path / f"x.{ext}")
        assert pln.write(back, tmp_path / "re.pln") == []
