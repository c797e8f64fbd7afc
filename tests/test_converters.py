"""Format converters: corpus reads, round trips, validators, bad input, atomic output."""

from __future__ import annotations

import functools
import json
import shutil
import struct
import sys
from pathlib import Path

import numpy as np
import pytest

from planefmt.errors import ConversionError
from planefmt.model import Mesh, Node, Scene, Units
from planefmt_converters import registry
from planefmt_converters.assemble import build_mesh, flatten, in_metres, reoriented, world_transforms
from planefmt_converters.atomic import atomic_paths
from planefmt_converters.polygons import triangulate
from planefmt_converters.validators import ValidatorUnavailable, validate_gltf, validate_usd

import corpus

CORPUS_FILES = corpus.files()
CORPUS_IDS = corpus.ids(CORPUS_FILES)
CORPUS = corpus.CORPUS

FLAT_FORMATS = [".obj", ".ply", ".stl", ".off"]
SCENE_FORMATS = [".glb", ".gltf", ".usda", ".usdc", ".usdz"]
GLTF_FORMATS = [".glb", ".gltf"]
USD_FORMATS = [".usda", ".usdc", ".usdz"]
#: Formats that store coordinates as float32.
FLOAT32_FORMATS = {".ply", ".stl", ".glb", ".gltf", ".usda", ".usdc", ".usdz"}

#: The format each corpus extension is detected as, by content.
EXPECTED_FORMAT = {".stl": "stl", ".obj": "obj", ".ply": "ply", ".off": "off", ".glb": "glb",
                   ".gltf": "gltf", ".usda": "usda", ".usdz": "usdz"}


@functools.lru_cache(maxsize=None)
def corpus_scene(path: Path) -> tuple[Scene, tuple[str, ...]]:
    scene, dropped = registry.read(path)
    return scene, tuple(dropped)


@pytest.fixture(scope="module")
def out_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("converted")


@functools.lru_cache(maxsize=None)
def converted(folder: Path, source: Path, suffix: str) -> tuple[Path, tuple[str, ...]]:
    """Write a corpus scene once per output format; later tests reuse the file."""
    target = folder / f"{source.parent.name}-{source.stem}{suffix}"
    notes = registry.write(corpus_scene(source)[0], target)
    return target, tuple(notes)


def corners(mesh: Mesh) -> np.ndarray:
    """(m, 3, 3) triangle corner coordinates: independent of vertex numbering."""
    return mesh.vertices[mesh.faces]


def diagonal(mesh: Mesh) -> float:
    return float(np.linalg.norm(mesh.vertices.max(axis=0) - mesh.vertices.min(axis=0)))


def leftovers(folder: Path) -> list[str]:
    """Temporary files a writer left behind."""
    return sorted(p.name for p in folder.iterdir() if ".tmp" in p.name)


# --------------------------------------------------------------------------- corpus reads

@pytest.mark.parametrize("path", CORPUS_FILES, ids=CORPUS_IDS)
def test_corpus_file_reads(path: Path) -> None:
    scene, dropped = corpus_scene(path)
    meshes = [node.mesh for node in scene.nodes if node.mesh is not None]
    assert meshes
    assert all(isinstance(note, str) and note for note in dropped)
    for index, node in enumerate(scene.nodes):
        assert node.parent is None or 0 <= node.parent < index  # parents come first
    for mesh in meshes:
        assert mesh.vertices.dtype == np.float64 and mesh.faces.dtype == np.int64
        assert np.isfinite(mesh.vertices).all()
        assert mesh.faces.min() >= 0 and mesh.faces.max() < len(mesh.vertices)
        # merged by exact position: every position once, every vertex used
        assert len(np.unique(mesh.vertices, axis=0)) == len(mesh.vertices)
        assert len(np.unique(mesh.faces)) == len(mesh.vertices)
        f = mesh.faces
        assert ((f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])).all()


@pytest.mark.parametrize("path", CORPUS_FILES, ids=CORPUS_IDS)
def test_corpus_format_detected_by_content(path: Path, tmp_path: Path) -> None:
    expected = EXPECTED_FORMAT.get(path.suffix.lower())
    if path.suffix.lower() == ".usd":
        expected = "usdc" if path.read_bytes().startswith(b"PXR-USDC") else "usda"
    renamed = tmp_path / "mesh.data"
    shutil.copy(path, renamed)
    assert registry.detect(renamed).name == expected
    assert registry.detect(path).name == expected


def test_usd_prims_from_corpus_keep_hierarchy() -> None:
    path = CORPUS / "usd" / "RoughnessTest.usdz"
    scene, dropped = corpus_scene(path)
    names = [node.name for node in scene.nodes]
    assert names[:4] == ["Roughness", "Tex", "Tex000", "Mesh"]
    assert sum(node.mesh is not None for node in scene.nodes) == 6
    assert scene.up_axis == "Z" and not any("upAxis" in note for note in dropped)
    assert {"texture coordinates", "materials", "textures"} <= set(dropped)
    # the Material scope holds no mesh and is left out
    assert "Materials" not in names


# --------------------------------------------------------------------------- round trips

@pytest.mark.parametrize("suffix", FLAT_FORMATS + SCENE_FORMATS)
@pytest.mark.parametrize("path", CORPUS_FILES, ids=CORPUS_IDS)
def test_round_trip_keeps_geometry(path: Path, suffix: str, out_dir: Path) -> None:
    scene, _ = corpus_scene(path)
    target, notes = converted(out_dir, path, suffix)
    again, _ = registry.read(target)
    # glTF is in metres: a source in other units comes back scaled. A format with an up axis of its
    # own (glTF: Y) holds the scene turned into it.
    scene = in_metres(scene) if suffix in GLTF_FORMATS else scene
    upright = scene if again.up_axis is None else reoriented(scene, again.up_axis)
    before, after = flatten(upright), flatten(again)
    assert len(after.faces) == len(before.faces)
    # float32 formats: half a float32 ulp of the largest coordinate; text: 17 decimals
    scale = max(diagonal(before), float(np.abs(before.vertices).max()))
    tolerance = 1e-7 * scale if suffix in FLOAT32_FORMATS else 1e-12 * scale
    assert np.abs(corners(after) - corners(before)).max() <= tolerance
    # flat formats store world coordinates, scene formats each node's own
    stored = [before] if suffix in FLAT_FORMATS else [n.mesh for n in scene.nodes if n.mesh]
    rounded = any((m.vertices.astype(np.float32) != m.vertices).any() for m in stored)
    assert ("coordinates rounded to float32" in notes) == (rounded and suffix in FLOAT32_FORMATS)
    if len(scene.nodes) > 1 and suffix in FLAT_FORMATS:
        assert any(note.startswith("scene hierarchy") for note in notes)


@pytest.mark.parametrize("suffix", SCENE_FORMATS)
@pytest.mark.parametrize("path", CORPUS_FILES, ids=CORPUS_IDS)
def test_scene_formats_keep_nodes(path: Path, suffix: str, out_dir: Path) -> None:
    source, _ = corpus_scene(path)
    target, _ = converted(out_dir, path, suffix)
    again, _ = registry.read(target)
    scene = reoriented(in_metres(source) if suffix in GLTF_FORMATS else source, again.up_axis)
    assert [n.name for n in again.nodes] == [n.name for n in scene.nodes]
    assert [n.parent for n in again.nodes] == [n.parent for n in scene.nodes]
    for node, back in zip(scene.nodes, again.nodes):
        assert np.array_equal(np.eye(4) if node.transform is None else node.transform,
                              np.eye(4) if back.transform is None else back.transform)
        assert (node.mesh is None) == (back.mesh is None)
        if node.mesh is None:
            continue
        assert len(back.mesh.faces) == len(node.mesh.faces)
        assert len(back.mesh.vertices) == len(node.mesh.vertices)
        assert np.array_equal(corners(back.mesh), corners(node.mesh).astype(np.float32))
        if node.mesh.face_colours is None:
            assert back.mesh.face_colours is None
        else:
            assert np.array_equal(back.mesh.face_colours, node.mesh.face_colours)
    if suffix in USD_FORMATS and scene.units != Units.UNSPECIFIED:
        assert again.units == scene.units



@pytest.mark.parametrize("rel", ["cad/plate_holes.STL", "convex/cube_subd.obj", "smooth_dense/npm_bunny.ply"])
def test_a_name_made_from_the_file_name_is_not_kept(rel: str) -> None:
    # trimesh names a file's only node after the file; that is the file's name, not the mesh's.
    scene, _ = registry.read(CORPUS / rel)
    assert [n.name for n in scene.nodes] == [""]


@pytest.mark.parametrize("suffix", [".glb", ".gltf", ".usda", ".usdc"])
def test_unnamed_and_named_nodes_come_back_as_they_were(suffix: str, tmp_path: Path) -> None:
    mesh = Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64),
                np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    # "1" is the name trimesh gives glTF's unnamed node 1: a node that holds it keeps it.
    scene = Scene(nodes=(Node(name="", mesh=mesh), Node(name="1", parent=0, mesh=mesh),
                         Node(name="", parent=0, mesh=mesh), Node(name="wheel", parent=0, mesh=mesh)))
    target = tmp_path / f"nodes{suffix}"
    registry.write(scene, target)
    again, _ = registry.read(target)
    assert sorted(n.name for n in again.nodes) == ["", "", "1", "wheel"]

# --------------------------------------------------------------------------- validators

def khronos_report(path: Path) -> dict:
    """glTF-Validator's report; skips without node, fails if only the npm package is missing."""
    try:
        return validate_gltf(path)
    except ValidatorUnavailable as exc:
        if shutil.which("node") is None:
            pytest.skip(f"node is not installed: {exc}")
        pytest.fail(f"{exc} (tools/install_validators.sh installs it)")


@pytest.mark.parametrize("suffix", GLTF_FORMATS)
@pytest.mark.parametrize("path", CORPUS_FILES, ids=CORPUS_IDS)
def test_gltf_output_passes_khronos_validator(path: Path, suffix: str, out_dir: Path) -> None:
    target, _ = converted(out_dir, path, suffix)
    report = khronos_report(target)
    errors = [m for m in report["issues"]["messages"] if m["severity"] == 0]
    assert report["issues"]["numErrors"] == 0, errors[:5]
    assert report["info"]["totalVertexCount"] > 0


@pytest.mark.parametrize("suffix", USD_FORMATS)
@pytest.mark.parametrize("path", CORPUS_FILES, ids=CORPUS_IDS)
def test_usd_output_passes_usd_validation(path: Path, suffix: str, out_dir: Path) -> None:
    target, _ = converted(out_dir, path, suffix)
    errors = [message for severity, message in validate_usd(target) if severity == "error"]
    assert errors == []


def test_validators_report_broken_files(tmp_path: Path) -> None:
    usda = tmp_path / "bare.usda"
    usda.write_text('#usda 1.0\ndef Mesh "m" {}\n')
    assert any("metersPerUnit" in message for _, message in validate_usd(usda))
    glb = tmp_path / "cut.glb"
    registry.write(_coloured_scene(), tmp_path / "whole.glb")
    data = (tmp_path / "whole.glb").read_bytes()
    glb.write_bytes(data[:len(data) // 2])
    assert khronos_report(glb)["issues"]["numErrors"] > 0


# --------------------------------------------------------------------------- synthetic scenes

def _cube(offset: float = 0.0, colours: bool = False) -> Mesh:
    corners_ = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    rgba = None
    if colours:
        rgba = np.zeros((12, 4), np.uint8)
        rgba[:, 0] = np.arange(12) * 20
        rgba[:, 3] = np.where(np.arange(12) % 2, 255, 128)
    return Mesh(vertices=corners_ + offset, faces=faces, face_colours=rgba)


def _coloured_scene() -> Scene:
    shared = _cube(colours=True)
    move = np.eye(4)
    move[:3, 3] = [3.0, 0.0, 0.0]
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    return Scene(nodes=(
        Node("root", None, None, _cube(10.0)),      # a mesh node with children
        Node("same name", 0, move, shared),
        Node("same name", 0, mirror, shared),       # repeated name, instanced mesh
        Node("second root", None, move, None),      # a second root without mesh
        Node("leaf", 3, None, _cube(-5.0)),
    ), units=Units.MILLIMETRE)


@pytest.mark.parametrize("suffix", SCENE_FORMATS)
def test_scene_structure_survives(suffix: str, tmp_path: Path) -> None:
    written = _coloured_scene()
    registry.write(written, tmp_path / f"s{suffix}")
    again, _ = registry.read(tmp_path / f"s{suffix}")
    # glTF holds the millimetre scene in metres: scaled by 0.001, then rounded to float32
    scene = in_metres(written) if suffix in GLTF_FORMATS else written
    exact = suffix not in GLTF_FORMATS
    # the repeated name too: trimesh's reader makes it unique (issue 50's sweep: bench usd/texturedcube's
    # /Cube/Cube read back from GLB as Cube_1), glTF's reader takes the file's own
    assert [n.name for n in again.nodes] == [n.name for n in scene.nodes]
    assert [n.parent for n in again.nodes] == [n.parent for n in scene.nodes]
    for node, back in zip(scene.nodes, again.nodes):
        if node.mesh is not None:
            expected = corners(node.mesh) if exact else corners(node.mesh).astype(np.float32)
            assert np.array_equal(corners(back.mesh), expected)
            assert (back.mesh.face_colours is None) == (node.mesh.face_colours is None)
            if node.mesh.face_colours is not None:
                assert np.array_equal(back.mesh.face_colours, node.mesh.face_colours)
    for a, b in zip(world_transforms(scene), world_transforms(again)):
        assert np.array_equal(a, b) if exact else np.allclose(a, b, rtol=0, atol=1e-7 * np.abs(a).max())
    if suffix in USD_FORMATS:
        assert again.units == Units.MILLIMETRE
    else:
        assert again.nodes[1].mesh is again.nodes[2].mesh  # instancing kept


def test_gltf_instances_and_sidecar(tmp_path: Path) -> None:
    notes = registry.write(_coloured_scene(), tmp_path / "s.gltf")
    tree = json.loads((tmp_path / "s.gltf").read_text())
    assert tree["buffers"][0]["uri"] == "s.bin" and (tmp_path / "s.bin").exists()
    assert len(tree["meshes"]) == 3  # the shared cube once
    assert [node.get("name") for node in tree["nodes"]].count("same name") == 2
    assert any(note.startswith("units (millimetre") for note in notes)


@pytest.mark.parametrize("suffix,keeps_colours", [
    (".ply", True), (".obj", False), (".stl", False), (".off", False)])
def test_flat_formats_and_colours(suffix: str, keeps_colours: bool, tmp_path: Path) -> None:
    scene = _coloured_scene()
    notes = registry.write(scene, tmp_path / f"s{suffix}")
    again, _ = registry.read(tmp_path / f"s{suffix}")
    assert len(again.nodes) == 1
    world = flatten(scene)
    assert np.allclose(corners(again.nodes[0].mesh), corners(world), atol=1e-6)
    assert ("face colours" in notes) != keeps_colours
    if keeps_colours:
        assert np.array_equal(again.nodes[0].mesh.face_colours, world.face_colours)
    assert "units (millimetre)" in notes


def test_mirroring_transform_keeps_outward_winding() -> None:
    scene = Scene(nodes=(Node("m", None, np.diag([-1.0, 1.0, 1.0, 1.0]), _cube()),))
    mesh = flatten(scene)
    tri = corners(mesh)
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    outward = tri.mean(axis=1) - mesh.vertices.mean(axis=0)
    assert (np.einsum("ij,ij->i", normals, outward) > 0).all()


@pytest.mark.parametrize("suffix,magic", [(".ply", b"ply\nformat ascii"), (".stl", b"solid")])
def test_ascii_option(suffix: str, magic: bytes, tmp_path: Path) -> None:
    registry.write(Scene(nodes=(Node("c", mesh=_cube()),)), tmp_path / f"a{suffix}", ascii=True)
    assert (tmp_path / f"a{suffix}").read_bytes().startswith(magic)
    with pytest.raises(ConversionError, match="options"):
        registry.write(Scene(nodes=(Node("c", mesh=_cube()),)), tmp_path / "a.glb", ascii=True)
    assert not (tmp_path / "a.glb").exists()


# --------------------------------------------------------------------------- USD details

USDA_POLYGONS = """#usda 1.0
(
    defaultPrim = "W"
    metersPerUnit = 0.001
    upAxis = "Z"
)
def Xform "W"
{
    def Xform "Moved"
    {
        double3 xformOp:translate = (0, 0, 5)
        uniform token[] xformOpOrder = ["xformOp:translate"]
        def Mesh "L"
        {
            point3f[] points = [(0,0,0),(2,0,0),(2,1,0),(1,1,0),(1,2,0),(0,2,0),
                                (5,0,0),(6,0,0),(6,1,0)]
            int[] faceVertexCounts = [6, 3, 3]
            int[] faceVertexIndices = [3,4,5,0,1,2, 6,7,8, 6,8,7]
            int[] holeIndices = [2]
            uniform token orientation = "leftHanded"
            uniform token subdivisionScheme = "none"
            color3f[] primvars:displayColor = [(1,0,0),(0,1,0),(0,0,1)] (interpolation = "uniform")
        }
    }
    def Mesh "Guide"
    {
        uniform token purpose = "guide"
        point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0,1,2]
    }
}
"""


def test_usd_reader_polygons_orientation_holes_colours(tmp_path: Path) -> None:
    path = tmp_path / "poly.usda"
    path.write_text(USDA_POLYGONS)
    scene, dropped = registry.read(path)
    assert scene.units == Units.MILLIMETRE
    assert [n.name for n in scene.nodes] == ["W", "Moved", "L"]
    assert scene.nodes[1].transform[2, 3] == 5.0
    mesh = scene.nodes[2].mesh
    tri = corners(mesh)
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert len(mesh.faces) == 5  # L hexagon: 4 triangles, one triangle, the hole dropped
    assert np.isclose(np.abs(normals[:, 2]).sum() / 2, 3.5)  # areas: L = 3, triangle = 0.5
    assert (normals[:, 2] < 0).all()  # leftHanded: counter-clockwise seen from -z
    red = (mesh.face_colours == [255, 0, 0, 255]).all(axis=1)
    assert red.sum() == 4
    assert "guide prims" in dropped and scene.up_axis == "Z"


def test_usd_writer_marks_and_names(tmp_path: Path) -> None:
    from pxr import Usd, UsdGeom

    registry.write(_coloured_scene(), tmp_path / "s.usda", up_axis="Z")
    stage = Usd.Stage.Open(str(tmp_path / "s.usda"))
    assert UsdGeom.GetStageUpAxis(stage) == "Z"
    assert stage.GetDefaultPrim().GetName() == "Scene"  # two roots: wrapped
    root_mesh = stage.GetPrimAtPath("/Scene/root/mesh")
    assert root_mesh.IsA(UsdGeom.Mesh)
    assert UsdGeom.Mesh(root_mesh).GetSubdivisionSchemeAttr().Get() == "none"
    assert stage.GetPrimAtPath("/Scene/root/same_name_1").GetDisplayName() == "same name"
    extent = UsdGeom.Mesh(root_mesh).GetExtentAttr().Get()
    assert tuple(extent[0]) == (10, 10, 10) and tuple(extent[1]) == (11, 11, 11)


# --------------------------------------------------------------------------- bad input

def _binary_ply(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    body = np.asarray(vertices, "<f4").tobytes() + b"".join(
        struct.pack("<B3i", 3, *face) for face in faces)
    return header.encode() + body


BAD_INPUTS = {
    "empty.obj": b"",
    "empty.glb": b"",
    "empty.stl": b"",
    "empty.usda": b"",
    "text.glb": b"this is not a binary glTF file\n",
    "text.usdz": b"nor a usdz package\n",
    "truncated.ply": _binary_ply(np.eye(3), [(0, 1, 2)] * 40)[:-90],
    "nan.obj": b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n",
    "inf.ply": b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
               b"property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
               b"end_header\n0 0 0\n1 0 0\ninf 1 0\n3 0 1 2\n",
    "nan.usda": b'#usda 1.0\ndef Mesh "m" {\n point3f[] points = [(0,0,0),(1,0,0),(nan,1,0)]\n'
                b' int[] faceVertexCounts = [3]\n int[] faceVertexIndices = [0,1,2]\n}\n',
    "badindex.usda": b'#usda 1.0\ndef Mesh "m" {\n point3f[] points = [(0,0,0),(1,0,0)]\n'
                     b' int[] faceVertexCounts = [3]\n int[] faceVertexIndices = [0,1,2]\n}\n',
    "unknown.xyz": b"\x00\x01 some bytes no reader claims",
    "points.obj": b"v 0 0 0\nv 1 0 0\n",
}


@pytest.mark.parametrize("name", sorted(BAD_INPUTS))
def test_bad_input_raises_and_writes_nothing(name: str, tmp_path: Path) -> None:
    source = tmp_path / name
    source.write_bytes(BAD_INPUTS[name])
    target = tmp_path / "out.glb"
    with pytest.raises(ConversionError) as caught:
        scene, _ = registry.read(source)
        registry.write(scene, target)
    assert caught.value.file == str(source)
    assert str(source) in str(caught.value)
    if name == "unknown.xyz":
        assert caught.value.code == "UNKNOWN_FORMAT"
    if name.startswith(("nan", "inf")):
        assert "NaN or infinite" in str(caught.value)
    assert not target.exists()
    assert leftovers(tmp_path) == []


def test_missing_file_and_unknown_names(tmp_path: Path) -> None:
    with pytest.raises(ConversionError, match="cannot open"):
        registry.read(tmp_path / "absent.obj")
    with pytest.raises(ConversionError) as caught:
        registry.write(Scene(nodes=(Node("c", mesh=_cube()),)), tmp_path / "out.xyz")
    assert caught.value.code == "UNKNOWN_FORMAT"
    with pytest.raises(ConversionError) as caught:
        registry.get("nope")
    assert caught.value.code == "UNKNOWN_FORMAT"


def test_build_mesh_rejects_and_cleans() -> None:
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [-0.0, 0, 0], [5, 5, 5]], float)
    mesh, degenerate = build_mesh(vertices, [[0, 1, 2], [3, 1, 2], [0, 3, 1]])
    assert degenerate == 1  # -0.0 merged with 0.0: the last face lost a corner
    assert len(mesh.vertices) == 3  # the unused vertex dropped
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 1, 2]]  # a repeated face is kept
    with pytest.raises(ConversionError, match="outside"):
        build_mesh(vertices, [[0, 1, 9]])
    with pytest.raises(ConversionError, match="NaN"):
        build_mesh(np.array([[0, 0, np.inf]] * 3), [[0, 1, 2]])


# --------------------------------------------------------------------------- atomic output

@pytest.mark.parametrize("suffix", FLAT_FORMATS + SCENE_FORMATS)
def test_failed_write_leaves_target_untouched(suffix: str, tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / f"old{suffix}"
    target.write_bytes(b"previous content")

    def refuse(*args: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("planefmt_converters.atomic.os.replace", refuse)
    with pytest.raises(ConversionError, match="No space left"):
        registry.write(_coloured_scene(), target)
    assert target.read_bytes() == b"previous content"
    assert sorted(p.name for p in tmp_path.iterdir()) == [target.name]  # no .bin, no temp


def test_atomic_paths_all_or_nothing(tmp_path: Path) -> None:
    targets = [tmp_path / "a.bin", tmp_path / "a.gltf"]
    with pytest.raises(RuntimeError):
        with atomic_paths(targets) as temps:
            for temp in temps:
                temp.write_bytes(b"partial")
            raise RuntimeError("crash while writing")
    assert list(tmp_path.iterdir()) == []
    with atomic_paths(targets) as temps:
        for temp in temps:
            temp.write_bytes(b"done")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.bin", "a.gltf"]


# --------------------------------------------------------------------------- registry

def test_polygon_triangulation_fans_convex_and_clips_concave() -> None:
    points = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)
    # start the ring at the reflex corner (3): a fan from there would leave the polygon
    triangles, face = triangulate(points, np.array([6, 2]), np.array([3, 4, 5, 0, 1, 2, 0, 1]))
    assert len(triangles) == 4 and (face == 0).all()
    tri = points[triangles]
    area = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2] / 2
    assert (area > 0).all() and np.isclose(area.sum(), 3.0)


class _EntryPoint:
    def __init__(self, name: str, value: object) -> None:
        self.name, self.value, self._value = name, f"tests:{name}", value

    def load(self) -> object:
        if isinstance(self._value, Exception):
            raise self._value
        return self._value


def test_entry_point_formats_load_lazily(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[str] = []

    def read_xyz(path: str) -> tuple[Scene, list[str]]:
        calls.append(path)
        return Scene(nodes=(Node("xyz", mesh=_cube()),)), ["everything"]

    plugin = registry.Format("xyz", (".xyz",), lambda head, size: head.startswith(b"XYZ"),
                             read_xyz, None, "test format")
    entries = [_EntryPoint("xyz", lambda: plugin), _EntryPoint("broken", ImportError("no dep")),
               _EntryPoint("clash", registry.Format("obj", (".obj2",)))]
    monkeypatch.setattr(registry.metadata, "entry_points", lambda group: entries)
    monkeypatch.setattr(registry, "_plugins", None)
    monkeypatch.setattr(registry, "_plugin_errors", [])
    source = tmp_path / "thing.bin"
    source.write_bytes(b"XYZ data")
    scene, dropped = registry.read(source)
    assert registry.detect(source) is plugin and calls and dropped == ["everything"]
    errors = registry.plugin_errors()
    assert any("broken" in line and "no dep" in line for line in errors)
    assert any("'obj' is already taken" in line for line in errors)
    with pytest.raises(ConversionError, match="no writable format"):
        registry.write(scene, tmp_path / "out.xyz")


def test_missing_dependency_fails_only_its_formats(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    scene = Scene(nodes=(Node("c", mesh=_cube()),))
    registry.write(scene, tmp_path / "c.obj")
    registry.write(scene, tmp_path / "c.usda")
    monkeypatch.setitem(sys.modules, "pxr", None)  # as if usd-core were not installed
    with pytest.raises(ConversionError, match="needs usd-core"):
        registry.read(tmp_path / "c.usda")
    assert registry.read(tmp_path / "c.obj")[0].nodes[0].mesh is not None
    monkeypatch.delitem(sys.modules, "pxr")
    monkeypatch.setitem(sys.modules, "trimesh", None)
    with pytest.raises(ConversionError, match="needs trimesh"):
        registry.read(tmp_path / "c.obj")
    assert registry.read(tmp_path / "c.usda")[0].nodes[0].mesh is not None


def test_a_gltf_file_converts_to_the_same_bytes_every_time(tmp_path: Path) -> None:
    """trimesh names the frames of a mesh's primitives with a random suffix (TestScene.gltf's two d8
    meshes of two primitives each); the reader numbers them instead, so outputs are reproducible."""
    from planefmt_converters.cli import main

    src = CORPUS / "gltf_scene" / "TestScene.gltf"
    outputs = []
    for k in range(2):
        assert main(["convert", str(src), str(tmp_path / f"{k}.pln"), "--tolerance", "1e-4"]) == 0
        outputs.append((tmp_path / f"{k}.pln").read_bytes())
    assert outputs[0] == outputs[1]
    from planefmt_converters import registry

    names = [node.name for node in registry.read(str(src))[0].nodes]
    assert {"d8_0", "d8_1", "d8 (1)_0", "d8 (1)_1"} <= set(names)
