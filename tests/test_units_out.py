"""Issue 50 item 3: glTF is in metres, so a scene in other units is written scaled to metres; ``--units``
says what unit a source without one is in; USD keeps the unit as metersPerUnit."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from planefmt.model import Units
from planefmt_converters import registry
from planefmt_converters.cli import main

from corpus import CORPUS

CUBE = CORPUS / "cad" / "20mm-xyz-cube.stl"  # 20 units across


def _world_extent(path: Path) -> np.ndarray:
    from planefmt_converters.assemble import flatten

    scene, _ = registry.read(path)
    return np.ptp(flatten(scene).vertices, axis=0)


@pytest.mark.parametrize("units, metres", [("cm", 0.01), ("in", 0.0254), ("mm", 0.001), ("m", 1.0)])
def test_glb_from_a_source_in_other_units_is_in_metres(units: str, metres: float, tmp_path: Path) -> None:
    source_extent = _world_extent(CUBE)
    pln, glb = tmp_path / "cube.pln", tmp_path / "cube.glb"
    assert main(["convert", str(CUBE), str(pln), "--units", units]) == 0
    assert main(["convert", str(pln), str(glb)]) == 0
    scene, _ = registry.read(glb)
    assert scene.units == Units.METRE
    assert np.allclose(_world_extent(glb), source_extent * metres, rtol=1e-6)
    direct = tmp_path / "direct.glb"
    assert main(["convert", str(CUBE), str(direct), "--units", units]) == 0
    assert np.allclose(_world_extent(direct), source_extent * metres, rtol=1e-6)


def test_the_scaling_is_said(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["convert", str(CUBE), str(tmp_path / "c.glb"), "--units", "in", "-v"]) == 0
    assert "units (inch; glTF is in metres: coordinates scaled by 0.0254)" in capsys.readouterr().err


def test_usd_keeps_the_unit(tmp_path: Path) -> None:
    pytest.importorskip("pxr")
    out = tmp_path / "c.usda"
    assert main(["convert", str(CUBE), str(out), "--units", "cm"]) == 0
    assert "metersPerUnit = 0.01" in out.read_text()
    assert registry.read(out)[0].units == Units.CENTIMETRE
    assert np.allclose(_world_extent(out), _world_extent(CUBE))


def test_units_that_contradict_the_file_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    glb = tmp_path / "c.glb"
    assert main(["convert", str(CUBE), str(glb)]) == 0
    assert main(["convert", str(glb), str(tmp_path / "c.pln"), "--units", "mm"]) == 2
    assert "says its unit is the metre" in capsys.readouterr().err
    assert not (tmp_path / "c.pln").exists()
