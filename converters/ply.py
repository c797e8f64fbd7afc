"""Stanford PLY (ASCII and binary) through trimesh.

Face colours are read and written (``red green blue alpha`` on the face
element). Vertex properties other than position, and vertex colours that
differ within a face, are reported as dropped. Writing flattens the scene
into one world-space mesh; binary little-endian by default. trimesh writes
coordinates as float32, welded after rounding, with no triangle left without
area (:func:`.assemble.at_float32`).

Triangle strips (a ``tristrips`` element of ``vertex_indices`` lists, -1 ending a strip: the Cyberware
scans of the Stanford repository) are read as triangles, alternate ones flipped to keep the strip's
winding, the triangles strips use as joints (two equal corners) dropped; rows of the element are strips
of their own.

A file that ends before the rows its header declares is a ``TRUNCATED``
error naming, per element, how many rows are complete (trimesh reads a cut
ASCII file as a smaller mesh without a word). A binary row is complete when
all its bytes are there, list lengths taken from the first row as trimesh
does; an ASCII row when its last line holds every value its properties and
list lengths call for. An ASCII file cut at the end of a line inside a
number, or a binary file cut at a row boundary of the last element, reads as
complete rows: only the row count tells, and it does.
"""

from __future__ import annotations

import os
import re
from functools import partial
from typing import BinaryIO

import numpy as np

from planefmt.errors import ConversionError
from planefmt.model import Scene, Units

from .assemble import flattened, float32_shift
from .dropped import PLY_ELEMENT
from .failures import describe
from .trimesh_bridge import read_scene, require_trimesh, scene_from_trimesh, write_flat


def sniff(head: bytes, size: int) -> bool:
    """PLY files start with the line ``ply``."""
    return head.startswith((b"ply\n", b"ply\r\n", b"ply\r"))


#: Properties the reader keeps or trimesh already reports (normals, texture coordinates, colours).
_KNOWN = {
    "vertex": {"x", "y", "z", "nx", "ny", "nz", "s", "t", "u", "v", "texture_u", "texture_v",
               "red", "green", "blue", "alpha"},
    "face": {"vertex_indices", "vertex_index", "red", "green", "blue", "alpha"},
    "tristrips": {"vertex_indices"},
}


def read(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    """Read a PLY file into ``(scene, dropped)``; a cut file is a ``TRUNCATED`` error."""
    file = os.fspath(path)
    try:
        _check_complete(file)
    except OSError as exc:
        raise ConversionError(f"cannot open: {exc.strerror or exc}", file=file) from exc
    elements = _header_elements(file)
    if elements.get("tristrips") and not elements.get("face"):
        scene, dropped = _read_strips(file)
    else:
        scene, dropped = read_scene(file, "ply", "PLY")
    return scene, sorted(dropped + _unused_properties(file))


def _header_elements(file: str) -> dict[str, int]:
    """The header's elements and their declared row counts (0 where the count is not a number)."""
    counts: dict[str, int] = {}
    with open(file, "rb") as handle:
        for raw in handle:
            words = raw.decode("ascii", "replace").split()
            if not words or words[0] == "end_header":
                break
            if words[0] == "element" and len(words) > 2:
                counts[words[1]] = int(words[2]) if words[2].isdigit() else 0
    return counts


def _read_strips(file: str) -> tuple[Scene, list[str]]:
    """A PLY of triangle strips: trimesh parses the elements (it makes no faces of strips), the strips
    become triangles here."""
    tm = require_trimesh("PLY")
    try:
        with open(file, "rb") as handle:
            kwargs = tm.exchange.ply.load_ply(handle)
        data = kwargs["metadata"]["_ply_raw"]["tristrips"]["data"]
        rows = data["vertex_indices"]
        # binary: one structured array of (length, items) rows; ASCII: one array per row
        rows = list(rows["f1"]) if getattr(rows, "dtype", None) is not None and rows.dtype.names else list(rows)
        faces = strip_triangles(rows, len(kwargs.get("vertices", ())))
        kwargs.pop("metadata")
        mesh = tm.Trimesh(faces=faces, process=False, **kwargs)
    except ConversionError as exc:
        raise exc.located(file=file)
    except MemoryError:
        raise
    except Exception as exc:  # noqa: BLE001 - trimesh raises anything on bad input
        raise ConversionError(f"cannot read as PLY: {describe(exc)}", file=file) from exc
    loaded = tm.Scene()
    # named after the file, as trimesh names a file's only mesh: the node is then left unnamed
    loaded.add_geometry(mesh, node_name=os.path.basename(file), geom_name=os.path.basename(file))
    scene, dropped = scene_from_trimesh(loaded, Units.UNSPECIFIED, file)
    if not any(node.mesh is not None for node in scene.nodes):
        raise ConversionError("no triangle mesh found in this PLY file", file=file)
    return scene, dropped


def strip_triangles(strips: list[np.ndarray], vertices: int) -> np.ndarray:
    """The triangles of triangle strips, ``(n, 3)``: each strip's triangle ``k`` is its corners
    ``k, k+1, k+2``, with the first two swapped for odd ``k`` (a strip alternates its winding); -1
    inside a strip ends it and starts another; triangles with two equal corners (a strip's joints)
    are dropped. An index outside the ``vertices`` is a ``ConversionError``."""
    if not strips:
        return np.zeros((0, 3), dtype=np.int64)
    parts = [np.asarray(strip, dtype=np.int64).reshape(-1) for strip in strips]
    # each row is a strip of its own: a -1 between rows
    flat = np.concatenate([np.append(part, -1) for part in parts])
    bad = (flat < -1) | (flat >= vertices)
    if bad.any():
        raise ConversionError(f"tristrips: vertex index {flat[bad][0]} is outside the {vertices:,} vertices")
    index = np.arange(len(flat))
    # where the strip holding each position began: one past the last -1 before it
    start = np.maximum.accumulate(np.where(flat < 0, index, -1)) + 1
    corners = np.stack([flat[:-2], flat[1:-1], flat[2:]], axis=1)
    odd = (index[:-2] - start[:-2]) % 2 == 1
    corners[odd] = corners[odd][:, [1, 0, 2]]
    keep = (corners >= 0).all(axis=1)
    keep &= (corners[:, 0] != corners[:, 1]) & (corners[:, 1] != corners[:, 2]) & (corners[:, 0] != corners[:, 2])
    return corners[keep]


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
            notes.append(f"{PLY_ELEMENT} {element}")
            continue
        extra = [name for name in properties if name not in _KNOWN[element]]
        if extra:
            notes.append(f"PLY {element} properties ({', '.join(extra)})")
    return notes


#: PLY's scalar types and their sizes in bytes.
_SIZES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2, "int16": 2, "uint16": 2,
          "int": 4, "uint": 4, "int32": 4, "uint32": 4, "float": 4, "float32": 4, "double": 8, "float64": 8}
#: The most bytes a header or an ASCII row is looked for in.
_HEADER_LIMIT = 1 << 16
_ENCODINGS = ("ascii", "binary_little_endian", "binary_big_endian")
_END_HEADER = re.compile(rb"^end_header[ \t]*(\r\n|\r|\n)", re.MULTILINE)


def _check_complete(file: str) -> None:
    """Raise ``TRUNCATED`` where the data ends before the rows the header declares (see the docstring)."""
    with open(file, "rb") as handle:
        head = handle.read(_HEADER_LIMIT)
        end = _END_HEADER.search(head)
        if end is None:
            if len(head) < _HEADER_LIMIT:
                raise ConversionError(f"the file ends after {len(head):,} bytes, inside the PLY header (no "
                                      "end_header line)", code="TRUNCATED", file=file)
            return  # no header this check can follow: trimesh says what is wrong
        encoding, elements = None, []
        for line in head[:end.start()].decode("ascii", "replace").splitlines():
            words = line.split()
            if len(words) >= 2 and words[0] == "format":
                encoding = words[1]
            elif len(words) >= 3 and words[0] == "element" and words[2].isdigit():
                elements.append((words[1], int(words[2]), []))
            elif len(words) >= 3 and words[0] == "property" and elements:
                elements[-1][2].append(words[1:-1])
        types = [kind[1:3] if kind[0] == "list" else kind[:1] for _, _, props in elements for kind in props]
        if encoding not in _ENCODINGS or not all(len(t) == len(set(t) & _SIZES.keys()) > 0 for t in types):
            return
        handle.seek(end.end())
        complete = (_ascii_rows(handle, elements) if encoding == "ascii"
                    else _binary_rows(handle, elements, big_endian=encoding == "binary_big_endian"))
    cut = [f"{name} {have:,} of {count:,}" for (name, count, _), have in zip(elements, complete) if have < count]
    if cut:
        raise ConversionError(f"PLY ends before the rows its header declares (complete rows: {', '.join(cut)}): "
                              "the file is cut short", code="TRUNCATED", file=file)


def _spread(rows: int, elements: list) -> list[int]:
    """``rows`` complete rows in file order, as complete rows per element."""
    complete = []
    for _, count, _ in elements:
        complete.append(min(rows, count))
        rows -= complete[-1]
    return complete


def _ascii_rows(handle: BinaryIO, elements: list) -> list[int]:
    """Complete rows per element of an ASCII body read from ``handle``: one row per line (blank lines at
    the end not counted), the last line short of a row where it lacks a value its properties call for."""
    newlines = returns = 0
    tail = b""
    for block in iter(partial(handle.read, 1 << 20), b""):
        newlines += block.count(b"\n")
        returns += block.count(b"\r")
        tail = (tail + block)[-_HEADER_LIMIT:]
    text = tail.rstrip()
    blank = tail[len(text):]
    lines = newlines - blank.count(b"\n") if newlines else returns - blank.count(b"\r")
    lines += bool(text)
    total = sum(count for _, count, _ in elements)
    if lines > total or not lines:
        return _spread(lines, elements)
    last = text[max(text.rfind(b"\n"), text.rfind(b"\r")) + 1:].split()
    row = lines - 1  # the last line's row in file order
    for _, count, props in elements:
        if row < count:
            break
        row -= count
    needed = 0
    for kind in props:
        if kind[0] == "list" and needed < len(last):
            length = last[needed]
            needed += 1 + (int(length) if length.isdigit() else len(last))
        else:
            needed += 1
    return _spread(lines - (len(last) < needed), elements)


def _binary_rows(handle: BinaryIO, elements: list, big_endian: bool) -> list[int]:
    """Complete rows per element of a binary body, each list's length taken from the element's first row
    (as trimesh reads them). An element whose first row is cut before its list lengths has no complete row."""
    start = handle.tell()
    left = os.fstat(handle.fileno()).st_size - start
    complete = []
    for _, count, props in elements:
        size = 0
        for kind in props:
            if kind[0] != "list":
                size += _SIZES[kind[0]]
                continue
            length_size, item_size = _SIZES[kind[1]], _SIZES[kind[2]]
            if left < size + length_size:
                size = None
                break
            handle.seek(start + size)
            length = int.from_bytes(handle.read(length_size), "big" if big_endian else "little")
            size += length_size + length * item_size
        rows = 0 if size is None else min(count, left // size) if size else count
        complete.append(rows)
        left -= rows * (size or 0)
        start += rows * (size or 0)
    return complete


def write(scene: Scene, path: str | os.PathLike[str], *, ascii: bool = False) -> list[str]:
    """Write ``scene`` as one PLY mesh, binary unless ``ascii``; returns what PLY lacks."""
    export = partial(require_trimesh("PLY").exchange.ply.export_ply,
                     encoding="ascii" if ascii else "binary",
                     vertex_normal=False, include_attributes=False)
    return write_flat(scene, path, what="PLY", export=export, colours=True, float32=True)


def rounding(scene: Scene) -> float:
    """How far writing ``scene`` moves its surface, as a fraction of its diagonal: world coordinates to float32."""
    return float32_shift(flattened(scene))
