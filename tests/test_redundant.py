"""Corners that carry no shape (planefmt.geometry.redundant): dropped at a lossy tolerance, the surface
kept within the bound the reduction reports, which the file's error bound counts."""

from __future__ import annotations

import io
import subprocess
import sys

import numpy as np
import pytest
import trimesh

from planefmt import codec
from planefmt.geometry import redundant
from planefmt.geometry.hausdorff import relative_hausdorff
from planefmt.geometry.polygonize import polygonize
from planefmt.geometry.topology import euler_characteristic, is_closed_manifold, signed_volume
from planefmt.model import Mesh, Node, Scene
from planefmt_converters.assemble import flatten
from planefmt_converters.registry import read

from corpus import CORPUS
from shapes import area, cube, fig7_block


def subdivided(v: np.ndarray, f: np.ndarray, times: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Each triangle split in four ``times`` times: corners inside the faces and on the edges."""
    for _ in range(times):
        v, f = trimesh.remesh.subdivide(v, f)
    return np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64)


def subdivided_cube(times: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """The unit cube subdivided: every corner but its eight carries no shape."""
    return subdivided(*cube(), times)


def reduce(v: np.ndarray, f: np.ndarray, cap: float = 1e-3) -> redundant.Reduced:
    poly = polygonize(v, f)
    on = np.maximum(poly.face_plane, 0)
    return redundant.drop_redundant_corners(poly.vertices, poly.faces, poly.face_plane, poly.omega[on],
                                            poly.distance[on], cap * poly.diagonal)


@pytest.fixture(params=["c", "python"])
def passes(request, monkeypatch):
    """Each test runs with the C passes and with the Python ones (the C ones where built)."""
    if request.param == "python":
        monkeypatch.setattr(redundant, "_passes_c", None)
    elif redundant._passes_c is None:
        pytest.skip("planefmt.geometry._collapse was not built")
    return request.param


def test_a_subdivided_cube_drops_to_its_eight_corners(passes):
    v, f = subdivided_cube()
    assert len(v) == 98 and len(f) == 192
    r = reduce(v, f)
    assert len(r.vertices) == 8 and len(r.faces) == 12 and r.dropped == 90
    assert r.offset == 0.0  # exact planes: nothing moves
    assert is_closed_manifold(r.faces, 8) and euler_characteristic(r.faces) == 2
    assert signed_volume(r.vertices, r.faces) == pytest.approx(1.0, abs=1e-12)
    assert area(r.vertices, r.faces) == pytest.approx(6.0, abs=1e-12)
    assert relative_hausdorff((v, f), (r.vertices, r.faces), tolerance=1e-12).upper <= 1e-12
    assert sorted(map(tuple, r.vertices.tolist())) == sorted({tuple(p) for p in v.tolist() if set(p) <= {0.0, 1.0}})


def test_a_circle_keeps_its_corners_and_a_cap_centre_goes(passes):
    """A cylinder's rim corners are on three planes (cap and two walls); its caps' centres on one."""
    cyl = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=16)
    v, f = np.asarray(cyl.vertices, dtype=np.float64), np.asarray(cyl.faces, dtype=np.int64)
    r = reduce(v, f)
    assert r.dropped == 2 and len(r.vertices) == 32
    assert np.allclose(np.linalg.norm(r.vertices[:, :2], axis=1), 1.0)
    assert signed_volume(r.vertices, r.faces) == pytest.approx(signed_volume(v, f), rel=1e-12)


def test_a_bent_crease_keeps_its_corner(passes):
    """Two planes meet along a crease; its middle corner is pushed off the line: not straight, kept."""
    v, f = subdivided_cube(1)
    mid = np.flatnonzero((v == [0.5, 0.0, 0.0]).all(axis=1))[0]
    v = v.copy()
    v[mid] = [0.5, 0.01, 0.01]
    r = reduce(v, f)
    assert any(np.allclose(p, [0.5, 0.01, 0.01]) for p in r.vertices)


def test_a_corner_two_solids_share_is_kept(passes):
    """Two subdivided cubes touching at a corner (welded into one): two fans meet there, not one; every
    other corner but the cubes' own goes."""
    v, f = subdivided_cube(1)
    r = reduce(np.vstack([v, v + 1.0]), np.vstack([f, f + len(v)]))
    assert len(r.vertices) == 15 and len(r.faces) == 24
    assert any(np.array_equal(p, [1.0, 1.0, 1.0]) for p in r.vertices)


def test_colours_on_one_plane_keep_their_border(passes):
    """A plane in two colours is two labels with one normal: the border between them is no crease,
    no corner on it goes, and each colour keeps its area."""
    v, f = subdivided_cube(2)
    poly = polygonize(v, f)
    centre = v[f].mean(axis=1)
    colour = ((np.isclose(centre[:, 2], 0.0)) & (centre[:, 0] < 0.5)).astype(np.int64)
    label = poly.face_plane * 2 + colour
    on = np.maximum(poly.face_plane, 0)
    r = redundant.drop_redundant_corners(poly.vertices, poly.faces, label, poly.omega[on], poly.distance[on], 1e-3)
    kept_colour = colour[r.origin]
    for c in (0, 1):
        assert area(r.vertices, r.faces[kept_colour == c]) == pytest.approx(area(v, f[colour == c]), abs=1e-12)
    assert any(np.allclose(p, [0.5, 0.5, 0.0]) for p in r.vertices)


@pytest.mark.parametrize("name", ["box.STL", "1002_tray_bottom.STL", "octagonal_pocket.stl"])
def test_cad_parts_keep_their_surface_within_the_bound(name, passes):
    scene, _ = read(str(CORPUS / "cad" / name))
    mesh = flatten(scene)
    poly = polygonize(mesh.vertices, mesh.faces)
    on = np.maximum(poly.face_plane, 0)
    r = redundant.drop_redundant_corners(poly.vertices, poly.faces, poly.face_plane, poly.omega[on],
                                         poly.distance[on], 1e-6 * poly.diagonal)
    assert r.dropped > 0 and 0.0 < r.offset <= 1e-6 * poly.diagonal
    assert euler_characteristic(r.faces) == euler_characteristic(poly.faces)
    assert is_closed_manifold(r.faces, len(r.vertices)) == is_closed_manifold(poly.faces, len(poly.vertices))
    h = relative_hausdorff((poly.vertices, poly.faces), (r.vertices, r.faces), tolerance=1e-3 * r.offset / poly.diagonal)
    assert h.certified and h.upper * poly.diagonal <= r.offset


@pytest.mark.skipif(redundant._passes_c is None, reason="planefmt.geometry._collapse was not built")
@pytest.mark.parametrize("name", ["box.STL", "ADIS16480.STL"])
def test_c_and_python_drop_the_same_corners(name, monkeypatch):
    scene, _ = read(str(CORPUS / "cad" / name))
    mesh = flatten(scene)
    poly = polygonize(mesh.vertices, mesh.faces)
    on = np.maximum(poly.face_plane, 0)
    args = (poly.vertices, poly.faces, poly.face_plane, poly.omega[on], poly.distance[on], 1e-6 * poly.diagonal)
    a = redundant.drop_redundant_corners(*args)
    monkeypatch.setattr(redundant, "_passes_c", None)
    b = redundant.drop_redundant_corners(*args)
    assert a.dropped == b.dropped > 0 and a.offset == b.offset
    assert np.array_equal(a.faces, b.faces) and np.array_equal(a.vertices, b.vertices)


def _decoded(data: bytes) -> Mesh:
    return flatten(codec.decode_scene(io.BytesIO(data)))


def test_a_lossy_encode_drops_them_and_counts_the_move_in_its_bound():
    scene, _ = read(str(CORPUS / "cad" / "box.STL"))
    source = flatten(scene)
    files = {}
    for keep in (False, True):
        buf = io.BytesIO()
        header = codec.encode_scene(scene, buf, tolerance=4e-5, keep_corners=keep)
        back = _decoded(buf.getvalue())
        h = relative_hausdorff((source.vertices, source.faces), (back.vertices, back.faces), tolerance=1e-7)
        assert h.upper <= header.error_bound <= 4e-5
        files[keep] = (len(buf.getvalue()), len(back.faces))
    assert files[True][1] == len(source.faces) and files[False][1] < len(source.faces) / 3
    assert files[False][0] < 0.6 * files[True][0]


def test_only_a_lossy_encode_drops_corners():
    """The paper's stepped block (not convex: a shell), subdivided: at 1e-4 its 16 corners and 28
    triangles are left; lossless, or with keep_corners, all 448 triangles."""
    v, f = subdivided(*fig7_block())
    scene = Scene((Node("block", mesh=Mesh(v, f)),))
    counts = {}
    for tolerance, keep in ((1e-4, False), (1e-6, False), (1e-4, True)):
        buf = io.BytesIO()
        codec.encode_scene(scene, buf, tolerance=tolerance, keep_corners=keep)
        back = _decoded(buf.getvalue())
        counts[tolerance, keep] = (len(back.vertices), len(back.faces))
        assert signed_volume(back.vertices, back.faces) == pytest.approx(22.0, rel=1e-3)
    assert counts == {(1e-4, False): (16, 28), (1e-6, False): (len(v), 448), (1e-4, True): (len(v), 448)}


def test_cli_keep_corners(tmp_path):
    v, f = subdivided(*fig7_block())
    src = tmp_path / "block.obj"
    trimesh.Trimesh(v, f, process=False).export(src)
    counts = {}
    for flag in ([], ["--keep-corners"]):
        out = tmp_path / f"block{len(flag)}.pln"
        run = subprocess.run([sys.executable, "-m", "planefmt_converters.cli", "convert", str(src), str(out),
                              "--tolerance", "1e-4", *flag], capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        counts[bool(flag)] = len(_decoded(out.read_bytes()).faces)
    assert counts == {False: 28, True: 448}
