"""A closed source that no coding decodes closed: an error by default, an open surface on request.

What makes a solid impossible is stubbed (the BSP encoder finds no tree, as for busted.STL, whose
real encode takes over a minute); the patches, their decoding and every check are real.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from planefmt.groups import bodies
from planefmt import codec
from planefmt.geometry.topology import is_closed_manifold
from planefmt.errors import GeometryError, PlnWarning
from planefmt.geometry.hausdorff import hausdorff
from planefmt_converters import pln as pln_format
from planefmt.model import Mesh, Node, Scene

from test_codec_bodies import l_prism, area

TOL = 1e-6


@pytest.fixture
def no_solid(monkeypatch):
    """No tree and no sealed group: a closed body the encoder cannot keep closed."""
    def nothing(vertices, faces, face_plane, omega, h, target, report, **_):
        report.note = "stubbed: no tree"
        return None

    monkeypatch.setattr(bodies, "encode_solid", nothing)
    monkeypatch.setattr(bodies, "_sealed_group", lambda *args: None)


def test_a_closed_source_decoding_open_fails_by_default(no_solid):
    v, f = l_prism()
    with pytest.raises(GeometryError) as err:
        codec.encode_mesh(v, f, tolerance=TOL, scheme="paper")
    assert err.value.code == "TOLERANCE_NOT_MET"
    assert "a closed source decodes open" in str(err.value)
    assert "watertight=False (pln convert --allow-open) would store it as an open surface" in str(err.value)


def test_allowed_open_it_is_stored_as_a_lossy_surface_within_the_tolerance(no_solid):
    v, f = l_prism()
    assert is_closed_manifold(f, len(v))
    with pytest.warns(PlnWarning, match=r"object 0 is closed but no coding keeps it a closed solid"):
        enc = codec.encode_mesh(v, f, tolerance=TOL, watertight=False, scheme="paper")
    assert enc.lossy
    assert {int(g.kind) for g in enc.groups} <= {3, 4}
    mesh = codec.decode_mesh(enc)
    assert not is_closed_manifold(mesh.faces, len(mesh.vertices))
    diag = float(np.linalg.norm(np.ptp(v, axis=0)))
    r = hausdorff(mesh.vertices, mesh.faces, v, f, target=TOL * diag)
    assert r.upper <= TOL * diag
    assert enc.error_bound <= TOL
    assert abs(area(mesh.vertices, mesh.faces) - area(v, f)) <= 1e-6 * area(v, f)


def test_a_solid_that_closes_is_not_opened_when_allowed():
    v, f = l_prism()
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlnWarning)
        enc = codec.encode_mesh(v, f, tolerance=TOL, watertight=False, scheme="paper")
    assert not enc.lossy
    mesh = codec.decode_mesh(enc)
    assert is_closed_manifold(mesh.faces, len(mesh.vertices))


def test_the_pln_writer_reports_the_opened_object_by_name(no_solid, tmp_path):
    v, f = l_prism()
    scene = Scene(nodes=(Node(name="prism", mesh=Mesh(v, f)),))
    out = tmp_path / "prism.pln"
    notes = pln_format.write(scene, out, watertight=False, scheme="paper")
    assert len(notes) == 1 and "object 0 ('prism') is closed" in notes[0]
    decoded = codec.decode_scene(out)
    assert [n.name for n in decoded.nodes] == ["prism"]
    with pytest.raises(GeometryError):
        pln_format.write(scene, tmp_path / "strict.pln", scheme="paper")
    assert not (tmp_path / "strict.pln").exists()


def test_pln_convert_allow_open_writes_the_file_and_says_what_it_gave_up(no_solid, tmp_path, capsys):
    import trimesh

    from planefmt_converters.cli import main

    v, f = l_prism()
    src = tmp_path / "prism.stl"
    trimesh.Trimesh(v, f, process=False).export(src)
    strict = tmp_path / "strict.pln"
    assert main(["convert", "--scheme", "paper", str(src), str(strict)]) == 2
    assert "a closed source decodes open" in capsys.readouterr().err
    assert not strict.exists()
    out = tmp_path / "open.pln"
    assert main(["convert", "--scheme", "paper", "--allow-open", str(src), str(out)]) == 0
    err = capsys.readouterr().err
    assert "is closed but no coding keeps it a closed solid" in err and "not watertight" in err
    assert codec.decode_scene(out).nodes[0].mesh is not None
