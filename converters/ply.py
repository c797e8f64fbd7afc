"""Stanford PLY (ASCII and binary) through trimesh.

Face colours are read and written (``red green blue alpha`` on the face
element). Vertex properties other than position, and vertex colours that
differ within a face, are reported as dropped. Writing flattens the scene
into one world-space mesh; binary little-endian by default. trimesh writes
coordinates as float32, welded after rounding, with no triangle left without
area (:func:`.assemble.at_float32`).
"""

from __future__ import annotations

import os
from functools import partial

from planefmt.model import Scene

from .trimesh_bridge import read_scene, require_trimesh, write_flat


def sniff(head: bytes, size: int) -> bool:
    """PLY files start with the line ``ply``."""
    return head.startswith((b"ply\n", b"ply\r\n", b"ply\r"))


#: Properties the reader keeps or trimesh already reports (normals, UVs, colours).
_KNOWN = {
    "vertex": {"x", "y", "z", "nx", "ny", "nz", "s", "t", "u", "v", "texture_u", "texture_v",
               "red", "green", "blue", "alpha"},
    "face": {"vertex_indices", "vertex_index", "red", "green", "blue", "alpha"},
}


def read(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    """Read a PLY file into ``(scene, dropped)``."""
    scene, dropped = read_scene(path, "ply", "PLY")
    return scene, sorted(dropped + _unused_properties(path))


def _unused_properties(path: str | os.PathLike[str]) -> list[str]:
    """Notes naming the header's elements and properties that the model has no room for."""
    elements: dict[str, list[str]] = {}
    current: list[str] = []
    with open(path, "rb") as handle:
        for raw in handle:
            words = raw.decode("ascii", "replace").split()
            if not words or words[0] == "end_header":
                break
            if words[0] == "element" and len(words) > 1:
                current = elements.setdefault(words[1], [])
            elif words[0] == "property" and len(words) > 1:
                current.append(words[-1])
    notes = []
    for element, properties in elements.items():
        if element not in _KNOWN:
            notes.append(f"PLY element {element}")
            continue
        extra = [name for name in properties if name not in _KNOWN[element]]
        if extra:
            notes.append(f"PLY {element} properties ({', '.join(extra)})")
    return notes


def write(scene: Scene, path: str | os.PathLike[str], *, ascii: bool = False) -> list[str]:
    """Write ``scene`` as one PLY mesh, binary unless ``ascii``; returns what PLY lacks."""
    export = partial(require_trimesh("PLY").exchange.ply.export_ply,
                     encoding="ascii" if ascii else "binary",
                     vertex_normal=False, include_attributes=False)
    return write_flat(scene, path, what="PLY", export=export, colours=True, float32=True)
