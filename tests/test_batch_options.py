"""Batch runs (issue 33) beyond the Dask dataset of test_batch.py: limits per input, lost and overdue
worker processes, folders and lists of inputs, resuming, fsspec URLs, an existing Dask cluster, the
ledger's torn lines, ``pln report`` and the progress line."""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from planefmt_converters.cli import engines, ledger, main
from planefmt_converters.cli.progress import RunBar

from corpus import CORPUS

PLN = [sys.executable, "-m", "planefmt_converters.cli"]
TET = CORPUS / "convex" / "tet.ply"
CUBE = CORPUS / "convex" / "cube_subd.obj"
BOX = CORPUS / "cad" / "box.STL"  # with the paper's scheme, tens of seconds to encode
BUNNY = CORPUS / "smooth_dense" / "bun_zipper.ply"  # 69k triangles: tens of MB
OPTS = {"tolerance": 1e-6, "compress": True, "compact": True, "watertight": True, "scheme": "shell"}


def _entries(path: Path) -> dict[str, dict]:
    return {e["source"]: e for e in ledger.read(path)}


def _job(src: Path, out: Path, **limits) -> dict:
    opts = {**OPTS, "scheme": "paper"} if src == BOX else OPTS  # BOX: long enough to be stopped midway
    return {"source": str(src), "output": str(out / (src.stem + ".pln")), "to": "pln", "from_": None, "opts": opts,
            "salvage": False, "timeout": None, "max_memory_mb": None, "token": f"test-{src.stem}", **limits}


def test_over_time_or_memory_fails_the_input_and_the_run_goes_on(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    # --timeout 1 is what the test checks, not a verdict on speed: BOX's paper scheme takes tens of
    # seconds of CPU (28 s measured), so it is stopped on any machine, the more surely the busier.
    assert main(["convert", str(BOX), str(TET), "-d", str(out), "--timeout", "1", "--jobs", "2",
                 "--scheme", "paper"]) == 1
    assert main(["convert", str(BUNNY), str(TET), "-d", str(tmp_path / "mem"), "--max-memory", "20"]) == 1
    timed, capped = _entries(out / "pln-report.jsonl"), _entries(tmp_path / "mem" / "pln-report.jsonl")
    assert timed[str(BOX)]["code"] == "TIMEOUT" and "1 s" in timed[str(BOX)]["message"]
    assert capped[str(BUNNY)]["code"] == "MEMORY_LIMIT" and "20 MB" in capped[str(BUNNY)]["message"]
    assert timed[str(TET)]["status"] == capped[str(TET)]["status"] == "ok"
    assert sorted(p.name for p in out.iterdir()) == ["pln-report.jsonl", "tet.pln"]
    assert sorted(p.name for p in (tmp_path / "mem").iterdir()) == ["pln-report.jsonl", "tet.pln"]
    err = capsys.readouterr().err.splitlines()
    assert err == [f"pln: {timed[str(BOX)]['message']}", f"pln: {capped[str(BUNNY)]['message']}"]


def test_a_conversion_past_its_grace_is_killed_and_its_process_replaced(tmp_path: Path,
                                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    # The parent's deadline before the worker's own alarm: the path of a conversion stuck in C code.
    monkeypatch.setattr(engines, "GRACE", -0.9)
    jobs = [_job(BOX, tmp_path, timeout=1.0), _job(TET, tmp_path)]  # BOX: tens of seconds, as above
    entries = {e["source"]: e for e in engines.local(jobs, 1)}
    assert entries[str(BOX)]["code"] == "TIMEOUT" and "killed" in entries[str(BOX)]["message"]
    assert entries[str(TET)]["status"] == "ok"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tet.pln"]  # its scratch folder removed


def test_a_lost_worker_process_fails_its_input_only(tmp_path: Path) -> None:
    worker = engines.Worker()
    try:
        assert worker.run(_job(TET, tmp_path))["status"] == "ok"
        result: list[dict] = []
        thread = threading.Thread(target=lambda: result.append(worker.run(_job(BOX, tmp_path))))
        thread.start()
        time.sleep(0.5)  # BOX's conversion under way: it takes tens of seconds
        worker.proc.kill()
        thread.join(600)  # a hang guard far above normal (the kill ends the run at once)
        assert result[0]["code"] == "WORKER_LOST" and "SIGKILL" in result[0]["message"], result
        assert worker.run(_job(CUBE, tmp_path))["status"] == "ok"
    finally:
        worker.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cube_subd.pln", "tet.pln"]


def test_folders_and_lists_keep_their_layout(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    data = tmp_path / "data"
    (data / "a" / "b").mkdir(parents=True)
    (data / ".hidden").mkdir()
    shutil.copy(TET, data / "a" / "tet.ply")
    shutil.copy(CUBE, data / "a" / "b" / "cube.obj")
    shutil.copy(CUBE, data / "a" / "b" / "cubeish.mesh")  # no mesh extension: recognised by its content
    shutil.copy(CUBE, data / ".hidden" / "cube.obj")
    (data / "notes.txt").write_text("not a mesh\n")
    extra = shutil.copy(TET, tmp_path / "listed.ply")
    (tmp_path / "list.txt").write_text(f"# inputs\n{extra}\n\n")
    out = tmp_path / "out"
    assert main(["convert", str(data), "-d", str(out), "--from-list", str(tmp_path / "list.txt")]) == 0
    found = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert found == ["a/b/cube.pln", "a/b/cubeish.pln", "a/tet.pln", "listed.pln", "pln-report.jsonl"]
    monkeypatch.setattr("sys.stdin", io.StringIO(f"{TET}\n"))
    assert main(["convert", "-d", str(tmp_path / "stdin"), "--from-list", "-"]) == 0
    assert (tmp_path / "stdin" / "tet.pln").exists()
    # Folders and lists need the output folder.
    assert main(["convert", str(data)]) == 2


def test_resume_skips_what_was_done_and_cleans_what_a_killed_run_left(tmp_path: Path) -> None:
    data = tmp_path / "data"
    data.mkdir()
    for src in (TET, CUBE, CORPUS / "convex" / "cylinder.stl"):
        shutil.copy(src, data)
    out = tmp_path / "out"
    report = out / "pln-report.jsonl"
    assert main(["convert", str(data), "-d", str(out)]) == 0
    first = report.read_text()
    # What a SIGKILL leaves: a torn ledger line and a scratch folder with a partial output.
    with open(report, "a") as f:
        f.write('{"source": "/x", "stat')
    stale = out / ".pln-batch-dead0000-1"
    stale.mkdir()
    (stale / "cylinder.pln").write_bytes(b"partial")
    cube = data / "cube_subd.obj"
    os.utime(cube, ns=(cube.stat().st_atime_ns, cube.stat().st_mtime_ns + 10**9))  # changed since
    (out / "tet.pln").unlink()  # output gone
    assert main(["convert", str(data), "-d", str(out), "--resume"]) == 0
    text = report.read_text()
    assert text.startswith(first) and text.endswith("\n")
    resumed = [json.loads(line) for line in text[len(first):].splitlines()]
    status = {Path(e["source"]).name: e["status"] for e in resumed}
    assert status == {"cube_subd.obj": "ok", "tet.ply": "ok", "cylinder.stl": "skipped"}
    assert not stale.exists()
    # Other options: nothing is skipped.
    assert main(["convert", str(data), "-d", str(out), "--resume", "--tolerance", "1e-5"]) == 0
    assert {e["status"] for e in list(ledger.read(report))[-3:]} == {"ok"}
    summary = subprocess.run([*PLN, "report", str(report)], capture_output=True, text=True)
    assert summary.returncode == 0 and summary.stdout.startswith("3 inputs: 3 converted, 0 skipped"), summary.stdout


def test_fsspec_urls_on_an_existing_dask_cluster(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    data = tmp_path / "data"
    (data / "sub").mkdir(parents=True)
    shutil.copy(TET, data / "sub")
    shutil.copy(CUBE, data)
    with distributed.LocalCluster(n_workers=1, processes=True, threads_per_worker=1,
                                  dashboard_address=None, scheduler_kwargs={"dashboard_address": ":0"}) as cluster:
        run = subprocess.run([*PLN, "convert", f"file://{data}", "-d", f"file://{tmp_path / 'out'}",
                              "--report", str(tmp_path / "run.jsonl"), "--engine", "dask",
                              "--scheduler", cluster.scheduler_address], capture_output=True, text=True,
                             timeout=1800)  # a hang guard far above normal (18 s at load 7)
    assert run.returncode == 0, run.stderr
    assert sorted(str(p.relative_to(tmp_path / "out")) for p in (tmp_path / "out").rglob("*")) == \
        ["cube_subd.pln", "sub", "sub/tet.pln"]
    entries = list(ledger.read(tmp_path / "run.jsonl"))
    assert {e["source"] for e in entries} == {f"file://{data}/cube_subd.obj", f"file://{data}/sub/tet.ply"}
    assert all(e["status"] == "ok" and e["triangles"] > 0 for e in entries)


def test_dask_engine_without_dask_says_what_to_install(tmp_path: Path) -> None:
    code = ("import sys; sys.modules['distributed'] = None; from planefmt_converters.cli import main; "
            f"sys.exit(main(['convert', {str(TET)!r}, '-d', {str(tmp_path)!r}, '--engine', 'dask']))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == ["pln: --engine dask needs Dask distributed: "
                                               "pip install 'planefmt[dask]'"]


def test_ledger_reader_passes_over_a_torn_line(tmp_path: Path) -> None:
    path = tmp_path / "l.jsonl"
    with ledger.Ledger(path, resume=False) as book:
        book.append({"source": "a", "status": "ok"})
    path.write_text(path.read_text() + '{"source": "b", "status": "o')
    assert [e["source"] for e in ledger.read(path)] == ["a"]
    with ledger.Ledger(path, resume=True) as book:
        book.append({"source": "c", "status": "failed"})
    assert [e["source"] for e in ledger.read(path)] == ["a", "c"]


def test_run_bar_draws_only_on_a_terminal() -> None:
    shown, hidden = io.StringIO(), io.StringIO()
    for stream, enabled in ((shown, True), (hidden, False)):
        bar = RunBar(stream, 2, enabled)
        bar.add(False, 1000, 10)
        bar.add(True, 2000, 0)
        bar.close()
    assert hidden.getvalue() == ""
    assert "2/2 files, 1 failed, 3.0 kB in, 10 B out, ETA 0:00" in shown.getvalue()


@pytest.mark.parametrize("engine", ["local", "dask"])
def test_ctrl_c_stops_the_run_and_resume_finishes_it(engine: str, tmp_path: Path) -> None:
    if engine == "dask":
        pytest.importorskip("distributed")
    data = tmp_path / "data"
    data.mkdir()
    for i in range(8):
        shutil.copy(CUBE, data / f"cube{i:02d}.obj")
    out = tmp_path / "out"
    args = [*PLN, "convert", str(data), "-d", str(out), "--jobs", "2", "--engine", engine]
    proc = subprocess.Popen(args, stderr=subprocess.PIPE, text=True, start_new_session=True)
    report = out / "pln-report.jsonl"
    end = time.monotonic() + 600  # a hang guard far above normal (the first of 8 cubes: a few seconds)
    while not (report.exists() and report.read_text().count("\n") >= 1):
        assert proc.poll() is None and time.monotonic() < end
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGINT)  # what Ctrl-C on a terminal sends: to the whole process group
    _, err = proc.communicate(timeout=600)  # a hang guard far above normal (Ctrl-C stops it at once)
    assert proc.returncode == 130 and err == "pln: interrupted\n", err
    stopped = list(ledger.read(report))
    assert all(e["status"] == "ok" for e in stopped) and len(stopped) < 8
    assert [p.name for p in out.iterdir() if p.name.startswith(".")] == []
    assert main(["convert", str(data), "-d", str(out), "--jobs", "2", "--resume"]) == 0
    assert len({e["source"] for e in ledger.read(report)}) == 8
    assert sorted(p.name for p in out.iterdir()) == [f"cube{i:02d}.pln" for i in range(8)] + ["pln-report.jsonl"]


def test_a_terminal_sees_one_progress_line(tmp_path: Path) -> None:
    import pty

    for i in range(3):
        shutil.copy(TET, tmp_path / f"tet{i}.ply")
    leader, follower = pty.openpty()
    proc = subprocess.Popen([*PLN, "convert", str(tmp_path), "-d", str(tmp_path / "out")], stderr=follower)
    os.close(follower)
    shown = b""
    with contextlib.suppress(OSError):  # EIO once the process has closed its side
        while chunk := os.read(leader, 4096):
            shown += chunk
    os.close(leader)
    assert proc.wait(timeout=600) == 0  # a hang guard far above normal (three tetrahedra: seconds)
    text = shown.decode()
    assert "\r" in text and "3/3 files, 0 failed" in text and "ETA 0:00" in text, text
    assert text.rstrip().splitlines()[-1].startswith("pln: 3 converted, 0 skipped"), text
