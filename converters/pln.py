"""The .pln format itself, through planefmt's codec, as one more registry entry."""

from __future__ import annotations

import os
import warnings
from dataclasses import replace

import numpy as np

from planefmt.container.chunks import Limits
from planefmt.errors import GeometryError, PlnWarning, SkippedGroupsWarning
from planefmt.model import GroupKind, Mesh, Scene

from .assemble import build_mesh, instancing_note, with_area, world_transforms

SIGNATURE_TAIL = b"PLN"


def sniff(head: bytes, size: int) -> bool:
    """The .pln signature, also when a text-mode transfer damaged it (the reader then says so)."""
    return len(head) >= 4 and head[1:4] == SIGNATURE_TAIL and head[0] in (0x89, 0x09)


def read(path: str | os.PathLike[str], limits: Limits | None = None) -> tuple[Scene, list[str]]:
    """The scene of a .pln file and what decoding skipped; ``limits`` the reader's (spec §12.4)."""
    # The codec (scipy) loads only when a .pln is decoded or encoded, not for `pln info`.
    from planefmt import codec

    # Decoding warns of what it skipped (groups of a newer minor version's kinds): that was dropped.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlnWarning)
        scene = codec.decode_scene(path, limits=limits)
    return scene, [w.what if isinstance(w, SkippedGroupsWarning) else str(w) for w in _pln_warnings(caught)]


def write(scene: Scene, path: str | os.PathLike[str], *, tolerance: float = 1e-6, bits=None, coding=None,
          delta: float | None = None, tau: float | None = None, compress: bool = True,
          compact: bool = True, watertight: bool = True, scheme: str = "shell", major: int = 6,
          keep_corners: bool = False, keep_triangles: bool = False) -> list[str]:
    """Encode ``scene`` (atomically); face colours go into cOLR chunks, one colour per plane.

    Returns what the encoder gave up (its :class:`PlnWarning` lines): with
    ``watertight=False``, the closedness of solids that planes cannot close.
    """
    from planefmt import codec

    scene, dropped = without_zero_area(scene)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlnWarning)
        header = codec.encode_scene(scene, path, tolerance=tolerance, bits=bits, coding=coding, delta=delta,
                                    tau=tau, compress=compress, compact=compact, watertight=watertight, major=major,
                                    scheme=scheme, keep_corners=keep_corners, keep_triangles=keep_triangles)
    notes = [f"{dropped} zero-area triangle{'s' if dropped > 1 else ''} (no plane to store)"] if dropped else []
    instancing = instancing_note(scene)
    if instancing:
        notes.append(instancing)
    if header.error_bound > header.tolerance:
        # Only a forced coding gets here: the codec refuses any other that misses the tolerance.
        notes.append(f"the tolerance {header.tolerance:g} (the forced coding measured {header.error_bound:.3g} of "
                     "the diagonal; the file is marked lossy)")
    return notes + [str(w) for w in _pln_warnings(caught)]


def beyond_version_1(path: str | os.PathLike[str]) -> tuple[tuple[int, int], list[str]]:
    """The version of the .pln file at ``path`` and, in order of kind, the names of its group kinds
    that version 1.0 does not have (5 and up: sealed, shell, ...): why a file written with
    ``compact=False`` is not 1.0."""
    import planefmt

    with planefmt.open(path) as r:
        if r.header.version == (1, 0):
            return r.header.version, []
        kinds = sorted({GroupKind(g.kind) for g in r.part_groups() if g.kind >= GroupKind.SEALED})
        return r.header.version, [k.name.lower().replace("_", " ") for k in kinds]


#: The header's bounding box is float32 (spec §5): a coordinate beyond this cannot be recorded.
FLOAT32_MAX = float(np.finfo(np.float32).max)

#: The codec's plane arithmetic squares cross products of edges (edge length to the fourth power), which
#: underflows float64 below about 1e-77; this leaves room for triangles smaller than their mesh (a
#: tetrahedron 1e-60 across encodes, one 1e-100 across does not).
SMALLEST_DIAGONAL = 1e-60


def without_zero_area(scene: Scene) -> tuple[Scene, int]:
    """``scene`` without its zero-area triangles (which have no plane), and how many were dropped.

    Raises :class:`GeometryError` (``DEGENERATE_GEOMETRY``) when no triangle is left, and
    for coordinates a .pln header cannot record.
    """
    cleaned: dict[int, Mesh | None] = {}
    dropped = 0
    for node, world in zip(scene.nodes, world_transforms(scene)):
        mesh = node.mesh
        if mesh is None:
            continue
        placed = mesh.vertices @ world[:3, :3].T + world[:3, 3]
        largest = np.abs(placed).max(initial=0.0)
        if not largest <= FLOAT32_MAX:
            raise GeometryError(f"coordinates up to {largest:.3g} are beyond the float32 "
                                f"range (±{FLOAT32_MAX:.3g}) of a .pln bounding box", code="DEGENERATE_GEOMETRY")
        diagonal = float(np.linalg.norm(np.ptp(placed, axis=0))) if len(placed) else 0.0
        if 0 < diagonal < SMALLEST_DIAGONAL:
            raise GeometryError(f"a mesh {diagonal:.3g} across is too small for the plane arithmetic (at least "
                                f"{SMALLEST_DIAGONAL:g}): scale it up", code="DEGENERATE_GEOMETRY")
        if id(mesh) not in cleaned:
            keep = with_area(mesh.vertices, mesh.faces)
            dropped += int(len(keep) - np.count_nonzero(keep))
            cleaned[id(mesh)] = mesh if keep.all() else build_mesh(
                mesh.vertices, mesh.faces[keep],
                None if mesh.face_colours is None else mesh.face_colours[keep], what=node.name)[0]
    if not any(kept is not None for kept in cleaned.values()):
        raise GeometryError("every triangle has zero area (its corners are collinear): no plane to store",
                            code="DEGENERATE_GEOMETRY")
    if not dropped:
        return scene, 0
    nodes = tuple(replace(node, mesh=None if node.mesh is None else cleaned[id(node.mesh)]) for node in scene.nodes)
    return replace(scene, nodes=nodes), dropped


def _pln_warnings(caught: list[warnings.WarningMessage]) -> list[PlnWarning]:
    """The :class:`PlnWarning` instances among ``caught``; other warnings are issued again."""
    for w in caught:
        if not issubclass(w.category, PlnWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return [w.message for w in caught if issubclass(w.category, PlnWarning)]
