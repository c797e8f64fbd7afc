"""Progress of long library calls, for a caller that shows it (the ``pln`` command line).

The library never prints: it reports stages to the callback a caller installed with :func:`reporting`,
and does nothing when none is installed. A context variable holds the callback, so threads and
concurrent calls each see their own.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from contextvars import ContextVar

#: ``callback(stage, done, total)``: ``done`` steps of ``stage`` finished, of ``total`` (None: not known).
Callback = Callable[[str, int, "int | None"], None]

_callback: ContextVar[Callback | None] = ContextVar("planefmt_progress", default=None)


@contextlib.contextmanager
def reporting(callback: Callback) -> Iterator[None]:
    """Within the block, the library's long calls report their progress to ``callback``."""
    token = _callback.set(callback)
    try:
        yield
    finally:
        _callback.reset(token)


def report(stage: str, done: int, total: int | None = None) -> None:
    """Tell the installed callback, if any, that ``done`` steps of ``stage`` (of ``total``) are finished."""
    callback = _callback.get()
    if callback is not None:
        callback(stage, done, total)
