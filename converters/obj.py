"""Wavefront OBJ through trimesh.

Reading keeps each object trimesh separates (by material) as a node;
polygons are triangulated by trimesh. Normals, UVs and materials are
reported as dropped. Writing flattens the scene into one mesh in world
coordinates; OBJ has no face colours. Coordinates are written with 17
decimals, enough to round-trip float64 at model scales.

OBJ declares no counts, so a cut file shows only where it ends inside a
statement: a last line without a line break that is short of a statement
(a face of fewer than three corners, a corner ending in ``/``, a vertex of
fewer than three coordinates) is a ``TRUNCATED`` error (trimesh would drop
that face without a word). A cut at a line break, or inside a number
(``f 1 2 34`` cut to ``f 1 2 3``), leaves a valid shorter file: undetectable.
"""

from __future__ import annotations

import codecs
import os
from functools import partial

from planefmt.errors import ConversionError
from planefmt.model import Scene

from .trimesh_bridge import read_scene, require_trimesh, write_flat

#: First words of OBJ statements (geometry, grouping, display, free-form).
_KEYWORDS = frozenset(
    b"v vt vn vp f l p o g s mg usemtl mtllib maplib usemap lod bevel c_interp d_interp "
    b"shadow_obj trace_obj cstype deg bmat step curv curv2 surf parm trim hole scrv sp end "
    b"con ctech stech".split())


def sniff(head: bytes, size: int) -> bool:
    """Text whose statements all start with OBJ keywords, with at least one ``v``."""
    if b"\0" in head:
        return False
    lines = head.splitlines()
    if size > len(head):
        lines = lines[:-1]  # the last line may be cut short
    vertices = False
    for line in lines:
        words = line.split(None, 1)
        if not words or words[0].startswith(b"#"):
            continue
        if words[0] not in _KEYWORDS:
            return False
        vertices = vertices or words[0] == b"v"
    return vertices


def read(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    """Read an OBJ file into ``(scene, dropped)``; one cut inside its last statement is ``TRUNCATED``."""
    file = os.fspath(path)
    try:
        with open(file, "rb") as handle:
            head = handle.read(65536)
        # Final=False: the block may end inside a character. trimesh would guess another encoding
        # through an optional module and report that module missing, not that the file is no text.
        codecs.getincrementaldecoder("utf-8")().decode(head, final=False)
        _check_last_line(file)
    except UnicodeDecodeError as exc:
        raise ConversionError(f"not OBJ text: byte {exc.start} is not UTF-8 text", file=file) from exc
    except OSError as exc:
        raise ConversionError(f"cannot open: {exc.strerror or exc}", file=file) from exc
    return read_scene(file, "obj", "OBJ")


#: The fewest values of the statements a cut can visibly shorten.
_FEWEST = {b"v": 3, b"vn": 3, b"vt": 1, b"f": 3, b"l": 2}


def _check_last_line(file: str) -> None:
    """Raise ``TRUNCATED`` where the file ends, without a line break, inside a statement."""
    with open(file, "rb") as handle:
        size = handle.seek(0, os.SEEK_END)
        handle.seek(max(0, size - 4096))
        tail = handle.read()
    if not tail or tail.endswith((b"\n", b"\r")):
        return
    line = tail.splitlines()[-1]
    words = line.split()
    if not words or words[0] not in _FEWEST:
        return
    values = words[1:]
    if len(values) < _FEWEST[words[0]] or (words[0] == b"f" and values[-1].endswith(b"/")):
        shown = line.decode("utf-8", "replace").strip()
        raise ConversionError(f"the file ends inside a statement: its last line, {shown!r}, has no line break and "
                              "is cut short; the file is truncated", code="TRUNCATED", file=file)


def write(scene: Scene, path: str | os.PathLike[str]) -> list[str]:
    """Write ``scene`` as one OBJ mesh; returns what OBJ could not hold."""
    exchange = require_trimesh("OBJ").exchange.obj
    export = partial(exchange.export_obj, include_normals=False, include_color=False,
                     include_texture=False, write_texture=False, digits=17, header=None)
    return write_flat(scene, path, what="OBJ", export=export, colours=False, float32=False)
