"""Outputs do not grow without a word (issue 35, item 14): triangles stay one to one with the source's,
and a mesh that several nodes share (instancing), which a .pln file stores once per node, is named in
a warning with the factor the output grows by."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from planefmt.model import Mesh, Node, Scene
from planefmt_converters import registry
from planefmt_converters.cli import main

import corpus

GLTF_SCENES = corpus.files("gltf_scene")


def _mesh(m: trimesh.Trimesh) -> Mesh:
    return Mesh(np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64))


def _moved(x: float) -> np.ndarray:
    t = np.eye(4)
    t[0, 3] = x
    return t


def shared_scene() -> Scene:
    """Three nodes placing one 12-triangle box, and a tetrahedron of its own: 40 triangles placed, 16 stored."""
    box = _mesh(trimesh.creation.box())
    tetra = Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]),
                 np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    return Scene((*(Node(f"box{k}", transform=_moved(3.0 * k), mesh=box) for k in range(3)),
                  Node("tetra", transform=_moved(-3.0), mesh=tetra)))


def _instancing_lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if "instancing" in line]


@pytest.mark.parametrize("suffix", [".pln", ".obj"])
def test_flattened_instancing_is_named_with_its_factor(suffix: str, tmp_path: Path,
                                                       capsys: pytest.CaptureFixture) -> None:
    registry.write(shared_scene(), tmp_path / "shared.glb")
    assert main(["convert", str(tmp_path / "shared.glb"), str(tmp_path / f"out{suffix}")]) == 0
    lines = _instancing_lines(capsys.readouterr().err)
    assert len(lines) == 1, lines
    assert "instancing flattened (3 nodes share 1 mesh; output 2.5× the source's triangles)" in lines[0]


@pytest.mark.parametrize("suffix", [".glb", ".usda", ".usdz"])
def test_scene_formats_keep_instancing_without_a_word(suffix: str, tmp_path: Path,
                                                      capsys: pytest.CaptureFixture) -> None:
    registry.write(shared_scene(), tmp_path / "shared.glb")
    assert main(["convert", str(tmp_path / "shared.glb"), str(tmp_path / f"again{suffix}")]) == 0
    assert _instancing_lines(capsys.readouterr().err) == []
    again, _ = registry.read(tmp_path / f"again{suffix}")
    assert len({id(n.mesh) for n in again.nodes if n.mesh is not None}) == 2
    assert [n.name for n in again.nodes] == [n.name for n in shared_scene().nodes]


@pytest.mark.parametrize("path", GLTF_SCENES, ids=corpus.ids(GLTF_SCENES))
def test_corpus_scenes_keep_their_triangles(path: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    source, _ = registry.read(path)
    meshes = {id(n.mesh): len(n.mesh.faces) for n in source.nodes if n.mesh is not None}
    placed = sum(len(n.mesh.faces) for n in source.nodes if n.mesh is not None)
    assert main(["convert", str(path), str(tmp_path / "out.pln")]) == 0
    lines = _instancing_lines(capsys.readouterr().err)
    decoded, _ = registry.read(tmp_path / "out.pln")
    # Shells keep the source's triangles one to one (zero-area ones left out, with a warning of their own).
    assert sum(len(n.mesh.faces) for n in decoded.nodes if n.mesh is not None) <= placed
    if placed > sum(meshes.values()):
        assert len(lines) == 1 and f"output {placed / sum(meshes.values()):.3g}×" in lines[0], lines
    else:
        assert lines == []


USD_INSTANCES = """#usda 1.0
(
    defaultPrim = "World"
    upAxis = "Z"
)
class Xform "Proto"
{
    def Mesh "tri"
    {
        point3f[] points = [(0,0,0),(1,0,0),(0,1,0),(0,0,1)]
        int[] faceVertexCounts = [3, 3, 3, 3]
        int[] faceVertexIndices = [0,2,1, 0,1,3, 0,3,2, 1,2,3]
        uniform token subdivisionScheme = "none"
    }
}
def Xform "World"
{
    def Xform "A" (
        instanceable = true
        references = </Proto>
    )
    {
        double3 xformOp:translate = (2, 0, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def Xform "B" (
        instanceable = true
        references = </Proto>
    )
    {
        double3 xformOp:translate = (-2, 0, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
}
"""


def test_usd_instances_share_a_mesh(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "inst.usda").write_text(USD_INSTANCES)
    scene, _ = registry.read(tmp_path / "inst.usda")
    placed = [n.mesh for n in scene.nodes if n.mesh is not None]
    assert len(placed) == 2 and placed[0] is placed[1]
    assert main(["convert", str(tmp_path / "inst.usda"), str(tmp_path / "inst.glb")]) == 0
    assert _instancing_lines(capsys.readouterr().err) == []  # glTF instances it
    again, _ = registry.read(tmp_path / "inst.glb")
    assert len({id(n.mesh) for n in again.nodes if n.mesh is not None}) == 1
    assert main(["convert", str(tmp_path / "inst.usda"), str(tmp_path / "inst.pln")]) == 0
    assert "instancing flattened (2 nodes share 1 mesh; output 2× the source's triangles)" in \
        capsys.readouterr().err


def _distinct_meshes(scene: Scene) -> int:
    return len({id(n.mesh) for n in scene.nodes if n.mesh is not None})


def test_pln_decoding_shares_the_instances_again(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    registry.write(shared_scene(), tmp_path / "shared.glb")
    assert main(["convert", str(tmp_path / "shared.glb"), str(tmp_path / "shared.pln")]) == 0
    capsys.readouterr()
    # The .pln holds the box once per node; its three objects decode to the same triangles.
    decoded, _ = registry.read(tmp_path / "shared.pln")
    assert _distinct_meshes(decoded) == 2
    assert main(["convert", str(tmp_path / "shared.pln"), str(tmp_path / "back.glb")]) == 0
    assert _instancing_lines(capsys.readouterr().err) == []
    assert _distinct_meshes(registry.read(tmp_path / "back.glb")[0]) == 2


def test_instanced_coloured_corpus_scene_does_not_grow_through_pln(tmp_path: Path) -> None:
    # pins.glb: six nodes place one dowel, every mesh one base colour (the 35 KB -> 330 KB .glb).
    source = corpus.CORPUS / "gltf_scene" / "pins.glb"
    assert main(["convert", str(source), str(tmp_path / "pins.pln")]) == 0
    assert main(["convert", str(tmp_path / "pins.pln"), str(tmp_path / "pins.glb")]) == 0
    assert _distinct_meshes(registry.read(tmp_path / "pins.glb")[0]) == _distinct_meshes(registry.read(source)[0])
    assert (tmp_path / "pins.glb").stat().st_size <= 1.05 * source.stat().st_size
