"""bench/corpus_roundtrip.py's checks of issue 50's sweep fail where they should: an output farther from its
source than the bound its conversion printed, bodies that share an edge once welded by position, a file
that grows as the tolerance loosens; and pass on a real corpus file at two tolerances."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from planefmt.model import Mesh

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import corpus_roundtrip as sweep  # noqa: E402

TET = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64),
       np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))


def test_an_output_beyond_its_printed_bound_fails_and_one_within_passes():
    v, f = TET
    moved = Mesh(vertices=v + [0.0, 0.0, 1e-3], faces=f)
    source = Mesh(vertices=v, faces=f)
    diag = float(np.linalg.norm(np.ptp(v, axis=0)))
    # The triangle inequality's sum over the bound sends the check to the certified measure itself.
    assert "over its printed bound" in sweep._within_bound(1e-4, 1e-3, 0.0, diag, moved, source)
    assert sweep._within_bound(1e-3, 1e-3, 0.0, diag, moved, source) is None
    assert sweep._within_bound(None, 0.0, 0.0, diag, source, source) == "no error bound printed"


def test_bodies_sharing_an_edge_are_closed_as_indexed_but_not_once_welded():
    v, f = TET
    other = v.copy()
    other[2:] = [[0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]  # corners 0 and 1, the edge, in the same places
    both = Mesh(vertices=np.vstack([v, other]), faces=np.vstack([f, f + 4]))
    assert sweep._closed(both) and not sweep._closed_welded(both)
    assert sweep._closed_welded(Mesh(vertices=v, faces=f))


def test_a_file_larger_at_a_looser_tolerance_fails(monkeypatch: pytest.MonkeyPatch):
    sizes = {1e-6: 500, 1e-5: 400, 1e-4: 450}
    monkeypatch.setattr(sweep, "tolerances_of", lambda path, spec, cache: sorted(sizes))
    monkeypatch.setattr(sweep, "_source", lambda path: {})
    monkeypatch.setattr(sweep, "check", lambda path, timeout, work, t, *rest: ("| row |", [], sizes[t]))
    rows, problems = sweep.check_file("x.obj", 60.0, ["1e-6", "1e-5", "1e-4"], False, "shell", "unused.json")
    assert len(rows) == 3 and problems == ["450 B at 0.0001, larger than 400 B at 1e-05"]


def test_a_real_file_passes_at_two_tolerances(tmp_path: Path):
    rows, problems = sweep.check_file(str(ROOT / "tests" / "corpus" / "convex" / "tet.ply"), 300.0,
                                      ["1e-6", "1e-4"], False, "shell", str(tmp_path / "draco.json"), False)
    assert problems == [] and len(rows) == 2
    # every output format's cell, then the .pln file's own (re.pln)
    assert all([c.strip() for c in row.split("|")][6:6 + len(sweep.FORMATS) + 1] == ["ok"] * (len(sweep.FORMATS) + 1)
               for row in rows), rows
