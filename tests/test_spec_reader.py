"""conformance/independent/plnspec.py, a container-level reader written from spec/pln.md alone,
passes every conformance case at container level: in process, case by case (so that a failure
names its case), and through the runner's command-line contract (``python -m conformance``)."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # conformance/ is a folder of the repository, not an installed package

from conformance import runner  # noqa: E402
from conformance.runner import Case, Outcome  # noqa: E402

SUITE = ROOT / "conformance"
READER = SUITE / "independent" / "plnspec.py"
CASES = runner.load_manifest()

_spec = importlib.util.spec_from_file_location("plnspec", READER)
plnspec = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(plnspec)


def in_process(path: Path) -> Outcome:
    """What ``python plnspec.py path`` answers, without starting a process."""
    try:
        result = plnspec.Reader(path.read_bytes()).read()
    except plnspec.PlnError as exc:
        return Outcome(1, {"error": exc.code}, str(exc))
    return Outcome(0, json.loads(json.dumps(result, allow_nan=False)), "")


@pytest.mark.parametrize("case", CASES, ids=[c.path for c in CASES])
def test_spec_reader_conforms_at_container_level(case: Case):
    expected = json.loads((SUITE / case.path).with_suffix(".json").read_text(encoding="utf-8"))
    assert runner.check(case, expected, in_process(SUITE / case.path), "container") is None


def test_spec_reader_passes_the_suite_through_the_runner():
    impl = f"{sys.executable} {READER}"
    p = subprocess.run([sys.executable, "-m", "conformance", "--impl", impl, "--level", "container",
                        "--jobs", "2"], capture_output=True, text=True, cwd=ROOT, timeout=900)
    assert p.returncode == 0, p.stdout[-2000:]
    assert p.stdout.splitlines()[-1] == f"{len(CASES)} passed, 0 failed"


def test_spec_reader_reports_no_geometry():
    # A container-level reader: the runner compares no geometry, and geometry defects pass as accepted.
    got = in_process(SUITE / "valid" / "cube_v3.pln")
    assert got.exit_code == 0 and got.result["geometry"] is None
