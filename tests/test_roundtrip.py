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
import trimesh

from planefmt.bodies import is_closed_manifold
from planefmt.model import Mesh, Node, Scene
from planefmt_converters import registry
from planefmt_converters.assemble import at_float32, flatten, with_area
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


def _check_output(out: Path, closed: bool, faces: int, capsys: pytest.CaptureFixture[str]) -> None:
    back, dropped = _read(out)
    mesh = flatten(back)
    # the reader drops (and reports) triangles whose corners it welded into one
    assert not any("degenerate" in note for note in dropped), (out.suffix, dropped)
    assert len(mesh.faces) == faces, out.suffix
    assert with_area(mesh.vertices, mesh.faces).all(), f"{out.suffix}: zero-area triangles"
    assert _closed(back) == closed, out.suffix
    again = out.with_suffix(out.suffix + ".pln")
    capsys.readouterr()
    assert main(["convert", str(out), str(again)]) == 0, out.suffix
    # re-encoding dropped no triangle (the encoder warns of those without area) and kept the surface closed
    assert "zero-area" not in capsys.readouterr().err, out.suffix
    assert _closed(_read(again)[0]) == closed, out.suffix


@pytest.mark.parametrize("source", SOURCES, ids=[p.name for p in SOURCES])
def test_every_output_of_a_corpus_mesh_survives_its_round_trip(source: Path, tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    x = tmp_path / "x.pln"
    assert main(["convert", str(source), str(x)]) == 0
    assert main(["convert", str(x), str(tmp_path / "again.pln")]) == 0
    decoded, _ = _read(x)
    closed = _closed(_read(source)[0])
    assert _closed(decoded) == closed
    for ext in OUTPUTS:
        out = tmp_path / f"x.{ext}"
        assert main(["convert", str(x), str(out)]) == 0, ext
        _check_output(out, closed, len(flatten(decoded).faces), capsys)


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


#: Text formats write 17 decimals: float64 survives, nothing is welded or flipped there.
FLOAT32 = {"ply", "stl", "glb", "gltf", "usda", "usdc", "usdz"}


@pytest.mark.parametrize("ext", OUTPUTS)
@pytest.mark.parametrize(("mesh", "welded"), [(_cube_with_sliver(), 0), (_fan_with_short_edge(), 2)],
                         ids=["closed-sliver", "open-weld"])
def test_a_float32_output_holds_what_its_readers_see(mesh: Mesh, welded: int, ext: str, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """``welded``: the triangles a float32 output loses because two of their corners become one (the
    sliver of the cube is flipped away: the count stays)."""
    assert with_area(mesh.vertices, mesh.faces).all()
    closed = is_closed_manifold(mesh.faces, len(mesh.vertices))
    out = tmp_path / f"x.{ext}"
    notes = registry.write(Scene(nodes=(Node(name="part", mesh=mesh),)), out)
    _check_output(out, closed, len(mesh.faces) - (welded if ext in FLOAT32 else 0), capsys)
    assert any("without area at float32 precision" in note for note in notes) == (ext in FLOAT32), notes


def test_many_flat_triangles_leave_a_closed_mesh_closed() -> None:
    """Folds on random edges of a subdivided cube, some on neighbouring triangles (whose flat
    triangles then share a neighbour and are only dropped): none is left, and the cube stays closed."""
    cube = trimesh.creation.box(extents=(1, 1, 1))
    cube.apply_translation((1.5, 1.5, 1.5))
    cube = cube.subdivide().subdivide()
    v, faces = np.array(cube.vertices), [tuple(t) for t in cube.faces]
    across = {(t[k], t[(k + 1) % 3]): i for i, t in enumerate(faces) for k in range(3)}
    rng = np.random.default_rng(1)
    taken: set[int] = set()
    for i in rng.permutation(len(faces))[:60]:
        x, y, q = np.roll(faces[i], -rng.integers(3))
        if i in taken or across[y, x] in taken:
            continue
        taken.add(i)
        # 1e-9 outwards from a point of the edge x-y: rounded to float32, it is back on the edge
        m = v[x] + 0.37 * (v[y] - v[x])
        v = np.vstack([v, m + 1e-9 * (m - 1.5) / np.linalg.norm(m - 1.5)])
        faces[i] = (x, y, len(v) - 1)
        faces += [(x, len(v) - 1, q), (len(v) - 1, y, q)]
    mesh = Mesh(vertices=v, faces=np.array(faces))
    assert is_closed_manifold(mesh.faces, len(v)) and with_area(v, mesh.faces).all()
    flat = int((~with_area(v.astype(np.float32).astype(np.float64), mesh.faces)).sum())
    assert flat == len(taken) > 20
    scene, notes = at_float32(Scene(nodes=(Node(name="cube", mesh=mesh),)))
    out = scene.nodes[0].mesh
    assert f"{flat} triangles without area at float32 precision" in notes
    assert with_area(out.vertices, out.faces).all()
    assert is_closed_manifold(out.faces, len(out.vertices))
