"""STL (binary and ASCII) through trimesh.

STL is a triangle soup of float32 coordinates: the reader merges equal
positions back into shared vertices (see :mod:`.assemble`). Writing
flattens the scene into one world-space mesh, binary by default, welded
after float32 rounding with no triangle left without area
(:func:`.assemble.at_float32`); STL has no units, names or colours (the
vendor colour conventions are not used).
"""

from __future__ import annotations

import os

from planefmt.model import Scene

from .trimesh_bridge import read_scene, require_trimesh, write_flat

_BINARY_HEADER = 84  # 80-byte header + uint32 triangle count
_BINARY_TRIANGLE = 50  # normal, three corners (float32) and a uint16 attribute


def sniff(head: bytes, size: int) -> bool:
    """Binary STL: the size matches the triangle count. ASCII: ``solid`` … ``facet``."""
    if size >= _BINARY_HEADER and len(head) >= _BINARY_HEADER:
        count = int.from_bytes(head[80:84], "little")
        if size == _BINARY_HEADER + _BINARY_TRIANGLE * count:
            return True
    text = head.lstrip()
    return text[:5].lower() == b"solid" and (b"facet" in text or b"endsolid" in text)


def read(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    """Read an STL file into ``(scene, dropped)``."""
    return read_scene(path, "stl", "STL")


def write(scene: Scene, path: str | os.PathLike[str], *, ascii: bool = False) -> list[str]:
    """Write ``scene`` as one STL mesh, binary unless ``ascii``; returns what STL lacks."""
    exchange = require_trimesh("STL").exchange.stl
    export = exchange.export_stl_ascii if ascii else exchange.export_stl
    return write_flat(scene, path, what="STL", export=export, colours=False, float32=True)
