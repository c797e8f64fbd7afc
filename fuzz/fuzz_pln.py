"""Coverage-guided fuzzing of the .pln reader with atheris (libFuzzer).

    python fuzz/fuzz_pln.py [libFuzzer options] [CORPUS_DIR ...]

Every input is read to the end through ``planefmt.open`` (streaming) and,
where it parses, through ``salvage``, random access and ``validate`` with
geometry (which decodes every part group planefmt can decode: the
half-space intersection of hostile plane sets). Any exception outside
the ``PlnError`` tree is a crash; libFuzzer's ``-timeout`` and
``-rss_limit_mb`` turn hangs and memory blow-ups into crashes too. Crash
inputs belong in ``fuzz/regressions/`` (``tests/test_fuzz_regressions.py``
replays them). ``python fuzz/seeds.py DIR`` writes the seed corpus.
"""

from __future__ import annotations

import sys

import atheris

with atheris.instrument_imports():
    from exercise import exercise


def test_one_input(data: bytes) -> None:
    exercise(data)


if __name__ == "__main__":
    atheris.Setup(sys.argv, test_one_input)
    atheris.Fuzz()
