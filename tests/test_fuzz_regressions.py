"""Replay every input the fuzzer ever found (fuzz/regressions/) and a short fuzzing run of a fixed
number of inputs (the long run is `make fuzz`)."""

from __future__ import annotations

import io
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from planefmt.container.salvage import salvage

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "fuzz"))

REGRESSIONS = sorted(p for p in (ROOT / "fuzz" / "regressions").iterdir() if p.name != ".keep")
#: A hang guard in CPU seconds, far above normal: the slowest of these inputs takes 1.3 ms of CPU (the
#: salvage bug it was saved for took 1.8 s); CPU time, unlike wall time, does not grow when other
#: processes load the machine.
TIMEOUT = 2.0
#: Inputs of the suite's fuzzing run: 15 s of CPU time with the 308 seeds (36 s of wall time at a load
#: average of 7). `make fuzz` runs longer.
RUNS = 20000


@pytest.mark.parametrize("path", REGRESSIONS, ids=[p.name for p in REGRESSIONS])
def test_regression_input_raises_only_pln_errors_and_ends(path):
    # exercise raises whatever is not a PlnError: that exception fails the test.
    from exercise import exercise

    start = time.process_time()
    exercise(path.read_bytes())
    assert time.process_time() - start < TIMEOUT


def test_a_run_of_missing_groups_is_one_loss():
    """timeout-group-index-run: group 0, then a GRUP whose damaged index claims 589,824. Salvage
    once recorded each of the 589,823 missing groups as a loss of its own (an index near 2**32
    would not have ended); the run is one loss."""
    from exercise import LIMITS

    losses = [x.message for x in salvage(io.BytesIO((ROOT / "fuzz" / "regressions" / "timeout-group-index-run")
                                                    .read_bytes()), limits=LIMITS).losses]
    assert "part groups 1..589824 lost" in losses
    assert not any(m.startswith("part group ") and "groups" not in m for m in losses), losses


def test_short_fuzzing_run(tmp_path):
    """A fixed number of fuzzed inputs: an exception outside PlnError, an input past fuzz_pln.py's
    CPU_LIMIT (a hang) or over 256 MB RSS fails the test; no wall-clock limit can."""
    pytest.importorskip("atheris")
    corpus = tmp_path / "corpus"
    subprocess.run([sys.executable, str(ROOT / "fuzz" / "seeds.py"), str(corpus)], check=True)
    runs = int(os.environ.get("PLN_FUZZ_RUNS", str(RUNS)))
    # A fixed seed keeps CI reproducible; the longer documented run (fuzz/README.md) varies it.
    seed = int(os.environ.get("PLN_FUZZ_SEED", "1"))
    fuzzer = [sys.executable, str(ROOT / "fuzz" / "fuzz_pln.py"), f"-runs={runs}", f"-seed={seed}", "-timeout=0",
              "-rss_limit_mb=256", "-max_len=4096", f"-artifact_prefix={tmp_path}/", "-print_final_stats=1",
              str(corpus)]
    # Linux keeps ru_maxrss across fork and exec, so a fuzzer started straight from this (by now
    # large) pytest process would see pytest's peak as its own and stop at once on -rss_limit_mb.
    # A shell that forks it (no exec: the command is not the last) gives it a fresh count.
    # timeout: a hang guard far above normal (the run takes under a minute), not a verdict on speed.
    p = subprocess.run(["sh", "-c", '"$@"; exit $?', "sh", *fuzzer], capture_output=True, text=True, timeout=3600)
    # Enough lines for a whole Python stack (innermost frame first) and what a library printed above
    # it: a run that once exited inside halfspace.intersect was cut below its innermost frames.
    tail = "\n".join(p.stderr.splitlines()[-100:])
    assert p.returncode == 0, f"fuzzer found a crash; input saved under {tmp_path}:\n{tail}"
    assert "Done" in p.stderr and f"Done {runs} runs" in p.stderr, tail


def test_a_run_stretched_by_load_is_not_cut_short(tmp_path):
    """The run has no wall-clock limit (-timeout=0), however long one input takes on a loaded machine:
    the fuzzer is stopped for 2.5 s (SIGSTOP) while it runs its seeds, and then finishes. atheris took
    -timeout=0 as 0 s and ended such a run with "fuzz target exited", which the suite's run hit now and
    then under load."""
    pytest.importorskip("atheris")
    import signal

    corpus = tmp_path / "corpus"
    subprocess.run([sys.executable, str(ROOT / "fuzz" / "seeds.py"), str(corpus)], check=True)
    fuzzer = [sys.executable, str(ROOT / "fuzz" / "fuzz_pln.py"), "-runs=1", "-seed=1", "-timeout=0",
              "-max_len=4096", f"-artifact_prefix={tmp_path}/", str(corpus)]
    p = subprocess.Popen(["sh", "-c", '"$@"; exit $?', "sh", *fuzzer], stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    lines = []
    for line in p.stderr:
        lines.append(line)
        if line.startswith("INFO: seed corpus:"):  # from here on it runs one seed after another
            break
    time.sleep(0.5)
    os.killpg(p.pid, signal.SIGSTOP)
    time.sleep(2.5)
    os.killpg(p.pid, signal.SIGCONT)
    lines += p.stderr.read().splitlines(keepends=True)
    tail = "".join(lines[-40:])
    assert p.wait(timeout=600) == 0, tail
    assert "fuzz target exited" not in tail and "Done" in tail, tail
