"""Coverage-guided fuzzing of the .pln reader with atheris (libFuzzer).

    python fuzz/fuzz_pln.py [libFuzzer options] [CORPUS_DIR ...]

Every input is read to the end through ``planefmt.open`` (streaming) and,
where it parses, through ``salvage``, random access and ``validate`` with
geometry (which decodes every part group planefmt can decode: the
half-space intersection of hostile plane sets). Any exception outside
the ``PlnError`` tree is a crash; an input past ``CPU_LIMIT`` seconds of CPU
time and libFuzzer's ``-rss_limit_mb`` turn hangs and memory blow-ups into
crashes too. Crash
inputs belong in ``fuzz/regressions/`` (``tests/test_fuzz_regressions.py``
replays them). ``python fuzz/seeds.py DIR`` writes the seed corpus.
"""

from __future__ import annotations

import signal
import sys

import atheris

# planefmt's code alone is instrumented: numpy's and scipy's Python code is not the reader's, and
# instrumenting it took 30 of the 33 s of CPU a run spent before its first input.
with atheris.instrument_imports(include=["planefmt"]):
    from exercise import exercise

#: CPU seconds one input may take before it counts as a hang. A guard far above normal: the slowest
#: input of the documented runs took under 1 s (fuzz/README.md). CPU time, unlike libFuzzer's wall-clock
#: -timeout (which the runs turn off with -timeout=0), does not grow when other processes load the machine.
CPU_LIMIT = 30

#: What ``-timeout=0`` becomes. libFuzzer reads 0 as "no timeout", but atheris (3.0) reads it as a
#: wall-clock limit of 0 s: its alarm, every second, ends the run ("fuzz target exited") whenever one
#: input spans a second boundary, which a loaded machine makes likely (the suite's run failed so).
NO_WALL_LIMIT = 10**8


def wall_limit_off(argv: list[str]) -> list[str]:
    """``argv`` with ``-timeout=0`` (libFuzzer's "no wall-clock limit") as atheris needs it said."""
    return [f"-timeout={NO_WALL_LIMIT}" if a == "-timeout=0" else a for a in argv]


def _hang(signum: int, frame: object) -> None:
    raise TimeoutError(f"one input took over {CPU_LIMIT} s of CPU time")


def test_one_input(data: bytes) -> None:
    signal.setitimer(signal.ITIMER_PROF, CPU_LIMIT)
    try:
        exercise(data)
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)


if __name__ == "__main__":
    signal.signal(signal.SIGPROF, _hang)
    atheris.Setup(wall_limit_off(sys.argv), test_one_input)
    atheris.Fuzz()
