"""STL (binary and ASCII) through trimesh.

STL is a triangle soup of float32 coordinates: the reader merges equal
positions back into shared vertices (see :mod:`.assemble`). Writing
flattens the scene into one world-space mesh, binary by default, welded
after float32 rounding with no triangle left without area
(:func:`.assemble.at_float32`); STL has no units, names or colours (the
vendor colour conventions are not used).

A cut file is a ``TRUNCATED`` error, not a smaller mesh: a binary STL
shorter than its declared facet count, or an ASCII STL whose last solid has
no ``endsolid`` (trimesh would drop that solid without a word). An ASCII
file cut exactly after an ``endsolid`` line is a valid file of fewer solids
and cannot be told from one.
"""

from __future__ import annotations

import os
import re

from planefmt.errors import ConversionError
from planefmt.model import Scene

from .assemble import flattened, float32_shift
from .trimesh_bridge import read_scene, require_trimesh, write_flat

_BINARY_HEADER = 84  # 80-byte header + uint32 triangle count
_BINARY_TRIANGLE = 50  # normal, three corners (float32) and a uint16 attribute
#: The lines that open and close a solid of an ASCII STL.
_SOLID = re.compile(rb"^[ \t]*(end)?solid\b([^\r\n]*)", re.IGNORECASE | re.MULTILINE)
_ENDFACET = re.compile(rb"\bendfacet\b", re.IGNORECASE)


def sniff(head: bytes, size: int) -> bool:
    """Binary STL: the size matches the triangle count. ASCII: ``solid`` … ``facet``."""
    if size >= _BINARY_HEADER and len(head) >= _BINARY_HEADER:
        count = int.from_bytes(head[80:84], "little")
        if size == _BINARY_HEADER + _BINARY_TRIANGLE * count:
            return True
    text = head.lstrip()
    return text[:5].lower() == b"solid" and (b"facet" in text or b"endsolid" in text)


def read(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    """Read an STL file into ``(scene, dropped)``; a cut file is a ``TRUNCATED`` error."""
    file = os.fspath(path)
    try:
        _check_complete(file)
    except OSError as exc:
        raise ConversionError(f"cannot open: {exc.strerror or exc}", file=file) from exc
    return read_scene(file, "stl", "STL")


def _check_complete(file: str) -> None:
    """Raise ``TRUNCATED`` where the file ends before what it declares (see the module's docstring)."""
    size = os.path.getsize(file)
    with open(file, "rb") as handle:
        head = handle.read(_BINARY_HEADER)
        declared = int.from_bytes(head[80:84], "little") if len(head) == _BINARY_HEADER else None
        if declared is not None and size == _BINARY_HEADER + _BINARY_TRIANGLE * declared:
            return
        # A binary STL's floats hold zero bytes within its first facets (0.0, 1.0), text never does.
        text = head.lstrip()[:5].lower() == b"solid" and b"\0" not in head[80:] + handle.read(4096)
        if text:
            handle.seek(0)
            _check_ascii(handle.read(), file)
            return
    if declared is None:
        raise ConversionError(f"the file ends after {size} bytes, inside the {_BINARY_HEADER}-byte header of a "
                              "binary STL", code="TRUNCATED", file=file)
    expected = _BINARY_HEADER + _BINARY_TRIANGLE * declared
    if size < expected:
        complete = (size - _BINARY_HEADER) // _BINARY_TRIANGLE
        raise ConversionError(f"binary STL declares {declared:,} facets ({expected:,} bytes) but the file ends after "
                              f"{size:,} bytes: only {complete:,} facets are complete, {declared - complete:,} are "
                              "missing", code="TRUNCATED", file=file)
    raise ConversionError(f"binary STL declares {declared:,} facets ({expected:,} bytes) but the file has "
                          f"{size - expected:,} bytes more", file=file)


def _check_ascii(data: bytes, file: str) -> None:
    """An ASCII STL must close its last solid: a cut file ends inside one."""
    last = None
    for last in _SOLID.finditer(data):
        pass
    if last is None or last.group(1):
        return
    name = last.group(2).decode("utf-8", "replace").strip()
    complete = len(_ENDFACET.findall(data, last.end()))
    solids = sum(1 for match in _SOLID.finditer(data, 0, last.start()) if not match.group(1))
    raise ConversionError(f"ASCII STL ends inside its solid {solids + 1}, {name!r}, which has no endsolid: the file is "
                          f"cut short, and reading it would drop that solid ({complete:,} complete facets and what "
                          "the cut took)", code="TRUNCATED", file=file)


def write(scene: Scene, path: str | os.PathLike[str], *, ascii: bool = False) -> list[str]:
    """Write ``scene`` as one STL mesh, binary unless ``ascii``; returns what STL lacks."""
    exchange = require_trimesh("STL").exchange.stl
    export = exchange.export_stl_ascii if ascii else exchange.export_stl
    return write_flat(scene, path, what="STL", export=export, colours=False, float32=True)


def rounding(scene: Scene) -> float:
    """How far writing ``scene`` moves its surface, as a fraction of its diagonal: world coordinates to float32."""
    return float32_shift(flattened(scene))
