"""The run ledger of a batch conversion: one JSON line per input, written as the input finishes.

Each line is flushed and fsync'd before the next input is reported, so a SIGKILL or a power cut loses
at most the line being written; a reader skips a last line without its newline (torn), and a writer
that appends to such a ledger cuts that line off first. A line holds:

    source, output       the paths (or URLs) as the run named them
    status               "ok", "failed" or "skipped" (converted by an earlier run: --resume)
    code, message        the error code (planefmt.errors.CODES) and its one-line message, when failed
    size, mtime_ns       the source's identity when it was read: --resume trusts an "ok" only for these
    triangles            the source's triangles
    bytes_in, bytes_out  the bytes of every file the source is made of (a .gltf's buffers and images, an OBJ's
                         materials and textures) and of every file written (a .gltf's .bin)
    error_bound          the error bound the .pln side records, a fraction of the bbox diagonal
    seconds, peak_mb     wall time and peak resident memory (MB) of the conversion
    settings             the options the output depends on (--to, --tolerance...): --resume skips only
                         for the same
    finished             when the line was written (UNIX time)
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from pathlib import Path

#: The ledger's name in the output folder when --report names none.
DEFAULT_NAME = "pln-report.jsonl"
STATUSES = ("ok", "failed", "skipped")


class Ledger:
    """An open ledger file; ``append`` is safe to interrupt at any moment."""

    def __init__(self, path: str | os.PathLike[str], *, resume: bool) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if resume and self.path.exists():
            _cut_torn_line(self.path)
            self._file = open(self.path, "a", encoding="utf-8")
        else:
            self._file = open(self.path, "w", encoding="utf-8")

    def append(self, entry: dict) -> None:
        self._file.write(json.dumps(entry, separators=(",", ":")) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> Ledger:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def read(path: str | os.PathLike[str]) -> Iterator[dict]:
    """The ledger's entries in order; a torn or unreadable line (a killed writer's) is skipped."""
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            if not line.endswith("\n"):
                return
            try:
                entry = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(entry, dict) and entry.get("status") in STATUSES and "source" in entry:
                yield entry


def completed(path: str | os.PathLike[str]) -> dict[str, dict]:
    """Per source, its last entry that says it was converted (``ok``, or ``skipped`` after one):
    what ``--resume`` may skip, if the source still has the same size and mtime."""
    done: dict[str, dict] = {}
    if not os.path.exists(path):
        return done
    for entry in read(path):
        if entry["status"] in ("ok", "skipped"):
            done[entry["source"]] = entry
        else:
            done.pop(entry["source"], None)
    return done


def _cut_torn_line(path: Path) -> None:
    """Drop a last line without its newline, so that the next line starts on a line of its own."""
    with open(path, "rb+") as f:
        data = f.read()
        if data and not data.endswith(b"\n"):
            f.truncate(data.rfind(b"\n") + 1)
