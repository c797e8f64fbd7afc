"""Whole datasets (issue 33): a generated dataset of 200 tiny meshes in five formats, small corpus files
and broken files, converted on a Dask LocalCluster of 2 workers; and the same run killed part-way (a
worker process killed, then the client SIGKILLed) and resumed."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import planefmt
from planefmt.errors import CODES

import meshsets
from corpus import CORPUS

pytest.importorskip("distributed")
import psutil  # noqa: E402 - a dependency of distributed

PLN = [sys.executable, "-m", "planefmt_converters.cli"]


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[meshsets.Expected]]:
    folder = tmp_path_factory.mktemp("dataset")
    return folder, meshsets.build(folder, count=200, broken=12, corpus=CORPUS)


def _ledger(path: Path) -> list[dict]:
    """Complete lines only: the last may be torn by a SIGKILL."""
    text = path.read_text() if path.exists() else ""
    return [json.loads(line) for line in text.splitlines(keepends=True) if line.endswith("\n")]


def _output(root: Path, out: Path, path: Path) -> Path:
    return out / path.relative_to(root).with_suffix(".pln")


def _check_outputs(root: Path, out: Path, expected: list[meshsets.Expected]) -> None:
    """Every good file's output decodes to its triangles within its bounding box."""
    for e in expected:
        if not e.good:
            continue
        mesh = planefmt.decode_mesh(_output(root, out, e.path))
        assert len(mesh.faces) == e.triangles, e.path
        diagonal = np.linalg.norm(e.bbox[1] - e.bbox[0])
        box = np.array([mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)])
        assert np.abs(box - e.bbox).max() <= 1e-5 * diagonal, e.path


def _strays(out: Path) -> list[str]:
    return [str(p) for p in out.rglob("*") if ".pln-batch-" in p.name or ".tmp" in p.name]


def test_dataset_on_a_dask_local_cluster(dataset: tuple[Path, list[meshsets.Expected]], tmp_path: Path) -> None:
    root, expected = dataset
    assert len(expected) >= 200 and {e.path.suffix for e in expected} >= {".obj", ".ply", ".stl", ".off", ".glb"}
    out = tmp_path / "out"
    run = subprocess.run([*PLN, "convert", str(root), "-d", str(out), "--engine", "dask", "--jobs", "2"],
                         capture_output=True, text=True, timeout=1800)  # a hang guard (33 s at load 7)
    assert run.returncode == 1, run.stderr  # some inputs failed
    assert "Traceback" not in run.stderr and "\r" not in run.stderr, run.stderr
    entries = {e["source"]: e for e in _ledger(out / "pln-report.jsonl")}
    assert sorted(entries) == sorted(str(e.path) for e in expected)
    for e in expected:
        entry = entries[str(e.path)]
        if e.good:
            assert entry["status"] == "ok", entry
            assert entry["triangles"] == e.triangles and entry["bytes_out"] > 0 and entry["bytes_in"] > 0
            assert entry["size"] == e.path.stat().st_size and entry["mtime_ns"] == e.path.stat().st_mtime_ns
            assert entry["seconds"] > 0 and entry["peak_mb"] > 0 and entry["error_bound"] <= 1e-6
        else:
            assert entry["status"] == "failed" and entry["code"] in CODES, entry
            assert entry["message"].startswith(str(e.path)), entry
            assert f"pln: {entry['message']}" in run.stderr.splitlines()
            assert not _output(root, out, e.path).exists()
    _check_outputs(root, out, expected)
    assert _strays(out) == []
    summary = subprocess.run([*PLN, "report", str(out / "pln-report.jsonl")], capture_output=True, text=True)
    assert summary.returncode == 1 and summary.stdout.startswith(f"{len(expected)} inputs: "
                                                                 f"{sum(e.good for e in expected)} converted")


def _wait_for_lines(ledger: Path, count: int, proc: subprocess.Popen, limit: float = 1800) -> None:
    # limit: a hang guard far above normal (the whole killed and resumed run took 44 s at load 7)
    end = time.monotonic() + limit
    while len(_ledger(ledger)) < count:
        assert proc.poll() is None, "the run ended before it was to be killed"
        assert time.monotonic() < end, "the run made no progress"
        time.sleep(0.05)


def test_killed_run_resumes_where_it_stopped(dataset: tuple[Path, list[meshsets.Expected]], tmp_path: Path) -> None:
    """Killed part-way, first one Dask worker process then the client (SIGKILL), and resumed: the
    ledger's lines up to the kill point (the ones complete when the client died) and the resumed
    run's lines after it split the inputs exactly: every input has one line after the kill point, which
    is ``skipped`` for an input with an ``ok`` line before it (its output untouched since) and a
    conversion (``ok``, or ``failed`` for a broken file) for every other; no input has two ``ok``
    lines; every output decodes whole; nothing temporary is left."""
    root, expected = dataset
    out = tmp_path / "out"
    ledger = out / "pln-report.jsonl"
    args = [*PLN, "convert", str(root), "-d", str(out), "--engine", "dask", "--jobs", "2"]
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    try:
        _wait_for_lines(ledger, 40, proc)
        dask_workers = [p for p in psutil.Process(proc.pid).children() if "spawn_main" in " ".join(p.cmdline())]
        assert len(dask_workers) == 2
        dask_workers[0].kill()
        _wait_for_lines(ledger, 100, proc)
        processes = psutil.Process(proc.pid).children(recursive=True)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stderr.close()
    # What a SIGKILLed client leaves: its workers and their conversion processes end with it.
    _, alive = psutil.wait_procs(processes, timeout=30)  # a hang guard: SIGKILLed processes end at once
    assert alive == [], alive
    before = _ledger(ledger)
    assert 100 <= len(before) < len(expected)
    ok_before = {e["source"] for e in before if e["status"] == "ok"}
    untouched = {e["source"]: Path(e["output"]).stat().st_mtime_ns for e in before if e["status"] == "ok"}

    resumed = subprocess.run([*args, "--resume"], capture_output=True, text=True, timeout=1800)  # a hang guard
    assert resumed.returncode == 1, resumed.stderr
    entries = _ledger(ledger)
    assert entries[:len(before)] == before
    after = entries[len(before):]
    assert sorted(e["source"] for e in after) == sorted(str(e.path) for e in expected)  # each input once
    good = {str(e.path) for e in expected if e.good}
    for entry in after:
        source = entry["source"]
        if source in ok_before:
            assert entry["status"] == "skipped", entry
            assert Path(entry["output"]).stat().st_mtime_ns == untouched[source]
        else:
            assert entry["status"] == ("ok" if source in good else "failed"), entry
    oks: dict[str, int] = {}
    for entry in entries:
        if entry["status"] == "ok":
            oks[entry["source"]] = oks.get(entry["source"], 0) + 1
    assert oks == {source: 1 for source in good}
    _check_outputs(root, out, expected)
    assert _strays(out) == []
