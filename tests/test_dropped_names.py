"""Issue 50 item 2: every kind of data a reader drops is named, in one vocabulary (:mod:`.dropped`)
across OBJ, PLY, glTF and USD: skins, animations, morph targets, tangents, textures... on real files."""

from __future__ import annotations

from pathlib import Path

import pytest

from planefmt_converters import dropped as kinds
from planefmt_converters import registry
from planefmt_converters.cli import main

from corpus import CORPUS

DATA = Path(__file__).resolve().parent / "data"
#: Every name a reader may use for a kind of data without a detail in parentheses.
VOCABULARY = {value for name, value in vars(kinds).items() if name.isupper()}


@pytest.mark.parametrize("path, expected", [
    (DATA / "simple_skin.gltf", {kinds.SKINS, kinds.ANIMATIONS}),
    (DATA / "singleBlendshapeCube_sparse.glb", {kinds.MORPH_TARGETS, kinds.ANIMATIONS, kinds.TEXTURE_COORDINATES,
                                                kinds.VERTEX_NORMALS}),
    (CORPUS / "gltf_scene" / "TestScene.gltf", {kinds.TANGENTS, kinds.TEXTURE_COORDINATES, kinds.VERTEX_NORMALS}),
    (CORPUS / "gltf_scene" / "CesiumMilkTruck.glb", {kinds.ANIMATIONS, kinds.TEXTURES, kinds.TEXTURE_COORDINATES}),
    (CORPUS / "usd" / "RoughnessTest.usdz", {kinds.TEXTURES, kinds.MATERIALS, kinds.TEXTURE_COORDINATES}),
], ids=lambda value: value.name if isinstance(value, Path) else "")
def test_real_files_name_what_they_lose(path: Path, expected: set[str]) -> None:
    _, dropped = registry.read(path)
    assert expected <= set(dropped), dropped


@pytest.mark.parametrize("path", sorted((CORPUS / "gltf_scene").glob("*.gl*")) + sorted((CORPUS / "usd").glob("*"))
                         + sorted(DATA.glob("*.gl*")), ids=lambda path: path.name)
def test_every_note_is_in_the_vocabulary(path: Path) -> None:
    _, dropped = registry.read(path)
    for note in dropped:
        assert note in VOCABULARY or any(note.startswith(f"{name} ") for name in VOCABULARY) \
            or note[:1].isdigit(), note
    assert "UVs" not in dropped


def test_obj_material_with_an_image_names_textures(tmp_path: Path) -> None:
    (tmp_path / "tet.mtl").write_text("newmtl red\nKd 1 0 0\nmap_Kd red.png\n")  # the image itself is missing
    (tmp_path / "tet.obj").write_text("mtllib tet.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                      "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    _, dropped = registry.read(tmp_path / "tet.obj")
    assert kinds.TEXTURES in dropped, dropped


def test_the_warning_names_skins_and_animations(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["convert", str(DATA / "simple_skin.gltf"), str(tmp_path / "skin.pln")]) == 0
    (line,) = capsys.readouterr().err.splitlines()
    assert "dropped animations; skins" in line, line
