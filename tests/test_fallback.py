"""The package without its C extensions (pyproject.toml builds them as optional): it imports, and
encodes and decodes a file byte for byte as with them."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from corpus import CORPUS

ROOT = Path(__file__).resolve().parent.parent
EXTENSIONS = ("planefmt.container._chains", "planefmt.geometry._collapse")
#: A CAD part at a lossy tolerance: a shell walk (the walk's C loop), 3,395 of its 4,455 corners dropped
#: (_collapse.c's passes).
SOURCE = CORPUS / "cad" / "box.STL"

# Run in a fresh interpreter, whose import system refuses the extension modules as a machine without a
# compiler lacks them; prints the .pln bytes' length and digest and the decoded mesh's sizes.
_ENCODE = """
import hashlib, importlib.abc, io, sys
blocked = set(sys.argv[2].split(",")) if sys.argv[2] else set()
class Hide(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name in blocked:
            raise ImportError(f"{name} hidden")
sys.meta_path.insert(0, Hide())
import planefmt
from planefmt_converters import registry
scene, _ = registry.read(sys.argv[1])
out = io.BytesIO()
planefmt.encode_scene(scene, out, tolerance=1e-4)
mesh = planefmt.decode_mesh(io.BytesIO(out.getvalue()))
loaded = sorted(m for m in sys.modules if m in {"planefmt.container._chains", "planefmt.geometry._collapse"})
print(len(out.getvalue()), hashlib.sha256(out.getvalue()).hexdigest(), len(mesh.vertices), len(mesh.faces), loaded)
"""


def _run(hidden: tuple[str, ...]) -> list[str]:
    # timeout: a hang guard far above normal (each run took 0.9-1.3 s of CPU, 5-8 s of wall time on
    # a loaded machine)
    p = subprocess.run([sys.executable, "-c", _ENCODE, str(SOURCE), ",".join(hidden)], capture_output=True,
                       text=True, cwd=ROOT, timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    return p.stdout.strip().split(maxsplit=4)


def test_without_the_c_extensions_the_package_writes_the_same_file():
    with_c = _run(())
    if with_c[4] != repr(sorted(EXTENSIONS)):
        pytest.skip(f"the C extensions were not built: {with_c[4]}")
    without = _run(EXTENSIONS)
    assert without[4] == "[]"
    assert without[:4] == with_c[:4]
