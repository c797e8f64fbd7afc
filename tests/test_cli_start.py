"""Issue 55: a command imports only what it uses. ``pln --version``, ``pln info`` and ``pln validate
--no-geometry`` load neither the converters' trimesh nor usd-core (pxr), nor the codec and its scipy;
``pln --version`` not even numpy or construct. Checked by the modules a fresh interpreter holds after
``main()``, not by time."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from planefmt_converters.cli import main

from corpus import CORPUS

#: Every command of the command line loads none of these unless it converts, decodes or draws.
CONVERTERS = ("trimesh", "pxr")
GEOMETRY = ("planefmt.codec", "scipy")

# Runs main() in a fresh interpreter and writes the names of the modules it then holds to argv[1].
_PROBE = """
import json, sys
from planefmt_converters.cli import main
code = main(sys.argv[2:])
with open(sys.argv[1], "w") as f:
    json.dump({"code": code, "modules": sorted(sys.modules)}, f)
"""


def loaded(tmp_path: Path, *argv: str) -> set[str]:
    """Top-level names and dotted names of the modules ``pln ARGV`` imported (it must succeed)."""
    out = tmp_path / "modules.json"
    # timeout: a hang guard far above normal (1 s on a loaded machine)
    run = subprocess.run([sys.executable, "-c", _PROBE, str(out), *argv], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr
    got = json.loads(out.read_text())
    assert got["code"] == 0, run.stdout + run.stderr
    return set(got["modules"])


@pytest.fixture(scope="module")
def pln_files(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """.pln files of a convex corpus mesh (one convex group) and a non-convex one (a shell walk)."""
    folder = tmp_path_factory.mktemp("start")
    files = []
    for mesh in (CORPUS / "convex" / "cylinder.stl", CORPUS / "nonconvex_watertight" / "fuze.obj"):
        files.append(folder / f"{mesh.stem}.pln")
        assert main(["convert", str(mesh), str(files[-1])]) == 0
    return files


def test_version_imports_no_numpy_no_construct_and_no_converter(tmp_path: Path) -> None:
    assert loaded(tmp_path, "--version") & {*CONVERTERS, *GEOMETRY, "numpy", "construct"} == set()


@pytest.mark.parametrize("command", [["info"], ["info", "--json"], ["info", "--salvage"],
                                     ["validate", "--no-geometry"]], ids=" ".join)
def test_reading_a_file_imports_no_codec_and_no_converter(command: list[str], pln_files: list[Path],
                                                           tmp_path: Path) -> None:
    for path in pln_files:
        modules = loaded(tmp_path, *command, str(path))
        assert "planefmt.container.reader" in modules or "planefmt.container.salvage" in modules
        assert modules & {*CONVERTERS, *GEOMETRY} == set(), path.name


def test_validating_geometry_imports_the_codec_but_no_converter(pln_files: list[Path], tmp_path: Path) -> None:
    # The codec decodes every part group here: the probe sees the modules a command imports when it runs.
    modules = loaded(tmp_path, "validate", str(pln_files[1]))
    assert "planefmt.codec" in modules
    assert modules & set(CONVERTERS) == set()
