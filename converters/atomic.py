"""Atomic file output: a failed or interrupted write never leaves a partial file.

Writers produce their output under temporary names in the target's directory
(same file system, so the final ``os.replace`` is an atomic rename) and
rename them over the targets only once everything was written. On any
exception, or after a SIGINT or SIGTERM (:mod:`.interrupts`), the
temporaries are removed and the targets are left as they were.

Temporary names keep the target's suffix because some libraries (usd-core)
choose the file format from the extension.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

from . import interrupts


def _current_umask() -> int:
    # os.umask can only be read by setting it; done once, at import time.
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: Mode of a newly created output file: what open() would have given it
#: (mkstemp creates its files 0600, too private for an output file).
_NEW_FILE_MODE = 0o666 & ~_current_umask()


@contextlib.contextmanager
def atomic_paths(targets: Sequence[str | os.PathLike[str]]) -> Iterator[list[Path]]:
    """Yield one temporary path per target; on success rename each over its target.

    The temporaries are renamed in the order given, so a file that refers to
    another (a ``.gltf`` to its ``.bin``) should come after it: a reader never
    sees the referring file before the referred one exists. Each rename is
    atomic; the group is not (a crash between two renames leaves the new
    sidecar beside the old main file).
    """
    temps: list[Path] = []
    try:
        for target in targets:
            target = Path(target)
            fd, name = tempfile.mkstemp(prefix=f".{target.stem}.", suffix=f".tmp{target.suffix}",
                                        dir=target.parent)
            os.close(fd)
            temps.append(Path(name))
            try:
                mode = target.stat().st_mode & 0o7777
            except FileNotFoundError:
                mode = _NEW_FILE_MODE
            os.chmod(name, mode)
        yield temps
        # A signal whose exception the writer swallowed must still keep the output out.
        interrupts.check()
        for temp, target in zip(temps, targets):
            os.replace(temp, target)
    finally:
        for temp in temps:
            with contextlib.suppress(FileNotFoundError):
                temp.unlink()


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path; on success rename it over ``target`` (see :func:`atomic_paths`)."""
    with atomic_paths([target]) as (temp,):
        yield temp


def write_bytes(target: str | os.PathLike[str], data: bytes) -> None:
    """Write ``data`` to ``target`` atomically, flushed to disk before the rename."""
    with atomic_path(target) as temp:
        with open(temp, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
