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

from corpus import CORPUS

SOURCE = Path(__file__).resolve().parents[1] / "samples" / "cylinder.stl"

# `pln convert` with a pause at each stage of the conversion: the child prints the stage's name and
# waits for a line on stdin, so a test signals it at that stage exactly, however loaded the machine.
_STAGED = """
import os, sys

from planefmt_converters import registry
from planefmt_converters.cli import main


def pause(stage):
    print(stage, flush=True)
    sys.stdin.readline()


def before(stage, call):
    def staged(*args, **kwargs):
        pause(stage)
        return call(*args, **kwargs)
    return staged


def after(stage, call):
    def staged(*args, **kwargs):
        out = call(*args, **kwargs)
        pause(stage)
        return out
    return staged


registry.read = before("read", registry.read)  # the input not read yet
# An empty temporary beside the target, once the atomic writer holds it for removal (it sets the
# mode after mkstemp: a signal between mkstemp's return and that would leave the file, a window this
# test does not widen).
os.chmod = after("temporary", os.chmod)
os.replace = after("renamed", before("rename", os.replace))  # the temporary written; then renamed
sys.exit(main(sys.argv[1:]))
"""
#: Every stage, in the order a conversion reaches them.
STAGES = ("read", "temporary", "rename", "renamed")


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _staged(target: Path, stage: str | None, sig: signal.Signals = signal.SIGKILL) -> tuple[int, str, list[str]]:
    """A conversion of SOURCE to ``target`` sent ``sig`` at ``stage`` (None: at none): its exit status,
    its stderr and the stages it reached."""
    proc = subprocess.Popen([sys.executable, "-c", _STAGED, "convert", str(SOURCE), str(target)],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seen = []
    for line in proc.stdout:
        seen.append(line.strip())
        if seen[-1] == stage:
            proc.send_signal(sig)
            break
        proc.stdin.write("\n")
        proc.stdin.flush()
    # Not communicate(): closing stdin would end the pause before the signal is handled.
    # timeout: a hang guard far above normal (each case takes under 2 s on a loaded machine)
    code = proc.wait(timeout=300)
    err = proc.stderr.read()
    for stream in (proc.stdin, proc.stdout, proc.stderr):
        stream.close()
    return code, err, seen


@pytest.fixture(scope="module", params=[".obj", ".glb"])
def reference(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An uninterrupted conversion's output, once per output format."""
    out = tmp_path_factory.mktemp("reference") / f"reference{request.param}"
    code, err, seen = _staged(out, None)
    assert code == 0, err
    # Each stage a test below signals at is one the conversion passes through.
    assert seen == list(STAGES)
    return out


def test_every_stage_is_reached_once_in_order(reference: Path) -> None:
    assert reference.stat().st_size > 0


@pytest.mark.parametrize("stage", STAGES)
def test_sigkill_at_any_stage_leaves_no_file_under_the_target_name(stage: str, reference: Path,
                                                                  tmp_path: Path) -> None:
    before = _digest(SOURCE)
    target = tmp_path / f"out{reference.suffix}"
    code, err, seen = _staged(target, stage)
    assert seen[-1] == stage and code == -signal.SIGKILL, err
    if stage == "renamed":
        # Killed after the rename: the whole output, never a part.
        assert target.read_bytes() == reference.read_bytes()
    else:
        assert not target.exists()
    # SIGKILL allows no clean-up: besides the outputs, only hidden temporaries may stay.
    strays = [p.name for p in tmp_path.iterdir() if p.name != target.name]
    assert all(n.startswith(".") and ".tmp" in n for n in strays), strays
    assert len(strays) == (1 if stage in ("temporary", "rename") else 0), strays
    assert _digest(SOURCE) == before


@pytest.mark.parametrize("stage", STAGES)
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_sigterm_and_sigint_at_any_stage_clean_up_and_exit_130(sig: signal.Signals, stage: str, reference: Path,
                                                              tmp_path: Path) -> None:
    target = tmp_path / f"out{reference.suffix}"
    code, err, seen = _staged(target, stage, sig)
    assert seen[-1] == stage
    assert code == 130 and err.strip() == "pln: interrupted", err
    if stage == "renamed":
        # The signal came after the output was renamed into place: the whole output, never a part.
        assert target.read_bytes() == reference.read_bytes()
        assert [p.name for p in tmp_path.iterdir()] == [target.name]
    else:
        assert list(tmp_path.iterdir()) == [], "temporary files left behind"


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
    # timeout: a hang guard far above normal (2 s on a loaded machine)
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
    worker.join(timeout=300)  # a hang guard far above normal (under 2 s)
    assert codes == [0, 0]
