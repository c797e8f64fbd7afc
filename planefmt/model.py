"""The in-memory model of a .pln file: small frozen records holding numpy arrays.

Conventions used throughout planefmt:

* A plane triplet is ``(nu, phi, h)``: ``nu`` in [0, pi] radians is the angle
  of the outward unit normal ``omega`` from +z, ``phi`` in [0, 2*pi) radians
  the angle of its xy-projection from +x, ``h`` the signed distance in model
  units, so that the plane is ``omega . x = h`` and the solid side (the closed
  negative half-space) is ``omega . x <= h``.
* Triplet arrays are ``float64`` of shape ``(n, 3)``.
* Transforms are 4x4 ``float64`` row-major affine matrices acting on column
  vectors ``(x, y, z, 1)``: object-local coordinates to the parent's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # numpy in annotations and one method only: the command line's parsers (``pln --version``)
    import numpy as np  # use the model's names without loading it


class Coding(IntEnum):
    """How plane triplets are stored in PLNS chunks (spec §7)."""

    FLOAT32 = 0
    FLOAT64 = 1
    QUANTIZED = 2
    #: Version 2: the codes of QUANTIZED, each predicted from the previous plane's (spec §7.4).
    PREDICTED = 3

    @property
    def quantized(self) -> bool:
        """Whether planes are integer codes of the header's widths and h range (codings 2 and 3)."""
        return self in (Coding.QUANTIZED, Coding.PREDICTED)


class Units(IntEnum):
    """Length unit of coordinates and ``h`` (spec §5)."""

    UNSPECIFIED = 0
    METRE = 1
    CENTIMETRE = 2
    MILLIMETRE = 3
    MICROMETRE = 4
    KILOMETRE = 5
    INCH = 6
    FOOT = 7


class GroupKind(IntEnum):
    """Part group kinds: 0-4 of version 1.0 (spec §9), 5 of version 3.1 (spec §9.9), 6 of
    version 3.2 (spec §9.10), 7 of version 3.3 (spec §9.11), 8 of version 3.4 (spec §9.12), 9 of
    version 4.1 (spec §9.13)."""

    CONVEX = 0
    CELLS = 1
    BSP = 2
    PSEUDO_CONVEX = 3
    PSEUDO_CONCAVE = 4
    SEALED = 5
    SHELL = 6
    SHELL_TREE = 7
    SHELL_TREE_PARALLELOGRAM = 8
    SHELL_WALK = 9
    SHELL_WALK_MULTI = 10
    COPY = 11
    SHELL_WALK_REFLECT = 12
    SHELL_WALK_LATER = 13


#: The shell trees (spec §9.11): kind 7, kind 8 whose explicit corners parallelograms predict (§9.12),
#: kind 9 whose tree and corners are coded as a walk (§9.13), and kind 10, a walk whose explicit corners
#: averaged parallelograms predict (§9.14), kind 12, a walk whose explicit corners a turning chain of
#: steps predicts (§9.16), and kind 13, a walk whose explicit corners step from the later-named corner
#: of their gate (§9.17).
TREE_KINDS = (GroupKind.SHELL_TREE, GroupKind.SHELL_TREE_PARALLELOGRAM, GroupKind.SHELL_WALK,
              GroupKind.SHELL_WALK_MULTI, GroupKind.SHELL_WALK_REFLECT, GroupKind.SHELL_WALK_LATER)
#: The kinds of shell groups, which the encoder chooses between by size once their corners are known
#: (:data:`planefmt.codec.choosing.SHELL_LAYOUTS`).
SHELL_KINDS = (GroupKind.SHELL, *TREE_KINDS)


#: BSP tree leaf tokens in version 1.0's numbering (spec Appendix A.1), which the model uses for every
#: version (spec §9.7 codes IN 0, OUT 1, a split on j as j + 2); every smaller token is a split plane.
BSP_IN = 0xFFFFFFFE
BSP_OUT = 0xFFFFFFFF
BSP_MAX_SPLIT = 0xFFFFFFEF

#: Sentinel for "no parent" in object records.
NO_PARENT = 0xFFFFFFFF


@dataclass(frozen=True)
class Quantization:
    """Bit widths and the ``h`` range of the quantized coding (spec §7.3)."""

    bits_nu: int
    bits_phi: int
    bits_h: int
    h_min: float
    h_max: float

    @property
    def bits_per_plane(self) -> int:
        return self.bits_nu + self.bits_phi + self.bits_h

    def steps(self) -> tuple[float, float, float]:
        """Quantization step of nu (rad), phi (rad) and h (model units)."""
        h_step = (self.h_max - self.h_min) / ((1 << self.bits_h) - 1)
        return (math.pi / (1 << (self.bits_nu - 1)),
                2.0 * math.pi / (1 << self.bits_phi),
                h_step)


@dataclass(frozen=True)
class Header:
    """The PHDR chunk (spec §5). Counts are ``None`` where the writer did not know them."""

    version: tuple[int, int] = (1, 0)
    lossy: bool = False
    coding: Coding = Coding.FLOAT64
    quantization: Quantization | None = None
    units: Units = Units.UNSPECIFIED
    bbox: np.ndarray | None = None  # (2, 3) float64: min corner, max corner
    tolerance: float = math.nan  # requested, relative to the bbox diagonal
    error_bound: float = math.nan  # verified two-sided Hausdorff / bbox diagonal
    plane_count: int | None = None
    object_count: int | None = None
    group_count: int | None = None
    extra: bytes = b""  # trailing PHDR bytes of a newer minor version, kept verbatim
    up_axis: str | None = None  # version 5: the world axis that points up, "Y" or "Z" (spec §5); before, mETA

    @property
    def diagonal(self) -> float:
        """Length of the bounding-box diagonal in model units (NaN if no bbox)."""
        import numpy as np

        if self.bbox is None:
            return math.nan
        return float(np.linalg.norm(self.bbox[1] - self.bbox[0]))


@dataclass(frozen=True)
class ObjectRecord:
    """An OBJT chunk: a named node of the scene (spec §8)."""

    index: int
    name: str
    parent: int | None = None
    transform: np.ndarray | None = None  # (4, 4) float64, local -> parent


@dataclass(frozen=True)
class PlaneBlock:
    """A PLNS chunk: planes ``first .. first+len(triplets)-1`` of the plane table."""

    first: int
    triplets: np.ndarray  # (n, 3) float64, dequantized where quantized


#: Face reference of a free triangle (no face plane), in :attr:`Shell.facets`.
FREE = -1
#: Largest magnitude of a grid coordinate (spec §9.10): integers of float64 exactly.
MAX_GRID = 1 << 52


@dataclass(frozen=True)
class Shell:
    """A shell group's corners and triangles in local references.

    ``explicit`` (V,) bool: which corners store coordinates; ``vertex_planes``
    (N, 3) the three references of each named corner, in corner order;
    ``grid`` (E, 3) int64 the integer coordinates of each explicit corner, in
    corner order, at ``origin + step * grid`` (model units); ``facets`` (T, 4)
    each triangle's face reference (:data:`FREE` for none) and its three
    corners, planar triangles in non-decreasing face order, then free ones;
    corners numbered in order of first use.

    A shell tree (kind 7, spec 3.3 §8.10) has ``links`` (T,): 0 for a root
    triangle, ``3 * (d - 1) + e + 1`` for one attached to edge ``e`` of the
    triangle ``d`` before it; its triangles are in that order (any face order),
    each starting with the gate edge it shares with its parent, and its named
    corners' references ascending.
    """

    explicit: np.ndarray
    vertex_planes: np.ndarray
    grid: np.ndarray
    origin: np.ndarray
    step: float
    facets: np.ndarray
    links: np.ndarray | None = None

    def __repr__(self) -> str:
        return (f"Shell({len(self.explicit)} corners, {len(self.vertex_planes)} named, "
                f"{len(self.facets)} triangles, step {self.step:g})")



@dataclass(frozen=True)
class PartGroup:
    """A GRUP chunk (spec §9).

    ``refs`` are indices into the file's plane table; ``bounding[i]`` is True
    where ``refs[i]`` is a bounding or cut plane rather than a face plane.
    For CELLS groups, ``cells`` holds one uint32 array per convex cell whose
    entries are ``2 * local + complement`` (``local`` indexes ``refs``;
    ``complement`` 1 means the half-space ``omega . x >= h``). For BSP groups,
    ``tree`` holds the preorder tokens of spec §9.7 in version 1.0's numbering (:data:`BSP_IN`,
    :data:`BSP_OUT`, a split on j as j). For SEALED groups,
    ``vertex_planes`` (V, 3) holds each vertex's three local references and
    ``facets`` (T, 4) each triangle's face local reference and three vertices
    (spec §9.9). ``planes`` holds the referenced triplets when the reader
    resolved them.
    """

    index: int
    object: int
    kind: GroupKind | int  # an int for a kind of a newer minor version, which this reader does not know
    refs: np.ndarray  # (m,) uint32
    bounding: np.ndarray  # (m,) bool
    cells: tuple[np.ndarray, ...] | None = None
    tree: np.ndarray | None = None
    extra: bytes = b""  # kind-specific bytes of a kind this reader does not know
    vertex_planes: np.ndarray | None = None  # (V, 3) uint32, SEALED groups
    facets: np.ndarray | None = None  # (T, 4) uint32, SEALED groups
    shell: Shell | None = None  # SHELL groups
    planes: np.ndarray | None = field(default=None, compare=False)
    #: A copy's source group (spec §9.15): a reader gives a copy its source's kind and surface, and this.
    source: int | None = None

    def __repr__(self) -> str:
        kind = self.kind.name if isinstance(self.kind, GroupKind) else self.kind
        return f"PartGroup({self.index}, object={self.object}, kind={kind}, {len(self.refs)} refs)"


@dataclass(frozen=True)
class Colours:
    """A cOLR chunk: one RGBA8 colour per reference of a part group (spec §10.1)."""

    group: int
    rgba: np.ndarray  # (m, 4) uint8


#: The mETA keyword naming the axis that points up (spec §10.3), and its values.
UP_AXIS = "up_axis"
UP_AXES = ("Y", "Z")


@dataclass(frozen=True)
class Metadata:
    """A mETA chunk: one keyword and its text value (spec §10.3).

    ``key`` is 1 to 79 characters of printable ASCII without space; ``value`` any text. The
    keyword :data:`UP_AXIS` has the value ``"Y"`` or ``"Z"``.
    """

    key: str
    value: str


@dataclass(frozen=True)
class UnknownChunk:
    """An ancillary chunk this implementation does not interpret, kept verbatim."""

    type: bytes
    payload: bytes
    offset: int | None = None


Record = ObjectRecord | PlaneBlock | PartGroup | Colours | Metadata | UnknownChunk


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh: the geometry converters and the codec exchange.

    ``vertices`` (n, 3) float64 in model units; ``faces`` (m, 3) int64 indices,
    counter-clockwise seen from outside (right-hand rule gives the outward
    normal); ``face_colours`` (m, 4) uint8 RGBA or None.
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_colours: np.ndarray | None = None

    # Short reprs: the default one prints whole arrays (a million vertices in a traceback or a REPL).
    def __repr__(self) -> str:
        colours = "" if self.face_colours is None else ", face colours"
        return f"Mesh({len(self.vertices)} vertices, {len(self.faces)} faces{colours})"


@dataclass(frozen=True)
class Node:
    """A scene node: a name, its parent node index, a local transform, an optional mesh."""

    name: str
    parent: int | None = None
    transform: np.ndarray | None = None  # (4, 4) float64, local -> parent
    mesh: Mesh | None = None

    def __repr__(self) -> str:
        transform = "" if self.transform is None else ", transform"
        return f"Node({self.name!r}, parent={self.parent}{transform}, mesh={self.mesh!r})"


@dataclass(frozen=True)
class Scene:
    """Nodes in an order where every parent precedes its children.

    ``up_axis`` is the world axis that points up, away from the ground (spec §10.3): ``"Y"``
    (+y up: glTF's convention, USD's default) or ``"Z"`` (+z up: USD ``upAxis = "Z"``, most CAD),
    or None where the source does not say (OBJ, PLY, STL, OFF). Coordinates are right-handed and
    kept as authored whatever the axis: it tells viewers which way is up, and converters to a
    format with a fixed up axis (glTF: Y) rotate the scene into it.
    """

    nodes: tuple[Node, ...]
    units: Units = Units.UNSPECIFIED
    up_axis: str | None = None

    def __repr__(self) -> str:
        meshes = {id(node.mesh) for node in self.nodes if node.mesh is not None}
        up = "" if self.up_axis is None else f", up_axis={self.up_axis}"
        return f"Scene({len(self.nodes)} nodes, {len(meshes)} meshes, units={self.units.name}{up})"
