"""The two readers give the same answer on every class of fuzz/hostile.py (issue 49): planefmt's
decode_mesh and node js/cli.mjs, each in a capped child process (fuzz/capped.py, hang guards far
above what the files need), end alike: the same error code, or results with the same vertex and
triangle counts and the same area (to 1e-9 relative; readers' planes differ by ~1e-16, spec §9.4).

Counts are compared where the spec makes them normative: not for cells and trees (kinds 1, 2), whose
vertex and triangle counts are the decoder's choice (§9.4, "Watertight output"), only their area."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "fuzz"))

import capped  # noqa: E402
import hostile  # noqa: E402

#: Classes whose readers still disagree, each owned by another part of issue 49; remove an entry once
#: its fix is merged.
SKIP: dict[str, str] = {}

#: Classes whose groups are cells or trees: area only (§9.4).
AREA_ONLY = {"x_cells_overlapping"}

#: The sizes the classes run at: modest ones, smaller than test_hostile's where a class costs seconds.
SIZES = {name: (modest if modest < 20_000 else modest // 10) for name, (_, modest, _) in hostile.CLASSES.items()}


def _counts(detail: str) -> tuple[int, int]:
    vertices, triangles = (int(part.split()[0]) for part in detail.split(", "))
    return vertices, triangles


@pytest.mark.parametrize("name", list(hostile.CLASSES))
def test_readers_agree(name: str, tmp_path: Path):
    if name in SKIP:
        pytest.skip(SKIP[name])
    if capped.node() is None:
        pytest.skip("node is not installed")
    make, _, _ = hostile.CLASSES[name]
    path = tmp_path / f"{name}.pln"
    path.write_bytes(make(SIZES[name]))
    py, js = (capped.run(reader, path, cpu_s=60, mem_mb=2048) for reader in ("py", "js"))
    assert py.kind in ("result", "error") and py.kind == js.kind, (py, js)
    if py.kind == "error":
        assert py.detail == js.detail
        return
    if name not in AREA_ONLY:
        assert _counts(py.detail) == _counts(js.detail)
    assert py.area == pytest.approx(js.area, rel=1e-9, abs=1e-300)


def test_skip_names_are_classes():
    assert set(SKIP) | AREA_ONLY <= set(hostile.CLASSES)
