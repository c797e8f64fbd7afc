"""The up axis (issue 35, item 8): kept through .pln as a mETA chunk (spec §10.3), read from and
written to USD's upAxis, and glTF's +Y up reached by turning a Z-up scene."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

import planefmt
from planefmt import codec
from planefmt.model import Coding, Header, Mesh, Node, Scene
from planefmt_converters import registry
from planefmt_converters.assemble import flatten, up_rotation
from planefmt_converters.cli import main

from corpus import CORPUS
from streams import TrickleReader

#: Z-up USD (centimetres, a bolt standing along +z) and a Y-up glTF scene (a ground plane in xz).
BOLT = CORPUS / "usd" / "bolt.usda"
GLTF_SCENE = CORPUS / "gltf_scene" / "TestScene.gltf"


def world_box(path: Path) -> tuple[str | None, np.ndarray]:
    scene, _ = registry.read(path)
    mesh = flatten(scene)
    return scene.up_axis, np.array([mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)])


def turned(box: np.ndarray, source: str, target: str) -> np.ndarray:
    """The world box of a scene turned from ``source`` up to ``target`` up."""
    corners = np.array([[box[i, 0], box[j, 1], box[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    moved = corners @ up_rotation(source, target)[:3, :3].T
    return np.array([moved.min(axis=0), moved.max(axis=0)])


def stage_up_axis(path: Path) -> str:
    from pxr import Usd, UsdGeom

    return str(UsdGeom.GetStageUpAxis(Usd.Stage.Open(str(path))))


@pytest.fixture(scope="module")
def plns(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("up")
    out = {}
    for name, source in (("bolt", BOLT), ("scene", GLTF_SCENE)):
        out[name] = folder / f"{name}.pln"
        assert main(["convert", str(source), str(out[name])]) == 0
    return out


def test_pln_stores_the_source_up_axis(plns: dict[str, Path]) -> None:
    for name, axis in (("bolt", "Z"), ("scene", "Y")):
        with planefmt.open(plns[name]) as r:
            # Versions 5 and 6: in the header, so a stream knows it before any record.
            assert r.header.version == (6, 0) and r.header.up_axis == axis and r.up_axis == axis
            assert not any(isinstance(rec, planefmt.Metadata) for rec in r)


@pytest.mark.parametrize("suffix,axis", [(".usda", "Z"), (".usdc", "Z"), (".glb", "Y"), (".gltf", "Y")])
def test_z_up_usd_keeps_its_up_axis(suffix: str, axis: str, plns: dict[str, Path], tmp_path: Path) -> None:
    up, box = world_box(BOLT)
    assert up == "Z"
    diagonal = np.linalg.norm(box[1] - box[0])
    for source in (BOLT, plns["bolt"]):  # directly and through .pln
        target = tmp_path / f"{source.suffix[1:]}{suffix}"
        assert main(["convert", str(source), str(target)]) == 0
        got_up, got_box = world_box(target)
        assert got_up == axis
        # glTF is +Y up: the bolt stands along +y there, as along +z in the USD stage; and in metres, the
        # bolt's centimetres scaled by 0.01 (issue 50)
        scale = 0.01 if suffix.startswith(".gl") else 1.0
        assert np.allclose(got_box, scale * turned(box, "Z", axis), atol=1e-5 * scale * diagonal), (source, got_box)
        if suffix.startswith(".usd"):
            assert stage_up_axis(target) == "Z"


@pytest.mark.parametrize("suffix", [".usda", ".glb"])
def test_y_up_gltf_keeps_its_up_axis(suffix: str, plns: dict[str, Path], tmp_path: Path) -> None:
    up, box = world_box(GLTF_SCENE)
    assert up == "Y"
    target = tmp_path / f"scene{suffix}"
    assert main(["convert", str(plns["scene"]), str(target)]) == 0
    got_up, got_box = world_box(target)
    assert got_up == "Y"
    assert np.allclose(got_box, box, atol=1e-5 * np.linalg.norm(box[1] - box[0]))
    if suffix == ".usda":
        assert stage_up_axis(target) == "Y"


def test_usd_writer_turns_a_scene_into_the_up_axis_asked_for(tmp_path: Path) -> None:
    scene, _ = registry.read(GLTF_SCENE)
    registry.write(scene, tmp_path / "z.usda", up_axis="Z")
    assert stage_up_axis(tmp_path / "z.usda") == "Z"
    _, box = world_box(GLTF_SCENE)
    up, got = world_box(tmp_path / "z.usda")
    assert up == "Z" and np.allclose(got, turned(box, "Y", "Z"), atol=1e-5 * np.linalg.norm(box[1] - box[0]))


TETRA = Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]), np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))


@pytest.mark.parametrize("axis", ["Y", "Z", None])
def test_scene_up_axis_survives_encoding_from_a_trickling_stream(axis: str | None) -> None:
    for major in (4, 5):
        buf = io.BytesIO()
        codec.encode_scene(Scene((Node("t", mesh=TETRA),), up_axis=axis), buf, major=major)
        data = buf.getvalue()
        # Version 4: a mETA chunk where the scene says; version 5: the header's units byte, never mETA.
        assert (b"mETA" in data) == (axis is not None and major == 4)
        assert planefmt.open(io.BytesIO(data)).header.up_axis == (axis if major == 5 else None)
        assert codec.decode_scene(TrickleReader(data)).up_axis == axis
        assert codec.salvage_scene(io.BytesIO(data))[0].up_axis == axis


def test_writer_refuses_metadata_a_reader_would_reject() -> None:
    with planefmt.Writer(io.BytesIO(), Header(coding=Coding.FLOAT64)) as w:
        for key, value in (("up_axis", "X"), ("up axis", "Z"), ("", "Z"), ("a\x00b", "c")):
            with pytest.raises(planefmt.PlnError) as e:
                w.add_metadata(key, value)
            assert e.value.code == "BAD_METADATA"
        w.add_metadata("up_axis", "Y")
        with pytest.raises(planefmt.PlnError, match="already"):
            w.add_metadata("up_axis", "Y")
        w.add_object("o")
        with pytest.raises(planefmt.PlnError, match="before the first object"):
            w.add_metadata("title", "late")
