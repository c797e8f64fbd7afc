"""Interrupted conversions (issue 7): SIGKILL, SIGTERM or SIGINT at any moment leave nothing under
the target name but the whole output (when they arrive after it was renamed into place), and never
touch the input."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import trimesh

from corpus import CORPUS

BUNNY = CORPUS / "smooth_dense" / "bun_zipper.ply"
PLN = [sys.executable, "-m", "planefmt_converters.cli", "convert"]


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _full_run(target: Path) -> float:
    t0 = time.perf_counter()
    subprocess.run([*PLN, str(BUNNY), str(target)], check=True, capture_output=True)
    return time.perf_counter() - t0


def _signalled(target: Path, sig: signal.Signals, fraction: float, runtime: list[float],
               left: list[str]) -> tuple[subprocess.Popen, Path] | None:
    """A conversion to ``target`` sent ``sig`` at ``fraction`` of the runtime; None if every try ended first.

    The runtime is a guess from a timed run, which a loaded machine can make several times too long:
    a run that ends before its signal shortens it to that run's own duration and the signal is tried
    again on a fresh run (its whole output, checked, is named in ``left``).
    """
    for attempt in range(3):
        out = target.with_name(f"{target.stem}-{attempt}{target.suffix}")
        t0 = time.perf_counter()
        proc = subprocess.Popen([*PLN, str(BUNNY), str(out)], stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True)
        try:
            proc.wait(timeout=fraction * runtime[0])
        except subprocess.TimeoutExpired:
            proc.send_signal(sig)
            return proc, out
        runtime[0] = min(runtime[0], time.perf_counter() - t0)
        assert proc.returncode == 0, proc.stderr.read() if proc.stderr else ""
        proc.stderr.close()
        assert len(trimesh.load(out, force="mesh").faces) > 60_000
        left.append(out.name)
    return None


def test_sigkill_at_any_moment_leaves_no_file_under_the_target_name(tmp_path: Path) -> None:
    before = _digest(BUNNY)
    runtime = [_full_run(tmp_path / "reference.obj")]
    left = ["reference.obj"]
    killed = 0
    # Kill points spread over the whole conversion, start-up and writing included.
    for k, fraction in enumerate((0.15, 0.35, 0.55, 0.75, 0.85, 0.95)):
        run = _signalled(tmp_path / f"out{k}.obj", signal.SIGKILL, fraction, runtime, left)
        if run is None:
            continue
        proc, target = run
        _, err = proc.communicate(timeout=60)
        assert proc.returncode in (0, -signal.SIGKILL), err
        if target.exists():
            # Only ever the whole output: renamed into place once written (the process may be
            # killed after that, while it exits).
            assert len(trimesh.load(target, force="mesh").faces) > 60_000
            left.append(target.name)
        else:
            assert proc.returncode == -signal.SIGKILL
            killed += 1
    assert killed >= 3, "the conversion finished before most kill points: the test did not test"
    # SIGKILL allows no clean-up: besides the whole outputs, only hidden temporaries may stay.
    strays = [p.name for p in tmp_path.iterdir() if p.name not in left]
    assert all(n.startswith(".") and ".tmp" in n for n in strays), strays
    assert _digest(BUNNY) == before


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_sigterm_and_sigint_clean_up_and_exit_non_zero(sig: signal.Signals, tmp_path: Path) -> None:
    runtime = [_full_run(tmp_path / "reference.glb")]
    left = ["reference.glb"]
    interrupted = 0
    # Signal early, in the middle and late, and require that one interrupted a conversion. Not
    # before about 1/5: until `pln` has imported planefmt, Python's own SIGINT handling prints a
    # traceback (known).
    for k, fraction in enumerate((0.35, 0.6, 0.85)):
        run = _signalled(tmp_path / f"out{k}.glb", sig, fraction, runtime, left)
        if run is None:
            continue
        proc, target = run
        _, err = proc.communicate(timeout=60)
        assert "Traceback" not in err, err
        if target.exists():
            # The signal came after the output was renamed into place: then it is the whole
            # output, never a part.
            assert len(trimesh.load(target, force="mesh").faces) > 60_000
            left.append(target.name)
        else:
            assert proc.returncode != 0, "no output and yet exit status 0"
            interrupted += 1
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted(left), "temporary files left behind"
    assert interrupted >= 1, "every conversion finished before its signal: the test did not test"


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_whose_exception_the_reader_swallowed_still_stops_the_conversion(
        sig: signal.Signals, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # As trimesh does when a signal lands in one of its optional imports: the KeyboardInterrupt is
    # caught and the reading goes on.
    from planefmt_converters import registry
    from planefmt_converters.cli import main

    real_read = registry.read

    def swallowing_read(*args, **kwargs):
        try:
            os.kill(os.getpid(), sig)
            time.sleep(5)
        except BaseException:  # noqa: BLE001
            pass
        return real_read(*args, **kwargs)

    monkeypatch.setattr(registry, "read", swallowing_read)
    source = CORPUS / "convex" / "tet.ply"
    before = _digest(source)
    # Whatever they were (a CI job may start with SIGINT ignored), the handlers are restored.
    handlers = [signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)]
    assert main(["convert", str(source), str(tmp_path / "out.obj")]) == 130
    assert list(tmp_path.iterdir()) == []
    assert _digest(source) == before
    assert [signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)] == handlers
    # Once the conversion is over, the signal no longer holds back other writes.
    registry.write(real_read(source)[0], tmp_path / "after.obj")
    assert (tmp_path / "after.obj").exists()


# Sends the signal while planefmt is being imported: the moment is exact, not a guess at timings.
_DURING_IMPORT = """
import importlib.abc, os, signal, sys

class Signal(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "planefmt":
            sys.meta_path.remove(self)
            os.kill(os.getpid(), signal.{sig})
        return None

import planefmt_converters.cli
assert "planefmt" not in sys.modules and "numpy" not in sys.modules, sorted(sys.modules)
sys.meta_path.insert(0, Signal())
sys.exit(planefmt_converters.cli.main(sys.argv[1:]))
"""


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_a_signal_during_start_up_ends_the_command_without_a_traceback(sig: str, tmp_path: Path) -> None:
    # Importing the command line's package imports neither planefmt nor numpy, so the signal lands
    # in main(), under its handlers, and is reported as one during a conversion is.
    target = tmp_path / "out.glb"
    source = Path(__file__).resolve().parents[1] / "samples" / "cylinder.stl"
    run = subprocess.run([sys.executable, "-c", _DURING_IMPORT.format(sig=sig), "convert", str(source),
                          str(target)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 130, run.stderr
    assert run.stderr.strip() == "pln: interrupted"
    assert not target.exists() and list(tmp_path.iterdir()) == []


def test_the_command_line_runs_outside_the_main_thread(tmp_path: Path) -> None:
    # Signal handlers can be set in the main thread only: elsewhere main() runs without them.
    from planefmt_converters import cli

    source = Path(__file__).resolve().parents[1] / "samples" / "cylinder.stl"
    codes: list[int] = []

    def run() -> None:
        codes.append(cli.main(["convert", str(source), str(tmp_path / "out.pln")]))
        codes.append(cli.main(["info", str(tmp_path / "out.pln")]))

    worker = threading.Thread(target=run)
    worker.start()
    worker.join(timeout=300)
    assert codes == [0, 0]
