"""``pln convert`` in everyday use (issue 35): it never overwrites an input, a sibling output or a file
the user did not name."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from planefmt_converters import registry
from planefmt_converters.cli import main

CORPUS = Path(__file__).resolve().parents[2] / "shared" / "corpus"
CUBE = CORPUS / "convex" / "cube_subd.obj"
TET = CORPUS / "convex" / "tet.ply"


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _forbid_reading(monkeypatch: pytest.MonkeyPatch) -> None:
    """A refusal comes before any work: from here on, reading an input fails the test."""
    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("the conversion started")

    monkeypatch.setattr(registry, "read", refuse)


@pytest.fixture
def cube_pln(tmp_path: Path) -> Path:
    out = tmp_path / "m.pln"
    assert main(["convert", str(CUBE), str(out)]) == 0
    return out


@pytest.mark.parametrize("link", ["same", "symlink", "hardlink", "dotted"])
@pytest.mark.parametrize("name", ["m.pln", "t.obj"])
def test_output_that_is_the_input_is_refused(name: str, link: str, tmp_path: Path, cube_pln: Path,
                                             monkeypatch: pytest.MonkeyPatch,
                                             capsys: pytest.CaptureFixture) -> None:
    src = cube_pln if name == "m.pln" else Path(shutil.copy(CUBE, tmp_path / name))
    dst = {"same": src, "dotted": tmp_path / "." / src.name, "symlink": tmp_path / f"link{src.suffix}",
           "hardlink": tmp_path / f"hard{src.suffix}"}[link]
    if link == "symlink":
        dst.symlink_to(src.name)
    elif link == "hardlink":
        os.link(src, dst)
    before = _snapshot(tmp_path)
    _forbid_reading(monkeypatch)
    assert main(["convert", str(src), str(dst)]) == 2
    err = capsys.readouterr().err
    assert str(src) in err and str(dst) in err and "same file" in err, err
    assert len(err.splitlines()) == 1
    assert _snapshot(tmp_path) == before


def test_batch_inputs_with_one_output_name_are_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    first, second = (str(shutil.copy(src, tmp_path / dst)) for src, dst in ((CUBE, "a/model.obj"), (TET, "b/model.ply")))
    _forbid_reading(monkeypatch)
    out = tmp_path / "out"
    assert main(["convert", first, second, "-d", str(out), "--to", "obj"]) == 2
    err = capsys.readouterr().err
    assert first in err and second in err and str(out / "model.obj") in err, err
    assert len(err.splitlines()) == 1
    assert not out.exists()


def test_batch_output_that_is_an_input_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                  capsys: pytest.CaptureFixture) -> None:
    src, other = str(shutil.copy(CUBE, tmp_path / "model.obj")), str(shutil.copy(TET, tmp_path / "tet.ply"))
    before = _snapshot(tmp_path)
    _forbid_reading(monkeypatch)
    assert main(["convert", other, src, "-d", str(tmp_path), "--to", "obj"]) == 2
    err = capsys.readouterr().err
    assert src in err and "same file" in err, err
    assert _snapshot(tmp_path) == before
