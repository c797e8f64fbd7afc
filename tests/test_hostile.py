"""Every class of fuzz/hostile.py, at a modest size, through both readers (planefmt's decode_mesh
and node js/cli.mjs) in a child process under a CPU-time and a memory cap far above what the file
needs (hang guards, not speed checks): each must end in a result or one of the reader's own errors
(spec §12.2), never a crash, an exception outside PlnError, or a cap.

Case names are ``test_hostile[<class>-<reader>]``, the class named for issue 49's item (``i1_``
copies ... ``i10_``) or ``x_`` for one found beyond it; bench/hostile.py prints the same classes'
figures at 10x the issue's sizes."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "fuzz"))

import capped  # noqa: E402
import hostile  # noqa: E402

CPU_S, MEMORY_MB = 20, 1024


def _reader_codes() -> set[str]:
    """The codes of spec §12.2's catalogue: those a reader may raise (§12.3's eight are not)."""
    text = (ROOT / "spec" / "pln.md").read_text()
    table = text[text.index("### 12.2 Errors"):text.index("### 12.3")]
    return set(re.findall(r"^\| `([A-Z_]+)` \|", table, re.M))


READER_CODES = _reader_codes()


def test_reader_codes_parsed():
    assert {"BAD_PAYLOAD", "LIMIT_EXCEEDED", "UNBOUNDED_POLYTOPE"} <= READER_CODES
    assert "DEGENERATE_GEOMETRY" not in READER_CODES


@pytest.mark.parametrize("reader", ["py", "js"])
@pytest.mark.parametrize("name", list(hostile.CLASSES))
def test_hostile(name: str, reader: str, tmp_path: Path):
    if reader == "js" and capped.node() is None:
        pytest.skip("node is not installed")
    make, size, _ = hostile.CLASSES[name]
    path = tmp_path / f"{name}.pln"
    path.write_bytes(make(size))
    outcome = capped.run(reader, path, cpu_s=CPU_S, mem_mb=MEMORY_MB)
    assert outcome.kind in ("result", "error"), outcome
    if outcome.kind == "error":
        assert outcome.detail in READER_CODES, outcome
