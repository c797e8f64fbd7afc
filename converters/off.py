"""Object File Format (OFF) through trimesh.

Reads ``OFF`` and ``COFF`` (colours ignored) with polygon faces; writes
plain OFF with the scene flattened into one world-space mesh, 17 decimals.
"""

from __future__ import annotations

import os
from functools import partial

from planefmt.model import Scene

from .trimesh_bridge import read_scene, require_trimesh, write_flat

_HEADERS = (b"OFF", b"COFF", b"NOFF", b"CNOFF")


def sniff(head: bytes, size: int) -> bool:
    """The first word that is not in a ``#`` comment is an OFF header keyword."""
    for line in head.splitlines():
        words = line.split(b"#", 1)[0].split()
        if words:
            return words[0] in _HEADERS
    return False


def read(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    """Read an OFF file into ``(scene, dropped)``."""
    return read_scene(path, "off", "OFF")


def write(scene: Scene, path: str | os.PathLike[str]) -> list[str]:
    """Write ``scene`` as one OFF mesh; returns what OFF could not hold."""
    export = partial(require_trimesh("OFF").exchange.off.export_off, digits=17)
    return write_flat(scene, path, what="OFF", export=export, colours=False, float32=False)
