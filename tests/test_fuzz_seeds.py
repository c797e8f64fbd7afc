"""The fuzzers' seeds (fuzz/seeds.py: generated files and the conformance suite) hold a group of every
kind 0-13, so that mutations reach every kind's decoder; and the harness (fuzz/exercise.py) decodes
geometry, not only the container."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import planefmt

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "fuzz"))

import exercise  # noqa: E402
import seeds  # noqa: E402


def _kinds(data: bytes) -> set[int]:
    try:
        with planefmt.open(io.BytesIO(data)) as r:
            return {11 if g.source is not None else int(g.kind) for g in r.part_groups()}
    except planefmt.PlnError:
        return set()


def test_seeds_hold_every_kind():
    files = list(seeds.generated().values()) + [p.read_bytes() for p in (ROOT / "conformance" / "valid").glob("*.pln")]
    assert set().union(*map(_kinds, files)) >= set(range(14))


def test_exercise_decodes_geometry(monkeypatch):
    seen = []
    real = exercise.decode_mesh
    monkeypatch.setattr(exercise, "decode_mesh", lambda source: seen.append(real(source)))
    exercise.exercise((ROOT / "conformance" / "valid" / "shell_walk_later_named_v5_2.pln").read_bytes())
    assert len(seen) == 1 and len(seen[0].faces) == 48
