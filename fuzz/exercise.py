"""What the fuzzer does with one input, without atheris: ``tests/test_fuzz_regressions.py`` replays
the saved crash inputs through it on machines where atheris is not installed."""

from __future__ import annotations

import io

import planefmt
from planefmt.container.chunks import Limits
from planefmt.container.salvage import salvage
from planefmt.codec import decode_mesh, validate

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
        # the geometry of every kind, copies and transforms included, as a user's decode reaches it
        try:
            decode_mesh(io.BytesIO(data))
        except planefmt.PlnError:
            pass
