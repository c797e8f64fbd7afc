"""SIGINT and SIGTERM during a conversion: they stop it, and they are never lost.

The handler raises ``KeyboardInterrupt``, so a long encode stops at once and
every atomic writer on the stack discards its temporaries. Code between the
signal and the command line may swallow that exception: trimesh wraps an
optional import that fails, ``KeyboardInterrupt`` included, in a placeholder
module and carries on, so the conversion would finish (exit 0, a signal
lost) or fail later with an unrelated error. The handler therefore also
records the signal: :func:`check` raises again, before an output is renamed
into place and where the command line would report that error instead.
"""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator

_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_received: int | None = None


def _handler(signum: int, frame: object) -> None:
    global _received
    _received = signum
    raise KeyboardInterrupt


@contextlib.contextmanager
def handled() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM raise ``KeyboardInterrupt`` and are recorded for
    :func:`check` (main thread only); on leaving it, the handlers and the record are as before."""
    global _received
    _received = None
    previous = {s: signal.signal(s, _handler) for s in _SIGNALS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        _received = None


def check() -> None:
    """Raise ``KeyboardInterrupt`` if a signal arrived, even one whose exception was swallowed."""
    if _received is not None:
        raise KeyboardInterrupt
