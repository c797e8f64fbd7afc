"""glTF 2.0 (``.gltf`` + ``.bin``, and binary ``.glb``) through trimesh.

Reading keeps trimesh's scene graph: every node (with or without a mesh)
with its name, parent and local matrix. trimesh splits a mesh of several
primitives into one child node per primitive. glTF's unit is the metre.
A material's plain base colour becomes the face colour; the rest is
reported as dropped, in :mod:`.dropped`'s words: texture coordinates, normals, tangents, other
material properties, textures (a material using an image), skins, animations, morph targets, cameras
and lights (read from the file's JSON: trimesh drops them without a trace). Draco-compressed
primitives (``KHR_draco_mesh_compression``) are decoded by trimesh through DracoPy. The scene
is Y-up, as glTF says every file is.

Writing keeps node names (repeated names too), hierarchy, transforms and
instancing (nodes sharing one :class:`Mesh` share one glTF mesh). glTF has
no face colours: a mesh of one colour is written with a material of that
base colour, one of several colours with three vertices of its own per face
carrying the face's ``COLOR_0``; the reader turns both back into face colours.
Positions are float32. A Z-up scene is turned Y-up, glTF's convention, by
rotating its root nodes (``assemble.reoriented``: (x, y, z) -> (x, z, -y));
vertices are written as they are, welded after rounding, with no triangle left
without area (:func:`.assemble.at_float32`). The ``.gltf`` writer puts all binary data in one
``<stem>.bin`` beside the JSON.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote, urlsplit

from planefmt.errors import ConversionError
from planefmt.model import Scene, Units

from .assemble import METERS_PER_UNIT, at_float32, float32_shift, in_metres, reoriented
from .atomic import atomic_paths, write_bytes
from .dropped import (ANIMATIONS, CAMERAS, LIGHTS, MORPH_TARGETS, SKINS, TANGENTS, TEXTURE_COORDINATES, TEXTURES,
                      VERTEX_NORMALS, listed)
from .failures import describe
from .trimesh_bridge import read_scene, require_trimesh, to_trimesh_scene

_GLB_MAGIC = b"glTF"
#: glTF 2.0 §3.4: +Y is up.
GLTF_UP_AXIS = "Y"


def sniff_glb(head: bytes, size: int) -> bool:
    """Binary glTF starts with ``glTF``."""
    return head.startswith(_GLB_MAGIC)


def sniff_gltf(head: bytes, size: int) -> bool:
    """A JSON object mentioning glTF's required ``asset`` property early on."""
    text = head.lstrip(b"\xef\xbb\xbf \t\r\n")
    return text.startswith(b"{") and b'"asset"' in text


def sidecars(path: str | os.PathLike[str]) -> tuple[str, ...]:
    """The file a ``.gltf`` write of ``path`` creates beside it: its buffer, ``<stem>.bin``."""
    return (os.fspath(Path(path).with_suffix(".bin")),)


def references(path: str | os.PathLike[str]) -> tuple[str, ...]:
    """The local files (buffers, images) the ``.gltf`` at ``path`` refers to; none if it is no glTF JSON."""
    try:
        tree = json.loads(Path(path).read_bytes())
    except (OSError, ValueError):
        return ()
    if not isinstance(tree, dict):
        return ()
    items = [item for key in ("buffers", "images") if isinstance(tree.get(key), list)
             for item in tree[key] if isinstance(item, dict)]
    uris = [item["uri"] for item in items if isinstance(item.get("uri"), str)]
    # data: and other URIs with a scheme are not files beside the .gltf
    return tuple(os.path.join(os.path.dirname(os.fspath(path)), unquote(uri)) for uri in uris
                 if not urlsplit(uri).scheme)


def read_glb(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    """Read a ``.glb`` file into ``(scene, dropped)``."""
    return _read(path, binary=True)


def read_gltf(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    """Read a ``.gltf`` file (and the buffers and images it refers to) into ``(scene, dropped)``."""
    return _read(path, binary=False)


def _read(path: str | os.PathLike[str], binary: bool) -> tuple[Scene, list[str]]:
    tree = _json(path, binary)
    _require_draco(tree, os.fspath(path))
    scene, dropped = read_scene(path, "glb" if binary else "gltf", "binary glTF" if binary else "glTF",
                                units=Units.METRE, up_axis=GLTF_UP_AXIS, reversed_siblings=True,
                                resolver=None if binary else _uri_resolver(path), primitives=True,
                                renamed=_node_names(tree))
    counts = [note for note in dropped if note[:1].isdigit()]
    return scene, listed([note for note in dropped if note not in counts] + _dropped_kinds(tree)) + counts


def _json(path: str | os.PathLike[str], binary: bool) -> dict[str, Any]:
    """The file's glTF JSON; empty where it cannot be read (trimesh's own read then says why)."""
    try:
        with open(path, "rb") as handle:
            if binary:
                head = handle.read(20)
                if len(head) < 20 or head[:4] != b"glTF" or head[16:20] != b"JSON":
                    return {}
                text = handle.read(int.from_bytes(head[12:16], "little"))
            else:
                text = handle.read()
        tree = json.loads(text)
    except (OSError, ValueError):
        return {}
    return tree if isinstance(tree, dict) else {}


def _require_draco(tree: dict[str, Any], file: str) -> None:
    """A file whose primitives are Draco-compressed needs DracoPy: without it trimesh reads zeros and
    logs why, and the file would read as holding no mesh."""
    used = tree.get("extensionsUsed")
    if not isinstance(used, list) or "KHR_draco_mesh_compression" not in used:
        return
    try:
        import DracoPy  # noqa: F401
    except ImportError as exc:
        raise ConversionError("the meshes of this file are Draco-compressed (KHR_draco_mesh_compression): reading "
                              f"them needs DracoPy (pip install DracoPy): {exc}", file=file) from exc


def _items(tree: dict[str, Any], key: str) -> list[dict[str, Any]]:
    found = tree.get(key)
    return [item for item in found if isinstance(item, dict)] if isinstance(found, list) else []


def _dropped_kinds(tree: dict[str, Any]) -> list[str]:
    """What of the glTF JSON the model has no room for, besides what trimesh's meshes show."""
    kinds = []
    primitives = [primitive for mesh in _items(tree, "meshes") for primitive in _items(mesh, "primitives")]
    attributes = {name for primitive in primitives if isinstance(primitive.get("attributes"), dict)
                  for name in primitive["attributes"]}
    if any(name.startswith("TEXCOORD_") for name in attributes):
        kinds.append(TEXTURE_COORDINATES)
    if "NORMAL" in attributes:
        kinds.append(VERTEX_NORMALS)
    if "TANGENT" in attributes:
        kinds.append(TANGENTS)
    if any(primitive.get("targets") for primitive in primitives):
        kinds.append(MORPH_TARGETS)
    if _items(tree, "skins"):
        kinds.append(SKINS)
    if _items(tree, "animations"):
        kinds.append(ANIMATIONS)
    if _items(tree, "cameras"):
        kinds.append(CAMERAS)
    extensions = tree.get("extensions")
    lights = extensions.get("KHR_lights_punctual") if isinstance(extensions, dict) else None
    if isinstance(lights, dict) and _items(lights, "lights"):
        kinds.append(LIGHTS)
    if any(_uses_texture(material) for material in _items(tree, "materials")):
        kinds.append(TEXTURES)
    return kinds


def _uses_texture(value: Any) -> bool:
    """Whether a material (or a part of one: pbrMetallicRoughness, an extension) names a texture:
    every textureInfo is an object under a key ending in ``Texture`` with an ``index``."""
    if not isinstance(value, dict):
        return False
    return any((key.endswith("Texture") and isinstance(item, dict) and "index" in item) or _uses_texture(item)
               for key, item in value.items())


def _node_names(tree: dict[str, Any]) -> dict[str, str]:
    """The file's name of each node of ``tree`` whose name trimesh made up or changed: ``""`` for a node
    without one (trimesh names it by its index), the repeated name for a node named as an earlier one
    (trimesh makes it unique: the second ``Cube`` becomes ``Cube_1``). trimesh's own naming replayed."""
    from trimesh.util import unique_name

    taken: dict[str, int] = {}
    counts: dict[str, int] = {}
    renamed: dict[str, str] = {}
    nodes = tree.get("nodes")
    for i, node in enumerate(nodes if isinstance(nodes, list) else []):
        given = node.get("name", str(i)) if isinstance(node, dict) else str(i)
        label = unique_name(given, taken, counts=counts)
        taken[label] = i
        own = node.get("name") if isinstance(node, dict) else None
        if not isinstance(own, str):
            renamed[label] = ""
        elif label != own:
            renamed[label] = own
    return renamed


def _uri_resolver(path: str | os.PathLike[str]) -> Any:
    """A trimesh resolver for the files beside ``path`` that decodes percent-encoded URIs.

    glTF URIs are URI references (RFC 3986): ``back 1.bin`` is written ``back%201.bin`` (this
    module's writer does so) and trimesh 5.2 looks for the encoded name. The name as written is
    still tried, for writers that did not encode it.
    """
    resolvers = require_trimesh("glTF").resolvers

    class Decoding(resolvers.FilePathResolver):
        def get(self, name: str) -> bytes:
            try:
                return super().get(unquote(name))
            except FileNotFoundError:
                return super().get(name)

    return Decoding(os.fspath(path))


def write_glb(scene: Scene, path: str | os.PathLike[str]) -> list[str]:
    """Write ``scene`` as one ``.glb`` file; returns what glTF could not hold."""
    file = os.fspath(path)
    data, notes = _export(scene, file, binary=True)
    try:
        write_bytes(file, data)
    except OSError as exc:
        raise ConversionError(f"cannot write glTF: {exc.strerror or exc}", file=file) from exc
    return notes


def write_gltf(scene: Scene, path: str | os.PathLike[str]) -> list[str]:
    """Write ``scene`` as ``<stem>.gltf`` plus ``<stem>.bin``; returns what glTF could not hold."""
    target = Path(path)
    files, notes = _export(scene, os.fspath(target), binary=False)
    tree = json.loads(files.pop("model.gltf"))
    sidecar = target.with_suffix(".bin")
    outputs: dict[Path, bytes] = {}
    if files:
        (buffer,) = files.values()  # merge_buffers: exactly one .bin
        tree["buffers"][0]["uri"] = quote(sidecar.name)
        outputs[sidecar] = buffer
    # the sidecar first: the .gltf never appears before the data it points to
    outputs[target] = json.dumps(tree, separators=(",", ":")).encode("utf-8")
    try:
        with atomic_paths(list(outputs)) as temps:
            for temp, data in zip(temps, outputs.values()):
                temp.write_bytes(data)
    except OSError as exc:
        raise ConversionError(f"cannot write glTF: {exc.strerror or exc}",
                              file=str(target)) from exc
    return notes


def rounding(scene: Scene) -> float:
    """How far writing ``scene`` moves its surface, as a fraction of its diagonal: its coordinates in metres
    rounded to float32 (turning it Y-up is a rotation of the root nodes, which moves no vertex farther)."""
    return float32_shift(in_metres(scene))


def _export(scene: Scene, file: str, *, binary: bool) -> tuple[Any, list[str]]:
    """trimesh's glTF export of ``scene`` with the node names restored, and the notes."""
    exchange = require_trimesh("glTF").exchange.gltf
    notes = []
    if scene.units not in (Units.METRE, Units.UNSPECIFIED):
        notes.append(f"units ({scene.units.name.lower()}; glTF is in metres: coordinates scaled by "
                     f"{METERS_PER_UNIT[scene.units]:g})")
    try:
        scene, rounding = at_float32(reoriented(in_metres(scene), GLTF_UP_AXIS))
        notes += rounding
        tm_scene, names = to_trimesh_scene(scene)

        def restore_names(tree: dict[str, Any]) -> None:
            for node in tree.get("nodes", []):
                name = names.get(node.get("name"))
                if name:
                    node["name"] = name
                elif name is not None:
                    del node["name"]  # an unnamed node stays unnamed

        if binary:
            result = exchange.export_glb(tm_scene, include_normals=False,
                                         tree_postprocessor=restore_names)
        else:
            result = exchange.export_gltf(tm_scene, include_normals=False, merge_buffers=True,
                                          tree_postprocessor=restore_names)
    except ConversionError as exc:
        raise exc.located(file=file)
    except Exception as exc:  # noqa: BLE001 - trimesh raises anything
        raise ConversionError(f"cannot write glTF: {describe(exc)}", file=file) from exc
    return result, notes
