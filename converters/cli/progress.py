"""What a long conversion shows on a terminal: one status line while it runs, one summary line at the end.

The status line (stage, percent where the stage knows its total, elapsed seconds) is redrawn in place on
stderr, only when stderr is a terminal and only once the conversion has run for :data:`DELAY` seconds,
so quick conversions and pipes or logs see nothing of it. The library reports its stages through
:mod:`planefmt.progress`; a thread redraws the line, so the elapsed time moves while a stage runs.
"""

from __future__ import annotations

import math
import threading
import time
from typing import TextIO

#: Seconds before the status line appears: a conversion quicker than that shows none.
DELAY = 0.5
#: Seconds between redraws.
INTERVAL = 0.2


class Status:
    """The status line of one conversion on ``stream``; inert unless ``enabled``."""

    def __init__(self, stream: TextIO, enabled: bool) -> None:
        self.stream = stream
        self.enabled = enabled
        self.start = time.monotonic()
        self._stage, self._done, self._total = "starting", 0, None
        self._width = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = None
        if enabled:
            self._thread = threading.Thread(target=self._run, name="pln-status", daemon=True)
            self._thread.start()

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.start

    def update(self, stage: str, done: int = 0, total: int | None = None) -> None:
        """The conversion is at ``stage``, ``done`` of ``total`` steps (None: a count with no known end)."""
        with self._lock:
            self._stage, self._done, self._total = stage, done, total

    def close(self) -> None:
        """Stop redrawing and clear the line, so that what is printed next starts at its beginning."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        with self._lock:
            if self._width:
                self.stream.write("\r" + " " * self._width + "\r")
                self.stream.flush()
                self._width = 0

    def _run(self) -> None:
        while not self._stop.wait(INTERVAL):
            if self.elapsed >= DELAY:
                self._draw()

    def _draw(self) -> None:
        with self._lock:
            if self._stop.is_set():
                return
            if self._total:
                where = f" {self._done}/{self._total} ({100 * self._done // self._total}%)"
            elif self._done:
                where = f" ({self._done} so far)"
            else:
                where = ""
            text = f"pln: {self._stage}{where}, {self.elapsed:.0f} s"
            self.stream.write("\r" + text.ljust(self._width))
            self.stream.flush()
            self._width = max(self._width, len(text))


def summary(src: str, dst: str, bytes_in: int, bytes_out: int, error: float | None, seconds: float,
            recorded_in_input: bool = False, rounding: float = 0.0) -> str:
    """The one line a conversion ends with: what went in and out, the error bound, how long it took.

    ``rounding``: how far writing the output moved the surface (float32 coordinates), added to ``error``
    (the input's recorded bound; none for an exact input): the bound holds for the file written.
    """
    bound = ""
    if error is not None and rounding:
        bound = (f", error at most {_up(error + rounding)} of the diagonal ({_up(error)} recorded in the input, "
                 f"{_up(rounding)} from rounding to float32)")
    elif rounding:
        bound = f", error at most {_up(rounding)} of the diagonal (from rounding to float32)"
    elif error is not None:
        bound = f", error at most {_up(error)} of the diagonal" + (" (recorded in the input)" if recorded_in_input
                                                                   else "")
    return f"pln: {src} -> {dst}: {bytes_in:,} B in, {bytes_out:,} B out{bound}, {seconds:.1f} s"


def _up(value: float) -> str:
    """``value`` to three significant digits, rounded up: a bound printed shorter must still be a bound."""
    if not value > 0 or not math.isfinite(value):
        return f"{value:.3g}"
    scale = 10.0 ** (math.floor(math.log10(value)) - 2)
    return f"{math.ceil(value / scale * (1 - 1e-12)) * scale:.3g}"


class RunBar:
    """The one line of a batch run on ``stream``: files done of the total, failed, bytes in and out,
    estimated time left; redrawn as inputs finish, at most every :data:`INTERVAL` seconds, and inert
    unless ``enabled`` (a terminal)."""

    def __init__(self, stream: TextIO, total: int, enabled: bool) -> None:
        self.stream, self.total, self.enabled = stream, total, enabled
        self.done = self.failed = self.bytes_in = self.bytes_out = 0
        self.start = time.monotonic()
        self._drawn = 0.0
        self._width = 0

    def add(self, failed: bool, bytes_in: int, bytes_out: int) -> None:
        self.done += 1
        self.failed += failed
        self.bytes_in += bytes_in
        self.bytes_out += bytes_out
        now = time.monotonic()
        if self.enabled and (now - self._drawn >= INTERVAL or self.done == self.total):
            self._drawn = now
            self._draw()

    def clear(self) -> None:
        """Take the line away, so that a message starts at the beginning of its own line."""
        if self.enabled and self._width:
            self.stream.write("\r" + " " * self._width + "\r")
            self.stream.flush()
            self._width = 0

    def close(self) -> None:
        if self.enabled and self._width:
            self.stream.write("\n")
            self.stream.flush()

    def _draw(self) -> None:
        width = 24
        filled = width * self.done // max(self.total, 1)
        elapsed = time.monotonic() - self.start
        left = elapsed / self.done * (self.total - self.done) if self.done else 0
        text = (f"pln: [{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} files, "
                f"{self.failed} failed, {_size(self.bytes_in)} in, {_size(self.bytes_out)} out, "
                f"ETA {_duration(left)}")
        self.stream.write("\r" + text.ljust(self._width))
        self.stream.flush()
        self._width = max(self._width, len(text))


def _size(n: float) -> str:
    if n < 1000:
        return f"{n:.0f} B"
    for unit in ("kB", "MB", "GB", "TB"):
        n /= 1000
        if n < 1000 or unit == "TB":
            break
    return f"{n:.1f} {unit}"


def _duration(seconds: float) -> str:
    seconds = int(seconds + 0.5)
    return f"{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}" if seconds >= 3600 else \
        f"{seconds // 60}:{seconds % 60:02d}"
