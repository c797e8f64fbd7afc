"""Wavefront OBJ through trimesh.

Reading keeps each object trimesh separates (by material) as a node;
polygons are triangulated by trimesh. Normals, texture coordinates and materials are
reported as dropped, and textures where a material library names an image (``map_Kd`` and the other
map statements), present or not. The material libraries and the images present are the files the
OBJ is made of (:func:`references`). Writing flattens the scene into one mesh in world
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
import mmap
import os
import re
from functools import partial

from planefmt.errors import ConversionError
from planefmt.model import Scene

from .dropped import TEXTURES, listed
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
    scene, dropped = read_scene(file, "obj", "OBJ")
    if _material_files(file)[1]:
        counts = [note for note in dropped if note[:1].isdigit()]
        dropped = listed([note for note in dropped if note not in counts] + [TEXTURES]) + counts
    return scene, dropped


_MTLLIB = re.compile(rb"^[ \t]*mtllib[ \t]+([^\r\n]*?)[ \t]*\r?$", re.MULTILINE)
#: MTL statements naming an image: its file name is the last word, after any options.
_MAP = re.compile(rb"^[ \t]*(?:map_\w+|bump|disp|decal|refl|norm)[ \t]+([^\r\n]*?)[ \t]*\r?$", re.MULTILINE)


def _named(folder: str, text: bytes) -> str:
    return os.path.join(folder, text.decode("utf-8", "replace"))


def _material_files(path: str | os.PathLike[str]) -> tuple[list[str], list[str]]:
    """The material libraries the OBJ at ``path`` names that exist, and the images they name (present
    or not). A name with spaces is taken whole where that file exists, else word by word."""
    file = os.fspath(path)
    folder = os.path.dirname(file)
    libraries: list[str] = []
    try:
        with open(file, "rb") as handle, mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_READ) as data:
            for match in _MTLLIB.finditer(data):
                whole = _named(folder, match.group(1))
                names = [whole] if os.path.isfile(whole) else [_named(folder, word) for word in match.group(1).split()]
                libraries += [name for name in names if os.path.isfile(name) and name not in libraries]
    except (OSError, ValueError):  # unreadable, or empty (mmap of nothing)
        return [], []
    images: list[str] = []
    for library in libraries:
        try:
            with open(library, "rb") as handle:
                text = handle.read()
        except OSError:
            continue
        for match in _MAP.finditer(text):
            words = match.group(1).split()
            if words:
                image = _named(os.path.dirname(library), words[-1])
                if image not in images:
                    images.append(image)
    return libraries, images


def references(path: str | os.PathLike[str]) -> tuple[str, ...]:
    """The files beside the OBJ at ``path`` that its reading opens: its material libraries and the
    images they name that exist."""
    libraries, images = _material_files(path)
    return tuple(libraries + [image for image in images if os.path.isfile(image)])


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
