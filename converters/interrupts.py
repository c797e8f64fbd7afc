"""SIGINT and SIGTERM during a conversion: they stop it, and they are never lost.

The handler raises ``KeyboardInterrupt``, so a long encode stops at once and
every atomic writer on the stack discards its temporaries. Code between the
signal and the command line may swallow that exception: trimesh wraps an
optional import that fails, ``KeyboardInterrupt`` included, in a placeholder
module and carries on, so the conversion would finish (exit 0, a signal
lost) or fail later with an unrelated error, and an extension module can
abort the process on it. The handler therefore raises only outside imports
(within one it sends the signal again shortly), and it also records the
signal: :func:`check` raises again, before an output is renamed
into place and where the command line would report that error instead.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import types
from collections.abc import Iterator

_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_received: int | None = None


#: Seconds after which a signal that arrived during an import is delivered again.
_RETRY = 0.05


def _handler(signum: int, frame: types.FrameType | None) -> None:
    global _received
    _received = signum
    if _importing(frame):
        # Raised inside an import, the exception can abort the process (a C++ extension's module
        # initialisation turns it into std::terminate: manifold3d under trimesh) or be swallowed:
        # the signal is sent again shortly, until it lands outside any import.
        timer = threading.Timer(_RETRY, _redeliver, (signum,))
        timer.daemon = True
        timer.start()
        return
    raise KeyboardInterrupt


def _importing(frame: types.FrameType | None) -> bool:
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib._bootstrap"):
            return True
        frame = frame.f_back
    return False


def _redeliver(signum: int) -> None:
    if _received is not None:
        os.kill(os.getpid(), signum)


@contextlib.contextmanager
def handled() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM raise ``KeyboardInterrupt`` and are recorded for
    :func:`check`; on leaving it, the handlers and the record are as before. Outside the main
    thread, where Python neither delivers signals nor lets handlers be set, it does nothing."""
    global _received
    if threading.current_thread() is not threading.main_thread():
        yield
        return
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
