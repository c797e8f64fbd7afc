"""USD (``.usd``, ``.usda``, ``.usdc``, ``.usdz``) through usd-core's ``pxr``.

Reading composes the stage (references, payloads, instancing) and keeps
every ``UsdGeom.Mesh`` with the prims above it, so the hierarchy and the
local transforms survive; the instances of one prototype share one mesh.
Polygons are triangulated (fans for convex faces, ear clipping for concave
ones), hole faces removed, ``leftHanded`` winding flipped to the model's
counter-clockwise-outward convention. Attributes are read at their earliest
time sample (their default when not animated). ``metersPerUnit`` becomes
:class:`Units` where it matches one; ``upAxis`` becomes the scene's
``up_axis`` (coordinates are kept as authored). ``displayColor`` and
``displayOpacity`` with constant or uniform interpolation become face colours; the rest (texture coordinates, normals, other primvars,
materials, textures, skins, blend shapes, animations, cameras, lights, subdivision schemes: the cage is
kept) is reported as dropped, in :mod:`.dropped`'s words.
Prims with purpose guide or proxy, and invisible prims, are skipped.

Writing makes one prim per node: an ``Xform`` (or a ``Mesh`` for a childless
mesh node) with its local transform as a single ``xformOp:transform``; a node
with both a mesh and children becomes an ``Xform`` holding a ``Mesh`` child
marked ``planefmt:nodeMesh``. A mesh several childless nodes share is
written once, as the ``mesh`` child of a root ``class`` prim, and each of
those nodes is an instanceable ``Xform`` referencing it (the reader folds
the instance's mesh back, shared); a node with children keeps a copy of its
own, which the notes report. Several root nodes are wrapped in one ``Xform``
marked ``planefmt:sceneRoot`` (USD wants a single default prim). The reader
folds both markers back, so a scene survives a round trip node for node.
Prim names are made valid identifiers and unique; a node name that had to
change is kept as the prim's ``displayName``. Stage metadata: ``upAxis``
(the scene's, Y where it has none; another on request, the scene turned
into it), ``metersPerUnit`` (1 when the units are unspecified)
and ``defaultPrim``. Points are float32 as the schema has them (welded after
rounding, with no triangle left without area: :func:`.assemble.at_float32`); face colours
go to a uniform ``displayColor`` (and ``displayOpacity`` when not opaque),
as the stored 8-bit values divided by 255.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections import Counter
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from planefmt.errors import ConversionError
from planefmt.model import UP_AXES, Mesh, Node, Scene, Units

from .assemble import METERS_PER_UNIT, at_float32, build_mesh, float32_shift, instancing_note, reoriented
from .atomic import atomic_path
from .dropped import (ANIMATIONS, ANIMATIONS_FIRST_SAMPLE, CAMERAS, LIGHTS, MATERIALS, MORPH_TARGETS,
                      NON_MESH_GEOMETRY, PRIMVARS, SKINS, SUBDIVISION_SCHEME, TEXTURE_COORDINATES, TEXTURES,
                      VERTEX_COLOURS, VERTEX_NORMALS, listed)
from .failures import describe
from .polygons import triangulate

#: customData keys that mark prims the writer added for USD's sake.
SCENE_ROOT_KEY = "planefmt:sceneRoot"
NODE_MESH_KEY = "planefmt:nodeMesh"

_MAGIC_USDC = b"PXR-USDC"
_MAGIC_USDA = b"#usda"
_USD_EXTENSIONS = (".usd", ".usda", ".usdc")


def sniff_usda(head: bytes, size: int) -> bool:
    """Text USD starts with ``#usda``."""
    return head.startswith(_MAGIC_USDA)


def sniff_usdc(head: bytes, size: int) -> bool:
    """Crate files start with ``PXR-USDC``."""
    return head.startswith(_MAGIC_USDC)


def sniff_usdz(head: bytes, size: int) -> bool:
    """A usdz is a zip whose first member is a USD layer."""
    if not head.startswith(b"PK\x03\x04") or len(head) < 30:
        return False
    name_length = int.from_bytes(head[26:28], "little")
    name = head[30:30 + name_length].decode("utf-8", "replace").lower()
    return name.endswith(_USD_EXTENSIONS)


def _pxr() -> SimpleNamespace:
    """Import the pxr modules, or explain that USD support needs usd-core."""
    try:
        from pxr import Gf, Sdf, Tf, Usd, UsdGeom, UsdUtils, Vt
    except ImportError as exc:
        raise ConversionError(f"USD support needs usd-core (pip install usd-core): {exc}") from exc
    return SimpleNamespace(Gf=Gf, Sdf=Sdf, Tf=Tf, Usd=Usd, UsdGeom=UsdGeom,
                           UsdUtils=UsdUtils, Vt=Vt)


# --------------------------------------------------------------------------- reading

def read(path: str | os.PathLike[str]) -> tuple[Scene, list[str]]:
    """Read a USD stage into ``(scene, dropped)``; see the module docstring."""
    pxr = _pxr()
    file = os.fspath(path)
    try:
        stage = pxr.Usd.Stage.Open(file)
    except Exception as exc:  # noqa: BLE001 - Tf.ErrorException and friends
        raise ConversionError(f"cannot open as USD: {describe(exc)}", file=file) from exc
    if stage is None:
        raise ConversionError("cannot open as USD", file=file)
    try:
        return _StageReader(pxr, stage, file).read()
    except ConversionError:
        raise
    except Exception as exc:  # noqa: BLE001 - malformed values surface as anything
        raise ConversionError(f"cannot read USD stage: {describe(exc)}", file=file) from exc


class _StageReader:
    """One read of one stage: the traversal state and the dropped notes."""

    def __init__(self, pxr: SimpleNamespace, stage: Any, file: str) -> None:
        self.pxr = pxr
        self.stage = stage
        self.file = file
        self.time = pxr.Usd.TimeCode.EarliestTime()
        self.xforms = pxr.UsdGeom.XformCache(self.time)
        self.dropped: set[str] = set()
        self.degenerate = 0
        self.prototypes: dict[Any, Mesh | None] = {}

    def read(self) -> tuple[Scene, list[str]]:
        UsdGeom = self.pxr.UsdGeom
        predicate = self.pxr.Usd.TraverseInstanceProxies(self.pxr.Usd.PrimDefaultPredicate)
        prims = list(self.pxr.Usd.PrimRange.Stage(self.stage, predicate))
        meshes = {prim.GetPath() for prim in prims
                  if prim.IsA(UsdGeom.Mesh) and self._wanted(prim)}
        others = sorted({str(p.GetTypeName()) for p in prims
                         if p.IsA(UsdGeom.Gprim) and not p.IsA(UsdGeom.Mesh)})
        if others:
            self.dropped.add(f"{NON_MESH_GEOMETRY} ({', '.join(others)})")
        self.dropped.update(kind for prim in prims for kind in _prim_kinds(prim))
        needed = set()
        for path in meshes:
            while not path.IsAbsoluteRootPath() and path not in needed:
                needed.add(path)
                path = path.GetParentPath()

        nodes: list[Node] = []
        index: dict[Any, int | None] = {}
        for prim in prims:  # depth-first preorder: parents come first
            path = prim.GetPath()
            if path not in needed:
                continue
            parent_path = path.GetParentPath()
            parent = None if parent_path.IsAbsoluteRootPath() else index[parent_path]
            if self._marked(prim, SCENE_ROOT_KEY) and parent is None \
                    and self._local(prim, parent_path) is None:
                index[path] = None
                continue
            mesh = self._shared_mesh(prim) if path in meshes else None
            transform = self._local(prim, parent_path)
            if (self._marked(prim, NODE_MESH_KEY) and parent is not None and transform is None
                    and nodes[parent].mesh is None):
                owner = nodes[parent]
                nodes[parent] = Node(owner.name, owner.parent, owner.transform, mesh)
                index[path] = parent
                continue
            nodes.append(Node(name=self._name(prim), parent=parent, transform=transform,
                              mesh=mesh))
            index[path] = len(nodes) - 1

        if not any(node.mesh is not None for node in nodes):
            raise ConversionError("no polygon mesh found in this USD stage", file=self.file)
        # The authored upAxis, else USD's fallback (Y unless a site configured otherwise): a stage always
        # has one, unlike metersPerUnit, whose fallback (cm) is not the author's word.
        up = str(self.pxr.UsdGeom.GetStageUpAxis(self.stage))
        units = self._units()
        notes = listed(self.dropped)
        if self.degenerate:
            notes.append(f"{self.degenerate} degenerate faces")
        return Scene(nodes=tuple(nodes), units=units, up_axis=up), notes

    def _shared_mesh(self, prim: Any) -> Mesh | None:
        """The prim's mesh; instance proxies of one prototype prim share one (scenegraph instancing), as
        the nodes of a glTF mesh do, so that writers keep or report the sharing."""
        if not prim.IsInstanceProxy():
            return self._mesh(prim)
        key = prim.GetPrimInPrototype().GetPath()
        if key not in self.prototypes:
            self.prototypes[key] = self._mesh(prim)
        return self.prototypes[key]

    def _wanted(self, prim: Any) -> bool:
        """False for meshes a renderer would not show as the asset's surface."""
        imageable = self.pxr.UsdGeom.Imageable(prim)
        purpose = imageable.ComputePurpose()
        if purpose in (self.pxr.UsdGeom.Tokens.guide, self.pxr.UsdGeom.Tokens.proxy):
            self.dropped.add(f"{purpose} prims")
            return False
        if imageable.ComputeVisibility(self.time) == self.pxr.UsdGeom.Tokens.invisible:
            self.dropped.add("invisible prims")
            return False
        return True

    @staticmethod
    def _marked(prim: Any, key: str) -> bool:
        return bool(prim.GetCustomDataByKey(key))

    @staticmethod
    def _name(prim: Any) -> str:
        display = prim.GetDisplayName()
        # An empty display name is authored for a node without a name (the prim needs one).
        return display if display or prim.HasAuthoredDisplayName() else prim.GetName()

    def _units(self) -> Units:
        if not self.stage.HasAuthoredMetadata("metersPerUnit"):
            return Units.UNSPECIFIED  # USD's fallback (cm) is not the author's word
        value = self.pxr.UsdGeom.GetStageMetersPerUnit(self.stage)
        for unit, meters in METERS_PER_UNIT.items():
            if math.isclose(value, meters, rel_tol=1e-9):
                return unit
        self.dropped.add(f"metersPerUnit {value} (no matching unit)")
        return Units.UNSPECIFIED

    def _local(self, prim: Any, parent_path: Any) -> np.ndarray | None:
        """Local transform as a column-vector matrix, None for identity."""
        if not prim.IsA(self.pxr.UsdGeom.Xformable):
            return None
        xformable = self.pxr.UsdGeom.Xformable(prim)
        if xformable.TransformMightBeTimeVarying():
            self.dropped.add(ANIMATIONS_FIRST_SAMPLE)
        matrix, resets = self.xforms.GetLocalTransformation(prim)
        if resets and not parent_path.IsAbsoluteRootPath():
            # resetXformStack: the prim ignores its ancestors' transforms, so
            # its local matrix relative to the parent node is world * parent^-1.
            parent = self.stage.GetPrimAtPath(parent_path)
            matrix = (self.xforms.GetLocalToWorldTransform(prim)
                      * self.xforms.GetLocalToWorldTransform(parent).GetInverse())
        # USD multiplies row vectors (p' = p M); the model uses column vectors.
        result = np.array(matrix, dtype=np.float64).T
        return None if np.array_equal(result, np.eye(4)) else result

    def _mesh(self, prim: Any) -> Mesh | None:
        UsdGeom = self.pxr.UsdGeom
        usd_mesh = UsdGeom.Mesh(prim)
        where = str(prim.GetPath())
        points_attr = usd_mesh.GetPointsAttr()
        if points_attr.GetNumTimeSamples() > 1:
            self.dropped.add(ANIMATIONS_FIRST_SAMPLE)
        points = _array(points_attr.Get(self.time), np.float64).reshape(-1, 3)
        counts = _array(usd_mesh.GetFaceVertexCountsAttr().Get(self.time), np.int64)
        indices = _array(usd_mesh.GetFaceVertexIndicesAttr().Get(self.time), np.int64)
        if counts.sum() != len(indices) or (counts < 0).any():
            raise ConversionError(
                f"{where}: faceVertexCounts sum to {counts.sum()} "
                f"but there are {len(indices)} faceVertexIndices", file=self.file)
        if len(indices) and (indices.min() < 0 or indices.max() >= len(points)):
            raise ConversionError(f"{where}: face vertex index outside the {len(points)} points",
                                  file=self.file)
        if (counts < 3).any():
            self.dropped.add("faces with fewer than three corners")
        holes = _array(usd_mesh.GetHoleIndicesAttr().Get(self.time), np.int64)
        triangles, face = triangulate(points, counts, indices)
        if len(holes):
            keep = ~np.isin(face, holes)
            triangles, face = triangles[keep], face[keep]
        if usd_mesh.GetOrientationAttr().Get(self.time) == UsdGeom.Tokens.leftHanded:
            triangles = triangles[:, ::-1]
        colours = self._face_colours(prim, len(counts))
        self._note_dropped(prim, usd_mesh)
        mesh, degenerate = build_mesh(points, triangles,
                                      None if colours is None else colours[face],
                                      what=where, file=self.file)
        self.degenerate += degenerate
        return mesh

    def _face_colours(self, prim: Any, faces: int) -> np.ndarray | None:
        """RGBA8 per polygon from constant/uniform displayColor and displayOpacity."""
        primvars = self.pxr.UsdGeom.PrimvarsAPI(prim)
        rgb = self._per_face(primvars.GetPrimvar("displayColor"), faces)
        alpha = self._per_face(primvars.GetPrimvar("displayOpacity"), faces)
        if rgb is None:
            return None
        rgb = rgb.reshape(faces, 3)
        alpha = np.ones((faces, 1)) if alpha is None else alpha.reshape(faces, 1)
        rgba = np.concatenate([rgb, alpha], axis=1)
        return np.round(np.clip(rgba, 0.0, 1.0) * 255.0).astype(np.uint8)

    def _per_face(self, primvar: Any, faces: int) -> np.ndarray | None:
        """A primvar's values repeated or indexed per face; None if not per face."""
        if not primvar or not primvar.HasValue():
            return None
        values = _array(primvar.ComputeFlattened(self.time), np.float64)
        interpolation = primvar.GetInterpolation()
        tokens = self.pxr.UsdGeom.Tokens
        width = 3 if values.ndim == 2 else 1
        values = values.reshape(-1, width)
        if interpolation == tokens.constant and len(values) >= 1:
            return np.repeat(values[:1], faces, axis=0)
        if interpolation == tokens.uniform and len(values) == faces:
            return values
        self.dropped.add(VERTEX_COLOURS)
        return None

    def _note_dropped(self, prim: Any, usd_mesh: Any) -> None:
        """Record what of this mesh the model cannot hold."""
        UsdGeom = self.pxr.UsdGeom
        scheme = usd_mesh.GetSubdivisionSchemeAttr().Get(self.time)
        if scheme != UsdGeom.Tokens.none:
            self.dropped.add(f"{SUBDIVISION_SCHEME} {scheme} (control cage kept)")
        if usd_mesh.GetNormalsAttr().HasAuthoredValue():
            self.dropped.add(VERTEX_NORMALS)
        others = []
        for primvar in UsdGeom.PrimvarsAPI(prim).GetPrimvarsWithValues():
            name = primvar.GetPrimvarName()
            if name in ("displayColor", "displayOpacity"):
                continue
            if primvar.GetTypeName().role == "TextureCoordinate" \
                    or str(primvar.GetTypeName()) in ("float2[]", "texCoord2f[]", "texCoord3f[]"):
                self.dropped.add(TEXTURE_COORDINATES)
            elif name == "normals":
                self.dropped.add(VERTEX_NORMALS)
            elif name.startswith("skel:"):  # joint indices and weights, the bind transform
                self.dropped.add(SKINS)
            else:
                others.append(str(name))
        if others:
            self.dropped.add(f"{PRIMVARS} ({', '.join(sorted(others))})")
        binding = prim.GetRelationship("material:binding")
        if (binding and binding.GetTargets()) or UsdGeom.Subset.GetAllGeomSubsets(usd_mesh):
            self.dropped.add(MATERIALS)


#: Prim types (UsdSkel, UsdGeom) whose data the model has no room for, by the kind they carry.
_TYPE_KINDS = {"SkelRoot": SKINS, "Skeleton": SKINS, "SkelAnimation": ANIMATIONS, "BlendShape": MORPH_TARGETS,
               "Camera": CAMERAS}


def _prim_kinds(prim: Any) -> list[str]:
    """The dropped kinds a prim itself stands for: skins, animations, blend shapes, cameras, lights
    (UsdLux types all end in ``Light``), textures (a shader reading an image through an asset input)."""
    kind = str(prim.GetTypeName())
    found = [_TYPE_KINDS[kind]] if kind in _TYPE_KINDS else []
    if kind.endswith("Light") or any(str(name).endswith("LightAPI") for name in prim.GetAppliedSchemas()):
        found.append(LIGHTS)
    if kind == "Shader" and any(str(attr.GetTypeName()) == "asset" and attr.HasAuthoredValue()
                                for attr in prim.GetAttributes() if attr.GetName().startswith("inputs:")):
        found.append(TEXTURES)
    return found


def _array(value: Any, dtype: type) -> np.ndarray:
    """A Vt array (or None for an unauthored attribute) as numpy."""
    if value is None:
        return np.zeros(0, dtype=dtype)
    return np.asarray(value, dtype=dtype)


# --------------------------------------------------------------------------- writing

def write(scene: Scene, path: str | os.PathLike[str], *, up_axis: str | None = None) -> list[str]:
    """Write ``scene`` as ``.usda``, ``.usdc``, ``.usd`` (crate) or ``.usdz``, atomically.

    The format follows the extension. The stage's ``upAxis`` is ``up_axis``
    ("Y" or "Z"), else the scene's, else Y; a scene whose own up axis differs
    is turned into it (its root nodes rotated, ``assemble.reoriented``).
    """
    pxr = _pxr()
    target = Path(path)
    up_axis = up_axis or scene.up_axis or "Y"
    if up_axis not in UP_AXES:
        raise ConversionError(f"up_axis must be one of {', '.join(UP_AXES)}, not {up_axis!r}", file=str(target))
    try:
        stage, notes = _build_stage(pxr, reoriented(scene, up_axis), up_axis)
        layer = stage.GetRootLayer()
        with atomic_path(target) as temp:
            if target.suffix.lower() == ".usdz":
                _package_usdz(pxr, layer, target.stem, temp)
            elif not layer.Export(str(temp)):
                raise ConversionError("usd-core could not export the layer", file=str(target))
    except ConversionError as exc:
        raise exc.located(file=str(target))
    except Exception as exc:  # noqa: BLE001 - Tf.ErrorException, OSError
        raise ConversionError(f"cannot write USD: {describe(exc)}", file=str(target)) from exc
    return notes


def _package_usdz(pxr: SimpleNamespace, layer: Any, stem: str, temp: Path) -> None:
    """Export ``layer`` as a crate file and package it alone into the usdz ``temp``."""
    # Beside the output, hidden and named as its temporaries are: a SIGKILL, which allows no clean-up,
    # leaves it where the output was going, not in the system's temporary folder.
    with tempfile.TemporaryDirectory(prefix=f"{temp.stem}.", suffix=".tmp", dir=temp.parent) as folder:
        inner = Path(folder) / f"{pxr.Tf.MakeValidIdentifier(stem)}.usdc"
        if not layer.Export(str(inner)):
            raise ConversionError("usd-core could not export the layer")
        if not pxr.UsdUtils.CreateNewUsdzPackage(pxr.Sdf.AssetPath(str(inner)), str(temp)):
            raise ConversionError("usd-core could not create the usdz package")


def _build_stage(pxr: SimpleNamespace, scene: Scene, up_axis: str) -> tuple[Any, list[str]]:
    """An in-memory stage holding ``scene``, and the writer's notes."""
    UsdGeom, Sdf = pxr.UsdGeom, pxr.Sdf
    stage = pxr.Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z if up_axis == "Z" else UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, METERS_PER_UNIT.get(scene.units, 1.0))
    scene, notes = at_float32(scene)

    children: dict[int | None, int] = {}
    for node in scene.nodes:
        children[node.parent] = children.get(node.parent, 0) + 1
    # A mesh that several childless nodes place is written once, as a prototype those nodes instance
    # (an instance's own children would be ignored: nodes with children keep a copy of their own).
    leaves = Counter(id(node.mesh) for k, node in enumerate(scene.nodes) if node.mesh is not None
                     and not children.get(k))
    instanced = frozenset(k for k, node in enumerate(scene.nodes) if node.mesh is not None
                          and not children.get(k) and leaves[id(node.mesh)] > 1)
    instancing = instancing_note(scene, instanced)
    notes += [instancing] if instancing else []
    prototypes: dict[int, Any] = {}

    taken: dict[Any, set[str]] = {}
    root = Sdf.Path.absoluteRootPath
    if children.get(None, 0) != 1:
        taken[root] = {"Scene"}
        wrapper = UsdGeom.Xform.Define(stage, root.AppendChild("Scene")).GetPrim()
        wrapper.SetCustomDataByKey(SCENE_ROOT_KEY, True)
        root = wrapper.GetPath()
        stage.SetDefaultPrim(wrapper)

    paths: list[Any] = []
    for index, node in enumerate(scene.nodes):
        parent_path = root if node.parent is None else paths[node.parent]
        name = _unique_name(pxr, node.name, taken.setdefault(parent_path, set()))
        path = parent_path.AppendChild(name)
        paths.append(path)
        if index in instanced:
            prototype = prototypes.get(id(node.mesh))
            if prototype is None:
                prototype = _prototype(pxr, stage, len(prototypes), taken.setdefault(Sdf.Path.absoluteRootPath, set()))
                _write_mesh(pxr, UsdGeom.Mesh(stage.GetPrimAtPath(prototype.AppendChild("mesh"))), node.mesh)
                prototypes[id(node.mesh)] = prototype
            prim = UsdGeom.Xform.Define(stage, path).GetPrim()
            prim.GetReferences().AddInternalReference(prototype)
            prim.SetInstanceable(True)
        elif node.mesh is not None and not children.get(index):
            prim = UsdGeom.Mesh.Define(stage, path).GetPrim()
            _write_mesh(pxr, UsdGeom.Mesh(prim), node.mesh)
        else:
            prim = UsdGeom.Xform.Define(stage, path).GetPrim()
            if node.mesh is not None:
                own = _unique_name(pxr, "mesh", taken.setdefault(path, set()))
                mesh_path = path.AppendChild(own)
                mesh_prim = UsdGeom.Mesh.Define(stage, mesh_path)
                mesh_prim.GetPrim().SetCustomDataByKey(NODE_MESH_KEY, True)
                _write_mesh(pxr, mesh_prim, node.mesh)
        if path.name != node.name:
            prim.SetDisplayName(node.name)
        if node.transform is not None:
            matrix = np.asarray(node.transform, dtype=np.float64)
            # transpose: USD matrices act on row vectors
            UsdGeom.Xformable(prim).AddTransformOp().Set(pxr.Gf.Matrix4d(matrix.T.tolist()))
        if node.parent is None and children.get(None, 0) == 1:
            stage.SetDefaultPrim(prim)
    return stage, notes


def _prototype(pxr: SimpleNamespace, stage: Any, number: int, taken: set[str]) -> Any:
    """A root class prim (abstract: not traversed, not drawn) holding an empty Mesh ``mesh`` marked as its
    node's own, for instances to reference; its path."""
    path = pxr.Sdf.Path.absoluteRootPath.AppendChild(_unique_name(pxr, f"Prototype{number}", taken))
    stage.CreateClassPrim(path).SetTypeName("Xform")
    pxr.UsdGeom.Mesh.Define(stage, path.AppendChild("mesh")).GetPrim().SetCustomDataByKey(NODE_MESH_KEY, True)
    return path


def _unique_name(pxr: SimpleNamespace, name: str, taken: set[str]) -> str:
    """A valid prim identifier for ``name``, not yet in ``taken`` (which it joins)."""
    base = pxr.Tf.MakeValidIdentifier(name) if name else "node"
    candidate, suffix = base, 1
    while candidate in taken:
        candidate = f"{base}_{suffix}"
        suffix += 1
    taken.add(candidate)
    return candidate


def _write_mesh(pxr: SimpleNamespace, usd_mesh: Any, mesh: Mesh) -> None:
    """Author a triangle mesh, its coordinates float32 already (:func:`.assemble.at_float32`), on ``usd_mesh``."""
    Vt, UsdGeom = pxr.Vt, pxr.UsdGeom
    points = np.ascontiguousarray(mesh.vertices, dtype=np.float32)
    usd_mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    usd_mesh.CreateFaceVertexCountsAttr(
        Vt.IntArray.FromNumpy(np.full(len(mesh.faces), 3, dtype=np.int32)))
    usd_mesh.CreateFaceVertexIndicesAttr(
        Vt.IntArray.FromNumpy(np.ascontiguousarray(mesh.faces, dtype=np.int32).ravel()))
    usd_mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(
        np.stack([points.min(axis=0), points.max(axis=0)])))
    # The schema's fallback is catmullClark: a triangle mesh must say it is not a cage.
    usd_mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    if mesh.face_colours is not None:
        rgba = mesh.face_colours.astype(np.float32) / 255.0
        usd_mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.uniform).Set(
            Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(rgba[:, :3])))
        if (mesh.face_colours[:, 3] != 255).any():
            usd_mesh.CreateDisplayOpacityPrimvar(UsdGeom.Tokens.uniform).Set(
                Vt.FloatArray.FromNumpy(np.ascontiguousarray(rgba[:, 3])))


def rounding(scene: Scene) -> float:
    """How far writing ``scene`` moves its surface, as a fraction of its diagonal: points are float3."""
    return float32_shift(scene)
