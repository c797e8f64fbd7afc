"""planefmt: the reference implementation of the .pln format, 3D meshes stored as planes.

Conventions: a plane is the triplet (nu, phi, h) of spec/pln.md §2.3: nu in
[0, pi] and phi in [0, 2*pi) in radians give the outward unit normal omega,
h the signed distance in model units; the solid lies where omega . x <= h.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .codec import decode_mesh, decode_scene, encode_mesh, encode_scene, salvage_scene
    from .container.chunks import chunk_bytes
    from .container.limits import Limits
    from .errors import (CODES, ChecksumError, ConversionError, FormatError, GeometryError, LimitError,
                         PlnError, PlnWarning, SkippedGroupsWarning, TruncatedError, VersionError)
    from .model import (UP_AXES, UP_AXIS, Coding, Colours, GroupKind, Header, Mesh, Metadata, Node,
                        ObjectRecord, PartGroup, PlaneBlock, Quantization, Scene, UnknownChunk, Units)
    from .container.reader import Reader, open
    from .container.writer import Writer

__version__ = "0.1.0"

#: The module each public name comes from, imported on first use (PEP 562): ``pln --version`` imports
#: planefmt and must not pay for numpy and construct (container, model), nor the codec's scipy (which a
#: reader that only walks the container, ``pln info``, does not need either).
_HOMES = {
    "Limits": "container.limits",
    "chunk_bytes": "container.chunks",
    **dict.fromkeys(("CODES", "ChecksumError", "ConversionError", "FormatError", "GeometryError", "LimitError",
                     "PlnError", "PlnWarning", "SkippedGroupsWarning", "TruncatedError", "VersionError"), "errors"),
    **dict.fromkeys(("UP_AXES", "UP_AXIS", "Coding", "Colours", "GroupKind", "Header", "Mesh", "Metadata", "Node",
                     "ObjectRecord", "PartGroup", "PlaneBlock", "Quantization", "Scene", "UnknownChunk", "Units"),
                    "model"),
    **dict.fromkeys(("Reader", "open"), "container.reader"),
    "Writer": "container.writer",
    **dict.fromkeys(("decode_mesh", "decode_scene", "encode_mesh", "encode_scene", "salvage_scene"), "codec"),
}

#: The modules that ``import planefmt`` made attributes of it when it imported the names above at once;
#: ``planefmt.container`` brings its reader and writer, as then (``planefmt.container.quantize`` resolves).
_MODULES = ("container", "errors", "model")


def __getattr__(name: str):
    if name in _HOMES:
        value = getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
    elif name in _MODULES:
        value = importlib.import_module(f"{__name__}.{name}")
        if name == "container":
            importlib.import_module(f"{__name__}.container.reader")
            importlib.import_module(f"{__name__}.container.writer")
    else:
        raise AttributeError(f"module 'planefmt' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


__all__ = [
    "CODES", "ChecksumError", "Coding", "Colours", "ConversionError", "FormatError", "GeometryError",
    "GroupKind", "Header", "Limits", "LimitError", "Mesh", "Metadata", "Node", "ObjectRecord", "PartGroup",
    "PlaneBlock", "PlnError", "PlnWarning", "Quantization", "Reader", "Scene", "SkippedGroupsWarning",
    "TruncatedError", "UP_AXES", "UP_AXIS", "UnknownChunk", "Units", "VersionError", "Writer", "chunk_bytes",
    "decode_mesh", "decode_scene", "encode_mesh", "encode_scene", "open", "salvage_scene",
]
