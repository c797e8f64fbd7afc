"""planefmt: the reference implementation of the .pln format, 3D meshes stored as planes.

Conventions: a plane is the triplet (nu, phi, h) of spec/pln.md §2.3: nu in
[0, pi] and phi in [0, 2*pi) in radians give the outward unit normal omega,
h the signed distance in model units; the solid lies where omega . x <= h.
"""

from .chunks import Limits, chunk_bytes
from .errors import (CODES, ChecksumError, ConversionError, FormatError, GeometryError, LimitError,
                     PlnError, PlnWarning, SkippedGroupsWarning, TruncatedError, VersionError)
from .model import (UP_AXES, UP_AXIS, Coding, Colours, GroupKind, Header, Mesh, Metadata, Node, ObjectRecord,
                    PartGroup, PlaneBlock, Quantization, Scene, UnknownChunk, Units)
from .reader import Reader, open
from .writer import Writer

__version__ = "0.1.0"

#: The geometry codec's entry points, loaded on first use: they pull in scipy, which a reader
#: that only walks the container (``pln info`` on a pipe) should not pay for.
_CODEC = ("decode_mesh", "decode_scene", "encode_mesh", "encode_scene", "salvage_scene")


def __getattr__(name: str):
    if name in _CODEC:
        from . import codec

        return getattr(codec, name)
    raise AttributeError(f"module 'planefmt' has no attribute {name!r}")


__all__ = [
    "CODES", "ChecksumError", "Coding", "Colours", "ConversionError", "FormatError", "GeometryError",
    "GroupKind", "Header", "Limits", "LimitError", "Mesh", "Metadata", "Node", "ObjectRecord", "PartGroup",
    "PlaneBlock", "PlnError", "PlnWarning", "Quantization", "Reader", "Scene", "SkippedGroupsWarning",
    "TruncatedError", "UP_AXES", "UP_AXIS", "UnknownChunk", "Units", "VersionError", "Writer", "chunk_bytes",
    "decode_mesh", "decode_scene", "encode_mesh", "encode_scene", "open", "salvage_scene",
]
