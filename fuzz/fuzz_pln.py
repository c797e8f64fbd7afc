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

import io
import sys

import atheris

with atheris.instrument_imports():
    import planefmt
    from planefmt import codec  # noqa: F401  (registers the geometry checks of validate)
    from planefmt.chunks import Limits
    from planefmt.salvage import salvage
    from planefmt.validate import validate

#: Small caps: a fuzzer input is at most a few kB, so anything bigger is hostile.
LIMITS = Limits(max_chunk_length=1 << 20, max_raw_size=1 << 22, max_planes=1 << 16,
                max_refs_per_group=1 << 16, max_objects=1 << 12)


def exercise(data: bytes) -> None:
    """Read ``data`` every way a user can; only ``PlnError`` may escape."""
    groups = 0
    try:
        with planefmt.open(io.BytesIO(data), limits=LIMITS) as r:
            groups = sum(1 for _ in r.part_groups())
        if groups:
            with planefmt.open(io.BytesIO(data), limits=LIMITS) as r:
                r.group(groups - 1)
    except planefmt.PlnError:
        pass
    try:
        salvage(io.BytesIO(data), limits=LIMITS)
    except planefmt.PlnError:
        pass
    if groups:
        # validate reports every PlnError as a finding: anything it raises is a crash.
        validate(io.BytesIO(data), geometry=True, limits=LIMITS)


def test_one_input(data: bytes) -> None:
    exercise(data)


if __name__ == "__main__":
    atheris.Setup(sys.argv, test_one_input)
    atheris.Fuzz()
