"""The package layout of issue 32 (tools/layers.py): no import cycles, modules of at most 800 lines,
sub-packages whose imports go one way, converters off planefmt's private names."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TOOL = ROOT / "tools" / "layers.py"


def _run(root: Path) -> subprocess.CompletedProcess:
    # timeout: a hang guard far above normal (3 s on a loaded machine)
    return subprocess.run([sys.executable, str(TOOL), str(root)], capture_output=True, text=True, timeout=120)


def test_the_repository_keeps_its_layers() -> None:
    done = _run(ROOT)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "FAIL" not in done.stdout


def _write(root: Path, files: dict[str, str]) -> None:
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def test_a_cycle_an_import_upwards_and_a_private_name_are_each_reported(tmp_path: Path) -> None:
    """A lazy import inside a function counts: that is how the validator and the codec cycled."""
    _write(tmp_path, {
        "planefmt/__init__.py": "",
        "planefmt/container/__init__.py": "",
        "planefmt/container/validate.py": "def validate():\n    from .. import codec\n",
        "planefmt/codec/__init__.py": "from ..container.validate import validate\n_private = 1\n",
        "converters/cli.py": "from planefmt import codec\nx = codec._private\n",
    })
    done = _run(tmp_path)
    assert done.returncode == 1
    lines = done.stdout.splitlines()
    assert "FAIL import cycles among 4 planefmt modules: 1" in lines
    assert "    planefmt.codec <-> planefmt.container.validate" in lines
    assert "    planefmt.container.validate -> planefmt.codec" in lines
    assert "FAIL sub-packages: 2 (codec, container; at least 3)" in lines
    assert "FAIL spec/pln.md: missing" in lines
    assert "    cli.py:2 codec._private" in lines


def test_a_module_over_800_lines_is_reported(tmp_path: Path) -> None:
    _write(tmp_path, {
        "planefmt/__init__.py": "",
        "planefmt/geometry/__init__.py": "",
        "planefmt/geometry/big.py": "x = 1\n" * 801,
        "spec/pln.md": "",
        "converters/__init__.py": "",
    })
    done = _run(tmp_path)
    assert "FAIL largest module: planefmt.geometry.big, 801 lines (at most 800)" in done.stdout.splitlines()
