"""The geometry codec: triangle meshes to part groups of planes and back, with verified error.

Conventions (spec §2.3): planes ``(omega, h)`` with outward unit normals,
the solid where ``omega . x <= h``; triplets ``(nu, phi, h)`` in radians,
radians, model units; triangles counter-clockwise seen from outside.
Tolerances and error bounds are **fractions of the bounding-box diagonal**;
distances are otherwise in model units.

Encoding a mesh (:func:`encode_mesh`):

1. Vertices are welded by position and adjacent coplanar triangles merged
   into polygons, one plane each (:mod:`planefmt.geometry.polygonize`, coplanarity
   tolerance ``min(5e-7, tolerance / 2)`` of the diagonal).
2. Lossy options of the paper (§5 there): ``tau`` merges neighbouring planes
   whose normals differ by less than ``tau`` radians, ``delta`` drops planes
   whose faces cover less than ``delta`` of the total area.
3. The mesh is split into bodies (edge-connected pieces). Each body goes to
   the first strategy of :data:`BODY_STRATEGIES` that takes it; a strategy
   returns the body's part groups: a closed, outward, convex body (within
   the tolerance) one ``CONVEX`` group; any other body what
   :func:`planefmt.groups.bodies.encode_body` makes of it (a ``BSP`` group for a
   closed solid, a ``SEALED`` group for a closed body no tree decodes with
   its topology, else pseudo-convex / pseudo-concave patches).
4. The triplet coding is chosen and **verified**: each candidate's planes go
   through :func:`quantize.roundtrip` (exactly what a reader gets back), are
   decoded, and the two-sided Hausdorff distance between decoded and source
   surface is measured (:func:`planefmt.geometry.hausdorff.hausdorff`); a candidate
   must meet the tolerance and keep the source's structure
   (:func:`structure_kept`). A first-order prediction of the vertex
   displacement (planes re-intersected at each decoded vertex) skips widths
   that cannot pass without decoding them: where faces meet at a small angle
   the vertex error grows like ``1 / sin angle``, so the angles, not ``h``,
   set the widths. Among the remaining quantized widths the narrowest that
   passes is found by bisection (coarse planes can drop a thin cell of a BSP
   solid where finer ones keep it, so a few failures at the narrow end say
   nothing of the rest); if none passes, float32, then float64. The winner's
   measured error is the header's ``error_bound``.
5. At a lossy tolerance, where a body kept a hull-first BSP tree, steps 3–4
   run again with the flat splitter strategies and the smaller file is kept
   (:func:`planefmt.codec.encoding._encode_objects`; :func:`encode_scene` does the same per scene).

Decoding dispatches on ``group.kind`` through :data:`DECODERS`.

The modules, in the order data flows through them:

* :mod:`.decoding`: one decoder per part-group kind, the plane error a coding allows;
* :mod:`.strategies`: bodies to part groups (the paper's scheme and the shell scheme);
* :mod:`.lossy`: the paper's ``tau`` and ``delta``;
* :mod:`.preparing`: a mesh welded, polygonized and encoded body by body; the structure it must keep;
* :mod:`.verifying`: certified distances between a decoding and its source;
* :mod:`.choosing`: the triplet coding, verified;
* :mod:`.encoding`: :func:`encode_mesh`, :func:`encode_scene`;
* :mod:`.scenes`: :func:`decode_scene`, :func:`decode_mesh`, :func:`salvage_scene`;
* :mod:`.checks`: :func:`validate` with the geometry checks.

Names with a leading underscore are shared among these modules only.
"""

# The model's types and the verification budget that the codec's signatures and results use.
from ..geometry.hausdorff import DEFAULT_MAX_PIECES
from ..model import Coding, GroupKind, Mesh
from .checks import check_group, validate
from .choosing import MAX_BITS, MIN_BITS, SHELL_WIDTHS
from .decoding import (DECODERS, EXACT, SHELL_KINDS, DecodedGroup, GroupLike, PlaneError, decode_bsp, decode_cells,
                       decode_convex_group, decode_group, decode_groups, decode_patch, decode_sealed_group,
                       decode_shell_group, header_plane_error, plane_error)
from .encoding import Encoded, encode_mesh, encode_scene
from .lossy import drop_planes, merge_planes
from .preparing import LOSSLESS_TOLERANCE, SOLID_KINDS, STRUCTURE_TOLERANCE, structure_kept, structure_problem
from .scenes import UNCOLOURED, decode_mesh, decode_scene, salvage_scene, skipped_groups
from .strategies import (BODY_STRATEGIES, CONVEX_MAX_PLANES, SCHEMES, SHELL_STRATEGIES, Body, GroupSpec,
                         encode_convex_body, encode_convex_or_shell, encode_general_body, encode_shell_body,
                         is_convex)

__all__ = [
    "BODY_STRATEGIES", "Body", "CONVEX_MAX_PLANES", "Coding", "DECODERS", "DEFAULT_MAX_PIECES", "DecodedGroup",
    "EXACT", "Encoded", "GroupKind", "GroupLike", "GroupSpec", "LOSSLESS_TOLERANCE", "MAX_BITS", "MIN_BITS", "Mesh",
    "PlaneError", "SCHEMES", "SHELL_KINDS", "SHELL_STRATEGIES", "SHELL_WIDTHS", "SOLID_KINDS", "STRUCTURE_TOLERANCE",
    "UNCOLOURED", "check_group", "decode_bsp", "decode_cells", "decode_convex_group", "decode_group",
    "decode_groups", "decode_mesh", "decode_patch", "decode_scene", "decode_sealed_group", "decode_shell_group",
    "drop_planes", "encode_convex_body", "encode_convex_or_shell", "encode_general_body", "encode_mesh",
    "encode_scene", "encode_shell_body", "header_plane_error", "is_convex", "merge_planes", "plane_error",
    "salvage_scene", "skipped_groups", "structure_kept", "structure_problem", "validate",
]
