"""Issue 50 items 1 and 11: a cut OBJ, PLY or STL is a ``TRUNCATED`` error naming what is missing, never a
smaller mesh converted without a word nor a message about a missing text-encoding module."""

from __future__ import annotations

from pathlib import Path

import pytest

from planefmt_converters.cli import main

from corpus import CORPUS


def _convert(src: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> tuple[int, str]:
    out = tmp_path / "out.pln"
    code = main(["convert", str(src), str(out)])
    assert not out.exists() or code == 0
    return code, capsys.readouterr().err


def _cut(tmp_path: Path, name: str, data: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def test_ascii_stl_cut_inside_its_second_solid(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    first = (CORPUS / "cad" / "1002_tray_bottom.STL").read_bytes()
    second = (CORPUS / "cad" / "ADIS16480.STL").read_bytes()
    both = first + b"\r\n" + second
    end = len(first)
    for _ in range(7):
        end = both.index(b"endfacet", end) + len(b"endfacet")
    src = _cut(tmp_path, "two.stl", both[:end + 40])  # 7 complete facets of the second solid, and a cut one
    code, err = _convert(src, tmp_path, capsys)
    assert code == 2
    assert "solid 2, 'ci - ADIS16480-1'" in err and "7 complete facets" in err
    assert "--salvage" not in err


@pytest.mark.parametrize("name", ["cad/box.STL", "cad/angle_block.STL", "nonconvex_watertight/round.stl"])
def test_binary_stl_shorter_than_its_facet_count(name: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    data = (CORPUS / name).read_bytes()
    declared = (len(data) - 84) // 50
    src = _cut(tmp_path, "cut.stl", data[:-1020])  # 20 facets and 20 bytes of one more gone
    code, err = _convert(src, tmp_path, capsys)
    assert code == 2
    assert f"declares {declared:,} facets" in err and f"only {declared - 21:,} facets are complete" in err
    assert "charset_normalizer" not in err


def test_binary_stl_cut_inside_its_header(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    src = _cut(tmp_path, "cut.stl", (CORPUS / "cad" / "box.STL").read_bytes()[:50])
    code, err = _convert(src, tmp_path, capsys)
    assert code == 2 and "inside the 84-byte header" in err


@pytest.mark.parametrize("name, cut, says", [
    ("smooth_dense/npm_bunny.ply", -3000, "face 3,489 of 3,674"),
    ("smooth_dense/npm_bunny.ply", -20, "face 3,672 of 3,674"),  # the last line cut inside its list
    ("open/suzanne.ply", 77900, "vertex 1,052 of 1,966, face 0 of 500"),
    ("convex/tet.ply", -1, "face 3 of 4"),  # binary
    ("convex/tet.ply", -30, "face 1 of 4"),
])
def test_ply_shorter_than_its_element_counts(name: str, cut: int, says: str, tmp_path: Path,
                                             capsys: pytest.CaptureFixture) -> None:
    src = _cut(tmp_path, "cut.ply", (CORPUS / name).read_bytes()[:cut])
    code, err = _convert(src, tmp_path, capsys)
    assert code == 2
    assert "PLY ends before the rows its header declares" in err and says in err


def test_ply_cut_inside_its_header(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    src = _cut(tmp_path, "cut.ply", (CORPUS / "convex" / "tet.ply").read_bytes()[:151])
    code, err = _convert(src, tmp_path, capsys)
    assert code == 2 and "inside the PLY header" in err


@pytest.mark.parametrize("name, cut, line", [
    ("nonconvex_watertight/fuze.obj", -2000, "'f 204/381'"),
    ("open/capsule.obj", -5, "'f 5150/5150/5150 5252/5252/5252 5251/5251/'"),
    ("convex/cube_subd.obj", 45205, "'f 483 484'"),
])
def test_obj_cut_inside_its_last_statement(name: str, cut: int, line: str, tmp_path: Path,
                                           capsys: pytest.CaptureFixture) -> None:
    src = _cut(tmp_path, "cut.obj", (CORPUS / name).read_bytes()[:cut])
    code, err = _convert(src, tmp_path, capsys)
    assert code == 2 and line in err and "truncated" in err


@pytest.mark.parametrize("name, cut", [
    ("nonconvex_watertight/fuze.obj", -5),  # inside the closing comment
    ("smooth_dense/npm_bunny.ply", -1),  # the final line break: every row is there
])
def test_complete_data_still_converts(name: str, cut: int, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    src = _cut(tmp_path, f"cut{Path(name).suffix}", (CORPUS / name).read_bytes()[:cut])
    code, _ = _convert(src, tmp_path, capsys)
    assert code == 0


@pytest.mark.parametrize("name, cut", [("cad/box.STL", -1020), ("convex/tet.ply", -1), ("open/suzanne.ply", -3000),
                                       ("convex/cube_subd.obj", 45205)])
def test_the_library_raises_truncated(name: str, cut: int, tmp_path: Path) -> None:
    from planefmt.errors import ConversionError
    from planefmt_converters import registry

    src = _cut(tmp_path, f"cut{Path(name).suffix}", (CORPUS / name).read_bytes()[:cut])
    with pytest.raises(ConversionError) as caught:
        registry.read(src)
    assert caught.value.code == "TRUNCATED"
