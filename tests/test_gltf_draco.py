"""Issue 50 item 9: a glTF whose primitives are Draco-compressed (``KHR_draco_mesh_compression``) is read,
and the libraries' log lines stay off the user's terminal (``-v`` shows them)."""

from __future__ import annotations

import logging
import sys
from pathlib import Path

import numpy as np
import pytest

from planefmt_converters import registry
from planefmt_converters.cli import main

from corpus import CORPUS

DATA = Path(__file__).resolve().parent / "data"


def test_draco_glb_reads_as_its_source() -> None:
    draco, _ = registry.read(DATA / "simple_pole_draco.glb")
    plain, _ = registry.read(CORPUS / "gltf_scene" / "simple_pole.glb")
    meshes = [node.mesh for node in draco.nodes if node.mesh is not None]
    originals = [node.mesh for node in plain.nodes if node.mesh is not None]
    assert sorted(len(m.faces) for m in meshes) == sorted(len(m.faces) for m in originals)
    low = np.min([m.vertices.min(axis=0) for m in originals], axis=0)
    high = np.max([m.vertices.max(axis=0) for m in originals], axis=0)
    # 14-bit quantization over each primitive's own box: within 1e-3 of the scene's diagonal
    for got in meshes:
        assert np.isfinite(got.vertices).all() and (got.vertices >= low - 1e-3 * np.linalg.norm(high - low)).all()


def test_draco_glb_converts_without_library_lines(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["convert", str(DATA / "simple_pole_draco.glb"), str(tmp_path / "pole.pln")]) == 0
    err = capsys.readouterr().err
    assert all(line.startswith("pln: ") for line in err.splitlines()), err


def test_without_dracopy_one_line_names_it(tmp_path: Path, capsys: pytest.CaptureFixture,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "DracoPy", None)  # import DracoPy now fails
    assert main(["convert", str(DATA / "simple_pole_draco.glb"), str(tmp_path / "pole.pln")]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert "KHR_draco_mesh_compression" in line and "DracoPy" in line


@pytest.mark.parametrize("verbose", [False, True])
def test_library_log_lines_only_with_verbose(verbose: bool, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    src = CORPUS / "gltf_scene" / "pins.glb"
    assert main(["convert", str(src), str(tmp_path / "pins.obj")] + ["-v"] * verbose) == 0
    logging.getLogger("trimesh.util").warning("a library's warning")
    err = capsys.readouterr().err
    assert ("pln: library: trimesh.util: a library's warning" in err) is verbose
    assert "a library's warning" in err or not verbose
    assert all(line.startswith("pln: ") for line in err.splitlines()), err
