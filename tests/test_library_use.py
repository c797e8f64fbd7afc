"""The library as a program uses it (issue 35): defaults as the CLI's, paths accepted, counts known from the
header, enum kinds, short reprs."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

import planefmt
from planefmt import GroupKind, Mesh, Node, Scene, Units
from planefmt_converters import registry
from planefmt_converters.cli import main

from corpus import CORPUS

CUBE = CORPUS / "convex" / "cube_subd.obj"


@pytest.fixture(scope="module")
def cube_scene() -> Scene:
    return registry.read(CUBE)[0]


def test_encode_scene_defaults_are_the_command_lines(cube_scene: Scene, tmp_path: Path) -> None:
    library = tmp_path / "library.pln"
    header = planefmt.encode_scene(cube_scene, library)
    assert main(["convert", str(CUBE), str(tmp_path / "cli.pln")]) == 0
    assert header.version == (6, 0)
    assert library.read_bytes() == (tmp_path / "cli.pln").read_bytes()


def test_decode_mesh_reads_a_path_or_a_stream(cube_scene: Scene, tmp_path: Path) -> None:
    path = tmp_path / "cube.pln"
    planefmt.encode_scene(cube_scene, path)
    for source in (path, str(path), io.BytesIO(path.read_bytes())):
        mesh = planefmt.decode_mesh(source)
        assert len(mesh.faces) == 12 and np.allclose(np.ptp(mesh.vertices, axis=0), 1.0)


def test_decode_mesh_places_every_object_in_world_space(tmp_path: Path) -> None:
    cube = registry.read(CUBE)[0].nodes[0].mesh
    shift = np.eye(4)
    shift[:3, 3] = [10, 0, 0]
    mirror = np.diag([-1.0, 1, 1, 1])
    scene = Scene(nodes=(Node("a", mesh=cube), Node("b", None, shift, None), Node("c", 1, mirror, cube)))
    planefmt.encode_scene(scene, tmp_path / "two.pln")
    mesh = planefmt.decode_mesh(tmp_path / "two.pln")
    assert len(mesh.faces) == 24
    low = cube.vertices.min(axis=0)
    assert np.allclose(mesh.vertices.min(axis=0), low) and np.isclose(mesh.vertices[:, 0].max(), 10 - low[0])
    corners = mesh.vertices[mesh.faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.einsum("ij,ij->", normals, corners.mean(axis=1)) > 0  # both cubes still wound outward


def test_decode_mesh_of_something_else_is_a_pln_error() -> None:
    with pytest.raises(planefmt.PlnError):
        planefmt.decode_mesh(CUBE)
    with pytest.raises(planefmt.PlnError):
        planefmt.decode_mesh(42)


def test_reader_counts_come_from_the_header_before_iterating(cube_scene: Scene, tmp_path: Path) -> None:
    path = tmp_path / "cube.pln"
    planefmt.encode_scene(cube_scene, path, major=5)
    with planefmt.open(path) as f:
        assert (f.plane_count, f.group_count, f.object_count) == (6, 1, 1)
        groups = list(f.part_groups())
        assert (f.plane_count, f.group_count, f.object_count) == (6, 1, 1)
    # Version 6 leaves the counts of a file of one small segment out (spec §5): they are what was read.
    planefmt.encode_scene(cube_scene, path)
    with planefmt.open(path) as f:
        assert f.header.plane_count is None and (f.plane_count, f.group_count, f.object_count) == (0, 0, 0)
        list(f)
        assert (f.plane_count, f.group_count, f.object_count) == (6, 1, 1)
    assert groups[0].kind is GroupKind.CONVEX
    assert repr(groups[0]) == "PartGroup(0, object=0, kind=CONVEX, 6 refs)"


def test_reprs_are_short(cube_scene: Scene) -> None:
    big = Mesh(np.zeros((100_000, 3)), np.zeros((50_000, 3), dtype=np.int64))
    scene = Scene(nodes=(Node("big", mesh=big), Node("child", 0, np.eye(4), None)), units=Units.METRE)
    for thing in (big, scene.nodes[0], scene):
        assert len(repr(thing)) < 200 and "\n" not in repr(thing), repr(thing)
    assert "100000" in repr(big) and "50000" in repr(big)
    assert "2 nodes" in repr(scene)
