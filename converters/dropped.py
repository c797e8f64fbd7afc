"""The names every reader gives the kinds of data it drops, so that one warning reads the same for any
format (``pln: warning: x.glb: dropped animations; skins; textures; ...``).

Readers add a detail in parentheses where it helps (``primvars (rest)``); a kind named with a detail
and without one is listed once, with it. Counts (``3 degenerate faces``) come last.
"""

from __future__ import annotations

from collections.abc import Iterable

TEXTURE_COORDINATES = "texture coordinates"
VERTEX_NORMALS = "vertex normals"
VERTEX_COLOURS = "vertex colours"
TANGENTS = "tangents"
MATERIALS = "materials"
#: A material of one plain colour: the colour is kept, as the faces' colour, the rest of it is not.
MATERIAL_COLOUR_KEPT = "materials (base colour kept as face colour)"
#: Images a material uses (glTF textures, OBJ map_ statements, USD texture shaders).
TEXTURES = "textures"
SKINS = "skins"
ANIMATIONS = "animations"
#: A time-varying USD attribute, read at its first time sample.
ANIMATIONS_FIRST_SAMPLE = "animations (first time sample used)"
MORPH_TARGETS = "morph targets"
CAMERAS = "cameras"
LIGHTS = "lights"
NON_TRIANGLE_GEOMETRY = "non-triangle geometry (points, lines)"
#: Beginnings of notes a reader completes: ``subdivision scheme catmullClark (control cage kept)``,
#: ``primvars (rest)``, ``vertex attributes (_ID)``, ``PLY element range_grid``.
SUBDIVISION_SCHEME = "subdivision scheme"
PRIMVARS = "primvars"
VERTEX_ATTRIBUTES = "vertex attributes"
FACE_ATTRIBUTES = "face attributes"
NON_MESH_GEOMETRY = "non-mesh geometry"
PLY_ELEMENT = "PLY element"


def listed(notes: Iterable[str]) -> list[str]:
    """``notes`` as a reader returns them: each kind once, sorted, counts last."""
    notes = set(notes)
    kinds = {note for note in notes if not note[:1].isdigit()}
    kinds = {note for note in kinds if not any(other.startswith(f"{note} (") for other in kinds)}
    return sorted(kinds) + sorted(note for note in notes if note[:1].isdigit())
