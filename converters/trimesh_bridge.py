"""trimesh scenes and meshes to and from the planefmt model.

The OBJ, PLY, STL, OFF and glTF modules parse and serialise through trimesh;
this module holds what they share: loading a file into a trimesh scene and
walking its scene graph into model nodes, turning a trimesh geometry into a
clean :class:`Mesh` with face colours, and the reverse for the writers.

trimesh is imported on first use, so that a missing trimesh fails only the
formats that need it.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Mapping
from dataclasses import replace
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from planefmt.errors import ConversionError
from planefmt.model import Mesh, Node, Scene, Units

from .assemble import at_float32, build_mesh, flatten, instancing_note
from .atomic import write_bytes
from .dropped import (FACE_ATTRIBUTES, MATERIAL_COLOUR_KEPT, MATERIALS, NON_TRIANGLE_GEOMETRY, TEXTURE_COORDINATES,
                      TEXTURES, VERTEX_ATTRIBUTES, VERTEX_COLOURS, VERTEX_NORMALS, listed)
from .failures import describe

if TYPE_CHECKING:
    import trimesh


def require_trimesh(what: str) -> ModuleType:
    """Import trimesh, or explain which format needs it."""
    try:
        import trimesh
    except ImportError as exc:
        raise ConversionError(f"{what} support needs trimesh (pip install trimesh): {exc}") from exc
    return trimesh


#: The suffix trimesh's glTF loader gives the frame of each primitive of a mesh of several:
#: ``util.unique_id(length=6)``, random hex.
_PRIMITIVE_FRAME = re.compile(r"_[0-9a-f]{6}")


def read_scene(path: str | os.PathLike[str], file_type: str, what: str,
               units: Units = Units.UNSPECIFIED, up_axis: str | None = None,
               reversed_siblings: bool = False, resolver: Any = None,
               primitives: bool = False, renamed: Mapping[str, str] | None = None) -> tuple[Scene, list[str]]:
    """Read ``path`` as ``file_type`` through trimesh into ``(scene, dropped)``.

    ``what`` names the format in messages ("binary glTF"); ``units`` and
    ``up_axis`` are the format's own (glTF: metres, +y up). Any trimesh
    failure becomes a :class:`ConversionError`; so does a file with no
    triangle. ``reversed_siblings``: trimesh's graph lists each node's
    children in reverse file order (see :func:`scene_from_trimesh`). ``resolver``:
    how trimesh finds the files ``path`` refers to (default: by name beside it). ``primitives``,
    ``renamed``: see :func:`scene_from_trimesh`.
    """
    tm = require_trimesh(what)
    file = os.fspath(path)
    try:
        # process=False: trimesh would merge vertices by position *and*
        # attributes (UV seams stay split); build_mesh merges by position only.
        loaded = tm.load_scene(file, file_type=file_type, resolver=resolver, process=False)
    except MemoryError:
        raise  # not a property of the file
    except Exception as exc:  # noqa: BLE001 - trimesh raises anything on bad input
        raise ConversionError(f"cannot read as {what}: {describe(exc)}", file=file) from exc
    scene, dropped = scene_from_trimesh(loaded, units, file, reversed_siblings, primitives, renamed)
    scene = replace(scene, up_axis=up_axis)
    if not any(node.mesh is not None for node in scene.nodes):
        raise ConversionError(f"no triangle mesh found in this {what} file", file=file)
    return scene, dropped


def scene_from_trimesh(loaded: "trimesh.Scene", units: Units, file: str | None,
                       reversed_siblings: bool = False, primitives: bool = False,
                       renamed: Mapping[str, str] | None = None) -> tuple[Scene, list[str]]:
    """Walk a trimesh scene graph into model nodes (depth first, parents first).

    Every graph node except trimesh's synthetic base frame becomes a node,
    with or without a mesh, so the hierarchy survives. Geometry shared by
    several nodes (instancing) becomes one shared :class:`Mesh`. With
    ``reversed_siblings`` each node's children are taken in reverse graph
    order: trimesh 5's glTF loader builds the graph popping a stack, which
    reverses the file's sibling order (the round-trip tests watch this). With ``primitives`` (glTF),
    the frames trimesh makes for the primitives of a mesh of several, named after their node and a
    random suffix (``d8_6cf88e``), are named ``<node>_<k>`` in order instead: a file converts to the
    same bytes every time. ``renamed`` maps the frames trimesh named otherwise than the file to the
    file's names: "" for a glTF node without a name, which trimesh names by its index, the repeated
    name of a glTF node named as an earlier one, which trimesh makes unique. A file's only node, which
    trimesh names after the file, is unnamed ("").
    """
    graph = loaded.graph
    children = graph.transforms.children
    dropped: set[str] = set()
    degenerate = 0
    meshes: dict[str, Mesh | None] = {}
    nodes: list[Node] = []
    numbered: dict[int, int] = {}  # primitive frames named so far under each node

    def pushed_order(node: str) -> list[str]:
        # the stack pops the last pushed first: push in reverse of the wanted order
        found = list(children.get(node, []))
        return found if reversed_siblings else found[::-1]

    stack: list[tuple[str, str, int | None]] = [
        (child, graph.base_frame, None) for child in pushed_order(graph.base_frame)]
    while stack:
        name, parent_name, parent = stack.pop()
        matrix, geometry_name = graph.get(frame_to=name, frame_from=parent_name)
        # trimesh names a file's only node after the file: not a name the file holds
        after_file = file is not None and str(name) == os.path.basename(file)
        mesh = None
        if geometry_name is not None:
            if geometry_name not in meshes:
                # (the message names the file already)
                what = None if after_file else name
                mesh, notes, removed = mesh_from_trimesh(loaded.geometry[geometry_name], what=what, file=file)
                meshes[geometry_name] = mesh
                dropped.update(notes)
                degenerate += removed
            mesh = meshes[geometry_name]
        matrix = np.asarray(matrix, dtype=np.float64)
        label, stem = str(name), str(parent_name)
        if (primitives and geometry_name is not None and parent is not None and label.startswith(stem)
                and _PRIMITIVE_FRAME.fullmatch(label[len(stem):])):
            numbered[parent] = numbered.get(parent, -1) + 1
            label = f"{stem}_{numbered[parent]}"
        elif after_file:
            # A .pln keeping a made-up name would pay 13-20 bytes (3-9 % of a small convex file) for
            # the name the file itself has, or an index.
            label = ""
        elif renamed and label in renamed:
            label = renamed[label]
        nodes.append(Node(name=label, parent=parent,
                          transform=None if np.array_equal(matrix, np.eye(4)) else matrix,
                          mesh=mesh))
        index = len(nodes) - 1
        stack.extend((child, name, index) for child in pushed_order(name))
    notes = listed(dropped)
    if degenerate:
        notes.append(f"{degenerate} degenerate faces")
    return Scene(nodes=tuple(nodes), units=units), notes


def mesh_from_trimesh(geometry: Any, *, what: str | None,
                      file: str | None) -> tuple[Mesh | None, set[str], int]:
    """Convert one trimesh geometry: ``(mesh or None, dropped notes, degenerate faces)``."""
    if not hasattr(geometry, "faces") or len(geometry.faces) == 0:
        return None, {NON_TRIANGLE_GEOMETRY}, 0
    faces = np.asarray(geometry.faces, dtype=np.int64)
    colours, notes = _face_colours(geometry, faces)
    if "vertex_normals" in geometry._cache:  # trimesh keeps normals read from a file there
        notes.add(VERTEX_NORMALS)
    extra = sorted(key for key in getattr(geometry, "vertex_attributes", {}) if key != "color")
    if extra:
        notes.add(f"{VERTEX_ATTRIBUTES} ({', '.join(extra)})")
    # STL's per-face uint16 "attribute" arrives as a face attribute, nearly always zero
    extra = sorted(key for key, value in getattr(geometry, "face_attributes", {}).items()
                   if np.any(np.asarray(value) != 0))
    if extra:
        notes.add(f"{FACE_ATTRIBUTES} ({', '.join(extra)})")
    mesh, degenerate = build_mesh(geometry.vertices, faces, colours, what=what, file=file)
    return mesh, notes, degenerate


def _face_colours(geometry: Any, faces: np.ndarray) -> tuple[np.ndarray | None, set[str]]:
    """Per-face RGBA of a trimesh geometry, and what of its appearance is lost.

    Face colours are kept; vertex colours only where each face's three
    vertices agree (that is how the glTF writer stores face colours); a
    material's plain base colour becomes a uniform face colour.
    """
    visual = geometry.visual
    notes: set[str] = set()
    if visual.kind == "face":
        return np.asarray(visual.face_colors, dtype=np.uint8), notes
    if visual.kind == "vertex":
        corner = np.asarray(visual.vertex_colors, dtype=np.uint8)[faces]
        if (corner == corner[:, :1]).all():
            return corner[:, 0], notes
        notes.add(VERTEX_COLOURS)
        return None, notes
    uv = getattr(visual, "uv", None)
    if uv is not None and len(uv):
        notes.add(TEXTURE_COORDINATES)
    if "color" in getattr(visual, "vertex_attributes", {}):
        notes.add(VERTEX_COLOURS)
    material = getattr(visual, "material", None)
    if material is None:
        return None, notes
    textures = [getattr(material, key, None) for key in (
        "image", "baseColorTexture", "normalTexture", "emissiveTexture",
        "metallicRoughnessTexture", "occlusionTexture")]
    if any(texture is not None for texture in textures):
        notes.add(TEXTURES)
    base = getattr(material, "baseColorFactor", None)
    if base is not None and getattr(material, "baseColorTexture", None) is None:
        notes.add(MATERIAL_COLOUR_KEPT)
        return np.broadcast_to(np.asarray(base, dtype=np.uint8), (len(faces), 4)).copy(), notes
    notes.add(MATERIALS)
    return None, notes


def to_trimesh(mesh: Mesh, *, colours_per_vertex: bool = False) -> "trimesh.Trimesh":
    """A trimesh mesh for ``mesh``; face colours as trimesh face colours.

    With ``colours_per_vertex`` (formats without face colours: glTF) a mesh of
    one colour gets a material of that base colour, which :func:`_face_colours`
    reads back as that face colour; any other gets three vertices of its own
    per face carrying the face's colour, which :func:`build_mesh` merges again
    on reading (three times the vertices: kept for meshes that need it).
    """
    tm = require_trimesh("mesh export")
    if mesh.face_colours is None:
        return tm.Trimesh(vertices=mesh.vertices, faces=mesh.faces, process=False)
    if colours_per_vertex and (mesh.face_colours == mesh.face_colours[0]).all():
        rgba = mesh.face_colours[0]
        # Metallic 0: glTF's default of 1 would show a plain colour as metal.
        material = tm.visual.material.PBRMaterial(baseColorFactor=rgba, metallicFactor=0.0,
                                                   alphaMode="BLEND" if rgba[3] < 255 else None)
        return tm.Trimesh(vertices=mesh.vertices, faces=mesh.faces,
                          visual=tm.visual.TextureVisuals(material=material), process=False)
    if colours_per_vertex:
        return tm.Trimesh(vertices=mesh.vertices[mesh.faces].reshape(-1, 3),
                          faces=np.arange(3 * len(mesh.faces)).reshape(-1, 3),
                          vertex_colors=np.repeat(mesh.face_colours, 3, axis=0),
                          process=False)
    return tm.Trimesh(vertices=mesh.vertices, faces=mesh.faces,
                      face_colors=mesh.face_colours, process=False)


def to_trimesh_scene(scene: Scene) -> tuple["trimesh.Scene", dict[str, str]]:
    """A trimesh scene with the nodes, hierarchy and transforms of ``scene``.

    trimesh needs unique node names, so nodes are keyed by index; the
    returned map from key to the node's own name lets the glTF writer put the
    original (possibly repeated) names back into the exported file. Meshes
    shared by several nodes are exported once and instanced.
    """
    tm = require_trimesh("glTF export")
    out = tm.Scene()
    names: dict[str, str] = {}
    geometry_keys: dict[int, str] = {}
    for index, node in enumerate(scene.nodes):
        key = f"node{index}"
        names[key] = node.name
        geometry = None
        if node.mesh is not None:
            geometry = geometry_keys.get(id(node.mesh))
            if geometry is None:
                geometry = node.name or key
                if geometry in out.geometry:
                    geometry = f"{geometry}_{index}"
                out.geometry[geometry] = to_trimesh(node.mesh, colours_per_vertex=True)
                geometry_keys[id(node.mesh)] = geometry
        parent = out.graph.base_frame if node.parent is None else f"node{node.parent}"
        matrix = np.eye(4) if node.transform is None else np.asarray(node.transform, np.float64)
        out.graph.update(frame_from=parent, frame_to=key, matrix=matrix, geometry=geometry)
    return out, names


def write_flat(scene: Scene, path: str | os.PathLike[str], *, what: str,
               export: Callable[["trimesh.Trimesh"], bytes | str],
               colours: bool, float32: bool) -> list[str]:
    """Write ``scene`` flattened into one world-space mesh with ``export``, atomically.

    For the single-mesh formats. ``colours`` says whether the format keeps
    face colours, ``float32`` whether it stores coordinates as float32.
    Returns the notes on what the format could not hold.
    """
    file = os.fspath(path)
    try:
        mesh = flatten(scene)
    except ConversionError as exc:
        raise exc.located(file=file)
    notes = []
    if len(scene.nodes) > 1:
        notes.append(f"scene hierarchy and node names "
                     f"({len(scene.nodes)} nodes merged into one mesh)")
    instancing = instancing_note(scene)
    if instancing:
        notes.append(instancing)
    if scene.units != Units.UNSPECIFIED:
        notes.append(f"units ({scene.units.name.lower()})")
    if scene.up_axis is not None:
        notes.append(f"up axis ({scene.up_axis})")
    if mesh.face_colours is not None and not colours:
        notes.append("face colours")
        mesh = Mesh(vertices=mesh.vertices, faces=mesh.faces)
    if float32:
        try:
            flat, rounding = at_float32(Scene(nodes=(Node(name="", mesh=mesh),), units=scene.units))
        except ConversionError as exc:
            raise exc.located(file=file)
        mesh = flat.nodes[0].mesh
        notes += rounding
    try:
        data = export(to_trimesh(mesh))
    except Exception as exc:  # noqa: BLE001 - trimesh raises anything
        raise ConversionError(f"cannot write {what}: {describe(exc)}", file=file) from exc
    try:
        write_bytes(file, data.encode("utf-8") if isinstance(data, str) else data)
    except OSError as exc:
        raise ConversionError(f"cannot write {what}: {exc.strerror or exc}", file=file) from exc
    return notes
